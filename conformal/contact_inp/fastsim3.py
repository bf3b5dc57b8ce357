"""CONTACT's simplified theory (M = 2, 3 with the traction bound B = 2, 3) onto the project's
FASTSIM (conformal.theories.fastsim, ``discretisation = "contact"``, which reproduces CONTACT's
grid FASTSIM for given flexibilities).

The flexibilities are CONTACT's (user guide, "Flexibilities of the simplified theory"):

* M = 2: one flexibility FLX for all three creepages;
* M = 3: Kalker's three, L1 = 8a/(3 G C11), L2 = 8a/(3 G C22), L3 = pi a sqrt(a/b)/(4 G C23)
  (seed Eq. 27), with CONTACT's creep coefficients -- Kalker's Table E.3 interpolated linearly
  in g = min(a/b, b/a) between the rows 0.1 apart and quadratically in nu through 1/C at nu = 0,
  0.25, 0.5, the slender asymptotes below g = 0.101 -- and, for prescribed creepages, the
  blending approach (Vollebregt 2022, "1 flexibility"): with the characteristic creepages
  xi_c = mu FN/(c^2 G C11), eta_c = mu FN/(c^2 G C22), c^2 = ab, the weight
  w = min(1, sqrt((xi^2 + eta^2)/(xi_c^2 + eta_c^2))/3) moves each L_i towards the combined
  L_x = (xi^2 + eta^2 + (phi f)^2)/(xi^2/L1 + eta^2/L2 + (phi f)^2/L3), f = 3 pi a/32:
  L_i' = (1 - w) L_i + w L_x.

Modified FASTSIM's reduction factor k = k0 (alpha + (1 - alpha)/(1 + beta eps)) (user guide eq.
``eq:k_modif_fs``) is supported for alpha = 1 (then L/k0); the slip-area measure eps for
alpha < 1 is not specified in the guide: such a case is refused.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from conformal.theories import coefficients as coef


@lru_cache(maxsize=1)
def _table() -> dict:
    rows = coef._read_rows(coef.TABLE_FILE, ("C11", "C22", "C23"))
    out: dict = {}
    for branch, g, nu, vals in rows:
        out[(branch, int(round(10 * g)), nu)] = vals
    return out


def contact_creep_coefficients(a_over_b: float, nu: float) -> tuple[float, float, float]:
    """C11, C22, C23 interpolated as CONTACT's simplified theory does (module docstring).

    >>> [round(c, 4) for c in contact_creep_coefficients(1.0, 0.25)]
    [4.12, 3.67, 1.47]
    """
    if a_over_b <= 1.0:
        g, branch = a_over_b, "a<=b"
    else:
        g, branch = 1.0 / a_over_b, "a>b"
    if g < 0.101:
        c = coef.asymptotic_coefficients(a_over_b, nu)
        return float(c[0]), float(c[1]), float(c[2])
    tab = _table()
    irow = int(10.0 * g - 0.005)
    fac = 10.0 * g - irow
    c = {n: [fac * tab[(branch, irow + 1, n)][k] + (1 - fac) * tab[(branch, irow, n)][k] for k in range(3)]
         for n in (0.0, 0.25, 0.5)}
    inv = [(nu - 0.25) * (nu - 0.5) * 8.0 / c[0.0][k] - (nu - 0.5) * nu * 16.0 / c[0.25][k]
           + nu * (nu - 0.25) * 8.0 / c[0.5][k] for k in range(3)]
    return 1.0 / inv[0], 1.0 / inv[1], 1.0 / inv[2]


def contact_flexibilities(a: float, b: float, G: float, nu: float, *, FN: float, mu: float,
                          xi: float, eta: float, phi: float, blend: bool = True) -> tuple[float, float, float]:
    """L1, L2, L3 (mm³/N) of CONTACT's M = 3 (module docstring)."""
    aob = a / b
    c11, c22, c23 = contact_creep_coefficients(aob, nu)
    L = np.array([8 * a / (3 * c11 * G), 8 * a / (3 * c22 * G), math.pi * a * math.sqrt(aob) / (4 * c23 * G)])
    if not blend:
        return tuple(float(v) for v in L)
    cc = math.sqrt(a * b)
    xi_c = mu * FN / (cc**2 * G * c11)
    eta_c = mu * FN / (cc**2 * G * c22)
    f = (math.pi * a**2 / 4.0) / (8.0 * a / 3.0)
    num = xi**2 + eta**2 + (phi * f) ** 2
    den = xi**2 / L[0] + eta**2 / L[1] + (phi * f) ** 2 / L[2]
    lx = num / (den if abs(den) >= 1e-14 else 1e-14)
    w = min(1.0, max(0.0, max(1e-10, math.sqrt((xi**2 + eta**2) / (xi_c**2 + eta_c**2))) / 3.0))
    return tuple(float((1 - w) * v + w * lx) for v in L)
