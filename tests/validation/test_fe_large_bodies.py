"""FE quasi-quarter spaces behave like large bodies: judged in the contact problem at a prescribed
approach, where a per-number truncation offset sums over the whole patch.

Oracles: Hertz (conformal.theories.hertz, elliptic integrals) for the crowned wheel on a flat
rail, and the direct FE method (plain P2, unit loads) for the split method on a curved rail.
"""
from __future__ import annotations


import numpy as np
import pytest

from conformal.influence.fe import FESettings, body_influence
from conformal.materials import Material
from conformal.meshing.bodies import BodyModel, Profile2D, StripPatch
from conformal.meshing.gmsh_body import MeshSpec
from conformal.scene import load_scene
from conformal.dispatch import solve_scene
from conformal.theories.hertz import hertz_from_curvatures
from _paths import PROFILES, ROOT, SCENES

G, NU = 82000.0, 0.28


def _solve(name: str, influence: str, **options):
    sc = load_scene(SCENES / name)
    opts = dict(sc.model.options)
    opts.update(options)
    return solve_scene(sc.with_model(influence=influence, options=opts))


@pytest.mark.slow
def test_crowned_wheel_on_flat_rail_gives_hertz_at_prescribed_approach(tmp_path, monkeypatch):
    """Crowned wheel (transverse radius 300 mm, rolling radius 460 mm) on a flat rail at an
    approach of 0.05 mm, grid n = 30, default FE settings: Hertz gives FN = 32847 N and
    pmax = 846 N/mm².  Measured: half-space +0.07 % / -0.1 %, FE -0.03 % / -0.2 %; with the
    clamped far field (the earlier default) FE gave +33 % in FN."""
    monkeypatch.setenv("CONFORMAL_CACHE", str(tmp_path))
    hz = hertz_from_curvatures(1 / 920.0, 1 / 600.0, Material.identical(G, NU), approach=0.05)
    assert hz.FN == pytest.approx(32847, rel=1e-4) and hz.pmax == pytest.approx(846, rel=1e-3)
    fe = _solve("hertz_crowned_wheel.toml", "fe")
    hs = _solve("hertz_crowned_wheel.toml", "halfspace")
    assert fe.FN == pytest.approx(hz.FN, rel=0.01)
    assert fe.pmax == pytest.approx(hz.pmax, rel=0.02)
    assert fe.FN == pytest.approx(hs.FN, rel=0.003)       # a wheel of R 300/460 against a 10 mm patch


@pytest.mark.slow
def test_split_and_direct_methods_agree_on_the_gauge_corner():
    """R13 gauge corner of the UIC 60 rail (3 x 3 elements of 1 mm): the normal displacement under
    a uniform pressure on the patch, split P1 against direct P2 (loaded column refined to d/4),
    both with the half-space far field.  Measured: they agree within 0.42 %, and both see the
    convex corner's extra compliance over the half-space (+0.9 %)."""
    yz = np.loadtxt(PROFILES / "uic60_head_r300w21_analytic.csv", delimiter=",")
    rail = BodyModel("rail", Profile2D.from_points(yz, "uic60"))
    patch = StripPatch.uniform(3, 1.0, 3, 1.0, float(rail.profile.project(np.array([-30.0, 5.0]))))

    def uniform_pressure_un(K):   # element ix = 1 (the middle column), each I
        return np.array([sum(K[1 - jx + 2, I, J, 2, 2] for jx in range(3) for J in range(3)) for I in range(3)])

    split = body_influence(rail, patch, G, NU, FESettings(mesh=MeshSpec(body_size=1.0))).kernel
    direct = body_influence(rail, patch, G, NU, FESettings(
        method="direct", mesh=MeshSpec(order=2, h_patch=1.0, h_load=0.25, body_size=1.0))).kernel
    flat = BodyModel("block", Profile2D(np.array([-20.0, 20.0]), np.zeros(2)))
    hs = body_influence(flat, StripPatch.uniform(3, 1.0, 3, 1.0, 20.0), G, NU).kernel   # = the half-space
    us, ud, uh = (uniform_pressure_un(k) for k in (split, direct, hs))
    assert np.abs(ud / us - 1).max() < 0.006
    assert np.all(us / uh > 1.004) and np.all(ud / uh > 1.003)


@pytest.mark.slow
def test_fe_for_profiles_that_are_not_graphs_over_y(tmp_path, monkeypatch):
    """The deep conformal pair: vertical gauge and flange faces (neither profile is a graph over
    y), rail corner R10 against flange root R10.2, contact angles over tens of degrees.  FE
    meshes both bodies along the arc length, continued straight beyond the profiles' ends to the
    default body size (16 patch sizes).  At the prescribed approach 0.05 mm the size-converged FE
    bodies carry 1.0 % less than the turned-frame half-spaces (studies/fe_far_field_limit.py:
    limit 0.9897 +- 0.0003 frictionless; the default 0.9914 on this n = 16 grid, 0.9900 at n = 30,
    against the earlier coupling sense); issue 20 asked 0.984-0.997 against that sense.  The JSON
    reports each body's size and closure."""
    monkeypatch.setenv("CONFORMAL_CACHE", str(tmp_path))
    sc = load_scene(SCENES / "deep_conformal_pair.toml")
    sc = sc.with_("grid.n", 16)
    fe = solve_scene(sc)
    hs = solve_scene(sc.with_model(influence="halfspace"))
    # issue 20's band 0.984-0.997 was set against turned frames with the reversed coupling sense;
    # with the corrected sense the half-space FN of this rolling case is 1.08 % higher (26089 ->
    # 26372 N) while the FE bodies (which do not depend on it) give 25865 N as before: the band
    # moves by that factor to 0.973-0.987 (measured 0.9808)
    assert fe.converged and 0.973 < fe.FN / hs.FN < 0.987, fe.FN / hs.FN
    assert fe.summary()["contact_angle_spread_deg"] > 30.0
    for kind in ("rail", "wheel"):
        body = fe.to_dict()["fe"][kind]["body"]
        assert body["margin_mm"] == pytest.approx(body["margin_requested_mm"]) and body["margin_limited_by"] == ""
        assert body["closure_lo"] == body["closure_hi"] == "extended"
        assert body["extension_lo_mm"] > 100 and body["extension_hi_mm"] > 100
        assert body["mesh_reach_mm"] == pytest.approx(body["disc_radius_mm"], rel=1e-3)


@pytest.mark.slow
def test_sphere_on_flat_block_gives_hertz(tmp_path, monkeypatch):
    """The crowned wheel with a rolling radius equal to its transverse radius (300 mm) is a sphere
    on a flat FE block: Hertz FN within 1 % at the prescribed approach (default FE settings)."""
    monkeypatch.setenv("CONFORMAL_CACHE", str(tmp_path))
    sc = load_scene(SCENES / "hertz_crowned_wheel.toml")
    sc = sc.with_("geometry.wheel_radius", 300.0)
    hz = hertz_from_curvatures(1 / 600.0, 1 / 600.0, Material.identical(G, NU), approach=0.05)
    r = solve_scene(sc)
    assert r.FN == pytest.approx(hz.FN, rel=0.01) and r.pmax == pytest.approx(hz.pmax, rel=0.02)


@pytest.mark.slow
def test_fn_converges_with_body_size(tmp_path, monkeypatch):
    """FN at a prescribed approach against the FE body size (crowned wheel, grid n = 16).  With
    the half-space far field it is converged at every size (changes < 0.3 %); with clamped
    artificial boundaries it converges to the same limit at the fitted rate of a truncation
    offset, size^-1 (measured on the study's n = 30 grid: 1.44, 1.25, 1.13, 1.07 x the
    half-space at sizes 0.5, 1, 2, 4; fitted order 1.06)."""
    monkeypatch.setenv("CONFORMAL_CACHE", str(tmp_path))
    sc = load_scene(SCENES / "hertz_crowned_wheel.toml")
    sc = sc.with_("grid.n", 16)

    def fn(size, far):
        return solve_scene(sc.with_model(options={"fe_body_size": size, "fe_far_field": far})).FN

    hs = [fn(s, "halfspace") for s in (0.5, 2.0)]
    assert abs(hs[1] / hs[0] - 1) < 0.003
    sizes = np.array([0.5, 1.0, 2.0])
    cl = np.array([fn(s, "clamped") for s in sizes]) / hs[1] - 1.0     # excess stiffness
    assert np.all(np.diff(cl) < 0) and cl[-1] > 0
    rate = -np.polyfit(np.log(sizes), np.log(cl), 1)[0]
    assert 0.7 < rate < 1.4


@pytest.mark.slow
def test_body_size_study_quick(tmp_path, monkeypatch):
    """studies/fe_body_size.py --quick: the crowned wheel at body sizes 0.5 and 1 with both far
    fields; its table and sidecar are written and its FE rows are within 1 % of Hertz."""
    import csv
    import runpy
    import sys

    monkeypatch.setenv("CONFORMAL_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(sys, "argv", ["fe_body_size.py", "--quick", "--out", str(tmp_path / "out")])
    with pytest.raises(SystemExit) as done:
        runpy.run_path(str(ROOT / "studies" / "fe_body_size.py"), run_name="__main__")
    assert done.value.code == 0
    rows = list(csv.DictReader(open(tmp_path / "out" / "fe_body_size.csv")))
    fe_hs = [r for r in rows if r["far_field"] == "halfspace"]
    assert len(fe_hs) == 2 and all(abs(float(r["FN"]) / 32847.0 - 1) < 0.01 for r in fe_hs)
    assert (tmp_path / "out" / "run.json").exists() and (tmp_path / "out" / "fe_body_size.png").exists()
