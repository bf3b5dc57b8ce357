"""Kalker's linear theory of rolling contact (seed Eq. 13; Kalker 1967).

No slip anywhere (valid for vanishing creepage); forces on body 1, creepages of body 1 relative
to body 2 (CONTACT's convention, so xi > 0 gives FX < 0)::

    FX = -G a b C11 xi
    FY = -G a b C22 eta - G (ab)^1.5 C23 phi
    MZ =  G (ab)^1.5 C23 eta - G (ab)^2 C33 phi

with the combined constants G, nu of seed Eqs. 16-17 and Kalker's coefficients at (a/b, nu)
(:mod:`conformal.theories.coefficients`).  C33 is needed only when phi != 0 (or when asked);
until the exact solver has tabulated it, a spinning contact raises ConformalError.

>>> f = linear_forces(6.0, 6.0, 82000.0, 0.25, xi=1e-4)
>>> round(f.FX, 3)   # -G a b C11 xi with C11(a/b = 1, nu = 0.25) = 4.12
-1216.224
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.errors import ConformalError, InputError
from conformal.theories import coefficients as coef


@dataclass(frozen=True)
class LinearForces:
    FX: float
    FY: float
    MZ: float
    C11: float
    C22: float
    C23: float
    C33: float | None


def linear_forces(a: float, b: float, G: float, nu: float, xi: float = 0.0, eta: float = 0.0,
                  phi: float = 0.0, *, need_c33: bool | None = None) -> LinearForces:
    """Creep forces and spin moment of linear theory (seed Eq. 13).

    ``need_c33``: None (default) = only when phi != 0; True = always (MZ complete); False =
    never (MZ then lacks the -G (ab)² C33 phi term and is NaN where phi != 0).
    """
    if not (a > 0 and b > 0 and G > 0):
        raise InputError(f"linear theory: a, b, G must be > 0, got a={a}, b={b}, G={G}")
    c = coef.kalker_coefficients(a / b, nu)
    ab = a * b
    use_c33 = (phi != 0.0) if need_c33 is None else need_c33
    c33 = coef.c33(a / b, nu) if use_c33 else None
    FX = -G * ab * c.C11 * xi
    FY = -G * ab * c.C22 * eta - G * ab**1.5 * c.C23 * phi
    if c33 is not None:
        MZ = G * ab**1.5 * c.C23 * eta - G * ab**2 * c33 * phi
    else:
        MZ = G * ab**1.5 * c.C23 * eta if phi == 0.0 else math.nan
    return LinearForces(FX, FY, MZ, c.C11, c.C22, c.C23, c33)


# ----------------------------------------------------------------------------- shared checks
def steady_hertz(problem, who: str):
    """The Hertz contact of a problem for a fast theory, after the checks every fast theory
    needs: a quadratic (Hertzian) geometry and steady rolling."""
    hz = problem.require_hertz(f"theory \"{who}\"")
    if problem.kinematics.rolling != "steady":
        raise InputError(f"[kinematics] rolling: theory \"{who}\" handles steady rolling only, "
                         f"got {problem.kinematics.rolling!r} (use theory = \"exact\" for shifts)")
    for key in ("xi", "eta", "phi"):
        v = getattr(problem.kinematics, key)
        if not math.isfinite(v):
            raise InputError(f"[kinematics] {key}: must be a finite number, got {v!r}")
    return hz


def material_notes(problem) -> dict:
    """Notes for ``Result.extra`` that every fast theory shares."""
    notes = {}
    if not problem.material.quasi_identical:
        notes["note_materials"] = ("dissimilar materials (K = %.4g): the fast theories use the combined "
                                   "G, nu (seed Eqs. 16-17) and neglect the normal-tangential coupling"
                                   % problem.material.K)
    return notes


def solve(problem):
    """Linear theory as a model.  Prescribed forces (fx_rel, fy_rel) are inverted exactly.

    ``[model] require_c33 = true`` asks for the complete MZ (with C33) also when phi = 0.
    """
    from conformal.result import Result

    hz = steady_hertz(problem, "linear")
    kin, mat, mu = problem.kinematics, problem.material, problem.friction.mu
    G, nu, a, b = mat.G, mat.nu, hz.a, hz.b
    c = coef.kalker_coefficients(a / b, nu)
    xi, eta, phi = kin.xi, kin.eta, kin.phi
    if kin.fx_rel is not None:   # FX = -G a b C11 xi
        xi = -kin.fx_rel * mu * hz.FN / (G * a * b * c.C11)
    if kin.fy_rel is not None:   # FY = -G a b C22 eta - G (ab)^1.5 C23 phi
        eta = (-kin.fy_rel * mu * hz.FN - G * (a * b) ** 1.5 * c.C23 * phi) / (G * a * b * c.C22)
    require = problem.model.options.get("require_c33", False)
    if not isinstance(require, bool):
        raise InputError(f"[model] require_c33: must be true or false, got {require!r}")
    need = require or phi != 0.0
    try:
        f = linear_forces(a, b, G, nu, xi, eta, phi, need_c33=need)
    except ConformalError as exc:
        raise ConformalError(f"[kinematics] phi: linear theory with spin needs C33: {exc}") from None
    ratio = math.hypot(f.FX, f.FY) / (mu * hz.FN)
    extra = {"C11": f.C11, "C22": f.C22, "C23": f.C23, "C33": f.C33,
             "coefficients": c.source, "F_over_muFN": ratio, **material_notes(problem)}
    if ratio > 1.0:
        extra["note"] = ("linear theory exceeds the friction bound |F| <= mu FN (|F|/(mu FN) = %.3g): "
                         "the creepage is too large for it; use fastsim, empirical or exact" % ratio)
        extra["warnings"] = [extra["note"]]
    return Result(theory="linear", FN=hz.FN, FX=f.FX, FY=f.FY, MZ=f.MZ, a=a, b=b, pmax=hz.pmax,
                  approach=hz.approach, xi=xi, eta=eta, phi=phi, extra=extra)


def linear_force_arrays(a, b, G, nu, xi, eta, phi=0.0):
    """Vectorised FX, FY (no MZ) of linear theory for arrays of contacts."""
    a, b, G, nu, xi, eta, phi = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                                      for v in (a, b, G, nu, xi, eta, phi)))
    c11, c22, c23 = coef.coefficient_arrays(a / b, nu)
    ab = a * b
    return -G * ab * c11 * xi, -G * ab * c22 * eta - G * ab**1.5 * c23 * phi
