"""The one-patch vertical balance of a sweep (seed Eq. 46, the height as the unknown) with fewer
solves: a loose first pass, one settling normal solve, the neighbour's FS/FN across a contact
jump, the lobes of a two-lobe patch searched at their Hertz height.  Each is checked against an
independent path: the passes all solved to ``[model] tol``, and the general balance run cold
with the force and height tolerances 1e-8 W and 1e-7 mm (tests/_scenes.tight_general_balance),
on the Manchester A-2.2 wheel (S1002 on UIC60 1:40, CONTACT's yaw, roll and pitch velocity)."""
from __future__ import annotations

import json

import conformal.cases.wheelrail as wr
from _paths import CONTACT_CASES
from _scenes import mbench_case_scene, tight_general_balance

CASES = json.loads(CONTACT_CASES.read_text())["cases"]["mbench_a22"]["right"]
W = 10000.0


def mbench_case(y, element_size=0.2):
    return mbench_case_scene(next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == y),
                             element_size=element_size)


def sweep(shifts):
    """The results of a warm-started sweep over ``shifts`` and the last warm start."""
    warm, out = None, []
    for y in shifts:
        r = wr.solve_wheel_rail(mbench_case(y), warm=warm)
        warm = wr.WarmStart.from_result(r, warm)
        out.append(r)
    return out, warm


def test_loose_first_pass_gives_the_answers_of_tight_passes(monkeypatch):
    """The first pass of a position solved to FIRST_PASS_TOL (1e-4) and never taken as the answer:
    the forces of passes all solved to 1e-6 within 0.05 N (measured 1e-5 N on the tread at 3 mm,
    0.034 N at most over the 21 positions of the sequence; the balance itself is 1e-5 W = 0.1 N),
    the vertical force within ONE_PATCH_TOL, and the loose pass is not the last."""
    tols = []
    solve = wr.solve_problem

    def recorded(problem):
        tols.append(problem.model.tol)
        return solve(problem)

    monkeypatch.setattr(wr, "solve_problem", recorded)
    loose, _ = sweep((2.5, 3.0))
    n = loose[-1].extra["balance"]["tangential_solves"]
    assert tols[-n] == wr.FIRST_PASS_TOL == 1e-4 and tols[-1] == 1e-6
    monkeypatch.setattr(wr, "FIRST_PASS_TOL", 1e-6)
    tight, _ = sweep((2.5, 3.0))
    a, b = loose[-1], tight[-1]
    assert a.extra["balance"]["tangential_solves"] >= 2
    assert abs(a.extra["FZ_track"] - W) <= wr.ONE_PATCH_TOL * W
    for k in ("FN", "FX", "FY"):
        assert abs(getattr(a, k) - getattr(b, k)) <= 0.05, k
    assert a.patches[0].converged


def test_two_lobe_patch_after_one_patch_costs_one_settling_normal_solve():
    """At 5 mm the neighbour's height finds the two lobes of the coming two-lobe patch: searched
    again at their Hertz height they join, one normal solve settles the height (the reference
    point moves about 180 mm per mm of lowering), two contact solves (before: 5 searches, 10 normal
    and 4 contact solves).  The answers against the tight general balance: FN and FS within
    5e-5 W, FX within 1e-4 W, the height within 5e-5 mm (measured 4e-6 W, 1e-6 W and 5e-7 mm)."""
    (_, r), _ = sweep((4.5, 5.0))
    b = r.extra["balance"]
    assert b["one_patch_passes"] and len(r.patches) == 1 and r.patches[0].extra["n_lobes"] == 2
    assert b["searches"] <= 3 and b["normal_solves"] <= 2 and b["tangential_solves"] <= 2
    ref, z = tight_general_balance(mbench_case(5.0))
    assert abs(r.FN - ref.FN) <= 5e-5 * W
    assert abs(r.FY - ref.FY) <= 5e-5 * W
    assert abs(r.FX - ref.FX) <= 1e-4 * W
    assert abs(r.extra["z_ws"] - z) <= 5e-5


def test_cold_one_patch_start_settles_with_one_normal_solve():
    """Without a neighbour (0 mm, the wide tread patch): the Hertz-like estimate, one normal solve
    and a search set the height of the first contact solve (the general balance's second normal
    solve only confirmed a step of 1e-6 mm); the answers against the tight general balance as in
    the sweep test (measured 1e-7 W in FN, 3e-6 W in FS, 1e-6 mm)."""
    sc = mbench_case(0.0)
    r = wr.solve_wheel_rail(sc)
    b = r.extra["balance"]
    assert b["one_patch_passes"] and b["normal_solves"] == 1 and b["tangential_solves"] == 2
    ref, z = tight_general_balance(sc)
    assert abs(r.FN - ref.FN) <= 5e-5 * W
    assert abs(r.FY - ref.FY) <= 5e-5 * W
    assert abs(r.FX - ref.FX) <= 1e-4 * W
    assert abs(r.extra["z_ws"] - z) <= 5e-5


def test_contact_jump_leaves_no_slope_and_keeps_the_ratio():
    """Across the jump onto the flange (6 -> 6.5 mm: the reference point moves 9.7 mm along the
    rail, the lowering triples) the warm start keeps the neighbour's FS/FN for the new patch
    (within 0.02 of the balanced -0.270; 0 had given FN 60 % off) and extrapolates neither the
    lowering nor the ratio; where the lobes change (5 -> 5.5 mm) not the lowering; on the tread
    (2.5 -> 3 mm) both."""
    (_, r65), warm = sweep((6.0, 6.5))
    assert warm.lowering_slope == 0.0 and warm.ratio_slopes == (0.0,)
    (_, r3), warm3 = sweep((2.5, 3.0))
    assert warm3.lowering_slope != 0.0 and warm3.ratio_slopes[0] != 0.0
    # the two-lobe patch at 5 mm becomes one lobe at 5.5 mm: the shape changed, no slope either
    # (the slope of 5 -> 5.5 mm put the first search at 6 mm 2.9e-3 mm off, without it 1.2e-3)
    (r5, r55), warm55 = sweep((5.0, 5.5))
    assert r5.patches[0].extra["n_lobes"] == 2 and r55.patches[0].extra["n_lobes"] == 1
    assert warm55.lowering_slope == 0.0 and warm55.ratio_slopes[0] != 0.0
    ref, z = tight_general_balance(mbench_case(6.5))
    assert abs(r65.FN - ref.FN) <= 5e-5 * W
    assert abs(r65.FY - ref.FY) <= 5e-5 * W
    assert abs(r65.extra["z_ws"] - z) <= 5e-5
    start = wr.WarmStart.from_result(r65)
    assert abs(start.ratios[0][1] - (-0.270)) < 0.02


def test_pass_after_a_search_takes_the_searched_contact_angle():
    """After a pass searches the geometry again, the next normal force W / (cos d + r sin d) takes
    the contact angle d of the new geometry: at 0.5 mm (the wide tread patch, whose contact angle
    moves 1.2e-4 rad between the first pass's geometry and the next) the pass after the search
    balances (FZ 2.0e-6 W off, with the previous angle 2.1e-5 W and a third contact solve).  The
    answers against the tight general balance as in the sweep tests (measured 2e-6 W in FN,
    5e-7 W in FS, 4e-7 mm)."""
    (_, r), _ = sweep((0.0, 0.5))
    b = r.extra["balance"]
    assert b["one_patch_passes"] and b["tangential_solves"] == 2 and b["searches"] == 3
    assert abs(r.extra["FZ_track"] - W) <= wr.ONE_PATCH_TOL * W
    ref, z = tight_general_balance(mbench_case(0.5))
    assert abs(r.FN - ref.FN) <= 5e-5 * W
    assert abs(r.FY - ref.FY) <= 5e-5 * W
    assert abs(r.FX - ref.FX) <= 1e-4 * W
    assert abs(r.extra["z_ws"] - z) <= 5e-5
