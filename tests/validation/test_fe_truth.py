"""The FE contact ground truth: whole rail and wheel sections clamped far away (issue 20, items 3-4)."""
from __future__ import annotations

import sys

import numpy as np
import pytest

from conformal.errors import InputError
from conformal.fe_contact.problems import settings_from_options
from conformal.geometry.profiles import load_profile
from conformal.geometry.sections import (UIC60_AREA, UIC60_CENTROID, UIC60_I, block_section, section_properties,
                                         uic60_section, wheel_rim_section)
from _paths import ROOT



def test_uic60_section_has_the_published_60e1_properties():
    """EN 13674-1 publishes 76.70 cm², 80.9 mm and 3038.3 cm⁴ for 60E1; the simplified section
    (no fillets, one foot slope) must reproduce them within 1 %, and its main dimensions exactly."""
    sec = uic60_section(load_profile("UIC60", "rail").points)
    A, zc, I = section_properties(sec.points)
    assert abs(A / UIC60_AREA - 1) < 0.01
    assert abs((172.0 - zc) / UIC60_CENTROID - 1) < 0.01
    assert abs(I / UIC60_I - 1) < 0.01
    P = sec.points
    assert P[:, 1].max() == pytest.approx(172.0) and P[:, 1].min() == pytest.approx(0.0, abs=1e-6)
    assert np.ptp(P[:, 0]) == pytest.approx(150.0)
    web = P[(P[:, 1] > 40) & (P[:, 1] < 150) & (np.abs(P[:, 0]) < 20)]       # the web's four corners
    assert len(web) == 4 and np.ptp(web[:, 0]) == pytest.approx(16.5)
    # the clamped edge is the foot's lower face
    i = sec.clamped[0]
    assert P[i, 1] == pytest.approx(172.0) and P[(i + 1) % len(P), 1] == pytest.approx(172.0)


def test_wheel_rim_section_dimensions():
    prof = load_profile("S1002", "wheel").points
    sec = wheel_rim_section(prof, 460.0)
    P = sec.points
    assert np.ptp(P[:, 0]) == pytest.approx(135.0)
    assert sec.hub_z == pytest.approx(125.0 - 460.0)
    i = sec.clamped[0]
    assert P[i, 1] == pytest.approx(sec.hub_z) and P[(i + 1) % len(P), 1] == pytest.approx(sec.hub_z)
    np.testing.assert_allclose(sec.profile, prof)
    with pytest.raises(InputError):
        wheel_rim_section(prof, 460.0, hub_radius=420.0)


def test_block_section_extends_the_profile_and_clamps_only_the_closure():
    rail = np.loadtxt(ROOT / "meshes/scenes/deep_rail_r10.csv", delimiter=",", comments="#")
    sec = block_section(rail, "rail", 100.0)
    P = sec.points
    n = sec.n_profile
    # the gauge face continues 100 mm down, the top 100 mm on; the closing edges are clamped
    assert P[-1] == pytest.approx([-10.0, 140.0]) and P[n] == pytest.approx([130.0, 0.0])
    assert set(sec.clamped) == set(range(n, len(P) - 1))
    for i in sec.clamped:                              # every clamped edge lies >= 100 mm from the profile
        mid = 0.5 * (P[i] + P[(i + 1) % len(P)])
        assert np.min(np.linalg.norm(rail - mid, axis=1)) >= 100.0 - 1e-9
    with pytest.raises(InputError):
        block_section(rail, "rail", -1.0)


def test_section_bodies_are_clamped_far_away_and_never_use_the_halfspace_field():
    mesh, st = settings_from_options({"fec_body": "section"})
    assert mesh.body == "section" and st.far_field == "clamped" and mesh.section_size == 20.0
    assert settings_from_options({"fec_body": "block"})[1].far_field == "clamped"
    assert settings_from_options({})[1].far_field == "halfspace"          # existing default kept
    with pytest.raises(InputError, match="fec_far_field"):
        settings_from_options({"fec_body": "section", "fec_far_field": "halfspace"})
    with pytest.raises(InputError, match="fec_body"):
        settings_from_options({"fec_body": "whole"})
    with pytest.raises(InputError, match="fec_section_size"):
        settings_from_options({"fec_body": "section", "fec_section_size": 0})


@pytest.mark.slow
def test_ground_truth_quick_study_agrees_with_conformal(tmp_path):
    """The quick study (flange root at 6.2 mm, 10 kN; a coarse truth: a / 3, quadratic, the 60E1
    section and the wheel rim + web 10 patch sizes beyond the patch, clamped): at the prescribed
    wheel load conformal contact with half-space numbers meets the issue's targets against it
    (measured: FN -0.4 %, pmax -0.2 %, area +3.0 %; the converged a / 6 truth: docs/validation/ground-truth.md)."""
    sys.path.insert(0, str(ROOT / "studies"))
    import fe_ground_truth as study

    study.main(["--quick", "--out", str(tmp_path)])
    rec = study.build(tmp_path)["scenes"][0]
    t = rec["truth"]
    assert t["mesh1"]["section"] == "60E1 section" and t["mesh2"]["section"] == "wheel rim and web"
    assert t["stats"]["far_field"] == "clamped"
    assert not t["edge"]                                  # the contact lies inside the slave surface
    hs = rec["models"]["conformal half-space"]["err"]
    assert abs(hs["FN"]) < 0.01
    assert abs(hs["pmax"]) < 0.02
    assert abs(hs["area"]) < 0.05
    assert (tmp_path / "ground_truth.md").exists() and (tmp_path / "ground_truth.png").exists()


def test_rigid_fit_recovers_a_rigid_motion():
    """The structure study's rigid fit (translation + small rotation about a centre) is exact for
    a rigid displacement field and leaves a residual where the field is not rigid."""
    sys.path.insert(0, str(ROOT / "studies"))
    from fe_truth_structure import rigid_fit

    rng = np.random.default_rng(1)
    P = rng.uniform(-30, 30, (200, 3))
    c = np.array([1.0, -2.0, 3.0])
    t, w = np.array([0.01, -0.02, 0.005]), np.array([2e-4, -1e-4, 3e-4])
    U = t + np.cross(w, P - c)
    fit = rigid_fit(P, U, c)
    np.testing.assert_allclose(fit["t"], t, atol=1e-12)
    np.testing.assert_allclose(fit["w"], w, atol=1e-12)
    assert fit["rms_residual"] < 1e-12
    U2 = U.copy()
    U2[:, 0] += 1e-3 * P[:, 0] ** 2 / 900.0                     # a non-rigid part
    assert rigid_fit(P, U2, c)["rms_residual"] > 1e-5


@pytest.mark.slow
def test_contact_displacements_close_the_gap():
    """ContactModel.displacements: at every node in contact the recovered displacements of the
    two bodies (body 2's with its rigid approach) close the undeformed gap, n . (u1 - u2) = -g0
    (the solver's own gap equation, recomputed from one more solve per body; body 2 taken at
    its nearest vertex, so within a few µm), and body 2's clamped faces moved by the approach."""
    from scipy.spatial import cKDTree

    from conformal.fe_contact.bodies import sphere_on_block
    from conformal.fe_contact.solver import ContactModel, FEContactSettings, prepare_contact

    b1, b2 = sphere_on_block(50.0, (2.0, 2.0), n=2)
    model = prepare_contact(b1, b2, settings=FEContactSettings(order=1, far_field="clamped"))
    sol = model.solve(approach=0.08)
    u1, u2 = model.displacements(sol)
    i = np.where(sol.active)[0]
    k = cKDTree(b2.points).query(sol.X[i])[1]
    n = sol.normal[i] / np.linalg.norm(sol.normal[i], axis=1, keepdims=True)
    closure = np.einsum("ij,ij->i", n, u1[sol.nodes[i]] - u2[k]) + sol.g0[i]
    assert np.abs(closure).max() < 1e-4 * 0.08 * 10
    assert np.abs(sol.g0[i]).max() > 0.01                        # the check is not trivially zero
    far = np.unique(b2.mesh.clamped_tris)
    np.testing.assert_allclose(u2[far], np.broadcast_to(sol.approach * sol.direction, (far.size, 3)), atol=1e-12)
    with pytest.raises(InputError):
        ContactModel(None, {}).displacements(sol)               # a model without the fields


@pytest.mark.slow
def test_conformal_meets_the_section_truth_at_the_same_lateral_load():
    """Root + flank at 6.25 mm (S1002 / UIC60, 10 kN): the stored reference truth (60E1 section +
    wheel rim and web, clamped, a / 6, 20 patch sizes; studies/fe_truth_structure.py) and
    conformal contact with half-space numbers.  At the same wheelset shift they differ by 10 % in
    FN and 18 % in pmax, because the truth's rail head moves 13 µm outwards and its rim 6 µm
    inwards (web bending; measured on the truth, away from the contact) and a few µm decide this
    contact (2 µm: > 2 % in pmax).  At the same vertical AND lateral load (L/V of the normal
    forces; the shift is then an output, like the approach) the contact model meets the issue's
    targets in pmax (2 %) and the load split on the flank (2 percentage points), not quite in the
    contact area (5 %): measured with the corrected coupling sense of the turned frames -0.1 %,
    +6.2 %, +1.4 points; FN +1.1 % (before that correction: -0.7 %, +4.1 %, +1.2; FN -0.6 %)."""
    import json

    sys.path.insert(0, str(ROOT / "studies"))
    import fe_ground_truth as gt
    import fe_truth_structure as fts

    from conformal.cases.conformal import curved_problem_from_wheel_rail

    rec = json.loads((ROOT / "studies/out/fe_truth_structure/parts/flange_y6.25.json").read_text())
    t = rec["truth"]
    assert t["options"] == gt.TRUTH and rec["wheel_load"] == 10000.0
    ck = t["checks"]
    assert abs(ck["F_load"] / ck["wheel_load"] - 1) < 1e-6 and ck["rail"]["elsewhere"] == ck["wheel"]["elsewhere"] == 0
    fit = t["fits"]["R20"]
    assert fit["rail_head_lateral"] > 0.005 and fit["wheel_rim_lateral"] < -0.002   # outwards / inwards
    scene = dict(gt.scenes(False))["flange_y6.25"]
    grid = curved_problem_from_wheel_rail(scene).grid
    lv, flank = gt.normal_lv(t, grid), gt.share(t, gt.flank_boundary(grid))
    m = fts.match_lv(scene, lv, lo=-0.03, hi=0.0)
    assert abs(m["pmax"] / t["pmax"] - 1) < 0.02
    # the area misses the 5 % (+6.2 % since the coupling sense of the turned frames was
    # corrected; +4.1 % before): bounded here at the measured value plus the truth's own remeshing
    # scatter (area +2.4 % on a rerun), and reported as a miss
    assert abs(m["area"] / t["area"] - 1) < 0.07
    assert abs(m["flank_share"] - flank) < 0.02
    assert abs(m["FN"] / t["FN"] - 1) < 0.015
    assert -0.025 < m["dy"] < -0.005                  # 5-25 µm less flange than the nominal shift
    # at the prescribed shift the same model misses, and 2 µm of shift alone move pmax by > 2 %
    hs, hs2 = fts.conformal_at(scene), fts.conformal_at(scene, -0.002)
    assert hs["pmax"] / t["pmax"] - 1 < -0.10 and hs["area"] / t["area"] - 1 > 0.3
    assert abs(hs2["pmax"] / hs["pmax"] - 1) > 0.02


@pytest.mark.slow
def test_prescribed_lateral_force_moves_the_wheel_rigidly():
    """ContactModel.solve with a prescribed lateral force (a second rigid motion s of the wheel
    along e, across the load direction): given the lateral force of the solution at the nominal
    position it returns that solution (s = 0); given 5 % more, both resultants hold exactly and the
    wheel moves towards the flange (s > 0), by micrometres (coarse flange scene at 6.2 mm, 10 kN)."""
    from conformal.cases.fe_contact import load_direction, run_wheel_rail
    from conformal.scene import load_scene

    sys.path.insert(0, str(ROOT / "studies"))
    from fe_truth_convergence import lateral_direction

    scene = load_scene(ROOT / "meshes/scenes/flange_s1002_uic60.toml")
    scene = scene.with_model(theory="fe_contact", options={"fec_n": 2, "fec_order": 1, "fec_far_field": "clamped"})
    run, prob = run_wheel_rail(scene)
    d = load_direction(prob.grid)
    e = lateral_direction(d)
    assert abs(e @ d) < 1e-12 and e[1] > 0
    s0 = run.solution
    f0 = float(s0.force_vector @ e)
    assert f0 > 3000.0                                 # the flange root pushes the rail outwards
    same = run.model.solve(normal_force=prob.normal_force, shift_direction=e, shift_force=f0,
                           approach_guess=s0.approach)
    assert abs(same.shift) < 1e-7 and abs(same.approach - s0.approach) < 1e-7
    np.testing.assert_allclose(same.force, s0.force, rtol=1e-6, atol=1e-9 * s0.FN)
    more = run.model.solve(normal_force=prob.normal_force, shift_direction=e, shift_force=1.05 * f0,
                           approach_guess=s0.approach)
    assert abs(more.F_load - prob.normal_force) < 1e-9 * prob.normal_force
    assert abs(more.force_vector @ e - 1.05 * f0) < 1e-9 * f0
    assert 1e-4 < more.shift < 0.05
    with pytest.raises(InputError):
        run.model.solve(approach=0.01, shift_direction=e, shift_force=f0)


def _convergence() -> dict:
    import json

    path = ROOT / "studies/out/fe_truth_convergence/convergence.json"
    return {r["scene"]: r for r in json.loads(path.read_text())["scenes"]}


def test_truth_series_carry_the_prescribed_loads():
    """Every truth mesh of studies/fe_truth_convergence.py was solved again at the prescribed
    vertical AND lateral load (the reference mesh's lateral force): both resultants hold to
    rounding, and on the reference mesh that solve is the nominal one (shift 0)."""
    for name, rec in _convergence().items():
        T = rec["truths"]
        ref = T["reference"]
        if "from" in ref:          # a stored reference (nominal position only)
            continue
        assert abs(ref["loaded"]["shift"]) < 1e-6
        assert abs(ref["loaded"]["FN"] / ref["nominal"]["FN"] - 1) < 1e-6
        for label, r in T.items():
            assert abs(r["loaded"]["F_load"] / rec["wheel_load"] - 1) < 1e-9, (name, label)
            assert abs(r["loaded"]["F_lat"] / ref["F_lat_target"] - 1) < 1e-9, (name, label)
            assert r["loaded"]["area_bounds"][0] <= r["loaded"]["area"] <= r["loaded"]["area_bounds"][1]


def test_deep_pair_reference_is_converged_at_prescribed_loads():
    """The deep pair's reference truth (clamped blocks, quadratic, a / 6, 20 patch sizes) against a
    finer mesh (a / 8) and a larger body (40 patch sizes), each at the same vertical and lateral
    load (studies/fe_truth_convergence.py): FN and pmax within the issue's 0.5 % (measured FN
    0.00 / 0.00 %, pmax +0.46 / -0.25 %), the flank share (spread) within 0.2 points, the contact
    area within 1.5 % (+1.10 / 0.00 %; its two bounds lie +-9 % apart).  A third mesh (a / 10)
    shows pmax still rising by 0.4-0.5 % per step (+0.85 % against a / 6: a miss of the 0.5 %
    between a / 6 and a / 10, recorded with its bound; a / 8 to a / 10 +0.39 %), FN converged."""
    rec = _convergence()["deep_pair"]
    T = rec["truths"]
    c = rec["summary"]["convergence"]
    for label in ("finer mesh", "larger body"):
        d = c[label]["loaded"]
        assert abs(d["FN"]) < 0.005 and abs(d["pmax"]) < 0.005, label
        assert abs(d["flank_share_spread"]) < 0.002 and abs(d["area"]) < 0.015, label
    d = c["finest mesh"]["loaded"]
    assert abs(d["FN"]) < 0.001 and 0.0 < d["pmax"] < 0.01 and abs(d["area"]) < 0.03
    assert abs(T["finest mesh"]["loaded"]["pmax"] / T["finer mesh"]["loaded"]["pmax"] - 1) < 0.005


def test_production_model_meets_the_reference_at_the_same_loads():
    """conformal + FE influence numbers (the package's defaults) at the truth's L/V, against the
    reference truth (studies/fe_truth_convergence.py): the issue's targets pmax 2 %, contact area
    5 %, flank share 2 points, on the deep pair (measured +1.24 %, +1.81 %, -0.16 points; FN +0.63 %),
    at 6.2 mm (+1.30 %, -1.28 %, 0 points (root only); FN +0.34 %) and at 6.25 mm against its
    a / 8 reference (+1.45 %, -1.15 %, -0.80 points; FN +0.65 %)."""
    recs = _convergence()
    for name in ("deep_pair", "flange_y6.2", "flange_y6.25"):
        e = recs[name]["summary"]["errors"]["conformal FE"]
        assert abs(e["pmax"]) < 0.02 and abs(e["area"]) < 0.05 and abs(e["FN"]) < 0.01, name
        assert abs(e["flank_share_spread"]) < 0.02, name
        assert abs(e["LV"]) < 2e-3, name                            # compared at the same L/V


@pytest.mark.slow
def test_halfspace_model_at_the_deep_pair_truths_lv():
    """Recomputed here: conformal + half-space numbers matched to the stored deep-pair reference
    truth's L/V (wheelset shift an output) meets it within pmax 2 %, area 5 %, flank share
    (spread) 2 points, FN 1 % (measured +1.17 %, +1.81 %, -0.16 points, +0.75 %)."""
    sys.path.insert(0, str(ROOT / "studies"))
    import fe_ground_truth as gt
    import fe_truth_convergence as ftc

    rec = _convergence()["deep_pair"]
    t = rec["truths"]["reference"]["loaded"]
    m = ftc.production(dict(gt.scenes(False))["deep_pair"], t["LV"], None, "halfspace", lo=-0.01, hi=0.01)
    assert abs(m["LV"] - t["LV"]) < 5e-4
    assert abs(m["pmax"] / t["pmax"] - 1) < 0.02
    assert abs(m["area"] / t["area"] - 1) < 0.05
    assert abs(m["FN"] / t["FN"] - 1) < 0.01
    assert abs(m["flank_share_spread"] - t["flank_share_spread"]) < 0.02


def test_flange_625_reference_mesh_convergence_at_prescribed_loads():
    """Root + flank at 6.25 mm: the a / 8 reference (h = 0.453 mm: a is the half-space estimate's,
    whose patch is about 60 % wider than the truth's, so this is about a / 6 of the real patch)
    against a / 11 (h = 0.330 mm) at the reference's vertical and lateral load
    (studies/fe_truth_convergence.py): FN and pmax within the issue's 0.5 % (measured -0.00 %,
    +0.04 %), the area inside the reference's own bounds (-2.2 % against bounds of -8.7 / +8.7 %),
    flank share (spread) within 0.2 points (-0.07), the wheel hardly moving laterally once the
    lateral force is prescribed (|s| < 0.1 µm); no truth's contact reaches its candidate box."""
    rec = _convergence()["flange_y6.25"]
    T = rec["truths"]
    ref, fine = T["reference"]["loaded"], T["finer mesh"]["loaded"]
    assert T["finer mesh"]["h_contact"] < 0.75 * T["reference"]["h_contact"]
    d = rec["summary"]["convergence"]["finer mesh"]["loaded"]
    assert abs(d["FN"]) < 0.005 and abs(d["pmax"]) < 0.005
    assert ref["area_bounds"][0] < fine["area"] < ref["area_bounds"][1]
    assert abs(d["flank_share_spread"]) < 0.002 and abs(fine["shift"]) < 1e-4
    assert not any(r[k]["edge"] for r in T.values() for k in ("nominal", "loaded"))


def test_flange_62_reference_is_converged_at_prescribed_loads():
    """Root contact at 6.2 mm: a finer mesh (a / 8) and a larger body (40 patch sizes, rail +-494 mm)
    at the reference's vertical and lateral load (studies/fe_truth_convergence.py): FN and pmax
    within the issue's 0.5 % (measured FN 0.00 / 0.00 %, pmax +0.48 / +0.34 %), the area inside the
    reference's own bounds (-2.2 / 0.0 % against +-8 %)."""
    rec = _convergence()["flange_y6.2"]
    ref = rec["truths"]["reference"]["loaded"]
    for label in ("finer mesh", "larger body"):
        d = rec["summary"]["convergence"][label]["loaded"]
        assert abs(d["FN"]) < 0.005 and abs(d["pmax"]) < 0.005, label
        assert ref["area_bounds"][0] < rec["truths"][label]["loaded"]["area"] < ref["area_bounds"][1], label


def test_flange_625_reference_body_size_at_prescribed_loads():
    """Root + flank at 6.25 mm, the a / 8 reference (h = 0.453 mm, about a / 6 of the truth's own
    patch) at 20 -> 40 patch sizes (rail +-248 -> +-493 mm) at the same vertical and lateral load:
    FN and pmax within the issue's 0.5 % (measured -0.00 / -0.04 %), the same contact area and
    flank share; the wheel sits 49 µm further out on the longer rail, which rolls 0.2 mrad more,
    while the rim against the head at the gauge point stays within 1 µm laterally."""
    rec = _convergence()["flange_y6.25"]
    assert rec["truths"]["reference"]["options"]["fec_n"] == 8
    d = rec["summary"]["convergence"]["larger body"]["loaded"]
    assert abs(d["FN"]) < 0.005 and abs(d["pmax"]) < 0.005 and abs(d["area"]) < 0.01
    assert abs(d["flank_share_spread"]) < 0.002
    ref, big = rec["truths"]["reference"]["loaded"], rec["truths"]["larger body"]["loaded"]
    assert 0.03 < big["shift"] - ref["shift"] < 0.07
    assert abs(big["pose"]["dy_lateral"] - ref["pose"]["dy_lateral"]) < 1e-3


def test_truth_part_file_keeps_other_entries_and_supersedes_old_references(tmp_path):
    """studies/fe_truth_convergence.py: a partial run adds its entry to the scene's part file and
    keeps the others; a part file stored on other reference options is kept under "superseded"
    (not compared, not lost); the 6.25 mm reference meshes the truth's own patch at about a / 6
    (fec_n 8 of the half-space estimate) with the candidate box enlarged."""
    import json

    sys.path.insert(0, str(ROOT / "studies"))
    import fe_truth_convergence as ftc

    path = tmp_path / "s.json"
    old = {"scene": "s", "base_options": {"fec_n": 6}, "wheel_load": 1.0, "truths": {"reference": {"x": 1}},
           "models": {"m": {"y": 2}}}
    path.write_text(json.dumps(old))
    fresh = {"scene": "s", "base_options": {"fec_n": 8}, "wheel_load": 1.0}
    ftc._update(path, fresh, "truths", "reference", {"x": 3})
    ftc._update(path, fresh, "truths", "larger body", {"x": 4})
    ftc._update(path, fresh, "models", "m", {"y": 5})
    rec = json.loads(path.read_text())
    assert rec["truths"] == {"reference": {"x": 3}, "larger body": {"x": 4}} and rec["models"] == {"m": {"y": 5}}
    assert len(rec["superseded"]) == 1 and rec["superseded"][0]["truths"] == {"reference": {"x": 1}}
    assert rec["superseded"][0]["base_options"] == {"fec_n": 6}
    ref = ftc.reference_options("flange_y6.25")
    assert ref["fec_n"] == 8 and ref["fec_slave"] == 2.0 and ftc.reference_options("flange_y6.2") == ftc.gt.TRUTH
