"""Building a creep-force table: one exact steady-rolling solve per node, as chunked jobs.

``conformal table build SPEC.toml --out TABLE.npz [--workers N] [--scheduler ADDRESS]``

Nodes (:class:`~conformal.tables.spec.TableSpec`, Eqs. T1-T4) are numbered in C order over
(ln a/b, nu, s, theta, q) and cut into chunks of ``[build] chunk`` nodes.  Every chunk is one task
(:func:`solve_chunk`) of :func:`conformal.jobs.run_tasks`: in this process, a pool of local
processes (``--workers N``), a Dask LocalCluster (``--scheduler local``) or any Dask scheduler
(``--scheduler tcp://host:8786``).  Workers return the node values; this process writes each
finished chunk atomically (temporary file + rename) into ``TABLE.npz.parts/<spec digest>/``, so
an interrupted build (Ctrl-C, a lost worker, a failed chunk) keeps its finished chunks and the
same command resumes with the rest.  When all chunks are there the table is assembled, written
atomically with its metadata and content hash (:func:`conformal.tables.table.save_table`), and
the chunk folder removed.

Each node: semi-axes with ab = 1 on :func:`conformal.theories.c33.grid_for` (``[solver] grid_n``
elements across the short axis of the box 1.1a x 1.1b), G = 82000 N/mm², mu = 0.3, FN = 100 N
(the outputs of Eq. T2 do not depend on these), creepages from Eq. T1 inverted with Kalker's
C11, C22, C23 at the node, steady rolling by the exact theory as in
:func:`conformal.solvers.exact.solve`, with the normal problem (:func:`~conformal.solvers.normal.
solve_normal`) solved once per (a/b, nu) and the tangential problem (:func:`~conformal.solvers.
tangential.solve_tangential`) per node, started from the previous node's tractions
(:class:`SliceSolver`; measured within 2e-8 of cold-started ``exact.solve`` and 1.6x faster).
:func:`solve_points` (the reference of the accuracy checks) calls ``exact.solve`` itself.

A targeted partial rebuild (``conformal table refine``, :func:`add_patch`) adds extra q nodes in
a box of a built table: one task per (a/b, nu) node pair (:func:`solve_patch_slice`), finished
tasks kept in ``OUT.npz.parts/patch_<digest>/`` as for a build, the result a
:class:`~conformal.tables.table.Patch` stored with the table.
"""
from __future__ import annotations

import hashlib
import json
import math
import platform
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from conformal._threads import single_threaded_blas
from conformal.errors import ConformalError, InputError
from conformal.files import read_npz, save_npz_atomic
from conformal.tables.spec import N_OUT, TableSpec, creepages_of_node, saturation_scales
from conformal.tables.table import CreepTable, save_table

#: code version of the node values (bump when the node solve changes)
TABLE_VERSION = "1"
_G, _MU, _FN = 82000.0, 0.3, 100.0


@dataclass(frozen=True)
class NodeResult:
    """(fx, fy, mz) of Eq. T2 at one node, the solver's convergence and its wall time."""

    fx: float
    fy: float
    mz: float
    converged: bool
    wall_s: float


def node_coefficients(spec: TableSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kalker's C11, C22, C23 (conformal.theories.coefficients) at the (a/b, nu) nodes."""
    from conformal.theories.coefficients import coefficient_arrays

    t, nu = spec.axes()[:2]
    T, NU = np.meshgrid(np.exp(t), nu, indexing="ij")
    c11, c22, c23 = coefficient_arrays(T, NU)
    return np.asarray(c11, float), np.asarray(c22, float), np.asarray(c23, float)


def exact_problem(a_over_b: float, nu: float, xi: float, eta: float, phi: float, *, grid_n: int,
                  tol: float, G: float = _G, mu: float = _MU, FN: float = _FN):
    """The Hertzian steady-rolling problem with ab = 1 mm² that a node (or a check) solves exactly."""
    from conformal.materials import Material
    from conformal.problem import ContactProblem
    from conformal.scene import Friction, Kinematics, ModelSpec
    from conformal.theories.c33 import grid_for
    from conformal.theories.hertz import hertz_from_semiaxes

    a, b, grid = grid_for(a_over_b, grid_n)
    mat = Material.identical(G, nu)
    hz = hertz_from_semiaxes(a, b, mat, normal_force=FN)
    X, Y = grid.mesh()
    return ContactProblem(material=mat, friction=Friction(mu, mu), kinematics=Kinematics(xi=xi, eta=eta, phi=phi),
                          model=ModelSpec(theory="exact", tol=tol), normal_force=FN, hertz=hz, grid=grid,
                          h=hz.A * X**2 + hz.B * Y**2, label="table node")


def solve_normalised(a_over_b: float, nu: float, nx: float, ny: float, nphi: float, c: tuple[float, float, float],
                     *, grid_n: int, tol: float) -> NodeResult:
    """(fx, fy, mz) of Eq. T2 by the exact theory at normalised creepages (nx, ny, nphi) of Eq. T1
    with the coefficients c = (C11, C22, C23)."""
    from conformal.solvers.exact import solve

    a, b = math.sqrt(a_over_b), 1.0 / math.sqrt(a_over_b)
    kx, ky, kp = (float(k) for k in saturation_scales(a, b, _FN, _MU, _G, *c))
    t0 = time.perf_counter()
    r = solve(exact_problem(a_over_b, nu, nx / kx, ny / ky, nphi / kp, grid_n=grid_n, tol=tol))
    muFN = _MU * r.FN
    return NodeResult(r.FX / muFN, r.FY / muFN, r.MZ / (muFN * math.sqrt(a * b)), bool(r.converged),
                      time.perf_counter() - t0)


@dataclass(frozen=True)
class Chunk:
    """Nodes start..stop-1 (flat C-order index) of a table build."""

    spec: TableSpec
    index: int
    start: int
    stop: int


class SliceSolver:
    """The nodes of one (a/b, nu): the grid, the influence operator and the normal problem are the
    same for every creepage (quasi-identical bodies: the problems decouple, as in
    :func:`conformal.solvers.exact.solve`), so they are set up once; each node then solves the
    tangential problem (:func:`conformal.solvers.tangential.solve_tangential`) starting from the
    previous node's tractions (neighbouring nodes, nearly the same solution: fewer Newton steps)."""

    def __init__(self, a_over_b: float, nu: float, c: tuple[float, float, float], *, grid_n: int, tol: float,
                 maxit: int = 1000):
        from conformal.influence.operator import build_operator
        from conformal.solvers.normal import solve_normal

        self.problem = exact_problem(a_over_b, nu, 0.0, 0.0, 0.0, grid_n=grid_n, tol=tol)
        g, mat = self.problem.grid, self.problem.material
        self.op, _ = build_operator(g, mat)
        self.normal = solve_normal(self.op, g, self.problem.h, normal_force=_FN, tol=tol, maxit=maxit)
        if not self.normal.converged:
            raise ConformalError(f"table node a/b = {a_over_b:g}, nu = {nu:g}: normal problem not converged")
        self.X, self.Y = g.mesh()
        self.FN = float(self.normal.pn.sum() * g.area)
        self.ab = 1.0
        a, b = math.sqrt(a_over_b), 1.0 / math.sqrt(a_over_b)
        self.k = tuple(float(k) for k in saturation_scales(a, b, _FN, _MU, _G, *c))
        self.tol, self.maxit, self.p_prev = tol, maxit, None

    def solve(self, nx: float, ny: float, nphi: float) -> NodeResult:
        from conformal.solvers.tangential import solve_tangential

        t0 = time.perf_counter()
        g = self.problem.grid
        kx, ky, kp = self.k
        t = solve_tangential(self.op, g, self.normal.pn, xi=nx / kx, eta=ny / ky, phi=nphi / kp, mu_static=_MU,
                             mu_kinetic=_MU, tol=self.tol, maxit=self.maxit, p_start=self.p_prev)
        if not t.converged:   # retry from zero tractions before giving up on the warm start
            t = solve_tangential(self.op, g, self.normal.pn, xi=nx / kx, eta=ny / ky, phi=nphi / kp,
                                 mu_static=_MU, mu_kinetic=_MU, tol=self.tol, maxit=self.maxit)
        self.p_prev = np.stack([t.px, t.py])
        dA, muFN = g.area, _MU * self.FN
        FX, FY = float(t.px.sum() * dA), float(t.py.sum() * dA)
        MZ = float((self.X * t.py - self.Y * t.px).sum() * dA)
        return NodeResult(FX / muFN, FY / muFN, MZ / (muFN * math.sqrt(self.ab)), bool(t.converged),
                          time.perf_counter() - t0)


def solve_chunk(chunk: Chunk) -> dict:
    """Worker: solve every node of a chunk.  Returns {"values": (n, 3), "converged": (n,),
    "wall_s": total solve time, "host": worker host name}.  BLAS runs on one thread in the worker
    (threadpoolctl, :func:`conformal._threads.single_threaded_blas`: numpy is loaded by then, so an
    environment variable set here would have no effect)."""
    with single_threaded_blas():
        return _solve_chunk(chunk)


def _solve_chunk(chunk: Chunk) -> dict:
    spec = chunk.spec
    axes = spec.axes()
    c11, c22, c23 = node_coefficients(spec)
    idx = np.unravel_index(np.arange(chunk.start, chunk.stop), spec.shape)
    vals = np.empty((chunk.stop - chunk.start, N_OUT))
    conv = np.empty(chunk.stop - chunk.start, dtype=bool)
    t0 = time.perf_counter()
    solver, key = None, None
    for k in range(chunk.stop - chunk.start):
        it, iv, i_s, ith, iq = (int(i[k]) for i in idx)
        if (it, iv) != key:
            key = (it, iv)
            solver = SliceSolver(math.exp(axes[0][it]), float(axes[1][iv]), (c11[it, iv], c22[it, iv], c23[it, iv]),
                                 grid_n=spec.grid_n, tol=spec.tol)
        r = solver.solve(*creepages_of_node(axes[2][i_s], axes[3][ith], axes[4][iq]))
        vals[k] = (r.fx, r.fy, r.mz)
        conv[k] = r.converged
    return {"values": vals, "converged": conv, "wall_s": time.perf_counter() - t0, "host": platform.node()}


# ----------------------------------------------------------------------------- chunk files
def parts_folder(out: str | Path, spec: TableSpec) -> Path:
    """Where the finished chunks of a build of ``spec`` into ``out`` are kept."""
    out = Path(out)
    return out.with_name(out.name + ".parts") / spec.digest()[:16]


def _chunk_path(folder: Path, index: int) -> Path:
    return folder / f"chunk_{index:06d}.npz"


def write_chunk(folder: Path, chunk: Chunk, result: dict) -> Path:
    """Atomic write of one finished chunk."""
    return save_npz_atomic(_chunk_path(folder, chunk.index), values=result["values"], converged=result["converged"],
                           wall_s=result["wall_s"], start=chunk.start, stop=chunk.stop,
                           digest=np.array(chunk.spec.digest()))


def read_chunk(folder: Path, chunk: Chunk) -> dict | None:
    """A finished chunk, or None if it is missing, unreadable or from another spec/range."""
    path = _chunk_path(folder, chunk.index)
    if not path.is_file():
        return None
    try:
        z = read_npz(path)
        ok = (str(z["digest"]) == chunk.spec.digest() and int(z["start"]) == chunk.start
              and int(z["stop"]) == chunk.stop and z["values"].shape == (chunk.stop - chunk.start, N_OUT)
              and np.all(np.isfinite(z["values"])))
        return {"values": z["values"], "converged": z["converged"], "wall_s": float(z["wall_s"])} if ok else None
    except (OSError, ValueError, KeyError, TypeError):   # unreadable, truncated or foreign: solved again
        return None


def chunks(spec: TableSpec) -> list[Chunk]:
    n = spec.n_nodes
    return [Chunk(spec, k, lo, min(lo + spec.chunk, n)) for k, lo in enumerate(range(0, n, spec.chunk))]


# ----------------------------------------------------------------------------- build
@dataclass
class BuildReport:
    """What a build did: chunks planned / already finished / solved / failed, wall and solve time."""

    chunks: int
    resumed: int
    solved: int
    failed: list
    nodes: int
    wall_s: float
    solve_s: float
    path: Path | None
    nonconverged: int = 0      # nodes of the written table whose exact solve did not converge

    def summary(self) -> str:
        text = (f"{self.nodes} nodes in {self.chunks} chunks: {self.resumed} already done, {self.solved} solved"
                + (f", {len(self.failed)} FAILED" if self.failed else "")
                + (f", {self.nonconverged} NOT CONVERGED" if self.nonconverged else "") + f" ({self.wall_s:.1f} s")
        if self.solved:
            text += f", {self.solve_s:.1f} s of solves"
        text += ")"
        return text + (f"; wrote {self.path}" if self.path else "; table not written (rerun to resume)")


def build_table(spec: TableSpec, out: str | Path, *, workers: int = 1, scheduler: str | None = None,
                progress: bool = True, keep_parts: bool = False) -> BuildReport:
    """Build (or resume building) the table of ``spec`` into ``out`` (see the module docstring).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> spec = TableSpec(ratio_min=1.0, ratio_max=1.0, n_ratio=1, nu_min=0.28, nu_max=0.28, n_nu=1,
    ...                  rho_max=1.0, n_rho=2, n_theta=2, spin_max=0.0, n_spin=1, grid_n=8, chunk=2)
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "t.npz"
    >>> rep = build_table(spec, out, progress=False)
    >>> rep.solved, rep.failed, out.is_file()
    (2, [], True)
    """
    from conformal.jobs import run_tasks

    out = Path(out)
    if workers < 1:
        raise InputError(f"--workers: must be >= 1, got {workers}")
    t0 = time.perf_counter()
    folder = parts_folder(out, spec)
    plan = chunks(spec)
    done = {c.index: r for c in plan if (r := read_chunk(folder, c)) is not None}
    todo = [c for c in plan if c.index not in done]
    solved: dict[int, dict] = {}

    def keep(chunk: Chunk, result: dict) -> None:
        write_chunk(folder, chunk, result)
        solved[chunk.index] = result

    rep = run_tasks(solve_chunk, todo, [f"nodes {c.start}-{c.stop - 1}" for c in todo], workers=workers,
                    scheduler=scheduler, progress=progress, on_result=keep, desc="creep table", unit="chunk")
    report = BuildReport(chunks=len(plan), resumed=len(done), solved=len(solved), failed=rep.failed,
                         nodes=spec.n_nodes, wall_s=0.0, solve_s=sum(r["wall_s"] for r in solved.values()),
                         path=None)
    if not rep.failed and len(done) + len(solved) == len(plan):
        results = {**done, **solved}
        values = np.concatenate([results[c.index]["values"] for c in plan]).reshape(spec.shape + (N_OUT,))
        conv = np.concatenate([results[c.index]["converged"] for c in plan])
        c11, c22, c23 = node_coefficients(spec)
        meta = {
            "spec": spec.to_dict(), "table_version": TABLE_VERSION, "code_version": _code_version(),
            "normalisation": "Eqs. T1-T4 of conformal.tables.spec (saturation factor 3)",
            "solver": {"theory": "exact", "grid_n": spec.grid_n, "tol": spec.tol, "rolling": "steady",
                       "G": _G, "mu": _MU, "FN": _FN, "ab": 1.0},
            "coefficients": "Kalker (1990) Table E.3 via conformal.theories.coefficients",
            "nonconverged_nodes": int((~conv).sum()),
            "solve_s": float(sum(r["wall_s"] for r in results.values())),
            "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        }
        report.path = save_table(CreepTable(spec, values, c11, c22, c23, meta), out)
        report.nonconverged = meta["nonconverged_nodes"]
        if not keep_parts:
            _remove_parts(folder)
    report.wall_s = time.perf_counter() - t0
    return report


def _code_version() -> str:
    try:
        from importlib.metadata import version

        v = version("conformal")
    except Exception:  # noqa: BLE001 - not installed as a distribution
        v = "unknown"
    return f"conformal {v}, table {TABLE_VERSION}"


def solve_points(a_over_b, nu, nx, ny, nphi, *, grid_n: int, tol: float) -> np.ndarray:
    """Direct exact solves at arbitrary normalised points (for accuracy checks): (N, 3) of Eq. T2,
    with Kalker's coefficients at each point's own (a/b, nu)."""
    from conformal.theories.coefficients import coefficient_arrays

    pts = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, float)) for v in (a_over_b, nu, nx, ny, nphi)))
    out = np.empty((pts[0].size, N_OUT))
    for k, (r, v, x, y, p) in enumerate(zip(*(q.ravel() for q in pts))):
        c = tuple(float(np.asarray(ci)) for ci in coefficient_arrays(r, v))
        res = solve_normalised(r, v, x, y, p, c, grid_n=grid_n, tol=tol)
        if not res.converged:
            raise ConformalError(f"exact solve at a/b={r:g}, nu={v:g}, n=({x:g}, {y:g}, {p:g}) did not converge")
        out[k] = (res.fx, res.fy, res.mz)
    return out


# ----------------------------------------------------------------------------- targeted refinement
@dataclass(frozen=True)
class PatchSlice:
    """The extra nodes of one (a/b, nu) node pair of a :class:`~conformal.tables.table.Patch`."""

    spec: TableSpec
    box: tuple
    q: tuple
    it: int
    iv: int
    index: int


def solve_patch_slice(task: PatchSlice) -> dict:
    """Worker: the extra q nodes of one (a/b, nu) inside the box (:class:`SliceSolver`).  Returns
    {"values": (s1 - s0, th1 - th0, len(q), 3), "converged", "wall_s"}; BLAS on one thread as in
    :func:`solve_chunk`."""
    with single_threaded_blas():
        return _solve_patch_slice(task)


def _solve_patch_slice(task: PatchSlice) -> dict:
    spec = task.spec
    axes = spec.axes()
    c11, c22, c23 = node_coefficients(spec)
    _, _, s0, s1, h0, h1 = task.box
    it, iv = task.it, task.iv
    solver = SliceSolver(math.exp(axes[0][it]), float(axes[1][iv]), (c11[it, iv], c22[it, iv], c23[it, iv]),
                         grid_n=spec.grid_n, tol=spec.tol)
    vals = np.empty((s1 - s0, h1 - h0, len(task.q), N_OUT))
    conv = np.ones(vals.shape[:3], dtype=bool)
    t0 = time.perf_counter()
    for i in range(s1 - s0):
        for j in range(h1 - h0):
            for k, q in enumerate(task.q):
                r = solver.solve(*creepages_of_node(axes[2][s0 + i], axes[3][h0 + j], q))
                vals[i, j, k] = (r.fx, r.fy, r.mz)
                conv[i, j, k] = r.converged
    return {"values": vals, "converged": conv, "wall_s": time.perf_counter() - t0}


def midpoints(spec: TableSpec, q_lo: float, q_hi: float) -> np.ndarray:
    """The midpoints of the table's q cells that lie in [q_lo, q_hi]."""
    q = spec.axes()[4]
    mid = 0.5 * (q[1:] + q[:-1])
    return mid[(mid >= q_lo) & (mid <= q_hi)]


def add_patch(table_path: str | Path | None, box: tuple, q, out: str | Path, *, workers: int = 1,
              scheduler: str | None = None, progress: bool = True) -> BuildReport:
    """Refine a built table in one box: solve the extra q nodes ``q`` for every (a/b, nu, s,
    theta) node of ``box`` = (t0, t1, s0, s1, th0, th1) (half-open index ranges; every nu) and
    write the table with this :class:`~conformal.tables.table.Patch` added to ``out``.  One task
    per (a/b, nu) node pair, written atomically into ``out.parts/patch_<digest>/`` as it
    finishes: an interrupted run resumes with the missing ones (as :func:`build_table`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from conformal.tables.table import load_table
    >>> spec = TableSpec(ratio_min=1.0, ratio_max=1.0, n_ratio=1, nu_min=0.28, nu_max=0.28, n_nu=1,
    ...                  rho_max=1.0, n_rho=2, n_theta=2, spin_max=1.0, n_spin=3, grid_n=8, chunk=6)
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = build_table(spec, d / "t.npz", progress=False)
    >>> rep = add_patch(d / "t.npz", (0, 1, 1, 2, 0, 2), [0.25], d / "p.npz", progress=False)
    >>> rep.solved, load_table(d / "p.npz").info()["patch_nodes"]
    (1, 2)
    """
    from conformal.jobs import run_tasks
    from conformal.tables.table import Patch, load_table

    base = load_table(table_path)
    spec = base.spec
    q = tuple(float(v) for v in np.atleast_1d(np.asarray(q, dtype=float)))
    box = tuple(int(i) for i in box)
    if len(box) != 6:
        raise InputError(f"patch box: 6 indices (t0, t1, s0, s1, th0, th1), got {box}")
    Patch(box, np.array(q), np.zeros((box[1] - box[0], spec.n_nu, box[3] - box[2], box[5] - box[4], len(q), N_OUT))
          ).check(spec)                                                  # validate before solving
    t0 = time.perf_counter()
    out = Path(out)
    key = json.dumps({"table": base.content_hash, "box": box, "q": q}, sort_keys=True)
    folder = out.with_name(out.name + ".parts") / ("patch_" + hashlib.sha256(key.encode()).hexdigest()[:16])
    plan = [PatchSlice(spec, box, q, it, iv, k) for k, (it, iv) in
            enumerate((it, iv) for it in range(box[0], box[1]) for iv in range(spec.n_nu))]
    done = {}
    for task in plan:
        path = _chunk_path(folder, task.index)
        if path.is_file():
            try:
                z = read_npz(path)
                if str(z["digest"]) == key and np.all(np.isfinite(z["values"])):
                    done[task.index] = {"values": z["values"], "converged": z["converged"],
                                        "wall_s": float(z["wall_s"])}
            except (OSError, ValueError, KeyError, TypeError):   # unreadable or truncated: solved again
                pass
    todo = [task for task in plan if task.index not in done]
    solved: dict[int, dict] = {}

    def keep(task: PatchSlice, result: dict) -> None:
        save_npz_atomic(_chunk_path(folder, task.index), values=result["values"], converged=result["converged"],
                        wall_s=result["wall_s"], digest=np.array(key))
        solved[task.index] = result

    rep = run_tasks(solve_patch_slice, todo, [f"a/b node {t.it}, nu node {t.iv}" for t in todo], workers=workers,
                    scheduler=scheduler, progress=progress, on_result=keep, desc="table patch", unit="slice")
    report = BuildReport(chunks=len(plan), resumed=len(done), solved=len(solved), failed=rep.failed,
                         nodes=int(np.prod([box[1] - box[0], spec.n_nu, box[3] - box[2], box[5] - box[4], len(q)])),
                         wall_s=0.0, solve_s=sum(r["wall_s"] for r in solved.values()), path=None)
    if not rep.failed and len(done) + len(solved) == len(plan):
        results = {**done, **solved}
        values = np.stack([results[t.index]["values"] for t in plan]).reshape(
            (box[1] - box[0], spec.n_nu, box[3] - box[2], box[5] - box[4], len(q), N_OUT))
        conv = np.concatenate([results[t.index]["converged"].ravel() for t in plan])
        meta = dict(base.meta)
        meta["patches"] = list(meta.get("patches", [])) + [{
            "box": list(box), "q": list(q), "nodes": int(conv.size), "nonconverged_nodes": int((~conv).sum()),
            "solve_s": float(sum(r["wall_s"] for r in results.values())), "code_version": _code_version(),
            "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}]
        table = CreepTable(spec, base.values, base.c11, base.c22, base.c23, meta,
                           patches=tuple(base.patches) + (Patch(box, np.array(q), values),))
        report.path = save_table(table, out)
        report.nonconverged = meta["patches"][-1]["nonconverged_nodes"]
        _remove_parts(folder)
    report.wall_s = time.perf_counter() - t0
    return report


def _remove_parts(folder: Path) -> None:
    """Delete the finished build's chunk folder (and its parent when that is now empty)."""
    shutil.rmtree(folder, ignore_errors=True)
    try:
        folder.parent.rmdir()
    except OSError:
        pass
