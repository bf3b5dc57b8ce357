"""Jobs: sweeps, FE items and the parallel runner (local processes or Dask).

The planning of a precomputation (which wheel-rail grids a sweep needs) is
:mod:`conformal.cases.precompute`; this module runs the items: ``conformal precompute SCENE.toml
--sweep shift=0:10:0.5`` computes the FE influence numbers of every grid into the cache
(:mod:`conformal.influence.cache`).  Items already in the cache are skipped, so an interrupted job
only redoes what is missing; an item that fails leaves nothing in the cache.  Ctrl-C stops the
workers within seconds; what finished stays.

Items run in parallel in local processes (default), in a local Dask cluster
(``--scheduler local``) or on an existing Dask cluster (``--scheduler tcp://host:8786``; its
workers must see the same cache folder, e.g. set CONFORMAL_CACHE to a shared path).  Dask is
optional (``pip install "conformal[dask]"``).

>>> parse_sweep("shift=0:1:0.5")
Sweep(key='shift', values=(0.0, 0.5, 1.0))
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field
from functools import partial
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
            if not all(math.isfinite(v) for v in parts):
                raise InputError(f"--sweep: start, stop and step must be finite numbers, got {spec!r}")
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


def compute_item(item: Item, cache_folder: str) -> dict:
    """Worker: compute one body into the cache (BLAS single-threaded: the workers share the cores);
    returns its statistics (not the kernel).  An entry that cannot be written fails the item
    (CacheWriteError): computing it was the job."""
    from conformal._threads import single_threaded_blas
    from conformal.influence.fe import cached_body_influence

    t0 = time.perf_counter()
    with single_threaded_blas():
        r = cached_body_influence(item.body, item.patch, item.G, item.nu, item.settings, cache=cache_folder,
                                  strict_cache=True)
    return {"label": item.label, "wall_s": time.perf_counter() - t0, "dofs": r.stats.get("dofs"),
            "cache_hit": bool(r.stats.get("cache_hit", False))}


class _Progress:
    def __init__(self, total: int, enabled: bool, desc: str = "FE influence", unit: str = "body"):
        self.bar = None
        self.total, self.n, self.enabled = total, 0, enabled
        if enabled:
            try:
                from tqdm import tqdm

                self.bar = tqdm(total=total, unit=unit, desc=desc, file=sys.stderr)
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


def _stop_pool(ex) -> None:
    """Ctrl-C: drop the queued items and end the worker processes now (an item in progress is lost;
    finished items are already in the cache, written atomically)."""
    procs = list(getattr(ex, "_processes", {}).values())
    ex.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=5)
        if p.is_alive():
            p.kill()


def run(items: list[Item], *, cache_folder: str, workers: int = 1, scheduler: str | None = None,
        progress: bool = True) -> JobReport:
    """Compute every item that is not cached yet (in parallel); failures are collected."""
    todo = [it for it in items if not it.cached]
    rep = run_tasks(partial(_compute_into, cache_folder), todo, [it.label for it in todo], workers=workers,
                    scheduler=scheduler, progress=progress)
    rep.planned, rep.skipped = len(items), len(items) - len(todo)
    return rep


def _compute_into(cache_folder: str, item: Item) -> dict:
    return compute_item(item, cache_folder)


def run_tasks(func: Callable, tasks: list, labels: list[str], *, workers: int = 1, scheduler: str | None = None,
              progress: bool = True, on_result: Callable | None = None, desc: str = "FE influence",
              unit: str = "body") -> JobReport:
    """Run ``func(task)`` for every task: in this process (``workers <= 1``), in a pool of
    ``workers`` spawned processes, or on Dask (``scheduler``: "local" for a LocalCluster of
    ``workers`` processes, or a scheduler address).  ``on_result(task, value)`` is called in
    this process as each task finishes (e.g. to write its output); a task that raises is counted
    in ``failed`` with its error (ConformalError only in-process, where other exceptions, e.g.
    KeyboardInterrupt, propagate) and the others go on.  ``func`` must be picklable (a module-level
    function or a functools.partial of one) for the parallel paths.  Ctrl-C (KeyboardInterrupt)
    ends the worker processes within seconds and propagates; finished tasks keep their output.
    """
    rep = JobReport(planned=len(tasks))
    t0 = time.perf_counter()
    bar = _Progress(len(tasks), progress, desc=desc, unit=unit)
    try:
        if not tasks:
            return rep
        if scheduler:
            client, cluster = _dask_client(scheduler, workers)
            try:
                from dask.distributed import as_completed

                futs = {client.submit(func, t, pure=False): (t, lab) for t, lab in zip(tasks, labels)}
                try:
                    _collect(futs, as_completed(futs), rep, bar, on_result)
                except KeyboardInterrupt:
                    client.cancel(list(futs), force=True)
                    raise
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
        elif workers <= 1:
            for t, lab in zip(tasks, labels):
                try:
                    value = func(t)
                    if on_result is not None:
                        on_result(t, value)
                    rep.done += 1
                except ConformalError as exc:
                    rep.failed.append((lab, str(exc)))
                bar.update(lab)
        else:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor, as_completed as cf_completed

            # spawn: gmsh and MKL threads do not survive fork safely; one gmsh model per process
            ex = ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"))
            try:
                futs = {ex.submit(func, t): (t, lab) for t, lab in zip(tasks, labels)}
                _collect(futs, cf_completed(futs), rep, bar, on_result)
            except BaseException:       # Ctrl-C (or an error of the pool): end the workers now
                _stop_pool(ex)
                raise
            ex.shutdown(wait=True)
    finally:
        bar.close()
        rep.wall_s = time.perf_counter() - t0
    return rep


def _collect(futures: dict, completed, rep: "JobReport", bar, on_result: Callable | None = None) -> None:
    """Wait for parallel tasks (Dask or process-pool futures -> (task, label)) as they complete;
    count each as done or failed with its error (one task's failure does not stop the others)."""
    for fut in completed:
        task, label = futures[fut]
        try:
            value = fut.result()
            if on_result is not None:
                on_result(task, value)
            rep.done += 1
        except Exception as exc:  # noqa: BLE001 - reported per task
            rep.failed.append((label, f"{type(exc).__name__}: {exc}"))
        bar.update(label)
