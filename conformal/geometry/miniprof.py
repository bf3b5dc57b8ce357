"""Miniprof profile files (``.ban`` rail, ``.whl`` wheel) and CONTACT's profile conversions.

File format (CONTACT user guide, "Inputs regarding wheel and rail profiles"; the layout of the
files in CONTACT's testbank): header lines ``Key=value`` (or, in old-style files that name
``MINIPROF`` in their first lines, plain text lines) up to the first empty line, then one point a
line, values separated by blanks, tabs or commas.  ``ColumnDef=X,Y,A,...`` names the columns
(X the lateral coordinate, Y the vertical one; default ``X,Y``); ``XOffset`` / ``YOffset`` are
added to them.  ``!``, ``"``, ``%`` and ``#`` start comments.  Points closer than 1e-4 mm to the
previous one are dropped, and a zig-zag (two successive turns of the curve sharper than the
threshold, CONTACT's ZIGTHRS, default 150 degrees: a point repeated with a slight offset where
two measured sections were stitched) is replaced by the mean of its two points.

The conversions a CONTACT deck applies to any profile (MIRRORY, MIRRORZ, SCALEYZ) are
:func:`contact_canonical`; MIRRORZ = 0 detects whether z must be mirrored to point downwards from
the side faces (:func:`z_needs_mirror`).

>>> import numpy as np
>>> p = np.array([[0, 5], [1, 1], [2, 0.2], [3, 0], [4, 0.2], [5, 1], [6, 5]], float)
>>> z_needs_mirror(p, "rail"), z_needs_mirror(-p, "rail")
(False, True)
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from conformal.errors import InputError

#: suffixes read as Miniprof files
SUFFIXES = (".ban", ".whl")
#: CONTACT drops points this close to the previous one (mm)
POINT_DIST_MIN = 1e-4
#: CONTACT's default zig-zag threshold ZIGTHRS (rad)
ZIG_THRESHOLD = 5.0 * math.pi / 6.0

_COMMENT = re.compile(r"[!\"%#]")
_KEY = re.compile(r"^\s*([A-Za-z][\w. ]*?)\s*=(.*)$")


def _values(text: str) -> list[float] | None:
    """The leading numbers of a line (free text after them is ignored), None if it has none."""
    out = []
    for t in (t for t in re.split(r"[,\s]+", text.strip()) if t):
        try:
            out.append(float(t))
        except ValueError:
            break
    return out or None


def read_miniprof(path: str | Path, zig_threshold: float = ZIG_THRESHOLD) -> np.ndarray:
    """The (y, z) points of a Miniprof file as stored (columns X, Y plus XOffset / YOffset), with
    close points dropped and zig-zags repaired (module docstring); no mirroring or reordering."""
    path = Path(path)
    raw = path.read_bytes()
    if b"\0" in raw[:4096]:
        raise InputError(f"not a profile: {path} is a binary file (expected a Miniprof .ban/.whl file)")
    lines = raw.decode("latin-1").splitlines()
    old_style = any("MINIPROF" in ln for ln in lines[:3])
    in_header = True
    coldef = ["X", "Y"]
    offset = [0.0, 0.0]
    rows: list[tuple[float, float]] = []
    for lineno, line in enumerate(lines, 1):
        m = _COMMENT.search(line)
        text = line[:m.start()] if m else line
        if not text.strip():
            if m is None:                  # a blank line (not a comment) ends the header
                in_header = False
            continue
        key = _KEY.match(text)
        if key:
            if rows:
                raise InputError(f"profile {path.name}: line {lineno}: a keyword after the points")
            name, value = key.group(1).strip(), key.group(2).strip()
            if name == "ColumnDef":
                coldef = [c.strip() for c in value.split(",")]
                if "X" not in coldef or "Y" not in coldef:
                    raise InputError(f"profile {path.name}: line {lineno}: ColumnDef={value} names no X and Y")
            elif name.lower() in ("xoffset", "yoffset") and value:
                v = _values(value)
                if v:
                    offset[name.lower() == "yoffset"] = v[0]
            continue
        vals = _values(text)
        if in_header and (old_style or vals is None):
            continue                       # old-style header text, or a keyword without '='
        in_header = False
        if vals is None:
            raise InputError(f"profile {path.name}: line {lineno}: need numbers, got {text.strip()[:60]!r}")
        need = max(coldef.index("X"), coldef.index("Y")) + 1
        if len(vals) < need:
            continue                       # CONTACT skips lines with too few values
        y, z = vals[coldef.index("X")], vals[coldef.index("Y")]
        if not (math.isfinite(y) and math.isfinite(z)):
            raise InputError(f"profile {path.name}: line {lineno}: NaN or infinite value ({y}, {z})")
        rows.append((y + offset[0], z + offset[1]))
    if len(rows) < 2:
        raise InputError(f"profile {path.name}: a Miniprof file needs at least 2 points, got {len(rows)}")
    p = np.array(rows, dtype=float)
    return repair_zigzags(drop_close_points(p), zig_threshold)


def drop_close_points(p: np.ndarray, dist: float = POINT_DIST_MIN) -> np.ndarray:
    """The points without those closer than ``dist`` (mm) to the previous point kept."""
    keep = [0]
    for i in range(1, len(p)):
        if math.hypot(*(p[i] - p[keep[-1]])) >= dist:
            keep.append(i)
    return p[keep]


def repair_zigzags(p: np.ndarray, threshold: float = ZIG_THRESHOLD) -> np.ndarray:
    """Replace each zig-zag, two successive changes of the segment direction both larger than
    ``threshold`` (rad), by the mean of the two points between those turns."""
    if threshold >= math.pi:
        return p
    pts = [tuple(r) for r in p]
    i = 1
    while i + 2 < len(pts):
        a = [math.atan2(pts[k + 1][1] - pts[k][1], pts[k + 1][0] - pts[k][0]) for k in (i - 1, i, i + 1)]
        d1 = abs((a[1] - a[0] + math.pi) % (2 * math.pi) - math.pi)
        d2 = abs((a[2] - a[1] + math.pi) % (2 * math.pi) - math.pi)
        if d1 > threshold and d2 > threshold:
            mid = (0.5 * (pts[i][0] + pts[i + 1][0]), 0.5 * (pts[i][1] + pts[i + 1][1]))
            pts[i:i + 2] = [mid]
        else:
            i += 1
    return np.array(pts, dtype=float)


def z_needs_mirror(p: np.ndarray, kind: str) -> bool:
    """Whether z must be mirrored to point downwards (CONTACT's MIRRORZ = 0, user guide: rails have
    side faces towards positive z, wheels towards negative z).  Wheel: the lowest z lies within the
    first or last 5 % of the points (a side face) unless the largest does, else the middle between
    them lies above the straight line.  Rail: the first change of z from either end (by more than
    0.1 % of the range) within the outer 10 % of the points is a rise; undecided: the lowest z
    lies within the outer 10 %."""
    p = np.asarray(p, float)
    n = len(p)
    z = p[:, 1]
    imin, imax = int(np.argmin(z)), int(np.argmax(z))
    fmin, fmax = (imin + 1) / n, (imax + 1) / n
    if kind == "wheel":
        if fmin < 0.05 or fmin > 0.95:
            return False
        if fmax < 0.05 or fmax > 0.95:
            return True
        mid = int(round(n * (fmin + fmax) / 2.0)) - 1
        return bool(z[mid] > 0.5 * (z[imin] + z[imax]))
    dz_tot = max(1e-5, float(z[imax] - z[imin]))

    def first_change(order, ref):
        for i in order:
            dz = z[i] - z[ref]                      # interior minus end point
            if abs(dz) > 1e-3 * dz_tot:
                return 1 if dz > 0 else -1
        return 0

    sta = first_change(range(1, int(round(0.1 * n))), 0)
    fin = first_change(range(n - 2, int(round(0.9 * n)) - 2, -1), n - 1)
    if sta == fin or fin == 0:
        mirror = sta
    elif sta == 0:
        mirror = fin
    else:
        mirror = -1
    if mirror == 0:
        mirror = 1 if (fmin < 0.1 or fmin > 0.9) else -1
    return mirror == 1


def contact_canonical(p: np.ndarray, kind: str, *, mirror_y: int = 0, mirror_z: int = 0,
                      scale: float = 1.0) -> np.ndarray:
    """CONTACT's conversions of the deck (MIRRORY: 1 mirrors y; MIRRORZ: 1 mirrors z, -1 keeps
    it, 0 mirrors where :func:`z_needs_mirror`; SCALEYZ multiplies both), in that order."""
    q = np.array(p, dtype=float)
    if mirror_y >= 1:
        q[:, 0] *= -1.0
    if mirror_z == 1 or (mirror_z == 0 and z_needs_mirror(q, kind)):
        q[:, 1] *= -1.0
    return q * float(scale)
