"""Direct FE contact of two elastic bodies: frictionless Signorini contact, dual mortar.

The bodies are tetrahedral meshes (:class:`~conformal.meshing.gmsh_body.BodyMesh`, made by gmsh;
quadratic or linear elements) of linear-elastic material (small strains), placed in one common
frame whose contact normal n points into body 1 (the rail or block) and out of body 2 (the wheel
or sphere).  Body 2 moves rigidly by the approach ``delta`` along the unit load direction d.  At a
point x of body 1's surface, paired with the point pi(x) of body 2's surface on the line along
n(x) (small sliding), the linearised gap is

    g(x) = g0(x) - delta (n . d) + n . (u1(x) - u2(pi(x))),                          (1)

g0 the undeformed distance, taken from the exact surfaces (profiles), not from the facets.  The
contact pressure is p = sum_i lambda_i psi_i with the dual (biorthogonal) basis psi_i = 4 phi_i - 1
on body 1's surface triangles (Wohlmuth 2000), and the gap is tested with the same functions,
g_i = int psi_i g dA / a_i, a_i = int phi_i dA (integrals by a composite rule on each triangle:
the mortar projection of body 2's displacement).  The discrete Signorini conditions (Signorini
1933; Kikuchi and Oden 1988, ch. 6; Hueeber and Wohlmuth 2005) are

    g_i >= 0,   lambda_i >= 0,   lambda_i g_i = 0,                                   (2)

and the nodal force on body 1 is a_i lambda_i (a diagonal slave side, so lambda_i is the nodal
pressure).  Elasticity is linear, so u = sum_j lambda_j U_j with U_j the response of both bodies to
the load of a unit lambda_j: g = r + W lambda with W = B K^-1 B^T a, exactly (static condensation
of the FE system onto the contact nodes).  (1)-(2) is solved by the primal-dual active set method,
i.e. semismooth Newton on lambda - max(0, lambda - c g) = 0 (Hintermueller, Ito and Kunisch 2002):
with the active set A = {lambda - c g > 0}, W_AA lambda_A = -r_A, lambda = 0 elsewhere; should a
set come back (W is not an M-matrix) it continues one change per step.  The columns W[:, j] are
computed only for nodes that become active (one sparse factorisation per body, block solves).
With a prescribed normal force the approach is one more unknown with the equation
sum_A a_j lambda_j (n_j . d) = F.

Artificial boundaries.  A body cut out of a large one and clamped at its cut faces is stiffer
than the large body (docs/architecture.md §5: 20-40 % in FN at a prescribed approach).  With
``far_field = "halfspace"`` (default) the cut faces of each body carry, instead of zero, the
displacement of the half-space tangent to the contact at the loaded node under the same point
force (Boussinesq 1885; Johnson 1985, eq. 3.19): the truncated body then behaves like a
half-space far from the contact, which is what Hertz's theory and the half-space influence numbers
assume, and the approach delta is the approach of distant points as in Hertz's theory.  The
boundary data are linear in lambda, so they enter each column U_j exactly (no iteration).
``far_field = "clamped"`` fixes the cut faces (body 1) or moves them rigidly (body 2).

Pressure: the nodal values lambda_i; ``pmax`` after a local least-squares recovery
(:func:`recovered_pressure`).  Contact area: between the triangles with all nodes in contact and
the lumped areas of the nodes in contact (:attr:`FEContactSolution.contact_area_bounds`).

>>> import numpy as np
>>> round(float(boussinesq(np.array([[0.0, 0.0, 1.0]]), np.array([0.0, 0.0, 1.0]), 1.0, 0.25)[0, 2]
...       * 4 * np.pi), 6)   # u_z on the axis: (1 + 2 (1 - nu)) / (4 pi G z)
2.5
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from conformal.errors import ConformalError, ConvergenceError, InputError, NoContactError
from conformal.influence.factor import Factor
from conformal.influence.fe_toolkit import (clamped_dofs, direct_solver, scalar_positions, stiffness, trace_matrix,
                                            vector_space)
from conformal.meshing.gmsh_body import BodyMesh, surface_frame, surface_point

FAR_FIELDS = ("halfspace", "clamped")
SOLVERS = ("auto", "splu", "pardiso")


class FEContactError(ConformalError):
    """The FE contact solve failed (too many unknowns, no pairing between the surfaces)."""


@dataclass(frozen=True)
class FEContactSettings:
    """Solver settings (the meshes carry their own refinement).

    far_field : "halfspace" (half-space field of the contact forces on the cut faces) | "clamped".
    solver : sparse direct solver: "auto" (pypardiso when installed, else scipy's splu) | "splu" |
        "pardiso".
    max_iter : active-set iterations (all changes at once) before one change per step.
    block : right-hand sides per block solve.
    max_dofs : refuse larger FE models (memory).
    subdivision : the mortar integrals use k x k sub-triangles per surface triangle.
    multiplier : "dual" (biorthogonal, default) or "standard" (P1) test functions.
    order : 1 or 2, the element order ([model] fec_order).
    """

    far_field: str = "halfspace"
    solver: str = "auto"
    max_iter: int = 60
    block: int = 96
    max_dofs: int = 600_000
    subdivision: int = 4
    multiplier: str = "dual"
    order: int = 2

    def __post_init__(self):
        if self.far_field not in FAR_FIELDS:
            raise InputError(f"[model] fec_far_field: must be one of {', '.join(FAR_FIELDS)}, got {self.far_field!r}")
        if self.solver not in SOLVERS:
            raise InputError(f"[model] fec_solver: must be one of {', '.join(SOLVERS)}, got {self.solver!r}")
        if self.order not in (1, 2):
            raise InputError(f"[model] fec_order: must be 1 or 2, got {self.order!r}")
        if self.multiplier not in ("dual", "standard"):
            raise InputError(f"FEContactSettings: multiplier must be \"dual\" or \"standard\", got {self.multiplier!r}")
        if self.max_iter < 1 or self.block < 1 or self.max_dofs < 1 or self.subdivision < 1:
            raise InputError("FEContactSettings: max_iter, block and max_dofs must be >= 1")


@dataclass(frozen=True, eq=False)
class ContactBody:
    """One meshed body, its material and its placement in the common frame.

    A mesh point p (the body's own frame, see :mod:`conformal.meshing.bodies`) lies at
    ``origin + rotation @ p`` in the common frame.
    """

    mesh: BodyMesh
    G: float
    nu: float
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self):
        if not (self.G > 0 and math.isfinite(self.G)):
            raise InputError(f"[material] G: must be > 0, got {self.G}")
        if not -1.0 < self.nu < 0.5:
            raise InputError(f"[material] nu: must lie in (-1, 0.5), got {self.nu}")
        R = np.asarray(self.rotation, dtype=float)
        if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
            raise InputError("ContactBody: rotation must be a 3 x 3 orthogonal matrix")

    @property
    def points(self) -> np.ndarray:
        """Mesh points in the common frame (N, 3)."""
        return np.asarray(self.origin, float) + self.mesh.points @ np.asarray(self.rotation, float).T


@dataclass(frozen=True, eq=False)
class FEContactSolution:
    """The solution on the slave nodes (free-surface nodes of body 1 paired with body 2).

    nodes : (n,) node indices in body 1's mesh; X (n, 3) their positions, normal (n, 3) the
    contact normals (into body 1; averaged with the dual weights, so |normal| <= 1 where the
    surface curves), uv (n, 2) their (x, s) surface coordinates; g0 (n,) the
    undeformed distance; force (n,) the normal nodal forces lambda a (N); area (n,) lumped areas
    (mm²); pressure = force / area (N/mm²); gap (n,) the deformed gap; active (n,) bool; tris
    (t, 3) the slave triangles (as indices into these arrays) and tri_area (t,) their areas.
    approach : rigid approach delta of body 2 along ``direction`` (mm).
    shift, shift_direction : a second rigid motion of body 2, ``shift`` (mm) along the unit
        ``shift_direction`` (zero unless a lateral force was prescribed, :meth:`ContactModel.solve`).
    """

    nodes: np.ndarray
    X: np.ndarray
    normal: np.ndarray
    uv: np.ndarray
    g0: np.ndarray
    force: np.ndarray
    area: np.ndarray
    gap: np.ndarray
    active: np.ndarray
    approach: float
    direction: np.ndarray
    iterations: int
    n_unknowns: int
    stats: dict
    tris: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int64))
    tri_area: np.ndarray = field(default_factory=lambda: np.zeros(0))
    shift: float = 0.0
    shift_direction: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def pressure(self) -> np.ndarray:
        return self.force / self.area

    @property
    def FN(self) -> float:
        """Total normal force sum(lambda) (N)."""
        return float(self.force.sum())

    @property
    def F_load(self) -> float:
        """Force along the load direction, sum(lambda (n . d)) (N)."""
        return float(self.force @ (self.normal @ self.direction))

    @property
    def force_vector(self) -> np.ndarray:
        """Resultant contact force on body 1 in the common frame (N)."""
        return self.force @ self.normal

    @property
    def pmax_nodal(self) -> float:
        """Largest nodal pressure lambda_i (N/mm²)."""
        return float(self.pressure.max()) if self.force.size else 0.0

    @property
    def pmax(self) -> float:
        """Largest recovered pressure (:func:`recovered_pressure`) (N/mm²)."""
        return float(recovered_pressure(self).max()) if self.force.size else 0.0

    @property
    def contact_area_bounds(self) -> tuple[float, float]:
        """(inner, outer) estimates of the contact area (mm²): the slave triangles with all three
        nodes in contact, and the lumped areas of the nodes in contact (the edge of the contact
        lies between the last node in contact and the first one out)."""
        inner = float(self.tri_area[self.active[self.tris].all(axis=1)].sum())
        return inner, float(self.area[self.active].sum())

    @property
    def contact_area(self) -> float:
        """Contact area: the mean of :attr:`contact_area_bounds` (mm²)."""
        return 0.5 * sum(self.contact_area_bounds)

    @property
    def overlap_approach(self) -> float:
        """Largest rigid overlap along the local normals, max(delta n.d - g0) (mm)."""
        return float(np.max(self.approach * (self.normal @ self.direction) - self.g0))


def recovered_pressure(sol: FEContactSolution, radius: float = 2.0) -> np.ndarray:
    """Pressure recovered by local least squares: at every active node the value at that node of
    the quadratic in (x, s) fitted to the nodal pressures of the active nodes within ``radius``
    mesh spacings (sqrt of the median lumped area), where at least 10 of them lie; the nodal
    value elsewhere (contact edge).  Linear tetrahedra, and to a lesser degree quadratic ones,
    give nodal contact pressures with a scatter of a few per cent from node to node (the
    irregular tetrahedra under the surface); the fit removes the scatter, not the trend
    (exact for a quadratic pressure), so that pmax is not the largest scatter."""
    from scipy.spatial import cKDTree

    p = sol.pressure.copy()
    act = np.where(sol.active)[0]
    if act.size < 10:
        return p
    uv = sol.uv[act]
    r = radius * math.sqrt(float(np.median(sol.area[act])))
    tree = cKDTree(uv)
    for k, nb in enumerate(tree.query_ball_point(uv, r)):
        if len(nb) < 10:
            continue
        d = uv[nb] - uv[k]
        V = np.column_stack([np.ones(len(nb)), d[:, 0], d[:, 1], d[:, 0] ** 2, d[:, 0] * d[:, 1], d[:, 1] ** 2])
        coef = np.linalg.lstsq(V / r ** np.array([0, 1, 1, 2, 2, 2]), sol.pressure[act[nb]], rcond=None)[0]
        p[act[k]] = coef[0]
    return p


# ----------------------------------------------------------------------------- half-space field
def boussinesq(r: np.ndarray, e: np.ndarray, G: float, nu: float) -> np.ndarray:
    """Displacement (..., 3) at offsets r (..., 3) from a unit point force along e, the inner
    normal of the half-space (Boussinesq 1885; Johnson 1985, eq. 3.19 in vector form):

        u = [(z / rho^3 - (1 - 2 nu) / (rho (rho + z))) r_t + (z^2 / rho^3 + 2 (1 - nu) / rho) e] / (4 pi G)

    with z = r . e (depth, clipped at 0 for points above the tangent plane), r_t = r - z e.
    """
    r = np.asarray(r, dtype=float)
    e = np.asarray(e, dtype=float)
    z = np.einsum("...k,...k->...", r, np.broadcast_to(e, r.shape))
    rt = r - z[..., None] * e
    z = np.maximum(z, 0.0)
    rho = np.sqrt(np.einsum("...k,...k->...", rt, rt) + z * z)
    rho = np.maximum(rho, 1e-300)
    k = 1.0 - 2.0 * nu
    a = z / rho ** 3 - k / (rho * (rho + z))
    b = z * z / rho ** 3 + 2.0 * (1.0 - nu) / rho
    return (a[..., None] * rt + b[..., None] * e) / (4.0 * math.pi * G)


# ----------------------------------------------------------------------------- FE pieces
@dataclass(eq=False)
class _FEBody:
    points: np.ndarray        # vertices, common frame
    dofmap: np.ndarray        # (3, n_scalar) dof of component c at scalar node g (vertices, then edges)
    D: np.ndarray             # Dirichlet dofs (all components, sorted)
    free: np.ndarray
    D_scalar: np.ndarray      # scalar nodes on the cut faces
    X_scalar: np.ndarray      # (n_scalar, 3) positions of the scalar nodes
    space: object             # the vector space (conformal.influence.fe_toolkit.vector_space)
    K_fD: sp.csr_matrix
    factor: Factor
    ndofs: int
    order: int
    G: float
    nu: float


def _fe_body(body: ContactBody, solver: str, max_dofs: int, order: int) -> _FEBody:
    pts = body.points
    m, space = vector_space(pts, body.mesh.tets, order)
    basis, dofmap = space.basis, space.dofmap
    ndofs = basis.N
    if ndofs > max_dofs:
        raise FEContactError(f"the {body.mesh.body.kind} body has {ndofs} unknowns, more than max_dofs = "
                             f"{max_dofs}; coarsen the mesh ([model] fec_n, fec_growth)")
    K = stiffness(space, body.G, body.nu)
    X_scalar = scalar_positions(space)
    fb = _FEBody(pts, dofmap, np.zeros(0, int), np.zeros(0, int), np.zeros(0, int), X_scalar, space,
                 None, None, ndofs, order, body.G, body.nu)
    clamped = body.mesh.clamped_tris
    if len(clamped) == 0:
        raise FEContactError(f"the {body.mesh.body.kind} body has no cut faces to hold it")
    D_scalar, D = clamped_dofs(space, clamped)
    free = np.setdiff1d(np.arange(ndofs), D)
    Kf = K[free]
    try:
        # K_ff is SPD: a symmetric ordering without pivoting (half the fill and time of COLAMD)
        factor = Factor(Kf[:, free].tocsr(), solver, ordering="MMD_AT_PLUS_A")
    except MemoryError:
        raise FEContactError(f"out of memory factorising the {body.mesh.body.kind} body ({ndofs} unknowns)") from None
    fb.D, fb.free, fb.D_scalar, fb.K_fD, fb.factor = D, free, D_scalar, Kf[:, D].tocsr(), factor
    return fb


def _ray_triangles(X: np.ndarray, n: np.ndarray, T: np.ndarray):
    """Intersections of the lines X + t n with triangles T (..., 3, 3): t and barycentric (b1, b2)."""
    e1 = T[..., 1, :] - T[..., 0, :]
    e2 = T[..., 2, :] - T[..., 0, :]
    pv = np.cross(n, e2)
    det = np.einsum("...k,...k->...", e1, pv)
    det = np.where(np.abs(det) < 1e-300, 1e-300, det)
    tv = X - T[..., 0, :]
    b1 = np.einsum("...k,...k->...", tv, pv) / det
    qv = np.cross(tv, e1)
    b2 = np.einsum("...k,...k->...", n, qv) / det
    t = np.einsum("...k,...k->...", e2, qv) / det
    return t, b1, b2


def pair_surfaces(X: np.ndarray, normal: np.ndarray, points2: np.ndarray, tris2: np.ndarray, *, k: int = 12):
    """Node-to-surface pairing: for each point X_i the point of the triangulated surface
    (points2, tris2) on the line X_i + t n_i nearest to X_i.

    Returns (ok, tri, bary, g0): ok (n,) bool, tri (n,) triangle index, bary (n, 3) barycentric
    coordinates, g0 (n,) = -t, the distance from the surface to X_i along n_i (> 0: apart).
    """
    from scipy.spatial import cKDTree

    C = points2[tris2].mean(axis=1)
    tree = cKDTree(C)
    n_pts = len(X)
    ok = np.zeros(n_pts, dtype=bool)
    tri = np.zeros(n_pts, dtype=np.int64)
    bary = np.zeros((n_pts, 3))
    g0 = np.full(n_pts, np.inf)
    query = X.copy()
    for attempt in range(3):
        todo = np.where(~ok)[0]
        if todo.size == 0:
            break
        kk = min(k * (2 ** attempt), len(C))
        _, cand = tree.query(query[todo], k=kk)
        cand = cand.reshape(len(todo), -1)
        T = points2[tris2[cand]]                                   # (m, kk, 3, 3)
        t, b1, b2 = _ray_triangles(X[todo, None, :], normal[todo, None, :], T)
        eps = 1e-7
        inside = (b1 >= -eps) & (b2 >= -eps) & (b1 + b2 <= 1 + eps)
        score = np.where(inside, np.abs(t), np.inf)
        best = np.argmin(score, axis=1)
        rows = np.arange(len(todo))
        hit = np.isfinite(score[rows, best])
        i = todo[hit]
        ok[i] = True
        tri[i] = cand[rows, best][hit]
        bb1, bb2 = b1[rows, best][hit], b2[rows, best][hit]
        bary[i] = np.column_stack([1 - bb1 - bb2, bb1, bb2])
        g0[i] = -t[rows, best][hit]
        # next attempt: query near the intersection with the plane of the nearest triangle
        miss = todo[~hit]
        tm = t[rows, 0][~hit]
        query[miss] = X[miss] + np.clip(tm, -1e6, 1e6)[:, None] * normal[miss]
    return ok, tri, bary, g0


def _subdivided_rule(k: int) -> tuple[np.ndarray, np.ndarray]:
    """Quadrature on a triangle split into k x k similar triangles, 3 points (degree 2) in each:
    barycentric points (3 k², 3) and weights (sum 1).  The integrands of the weighted gap are
    piecewise smooth (kinks on the master triangles' edges): a composite rule, not a high order."""
    base = np.array([[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])
    pts = []
    for i in range(k):
        for j in range(k - i):
            up = np.array([[i, j], [i + 1, j], [i, j + 1]], dtype=float) / k
            pts.append(base @ up)
            if i + j < k - 1:
                down = np.array([[i + 1, j + 1], [i, j + 1], [i + 1, j]], dtype=float) / k
                pts.append(base @ down)
    ab = np.concatenate(pts)
    lam = np.column_stack([1.0 - ab.sum(axis=1), ab[:, 0], ab[:, 1]])
    return lam, np.full(len(lam), 1.0 / len(lam))


# ----------------------------------------------------------------------------- the solve
class ContactModel:
    """A prepared contact problem (:func:`prepare_contact`): meshes paired, stiffness matrices
    factorised; :meth:`solve` solves it at an approach or a normal force, as often as wanted,
    sharing the columns of the condensed flexibility W computed so far."""

    def __init__(self, run, stats: dict, fields=None):
        self._run = run
        self.stats = stats
        self._fields = fields

    def displacements(self, sol: FEContactSolution) -> tuple[np.ndarray, np.ndarray]:
        """Displacements (common frame, mm) of the mesh vertices of body 1 and body 2 under the
        contact pressure of ``sol`` (a solution of this model): K u = B^T (a lambda) on each body,
        one more solve with the factorised stiffness; body 2's include its rigid approach (and shift)
        ``sol.approach`` along the load direction.  Clamped far field only (the half-space field
        on the cut faces is not reconstructed here).  For studies of the bodies' structural
        deflection (the rail head's and the wheel rim's motion)."""
        if self._fields is None:
            raise InputError("displacements: not available for this model")
        return self._fields(sol)

    def solve(self, *, approach: float | None = None, normal_force: float | None = None,
              approach_guess: float = 0.0, shift_direction=None, shift_force: float | None = None
              ) -> FEContactSolution:
        """See :func:`solve_contact`.  With ``shift_direction`` e (a vector across the load
        direction d) and ``shift_force`` F_e (N), body 2 moves rigidly by delta d + s e and both
        forces are prescribed: sum a_j lambda_j (n_j . d) = normal_force and
        sum a_j lambda_j (n_j . e) = F_e (the second rigid motion s is one more unknown, its
        gap term -s (n . e) linearised as the approach's in (1)).  A wheel on a real rail has a
        lateral position relative to the rail head that depends on the structure (web bending,
        rim bending): prescribing the lateral force as well compares contacts at the same
        loads, not at the same position of distant points."""
        if (shift_force is None) != (shift_direction is None):
            raise InputError("shift_force and shift_direction: give both or neither")
        if shift_force is not None:
            if normal_force is None:
                raise InputError("shift_force: needs a prescribed normal_force")
            e = np.asarray(shift_direction, dtype=float)
            if e.shape != (3,) or not np.isfinite(e).all() or np.linalg.norm(e) == 0 or not math.isfinite(shift_force):
                raise InputError("shift_direction: need a finite non-zero 3-vector and a finite shift_force")
            return self._run(approach, normal_force, float(approach_guess), (e / np.linalg.norm(e), float(shift_force)))
        if (approach is None) == (normal_force is None):
            raise InputError("[load] normal_force: give exactly one of normal_force (N) or approach (mm)")
        if approach is not None and not math.isfinite(approach):
            raise InputError(f"[load] approach: must be finite, got {approach}")
        if normal_force is not None and not (normal_force > 0 and math.isfinite(normal_force)):
            raise InputError(f"[load] normal_force: must be > 0, got {normal_force}")
        return self._run(approach, normal_force, float(approach_guess), None)


def solve_contact(body1: ContactBody, body2: ContactBody, *, approach: float | None = None,
                  normal_force: float | None = None, direction=(0.0, 0.0, 1.0),
                  settings: FEContactSettings = FEContactSettings(), approach_guess: float = 0.0,
                  region=None) -> FEContactSolution:
    """Frictionless contact of two meshed elastic bodies at a prescribed approach or normal force.

    Parameters
    ----------
    body1, body2 : the bodies; body 1's free surface carries the slave nodes, the common normal
        points into body 1 (z down: body 1 below, body 2 above).
    approach, normal_force : exactly one: the rigid approach of body 2 along ``direction`` (mm),
        or the total contact force along ``direction``, sum lambda_i (n_i . d) (N).
    direction : unit load direction d in the common frame (body 2 moves along +d).
    approach_guess : starting approach for a prescribed force (mm).
    region : optional callable uv (n, 2) -> bool mask restricting the slave nodes (by their
        surface coordinates x, s on body 1).

    Returns
    -------
    FEContactSolution

    Examples
    --------
    A sphere of radius 50 mm pressed 0.08 mm into a block (Hertz: a = 2 mm, FN = 24296 N), on a
    very coarse linear mesh (a second; the default quadratic mesh is within 1 %):

    >>> from conformal.fe_contact.bodies import sphere_on_block
    >>> b1, b2 = sphere_on_block(50.0, (2.0, 2.0), n=2)
    >>> sol = solve_contact(b1, b2, approach=0.08, settings=FEContactSettings(order=1))
    >>> 0.95 < sol.FN / 24296.3 < 1.25
    True
    """
    if (approach is None) == (normal_force is None):
        raise InputError("[load] normal_force: give exactly one of normal_force (N) or approach (mm)")
    model = prepare_contact(body1, body2, direction=direction, settings=settings, region=region)
    return model.solve(approach=approach, normal_force=normal_force, approach_guess=approach_guess)


def prepare_contact(body1: ContactBody, body2: ContactBody, *, direction=(0.0, 0.0, 1.0),
                    settings: FEContactSettings = FEContactSettings(), region=None) -> ContactModel:
    """Pair the surfaces and factorise both bodies once (see :func:`solve_contact`)."""
    d = np.asarray(direction, dtype=float)
    if d.shape != (3,) or not np.isfinite(d).all() or np.linalg.norm(d) == 0:
        raise InputError("direction: need a finite non-zero 3-vector")
    d = d / np.linalg.norm(d)
    t0 = time.perf_counter()
    solver = direct_solver(settings.solver, "[model] fec_solver")

    # slave side: free-surface triangles of body 1 off the cut faces; quadrature points on them
    m1, m2 = body1.mesh, body2.mesh
    R1 = np.asarray(body1.rotation, float)
    P1, P2 = body1.points, body2.points
    tris = m1.free_tris
    tris = tris[~np.isin(tris, m1.clamped_nodes).any(axis=1)]
    if region is not None:
        tris = tris[region(m1.uv[tris].mean(axis=1))]
    if len(tris) == 0:
        raise FEContactError("no free surface of body 1 in the contact region")
    lamq, wq = _subdivided_rule(settings.subdivision)
    Xt = P1[tris]                                                         # (T, 3, 3)
    area_t = 0.5 * np.linalg.norm(np.cross(Xt[:, 1] - Xt[:, 0], Xt[:, 2] - Xt[:, 0]), axis=1)
    Xq = np.einsum("qk,tkd->tqd", lamq, Xt).reshape(-1, 3)
    uvq = np.einsum("qk,tkd->tqd", lamq, m1.uv[tris]).reshape(-1, 2)
    nq = surface_frame(m1.body, m1.extent, uvq[:, 0], uvq[:, 1])[:, 2, :] @ R1.T
    tq = np.repeat(np.arange(len(tris)), len(wq))                          # triangle of each point
    phi = np.tile(lamq, (len(tris), 1))                                   # (Q, 3) slave shape functions
    wts = (area_t[:, None] * wq[None, :]).ravel()
    tris2 = m2.free_tris
    ok, mtri, bary, g0q = pair_surfaces(Xq, nq, P2, tris2)
    reach = 0.25 * min(m1.extent.depth, m2.extent.depth)
    ok &= np.abs(g0q) < reach
    # the surfaces must face each other: body 2's outer normal at the paired point within 30
    # degrees of n (a line along a steep normal may cross body 2's surface elsewhere, e.g. a
    # flange flank beside a gauge face)
    uv2 = np.einsum("qk,qkd->qd", bary[ok], m2.uv[tris2[mtri[ok]]])
    n2 = surface_frame(m2.body, m2.extent, uv2[:, 0], uv2[:, 1])[:, 2, :] @ np.asarray(body2.rotation, float).T
    ok[np.where(ok)[0][np.einsum("qd,qd->q", n2, nq[ok]) < math.cos(math.radians(30.0))]] = False
    # the undeformed gap from the exact surfaces, not the flat facets: a facet of size h on a
    # surface of radius R lies up to h²/(8 R) inside it (13 µm for 1.3 mm on a 15 mm flange root,
    # as much as the whole overlap of a conformal contact); the points keep their (x, s)
    uv2 = np.einsum("qk,qkd->qd", bary, np.nan_to_num(m2.uv[tris2[mtri]]))
    X1e = np.asarray(body1.origin, float) + surface_point(m1.body, m1.extent, uvq[:, 0], uvq[:, 1]) @ R1.T
    X2e = (np.asarray(body2.origin, float)
           + surface_point(m2.body, m2.extent, uv2[:, 0], uv2[:, 1]) @ np.asarray(body2.rotation, float).T)
    g0q = np.where(ok, np.einsum("qd,qd->q", X1e - X2e, nq), g0q)
    # whole triangles only: on a partly paired triangle int psi_i (psi_i = 4 phi_i - 1 changes
    # sign) may vanish, and the node's weighted gap and pressure with it
    ok = np.repeat(ok.reshape(len(tris), -1).all(axis=1), len(wq))
    if not ok.any():
        raise FEContactError("no point of body 1's surface faces the surface of body 2 (check the placement)")
    Xq, nq, tq, phi, wts, mtri, bary, g0q = Xq[ok], nq[ok], tq[ok], phi[ok], wts[ok], mtri[ok], bary[ok], g0q[ok]
    # slave nodes (rows): the vertices of triangles with paired points
    nodes, inv = np.unique(tris[tq], return_inverse=True)
    rowq = inv.reshape(-1, 3)                                              # (Q, 3) row of each vertex
    n_c = len(nodes)
    # weighted (mortar) quantities: a_i = int phi_i, g0_i = int phi_i g0 / a_i, w_i = int phi_i n.d / a_i
    # dual (biorthogonal) test functions psi_i = 4 phi_i - 1 on each slave triangle (Wohlmuth 2000):
    # int psi_i phi_j = delta_ij int phi_j, so the slave side is diagonal and lambda_i a nodal pressure
    wphi = (4.0 * phi - 1.0) * wts[:, None] if settings.multiplier == "dual" else phi * wts[:, None]
    area = np.bincount(rowq.ravel(), weights=wphi.ravel(), minlength=n_c)
    g0 = np.bincount(rowq.ravel(), weights=(wphi * g0q[:, None]).ravel(), minlength=n_c) / area
    w = np.bincount(rowq.ravel(), weights=(wphi * (nq @ d)[:, None]).ravel(), minlength=n_c) / area
    # the normal of node i as the force sees it: N_i = int psi_i n dA / a_i (total force on body 1:
    # sum lambda_i a_i N_i); unit_n its direction (the half-space field's axis)
    normal = np.column_stack([np.bincount(rowq.ravel(), weights=(wphi * nq[:, k][:, None]).ravel(), minlength=n_c)
                              for k in range(3)]) / area[:, None]
    unit_n = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    X = P1[nodes]
    uv = m1.uv[nodes]
    X2 = X - g0[:, None] * unit_n
    inside = np.isin(tris, nodes).all(axis=1)
    loc_tris = np.searchsorted(nodes, tris[inside])
    loc_area = area_t[inside]
    t_pair = time.perf_counter()

    f1 = _fe_body(body1, solver, settings.max_dofs, settings.order)
    f2 = _fe_body(body2, solver, settings.max_dofs, settings.order)
    t_fac = time.perf_counter()
    # weighted gap per unit area: (B u)_i = int psi_i n . (u1 - u2(pi(x))) dA / a_i; the contact
    # pressure p = sum lambda_i psi_i acts on body 1 as B^T (a lambda), on body 2 with the sign reversed
    Q = len(wts)
    wn = wphi / area[rowq]                                                # (Q, 3)

    def coupling(fb: _FEBody, tri_nodes: np.ndarray, lam_pts: np.ndarray, sign: float) -> sp.csr_matrix:
        # the trace at the points (Q, n_scalar), its normal component per dof, tested with wn
        T = trace_matrix(fb.space, tri_nodes, lam_pts)
        R = sp.csr_matrix((sign * wn.ravel(), (rowq.ravel(), np.repeat(np.arange(Q), 3))), shape=(n_c, Q))
        return sp.hstack([R @ sp.diags(nq[:, c]) @ T for c in range(3)]).tocsr()[:, np.argsort(fb.dofmap.ravel())]

    B1 = coupling(f1, tris[tq], phi, 1.0)
    B2 = coupling(f2, tris2[mtri], bary, -1.0)
    halfspace = settings.far_field == "halfspace"
    XD1, XD2 = f1.X_scalar[f1.D_scalar], f2.X_scalar[f2.D_scalar]

    W = np.zeros((n_c, 0))
    col_of = -np.ones(n_c, dtype=np.int64)            # column of W for slave node j (or -1)

    def body_columns(fb: _FEBody, Bm: sp.csr_matrix, J: np.ndarray, XD: np.ndarray, src: np.ndarray, e: np.ndarray):
        # unit multiplier lambda_j: the load a_j B^T e_j (total force about a_j along the normal)
        rhs = (Bm[J].T.tocsr()[fb.free] @ sp.diags(area[J])).toarray()
        U = np.zeros((fb.ndofs, len(J)))
        if halfspace:
            # boundary data: the half-space field of the force a_j along the inner normal e_j
            uD = boussinesq(XD[:, None, :] - src[None, :, :], e[None, :, :], fb.G, fb.nu) * area[J][None, :, None]
            UD = np.zeros((fb.ndofs, len(J)))
            for c in range(3):
                UD[fb.dofmap[c, fb.D_scalar]] = uD[:, :, c]
            rhs -= fb.K_fD @ UD[fb.D]
            U[fb.D] = UD[fb.D]
        U[fb.free] = fb.factor.solve(rhs)
        return Bm @ U

    def ensure(J: np.ndarray) -> None:
        nonlocal W
        new = J[col_of[J] < 0]
        for k in range(0, len(new), settings.block):
            Jb = new[k:k + settings.block]
            cols = (body_columns(f1, B1, Jb, XD1, X[Jb], unit_n[Jb])
                    + body_columns(f2, B2, Jb, XD2, X2[Jb], -unit_n[Jb]))
            col_of[Jb] = W.shape[1] + np.arange(len(Jb))
            W = np.concatenate([W, cols], axis=1)

    prep = {"pairing_s": t_pair - t0, "factor_s": t_fac - t_pair, "dofs_body1": int(f1.ndofs),
            "dofs_body2": int(f2.ndofs), "slave_nodes": int(n_c), "quadrature_points": int(Q), "solver": solver,
            "far_field": settings.far_field}

    def run(approach, normal_force, approach_guess, lateral):
        t_start = time.perf_counter()
        prescribed_force = normal_force is not None
        if lateral is not None:      # the second rigid motion: v_i = int psi_i n.e dA / a_i
            e_sh, f_sh = lateral
            v = np.bincount(rowq.ravel(), weights=(wphi * (nq @ e_sh)[:, None]).ravel(), minlength=n_c) / area
        shift = 0.0
        delta = float(approach_guess if prescribed_force else approach)
        g_rigid = g0 - delta * w
        if g_rigid.min() >= 0:
            if not prescribed_force:
                raise NoContactError(f"the bodies do not touch at approach {delta:g} mm (smallest gap "
                                     f"{g_rigid.min():.4g} mm)")
            pos = w > 0.1
            delta = float(np.min(g0[pos] / w[pos])) + 1e-6 * float(np.ptp(g0) + 1e-9)
            g_rigid = g0 - delta * w
        A = g_rigid < 0.5 * g_rigid.min()                  # Hertz: the contact is where g0 < delta / 2
        scale = max(float(np.abs(g_rigid).max()), 1e-12)
        tol = 1e-10 * scale
        def solve_set(Aidx):
            ensure(Aidx)
            WA = W[:, col_of[Aidx]]                        # (n_c, |A|)
            lam = np.zeros(n_c)
            dl = delta
            ds = 0.0
            if lateral is not None:
                k = Aidx.size
                M = np.zeros((k + 2, k + 2))
                M[:k, :k] = WA[Aidx]
                M[:k, k], M[:k, k + 1] = -w[Aidx], -v[Aidx]
                M[k, :k], M[k + 1, :k] = (area * w)[Aidx], (area * v)[Aidx]
                sol = np.linalg.solve(M, np.concatenate([-g0[Aidx], [normal_force, f_sh]]))
                lam[Aidx], dl, ds = sol[:k], float(sol[k]), float(sol[k + 1])
                return lam, dl, ds, g0 - dl * w - ds * v + WA @ lam[Aidx]
            if prescribed_force:
                M = np.zeros((Aidx.size + 1, Aidx.size + 1))
                M[:-1, :-1] = WA[Aidx]
                M[:-1, -1] = -w[Aidx]
                M[-1, :-1] = (area * w)[Aidx]
                sol = np.linalg.solve(M, np.concatenate([-g0[Aidx], [normal_force]]))
                lam[Aidx], dl = sol[:-1], float(sol[-1])
            else:
                lam[Aidx] = np.linalg.solve(WA[Aidx], -(g0 - dl * w)[Aidx])
            return lam, dl, ds, g0 - dl * w + WA @ lam[Aidx]

        # primal-dual active set (semismooth Newton): all changes at once; if a set comes back
        # (cycling, possible where W is not an M-matrix), one change per step: drop the most
        # negative force, else add the most penetrating node (a Lawson-Hanson-like active set)
        seen: set = set()
        single = False
        for it in range(1, settings.max_iter * max(1, n_c // 10) + 1):
            Aidx = np.where(A)[0]
            if Aidx.size == 0:
                raise NoContactError("the active set became empty (no contact)")
            lam, delta, shift, gap = solve_set(Aidx)
            neg = A & (lam <= 0.0)
            pen = ~A & (gap < -tol)
            if not neg.any() and not pen.any():
                break
            if not single:
                key = A.tobytes()
                if key in seen or it >= settings.max_iter:
                    single = True
                seen.add(key)
            if single:
                A = A.copy()
                if neg.any():
                    A[np.argmin(np.where(neg, lam, np.inf))] = False
                else:
                    A[np.argmin(np.where(pen, gap, np.inf))] = True
            else:
                A = np.where(A, lam > 0.0, gap < -tol)
        else:
            raise ConvergenceError(f"FE contact: the active set did not settle in {it} iterations "
                                   f"({int(A.sum())} active nodes)")
        t_end = time.perf_counter()
        stats = dict(prep, active_set_s=t_end - t_start, columns=int(W.shape[1]),
                     total_s=prep["pairing_s"] + prep["factor_s"] + t_end - t_start)
        return FEContactSolution(nodes=nodes, X=X, normal=normal, uv=uv, g0=g0, force=lam * area, area=area, gap=gap,
                                 active=A.copy(), approach=delta, direction=d, iterations=it,
                                 n_unknowns=int(f1.ndofs + f2.ndofs), stats=stats, tris=loc_tris, tri_area=loc_area,
                                 shift=shift, shift_direction=(np.zeros(3) if lateral is None else e_sh))

    def fields(sol: FEContactSolution):
        if halfspace:
            raise InputError("displacements: only with the clamped far field (fec_far_field = \"clamped\")")
        out = []
        for fb, Bm in ((f1, B1), (f2, B2)):
            rhs = np.asarray(Bm.T @ sol.force).ravel()
            U = np.zeros(fb.ndofs)
            U[fb.free] = fb.factor.solve(rhs[fb.free][:, None])[:, 0]
            out.append(U[fb.dofmap[:, :len(fb.points)]].T)
        return out[0], out[1] + sol.approach * sol.direction[None, :] + sol.shift * sol.shift_direction[None, :]

    return ContactModel(run, prep, fields)
