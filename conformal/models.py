"""The models by name: ``[model] theory`` -> the module whose ``solve(problem) -> Result`` solves one
planar contact problem (imported when first asked for).

A layer below the wheel-rail cases (conformal.cases) and above the solvers and theories.
"""
from __future__ import annotations

import importlib
import time
from dataclasses import replace

from conformal.errors import InputError
from conformal.problem import ContactProblem
from conformal.result import Result

MODELS = {
    "hertz": "conformal.theories.hertz",
    "linear": "conformal.theories.linear",
    "empirical": "conformal.theories.empirical",
    "johnson_vermeulen": "conformal.theories.empirical",
    "fastsim": "conformal.theories.fastsim",
    "exact": "conformal.solvers.exact",
    "conformal": "conformal.solvers.conformal",
    "table": "conformal.tables.model",
    "fe_contact": "conformal.fe_contact.problems",
}


def solve_problem(problem: ContactProblem) -> Result:
    """Solve one contact problem with ``problem.model.theory``; wall_s is measured here."""
    if getattr(problem.kinematics, "direction", 1) == -1:   # rolling in -x: mirrored, solved, mapped back
        from conformal.solvers.direction import mirrored, unmirror

        return unmirror(solve_problem(mirrored(problem)), problem)
    module = importlib.import_module(MODELS[problem.model.theory])
    if problem.info.get("line_contact"):   # [geometry] B = 0: plane strain on the half-plane
        if problem.model.theory != "exact":
            raise InputError(f"[model] theory: line contact ([geometry] B = 0) is solved by theory \"exact\" "
                             f"(half-plane influence numbers), not {problem.model.theory!r}")
        module = importlib.import_module("conformal.solvers.line")
    t0 = time.perf_counter()
    result = module.solve(problem)
    return replace(result, wall_s=time.perf_counter() - t0)


def combine(results: list[Result], theory: str) -> Result:
    """Totals over several patches: forces add; a, b, pmax, approach of the most loaded patch.
    Forces are summed as given, i.e. all patches must report forces in one common frame."""
    main = max(results, key=lambda r: r.FN)
    return Result(theory=theory, FN=sum(r.FN for r in results), FX=sum(r.FX for r in results),
                  FY=sum(r.FY for r in results), MZ=sum(r.MZ for r in results), a=main.a, b=main.b,
                  pmax=max(r.pmax for r in results), approach=main.approach, xi=main.xi, eta=main.eta,
                  phi=main.phi, converged=all(r.converged for r in results),
                  wall_s=sum(r.wall_s for r in results), patches=tuple(results))
