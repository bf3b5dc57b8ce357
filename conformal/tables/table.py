"""A creep-force table in memory and on disk (NPZ), and its vectorised evaluator.

File layout (``numpy.savez``, no pickles): ``values`` (n_ratio, n_nu, n_rho, n_theta, n_spin, 3)
= (fx, fy, mz) of Eq. T2 at the nodes; ``c11, c22, c23`` (n_ratio, n_nu): the linear-theory
coefficients used in Eq. T1 at the (a/b, nu) nodes; ``meta``: JSON text (spec, ranges, grid,
solver tolerance, code version, build statistics); ``content_hash``: sha256 over the arrays and
``meta``, verified on load (a corrupt or edited file raises InputError, never loads silently).

Evaluation (:func:`evaluate`): Eq. T1 with C11, C22, C23 from the stored nodes (cubic in ln a/b,
linear in nu), the symmetries and maps of Eqs. T3-T4, then (fx, fy, mz) from tensor-product cubic
splines of the node values along ln(a/b), s, theta, q (linear in nu), sampled once on a grid
``REFINE`` times finer and read multilinearly there (:func:`eval_grid`, :func:`interpolate`: about
1e6 contacts per CPU second), then F = mu FN (fx, fy) and MZ = mu FN sqrt(ab) mz (Eq. T2).
Points outside the tabulated a/b, nu, rho or spin ranges raise InputError (``outside="error"``,
default), or give NaN with a RuntimeWarning (``outside="nan"``), or are clamped onto the range
with a RuntimeWarning (``outside="clamp"``): never a silent extrapolation.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from conformal.errors import InputError
from conformal.tables.spec import N_OUT, TableSpec, polar, saturation_scales

#: format version of the NPZ file
FORMAT = 1
DEFAULT_TABLE = Path(__file__).resolve().parent.parent / "data" / "tables" / "creep_default.npz"
OUTSIDE = ("error", "nan", "clamp")
_CHUNK = 1 << 15


@dataclass(frozen=True, eq=False)
class CreepTable:
    """Node values of a creep-force table (see the module docstring for the layout)."""

    spec: TableSpec
    values: np.ndarray
    c11: np.ndarray
    c22: np.ndarray
    c23: np.ndarray
    meta: Mapping[str, Any] = field(default_factory=dict)
    path: str | None = None

    def __post_init__(self):
        shape = self.spec.shape
        if self.values.shape != shape + (N_OUT,):
            raise InputError(f"creep table: values have shape {self.values.shape}, the spec needs "
                             f"{shape + (N_OUT,)}")
        for name in ("c11", "c22", "c23"):
            c = getattr(self, name)
            if c.shape != shape[:2] or not np.all(c > 0):
                raise InputError(f"creep table: {name} must be positive of shape {shape[:2]}")
        if not np.all(np.isfinite(self.values)):
            raise InputError("creep table: node values contain NaN or infinite values (unfinished build?)")

    @property
    def content_hash(self) -> str:
        return content_hash(self.values, self.c11, self.c22, self.c23, _meta_text(self.meta))

    def ranges(self) -> dict:
        s = self.spec
        return {"a/b": [s.ratio_min, s.ratio_max], "nu": [s.nu_min, s.nu_max],
                "rho = hypot(nx, ny)": [0.0, s.rho_max], "|nphi|": [0.0, s.spin_max]}

    def info(self) -> dict:
        """What ``conformal table info`` prints."""
        return {"path": self.path, "format": FORMAT, "content_hash": self.content_hash,
                "shape": list(self.spec.shape), "nodes": self.spec.n_nodes, "ranges": self.ranges(),
                "spec": self.spec.to_dict(), **{k: v for k, v in self.meta.items() if k != "spec"}}


def _meta_text(meta: Mapping[str, Any]) -> str:
    return json.dumps(meta, sort_keys=True)


def content_hash(values, c11, c22, c23, meta_text: str) -> str:
    h = hashlib.sha256()
    for arr in (values, c11, c22, c23):
        a = np.ascontiguousarray(arr, dtype=np.float64)
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    h.update(meta_text.encode())
    return h.hexdigest()


def save_table(table: CreepTable, path: str | Path) -> Path:
    """Write ``table`` to ``path`` atomically (temporary file in the same folder, then rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    meta_text = _meta_text(table.meta)
    digest = content_hash(table.values, table.c11, table.c22, table.c23, meta_text)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "wb") as f:
            np.savez_compressed(f, values=table.values, c11=table.c11, c22=table.c22, c23=table.c23,
                                meta=np.array(meta_text), content_hash=np.array(digest),
                                format=np.array(FORMAT))
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def load_table(path: str | Path | None = None) -> CreepTable:
    """Load and verify a table; ``None`` (or ``"default"``) loads the table shipped with the package.

    >>> t = load_table()
    >>> t.spec.ratio_min <= 1.0 <= t.spec.ratio_max
    True
    """
    path = DEFAULT_TABLE if path in (None, "default") else Path(path)
    cached = _loaded.get(str(path))
    try:
        stamp = path.stat().st_mtime_ns
    except FileNotFoundError:
        raise InputError(f"creep table: file not found: {path}") from None
    if cached is not None and cached[0] == stamp:
        return cached[1]
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError) as exc:
        raise InputError(f"creep table: cannot read {path}: {exc}") from None
    missing = {"values", "c11", "c22", "c23", "meta", "content_hash", "format"} - set(data)
    if missing:
        raise InputError(f"creep table: {path} is not a creep-force table (missing {', '.join(sorted(missing))})")
    if int(data["format"]) != FORMAT:
        raise InputError(f"creep table: {path} has format {int(data['format'])}, this version reads {FORMAT}")
    meta_text = str(data["meta"])
    digest = content_hash(data["values"], data["c11"], data["c22"], data["c23"], meta_text)
    if digest != str(data["content_hash"]):
        raise InputError(f"creep table: {path} is corrupt or was modified (content hash mismatch)")
    meta = json.loads(meta_text)
    table = CreepTable(spec=TableSpec(**meta["spec"]), values=data["values"], c11=data["c11"],
                       c22=data["c22"], c23=data["c23"], meta=meta, path=str(path))
    _loaded[str(path)] = (stamp, table)
    return table


_loaded: dict[str, tuple[int, CreepTable]] = {}


# ----------------------------------------------------------------------------- evaluation
#: refinement factors of the evaluation grid along (ln a/b, nu, s, theta, q)
REFINE = (2, 1, 3, 2, 3)


@dataclass(frozen=True, eq=False)
class EvalGrid:
    """The table resampled for fast evaluation: tensor-product cubic splines (not-a-knot) of the
    node values along ln(a/b), s, theta and q (axes with >= 3 nodes) evaluated on a grid
    ``REFINE`` times finer, on which :func:`interpolate` is multilinear (linear in nu).  ``rows``
    packs, per cell along nu and q, the values at its four corners (nu0 q0, nu0 q1, nu1 q0, nu1 q1):
    shape ((n_nu - 1) n_t n_s n_theta (n_q - 1), 12), float32, so that one gather per corner of the
    other three axes fetches them.  ``c`` holds C11, C22, C23 on the refined (ln a/b, nu) grid (cubic in ln a/b)."""

    axes: tuple
    rows: np.ndarray
    c: np.ndarray
    strides: tuple


def _refined_axis(x: np.ndarray, factor: int) -> np.ndarray:
    if x.size == 1:
        return np.array([x[0], x[0] + 1.0])
    if x.size < 3 or factor == 1:
        return x.copy()
    return np.linspace(x[0], x[-1], (x.size - 1) * factor + 1)


def _resample(values: np.ndarray, x: np.ndarray, xf: np.ndarray, axis: int) -> np.ndarray:
    from scipy.interpolate import CubicSpline

    if x.size == 1:
        return np.repeat(values, 2, axis=axis)
    if xf.size == x.size:
        return values
    return CubicSpline(x, values, axis=axis)(xf)


def eval_grid(table: CreepTable) -> EvalGrid:
    """The (cached) evaluation grid of a table."""
    cached = table.__dict__.get("_eval")
    if cached is not None:
        return cached
    axes = table.spec.axes()
    fine = tuple(_refined_axis(x, f) for x, f in zip(axes, REFINE))
    v = table.values
    for k in range(5):
        v = _resample(v, axes[k], fine[k], k)
    packed = np.concatenate([v[..., :-1, :], v[..., 1:, :]], axis=-1)            # q cell ends
    packed = np.concatenate([packed[:, :-1], packed[:, 1:]], axis=-1).astype(np.float32)   # nu cell ends
    packed = np.moveaxis(packed, 1, 0)                       # nu cells outermost
    n_cells = packed.shape[0]
    dims = packed.shape[1:5]                                  # t, s, theta, q-cells
    strides = tuple(int(x) for x in np.cumprod((1,) + dims[::-1])[:-1][::-1])
    rows = np.ascontiguousarray(packed.reshape(n_cells * int(np.prod(dims)), 4 * N_OUT))
    c = np.stack([np.exp(_resample(np.log(ci), axes[0], fine[0], 0)) for ci in (table.c11, table.c22, table.c23)])
    if c.shape[2] == 1:
        c = np.repeat(c, 2, axis=2)
    grid = EvalGrid(fine, rows, c, strides)
    object.__setattr__(table, "_eval", grid)
    return grid


def _axis_position(x: np.ndarray, nodes: np.ndarray):
    """Cell index and weight on a uniform axis (x already inside [nodes[0], nodes[-1]])."""
    n = nodes.size
    u = (x - nodes[0]) * ((n - 1) / (nodes[-1] - nodes[0]))
    i = np.minimum(u.astype(np.intp), n - 2)
    np.maximum(i, 0, out=i)
    return i, u - i


def _check_range(name: str, x: np.ndarray, lo: float, hi: float, outside: str, bad: np.ndarray) -> np.ndarray:
    tol = 1e-9 * max(1.0, abs(lo), abs(hi))
    out = (x < lo - tol) | (x > hi + tol)
    if out.any():
        k = int(np.flatnonzero(out)[0])
        msg = (f"creep table: {name} = {x.flat[k]:.6g} outside the tabulated range [{lo:.6g}, {hi:.6g}]"
               f" ({int(out.sum())} of {x.size} contacts)")
        if outside == "error":
            raise InputError(msg)
        warnings.warn(msg + ("; clamped onto the range" if outside == "clamp" else "; NaN returned"),
                      RuntimeWarning, stacklevel=4)
        bad |= out
    return np.clip(x, lo, hi)


def _interp5(rows: np.ndarray, strides: tuple, cell_size: int, pos: list, out: np.ndarray) -> None:
    """Multilinear interpolation of the packed rows (:class:`EvalGrid`): 8 gathers of 12 values."""
    (it, wt), (iv, wv), (i_s, ws), (ith, wth), (iq, wq) = pos
    base = iv * cell_size + it * strides[0] + i_s * strides[1] + ith * strides[2] + iq
    wv, wq, wth, ws, wt = wv[:, None], wq[:, None], wth[:, None], ws[:, None], wt[:, None]
    n2, n3 = 2 * N_OUT, N_OUT
    lev = []
    for a in (0, strides[0]):
        for b in (0, strides[1]):
            pair = []
            for c in (0, strides[2]):
                g = rows[base + (a + b + c)]
                lo = g[:, :n2] + wv * (g[:, n2:] - g[:, :n2])          # nu
                pair.append(lo[:, :n3] + wq * (lo[:, n3:] - lo[:, :n3]))  # q
            lev.append(pair[0] + wth * (pair[1] - pair[0]))
    v0 = lev[0] + ws * (lev[1] - lev[0])
    v1 = lev[2] + ws * (lev[3] - lev[2])
    out[:] = v0 + wt * (v1 - v0)


def _interp4(rows: np.ndarray, strides: tuple, pos: list, out: np.ndarray) -> None:
    """Multilinear interpolation in (t, s, theta, q) of rows already blended in nu (6 values)."""
    (it, wt), (i_s, ws), (ith, wth), (iq, wq) = pos
    base = it * strides[0] + i_s * strides[1] + ith * strides[2] + iq
    wq, wth, ws, wt = wq[:, None], wth[:, None], ws[:, None], wt[:, None]
    lev = []
    for a in (0, strides[0]):
        for b in (0, strides[1]):
            pair = []
            for c in (0, strides[2]):
                g = rows[base + (a + b + c)]
                lo = g[:, :N_OUT]
                pair.append(lo + wq * (g[:, N_OUT:] - lo))
            lev.append(pair[0] + wth * (pair[1] - pair[0]))
    v0 = lev[0] + ws * (lev[1] - lev[0])
    v1 = lev[2] + ws * (lev[3] - lev[2])
    out[:] = v0 + wt * (v1 - v0)


def _nu_rows(table: CreepTable, g: EvalGrid, cell: int, w: float) -> np.ndarray:
    """The rows of nu cell ``cell`` blended at weight ``w`` (one material: one gather of 6 values
    per corner instead of 12); cached for the last few nu."""
    cache = table.__dict__.setdefault("_nu_rows", {})
    key = (cell, w)
    if key not in cache:
        if len(cache) >= 4:
            cache.clear()
        size = g.strides[0] * g.axes[0].size
        r = g.rows[cell * size:(cell + 1) * size]
        cache[key] = np.ascontiguousarray(r[:, :2 * N_OUT] + np.float32(w) * (r[:, 2 * N_OUT:] - r[:, :2 * N_OUT]))
    return cache[key]


def interpolate(table: CreepTable, ln_ratio, nu, s, theta, q) -> np.ndarray:
    """(fx, fy, mz) of Eq. T2 at points inside the axes (no range checks): returns (N, 3).

    Cubic splines of the node values (:func:`eval_grid`) sampled on a finer grid and read
    multilinearly there; linear in nu.  Exact at the nodes."""
    g = eval_grid(table)
    coords = [np.ravel(np.asarray(v, dtype=float)) for v in (ln_ratio, nu, s, theta, q)]
    N = coords[0].size
    out = np.empty((N, N_OUT))
    if N == 0:
        return out
    cell_size = g.strides[0] * g.axes[0].size
    nu_c = np.clip(coords[1], g.axes[1][0], g.axes[1][-1])
    one_nu = bool(np.all(nu_c == nu_c[0]))
    if one_nu:      # one material in the batch: blend the nu cell once
        iv, wv = _axis_position(nu_c[:1], g.axes[1])
        rows4 = _nu_rows(table, g, int(iv[0]), float(wv[0]))
    for lo in range(0, N, _CHUNK):
        sl = slice(lo, lo + _CHUNK)
        pos = [_axis_position(np.clip(coords[k][sl], g.axes[k][0], g.axes[k][-1]), g.axes[k]) for k in range(5)]
        if one_nu:
            _interp4(rows4, g.strides, [pos[0]] + pos[2:], out[sl])
        else:
            _interp5(g.rows, g.strides, cell_size, pos, out[sl])
    return out


def coefficients_at(table: CreepTable, ln_ratio, nu) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """C11, C22, C23 of Eq. T1 at (ln a/b, nu): cubic in ln(a/b) through the stored nodes (read
    linearly on the refined grid), linear in nu."""
    g = eval_grid(table)
    it, wt = _axis_position(np.clip(ln_ratio, g.axes[0][0], g.axes[0][-1]), g.axes[0])
    iv, wv = _axis_position(np.clip(nu, g.axes[1][0], g.axes[1][-1]), g.axes[1])
    c = g.c
    out = ((1 - wt) * ((1 - wv) * c[:, it, iv] + wv * c[:, it, iv + 1])
           + wt * ((1 - wv) * c[:, it + 1, iv] + wv * c[:, it + 1, iv + 1]))
    return out[0], out[1], out[2]


def evaluate(table: CreepTable | str | Path | None, a, b, FN, mu, G, nu, xi, eta, phi=0.0, *,
             outside: str = "error") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Creep forces FX, FY (N) and spin moment MZ (N mm, about the ellipse centre) from a table.

    Parameters
    ----------
    table : CreepTable, path, or None
        The table (None: the one shipped with the package, :func:`load_table`).
    a, b : array_like
        Semi-axes of the Hertzian contact (mm), a along the rolling direction.
    FN, mu, G, nu : array_like
        Normal force (N), friction coefficient, combined shear modulus (N/mm²) and Poisson's
        ratio (seed Eqs. 16-17).
    xi, eta, phi : array_like
        Creepages (-) and spin (rad/mm) of body 1 relative to body 2 (CONTACT's signs).
    outside : {"error", "nan", "clamp"}
        Points outside the tabulated ranges: InputError, NaN with a warning, or clamped onto the
        range with a warning.

    Returns
    -------
    FX, FY, MZ : ndarray
        Broadcast shape of the inputs.

    Examples
    --------
    A small creepage follows linear theory (seed Eq. 13), FX = -G ab C11 xi with Kalker's
    C11(a/b = 1, nu = 0.28) = 4.23 (the shipped table's exact solves on 24 elements across the
    patch are 4 % stiffer); a large one saturates at mu FN:

    >>> t = load_table()
    >>> FX, FY, MZ = evaluate(t, 6.0, 6.0, 1e5, 0.3, 82000.0, 0.28, [1e-5, 0.03], 0.0, 0.0)
    >>> round(float(FX[0] / (-82000.0 * 36 * 4.23 * 1e-5)), 2), round(float(FX[1] / 3e4), 2)
    (1.04, -1.0)
    """
    if outside not in OUTSIDE:
        raise InputError(f"creep table: outside must be one of {', '.join(OUTSIDE)}, got {outside!r}")
    if not isinstance(table, CreepTable):
        table = load_table(table)
    arrs = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (a, b, FN, mu, G, nu, xi, eta, phi)))
    shape = arrs[0].shape
    a, b, FN, mu, G, nu, xi, eta, phi = (x.ravel() for x in arrs)
    for name, v in (("a", a), ("b", b), ("FN", FN), ("mu", mu), ("G", G)):
        if not np.all(v > 0) or not np.all(np.isfinite(v)):
            k = int(np.flatnonzero(~((v > 0) & np.isfinite(v)))[0])
            raise InputError(f"creep table: {name} must be a positive finite number, got {v[k]!r}")
    for name, v in (("nu", nu), ("xi", xi), ("eta", eta), ("phi", phi)):
        if not np.all(np.isfinite(v)):
            raise InputError(f"creep table: {name} must be finite, got {v[np.flatnonzero(~np.isfinite(v))[0]]!r}")
    spec = table.spec
    bad = np.zeros(a.shape, dtype=bool)
    t = _check_range("a/b", a / b, spec.ratio_min, spec.ratio_max, outside, bad)
    t = np.log(t)
    nu_c = _check_range("nu", nu, spec.nu_min, spec.nu_max, outside, bad)
    c11, c22, c23 = coefficients_at(table, t, nu_c)
    kx, ky, kp = saturation_scales(a, b, FN, mu, G, c11, c22, c23)
    nx, ny, nphi = kx * xi, ky * eta, kp * phi
    rho = np.hypot(nx, ny)
    rho_c = _check_range("rho = hypot(nx, ny) (Eq. T1)", rho, 0.0, spec.rho_max, outside, bad)
    shrink = np.where(rho > rho_c, rho_c / np.where(rho > 0, rho, 1.0), 1.0)
    nphi = _check_range("nphi (Eq. T1)", nphi, -spec.spin_max, spec.spin_max, outside, bad)
    s, theta, q, sign_all, sign_y = polar(nx * shrink, ny * shrink, nphi)
    f = interpolate(table, t, nu_c, s, theta, q)
    if outside == "nan" and bad.any():
        f[bad] = np.nan
    scale = mu * FN * sign_all
    FX = scale * f[:, 0]
    FY = scale * sign_y * f[:, 1]
    MZ = scale * sign_y * np.sqrt(a * b) * f[:, 2]
    return FX.reshape(shape), FY.reshape(shape), MZ.reshape(shape)
