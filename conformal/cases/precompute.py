"""Precomputation of FE influence numbers for a sweep of wheel-rail positions.

``conformal precompute SCENE.toml --sweep shift=0:10:0.5`` places the wheelset at every lateral
shift of the sweep, finds the curved grids the solver will use (one per patch; theory
"conformal": one strip over all patches of the wheel, :mod:`conformal.cases.conformal`), and
computes the FE influence numbers of the rail and the wheel body of every grid into the cache
(:mod:`conformal.influence.cache`) with the runner of :mod:`conformal.jobs` (local processes or
Dask).  Items already in the cache are skipped, so an interrupted job only redoes what is missing.
"""
from __future__ import annotations

import os
from typing import Callable

from conformal.cases.conformal import curved_problem_from_wheel_rail, fe_profiles
from conformal.cases.wheelrail import curved_problems_from_wheel_rail
from conformal.errors import ConformalError, InputError
from conformal.influence.cache import Cache
from conformal.influence.fe import body_key, rail_body_from_grid, settings_from_options, wheel_body_from_grid
from conformal.jobs import SWEEP_KEYS, Item, JobReport, Sweep, run
from conformal.registry import CURVED_STRIP, MODELS

__all__ = ["plan", "precompute"]


def _scene_at(scene, key: str, value: float):
    geo = scene.geometry
    if geo.kind != "wheel_rail":
        raise InputError("precompute: the scene's [geometry] kind must be \"wheel_rail\"")
    return scene.with_(f"geometry.{SWEEP_KEYS[key]}", value)


def _solver_grids(scene, per_patch) -> list[tuple]:
    """The curved grids the solver of ``[model] theory`` will use, as (grid, ...) tuples: for the
    conformal theory ONE strip over every patch of the wheel
    (conformal.cases.conformal.curved_problem_from_wheel_rail; per-patch grids would fill the
    cache with kernels it never asks for), else one grid per patch (``per_patch(scene)``)."""
    if MODELS.accepts(scene.model.theory, CURVED_STRIP):
        return [(curved_problem_from_wheel_rail(scene).grid,)]
    return list(per_patch(scene))


def plan(scene, sweep: Sweep, settings=None, cache=None,
         on_position: Callable[[float, Exception], None] | None = None, *, repair: bool = True
         ) -> tuple[list[Item], list]:
    """The FE items of a sweep: (items, failed positions).  Grids: those the solver of
    [model] theory will use (:func:`_solver_grids`).  ``repair``: move unusable cache entries
    aside (False: only report them; a dry run changes nothing)."""
    settings = settings or settings_from_options(scene.model.options)
    c = cache if isinstance(cache, Cache) else Cache(cache)
    m = scene.material
    items, failed, seen = [], [], set()
    for v in sweep.values:
        sc = _scene_at(scene, sweep.key, v)
        rail_pts, wheel_pts = fe_profiles(sc)
        try:
            problems = _solver_grids(sc, curved_problems_from_wheel_rail)
        except ConformalError as exc:
            failed.append((v, str(exc)))
            if on_position:
                on_position(v, exc)
            continue
        for k, (grid, *_rest) in enumerate(problems):
            rail, rpatch = rail_body_from_grid(grid, rail_pts, name=str(sc.geometry.rail_profile))
            wheel, wpatch, _ = wheel_body_from_grid(grid, wheel_pts, name=str(sc.geometry.wheel_profile))
            for kind, body, patch, G, nu in (("rail", rail, rpatch, m.G1, m.nu1), ("wheel", wheel, wpatch, m.G2, m.nu2)):
                key = c.key(body_key(body, patch, G, nu, settings))
                if key in seen:
                    continue
                seen.add(key)
                label = f"{sweep.key}={v:g} patch {k} {kind} ({patch.n_columns}x{patch.ms})"
                cached = c.load(key, body_key(body, patch, G, nu, settings), repair=repair) is not None
                items.append(Item(label, body, patch, G, nu, settings, key, cached))
    return items, failed


def precompute(scene, sweep: Sweep, *, cache=None, workers: int | None = None, scheduler: str | None = None,
               progress: bool = True, dry_run: bool = False) -> JobReport:
    """Plan and run a precomputation job (see the module docstring)."""
    c = cache if isinstance(cache, Cache) else Cache(cache)
    items, failed = plan(scene, sweep, cache=c, repair=not dry_run)
    if workers is None:
        workers = max(1, (os.cpu_count() or 2) // 2)
    if dry_run:
        rep = JobReport(planned=len(items), skipped=sum(it.cached for it in items), dry_run=True)
    else:
        rep = run(items, cache_folder=str(c.folder), workers=workers, scheduler=scheduler, progress=progress)
    rep.positions_failed = failed
    return rep
