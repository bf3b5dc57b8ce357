"""Manchester contact benchmark A-2.2 (CONTACT examples/mbench_a22_left/right, reference A5), coarse.

The full table (every shift, both wheels, 0.2 mm elements) is studies/manchester_a22.py.
"""

import pytest

from conformal.geometry.patches import find_patches
from conformal.cases.wheelrail import place_scene, problems_from_wheel_rail, solve_wheel_rail
from _paths import CONTACT_CASES, reference_cases
from _scenes import mbench_case_scene

REF = CONTACT_CASES


@pytest.fixture(scope="module")
def ref():
    if not REF.is_file():
        pytest.skip("shared reference data not available")
    return reference_cases()["mbench_a22"]


@pytest.mark.slow
def test_reference_points_at_contacts_wheelset_heights(ref):
    """Given CONTACT's solved wheelset height Z_WS, all 42 contact reference points agree: the
    pen²-weighted centre of the interpenetration (see conformal.geometry.patches) lies within
    0.03 mm of CONTACT's YCP(R) (measured: 0.001 mm on treads, 0.02 mm on flanges), the contact
    angle within 0.004 rad and the approach within 1.5 %."""
    for side in ("right", "left"):
        for case in ref[side]:
            out = case["outputs"]["patches"][0]
            pl = place_scene(mbench_case_scene(case["inputs"], side, theory="hertz"))
            p = find_patches(pl.pair.wheel(case["outputs"]["Z_WS"]), pl.pair.rail, pl.top)[0]
            m = pl.pair.mirror
            label = (side, case["inputs"]["Y_WS_mm"])
            assert m * pl.pair.rail.to_own(p.point[1:])[0] == pytest.approx(out["YCP(R)"], abs=0.03), label
            assert m * p.delta == pytest.approx(out["DELTCP(TR)"], abs=4e-3), label
            assert p.penetration == pytest.approx(out["APPROACH"], rel=0.015), label
            assert p.x_ref == pytest.approx(out["XCP(TR)"], abs=0.1), label


# shifts (index into the 21 cases): tread, the jump between 4.5 and 5 mm, gauge corner, flange
RIGHT = (0, 1, 4, 9, 10, 12, 13, 16, 20)
LEFT = (0, 10, 20)


@pytest.mark.slow
def test_contact_positions_with_own_vertical_balance(ref):
    """Our own wheelset height (vertical load balanced by half-space normal solves on 0.4 mm grids;
    the small vertical share of the tangential forces is left out here): contact positions within
    0.5 mm of CONTACT, the jump from the tread (4.5 mm) to the gauge corner (5 mm) and flange
    contact from 6.5 mm on (|delta| > 1 rad)."""
    pytest.importorskip("conformal.solvers.normal")
    worst = 0.0
    for side, cases in (("right", RIGHT), ("left", LEFT)):
        for k in cases:
            case = ref[side][k]
            out = case["outputs"]["patches"][0]
            probs = problems_from_wheel_rail(mbench_case_scene(case["inputs"], side))
            main = max(probs, key=lambda p: p.normal_force)
            err = abs(main.info["y_rail"] - out["YCP(R)"])
            worst = max(worst, err)
            assert err < 0.5, (side, k, main.info["y_rail"], out["YCP(R)"])
            y = case["inputs"]["Y_WS_mm"]
            if side == "right" and y == 4.5:
                assert main.info["y_rail"] > -25.0
            if side == "right" and y == 5.0:
                assert main.info["y_rail"] < -30.0
            if side == "right" and y >= 6.5:
                assert main.info["contact_angle"] < -0.79
    assert worst < 0.35     # measured 0.33 mm at 5 mm (two lobes, see the study), else <= 0.03 mm


# Force metric against CONTACT (also studies/manchester_a22.py):
#   |F - F_CONTACT| <= max(1 % |F_CONTACT|, 0.002 mu FN_CONTACT).
# A relative error alone means nothing for forces near zero: FX = 0.28 N at y_ws = 0 is the balance
# of xi against the lateral spin term, and a creepage 1.35e-6 off (a rolling radius 0.6 um off)
# moves it by 5 N; the floor 0.002 mu FN = 6 N is of that size.  The 1 % covers CONTACT's 4-digit
# print and, in flange contact, our reference normal 0.0032 rad off CONTACT's (0.4 % in FN and
# FS, measured).  The brief's looser max(3 %, 0.01 mu FN) would have passed the 3.2 % FX error at
# 0.5 mm that the wheel material point of the creepages caused before Patch.creep_point.
# Measured over all 42 cases (0.2 mm elements): largest error / tolerance 0.45 (right 6.5 mm),
# except FX at right 5.0 mm (below).
REL_TOL, MU_FN_TOL = 0.01, 0.002
# right 5.0 mm: CONTACT merges a gauge-corner and a tread lobe 6.8 mm apart along the profile into
# one patch.  Geometry and creepages agree at CONTACT's height, but our planar half-space patch puts
# 1100 N on the tread lobe (whose rigid slip xi - phi y has the opposite sign), CONTACT about 1300 N:
# FX -798 N vs -763 N (0.012 mu FN).  A 1 um deeper tread lobe would close it; solving the lobes
# without elastic interaction gives -741 N: CONTACT lies between.  Allowed: 0.015 mu FN.
MU_FN_TOL_TWO_LOBES = 0.015
# tread (0, 0.5, 2, 10 mm right; 0.5, 10 left), two lobes (5), gauge corner (5.5), flange (6.5, 10)
FORCE_CASES = (("right", 0), ("right", 1), ("right", 4), ("right", 10), ("right", 11), ("right", 13),
               ("right", 20), ("left", 1), ("left", 13), ("left", 20))


@pytest.mark.slow
def test_forces_with_the_exact_solver(ref):
    """Exact half-space theory on CONTACT's 0.2 mm planar grids, own vertical balance (normal and
    tangential forces): FN, FX, FS per patch against CONTACT with the metric above (about 8 s)."""
    pytest.importorskip("conformal.solvers.tangential")
    for side, k in FORCE_CASES:
        case = ref[side][k]
        out = case["outputs"]["patches"][0]
        sc = mbench_case_scene(case["inputs"], side, element_size=0.2)
        r = solve_wheel_rail(sc)
        assert r.converged and len(r.patches) == 1, (side, k)
        main = r.patches[0]
        label = (side, case["inputs"]["Y_WS_mm"])
        two_lobes = side == "right" and k == 10
        assert r.extra["FZ_track"] == pytest.approx(10000.0, rel=1e-3)
        # positions: 0.02 mm measured (0.13 mm at 5 mm, where the combined reference point moves
        # 0.13 mm for a 0.8 um lower wheelset)
        assert main.extra["y_rail"] == pytest.approx(out["YCP(R)"], abs=0.2 if two_lobes else 0.03), label
        mu_fn = sc.friction.mu * out["FN"]
        for ours, theirs, name in ((main.FN, out["FN"], "FN"), (main.FX, out["FX"], "FX"),
                                   (main.FY, out["FS"], "FS")):
            tol = max(REL_TOL * abs(theirs), MU_FN_TOL * mu_fn)
            if two_lobes and name == "FX":
                tol = MU_FN_TOL_TWO_LOBES * mu_fn
            assert abs(ours - theirs) <= tol, (label, name, ours, theirs, tol)
