"""The one-patch balance keeps a searched geometry while the height moves (seed Eq. 46 with the
height as the unknown): each element's undeformed distance moves at its own rate
(``conformal.cases.wheelrail.gap_rate``), the creep point follows the penetration, and the
reference point's rate along the rail profile (``Patch.s_ref_rate``) decides when the geometry must
be searched again.  Each is checked against the geometry searched afresh at the other height (the
independent method: the true profiles intersected again), on the Manchester A-2.2 wheel (S1002 on
UIC60 1:40, CONTACT's yaw, roll and pitch velocity per case)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

import conformal.cases.wheelrail as wr
from conformal.geometry.patches import planar_distance
from conformal.models import solve_problem
from _paths import CONTACT_CASES
from _scenes import mbench_case_scene, tight_general_balance

CASES = json.loads(CONTACT_CASES.read_text())["cases"]["mbench_a22"]["right"]


def mbench_case(y, element_size=0.2):
    return mbench_case_scene(next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == y),
                             element_size=element_size)


def _state(y, lowering, element_size=0.2):
    sc = mbench_case(y, element_size)
    pl = wr.place_scene(sc)
    return sc, pl, wr.state_at(pl.pair, pl.top, pl.z_touch + lowering, pl.roll, sc)


@pytest.mark.parametrize("y, lowering", [(5.0, 0.03), (8.0, 0.06), (0.0, 0.02)])
def test_gap_rate_equals_the_distance_searched_at_another_height(y, lowering):
    """gap_rate against the distances of the same patch frame and grid with the wheel lowered by
    1e-3 mm (planar_distance of the moved wheel, a finite difference): within 5e-4 of the rate over
    the elements within 0.02 mm of contact (measured 2.2e-4 on the two-lobe patch at 5 mm, where
    the rate spans -1.010 .. -0.942; 1.9e-5 on the flange at 8 mm, 1.6e-5 on the tread at 0 mm, the
    error of the centred difference along eta).  The uniform rate -cos(delta) the balance used
    before is off by 5.1 % and 3.8 % on the first two: the check tells them apart."""
    sc, pl, st = _state(y, lowering)
    pg = st.patches[0]
    X, Y = pg.grid.mesh()
    eps = 1e-3
    z = st.z
    d0 = planar_distance(pl.pair.wheel(z), pl.pair.rail, pg.patch, X, Y)
    d1 = planar_distance(pl.pair.wheel(z + eps), pl.pair.rail, pg.patch, X, Y)
    fd = (d1 - d0) / eps
    near = d0 < 0.02            # overlapping or within 0.02 mm of contact
    rate = wr.gap_rate(pl.pair, pg)
    assert np.abs(rate - fd)[near].max() < 5e-4
    uniform = np.abs(-math.cos(pg.patch.delta) - fd)[near].max()
    if y != 0.0:
        assert uniform > 0.03


@pytest.mark.parametrize("y, lowering", [(0.5, 0.0196), (3.0, 0.0245), (8.0, 0.0604)])
def test_reference_point_rate_equals_the_searched_one(y, lowering):
    """Patch.s_ref_rate (from the locus samples: each overlap grows by dz cos(delta_i), each rail
    point moves by dz sin(delta_i)) against the reference points searched 1e-4 mm above and below:
    within 3 % of it plus 0.02 (measured 224.33 vs 224.34 mm/mm on the wide tread patch at 0.5 mm,
    -1.235 vs -1.235 at 3 mm, -0.384 vs -0.387 on the flange at 8 mm)."""
    sc = mbench_case(y)
    pl = wr.place_scene(sc)
    s = [wr.state_at(pl.pair, pl.top, pl.z_touch + lowering + e, pl.roll, sc).patches[0].patch for e in (-1e-4, 0, 1e-4)]
    fd = (s[2].s_ref - s[0].s_ref) / 2e-4
    assert s[1].s_ref_rate == pytest.approx(fd, rel=0.03, abs=0.02)


def test_kept_geometry_gives_the_forces_of_a_fresh_search():
    """A geometry searched 2e-3 mm (GEOMETRY_KEEP) below the height of a solved position and
    raised back by PairState.lowered gives the forces of the geometry searched at that height, for
    the same normal force (tread, 3 mm shift): FX within 0.1 N and FS within 0.02 N (measured 0.024
    and 0.004 N), the height of the balance within 1e-5 mm (2.9e-6).  With the old uniform lowering
    and the creep point left where it was searched, FX moved by 1.7 N: the test tells them apart."""
    from dataclasses import replace

    sc, pl, fresh = _state(3.0, 0.0245)
    fn = 9774.0
    ref = solve_problem(wr.problems_at(sc, pl, fresh, [fn])[0])
    kept_st = wr.state_at(pl.pair, pl.top, fresh.z + 2e-3, pl.roll, sc).lowered(-2e-3)
    kept = solve_problem(wr.problems_at(sc, pl, kept_st, [fn])[0])
    assert abs(kept.FX - ref.FX) < 0.1 and abs(kept.FY - ref.FY) < 0.02
    # the balance's height from the kept geometry: within 1e-5 mm of the fresh one's
    c = math.cos(fresh.patches[0].patch.delta)
    z_kept = kept_st.z + (kept.approach - kept_st.patches[0].approach) / c
    z_ref = fresh.z + (ref.approach - fresh.patches[0].approach) / c
    assert abs(z_kept - z_ref) < 1e-5
    # the old lowering: uniform dz cos(delta), creep point not moved
    searched = wr.state_at(pl.pair, pl.top, fresh.z + 2e-3, pl.roll, sc)
    pg = searched.patches[0]
    old = replace(searched, z=fresh.z, z_geometry=searched.z,
                  patches=[replace(pg, approach=pg.approach - 2e-3 * c)])
    stale = solve_problem(wr.problems_at(sc, pl, old, [fn])[0])
    assert abs(stale.FX - ref.FX) > 1.0


def test_sweep_keeps_the_geometry_and_balances():
    """Two neighbouring tread positions as a sweep (0.2 mm elements): the second position needs one
    geometry search and at most two contact solves (no normal solve), balanced within 1e-5 W."""
    W = 10000.0
    warm = None
    for y in (2.5, 3.0, 3.5):
        r = wr.solve_wheel_rail(mbench_case(y), warm=warm)
        warm = wr.WarmStart.from_result(r, warm)
    b = r.extra["balance"]
    assert b["one_patch_passes"] and b["searches"] == 1 and b["normal_solves"] == 0
    assert b["tangential_solves"] <= 2
    assert abs(r.extra["FZ_track"] - W) <= 1e-5 * W


def test_fast_moving_reference_point_is_settled_and_searched_again():
    """At 0.5 mm the wide tread patch's reference point moves about 225 mm per mm of lowering: the
    sweep keeps its geometry over about 2e-5 mm only (REFERENCE_KEEP), so normal solves set the
    height before the contact solves (SETTLE_BELOW), and FX lands within 0.2 N of the general
    balance run cold to 1e-8 W with its geometry searched at the balanced height (measured 0.003 N;
    keeping that geometry over 2e-3 mm had moved FX by 7.6 N)."""
    warm = None
    for y in (0.0, 0.5):
        sc = mbench_case(y)
        r = wr.solve_wheel_rail(sc, warm=warm)
        warm = wr.WarmStart.from_result(r, warm)
    b = r.extra["balance"]
    assert b["one_patch_passes"] and b["normal_solves"] >= 1 and b["searches"] >= 2
    ref, _ = tight_general_balance(sc)
    assert abs(r.FX - ref.FX) < 0.2 and abs(r.FN - ref.FN) < 0.5
