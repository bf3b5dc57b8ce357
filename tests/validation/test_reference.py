"""The analytic oracles (conformal.reference) against the numbers quoted in
tests/reference/contact_cases.json (computed there from Johnson's and Kalker's formulas) and
against their own integrals (the traction must integrate to the force)."""
import math

import numpy as np
import pytest
from scipy import integrate

from conformal import reference as ref
from _paths import reference_cases

CASES = reference_cases()


def test_carter_against_the_reference_numbers():
    ana = CASES["carter2d"]["analytic"]
    E_star = 82000.0 / (1 - 0.28)
    a, p0 = ref.hertz_2d(ana["FN_per_mm_N"], ana["R_mm"], E_star)
    assert a == pytest.approx(ana["a_mm"], rel=1e-5) and p0 == pytest.approx(ana["p0_Nmm2"], rel=1e-5)
    xi = ana["xi"]
    assert ref.carter_adhesion_width(xi, mu=0.3, a=a, R=500.0) == pytest.approx(ana["adhesion_half_width_a_prime_mm"])
    assert ref.carter_force(xi, mu=0.3, a=a, R=500.0) == pytest.approx(ana["FX_over_muFN"], abs=1e-4)
    rows = CASES["carter2d"]["steps"][0]["outputs"]["centreline_tractions"]["rows"]
    x = np.array([r["x_mm"] for r in rows])
    px = ref.carter_traction(x, xi, mu=0.3, a=a, R=500.0, p0=p0)
    assert px == pytest.approx([r["px_carter_analytic_Nmm2"] for r in rows], abs=2e-3)


def test_carter_traction_integrates_to_the_force():
    a, R, mu, p0 = 1.0, 500.0, 0.3, 113.889
    FN = math.pi * a * p0 / 2  # per unit width
    for xi in (-4e-4, -1e-4, 2.4e-4, 7e-4):
        F, _ = integrate.quad(lambda x: float(ref.carter_traction(x, xi, mu=mu, a=a, R=R, p0=p0)), -a, a,
                              points=[a - 2 * ref.carter_adhesion_width(xi, mu=mu, a=a, R=R)], limit=200)
        assert F / (mu * FN) == pytest.approx(ref.carter_force(xi, mu=mu, a=a, R=R), abs=1e-7)
    # sign: positive creepage -> negative force; full slip from |xi| = mu a / R on
    assert ref.carter_force(1e-4, mu=mu, a=a, R=R) < 0 < ref.carter_force(-1e-4, mu=mu, a=a, R=R)
    assert ref.carter_force(mu * a / R, mu=mu, a=a, R=R) == -1.0 and ref.carter_force(0.0, mu=mu, a=a, R=R) == 0.0


def test_carter_traction_solves_the_rolling_problem():
    """Independent of Carter's derivation: the displacement gradient of his traction, from the 2-D
    line-load solution u_x = -2(1-nu)/(pi G) ln|x - t| p_x (halfspace_influence.md §6), gives the
    steady-rolling slip s = xi - du/dx (u' taken upstream, rolling in +x): zero in the adhesion
    zone, opposite to the traction in the slip zone."""
    a, R, mu, G, nu, xi = 1.0, 500.0, 0.3, 82000.0, 0.28, -2.4e-4
    FN = math.pi * a * a * G / (1 - nu) / (4 * R)
    p0 = 2 * FN / (math.pi * a)
    f = lambda t: float(ref.carter_traction(t, xi, mu=mu, a=a, R=R, p0=p0))
    x_stick = a - 2 * ref.carter_adhesion_width(xi, mu=mu, a=a, R=R)   # -0.2
    for x in (-0.9, -0.6, -0.3, -0.1, 0.3, 0.8):
        pv, _ = integrate.quad(f, -a, a, weight="cauchy", wvar=x, limit=400)  # PV int p/(t - x)
        slip = xi - 2 * (1 - nu) / (math.pi * G) * pv
        if x > x_stick:
            assert abs(slip) < 1e-9 * abs(xi)
        else:
            assert slip * f(x) < 0 and abs(slip) > 0.1 * abs(xi)


def test_cattaneo_against_the_reference_numbers():
    ana = CASES["cattaneo"]["analytic"]
    q = -ana["cattaneo"]["Q_over_muFN"]  # CONTACT's case: FX/(mu FN) = -7/8 on body 1
    assert ref.cattaneo_force(0.5) == pytest.approx(0.875)
    assert ref.cattaneo_stick_ratio(q) == pytest.approx(ana["cattaneo"]["adhesion_radius_mm"])
    W = ref.cattaneo_shift(q, mu=0.4, FN=ana["hertz"]["FN_N"], a=1.0, G=200.0, nu=0.42)
    assert W == pytest.approx(ana["cattaneo"]["shift_Wx_mm"], rel=1e-4)
    assert float(ref.cattaneo_traction(0.0, q, mu=0.4, a=1.0, p0=ana["hertz"]["pmax_Nmm2"])) == pytest.approx(
        ana["cattaneo"]["px_at_centre_Nmm2"], abs=1e-4)
    rows = CASES["cattaneo"]["steps"][1]["outputs"]["centreline_y0_tractions"]["rows"]
    r = np.abs([row["x_mm"] for row in rows])
    px = ref.cattaneo_traction(r, q, mu=0.4, a=1.0, p0=ana["hertz"]["pmax_Nmm2"])
    assert px == pytest.approx([row["px_cattaneo_analytic_Nmm2"] for row in rows], abs=2e-4)


def test_cattaneo_traction_integrates_to_the_force():
    a, mu, FN = 1.0, 0.4, 9.1954
    p0 = 3 * FN / (2 * math.pi * a * a)
    for q in (-0.875, -0.3, 0.6):
        F, _ = integrate.quad(lambda r: 2 * math.pi * r * float(ref.cattaneo_traction(r, q, mu=mu, a=a, p0=p0)),
                              0.0, a, points=[ref.cattaneo_stick_ratio(q) * a], limit=200)
        assert F / (mu * FN) == pytest.approx(q, abs=1e-7)
        # shift grows from 0 to the full-slip value 3 mu FN (2 - nu) / (8 G a) as |q| -> 1
        assert np.sign(ref.cattaneo_shift(q, mu=mu, FN=FN, a=a, G=200.0, nu=0.42)) == -np.sign(q)
    full = 3 * mu * FN * (2 - 0.42) / (8 * 200.0 * a)
    assert abs(ref.cattaneo_shift(-0.999999, mu=mu, FN=FN, a=a, G=200.0, nu=0.42)) == pytest.approx(full, rel=1e-3)
