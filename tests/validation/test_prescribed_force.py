"""Prescribed tangential force near saturation with a strong normal-tangential coupling.

Dissimilar rollers (aluminium on steel, K = 0.076) with a tiny friction coefficient (mu = 1e-4):
the coupling's slip dominates the friction bound, and the bordered Newton system that solves for
the creepage together with the tractions used to diverge (FX/(mu FN) = +0.5 ended at -0.89).
The solver now falls back to a bracketing search on the creepage.  The independent check is a
root search through the public API (scipy's brentq on FX(xi) with xi fixed): the same creepage to
four digits, as CONTACT's answer was found.
"""
import pytest
from scipy.optimize import brentq

from conformal.scene import scene_from_dict
from conformal.dispatch import solve_scene

DISSIMILAR = {"G": 26000.0, "nu": 0.33, "body2": {"G": 82000.0, "nu": 0.28}}
MU = 1e-4


def _solve(kinematics):
    return solve_scene(scene_from_dict({
        "material": DISSIMILAR, "friction": {"mu": MU}, "load": {"normal_force": 1000.0},
        "geometry": {"kind": "quadratic", "A": 0.01, "B": 0.01}, "grid": {"n": 24},
        "kinematics": kinematics, "model": {"theory": "exact"}}, base_dir="."))


@pytest.mark.parametrize("fx_rel", [0.5, -0.99])
def test_prescribed_force_near_saturation_matches_a_root_search(fx_rel):
    r = _solve({"fx_rel": fx_rel})
    assert r.converged, r.warnings
    assert r.FX / (MU * r.FN) == pytest.approx(fx_rel, abs=1e-5)
    xi = r.summary()["xi"]

    def residual(x):
        s = _solve({"xi": x})
        return s.FX / (MU * s.FN) - fx_rel

    # bracket around the solved value (FX decreases with xi); brentq to 1e-9 relative
    lo, hi = xi - 2e-4, xi + 2e-4
    assert residual(lo) > 0 > residual(hi)
    xi_ref = brentq(residual, lo, hi, xtol=1e-12, rtol=1e-9)
    assert xi == pytest.approx(xi_ref, rel=1e-4)
