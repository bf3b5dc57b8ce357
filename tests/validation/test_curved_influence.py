"""The x-invariant curved-strip operator: planar limit, reciprocity, FFT product against the dense matrix."""
import numpy as np
import pytest

from conformal.influence.curved import CurvedInfluence, curved_halfspace_kernel
from conformal.influence.halfspace import HalfSpaceInfluence
from conformal.materials import Material
from _paths import SCENES

DISSIMILAR = Material(0.6875, 0.28, 1.833333, 0.28)  # K = 0.1: couplings switched on


def _strip(mx=7, ms=5, dx=0.4, ds=0.3, delta=None, material=DISSIMILAR):
    s = (np.arange(ms) + 0.5) * ds - 1.0
    delta = np.zeros(ms) if delta is None else delta
    return CurvedInfluence.from_kernel(curved_halfspace_kernel(mx, dx, s, np.full(ms, ds), delta, material))


def test_flat_strip_equals_planar_half_space():
    op = _strip()
    hs = HalfSpaceInfluence.for_grid(7, 5, 0.4, 0.3, DISSIMILAR)
    p = np.random.default_rng(0).random((3, 7, 5))
    scale = np.abs(hs.apply(p)).max()
    np.testing.assert_allclose(op.apply(p), hs.apply(p), rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(op.apply_normal(p[2]), hs.apply_normal(p[2]), rtol=0, atol=1e-13 * scale)
    for a, b in zip(op.apply_tangential(p[0], p[1]), hs.apply_tangential(p[0], p[1])):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * scale)


@pytest.mark.parametrize("mx", [1, 2, 6])
def test_curved_strip_is_reciprocal_and_fft_matches_dense(mx):
    op = _strip(mx=mx, delta=np.linspace(0.0, 1.2, 5))  # 0 to 69 degrees across the strip
    D = op.dense()
    assert np.abs(D - D.T).max() < 1e-14 * np.abs(D).max()
    p = np.random.default_rng(mx).random((3, mx, 5))
    np.testing.assert_allclose(op.apply(p).ravel(), D @ p.ravel(), rtol=0, atol=1e-14 * np.abs(D).max())


def test_angle_correction_rotates_normal_load_into_lateral_displacement():
    # two elements at 90 degrees to each other: a normal load on one is a lateral load for the other
    s = np.array([0.0, 5.0])
    K0 = curved_halfspace_kernel(1, 1.0, s, np.ones(2), np.zeros(2), Material.steel(), angle_correction=True)
    K1 = curved_halfspace_kernel(1, 1.0, s, np.ones(2), np.array([0.0, np.pi / 2]), Material.steel())
    # flat: u_n at element 1 due to p_n at element 0 is the Boussinesq number; no u_s from p_n (K = 0)
    assert K0[0, 1, 0, 1, 2] == 0.0 and K0[0, 1, 0, 2, 2] > 0
    # rotated by 45 degrees on each side: u_n and u_s both get a share
    assert abs(K1[0, 1, 0, 1, 2]) > 0.1 * K0[0, 1, 0, 2, 2]


@pytest.mark.parametrize("delta", [np.zeros(5), np.linspace(0.0, 1.2, 5)])
def test_coupling_products_are_the_off_diagonal_blocks(delta):
    """apply_coupling_nt / _tn are the n-t blocks of apply (the Panagiotopoulos loop uses them)."""
    op = _strip(delta=delta)
    p = np.random.default_rng(3).random((3, 7, 5))
    full_n = op.apply(np.stack([p[0], p[1], 0 * p[2]]))[2]
    full_t = op.apply(np.stack([0 * p[0], 0 * p[1], p[2]]))[:2]
    scale = np.abs(op.apply(p)).max()
    assert op.coupled
    np.testing.assert_allclose(op.apply_coupling_nt(p[0], p[1]), full_n, rtol=0, atol=1e-14 * scale)
    np.testing.assert_allclose(op.apply_coupling_tn(p[2]), full_t, rtol=0, atol=1e-14 * scale)
    # quasi-identical bodies on a flat strip: no coupling at all, exactly as the planar operator
    flat = _strip(material=Material.steel())
    assert not flat.coupled and not np.any(flat.apply_coupling_nt(p[0], p[1]))


@pytest.mark.slow
def test_turned_frames_couple_normal_and_tangential_as_the_fe_bodies_do(tmp_path):
    """The sense of the turn between element frames (frames21): on the deep pair (R10 rail corner
    against a R10.2 flange root, contact angles -70 .. -3 degrees over an 8 x 8 grid) the FE numbers
    of the real bodies (identical materials, so the only normal-tangential coupling is geometric)
    have u_n at I due to p_s at J of the sign of R((delta_J - delta_I) / 2) A R((delta_J - delta_I) / 2)
    and the size within 45 % (measured 0.63-1.1 of it at n = 12); the opposite sense
    (the project's numbers before frames21) has the opposite sign, off by 150-200 %.  About 30 s."""

    from conformal.cases.conformal import curved_problem_from_wheel_rail
    from conformal.influence.cache import Cache
    from conformal.influence.fe import FESettings, wheel_rail_kernel
    from conformal.scene import load_scene

    scene = SCENES / "deep_conformal_pair.toml"
    sc = load_scene(scene).with_("grid.n", 8).with_model(theory="conformal", influence="halfspace")
    pr = curved_problem_from_wheel_rail(sc)
    g = pr.grid
    fe, _ = wheel_rail_kernel(g, sc.material, FESettings(), cache=Cache(tmp_path), rail_points=pr.rail_points,
                              wheel_points=pr.wheel_points, workers=1)
    turned = curved_halfspace_kernel(g.mx, g.dx, g.s - g.s_ref, g.ds, g.delta, sc.material)
    k0 = g.mx - 1
    I, J = np.nonzero(np.abs(np.subtract.outer(np.arange(g.ms), np.arange(g.ms))) >= 1)
    keep = np.abs(g.delta[I] - g.delta[J]) > np.radians(5.0)
    I, J = I[keep], J[keep]
    ns, sn = turned[k0, I, J, 2, 1], turned[k0, I, J, 1, 2]     # u_n due to p_s, u_s due to p_n
    assert np.all(np.abs(ns) > 0.05 * np.abs(turned[k0, I, J, 2, 2]))
    r_ns, r_sn = fe[k0, I, J, 2, 1] / ns, fe[k0, I, J, 1, 2] / sn
    # the same sign everywhere (the opposite sense gives ratios of -0.5 .. -2)
    assert r_ns.min() > 0.4 and r_ns.max() < 1.5, (r_ns.min(), r_ns.max())
    assert r_sn.min() > 0.5 and r_sn.max() < 2.0, (r_sn.min(), r_sn.max())
    # the antisymmetric (rotation) part of the pair: the mean ratio within 20 %
    rot = (fe[k0, I, J, 2, 1] - fe[k0, I, J, 1, 2]) / (ns - sn)
    assert abs(rot.mean() - 1.0) < 0.2, rot.mean()
