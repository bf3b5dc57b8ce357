"""The finite-element pieces shared by the FE influence numbers (:mod:`conformal.influence.fe`),
the direct FE contact solve (:mod:`conformal.fe_contact.solver`) and the stresses in the FE
bodies (:mod:`conformal.stresses.bodies`), on scikit-fem's own bases.

- :func:`vector_space`: the P1/P2 vector space of a tetrahedral body (``skfem.Basis`` with
  ``ElementVector``), with the numbering of its scalar nodes (vertices, then edges) that the
  surface traces use (:meth:`VectorSpace.scalar_nodes`, :func:`trace_shape`, :func:`trace_matrix`).
- :func:`stiffness`: the linear-elasticity matrix (``skfem.models.elasticity.linear_elasticity``)
  with Lamé's constants from :mod:`conformal.materials`; :func:`hooke` the stress of a strain.
- :func:`clamped_dofs`: the Dirichlet dofs of the clamped faces.
- :func:`facet_quadrature`: quadrature on a set of surface triangles through ``skfem.FacetBasis``
  (``facets=``), with its load operator (values at the quadrature points -> load vector, for many
  right-hand sides at once); :func:`traction_load`: the load vector of one traction field, a
  ``LinearForm`` on the same facet basis.
- :func:`probes`: values or gradients of a field at points (``Basis.probes`` with a point
  location, :func:`locate_cells`, that also takes points just outside the faceted surface).
- :func:`direct_solver`: the sparse direct solver behind ``"auto"``.

>>> import numpy as np
>>> pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
>>> m, space = vector_space(pts, np.array([[0, 1, 2, 3]]), 1)
>>> space.n_scalar, int(space.basis.N)
(4, 12)
>>> q = facet_quadrature(space, m, facet_indices(m, np.array([[0, 1, 2]])), intorder=2)
>>> round(float(q.weights.sum()), 12)     # the area of the facet z = 0
0.5
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from conformal.errors import InputError
from conformal.influence.factor import FESolveError, pardiso_available
from conformal.materials import lame_lambda


# ----------------------------------------------------------------------------- spaces
def trace_shape(lam: np.ndarray, order: int) -> np.ndarray:
    """Lagrange shape functions of a triangle (the trace of P1/P2 tetrahedra) at barycentric
    points ``lam`` (..., 3).  P2 order: vertices 0, 1, 2, then edges (0, 1), (1, 2), (0, 2)
    (the columns of :meth:`VectorSpace.scalar_nodes`).

    >>> trace_shape(np.array([[0.5, 0.5, 0.0]]), 2).round(12).tolist()
    [[0.0, 0.0, -0.0, 1.0, 0.0, 0.0]]
    """
    if order == 1:
        return lam
    l0, l1, l2 = lam[..., 0], lam[..., 1], lam[..., 2]
    return np.stack([l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1),
                     4 * l0 * l1, 4 * l1 * l2, 4 * l0 * l2], axis=-1)


@dataclass(frozen=True, eq=False)
class VectorSpace:
    """The P1/P2 vector space of a tetrahedral body and the numbering of its scalar nodes.

    Attributes
    ----------
    basis : skfem.CellBasis
        ``ElementVector`` of ``ElementTetP1`` / ``ElementTetP2``.
    dofmap : ndarray (3, n_scalar)
        The dof of component c at scalar node g (vertices, then edges for P2).
    n_scalar, nverts, order : int
        Scalar nodes, vertices, element order.
    edge_key, edge_id : ndarray
        Sorted keys lo * nverts + hi of the mesh edges and their edge numbers (P2).
    """

    basis: object
    dofmap: np.ndarray
    n_scalar: int
    edge_key: np.ndarray
    edge_id: np.ndarray
    nverts: int
    order: int

    def scalar_nodes(self, tris: np.ndarray, strict: bool = True) -> np.ndarray:
        """Scalar nodes of surface triangles (F, 3 or 6).  ``strict = False``: an edge that no
        tetrahedron has (gmsh's volume mesh took the other diagonal of a quad of the surface mesh,
        seen on a clamped face of a wheel body) gets -1 instead of raising FESolveError."""
        if self.order == 1:
            return tris
        n = self.nverts
        out = [tris]
        for a, b in ((0, 1), (1, 2), (0, 2)):
            lo, hi = np.minimum(tris[:, a], tris[:, b]), np.maximum(tris[:, a], tris[:, b])
            key = lo.astype(np.int64) * n + hi
            pos = np.searchsorted(self.edge_key, key)
            found = (pos < self.edge_key.size) & (self.edge_key[np.minimum(pos, self.edge_key.size - 1)] == key)
            if strict and not found.all():
                raise FESolveError("surface triangle edge not found in the tetrahedral mesh")
            pos = np.minimum(pos, self.edge_key.size - 1)
            out.append(np.where(found, self.nverts + self.edge_id[pos], -1)[:, None])
        return np.concatenate(out, axis=1)

    def components(self, values: np.ndarray) -> np.ndarray:
        """A vector field (N, ...) as its components at the scalar nodes (3, n_scalar, ...)."""
        return np.stack([values[self.dofmap[c]] for c in range(3)])

    def from_components(self, comps: np.ndarray) -> np.ndarray:
        """Components at the scalar nodes (3, n_scalar, ...) as a vector field (N, ...)."""
        out = np.zeros((self.basis.N,) + comps.shape[2:])
        for c in range(3):
            out[self.dofmap[c]] = comps[c]
        return out


def vector_space(points: np.ndarray, tets: np.ndarray, order: int) -> tuple[object, VectorSpace]:
    """The skfem mesh and the P1/P2 vector space of a tetrahedral body.

    Parameters
    ----------
    points : ndarray (n, 3)
        Vertices (mm).
    tets : ndarray (t, 4)
        Tetrahedra (vertex indices).
    order : int
        1 or 2; the volume quadrature has degree 2 for P2, 1 for P1 (exact for the stiffness of
        straight-sided elements).

    Returns
    -------
    mesh : skfem.MeshTet
    space : VectorSpace
    """
    from skfem import Basis, ElementTetP1, ElementTetP2, ElementVector, MeshTet

    m = MeshTet(np.asarray(points, float).T.copy(), np.asarray(tets).T.copy())
    elem = ElementTetP2() if order == 2 else ElementTetP1()
    basis = Basis(m, ElementVector(elem), intorder=2 if order == 2 else 1)
    nv = m.nvertices
    if order == 2:
        dofmap = np.concatenate([basis.nodal_dofs, basis.edge_dofs], axis=1)
        key = m.edges[0].astype(np.int64) * nv + m.edges[1]
        srt = np.argsort(key)
        edge_key, edge_id = key[srt], srt
    else:
        dofmap = basis.nodal_dofs
        edge_key = edge_id = np.zeros(0, dtype=np.int64)
    return m, VectorSpace(basis, dofmap, dofmap.shape[1], edge_key, edge_id, nv, order)


def scalar_positions(space: VectorSpace) -> np.ndarray:
    """(n_scalar, 3) positions of the scalar nodes (vertices, then edge midpoints for P2)."""
    return space.basis.doflocs[:, space.dofmap[0]].T


def trace_matrix(space: VectorSpace, tris: np.ndarray, lam: np.ndarray) -> sp.csr_matrix:
    """(M, n_scalar) matrix evaluating the trace of a scalar field at M points given by their
    triangles ``tris`` (M, 3) (surface triangles of the mesh) and barycentric coordinates ``lam``
    (M, 3) in them (the vertex order of ``tris``)."""
    phi = trace_shape(lam, space.order)
    nodes = space.scalar_nodes(tris)
    rows = np.repeat(np.arange(len(lam)), nodes.shape[1])
    return sp.csr_matrix((phi.ravel(), (rows, nodes.ravel())), shape=(len(lam), space.n_scalar))


# ----------------------------------------------------------------------------- elasticity
def stiffness(space: VectorSpace, G: float, nu: float) -> sp.csr_matrix:
    """The linear-elasticity stiffness matrix of an isotropic body (scikit-fem's
    ``linear_elasticity`` form, Lamé's lambda from :func:`conformal.materials.lame_lambda`).

    Parameters
    ----------
    space : VectorSpace
    G, nu : float
        Shear modulus (N/mm²) and Poisson's ratio.

    Returns
    -------
    scipy.sparse.csr_matrix (N, N)
    """
    from skfem import asm
    from skfem.models.elasticity import linear_elasticity

    return asm(linear_elasticity(lame_lambda(G, nu), G), space.basis).tocsr()


def hooke(eps: np.ndarray, G: float, nu: float) -> np.ndarray:
    """Stress sigma = 2 G eps + lambda tr(eps) I of strains ``eps`` (..., 3, 3) (N/mm²).

    >>> float(hooke(np.diag([1e-3, 0.0, 0.0]), 80000.0, 0.25)[1, 1])   # lambda eps_xx
    80.0
    """
    eps = np.asarray(eps, float)
    return 2.0 * G * eps + lame_lambda(G, nu) * np.trace(eps, axis1=-2, axis2=-1)[..., None, None] * np.eye(3)


def clamped_dofs(space: VectorSpace, tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The scalar nodes (sorted) and all dofs (sorted) of clamped surface triangles (vertex and,
    for P2, edge nodes).  P2: an edge of a clamped triangle that the volume mesh does not have
    carries no dof (the volume's own diagonal of that quad then keeps its mid-side dof free: on an
    artificial boundary far from the contact)."""
    if len(tris) == 0:
        raise FESolveError("the body has no clamped face")
    nodes = space.scalar_nodes(np.sort(tris, axis=1), strict=False)
    nodes = np.unique(nodes[nodes >= 0])
    return nodes, np.unique(space.dofmap[:, nodes].ravel())


# ----------------------------------------------------------------------------- facets
def facet_indices(mesh, tris: np.ndarray, strict: bool = True) -> np.ndarray:
    """Indices into ``mesh.facets`` (a ``MeshTet``) of surface triangles ``tris`` (F, 3), in their
    order; where a triangle is no facet of the tetrahedra: FESolveError, or -1 if not ``strict``."""
    nv = np.int64(mesh.nvertices)
    fac = np.sort(mesh.facets, axis=0).astype(np.int64)
    key = (fac[0] * nv + fac[1]) * nv + fac[2]
    srt = np.argsort(key)
    t = np.sort(np.asarray(tris), axis=1).astype(np.int64)
    want = (t[:, 0] * nv + t[:, 1]) * nv + t[:, 2]
    pos = np.minimum(np.searchsorted(key[srt], want), key.size - 1)
    found = key[srt][pos] == want
    if strict and not found.all():
        raise FESolveError("surface triangle not found among the facets of the tetrahedral mesh")
    return np.where(found, srt[pos], -1)


@dataclass(frozen=True, eq=False)
class FacetQuadrature:
    """Quadrature on surface facets (``skfem.FacetBasis`` of the scalar element), facet by facet;
    the points of facet f are f q ... f q + q - 1 (q points per facet).

    Attributes
    ----------
    basis : skfem.FacetBasis
        Scalar P1/P2 element, ``facets=`` the given facets.
    tris : ndarray (F, 3)
        Vertices of each facet (skfem's order; ``bary`` refers to it).
    points, bary, normals : ndarray (F q, 3)
        The quadrature points, their barycentric coordinates in their facet, the outward unit normals.
    weights : ndarray (F q,)
        The weights w_q A_f (A_f: the area of the facet, mm²).
    load : scipy.sparse.csc_matrix (n_scalar, F q)
        F_a = sum_q w_q phi_a(x_q) t(x_q): the load vector of values t at the points (columns
        sliced by facet for a subset).
    """

    basis: object
    tris: np.ndarray
    points: np.ndarray
    bary: np.ndarray
    normals: np.ndarray
    weights: np.ndarray
    load: sp.csc_matrix

    @property
    def per_facet(self) -> int:
        return self.basis.X.shape[1]


#: the one-point rule of the reference triangle: its centroid, weight = its area
CENTROID = (np.full((2, 1), 1.0 / 3.0), np.array([0.5]))


def facet_quadrature(space: VectorSpace, mesh, facets: np.ndarray, intorder: int | None = None,
                     quadrature: tuple | None = None) -> FacetQuadrature:
    """:class:`FacetQuadrature` on the facets ``facets`` (indices into ``mesh.facets``, e.g.
    :func:`facet_indices`; boundary facets) of the body of ``space``: skfem's rule of degree
    ``intorder`` (4: Dunavant's 6-point rule) or the rule ``quadrature`` = (points (2, q) and
    weights (q,) on the reference triangle, e.g. :data:`CENTROID`)."""
    from skfem import ElementTetP1, ElementTetP2, FacetBasis

    elem = ElementTetP2() if space.order == 2 else ElementTetP1()
    facets = np.asarray(facets)
    fb = FacetBasis(mesh, elem, intorder=intorder, quadrature=quadrature, facets=facets)
    F, q = len(facets), fb.X.shape[1]
    X = np.transpose(np.asarray(fb.global_coordinates()), (1, 2, 0)).reshape(F * q, 3)
    ref = fb.X                                           # (2, q) reference points of the facet
    bary = np.tile(np.column_stack([1.0 - ref.sum(axis=0), ref[0], ref[1]]), (F, 1))
    normals = np.transpose(np.asarray(fb.normals), (1, 2, 0)).reshape(F * q, 3)
    w = fb.dx.ravel()
    # rows: the scalar dofs of the facet's tetrahedron (those off the facet vanish on it: dropped)
    phi = np.stack([np.asarray(fb.basis[k][0]) for k in range(fb.Nbfun)])       # (nb, F, q)
    rows = np.broadcast_to(fb.element_dofs[:, :, None], phi.shape)
    cols = np.broadcast_to(np.arange(F * q).reshape(1, F, q), phi.shape)
    keep = np.abs(phi) > 1e-12
    load = sp.csc_matrix(((phi * fb.dx[None])[keep], (rows[keep], cols[keep])), shape=(space.n_scalar, F * q))
    return FacetQuadrature(fb, mesh.facets[:, facets].T.copy(), X, bary, normals, w, load)


def surface_quadrature(space: VectorSpace, mesh, tris: np.ndarray, intorder: int | None = None,
                       quadrature: tuple | None = None) -> FacetQuadrature:
    """:func:`facet_quadrature` on the surface triangles ``tris`` (F, 3) of a mesh, in their order.

    gmsh's volume mesh may take the other diagonal of a quad of its surface mesh (seen at the
    centre of a crowned wheel's patch): such a surface triangle is no facet of the tetrahedra.
    It keeps its own vertices (``tris``), its points and weights come from the same reference
    rule mapped onto it, its load rows from :func:`trace_shape` at them (P1: its vertices; P2:
    FESolveError, its edges have no dofs), its normal points away from the tetrahedra at its
    first vertex.  ``basis`` then holds only the triangles that are facets.
    """
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTri

    tris = np.asarray(tris)
    ref, W = quadrature if quadrature is not None else get_quadrature(RefTri, intorder)
    f = facet_indices(mesh, tris, strict=False)
    ok = f >= 0
    fq = facet_quadrature(space, mesh, f[ok], quadrature=(ref, W))
    if ok.all():
        return fq
    q = W.size
    bad = np.flatnonzero(~ok)
    tb = tris[bad]
    X = mesh.p.T[tb]                                              # (B, 3, 3)
    lam = np.column_stack([1.0 - ref.sum(axis=0), ref[0], ref[1]])   # (q, 3)
    nrm = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    area = 0.5 * np.linalg.norm(nrm, axis=1)
    nrm /= (2 * area)[:, None]
    for i, t in enumerate(tb):                                    # outward: away from the tetrahedra at vertex 0
        star = mesh.p[:, mesh.t[:, (mesh.t == t[0]).any(axis=0)]].mean(axis=(1, 2))
        if nrm[i] @ (X[i].mean(axis=0) - star) < 0:
            nrm[i] *= -1
    w_bad = (2.0 * area[:, None] * W[None, :]).ravel()
    nodes = space.scalar_nodes(tb)
    phi = trace_shape(lam, space.order)                           # (q, a)
    rows = np.repeat(nodes[:, None, :], q, axis=1).ravel()
    cols = np.repeat(np.arange(len(bad) * q), nodes.shape[1])
    vals = (phi[None, :, :] * w_bad.reshape(-1, q)[:, :, None]).ravel()
    load_bad = sp.csc_matrix((vals, (rows, cols)), shape=(space.n_scalar, len(bad) * q))
    pos_ok = (np.flatnonzero(ok)[:, None] * q + np.arange(q)).ravel()
    pos_bad = (bad[:, None] * q + np.arange(q)).ravel()
    order = np.argsort(np.concatenate([pos_ok, pos_bad]))         # merged column -> position
    n = len(tris) * q

    def merge(a_ok, a_bad):
        out = np.empty((n,) + a_ok.shape[1:])
        out[pos_ok], out[pos_bad] = a_ok, a_bad
        return out

    out_tris = tris.copy()
    out_tris[ok] = fq.tris
    return FacetQuadrature(fq.basis, out_tris,
                           merge(fq.points, np.einsum("qk,bkd->bqd", lam, X).reshape(-1, 3)),
                           merge(fq.bary, np.tile(lam, (len(bad), 1))),
                           merge(fq.normals, np.repeat(nrm, q, axis=0)),
                           merge(fq.weights, w_bad),
                           sp.hstack([fq.load, load_bad]).tocsc()[:, order])


def traction_load(space: VectorSpace, mesh, facets: np.ndarray, traction, intorder: int = 4) -> np.ndarray:
    """Load vector of a traction on surface facets: F = int_S t . v dA, a ``LinearForm`` on a
    vector ``FacetBasis``.

    Parameters
    ----------
    space : VectorSpace
    mesh : skfem.MeshTet
    facets : ndarray
        Indices into ``mesh.facets`` (:func:`facet_indices`).
    traction : callable
        t(x, n) of the global coordinates and the outward normals (each (3, ...)), returning
        (3, ...) (N/mm²), e.g. ``lambda x, n: -p * n`` for a pressure p.
    intorder : int
        Degree of the facet quadrature.

    Returns
    -------
    ndarray (N,)
        Nodal forces (N).
    """
    from skfem import ElementTetP1, ElementTetP2, ElementVector, FacetBasis, LinearForm, asm
    from skfem.helpers import dot

    elem = ElementVector(ElementTetP2() if space.order == 2 else ElementTetP1())
    fb = FacetBasis(mesh, elem, intorder=intorder, facets=np.asarray(facets))

    @LinearForm
    def form(v, w):
        return dot(traction(w.x, w.n), v)

    return asm(form, fb)


# ----------------------------------------------------------------------------- points
def locate_cells(mesh, X: np.ndarray, k: int = 16) -> np.ndarray:
    """The tetrahedron containing each point X (n, 3), or, for a point outside (a surface point
    just outside the faceted mesh of a convex surface), the candidate it is closest to containing
    (largest smallest barycentric coordinate) among the k with the nearest centroids.
    (``MeshTet.element_finder`` refuses points outside the mesh, after a search of every
    tetrahedron for every point of the batch.)"""
    from scipy.spatial import cKDTree

    X = np.asarray(X, float).reshape(-1, 3)
    V = mesh.p[:, mesh.t]                                       # (3, 4, T)
    cent = V.mean(axis=1).T
    k = min(k, cent.shape[0])
    _, cand = cKDTree(cent).query(X, k=k)
    cand = np.asarray(cand).reshape(len(X), k)
    V0 = V[:, 0, cand]                                          # (3, n, k)
    E = np.transpose(V[:, 1:, cand] - V0[:, None], (2, 3, 0, 1))  # (n, k, 3 coords, 3 edges)
    lam = np.linalg.solve(E, (X.T[:, :, None] - V0).transpose(1, 2, 0)[..., None])[..., 0]
    bary = np.concatenate([1.0 - lam.sum(axis=-1, keepdims=True), lam], axis=-1)
    best = np.argmax(bary.min(axis=-1), axis=1)
    return cand[np.arange(len(X)), best]


def probes(basis, X: np.ndarray, cells: np.ndarray | None = None, gradient: bool = False) -> sp.csr_matrix:
    """Sparse matrix evaluating a field at points: scikit-fem's ``Basis.probes``, with the cells
    from :func:`locate_cells` unless given, and optionally the gradient.

    Parameters
    ----------
    basis : skfem.CellBasis
        A scalar or vector basis.
    X : ndarray (n, 3)
        The points.
    cells : ndarray (n,), optional
        Their cells.
    gradient : bool
        The derivatives instead of the values.

    Returns
    -------
    scipy.sparse.csr_matrix
        Values: rows c n + i (component c at point i); gradients: rows (3 c + j) n + i
        (d u_c / d x_j at point i; a scalar field: rows j n + i).
    """
    X = np.asarray(X, float).reshape(-1, 3)
    n = len(X)
    if cells is None:
        cells = locate_cells(basis.mesh, X)
    ref = basis.mapping.invF(X.T[:, :, None], tind=cells)                # (3, n, 1)
    vals = []
    for k in range(basis.Nbfun):
        f = basis.elem.gbasis(basis.mapping, ref, k, tind=cells)[0]
        vals.append(np.asarray(f.grad if gradient else f).reshape(-1))      # (..., n, 1) -> comp-major
    vals = np.array(vals)                                               # (Nbfun, ncomp n)
    ncomp = vals.shape[1] // n
    rows = np.tile(np.arange(ncomp * n), basis.Nbfun)
    cols = basis.element_dofs[:, np.tile(cells, ncomp)].ravel()
    return sp.csr_matrix((vals.ravel(), (rows, cols)), shape=(ncomp * n, basis.N))


# ----------------------------------------------------------------------------- solver
def direct_solver(name: str, key: str = "[model] fe_solver") -> str:
    """The factorisation (:class:`conformal.influence.factor.Factor`) for a solver name: ``"auto"``
    is pypardiso where it is installed, else scipy's splu; ``"pardiso"`` or ``"amg"`` without the
    package is an InputError naming ``key``."""
    if name == "auto":
        return "pardiso" if pardiso_available() else "splu"
    if name == "pardiso" and not pardiso_available():
        raise InputError(f"{key}: pypardiso is not installed (pip install pypardiso), use \"splu\" or \"auto\"")
    if name == "amg":
        from conformal.influence.factor import amg_available

        if not amg_available():
            raise InputError(f"{key}: pyamg is not installed (pip install pyamg), use \"splu\"")
    return name
