"""Stresses inside the FE rail body under the solved tractions of a conformal strip (issue 24, item 2).

One FE solve of the rail (body 1) with the final surface load, by the split method of
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
along x changes nothing, and the points are given and returned in the strip's own x.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from conformal.errors import InputError
from conformal.influence.factor import Factor
from conformal.influence.fe import (FESettings, _clamped_dofs, _free_surface, _loads, _residual_load, _space,
                                    rail_body_from_grid)
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


def _p1_gradients(m, U: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Displacement gradients (len(tets), 3, 3) [i, j] = d u_i / d x_j of a P1 field U (3, nverts)."""
    X = m.p[:, m.t[:, tets]]                                   # (3, 4, n)
    E = np.transpose(X[:, 1:, :] - X[:, :1, :], (2, 1, 0))     # (n, 3 edges, 3 coords)
    Ui = U[:, m.t[:, tets]]                                    # (3, 4, n)
    dU = np.transpose(Ui[:, 1:, :] - Ui[:, :1, :], (2, 1, 0))  # (n, 3 edges, 3 comps)
    # E @ grad^T = dU  ->  grad^T = E^-1 dU
    return np.swapaxes(np.linalg.solve(E, dU), 1, 2)


def _locate_tets(m, P: np.ndarray, k: int = 16) -> np.ndarray:
    """The tetrahedron containing each point, or (a surface point just outside the faceted mesh)
    the candidate it is closest to containing (largest smallest barycentric coordinate)."""
    from scipy.spatial import cKDTree

    X = m.p[:, m.t]                                            # (3, 4, T)
    cent = X.mean(axis=1).T
    k = min(k, cent.shape[0])
    _, cand = cKDTree(cent).query(P, k=k)                      # (n, k)
    cand = np.atleast_2d(cand)
    X0 = X[:, 0, cand]                                         # (3, n, k)
    E = np.transpose(X[:, 1:, cand] - X0[:, None], (2, 3, 0, 1))  # (n, k, 3 coords, 3 edges)
    lam = np.linalg.solve(E, (P.T[:, :, None] - X0).transpose(1, 2, 0)[..., None])[..., 0]   # (n, k, 3)
    bary = np.concatenate([1.0 - lam.sum(axis=-1, keepdims=True), lam], axis=-1)
    best = np.argmax(bary.min(axis=-1), axis=1)
    return cand[np.arange(len(P)), best]


def rail_body_stresses(field, points, *, G: float, nu: float, settings: FESettings = FESettings(),
                       rail_points: np.ndarray | None = None) -> BodyStresses:
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
    """
    from skfem import asm
    from skfem.models.elasticity import linear_elasticity

    grid = getattr(field, "curved", None)
    if grid is None:
        raise InputError("stresses: FE body stresses need a conformal strip (theory \"conformal\")")
    if settings.far_field != "halfspace":
        raise InputError("stresses: FE body stresses need [model] fe_far_field = \"halfspace\"")
    t0 = time.perf_counter()
    pts = np.asarray(points, float)
    shape = pts.shape[:-1]
    P = pts.reshape(-1, 3)
    pn, px, ps = (np.asarray(field.side_frame(k), float) for k in ("pn", "px", "py"))
    rail, patch = rail_body_from_grid(grid, rail_points)
    spec = replace(settings.mesh, conform="all", order=1)
    bm = mesh_body(rail, patch, spec)
    m, space = _space(bm, 1)
    lam = 2.0 * G * nu / (1.0 - 2.0 * nu)
    K = asm(linear_elasticity(lam, G), space.basis).tocsr()
    D = _clamped_dofs(m, space, bm)
    free = np.setdiff1d(np.arange(space.basis.N), D)
    surf = _free_surface(bm, space)
    t_mesh = time.perf_counter()
    ic = grid.mx // 2
    shift = grid.xl + (ic + 0.5) * grid.dx                    # strip x of the mesh's column x = 0
    Fc = np.zeros((3, space.n_scalar))
    loaded = np.argwhere((pn != 0) | (px != 0) | (ps != 0))
    for ix in np.unique(loaded[:, 0]):
        loads = _loads(bm, float((ix - ic) * grid.dx))
        for J in loaded[loaded[:, 0] == ix, 1]:
            r = _residual_load(loads, surf, space, patch, G, nu, int(J))        # (3, n_scalar, 3 loads)
            Fc += r @ np.array([px[ix, J], ps[ix, J], pn[ix, J]])
    F = np.zeros(space.basis.N)
    for c in range(3):
        F[space.dofmap[c]] = Fc[c]
    t_rhs = time.perf_counter()
    solver = settings.solver if settings.solver in ("splu", "pardiso", "amg") else "splu"
    if solver == "pardiso":
        from conformal.influence.factor import pardiso_available

        solver = "pardiso" if pardiso_available() else "splu"
    U = np.zeros(space.basis.N)
    if F.any():
        U[free] = Factor(K[free][:, free].tocsr(), solver, settings.amg_tol).solve(F[free])
    t_solve = time.perf_counter()
    # the FE correction's stress at the points (P1: constant per tetrahedron)
    Pm = P.copy()
    Pm[:, 0] -= shift
    tets = _locate_tets(m, Pm)
    Uc = np.stack([U[space.dofmap[c]] for c in range(3)])[:, :m.nvertices]
    grad = _p1_gradients(m, Uc, tets)
    eps = 0.5 * (grad + np.swapaxes(grad, 1, 2))
    sig_c = 2.0 * G * eps + lam * np.trace(eps, axis1=1, axis2=2)[:, None, None] * np.eye(3)
    sig_hs = halfspace_stresses(field, P, nu=nu, body=1)
    t_end = time.perf_counter()
    stats = {"dofs": int(space.basis.N), "tets": int(m.nelements), "loaded_elements": int(len(loaded)),
             "mesh_s": t_mesh - t0, "rhs_s": t_rhs - t_mesh, "solve_s": t_solve - t_rhs,
             "stress_s": t_end - t_solve, "residual_norm": float(np.abs(F).sum())}
    return BodyStresses(pts, sig_hs.reshape(shape + (3, 3)), sig_c.reshape(shape + (3, 3)), stats)
