"""A model added from outside the package: Hertz's closed form for a circular contact.

The whole model is this module: its declaration (:data:`MODEL`, one :class:`~conformal.registry.Model`
call with its option, capabilities and memory) and its ``solve(problem) -> Result``.  It is added
with one registry line, ``MODELS.with_model(example_model.MODEL)`` (tests/unit/test_registry.py).
Inside the package the same module (as conformal/theories/circular_hertz.py) is added with one
``Model(..., solve="conformal.theories.circular_hertz:solve")`` line in ``registry.MODELS``, in a
copy of the package (tests/unit/test_registry.py).

Equal curvatures A = B = 1/(2R) (a sphere on a plane, relative radius R) under a normal force N
(Johnson 1985, eqs. 4.22-4.23 with the contact modulus E* = G/(1-nu) of the combined constants)::

    a = (3 N R / (4 E*))^(1/3),    p0 = 3 N / (2 pi a²),    approach = a² / R
"""
from __future__ import annotations

import math

from conformal.errors import InputError
from conformal.registry import Model, Option
from conformal.result import Result


def solve(problem) -> Result:
    """The circular Hertz contact of ``problem`` (quadratic geometry, prescribed normal force)."""
    hz = problem.require_hertz('theory "circular_hertz"')
    limit = problem.model.options.get("max_ellipticity", 1e-9)
    if abs(hz.A - hz.B) > limit * (hz.A + hz.B):
        raise InputError(f"[model] theory: circular_hertz needs A = B, got A = {hz.A:g}, B = {hz.B:g}")
    if problem.normal_force is None:
        raise InputError("[load] normal_force: circular_hertz needs the normal force")
    R = 1.0 / (2.0 * hz.A)
    N = problem.normal_force
    a = (3.0 * N * R / (4.0 * problem.material.E_star)) ** (1.0 / 3.0)
    return Result(theory="circular_hertz", FN=N, FX=0.0, FY=0.0, MZ=0.0, a=a, b=a,
                  pmax=3.0 * N / (2.0 * math.pi * a * a), approach=a * a / R)


MODEL = Model("circular_hertz", "Hertz's closed form for a circular contact (Johnson 1985, eqs. 4.22-4.23)",
              options=(Option("max_ellipticity", "float", 1e-9, "", "largest |A - B| / (A + B) accepted",
                              minimum=0.0),),
              bytes_per_element=0.0, solve=solve)
