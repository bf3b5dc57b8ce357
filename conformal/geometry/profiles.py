"""Wheel and rail cross-section profiles: reading, checking, built-in names.

A profile is a list of points (y, z) in mm in CONTACT's *right-side* form (see
``meshes/profiles/README.md``; the files are the package's, ``conformal/data/profiles/``):

* rail: y lateral, positive towards the field side, z positive **downwards**; the rail body lies
  below the curve (larger z);
* wheel: y lateral from the profile origin (the tape circle for S1002 and EN 13715 wheels),
  positive towards the field side, flange at y < 0; z = increase of the radius, positive towards
  the flange tip (downwards when the wheel stands on the rail); the wheel body lies above.

Points are ordered from the flange/gauge side to the field side (increasing y overall); files in
the opposite order are reversed.  Files are CSV/text (``y,z`` rows, '#' comments) or CONTACT's
SIMPACK-like ``.prw``/``.prr`` files (``point.begin ... point.end`` block, '!' comments, header
keys ``mirror.y``, ``inversion``, ``units.len.f``) or Miniprof ``.ban``/``.whl`` files
(conformal.geometry.miniprof; ``[geometry] rail_mirror_y`` / ``wheel_mirror_y`` and ``rail_z`` /
``wheel_z = "auto"`` bring them into this form as CONTACT's MIRRORY / MIRRORZ do).

Every defect raises :class:`~conformal.errors.InputError` naming the file: NaN or infinite values,
too few points, points out of order (the curve turns back), self-intersection, and a flanged wheel
given upside down (z positive upwards).  A concave rail (a groove rail, or a head given upside
down: the points cannot tell them apart) is accepted with a warning; ``[geometry] rail_z = "up"`` /
``wheel_z = "up"`` read files with z positive upwards.

>>> p = load_profile("S1002", kind="wheel")
>>> p.name, p.points.shape[1], float(p.points[0, 0])
('S1002', 2, -70.0)
"""
from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from conformal.errors import InputError

MIN_POINTS = 5


@dataclass(frozen=True)
class BuiltinProfile:
    file: str
    kind: str                 # "wheel" | "rail"
    mirror_y: bool = False    # the file stores y with the opposite sign
    y_offset: float = 0.0     # added to y after mirroring (re-reference the origin)
    note: str = ""
    flange_back: float | None = None   # wheel: y of the flange back when the points do not reach it


# Built-in names (case-insensitive).  Rail heads named without a cant are uncanted: the scene's
# rail_cant rotates them.  Files with the cant included say so; use rail_cant = 0 with them.
BUILTIN: dict[str, BuiltinProfile] = {
    "S1002": BuiltinProfile("s1002_analytic.csv", "wheel", note="S1002/h28/e32.5/6.7%, analytic"),
    "S1002_MBENCH": BuiltinProfile("s1002_contact_mbench_v3.csv", "wheel", mirror_y=True,
                                   note="S1002, CONTACT Manchester benchmark v3 (raw points)"),
    "EN13715_1IN40": BuiltinProfile("en13715_1in40_h28_e32p5_analytic.csv", "wheel"),
    "EN15302_WHEEL_A": BuiltinProfile("en15302_wheelA_analytic.csv", "wheel"),
    "EN15302_WHEEL_B": BuiltinProfile("en15302_wheelB_analytic.csv", "wheel"),
    "EN15302_WHEEL_H": BuiltinProfile("en15302_wheelH_analytic.csv", "wheel"),
    "EN15302_WHEEL_I": BuiltinProfile("en15302_wheelI_analytic.csv", "wheel"),
    "APTA140": BuiltinProfile("apta140_1in40_analytic.csv", "wheel",
                              note="origin at the gauge point, not a tape circle"),
    "WORN_WHEEL_HM": BuiltinProfile("worn_wheel_contact_high_mileage.csv", "wheel", y_offset=-70.0,
                                    note="worn heavy-haul wheel; origin moved to the tape circle (y = 70)",
                                    flange_back=-70.0),
    "UIC60": BuiltinProfile("uic60_head_r300w21_analytic.csv", "rail",
                            note="UIC 60 head (Manchester/EN 15302 variant), uncanted"),
    "60E1": BuiltinProfile("uic60_60e1_en13674_head_analytic.csv", "rail",
                           note="60E1 head, EN 13674-1, uncanted"),
    "UIC60_MBENCH_1IN40": BuiltinProfile("uic60_contact_mbench_v3_canted1in40.csv", "rail",
                                         note="CONTACT Manchester rail, 1:40 cant INCLUDED (use rail_cant = 0)"),
    "EN15302_RAIL_A_1IN20": BuiltinProfile("en15302_railA_1in20_analytic.csv", "rail",
                                           note="EN 15302 rail A, 1:20 cant INCLUDED (use rail_cant = 0)"),
    "WORN_RAIL_SITE_B": BuiltinProfile("worn_rail_contact_site_b_high_rail.csv", "rail",
                                       note="worn heavy-haul high rail, as measured (use rail_cant = 0)"),
}


@dataclass(frozen=True, eq=False)
class Profile:
    """Checked profile points (n, 2) in right-side form, ordered by increasing y overall."""

    name: str
    kind: str
    points: np.ndarray
    source: str = ""


#: mm, the longest profile (arc length of its points): a whole rail section is about 600 mm round
MAX_PROFILE_LENGTH = 2000.0


def builtin_dir() -> Path:
    return Path(str(resources.files("conformal") / "data" / "profiles"))


# ----------------------------------------------------------------------------- reading
def _read_csv(path: Path) -> np.ndarray:
    """Rows 'y, z' (comma, semicolon or white space; '#' comments; one header line tolerated).  A
    file that does not start as a profile is refused as "not a profile" without quoting it (a
    mistyped path may name any file); lines after the first numbers are quoted (60 characters)."""
    raw = path.read_bytes()
    if b"\0" in raw[:4096]:
        raise InputError(f"not a profile: {path} is a binary file (expected rows 'y, z' in mm)")
    lines = raw.decode("utf-8", errors="replace").splitlines()
    fast = _rows_fast(lines)
    if fast is not None:
        return fast
    rows, header = [], False
    for lineno, line in enumerate(lines, 1):
        text = line.split("#")[0].strip()
        if not text:
            continue
        parts = text.replace(",", " ").replace(";", " ").split()   # runs of , ; and white space
        try:
            y, z = float(parts[0]), float(parts[1])
        except (ValueError, IndexError):
            if not rows and not header and len(parts) >= 2:   # a header such as "y_mm,z_mm"
                header = True
                continue
            if not rows:
                raise InputError(f"not a profile: {path} (line {lineno} is not two numbers 'y, z' in mm)") from None
            raise InputError(f"profile {path.name}: line {lineno}: need two numbers 'y, z', got "
                             f"{text[:60]!r}") from None
        if len(parts) > 2:               # x, y, z points or a column more: which two are y, z is a guess
            raise InputError(f"profile {path.name}: line {lineno}: {len(parts)} values; a profile file has two "
                             f"columns 'y, z' in mm, got {text[:60]!r}")
        rows.append((y, z, lineno))
    return _as_array(rows, path)


def _rows_fast(lines: list[str]) -> np.ndarray | None:
    """The points of lines that are all 'y,z' rows of finite numbers (comma separated, '#'
    comments, blank lines), read by numpy's parser in C (the numbers of ``float``: both round
    correctly); None for anything else (another separator, a header, a bad row, no rows), which
    the row-by-row reading of :func:`_read_csv` then reads or refuses with its message."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")           # "input contained no data": read row by row
            p = np.loadtxt(lines, dtype=float, delimiter=",", comments="#", ndmin=2)
    except ValueError:
        return None
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] == 0 or not np.isfinite(p).all():
        return None
    return p


def _as_array(rows, path: Path) -> np.ndarray:
    for y, z, lineno in rows:
        if not (math.isfinite(y) and math.isfinite(z)):
            raise InputError(f"profile {path.name}: line {lineno}: NaN or infinite value ({y}, {z})")
    return np.array([(y, z) for y, z, _ in rows], dtype=float).reshape(-1, 2)


def _read_simpack(path: Path) -> np.ndarray:
    """CONTACT/SIMPACK ``.prw`` (wheel) or ``.prr`` (rail) file."""
    rows, in_points, saw_points = [], False, False
    mirror_y = mirror_z = False
    scale = 1.0
    for lineno, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
        text = line.split("!")[0].strip()
        if not text:
            continue
        low = text.lower()
        if low == "point.begin":
            in_points, saw_points = True, True
            continue
        if low == "point.end":
            in_points = False
            continue
        if in_points:
            parts = text.replace(",", " ").split()
            try:
                y, z = float(parts[0]), float(parts[1])
            except (ValueError, IndexError):
                raise InputError(f"profile {path.name}: line {lineno}: need two numbers 'y z' "
                                 f"in the point block, got {text!r}") from None
            rows.append((y, z, lineno))
            continue
        m = re.match(r"([\w.]+)\s*=\s*([-+0-9.eE]+)", text)
        if m:
            key, value = m.group(1).lower(), float(m.group(2))
            if key == "mirror.y":
                mirror_y = value == 1
            elif key == "mirror.z":
                mirror_z = value == 1
            elif key == "units.len.f":
                if value <= 0:
                    raise InputError(f"profile {path.name}: line {lineno}: units.len.f must be > 0")
                scale = 1000.0 / value   # units.len.f = 1000: the file is in mm
    if not saw_points:
        raise InputError(f"profile {path.name}: no 'point.begin ... point.end' block")
    if in_points:
        raise InputError(f"profile {path.name}: 'point.begin' without 'point.end'")
    p = _as_array(rows, path) * scale
    if mirror_y:
        p[:, 0] *= -1.0
    if mirror_z:
        p[:, 1] *= -1.0
    return p


def read_points(path: str | Path) -> np.ndarray:
    """Raw (y, z) points of a profile file (CSV/text, .prw/.prr, or Miniprof .ban/.whl read by
    conformal.geometry.miniprof), no checks beyond parsing."""
    from conformal.geometry.miniprof import SUFFIXES, read_miniprof

    path = Path(path)
    if not path.is_file():
        raise InputError(f"profile file not found: {path}")
    if path.suffix.lower() in (".prw", ".prr", ".prf"):
        return _read_simpack(path)
    if path.suffix.lower() in SUFFIXES:
        return read_miniprof(path)
    return _read_csv(path)


# ----------------------------------------------------------------------------- checks
def _orient(P, Q, R):
    return (Q[..., 0] - P[..., 0]) * (R[..., 1] - P[..., 1]) - (Q[..., 1] - P[..., 1]) * (R[..., 0] - P[..., 0])


def _proper_crossing(a, b, ii, jj) -> np.ndarray:
    """Whether segments ii and jj (a -> b) properly cross (each one's ends on opposite sides of the other)."""
    d1 = _orient(a[ii], b[ii], a[jj])
    d2 = _orient(a[ii], b[ii], b[jj])
    d3 = _orient(a[jj], b[jj], a[ii])
    d4 = _orient(a[jj], b[jj], b[ii])
    return (d1 * d2 < 0) & (d3 * d4 < 0)


def _segments_cross(p: np.ndarray) -> tuple[int, int] | None:
    """First pair (i, j), i < j - 1, of polyline segments that properly cross (the least i, then the
    least j), or None.  The pairs whose bounding boxes overlap are found from the segments sorted
    by their least y (of two overlapping y ranges one starts within the other): a profile's
    segments overlap a few neighbours each, so this tests O(n) pairs, not n^2 (the pairwise test,
    :func:`_segments_cross_pairwise`, where the y ranges overlap much: the same answer)."""
    a, b = p[:-1], p[1:]
    n = len(a)
    if n < 3:
        return None
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.argsort(lo[:, 0], kind="stable")
    lo_sorted = lo[order, 0]
    start = np.searchsorted(lo_sorted, lo[:, 0], side="left")
    count = np.searchsorted(lo_sorted, hi[:, 0], side="right") - start
    total = int(count.sum())
    if total > 20 * n + 10_000:
        return _segments_cross_pairwise(p)
    i = np.repeat(np.arange(n), count)
    first = np.repeat(start - (np.cumsum(count) - count), count)   # sorted position = first + running index
    q = order[first + np.arange(total)]
    ii, jj = np.minimum(i, q), np.maximum(i, q)
    keep = jj > ii + 1
    ii, jj = ii[keep], jj[keep]
    cand = ((lo[ii, 0] <= hi[jj, 0]) & (lo[jj, 0] <= hi[ii, 0]) & (lo[ii, 1] <= hi[jj, 1])
            & (lo[jj, 1] <= hi[ii, 1]))
    ii, jj = ii[cand], jj[cand]
    hit = _proper_crossing(a, b, ii, jj)
    if not hit.any():
        return None
    ii, jj = ii[hit], jj[hit]
    k = int(np.lexsort((jj, ii))[0])
    return int(ii[k]), int(jj[k])


def _segments_cross_pairwise(p: np.ndarray) -> tuple[int, int] | None:
    """:func:`_segments_cross` by testing all pairs (in chunks of rows)."""
    a, b = p[:-1], p[1:]
    n = len(a)
    lo, hi = np.minimum(a, b), np.maximum(a, b)

    chunk = max(1, 400_000 // max(n, 1))
    for i0 in range(0, n, chunk):
        i = np.arange(i0, min(n, i0 + chunk))[:, None]
        j = np.arange(n)[None, :]
        # bounding boxes overlap and the segments are not neighbours
        cand = ((lo[i, 0] <= hi[j, 0]) & (lo[j, 0] <= hi[i, 0]) & (lo[i, 1] <= hi[j, 1])
                & (lo[j, 1] <= hi[i, 1]) & (j > i + 1))
        ii, jj = np.nonzero(cand)
        if ii.size == 0:
            continue
        ii = ii + i0
        hit = _proper_crossing(a, b, ii, jj)
        if hit.any():
            k = int(np.argmax(hit))
            return int(ii[k]), int(jj[k])
    return None


def check_points(points: np.ndarray, kind: str, name: str) -> np.ndarray:
    """Validate and normalise profile points; returns the (n, 2) array ordered by increasing y.

    Raises InputError for too few points, NaN, points out of order, self-intersection, or a
    profile given upside down.
    """
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise InputError(f"profile {name}: need (y, z) pairs, got an array of shape {p.shape}")
    if not np.all(np.isfinite(p)):
        i = int(np.argmax(~np.isfinite(p).all(axis=1)))
        raise InputError(f"profile {name}: point {i + 1} is NaN or infinite: {p[i].tolist()}")
    # drop exact repeats (zero-length segments) before counting
    keep = np.ones(len(p), bool)
    if len(p) > 1:
        keep[1:] = np.hypot(*np.diff(p, axis=0).T) > 1e-9
    p = p[keep]
    if len(p) < MIN_POINTS:
        raise InputError(f"profile {name}: too few points ({len(p)}); need at least {MIN_POINTS}")
    if p[0, 0] > p[-1, 0]:
        p = p[::-1].copy()
    seg = np.diff(p, axis=0)
    length = np.hypot(*seg.T)
    if length.sum() < 1.0:
        raise InputError(f"profile {name}: the points span only {length.sum():.3g} mm")
    if length.sum() > MAX_PROFILE_LENGTH:    # the fitted curve is sampled along its length: bounded work
        raise InputError(f"profile {name}: the points span {length.sum():.4g} mm along the curve; a wheel or rail "
                         f"profile is at most {MAX_PROFILE_LENGTH:g} mm long (coordinates in mm?)")
    # a curve that doubles back on itself (turn of more than 150 degrees between segments)
    cosang = np.einsum("ij,ij->i", seg[:-1], seg[1:]) / (length[:-1] * length[1:])
    bad = np.nonzero(cosang < math.cos(math.radians(150.0)))[0]
    if bad.size:
        i = int(bad[0]) + 1
        raise InputError(f"profile {name}: points out of order: the curve turns back at point {i + 1} "
                         f"(y = {p[i, 0]:.3f}, z = {p[i, 1]:.3f} mm)")
    cross = _segments_cross(p)
    if cross is not None:
        i, j = cross
        raise InputError(f"profile {name}: the curve intersects itself (segment at y = {p[i, 0]:.3f} "
                         f"crosses segment at y = {p[j, 0]:.3f} mm)")
    _check_orientation(p, kind, name)
    return p


def _check_orientation(p: np.ndarray, kind: str, name: str) -> None:
    """Detect a profile given with z positive upwards (upside down)."""
    z = p[:, 1]
    if kind == "rail":
        # a rail head given upside down looks like a groove (both are concave seen from above): it is
        # accepted, and placement_warning names the [geometry] rail_z key (issue 11: CONTACT's groove
        # rails were refused here)
        pass
    elif kind == "wheel":
        # a flanged wheel: the flange tip (largest z, towards the rail) lies on the flange side
        zmax, zmin = float(z.max()), float(z.min())
        y_at_max, y_at_min = p[np.argmax(z), 0], p[np.argmin(z), 0]
        mid = 0.5 * (p[0, 0] + p[-1, 0])
        if zmax - zmin > 10.0 and y_at_min < mid and y_at_max > mid:
            raise InputError(f"profile {name}: the wheel looks upside down (the flange points away from "
                             "the rail); z must be positive towards the flange tip, or set [geometry] "
                             "wheel_z = \"up\" for a file with z positive upwards")
    else:
        raise InputError(f"profile {name}: kind must be 'wheel' or 'rail', got {kind!r}")


# ----------------------------------------------------------------------------- public
def resolve_profile(spec: str, base_dir: str | Path = ".") -> tuple[Path, BuiltinProfile | None]:
    """A built-in name or a file path (relative to base_dir) -> (path, builtin entry or None).

    A path to a ``profiles/`` folder that does not hold the file, but names one of the package's
    profile files, is the package's copy (the files once also lay in the repository's
    ``meshes/profiles/``; scene files naming them there keep working).

    >>> resolve_profile("meshes/profiles/s1002_analytic.csv")[0] == builtin_dir() / "s1002_analytic.csv"
    True
    """
    entry = BUILTIN.get(str(spec).upper())
    if entry is not None:
        return builtin_dir() / entry.file, entry
    path = Path(spec)
    if not path.is_absolute():
        path = Path(base_dir) / path
    if not path.is_file() and path.parent.name == "profiles" and (builtin_dir() / path.name).is_file():
        path = builtin_dir() / path.name       # the one copy: conformal/data/profiles
    if not path.is_file():
        names = ", ".join(sorted(BUILTIN))
        raise InputError(f"profile {spec!r}: neither a built-in name ({names}) nor an existing file ({path})")
    return path, None


def builtin_flange_back(spec: str) -> float | None:
    """Flange-back position (wheel-profile y) of a built-in wheel whose points stop short of it."""
    entry = BUILTIN.get(str(spec).upper())
    return None if entry is None else entry.flange_back


def rail_orientation_warning(points: np.ndarray, name: str) -> str | None:
    """A warning for a concave rail profile (both ends more than 1 mm above its lowest point, z
    downwards): a groove rail, or a rail head given with z positive upwards, which the points
    cannot tell apart; None for a rail head."""
    z = np.asarray(points, float)[:, 1]
    top = float(z.min())
    if (z[0] <= top + 1e-9 or z[-1] <= top + 1e-9) and z.max() - z[0] > 1.0 and z.max() - z[-1] > 1.0:
        return (f"profile {name}: the rail profile is concave (its ends lie above its lowest point): a groove "
                "rail; if it is a rail head given with z positive upwards, set [geometry] rail_z = \"up\"")
    return None


def load_profile(spec: str, kind: str, base_dir: str | Path = ".", *, z_up: bool | None = False,
                 mirror_y: bool = False) -> Profile:
    """Read and check a profile given by built-in name or file path.  ``z_up``: the file gives z
    positive upwards (the opposite of this package's convention, module docstring); z is negated
    on reading; None: found from the side faces as CONTACT does (MIRRORZ = 0,
    :func:`conformal.geometry.miniprof.z_needs_mirror`).  ``mirror_y``: y is negated on reading
    (CONTACT's MIRRORY = 1, e.g. a Miniprof rail measured with the field side at negative y)."""
    from conformal.geometry.miniprof import contact_canonical

    path, entry = resolve_profile(spec, base_dir)
    if entry is not None and entry.kind != kind:
        raise InputError(f"profile {spec!r} is a {entry.kind} profile, used as a {kind} profile")
    points = contact_canonical(read_points(path), kind, mirror_y=int(mirror_y),
                               mirror_z=0 if z_up is None else (1 if z_up else -1))
    if entry is not None:
        if entry.mirror_y:
            points = points * np.array([-1.0, 1.0])
        points = points + np.array([entry.y_offset, 0.0])
    name = str(spec).upper() if entry is not None else path.name
    return Profile(name=name, kind=kind, points=check_points(points, kind, name), source=str(path))
