"""The shared FE toolkit (conformal.influence.fe_toolkit) on a small structured block, against exact
answers: a constant pressure on a face integrates to pressure x area, probes of linear fields are
exact (values and gradients), a uniaxial-stress patch test, the clamped dofs of a face."""
from __future__ import annotations

import numpy as np
import pytest

from conformal.influence.fe_toolkit import (CENTROID, clamped_dofs, facet_indices, facet_quadrature, hooke,
                                            locate_cells, probes, stiffness, trace_matrix, traction_load,
                                            vector_space)
from conformal.materials import lame_lambda

G, NU = 80000.0, 0.3
L = np.array([2.0, 1.0, 1.5])          # block size (mm)


def _block(n=(3, 2, 2)):
    """A box [0, Lx] x [0, Ly] x [0, Lz] in Kuhn tetrahedra (6 per cube, slightly skewed nodes inside)
    and its boundary triangles by face (face name -> (F, 3) vertex indices)."""
    nx, ny, nz = n
    g = np.stack(np.meshgrid(*[np.linspace(0, L[i], n[i] + 1) for i in range(3)], indexing="ij"), axis=-1)
    inner = np.zeros(g.shape[:3], bool)
    inner[1:-1, 1:-1, 1:-1] = True
    g[inner] += 0.05 * np.array([1.0, -0.7, 0.4])          # keep the faces plane, the inside irregular
    pts = g.reshape(-1, 3)
    idx = np.arange(pts.shape[0]).reshape(nx + 1, ny + 1, nz + 1)
    tets = []
    paths = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                for p in paths:
                    c = np.array([i, j, k])
                    v = [idx[tuple(c)]]
                    for ax in p:
                        c = c.copy()
                        c[ax] += 1
                        v.append(idx[tuple(c)])
                    tets.append(v)
    tets = np.array(tets)
    from skfem import MeshTet

    m = MeshTet(pts.T.copy(), tets.T.copy())
    bf = m.boundary_facets()
    tri = m.facets[:, bf].T
    X = pts[tri].mean(axis=1)
    faces = {"x0": np.isclose(X[:, 0], 0), "x1": np.isclose(X[:, 0], L[0]), "z1": np.isclose(X[:, 2], L[2])}
    return pts, tets, {k: tri[v] for k, v in faces.items()}


@pytest.mark.parametrize("order", [1, 2])
def test_constant_pressure_on_a_face_integrates_to_pressure_times_area(order):
    """F = int_S -p n . v dA: the load vector sums (per component) to -p n |S| exactly, by the
    LinearForm of traction_load and by the quadrature's load operator alike (P2: the vertex loads
    of a constant traction are zero, the mid-side ones carry all of it)."""
    pts, tets, faces = _block()
    m, space = vector_space(pts, tets, order)
    f = facet_indices(m, faces["z1"])
    p = 3.5
    F = traction_load(space, m, f, lambda x, n: -p * n)
    area = L[0] * L[1]
    total = space.components(F).sum(axis=1)
    np.testing.assert_allclose(total, [0.0, 0.0, -p * area], rtol=0, atol=1e-12 * p * area)
    q = facet_quadrature(space, m, f, intorder=4)
    np.testing.assert_allclose(q.weights.sum(), area, rtol=1e-13)
    np.testing.assert_allclose(q.normals, np.tile([0.0, 0.0, 1.0], (len(q.weights), 1)), atol=1e-13)
    Fz = q.load @ np.full(len(q.weights), -p)                    # z component through the operator
    np.testing.assert_allclose(Fz, space.components(F)[2], rtol=0, atol=1e-13 * p * area)
    if order == 2:
        assert np.abs(Fz[:space.nverts]).max() < 1e-12 * p * area
    # the centroid rule integrates the constant exactly as well
    q1 = facet_quadrature(space, m, f, quadrature=CENTROID)
    assert q1.per_facet == 1 and q1.weights.sum() == pytest.approx(area, rel=1e-13)


@pytest.mark.parametrize("order", [1, 2])
def test_probes_and_traces_of_a_linear_field_are_exact(order):
    """A linear displacement u = A x + b is in both spaces: its probes at interior points and at
    points on the faces (and just outside them, located to the nearest tetrahedron) equal u, its
    gradient probes equal A; the facet trace at the quadrature points equals u there."""
    pts, tets, faces = _block()
    m, space = vector_space(pts, tets, order)
    A = np.array([[1.0, 0.2, -0.3], [0.4, -1.1, 0.5], [0.0, 0.7, 0.9]]) * 1e-3
    b = np.array([0.01, -0.02, 0.03])
    X = space.basis.doflocs[:, space.dofmap[0]].T
    U = space.from_components((X @ A.T + b).T)
    rng = np.random.default_rng(5)
    P = np.vstack([rng.random((40, 3)) * L, [[0.0, 0.3, 0.4], [L[0], 0.5, 1.0], [1.0, 0.5, L[2] + 1e-9]]])
    vals = (probes(space.basis, P) @ U).reshape(3, -1).T
    np.testing.assert_allclose(vals, P @ A.T + b, rtol=0, atol=1e-14)
    grads = (probes(space.basis, P, gradient=True) @ U).reshape(3, 3, -1).transpose(2, 0, 1)
    np.testing.assert_allclose(grads, np.broadcast_to(A, grads.shape), rtol=0, atol=1e-13)
    cells = locate_cells(m, P[:40])
    V = pts[tets[cells]]                                       # the located tetrahedra contain the points
    lam = np.linalg.solve(np.transpose(V[:, 1:] - V[:, :1], (0, 2, 1)), (P[:40] - V[:, 0])[..., None])[..., 0]
    assert (lam.min(axis=1) > -1e-12).all() and (lam.sum(axis=1) < 1 + 1e-12).all()
    q = facet_quadrature(space, m, facet_indices(m, faces["x1"]), intorder=4)
    T = trace_matrix(space, np.repeat(q.tris, q.per_facet, axis=0), q.bary)
    np.testing.assert_allclose((T @ space.components(U).T), q.points @ A.T + b, rtol=0, atol=1e-14)


def test_uniaxial_stress_patch_test():
    """x = 0 held in x only (one point fixed, one more held in y, z against rigid motion), x = Lx
    pulled by a traction s: the FE solution is the uniaxial stress state sigma_xx = s, eps_xx =
    s / E, eps_yy = eps_zz = -nu s / E, exactly (linear field), with E = 2 G (1 + nu)."""
    import scipy.sparse.linalg as spla

    pts, tets, faces = _block()
    m, space = vector_space(pts, tets, 1)
    K = stiffness(space, G, NU)
    s = 120.0
    F = traction_load(space, m, facet_indices(m, faces["x1"]), lambda x, n: s * n)
    nodes, _ = clamped_dofs(space, faces["x0"])
    o = int(np.argmin(np.linalg.norm(pts, axis=1)))                       # the corner at the origin
    y1 = int(np.argmin(np.linalg.norm(pts - [0.0, L[1], 0.0], axis=1)))    # corner (0, Ly, 0)
    D = np.unique(np.concatenate([space.dofmap[0, nodes], space.dofmap[:, o], space.dofmap[2, [y1]]]))
    free = np.setdiff1d(np.arange(space.basis.N), D)
    U = np.zeros(space.basis.N)
    U[free] = spla.spsolve(K[free][:, free].tocsc(), F[free])
    E = 2 * G * (1 + NU)
    eps = np.diag([s / E, -NU * s / E, -NU * s / E])
    X = pts
    np.testing.assert_allclose(space.components(U).T, X @ eps.T, rtol=0, atol=1e-12 * s / E * L.max())
    P = np.random.default_rng(1).random((10, 3)) * L
    g = (probes(space.basis, P, gradient=True) @ U).reshape(3, 3, -1).transpose(2, 0, 1)
    sig = hooke(0.5 * (g + np.swapaxes(g, 1, 2)), G, NU)
    np.testing.assert_allclose(sig, np.broadcast_to(np.diag([s, 0.0, 0.0]), sig.shape), rtol=0, atol=1e-9 * s)
    # the stiffness uses materials.lame_lambda: u = e x has sigma : eps = 3 (3 lambda + 2 G) e^2 = u^T K u / V
    e = 1e-3
    Ud = space.from_components((X * e).T)
    V = np.prod(L)
    assert Ud @ K @ Ud == pytest.approx(3 * (3 * lame_lambda(G, NU) + 2 * G) * e * e * V, rel=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_clamped_dofs_of_a_face(order):
    """All three components of every vertex (and, P2, mid-side node) of the face x = 0."""
    pts, tets, faces = _block()
    m, space = vector_space(pts, tets, order)
    nodes, D = clamped_dofs(space, faces["x0"])
    X = space.basis.doflocs[:, space.dofmap[0]].T
    assert set(nodes) == set(np.flatnonzero(np.isclose(X[:, 0], 0.0)))
    assert D.size == 3 * nodes.size and np.array_equal(D, np.unique(space.dofmap[:, nodes]))


def test_surface_triangles_that_are_no_facets_keep_their_rule():
    """A surface mesh whose quads take the other diagonal than the tetrahedra (gmsh did this at the
    centre of a crowned wheel's patch): surface_quadrature maps the same rule onto those
    triangles, with outward normals; a constant pressure still integrates to pressure x area and
    the points agree with the facets' rule where the triangles are facets.  P2 refuses them (their
    edges have no dofs)."""
    from conformal.influence.factor import FESolveError
    from conformal.influence.fe_toolkit import surface_quadrature

    pts, tets, faces = _block()
    m, space = vector_space(pts, tets, 1)
    tris = faces["z1"]
    # each facet of the face z = Lz and its partner across the quad's diagonal: the other diagonal
    X = pts[tris]
    quads = {}
    for t, c in zip(tris, X.mean(axis=1)):
        quads.setdefault(tuple(np.floor(c[:2] / (L[:2] / np.array([3, 2]))).astype(int)), []).append(t)
    flipped = []
    for pair in quads.values():
        v = np.unique(np.concatenate(pair))
        d = [a for a in pair[0] if a in pair[1]]                    # the shared diagonal
        o = [a for a in v if a not in d]                            # the other diagonal
        flipped += [[o[0], o[1], d[0]], [o[0], o[1], d[1]]]
    flipped = np.array(flipped)
    assert (facet_indices(m, flipped, strict=False) < 0).all()
    mixed = np.vstack([tris[:3], flipped])
    q = surface_quadrature(space, m, mixed, intorder=4)
    X3 = pts[tris[:3]]
    area = L[0] * L[1] + 0.5 * np.linalg.norm(np.cross(X3[:, 1] - X3[:, 0], X3[:, 2] - X3[:, 0]), axis=1).sum()
    assert q.weights.sum() == pytest.approx(area, rel=1e-13)
    np.testing.assert_allclose(q.normals, np.tile([0.0, 0.0, 1.0], (len(q.weights), 1)), atol=1e-13)
    assert np.abs(q.load @ np.ones(len(q.weights))).sum() == pytest.approx(area, rel=1e-13)
    np.testing.assert_allclose(q.points[:, 2], L[2], atol=1e-13)
    ref = facet_quadrature(space, m, facet_indices(m, tris[:3]), intorder=4)
    np.testing.assert_allclose(q.points[:ref.points.shape[0]], ref.points, atol=1e-14)
    _, space2 = vector_space(pts, tets, 2)
    with pytest.raises(FESolveError, match="edge not found"):
        surface_quadrature(space2, m, flipped, intorder=4)
