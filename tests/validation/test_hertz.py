"""Hertz theory (conformal.theories.hertz) against closed forms, an independent numerical
integration of the Hertz displacement and CONTACT's printed Hertz data."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from conformal.errors import InputError
from conformal.materials import Material
from conformal.theories.hertz import hertz_from_curvatures, hertz_from_semiaxes
from _paths import CONTACT_CASES, reference_cases

REF = CONTACT_CASES
STEEL = Material.identical(82000.0, 0.28)


def hertz_displacement(x0, y0, a, b, p0, E_star):
    """Normal displacement difference u(x0, y0) under p = p0 sqrt(1 - x²/a² - y²/b²),
    u = 1/(pi E*) int int p/r dA, computed independently of hertz.py: polar coordinates about
    (x0, y0), the radial integral of the square root in closed form, the angle by quadrature."""
    t0 = 1.0 - (x0 / a) ** 2 - (y0 / b) ** 2

    def radial(th):
        c, s = math.cos(th), math.sin(th)
        k2 = (c / a) ** 2 + (s / b) ** 2
        k1 = x0 * c / a**2 + y0 * s / b**2
        D = (k1 * k1 + k2 * t0) / k2**2          # p along the ray: p0 sqrt(k2 (D - (r + v0)²))
        v0, sD = k1 / k2, math.sqrt((k1 * k1 + k2 * t0) / k2**2)
        return p0 * math.sqrt(k2) * (0.25 * math.pi * D - 0.5 * v0 * math.sqrt(max(D - v0 * v0, 0.0))
                                     - 0.5 * D * math.asin(max(-1.0, min(1.0, v0 / sD))))

    val, _ = quad(radial, 0.0, 2.0 * math.pi, limit=400, epsabs=0.0, epsrel=1e-11,
                  points=[0.5 * math.pi, math.pi, 1.5 * math.pi])
    return val / (math.pi * E_star)


def test_sphere_closed_form():
    # sphere of radius R on a plane: h = r²/(2R), A = B = 1/(2R)
    R, FN = 25.0, 1500.0
    hz = hertz_from_curvatures(1 / (2 * R), 1 / (2 * R), STEEL, normal_force=FN)
    Es = STEEL.G / (1 - STEEL.nu)
    a = (3 * FN * R / (4 * Es)) ** (1 / 3)
    # closed forms; only floating point rounding separates them (1e-12)
    assert hz.a == pytest.approx(a, rel=1e-12) and hz.b == pytest.approx(a, rel=1e-12)
    assert hz.pmax == pytest.approx(3 * FN / (2 * math.pi * a * a), rel=1e-12)
    assert hz.approach == pytest.approx(a * a / R, rel=1e-12)
    # the same contact from its approach
    hz2 = hertz_from_curvatures(1 / (2 * R), 1 / (2 * R), STEEL, approach=a * a / R)
    assert hz2.FN == pytest.approx(FN, rel=1e-12) and hz2.a == pytest.approx(a, rel=1e-12)


@pytest.mark.parametrize("A, B", [(0.0008, 0.0008 / 2.8428), (2.406e-3, 0.8464e-3), (1e-3, 1.7e-3)])
def test_ellipse_against_numerical_integration(A, B):
    """Approach and curvatures of the Hertz ellipse equal the numerically integrated
    displacement of its own pressure: u(0,0) = approach, u(x0,0) = approach - A x0², ..."""
    hz = hertz_from_curvatures(A, B, STEEL, normal_force=50000.0)
    u = lambda x, y: hertz_displacement(x, y, hz.a, hz.b, hz.pmax, hz.E_star)  # noqa: E731
    u0 = u(0.0, 0.0)
    assert u0 == pytest.approx(hz.approach, rel=1e-9)
    # u is exactly quadratic inside the contact: recover A and B from two interior points
    assert (u0 - u(0.6 * hz.a, 0.0)) / (0.6 * hz.a) ** 2 == pytest.approx(A, rel=1e-8)
    assert (u0 - u(0.0, 0.5 * hz.b)) / (0.5 * hz.b) ** 2 == pytest.approx(B, rel=1e-8)
    x, y = 0.3 * hz.a, -0.4 * hz.b
    assert u(x, y) == pytest.approx(hz.approach - A * x * x - B * y * y, rel=1e-8)
    assert 2 / 3 * math.pi * hz.a * hz.b * hz.pmax == pytest.approx(50000.0, rel=1e-12)


def test_contact_printed_hertz_data():
    """CONTACT's Hertz data (4 significant digits): tolerance half a unit of the last digit."""
    cases = reference_cases()
    # fastsim case: a = 8, b = 4 mm, FN = 82 kN -> A = 0.8464e-3, B = 2.406e-3, approach 0.09267
    out = cases["fastsim"]["steps"][1]["outputs"]
    hz = hertz_from_semiaxes(8.0, 4.0, STEEL, normal_force=82000.0)
    assert hz.A == pytest.approx(out["hz_A1_B1"][0], abs=0.00005e-3)
    assert hz.B == pytest.approx(out["hz_A1_B1"][1], abs=0.0005e-3)
    assert hz.approach == pytest.approx(out["approach_mm"], abs=0.000005)
    # tractcurv: A = 0.0008, B = 0.2814e-3 (CONTACT, from a/b = 0.5), FN = 106.7 kN
    out = cases["tractcurv"]["steps"][0]["outputs"]
    hz = hertz_from_curvatures(0.0008, out["hz_A1_B1"][1], STEEL, normal_force=106700.0)
    a, b, aob = out["hz_basic_semiaxes"]
    assert hz.a == pytest.approx(a, abs=0.0005) and hz.b == pytest.approx(b, abs=0.005)
    assert hz.a / hz.b == pytest.approx(aob, rel=2e-4)   # B has 4 digits -> a/b to ~1e-4
    # series 3/4 print the Hertz approach (the normal problem is not solved there)
    s3 = [s for s in cases["tractcurv"]["steps"] if s.get("series") == 3][0]["outputs"]
    assert hz.approach == pytest.approx(s3["approach_mm"], abs=0.000005 + 2e-4 * s3["approach_mm"])


@pytest.mark.parametrize("a_over_b", [0.05, 0.3, 1.0, 3.0, 20.0])
def test_inverse_round_trip(a_over_b):
    a, b = 5.0 * math.sqrt(a_over_b), 5.0 / math.sqrt(a_over_b)
    inv = hertz_from_semiaxes(a, b, STEEL, normal_force=20000.0)
    fwd = hertz_from_curvatures(inv.A, inv.B, STEEL, normal_force=20000.0)
    # brentq on the aspect ratio with xtol 1e-15: the round trip is exact to ~1e-10
    assert fwd.a == pytest.approx(a, rel=1e-9) and fwd.b == pytest.approx(b, rel=1e-9)
    assert fwd.approach == pytest.approx(inv.approach, rel=1e-9)
    via_approach = hertz_from_curvatures(inv.A, inv.B, STEEL, approach=inv.approach)
    assert via_approach.FN == pytest.approx(20000.0, rel=1e-9)
    assert hertz_from_semiaxes(a, b, STEEL, approach=inv.approach).FN == pytest.approx(20000.0, rel=1e-12)


@pytest.mark.parametrize("a_over_b", [0.05, 20.0])
def test_extreme_aspect_ratios_against_integration(a_over_b):
    a, b = 4.0 * math.sqrt(a_over_b), 4.0 / math.sqrt(a_over_b)
    hz = hertz_from_semiaxes(a, b, STEEL, normal_force=30000.0)
    u = lambda x, y: hertz_displacement(x, y, a, b, hz.pmax, hz.E_star)  # noqa: E731
    u0 = u(0.0, 0.0)
    assert u0 == pytest.approx(hz.approach, rel=1e-8)
    assert (u0 - u(0.5 * a, 0.0)) / (0.5 * a) ** 2 == pytest.approx(hz.A, rel=1e-7)
    assert (u0 - u(0.0, 0.5 * b)) / (0.5 * b) ** 2 == pytest.approx(hz.B, rel=1e-7)
    # the slender ellipse is long across the direction of the larger curvature
    assert (hz.A < hz.B) == (a > b)


def test_dissimilar_materials_combined_constants():
    """Steel on aluminium: combined G, nu of seed Eqs. 16-17; E* = G/(1-nu) must equal the
    textbook 1/E* = (1-nu1²)/E1 + (1-nu2²)/E2, and the sphere radius follows with it."""
    G1, nu1, G2, nu2 = 82000.0, 0.28, 26000.0, 0.33
    m = Material(G1, nu1, G2, nu2)
    assert 1 / m.G == pytest.approx(0.5 * (1 / G1 + 1 / G2), rel=1e-14)
    assert m.nu / m.G == pytest.approx(0.5 * (nu1 / G1 + nu2 / G2), rel=1e-14)
    E1, E2 = 2 * G1 * (1 + nu1), 2 * G2 * (1 + nu2)
    Es = 1 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)
    assert m.E_star == pytest.approx(Es, rel=1e-13)
    R, FN = 40.0, 5000.0
    hz = hertz_from_curvatures(1 / (2 * R), 1 / (2 * R), m, normal_force=FN)
    assert hz.a == pytest.approx((3 * FN * R / (4 * Es)) ** (1 / 3), rel=1e-12)
    # softer pair -> larger contact than steel on steel
    assert hz.a > hertz_from_curvatures(1 / (2 * R), 1 / (2 * R), STEEL, normal_force=FN).a


def test_bad_input_names_the_problem():
    with pytest.raises(InputError, match="normal_force"):
        hertz_from_curvatures(1e-3, 1e-3, STEEL, normal_force=-5.0)
    with pytest.raises(InputError, match="curvatures"):
        hertz_from_curvatures(1e-3, float("nan"), STEEL, normal_force=5.0)
    with pytest.raises(InputError, match="exactly one"):
        hertz_from_semiaxes(1.0, 2.0, STEEL)
    assert np.isfinite(hertz_from_semiaxes(1.0, 2.0, STEEL, normal_force=1.0).A)
