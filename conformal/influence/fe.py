"""FE influence numbers of wheel and rail bodies (scikit-fem, linear elasticity, P1/P2 tetrahedra).

For each body (:class:`~conformal.meshing.bodies.BodyModel`, meshed by
:func:`~conformal.meshing.gmsh_body.mesh_body`) the influence numbers are computed on ONE loaded
column of contact elements (the one at x = 0; the rail is an extrusion and the wheel a body of
revolution, so they depend only on the offset ix - jx, docs/architecture.md §4) and observed on the 2 mx - 1
columns around it.  The result is the kernel of :class:`~conformal.influence.curved.CurvedInfluence`:

    K[kx, I, J, i, j],  shape (2 mx - 1, ms, ms, 3, 3),  kx = ix - jx + mx - 1,

the displacement u_i of element (ix, I) per unit traction p_j on element (jx, J), components
(0, 1, 2) = (x, s, n) in the contact frame of each element (x rolling, s along the profile,
n the common normal pointing into body 1, the rail).  On a wheel the frame turns with the wheel
(rolling frame of the observed element).  For one body the kernel is that body's displacement
per unit traction acting ON it, both in the common frame; the two-body numbers of the contact
(u = u_rail - u_wheel for tractions p on the rail) are then K_rail + K_wheel (:func:`combine`).

Collocation (``collocation``): ``"centre"`` (the displacement at the element centre: CONTACT's
convention and that of conformal.influence.halfspace; default) or ``"average"`` (averaged over
the element; with ``conform = "all"`` the average is the exact facet integral, the transpose of
the load operator, and the direct method's matrix is exactly symmetric: reciprocity).

Two methods (``method``):

``"direct"``
    Plain FE: unit tractions on the loaded elements (the surface mesh must conform to them,
    ``conform = "column"`` or ``"all"``), far faces clamped, one factorisation, 3 ms right-hand
    sides as one block.  The traction jumps at the element edges make the field singular there,
    and the self terms converge slowly (51 x 39 grid, P2, h = d/4 at the loaded column: 4 %
    error in 45 s; studies/fe_influence_speed_error.py).

``"split"`` (default)
    The displacement is split as u = u_hs + u_c (in the spirit of Li's decomposition): u_hs is
    the analytic 3-D field of a half-space loaded on the tangent rectangle of the loaded element
    (conformal.influence.fe_halfspace3d), u_c an FE correction that vanishes on the artificial
    boundaries (see "Far field") and whose free surface carries the residual traction
    p - sigma(u_hs) n: zero on a flat surface, a curvature term of relative size d/R on a curved
    one.  The singular near field is exact and the mesh only carries the smooth correction, so P1
    on a coarse mesh suffices (flat limit: exact).  On a curved surface the mesh must conform to the loaded column (``conform = "column"``): the
    half-space traction of the flat rectangle turns from p to 0 in a layer as thin as the depth
    of the surface below the tangent plane (d^2/8R), and quadrature points must not fall into it.
    Points above the tangent plane (a concave surface) are evaluated at depth 0+.

Far field (``far_field``): the bodies are quasi-quarter spaces, large compared with the contact,
but the FE model is finite (a disc of ``fe_body_size`` patch sizes around the patch in the
cross-section, the same margin along x; conformal.meshing.bodies).  What the artificial
boundaries carry decides whether the truncated body behaves like the large one:

``"halfspace"`` (default)
    The displacement on the artificial boundaries is the half-space field of the load, i.e. the
    body continues beyond them as the half-space tangent to the loaded element.  In the split
    method the correction u_c is then zero there: a flat block gives the half-space numbers
    exactly (its correction has neither load nor boundary value), and on a curved body u_c
    carries only the effect of the real surface inside the disc, which converges as the disc
    grows.  Measured at a prescribed approach (studies/fe_body_size.py): a crowned wheel on a flat
    rail gives Hertz's FN within 0.1 % at every body size from 0.5 to 4 (its curvature is slight).
``"clamped"``
    Zero displacement (the earlier default).  Every number then carries a negative truncation
    offset of about 1/size of the self term; summed over the hundreds of elements in contact it
    made the bodies 20-45 % too stiff at a prescribed approach (crowned wheel: FN +44 % at size
    0.5, +25 % at 1, +7.5 % at 4).  Kept for comparison.

Body size (studies/fe_far_field_limit.py).  Both far fields converge to the same large-body
limit, with an error that decays like 1/size (the clamped one from the stiff side, 5-10 times
farther off); Richardson extrapolation in 1/size over doubling sizes gives that limit (on the flat
block it recovers the exact half-space compliance to 2e-4).  What the half-space far field
cannot remove is the curvature beyond the disc: the body beyond it is taken as the tangent
half-space of the loaded element, so a convex rail corner (a quarter-space-like wedge) is too
stiff and a concave flange root too compliant in a small body.  The deep pair's R10 rail corner
was 2.6 % too stiff at size 1, the earlier default; at the default 16 it is within 0.3 % of the
limit (flange root 0.1 %, pair FN 0.2 %), and with the existing grading the body of 16 patch
sizes has the same unknowns as that of size 1.  Where a profile ends inside the disc it is
continued straight (conformal.meshing.bodies.grow_profile), so that the size is the one asked
for; a wheel body is limited to 0.75 of the wheel's radius (reported, ``margin_limited_by``).

Defaults (MeshSpec): split, P1, h = 2 d on the observed patch, d/2 at the loaded column, growth
0.35, body margin 16 x the patch size, scipy splu or pypardiso; the grading chosen from the
Pareto front of studies/fe_influence_speed_error.py, the size from studies/fe_far_field_limit.py.

Influence numbers are cached by conformal.influence.cache; bump ``FE_VERSION`` whenever a change
here changes the numbers.
"""
from __future__ import annotations

import math
import resource
import time
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from conformal.errors import InputError
from conformal.influence.factor import Factor as _Factor
from conformal.influence.factor import FESolveError
from conformal.influence.fe_toolkit import (CENTROID, VectorSpace, clamped_dofs, direct_solver, stiffness,
                                            surface_quadrature, trace_matrix, vector_space)
from conformal.influence.fe_halfspace3d import _gauss_rectangle_stress, rectangle_displacement, rectangle_stress
from conformal.meshing.bodies import BodyModel, StripPatch
from conformal.meshing.gmsh_body import BodyMesh, MeshSpec, mesh_body, surface_frame, surface_point

# (closure "section": its bodies' meshes gained a cap at a fraction of the local wall thickness,
#  MeshSpec.h_wall; their key gained that entry, so that they are new keys without a version bump,
#  which would have recomputed every other body)
FE_VERSION = "6"   # 6: keys of every bit of the profile points and patch edges (were rounded to
#                    12 decimals, under which gmsh's mesh still changed): one key, one mesh (issue 22);
#                  5: profiles that end inside the body's disc continued straight (closure "extend"),
#                    wheel bodies limited to 0.75 of the radius, default body size 16
#                    (studies/fe_far_field_limit.py);
#                  4: bodies swept piece from piece (no boolean fragment): other tetrahedra, numbers
#                    moved by the mesh only (51 x 39, 0.4 mm: at most 2.8e-5 / 4.5e-5 of the self
#                    term on the rail / wheel);
#                  3: half-space far field on the artificial boundaries (was: clamped)
METHODS = ("split", "direct")
SOLVERS = ("auto", "pardiso", "splu", "amg")
COLLOCATIONS = ("centre", "average")
#: the body's size and closure (conformal.meshing.gmsh_body.closure_report), reported per body in
#: the statistics (``stats["body"]``) and so in a solve's JSON (``fe.rail.body``, ``fe.wheel.body``)
_BODY_KEYS = ("disc_radius_mm", "margin_mm", "margin_requested_mm", "closure_lo", "closure_hi",
              "extension_lo_mm", "extension_hi_mm", "margin_limited_by", "mesh_reach_mm", "wall_fraction",
              "wall_thickness_min_mm")
FAR_FIELDS = ("halfspace", "clamped")


@dataclass(frozen=True)
class FESettings:
    """Everything that controls the FE influence numbers besides body, grid and material."""

    method: str = "split"
    mesh: MeshSpec = MeshSpec()
    solver: str = "auto"
    collocation: str = "centre"
    far_field: str = "halfspace"
    n_average: int = 6          # Gauss points per direction for "average" collocation
    max_dofs: int = 1_500_000
    amg_tol: float = 1e-10

    def __post_init__(self):
        if self.method not in METHODS:
            raise InputError(f"[model] fe_method: must be one of {', '.join(METHODS)}, got {self.method!r}")
        if self.solver not in SOLVERS:
            raise InputError(f"[model] fe_solver: must be one of {', '.join(SOLVERS)}, got {self.solver!r}")
        if self.collocation not in COLLOCATIONS:
            raise InputError(f"[model] fe_collocation: must be one of {', '.join(COLLOCATIONS)}, "
                             f"got {self.collocation!r}")
        if self.far_field not in FAR_FIELDS:
            raise InputError(f"[model] fe_far_field: must be one of {', '.join(FAR_FIELDS)}, "
                             f"got {self.far_field!r}")
        if self.method == "direct" and self.mesh.conform == "none":
            raise InputError("[model] fe_conform: the direct method needs a mesh that conforms to the "
                             "loaded elements (\"column\" or \"all\")")

    def key(self) -> dict:
        """Settings that change the numbers (the solver choice does not, beyond round-off)."""
        return {"method": self.method, "mesh": self.mesh.key(), "collocation": self.collocation,
                "far_field": self.far_field,
                "n_average": self.n_average if self.collocation == "average" else None,
                "amg_tol": self.amg_tol if self.solver == "amg" else None}


@dataclass(frozen=True, eq=False)
class BodyInfluence:
    """The FE influence kernel of one body (see the module docstring for the layout)."""

    kernel: np.ndarray
    kind: str
    patch: StripPatch
    G: float
    nu: float
    settings: FESettings
    stats: dict = field(default_factory=dict)


# ----------------------------------------------------------------------------- surface maps
@dataclass(frozen=True, eq=False)
class _Surface:
    """Quadrature on the free surface and interpolation of the FE trace in (x, s).

    Two rules (:func:`~conformal.influence.fe_toolkit.facet_quadrature`, skfem's FacetBasis on the
    free-surface facets): 6 points per facet (``points``, ``P6``; Dunavant's degree-4 rule) near a
    loaded element, the centroid (``centroids``, ``P1``) elsewhere.  P6 and P1 map values at the
    points to the load vector: F_a = sum_q w_q phi_a(q) t(q), as (n_scalar, points) CSC matrices
    (column slices per facet).
    """

    points: np.ndarray       # (F*6, 3)
    uv: np.ndarray           # (F*6, 2) their (x, s)
    normal6: np.ndarray      # (F*6, 3) outward unit normals
    P6: sp.csc_matrix
    centroids: np.ndarray    # (F, 3)
    normal: np.ndarray       # (F, 3)
    diameter: np.ndarray     # (F,) longest edge
    P1: sp.csc_matrix
    tris: np.ndarray
    tri_uv: np.ndarray       # (F, 3, 2)


def _space(bm: BodyMesh, order: int) -> tuple[object, VectorSpace]:
    return vector_space(bm.points, bm.tets, order)


def _free_surface(bm: BodyMesh, m, space: VectorSpace) -> _Surface:
    q6 = surface_quadrature(space, m, bm.free_tris, intorder=4)
    q1 = surface_quadrature(space, m, bm.free_tris, quadrature=CENTROID)
    tris = q6.tris                                       # the facets' vertices (skfem's order)
    X = bm.points[tris]                                  # (F, 3, 3)
    tri_uv = bm.uv[tris]
    q = q6.per_facet
    diameter = np.max(np.linalg.norm(X - np.roll(X, 1, axis=1), axis=2), axis=1)
    return _Surface(points=q6.points, uv=np.einsum("fqk,fkd->fqd", q6.bary.reshape(-1, q, 3), tri_uv).reshape(-1, 2),
                    normal6=q6.normals, P6=q6.load, centroids=X.mean(axis=1), normal=q1.normals,
                    diameter=diameter, P1=q1.load, tris=tris, tri_uv=tri_uv)

def _locate(tri_uv: np.ndarray, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Triangle containing each point (x, s) and its barycentric coordinates, in the (x, s)
    parametrisation of the free surface.

    A point lies in the triangle whose barycentric coordinates have the largest minimum (>= 0
    up to round-off).  Candidates: the triangles whose centroids are nearest (k-d tree), and for
    points not placed that way every triangle whose centroid lies within the largest triangle
    diameter.  Degenerate (zero-area) triangles of the parametrisation are skipped: a point on
    one also lies in a neighbour.  (matplotlib's trifinder refused the whole surface of a steep
    flank, "Triangulation is invalid", for such triangles.)  Returns (f (M,), lam (M, 3)); f = -1
    where no triangle contains the point.
    """
    from scipy.spatial import cKDTree

    A = tri_uv[:, 0]
    T = np.stack([tri_uv[:, 1] - A, tri_uv[:, 2] - A], axis=-1)            # (F, 2, 2)
    det = T[:, 0, 0] * T[:, 1, 1] - T[:, 0, 1] * T[:, 1, 0]
    scale = np.max(np.abs(T), axis=(1, 2))
    ok = np.abs(det) > 1e-12 * scale ** 2
    inv = np.zeros_like(T)
    inv[ok, 0, 0], inv[ok, 1, 1] = T[ok, 1, 1] / det[ok], T[ok, 0, 0] / det[ok]
    inv[ok, 0, 1], inv[ok, 1, 0] = -T[ok, 0, 1] / det[ok], -T[ok, 1, 0] / det[ok]
    idx = np.flatnonzero(ok)
    tree = cKDTree(tri_uv[idx].mean(axis=1))
    tol = 1e-9

    def bary(pts, cand):                                                     # cand: indices into idx
        f = idx[cand]
        l12 = np.einsum("...ab,...b->...a", inv[f], pts - A[f])
        return np.concatenate([(1 - l12.sum(axis=-1))[..., None], l12], axis=-1)

    M = len(uv)
    f_out = np.full(M, -1)
    lam_out = np.zeros((M, 3))
    k = min(12, idx.size)
    _, cand = tree.query(uv, k=k)
    cand = cand.reshape(M, k)
    lam = bary(uv[:, None, :], cand)                                         # (M, k, 3)
    best = np.argmax(lam.min(axis=-1), axis=1)
    lam_b = lam[np.arange(M), best]
    hit = lam_b.min(axis=1) >= -tol
    f_out[hit], lam_out[hit] = idx[cand[np.arange(M), best]][hit], lam_b[hit]
    if not np.all(hit):
        diam = np.max(np.linalg.norm(tri_uv[idx] - np.roll(tri_uv[idx], 1, axis=1), axis=2))
        for m in np.flatnonzero(~hit):
            c = np.asarray(tree.query_ball_point(uv[m], diam), dtype=int)
            if c.size == 0:
                continue
            lm = bary(uv[m][None, :], c)
            b = int(np.argmax(lm.min(axis=-1)))
            if lm[b].min() >= -tol:
                f_out[m], lam_out[m] = idx[c[b]], lm[b]
    return f_out, lam_out


def _trace_interpolation(surf: _Surface, space: VectorSpace, uv: np.ndarray) -> sp.csr_matrix:
    """(M, n_scalar) matrix evaluating the FE trace at surface points given by (x, s)."""
    f, lam = _locate(surf.tri_uv, uv)
    if np.any(f < 0):
        bad = uv[f < 0][0]
        raise FESolveError(f"observation point (x, s) = ({bad[0]:.4f}, {bad[1]:.4f}) lies outside the "
                           "meshed surface")
    lam = np.clip(lam, 0.0, None)
    lam /= lam.sum(axis=1, keepdims=True)
    return trace_matrix(space, surf.tris[f], lam)


# ----------------------------------------------------------------------------- half-space part
@dataclass(frozen=True, eq=False)
class _Loads:
    """The loaded column: centres, frames and the local (inward) half-space frames."""

    centres: np.ndarray      # (ms, 3)
    frames: np.ndarray       # (ms, 3, 3) rows t_x, t_s, n (common)
    local: np.ndarray        # (ms, 3, 3) rows e1, e2, e3 = inward normal
    B: np.ndarray            # (3, 3) common load components -> local ones
    widths: np.ndarray       # (ms,) element widths along s
    x0: float = 0.0          # rolling coordinate of the loaded column's centre

    def in_column(self, uv: np.ndarray, dx: float, J: int, edges: np.ndarray) -> np.ndarray:
        """Points (x, s) inside loaded element J."""
        return (np.abs(uv[:, 0] - self.x0) < 0.5 * dx) & (uv[:, 1] > edges[J]) & (uv[:, 1] < edges[J + 1])


def _loads(bm: BodyMesh, x0: float = 0.0) -> _Loads:
    patch = bm.patch
    s = patch.s_centres
    c = surface_point(bm.body, bm.extent, np.full_like(s, x0), s)
    F = surface_frame(bm.body, bm.extent, np.full_like(s, x0), s)
    sig = 1.0 if bm.body.below else -1.0
    B = np.diag([1.0, sig, sig])
    local = np.einsum("ab,jbc->jac", B, F)
    return _Loads(c, F, local, B, patch.s_widths, float(x0))


def _hs_displacement(loads: _Loads, X: np.ndarray, dx: float, G: float, nu: float, J: int) -> np.ndarray:
    """u_hs of load row J at global points X (..., 3): (..., 3 global comps, 3 common loads)."""
    R = loads.local[J]
    q = (X - loads.centres[J]) @ R.T
    u = rectangle_displacement(q, dx, float(loads.widths[J]), G=G, nu=nu)
    return (R.T @ u) @ loads.B              # R^T u B per point (matmul: 5x faster than einsum)


def _residual_load(loads: _Loads, surf: _Surface, space: VectorSpace, patch: StripPatch, G: float, nu: float,
                   J: int, near: float = 3.0) -> np.ndarray:
    """Load vectors (3, n_scalar, 3 common loads) of the residual traction p chi_J - sigma(u_hs) n.

    Facets within ``near`` element sizes of the loaded rectangle (in its plane) use the 6-point rule
    and the closed-form stress; the surface mesh must conform to the loaded element there, so that
    no quadrature point falls into the thin layer (width = the depth of the curved surface below
    the tangent plane, ~d^2/8R) where the half-space traction of the flat rectangle turns from p
    to 0.  Farther facets use their centroid and point forces (2 x 2 Gauss up to 10 sizes, 1 beyond).
    """
    dx, ds = patch.dx, float(loads.widths[J])
    h = max(dx, ds)
    R = loads.local[J]
    qc = (surf.centroids - loads.centres[J]) @ R.T
    gap = np.maximum(np.abs(qc[:, 0]) - 0.5 * dx, np.abs(qc[:, 1]) - 0.5 * ds) - 0.5 * surf.diameter
    is_near = gap < near * h
    out = np.zeros((3, space.n_scalar, 3))
    # near facets: 6 points each, closed form
    fn = np.flatnonzero(is_near)
    if fn.size:
        idx = (fn[:, None] * 6 + np.arange(6)[None, :]).ravel()
        X = surf.points[idx]
        qn = (X - loads.centres[J]) @ R.T
        sig = rectangle_stress(qn, dx, ds, G=G, nu=nu, near=None)              # (Q, 3, 3, 3)
        t = -_to_common(_traction(sig, surf.normal6[idx] @ R.T), R, loads.B)
        t[loads.in_column(surf.uv[idx], dx, J, patch.edges)] += loads.frames[J].T
        P = surf.P6[:, idx]
        for c in range(3):
            out[c] += P @ t[:, c, :]
    # far facets: centroid rule, point forces
    for ng, sel in ((2, (~is_near) & (gap < 10 * h)), (1, gap >= 10 * h)):
        ff = np.flatnonzero(sel)
        if not ff.size:
            continue
        qf = qc[ff]
        sig = _gauss_rectangle_stress(qf[:, 0], qf[:, 1], np.maximum(qf[:, 2], 0.0), dx, ds, nu, ng)
        t = -_to_common(_traction(sig, surf.normal[ff] @ R.T), R, loads.B)
        P = surf.P1[:, ff]
        for c in range(3):
            out[c] += P @ t[:, c, :]
    return out


def _to_common(v_loc: np.ndarray, R: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Vectors per local load (Q, 3 local comps, 3 local loads) -> global comps, common loads."""
    return (R.T @ v_loc) @ B


def _traction(sig: np.ndarray, n: np.ndarray) -> np.ndarray:
    """t[q, k, s] = sum_l sig[q, k, l, s] n[q, l] (stress (Q, 3, 3, loads) on normals (Q, 3))."""
    return np.matmul(n[:, None, None, :], sig)[:, :, 0, :]


def _flat(body: BodyModel) -> bool:
    p = body.profile
    return (not body.revolved) and np.ptp(p.z) < 1e-12 * max(1.0, np.ptp(p.y))


# ----------------------------------------------------------------------------- solvers
def _peak_rss_gib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20


# Peak memory per unknown of assembly + direct factorisation + 3 ms right-hand sides, measured
# here (pypardiso): P1, 69k unknowns, 1.5 GiB; P2, 437k unknowns, 11 GiB -> about 25 kB each.
BYTES_PER_DOF = 25e3


def _available_memory() -> float | None:
    """Bytes of memory available to a new allocation (Linux /proc/meminfo), None if unknown."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return None


def _check_memory(ndofs: int, solver: str) -> None:
    avail = _available_memory()
    need = ndofs * BYTES_PER_DOF * (0.3 if solver == "amg" else 1.0)
    if avail is not None and need > 0.9 * avail:
        raise FESolveError(f"the FE model ({ndofs} unknowns) needs about {need / 2**30:.1f} GiB with the "
                           f"{solver} solver, {avail / 2**30:.1f} GiB are available; coarsen the mesh "
                           "([model] fe_h_patch, fe_growth, fe_order = 1) or use fe_solver = \"amg\"")


def _rigid_modes(points: np.ndarray, comp: np.ndarray) -> np.ndarray:
    """Rigid-body modes (3 translations, 3 rotations) at dofs of component ``comp`` located at
    ``points`` (n, 3): the near null space for smoothed-aggregation AMG."""
    n = len(points)
    B = np.zeros((n, 6))
    B[np.arange(n), comp] = 1.0
    x, y, z = points.T
    rot = {3: ((0, -y), (1, x)), 4: ((1, -z), (2, y)), 5: ((2, -x), (0, z))}
    for col, pairs in rot.items():
        for c, v in pairs:
            B[comp == c, col] = v[comp == c]
    return B


# ----------------------------------------------------------------------------- main
def _exact_averages(surf: _Surface, space: VectorSpace, patch: StripPatch, x0: float) -> sp.csr_matrix:
    """(n_obs, n_scalar): the exact mean of the FE trace over each observed element, from the
    facets inside it (conforming mesh).  It is the transpose of the element load operator divided
    by the element area, so the direct method's matrix is exactly symmetric (reciprocity)."""
    F = len(surf.tris)
    S = sp.csr_matrix((np.ones(6 * F), (np.arange(6 * F), np.repeat(np.arange(F), 6))), shape=(6 * F, F))
    facet_int = (surf.P6 @ S).tocsc()                      # (n_scalar, F): integral of phi_a over T
    cen = surf.tri_uv.mean(axis=1)
    kx = np.floor((cen[:, 0] - x0 - patch.x_edges[0]) / patch.dx).astype(int)
    I = np.searchsorted(patch.edges, cen[:, 1]) - 1
    ok = (kx >= 0) & (kx < patch.n_columns) & (I >= 0) & (I < patch.ms)
    elem = kx * patch.ms + I
    E = sp.csr_matrix((np.ones(ok.sum()), (np.flatnonzero(ok), elem[ok])), shape=(F, patch.n_columns * patch.ms))
    M = (facet_int @ E).T.tocsr()                          # (n_obs, n_scalar)
    # area of each element = integral of 1 = sum of the trace shape functions' integrals
    area = np.asarray(M.sum(axis=1)).ravel()
    if np.any(area <= 0):
        raise FESolveError("an observed element holds no surface facet (mesh does not conform)")
    return sp.diags(1.0 / area) @ M


def _observation_points(bm: BodyMesh, settings: FESettings, x0: float = 0.0):
    """(x, s) of the observation points and the weights that average them per element."""
    patch = bm.patch
    xc, sc, ws = patch.x_centres + x0, patch.s_centres, patch.s_widths
    if settings.collocation == "centre":
        X, S = np.meshgrid(xc, sc, indexing="ij")
        return np.column_stack([X.ravel(), S.ravel()]), np.ones(1)
    g, w = np.polynomial.legendre.leggauss(settings.n_average)
    gx = xc[:, None, None, None] + 0.5 * patch.dx * g[None, None, :, None]
    gs = sc[None, :, None, None] + 0.5 * ws[None, :, None, None] * g[None, None, None, :]
    GX, GS = np.broadcast_arrays(gx, gs)
    return np.column_stack([GX.ravel(), GS.ravel()]), 0.25 * np.outer(w, w).ravel()


def body_influence(body: BodyModel, patch: StripPatch, G: float, nu: float,
                   settings: FESettings = FESettings(), *, mesh: BodyMesh | None = None,
                   progress=None, load_column: int = 0) -> BodyInfluence:
    """FE influence kernel (2mx-1, ms, ms, 3, 3) of one body (see the module docstring).

    G, nu: this body's shear modulus (N/mm²) and Poisson ratio.  ``mesh``: a mesh made earlier
    for the same body, patch and ``settings.mesh`` (else it is made here).  ``load_column``:
    load the column ``load_column`` elements away from x = 0 instead (observed columns move
    with it; needs ``conform = "all"``): by the invariance along x the kernel must not change,
    which is what the tests check.
    """
    if not (G > 0 and math.isfinite(G)):
        raise InputError(f"material: G must be > 0, got {G}")
    if not -1.0 < nu < 0.5:
        raise InputError(f"material: nu must lie in (-1, 0.5), got {nu}")
    if settings.method == "split" and settings.mesh.conform == "none" and not _flat(body):
        raise InputError("[model] fe_conform: the split method on a curved body needs a mesh that conforms "
                         "to the loaded column (\"column\" or \"all\")")
    if load_column and settings.mesh.conform != "all":
        raise InputError("load_column: loading another column needs a mesh with conform = \"all\"")
    stats: dict = {}
    t0 = time.perf_counter()
    bm = mesh if mesh is not None else mesh_body(body, patch, settings.mesh)
    body = bm.body            # the profile as meshed (continued straight where it was short: the
    #                           arc lengths of the original points, and so the patch, are the same)
    stats.update({f"mesh_{k}": v for k, v in bm.stats.items()})
    stats["body"] = {k: bm.stats[k] for k in _BODY_KEYS if k in bm.stats}
    t_mesh = time.perf_counter()
    order = settings.mesh.order
    m, space = _space(bm, order)
    ndofs = space.basis.N
    stats["dofs"] = int(ndofs)
    if ndofs > settings.max_dofs:
        raise FESolveError(f"the FE model has {ndofs} unknowns, more than max_dofs = {settings.max_dofs}; "
                           "coarsen the mesh ([model] fe_h_patch, fe_growth) or raise the limit")
    try:
        K = stiffness(space, G, nu)
    except MemoryError:
        raise FESolveError(f"out of memory assembling the stiffness matrix ({ndofs} unknowns)") from None
    t_asm = time.perf_counter()
    _, D = clamped_dofs(space, bm.clamped_tris)
    free = np.setdiff1d(np.arange(ndofs), D)
    surf = _free_surface(bm, m, space)
    x0 = load_column * patch.dx
    loads = _loads(bm, x0)
    ms, nl = patch.ms, 3 * patch.ms
    dx = patch.dx

    # right-hand sides (n_scalar x loads per component) and Dirichlet values on the artificial
    # boundaries: the total field there is the half-space field u_hs ("halfspace") or zero
    # ("clamped"); the split method solves for u - u_hs, the direct method for u itself
    Fc = np.zeros((3, space.n_scalar, nl))
    UD = np.zeros((D.size, nl))
    flat = _flat(body)
    hs_on_boundary = (settings.method == "direct") == (settings.far_field == "halfspace")
    if hs_on_boundary:
        Xd = space.basis.doflocs.T[D]                 # (nD, 3) positions of the boundary dofs
        comp = np.zeros(D.size, dtype=int)
        for c in range(3):
            comp[np.isin(D, space.dofmap[c])] = c
        sign = 1.0 if settings.method == "direct" else -1.0
        for J in range(ms):
            UD[:, 3 * J:3 * J + 3] = sign * _hs_displacement(loads, Xd, dx, G, nu, J)[np.arange(D.size), comp]
    for J in range(ms):
        if settings.method == "direct":
            T = np.zeros((surf.uv.shape[0], 3, 3))
            T[loads.in_column(surf.uv, dx, J, patch.edges)] = loads.frames[J].T   # unit traction p_j
            for c in range(3):
                Fc[c, :, 3 * J:3 * J + 3] = surf.P6 @ T[:, c, :]
        elif not flat:                                # sigma(u_hs) n = p on a flat surface: no residual
            Fc[:, :, 3 * J:3 * J + 3] = _residual_load(loads, surf, space, patch, G, nu, J)
        if progress:
            progress(J + 1, ms)
    F = space.from_components(Fc)
    t_rhs = time.perf_counter()

    # solve K_ff U_f = F_f - K_fD U_D
    solver = direct_solver(settings.solver)
    _check_memory(ndofs, solver)
    Kff = K[free][:, free].tocsr()
    rhs = F[free] - K[free][:, D] @ UD
    near_null = None
    if solver == "amg":
        comp_all = np.zeros(ndofs, dtype=int)
        for c in range(3):
            comp_all[space.dofmap[c]] = c
        near_null = _rigid_modes(space.basis.doflocs.T[free], comp_all[free])
    try:
        corrected = bool(rhs.any())   # False: split method, flat body, half-space far field: no correction
        if not corrected:
            Uf, iterations, t_fac = np.zeros_like(rhs), 0, time.perf_counter()
        else:
            fac = _Factor(Kff, solver, settings.amg_tol, near_null, release=True)
            t_fac = time.perf_counter()
            Uf, iterations = fac.solve(rhs), fac.iterations
    except MemoryError:
        raise FESolveError(f"out of memory in the {solver} solve ({ndofs} unknowns); coarsen the mesh "
                           "([model] fe_h_patch, fe_growth) or use fe_solver = \"amg\"") from None
    except FESolveError:
        raise
    except Exception as exc:  # pypardiso raises PyPardisoError (e.g. error -2: not enough memory)
        if solver != "pardiso":
            raise
        raise FESolveError(f"pypardiso failed ({ndofs} unknowns): {exc}") from None
    U = np.zeros((ndofs, nl))
    U[free] = Uf
    U[D] = UD
    t_solve = time.perf_counter()

    # observation: FE part by trace interpolation (+ half-space part for the split method)
    obs_uv, wts = _observation_points(bm, settings, x0)
    per = wts.size
    nc = patch.n_columns
    exact = settings.collocation == "average" and settings.mesh.conform == "all"
    if exact:
        Q = _exact_averages(surf, space, patch, x0)
        u = np.stack([Q @ U[space.dofmap[c]] for c in range(3)], axis=1).reshape(nc, ms, 3, ms, 3)
    else:
        Q = _trace_interpolation(surf, space, obs_uv)
        u = np.stack([Q @ U[space.dofmap[c]] for c in range(3)], axis=1)     # (M, 3 comps, loads)
        u = np.einsum("kIpcJj,p->kIcJj", u.reshape(nc, ms, per, 3, ms, 3), wts)  # (kx, I, comp, J, j)
    if settings.method == "split":
        Xo = surface_point(body, bm.extent, obs_uv[:, 0], obs_uv[:, 1])
        uh = np.empty((len(obs_uv), 3, 3 * ms))
        for J in range(ms):
            uh[:, :, 3 * J:3 * J + 3] = _hs_displacement(loads, Xo, dx, G, nu, J)
        u += np.einsum("kIpcJj,p->kIcJj", uh.reshape(nc, ms, per, 3, ms, 3), wts)
    frames = surface_frame(body, bm.extent, x0 + patch.x_centres[:, None], patch.s_centres[None, :])
    kernel = np.einsum("kIic,kIcJj->kIJij", frames, u)
    t_obs = time.perf_counter()
    stats.update({"method": settings.method, "order": order, "solver": solver,
                  "mesh_s": t_mesh - t0, "assemble_s": t_asm - t_mesh, "rhs_s": t_rhs - t_asm,
                  "factor_s": t_fac - t_rhs, "solve_s": t_solve - t_fac, "observe_s": t_obs - t_solve,
                  "total_s": t_obs - t0, "peak_rss_gib": _peak_rss_gib(), "amg_iterations": iterations,
                  "corrected": corrected})
    return BodyInfluence(kernel, body.kind, patch, G, nu, settings, stats)


def combine(body1: BodyInfluence, body2: BodyInfluence) -> np.ndarray:
    """Two-body kernel u = u(body 1) - u(body 2) per unit traction on body 1 (the rail).

    Each body's kernel is its own displacement per unit traction acting on it, in the common
    frame; body 2 carries -p and its displacement enters with a minus sign, so the two add.
    """
    if body1.kernel.shape != body2.kernel.shape:
        raise InputError(f"FE kernels of different grids: {body1.kernel.shape} and {body2.kernel.shape}")
    return body1.kernel + body2.kernel


# ----------------------------------------------------------------------------- cache
def body_key(body: BodyModel, patch: StripPatch, G: float, nu: float, settings: FESettings) -> dict:
    """Everything that determines a body's FE kernel (the cache key inputs)."""
    return {"what": "fe-body-influence", "fe_version": FE_VERSION, "body": body.key(), "patch": patch.key(),
            "G": float(G), "nu": float(nu), "settings": settings.key()}


def cached_body_influence(body: BodyModel, patch: StripPatch, G: float, nu: float,
                          settings: FESettings = FESettings(), *, cache=None,
                          strict_cache: bool = False) -> BodyInfluence:
    """:func:`body_influence` through the NPZ cache (``cache``: a Cache, a folder, None = default,
    False = no cache).  ``strict_cache``: a failed cache write raises CacheWriteError (else it
    is warned about and the numbers are returned uncached)."""
    from conformal.influence.cache import Cache

    if cache is False:
        return body_influence(body, patch, G, nu, settings)
    c = cache if isinstance(cache, Cache) else Cache(cache)
    inputs = body_key(body, patch, G, nu, settings)
    result: dict = {}

    def compute():
        r = body_influence(body, patch, G, nu, settings)
        result["r"] = r
        stats = dict(r.stats, summary=f"{body.kind} {body.profile.name}: {patch.n_columns}x{patch.ms} "
                     f"dx={patch.dx:.4g} G={G:g} nu={nu:g} {settings.method} P{settings.mesh.order}")
        return {"kernel": r.kernel}, stats

    arrays, hit = c.get_or_compute(inputs, compute, strict=strict_cache)
    if not hit:
        return result["r"]
    meta = c.meta(c.key(inputs)) or {}
    stats = dict(meta.get("stats", {}), cache_hit=True)
    return BodyInfluence(arrays["kernel"], body.kind, patch, G, nu, settings, stats)


# ----------------------------------------------------------------------------- wheel and rail
def _edge_points(grid) -> np.ndarray:
    """Rail-profile-frame points (y, z) of the grid's s-edges (x = 0)."""
    return np.stack([np.interp(grid.s_edges, grid.rail_curve_s, grid.rail_curve[:, 0]),
                     np.interp(grid.s_edges, grid.rail_curve_s, grid.rail_curve[:, 1])], axis=1)


def rail_body_from_grid(grid, rail_points: np.ndarray | None = None, name: str = "rail"
                        ) -> tuple[BodyModel, StripPatch]:
    """The rail body and its patch for a :class:`~conformal.grid.CurvedGrid`.

    ``rail_points``: the whole rail profile (rail-profile frame) to give the FE body room beyond
    the grid's local curve (``grid.rail_curve`` reaches only a few mm past the grid).
    """
    pts = grid.rail_curve if rail_points is None else np.asarray(rail_points, dtype=float)
    from conformal.meshing.bodies import Profile2D

    prof = Profile2D.from_points(pts, name)
    P = _edge_points(grid)
    edges = prof.project(P)
    miss = float(np.max(np.linalg.norm(prof.point(edges) - P, axis=1)))
    if miss > 0.01:
        raise InputError(f"rail body: the grid does not lie on the given rail profile ({miss:.3f} mm off)")
    return BodyModel("rail", prof), StripPatch(grid.mx, grid.dx, tuple(float(v) for v in edges))


def wheel_axes(grid) -> np.ndarray:
    """The wheel's axes in the rail-profile frame (x, y, z).

    Parameters
    ----------
    grid : CurvedGrid
        Its ``wheel_axle`` and ``wheel_down`` directions.

    Returns
    -------
    ndarray (3, 3)
        Columns: forward, axle, down (unit vectors).
    """
    a = np.asarray(grid.wheel_axle, dtype=float)
    d = np.asarray(grid.wheel_down, dtype=float)
    f = np.cross(a, d)
    return np.column_stack([f / np.linalg.norm(f), a / np.linalg.norm(a), d / np.linalg.norm(d)])


def wheel_body_from_grid(grid, wheel_points: np.ndarray | None = None, name: str = "wheel"
                         ) -> tuple[BodyModel, StripPatch, np.ndarray]:
    """The wheel body (in its own frame: y along the axle, z = increase of radius, down), its
    patch (the grid's s-edges projected onto the wheel profile), and the rotations (ms, 3, 3) from
    the wheel's element frames to the rail's element frames (about x: the small angle between
    the wheel and rail normals across the patch, and the roll of the wheelset against the rail)."""
    from conformal.meshing.bodies import Profile2D

    pts = grid.wheel_profile if wheel_points is None else np.asarray(wheel_points, dtype=float)
    prof = Profile2D.from_points(pts, name)
    M = wheel_axes(grid)
    P = np.column_stack([np.zeros(grid.ms + 1), _edge_points(grid)])           # rail frame
    q = (P - np.asarray(grid.wheel_centre, dtype=float)) @ M                      # wheel axes
    yz = np.column_stack([q[:, 1], q[:, 2] - grid.wheel_radius])                # (y_w, z_w)
    edges = prof.project(yz)
    miss = float(np.max(np.linalg.norm(prof.point(edges) - yz, axis=1)))
    if miss > 10.0:
        raise InputError(f"wheel body: the wheel profile lies {miss:.1f} mm from the rail grid (wrong or "
                         "mirrored wheel profile?)")
    if np.any(np.diff(edges) <= 0):
        raise InputError("wheel body: the grid's elements do not map to increasing positions on the "
                         "wheel profile (the wheel profile does not face the rail grid)")
    body = BodyModel("wheel", prof, axle_z=-float(grid.wheel_radius))
    patch = StripPatch(grid.mx, grid.dx, tuple(float(v) for v in edges))
    # element frames: wheel (own axes) -> rail-profile frame -> rail element frames
    from conformal.meshing.bodies import body_extent

    ext = body_extent(body, patch, 1e-3)
    Fw = surface_frame(body, ext, np.zeros(patch.ms), patch.s_centres)            # (ms, 3, 3) rows
    n = np.asarray(grid.normal, dtype=float)
    Fr = np.zeros((grid.ms, 3, 3))
    Fr[:, 0, 0] = 1.0
    Fr[:, 1, 1], Fr[:, 1, 2] = n[:, 1], -n[:, 0]                                  # t_s = n x t_x
    Fr[:, 2, 1], Fr[:, 2, 2] = n[:, 0], n[:, 1]
    rot = np.einsum("Iab,bc,Idc->Iad", Fr, M, Fw)
    return body, patch, rot


def rotate_kernel(kernel: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """K'[k, I, J] = rot_I K[k, I, J] rot_J^T (components into other element frames)."""
    return np.matmul(np.matmul(rot[None, :, None], kernel), np.swapaxes(rot, 1, 2)[None, None, :])


def _body_worker(conn, args, cache) -> None:
    """Child process of :func:`wheel_rail_kernel`: one body's kernel (through the cache), sent back
    with its statistics, or the exception it raised."""
    try:
        r = cached_body_influence(*args, cache=cache)
        conn.send(("ok", r.kernel, r.stats))
    except BaseException as exc:  # noqa: BLE001 - re-raised in the parent
        try:
            conn.send(("error", exc, None))
        except Exception:  # an exception that cannot be pickled: its message
            conn.send(("error", FESolveError(f"{type(exc).__name__}: {exc}"), None))
    finally:
        conn.close()


#: observed elements ((2 mx - 1) x ms) above which the two bodies are not computed at once
PARALLEL_MAX_OBSERVED = 8000


def _fe_workers(workers: int | None) -> int:
    """Processes for the two bodies: ``workers``, else $CONFORMAL_FE_WORKERS, else 2 where the
    machine has two cores and this process runs no other Python thread; 1 where processes
    cannot be forked (not Linux)."""
    import multiprocessing as mp
    import os

    if workers is None:
        env = os.environ.get("CONFORMAL_FE_WORKERS", "").strip()
        if env:
            try:
                workers = int(env)
            except ValueError:
                raise InputError(f"CONFORMAL_FE_WORKERS: must be an integer, got {env!r}") from None
        else:
            # forking a process that runs other Python threads (a notebook kernel, a Dask
            # worker) may copy a lock held by one of them: one after the other there
            import threading

            workers = 2 if (os.cpu_count() or 1) >= 2 and threading.active_count() == 1 else 1
    if "fork" not in mp.get_all_start_methods():
        workers = 1
    return max(1, int(workers))


def body_influences(jobs: list[tuple], cache=None, workers: int | None = None) -> list[BodyInfluence]:
    """The kernels of two bodies, ``jobs`` = [(body, patch, G, nu, settings)] * 2 (through the
    cache, as :func:`cached_body_influence`).  Where neither is cached and two workers are allowed, the second one
    is computed in a forked child process while this process computes the first (each body is
    meshed by its own single-threaded gmsh: the same numbers as one after the other, in about
    half the wall time on two cores)."""
    from conformal.influence.cache import Cache

    # large patches (e.g. a 60 mm strip over three patches: 130k unknowns and 600 right-hand
    # sides, several GiB per body) run one after the other: two at once could exhaust the memory
    parallel = (_fe_workers(workers) >= 2 and len(jobs) == 2
                and all(patch.n_columns * patch.ms <= PARALLEL_MAX_OBSERVED for _, patch, *_ in jobs))
    if parallel and cache is not False:
        c = cache if isinstance(cache, Cache) else Cache(cache)
        parallel = not any(c.has(c.key(body_key(*args))) for args in jobs)
        cache = c
    if not parallel:
        return [cached_body_influence(*args, cache=cache) for args in jobs]
    import multiprocessing as mp

    ctx = mp.get_context("fork")    # a copy of this process: no re-import, no __main__ re-run
    recv, send = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_body_worker, args=(send, jobs[1], cache), daemon=True)
    try:
        child.start()
    except OSError:                  # cannot fork (limits): one after the other
        send.close()
        recv.close()
        return [cached_body_influence(*args, cache=cache) for args in jobs]
    send.close()
    try:
        first = cached_body_influence(*jobs[0], cache=cache)
        try:
            status, value, stats = recv.recv()
        except EOFError:              # the child died (killed, out of memory): redo it here
            status, value, stats = "lost", None, None
    finally:
        recv.close()
        child.join(timeout=60)
        if child.is_alive():
            child.kill()
            child.join()
    if status == "error":
        raise value
    if status == "lost":
        return [first, cached_body_influence(*jobs[1], cache=cache)]
    body, patch, G, nu, settings = jobs[1]
    return [first, BodyInfluence(value, body.kind, patch, G, nu, settings, dict(stats, process="child"))]


def wheel_rail_kernel(grid, material, settings: FESettings = FESettings(), *, cache=None,
                      rail_points: np.ndarray | None = None, wheel_points: np.ndarray | None = None,
                      names: tuple[str, str] = ("rail", "wheel"), workers: int | None = None
                      ) -> tuple[np.ndarray, dict]:
    """Two-body FE kernel (2mx-1, ms, ms, 3, 3) for a curved grid: rail (body 1: G1, nu1) plus
    wheel (body 2: G2, nu2), in the rail's element frames (CurvedInfluence.from_kernel takes it).

    ``workers``: processes for the two bodies when neither is cached (None: 2 on a machine with
    two cores or more, see :func:`_fe_workers`; 1: one after the other).  Returns (kernel, info)
    with the statistics of both bodies (times, unknowns, cache hits).
    """
    rail, rpatch = rail_body_from_grid(grid, rail_points, name=names[0])
    wheel, wpatch, rot = wheel_body_from_grid(grid, wheel_points, name=names[1])
    kr, kw = body_influences([(rail, rpatch, material.G1, material.nu1, settings),
                          (wheel, wpatch, material.G2, material.nu2, settings)], cache, workers)
    kernel = kr.kernel + rotate_kernel(kw.kernel, rot)
    return kernel, {"rail": kr.stats, "wheel": kw.stats}


# ----------------------------------------------------------------------------- settings
_OPTION_KEYS = {"fe_method": "method", "fe_order": "order", "fe_h_patch": "h_patch", "fe_h_load": "h_load",
                "fe_growth": "growth", "fe_h_max": "h_max", "fe_conform": "conform",
                "fe_body_size": "body_size", "fe_solver": "solver", "fe_collocation": "collocation",
                "fe_far_field": "far_field", "fe_closure": "closure", "fe_h_wall": "h_wall"}


def settings_from_options(options) -> FESettings:
    """FESettings from a scene's [model] keys fe_method, fe_order, fe_h_patch, fe_h_load, fe_growth,
    fe_h_max, fe_conform, fe_body_size, fe_solver, fe_collocation, fe_far_field, fe_closure, fe_h_wall
    (defaults for missing keys)."""
    opts = {k: v for k, v in dict(options or {}).items() if str(k).startswith("fe_")}
    unknown = sorted(set(opts) - set(_OPTION_KEYS))
    if unknown:
        raise InputError(f"[model] {unknown[0]}: unknown FE key (known: {', '.join(sorted(_OPTION_KEYS))})")
    mesh_kw, top_kw = {}, {}
    for k, v in opts.items():
        name = _OPTION_KEYS[k]
        if name in ("method", "solver", "collocation", "conform", "far_field", "closure"):
            if not isinstance(v, str):
                raise InputError(f"[model] {k}: must be a string, got {v!r}")
        elif name == "order":
            if isinstance(v, bool) or not isinstance(v, int):
                raise InputError(f"[model] {k}: must be 1 or 2, got {v!r}")
        elif isinstance(v, bool) or not isinstance(v, (int, float)):
            raise InputError(f"[model] {k}: must be a number, got {v!r}")
        (top_kw if name in ("method", "solver", "collocation", "far_field") else mesh_kw)[name] = v
    return FESettings(mesh=replace(MeshSpec(), **mesh_kw), **top_kw)
