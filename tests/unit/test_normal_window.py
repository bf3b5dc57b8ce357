"""The force-prescribed normal problem solved on a window around the contact
(conformal.solvers.normal: WINDOW_MARGIN, _window) against the same problem solved on the whole
grid (WINDOW_MARGIN = -1) and against Hertz: a cold start, a warm start from a neighbouring
solution, and a start whose contact leaves the window (the whole-grid fallback)."""
import numpy as np
import pytest

from conformal.grid import PlanarGrid
from conformal.materials import Material
from conformal.solvers import normal
from conformal.solvers.normal import solve_normal
from conformal.theories.hertz import hertz_from_semiaxes

STEEL = Material.steel()
TOL = 1e-9


def _hertz(n: int = 41, scale: float = 2.0, FN: float = 1e5):
    """A Hertz circle of radius 5 mm on an n x n grid of side 2 scale a: the contact covers about a
    fifth of the grid (an element centre at the origin for odd n)."""
    hz = hertz_from_semiaxes(5.0, 5.0, STEEL, normal_force=FN)
    g = PlanarGrid.around_ellipse(5.0, 5.0, n=n, scale=scale)
    X, Y = g.mesh()
    return hz, g, hz.A * X**2 + hz.B * Y**2


def _spy(monkeypatch):
    """Record the windows chosen and the grids the force-prescribed iterations run on."""
    seen = {"windows": [], "force": []}
    window, force = normal._window, normal._force

    def spy_window(op, p0):
        r = window(op, p0)
        seen["windows"].append(None if r is None else (r[1].mx, r[1].my))
        return r

    def spy_force(op, *args, **kwargs):
        seen["force"].append((op.mx, op.my))
        return force(op, *args, **kwargs)

    monkeypatch.setattr(normal, "_window", spy_window)
    monkeypatch.setattr(normal, "_force", spy_force)
    return seen


def _whole_grid(monkeypatch, *args, **kwargs):
    with monkeypatch.context() as m:
        m.setattr(normal, "WINDOW_MARGIN", -1)
        return solve_normal(*args, **kwargs)


def _assert_same(s, ref):
    """The same discrete problem: the same contact set, pressure and approach up to the
    iteration's tolerance (TOL relative change of the pressure) and rounding."""
    assert s.converged and ref.converged
    assert s.FN == pytest.approx(ref.FN, rel=1e-12)
    np.testing.assert_array_equal(s.contact, ref.contact)
    assert np.abs(s.pn - ref.pn).max() <= 1e-6 * ref.pmax
    assert s.approach == pytest.approx(ref.approach, rel=1e-8)
    assert np.abs(s.un - ref.un).max() <= 1e-8 * np.abs(ref.un).max()
    assert s.gap_residual < 1e-6
    assert s.pn.shape == ref.pn.shape == s.un.shape


@pytest.mark.parametrize("precondition", [None, True])
def test_cold_hertz_on_a_window_equals_the_whole_grid_and_hertz(monkeypatch, precondition):
    """Cold start (initial_pressure): the window (the start's support, WINDOW_MARGIN elements more
    on each side, sides multiples of 4) holds under half of the 41 x 41 grid; pmax and the approach within
    0.3 % of Hertz (a contact radius of 10 elements), the contact set within 3 % of the elements
    whose centres lie inside the Hertz circle."""
    hz, g, h = _hertz()
    seen = _spy(monkeypatch)
    s = solve_normal(None, g, h, normal_force=hz.FN, material=STEEL, tol=TOL, precondition=precondition)
    (win,) = seen["windows"]
    assert win is not None and win[0] * win[1] <= 0.5 * g.size and win[0] % 4 == 0 == win[1] % 4
    assert seen["force"] == [win]                     # no fallback: the contact stays inside
    assert s.preconditioned == bool(precondition)
    ref = _whole_grid(monkeypatch, None, g, h, normal_force=hz.FN, material=STEEL, tol=TOL,
                      precondition=precondition)
    assert seen["force"][-1] == g.shape
    _assert_same(s, ref)
    assert s.pmax == pytest.approx(hz.pmax, rel=3e-3)
    assert s.approach == pytest.approx(hz.approach, rel=3e-3)
    X, Y = g.mesh()
    inside = int(((X / hz.a) ** 2 + (Y / hz.b) ** 2 < 1).sum())
    assert abs(s.n_contact - inside) <= 0.03 * inside


def test_warm_start_on_a_window_equals_the_whole_grid(monkeypatch):
    """A start from the solution for 90 % of the load, moved by one element (a sweep's
    neighbour), preconditioned as the warm starts of a sweep are."""
    hz, g, h = _hertz()
    start = np.roll(solve_normal(None, g, h, normal_force=0.9 * hz.FN, material=STEEL, tol=TOL).pn, 1, axis=0)
    seen = _spy(monkeypatch)
    s = solve_normal(None, g, h, normal_force=hz.FN, material=STEEL, tol=TOL, p_start=start,
                     precondition=True)
    (win,) = seen["windows"]
    assert win is not None and seen["force"] == [win]
    ref = _whole_grid(monkeypatch, None, g, h, normal_force=hz.FN, material=STEEL, tol=TOL,
                      p_start=start, precondition=True)
    _assert_same(s, ref)


def test_a_contact_leaving_the_window_is_solved_on_the_whole_grid(monkeypatch):
    """A start pressed on 3 x 3 elements at the centre: its window (3 + 2 WINDOW_MARGIN elements
    rounded up to a multiple of 4) is far smaller than the contact (a radius of 10 elements), the
    check of the gap outside the window fails and the whole grid is solved from the window's
    pressure, to the same answer."""
    hz, g, h = _hertz()
    start = np.zeros(g.shape)
    start[19:22, 19:22] = 1.0
    seen = _spy(monkeypatch)
    s = solve_normal(None, g, h, normal_force=hz.FN, material=STEEL, tol=TOL, p_start=start,
                     precondition=True)
    (win,) = seen["windows"]
    side = -(-(3 + 2 * normal.WINDOW_MARGIN) // normal.WINDOW_STEP) * normal.WINDOW_STEP
    assert win == (side, side) and side < 20
    assert seen["force"] == [win, g.shape]            # the fallback ran
    ref = _whole_grid(monkeypatch, None, g, h, normal_force=hz.FN, material=STEEL, tol=TOL,
                      p_start=start, precondition=True)
    _assert_same(s, ref)
    assert s.pmax == pytest.approx(hz.pmax, rel=3e-3)


def test_no_window_where_it_would_hold_most_of_the_grid(monkeypatch):
    """The contact fills most of the grid (scale 1.1): no window, the whole-grid iteration."""
    hz, g, h = _hertz(n=31, scale=1.1)
    seen = _spy(monkeypatch)
    solve_normal(None, g, h, normal_force=hz.FN, material=STEEL)
    assert seen["windows"] == [None] and seen["force"] == [g.shape]
