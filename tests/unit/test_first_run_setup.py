"""One-off set-up of the contact solves, taken once where its parts coincide: checked against the
computation it replaces, bitwise."""
import numpy as np
import pytest

from conformal.grid import PlanarGrid
from conformal.influence import fft as ffts
from conformal.influence.halfspace import HalfSpaceInfluence
from conformal.materials import Material
from conformal.solvers import tangential as tang
from conformal.theories.hertz import hertz_from_semiaxes


def _four_transforms(L, probes):
    """The preconditioner's 2 x 2 inverse symbol from all four probed kernels (the computation
    before the coupling's transform was shared)."""
    (kxx, kyx), (kxy, kyy) = probes
    cx, cy = L.mx // 2, L.my // 2
    a, b, c, d = (ffts.rfft2(tang._centred_at(k, cx, cy)) for k in (kxx, kxy, kyx, kyy))
    det = a * d - b * c
    floor = 1e-8 * np.abs(det).max()
    det = np.where(np.abs(det) < floor, floor, det)
    inv = [v / det for v in (d, -b, -c, a)]
    real = all(ffts.imag_negligible(v, 1e-6) for v in inv)
    return [v.real.astype(np.float32) if real else v.astype(np.complex64) for v in inv]


@pytest.mark.parametrize("steady, n", [(True, 24), (False, 24), (True, 60)])
def test_preconditioner_shares_the_coupling_transform_bitwise(steady, n):
    """The probes of a unit traction in x and in y give A_yx = A_xy bitwise (reciprocity of the
    half-space, the same transforms), so the coupling's transform and inverse entry are taken once:
    the four entries equal those of the four transforms, bitwise; with a coupling perturbed in one
    probe (unequal), each entry from its own probe, again equal to the four transforms."""
    hz = hertz_from_semiaxes(6.0, 4.0, Material.steel(), normal_force=10e3)
    g = PlanarGrid.around_ellipse(hz.a, hz.b, n=n, scale=1.3)
    op = HalfSpaceInfluence.for_grid(g.mx, g.my, g.dx, g.dy, Material.steel(), shared=False)
    X, Y = g.mesh()
    L = tang._SlipOperator(op, g, hz.pressure(X, Y) > 0, steady)
    probes = [L._probe(0), L._probe(1)]
    assert np.array_equal(probes[0][1], probes[1][0])                 # A_yx = A_xy, bitwise
    ref = _four_transforms(L, probes)
    assert all(a.dtype == b.dtype and np.array_equal(a, b) for a, b in zip(L._inv, ref))
    assert L._inv[1] is L._inv[2]
    bent = [(probes[0][0], probes[0][1] * (1.0 + 1e-9)), probes[1]]   # the coupling of one probe moved
    L._probe = lambda k: bent[k]
    L._build_preconditioner()
    ref = _four_transforms(L, bent)
    assert all(a.dtype == b.dtype and np.array_equal(a, b) for a, b in zip(L._inv, ref))
    assert not np.array_equal(L._inv[1], L._inv[2])
