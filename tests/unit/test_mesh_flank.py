"""A wheel body whose grid rows lie on a steep flange flank (conformal.meshing.gmsh_body).

On the flank of S1002 (a straight line at 70 degrees to the axle) the grid rows of a 24-row strip
are 0.105 mm wide and are revolved about the axle with elements up to h_max = 0.2 x 354 mm = 71 mm
long far from the patch; their chords depart from the arcs, within the surface, by
h^2 |t_z| / (8 r) = 1.2 mm, twelve times a row's width: the triangles across a row fold over and
gmsh's surface mesher gave up on two of them, leaving three of the five swept volumes without
tetrahedra.  The mesh was then rejected only by the free-surface coverage check (free-surface nodes
of the empty volumes had been renumbered to -1).  The body is now meshed again with the sweep's
elements on such rows bounded by their sagitta (``sagitta_sizes``).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from conformal.meshing.bodies import BodyModel, Profile2D
from conformal.meshing.gmsh_body import SAGITTA_FRACTION, sagitta_sizes
from _paths import SCENES


def _wheel(angle_deg: float, axle_z: float = -500.0) -> BodyModel:
    """A wheel whose profile is a straight line at ``angle_deg`` to the axle, from (0, 0)."""
    t = np.array([math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))])
    s = np.linspace(0.0, 20.0, 201)
    return BodyModel("wheel", Profile2D.from_points(s[:, None] * t[None, :], "line"), axle_z)


def test_sagitta_sizes_analytic():
    """Chord h of a parallel circle of radius r with its sagitta within the surface
    h^2 kappa_g / 8 = fraction * w, kappa_g = |sin(angle)| / r (angle of the profile to the axle):
    a plane annulus (90 degrees), a cone, a cylinder (0 degrees: no curvature within the surface)
    and an extruded (not revolved) body."""
    breaks = np.array([1.0, 1.1, 3.0])
    for angle in (90.0, 70.0, 30.0):
        body = _wheel(angle)
        h = sagitta_sizes(body, breaks)
        # the largest |t_z| / r over the strip: |sin| / r at the strip's smallest radius
        r = body.radius_at(breaks[:-1])
        r_lo = np.minimum(r, body.radius_at(breaks[1:]))
        expect = np.sqrt(8 * SAGITTA_FRACTION * np.diff(breaks) * r_lo / abs(math.sin(math.radians(angle))))
        np.testing.assert_allclose(h, expect, rtol=1e-9)
    # the flank row of the S1002 case: w = 0.105 mm, r = 472.5 mm, 70 degrees: 20.6 mm at the fold
    # (fraction 1), 14.6 mm with the bound's fraction 1/2; h_max was 70.7 mm
    row = sagitta_sizes(_wheel(-70.0, axle_z=-472.5), np.array([0.0, 0.105]), fraction=1.0)
    assert row[0] == pytest.approx(math.sqrt(8 * 0.105 * 472.5 / math.sin(math.radians(70.0))), rel=1e-3)
    assert 20.0 < row[0] < 21.0
    assert np.all(np.isinf(sagitta_sizes(_wheel(0.0), breaks)))
    rail = BodyModel("rail", _wheel(70.0).profile)
    assert np.all(np.isinf(sagitta_sizes(rail, breaks)))


@pytest.mark.slow
def test_flank_wheel_body_meshes():
    """The wheel body of S1002/UIC60 at a lateral shift of 6.3 mm on a 24-row strip (the FE
    influence numbers' body, as studies/speed_vs_error.py builds it): before, MeshingError ("the
    free surface of the wheel body covers x = -25.838 .. 0.550 ... instead of x = -379.337 ..
    379.337"); now every swept volume has tetrahedra and the free surface covers the whole body
    surface, with the rows of the flank bounded.  About 40 s CPU."""
    from conformal.cases.conformal import curved_problem_from_wheel_rail, fe_profiles
    from conformal.influence.fe import settings_from_options, wheel_body_from_grid
    from conformal.meshing.gmsh_body import mesh_body
    from conformal.scene import load_scene

    sc = load_scene(SCENES / "flange_s1002_uic60.toml").with_model(theory="conformal", influence="fe")
    sc = sc.with_("geometry.lateral_shift", 6.3).with_("grid.n", 24)
    _, wheel_points = fe_profiles(sc)
    grid = curved_problem_from_wheel_rail(sc).grid
    body, patch, _ = wheel_body_from_grid(grid, wheel_points, name="S1002")
    spec = settings_from_options(sc.model.options).mesh
    bm = mesh_body(body, patch, spec)
    ext = bm.extent
    assert bm.stats["sagitta_strips"] >= 20                 # the flank's rows (24 measured)
    fn = np.unique(bm.free_tris)
    x, s = bm.uv[fn, 0], bm.uv[fn, 1]
    tol = 1e-3 * ext.depth
    assert abs(x.min() - ext.x_lo) < tol and abs(x.max() - ext.x_hi) < tol
    assert abs(s.min() - ext.s_lo) < tol and abs(s.max() - ext.s_hi) < tol
    assert np.unique(bm.tets).size == bm.n_nodes              # every node carries a tetrahedron
    # every part of the sweep holds tetrahedra: nodes in each x band of the body
    xs = np.linspace(ext.x_lo, ext.x_hi, 9)
    counts = np.histogram(x, bins=xs)[0]
    assert np.all(counts > 0), counts
