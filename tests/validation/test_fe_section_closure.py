"""FE influence bodies of real rails and wheels (issue 20, item 1): ``fe_closure = "section"``
cuts the whole cross-section (60E1 head, web and foot; the wheel's rim and web,
conformal.geometry.sections) by the body's disc, so that a real rail, whose head profile ends
35 mm down, grows with ``fe_body_size`` until the disc holds the whole section.  The tests check
what gmsh built (node positions, reach, which faces are free), not the keys; and that the gmsh
helpers shared by gmsh_body and section_body left their meshes unchanged."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from conformal.errors import InputError
from conformal.geometry.profiles import load_profile
from conformal.geometry.sections import block_section, uic60_section
from conformal.meshing.bodies import (BodyModel, Profile2D, StripPatch, closed_section_extent,
                                      section_profile)
from conformal.meshing.gmsh_body import MeshSpec, mesh_body
from _paths import SCENES


def _uic60_rail() -> tuple[BodyModel, StripPatch, np.ndarray]:
    """The 60E1 section opened at its foot, and a 3 x 3 patch of 2 mm elements at the gauge
    corner (y = -30 on the UIC 60 head)."""
    head = load_profile("UIC60", "rail").points
    sec = uic60_section(head)
    body = BodyModel("rail", section_profile(sec.points, sec.n_profile, sec.clamped[0], sec.name))
    k = int(np.argmin(np.abs(head[:, 0] + 30.0)))
    s0 = float(Profile2D.from_points(head).s[k])       # the head's own arc length = the section's
    return body, StripPatch.uniform(3, 2.0, 3, 2.0, s0), sec.points


def test_section_profile_keeps_the_head_arc_lengths_and_opens_at_the_foot():
    head = load_profile("UIC60", "rail").points
    body, patch, P = _uic60_rail()
    prof = body.profile
    own = Profile2D.from_points(head)
    np.testing.assert_allclose(prof.point(own.s), head, atol=1e-9)
    # the open ends are the foot's corners (+-75, 172): the foot's lower face is the support edge
    np.testing.assert_allclose([prof.y[0], prof.z[0], prof.y[-1], prof.z[-1]], [-75.0, 172.0, 75.0, 172.0])
    with pytest.raises(InputError, match="support edge"):
        section_profile(P, len(head), 3)                    # an edge of the head itself


def test_closed_section_extent_spans_the_parts_inside_the_disc():
    body, patch, P = _uic60_rail()
    small = closed_section_extent(body, patch, 2.0)          # 2 patch sizes: inside the head
    assert small.closed and small.radius == pytest.approx(small.depth + 3 * 2.0 * 2 ** 0.5 / 2, rel=0.2)
    c = np.asarray(small.centre)
    for s in (small.s_lo, small.s_hi):                      # where the profile leaves the disc
        assert np.linalg.norm(body.profile.point(s) - c) == pytest.approx(small.radius, rel=1e-9)
    big = closed_section_extent(body, patch, 40.0)           # the disc holds the whole section
    assert (big.s_lo, big.s_hi) == (pytest.approx(body.profile.s[0]), pytest.approx(body.profile.s[-1]))
    assert np.max(np.linalg.norm(P - np.asarray(big.centre), axis=1)) < big.radius


@pytest.mark.slow
def test_section_body_holds_head_web_and_foot_with_free_web_and_clamped_foot():
    """At 40 patch sizes the disc holds the whole 60E1 section: the mesh reaches the foot's far
    corner, its nodes fill y = -75 .. 75 and z = 0 .. 172, the web's faces are free (traction free,
    like the profile) and the foot's lower face and the ends are the artificial boundary."""
    body, patch, P = _uic60_rail()
    # the walls' cap (fe_h_wall, tests/unit/test_fe_section_wall.py) made not to bind: this test is
    # about the body's extent and faces, and the capped mesh of a 0.5 m rail costs a minute
    spec = replace(MeshSpec(), body_size=40.0, closure="section", h_wall=100.0)
    bm = mesh_body(body, patch, spec)
    st = bm.stats
    c = np.asarray(bm.extent.centre)
    far = float(np.max(np.linalg.norm(P - c, axis=1)))        # the section point farthest from the patch
    assert st["mesh_reach_mm"] == pytest.approx(far, rel=1e-6) and st["mesh_reach_mm"] < st["disc_radius_mm"]
    assert st["closure_lo"] == st["closure_hi"] == "section"
    y, z = bm.points[:, 1], bm.points[:, 2]
    assert (y.min(), y.max(), z.max()) == (pytest.approx(-75.0), pytest.approx(75.0), pytest.approx(172.0))
    free = np.unique(bm.free_tris)
    clamped = np.unique(bm.clamped_tris)
    web = free[(np.abs(np.abs(y[free]) - 8.25) < 1e-6) & (z[free] > 80) & (z[free] < 120)]
    assert web.size > 0                                       # the web is free surface
    foot = np.abs(z - 172.0) < 1e-6
    assert np.all(np.isin(np.flatnonzero(foot), clamped))     # the foot's lower face is held
    assert not np.any(foot[free] & (np.abs(y[free]) < 70))    # and not free
    # the body stops at the disc, not at the head's end 35 mm down (the "extend" closure makes
    # this head a slab limited to its width)
    assert z.max() > 4 * 35.0


def _arc_body(kind: str) -> tuple[BodyModel, StripPatch]:
    t = np.linspace(-0.9, 0.9, 181)
    prof = Profile2D(10 * np.sin(t), -10 * (1 - np.cos(t)), "arc")
    return BodyModel(kind, prof, axle_z=-100.0 if kind == "wheel" else None), StripPatch.uniform(4, 0.5, 4, 0.5, prof.s[90])


@pytest.mark.slow
def test_shared_gmsh_helpers_leave_the_meshes_unchanged():
    """gmsh_body and section_body share the profile curves, the sweep, the graded size field and
    the mesh options (gmsh_body.profile_curves, sweep_pieces, graded_size, set_mesh_options):
    the node and element counts are those of the code before (gmsh 4.15.2, measured on main)."""
    from conformal.meshing.section_body import mesh_section_body

    counts = []
    for kind in ("rail", "wheel"):
        body, patch = _arc_body(kind)
        bm = mesh_body(body, patch, replace(MeshSpec(), body_size=2.0))
        counts.append((bm.n_nodes, len(bm.tets), len(bm.free_tris), len(bm.clamped_tris)))
    body, patch = _arc_body("rail")
    sec = block_section(np.column_stack([body.profile.y, body.profile.z]), "rail", 10.0)
    e = patch.edges
    m = mesh_section_body(body, sec, patch, (2.0, e[0] - 1, e[-1] + 1), (-8.0, 8.0), h0=0.5, growth=0.35,
                          h_max=3.0, reach=8.0)
    counts.append((m.n_nodes, len(m.tets), len(m.free_tris), len(m.clamped_tris)))
    assert counts == [(1247, 4749, 814, 906), (1054, 3950, 802, 686), (1112, 4326, 182, 810)]


@pytest.mark.slow
def test_fe_closure_section_needs_known_sections():
    """``fe_closure = "section"`` on a scene: the S1002 / UIC 60 scene gets the 60E1 section and
    the rim and web (foot and hub at the open ends); the idealised deep pair is refused in one line."""

    from conformal.cases.conformal import fe_profiles
    from conformal.scene import load_scene

    scenes = SCENES
    sc = load_scene(scenes / "flange_s1002_uic60_fe.toml")
    sc = replace(sc, model=replace(sc.model, options={**dict(sc.model.options), "fe_closure": "section"}))
    rail, wheel = fe_profiles(sc)
    np.testing.assert_allclose(rail[[0, -1]], [[-75.0, 172.0], [75.0, 172.0]])
    hub = 125.0 - sc.geometry.wheel_radius
    assert wheel[0, 1] == pytest.approx(hub) and wheel[-1, 1] == pytest.approx(hub)
    deep = load_scene(scenes / "deep_conformal_pair.toml")
    deep = replace(deep, model=replace(deep.model, options={**dict(deep.model.options), "fe_closure": "section"}))
    with pytest.raises(InputError, match="no known section"):
        fe_profiles(deep)


def test_p2_clamped_triangle_with_an_edge_the_volume_lacks():
    """P2 (fe_order = 2): a clamped triangle whose edge no tetrahedron has (gmsh's volume mesh
    took the other diagonal of a surface quad; the deep pair's wheel at size 4) gets no dof on
    that edge instead of failing the solve; the free surface still refuses it."""
    from conformal.influence.factor import FESolveError
    from conformal.influence.fe_toolkit import vector_space

    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.3, 0.3, -1]], dtype=float)
    tets = np.array([[0, 1, 2, 3], [0, 2, 1, 4]])
    _, space = vector_space(pts, tets, 2)
    tri = np.array([[0, 3, 4]])                      # edge 3-4 crosses the shared face: no tet has it
    with pytest.raises(FESolveError, match="edge not found"):
        space.scalar_nodes(tri)
    nodes = space.scalar_nodes(tri, strict=False)
    assert nodes.shape == (1, 6) and (nodes[0, :3] == tri[0]).all()
    assert nodes[0, 4] == -1 and nodes[0, 3] >= space.nverts and nodes[0, 5] >= space.nverts


def test_project_beside_a_long_segment_whose_nearest_vertex_is_elsewhere():
    """Profile2D.project beside the middle of a long straight piece (a continuation of 350 mm,
    a web) whose nearest vertex is the far end of another long piece: the point's own segment is
    found (the S1002 wheel at 6.3 mm, its flange back continued 350 mm, failed to mesh before)."""
    fine = np.column_stack([np.linspace(0.0, 5.0, 51), np.zeros(51)])
    pts = np.vstack([[[0.0, -300.0]], fine, [[-20.0, -150.0]]])
    prof = Profile2D.from_points(pts)
    q = np.array([1.0, -150.0])
    s = float(prof.project(q))
    assert s == pytest.approx(150.0, abs=1e-9)                 # on the first (long) segment
    assert np.linalg.norm(prof.point(s) - q) == pytest.approx(1.0, abs=1e-9)
