"""Issue 22: inputs that used to give a wrong answer without a word (the right number, or a
refusal naming the key, or a warning)."""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import conformal
from conformal.grid import PlanarGrid
from conformal.materials import Material
from conformal.solvers.normal import solve_normal

# ----------------------------------------------------------------------------- item 2
#: a soft sphere (G 0.5, nu 0) on a stiff flat (G 1e5): K = 0.5, the largest difference parameter
SOFT_ON_STIFF = {
    "material": {"G": 0.5, "nu": 0.0, "body2": {"G": 1e5, "nu": 0.0}}, "friction": {"mu": 0.2986},
    "geometry": {"kind": "quadratic", "A": 0.004116, "B": 0.004116}, "load": {"normal_force": 1e-5},
    "grid": {"mx": 45, "my": 45, "dx": 0.2, "dy": 0.2, "xl": -4.4999, "yl": -4.4999},
    "model": {"theory": "exact"},
    "history": [{"normal_force": 1e-5}, {"normal_force": 0.1}, {"normal_force": 0.47}],
}


def test_normal_solver_grows_the_contact_set_from_one_element():
    """A start from the one-element pressure of a tiny load (the previous history step) must give
    the same pressure as a start from nothing: the projected CG used to stop at once (the gap on a
    one-element set is trivially uniform) without letting the interpenetrating elements in."""
    g = PlanarGrid(45, 45, 0.2, 0.2, -4.4999, -4.4999)
    X, Y = g.mesh()
    h = 0.004116 * (X**2 + Y**2)
    mat = Material(0.5, 0.0, 1e5, 0.0)
    start = np.zeros(g.shape)
    start[np.unravel_index(np.argmin(h), h.shape)] = 1.0
    ref = solve_normal(None, g, h, normal_force=0.47, material=mat, tol=1e-8)
    warm = solve_normal(None, g, h, normal_force=0.47, material=mat, tol=1e-8, p_start=start)
    assert warm.converged and ref.n_contact > 900
    assert warm.n_contact == ref.n_contact
    assert np.abs(warm.pn - ref.pn).max() < 1e-6 * ref.pmax
    # and Hertz: pmax = 3 FN / (2 pi a²), a = (3 FN R / (4 E*))^(1/3), R = 1/(2A), E* = 1/(1/1 + 1e-5)
    E = 1.0 / (1.0 / 1.0 + 1.0 / 1e5)
    a = (3 * 0.47 / (2 * 0.004116) / (4 * E)) ** (1 / 3)
    assert ref.pmax == pytest.approx(3 * 0.47 / (2 * math.pi * a * a), rel=0.03)


def test_history_with_dissimilar_materials_does_not_freeze_the_contact_area():
    """The issue's reproducer: the last step's pmax was 11.75 N/mm² on one element.  The right
    answer is the same history started at 0.01 N (which never passed through one element): 917
    elements, pmax 0.024 N/mm²; a single step to 0.47 N differs by the history of the frictional
    coupling (Spence) but has the same size (944 elements, 0.021 N/mm²)."""
    r = conformal.solve(SOFT_ON_STIFF)
    last = r.extra["history"][-1]
    alt = copy.deepcopy(SOFT_ON_STIFF)
    alt["history"][0]["normal_force"] = 0.01
    r_alt = conformal.solve(alt)
    assert last["converged"]
    assert last["n_contact"] == r_alt.extra["history"][-1]["n_contact"] == 917
    assert r.pmax == pytest.approx(r_alt.pmax, rel=0.01)
    assert r.pmax == pytest.approx(0.024, rel=0.03)
    single = copy.deepcopy(SOFT_ON_STIFF)
    del single["history"]
    single["load"]["normal_force"] = 0.47
    one = conformal.solve(single)
    assert one.pmax == pytest.approx(r.pmax, rel=0.2)
