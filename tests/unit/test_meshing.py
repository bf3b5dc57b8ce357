"""gmsh quasi-quarter-space bodies (conformal.meshing): geometry, conformity, errors."""
from __future__ import annotations

import math

import numpy as np
import pytest


from conformal.errors import InputError
from conformal.meshing import gmsh_body
from conformal.meshing.bodies import BodyModel, Profile2D, StripPatch, body_extent, flat_profile
from conformal.meshing.gmsh_body import MeshingError, MeshSpec, mesh_body, surface_frame, surface_point
from _paths import PROFILES

_trapz = getattr(np, "trapezoid", None) or np.trapz   # numpy < 2 has only trapz


def _tet_volume(m) -> np.ndarray:
    a, b, c, d = (m.points[m.tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def _tri_area(p, t) -> float:
    return 0.5 * np.linalg.norm(np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), axis=1).sum()


def _section(body: BodyModel, ext) -> np.ndarray:
    """Closed cross-section polygon (y, z): the profile from s_lo to s_hi (4001 points), then the
    artificial boundary (end cuts and the arc, 2048 segments) back to the start."""
    yz = body.profile.point(np.linspace(ext.s_lo, ext.s_hi, 4001))
    return np.vstack([yz, ext.closure(2048)])


def _area_centroid(poly: np.ndarray) -> tuple[float, np.ndarray]:
    """Area and centroid of a simple polygon (shoelace formula)."""
    y, z = poly[:, 0], poly[:, 1]
    y2, z2 = np.roll(y, -1), np.roll(z, -1)
    c = y * z2 - y2 * z
    A = 0.5 * c.sum()
    return abs(A), np.array([((y + y2) * c).sum(), ((z + z2) * c).sum()]) / (6 * A)


def _fine(prof: Profile2D, step: float = 0.05) -> Profile2D:
    """The same polyline sampled every ``step`` mm (corners kept), as measured profiles are."""
    s = np.unique(np.concatenate([np.arange(0.0, prof.length, step), prof.s]))
    yz = prof.point(s)
    return Profile2D(yz[:, 0], yz[:, 1], prof.name)


def _arc_h(m) -> float:
    """Element size on the artificial arc: the size field's largest element there."""
    return max(m.spec.h_max * m.extent.depth, m.spec.h_patch * m.stats["h_element"])


def _rail() -> BodyModel:
    yz = np.loadtxt(PROFILES / "uic60_head_r300w21_analytic.csv", delimiter=",")
    return BodyModel("rail", Profile2D.from_points(yz, "uic60"))


def test_block_geometry_and_conformity():
    body = BodyModel("block", flat_profile(-30, 30))
    patch = StripPatch.uniform(3, 1.0, 2, 1.0, 30.0)
    m = mesh_body(body, patch, MeshSpec(conform="all", body_size=1.0))
    ext = m.extent
    L, W = ext.x_hi - ext.x_lo, ext.s_hi - ext.s_lo
    R = ext.radius
    assert W == pytest.approx(2 * R) and ext.arc_mid[1] == pytest.approx(R)   # half-disc below the surface
    assert np.all(_tet_volume(m) > 0)
    # a half-cylinder: the faceted arc (chords of angle h / R) loses about (h / R)^2 / 6 of the area
    h = _arc_h(m)
    assert _tet_volume(m).sum() == pytest.approx(L * 0.5 * math.pi * R ** 2, rel=0.25 * (h / R) ** 2)
    assert _tet_volume(m).sum() < L * 0.5 * math.pi * R ** 2
    assert _tri_area(m.points, m.free_tris) == pytest.approx(L * W, rel=1e-12)
    assert np.allclose(m.points[np.unique(m.free_tris), 2], 0.0)
    # artificial boundary: the two x-end faces and the cylinder, nothing of the top surface inside
    cn = m.clamped_nodes
    p = m.points[cn]
    r = np.hypot(p[:, 1] - (-30 + 30.0), p[:, 2])
    on_cut = np.isclose(p[:, 0], ext.x_lo) | np.isclose(p[:, 0], ext.x_hi) | np.isclose(r, R, rtol=1e-6)
    assert on_cut.all()
    # conformity: every free triangle lies in one contact element of the observed patch or outside
    uv = m.uv[m.free_tris]                                   # (F, 3, 2)
    xe, se = patch.x_edges, patch.edges
    cen = uv.mean(axis=1)
    inside = (cen[:, 0] > xe[0]) & (cen[:, 0] < xe[-1]) & (cen[:, 1] > se[0]) & (cen[:, 1] < se[-1])
    kx = np.floor((cen[:, 0] - xe[0]) / patch.dx)
    ks = np.floor(cen[:, 1] - se[0])
    tol = 1e-9
    lo_x, hi_x = xe[0] + kx * patch.dx, xe[0] + (kx + 1) * patch.dx
    lo_s, hi_s = se[0] + ks, se[0] + ks + 1
    ok = ((uv[..., 0] >= lo_x[:, None] - tol) & (uv[..., 0] <= hi_x[:, None] + tol)
          & (uv[..., 1] >= lo_s[:, None] - tol) & (uv[..., 1] <= hi_s[:, None] + tol)).all(axis=1)
    assert ok[inside].all() and inside.sum() >= 2 * 5 * 2


def test_rail_body_volume_and_surface():
    rail = _rail()
    s0 = float(rail.profile.project(np.array([0.0, 0.0])))
    patch = StripPatch.uniform(3, 1.0, 3, 1.0, s0)
    m = mesh_body(rail, patch, MeshSpec(body_size=1.0))
    ext = m.extent
    area, _ = _area_centroid(_section(rail, ext))
    L = ext.x_hi - ext.x_lo
    # faceted arc: chords of angle h / R lose about (h / R)^2 / 6 of the area
    h = _arc_h(m)
    assert _tet_volume(m).sum() == pytest.approx(area * L, rel=0.25 * (h / ext.radius) ** 2)
    assert _tet_volume(m).sum() < area * L
    assert _tri_area(m.points, m.free_tris) == pytest.approx((ext.s_hi - ext.s_lo) * L, rel=2e-4)
    # frame: n points into the rail (down at the crown), right-handed (x, s, n)
    F = surface_frame(rail, ext, 0.0, s0)
    assert np.allclose(F[2], [0, 0, 1], atol=1e-3) and np.allclose(np.cross(F[0], F[1]), F[2])


def test_wheel_sector_volume_and_meshio(tmp_path):
    yz = np.loadtxt(PROFILES / "s1002_analytic.csv", delimiter=",")
    wheel = BodyModel("wheel", Profile2D.from_points(yz, "s1002"), axle_z=-460.0)
    s0 = float(wheel.profile.project(np.array([0.0, 0.0])))
    patch = StripPatch.uniform(3, 1.0, 3, 1.0, s0)
    m = mesh_body(wheel, patch, MeshSpec(body_size=1.0))
    ext = m.extent
    area, cen = _area_centroid(_section(wheel, ext))
    theta = ext.theta_hi - ext.theta_lo
    vol = theta * area * (cen[1] - wheel.axle_z)                      # Pappus: ring sector
    h = _arc_h(m)
    assert _tet_volume(m).sum() == pytest.approx(vol, rel=0.25 * (h / ext.radius) ** 2)
    # the surface point at (x, s) lies on the mesh's free surface nodes' surface; n points out of the wheel
    P = surface_point(wheel, ext, 0.0, s0)
    assert P[2] == pytest.approx(float(wheel.profile.point(s0)[1]))
    F = surface_frame(wheel, ext, 2.0, s0)
    c = surface_point(wheel, ext, 2.0, s0) - np.array([0.0, P[1], wheel.axle_z])
    assert np.dot(F[2], c) > 0.99 * np.linalg.norm(c)      # outward = radial at the tread
    path = tmp_path / "wheel.vtu"
    m.write(path)
    import meshio

    back = meshio.read(path)
    assert len(back.points) == m.n_nodes and back.cells_dict["tetra"].shape == m.tets.shape


def test_body_extent_and_bad_input():
    rail = _rail()
    with pytest.raises(InputError, match="too short for the requested patch"):
        body_extent(rail, StripPatch.uniform(3, 1.0, 10, 1.0, 2.0), 1.0)
    # a profile that turns back (not a graph over y) within the body is meshed like any other:
    # the patch sits on the segment from (20, 0) back to (15, 10)
    y = np.array([0.0, 10.0, 20.0, 15.0, 30.0, 40.0])
    z = np.array([0.0, 0.0, 0.0, 10.0, 10.0, 10.0])
    folded = BodyModel("rail", Profile2D(y, z))
    patch = StripPatch.uniform(2, 1.0, 2, 1.0, 25.0)
    m = mesh_body(folded, patch, MeshSpec(body_size=1.0))
    ext = m.extent
    assert not (ext.cut_lo or ext.cut_hi)
    assert _tri_area(m.points, m.free_tris) == pytest.approx((ext.x_hi - ext.x_lo) * (ext.s_hi - ext.s_lo), rel=1e-9)
    # a profile ending inside the disc: a straight cut along the inward normal closes the section
    short = body_extent(BodyModel("block", flat_profile(-3, 20)), StripPatch.uniform(2, 1.0, 2, 1.0, 3.0), 2.0)
    assert short.s_lo == 0.0 and short.cut_lo and not short.cut_hi
    assert short.q_lo[0] == pytest.approx(-3.0) and short.q_lo[1] == pytest.approx(4.0)   # |q - c| = R = 5
    # a profile end just inside the disc: the disc shrinks to it instead of a sliver cut
    near = body_extent(BodyModel("block", flat_profile(-4.5, 20)), StripPatch.uniform(2, 1.0, 2, 1.0, 4.5), 2.0)
    assert near.radius == pytest.approx(4.5) and not near.cut_lo
    # a profile hooking back under the running surface: a cut from its end along the inward normal
    # would cross the running surface, and one that does not would run nearly along it; the disc
    # shrinks to the hook's end (0.9 mm from the patch centre) and leaves the hook out
    hook = BodyModel("rail", _fine(Profile2D(np.array([0.0, -1.0, -1.0, 5.0, 20.0]), np.array([0.9, 0.9, 0.0, 0.0, 0.0]))))
    m = mesh_body(hook, StripPatch.uniform(1, 0.5, 2, 0.5, 2.9), MeshSpec(body_size=1.0, h_patch=1.0))
    ext = m.extent
    assert ext.radius == pytest.approx(0.9) and not (ext.cut_lo or ext.cut_hi)
    L = ext.x_hi - ext.x_lo
    assert _tri_area(m.points, m.free_tris) == pytest.approx(L * (ext.s_hi - ext.s_lo), rel=1e-9)
    area, _ = _area_centroid(_section(hook, ext))
    assert _tet_volume(m).sum() == pytest.approx(area * L, rel=0.25 * (_arc_h(m) / ext.radius) ** 2)
    # a gauge face turning past vertical (an undercut running back under the head): part of the
    # body's surface, meshed along its arc length
    under = _fine(Profile2D(np.array([-3.0, -5.0, 20.0]), np.array([6.0, 0.0, 0.0])))   # (-3, 6) up to (-5, 0)
    gauge = BodyModel("rail", under)
    sc = float(gauge.profile.project(np.array([-4.0, 0.0])))
    m = mesh_body(gauge, StripPatch.uniform(2, 0.5, 4, 0.5, sc), MeshSpec(body_size=2.0, h_patch=1.0))
    ext = m.extent
    assert ext.s_lo < float(gauge.profile.project(np.array([-5.0, 0.0]))) - 3.0     # 3 mm of undercut inside
    assert ext.q_lo[0] > -5.0                                            # ... which turns back under the head
    L = ext.x_hi - ext.x_lo
    assert _tri_area(m.points, m.free_tris) == pytest.approx(L * (ext.s_hi - ext.s_lo), rel=1e-9)
    area, _ = _area_centroid(_section(gauge, ext))
    assert _tet_volume(m).sum() == pytest.approx(area * L, rel=0.25 * (_arc_h(m) / ext.radius) ** 2)
    with pytest.raises(InputError, match="axle"):
        BodyModel("wheel", flat_profile(-1, 1), axle_z=5.0)
    with pytest.raises(InputError, match="kind"):
        BodyModel("tyre", flat_profile(-1, 1))
    with pytest.raises(InputError, match="fe_conform"):
        MeshSpec(conform="some")


def test_gmsh_failure_is_reported_and_finalised(monkeypatch):
    import gmsh

    def broken(*args, **kwargs):
        raise Exception("simulated OpenCASCADE failure")

    monkeypatch.setattr(gmsh_body, "_build", broken)
    body = BodyModel("block", flat_profile(-10, 10))
    with pytest.raises(MeshingError, match="gmsh failed while building the geometry.*simulated"):
        mesh_body(body, StripPatch.uniform(2, 1.0, 2, 1.0, 10.0))
    assert not gmsh.isInitialized()


def test_flat_tetrahedra_are_dropped_unless_a_node_needs_them():
    """HXT left flat tetrahedra (four nodes in one plane) on the faces between the swept pieces of
    a worn wheel; their element matrices are singular.  They carry no material and are dropped; a
    node that only a flat tetrahedron holds is an error, not a silently floating node."""
    body = BodyModel("block", flat_profile(-1, 1))
    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0.5, 0.5, 0.0]], dtype=float)
    good = np.array([[0, 1, 2, 3], [1, 4, 2, 3]])
    flat = np.array([[0, 1, 4, 2]])                                   # all in z = 0
    kept = gmsh_body._drop_flat(P[:5], np.vstack([good, flat]), body)
    assert np.array_equal(kept, good)
    with pytest.raises(MeshingError, match="flat tetrahedra"):
        gmsh_body._drop_flat(P, np.vstack([good, [[0, 1, 4, 5]]]), body)   # node 5 only in a flat one
