"""The wheel-rail geometry's shortcuts against the computations they replace.

What is cached (per profile curve and sampling step, per wheel-rail pair, per rail top) or skipped
(the projection's steps after a fixed point, the sort of a grid's lateral coordinates) must give
the same numbers exactly: these tests assert equality, no tolerance.  The coordinate-array Newton
steps of the line intersections and the contact point's vectors in Python floats repeat numpy's
arithmetic; they are checked against numpy's expressions to 1e-13 of the values (equal on the
machines measured; numpy's summation order for einsum may differ on others).
"""
import dataclasses
import math

import numpy as np
import pytest

from conformal.cases import wheelrail as wr
from conformal.geometry import patches as gp
from conformal.geometry import search as gs
from conformal.geometry.search import RailTop, pair_locus, wheel_locus
from _scenes import mbench_scene


@pytest.fixture(scope="module")
def placed():
    """The Manchester pair at 5 mm (tread; the flange near), placed."""
    return wr.place_scene(mbench_scene(5.0, element_size=0.4))


def test_sampled_profile_equals_its_evaluation(placed):
    """The profile derivatives cached per sampling step equal the curve evaluated at the samples
    (and are read-only: a cache must not be changed by its users)."""
    curve = placed.pair.wheel_curve
    s, *der = curve.sampled(0.05)
    s_ref, p = curve.sample(0.05)
    np.testing.assert_array_equal(s, s_ref)
    for got, ref in zip(der, curve.derivatives(s_ref)):
        np.testing.assert_array_equal(got, ref)
    np.testing.assert_array_equal(np.stack(der[:2], axis=-1), p)
    assert curve.sampled(0.05)[1] is der[0]
    with pytest.raises(ValueError):
        der[0][0] = 1.0


def test_piece_index_equals_clipped_searchsorted(placed):
    """The spline piece of an arc length from the inner breaks equals searchsorted on all breaks
    clipped to the pieces, beyond the ends and for NaN included."""
    pieces = placed.pair.rail.curve._pieces
    x = pieces.x
    s = np.r_[np.random.default_rng(0).uniform(-3.0, x[-1] + 3.0, 5000), x, x[-1] + 1e-9, np.nan, -np.inf, np.inf]
    ref = np.minimum(np.maximum(np.searchsorted(x, s, side="right") - 1, 0), x.size - 2)
    np.testing.assert_array_equal(pieces._index(s), ref)


def test_projection_with_fixed_points_equals_eight_steps(placed):
    """Closest-point projection: dropping points whose step no longer moves them gives the eight
    Newton steps of every point exactly (points 0-3 mm off the rail profile, starts up to 3 mm away)."""
    curve = placed.pair.rail.curve

    def eight_steps(q, s):
        for _ in range(8):
            y, z, y1, z1, y2, z2 = curve.derivatives(s)
            dy, dz = y - q[..., 0], z - q[..., 1]
            g = dy * y1 + dz * z1
            H = y1 * y1 + z1 * z1 + dy * y2 + dz * z2
            step = np.where(H > 0.1, g / np.where(H > 0.1, H, 1.0), g)
            s = np.clip(s - np.clip(step, -2.0, 2.0), 0.0, curve.length)
        return s

    rng = np.random.default_rng(1)
    s_true = rng.uniform(0.0, curve.length, 3000)
    q = curve.point(s_true) + curve.normal(s_true) * rng.uniform(-3.0, 3.0, (3000, 1))
    s0 = np.clip(s_true + rng.uniform(-3.0, 3.0, 3000), 0.0, curve.length)
    np.testing.assert_array_equal(curve.project(q, s0), eight_steps(q, s0.copy()))
    np.testing.assert_array_equal(curve.project(q[:6].reshape(2, 3, 2), s0[:6].reshape(2, 3)),
                                  eight_steps(q[:6], s0[:6].copy()).reshape(2, 3))


def test_pair_locus_carries_what_the_wheel_at_that_height_gives(placed):
    """The locus of a pair moved to a height carries the radial directions and radii of the wheel at
    that height and the rail top under its points, exactly; a new rail top is not mixed up with the
    cached one."""
    pair, top = placed.pair, placed.top
    z = placed.z_touch + 0.037
    loc = pair_locus(pair, top, z)
    wheel = pair.wheel(z)
    np.testing.assert_array_equal(loc.e_r, wheel.e_r(np.nan_to_num(loc.theta)))
    np.testing.assert_array_equal(loc.rho, wheel.rolling_radius(loc.s))
    gap = np.where(np.isnan(loc.theta), np.nan, top.z_at(loc.points[:, 1]) - loc.points[:, 2])
    np.testing.assert_array_equal(loc.gap, gap)
    other = RailTop.build(pair.rail, 0.04)
    np.testing.assert_array_equal(pair_locus(pair, other, z).gap,
                                  np.where(np.isnan(loc.theta), np.nan, other.z_at(loc.points[:, 1]) - loc.points[:, 2]))
    # sampled at that height: the same locus to rounding
    ref = wheel_locus(wheel, top)
    np.testing.assert_allclose(loc.points, ref.points, rtol=0, atol=1e-9)


def test_penetration_from_the_cached_radial_directions(placed):
    """The locus overlap with the pair's cached radial directions and radii equals the one that
    computes them from the wheel (s_r, overlap, curvature A, rail points and normals)."""
    pair, top = placed.pair, placed.top
    z = placed.z_touch + 0.05
    wheel = pair.wheel(z)
    loc = pair_locus(pair, top, z)
    a = gp._locus_penetration(wheel, pair.rail, top, loc)
    b = gp._locus_penetration(wheel, pair.rail, top, dataclasses.replace(loc, e_r=None, rho=None))
    for u, v in zip(a[1:], b[1:]):
        np.testing.assert_array_equal(u, v)
    # the rail points and normals handed to the patches are the rail's at s_r
    s_r, yzn = a[1], a[4]
    ok = np.isfinite(s_r)
    np.testing.assert_array_equal(yzn[:2, ok].T, pair.rail.point(s_r[ok]))
    np.testing.assert_array_equal(yzn[2:, ok].T, pair.rail.normal(s_r[ok]))


def test_grid_lateral_coordinates_unique_without_sorting():
    """A grid's lateral coordinates made unique by rows equal numpy.unique (values and inverse);
    other arrays go to numpy.unique."""
    xg, yg = np.meshgrid(np.linspace(-3.0, 3.0, 11), np.linspace(-2.0, 2.0, 7) + 1e-3, indexing="ij")
    for v in (yg, xg, np.array([[0.0, 1.0], [0.0, 1.5]]), np.array([[-0.0, 1.0], [0.0, 1.0]]), np.zeros((0, 4))):
        got, ref = gp._unique(v), np.unique(v.ravel(), return_inverse=True)
        for u, w in zip(got, ref):
            np.testing.assert_array_equal(u, w)
            assert u.dtype == w.dtype


def _wheel_on_lines_numpy(wheel, Q, n, s0, th0, maxit=30, tol=1e-10):
    """The (N, 3)-array Newton steps with numpy.cross and numpy.einsum (the former implementation)."""
    N = Q.shape[0]
    n = np.broadcast_to(np.asarray(n, float), (N, 3))
    s, th, t = np.array(s0, float), np.array(th0, float), np.zeros(N)
    f, L = wheel.frame, wheel.curve.length
    for _ in range(maxit):
        u, rho, u1, rho1, _, _ = wheel.meridian(s)
        er, et = wheel.e_r(th), wheel.e_t(th)
        F = f.O + u[:, None] * f.a + rho[:, None] * er - Q - t[:, None] * n
        c0, c1, c2 = u1[:, None] * f.a + rho1[:, None] * er, rho[:, None] * et, -n
        k12, k20, k01 = np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)
        det = np.einsum("ij,ij->i", c0, k12)
        d = np.stack([np.einsum("ij,ij->i", -F, k) for k in (k12, k20, k01)], axis=1) / det[:, None]
        s = np.clip(s + np.clip(d[:, 0], -2.0, 2.0), 0.0, L)
        th = th + np.clip(d[:, 1], -0.05, 0.05)
        t = t + d[:, 2]
        if np.max(np.abs(F)) < tol:
            break
    return s, th, t


def test_line_intersections_equal_the_numpy_steps(placed):
    """The wheel's line intersections on coordinate arrays (one direction, a direction per line)
    and for one line in floats equal the (N, 3)-array steps with numpy.cross / einsum to 1e-13 mm
    (equal on the machines measured)."""
    wheel = placed.pair.wheel(placed.z_touch + 0.05)
    patch = gp.find_patches(wheel, placed.pair.rail, placed.top)[0]
    X, Y = np.meshgrid(np.linspace(-5.0, 5.0, 21), np.linspace(-3.0, 3.0, 13), indexing="ij")
    Q = patch.point + X.reshape(-1, 1) * np.array([1.0, 0.0, 0.0]) + Y.reshape(-1, 1) * patch.t2
    s0, th0 = gp._wheel_start(wheel, patch, Q)
    tilt = patch.normal + 0.05 * np.random.default_rng(5).normal(size=Q.shape)
    for n in (patch.normal, tilt / np.linalg.norm(tilt, axis=1, keepdims=True)):
        got = gp.wheel_on_lines(wheel, Q, n, s0, th0)
        ref = _wheel_on_lines_numpy(wheel, Q, n, s0, th0)
        for u, v, scale in zip(got, ref, (wheel.curve.length, math.pi, 1.0)):
            np.testing.assert_allclose(u, v, rtol=0, atol=1e-13 * scale)
    one = gp.wheel_on_lines(wheel, Q[7:8], patch.normal, s0[7:8], th0[7:8])      # floats
    ref = _wheel_on_lines_numpy(wheel, Q[7:8], patch.normal, s0[7:8], th0[7:8])
    for u, v, scale in zip(one, ref, (wheel.curve.length, math.pi, 1.0)):
        assert u.shape == (1,)
        np.testing.assert_allclose(u, v, rtol=0, atol=1e-13 * scale)


def test_contact_point_vectors_in_floats_equal_numpy(placed):
    """The converged contact point's residual and vectors in Python floats equal the numpy
    expressions of the Newton system (seed Eqs. 54-55) to 1e-13 of their size."""
    wheel = placed.pair.wheel(placed.z_touch + 0.03)
    c = gs.find_contacts(wheel, placed.pair.rail, placed.top).contacts[0]
    for dq in ((0.0, 0.0, 0.0, 0.0), (0.3, 0.01, 0.5, -0.2)):
        q = np.array([c.s_w, c.theta, c.x, c.s_r]) + dq
        F, _, v = gs._residual_and_jacobian(wheel, placed.pair.rail, q)
        F2, v2 = gs._contact_values(wheel, placed.pair.rail, q)
        np.testing.assert_allclose(F2, F, rtol=0, atol=1e-13 * max(1.0, np.abs(F).max()))
        assert v2.keys() == v.keys()
        for k in v:
            np.testing.assert_allclose(v2[k], v[k], rtol=1e-13, atol=1e-13)
    np.testing.assert_array_equal(gs._cross_x(c.normal), np.cross(c.normal, [1.0, 0.0, 0.0]))
    # the curvatures, computed when first asked for, from the numpy vectors at the converged point
    _, _, v = gs._residual_and_jacobian(wheel, placed.pair.rail, np.array([c.s_w, c.theta, c.x, c.s_r]))
    K, kr, kw = gs._curvatures(wheel, placed.pair.rail, v)
    np.testing.assert_allclose(c.curvature, K, rtol=1e-12, atol=1e-15)
    assert c.kappa_rail == pytest.approx(kr, rel=1e-12) and c.kappa_wheel == pytest.approx(kw, rel=1e-12)
    assert c.curvature is c.curvature


def test_rail_profile_floats_equal_arrays(placed):
    """The placed rail profile at one arc length (Python floats) equals the array evaluation."""
    rail = placed.pair.rail
    s = np.linspace(0.0, rail.curve.length, 37)
    arrays = rail.profile(s)
    for i in (0, 11, 36):
        one = rail.profile(float(s[i]))
        assert all(isinstance(v, float) for v in one)
        assert one == tuple(float(a[i]) for a in arrays)


def test_both_coordinates_in_one_smoothing_solve():
    """fit_curve smooths y and z of a profile in one solve: the same spline as one solve per
    coordinate (coefficients to 1e-12 mm; equal on the machines measured), smoothing and not."""
    from scipy.interpolate import make_interp_spline, make_smoothing_spline

    from conformal.geometry.profiles import load_profile
    from conformal.geometry.spline import _chord_parameter

    p = load_profile("S1002", "wheel", ".").points
    t = _chord_parameter(p)
    lam = t[-1] / (len(t) - 1) * (5.0 / (2 * math.pi)) ** 4
    for both, one in ((make_smoothing_spline(t, p, lam=lam), lambda y: make_smoothing_spline(t, y, lam=lam)),
                      (make_interp_spline(t, p, k=3), lambda y: make_interp_spline(t, y, k=3))):
        for k in range(2):
            np.testing.assert_allclose(both.c[:, k], one(p[:, k]).c, rtol=0, atol=1e-12)


def test_pair_frame_equals_the_pose_at_that_height(placed):
    """The pair's wheelset frame with its axes computed once equals the frame of the pose at each
    height, and the shared axes are read-only."""
    from conformal.geometry.surfaces import WheelFrame

    pair = placed.pair
    for z in (0.0, placed.z_touch, placed.z_touch + 0.123):
        got = pair.frame(z)
        ref = WheelFrame.from_pose(pair.pose.y, z, pair.pose.roll, pair.pose.yaw, pair.radius)
        for k in ("O", "a", "e_d", "e_f"):
            np.testing.assert_array_equal(getattr(got, k), getattr(ref, k))
    with pytest.raises(ValueError):
        pair.frame(0.0).a[0] = 1.0


def test_roll_search_places_each_roll_once(monkeypatch):
    """The wheelset roll's root search builds each trial roll's pairs once (the bracket's rolls are
    not searched again by Brent's method or for the height at the root)."""
    from conformal.geometry import wheelrail as gw

    sc = mbench_scene(3.0, element_size=0.4, roll=None)
    built = []
    build = gw.build_pair

    def counting(geo, base_dir=".", **kw):
        built.append((kw.get("side"), float(kw.get("roll"))))
        return build(geo, base_dir, **kw)

    monkeypatch.setattr(gw, "build_pair", counting)
    roll, z = gw.wheelset_roll(sc.geometry, sc.base_dir)
    assert len(built) == len(set(built)) > 6
    assert ("right", roll) in built and abs(roll) < 0.01
