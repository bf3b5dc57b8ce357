"""Kalker's creepage and spin coefficients C11, C22, C23 (and C33 where the exact solver has
tabulated it), as functions of the semi-axis ratio a/b and Poisson's ratio nu.

Sources
-------
* Table: Kalker (1990), *Three-dimensional elastic bodies in rolling contact*, App. E, Table E.3
  (``conformal/data/kalker_coefficients.csv``, Kalker's 1967 tables as reprinted in Kalker 1990).  Branch
  ``a<=b`` is tabulated in g = a/b, branch ``a>b`` in g = b/a, g = 0.1 ... 1, nu = 0, 0.25, 0.5.
  a is the semi-axis in the rolling direction x.  The csv carries C23(a<=b, g=0.8, nu=0.25) =
  1.25; CONTACT's usetab_table.f90 has the transcription error 1.15 (the test suite checks that
  every tabulated sequence is monotone, which 1.15 would break).
* Slender-ellipse asymptotes (g -> 0), Kalker (1990) Table E.3 footnote, after Kalker (1967,
  thesis) and Kalker (1972, "On elastic line contact", J. Appl. Mech. 39, 1125-1132), with
  Lambda = ln(16/g²):

  a/b -> 0 (contact long across the rolling direction, locally 2-D line contact)::

      C11 = pi²/(4(1-nu))          C22 = pi²/4
      C23 = pi sqrt(g)/(3(1-nu)) [1 + nu(Lambda/2 + ln 4 - 5)]
      C33 = pi²/(16 (1-nu) g)

  b/a -> 0 (contact long in the rolling direction)::

      C11 = 2 pi/((Lambda - 2nu) g) [1 + (3 - ln 4)/(Lambda - 2nu)]
      C22 = 2 pi/(((1-nu)Lambda + 2nu) g) [1 + (1-nu)(3 - ln 4)/((1-nu)Lambda + 2nu)]
      C23 = 2 pi/(3 g^1.5 ((1-nu)Lambda - 2 + 4nu))

  The leading a/b -> 0 terms follow from 2-D theory: Carter's small-creepage slope per unit
  width, F' = pi G a xi/(2(1-nu)), integrated over the ellipse gives C11 = pi²/(4(1-nu)); the
  same strip theory with xi = -phi y gives C33 = pi²/(16(1-nu)g).  At the table edge g = 0.1
  the asymptotes differ from the table by at most 4.3 % (C11, C22), 1 % (C23, b/a -> 0) and
  6 % (C23, a/b -> 0, nu = 0.5), and every one of them is closer to the table at g = 0.1 than
  at g = 0.2 (tests/validation/test_coefficients.py).

Interpolation
-------------
Inside the table: a not-a-knot cubic spline of ln C in t = ln(a/b) (one coordinate across both
branches, t in [ln 0.1, ln 10]) at each tabulated nu, then quadratic (Lagrange) interpolation
in nu through the three nu nodes.  Measured: leaving out every interior node, the spline on the
remaining (twice as coarse) nodes predicts it within 1.5 %; quadratic-in-nu reproduces the
flexibilities CONTACT prints for a/b = 0.5, nu = 0.28 (tractcurv) within 0.2 %, linear-in-nu
only within 0.8 %.  Outside the table (g < 0.1): the asymptote times a correction
1 + (r - 1) g/0.1 with r = table/asymptote at g = 0.1, i.e. continuous at g = 0.1 and equal to
the published asymptote as g -> 0 (the asymptotic expansions have O(g) remainders).

C33 is not in Kalker's table here: it is read from ``conformal/data/kalker_c33.csv``
(columns branch, g, nu, C33), which the exact half-space solver writes.  Without that file
:func:`c33` raises :class:`~conformal.errors.ConformalError`: no made-up numbers.  The file's
header carries the grid-convergence study of C33 (studies/c33_convergence.py: n = 16 ... 128
elements across the short axis, grid offsets averaged, Richardson with a fitted rate), with the
extrapolated values and their uncertainties at a/b = 0.1, 0.2, 1, 2, 5, 10 (e.g. a/b = 5,
nu = 0.25: 0.605 +- 0.001; a/b = 1: 1.180 +- 0.018); the tabulated nodes lie within 0.9 % of them.

>>> c = kalker_coefficients(1.0, 0.25)
>>> round(c.C11, 2), round(c.C22, 2), round(c.C23, 2)
(4.12, 3.67, 1.47)
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from conformal.errors import ConformalError, InputError

DATA_DIR = Path(__file__).resolve().parent.parent / "data"
TABLE_FILE = DATA_DIR / "kalker_coefficients.csv"
C33_FILE = DATA_DIR / "kalker_c33.csv"

G_MIN = 0.1          # smallest tabulated g (a/b or b/a)
T_EDGE = math.log(1.0 / G_MIN)  # |ln(a/b)| at the table edge
LN4 = math.log(4.0)


@dataclass(frozen=True)
class CreepCoefficients:
    """Kalker's coefficients at one (a/b, nu); ``source`` is "table" or "asymptote"."""

    C11: float
    C22: float
    C23: float
    a_over_b: float
    nu: float
    source: str


# ----------------------------------------------------------------------------- tables
@dataclass(frozen=True)
class _Table:
    """Values C[k, i_nu, i_t] on nodes t = ln(a/b) (ascending) and nu (ascending)."""

    names: tuple[str, ...]
    t: np.ndarray
    nu: np.ndarray
    values: np.ndarray  # (n_names, n_nu, n_t)

    @property
    def splines(self) -> list[list]:
        """ln C as a function of t per (name, nu node): not-a-knot cubic splines (>= 4 nodes)
        or linear interpolation; built once per table."""
        cached = self.__dict__.get("_splines")
        if cached is None:
            cached = [[_curve(self.t, np.log(self.values[k, j])) for j in range(len(self.nu))]
                      for k in range(len(self.names))]
            object.__setattr__(self, "_splines", cached)
        return cached


def _curve(t: np.ndarray, y: np.ndarray):
    if len(t) >= 4:
        return CubicSpline(t, y)
    if len(t) >= 2:
        return lambda tt: np.interp(tt, t, y)
    return lambda tt: np.full(np.shape(tt), y[0])


def _read_rows(path: Path, names: tuple[str, ...]) -> list[tuple[str, float, float, list[float]]]:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConformalError(f"cannot read coefficient table {path}: {exc}") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    reader = csv.DictReader(lines)
    rows = []
    for r in reader:
        try:
            rows.append((r["branch"].strip(), float(r["g"]), float(r["nu"]),
                         [float(r[n]) for n in names]))
        except (KeyError, TypeError, ValueError) as exc:
            raise ConformalError(f"{path.name}: bad row {r} ({exc})") from None
    return rows


def _build_table(path: Path, names: tuple[str, ...]) -> _Table:
    rows = _read_rows(path, names)
    pts: dict[tuple[float, float], list[float]] = {}
    for branch, g, nu, vals in rows:
        if branch not in ("a<=b", "a>b") or not 0 < g <= 1:
            raise ConformalError(f"{path.name}: bad branch/g {branch!r}, {g}")
        t = math.log(g) if branch == "a<=b" else -math.log(g)
        pts[(round(t, 12), nu)] = vals
    ts = np.array(sorted({k[0] for k in pts}))
    nus = np.array(sorted({k[1] for k in pts}))
    vals = np.full((len(names), len(nus), len(ts)), np.nan)
    for (t, nu), v in pts.items():
        vals[:, int(np.searchsorted(nus, nu)), int(np.searchsorted(ts, t))] = v
    if np.isnan(vals).any():
        raise ConformalError(f"{path.name}: the table is not a full (a/b, nu) grid")
    if (vals <= 0).any():
        raise ConformalError(f"{path.name}: coefficients must be positive")
    return _Table(names, ts, nus, vals)


@lru_cache(maxsize=None)
def kalker_table() -> _Table:
    """Kalker's C11, C22, C23 table (cached)."""
    return _build_table(TABLE_FILE, ("C11", "C22", "C23"))


_c33_cache: dict[tuple[Path, float], _Table] = {}


def c33_table(path: Path | None = None) -> _Table:
    """The exact solver's C33 table; ConformalError when it has not been computed yet."""
    path = C33_FILE if path is None else Path(path)
    if not path.is_file():
        raise ConformalError(
            "the spin coefficient C33 needs the exact solver's table conformal/data/kalker_c33.csv "
            "(columns branch,g,nu,C33), which has not been computed yet; Kalker's published table "
            "here has C11, C22, C23 only")
    key = (path, path.stat().st_mtime)
    if key not in _c33_cache:
        _c33_cache[key] = _build_table(path, ("C33",))
    return _c33_cache[key]


def _interp_table(table: _Table, t: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Interpolate every named coefficient at 1-D arrays (t, nu) inside the table:
    returns (n_names, len(t))."""
    n_nu, n_k = len(table.nu), len(table.names)
    # per nu node: cubic spline (linear for < 4 nodes) of ln C in t
    at_nodes = np.empty((n_k, n_nu, t.size))
    for k in range(n_k):
        for j in range(n_nu):
            at_nodes[k, j] = table.splines[k][j](t)
    at_nodes = np.exp(at_nodes)
    if n_nu == 1:
        if not np.allclose(nu, table.nu[0], atol=1e-9):
            raise ConformalError(f"coefficient table holds nu = {table.nu[0]:g} only, asked nu = "
                                 f"{np.unique(nu)}")
        return at_nodes[:, 0]
    # Lagrange in nu through the deg + 1 consecutive nodes nearest nu (deg <= 2)
    deg = min(n_nu - 1, 2)
    i0 = np.clip(np.searchsorted(table.nu, nu) - (deg + 1) // 2, 0, n_nu - deg - 1)
    cols = np.arange(t.size)
    out = np.zeros((n_k, t.size))
    for m in range(deg + 1):
        w = np.ones(t.size)
        for q in range(deg + 1):
            if q != m:
                w *= (nu - table.nu[i0 + q]) / (table.nu[i0 + m] - table.nu[i0 + q])
        out += w * at_nodes[:, i0 + m, cols]
    return out


# ----------------------------------------------------------------------------- asymptotes
def asymptotic_coefficients(a_over_b, nu):
    """Kalker's slender-ellipse asymptotes (C11, C22, C23) for g -> 0 (see module docstring).

    For a/b <= 1 the a/b -> 0 formulas with g = a/b, otherwise the b/a -> 0 formulas with
    g = b/a.  Arrays broadcast.  Valid for small g only (they join the table at g = 0.1 within a
    few per cent).
    """
    r = np.asarray(a_over_b, dtype=float)
    nu = np.asarray(nu, dtype=float)
    small_a = r <= 1.0
    g = np.where(small_a, r, 1.0 / r)
    lam = np.log(16.0 / g**2)
    # a/b -> 0
    c11_a = np.pi**2 / (4.0 * (1.0 - nu)) + 0.0 * g
    c22_a = np.pi**2 / 4.0 + 0.0 * g + 0.0 * nu
    c23_a = np.pi * np.sqrt(g) / (3.0 * (1.0 - nu)) * (1.0 + nu * (0.5 * lam + LN4 - 5.0))
    # b/a -> 0
    lx = lam - 2.0 * nu
    ly = (1.0 - nu) * lam + 2.0 * nu
    c11_b = 2.0 * np.pi / (lx * g) * (1.0 + (3.0 - LN4) / lx)
    c22_b = 2.0 * np.pi / (ly * g) * (1.0 + (1.0 - nu) * (3.0 - LN4) / ly)
    c23_b = 2.0 * np.pi / (3.0 * g**1.5 * ((1.0 - nu) * lam - 2.0 + 4.0 * nu))
    return (np.where(small_a, c11_a, c11_b), np.where(small_a, c22_a, c22_b),
            np.where(small_a, c23_a, c23_b))


def asymptotic_c33(a_over_b, nu):
    """C33 for a/b -> 0: pi²/(16(1-nu) g), g = a/b (2-D strip theory, Kalker 1990 Table E.3)."""
    g = np.asarray(a_over_b, dtype=float)
    return np.pi**2 / (16.0 * (1.0 - np.asarray(nu, dtype=float)) * g)


# ----------------------------------------------------------------------------- public
def _check(a_over_b: np.ndarray, nu: np.ndarray) -> None:
    if not np.all(np.isfinite(a_over_b) & (a_over_b > 0)):
        raise InputError(f"Kalker coefficients: a/b must be finite and > 0, got {a_over_b}")
    if not np.all(np.isfinite(nu) & (nu >= 0.0) & (nu <= 0.5)):
        raise InputError(f"[material] nu: Kalker's creep coefficients (theories linear, empirical, fastsim, table) "
                         f"are tabulated for 0 <= nu <= 0.5, got nu = {nu}")


def coefficient_arrays(a_over_b, nu) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vectorised C11, C22, C23 for arrays a/b and nu (broadcast).  See module docstring."""
    r, nu = np.broadcast_arrays(np.asarray(a_over_b, dtype=float), np.asarray(nu, dtype=float))
    _check(r, nu)
    t = np.log(r)
    table = kalker_table()
    inside = np.abs(t) <= T_EDGE + 1e-12
    out = np.empty((3,) + r.shape)
    if inside.any():
        out[:, inside] = _interp_table(table, t[inside], nu[inside])
    outside = ~inside
    if outside.any():
        to, no = t[outside], nu[outside]
        edge_t = np.sign(to) * T_EDGE
        edge_table = _interp_table(table, edge_t, no)
        edge_asym = np.array(asymptotic_coefficients(np.exp(edge_t), no))
        asym = np.array(asymptotic_coefficients(np.exp(to), no))
        g = np.exp(-np.abs(to))  # < G_MIN
        out[:, outside] = asym * (1.0 + (edge_table / edge_asym - 1.0) * g / G_MIN)
    return out[0], out[1], out[2]


def kalker_coefficients(a_over_b: float, nu: float) -> CreepCoefficients:
    """C11, C22, C23 for one contact ellipse (a along the rolling direction).

    >>> c = kalker_coefficients(2.0, 0.25)   # table node a>b, g = b/a = 0.5
    >>> round(c.C11, 12), round(c.C22, 12), round(c.C23, 12), c.source
    (5.1, 4.9, 2.62, 'table')
    """
    c11, c22, c23 = coefficient_arrays(a_over_b, nu)
    inside = abs(math.log(a_over_b)) <= T_EDGE + 1e-12
    return CreepCoefficients(float(c11), float(c22), float(c23), float(a_over_b), float(nu),
                             "table" if inside else "asymptote")


def c33(a_over_b, nu, path: Path | None = None):
    """The spin coefficient C33 from the exact solver's table (ConformalError without it).

    Inside the table's range of a/b: interpolated like C11 (spline of ln C33 in ln(a/b), at most
    quadratic in nu).  Below its smallest a/b: the a/b -> 0 asymptote pi²/(16(1-nu)a/b), blended
    as for C11.  Above its largest a/b (no published asymptote used here): ConformalError.
    """
    table = c33_table(path)
    r, nu = np.broadcast_arrays(np.asarray(a_over_b, dtype=float), np.asarray(nu, dtype=float))
    _check(r, nu)
    t = np.log(r)
    if np.any(t > table.t[-1] + 1e-12):
        raise ConformalError(f"C33: a/b = {float(np.max(r)):g} is beyond the computed C33 table "
                             f"(a/b <= {math.exp(table.t[-1]):g}); extend conformal/data/kalker_c33.csv")
    if np.any((nu < table.nu[0] - 1e-12) | (nu > table.nu[-1] + 1e-12)):
        raise ConformalError(f"C33: nu = {nu} outside the computed table "
                             f"({table.nu[0]:g} <= nu <= {table.nu[-1]:g})")
    out = np.empty(r.shape)
    inside = t >= table.t[0] - 1e-12
    if inside.any():
        out[inside] = _interp_table(table, t[inside], nu[inside])[0]
    if (~inside).any():
        t0 = np.full(int((~inside).sum()), table.t[0])
        no = nu[~inside]
        ratio = _interp_table(table, t0, no)[0] / asymptotic_c33(np.exp(t0), no)
        g, g0 = r[~inside], math.exp(table.t[0])
        out[~inside] = asymptotic_c33(g, no) * (1.0 + (ratio - 1.0) * g / g0)
    return float(out) if out.ndim == 0 else out


def c33_available(path: Path | None = None) -> bool:
    return (C33_FILE if path is None else Path(path)).is_file()
