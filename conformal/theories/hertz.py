"""Hertz theory of non-conformal contact by complete elliptic integrals (Hertz 1882; Johnson 1985, §4.2;
seed Eqs. 16-17 for the combined constants).

The undeformed distance is h = A x² + B y² (A, B > 0, 1/mm); the pressure is the semi-ellipsoid
p = p0 sqrt(1 - x²/a² - y²/b²).  With e² = 1 - (b/a)² for a >= b and K(e), E(e) the complete
elliptic integrals of the first and second kind (Johnson eqs. 4.39-4.40):

    A = p0 b (K - E) / (E* a² e²),   B = p0 b ((a/b)² E - K) / (E* a² e²),   approach = p0 b K / E*

and FN = 2/3 pi a b p0, with the contact modulus E* = G/(1-nu) of the combined constants.

>>> from conformal.materials import Material
>>> h = hertz_from_curvatures(0.01, 0.01, Material.identical(200.0, 0.42), normal_force=9.1954)
>>> round(h.a, 4), round(h.pmax, 4), round(h.approach, 4)
(1.0, 4.3905, 0.02)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

from scipy.special import ellipe, ellipk

from conformal.errors import InputError
from conformal.materials import Material


@dataclass(frozen=True)
class HertzContact:
    """A Hertzian contact: semi-axes a (x) and b (y), curvatures A, B, load, approach, pmax."""

    a: float
    b: float
    A: float
    B: float
    FN: float
    approach: float
    pmax: float
    E_star: float

    @property
    def area(self) -> float:
        return math.pi * self.a * self.b

    @property
    def c(self) -> float:
        """Effective radius sqrt(ab) of the contact ellipse."""
        return math.sqrt(self.a * self.b)

    def pressure(self, x, y):
        """Hertz pressure at (x, y) (arrays allowed), zero outside the ellipse."""
        import numpy as np

        r2 = 1.0 - (np.asarray(x) / self.a) ** 2 - (np.asarray(y) / self.b) ** 2
        return self.pmax * np.sqrt(np.clip(r2, 0.0, None))


def _shape_functions(k: float) -> tuple[float, float, float]:
    """For the aspect ratio k = b/a <= 1 return (kA, kB, kd) with
    A = p0/(E* a) kA, B = p0/(E* a) kB, approach = p0 a / E* kd."""
    m = 1.0 - k * k  # e²
    if m < 1e-7:  # series of (K - E)/m and K about m = 0 (avoid cancellation)
        K = math.pi / 2 * (1 + m / 4)
        k_minus_e = math.pi / 4 * m * (1 + 3 * m / 8)
        E = K - k_minus_e
    else:
        K, E = float(ellipk(m)), float(ellipe(m))
        k_minus_e = K - E
    if m < 1e-7:
        kA = k * math.pi / 4 * (1 + 3 * m / 8)
        # B/A -> 1 as m -> 0; (E/k² - K)/m = (pi/4)(1 + 9m/8) + O(m²)
        kB = k * math.pi / 4 * (1 + 9 * m / 8)
    else:
        kA = k * k_minus_e / m
        kB = k * (E / (k * k) - K) / m
    return kA, kB, k * K


#: the largest curvature ratio :func:`aspect_from_curvatures` resolves (semi-axis ratio 1e6)
MAX_CURVATURE_RATIO = 1e9


@lru_cache(maxsize=256)
def aspect_from_curvatures(A: float, B: float) -> float:
    """Semi-axis ratio a/b of the Hertz ellipse for curvatures A (x) and B (y).  Remembered for the
    last 256 pairs (a root search per pair): the passes of a wheel-rail balance ask again for the
    curvatures of a patch kept across heights (35 pairs for 76 problems of a 21-position sweep)."""
    if A == B:
        return 1.0
    lo, hi = min(A, B), max(A, B)
    ratio = hi / lo  # >= 1: curvature of the short axis over that of the long axis
    if not ratio <= MAX_CURVATURE_RATIO:      # outside the bracket of the root search below
        raise InputError(f"Hertz: the curvature ratio max(A, B)/min(A, B) = {ratio:.3g} exceeds {MAX_CURVATURE_RATIO:g} "
                         f"(a/b beyond 1e6: a line contact; give B = 0), got A = {A:g}, B = {B:g}")

    def f(log_k):
        kA, kB, _ = _shape_functions(math.exp(log_k))
        return math.log(kB / kA) - math.log(ratio)

    # k = b/a from 1 down to 1e-6 covers curvature ratios beyond 1e9
    from scipy.optimize import brentq   # here: scipy.optimize costs 0.2-0.3 s to import

    k = math.exp(brentq(f, math.log(1e-6), 0.0, xtol=1e-15, rtol=1e-15))
    return 1.0 / k if A < B else k  # A < B: curvature in x smaller, ellipse long in x


def hertz_from_curvatures(A: float, B: float, material: Material, *, normal_force: float | None = None,
                          approach: float | None = None) -> HertzContact:
    """Solve the Hertz problem for curvatures A, B and a prescribed normal force or approach."""
    if not (A > 0 and B > 0 and math.isfinite(A) and math.isfinite(B)):
        raise InputError(f"Hertz: curvatures A, B must be finite and > 0, got A={A!r}, B={B!r}")
    if (normal_force is None) == (approach is None):
        raise InputError("Hertz: give exactly one of normal_force or approach")
    Es = material.E_star
    a_over_b = aspect_from_curvatures(A, B)
    # work in the frame where 'long' >= 'short'
    k = min(a_over_b, 1.0 / a_over_b)
    kA, kB, kd = _shape_functions(k)
    curv_long = min(A, B)  # curvature along the long axis
    # curv_long = p0/(E* L) kA with p0 = 3FN/(2 pi L S), S = k L  ->  L³ = 3 FN kA / (2 pi k E* curv_long)
    if normal_force is not None:
        if not (normal_force > 0 and math.isfinite(normal_force)):
            raise InputError(f"Hertz: normal_force must be > 0, got {normal_force!r}")
        L = (3 * normal_force * kA / (2 * math.pi * k * Es * curv_long)) ** (1 / 3)
        p0 = 3 * normal_force / (2 * math.pi * L * L * k)
    else:
        if not (approach > 0 and math.isfinite(approach)):
            raise InputError(f"Hertz: approach must be > 0, got {approach!r}")
        # approach = p0 L kd / E* and curv_long = p0 kA / (E* L)  ->  L² = approach kA / (kd curv_long)
        L = math.sqrt(approach * kA / (kd * curv_long))
        p0 = curv_long * Es * L / kA
    S = k * L
    a, b = (L, S) if A <= B else (S, L)
    FN = 2.0 / 3.0 * math.pi * a * b * p0
    return HertzContact(a=a, b=b, A=A, B=B, FN=FN, approach=p0 * L * kd / Es, pmax=p0, E_star=Es)


def hertz_from_semiaxes(a: float, b: float, material: Material, *, normal_force: float | None = None,
                        approach: float | None = None) -> HertzContact:
    """Inverse Hertz problem: the curvatures A, B that give semi-axes a, b under the load."""
    if not (a > 0 and b > 0 and math.isfinite(a) and math.isfinite(b)):
        raise InputError(f"Hertz: semi-axes a, b must be finite and > 0, got a={a!r}, b={b!r}")
    if (normal_force is None) == (approach is None):
        raise InputError("Hertz: give exactly one of normal_force or approach")
    Es = material.E_star
    L, S = max(a, b), min(a, b)
    kA, kB, kd = _shape_functions(S / L)
    if normal_force is not None:
        if not (normal_force > 0 and math.isfinite(normal_force)):
            raise InputError(f"Hertz: normal_force must be > 0, got {normal_force!r}")
        p0 = 3 * normal_force / (2 * math.pi * a * b)
    else:
        if not (approach > 0 and math.isfinite(approach)):
            raise InputError(f"Hertz: approach must be > 0, got {approach!r}")
        p0 = approach * Es / (L * kd)
    c_long, c_short = p0 * kA / (Es * L), p0 * kB / (Es * L)
    A, B = (c_long, c_short) if a >= b else (c_short, c_long)
    FN = 2.0 / 3.0 * math.pi * a * b * p0
    return HertzContact(a=a, b=b, A=A, B=B, FN=FN, approach=p0 * L * kd / Es, pmax=p0, E_star=Es)


def solve(problem):
    """Hertz as a model: the normal solution only (no tangential tractions)."""
    from conformal.result import Result

    hz = problem.require_hertz("theory \"hertz\"")
    return Result(theory="hertz", FN=hz.FN, FX=0.0, FY=0.0, MZ=0.0, a=hz.a, b=hz.b, pmax=hz.pmax,
                  approach=hz.approach, xi=problem.kinematics.xi, eta=problem.kinematics.eta,
                  phi=problem.kinematics.phi, extra={"A": hz.A, "B": hz.B, "area": hz.area})
