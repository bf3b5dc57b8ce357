"""Kalker's linear theory (seed Eq. 13) against the coefficient table and CONTACT's exact
results at small creepage."""
import math

import numpy as np
import pytest

from conformal.errors import ConformalError, InputError
from conformal.theories import coefficients as coef
from conformal.theories import linear
from _paths import CONTACT_CASES, reference_cases
from _scenes import hertz_problem

REF = CONTACT_CASES


def problem(**kin):
    model = dict(kin.pop("model", {"theory": "linear"}))
    return hertz_problem(6.3036, 12.6072, 106700.0, mu=0.33, kinematics=kin, **model)


def test_forces_at_a_table_node():
    # a/b = 0.5, nu = 0.25: C11 = 3.62, C22 = 3.01, C23 = 0.929 (Kalker 1990, Table E.3)
    a, b, G = 3.0, 6.0, 80000.0
    f = linear.linear_forces(a, b, G, 0.25, xi=2e-4, eta=-1e-4, phi=3e-4, need_c33=False)
    assert f.FX == pytest.approx(-G * a * b * 3.62 * 2e-4, rel=1e-12)
    assert f.FY == pytest.approx(-G * a * b * 3.01 * -1e-4 - G * (a * b) ** 1.5 * 0.929 * 3e-4, rel=1e-12)
    assert math.isnan(f.MZ)            # MZ needs C33 when phi != 0
    f = linear.linear_forces(a, b, G, 0.25, eta=-1e-4)
    assert f.MZ == pytest.approx(G * (a * b) ** 1.5 * 0.929 * -1e-4, rel=1e-12)
    assert f.C33 is None


def test_signs_follow_contact_convention():
    # positive creepage of body 1 -> force on body 1 opposes it; positive spin -> FY < 0
    f = linear.linear_forces(5.0, 5.0, 82000.0, 0.28, xi=1e-4, eta=1e-4)
    assert f.FX < 0 and f.FY < 0 and f.MZ > 0
    assert linear.linear_forces(5.0, 5.0, 82000.0, 0.28, phi=1e-4, need_c33=False).FY < 0


def test_vectorised_forces_equal_scalar():
    rng = np.random.default_rng(1)
    a, b = rng.uniform(2, 10, 20), rng.uniform(2, 10, 20)
    xi, eta, phi = rng.normal(0, 1e-3, (3, 20))
    FX, FY = linear.linear_force_arrays(a, b, 82000.0, 0.28, xi, eta, phi)
    for i in range(20):
        f = linear.linear_forces(a[i], b[i], 82000.0, 0.28, xi[i], eta[i], phi[i], need_c33=False)
        assert FX[i] == pytest.approx(f.FX, rel=1e-12) and FY[i] == pytest.approx(f.FY, rel=1e-12)


def test_small_creepage_against_contact_exact():
    """tractcurv series 1, case 1 (xi = 1e-5, 2 of 1384 elements in slip): CONTACT's exact
    half-space solution FX = -247 N on its 48 x 44 grid.  Linear theory gives -243.7 N
    (-1.3 %); the tolerance of 2 % covers the discretisation error of CONTACT's grid (its
    FASTSIM on the same grid is 3 % off the continuum, see test_fastsim)."""
    out = reference_cases()["tractcurv"]["steps"][0]["outputs"]
    r = linear.solve(problem(xi=1e-5))
    assert r.FX == pytest.approx(out["FX_N"], rel=0.02)
    assert r.FY == 0.0 and r.MZ == 0.0 and r.FN == pytest.approx(106700.0)


def test_prescribed_forces_are_inverted_exactly():
    r = linear.solve(problem(fx_rel=-0.2, fy_rel=0.1))
    assert r.FX / (0.33 * r.FN) == pytest.approx(-0.2, rel=1e-12)
    assert r.FY / (0.33 * r.FN) == pytest.approx(0.1, rel=1e-12)
    assert r.xi > 0 and r.eta < 0


def test_friction_bound_note():
    r = linear.solve(problem(xi=0.01))
    assert r.extra["F_over_muFN"] > 1 and "exceeds the friction bound" in r.extra["note"]


def test_spin_needs_c33():
    p = problem(phi=1e-4)
    if coef.c33_available():
        r = linear.solve(p)
        c33 = coef.c33(0.5, 0.28)
        assert r.MZ == pytest.approx(-82000.0 * (6.3036 * 12.6072) ** 2 * c33 * 1e-4, rel=1e-9)
    else:
        with pytest.raises(ConformalError, match="C33"):
            linear.solve(p)
    # without spin C33 is not needed (and not used)
    assert linear.solve(problem(eta=1e-4)).extra["C33"] is None


def test_rejects_shift_and_bad_option():
    with pytest.raises(InputError, match="rolling"):
        linear.solve(problem(xi=1e-4, rolling="shift"))
    with pytest.raises(InputError, match="require_c33"):
        linear.solve(problem(xi=1e-4, model={"theory": "linear", "require_c33": "yes"}))
