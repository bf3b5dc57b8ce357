"""Time integration of the wheelset model with scipy's integrators, history and summary.

:func:`simulate` steps one of :mod:`scipy.integrate`'s solvers (``[simulation] method``, default
RK45 with rtol 1e-3) from the static equilibrium at ``initial_lateral``/``initial_yaw``, samples
the state every ``output_step`` seconds from the solver's dense output, and evaluates the contact
quantities there.  Runs longer than two seconds of wall time print a progress line on stderr.

>>> from conformal.dynamics.scene import EXAMPLE, scene_from_dict
>>> import tomllib
>>> d = tomllib.loads(EXAMPLE)
>>> d["simulation"].update(t_end=0.02, initial_lateral=2.0)
>>> d["track"]["irregularity"]["amplitude"] = 0.0
>>> r = simulate(scene_from_dict(d), table_step=0.5, table_range=3.0)
>>> len(r.history["t"]), round(float(r.history["y"][0]), 6)
(21, 2.0)
"""
from __future__ import annotations

import csv
import json
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import integrate

from conformal.dynamics.model import SIDES, WheelsetModel, build_model, equilibrium
from conformal.dynamics.scene import VehicleScene
from conformal.errors import ConvergenceError, InputError
from conformal.files import open_atomic, write_text

PER_WHEEL = ("xi", "eta", "phi", "a", "b", "FN", "FX", "FY", "FZ", "y_contact")
COLUMNS = ("t", "y", "yaw") + tuple(f"{s}_{q}" for s in SIDES for q in PER_WHEEL) \
    + ("z", "roll", "right_FN_flange", "left_FN_flange")
SOLVERS = {"RK45": integrate.RK45, "RK23": integrate.RK23, "DOP853": integrate.DOP853,
           "Radau": integrate.Radau, "BDF": integrate.BDF, "LSODA": integrate.LSODA}


#: the most integrator steps per output row (the seed's wheelset takes fewer than 1)
MAX_STEPS_PER_ROW = 200


def history_rows(t_end: float, output_step: float) -> int:
    """Rows of a run's history: one per output_step from 0 to t_end."""
    return int(math.floor(t_end / output_step + 1e-9)) + 1


def history_bytes(t_end: float, output_step: float, n_state: int = 8) -> float:
    """Memory (bytes) of a run's history: the states and the output columns, 8 bytes each per row."""
    return float(t_end / output_step + 1.0) * 8.0 * (n_state + len(COLUMNS))


def check_history_memory(t_end: float, output_step: float, n_state: int = 8) -> None:
    """Refuse ([simulation] t_end, InputError) a run whose history would take more than half of the
    memory available, before anything is allocated."""
    from conformal.scene import available_memory

    need = history_bytes(t_end, output_step, n_state)
    avail = available_memory()
    if avail is not None and need > 0.5 * avail:
        raise InputError(f"[simulation] t_end: {t_end:g} s at output_step = {output_step:g} s is "
                         f"{t_end / output_step + 1:.3g} output rows (about {need / 2**30:.3g} GiB "
                         f"of history), more than half of the {avail / 2**30:.3g} GiB available; shorten "
                         "t_end or raise output_step")


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """History (column -> array, see :data:`COLUMNS`), summary dict and the final state."""

    history: dict
    summary: dict
    final_state: np.ndarray = field(repr=False)


class _Progress:
    def __init__(self, total: float, enabled: bool):
        self.total, self.enabled, self.t0, self.last = total, enabled, time.perf_counter(), 0.0

    def update(self, t: float, done: bool = False) -> None:
        if not self.enabled:
            return
        now = time.perf_counter() - self.t0
        if (now > 2.0 and now - self.last > 0.5) or (done and self.last > 0):
            self.last = now
            frac = min(t / self.total, 1.0) if self.total > 0 else 1.0
            bar = "#" * int(30 * frac)
            print(f"\rsimulate [{bar:<30}] t = {t:.3f}/{self.total:.3f} s  {now:.1f} s wall", end="",
                  file=sys.stderr, flush=True)
            if done:
                print(file=sys.stderr)


def integrate_model(model: WheelsetModel, X0: np.ndarray, t_end: float, *, method: str = "RK45",
                    rtol: float = 1e-3, atol: float = 1e-7, output_step: float = 1e-3,
                    progress: bool = False, max_step: float = np.inf) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Integrate from X0 over [0, t_end]; returns output times, states (n, 8), steps, RHS calls."""
    if method not in SOLVERS:
        raise InputError(f"[simulation] method: unknown integrator {method!r}; one of {', '.join(SOLVERS)}")
    # absolute tolerances per component: atol for y (m) and psi (rad), atol/10 for z and phi (the
    # contact overlap, ~65 um, follows them), x10 for the velocities
    scale = np.array([1e-3, 1e-4, 1e-4, 1e-3, 1e-2, 1e-3, 1e-3, 1e-2])
    solver = SOLVERS[method](model.rhs, 0.0, np.asarray(X0, float), t_end, rtol=rtol, atol=atol * scale / 1e-3,
                             max_step=max_step)
    check_history_memory(t_end, output_step, X0.size)
    n_out = history_rows(t_end, output_step)
    times = output_step * np.arange(n_out)
    states = np.empty((n_out, X0.size))
    states[0] = X0
    k, steps = 1, 0
    max_steps = MAX_STEPS_PER_ROW * n_out
    bar = _Progress(t_end, progress)
    while solver.status == "running":
        if steps >= max_steps:       # a stiff model (damping = 1e300) shrinks the steps without end
            raise ConvergenceError(f"wheelset dynamics: the integrator took {steps} steps by t = {solver.t:.4g} s "
                                   f"(step {solver.step_size:.3g} s; at most {MAX_STEPS_PER_ROW} per output_step): "
                                   "a stiff model ([contact] damping, [vehicle] stiffnesses) or [simulation] "
                                   "rtol/atol too small; try method = \"Radau\"")
        msg = solver.step()
        if solver.status == "failed":
            why = msg
            try:
                model.contacts(solver.t, solver.y)
            except ConvergenceError as exc:      # the wheelset left the contact table
                why = str(exc)
            raise ConvergenceError(f"wheelset dynamics: the integrator stopped at t = {solver.t:.4f} s: {why}")
        steps += 1
        if k < n_out and times[k] <= solver.t:
            dense = solver.dense_output()
            while k < n_out and times[k] <= solver.t:
                states[k] = dense(times[k])
                k += 1
        bar.update(solver.t)
    bar.update(t_end, done=True)
    return times[:k], states[:k], steps, int(solver.nfev)


def decay_rate(t: np.ndarray, y: np.ndarray, t_from: float = 0.0) -> float | None:
    """Exponential decay rate (1/s, > 0 = decaying) of the peaks of |y - mean| after t_from, from a
    least-squares line through ln(peak) versus time; None with fewer than three peaks."""
    sel = t >= t_from
    t, y = t[sel], y[sel]
    if t.size < 5:
        return None
    d = np.abs(y - (y[-1] if abs(y[-1]) < 1e-9 else 0.0))
    i = np.nonzero((d[1:-1] > d[:-2]) & (d[1:-1] >= d[2:]) & (d[1:-1] > 1e-6))[0] + 1
    if i.size < 3:
        return None
    slope = np.polyfit(t[i], np.log(d[i]), 1)[0]
    return float(-slope)


def simulate(scene: VehicleScene, *, progress: bool = False, table_step: float | None = None,
             table_range: float | None = None, model: WheelsetModel | None = None) -> SimulationResult:
    """Simulate the scene's wheelset from its static equilibrium.

    Parameters
    ----------
    scene : VehicleScene
        The vehicle scene (:func:`conformal.dynamics.scene.load_vehicle_scene`).
    progress : bool
        Print a progress line on stderr when the run takes longer than two seconds.
    table_step, table_range : float, optional
        Override the contact table's grid (mm); default: the scene's ``[contact]`` keys.
    model : WheelsetModel, optional
        A model built before (reuses its contact table).

    Returns
    -------
    SimulationResult
        ``history`` (the columns of :data:`COLUMNS`, one row per ``output_step``), ``summary``
        (max lateral displacement, decay rate, wall time, steps, ...) and the final state.

    Examples
    --------
    >>> from conformal.dynamics.scene import EXAMPLE, scene_from_dict
    >>> import tomllib
    >>> d = tomllib.loads(EXAMPLE)
    >>> d["simulation"].update(t_end=0.01)
    >>> r = simulate(scene_from_dict(d), table_step=0.5, table_range=2.0)
    >>> round(r.summary["max_right_FZ"] / 49000.0, 2)      # the wheel carries W
    1.0
    """
    t0 = time.perf_counter()
    sim = scene.simulation
    check_history_memory(sim.t_end, sim.output_step)
    model = model or build_model(scene, table_step=table_step, table_range=table_range)
    X0 = equilibrium(model, sim.initial_lateral / 1000.0, sim.initial_yaw)
    t_setup = time.perf_counter() - t0
    t1, c1 = time.perf_counter(), time.process_time()
    times, states, steps, nfev = integrate_model(model, X0, sim.t_end, method=sim.method, rtol=sim.rtol,
                                                 atol=sim.atol, output_step=sim.output_step, progress=progress)
    t_int, cpu_int = time.perf_counter() - t1, time.process_time() - c1
    hist = {c: np.empty(len(times)) for c in COLUMNS}      # filled row by row: no list of dicts
    for i, (t, X) in enumerate(zip(times, states)):
        r = model.outputs(t, X)
        for c in COLUMNS:
            hist[c][i] = r[c]
    wall = time.perf_counter() - t0
    irr = scene.track.irregularity
    t_exc = (irr.start + irr.wavelength / 1000.0) / model.V if (irr.amplitude and model.V > 0) else 0.0
    flange = (hist["right_FN_flange"] > 0) | (hist["left_FN_flange"] > 0)
    summary = {
        "scene": scene.name, "speed": model.V, "creep_model": model.creep_name, "t_end": float(times[-1]),
        "max_lateral_displacement": float(np.max(np.abs(hist["y"]))),
        "max_yaw": float(np.max(np.abs(hist["yaw"]))),
        "decay_rate": decay_rate(times, hist["y"], t_exc),
        "decay_from": t_exc,
        "final_lateral_displacement": float(hist["y"][-1]),
        "max_right_FZ": float(np.max(hist["right_FZ"])), "max_right_FY": float(np.max(np.abs(hist["right_FY"]))),
        "flange_contact_time": float(flange.sum() * sim.output_step),
        "wall_s": wall, "integration_wall_s": t_int, "setup_wall_s": t_setup,
        "wall_per_simulated_s": t_int / max(float(times[-1]), 1e-12),
        "cpu_per_simulated_s": cpu_int / max(float(times[-1]), 1e-12),
        "steps": steps, "rhs_evaluations": nfev, "method": sim.method, "rtol": sim.rtol,
        "table_step_mm": model.table.step, "table_build_s": model.table.build_s,
        "rolling_radius_m": model.r0,
    }
    return SimulationResult(hist, summary, states[-1])


def write_outputs(result: SimulationResult, out: str | Path) -> list[Path]:
    """history.csv and summary.json in the folder ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    h = result.history
    with open_atomic(out / "history.csv", "w", newline="", encoding="utf-8") as fh:   # whole rows or none
        w = csv.writer(fh)
        w.writerow(COLUMNS)
        for i in range(len(h["t"])):
            w.writerow([f"{h[c][i]:.9g}" for c in COLUMNS])
    write_text(out / "summary.json", json.dumps(result.summary, indent=2) + "\n")
    return [out / "history.csv", out / "summary.json"]
