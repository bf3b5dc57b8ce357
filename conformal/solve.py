"""Dispatch: solve a scene with the model it names and return one :class:`Result`.

Every model module exposes ``solve(problem: ContactProblem) -> Result``.  A scene with several
contact patches returns the sum of the patches' forces with the patches listed in ``patches``.
"""
from __future__ import annotations

import importlib
import time
from dataclasses import replace

from conformal.problem import ContactProblem, problems_from_scene
from conformal.result import Result
from conformal.scene import Scene

MODELS = {
    "hertz": "conformal.theories.hertz",
    "linear": "conformal.theories.linear",
    "empirical": "conformal.theories.empirical",
    "johnson_vermeulen": "conformal.theories.empirical",
    "fastsim": "conformal.theories.fastsim",
    "exact": "conformal.solvers.exact",
    "conformal": "conformal.solvers.conformal",
}


def solve_problem(problem: ContactProblem) -> Result:
    """Solve one contact problem with ``problem.model.theory``; wall_s is measured here."""
    module = importlib.import_module(MODELS[problem.model.theory])
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


def solve_scene(scene: Scene) -> Result:
    t0 = time.perf_counter()
    if scene.geometry.kind == "wheel_rail":  # patches in their own frames, track-frame totals
        from conformal.geometry.wheelrail import solve_wheel_rail

        return replace(solve_wheel_rail(scene), wall_s=time.perf_counter() - t0)
    problems = problems_from_scene(scene)
    results = [solve_problem(p) for p in problems]
    out = results[0] if len(results) == 1 else combine(results, scene.model.theory)
    return replace(out, wall_s=time.perf_counter() - t0)
