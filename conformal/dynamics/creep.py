"""Creep-force models for the wheelset, a small registry: name -> factory(settings) -> evaluator.

Every evaluator takes arrays (one entry per active contact patch) and returns FX, FY (N) and
MZ (N mm) on the wheel in the patch frame (t1 = rolling direction, t2 = n x t1, n = inner rail
normal), for creepages of the wheel relative to the rail (seed Eq. 61); the contact theories'
own sign convention (forces on body 1, creepage of body 1) gives the same numbers because the
laws are odd in (xi, eta, phi).

* ``linear``: Kalker's linear theory (seed Eq. 13), C11..C33 from the contact table (no saturation);
* ``empirical``: Kalker's empirical law (seed Eqs. 18, 20; no spin, MZ = 0);
* ``fastsim``: FASTSIM in batch form (:func:`conformal.theories.fastsim.fastsim_batch`),
  flexibilities of seed Eq. 27 from the table's coefficients;
* ``table``: the creep-force table of :mod:`conformal.tables` (``[contact] table = PATH``,
  default: the table shipped with the package);
* ``none``: no tangential forces (frictionless; for the energy and static checks).

>>> import numpy as np
>>> f = make_creep_model("linear", mu=0.5, G=82000.0, nu=0.28)
>>> FX, FY, MZ = f(np.array([6.0]), np.array([6.0]), np.array([1e5]), np.array([1e-4]), np.array([0.0]),
...                np.array([0.0]), np.array([[4.15, 3.67, 1.56, 0.9]]))
>>> round(float(FX[0]) / (-82000.0 * 36 * 4.15 * 1e-4), 12)
1.0
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from conformal.errors import InputError
from conformal.theories.empirical import empirical_forces
from conformal.theories.fastsim import fastsim_batch

# evaluator(a, b, FN, xi, eta, phi, coeffs (n, 4) = C11, C22, C23, C33) -> FX, FY, MZ
CreepEvaluator = Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]]


def _linear(mu, G, nu, **_):
    def f(a, b, FN, xi, eta, phi, c):
        ab = a * b
        s = np.sqrt(ab)
        FX = -G * ab * c[:, 0] * xi                                    # seed Eq. 13
        FY = -G * ab * (c[:, 1] * eta + s * c[:, 2] * phi)
        MZ = G * ab * s * (c[:, 2] * eta - s * c[:, 3] * phi)
        return FX, FY, MZ
    return f


def _empirical(mu, G, nu, **_):
    def f(a, b, FN, xi, eta, phi, c):
        FX, FY, _ = empirical_forces(a, b, FN, mu, G, nu, xi, eta)
        return np.atleast_1d(FX), np.atleast_1d(FY), np.zeros_like(np.atleast_1d(a))
    return f


def _fastsim(mu, G, nu, n=12, **_):
    def f(a, b, FN, xi, eta, phi, c):
        L1 = 8.0 * a / (3.0 * G * c[:, 0])                             # seed Eq. 27
        L2 = 8.0 * a / (3.0 * G * c[:, 1])
        L3 = np.pi * a * np.sqrt(a / b) / (4.0 * G * c[:, 2])
        r = fastsim_batch(a, b, FN, mu, xi, eta, phi, L=(L1, L2, L3), nx=n, ny=n)
        return r.FX, r.FY, r.MZ
    return f


def _none(**_):
    def f(a, b, FN, xi, eta, phi, c):
        z = np.zeros_like(a)
        return z, z, z
    return f


def _table(mu, G, nu, table=None, **_):
    try:
        from conformal.tables import evaluate, load_table
    except ImportError:       # pragma: no cover - the tables package is part of this project
        raise InputError("[contact] creep_model: \"table\" needs the creep-force tables (conformal.tables) "
                         "with [contact] table = PATH") from None
    t = load_table(table)

    def f(a, b, FN, xi, eta, phi, c):
        FX, FY, MZ = evaluate(t, a, b, FN, mu, G, nu, xi, eta, phi, outside="clamp")
        return np.asarray(FX), np.asarray(FY), np.asarray(MZ)
    return f


REGISTRY: dict[str, Callable[..., CreepEvaluator]] = {
    "linear": _linear, "empirical": _empirical, "fastsim": _fastsim, "table": _table, "none": _none,
}


def make_creep_model(name: str, *, mu: float, G: float, nu: float, **options) -> CreepEvaluator:
    """The evaluator of creep model ``name`` (see module docstring); InputError for unknown names."""
    if name not in REGISTRY:
        raise InputError(f"[contact] creep_model: must be one of {', '.join(REGISTRY)}, got {name!r}")
    return REGISTRY[name](mu=mu, G=G, nu=nu, **options)
