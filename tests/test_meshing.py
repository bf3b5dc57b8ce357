"""gmsh quasi-quarter-space bodies (conformal.meshing): geometry, conformity, errors."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import conformal

from conformal.errors import InputError
from conformal.meshing import gmsh_body
from conformal.meshing.bodies import BodyModel, Profile2D, StripPatch, body_extent, flat_profile
from conformal.meshing.gmsh_body import MeshingError, MeshSpec, mesh_body, surface_frame, surface_point

_trapz = getattr(np, "trapezoid", None) or np.trapz   # numpy < 2 has only trapz
PROFILES = Path(conformal.__file__).parent / "data" / "profiles"   # packaged copies of ../shared/profiles


def _tet_volume(m) -> np.ndarray:
    a, b, c, d = (m.points[m.tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def _tri_area(p, t) -> float:
    return 0.5 * np.linalg.norm(np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), axis=1).sum()


def _rail() -> BodyModel:
    yz = np.loadtxt(PROFILES / "uic60_head_r300w21_analytic.csv", delimiter=",")
    return BodyModel("rail", Profile2D.from_points(yz, "uic60"))


def test_block_geometry_and_conformity():
    body = BodyModel("block", flat_profile(-30, 30))
    patch = StripPatch.uniform(3, 1.0, 2, 1.0, 30.0)
    m = mesh_body(body, patch, MeshSpec(conform="all", body_size=1.0))
    ext = m.extent
    L, W = ext.x_hi - ext.x_lo, ext.s_hi - ext.s_lo
    assert np.all(_tet_volume(m) > 0)
    assert _tet_volume(m).sum() == pytest.approx(L * W * ext.depth, rel=1e-12)     # a box: exact
    assert _tri_area(m.points, m.free_tris) == pytest.approx(L * W, rel=1e-12)
    assert np.allclose(m.points[np.unique(m.free_tris), 2], 0.0)
    # clamped faces: the four sides and the bottom, nothing of the top surface inside
    cn = m.clamped_nodes
    p = m.points[cn]
    on_cut = (np.isclose(p[:, 0], ext.x_lo) | np.isclose(p[:, 0], ext.x_hi) | np.isclose(p[:, 2], ext.depth)
              | np.isclose(p[:, 1], -30 + ext.s_lo) | np.isclose(p[:, 1], -30 + ext.s_hi))
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
    ss = np.linspace(ext.s_lo, ext.s_hi, 4001)
    yz = rail.profile.point(ss)
    # cross-section area between the profile and the bottom line (trapezoid rule on 4001 points)
    area = _trapz(ext.z_bottom - yz[:, 1], yz[:, 0])
    L = ext.x_hi - ext.x_lo
    # faceted curve: chord sag h^2/(8R) over the coarse parts; measured 1e-5 relative
    assert _tet_volume(m).sum() == pytest.approx(area * L, rel=2e-4)
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
    ss = np.linspace(ext.s_lo, ext.s_hi, 4001)
    yzs = wheel.profile.point(ss)
    r_out = yzs[:, 1] - wheel.axle_z
    r_in = ext.z_bottom - wheel.axle_z
    theta = ext.theta_hi - ext.theta_lo
    vol = 0.5 * theta * _trapz(r_out ** 2 - r_in ** 2, yzs[:, 0])      # ring sector
    assert _tet_volume(m).sum() == pytest.approx(vol, rel=2e-4)
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
    # a profile that turns back (not a graph over y) within the body
    y = np.array([0.0, 1.0, 2.0, 1.5, 3.0, 4.0])
    z = np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0])
    with pytest.raises(InputError, match="graph over y"):
        body_extent(BodyModel("rail", Profile2D(y, z)), StripPatch.uniform(1, 0.2, 1, 0.2, 0.5), 20.0)
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
