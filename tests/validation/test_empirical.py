"""Empirical creep-force laws: Kalker 1968 (seed Eqs. 18, 20) and Johnson-Vermeulen 1964."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from conformal.errors import InputError
from conformal.theories import coefficients as coef
from conformal.theories import empirical as emp
from _paths import CONTACT_CASES, reference_cases
from _scenes import hertz_problem

REF = CONTACT_CASES
G, NU, MU, FN = 82000.0, 0.28, 0.33, 106700.0
A, B = 6.3036, 12.6072          # tractcurv's Hertz ellipse, a/b = 0.5


def problem(theory, **kin):
    model = kin.pop("model", {})
    return hertz_problem(A, B, FN, theory=theory, material={"G": G, "nu": NU}, mu=MU, kinematics=kin, **model)


@pytest.mark.parametrize("k", [1.0, 0.9999, 0.97, 0.5, 0.05, 1e-3])
def test_elliptic_integrals_against_quadrature(k):
    """B, C, D of seed Eq. 18 (modulus g² = 1 - k²) against direct quadrature of their
    definitions; closed forms in K, E are exact, the series near k = 1 is O(m^4)."""
    m = 1 - k * k
    dl = lambda t: math.sqrt(1 - m * math.sin(t) ** 2)  # noqa: E731
    opts = dict(epsabs=0, epsrel=1e-13, limit=200)
    Bq = quad(lambda t: math.cos(t) ** 2 / dl(t), 0, math.pi / 2, **opts)[0]
    Dq = quad(lambda t: math.sin(t) ** 2 / dl(t), 0, math.pi / 2, **opts)[0]
    Cq = quad(lambda t: (math.cos(t) * math.sin(t)) ** 2 / dl(t) ** 3, 0, math.pi / 2, **opts)[0]
    Bc, Cc, Dc = emp.elliptic_integrals(k)
    assert (Bc, Cc, Dc) == pytest.approx((Bq, Cq, Dq), rel=1e-10)


@pytest.mark.parametrize("nu", [0.0, 0.25, 0.5])
def test_circle_coefficients_johnson_1958(nu):
    # a = b: phi = pi (4 - 3 nu)/16 (longitudinal), psi = pi (4 - nu)/16 (lateral)
    phi, psi = emp.phi_psi(3.0, 3.0, nu)
    assert phi == pytest.approx(math.pi * (4 - 3 * nu) / 16, rel=1e-13)
    assert psi == pytest.approx(math.pi * (4 - nu) / 16, rel=1e-13)
    # the two branches of seed Eq. 18 (a <= b, a >= b) meet continuously at the circle
    lo, hi = emp.phi_psi(3.0 * (1 - 1e-7), 3.0, nu), emp.phi_psi(3.0 * (1 + 1e-7), 3.0, nu)
    assert lo == pytest.approx(hi, rel=1e-6)


def slope(law, cc, direction):
    """dF/d(creepage) at vanishing creepage.  Both laws are f(tau) = s0 tau + c2 tau² + O(tau³)
    near 0, so the Richardson combination 2 F(d)/d - F(2d)/(2d) removes the tau² term; with
    tau ~ 1e-4 the error is ~1e-8 (truncation) + ~1e-12 (rounding of 1 - (1 - tau)³)."""
    vals = []
    for d in (1e-7, 2e-7):
        xi, eta = (d, 0.0) if direction == "x" else (0.0, d)
        fx, fy, _ = emp.empirical_forces(A, B, FN, MU, G, NU, xi, eta, law=law, coefficients=cc)
        vals.append((fx if direction == "x" else fy) / d)
    return 2 * vals[0] - vals[1]


def test_slopes_with_kalker_coefficients_equal_linear_theory():
    """Seed Eq. 20 (and the same normalisation for JV): the initial slopes are exactly linear
    theory's -G a b C11 and -G a b C22."""
    c = coef.kalker_coefficients(A / B, NU)
    for law in emp.LAWS:
        assert slope(law, "kalker", "x") == pytest.approx(-G * A * B * c.C11, rel=1e-7)
        assert slope(law, "kalker", "y") == pytest.approx(-G * A * B * c.C22, rel=1e-7)


def test_slopes_with_elliptic_coefficients():
    """Seed Eq. 18 normalisation: JV's slope is exactly -pi a b G/phi (Vermeulen-Johnson's own
    creep coefficient), Kalker 1968's -(pi²/4) a b G/phi.  Against Kalker's exact C11 (linear
    theory) at a/b = 0.5, nu = 0.28 these are +23.7 % (JV) and -2.9 % (Kalker 1968); over
    a/b = 0.05 ... 20 and nu = 0 ... 0.5 we measured JV +8 ... +29 %, Kalker 1968 -16 ... +1 %."""
    phi, psi = emp.phi_psi(A, B, NU)
    assert slope("johnson_vermeulen", "elliptic", "x") == pytest.approx(-math.pi * A * B * G / phi, rel=1e-7)
    assert slope("johnson_vermeulen", "elliptic", "y") == pytest.approx(-math.pi * A * B * G / psi, rel=1e-7)
    assert slope("kalker", "elliptic", "x") == pytest.approx(-math.pi**2 / 4 * A * B * G / phi, rel=1e-7)
    c = coef.kalker_coefficients(A / B, NU)
    assert (math.pi / phi) / c.C11 == pytest.approx(1.237, abs=0.002)
    assert (math.pi**2 / 4 / phi) / c.C11 == pytest.approx(0.971, abs=0.002)
    for r in (0.05, 0.2, 1.0, 5.0, 20.0):
        for nu in (0.0, 0.25, 0.5):
            ph, _ = emp.phi_psi(r, 1.0, nu)
            c11 = coef.kalker_coefficients(r, nu).C11
            assert 1.07 < (math.pi / ph) / c11 < 1.30
            assert 0.84 < (math.pi**2 / 4 / ph) / c11 < 1.02


@pytest.mark.parametrize("law", emp.LAWS)
@pytest.mark.parametrize("cc", emp.COEFFICIENTS)
def test_saturation_and_direction(law, cc):
    # far beyond tau = 1 the force is mu FN, opposite to the creepage direction
    fx, fy, tau = emp.empirical_forces(A, B, FN, MU, G, NU, 0.03, 0.04, law=law, coefficients=cc)
    assert tau > 1
    assert math.hypot(fx, fy) == pytest.approx(MU * FN, rel=1e-12)
    assert fx < 0 and fy < 0
    if law == "kalker":     # e2: the direction of the creepage itself
        assert fy / fx == pytest.approx(0.04 / 0.03, rel=1e-12)
    # |F| grows monotonically with the creepage and never exceeds mu FN
    s = np.linspace(0, 3e-3, 600)
    fx, fy, _ = emp.empirical_forces(A, B, FN, MU, G, NU, s, 0.5 * s, law=law, coefficients=cc)
    F = np.hypot(fx, fy)
    assert np.all(np.diff(F) >= 0) and F.max() <= MU * FN * (1 + 1e-12)


def test_johnson_vermeulen_law_value():
    """The published law 1 - (1 - tau)³ (the seed's printed Eq. 19 would give tau³)."""
    phi, _ = emp.phi_psi(A, B, NU)
    xi = 0.5 * 3 * MU * FN * phi / (math.pi * A * B * G)   # tau = 0.5
    fx, _, tau = emp.empirical_forces(A, B, FN, MU, G, NU, xi, 0.0, law="johnson_vermeulen",
                                      coefficients="elliptic")
    assert tau == pytest.approx(0.5, rel=1e-12)
    assert -fx / (MU * FN) == pytest.approx(1 - 0.5**3, rel=1e-12)


def test_against_contact_exact_creep_curve():
    """tractcurv series 1 (exact half-space, pure xi, 30 creepages): measured max |error| in
    FX/(mu FN): Kalker 1968 with Kalker's coefficients (Eq. 20) 0.003, with the elliptic
    coefficients 0.016; Johnson-Vermeulen with Kalker's coefficients 0.038, as published
    (elliptic) 0.068.  Bounds just above these measurements guard the implementation."""
    steps = [s for s in reference_cases()["tractcurv"]["steps"] if s.get("series") == 1]
    xi = np.array([s["inputs"]["loading"]["CKSI_xi"] for s in steps])
    ref = np.array([s["outputs"]["FX_over_muFN"] for s in steps])
    bounds = {("kalker", "kalker"): 0.004, ("kalker", "elliptic"): 0.018,
              ("johnson_vermeulen", "kalker"): 0.04, ("johnson_vermeulen", "elliptic"): 0.07}
    for (law, cc), bound in bounds.items():
        fx, _, _ = emp.empirical_forces(A, B, FN, MU, G, NU, xi, 0.0, law=law, coefficients=cc)
        assert np.abs(fx / (MU * FN) - ref).max() < bound, (law, cc)


def test_solve_dispatch_and_options():
    r = emp.solve(problem("empirical", xi=1e-3, phi=1e-4))
    assert r.theory == "empirical" and r.extra["law"] == "kalker" and r.extra["creep_coefficients"] == "kalker"
    assert math.isnan(r.MZ) and "ignored" in r.extra["note_spin"]
    fx, _, _ = emp.empirical_forces(A, B, FN, MU, G, NU, 1e-3, 0.0)
    assert r.FX == pytest.approx(fx, rel=1e-12)
    r = emp.solve(problem("johnson_vermeulen", xi=1e-3))
    assert r.extra["law"] == "johnson_vermeulen" and r.extra["creep_coefficients"] == "elliptic"
    r2 = emp.solve(problem("johnson_vermeulen", xi=1e-3, model={"creep_coefficients": "kalker"}))
    assert r2.FX != r.FX
    assert r.summary()["MZ"] is None
    with pytest.raises(InputError, match="creep_coefficients"):
        emp.solve(problem("empirical", xi=1e-3, model={"creep_coefficients": "nope"}))
