"""The conformal theory (conformal.solvers.conformal): the planar limit against the exact theory,
the weighted normal problem against Hertz, the force balance of seed Eqs. 46 and 49 on a flange
contact, the kinematics on the curved surface, and the hard cases (near-total conformity, 70-degree
contact angles, tread and flange at once, full slip, large spin, fine grids, clear messages)."""
import math
from dataclasses import replace

import numpy as np
import pytest

from conformal.errors import ConvergenceError, InputError
from conformal.grid import PlanarGrid
from conformal.materials import Material
from conformal.result import SLIP
from conformal.scene import load_scene
from conformal.dispatch import solve_scene
from conformal.cases import conformal as CC
from conformal.solvers import conformal as C
from conformal.solvers.normal import solve_normal
from conformal.theories.hertz import hertz_from_curvatures, hertz_from_semiaxes
from _paths import SCENES
from _scenes import hertz_scene as _hertz_scene

STEEL = Material.steel()


def hertz_scene(theory, kinematics=None, material=None, n=24, **model):
    return _hertz_scene(6.0, 3.0, 1e5, theory=theory, material=material, kinematics=kinematics, grid={"n": n},
                        **model)


@pytest.fixture(scope="module")
def flange():
    """S1002/UIC60 (1:40) at the lateral shift where the flange root meets the gauge corner, a
    coarse grid (20 x 20 on the patch)."""
    sc = load_scene(SCENES / "flange_s1002_uic60.toml")
    sc = sc.with_("grid.n", 20)
    problem = CC.curved_problem_from_wheel_rail(sc)
    return sc, problem, C.solve_curved(problem)


# ----------------------------------------------------------------------------- planar limit
@pytest.mark.parametrize("kinematics,material", [
    ({"xi": 0.001, "eta": 0.0005, "phi": 0.0003}, None),                       # steady rolling, partial slip
    ({"xi": 0.01, "eta": 0.005, "phi": 0.001, "rolling": "shift"}, None),      # transient shift
    ({"fx_rel": 0.5, "phi": 0.0005}, None),                                    # prescribed force
    ({"xi": 0.0005}, {"G": 82000.0, "nu": 0.28, "body2": {"G": 40000.0, "nu": 0.3}}),  # K != 0: outer loop
])
def test_planar_limit_reproduces_the_exact_theory(kinematics, material):
    """A planar problem solved as a flat conformal strip with half-space numbers is the exact theory:
    the same contact and slip areas, the same number of outer alternations, forces and tractions
    equal within the solvers' tolerance (1e-6; the planar tangential solver's Krylov products are
    single precision, 1e-7).  Measured: forces to 1e-8, tractions to 1.4e-7 of pmax."""
    r1 = solve_scene(hertz_scene("exact", kinematics, material))
    r2 = solve_scene(hertz_scene("conformal", kinematics, material))
    assert r1.converged and r2.converged
    assert (r1.n_contact, r1.n_slip) == (r2.n_contact, r2.n_slip) and 0 < r2.n_slip < r2.n_contact
    assert r1.extra.get("outer_iterations", 1) == r2.extra["outer_iterations"]
    scale = r1.FN * 0.3
    for key in ("FX", "FY"):
        assert getattr(r2, key) == pytest.approx(getattr(r1, key), abs=1e-6 * scale)
    assert r2.FN == pytest.approx(r1.FN, rel=1e-12)
    assert r2.MZ == pytest.approx(r1.MZ, abs=1e-6 * scale * 6.0)
    assert r2.approach == pytest.approx(r1.approach, rel=1e-9) and r2.pmax == pytest.approx(r1.pmax, rel=1e-8)
    for name in ("pn", "px", "py"):
        np.testing.assert_allclose(getattr(r2.field, name), getattr(r1.field, name), rtol=0, atol=1e-6 * r1.pmax)
    assert r2.extra["FZ_track"] == pytest.approx(r1.FN, rel=1e-12)      # flat strip: the load is FN


def test_flat_strip_geometry_and_creepages():
    """The flat strip of a planar grid: s = y + const, delta = 0, and the column creepages of a rigid
    motion are the planar rigid slip (xi - phi y, eta, phi)."""
    g = PlanarGrid.centred(6, 5, 0.5, 0.4)
    strip = C.flat_strip(g)
    np.testing.assert_allclose(strip.s - strip.s_ref, g.y, atol=1e-14)
    assert np.all(strip.delta == 0) and strip.ms == g.my
    xi, eta, phi = C.column_creepages(strip, 1e-3, 2e-4, 5e-3)
    np.testing.assert_allclose(xi, 1e-3 - 5e-3 * g.y, atol=1e-15)
    np.testing.assert_allclose(eta, 2e-4, atol=1e-18)
    np.testing.assert_allclose(phi, 5e-3, atol=1e-18)


@pytest.mark.slow
def test_column_creepages_are_a_rigid_motion():
    """On an inclined, curved profile: the velocity v_ref + Omega x dr with Omega = phi V n_ref,
    projected on each column's tangents (independent 3-D vector algebra), gives the column
    creepages; the spin follows the local normal, phi n_ref . n(s)."""
    sc = load_scene(SCENES / "flange_s1002_uic60.toml")
    g = CC.curved_problem_from_wheel_rail(sc.with_("grid.n", 10)).grid
    xi, eta, phi = 2e-3, -1e-3, 3e-3
    xs, es, ps = C.column_creepages(g, xi, eta, phi)
    (y0, z0), n0 = C.reference_point(g)
    n_ref = np.r_[0.0, n0]
    t_ref = np.cross(n_ref, [1.0, 0.0, 0.0])
    for j in range(g.ms):
        n = np.r_[0.0, g.normal[j]]
        t = np.cross(n, [1.0, 0.0, 0.0])
        v = xi * np.array([1.0, 0.0, 0.0]) + eta * t_ref + phi * np.cross(n_ref, [0.0, g.y[j] - y0, g.z[j] - z0])
        assert xs[j] == pytest.approx(v[0], abs=1e-15) and es[j] == pytest.approx(v @ t, abs=1e-15)
        assert ps[j] == pytest.approx(phi * (n_ref @ n), abs=1e-15)
    assert np.ptp(ps) > 0.01 * phi                                       # the spin varies over the patch


# ----------------------------------------------------------------------------- normal problem, weights
def test_oblique_load_on_an_inclined_strip_is_hertz():
    """A flat strip at contact angle delta0 = 30 degrees loaded vertically (seed Eqs. 45-46 with
    w = cos delta0): the vertical load N needs the normal force N / cos delta0, the approach along
    the vertical is the normal one / cos delta0.  Reference: the planar solver at FN = N / cos delta0
    (to the solver tolerance) and Hertz (pmax 0.5 %, the grid has an element at the centre)."""
    d0, N = math.radians(30.0), 5e4
    hz = hertz_from_semiaxes(6.0, 3.0, STEEL, normal_force=N / math.cos(d0))
    g = PlanarGrid.around_ellipse(hz.a, hz.b, n=25)
    X, Y = g.mesh()
    h = hz.A * X**2 + hz.B * Y**2
    strip = replace(C.flat_strip(g), delta=np.full(g.my, d0), normal=np.tile([-math.sin(d0), math.cos(d0)], (g.my, 1)))
    op, _ = C.influence_operator(strip, STEEL, hertz_scene("conformal").model)
    sol = solve_normal(op, strip, h, weights=C.approach_weights(strip, 0.0), normal_force=N, tol=1e-9)
    ref = solve_normal(None, g, h, normal_force=N / math.cos(d0), material=STEEL, tol=1e-9)
    assert sol.converged and sol.FN == pytest.approx(N / math.cos(d0), rel=1e-12)
    assert sol.load == pytest.approx(N, rel=1e-12)
    np.testing.assert_allclose(sol.pn, ref.pn, rtol=0, atol=1e-7 * ref.pmax)
    assert sol.approach == pytest.approx(ref.approach / math.cos(d0), rel=1e-8)
    assert sol.pmax == pytest.approx(hz.pmax, rel=5e-3)


# ----------------------------------------------------------------------------- force balance
def test_force_balance_of_a_flange_contact(flange):
    """Seed Eq. 46: sum pn cos(delta) dS = W - sum ps sin(delta) dS (to the outer tolerance 1e-6),
    with a tangential share that matters (measured 0.8 % of W); seed Eqs. 48-49: the track-frame
    forces.  Independent check: the 3-D traction vectors on the curved rail surface (rail-profile
    frame, from the grid normals), summed and rotated by the cant into the track frame, give FX,
    FY, FZ (round-off); FZ is the wheel load."""
    sc, problem, r = flange
    W = sc.load.wheel_load
    assert r.converged and r.extra["outer_iterations"] > 1
    g = problem.grid
    f = r.field
    pn, px, ps = f.side_frame("pn"), f.side_frame("px"), f.side_frame("py")
    dS = np.broadcast_to(g.area, g.shape)
    tangential_share = float((ps * np.sin(g.delta) * dS).sum())
    assert abs(tangential_share) > 0.003 * W
    assert float((pn * np.cos(g.delta) * dS).sum()) == pytest.approx(W - tangential_share, rel=1e-6)   # Eq. 46
    n = np.c_[np.zeros(g.ms), g.normal]
    t = np.c_[np.zeros(g.ms), g.normal[:, 1], -g.normal[:, 0]]
    F = ((px * dS).sum(), *((ps * dS) @ t[:, 1:] + (pn * dS) @ n[:, 1:]).sum(axis=0))
    c, s = math.cos(g.cant), math.sin(g.cant)
    F_track = np.array([F[0], c * F[1] + s * F[2], -s * F[1] + c * F[2]])   # side = R(cant) (y, z)
    np.testing.assert_allclose(F_track, [r.extra["FX_track"], r.extra["FY_track"], r.extra["FZ_track"]],
                               rtol=1e-10, atol=1e-9 * W)
    assert r.extra["FZ_track"] == pytest.approx(W, rel=1e-6)
    assert r.FN == pytest.approx(float((pn * dS).sum()), rel=1e-12)


def test_wheel_rail_scene_runs_the_conformal_theory(flange):
    """`solve_scene` routes a wheel-rail scene with theory "conformal" to the curved grid; the
    contact follows the gauge corner (contact angle range over the patch > 10 degrees: the planar
    theory warns that it is questionable there, the conformal one does not), near the exact planar
    theory in FN (1 %) and with a
    lateral force that differs (measured 2.5 %: the curved surface and the creepages varying along
    it)."""
    sc, problem, r = flange
    assert r.extra["contact_angle_spread_deg"] > 10.0 and "questionable" not in " ".join(r.warnings)
    ex = solve_scene(sc.with_model(theory="exact"))
    assert ex.patches[0].extra["contact_angle_spread_deg"] > 10.0
    assert any("theory 'exact' is questionable" in w for w in ex.warnings)
    assert r.FN == pytest.approx(ex.FN, rel=0.01)
    assert abs(r.extra["FY_track"] - ex.extra["FY_track"]) > 0.005 * abs(ex.extra["FY_track"])
    assert -45 < math.degrees(r.extra["contact_angle_min"]) < math.degrees(r.extra["contact_angle_max"]) < -20


# ----------------------------------------------------------------------------- hard cases
def test_near_total_conformity_groove():
    """A wheel of transverse radius 10.0 mm in a groove of 10.02 mm (relative curvature 1e-4 1/mm):
    at 20 N the patch is small (contact angles within +-8 degrees) and the conformal solution is
    Hertz's (measured on 30 x 30: pmax 0.07 %, half-width across 3 % -- the element-counted extent);
    at 2 kN the contact wraps round the groove (> 50 degrees of contact angle), the normal force
    exceeds the vertical load by the inclination, and the solver converges."""
    sc = load_scene(SCENES / "groove_conformal.toml")
    sc = sc.with_("grid.n", 30)
    small = solve_scene(sc.with_("load.wheel_load", 20.0))
    hz = hertz_from_curvatures(small.extra["curvature_A"], small.extra["curvature_B"], STEEL, normal_force=small.FN)
    assert small.converged and small.extra["contact_angle_spread_deg"] < 20
    assert small.pmax == pytest.approx(hz.pmax, rel=0.01) and small.b == pytest.approx(hz.b, rel=0.05)
    big = solve_scene(sc)
    assert big.converged and big.extra["contact_angle_spread_deg"] > 50
    assert big.extra["FZ_track"] == pytest.approx(2000.0, rel=1e-6) and big.FN > 1.02 * 2000.0


def test_flange_flank_at_70_degrees():
    """Contact angles of -66 to -73 degrees: the normal force is about W / cos(70 deg) = 2.9 W
    (less the vertical share of the creep forces); converges."""
    sc = load_scene(SCENES / "flange_s1002_uic60_70deg.toml")
    r = solve_scene(sc.with_("grid.n", 20))
    assert r.converged and -75 < math.degrees(r.extra["contact_angle_min"]) < -66
    assert r.extra["FZ_track"] == pytest.approx(10000.0, rel=1e-6) and 2.5 < r.FN / 10000.0 < 3.2


def test_tread_and_flange_at_once():
    """The worn pair on a test rig (9.93 mm): tread, flange root and flange flank carry the load
    together on one strip (-3, -34 and -73 degrees); the vertical loads add up to the wheel load."""
    sc = load_scene(SCENES / "flange_worn_three_patches.toml")
    sc = sc.with_("grid.n", 16).with_model(options={"max_ms": 120})
    r = solve_scene(sc)
    angles = sorted(round(math.degrees(g["contact_angle"])) for g in r.extra["regions"])
    assert r.converged and len(angles) == 3
    assert angles[0] < -65 and -40 < angles[1] < -28 and -6 < angles[2] < 0
    assert sum(g["FZ_track"] for g in r.extra["regions"]) == pytest.approx(10000.0, rel=1e-6)


def test_full_slip_and_large_spin():
    """Braking hard on the flange root: every contact element slips and |p_t| = mu p_n in each, so
    the tangential force is mu FN in magnitude (Coulomb, exactly); the spin of the rolling wheel
    varies across the patch with the contact angle."""
    sc = load_scene(SCENES / "flange_s1002_uic60.toml")
    sc = sc.with_(grid__n=16, kinematics__pitch_velocity=-2000.0 / 420.0)
    r = solve_scene(sc)
    f = r.field
    c = f.status > 0
    assert r.converged and np.all(f.status[c] == SLIP)
    # Coulomb in every element, to the tangential solver's tolerance (1e-6 of the largest traction)
    np.testing.assert_allclose(np.hypot(f.px, f.py)[c], 0.3 * f.pn[c], rtol=0, atol=2e-6 * 0.3 * r.pmax)
    assert np.ptp(CC.curved_problem_from_wheel_rail(sc).phi_s) > 0.2 * abs(r.phi)


def test_nadal_limit_stops_with_a_clear_message():
    """On the 70-degree flank with mu = 0.5 > cot(70 deg) = 0.36 in full lateral slip: with the slip
    one way the tangential tractions lift the wheel more than the pressure presses it down (Nadal:
    cos delta - mu |sin delta| < 0), and ConvergenceError says so; the other way the flank carries
    the load with a smaller normal force, W / (cos delta + mu |sin delta|) (within 10 %: the
    longitudinal part of the slip)."""
    sc = load_scene(SCENES / "flange_s1002_uic60_70deg.toml")
    sc = sc.with_(grid__n=12, friction__mu=0.5)
    p = CC.curved_problem_from_wheel_rail(sc)
    with pytest.raises(ConvergenceError, match="climbs the flange"):
        C.solve_curved(replace(p, eta_s=np.full(p.grid.ms, -0.05)))
    r = C.solve_curved(replace(p, eta_s=np.full(p.grid.ms, 0.05)))
    d = abs(r.extra["regions"][0]["contact_angle"])
    assert r.converged and r.extra["FZ_track"] == pytest.approx(10000.0, rel=1e-6)
    assert r.FN == pytest.approx(10000.0 / (math.cos(d) + 0.5 * math.sin(d)), rel=0.1)


@pytest.mark.slow
def test_very_fine_grid_converges():
    """120 x 120 elements on the flange-root patch: both stages converge in a few outer iterations."""
    sc = load_scene(SCENES / "flange_s1002_uic60.toml")
    r = solve_scene(sc.with_("grid.n", 120))
    assert r.converged and r.n_contact > 4000 and r.extra["outer_iterations"] <= 8


@pytest.mark.slow
def test_fe_influence_numbers_end_to_end(monkeypatch, tmp_path):
    """influence = "fe": FE bodies of the real wheel and rail (coarse P1 here), cached.  On the
    flange root the FE solution stays close to the curved half-space one (the bodies are massive
    there: FN 1 %, pmax 3 %, area 10 %; measured 0.2 %, 0.9 %, 4.7 % on 12 x 12 with P1) and the second
    solve reads the numbers from the cache and gives the same answer."""
    monkeypatch.setenv("CONFORMAL_CACHE", str(tmp_path))
    sc = load_scene(SCENES / "flange_s1002_uic60_fe.toml")
    sc = sc.with_("grid.n", 12).with_model(options={"fe_order": 1})
    fe1 = solve_scene(sc)
    hs = solve_scene(sc.with_model(influence="halfspace", options={}))
    assert fe1.converged and fe1.extra["influence"] == "fe"
    assert fe1.FN == pytest.approx(hs.FN, rel=0.01) and fe1.pmax == pytest.approx(hs.pmax, rel=0.03)
    assert fe1.extra["contact_area"] == pytest.approx(hs.extra["contact_area"], rel=0.1)
    fe2 = solve_scene(sc)
    assert all(v.get("cache_hit") for v in fe2.extra["fe"].values())
    assert fe2.FN == fe1.FN and fe2.FX == fe1.FX


def test_bad_input_messages():
    with pytest.raises(InputError, match=r"\[model\] influence: finite-element influence numbers need"):
        solve_scene(hertz_scene("conformal", influence="fe"))
    with pytest.raises(InputError, match=r"\[model\] maxout"):
        solve_scene(hertz_scene("conformal", {"xi": 1e-3}, maxout=0))
    g = PlanarGrid.centred(4, 3, 1.0, 1.0)
    steep = replace(C.flat_strip(g), delta=np.array([0.0, 1.0, 1.7]))
    with pytest.raises(InputError, match="no longer presses"):
        C.approach_weights(steep, 0.0)


@pytest.mark.parametrize("name", ["flange_s1002_uic60.toml", "mbench_right_y5.toml"])
def test_curved_creepages_use_the_planar_creep_point(name):
    """Per column the curved path takes the wheel material point of Patch.creep_point (CONTACT's
    rule: the rail point moved by the patch's penetration along the normal).  A one-column grid
    through the patch's reference point must then reproduce the planar creepages to round-off
    (the wheel surface point on the normal, the old rule, was 1.1e-6 off in xi = 0.0115 on the
    flange root and 3.2e-5 in xi = 0.0069 on the Manchester case with yaw)."""
    from types import SimpleNamespace

    from conformal.geometry.kinematics import WheelsetMotion
    from conformal.cases.wheelrail import _kinematics_for, balance_height, curved_creepages, place_scene

    sc = load_scene(SCENES / name)
    pl = place_scene(sc)
    _, st, _ = balance_height(pl, sc)
    p = st.patches[0].patch
    rail = pl.pair.rail
    yz = (np.asarray(p.point[1:]) - np.asarray(rail.origin)) @ rail.rotation     # rail-profile frame
    grid = SimpleNamespace(ms=1, y=yz[:1], z=yz[1:], normal=(np.asarray(p.normal[1:]) @ rail.rotation)[None, :],
                           s=np.array([p.s_ref]), s_ref=p.s_ref)
    k = sc.kinematics
    pitch = k.pitch_velocity if k.pitch_velocity is not None else -k.speed / sc.geometry.wheel_radius
    motion = WheelsetMotion(k.speed, pitch, k.yaw_rate, k.roll_rate, k.lateral_velocity)
    c = curved_creepages(pl.pair, st.z, motion, grid, p)
    kin, _ = _kinematics_for(sc, pl.pair, st.z, p)
    assert abs(kin.xi) > 1e-3                        # a real longitudinal creepage to compare
    np.testing.assert_allclose([c.xi[0], c.eta[0], c.phi[0]], [kin.xi, kin.eta, kin.phi], rtol=0, atol=1e-12)
