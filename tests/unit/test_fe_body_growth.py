"""FE bodies have the size they are asked for: a profile that ends inside the body's disc is
continued straight along its end tangent (conformal.meshing.bodies.grow_profile), and what the
mesher builds, not only the key that was set, grows with ``fe_body_size``."""
from __future__ import annotations

import math

import numpy as np
import pytest

from conformal.meshing.bodies import BodyModel, Profile2D, StripPatch, body_extent, grow_profile
from conformal.meshing.gmsh_body import MeshSpec, mesh_body


def _short_corner() -> BodyModel:
    """A rail gauge corner R10 (centre (0, 10), z down) from the flat top at y = 6 round to the
    vertical gauge face at z = 16: about 22 mm of profile, the corner's middle at 45 degrees."""
    t = np.linspace(0.0, 0.5 * math.pi, 158)
    arc = np.column_stack([-10 * np.sin(t), 10 - 10 * np.cos(t)])
    top = np.column_stack([np.linspace(6.0, 0.0, 31)[:-1], np.zeros(30)])
    face = np.column_stack([np.full(30, -10.0), np.linspace(10.0, 16.0, 31)[1:]])
    return BodyModel("rail", Profile2D.from_points(np.vstack([top, arc, face]), "short corner"))


def _patch(body: BodyModel) -> StripPatch:
    s0 = float(body.profile.project(np.array([-10 * math.sin(math.pi / 4), 10 - 10 * math.cos(math.pi / 4)])))
    return StripPatch.uniform(4, 1.0, 4, 1.0, s0)


def test_grow_profile_continues_straight_and_keeps_arc_lengths():
    body = _short_corner()
    patch = _patch(body)
    grown, closure = grow_profile(body, patch, 8.0)           # disc radius 2.8 + 32 mm
    prof, new = body.profile, grown.profile
    # the original points keep their arc lengths; the continuations are straight along the end
    # tangents: the flat top continues at z = 0 towards +y, the gauge face at y = -10 downwards
    assert new.s[1] == pytest.approx(prof.s[0]) and new.s[-2] == pytest.approx(prof.s[-1])
    np.testing.assert_allclose(new.point(prof.s), prof.point(prof.s), atol=1e-12)
    assert new.z[0] == pytest.approx(0.0, abs=1e-9) and new.y[0] > 25.0
    assert new.y[-1] == pytest.approx(-10.0, abs=1e-9) and new.z[-1] > 25.0
    assert closure.extension_lo == pytest.approx(new.y[0] - 6.0) and closure.extension_hi == pytest.approx(new.z[-1] - 16.0)
    # the disc has the radius asked for and the profile reaches it; the original profile ends
    # inside it and is cut there (its free surface ends 10-15 mm from the patch)
    ext_grown, ext_cut = body_extent(grown, patch, 8.0), body_extent(body, patch, 8.0)
    assert ext_grown.radius == pytest.approx(closure.radius) and not (ext_grown.cut_lo or ext_grown.cut_hi)
    assert ext_grown.depth == pytest.approx(8.0 * patch.size)
    assert ext_cut.cut_lo and ext_cut.cut_hi
    assert (ext_cut.s_lo, ext_cut.s_hi) == (pytest.approx(prof.s[0]), pytest.approx(prof.s[-1]))


def test_grow_profile_does_not_cross_the_profile():
    """A profile curling back under itself (a rail head's top, field side, underside and an end
    rising towards the top, as a worn gauge face can): that end's tangent points at the top
    surface, so it keeps the straight cut; the other end is continued.  A profile long enough
    needs nothing."""
    pts = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 10.0], [5.0, 10.0], [5.0, 3.0]])
    curl = BodyModel("rail", Profile2D.from_points(pts, "curl"))
    patch = StripPatch.uniform(3, 1.0, 3, 1.0, 12.0)                # on the top, around y = 12
    grown, closure = grow_profile(curl, patch, 8.0)
    assert closure.extension_hi == 0.0 and closure.extension_lo > 10.0
    assert grown.profile.y[0] < -10.0 and grown.profile.z[0] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(grown.profile.point(curl.profile.s[-1]), [5.0, 3.0], atol=1e-12)
    long_flat = BodyModel("block", Profile2D(np.array([-500.0, 500.0]), np.zeros(2)))
    same, c = grow_profile(long_flat, StripPatch.uniform(3, 1.0, 3, 1.0, 500.0), 4.0)
    assert same is long_flat and c.extension_lo == c.extension_hi == 0.0


@pytest.mark.slow
def test_mesh_grows_with_body_size_on_a_short_profile():
    """What gmsh built: the mesh's extent in the cross-section (nodes' distance from the disc's
    centre) and the reach of its free surface follow the disc radius asked for on a profile that
    ends 10-15 mm from the patch, and the statistics report it; with the earlier cut closure the
    free surface stops at the profile's ends (an artificial boundary close to the contact)."""
    body = _short_corner()
    patch = _patch(body)
    reach, free, stats = {}, {}, {}
    for size, closure in ((1.0, "extend"), (4.0, "extend"), (16.0, "extend"), (16.0, "cut")):
        m = mesh_body(body, patch, MeshSpec(body_size=size, closure=closure, h_patch=4.0, h_load=None))
        c = np.asarray(m.extent.centre)
        dist = np.linalg.norm(m.points[:, 1:] - c, axis=1)
        reach[size, closure] = float(dist.max())
        free[size, closure] = float(dist[np.unique(m.free_tris)].max())
        stats[size, closure] = m.stats
    r_patch = stats[1.0, "extend"]["disc_radius_mm"] - 1.0 * patch.size
    ends = max(np.linalg.norm(body.profile.point(body.profile.s[[0, -1]]) - np.asarray(m.extent.centre), axis=1))
    for size in (1.0, 4.0, 16.0):
        want = r_patch + size * patch.size
        assert reach[size, "extend"] == pytest.approx(want, rel=1e-3)
        assert free[size, "extend"] == pytest.approx(want, rel=1e-3)
        assert stats[size, "extend"]["disc_radius_mm"] == pytest.approx(want, rel=1e-9)
        assert stats[size, "extend"]["mesh_reach_mm"] == pytest.approx(reach[size, "extend"], rel=1e-9)
    st = stats[16.0, "extend"]
    assert st["closure_lo"] == st["closure_hi"] == "extended"
    assert st["extension_lo_mm"] > 40 and st["extension_hi_mm"] > 40
    assert stats[1.0, "extend"]["closure_lo"] == "profile"
    # the cut closure: the free surface ends with the profile (about 16 mm from the centre)
    assert free[16.0, "cut"] == pytest.approx(ends, rel=1e-3) and free[16.0, "cut"] < 0.3 * free[16.0, "extend"]
    assert stats[16.0, "cut"]["closure_lo"] == stats[16.0, "cut"]["closure_hi"] == "cut"


def test_wheel_body_size_is_limited_by_the_wheel():
    """A 50 mm wheel cannot hold a body of 16 patch sizes (5 mm patch): the margin is cut to a disc
    reaching 0.75 of the wheel's radius towards the axle, and the extent says so (the report's
    margin_limited_by); a grid far larger than the wheel is still refused."""
    from conformal.errors import InputError
    from conformal.meshing.bodies import WHEEL_REACH

    t = np.linspace(-0.5, 0.5, 201)
    wheel = BodyModel("wheel", Profile2D.from_points(np.column_stack([10 * np.sin(t), -10 * (1 - np.cos(t))]),
                                                     "crown"), axle_z=-50.0)
    patch = StripPatch.uniform(5, 1.0, 5, 1.0, 0.5 * wheel.profile.length)
    small, big = (body_extent(grow_profile(wheel, patch, z)[0], patch, z) for z in (1.0, 16.0))
    assert not small.wheel_limited and small.depth == pytest.approx(patch.size)
    r_patch = small.radius - small.depth
    assert big.wheel_limited and big.radius == pytest.approx(WHEEL_REACH * 50.0)
    assert big.depth == pytest.approx(WHEEL_REACH * 50.0 - r_patch) and big.depth < 16 * patch.size
    with pytest.raises(InputError, match="larger than the wheel"):
        body_extent(wheel, StripPatch.uniform(200, 1.0, 5, 1.0, 0.5 * wheel.profile.length), 1.0)
