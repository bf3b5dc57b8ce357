"""The planar grid's wheel distances in two unknowns (the line's axial position and radius against
the wheel's meridian) against the three-unknown Newton-Raphson they replace (wheel_on_lines: the
same root to rounding, within 1e-12 mm), and the spline cursor's values against ProfileCurve.stack
(bitwise: the same pieces and expressions)."""
import json

import numpy as np
import pytest

from conformal.cases import wheelrail as wr
from conformal.geometry import patches as gp
from conformal.geometry.spline import fit_curve
from _paths import CONTACT_CASES
from _scenes import mbench_case_scene

CASES = json.loads(CONTACT_CASES.read_text())["cases"]["mbench_a22"]["right"]


@pytest.fixture(scope="module", params=[0.0, 5.0, 7.0])
def placed(request):
    inputs = next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == request.param)
    return wr.place_scene(mbench_case_scene(inputs, element_size=0.2))


def test_cursor_equals_stack_as_the_points_move():
    """The cursor's values and slopes are ProfileCurve.stack(s, 1)'s, bitwise, for points that
    move by less and by more than a piece (0.025 mm), beyond the profile's ends and NaN."""
    t = np.linspace(-1.0, 1.0, 401)
    curve = fit_curve(np.c_[300 * np.sin(t / 3), 300 * (1 - np.cos(t / 3))], name="arc")
    cur = curve._pieces.cursor()
    rng = np.random.default_rng(3)
    s = rng.uniform(-1.0, curve.length + 1.0, 2500)
    for k in range(7):
        got = cur.stack1(s)
        assert got.tobytes() == curve.stack(s, 1).tobytes()
        s = s + rng.normal(0.0, 0.1 * 10.0 ** -k, s.size)
    s[[3, 10]] = np.nan
    assert np.array_equal(cur.stack1(s), curve.stack(s, 1), equal_nan=True)
    few = s[:40].copy()                     # another size: looked up afresh
    assert np.array_equal(cur.stack1(few), curve.stack(few, 1), equal_nan=True)


def test_grid_lines_meet_the_wheel_where_the_three_unknown_newton_does(placed):
    """On a grid wider than the patch (12 x 10 mm) on the tread, the two-lobe patch at 5 mm and the
    flange, the distances of the two-unknown solve lie within 1e-12 mm of wheel_on_lines' (Newton
    on r_w(s, theta) - q - t n from the same linear start), and its points are on the wheel: the
    surface point of wheel_on_lines' parameters (s, theta)."""
    z = placed.z_touch + 0.05
    wheel = placed.pair.wheel(z)
    patch = gp.find_patches(wheel, placed.pair.rail, placed.top)[0]
    X, Y = np.meshgrid(np.linspace(-6.0, 6.0, 41), np.linspace(-5.0, 5.0, 37), indexing="ij")
    Q = patch.point + X.reshape(-1, 1) * np.array([1.0, 0.0, 0.0]) + Y.reshape(-1, 1) * patch.t2
    s0, th0 = gp._wheel_start(wheel, patch, Q)
    s_w, th, t_ref = gp.wheel_on_lines(wheel, Q, patch.normal, s0, th0)
    t = gp._wheel_on_grid_lines(wheel, patch, np.ascontiguousarray(Q.T), patch.normal)
    assert np.max(np.abs(t - t_ref)) < 1e-12
    on_wheel = wheel.point(s_w, th)
    np.testing.assert_allclose(Q + t[:, None] * patch.normal, on_wheel, rtol=0, atol=1e-9)
    # planar_distance: the rail's distance minus these
    d = gp.planar_distance(wheel, placed.pair.rail, patch, X, Y)
    _, t_r = gp.rail_on_lines(placed.pair.rail, patch.point[1:] + Y[0][:, None] * patch.t2[1:], patch.normal[1:],
                              patch.s_ref + Y[0])
    assert np.max(np.abs(d - (t_r[None, :] - t_ref.reshape(X.shape)))) < 1e-12


def test_grid_lines_that_miss_the_wheel_are_refused(placed):
    """Lines beyond the wheel profile do not converge: ConvergenceError, as wheel_on_lines."""
    z = placed.z_touch + 0.05
    wheel = placed.pair.wheel(z)
    patch = gp.find_patches(wheel, placed.pair.rail, placed.top)[0]
    q = np.ascontiguousarray((patch.point + np.array([[0.0, 0.0, 0.0], [0.0, 400.0, 0.0]])).T)
    with pytest.raises(gp.ConvergenceError):
        gp._wheel_on_grid_lines(wheel, patch, q, patch.normal)


def _rail_on_lines_reference(rail, Q, n, s0, maxit=30, tol=1e-10):
    """rail_on_lines as it was written with ProfileSurface.profile_slopes (the reference)."""
    n0, n1 = float(n[0]), float(n[1])
    q0, q1 = Q[:, 0].copy(), Q[:, 1].copy()
    s, t = np.array(s0, float).copy(), np.zeros(len(Q))
    for _ in range(maxit):
        Y, Z, Y1, Z1 = rail.profile_slopes(s)
        F0, F1 = (Y - q0) - t * n0, (Z - q1) - t * n1
        mF0, mF1 = -F0, -F1
        det = Y1 * -n1 - -n0 * Z1
        ds = (mF0 * -n1 + n0 * mF1) / det
        dt = (Y1 * mF1 - Z1 * mF0) / det
        s = np.clip(s + np.clip(ds, -2.0, 2.0), 0.0, rail.curve.length)
        t += dt
        if np.max([np.max(np.abs(F0)), np.max(np.abs(F1))]) < tol:
            break
    return s, t


def test_grid_distance_and_rail_lines_equal_their_references(placed):
    """The grid's distances (columns and broadcast points) are planar_distance's on the grid's mesh,
    bitwise, and the rail lines (spline cursor) those of the profile_slopes iteration."""
    z = placed.z_touch + 0.05
    wheel, rail = placed.pair.wheel(z), placed.pair.rail
    patch = gp.find_patches(wheel, rail, placed.top)[0]
    grid, h, approach = gp.planar_grid_for_patch(wheel, rail, patch, element_size=0.2)
    X, Y = grid.mesh()
    d = gp.planar_distance(wheel, rail, patch, X, Y)
    assert (d + approach).tobytes() == h.tobytes()
    eta = grid.y
    Q = patch.point[1:][None, :] + eta[:, None] * patch.t2[1:][None, :]
    got = gp.rail_on_lines(rail, Q, patch.normal[1:], patch.s_ref + eta)
    ref = _rail_on_lines_reference(rail, Q, patch.normal[1:], patch.s_ref + eta)
    assert all(g.tobytes() == r.tobytes() for g, r in zip(got, ref))


def test_runs_equal_the_padded_difference():
    """The runs of True are those of the padded integer difference they replace."""
    rng = np.random.default_rng(5)
    for size in (0, 1, 2, 7, 300):
        for _ in range(50):
            mask = rng.random(size) < 0.6
            m = np.r_[False, mask, False].astype(int)
            d = np.diff(m)
            ref = list(zip(np.nonzero(d == 1)[0].tolist(), (np.nonzero(d == -1)[0] - 1).tolist()))
            assert gp._runs(mask) == ref


def test_nearest_sample_equals_the_tree_query(placed):
    """The windowed nearest rail sample is the k-d tree's, for the locus points the patch search
    projects, points deep below and far above the rail (the tree's fallback) and off its ends."""
    from conformal.geometry.search import pair_locus
    top = placed.top
    loc = pair_locus(placed.pair, top, placed.z_touch + 0.1)
    ok = np.isfinite(loc.gap) & (loc.gap < 0.1)
    pts = loc.points[ok][:, 1:]
    rng = np.random.default_rng(2)
    y = rng.uniform(top.y_min - 5.0, top.y_max + 5.0, 400)
    z = top.z_at(np.clip(y, top.y_min, top.y_max)) + rng.uniform(-3.0, 3.0, y.size)
    far = np.c_[y, z][np.isfinite(z)]
    for yz in (pts, far, pts + [0.0, 1.5]):
        assert len(yz) >= 8
        assert np.array_equal(top.s_near(yz), top.s_samples[top.tree.query(yz)[1]])


def _project_reference(curve, q, s0):
    """ProfileCurve.project as written before the two-cycle exit (eight steps or a fixed point)."""
    from conformal.geometry.spline import clip
    s = np.array(s0, dtype=float, copy=True).reshape(-1)
    qy, qz = q[:, 0].copy(), q[:, 1].copy()
    act, sa = None, s
    for _ in range(8):
        y, z, y1, z1, y2, z2 = curve.derivatives(sa)
        dy, dz = y - qy, z - qz
        g = dy * y1 + dz * z1
        H = y1 * y1 + z1 * z1 + dy * y2 + dz * z2
        curved = H > 0.1
        step = np.where(curved, g / np.where(curved, H, 1.0), g)
        s_new = clip(sa - clip(step, -2.0, 2.0), 0.0, curve.length)
        moved = s_new != sa
        if act is None:
            s = s_new
        else:
            s[act] = s_new
        if not moved.all():
            act = np.nonzero(moved)[0] if act is None else act[moved]
            if act.size == 0:
                break
            sa, qy, qz = s_new[moved], qy[moved], qz[moved]
        else:
            sa = s_new
    return s


def test_projection_equals_the_eight_step_iteration(placed):
    """The closest-point projection with its early exits (fixed points, cycles of two) gives the
    arc lengths of the plain iteration, bitwise, for points near and far from the rail profile,
    started at and away from their nearest samples."""
    rail = placed.pair.rail
    curve = rail.curve
    rng = np.random.default_rng(11)
    s_true = rng.uniform(0.0, curve.length, 4000)
    pts = curve.point(s_true) + curve.normal(s_true) * rng.normal(0.0, 0.3, (s_true.size, 1))
    for s0 in (s_true + rng.normal(0.0, 0.01, s_true.size), s_true + rng.normal(0.0, 0.5, s_true.size),
               np.clip(s_true + 3.0, 0.0, curve.length)):
        got = curve.project(pts, s0)
        ref = _project_reference(curve, pts, s0)
        assert got.tobytes() == ref.tobytes()
