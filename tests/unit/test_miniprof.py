"""Miniprof profiles (.ban/.whl) and CONTACT's profile conversions (MIRRORY, MIRRORZ, SMOOTH).

Data: CONTACT's examples/MBench_UIC60_v3.ban (the Manchester UIC60 rail as a Miniprof file) and
testbank/profiles/avg_HR.BAN, avg_wheel.whl (tests/reference/contact_decks, README there)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from conformal.errors import InputError
from conformal.geometry.miniprof import read_miniprof, repair_zigzags, z_needs_mirror
from conformal.geometry.profiles import load_profile, read_points
from _paths import DECKS



def test_miniprof_rail_is_the_simpack_rail_mirrored():
    """MBench_UIC60_v3.ban holds the points of MBench_UIC60_v3.prr with y mirrored; CONTACT reads
    it with MIRRORY = 1 and MIRRORZ = 0 (z detected as already downwards).  Lines that start with
    '"' are comments in CONTACT's reader, so 476 of its 495 points are read: every one of them is
    a point of the .prr file to the digit."""
    raw = read_points(DECKS / "MBench_UIC60_v3.ban")
    assert raw.shape == (476, 2)
    assert not z_needs_mirror(raw * [-1.0, 1.0], "rail")
    ban = load_profile("MBench_UIC60_v3.ban", "rail", DECKS, z_up=None, mirror_y=True).points
    prr = load_profile("MBench_UIC60_v3.prr", "rail", DECKS).points
    d = np.min(np.hypot(ban[:, None, 0] - prr[None, :, 0], ban[:, None, 1] - prr[None, :, 1]), axis=1)
    assert d.max() < 1e-9
    assert ban[0, 0] < ban[-1, 0]                       # ordered from the gauge side to the field side


def test_z_orientation_detected_from_the_side_faces():
    """CONTACT's MIRRORZ = 0: a rail (z down) and a flanged wheel are kept as they are, and
    mirrored when given upside down."""
    rail = load_profile("MBench_UIC60_v3.prr", "rail", DECKS).points
    wheel = load_profile("MBench_S1002_v3.prw", "wheel", DECKS).points
    up = np.array([1.0, -1.0])
    assert (z_needs_mirror(rail, "rail"), z_needs_mirror(rail * up, "rail")) == (False, True)
    assert (z_needs_mirror(wheel, "wheel"), z_needs_mirror(wheel * up, "wheel")) == (False, True)
    again = load_profile("MBench_UIC60_v3.prr", "rail", DECKS, z_up=None).points
    assert np.array_equal(again, rail)


def test_measured_rail_with_a_zigzag_and_keywords():
    """avg_HR.BAN: 'Key=value' header up to the first blank line, ColumnDef=X,Y,A,C (four columns,
    the first two used), 147 points with one stitching zig-zag (29.27, 29.26 mm: both turns of
    about 166 degrees, beyond ZIGTHRS = 150 degrees) replaced by its mean: 146 points."""
    p = read_miniprof(DECKS / "avg_HR.BAN")
    assert p.shape == (146, 2)
    assert p[0].tolist() == [-11.73, -1.52]
    k = int(np.argmin(np.abs(p[:, 0] - 29.265)))
    assert p[k].tolist() == pytest.approx([29.265, -2.55])
    assert read_miniprof(DECKS / "avg_HR.BAN", zig_threshold=np.pi).shape == (147, 2)   # >= pi: off


def test_old_style_wheel_file_skips_its_text_header():
    """avg_wheel.whl: an old-style file (MINIPROF in its first line, a line of numbers with text in
    the header) whose points start after the blank line."""
    p = read_miniprof(DECKS / "avg_wheel.whl")
    assert p[0].tolist() == [1.55, 15.34] and p[-1].tolist() == [139.70, -32.34]
    assert len(p) == 728


def test_zigzag_repair_and_bad_files(tmp_path):
    p = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [1.9, 0.0], [3.0, 0.0], [4.0, 0.0]])
    q = repair_zigzags(p)
    assert q.tolist() == [[0.0, 0.0], [1.0, 0.0], [1.95, 0.0], [3.0, 0.0], [4.0, 0.0]]
    f = tmp_path / "one.ban"
    f.write_text("ColumnDef=X,Y\n\n1.0 2.0\n")
    with pytest.raises(InputError, match="at least 2 points"):
        read_miniprof(f)
    f.write_text("ColumnDef=X,Y\n\n1.0 2.0\n2.0 3.0\nXYPoints=2\n")
    with pytest.raises(InputError, match="keyword after the points"):
        read_miniprof(f)
    f.write_text("ColumnDef=A,C\n\n1.0 2.0\n2.0 3.0\n")
    with pytest.raises(InputError, match="names no X and Y"):
        read_miniprof(f)


def test_scene_keys_for_profile_conversions(tmp_path):
    """``[geometry] rail_mirror_y`` must be true/false; ``rail_z = "auto"``, per-profile smoothing."""
    from conformal.scene import scene_from_dict

    geo = {"kind": "wheel_rail", "rail_profile": str(DECKS / "MBench_UIC60_v3.ban"), "rail_mirror_y": True,
           "rail_z": "auto", "wheel_profile": str(DECKS / "MBench_S1002_v3.prw"), "rail_cant": 0.0,
           "rail_smoothing": 0.0, "wheel_smoothing": 0.0}
    sc = scene_from_dict({"geometry": geo, "load": {"wheel_load": 10000.0}})
    assert sc.geometry.rail_mirror_y and sc.geometry.rail_z == "auto" and sc.geometry.rail_smoothing == 0.0
    with pytest.raises(InputError, match=r"\[geometry\] rail_mirror_y: must be true or false"):
        scene_from_dict({"geometry": {**geo, "rail_mirror_y": 1}, "load": {"wheel_load": 10000.0}})


@pytest.mark.slow
@pytest.mark.parametrize("case", [22, 23])
def test_testbank_miniprof_cases_against_contact(case):
    """testbank cases 22 and 23 (steady curving, high and low rail: Miniprof rails avg_HR.BAN,
    avg_low2.ban with MIRRORY = 1 and wheel avg_wheel.whl, all smoothed with CONTACT's lambda = 10,
    friction 0.6 given over the profile, V = 1; 5-10 s each): FN, FX, FS, pmax, elements, position
    on the rail and track forces within the Manchester tolerances (units of the tolerance <= 1).
    Case 22 (flange contact at 37 degrees): the contact angle is 0.006 rad off and with it track FY
    3.5 % (CONTACT keeps the profiles' kinks through its smoothing, the project's spline does not)."""
    from conformal.contact_inp.deck import read_deck, solve_deck
    from conformal.contact_inp.refout import compare_wheelrail, read_ref_out_wheelrail

    parsed = read_deck(DECKS / "testbank.inp", ignore_subsurface=True, ignore_temperature=True)
    ref = read_ref_out_wheelrail((DECKS / "testbank.ref_out").read_text(encoding="utf-8"))
    (d,) = list(solve_deck(parsed, cases=[case]))
    dev = compare_wheelrail(d, ref[case], mu=0.6)
    loose = ("patch1.contact_angle", "FY_track") if case == 22 else ()
    within = {k: v for k, v in dev.items() if k not in loose}
    assert max(within.values()) <= 1.0, within
    if case == 22:
        assert dev["patch1.contact_angle"] <= 1.5 and dev["FY_track"] <= 4.0
    assert json.dumps(d)


def test_deck_smoothing_limit_and_scene_default():
    """A scene refuses smoothing that moves a profile more than ``[geometry] max_smoothing_error``
    (default 0.1 mm); the deck reader allows CONTACT's smoothing up to 2 mm."""
    from conformal.contact_inp.solve1 import DECK_SMOOTHING_ERROR
    from conformal.geometry.wheelrail import profile_curves
    from conformal.scene import scene_from_dict

    geo = {"kind": "wheel_rail", "rail_profile": str(DECKS / "avg_HR.BAN"), "rail_mirror_y": True, "rail_z": "auto",
           "wheel_profile": str(DECKS / "avg_wheel.whl"), "wheel_z": "auto", "rail_cant": 0.0, "smoothing": 40.0,
           "flange_back": 1352.2, "gauge": 1435.1}
    sc = scene_from_dict({"geometry": geo, "load": {"wheel_load": 10000.0}})
    assert sc.geometry.max_smoothing_error == 0.1
    with pytest.raises(InputError, match=r"\[geometry\] smoothing: .* max_smoothing_error"):
        profile_curves(sc.geometry, DECKS)
    loose = scene_from_dict({"geometry": {**geo, "max_smoothing_error": DECK_SMOOTHING_ERROR},
                             "load": {"wheel_load": 10000.0}})
    w, r = profile_curves(loose.geometry, DECKS)
    assert 0.1 < max(w.smoothing_error, r.smoothing_error) <= DECK_SMOOTHING_ERROR
