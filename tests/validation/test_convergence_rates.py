"""Fitted convergence rates (np.polyfit of log error against log element size) against independent
references: the normal problem of the exact theory against Hertz's closed form, and the creep
coefficients of the exact theory (full-stick rolling) against Kalker's table (Kalker 1967, as
reprinted in Kalker 1990).  A rate that drops shows a discretisation error creeping in long before
a single-grid tolerance would."""
import numpy as np
import pytest

from conformal.problem import problems_from_scene
from conformal.solvers.normal import solve_normal
from conformal.theories.c33 import exact_coefficients
from conformal.theories.coefficients import kalker_coefficients

from _paths import SCENES


def rate(h, err) -> float:
    """Slope of log(err) against log(h)."""
    return float(np.polyfit(np.log(np.asarray(h, float)), np.log(np.asarray(err, float)), 1)[0])


def test_normal_problem_converges_to_hertz_at_second_order():
    """Circular Hertz contact (CONTACT's case circ, FN = 100 kN): the discrete pressure peak and
    approach of the projected-CG normal problem on grids of 10 to 80 elements across the patch.
    Measured: rates 1.93 (pmax) and 1.76 (approach); 0.015 % and 0.002 % on 80 x 80."""
    import conformal

    h, e_p, e_a = [], [], []
    for n in (10, 14, 20, 28, 40, 56, 80):
        sc = conformal.load_scene(SCENES / "circ.toml", model__theory="exact", grid__n=n, kinematics__xi=0.0)
        p = problems_from_scene(sc)[0]
        sol = solve_normal(None, p.grid, p.h, normal_force=p.normal_force, material=p.material, tol=1e-10,
                           maxit=5000)
        hz = p.hertz
        h.append(p.grid.dx)
        e_p.append(abs(float(sol.pn.max()) - hz.pmax) / hz.pmax)
        e_a.append(abs(sol.approach - hz.approach) / hz.approach)
    assert 1.7 < rate(h, e_p) < 2.2
    assert 1.4 < rate(h, e_a) < 2.2
    assert e_p[-1] < 3e-4 and e_a[-1] < 1e-4


@pytest.mark.parametrize("name", ["C11", "C22"])
def test_creep_coefficients_converge_to_kalkers_table_at_first_order(name):
    """Full-stick rolling on a circle (a/b = 1, nu = 0.25) with 8 to 64 elements across the patch:
    the computed coefficient approaches Kalker's tabulated one (C11 = 4.12, C22 = 3.67, three digits)
    at first order (the contact edge is resolved to one element).  Measured: rates 1.18 (C11) and
    1.10 (C22); 0.36 % and 0.56 % off on the finest grid."""
    ref = getattr(kalker_coefficients(1.0, 0.25), name)
    ns = np.array([8, 12, 16, 24, 32, 48, 64])
    err = [abs(getattr(exact_coefficients(1.0, 0.25, int(n)), name) - ref) / ref for n in ns]
    assert 0.9 < rate(1.0 / ns, err) < 1.5
    assert err[-1] < 0.008
