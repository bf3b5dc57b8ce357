"""The models by name: ``[model] theory`` -> the function ``solve(problem) -> Result`` that solves
one planar contact problem.

What each model is, reads and accepts is declared in :mod:`conformal.registry`, together with
where its solve function is (``Model(..., solve="conformal.theories.hertz:solve")``); this module
loads those functions (:data:`SOLVE` is derived from the declarations, not written out).  A layer
below the wheel-rail cases (conformal.cases) and above the solvers and theories: the import
contract sees each declared module as an import of this one (tests/unit/test_architecture.py adds
them to the import graph), so a model module above this layer is refused.

>>> SOLVE["hertz"].__module__, tuple(SOLVE) == MODELS.names
('conformal.theories.hertz', True)
"""
from __future__ import annotations

import importlib
import time
from collections.abc import Iterator, Mapping
from dataclasses import replace
from functools import lru_cache
from typing import Callable

from conformal.errors import InputError
from conformal.problem import ContactProblem
from conformal.registry import LINE_CONTACT, MODELS, Registry
from conformal.result import Result


@lru_cache(maxsize=None)
def _load(entry: str) -> Callable[[ContactProblem], Result]:
    module, _, name = entry.partition(":")
    return getattr(importlib.import_module(module), name)


def load_solve(solve: str | Callable | None, theory: str = "") -> Callable[[ContactProblem], Result]:
    """The function a :class:`~conformal.registry.Model` names: ``"module:function"`` is imported
    (once), a function is returned as it is.

    Parameters
    ----------
    solve : str or callable
        ``Model.solve``: ``"conformal.theories.hertz:solve"`` or the function itself.
    theory : str
        The model's name, for the message when it declares no solve function.

    Returns
    -------
    callable
        ``solve(problem) -> Result``.
    """
    if solve is None:
        raise InputError(f"[model] theory: model {theory!r} declares no solve function")
    return _load(solve) if isinstance(solve, str) else solve


class _DeclaredSolves(Mapping):
    """The solve function of each model of a registry by name, each module imported when its
    function is first asked for: a process that solves with one theory does not import the
    others (the FE contact model alone pulls in the meshing modules)."""

    def __init__(self, registry: Registry):
        self._registry = registry

    def __getitem__(self, theory: str) -> Callable[[ContactProblem], Result]:
        if theory not in self._registry:
            raise KeyError(theory)
        return load_solve(self._registry[theory].solve, theory)

    def __iter__(self) -> Iterator[str]:
        return iter(self._registry.names)

    def __len__(self) -> int:
        return len(self._registry.names)


#: the solve function of each registered model, loaded from its declaration (conformal.registry.MODELS)
#: on first use
SOLVE: Mapping[str, Callable[[ContactProblem], Result]] = _DeclaredSolves(MODELS)


def solve_function(theory: str, registry: Registry = MODELS) -> Callable[[ContactProblem], Result]:
    """The solve function ``theory``'s declaration names (``Model.solve``, :func:`load_solve`)."""
    if theory not in registry:
        raise InputError(f"[model] theory: must be one of {', '.join(registry.names)}, got {theory!r}")
    return load_solve(registry[theory].solve, theory)


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
        from conformal.solvers import line

        solve = line.solve
    t0 = time.perf_counter()
    result = solve(problem)
    return replace(result, wall_s=time.perf_counter() - t0)


def combine(results: list[Result], theory: str) -> Result:
    """Totals over several patches: :meth:`conformal.result.Result.combined`."""
    return Result.combined(results, theory)
