"""The FFT products of the half-space operator (conformal.influence.halfspace through
conformal.influence.fft) against the dense matrix of the closed-form influence numbers, and the
direct pocketfft calls against scipy.fft."""
import numpy as np
import pytest
from scipy import fft as sfft

from conformal.influence import fft as ffts
from conformal.influence import halfspace as hs
from conformal.influence.halfspace import HalfSpaceInfluence, rectangle_influence
from conformal.materials import Material

# dissimilar bodies (K != 0: every coupling product), non-square elements, odd and even sizes
STEEL_ALU = Material(82000.0, 0.28, 26000.0, 0.33)


def dense_closed_form(mx, my, dx, dy, mat):
    """The 3N x 3N matrix from rectangle_influence at every element-centre offset (Love 1929,
    Kalker 1990), independent of the operator's kernels and transforms."""
    ix, iy = np.meshgrid(np.arange(mx), np.arange(my), indexing="ij")
    ix, iy = ix.ravel(), iy.ravel()
    A = rectangle_influence((ix[:, None] - ix[None, :]) * dx, (iy[:, None] - iy[None, :]) * dy, dx, dy,
                            G=mat.G, nu=mat.nu, K=mat.K)
    N = ix.size
    return np.block([[A[:, :, i, j] for j in range(3)] for i in range(3)]).reshape(3 * N, 3 * N)


def rel(a, b):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(b).max())


@pytest.mark.parametrize("mx, my, dx, dy", [(7, 5, 0.2, 0.3), (6, 9, 0.5, 0.25), (1, 4, 0.1, 0.1), (11, 1, 0.3, 0.1)])
def test_products_equal_the_dense_closed_form(mx, my, dx, dy):
    mat = STEEL_ALU
    assert mat.K != 0.0
    op = HalfSpaceInfluence.for_grid(mx, my, dx, dy, mat, shared=False)
    D = dense_closed_form(mx, my, dx, dy, mat)
    N = mx * my
    p = np.random.default_rng(mx * 100 + my).normal(size=(3, mx, my))
    u = (D @ p.reshape(-1)).reshape(3, mx, my)
    assert rel(op.apply(p), u) <= 1e-12
    Dzz = D[2 * N:, 2 * N:]
    assert rel(op.apply_normal(p[2]), (Dzz @ p[2].reshape(-1)).reshape(mx, my)) <= 1e-12
    Dtt = D[:2 * N, :2 * N]
    ut = (Dtt @ p[:2].reshape(-1)).reshape(2, mx, my)
    assert rel(np.stack(op.apply_tangential(p[0], p[1])), ut) <= 1e-12
    unt = (D[2 * N:, :2 * N] @ p[:2].reshape(-1)).reshape(mx, my)
    assert rel(op.apply_coupling_nt(p[0], p[1]), unt) <= 1e-12
    utn = (D[:2 * N, 2 * N:] @ p[2].reshape(-1)).reshape(2, mx, my)
    assert rel(op.apply_coupling_tn(p[2]), utn) <= 1e-12
    # the single-precision product: float32 transforms, about 1e-7 of the largest value
    u32 = op.tangential_product32()(p[:2].astype(np.float32))
    assert u32.dtype == np.float32 and rel(u32, ut) <= 2e-6


def test_blocked_single_precision_product_equals_unblocked(monkeypatch):
    """Column blocks of the half-spectrum (large grids) give the numbers of the whole spectrum."""
    op = HalfSpaceInfluence.for_grid(13, 17, 0.2, 0.2, Material.steel(), shared=False)
    p = np.random.default_rng(3).normal(size=(2, 13, 17)).astype(np.float32)
    whole = hs.TangentialProduct32(op)(p)
    monkeypatch.setattr(hs, "BLOCK_FROM_BYTES", 0)
    monkeypatch.setattr(hs, "BLOCK_COLUMNS", 4)   # 18 // 2 + 1 = 10 columns: blocks of 4, 4, 2
    blocked = hs.TangentialProduct32(op)
    assert blocked.block == 4
    assert np.array_equal(blocked(p), whole)
    ut = dense_closed_form(13, 17, 0.2, 0.2, Material.steel())[:2 * 221, :2 * 221] @ p.astype(float).reshape(-1)
    assert rel(whole, ut.reshape(2, 13, 17)) <= 2e-6


def test_direct_transforms_are_scipy_fft_bitwise(monkeypatch):
    """The direct pocketfft calls and the scipy.fft fallback give the same bits for every product."""
    if not ffts.DIRECT:   # this scipy's binding failed the import check: the products use scipy.fft
        pytest.skip("scipy's pocketfft binding is not used with this scipy (the fallback is scipy.fft itself)")
    op = HalfSpaceInfluence.for_grid(9, 14, 0.2, 0.1, STEEL_ALU, shared=False)
    rng = np.random.default_rng(7)
    p = rng.normal(size=(3, 9, 14))
    p32 = p[:2].astype(np.float32)
    field = rng.normal(size=(2, 9, 14)).astype(np.float32)

    def products():
        pc = op.normal_preconditioner()
        return [op.apply(p), op.apply_normal(p[2]), *op.apply_tangential(p[0], p[1]), op.apply_coupling_nt(p[0], p[1]),
                op.apply_coupling_tn(p[2]), pc(p[2].copy()), hs.TangentialProduct32(op)(p32),
                ffts.irfft2(ffts.rfft2(field), (9, 14))]

    direct = products()
    monkeypatch.setattr(ffts, "_PF", None)
    fallback = products()
    for a, b in zip(direct, fallback):
        assert a.dtype == b.dtype and np.array_equal(a, b)


def test_integer_input_is_transformed_as_float64():
    x = np.arange(12).reshape(3, 4)
    assert np.array_equal(ffts.rfft(x, 6), sfft.rfft(x.astype(float), 6))
    assert np.array_equal(ffts.rfft2(x), ffts.rfft2(x.astype(float)))


def test_irfft2_refuses_a_spectrum_of_another_shape():
    with pytest.raises(ValueError, match="half-spectrum"):
        ffts.irfft2(np.zeros((4, 3), complex), (4, 6))


@pytest.mark.parametrize("shape", [(55, 33), (100, 11), (7, 40)])
def test_normal_product_in_one_call_is_bitwise_the_four_transforms(shape):
    """apply_normal's one-call product (fft.padded_product) against the general path it replaces:
    the forward transforms, the kernel, the back transforms, each its own call (same numbers)."""
    from conformal.influence.halfspace import Z

    mx, my = shape
    op = HalfSpaceInfluence.for_grid(mx, my, 0.2, 0.2, Material.steel(), shared=False)
    p = np.random.default_rng(mx * my).random(shape)
    uh = op._forward(p)
    uh *= op._kernel_hat(Z, Z)
    assert np.array_equal(op.apply_normal(p), op._back(uh))


def test_doubled_and_imag_negligible_are_the_numpy_forms():
    """ffts.doubled is numpy.repeat(v, 2, axis=-1) (the same array, any dtype and rank); the
    real-spectrum test ffts.imag_negligible decides as max|Im v| <= rtol max|v| does, on spectra
    real to rounding, with a large imaginary part, with the imaginary parts deciding alone, and
    with NaN."""
    rng = np.random.default_rng(5)
    for v in (rng.random((7, 5)).astype(np.float32), rng.random((2, 3, 4)), np.zeros((3, 0))):
        d = ffts.doubled(v)
        assert d.dtype == v.dtype and np.array_equal(d, np.repeat(v, 2, axis=-1))
    re = rng.normal(size=(6, 9))
    cases = [re + 1e-12j * rng.normal(size=re.shape), re + 1j * rng.normal(size=re.shape),
             1e-3 * re + 1j * np.full(re.shape, 1e-12),          # |Re| small: the moduli decide
             np.zeros((2, 2), complex), np.array([1.0 + np.nan * 1j, 2.0])]
    for v in cases:
        for rtol in (1e-9, 1e-6, 1e-2):
            assert ffts.imag_negligible(v, rtol) == bool(np.abs(v.imag).max() <= rtol * np.abs(v).max())
