"""The geometry shortcuts of the sequence's contact searches against the paths they replace,
bitwise (the same floating-point operations in the same order): the spline's values and slopes in
one array pass, the grid's wheel-line Newton steps in work rows, the projections of the locus
samples near the overlap, the locus angles only where a sample can lie over the rail, the angle
wrap, the contact Newton's 4 x 4 solve, and the lift check's pair with the locus of its neighbour.
"""
import dataclasses
import json
import math

import numpy as np
import pytest

from conformal.cases import wheelrail as wr
from conformal.geometry import patches as gp
from conformal.geometry import search as gs
from conformal.geometry import surfaces as gsu
from conformal.geometry.placement import WheelRailPair
from conformal.geometry.spline import clip
from _paths import CONTACT_CASES
from _scenes import mbench_case_scene

CASES = json.loads(CONTACT_CASES.read_text())["cases"]["mbench_a22"]["right"]


def mbench_case(y, element_size=0.2):
    return mbench_case_scene(next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == y),
                             element_size=element_size)


@pytest.fixture(scope="module", params=[0.0, 5.0, 7.0])
def placed(request):
    return wr.place_scene(mbench_case(request.param))


def _same(a, b):
    """Bitwise equality of floats and arrays (NaN equal to NaN, signed zeros told apart)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def test_spline_stack_equals_the_expressions_per_coordinate(placed):
    """y, z and their first two derivatives from one (2, N) pass are the numbers of the
    expressions evaluated per coordinate (the Taylor form at the left break), and equal the
    scalar path at single points."""
    for curve in (placed.pair.wheel_curve, placed.pair.rail.curve):
        pc = curve._pieces
        s = np.r_[np.linspace(-0.5, curve.length + 0.5, 3001), pc.x[5], pc.x[-3]]
        i = pc._index(s)
        t = s - pc.x.take(i)
        a0y, a0z, a1y, a1z, a2y, a2z, a3y, a3z = pc.rows.take(i, axis=1)
        ref = []
        for a0, a1, a2, a3 in ((a0y, a1y, a2y, a3y), (a0z, a1z, a2z, a3z)):
            ref.append((((a3 * t + a2) * t + a1) * t + a0, (3.0 * a3 * t + 2.0 * a2) * t + a1,
                        6.0 * a3 * t + 2.0 * a2))
        (y, y1, y2), (z, z1, z2) = ref
        got = curve.derivatives(s)
        assert all(_same(g, r) for g, r in zip(got, (y, z, y1, z1, y2, z2)))
        first = curve.stack(s, 1)
        assert first.shape == (2, 2, s.size) and _same(first, curve.stack(s)[:2])
        for k in (0, 1500, 3002):
            assert _same(curve.derivatives(float(s[k])), [v[k] for v in got])
    rail = placed.pair.rail
    s = np.linspace(0.0, rail.curve.length, 777)
    assert all(_same(a, b) for a, b in zip(rail.profile_slopes(s), rail.profile(s)[:4]))


def test_grid_wheel_lines_equal_the_per_coordinate_steps(placed):
    """The grid's wheel-line intersections (Newton steps written into work rows) are the numbers
    of the steps of the float path applied per coordinate array (numpy's cos, sin)."""
    z = placed.z_touch + 0.05
    wheel = placed.pair.wheel(z)
    patch = gp.find_patches(wheel, placed.pair.rail, placed.top)[0]
    X, Y = np.meshgrid(np.linspace(-6.0, 6.0, 31), np.linspace(-5.0, 5.0, 23), indexing="ij")
    Q = patch.point + X.reshape(-1, 1) * np.array([1.0, 0.0, 0.0]) + Y.reshape(-1, 1) * patch.t2
    s0, th0 = gp._wheel_start(wheel, patch, Q)
    n0, n1, n2 = (float(c) for c in patch.normal)
    s, th, t = s0.copy(), th0.copy(), np.zeros(len(Q))
    q = tuple(np.ascontiguousarray(c) for c in Q.T)
    steps = 0
    for _ in range(30):
        F, (ds, dth, dt) = gp._wheel_line_step(wheel.meridian(s), th, t, np.cos, np.sin, wheel.frame_floats, q,
                                               (n0, n1, n2), (-n0, -n1, -n2))
        s = clip(s + clip(ds, -2.0, 2.0), 0.0, wheel.curve.length)
        th += clip(dth, -0.05, 0.05)
        t += dt
        steps += 1
        if np.max([np.max(np.abs(Fk)) for Fk in F]) < 1e-10:
            break
    assert 2 <= steps < 30
    got = gp.wheel_on_lines(wheel, Q, patch.normal, s0, th0)
    assert all(_same(g, r) for g, r in zip(got, (s, th, t)))


def test_overlap_samples_give_the_patches_of_all_samples(placed, monkeypatch):
    """Projecting the locus samples near the overlap first (OVERLAP_GAP and their neighbours)
    gives the patches of projecting all NEAR_GAP samples, bitwise, on the tread, the two-lobe
    patch at 5 mm and the flange, at the touching height and 0.02 and 0.2 mm below it; a wheel
    above the rail still finds no contact."""
    fields = ("s_ref", "x_ref", "point", "normal", "t2", "wheel_point", "wheel_s", "wheel_theta", "penetration",
              "s_range", "x_range", "eta_range", "n_lobes", "s_ref_rate")
    pair, top = placed.pair, placed.top
    for dz in (0.001, 0.02, 0.2):
        z = placed.z_touch + dz
        loc = gs.pair_locus(pair, top, z)
        near = gp.find_patches(pair.wheel(z), pair.rail, top, locus=loc)
        with monkeypatch.context() as m:
            m.setattr(gp, "OVERLAP_GAP", math.inf)
            every = gp.find_patches(pair.wheel(z), pair.rail, top, locus=loc)
        assert len(near) == len(every) >= 1
        for p, r in zip(near, every):
            assert all(_same(getattr(p, f), getattr(r, f)) for f in fields)
            assert _same(p.deepest.penetration, r.deepest.penetration)
    with pytest.raises(gs.NoContactError):
        gp.find_patches(pair.wheel(placed.z_touch - 0.3), pair.rail, top)


def test_locus_angles_only_where_the_rail_can_be(placed):
    """The pair's locus has the angles of the wheel's locus_theta wherever its gap to the rail
    is finite, NaN angles only where the gap is NaN anyway, and the locus found by the contact
    search from all samples (the wheel's own, theta everywhere) has the same gaps."""
    pair, top = placed.pair, placed.top
    z = placed.z_touch + 0.03
    loc = gs.pair_locus(pair, top, z)
    wheel = pair.wheel(z)
    full = wheel.locus_theta(loc.s)
    ok = np.isfinite(loc.gap)
    assert ok.sum() > 500
    assert _same(loc.theta[ok], full[ok])
    assert np.all(np.isnan(loc.gap[np.isnan(loc.theta)]))
    # all samples (as before the reach test): the same gaps, bitwise
    pts = wheel.point(loc.s, np.nan_to_num(full))
    gap_all = np.where(np.isnan(full), np.nan, top.z_at(pts[:, 1]) - pts[:, 2])
    moved = pair.locus_samples(z, gs.LOCUS_STEP)[2]      # the pair's way: moved from z = 0
    gap_pair = np.where(np.isnan(loc.theta), np.nan, top.z_at(moved[:, 1]) - moved[:, 2])
    assert _same(loc.gap, gap_pair)
    np.testing.assert_allclose(loc.gap, gap_all, rtol=0, atol=1e-9)
    assert np.array_equal(np.isnan(loc.gap), np.isnan(gap_all))
    # the samples left out cannot reach the rail's lateral range
    out = ~pair._locus_at_zero(gs.LOCUS_STEP, (top.y_min, top.y_max))[5]
    assert out.any() and np.all((pts[out, 1] < top.y_min - 0.5) | (pts[out, 1] > top.y_max + 0.5))


def test_angle_wrap_equals_the_remainder():
    x = np.random.default_rng(7).uniform(-9.0, 9.0, 20001)
    x[:6] = [-math.pi, math.pi, 0.0, -0.0, np.nan, 3 * math.pi]
    assert _same(gsu._wrap(x), (x + np.pi) % (2 * np.pi) - np.pi)
    assert _same(gsu._wrap(np.float64(4.0)), (4.0 + np.pi) % (2 * np.pi) - np.pi)


def test_contact_newton_solve_equals_numpy_solve():
    """numpy.linalg.solve's gufunc under its error state: the same numbers, and a singular
    Jacobian raises LinAlgError."""
    rng = np.random.default_rng(11)
    with np.errstate(**gs._SOLVE_ERRSTATE):
        for _ in range(200):
            J, F = rng.normal(size=(4, 4)), rng.normal(size=4)
            assert _same(gs._solve1(J, F), np.linalg.solve(J, F))
        with pytest.raises(np.linalg.LinAlgError):
            gs._solve1(np.ones((4, 4)), F)


def test_lift_check_pair_takes_the_neighbours_locus(placed):
    """A pair at another lateral shift with the same orientation takes the placed pair's locus
    angles and radial directions: its locus equals the one it computes itself; a pair of another
    roll takes nothing."""
    pair, top = placed.pair, placed.top
    span = (top.y_min, top.y_max)
    gs.pair_locus(pair, top, placed.z_touch)
    pose = dataclasses.replace(pair.pose, y=pair.pose.y - 0.1)
    own = WheelRailPair(pair.wheel_curve, pair.rail, pair.radius, pair.offset, pose, pair.side)
    shared = WheelRailPair(pair.wheel_curve, pair.rail, pair.radius, pair.offset, pose, pair.side)
    shared.share_locus(pair)
    assert any(k[0] == "shared" for k in shared._loci)
    a, b = own._locus_at_zero(gs.LOCUS_STEP, span), shared._locus_at_zero(gs.LOCUS_STEP, span)
    assert all(_same(u, v) for u, v in zip(a, b))
    rolled = WheelRailPair(pair.wheel_curve, pair.rail, pair.radius, pair.offset,
                           dataclasses.replace(pose, roll=pose.roll + 1e-4), pair.side)
    rolled.share_locus(pair)
    assert not rolled._loci


def test_curvature_gufuncs_equal_numpy_linalg():
    """The principal curvatures' eigh and lstsq by numpy's gufuncs: numpy.linalg's numbers."""
    rng = np.random.default_rng(13)
    for _ in range(100):
        K = rng.normal(size=(2, 2))
        K = K + K.T
        w, v = gs._eigh(K)
        ref = np.linalg.eigh(K)
        assert _same(w, ref.eigenvalues) and _same(v, ref.eigenvectors)
        a, b = rng.normal(size=(3, 2)), rng.normal(size=(3, 2))
        assert _same(gs._lstsq(a, b), np.linalg.lstsq(a, b, rcond=None)[0])


def test_piece_index_equals_the_binary_search(placed):
    """The piece index from the uniform break spacing equals numpy's binary search (the count of
    inner breaks <= s) at random points, every break, its neighbouring floats, the ends, beyond
    them, NaN and infinities."""
    rng = np.random.default_rng(17)
    for curve in (placed.pair.wheel_curve, placed.pair.rail.curve):
        pc = curve._pieces
        assert pc._uniform is not None
        inner = pc._inner
        s = np.r_[rng.uniform(-2.0, curve.length + 2.0, 20000), pc.x, np.nextafter(inner, -np.inf),
                  np.nextafter(inner, np.inf), np.nan, np.inf, -np.inf, 0.0, -0.0, curve.length]
        assert np.array_equal(pc._index(s), np.searchsorted(inner, s, side="right"))
        assert np.array_equal(pc._index(s[:3000].reshape(30, 100)), np.searchsorted(inner, s[:3000].reshape(30, 100),
                                                                                      side="right"))


def test_surface_vectors_equal_the_broadcast_expressions(placed):
    """Radial and circumferential directions and surface points one coordinate at a time: the
    numbers of the broadcast expressions, for scalars and arrays."""
    wheel = placed.pair.wheel(placed.z_touch)
    f = wheel.frame
    rng = np.random.default_rng(19)
    for th in (0.3, np.float64(-0.2), rng.normal(size=7), rng.normal(size=(4, 5))):
        t = np.asarray(th)[..., None]
        er = np.cos(t) * f.e_d + np.sin(t) * f.e_f
        assert _same(wheel.e_r(th), er)
        assert _same(wheel.e_t(th), -np.sin(t) * f.e_d + np.cos(t) * f.e_f)
        u = rng.normal(size=np.shape(th)) if np.ndim(th) else 2.5
        rho = 460.0 + rng.normal(size=np.shape(th)) if np.ndim(th) else 455.0
        assert _same(wheel.point_of(u, rho, th), f.O + np.asarray(u)[..., None] * f.a + np.asarray(rho)[..., None] * er)
    s, th, pts = placed.pair.locus_samples(0.37, gs.LOCUS_STEP)
    assert _same(pts, placed.pair.locus_samples(0.0, gs.LOCUS_STEP)[2] + np.array([0.0, 0.0, 0.37]))
