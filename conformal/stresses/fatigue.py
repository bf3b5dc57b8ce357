"""Rolling-contact-fatigue indices (issue 24, item 3).

* Surface-initiated fatigue, the shakedown map (Johnson 1989; Ekberg, Kabo & Andersson 2002,
  Fatigue Fract. Engng Mater. Struct. 25, eq. 1):
  ``FI_surf = mu_eff - 2 pi a b k / (3 FN)`` with mu_eff = sqrt(FX² + FY²) / FN and k the yield
  stress in (cyclic) shear; 3 FN / (2 pi a b) is the Hertz peak pressure p0 of the ellipse a x b,
  so FI_surf = mu_eff - k / p0: FI_surf > 0 means ratchetting of the surface layer.
* Subsurface-initiated fatigue, Dang Van's criterion (Dang Van 1989; Ekberg et al. 2002, eq. 4):
  at a material point the stress history of one rolling pass is sigma(x), x the position of the
  point relative to the load along the rolling direction.  The mesoscopic shear is the Tresca
  shear of the deviator minus its mid-value s_m (taken componentwise as (max + min) / 2 over the
  pass, the usual approximation of the centre of the smallest ball around the deviatoric path):
  tau_a(x) = principal shear of (s(x) - s_m); with sigma_h(x) = tr sigma(x) / 3 (tension positive)
  the equivalent stress is ``tau_DV = max_x [tau_a(x) + alpha_DV sigma_h(x)]`` and
  ``FI_sub = tau_DV - tau_e`` (> 0: initiation predicted).

Defaults (inputs, typical of rail and wheel steels, to be replaced by the user's material data):
k = 300 N/mm², alpha_DV = 1/3, tau_e = 300 N/mm².

>>> round(surface_index(10000.0, 3000.0, 0.0, 3.0, 2.0, 300.0), 4)   # mu_eff 0.3 - k/p0 (p0 796)
-0.077
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.errors import InputError
from conformal.stresses.invariants import hydrostatic, principal_shear

#: default yield stress in shear k (N/mm²) of the shakedown map
K_SHEAR = 300.0
#: default Dang Van hydrostatic sensitivity alpha_DV (-)
ALPHA_DV = 1.0 / 3.0
#: default shear endurance limit tau_e (N/mm²)
TAU_E = 300.0


@dataclass(frozen=True)
class FatigueParameters:
    """k (N/mm²), alpha_dv (-), tau_e (N/mm²): see the module docstring."""

    k: float = K_SHEAR
    alpha_dv: float = ALPHA_DV
    tau_e: float = TAU_E

    def __post_init__(self):
        for name in ("k", "tau_e"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"[stresses] {name}: must be a positive number of N/mm², got {v!r}")
        if not (isinstance(self.alpha_dv, (int, float)) and math.isfinite(self.alpha_dv) and self.alpha_dv >= 0):
            raise InputError(f"[stresses] alpha_dv: must be a number >= 0, got {self.alpha_dv!r}")


def surface_index(FN: float, FX: float, FY: float, a: float, b: float, k: float) -> float:
    """FI_surf = mu_eff - 2 pi a b k / (3 FN) (shakedown map); NaN without a normal force."""
    if not (FN > 0 and a > 0 and b > 0):
        return float("nan")
    return math.hypot(FX, FY) / FN - 2.0 * math.pi * a * b * k / (3.0 * FN)


def surface_index_area(FN: float, FX: float, FY: float, area: float, k: float) -> float:
    """FI_surf of the ellipse with the patch's contact area (pi a b = area): mu_eff - 2 area k / (3 FN);
    for a non-elliptic patch (or one strip over several regions) the extents a, b overstate pi a b."""
    if not (FN > 0 and area > 0):
        return float("nan")
    return math.hypot(FX, FY) / FN - 2.0 * area * k / (3.0 * FN)


def dang_van(sigma: np.ndarray, alpha_dv: float, axis: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Dang Van equivalent stress of rolling passes.

    Parameters
    ----------
    sigma : ndarray (..., 3, 3)
        Stresses; along ``axis`` (an axis of the leading dimensions) lies the rolling direction,
        so that each line along it is the history of one material point during a pass.
    alpha_dv : float

    Returns
    -------
    tau_dv : ndarray
        max over the pass of tau_a + alpha_dv sigma_h, one per line (``axis`` removed).
    at : ndarray of int
        The index along ``axis`` where the maximum occurs.
    """
    s = np.moveaxis(np.asarray(sigma, float), axis, 0)
    h = hydrostatic(s)
    dev = s - h[..., None, None] * np.eye(3)
    mid = 0.5 * (dev.max(axis=0) + dev.min(axis=0))
    tau_a = principal_shear(dev - mid[None])
    eq = tau_a + alpha_dv * h
    return eq.max(axis=0), eq.argmax(axis=0)
