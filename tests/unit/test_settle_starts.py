"""The starts of the one-patch balance's settle normal solve and of the solves after a search on
the Manchester A-2.2 wheel (S1002 on UIC60 1:40): the settle solve to SETTLE_TOL from the rigid
overlap where no field is known, a field of the position moved along the rail with its reference
point.  Each is checked against the path it replaces (settle solves to 1e-6 from the solver's own
start, fields resampled where they lie) and against exact shifts of a field."""
from __future__ import annotations

import json

import numpy as np

import conformal.cases.wheelrail as wr
from _paths import CONTACT_CASES
from _scenes import mbench_case_scene
from conformal.grid import PlanarGrid
from conformal.solvers.normal import solve_normal, warm_precondition

CASES = json.loads(CONTACT_CASES.read_text())["cases"]["mbench_a22"]["right"]
W = 10000.0


def mbench_case(y, element_size=0.2):
    return mbench_case_scene(next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == y),
                             element_size=element_size)


def test_field_moves_along_the_rail_with_its_reference_point():
    """A field of this position on the grid of a patch whose reference point lies 0.4 mm further
    along the rail (two elements of 0.2 mm) lands two columns lower (eta = s - s_ref), exactly;
    mirrored for a left wheel; a neighbour's field (another lateral shift) is not moved."""
    grid = PlanarGrid(4, 8, 0.2, 0.2, -0.4, -0.8)
    pn = np.zeros((4, 8))
    pn[1:3, 3:6] = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
    here = wr.PatchField(10.0, grid, pn, here=True)
    moved = wr.resample(wr._moved_grid(here, 10.4, "right"), pn, grid)
    assert np.array_equal(moved[:, 1:4], pn[:, 3:6]) and moved.sum() == pn.sum()
    left = wr.resample(wr._moved_grid(here, 10.4, "left"), pn, grid)
    assert np.array_equal(left[:, 5:8], pn[:, 3:6]) and left.sum() == pn.sum()
    other = wr.PatchField(10.0, grid, pn)
    assert wr._moved_grid(other, 10.4, "right") is grid


def test_overlap_start_settles_the_cold_wide_patch_in_fewer_iterations():
    """The cold settle solve at 0 mm (the wide tread patch, 47 x 102 elements): from the square
    root of the rigid overlap 12 iterations at SETTLE_TOL instead of 20 from the solver's circular
    Hertz-like start (27 at 1e-6); the approach, which sets the next search's height, within
    2e-7 mm of the solve to 1e-6 (measured 6e-10), far below the range the geometry is kept over
    (4e-5 mm)."""
    sc = mbench_case(0.0)
    pl = wr.place_scene(sc)
    # the cold start's height: the Hertz-like estimate of the lowering (as _one_patch_start)
    lowering = wr._estimated_lowering(pl, sc, lambda z: wr.state_at(pl.pair, pl.top, z, pl.roll, sc),
                                      lambda z: wr.state_at(pl.pair, pl.top, z, pl.roll, sc, grids=False), [], [0])
    st = wr.state_at(pl.pair, pl.top, pl.z_touch + lowering, pl.roll, sc)
    assert len(st.patches) == 1 and st.patches[0].grid.my > 100
    pg = st.patches[0]
    fn = W / np.cos(pg.patch.delta)

    def solve(start, tol):
        return solve_normal(None, pg.grid, pg.h, normal_force=fn, material=sc.material, tol=tol,
                            p_start=start, precondition=warm_precondition(pg.grid, start))

    tight, cold, overlap = solve(None, 1e-6), solve(None, wr.SETTLE_TOL), solve(wr._overlap_start(pg), wr.SETTLE_TOL)
    assert overlap.converged and overlap.iterations < cold.iterations < tight.iterations
    assert overlap.iterations <= 0.7 * cold.iterations
    assert abs(overlap.approach - tight.approach) <= 2e-7
    assert abs(overlap.FN - fn) <= 1e-9 * fn


def _old_path(monkeypatch):
    """The path before: settle solves to 1e-6 from the solver's start, fields not moved."""
    monkeypatch.setattr(wr, "SETTLE_TOL", 1e-6)
    monkeypatch.setattr(wr, "_overlap_start", lambda pg: None)
    monkeypatch.setattr(wr, "_moved_grid", lambda f, s_ref, side: f.grid)


def _sweep(shifts):
    warm, out, iterations = None, [], []
    solve = wr.solve_normal

    def counted(*args, **kw):
        sol = solve(*args, **kw)
        iterations.append(sol.iterations)
        return sol

    wr.solve_normal = counted
    try:
        for y in shifts:
            r = wr.solve_wheel_rail(mbench_case(y), warm=warm)
            warm = wr.WarmStart.from_result(r, warm)
            out.append(r)
    finally:
        wr.solve_normal = solve
    return out, iterations


def test_settle_starts_give_the_answers_of_the_old_path(monkeypatch):
    """0 mm (cold) and 0.5 mm (the wide patch whose reference point moves 1 mm between the
    searches): the same counts of searches and solves, half the settle solves' iterations (main:
    27 + 28 + 8, now 12 + 10 + 8) and the forces within 0.05 N of the old path (the balance itself
    is 1e-5 W = 0.1 N; measured 0.016 N over the 21 positions of the sequence), the heights within
    1e-6 mm (measured 7e-8 mm)."""
    new, it_new = _sweep((0.0, 0.5))
    with monkeypatch.context() as m:
        _old_path(m)
        old, it_old = _sweep((0.0, 0.5))
    assert sum(it_new) <= 0.6 * sum(it_old)
    for a, b in zip(new, old):
        ba, bb = a.extra["balance"], b.extra["balance"]
        for k in ("searches", "normal_solves", "tangential_solves"):
            assert ba[k] == bb[k], k
        assert abs(a.extra["FZ_track"] - W) <= wr.ONE_PATCH_TOL * W
        for k in ("FN", "FX", "FY"):
            assert abs(getattr(a, k) - getattr(b, k)) <= 0.05, k
        assert abs(a.extra["z_ws"] - b.extra["z_ws"]) <= 1e-6
