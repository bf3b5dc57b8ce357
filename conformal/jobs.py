"""Precomputation jobs: FE influence numbers for a sweep of wheel-rail positions (DESIGN.md §6).

``conformal precompute SCENE.toml --sweep shift=0:10:0.5`` places the wheelset at every lateral
shift of the sweep, finds the curved grids the solver will use (conformal.geometry: one per patch;
theory "conformal": one strip over all patches of the wheel), and computes the FE influence
numbers of the rail and the wheel body of every grid into the cache
(conformal.influence.cache).  Items already in the cache are skipped, so an interrupted job only
redoes what is missing; an item that fails leaves nothing in the cache.

Items run in parallel in local processes (default), in a local Dask cluster
(``--scheduler local``) or on an existing Dask cluster (``--scheduler tcp://host:8786``; its
workers must see the same cache folder, e.g. set CONFORMAL_CACHE to a shared path).  Dask is
optional (``pip install "conformal[dask]"``).

>>> parse_sweep("shift=0:1:0.5")
Sweep(key='shift', values=(0.0, 0.5, 1.0))
"""
from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass, field, replace
from typing import Callable


from conformal.errors import ConformalError, InputError

# sweep keys -> [geometry] field
SWEEP_KEYS = {"shift": "lateral_shift", "lateral_shift": "lateral_shift", "yaw": "yaw", "roll": "roll"}
MAX_ITEMS = 10_000


@dataclass(frozen=True)
class Sweep:
    key: str
    values: tuple[float, ...]


def parse_sweep(text: str) -> Sweep:
    """``KEY=start:stop:step`` (stop included when on the step) or ``KEY=v1,v2,...``."""
    if "=" not in text:
        raise InputError(f"--sweep: expected KEY=start:stop:step, got {text!r}")
    key, spec = (t.strip() for t in text.split("=", 1))
    if key not in SWEEP_KEYS:
        raise InputError(f"--sweep: unknown key {key!r} (known: {', '.join(sorted(SWEEP_KEYS))})")
    try:
        if ":" in spec:
            parts = [float(v) for v in spec.split(":")]
            if len(parts) != 3:
                raise ValueError
            a, b, h = parts
            if h == 0 or (b - a) / h < 0:
                raise InputError(f"--sweep: step {h:g} does not lead from {a:g} to {b:g}")
            n = int(math.floor((b - a) / h + 1e-9)) + 1
            if n > MAX_ITEMS:
                raise InputError(f"--sweep: {n} positions, more than {MAX_ITEMS}")
            values = tuple(round(a + k * h, 12) for k in range(n))
        else:
            values = tuple(float(v) for v in spec.split(",") if v.strip())
    except InputError:
        raise
    except ValueError:
        raise InputError(f"--sweep: cannot read {spec!r} (use start:stop:step or v1,v2,...)") from None
    if not values or not all(math.isfinite(v) for v in values):
        raise InputError(f"--sweep: no finite values in {spec!r}")
    return Sweep(key, values)


@dataclass(frozen=True, eq=False)
class Item:
    """One FE body computation of a job."""

    label: str
    body: object          # conformal.meshing.bodies.BodyModel
    patch: object         # conformal.meshing.bodies.StripPatch
    G: float
    nu: float
    settings: object      # conformal.influence.fe.FESettings
    key: str
    cached: bool = False


@dataclass
class JobReport:
    planned: int = 0
    skipped: int = 0
    done: int = 0
    failed: list = field(default_factory=list)
    positions_failed: list = field(default_factory=list)
    wall_s: float = 0.0
    dry_run: bool = False

    def summary(self) -> str:
        if self.dry_run:
            parts = [f"{self.planned} FE bodies: {self.skipped} already cached, "
                     f"{self.planned - self.skipped} to compute"]
        else:
            parts = [f"{self.planned} FE bodies: {self.skipped} already cached, {self.done} computed"]
        if self.failed:
            parts.append(f"{len(self.failed)} failed")
        if self.positions_failed:
            parts.append(f"{len(self.positions_failed)} positions without contact grid")
        return ", ".join(parts) + f" ({self.wall_s:.1f} s)"


def _scene_at(scene, key: str, value: float):
    geo = scene.geometry
    if geo.kind != "wheel_rail":
        raise InputError("precompute: the scene's [geometry] kind must be \"wheel_rail\"")
    return replace(scene, geometry=replace(geo, **{SWEEP_KEYS[key]: value}))


def _solver_grids(scene, per_patch) -> list[tuple]:
    """The curved grids the solver of ``[model] theory`` will use, as (grid, ...) tuples: for the
    conformal theory ONE strip over every patch of the wheel
    (conformal.solvers.conformal.curved_problem_from_wheel_rail; per-patch grids would fill the
    cache with kernels it never asks for), else one grid per patch (``per_patch(scene)``)."""
    if scene.model.theory == "conformal":
        from conformal.solvers.conformal import curved_problem_from_wheel_rail

        return [(curved_problem_from_wheel_rail(scene).grid,)]
    return list(per_patch(scene))


def plan(scene, sweep: Sweep, settings=None, cache=None,
         on_position: Callable[[float, Exception], None] | None = None) -> tuple[list[Item], list]:
    """The FE items of a sweep: (items, failed positions).  Grids: those the solver of
    [model] theory will use (:func:`_solver_grids`)."""
    from conformal.geometry.wheelrail import curved_problems_from_wheel_rail
    from conformal.influence.cache import Cache
    from conformal.influence.fe import (body_key, rail_body_from_grid, scene_profiles, settings_from_options,
                                       wheel_body_from_grid)

    settings = settings or settings_from_options(scene.model.options)
    c = cache if isinstance(cache, Cache) else Cache(cache)
    m = scene.material
    items, failed, seen = [], [], set()
    for v in sweep.values:
        sc = _scene_at(scene, sweep.key, v)
        rail_pts, wheel_pts = scene_profiles(sc)
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
                items.append(Item(label, body, patch, G, nu, settings, key, c.load(key, body_key(body, patch, G, nu, settings)) is not None))
    return items, failed


def compute_item(item: Item, cache_folder: str) -> dict:
    """Worker: compute one body into the cache; returns its statistics (not the kernel)."""
    from conformal.influence.fe import cached_body_influence

    t0 = time.perf_counter()
    r = cached_body_influence(item.body, item.patch, item.G, item.nu, item.settings, cache=cache_folder)
    return {"label": item.label, "wall_s": time.perf_counter() - t0, "dofs": r.stats.get("dofs"),
            "cache_hit": bool(r.stats.get("cache_hit", False))}


class _Progress:
    def __init__(self, total: int, enabled: bool):
        self.bar = None
        self.total, self.n, self.enabled = total, 0, enabled
        if enabled:
            try:
                from tqdm import tqdm

                self.bar = tqdm(total=total, unit="body", desc="FE influence", file=sys.stderr)
            except ImportError:
                self.bar = None

    def update(self, text: str = "") -> None:
        self.n += 1
        if self.bar is not None:
            self.bar.update(1)
            if text:
                self.bar.set_postfix_str(text[-40:])
        elif self.enabled:
            print(f"[{self.n}/{self.total}] {text}", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _dask_client(scheduler: str, workers: int):
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise InputError("--scheduler: Dask is not installed; install it with pip install \"conformal[dask]\" "
                         "(or drop --scheduler to run in local processes)") from None
    if scheduler == "local":
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True)
        return Client(cluster), cluster
    try:
        return Client(scheduler, timeout="20s"), None
    except Exception as exc:
        raise ConformalError(f"--scheduler: cannot connect to {scheduler}: {exc}") from None


def run(items: list[Item], *, cache_folder: str, workers: int = 1, scheduler: str | None = None,
        progress: bool = True) -> JobReport:
    """Compute every item that is not cached yet (in parallel); failures are collected."""
    todo = [it for it in items if not it.cached]
    rep = JobReport(planned=len(items), skipped=len(items) - len(todo))
    t0 = time.perf_counter()
    bar = _Progress(len(todo), progress)
    try:
        if not todo:
            return rep
        if scheduler:
            client, cluster = _dask_client(scheduler, workers)
            try:
                from dask.distributed import as_completed

                futs = {client.submit(compute_item, it, cache_folder, pure=False): it for it in todo}
                _collect(futs, as_completed(futs), rep, bar)
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
        elif workers <= 1:
            for it in todo:
                try:
                    compute_item(it, cache_folder)
                    rep.done += 1
                except ConformalError as exc:
                    rep.failed.append((it.label, str(exc)))
                bar.update(it.label)
        else:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor, as_completed as cf_completed

            # spawn: gmsh and MKL threads do not survive fork safely; one gmsh model per process
            with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn")) as ex:
                futs = {ex.submit(compute_item, it, cache_folder): it for it in todo}
                _collect(futs, cf_completed(futs), rep, bar)
    finally:
        bar.close()
        rep.wall_s = time.perf_counter() - t0
    return rep


def _collect(futures: dict, completed, rep: "JobReport", bar) -> None:
    """Wait for parallel items (Dask or process-pool futures) as they complete; count each as done
    or failed with its error (one item's failure does not stop the others)."""
    for fut in completed:
        it = futures[fut]
        try:
            fut.result()
            rep.done += 1
        except Exception as exc:  # noqa: BLE001 - reported per item
            rep.failed.append((it.label, f"{type(exc).__name__}: {exc}"))
        bar.update(it.label)


def precompute(scene, sweep: Sweep, *, cache=None, workers: int | None = None, scheduler: str | None = None,
               progress: bool = True, dry_run: bool = False) -> JobReport:
    """Plan and run a precomputation job (see the module docstring)."""
    from conformal.influence.cache import Cache

    c = cache if isinstance(cache, Cache) else Cache(cache)
    items, failed = plan(scene, sweep, cache=c)
    if workers is None:
        workers = max(1, (os.cpu_count() or 2) // 2)
    if dry_run:
        rep = JobReport(planned=len(items), skipped=sum(it.cached for it in items), dry_run=True)
    else:
        rep = run(items, cache_folder=str(c.folder), workers=workers, scheduler=scheduler, progress=progress)
    rep.positions_failed = failed
    return rep
