"""The models by name: ``[model] theory`` -> the function ``solve(problem) -> Result`` that solves
one planar contact problem.

What each model is, reads and accepts is declared in :mod:`conformal.registry`; its solve function
is bound here, one line per model, from the model modules imported explicitly (so that the import
contract sees every dependency).  A layer below the wheel-rail cases (conformal.cases) and above
the solvers and theories.

>>> sorted(SOLVE) == sorted(MODELS.names)
True
"""
from __future__ import annotations

import time
from dataclasses import replace
from typing import Callable

from conformal.errors import InputError
from conformal.fe_contact import problems as fe_contact
from conformal.problem import ContactProblem
from conformal.registry import LINE_CONTACT, MODELS, Registry
from conformal.result import Result
from conformal.solvers import conformal as conformal_solver
from conformal.solvers import exact, line
from conformal.tables import model as table
from conformal.theories import empirical, fastsim, hertz, linear

#: the solve function of each registered model (conformal.registry.MODELS)
SOLVE: dict[str, Callable[[ContactProblem], Result]] = {
    "hertz": hertz.solve,
    "linear": linear.solve,
    "empirical": empirical.solve,
    "johnson_vermeulen": empirical.solve,
    "fastsim": fastsim.solve,
    "exact": exact.solve,
    "conformal": conformal_solver.solve,
    "table": table.solve,
    "fe_contact": fe_contact.solve,
}


def solve_function(theory: str, registry: Registry = MODELS) -> Callable[[ContactProblem], Result]:
    """The solve function of ``theory``: the registered model's own (``Model.solve``) or the
    package's (:data:`SOLVE`)."""
    if theory not in registry:
        raise InputError(f"[model] theory: must be one of {', '.join(registry.names)}, got {theory!r}")
    model = registry[theory]
    return model.solve if model.solve is not None else SOLVE[theory]


def solve_problem(problem: ContactProblem, registry: Registry = MODELS) -> Result:
    """Solve one contact problem with ``problem.model.theory``; wall_s is measured here.
    ``registry``: the models to look the theory up in (a registry extended by
    :meth:`conformal.registry.Registry.with_model` solves a model outside the package)."""
    if getattr(problem.kinematics, "direction", 1) == -1:   # rolling in -x: mirrored, solved, mapped back
        from conformal.solvers.direction import mirrored, unmirror

        return unmirror(solve_problem(mirrored(problem), registry), problem)
    theory = problem.model.theory
    solve = solve_function(theory, registry)
    if problem.line_contact:   # [geometry] B = 0: plane strain on the half-plane
        if not registry.accepts(theory, LINE_CONTACT):
            raise InputError(f"[model] theory: line contact ([geometry] B = 0) is solved by theory "
                             f"{registry.quoted(LINE_CONTACT)} (half-plane influence numbers), not {theory!r}")
        solve = line.solve
    t0 = time.perf_counter()
    result = solve(problem)
    return replace(result, wall_s=time.perf_counter() - t0)


def combine(results: list[Result], theory: str) -> Result:
    """Totals over several patches: :meth:`conformal.result.Result.combined`."""
    return Result.combined(results, theory)
