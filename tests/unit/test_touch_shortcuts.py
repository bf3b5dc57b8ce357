"""The touching height without the searches the sampled locus rules out, against the full search it
replaces: Newton-Raphson only from the locus minimum that can touch first (search.find_contacts
``deepest_only``, the main wheel of place_scene), the bounds of the sampled locus alone
(search.touch_bounds: the other wheel of a wheelset that touches later, the lift check's neighbour),
on the Manchester A-2.2 positions of both wheels, a sweep across the tread -> flange switch between
4.5 and 5 mm, the flange-climbing jump near 6.2 mm and its two-point contact."""
import json

import numpy as np
import pytest

from conformal.cases import wheelrail as wr
from conformal.geometry import search as gs
from conformal.geometry.wheelrail import build_pair, first_touch, touches_after
from _paths import CONTACT_CASES
from _scenes import mbench_case_pairs, mbench_case_scene

CASES = json.loads(CONTACT_CASES.read_text())["cases"]["mbench_a22"]["right"]
TWO_POINT = 6.2250108253756      # tread and flange touch at the same height (tests/unit/test_touch_point.py)


def _case(y):
    return mbench_case_scene(next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == y))


def _pairs():
    yield from mbench_case_pairs(CASES)
    # tread -> flange root (4.5 .. 5 mm) and the flange climbing onto the rail (6 .. 6.5 mm), every 0.05 mm
    for y0, ys in ((5.0, np.arange(4.5, 5.025, 0.05)), (6.0, np.arange(6.0, 6.525, 0.05))):
        geo, base = _case(y0).geometry, _case(y0).base_dir
        for y in ys:
            yield f"sweep {y:.2f}", build_pair(geo, base, roll=geo.roll, lateral_shift=float(y))
    sc = _case(6.0)
    for dy in (0.0, -1e-5, 1e-5):
        yield f"two-point {dy:+g}", build_pair(sc.geometry, sc.base_dir, roll=sc.geometry.roll,
                                               lateral_shift=TWO_POINT + dy)


PAIRS = list(_pairs())


@pytest.fixture(scope="module")
def searched():
    """(name, pair, z, search) of the full search per trial height, every candidate refined."""
    return [(name, pair, *gs.touch_height(pair)) for name, pair in PAIRS]


def test_deepest_only_gives_the_height_and_contact_of_the_full_search(searched):
    """Bitwise the same height and contact point; only the contact that touches is refined where the
    sampled gap rules out the others (tread and flange both within the search window: 0, 4, 4.5 mm,
    the tread -> flange switch, the jump), all of them at the two-point contact (both touch)."""
    fewer, both = [], []
    for name, pair, z_ref, sr_ref in searched:
        z, sr = gs.touch_height(pair, deepest_only=True)
        c, c_ref = sr.contacts[0], sr_ref.contacts[0]
        assert z == z_ref, name
        assert (c.s_w, c.s_r, c.penetration, c.at_end) == (c_ref.s_w, c_ref.s_r, c_ref.penetration, c_ref.at_end), name
        if len(sr_ref.contacts) > 1:
            (fewer if len(sr.contacts) == 1 else both).append(name)
    assert {"right 0", "right 4", "right 4.5", "right 5", "sweep 4.80", "sweep 6.20"} <= set(fewer)
    assert "two-point +0" in both
    # the switch: the contact jumps along the wheel profile (tread 70 .. 73 mm, flange root 60 .. 62 mm)
    s_w = {name: sr.contacts[0].s_w for name, _, _, sr in searched}
    assert s_w["sweep 4.50"] > 70.0 and s_w["sweep 5.00"] < 62.0 and s_w["sweep 6.00"] - s_w["sweep 6.50"] > 10.0


@pytest.mark.parametrize("step", [gs.LOCUS_STEP, gs.TOUCH_STEP])
def test_touch_point_takes_the_same_contact(searched, monkeypatch, step):
    """search.touch_point refines the same candidate, its height within 1e-9 mm of the search per
    trial height (measured <= 3.4e-13 mm): Newton-Raphson from the one locus sample that can touch
    first without a global search (find_contacts) wherever the sampled gap shows it, with one at
    the two-point contact."""
    calls = []
    find = gs.find_contacts
    monkeypatch.setattr(gs, "find_contacts", lambda *a, **k: calls.append(1) or find(*a, **k))
    searched_globally = []
    for name, pair, z_ref, sr_ref in searched:
        n = len(calls)
        z, c = gs.touch_point(pair, step=step)
        assert abs(z - z_ref) <= 1e-9 and abs(c.s_w - sr_ref.contacts[0].s_w) < 1e-6, name
        if len(calls) > n:
            searched_globally.append(name)
    assert "two-point +0" in searched_globally and len(searched_globally) <= 3


def test_touch_bounds_bracket_the_height(searched):
    """The sampled locus's bounds hold the searched height, within 5e-3 mm of it on the flange
    (steep rail top: its chords' error) and 1e-4 mm on the tread."""
    for name, pair, z, sr in searched:
        lo, hi, clear = gs.touch_bounds(pair, step=gs.TOUCH_STEP)
        assert lo <= z <= hi and clear, name
        assert hi - lo < (1e-4 if abs(sr.contacts[0].delta) < 0.2 else 5e-3), name


def test_coarse_bounds_of_the_other_wheel_hold_the_height(searched, monkeypatch):
    """The bounds of the locus sampled every AFTER_STEP mm (touches_after's first look) hold the
    searched height on every pair (tread, flange, the switch, the jump, the two-point contact);
    touches_after decides as the TOUCH_STEP bounds alone do on the Manchester left wheels (True at
    0.5 .. 10 mm), there from the coarse locus alone (no TOUCH_STEP locus sampled)."""
    from conformal.geometry import wheelrail as gw
    for name, pair, z, _ in searched:
        lo, hi, clear = gs.touch_bounds(pair, step=gw.AFTER_STEP)
        assert lo <= z <= hi and clear, name
    z = {name: z for name, _, z, _ in searched}
    pairs = dict(PAIRS)
    steps = []
    bounds = gs.touch_bounds
    monkeypatch.setattr(gw, "touch_bounds", lambda *a, **k: steps.append(k["step"]) or bounds(*a, **k))
    for c in CASES:
        y = c["inputs"]["Y_WS_mm"]
        left, z_r = pairs[f"left {y:g}"], z[f"right {y:g}"]
        n = len(steps)
        lo, _, clear = bounds(left, step=gs.TOUCH_STEP)
        assert touches_after(left, z_r) == (clear and lo > z_r + 1e-9), y
        assert steps[n:] == ([gw.AFTER_STEP, gs.TOUCH_STEP] if y == 0.0 else [gw.AFTER_STEP]), y


def test_the_other_wheel_is_searched_only_where_it_can_touch_first(searched):
    """touches_after is True only where the searched height of the other wheel lies below the
    right wheel's (0.0017 mm and more on the Manchester positions 0.5 .. 10 mm), False at 0 mm (both
    touch at the same height: CONTACT's roll); place_scene's heights are bitwise those of the search
    per trial height (z_touch) and of touch_point (the other wheel)."""
    z = {name: z for name, _, z, _ in searched}
    pairs = dict(PAIRS)
    skipped = []
    for c in CASES:
        y = c["inputs"]["Y_WS_mm"]
        z_r, z_l = z[f"right {y:g}"], z[f"left {y:g}"]
        if touches_after(pairs[f"left {y:g}"], z_r):
            assert z_l > z_r, y
            skipped.append(y)
    assert 0.0 not in skipped and len(skipped) == len(CASES) - 1
    for c in CASES[::4]:
        sc = mbench_case_scene(c["inputs"])
        pl = wr.place_scene(sc)
        y = c["inputs"]["Y_WS_mm"]
        z_other = first_touch(build_pair(sc.geometry, sc.base_dir, side="left", roll=pl.roll), step=gs.TOUCH_STEP)
        assert pl.z_touch == z[f"right {y:g}"] and pl.z_first == min(pl.z_touch, z_other)      # bitwise


def test_lift_check_bounds_the_neighbour_and_finds_the_jump():
    """The lift check's neighbour 0.1 mm back: the bounds of the wheel's locus moved by 0.1 mm hold
    its searched height; where they leave it within JUMP_WARN of the wheel's, the searched height is
    there too (the flange positions 6.5 .. 10 mm: 0.2 .. 0.7 mm apart); 1 mm back (5.5 mm on the roll of 6.5 mm, the flange contact 2.9 mm higher) the bounds
    cannot tell and the height is searched: the difference of the search.  A wheelset whose roll is
    found per shift jumps onto its flange tip (the worn pair at 15.55 mm: 12 mm): the warning says so."""
    for c in CASES:
        y = c["inputs"]["Y_WS_mm"]
        if y < 6.5:
            continue
        sc = mbench_case_scene(c["inputs"])
        pl = wr.place_scene(sc)
        assert -pl.z_touch > wr.LIFT_WARN
        z_back = first_touch(build_pair(sc.geometry, sc.base_dir, roll=pl.roll, lateral_shift=y - 0.1))
        lo, hi, _ = gs.touch_bounds(pl.pair, pl.top, dy=-0.1)      # pl's locus moved back by 0.1 mm
        assert lo <= z_back <= hi and hi - lo < 5e-3, y
        ref = pl.z_touch - z_back
        assert wr._height_jump(sc, pl, -0.1) is None and 0.1 < abs(ref) <= wr.JUMP_WARN, y
        if y == 6.5:
            ref = pl.z_touch - first_touch(build_pair(sc.geometry, sc.base_dir, roll=pl.roll, lateral_shift=y - 1.0))
            jump = wr._height_jump(sc, pl, -1.0)
            assert ref < -2.0 and abs(jump - ref) <= 1e-9
            with pytest.raises(ValueError):
                gs.touch_bounds(pl.pair, pl.top, dy=-1.0)
    from test_worn_placement import worn

    sc = worn(15.55)
    pl = wr.place_scene(sc)
    st = wr.state_at(pl.pair, pl.top, pl.z_touch + 0.01, pl.roll, sc, grids=False)
    msg = [w for w in wr.placement_warnings(sc, pl, st) if "above its nominal height" in w]
    assert len(msg) == 1 and "mm higher than at 0.1 mm less lateral shift: the height jumps" in msg[0]
