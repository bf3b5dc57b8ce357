"""Analytic oracles for the tangential problem: Carter's 2-D steady rolling and Cattaneo's shift.

Small pure functions used by the tests (and by anyone checking a solver), with the signs of
CONTACT's module 3: tractions and forces act on body 1, creepages and shifts are body 1 relative
to body 2, so a positive creepage or shift gives a negative force.  Rolling is in +x: material
enters the contact at the leading edge x = +a, where the adhesion zone lies.

Sources: Johnson (1985), Contact Mechanics, §7.2 (Cattaneo-Mindlin, sphere pulled tangentially
with Q < mu P) and §8.2 (Carter 1926, 2-D rolling with traction); Kalker (1990) §5.2; the
formulas and numbers quoted in the CONTACT cases (tests/reference/contact_cases.json) (cases cattaneo and carter2d).

Carter (2-D, cylinders with combined radius R, i.e. gap h = x²/(2R), contact modulus
E* = G/(1-nu) of the combined constants, load FN per unit width):

>>> a, p0 = hertz_2d(178.9, 500.0, 82000.0 / 0.72)
>>> round(a, 4), round(p0, 2)
(1.0, 113.89)
>>> round(carter_force(-0.00024, mu=0.3, a=1.0, R=500.0), 4)     # a' = 0.6 a
0.64
>>> round(carter_adhesion_width(-0.00024, mu=0.3, a=1.0, R=500.0), 4)
0.6
>>> round(float(carter_traction(-0.01, -0.00024, mu=0.3, a=1.0, R=500.0, p0=113.89)), 2)   # CONTACT table
19.2

Cattaneo (sphere on a plane, identical materials, combined G and nu; adhesion radius theta a):

>>> round(cattaneo_force(0.5), 4)                 # Q/(mu FN) for theta = 1/2
0.875
>>> round(cattaneo_stick_ratio(0.875), 6)
0.5
>>> # CONTACT's case: FX/(mu FN) = -7/8 on the sphere (body 1) needs a positive shift
>>> round(cattaneo_shift(-0.875, mu=0.4, FN=9.1954, a=1.0, G=200.0, nu=0.42), 7)
0.0081724
>>> round(float(cattaneo_traction(0.0, -0.875, mu=0.4, a=1.0, p0=4.3905)), 4)
-0.8781
"""
from __future__ import annotations

import math

import numpy as np


# ----------------------------------------------------------------------------- Carter (2-D)
def hertz_2d(FN_per_width: float, R: float, E_star: float) -> tuple[float, float]:
    """Half-width a (mm) and peak pressure p0 (N/mm²) of 2-D Hertz contact (Johnson 1985, eq. 4.45):
    FN = pi a² E* / (4 R) per unit width, p0 = 2 FN / (pi a)."""
    a = math.sqrt(4.0 * FN_per_width * R / (math.pi * E_star))
    return a, 2.0 * FN_per_width / (math.pi * a)


def carter_adhesion_width(xi: float, *, mu: float, a: float, R: float) -> float:
    """Half-width a' of Carter's adhesion zone [a - 2a', a]: xi = -mu (a - a')/R in magnitude,
    a' = a - |xi| R / mu, zero from full slip on (|xi| >= mu a / R)."""
    return max(a - abs(xi) * R / mu, 0.0)


def carter_force(xi: float, *, mu: float, a: float, R: float) -> float:
    """FX/(mu FN) of Carter's 2-D steady rolling (Johnson 1985, eq. 8.23):
    |FX| = (1 - (a'/a)²) mu FN, directed against the creepage (xi > 0 gives FX < 0)."""
    ratio = carter_adhesion_width(xi, mu=mu, a=a, R=R) / a
    return -math.copysign(1.0 - ratio * ratio, xi) if xi != 0.0 else 0.0


def carter_traction(x, xi: float, *, mu: float, a: float, R: float, p0: float):
    """p_x(x) on body 1 (N/mm²) of Carter's solution: the full-slip traction mu p0 sqrt(1 - x²/a²)
    minus (a'/a) mu p0 sqrt(1 - ((x - d)/a')²) inside the adhesion zone, d = a - a', with the sign
    opposing the creepage."""
    x = np.asarray(x, dtype=float)
    ap = carter_adhesion_width(xi, mu=mu, a=a, R=R)
    sgn = -math.copysign(1.0, xi) if xi != 0.0 else 0.0
    full = mu * p0 * np.sqrt(np.clip(1.0 - (x / a) ** 2, 0.0, None))
    if ap > 0.0:
        d = a - ap
        full = full - (ap / a) * mu * p0 * np.sqrt(np.clip(1.0 - ((x - d) / ap) ** 2, 0.0, None))
    return sgn * full


# ----------------------------------------------------------------------------- Cattaneo (shift)
def cattaneo_force(theta: float) -> float:
    """Q/(mu FN) = 1 - theta³ for an adhesion circle of radius theta a (Johnson 1985, eq. 7.40)."""
    return 1.0 - theta ** 3


def cattaneo_stick_ratio(q: float) -> float:
    """theta = (1 - Q/(mu FN))^(1/3): adhesion radius over contact radius for |Q| < mu FN."""
    return (1.0 - abs(q)) ** (1.0 / 3.0)


def cattaneo_shift(q: float, *, mu: float, FN: float, a: float, G: float, nu: float) -> float:
    """Rigid shift (mm) of body 1 relative to body 2 for Q/(mu FN) = q (Johnson 1985, eq. 7.42 with
    the combined G, nu of two identical bodies): W = (1 - theta²) 3 mu FN (2 - nu) / (8 G a),
    i.e. the CONTACT cases (tests/reference/contact_cases.json)'s (1 - theta²) 3 mu FN / (2 pi a G) (pi/2 - nu pi/4).
    The shift has the sign of -q (a force on body 1 opposite to its shift)."""
    theta = cattaneo_stick_ratio(q)
    W = (1.0 - theta * theta) * 3.0 * mu * FN * (2.0 - nu) / (8.0 * G * a)
    return -math.copysign(W, q) if q != 0.0 else 0.0


def cattaneo_traction(r, q: float, *, mu: float, a: float, p0: float):
    """p_x(r) (N/mm²) on body 1 at distance r from the centre, for Q/(mu FN) = q in x (the small
    p_y that the exact theory adds is neglected, as by Cattaneo):
    sign(q) mu p0/a (sqrt(a² - r²) - sqrt(theta² a² - r²)) in adhesion (r <= theta a), without the
    second term in slip (theta a <= r <= a), zero outside."""
    r = np.asarray(r, dtype=float)
    theta = cattaneo_stick_ratio(q)
    outer = np.sqrt(np.clip(a * a - r * r, 0.0, None))
    inner = np.sqrt(np.clip((theta * a) ** 2 - r * r, 0.0, None))
    return math.copysign(1.0, q) * mu * p0 / a * (outer - inner)
