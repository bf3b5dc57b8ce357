"""Stresses inside the FE rail and wheel bodies under the solved tractions of a conformal strip
(issue 24, item 2).

One FE solve of the rail (body 1) or of the wheel (body 2) with the final surface load, by the split method of
:mod:`conformal.influence.fe` (its mesh, space, assembly, loads and residual traction are reused
through its functions): sigma = sigma_hs + sigma_c, where sigma_hs is the superposed closed-form
half-space field of the loaded elements, each on its own tangent plane
(:func:`conformal.stresses.halfspace.stresses`), and sigma_c the stress of the FE correction u_c:
its free surface carries the residual traction sum_e (p_e chi_e - sigma_hs,e n) (the real, curved
surface is not the elements' tangent planes), and it vanishes on the artificial boundaries (the
``far_field = "halfspace"`` model: beyond the FE body the rail continues as the tangent half-space).
On a flat block the residual is zero and the FE body gives the half-space stresses exactly.

P1 tetrahedra (the correction is smooth; fe.py's default), the mesh conforming to every element of
the strip (``conform = "all"``: the residual traction jumps at the element edges).  The strip is
placed on the mesh's columns (x = (ix - mx // 2) dx); the rail is an extrusion, so this shift
along x changes nothing, and the points are given and returned in the strip's own x.  The wheel
(a body of revolution in its own axes, :func:`conformal.influence.fe.wheel_body_from_grid`)
carries the opposite tractions in its own element frames; the shift is a rotation about its axle,
and its half-space part is the field of its own tangent planes (:func:`_split_halfspace`), so
that sigma_hs + sigma_c is the split solution; points and stresses are in the rail-profile frame.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from conformal.errors import InputError
from conformal.influence.factor import Factor
from conformal.influence.fe import FESettings, _free_surface, _loads, _residual_load, rail_body_from_grid
from conformal.influence.fe_toolkit import clamped_dofs, direct_solver, hooke, probes, stiffness, vector_space
from conformal.meshing.gmsh_body import mesh_body
from conformal.stresses.halfspace import stresses as halfspace_stresses


@dataclass(frozen=True, eq=False)
class BodyStresses:
    """sigma_hs and sigma_c (N/mm², rail-profile frame) at the points (..., 3); ``stats`` times and sizes."""

    points: np.ndarray
    sigma_hs: np.ndarray
    sigma_c: np.ndarray
    stats: dict

    @property
    def sigma(self) -> np.ndarray:
        """The FE body's stress sigma_hs + sigma_c."""
        return self.sigma_hs + self.sigma_c


def rail_body_stresses(field, points, *, G: float, nu: float, settings: FESettings = FESettings(),
                       rail_points: np.ndarray | None = None, vtu=None, vtu_radius: float | None = None
                       ) -> BodyStresses:
    """Stresses in the FE rail under the tractions of a conformal strip, at ``points`` (..., 3)
    (rail-profile frame, mm; inside the rail, within the FE body).

    Parameters
    ----------
    field : CurvedTractionField
        The solved strip (``field.curved``).
    points : array_like (..., 3)
    G, nu : float
        The rail's shear modulus (N/mm²) and Poisson's ratio.
    settings : FESettings
        The FE model (the scene's [model] fe_* keys); method split, P1, ``conform = "all"`` are imposed.
    rail_points : (n, 2), optional
        The whole rail profile (else the grid's local curve).
    vtu, vtu_radius : optional
        Also write the FE body's stresses to this VTU file (:func:`write_body_vtu`).
    """
    return body_stresses(field, points, body=1, G=G, nu=nu, settings=settings, profile_points=rail_points,
                         vtu=vtu, vtu_radius=vtu_radius)


def wheel_body_stresses(field, points, *, G: float, nu: float, settings: FESettings = FESettings(),
                        wheel_points: np.ndarray | None = None, vtu=None, vtu_radius: float | None = None
                        ) -> BodyStresses:
    """Stresses in the FE wheel (body 2) under the tractions of a conformal strip, at ``points``
    (..., 3, rail-profile frame, mm, inside the wheel); returned in the rail-profile frame.

    The wheel carries the opposite tractions, given in its own element frames (the rotations of
    :func:`conformal.influence.fe.wheel_body_from_grid`, as in its FE influence numbers); the
    half-space part sigma_hs is that of the wheel's own tangent planes (so that sigma_hs + sigma_c
    is the split solution); the half-space field of the rail's planes is
    ``halfspace.stresses(field, points, body=2)``.  Parameters as :func:`rail_body_stresses`.
    """
    return body_stresses(field, points, body=2, G=G, nu=nu, settings=settings, profile_points=wheel_points,
                         vtu=vtu, vtu_radius=vtu_radius)


@dataclass(frozen=True, eq=False)
class _Placement:
    """Body mesh coordinates <-> rail-profile frame: X_mesh = Q (M^T (P - c) - o) + o (rotation
    about the wheel's axle for the strip's x shift; a translation along x for the rail)."""

    M: np.ndarray            # (3, 3) columns: mesh axes in the rail-profile frame
    c: np.ndarray            # (3,) mesh origin in the rail-profile frame (x-shifted for the rail)
    off: np.ndarray          # (3,) wheel: (0, 0, -R) (mesh origin at the wheel surface)
    Q: np.ndarray            # (3, 3) rotation about the axle (identity for the rail)
    axle: np.ndarray         # (3,) a point of the axle in mesh coordinates

    def to_mesh(self, P: np.ndarray) -> np.ndarray:
        q = (P - self.c) @ self.M + self.off
        return (q - self.axle) @ self.Q.T + self.axle

    def from_mesh(self, X: np.ndarray) -> np.ndarray:
        q = (X - self.axle) @ self.Q + self.axle
        return (q - self.off) @ self.M.T + self.c

    def tensor_from_mesh(self, sig: np.ndarray) -> np.ndarray:
        T = self.M @ self.Q.T                                  # mesh components -> rail-profile frame
        return T @ sig @ T.T


def _placement(grid, body: int, shift: float, bm) -> _Placement:
    if body == 1:
        return _Placement(np.eye(3), np.array([shift, 0.0, 0.0]), np.zeros(3), np.eye(3), np.zeros(3))
    from conformal.influence.fe import wheel_axes

    M = wheel_axes(grid)
    R = float(grid.wheel_radius)
    d = shift / float(bm.extent.x_ref_radius)                 # the strip's column x = shift is the mesh's x = 0
    Q = np.array([[math.cos(d), 0.0, -math.sin(d)], [0.0, 1.0, 0.0], [math.sin(d), 0.0, math.cos(d)]])
    return _Placement(M, np.asarray(grid.wheel_centre, float), np.array([0.0, 0.0, -R]), Q,
                      np.array([0.0, 0.0, float(bm.body.axle_z)]))


def _split_halfspace(bm, grid, loads_of, X: np.ndarray, G: float, nu: float) -> np.ndarray:
    """sigma_hs (n, 3, 3) in mesh coordinates at mesh points X: the closed-form field of every
    loaded element on its own tangent plane of the body mesh (the half-space part of the split
    method, consistent with :func:`conformal.influence.fe._residual_load`)."""
    from conformal.stresses.rectangle import rectangle_stress

    out = np.zeros((len(X), 3, 3))
    for x0, J, c in loads_of:
        loads = _loads(bm, float(x0))
        R = loads.local[J]
        q = (X - loads.centres[J]) @ R.T
        q[:, 2] = np.maximum(q[:, 2], 0.0)
        sig = rectangle_stress(q, grid.dx, float(loads.widths[J]), G=G, nu=nu, near=None)   # (n, 3, 3, 3 local)
        s_loc = sig @ (loads.B @ c)
        out += R.T @ s_loc @ R
    return out


def _mesh_isolated(model, patch, spec):
    """:func:`mesh_body` with gmsh's Delaunay 3-D mesher, in a forked child process.

    The bodies here are swept in one slab per strip column (``conform = "all"``), each dx thick
    across the whole cross-section; HXT (mesh_body's default) aborted the whole process on them
    (its boundary recovery inserts Steiner points on the surface mesh, an unfinished path of gmsh
    4.15: S1002/UIC60 at 6.2 and 6.25 mm and the deep pair, deterministic), Delaunay meshes them
    (see :func:`conformal.meshing.gmsh_body.mesh_body`).  The child keeps any other abort of
    gmsh from killing the caller: it ends in an FESolveError (exit 2 in the CLI, a note in the
    study)."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    for algorithm in _ALGORITHMS_3D:
        try:
            with ProcessPoolExecutor(1, mp_context=mp.get_context("fork")) as ex:
                return ex.submit(mesh_body, model, patch, spec, algorithm3d=algorithm).result()
        except BrokenProcessPool:
            continue
    from conformal.influence.factor import FESolveError

    raise FESolveError(f"stresses: gmsh aborted meshing the {model.kind} body (3-D algorithms "
                       f"{', '.join(str(a) for a in _ALGORITHMS_3D)}); try other [model] fe_h_load / "
                       "fe_h_patch or [grid] n")


#: gmsh's 3-D meshers tried in turn on the slab bodies: Delaunay, then Frontal (both abort on some
#: of these bodies: Delaunay on the deep pair's wheel after the frame-sense correction moved its patch)
_ALGORITHMS_3D = (1, 4)


def _rot_y(phi: float) -> np.ndarray:
    """Rotation by phi about the wheel's axle (mesh y): the point at angle 0 (x = 0, z - axle_z = r)
    goes to x = r sin(phi) (the mesh's rolling coordinate grows with phi)."""
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rect_stress_graded(q: np.ndarray, dx: float, dy: float, G: float, nu: float) -> np.ndarray:
    """rectangle_stress (n, 3, 3, 3 local loads) at local points q: the closed form within 4 element
    sizes, 3 x 3 Gauss point forces up to 10 (error ~ (h/r)^6), one point force beyond (~ (h/r)^2,
    1e-2 of a contribution that is itself ~1e-2 of the near field), the grading of the FE residual load."""
    from conformal.stresses.rectangle import _gauss_rectangle_stress, rectangle_stress

    h = max(dx, dy)
    r = np.maximum(np.abs(q[:, 0]), np.abs(q[:, 1]))
    out = np.empty((len(q), 3, 3, 3))
    near = r <= 4 * h
    mid = (~near) & (r <= 10 * h)
    far = r > 10 * h
    if near.any():
        out[near] = rectangle_stress(q[near], dx, dy, G=G, nu=nu, near=None)
    for sel, ng in ((mid, 3), (far, 1)):
        if sel.any():
            out[sel] = _gauss_rectangle_stress(q[sel, 0], q[sel, 1], np.maximum(q[sel, 2], 1e-12 * h), dx, dy, nu, ng)
    return out


def _wheel_rolling_block(m, place, bm, grid, sources, correction, P: np.ndarray, G: float, nu: float, ic: int):
    """sigma_hs, sigma_c (nd, mx, nc, 3, 3) of the wheel on the rolling block ``P`` (nd, mx, nc, 3)
    (a StressField's points: axis 1 the strip's columns).

    The wheel's material points travel on circles about its axle: the point of column ix is the
    section point of column ic (the mesh's angle 0) turned about the axle by (ix - ic) dx / R_ref,
    and its stress is turned back by the same angle, so that each line along axis 1 is the stress
    history of one material point in its own (co-rotating) frame, as Dang Van's criterion needs.
    The half-space part of the wheel's own tangent planes (:func:`_split_halfspace`) is then a
    convolution along the columns: source row J of column ix_s acts on column ix as the source of
    column ic on the column ic + ix - ix_s (the body is one of revolution), one kernel per row J."""
    nd, mx, nc = P.shape[:3]
    r_ref = float(bm.extent.x_ref_radius)
    axle = np.array([0.0, 0.0, float(bm.body.axle_z)])
    X0 = place.to_mesh(P[:, ic].reshape(-1, 3)) - axle                 # (npts, 3) about the axle
    npts = len(X0)
    sig_c = np.empty((mx, npts, 3, 3))
    for ix in range(mx):
        Rm = _rot_y((ix - ic) * grid.dx / r_ref)
        sig_c[ix] = Rm.T @ correction(X0 @ Rm.T + axle) @ Rm
    loads0 = _loads(bm, 0.0)
    cols = np.array([int(round(x0 / grid.dx)) + ic for x0, _, _ in sources])
    off = np.arange(-(int(cols.max()) if cols.size else 0), mx - (int(cols.min()) if cols.size else 0))
    Rms = np.stack([_rot_y(o * grid.dx / r_ref) for o in off])            # (no, 3, 3)
    Xk = np.einsum("oij,pj->opi", Rms, X0) + axle                        # (no, npts, 3)
    sig_hs = np.zeros((mx, npts, 3, 3))
    for J in sorted({j for _, j, _ in sources}):
        R = loads0.local[J]
        q = (Xk.reshape(-1, 3) - loads0.centres[J]) @ R.T
        q[:, 2] = np.maximum(q[:, 2], 0.0)
        k = _rect_stress_graded(q, grid.dx, float(loads0.widths[J]), G, nu).reshape(len(off), npts, 3, 3, 3)
        k = np.einsum("ab,opbcl,cd->opadl", R.T, k, R)                   # mesh components, per local load
        k = np.einsum("oba,opbcl,ocd->opadl", Rms, k, Rms)               # turned back: Rm^T s Rm
        for (x0, j, c), ix_s in zip(sources, cols):
            if j == J:
                lo = int(-off[0]) - ix_s                                  # the offset index of ix = 0
                sig_hs += k[lo:lo + mx] @ (loads0.B @ c)
    shape = (mx, nd, nc, 3, 3)
    return (place.tensor_from_mesh(np.swapaxes(sig_hs.reshape(shape), 0, 1)),
            place.tensor_from_mesh(np.swapaxes(sig_c.reshape(shape), 0, 1)))


def body_stresses(field, points, *, body: int, G: float, nu: float, settings: FESettings = FESettings(),
                  profile_points: np.ndarray | None = None, vtu=None, vtu_radius: float | None = None,
                  rolling_block: bool = False, sigma_hs: np.ndarray | None = None) -> BodyStresses:
    """The FE body ``body`` (1: rail, 2: wheel) under the strip's tractions at ``points`` (..., 3)
    in the rail-profile frame; see :func:`rail_body_stresses` and :func:`wheel_body_stresses`.

    ``rolling_block``: ``points`` is a StressField's block (nd, mx, nc, 3) whose axis 1 runs along
    the strip's mx columns (the rolling pass, for Dang Van's criterion): the rail (an extrusion)
    at the points themselves; the wheel on the circles about its axle through the section of the
    mesh's middle column, each line in its co-rotating frame (:func:`_wheel_rolling_block`).
    ``sigma_hs`` (rail only): the half-space part at the points if already known (the
    StressField's sigma of body 1: the same superposed field), else computed here."""
    from conformal.influence.fe import wheel_body_from_grid

    grid = getattr(field, "curved", None)
    if grid is None:
        raise InputError("stresses: FE body stresses need a conformal strip (theory \"conformal\")")
    if settings.far_field != "halfspace":
        raise InputError("stresses: FE body stresses need [model] fe_far_field = \"halfspace\"")
    if body not in (1, 2):
        raise InputError(f"stresses: body must be 1 or 2, got {body!r}")
    t0 = time.perf_counter()
    pts = np.asarray(points, float)
    if rolling_block and (pts.ndim != 4 or pts.shape[1] != grid.mx):
        raise InputError(f"stresses: a rolling block needs points (nd, {grid.mx}, nc, 3), got {pts.shape}")
    shape = pts.shape[:-1]
    P = pts.reshape(-1, 3)
    pn, px, ps = (np.asarray(field.side_frame(k), float) for k in ("pn", "px", "py"))
    if body == 1:
        model, patch = rail_body_from_grid(grid, profile_points)
        rot = np.broadcast_to(np.eye(3), (grid.ms, 3, 3))
    else:
        model, patch, rot = wheel_body_from_grid(grid, profile_points)
    spec = replace(settings.mesh, conform="all", order=1)
    bm = _mesh_isolated(model, patch, spec)
    m, space = vector_space(bm.points, bm.tets, 1)
    K = stiffness(space, G, nu)
    _, D = clamped_dofs(space, bm.clamped_tris)
    free = np.setdiff1d(np.arange(space.basis.N), D)
    surf = _free_surface(bm, m, space)
    t_mesh = time.perf_counter()
    ic = grid.mx // 2
    shift = grid.xl + (ic + 0.5) * grid.dx                    # strip x of the mesh's column x = 0
    place = _placement(grid, body, shift, bm)
    sgn = 1.0 if body == 1 else -1.0
    Fc = np.zeros((3, space.n_scalar))
    loaded = np.argwhere((pn != 0) | (px != 0) | (ps != 0))
    sources = []                                               # (x0, J, common load) per loaded element
    for ix in np.unique(loaded[:, 0]):
        x0 = float((ix - ic) * grid.dx)
        loads = _loads(bm, x0)
        for J in loaded[loaded[:, 0] == ix, 1]:
            # the traction on this body in its own element frames (common components, the
            # convention of fe.combine: the wheel carries -p, turned by rot^T into its frames)
            c = sgn * (rot[J].T @ np.array([px[ix, J], ps[ix, J], pn[ix, J]]))
            r = _residual_load(loads, surf, space, patch, G, nu, int(J))        # (3, n_scalar, 3 loads)
            Fc += r @ c
            sources.append((x0, int(J), c))
    F = space.from_components(Fc)
    t_rhs = time.perf_counter()
    solver = direct_solver(settings.solver)
    U = np.zeros(space.basis.N)
    if F.any():
        U[free] = Factor(K[free][:, free].tocsr(), solver, settings.amg_tol).solve(F[free])
    t_solve = time.perf_counter()

    def correction(X, cells=None):
        """The correction's stress (n, 3, 3) at mesh points X (n, 3) (P1: constant per tetrahedron;
        ``cells``: their tetrahedra, else located)."""
        grad = (probes(space.basis, X, cells, gradient=True) @ U).reshape(3, 3, -1).transpose(2, 0, 1)
        return hooke(0.5 * (grad + np.swapaxes(grad, 1, 2)), G, nu)

    # the FE correction's stress at the points (P1: constant per tetrahedron)
    if rolling_block and body == 2:
        sig_hs, sig_c = _wheel_rolling_block(m, place, bm, grid, sources, correction, pts, G, nu, ic)
        sig_hs, sig_c = sig_hs.reshape(-1, 3, 3), sig_c.reshape(-1, 3, 3)
    else:
        Pm = place.to_mesh(P)
        sig_c = place.tensor_from_mesh(correction(Pm))
        if body == 1:
            sig_hs = (halfspace_stresses(field, P, nu=nu, body=1) if sigma_hs is None
                      else np.asarray(sigma_hs, float).reshape(-1, 3, 3))
        else:
            sig_hs = place.tensor_from_mesh(_split_halfspace(bm, grid, sources, Pm, G, nu))
    t_end = time.perf_counter()
    stats = {"body": "rail" if body == 1 else "wheel", "dofs": int(space.basis.N), "tets": int(m.nelements),
             "loaded_elements": int(len(loaded)), "mesh_s": t_mesh - t0, "rhs_s": t_rhs - t_mesh,
             "solve_s": t_solve - t_rhs, "stress_s": t_end - t_solve, "residual_norm": float(np.abs(F).sum())}
    if vtu is not None:
        t1 = time.perf_counter()
        stats["vtu"] = write_body_vtu(vtu, m, place, correction, bm, grid, sources, field, body, G, nu, P,
                                      vtu_radius)
        stats["vtu_s"] = time.perf_counter() - t1
    return BodyStresses(pts, sig_hs.reshape(shape + (3, 3)), sig_c.reshape(shape + (3, 3)), stats)


def write_body_vtu(path, m, place, correction, bm, grid, sources, field, body, G, nu, P, radius=None) -> dict:
    """The FE body's tetrahedra within ``radius`` (default: 3 times the extent of ``P``, at least
    4 mm) of the points' centre as a VTU file in the rail-profile frame (mm): cell data (constant
    per P1 tetrahedron, evaluated at its centroid) sigma_xx ... sigma_yz of sigma_hs + sigma_c,
    von_mises, principal_shear, orthogonal_shear (sigma_xn, n the normal of the nearest strip
    column), max_principal, correction_von_mises (of sigma_c alone), N/mm².  Atomic write."""
    import meshio

    from conformal.files import atomic_path
    from conformal.stresses.invariants import max_principal, principal_shear, von_mises
    from conformal.stresses.plots import _COMPONENTS

    X = place.from_mesh(m.p.T)                                 # vertices, rail-profile frame
    cent = X[m.t].mean(axis=0)                                 # (T, 3)
    mid = P.mean(axis=0)
    if radius is None:
        radius = max(4.0, 3.0 * float(np.ptp(P, axis=0).max()))
    keep = np.flatnonzero(np.linalg.norm(cent - mid, axis=1) <= radius)
    cm = m.p[:, m.t[:, keep]].mean(axis=1).T                   # the centroids in mesh coordinates
    sc = place.tensor_from_mesh(correction(cm, keep))
    if body == 1:
        sh = halfspace_stresses(field, cent[keep], nu=nu, body=1)
    else:
        sh = place.tensor_from_mesh(_split_halfspace(bm, grid, sources, cm, G, nu))
    sig = sh + sc
    n = np.asarray(grid.normal, float)
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    cy, cz = np.asarray(grid.y, float), np.asarray(grid.z, float)
    near = np.argmin((cent[keep, 1, None] - cy) ** 2 + (cent[keep, 2, None] - cz) ** 2, axis=1)
    nn = np.column_stack([np.zeros(len(keep)), n[near, 0], n[near, 1]])
    verts, inv = np.unique(m.t[:, keep].T, return_inverse=True)
    data = {name: [sig[:, i, j]] for name, i, j in _COMPONENTS}
    data.update(von_mises=[von_mises(sig)], principal_shear=[principal_shear(sig)],
                orthogonal_shear=[np.einsum("ni,nij,nj->n", np.tile([1.0, 0, 0], (len(keep), 1)), sig, nn)],
                max_principal=[max_principal(sig)], correction_von_mises=[von_mises(sc)])
    mesh = meshio.Mesh(X[verts], [("tetra", inv.reshape(-1, 4))], cell_data=data)
    with atomic_path(path, keep_suffix=True) as tmp:
        meshio.write(tmp, mesh)
    return {"path": str(path), "cells": int(len(keep)), "radius": float(radius)}
