"""Lateral-shift sweeps of the rigid contact geometry: rolling-radius difference, contact angles
and contact positions (the functions behind equivalent conicity, EN 15302).

For each lateral shift the wheelset is placed with its scene yaw; the roll is the scene's roll,
or (roll not given) the one at which both wheels touch; each wheel is lowered until it touches its
rail (rigid profiles, no load).  Per wheel the touching contact point (seed Eqs. 54-56) gives:

* y_rail, z_rail: position on the rail profile (CONTACT's convention: y > 0 towards the field side
  on the right rail, towards the track centre on the left rail);
* y_wheel: position on the wheel profile (same orientation convention);
* contact_angle (rad, CONTACT's DELTCP: < 0 at the right flange, > 0 at the left);
* rolling_radius (mm).

Derived: delta_r = r_right - r_left (> 0 when the right wheel runs on a larger radius) and
contact_angle_difference = -(delta_right + delta_left) = |delta_right| - |delta_left| on treads.

>>> from conformal.scene import WheelRailGeometry
>>> rows = sweep(WheelRailGeometry(), [0.0, 3.0])
>>> round(rows[0]["delta_r"], 6), rows[1]["delta_r"] > 0
(0.0, True)
"""
from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from conformal.errors import ConformalError, InputError
from conformal.files import open_atomic, save_figure
from conformal.geometry.search import RailTop, touch_height
from conformal.geometry.wheelrail import build_pair, wheelset_roll
from conformal.scene import WheelRailGeometry

TOUCH_WINDOW = 0.01   # mm: candidate contacts within this gap count as touching
#: the most lateral shifts one sweep takes (a bound on its loop)
MAX_SHIFTS = 10000


def parse_range(text: str) -> list[float]:
    """'start:stop:step' (inclusive of stop) or a single number -> list of shifts (mm)."""
    try:
        parts = [float(p) for p in text.split(":")]
    except ValueError:
        raise InputError(f"--shift: expected start:stop:step in mm, got {text!r}") from None
    if not all(math.isfinite(v) for v in parts):
        raise InputError(f"--shift: expected finite numbers in mm, got {text!r}")
    if len(parts) == 1:
        return parts
    if len(parts) != 3 or parts[2] <= 0 or parts[1] < parts[0]:
        raise InputError(f"--shift: expected start:stop:step with step > 0 and stop >= start, got {text!r}")
    start, stop, step = parts
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    if n > MAX_SHIFTS:
        raise InputError(f"--shift: {n} shifts is too many (at most {MAX_SHIFTS})")
    return [round(start + i * step, 12) for i in range(n)]


def _wheel(geo: WheelRailGeometry, base_dir, side: str, shift: float, roll: float) -> dict:
    pair = build_pair(geo, base_dir, side=side, roll=roll, lateral_shift=shift)
    top = RailTop.of(pair.rail)
    try:
        z, sr = touch_height(pair, top)
    except ConformalError as exc:
        raise InputError(f"[geometry] lateral_shift: {shift:g} mm: {exc}") from None
    c = sr.contacts[0]
    if c.at_end:
        raise InputError(f"[geometry] lateral_shift: {shift:g} mm puts the {side} contact at the end of a "
                         "profile; the profiles do not cover this shift")
    m = pair.mirror
    own = pair.rail.to_own(c.rail_point[1:])
    touching = sum(1 for o in sr.contacts if o.penetration > -TOUCH_WINDOW)
    return {"z": z, "y_rail": float(m * own[0]), "z_rail": float(own[1]), "y_wheel": m * c.y_wheel,
            "contact_angle": m * c.delta, "rolling_radius": c.rolling_radius, "x": c.x,
            "n_contacts": touching}


def sweep(geo: WheelRailGeometry, shifts, base_dir: str | Path = ".") -> list[dict]:
    """Rigid contact geometry for each lateral shift (mm); one dict per shift (see module doc)."""
    rows = []
    for y in shifts:
        y = float(y)
        if geo.placement == "wheelset":
            roll = geo.roll if geo.roll is not None else wheelset_roll(geo, base_dir, lateral_shift=y)[0]
            right = _wheel(geo, base_dir, "right", y, roll)
            left = _wheel(geo, base_dir, "left", y, roll)
            rows.append({
                "shift": y, "roll": roll, "z_ws": max(right["z"], left["z"]),
                "r_right": right["rolling_radius"], "r_left": left["rolling_radius"],
                "delta_r": right["rolling_radius"] - left["rolling_radius"],
                "contact_angle_right": right["contact_angle"], "contact_angle_left": left["contact_angle"],
                "contact_angle_difference": -(right["contact_angle"] + left["contact_angle"]),
                "y_rail_right": right["y_rail"], "y_rail_left": left["y_rail"],
                "y_wheel_right": right["y_wheel"], "y_wheel_left": left["y_wheel"],
                "x_right": right["x"], "x_left": left["x"],
                "n_contacts_right": right["n_contacts"], "n_contacts_left": left["n_contacts"],
            })
        else:
            roll = geo.roll or 0.0
            w = _wheel(geo, base_dir, geo.side, y, roll)
            rows.append({"shift": y, "roll": roll, "z_ws": w["z"], "rolling_radius": w["rolling_radius"],
                         "contact_angle": w["contact_angle"], "y_rail": w["y_rail"], "z_rail": w["z_rail"],
                         "y_wheel": w["y_wheel"], "x": w["x"], "n_contacts": w["n_contacts"]})
    return rows


def jump_warnings(rows: list[dict], max_rate: float = 2.0) -> list[str]:
    """Warnings where the wheelset height jumps between neighbouring shifts: |dz_ws| > 0.5 mm and
    more than ``max_rate`` times the shift step (steeper than a 63-degree flank): the flange has
    climbed onto the rail, a state the vertical placement finds but the rolling wheelset does not
    reach (issue 11)."""
    out = []
    for a, b in zip(rows, rows[1:]):
        dz, dy = b["z_ws"] - a["z_ws"], abs(b["shift"] - a["shift"])
        if abs(dz) > 0.5 and abs(dz) > max_rate * dy:
            out.append(f"sweep: the wheelset height jumps by {dz:+.2f} mm between lateral shifts {a['shift']:g} and "
                       f"{b['shift']:g} mm (flange climbing onto the rail?)")
    return out


def write_csv(rows: list[dict], path: str | Path) -> None:
    with open_atomic(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.9g}" if isinstance(v, float) else v) for k, v in r.items()})


def plot(rows: list[dict], path: str | Path, title: str = "") -> None:
    from matplotlib.figure import Figure      # no pyplot: no backend switch, nothing global

    y = np.array([r["shift"] for r in rows])
    fig = Figure(figsize=(14, 4.2))
    ax = fig.subplots(1, 3)
    if "delta_r" in rows[0]:
        ax[0].plot(y, [r["delta_r"] for r in rows], "o-", ms=3)
        ax[0].set_ylabel("rolling-radius difference r_R - r_L [mm]")
        ax[1].plot(y, [r["contact_angle_right"] for r in rows], "o-", ms=3, label="right")
        ax[1].plot(y, [r["contact_angle_left"] for r in rows], "s-", ms=3, label="left")
        ax[1].plot(y, [r["contact_angle_difference"] for r in rows], "k--", lw=1, label="difference")
        ax[2].plot(y, [r["y_rail_right"] for r in rows], "o-", ms=3, label="right rail")
        ax[2].plot(y, [r["y_rail_left"] for r in rows], "s-", ms=3, label="left rail")
        ax[2].plot(y, [r["y_wheel_right"] for r in rows], "o:", ms=2, label="right wheel")
        ax[2].plot(y, [r["y_wheel_left"] for r in rows], "s:", ms=2, label="left wheel")
    else:
        ax[0].plot(y, [r["rolling_radius"] for r in rows], "o-", ms=3)
        ax[0].set_ylabel("rolling radius [mm]")
        ax[1].plot(y, [r["contact_angle"] for r in rows], "o-", ms=3, label="contact angle")
        ax[2].plot(y, [r["y_rail"] for r in rows], "o-", ms=3, label="rail")
        ax[2].plot(y, [r["y_wheel"] for r in rows], "s:", ms=2, label="wheel")
    ax[1].set_ylabel("contact angle [rad]")
    ax[2].set_ylabel("contact position [mm]")
    for a in ax:
        a.set_xlabel("lateral shift [mm]")
        a.grid(alpha=0.3)
    ax[1].legend(fontsize=8)
    ax[2].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
