"""Solved lateral-shift sweeps: forces, creepages and patch data for every wheelset position.

``conformal sweep SCENE.toml --shift 0:10:0.5 --solve`` and :func:`conformal.sweep` solve the scene
at every lateral shift with its own theory and influence numbers and return one
:class:`SweepTable` (one row per shift).  The positions are solved one after the other in one
process, each starting its vertical balance from its neighbour's wheelset lowering and
tangential-to-normal ratios (:class:`conformal.cases.wheelrail.WarmStart`; the result is the same
balance to its tolerance, BALANCE_TOL of the wheel load).  FE influence numbers ([model] influence
= "fe") missing from the cache are computed first, in parallel, by the precompute machinery
(:func:`conformal.cases.precompute.precompute`).  A position that cannot be solved (no contact,
the profiles end) gets a row with its error and NaN values; the sweep goes on.

Per-patch columns ``p<k>_*`` hold the patches of a position ordered by their contact position on
the rail (planar theories: the tangent-plane patches; theory "conformal": the contact regions of
the strip, their position the middle of their rail arc-length range ``p<k>_s_rail``).
"""
from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from conformal.errors import ConformalError, InputError
from conformal.files import save_figure, write_text
from conformal.registry import CURVED_STRIP, FE_INFLUENCE, MODELS

#: totals per position: (column, unit, description)
TOTALS = (
    ("shift", "mm", "lateral wheelset shift"),
    ("FN", "N", "normal force, sum over the patches"),
    ("FX", "N", "longitudinal force, sum over the patches"),
    ("FS", "N", "lateral force in the contact planes, sum over the patches"),
    ("FX_track", "N", "longitudinal force on the rail, track frame"),
    ("FY_track", "N", "lateral force on the rail, track frame"),
    ("FZ_track", "N", "vertical force on the rail, track frame"),
    ("MZ", "N mm", "spin moment, sum over the patches"),
    ("xi", "1", "longitudinal creepage of the main patch"),
    ("eta", "1", "lateral creepage of the main patch"),
    ("phi", "1/mm", "spin creepage of the main patch"),
    ("z_ws", "mm", "wheelset height (the loaded state)"),
    ("approach", "mm", "wheelset lowering below the first touch"),
    ("contact_angle", "rad", "contact angle of the main patch (reference point)"),
    ("y_rail", "mm", "contact position on the rail profile of the main patch"),
    ("pmax", "N/mm2", "largest pressure"),
    ("n_patches", "1", "number of contact patches (conformal: contact regions)"),
    ("converged", "1", "1 when every solve converged"),
    ("wall_s", "s", "wall time of the position's solve"),
)
#: per patch (column suffix, unit, description)
PATCH = (
    ("FN", "N", "normal force"),
    ("FX", "N", "longitudinal force"),
    ("FS", "N", "lateral force in the contact plane"),
    ("contact_angle", "rad", "contact angle"),
    ("y_rail", "mm", "contact position on the rail profile (planar theories)"),
    ("s_rail", "mm", "middle of the region's rail arc-length range (theory conformal)"),
    ("pmax", "N/mm2", "largest pressure"),
)
#: two neighbouring contact positions more than this (mm per mm of shift) apart: a contact jump
JUMP_RATE = 4.0


@dataclass(frozen=True, eq=False)
class SweepTable:
    """A solved sweep: ``columns`` maps a column name to one value per shift (numpy arrays),
    ``units`` to its unit; ``errors`` holds the message of every position that could not be solved
    (None where it was), ``warnings`` those of every solve."""

    scene: str
    theory: str
    influence: str
    columns: dict[str, np.ndarray]
    units: dict[str, str]
    errors: tuple[str | None, ...]
    warnings: tuple[tuple[str, ...], ...]
    descriptions: dict[str, str] = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def __len__(self) -> int:
        return len(self.errors)

    @property
    def n_patch_columns(self) -> int:
        return sum(1 for k in self.columns if k.startswith("p") and k.endswith("_FN") and k[1:-3].isdigit())

    def rows(self) -> list[dict[str, Any]]:
        """One dict per shift (NaN as None), with ``error`` and ``warnings``."""
        out = []
        for i in range(len(self)):
            r: dict[str, Any] = {}
            for k, v in self.columns.items():
                x = v[i].item() if hasattr(v[i], "item") else v[i]
                r[k] = None if isinstance(x, float) and not math.isfinite(x) else x
            r["error"] = self.errors[i]
            r["warnings"] = list(self.warnings[i])
            out.append(r)
        return out

    def to_dict(self) -> dict[str, Any]:
        """The JSON form: scene, theory, influence, units, descriptions and the rows."""
        return {"scene": self.scene, "theory": self.theory, "influence": self.influence, "units": dict(self.units),
                "descriptions": dict(self.descriptions), "rows": self.rows()}

    def to_csv(self, path: str | Path | None = None) -> str:
        """The table as CSV, units in the header (``FN [N]``), the error of a position in the last
        column; written atomically to ``path`` when given.  Returns the text."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        names = list(self.columns)
        w.writerow([f"{k} [{self.units[k]}]" for k in names] + ["error"])
        for i in range(len(self)):
            row = []
            for k in names:
                v = self.columns[k][i]
                row.append("" if isinstance(v, float) and not math.isfinite(v) else
                           (f"{v:.9g}" if isinstance(v, (float, np.floating)) else str(v)))
            w.writerow(row + [self.errors[i] or ""])
        text = buf.getvalue()
        if path is not None:
            write_text(path, text)
        return text

    def to_json(self, path: str | Path | None = None) -> str:
        text = json.dumps(self.to_dict(), indent=1)
        if path is not None:
            write_text(path, text + "\n")
        return text

    def segments(self, values: np.ndarray) -> list[slice]:
        """Index ranges of the rows between contact jumps (for lines that do not join points across
        a jump): a break where the number of patches changes, or where the main contact position or
        ``values`` (a per-patch position) moves faster than JUMP_RATE mm per mm of shift."""
        y = self.columns["shift"]
        breaks = [0]
        for i in range(1, len(y)):
            step = max(abs(y[i] - y[i - 1]), 1e-12)
            jump = (self.columns["n_patches"][i] != self.columns["n_patches"][i - 1]
                    or abs(self.columns["y_rail"][i] - self.columns["y_rail"][i - 1]) > JUMP_RATE * step
                    or abs(values[i] - values[i - 1]) > JUMP_RATE * step)
            if jump:
                breaks.append(i)
        breaks.append(len(y))
        return [slice(a, b) for a, b in zip(breaks, breaks[1:]) if b > a]

    def plot(self, path: str | Path, title: str = "") -> None:
        """Forces, contact angles (degrees) and contact positions against the shift, one line per
        patch, broken at contact jumps (:meth:`segments`)."""
        from matplotlib.figure import Figure      # no pyplot: nothing global

        y = self.columns["shift"]
        fig = Figure(figsize=(14, 4.4))
        ax = fig.subplots(1, 3)
        colours = ("C0", "C1", "C2", "C3", "C4")
        pos_key = "s_rail" if MODELS.accepts(self.theory, CURVED_STRIP) else "y_rail"

        def draw(a, values, where, style, colour, label):
            first = True
            for seg in self.segments(where):
                v = values[seg]
                if np.all(~np.isfinite(v)):
                    continue
                a.plot(y[seg], v, style, color=colour, ms=3, label=label if first else None)
                first = False

        for key, colour, label in (("FZ_track", "k", "FZ (track)"), ("FY_track", "C3", "FY (track)"),
                                   ("FX_track", "C2", "FX (track)"), ("FN", "C0", "FN (sum)")):
            draw(ax[0], self.columns[key], self.columns["y_rail"], "o-", colour, label)
        for k in range(self.n_patch_columns):
            c = colours[k % len(colours)]
            where = self.columns[f"p{k}_{pos_key}"]
            draw(ax[1], np.degrees(self.columns[f"p{k}_contact_angle"]), where, "o-", c, f"patch {k}")
            draw(ax[2], where, where, "o-", c, f"patch {k}")
        ax[0].set_ylabel("force on the rail [N]")
        ax[1].set_ylabel("contact angle [degrees]")
        ax[2].set_ylabel("contact position on the rail, " + ("y_rail [mm]" if pos_key == "y_rail"
                                                             else "arc length s [mm]"))
        for a in ax:
            a.set_xlabel("lateral shift [mm]")
            a.grid(alpha=0.3)
            a.legend(fontsize=8)
        fig.suptitle(title or f"{self.scene}: {self.theory} ({self.influence}) against lateral shift; "
                     "lines break at contact jumps")
        fig.tight_layout()
        save_figure(fig, path, dpi=110)


def parse_shifts(shift: str | float | Sequence[float]) -> list[float]:
    """Shifts (mm) from "start:stop:step" (stop included), one number or a sequence."""
    from conformal.geometry.sweep import MAX_SHIFTS, parse_range

    if isinstance(shift, str):
        return parse_range(shift)
    if isinstance(shift, (int, float)) and not isinstance(shift, bool):
        values = [float(shift)]
    else:
        try:
            values = [float(v) for v in shift]
            ok = not any(isinstance(v, (bool, str, bytes)) for v in shift)
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise InputError(f"--shift: give lateral shifts in mm as \"start:stop:step\", a number or a list of "
                             f"numbers, got {shift!r}")
    if not values or not all(math.isfinite(v) for v in values):
        raise InputError("--shift: give finite lateral shifts (mm)")
    if len(values) > MAX_SHIFTS:
        raise InputError(f"--shift: {len(values)} shifts is too many (at most {MAX_SHIFTS})")
    return values


def _patches(result, theory: str) -> list[dict]:
    """Per-patch values of a result, ordered by their position on the rail."""
    if result.patches:
        out = [{"FN": p.FN, "FX": p.FX, "FS": p.FY, "contact_angle": p.extra.get("contact_angle", math.nan),
                "y_rail": p.extra.get("y_rail", math.nan), "s_rail": math.nan, "pmax": p.pmax}
               for p in result.patches]
        return sorted(out, key=lambda d: d["y_rail"])
    regions = result.extra.get("regions") or []
    if regions:
        out = [{"FN": r["FN"], "FX": r["FX"], "FS": r["FS"], "contact_angle": r["contact_angle"],
                "y_rail": math.nan, "s_rail": 0.5 * (r["s_min"] + r["s_max"]), "pmax": r["pmax"]} for r in regions]
        return sorted(out, key=lambda d: d["s_rail"])
    return [{"FN": result.FN, "FX": result.FX, "FS": result.FY,
             "contact_angle": result.extra.get("contact_angle", math.nan),
             "y_rail": result.extra.get("y_rail", math.nan), "s_rail": math.nan, "pmax": result.pmax}]


def _totals(result) -> dict[str, float]:
    e = result.extra
    return {"FN": result.FN, "FX": result.FX, "FS": result.FY, "FX_track": e.get("FX_track", math.nan),
            "FY_track": e.get("FY_track", math.nan), "FZ_track": e.get("FZ_track", math.nan), "MZ": result.MZ,
            "xi": result.xi, "eta": result.eta, "phi": result.phi, "z_ws": e.get("z_ws", math.nan),
            "approach": result.approach, "contact_angle": e.get("contact_angle", math.nan),
            "y_rail": e.get("y_rail", math.nan), "pmax": result.pmax,
            "converged": 1 if result.converged else 0, "wall_s": result.wall_s}


def solve_sweep(scene, shifts: Sequence[float], *, workers: int | None = None, cache=None,
                progress: bool = False, warm_start: bool = True) -> SweepTable:
    """Solve ``scene`` at every lateral shift (mm) of ``shifts``: see the module docstring.

    Parameters
    ----------
    scene : conformal.scene.Scene
        A wheel-rail scene ([geometry] kind = "wheel_rail"); its lateral_shift is replaced.
    shifts : sequence of float
    workers : processes for missing FE influence numbers (default: cores / 2).
    cache : the FE cache folder (default: $CONFORMAL_CACHE or the user cache).
    warm_start : start every balance from the previous position's (default True; not with FE
        influence numbers, whose cache holds the strips of the cold balance).

    Returns
    -------
    SweepTable
    """
    from conformal._threads import single_threaded_blas
    from conformal.cases import solve_wheel_rail
    from conformal.cases.wheelrail import WarmStart
    from conformal.scene import scene_warnings

    if scene.geometry.kind != "wheel_rail":
        raise InputError(f"[geometry] kind: a sweep needs a wheel_rail scene, got {scene.geometry.kind!r}")
    shifts = [float(v) for v in shifts]
    if not shifts:
        raise InputError("--shift: no lateral shifts")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise InputError(f"--workers: must be a whole number >= 1, got {workers!r}")
    influence = getattr(scene.model, "influence", "halfspace") or "halfspace"
    if MODELS.accepts(scene.model.theory, FE_INFLUENCE) and influence == "fe":
        from conformal.cases.precompute import precompute
        from conformal.jobs import Sweep

        precompute(scene, Sweep("shift", tuple(shifts)), cache=cache, workers=workers, progress=progress)
    results, errors, warns = [], [], []
    warm = None
    # FE numbers are cached per strip: a warm-started balance moves the strip by up to BALANCE_ZTOL, so
    # the positions are solved cold, on exactly the strips the precomputation planned
    warm_start = warm_start and influence != "fe"
    base_warn = scene_warnings(scene)
    with single_threaded_blas():
        for y in shifts:
            sc = scene.with_("geometry.lateral_shift", y)
            try:
                r = solve_wheel_rail(sc, warm=warm)
            except ConformalError as exc:
                results.append(None)
                errors.append(str(exc))
                warns.append(())
                warm = None
                continue
            warm = WarmStart.from_result(r, warm) if warm_start else None
            results.append(r)
            errors.append(None)
            warns.append(tuple(dict.fromkeys(base_warn + r.warnings)))
    per_patch = [_patches(r, scene.model.theory) if r is not None else [] for r in results]
    n_p = max((len(p) for p in per_patch), default=0)
    cols: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    desc: dict[str, str] = {}
    for name, unit, text in TOTALS:
        if name == "shift":
            vals = shifts
        elif name == "n_patches":
            vals = [len(p) if r is not None else 0 for p, r in zip(per_patch, results)]
        else:
            vals = [_totals(r)[name] if r is not None else math.nan for r in results]
        dtype = int if name in ("n_patches", "converged") and all(r is not None for r in results) else float
        cols[name] = np.asarray(vals, dtype=dtype)
        units[name], desc[name] = unit, text
    for k in range(n_p):
        for name, unit, text in PATCH:
            key = f"p{k}_{name}"
            cols[key] = np.asarray([p[k][name] if len(p) > k else math.nan for p in per_patch], float)
            units[key], desc[key] = unit, f"patch {k} (by position on the rail): {text}"
    return SweepTable(scene=scene.name, theory=scene.model.theory, influence=influence, columns=cols, units=units,
                      errors=tuple(errors), warnings=tuple(warns), descriptions=desc)
