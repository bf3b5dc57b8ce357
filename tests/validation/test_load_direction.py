"""A load direction other than vertical in wheel-rail cases (issue 11, item 5): ``[load]
load_angle``, the wheel pressed along that direction with the wheel load as the force along it
(seed Eqs. 45-46, w = cos(delta - load angle)).

Independent check: Hertz.  The straight 70-degree flange flank of S1002 against the R13 gauge
corner of UIC 60 (``single_flange70.toml``) is one small patch whose contact angle varies by only
a few degrees (-1.22 rad at its centre), so without friction its resultant lies along its normal
whatever the load direction: the normal force is FN = W / cos(delta_c - load angle), and pmax and
the largest overlap follow Hertz's laws FN^(1/3) and FN^(2/3) from the vertical-load solution.
"""
import math

import pytest

from conformal.cases import solve_wheel_rail
from conformal.cases.conformal import force_along_load
from conformal.errors import InputError
from conformal.scene import load_scene, scene_from_dict
from _paths import SCENES

DELTA_C = -1.2217          # the flank's contact angle (rad): arctan of its slope 2.7475
W = 10000.0


def flank(load_angle: float, theory: str = "conformal"):
    raw = load_scene(SCENES / "single_flange70.toml").to_dict()
    raw.update(kinematics={}, grid={"n": 24}, model={"theory": theory},
               load={"wheel_load": W, "load_angle": load_angle})
    return scene_from_dict(raw, base_dir=SCENES, name="flank")


@pytest.fixture(scope="module")
def vertical():
    return solve_wheel_rail(flank(0.0))


@pytest.mark.parametrize("angle", [DELTA_C, 0.5 * DELTA_C])
def test_tilted_load_follows_hertz(vertical, angle):
    r = solve_wheel_rail(flank(angle))
    e = r.extra
    assert e["load_angle"] == pytest.approx(angle)
    # the force along the load direction is the wheel load (seed Eq. 46)
    assert force_along_load(e, angle) == pytest.approx(W, rel=1e-6)
    # one small patch: FN = W / cos(delta_c - angle); the spread of the contact angle over the
    # patch (3 degrees) moves it by well under 0.1 %
    assert r.FN == pytest.approx(W / math.cos(DELTA_C - angle), rel=2e-3)
    # at 70 degrees 1/cos magnifies the angle: the pressure centroid's 1 mrad off DELTA_C is 0.3 %
    assert vertical.FN == pytest.approx(W / math.cos(DELTA_C), rel=5e-3)
    # the resultant stays along the patch normal (its direction within 2 mrad of the flank's
    # normal, the pressure-weighted mean of a normal that turns by 80 mrad over the patch)
    for res in (r, vertical):
        assert math.atan2(res.extra["FY_track"], res.extra["FZ_track"]) == pytest.approx(-DELTA_C, abs=2e-3)
    # Hertz's laws from the vertical solution (24 elements: 1 % for pmax, the overlap closer)
    ratio = r.FN / vertical.FN
    assert r.pmax == pytest.approx(vertical.pmax * ratio ** (1 / 3), rel=0.01)
    assert e["overlap_max"] == pytest.approx(vertical.extra["overlap_max"] * ratio ** (2 / 3), rel=0.01)


def test_load_that_pulls_the_surfaces_apart_is_refused():
    # a load at +0.3 rad makes an angle of more than 90 degrees with the flank's normal
    with pytest.raises(InputError, match="no longer presses"):
        solve_wheel_rail(flank(0.3))


def test_load_angle_inputs():
    with pytest.raises(InputError, match="load_angle.*conformal"):
        solve_wheel_rail(flank(DELTA_C, theory="hertz"))
    with pytest.raises(InputError, match=r"\[load\] load_angle.*80 degrees"):
        flank(2.0)
    with pytest.raises(InputError, match=r"\[load\] load_angle.*wheel_rail"):
        scene_from_dict({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
                         "load": {"normal_force": 1e4, "load_angle": 0.1}})
    s = flank(DELTA_C)
    assert scene_from_dict(s.to_dict(), base_dir=SCENES).load == s.load
    assert s.with_("load.wheel_load", 5000.0).load.load_angle == DELTA_C     # kept when the load changes
    assert s.with_("load.load_angle", 0.0).load.wheel_load == W             # and the other way round
    assert "load_angle" not in flank(0.0).to_dict()["load"]


def test_separate_strips_share_the_lowering_along_the_load():
    """Two patches on separate strips (gauge corner at -31 degrees, flange at -70 degrees): the
    common lowering is along the load direction, the force along it is the wheel load, and a load
    turned towards the patches' normals needs less normal force (measured, 16 elements: 13 230 N
    vertical, 11 106 N at -0.3 rad)."""
    raw = load_scene(SCENES / "two_patches_s1002_uic60.toml").to_dict()
    raw["grid"] = {**raw.get("grid", {}), "n": 16, "strips": "separate"}
    out = []
    for angle in (0.0, -0.3):
        raw["load"] = {"wheel_load": W, "load_angle": angle}
        r = solve_wheel_rail(scene_from_dict(raw, base_dir=SCENES, name="two_patches"))
        assert r.extra["n_strips"] == 2
        assert force_along_load(r.extra, angle) == pytest.approx(W, rel=1e-4)
        out.append(r.FN)
    assert out[1] < 0.9 * out[0]
