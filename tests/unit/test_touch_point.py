"""The touching height of one global search (search.touch_point: a coarser locus, the candidates that
can touch first followed by Newton-Raphson from their previous contact point) against the search
per trial height it replaces (search.touch_height, every trial height a new global search with the
locus every 0.05 mm), on the Manchester A-2.2 positions of both wheels, the lift check's
neighbours and the flange-contact jump, and against the locus of the wheel at the height found
(touching: no sample overlaps, the nearest lies within the sampling's resolution)."""
import json

import numpy as np
import pytest

from conformal.cases import wheelrail as wr
from conformal.geometry import search as gs
from conformal.geometry.wheelrail import build_pair, first_touch
from _paths import CONTACT_CASES
from _scenes import mbench_case_pairs, mbench_case_scene

CASES = json.loads(CONTACT_CASES.read_text())["cases"]["mbench_a22"]["right"]


def _pairs():
    yield from mbench_case_pairs(CASES, neighbour_dy=0.1)
    # the flange-contact jump (tread and flange touch at nearly the same height), CONTACT's roll at 6 mm
    sc = mbench_case_scene(next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == 6.0))
    for y in np.arange(6.0, 6.55, 0.05):
        yield f"jump {y:.2f}", build_pair(sc.geometry, sc.base_dir, side="right", roll=sc.geometry.roll,
                                          lateral_shift=float(y))
    # the two-point contact of that jump: tread and flange touch at the same height (within 2e-12 mm
    # at 6.2250108253756 mm, found by bisection on the touching contact), and shifts 1e-7 .. 1e-4 mm away
    for dy in (0.0, -1e-7, 1e-7, -1e-5, 1e-5, -1e-4, 1e-4):
        yield f"two-point {dy:+g}", build_pair(sc.geometry, sc.base_dir, side="right", roll=sc.geometry.roll,
                                               lateral_shift=TWO_POINT + dy)


TWO_POINT = 6.2250108253756
PAIRS = list(_pairs())


@pytest.mark.parametrize("step", [gs.LOCUS_STEP, gs.TOUCH_STEP])
def test_touch_point_gives_the_height_of_the_search_per_trial_height(step):
    """The same height to rounding (1e-9 mm; measured <= 3e-13 mm) and the same contact point, the
    penetration there zero; the flange-contact jump and its two candidates included."""
    worst = 0.0
    for name, pair in PAIRS:
        z_ref, sr = gs.touch_height(pair)
        c_ref = sr.contacts[0]
        z, c = gs.touch_point(pair, step=step)
        worst = max(worst, abs(z - z_ref))
        assert abs(z - z_ref) <= 1e-9, name
        assert abs(c.s_w - c_ref.s_w) < 1e-6 and abs(c.s_r - c_ref.s_r) < 1e-6, name
        assert abs(c.penetration) < 1e-9 and c.at_end == c_ref.at_end, name
    assert worst > 0.0 or step == gs.LOCUS_STEP     # a different path: not the same floating-point numbers


def test_two_point_contact_takes_the_candidate_that_touches_first():
    """The two-point shift is one (both candidates touch within 1e-9 mm of the same height), and
    1e-5 mm to either side the other candidate touches first (tread 56.4 mm, flange 46.6 mm of wheel
    profile): touch_point takes the one touch_height takes, at its height."""
    pairs = dict(PAIRS)
    _, sr = gs.touch_height(pairs["two-point +0"])
    assert len(sr.contacts) == 2 and all(abs(c.penetration) < 1e-9 for c in sr.contacts)
    s_w = {}
    for dy in ("-1e-05", "+1e-05"):
        z_ref, sr = gs.touch_height(pairs[f"two-point {dy}"])
        z, c = gs.touch_point(pairs[f"two-point {dy}"], step=gs.TOUCH_STEP)
        assert abs(z - z_ref) <= 1e-9 and abs(c.s_w - sr.contacts[0].s_w) < 1e-6
        s_w[dy] = c.s_w
    assert abs(s_w["-1e-05"] - s_w["+1e-05"]) > 5.0


def test_touch_point_height_touches_the_fine_locus():
    """At the height found, no locus sample (every 0.05 mm of wheel profile) overlaps the rail and
    the nearest lies within the sampling's resolution of it (an independent check of the height:
    the locus is not the coarse one the search used)."""
    for name, pair in PAIRS:
        z, _ = gs.touch_point(pair, step=gs.TOUCH_STEP)
        gap = gs.pair_locus(pair, gs.RailTop.of(pair.rail), z).gap
        assert -1e-9 < np.nanmin(gap) < 1e-3, name


def test_place_scene_heights_of_the_other_wheel_and_the_lift_check():
    """place_scene's first-touch height and that of a touch-only placement (the lift check) equal
    first_touch on the full locus to rounding; the pair the contact searches use is the full one."""
    for c in CASES[::5]:
        sc = mbench_case_scene(c["inputs"])
        pl = wr.place_scene(sc)
        other = build_pair(sc.geometry, sc.base_dir, side="left", roll=pl.roll)
        z_other = first_touch(other)
        assert pl.z_touch == first_touch(build_pair(sc.geometry, sc.base_dir, roll=pl.roll))   # bitwise
        assert abs(pl.z_first - min(pl.z_touch, z_other)) <= 1e-9
        lift = wr.place_scene(sc.with_("geometry.lateral_shift", c["inputs"]["Y_WS_mm"] - 0.1), touch_only=True, like=pl)
        ref = first_touch(build_pair(sc.geometry, sc.base_dir, roll=pl.roll, lateral_shift=c["inputs"]["Y_WS_mm"] - 0.1))
        assert abs(lift.z_touch - ref) <= 1e-9


def test_locus_sample_range_as_a_slice():
    """The contiguous samples of a locus that can lie over the rail are read through a slice, other
    index sets as they are: the same elements either way."""
    from conformal.geometry.placement import _as_range

    a = np.arange(10.0)
    k = np.array([3, 4, 5, 6])
    assert _as_range(k) == slice(3, 7) and np.array_equal(a[_as_range(k)], a[k])
    gap = np.array([2, 3, 7])
    assert _as_range(gap) is gap and _as_range(gap[:0]).size == 0
    pair = PAIRS[0][1]
    top = gs.RailTop.of(pair.rail)
    span = (top.y_min, top.y_max)
    reach = pair._locus_at_zero(gs.LOCUS_STEP, span)[5]
    assert isinstance(_as_range(np.nonzero(reach)[0]), slice)        # the Manchester wheel: one range
    z_top = pair.rail_top_under_locus(top, gs.LOCUS_STEP, span)
    assert np.array_equal(z_top[reach], top.z_at(pair._locus_at_zero(gs.LOCUS_STEP, span)[2][reach, 1]), equal_nan=True)
    assert np.isnan(z_top[~reach]).all()
