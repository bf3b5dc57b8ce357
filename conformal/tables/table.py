"""A creep-force table in memory and on disk (NPZ), and its vectorised evaluator.

File layout (``numpy.savez``, no pickles): ``values`` (n_ratio, n_nu, n_rho, n_theta, n_spin, 3)
= (fx, fy, mz) of Eq. T2 at the nodes (float32); ``c11, c22, c23`` (n_ratio, n_nu): the linear-theory
coefficients used in Eq. T1 at the (a/b, nu) nodes; ``meta``: JSON text (spec, ranges, grid,
solver tolerance, code version, build statistics); ``content_hash``: sha256 over the arrays and
``meta``, verified on load (a corrupt or edited file raises InputError, never loads silently).
A table refined in boxes (:class:`Patch`, ``conformal table refine``) also holds, per patch k,
``patchk_box`` (t0, t1, s0, s1, th0, th1 node index ranges), ``patchk_q`` (the extra q nodes) and
``patchk_values`` (fx, fy, mz there), all in the content hash.

Evaluation (:func:`evaluate`): Eq. T1 with Kalker's C11, C22, C23 at the contact's own (a/b, nu)
(the coefficients the build used, :mod:`conformal.theories.coefficients`, sampled finely in ln a/b
and nu), the symmetries and maps of Eqs. T3-T4, then (fx, fy, mz) from the tensor-product
interpolant (Eq. T5)::

    f(t, nu, s, theta, q) = sum over the cell corners of  H_t  L_nu  L_s  L_theta  L_q  f_fine    (T5)

where the node values of fx, fy (inside a patch's box with its extra q nodes) are first
interpolated along q by Akima's local cubic (Akima 1970: near the narrow ridges of the force along
the spin axis, where spin opposes the lateral creepage and the contact reaches full slip, a
not-a-knot spline rings into the neighbouring cells; Akima's slopes do not) and those of mz by a
not-a-knot spline (mz rises steeply but smoothly with small spin on slender contacts, a/b -> 0.25,
where Akima's slopes are the worse: measured 0.057 against 0.027 of mu FN sqrt(ab) at the worst of
600 points), then along s by the monotone cubic of Fritsch and Carlson (PCHIP) for fx, fy (the
force bends sharply where the contact reaches full slip, up to rho = 4; a spline overshot that knee
by 0.013 of mu FN) and a not-a-knot spline for mz, along theta by not-a-knot cubic splines (linear
in nu), sampled once on a
grid :func:`refine` times finer along s, theta, q (at least 43 x 25 x 89 points; :func:`eval_grid`);
H_t is the cubic Hermite basis
along ln(a/b) with the slopes of the not-a-knot spline through the a/b nodes (so the spline
itself, no resampling along t), L the linear weights on the fine grid (:func:`interpolate`).
Measured on the shipped table (studies/creep_table_scaling.py): about 1.5e6 contacts per CPU
second, varying nu included; the evaluation grid takes about 173 MB (float32).  Then
F = mu FN (fx, fy) and MZ = mu FN sqrt(ab) mz (Eq. T2).
Points outside the tabulated a/b, nu, rho or spin ranges raise InputError (``outside="error"``,
default), or give NaN with a RuntimeWarning (``outside="nan"``), or are clamped onto the range
with a RuntimeWarning (``outside="clamp"``): never a silent extrapolation.
"""
from __future__ import annotations

import hashlib
import json
import math
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from conformal.errors import ConformalError, InputError
from conformal.files import read_npz, save_npz_atomic
from conformal.tables.spec import N_OUT, TableSpec, polar, saturation_scales

#: format version of the NPZ file
FORMAT = 1
DEFAULT_TABLE = Path(__file__).resolve().parent.parent / "data" / "tables" / "creep_default.npz"
OUTSIDE = ("error", "nan", "clamp")
_CHUNK = 1 << 14


@dataclass(frozen=True, eq=False)
class Patch:
    """Extra nodes along q inside a box of the table (a targeted refinement).

    ``box`` = (t0, t1, s0, s1, th0, th1): half-open node index ranges along ln(a/b), s and theta
    (every nu); ``q``: the extra q coordinates (sorted, strictly between the table's q nodes);
    ``values``: (fx, fy, mz) of Eq. T2 there, shape (t1 - t0, n_nu, s1 - s0, th1 - th0, len(q), 3).
    Inside the box the evaluator interpolates along q through the table's and the extra nodes
    together (:func:`eval_grid`)."""

    box: tuple
    q: np.ndarray
    values: np.ndarray

    def check(self, spec: TableSpec) -> None:
        t0, t1, s0, s1, h0, h1 = self.box
        n_t, n_nu, n_s, n_th, n_q = spec.shape
        if not (0 <= t0 < t1 <= n_t and 0 <= s0 < s1 <= n_s and 0 <= h0 < h1 <= n_th):
            raise InputError(f"creep table patch: box {self.box} outside the table's nodes {spec.shape}")
        q, nodes = np.asarray(self.q, float), spec.axes()[4]
        if (n_q < 3 or q.ndim != 1 or q.size == 0 or np.any(np.diff(q) <= 0) or q[0] <= nodes[0]
                or q[-1] >= nodes[-1] or np.min(np.abs(q[:, None] - nodes[None, :])) < 1e-9):
            raise InputError("creep table patch: q must be sorted, inside the spin range and off the table's nodes")
        want = (t1 - t0, n_nu, s1 - s0, h1 - h0, q.size, N_OUT)
        if self.values.shape != want or not np.all(np.isfinite(self.values)):
            raise InputError(f"creep table patch: values of shape {self.values.shape}, need finite {want}")


@dataclass(frozen=True, eq=False)
class CreepTable:
    """Node values of a creep-force table (see the module docstring for the layout), with any
    targeted refinements (:class:`Patch`, disjoint boxes)."""

    spec: TableSpec
    values: np.ndarray
    c11: np.ndarray
    c22: np.ndarray
    c23: np.ndarray
    meta: Mapping[str, Any] = field(default_factory=dict)
    path: str | None = None
    patches: tuple = ()

    def __post_init__(self):
        # node values in float32 (7 digits; the solves' tolerance is 1e-6): half the file size, and
        # the same content hash in memory and on disk
        object.__setattr__(self, "values", np.asarray(self.values, dtype=np.float32))
        object.__setattr__(self, "patches", tuple(replace(p, values=np.asarray(p.values, dtype=np.float32))
                                                  for p in self.patches))
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
        for k, p in enumerate(self.patches):
            p.check(self.spec)
            for o in self.patches[:k]:
                if all(max(p.box[i], o.box[i]) < min(p.box[i + 1], o.box[i + 1]) for i in (0, 2, 4)):
                    raise InputError(f"creep table: patch boxes {o.box} and {p.box} overlap")

    @property
    def content_hash(self) -> str:
        return content_hash(self.values, self.c11, self.c22, self.c23, _meta_text(self.meta), self.patches)

    def ranges(self) -> dict:
        s = self.spec
        return {"a/b": [s.ratio_min, s.ratio_max], "nu": [s.nu_min, s.nu_max],
                "rho = hypot(nx, ny)": [0.0, s.rho_max], "|nphi|": [0.0, s.spin_max]}

    def info(self) -> dict:
        """What ``conformal table info`` prints."""
        return {"path": self.path, "format": FORMAT, "content_hash": self.content_hash,
                "shape": list(self.spec.shape), "nodes": self.spec.n_nodes, "ranges": self.ranges(),
                "spec": self.spec.to_dict(), **{k: v for k, v in self.meta.items() if k != "spec"},
                "patch_nodes": int(sum(p.values.size // N_OUT for p in self.patches))}


def _meta_text(meta: Mapping[str, Any]) -> str:
    return json.dumps(meta, sort_keys=True)


def content_hash(values, c11, c22, c23, meta_text: str, patches: tuple = ()) -> str:
    h = hashlib.sha256()
    arrays = [values, c11, c22, c23]
    for p in patches:
        arrays += [np.asarray(p.box, dtype=np.float64), p.q, p.values]
    for arr in arrays[:4]:
        a = np.ascontiguousarray(arr, dtype=np.float64)
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    h.update(meta_text.encode())
    for arr in arrays[4:]:            # after the meta: a table without patches keeps its hash
        a = np.ascontiguousarray(arr, dtype=np.float64)
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _patch_arrays(patches: tuple) -> dict:
    out = {}
    for k, p in enumerate(patches):
        out[f"patch{k}_box"] = np.asarray(p.box, dtype=np.int64)
        out[f"patch{k}_q"] = np.asarray(p.q, dtype=np.float64)
        out[f"patch{k}_values"] = np.asarray(p.values, dtype=np.float32)
    return out


def save_table(table: CreepTable, path: str | Path) -> Path:
    """Write ``table`` to ``path`` atomically (:func:`save_npz_atomic`)."""
    meta_text = _meta_text(table.meta)
    digest = content_hash(table.values, table.c11, table.c22, table.c23, meta_text, table.patches)
    return save_npz_atomic(path, compressed=True, values=table.values, c11=table.c11, c22=table.c22,
                           c23=table.c23, meta=np.array(meta_text), content_hash=np.array(digest),
                           format=np.array(FORMAT), **_patch_arrays(table.patches))


def _require_npz(path: Path) -> None:
    """InputError "not a creep table" unless the file starts as a zip archive (an .npz): numpy would
    try any other file as a pickle and advise allow_pickle."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4)
    except OSError as exc:
        raise InputError(f"creep table: cannot read {path}: {exc.strerror or exc}") from None
    if head != b"PK\x03\x04":
        raise InputError(f"creep table: cannot read {path}: not a creep table (not an .npz file; "
                         "`conformal table build` writes one)")


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
    _require_npz(path)
    try:
        data = read_npz(path)
    except (OSError, ValueError) as exc:
        raise InputError(f"creep table: cannot read {path}: {exc}") from None
    missing = {"values", "c11", "c22", "c23", "meta", "content_hash", "format"} - set(data)
    if missing:
        raise InputError(f"creep table: {path} is not a creep-force table (missing {', '.join(sorted(missing))})")
    if int(data["format"]) != FORMAT:
        raise InputError(f"creep table: {path} has format {int(data['format'])}, this version reads {FORMAT}")
    meta_text = str(data["meta"])
    patches = []
    while f"patch{len(patches)}_values" in data:
        k = len(patches)
        try:
            patches.append(Patch(tuple(int(i) for i in data[f"patch{k}_box"]), data[f"patch{k}_q"],
                                 data[f"patch{k}_values"]))
        except (KeyError, ValueError, TypeError):
            raise InputError(f"creep table: {path} has an incomplete patch {k}") from None
    digest = content_hash(data["values"], data["c11"], data["c22"], data["c23"], meta_text, tuple(patches))
    if digest != str(data["content_hash"]):
        raise InputError(f"creep table: {path} is corrupt or was modified (content hash mismatch)")
    meta = json.loads(meta_text)
    table = CreepTable(spec=TableSpec(**meta["spec"]), values=data["values"], c11=data["c11"],
                       c22=data["c22"], c23=data["c23"], meta=meta, path=str(path), patches=tuple(patches))
    _loaded[str(path)] = (stamp, table)
    return table


_loaded: dict[str, tuple[int, CreepTable]] = {}


# ----------------------------------------------------------------------------- evaluation
#: the least number of points of the evaluation grid along (ln a/b, nu, s, theta, q) (0: the nodes;
#: ln a/b is cubic Hermite between its nodes, nu linear).  Chosen on the 300 points of
#: studies/creep_table_accuracy.py with the 7 x 22 x 9 x 23-node table: factors (1, 1, 2, 3, 4), max
#: 0.0077 / mean 0.0012 of mu FN with a 64 MB grid; (1, 1, 2, 3, 3) 0.0090 / 0.0012 with 48 MB;
#: (1, 1, 2, 2, 3) 0.0094 / 0.0014 with 32 MB
MIN_SAMPLES = (0, 0, 43, 25, 89)


def refine(spec) -> tuple:
    """How many times finer than the table's nodes the evaluation grid samples each axis (ln a/b,
    nu, s, theta, q): the least whole factor that gives at least ``MIN_SAMPLES`` points along s,
    theta and q (the nodes themselves along ln a/b and nu): (1, 1, 2, 3, 4) for 22 x 9 x 23 nodes,
    (1, 1, 2, 2, 2) for the shipped table's 32 x 13 x 45 (63 x 25 x 89 samples).

    >>> from conformal.tables.spec import TableSpec
    >>> refine(TableSpec(n_rho=22, n_theta=9, n_spin=23)), refine(TableSpec(n_rho=32, n_theta=13, n_spin=45))
    ((1, 1, 2, 3, 4), (1, 1, 2, 2, 2))
    """
    n = (spec.n_ratio, spec.n_nu, spec.n_rho, spec.n_theta, spec.n_spin)
    return tuple(1 if m == 0 or k < 2 else max(1, math.ceil((m - 1) / (k - 1))) for k, m in zip(n, MIN_SAMPLES))


#: fine points per table cell of the (ln a/b, nu) grid on which C11, C22, C23 are read
C_REFINE = (32, 8)


@dataclass(frozen=True, eq=False)
class EvalGrid:
    """The table resampled for fast evaluation (Eq. T5 of the module docstring).

    The node values are interpolated along q by Akima's local cubic for fx, fy (Akima 1970, J.
    ACM 17, 589-602: slopes from the neighbouring secants weighted by the jumps of the secant; no
    ringing next to the ridges of the spin axis) and a not-a-knot spline for mz, then along s by
    PCHIP for fx, fy (no overshoot at the knee of full slip) and a spline for mz, by not-a-knot
    cubic splines along theta (linear in nu), and sampled on a grid :func:`refine`
    times finer along s, theta, q; along ln(a/b) the nodes are kept with the slopes of the
    not-a-knot spline through them (cubic Hermite in :func:`interpolate`).  ``rows`` packs, per
    cell along nu and q, the values and ln(a/b) slopes at its four corners (nu0 q0, nu0 q1, nu1
    q0, nu1 q1): shape ((n_nu - 1) n_t n_s n_theta (n_q - 1), 24), float32, ordered (nu end, q
    end, value | slope, output), so that one gather of 8 rows (the corners along t, s, theta)
    fetches everything a point needs.  ``c`` holds rows (C11, C22, C23) on the fine (ln a/b, nu) grid
    ``c_axes`` (Kalker's coefficients of :mod:`conformal.theories.coefficients` itself where the
    table's node coefficients are those, else cubic in ln a/b through the stored nodes, linear
    in nu)."""

    axes: tuple
    rows: np.ndarray
    c: np.ndarray
    strides: tuple
    offsets: np.ndarray
    c_axes: tuple
    cell_size: int


def _refined_axis(x: np.ndarray, factor: int) -> np.ndarray:
    if x.size == 1:
        return np.array([x[0], x[0] + 1.0])
    if x.size < 3 or factor == 1:
        return x.copy()
    return np.linspace(x[0], x[-1], (x.size - 1) * factor + 1)


def _resample(values: np.ndarray, x: np.ndarray, xf: np.ndarray, axis: int, method: str = "spline") -> np.ndarray:
    """``values`` sampled at ``xf`` along ``axis``: not-a-knot cubic spline through the nodes ``x``
    (``"spline"``), Akima's local cubic (``"akima"``, with >= 5 nodes) or the monotone piecewise
    cubic of Fritsch and Carlson (``"pchip"``, with >= 3 nodes); an axis of one node is repeated."""
    from scipy.interpolate import Akima1DInterpolator, CubicSpline, PchipInterpolator

    if x.size == 1:
        return np.repeat(values, 2, axis=axis)
    if xf.size == x.size and np.array_equal(xf, x):
        return values
    if method == "akima" and x.size >= 5:
        return Akima1DInterpolator(x, values, axis=axis)(xf)
    if method == "pchip" and x.size >= 3:
        return PchipInterpolator(x, values, axis=axis)(xf)
    return CubicSpline(x, values, axis=axis)(xf)


def _force_resample(values: np.ndarray, x: np.ndarray, xf: np.ndarray, axis: int, method: str) -> np.ndarray:
    """fx, fy (the first two outputs) resampled by ``method``, mz by the not-a-knot spline."""
    return np.concatenate([_resample(values[..., :2], x, xf, axis, method), _resample(values[..., 2:], x, xf, axis)],
                          axis=-1)


def _q_resample(values: np.ndarray, q: np.ndarray, qf: np.ndarray) -> np.ndarray:
    """Along q (axis 4): Akima for fx, fy, not-a-knot spline for mz (Eq. T5)."""
    return _force_resample(values, q, qf, 4, "akima")


def _linear_resample(values: np.ndarray, x: np.ndarray, xf: np.ndarray, axis: int) -> np.ndarray:
    if x.size == 1:
        return np.repeat(values, xf.size, axis=axis)
    i, w = _axis_position(xf, x)
    shape = [1] * values.ndim
    shape[axis] = xf.size
    w = w.reshape(shape)
    return np.take(values, i, axis=axis) * (1 - w) + np.take(values, i + 1, axis=axis) * w


def _coefficient_grid(table: CreepTable, axes: tuple) -> tuple[tuple, np.ndarray]:
    """C11, C22, C23 on the fine (ln a/b, nu) grid: rows (n_t n_nu, 3) in C order, and its axes
    (an axis of one node gets a second, repeated one)."""
    t, nu = axes[:2]
    tf, nf = (np.linspace(x[0], x[-1], (x.size - 1) * f + 1) if x.size > 1 else _refined_axis(x, f)
              for x, f in ((t, C_REFINE[0]), (nu, C_REFINE[1])))
    tr, nr = (tf if t.size > 1 else t), (nf if nu.size > 1 else nu)      # the real points
    nodes = np.stack([table.c11, table.c22, table.c23], axis=-1)            # (n_t, n_nu, 3)
    try:
        from conformal.theories.coefficients import coefficient_arrays

        def kalker(tt, nn):
            T, NU = np.meshgrid(np.exp(tt), nn, indexing="ij")
            return np.stack(coefficient_arrays(T, NU), axis=-1)

        same = np.allclose(kalker(t, nu), nodes, rtol=1e-9, atol=0.0)   # the build's own coefficients
    except ConformalError:      # outside the coefficient table: interpolate the stored nodes
        same = False
    if same:
        c = kalker(tr, nr)
    else:
        lnc = np.log(nodes) if t.size == 1 else _resample(np.log(nodes), t, tr, 0)   # cubic in ln a/b
        c = np.exp(_linear_resample(lnc, nu, nr, 1))                                  # linear in nu
    if t.size == 1:
        c = np.repeat(c, 2, axis=0)
    if nu.size == 1:
        c = np.repeat(c, 2, axis=1)
    return (tf, nf), np.ascontiguousarray(c.reshape(-1, 3))


def eval_grid(table: CreepTable) -> EvalGrid:
    """The (cached) evaluation grid of a table."""
    cached = table.__dict__.get("_eval")
    if cached is not None:
        return cached
    from scipy.interpolate import CubicSpline

    axes = table.spec.axes()
    fine = tuple(_refined_axis(x, f) for x, f in zip(axes, refine(table.spec)))
    v = _q_resample(table.values, axes[4], fine[4])          # q first: Akima (F), spline (MZ)
    for p in table.patches:                                 # boxes with extra q nodes
        t0, t1, s0, s1, h0, h1 = p.box
        q = np.concatenate([axes[4], p.q])
        order = np.argsort(q)
        merged = np.concatenate([table.values[t0:t1, :, s0:s1, h0:h1], p.values], axis=4)[:, :, :, :, order]
        v[t0:t1, :, s0:s1, h0:h1] = _q_resample(merged, q[order], fine[4])
    v = _resample(v, axes[1], fine[1], 1)
    v = _force_resample(v, axes[2], fine[2], 2, "pchip")     # s: monotone, no overshoot at full slip
    v = _resample(v, axes[3], fine[3], 3)
    t = axes[0]
    if t.size == 1:
        vt = np.repeat(v, 2, axis=0)
        dv = np.zeros_like(vt)
    else:                    # ln a/b: the not-a-knot spline's values and slopes at its nodes
        vt = v
        dv = CubicSpline(t, v, axis=0)(t, 1) * (fine[0][1] - fine[0][0])   # slope per cell
    v = np.stack([vt, dv], axis=-2)                                          # (..., 2, 3)
    packed = np.concatenate([v[:, :, :, :, :-1], v[:, :, :, :, 1:]], axis=-2)            # q cell ends
    packed = np.concatenate([packed[:, :-1], packed[:, 1:]], axis=-1)             # nu cell ends
    # (t, nu cells, s, theta, q cells, [q0 f, q0 f', q1 f, q1 f'], [nu0, nu1] x 3) -> 24 values
    # ordered (nu end, q end, f | f', output)
    packed = packed.reshape(packed.shape[:5] + (2, 2, 2, N_OUT))            # q end, kind, nu end, out
    packed = np.moveaxis(packed, 7, 5)                                       # nu end, q end, kind, out
    packed = np.moveaxis(packed, 1, 0).astype(np.float32)                   # nu cells outermost
    n_cells = packed.shape[0]
    dims = packed.shape[1:5]                                  # t, s, theta, q-cells
    strides = tuple(int(x) for x in np.cumprod((1,) + dims[::-1])[:-1][::-1])
    rows = np.ascontiguousarray(packed.reshape(n_cells * int(np.prod(dims)), 8 * N_OUT))
    offsets = np.array([i + j + k for i in (0, strides[0]) for j in (0, strides[1]) for k in (0, strides[2])],
                       dtype=np.intp)
    c_axes, c = _coefficient_grid(table, axes)
    grid = EvalGrid(fine, rows, c, strides, offsets, c_axes, strides[0] * dims[0])
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


def _pair(w: np.ndarray) -> np.ndarray:
    """Linear weights (1 - w, w) of the two ends of a cell: (n, 2) float32."""
    w = w.astype(np.float32)
    return np.stack([1 - w, w], axis=1)


def _hermite(w: np.ndarray) -> np.ndarray:
    """Cubic Hermite weights of (f0, f0', f1, f1') at w in [0, 1] (slopes per cell): (n, 2, 2)."""
    w = w.astype(np.float32)
    w2 = w * w
    w3 = w2 * w
    return np.stack([2 * w3 - 3 * w2 + 1, w3 - 2 * w2 + w, 3 * w2 - 2 * w3, w3 - w2], axis=1).reshape(-1, 2, 2)


def _interp(g: EvalGrid, pos: list, out: np.ndarray) -> None:
    """Cubic Hermite along ln(a/b), multilinear along the others: one gather of the 8 packed rows
    (t, s, theta corners) x 24 values (nu, q corners, value and ln a/b slope, 3 outputs), then
    one small matrix product with the 64 weights (built by outer products, as batched matrix
    products: numpy's fastest path for many tiny arrays)."""
    (it, wt), (iv, wv), (i_s, ws), (ith, wth), (iq, wq) = pos
    st = g.strides
    base = iv * g.cell_size + it * st[0] + i_s * st[1] + ith * st[2] + iq
    corners = np.take(g.rows, base[:, None] + g.offsets, axis=0)             # (n, 8, 24)
    n = base.size
    s_, th_, v_, q_, h_ = _pair(ws), _pair(wth), _pair(wv), _pair(wq), _hermite(wt)
    bc = np.matmul(s_[:, :, None], th_[:, None, :]).reshape(n, 4, 1)          # s x theta
    vq = np.matmul(v_[:, :, None], q_[:, None, :]).reshape(n, 1, 4)           # nu x q
    bcvq = np.matmul(bc, vq).reshape(n, 16, 1)
    w = np.empty((n, 2, 16, 2), dtype=np.float32)                            # (t end, s th nu q, kind)
    np.matmul(bcvq, h_[:, 0, None, :], out=w[:, 0])
    np.matmul(bcvq, h_[:, 1, None, :], out=w[:, 1])
    out[:] = np.matmul(w.reshape(n, 1, 64), corners.reshape(n, 64, N_OUT))[:, 0]


def interpolate(table: CreepTable, ln_ratio, nu, s, theta, q) -> np.ndarray:
    """(fx, fy, mz) of Eq. T2 at points inside the axes (no range checks): returns (N, 3).

    Eq. T5: Akima along q (fx, fy; a not-a-knot spline for mz), cubic splines along s, theta
    sampled on a finer grid (:func:`eval_grid`) and read linearly there, cubic Hermite along
    ln(a/b) with the not-a-knot spline's slopes, linear in nu.  Exact at the nodes.

    >>> t = load_table()
    >>> f = interpolate(t, 0.0, 0.28, 0.0, 0.0, 0.0)      # no creepage, no force
    >>> bool(np.all(np.abs(f) < 1e-6))
    True
    """
    g = eval_grid(table)
    coords = [np.ravel(v) for v in
              np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (ln_ratio, nu, s, theta, q)))]
    N = coords[0].size
    out = np.empty((N, N_OUT))
    for lo in range(0, N, _CHUNK):
        sl = slice(lo, lo + _CHUNK)
        pos = [_axis_position(np.clip(coords[k][sl], g.axes[k][0], g.axes[k][-1]), g.axes[k]) for k in range(5)]
        _interp(g, pos, out[sl])
    return out


def coefficients_at(table: CreepTable, ln_ratio, nu) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """C11, C22, C23 of Eq. T1 at (ln a/b, nu): bilinear on the fine grid of :func:`eval_grid`
    (Kalker's coefficients, :mod:`conformal.theories.coefficients`, sampled 32 times per a/b
    cell and 8 times per nu cell)."""
    g = eval_grid(table)
    ta, na = g.c_axes
    it, wt = _axis_position(np.clip(ln_ratio, ta[0], ta[-1]), ta)
    iv, wv = _axis_position(np.clip(nu, na[0], na[-1]), na)
    k = it * na.size + iv
    wt, wv = wt[:, None], wv[:, None]
    c = g.c
    out = ((1 - wt) * ((1 - wv) * np.take(c, k, axis=0) + wv * np.take(c, k + 1, axis=0))
           + wt * ((1 - wv) * np.take(c, k + na.size, axis=0) + wv * np.take(c, k + na.size + 1, axis=0)))
    return out[:, 0], out[:, 1], out[:, 2]


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
