"""The real transforms of the even/odd half-space kernels (HalfSpaceInfluence._symmetric_hat)."""
import numpy as np
import pytest

from conformal.influence import fft as ffts
from conformal.influence.halfspace import HalfSpaceInfluence, _transform_type1
from conformal.materials import Material

MAT = Material.identical(80000.0, 0.28)


@pytest.mark.parametrize("mx, my, dy", [(28, 80, 0.2), (45, 100, 0.3), (4, 3, 0.2), (13, 21, 0.25)])
def test_kernel_spectra_are_the_rfft2_of_the_wrapped_kernels(mx, my, dy):
    """Real, and the rfft2 of the wrapped kernel to its rounding noise (even padded sizes:
    DCT-I/DST-I of the quarter; odd: the rfft2 itself, bitwise)."""
    op = HalfSpaceInfluence.for_grid(mx, my, 0.2, dy, MAT, shared=False)
    Mx, My = op.padded_shape
    even = Mx % 2 == 0 and My % 2 == 0
    for i, j in ((0, 0), (0, 1), (1, 0), (1, 1), (2, 2)):
        ref = ffts.rfft2(op.kernel(i, j))
        got = op.kernel_hat(i, j)
        assert got.shape == ref.shape and got.dtype == ref.dtype
        if even:
            assert not got.imag.any()
            assert np.abs(got - ref).max() <= 1e-14 * np.abs(ref).max()
        else:
            assert np.array_equal(got, ref)


def test_transform_type1_is_scipys():
    from scipy import fft as sfft
    q = np.random.default_rng(1).normal(size=(7, 9))
    assert np.array_equal(_transform_type1(q, odd=False), sfft.dctn(q, type=1))
    assert np.array_equal(_transform_type1(q, odd=True), sfft.dstn(q, type=1))


def test_single_precision_product_takes_the_real_factors():
    op = HalfSpaceInfluence.for_grid(28, 80, 0.2, 0.2, MAT, shared=False)
    p32 = op.tangential_product32()
    assert all(k.dtype == np.float32 for k in p32.k)
    assert np.array_equal(p32.k[0], op.kernel_hat(0, 0).real.astype(np.float32))
