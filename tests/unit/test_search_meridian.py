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
