"""Dispatch: solve a scene with the model it names and return one :class:`Result`.

Every model module exposes ``solve(problem: ContactProblem) -> Result``.  A scene with several
contact patches returns the sum of the patches' forces with the patches listed in ``patches``.

The API's ``conformal.solve(scene, **overrides)`` (a plain function of the package,
:func:`conformal.api.solve`) is :func:`solve` here: a scene, a TOML path or a dict with
``section__key=value`` overrides.  (Until version 0.1 this module was ``conformal.solve``.)

>>> import conformal
>>> r = conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
...                      "load": {"normal_force": 1e4}}, model__theory="hertz")
>>> r.theory, round(r.FN)
('hertz', 10000)
"""
from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

from conformal.problem import ContactProblem, problems_from_scene  # noqa: F401
from conformal.result import Result
from conformal._threads import single_threaded_blas
from conformal.scene import MIN_CONTACT_ELEMENTS, Scene, as_scene, scene_warnings

# the models by name live in conformal.models (below the wheel-rail cases); kept here for callers
from conformal.models import SOLVE, combine, solve_problem  # noqa: E402,F401


def solve_scene(scene: Scene, *, warm=None) -> Result:
    """Solve a validated scene with the model it names.

    Planar scenes give one contact problem (:func:`conformal.problem.problems_from_scene`) solved
    by the model of ``[model] theory`` (:mod:`conformal.models`); wheel-rail scenes go through the
    wheel-rail cases (:func:`conformal.cases.solve_wheel_rail`).  BLAS is single-threaded for the
    duration (:mod:`conformal._threads`); the scene's warnings join the result's ``warnings``.

    Parameters
    ----------
    scene : Scene
    warm : conformal.cases.wheelrail.WarmStart, optional
        A wheel-rail scene only: the warm start of a neighbouring position (a sequence of wheelset
        positions, e.g. a CONTACT deck's cases), passed to :func:`conformal.cases.solve_wheel_rail`.

    Returns
    -------
    Result
        With ``wall_s`` the wall time of the whole solve.

    Examples
    --------
    >>> from conformal.scene import scene_from_dict
    >>> s = scene_from_dict({"geometry": {"kind": "hertz", "a": 6.0, "b": 6.0},
    ...                      "load": {"normal_force": 1e5}, "model": {"theory": "hertz"}})
    >>> round(solve_scene(s).a, 6)
    6.0
    """
    t0 = time.perf_counter()
    with single_threaded_blas():
        if scene.geometry.kind == "wheel_rail":  # patches in their own frames, track-frame totals
            from conformal.cases import solve_wheel_rail

            out = solve_wheel_rail(scene, warm=warm)
        elif scene.history:  # [[history]]: steps with memory (seed Eqs. 39-40); the last step's result
            out = _solve_history(scene)
        else:
            problems = problems_from_scene(scene)
            results = [solve_problem(p) for p in problems]
            out = results[0] if len(results) == 1 else Result.combined(results, scene.model.theory)
    warnings = scene_warnings(scene) + out.warnings + result_warnings(scene, out)
    if warnings:
        out = replace(out, extra=dict(out.extra, warnings=list(dict.fromkeys(warnings))))
    return replace(out, wall_s=time.perf_counter() - t0)


def result_warnings(scene: Scene, result: Result) -> list[str]:
    """Warnings about a result that the models do not give themselves: a contact area of fewer
    than MIN_CONTACT_ELEMENTS grid elements (too coarse to resolve the tractions; names the grid
    key that sets the element size), and a result that did not converge without saying why."""
    out = []
    parts = [p for p in (result.patches or (result,)) if p.field is not None]
    for k, p in enumerate(parts):
        n = p.field.n_contact
        if 0 < n < MIN_CONTACT_ELEMENTS:
            g = scene.grid
            if scene.geometry.kind == "wheel_rail" and getattr(scene.geometry, "element_size", None):
                key = "[geometry] element_size"
            elif g.explicit:
                key = "[grid] dx, dy"
            else:
                key = f"[grid] scale (= {g.scale:g}) or n (= {g.n})"
            where = f"patch {k + 1}: " if len(parts) > 1 else ""
            out.append(f"{where}the contact area covers only {n} grid element{'s' if n != 1 else ''}, too few "
                       f"to resolve the tractions (at least {MIN_CONTACT_ELEMENTS}); refine the grid: {key}")
    if not result.converged and not any("converge" in w for w in result.warnings):
        out.append(f"not converged within [model] maxit = {scene.model.maxit} iterations, tol = "
                   f"{scene.model.tol:g}: the numbers are not a solution")
    return out


def _solve_history(scene: Scene) -> Result:
    """A ``[[history]]`` scene: the steps solved in order by :func:`conformal.solvers.history.
    solve_history` from the scene's load; the result is the last step's, with ``history`` (one
    summary per applied step) in its extra fields (the JSON's ``history`` list)."""
    from conformal.solvers.history import solve_history

    problem = problems_from_scene(scene)[0]
    h = solve_history(problem, list(scene.history))
    last = h.steps[-1]
    extra = dict(last.extra, **h.to_dict())
    earlier = [f"[[history]] step {k}: {w}" for k, r in enumerate(h.steps[:-1], 1) for w in r.warnings]
    if earlier:   # warnings of the earlier steps (non-convergence, contact at the grid border) join the last's
        extra["warnings"] = list(dict.fromkeys(earlier + list(last.extra.get("warnings", []))))
    return replace(last, converged=all(r.converged for r in h.steps), extra=extra)


def solve(scene: Any, **overrides: Any) -> Result:
    """``conformal.solve``: a validated scene (:func:`conformal.scene.as_scene`) solved by
    :func:`solve_scene`; see :func:`conformal.api.solve`."""
    return solve_scene(as_scene(scene, **overrides))
