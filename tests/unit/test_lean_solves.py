"""Lean contact solves (``ContactProblem.lean``): a solve that is never the answer (the loose
passes of the one-patch balance) returns the totals, the approach and the tractions alone, and
they are the numbers of the full solve, bit for bit: the lean solve skips only what follows the
iterations (the displacements u_x, u_y, the contact parts, CONTACT's totals, the warnings)."""
from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

import conformal.cases.wheelrail as wr
from conformal.models import solve_problem
from conformal.problem import problems_from_scene
from conformal.scene import scene_from_dict
from _paths import CONTACT_CASES
from _scenes import mbench_case_scene

CASES = json.loads(CONTACT_CASES.read_text())["cases"]["mbench_a22"]["right"]
TOTALS = ("FN", "FX", "FY", "MZ", "approach", "pmax", "a", "b", "xi", "eta", "converged", "iterations", "residual")


def _patch_problem(y, lowering, fn=1e4):
    """The contact problem of the Manchester A-2.2 wheel at lateral shift ``y`` (mm), the wheel
    lowered by ``lowering`` below touching, with the normal force ``fn`` (N)."""
    sc = mbench_case_scene(next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == y), element_size=0.2)
    pl = wr.place_scene(sc)
    st = wr.state_at(pl.pair, pl.top, pl.z_touch + lowering, pl.roll, sc)
    return wr.problems_at(sc, pl, st, [fn])[0]


def _assert_lean_is_the_full_solve(problem):
    full = solve_problem(problem)
    lean = solve_problem(replace(problem, lean=True))
    for key in TOTALS:
        assert getattr(lean, key) == getattr(full, key), key
    for key in ("pn", "px", "py", "status"):
        assert np.array_equal(getattr(lean.field, key), getattr(full.field, key)), key
    # the full solve carries the displacements, the contact parts and CONTACT's totals; the lean one not
    assert all(getattr(full.field, k) is not None for k in ("sx", "sy", "un", "ux", "uy"))
    assert {"n_patches", "patch_FN", "elastic_energy", "frictional_power"} <= set(full.extra)
    assert lean.field.ux is None and lean.field.uy is None and not lean.extra
    return full, lean


@pytest.mark.parametrize("y, lowering, tol", [(3.0, 0.0245, 1e-4), (8.0, 0.0604, 1e-6)])
def test_lean_wheel_rail_solve_gives_the_full_solves_numbers(y, lowering, tol):
    """Tread (3 mm, loose tolerance as a first pass) and flange (8 mm, the products on a window of
    the grid, the rest of the full solve's u from the single-precision product): same bits."""
    problem = _patch_problem(y, lowering)
    _assert_lean_is_the_full_solve(replace(problem, model=replace(problem.model, tol=tol)))


def test_lean_coupled_solve_gives_the_full_solves_numbers():
    """Dissimilar bodies (K != 0, Panagiotopoulos alternations): the lean solve leaves out the
    final u_n with the coupling A_nt p_t, nothing of the alternations."""
    scene = scene_from_dict({"geometry": {"kind": "quadratic", "A": 1.0 / 600.0, "B": 1.0 / 300.0},
                             "load": {"normal_force": 1e4}, "kinematics": {"xi": 5e-4, "eta": -3e-4},
                             "material": {"G": 82000.0, "nu": 0.28, "body2": {"G": 60000.0, "nu": 0.30}},
                             "grid": {"n": 16}, "model": {"theory": "exact"}})
    full, _ = _assert_lean_is_the_full_solve(problems_from_scene(scene)[0])
    assert full.extra["outer_iterations"] > 1


def test_loose_passes_are_lean_and_the_answer_is_full(monkeypatch):
    """In a warm-started sweep the passes solved to FIRST_PASS_TOL, and only those, are lean; the
    reported patch results are full ones."""
    seen = []
    solve = wr.solve_problem

    def recorded(problem):
        seen.append((problem.lean, problem.model.tol))
        return solve(problem)

    monkeypatch.setattr(wr, "solve_problem", recorded)
    warm = None
    for y in (2.5, 3.0):
        r = wr.solve_wheel_rail(mbench_case_scene(next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == y),
                                                  element_size=0.2), warm=warm)
        warm = wr.WarmStart.from_result(r, warm)
        assert r.patches[0].field.ux is not None and "elastic_energy" in r.patches[0].extra
    assert any(lean for lean, _ in seen)
    assert all(lean == (tol == wr.FIRST_PASS_TOL) for lean, tol in seen)
