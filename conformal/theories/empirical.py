"""Empirical creep-force laws: Kalker 1968 (seed Eqs. 18, 20) and Johnson-Vermeulen 1964 (Eq. 19).

Both laws give the total creep force from the longitudinal and lateral creepages only (no spin,
no spin moment) through a normalised creepage

    tau = sqrt(xi'² + eta'²).

Normalisations ("creep coefficients"):

* ``"elliptic"`` (seed Eq. 18, Vermeulen & Johnson 1964): xi' = pi a b G xi / (3 mu N phi),
  eta' = pi a b G eta / (3 mu N psi) with phi, psi from the complete elliptic integrals B, C, D
  of modulus g = sqrt(1 - (short/long)²)::

      a <= b:  phi = B - nu (D - C),           psi = B - nu (a/b)² C
      a >= b:  phi = [D - nu (D - C)] (b/a),   psi = (D - nu C) (b/a)

  For a circle phi = pi (4 - 3nu)/16, psi = pi (4 - nu)/16 (Johnson 1958).
* ``"kalker"`` (seed Eq. 20 for Kalker's law): xi' = G a b C11 xi / (s0 mu N),
  eta' = G a b C22 eta / (s0 mu N), with s0 = f'(0) the initial slope of the law
  (3 pi/4 for Kalker's f1, which gives exactly Eq. 20's 4 G a b C11/(3 pi mu N); 3 for
  Johnson-Vermeulen), so that both laws have the slope of linear theory at small creepage.

Laws (forces on body 1, opposite to the creepage: xi > 0 gives FX < 0):

* Kalker 1968 (seed Eq. 18): F/(mu N) = -[f1(tau) e1 + f2(tau) e2] for tau <= 1, -e2 beyond,
  f1 = 3/2 tau acos(tau), f2 = 1 - (1 + tau²/2) sqrt(1 - tau²), e1 = (xi', eta')/tau,
  e2 = (xi, eta)/|(xi, eta)|.  Initial slope: |F| = (3 pi/4) mu N tau.
* Johnson-Vermeulen 1964: F/(mu N) = -[1 - (1 - tau)³] e1 for tau <= 1, -e1 beyond.
  (The seed's printed Eq. 19, "[1 - (1 - tau³)]", is a typo: that would be tau³, with zero
  slope at the origin; the published law is 1 - (1 - tau)³.)  Initial slope: |F| = 3 mu N tau.

So with the elliptic coefficients the small-creepage slopes are dFX/dxi = -(pi²/4) G a b/phi
(Kalker 1968) and -pi G a b/phi (JV): "effective C11" pi²/(4 phi) and pi/phi.  For a circle
with nu = 0.25 these are 3.87 and 4.92 against Kalker's exact C11 = 4.12 (-6 %, +19 %).

>>> round(phi_psi(1.0, 1.0, 0.25)[0] * 16 / 3.141592653589793, 6)   # 4 - 3 nu
3.25
"""
from __future__ import annotations

import math

import numpy as np
from scipy.special import ellipe, ellipk, ellipkm1

from conformal.errors import InputError
from conformal.theories import coefficients as coef

LAWS = ("kalker", "johnson_vermeulen")
COEFFICIENTS = ("kalker", "elliptic")
SLOPE = {"kalker": 3.0 * math.pi / 4.0, "johnson_vermeulen": 3.0}  # f'(0) of each law


def elliptic_integrals(k):
    """B, C, D of seed Eq. 18 for the ratio k = short/long semi-axis (modulus g² = 1 - k²).

    B = int cos²/Delta, D = int sin²/Delta, C = int cos² sin²/Delta³ over (0, pi/2) with
    Delta = sqrt(1 - g² sin²): closed forms in K(m), E(m), m = g², with series near m = 0.
    """
    k = np.asarray(k, dtype=float)
    m = 1.0 - k * k
    small = m < 1e-3
    ms = np.where(small, 0.5, m)  # placeholder where the series is used
    K = np.where(k < 0.5, ellipkm1(k * k), ellipk(ms))
    E = ellipe(ms)
    D = (K - E) / ms
    B = K - D
    C = (D - B) / ms
    h = math.pi / 2  # series (m -> 0), truncation error O(m^4) < 1e-12
    Ds = h * (0.5 + 3 * m / 16 + 15 * m**2 / 128 + 175 * m**3 / 2048)
    Bs = h * (0.5 + m / 16 + 3 * m**2 / 128 + 25 * m**3 / 2048)
    Cs = h * (1 / 8 + 3 * m / 32 + 75 * m**2 / 1024 + 245 * m**3 / 4096)
    return np.where(small, Bs, B), np.where(small, Cs, C), np.where(small, Ds, D)


def phi_psi(a, b, nu):
    """Vermeulen-Johnson/Kalker 1968 coefficients phi (longitudinal), psi (lateral), seed Eq. 18."""
    a, b, nu = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (a, b, nu)))
    k = np.minimum(a, b) / np.maximum(a, b)
    B, C, D = elliptic_integrals(k)
    narrow = a <= b  # a <= b: g = sqrt(1 - (a/b)²)
    phi = np.where(narrow, B - nu * (D - C), (D - nu * (D - C)) * k)
    psi = np.where(narrow, B - nu * k * k * C, (D - nu * C) * k)
    if phi.ndim == 0:
        return float(phi), float(psi)
    return phi, psi


def normalised_creepages(a, b, FN, mu, G, nu, xi, eta, *, law="kalker", coefficients="kalker"):
    """xi', eta' of the chosen law and normalisation (arrays broadcast)."""
    if coefficients == "elliptic":
        phi, psi = phi_psi(a, b, nu)
        s = np.pi * a * b * G / (3.0 * mu * FN)
        return s * xi / phi, s * eta / psi
    if coefficients == "kalker":
        c11, c22, _ = coef.coefficient_arrays(np.asarray(a) / np.asarray(b), nu)
        s = G * a * b / (SLOPE[law] * mu * FN)
        return s * c11 * xi, s * c22 * eta
    raise InputError(f"[model] creep_coefficients: must be one of {', '.join(COEFFICIENTS)}, "
                     f"got {coefficients!r}")


def empirical_forces(a, b, FN, mu, G, nu, xi, eta, *, law="kalker", coefficients="kalker"):
    """FX, FY (N, on body 1) and tau of an empirical law; arrays broadcast (vectorised).

    >>> fx, fy, tau = empirical_forces(6.0, 6.0, 1e5, 0.3, 82000.0, 0.25, 1.0, 0.0)
    >>> round(fx / (0.3 * 1e5), 12), abs(fy)      # far beyond saturation
    (-1.0, 0.0)
    """
    if law not in LAWS:
        raise InputError(f"[model] theory: empirical law must be one of {', '.join(LAWS)}, got {law!r}")
    a, b, FN, mu, G, nu, xi, eta = np.broadcast_arrays(
        *(np.asarray(v, dtype=float) for v in (a, b, FN, mu, G, nu, xi, eta)))
    xn, yn = normalised_creepages(a, b, FN, mu, G, nu, xi, eta, law=law, coefficients=coefficients)
    tau = np.hypot(xn, yn)
    t = np.minimum(tau, 1.0)
    safe = np.where(tau > 0, tau, 1.0)
    e1x, e1y = xn / safe, yn / safe
    if law == "kalker":
        r = np.hypot(xi, eta)
        rs = np.where(r > 0, r, 1.0)
        e2x, e2y = xi / rs, eta / rs
        f1 = 1.5 * t * np.arccos(t)                       # seed Eq. 18
        f2 = 1.0 - (1.0 + 0.5 * t * t) * np.sqrt(1.0 - t * t)
        fx, fy = f1 * e1x + f2 * e2x, f1 * e1y + f2 * e2y
    else:
        f = 1.0 - (1.0 - t) ** 3                          # JV 1964 (seed Eq. 19, typo corrected)
        fx, fy = f * e1x, f * e1y
    FX, FY = -mu * FN * fx, -mu * FN * fy
    if np.ndim(FX) == 0:
        return float(FX), float(FY), float(tau)
    return FX, FY, tau


def solve(problem):
    """Kalker 1968 (theory "empirical") or Johnson-Vermeulen (theory "johnson_vermeulen").

    ``[model] creep_coefficients`` = "kalker" (default for "empirical": seed Eq. 20, the slope of
    linear theory) or "elliptic" (default for "johnson_vermeulen": the published 1964 law).
    MZ is not part of these theories and is reported as NaN (JSON null); spin is ignored.
    """
    from conformal.result import Result
    from conformal.theories.linear import material_notes, steady_hertz

    theory = problem.model.theory
    law = "johnson_vermeulen" if theory == "johnson_vermeulen" else "kalker"
    hz = steady_hertz(problem, theory)
    kin, mat, mu = problem.kinematics, problem.material, problem.friction.mu
    if kin.fx_rel is not None or kin.fy_rel is not None:
        raise InputError(f"[kinematics] fx_rel: theory \"{theory}\" takes creepages (xi, eta); "
                         "prescribed forces are supported by theory \"linear\"")
    cc = problem.model.options.get("creep_coefficients", "elliptic" if law == "johnson_vermeulen" else "kalker")
    if cc not in COEFFICIENTS:
        raise InputError(f"[model] creep_coefficients: must be one of {', '.join(map(repr, COEFFICIENTS))}, "
                         f"got {cc!r}")
    FX, FY, tau = empirical_forces(hz.a, hz.b, hz.FN, mu, mat.G, mat.nu, kin.xi, kin.eta,
                                   law=law, coefficients=cc)
    phi_, psi_ = phi_psi(hz.a, hz.b, mat.nu)
    extra = {"law": law, "creep_coefficients": cc, "tau": tau, "phi_coefficient": phi_,
             "psi_coefficient": psi_, "F_over_muFN": math.hypot(FX, FY) / (mu * hz.FN),
             "note_MZ": "the spin moment is not part of this theory (MZ = null)",
             **material_notes(problem)}
    if kin.phi != 0.0:
        extra["note_spin"] = "spin phi is not part of this theory and was ignored"
        extra["warnings"] = [f"theory {theory!r} ignores the spin phi = {kin.phi:.4g} rad/mm (FX, FY without "
                             "it, no MZ); use fastsim or exact"]
    return Result(theory=theory, FN=hz.FN, FX=FX, FY=FY, MZ=math.nan, a=hz.a, b=hz.b, pmax=hz.pmax,
                  approach=hz.approach, xi=kin.xi, eta=kin.eta, phi=kin.phi, extra=extra)
