"""Wheel-rail scenes: patches, grids from the true profiles, vertical balance, kinematics, CLI."""
import csv
from functools import partial
import json
import math

import numpy as np
import pytest

from conformal.cli import main
from conformal.errors import InputError, NoContactError
from conformal.geometry.kinematics import WheelsetMotion, creepages
from conformal.geometry.patches import find_patches, planar_distance
from conformal.cases.wheelrail import (curved_problems_from_wheel_rail, place_scene,
                                          problems_from_wheel_rail, solve_wheel_rail, state_at)
from conformal.scene import load_scene
from conformal.dispatch import solve_scene
from _paths import CONTACT_CASES, ROOT, reference_cases
from _scenes import MBENCH, mbench_scene as _mbench_scene

SWEEP = ROOT / "meshes" / "scenes" / "s1002_uic60_sweep.toml"
REF = CONTACT_CASES


#: the Manchester pair (tests/_scenes.py) with this file's defaults: Hertz, 0.5 mm elements
mbench_scene = partial(_mbench_scene, theory="hertz", element_size=0.5)


def test_planar_h_from_true_profiles():
    """h on the tangent plane is the distance of the true surfaces along the patch normal: it equals
    an independent evaluation (wheel circle cut by the normal line, solved by bisection) and departs
    from the quadratic (Hertz) form away from the centre."""
    sc = mbench_scene(2.0)
    (p,) = problems_from_wheel_rail(sc)
    g, h = p.grid, p.h
    assert h.min() == 0.0 and np.all(np.isfinite(h))
    pl = place_scene(sc)
    st = state_at(pl.pair, pl.top, p.info["z_ws"], pl.roll, sc)
    patch = st.patches[0].patch
    wheel = pl.pair.wheel(p.info["z_ws"])
    # independent: for a tangent-plane point (xi, eta), walk along the normal line with bisection on
    # the signed distance to the wheel (radius from the axle minus the profile radius at that axial position)
    f = wheel.frame

    def wheel_t(xi, eta):
        def inside(t):
            q = patch.point + xi * np.array([1.0, 0, 0]) + eta * patch.t2 + t * patch.normal
            d = q - f.O
            u = d @ f.a
            rho = np.linalg.norm(d - u * f.a)
            s = wheel.curve.s_at_y(u - wheel.offset)
            return rho - (wheel.radius + float(wheel.curve.z(s)))
        lo, hi = -1.0, 1.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if inside(mid) < 0 else (lo, mid)
        return 0.5 * (lo + hi)

    for xi, eta in ((0.0, 0.0), (2.0, -1.5), (-3.0, 2.5)):
        ours = float(planar_distance(wheel, pl.pair.rail, patch, np.array([xi]), np.array([eta]))[0])
        from conformal.geometry.patches import rail_on_lines
        _, t_r = rail_on_lines(pl.pair.rail, (patch.point[1:] + eta * patch.t2[1:])[None, :], patch.normal[1:],
                               np.array([patch.s_ref + eta]))
        assert ours == pytest.approx(float(t_r[0]) - wheel_t(xi, eta), abs=1e-7)
    # near the deepest point the distance follows the relative curvatures (seed Eqs. 52-53 second
    # fundamental forms, cross term from the yaw included) to a few per cent within 0.3 mm; over the
    # whole grid the true h departs from the Hertz quadratic by more than 0.01 mm (non-Hertzian)
    c = patch.deepest
    v0 = np.array([c.x - patch.x_ref, (c.rail_point - patch.point) @ patch.t2])
    ang = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    v = v0 + 0.3 * np.c_[np.cos(ang), np.sin(ang)]
    d = planar_distance(wheel, pl.pair.rail, patch, v[:, 0], v[:, 1])
    d0 = float(planar_distance(wheel, pl.pair.rail, patch, v0[:1], v0[1:])[0])
    dv = v - v0
    quad = 0.5 * np.einsum("ni,ij,nj->n", dv, c.curvature, dv)
    assert np.allclose(d - d0, quad, rtol=0.05)
    X, Y = g.mesh()
    assert np.abs(h - (p.hertz.A * X ** 2 + p.hertz.B * Y ** 2)).max() > 0.01


def test_vertical_balance_and_summary_with_hertz():
    r = solve_scene(mbench_scene(3.0))
    s = r.summary()
    assert s["FZ_track"] == pytest.approx(10000.0, rel=1e-4)
    (p,) = s["patches"]
    assert p["FN"] * math.cos(p["contact_angle"]) == pytest.approx(10000.0, rel=1e-4)
    for key in ("FN", "FX", "FY", "MZ", "pmax", "n_contact", "contact_angle", "y_rail"):
        assert key in p
    assert p["y_rail"] == pytest.approx(-20.56, abs=0.2)   # CONTACT -20.563 (elastic height differs slightly)
    json.dumps(s)


@pytest.mark.slow
def test_fastsim_balance_includes_tangential_forces():
    """In flange contact the lateral creep force carries a large share of the vertical load
    (CONTACT at 6.5 mm: FN cos(d) = 6181 N, FS sin(d) = 3821 N)."""
    r = solve_wheel_rail(mbench_scene(6.5, theory="fastsim", roll=-0.004376))
    (p,) = r.patches
    d = p.extra["contact_angle"]
    assert r.extra["FZ_track"] == pytest.approx(10000.0, rel=2e-4)
    assert p.FY * math.sin(d) > 0.25 * 10000.0
    assert -1.2 < d < -1.1


@pytest.mark.slow
def test_left_right_symmetry():
    """A centred wheelset without yaw and roll: the left wheel is the mirror image of the right one
    (contact angle, lateral positions, lateral force and spin moment change sign).  Both are balanced
    to 1e-4 of the wheel load, so forces agree to that."""
    a = solve_wheel_rail(mbench_scene(0.0, "right", theory="fastsim", roll=0.0))
    b = solve_wheel_rail(mbench_scene(0.0, "left", theory="fastsim", roll=0.0))
    pa, pb = a.patches[0], b.patches[0]
    assert pa.FN == pytest.approx(pb.FN, rel=1e-4)
    assert pa.extra["contact_angle"] == pytest.approx(-pb.extra["contact_angle"], abs=1e-7)
    assert pa.extra["y_rail"] == pytest.approx(-pb.extra["y_rail"], abs=1e-4)
    assert pa.FY == pytest.approx(-pb.FY, rel=1e-3) and pa.MZ == pytest.approx(-pb.MZ, rel=1e-3)
    assert pa.FX == pytest.approx(pb.FX, rel=1e-3)
    assert a.extra["FY_track"] == pytest.approx(-b.extra["FY_track"], rel=1e-3)


def test_creepages_match_contact():
    """Seed Eq. 61 with the rail as body 1, at CONTACT's wheelset heights: xi, eta, phi agree with
    the benchmark's printed creepages (4 digits) to 0.5 % (xi near pure rolling to 1e-6: measured
    6e-8 at 0 mm, -5.7e-5, and 3e-7 at 0.5 mm with the wheel material point Patch.creep_point;
    the wheel surface point on the normal line was 1.4e-6 and 1.5e-5 off there)."""
    if not REF.is_file():
        pytest.skip("shared reference data not available")
    ref = reference_cases()["mbench_a22"]
    for side in ("right", "left"):
        for k in (0, 1, 4, 10, 11, 16, 20):
            case = ref[side][k]
            inp, out = case["inputs"], case["outputs"]["patches"][0]
            sc = mbench_scene(inp["Y_WS_mm"], side, roll=inp["ROLL_WS_rad"])
            sc = sc.with_("geometry.yaw", inp["YAW_WS_rad"])
            pl = place_scene(sc)
            patch = find_patches(pl.pair.wheel(case["outputs"]["Z_WS"]), pl.pair.rail, pl.top)[0]
            m = pl.pair.mirror
            c = creepages(pl.pair.frame(case["outputs"]["Z_WS"]),
                          WheelsetMotion(2000.0, inp["VPITCH_rad_per_s"]).mirrored(side),
                          patch.creep_point, patch.normal)
            assert c.xi == pytest.approx(out["CKSI"], rel=5e-3, abs=1e-6)
            assert m * c.eta == pytest.approx(out["CETA"], rel=5e-3)
            assert m * c.phi == pytest.approx(out["CPHI"], rel=5e-3)
            assert c.velocity == pytest.approx(out["VELOC"], abs=1.0)   # printed as an integer


def test_two_simultaneous_patches():
    """Near 4.85 mm the right wheel touches both at the tread and at the gauge corner; with patches
    kept apart (patch_combine = 2 mm) the load splits over two patches whose vertical forces add up."""
    sc = mbench_scene(4.85, theory="hertz", patch_combine=2.0, roll=-0.00033)
    r = solve_wheel_rail(sc)
    assert len(r.patches) == 2
    angles = sorted(p.extra["contact_angle"] for p in r.patches)
    assert angles[0] < -0.25 and -0.15 < angles[1] < -0.1            # gauge corner and tread
    assert all(p.FN > 500.0 for p in r.patches)
    fz = sum(p.FN * math.cos(p.extra["contact_angle"]) for p in r.patches)
    assert fz == pytest.approx(10000.0, rel=1e-4) and r.extra["FZ_track"] == pytest.approx(10000.0, rel=1e-4)
    assert len(r.summary()["patches"]) == 2


def test_lifted_off_wheel_in_a_rolled_wheelset():
    """Roll the wheelset so that the left wheel touches first; lowered 0.02 mm beyond that, the right
    wheel still has a gap: NoContactError with the smallest gap.  Checked against a brute-force
    distance of wheel-surface samples to the rail curve (the closest approach is on the flange,
    where the normal is nearly horizontal, not below the tread)."""
    sc = load_scene(SWEEP)
    sc = sc.with_(geometry__roll=-0.002, load__approach=0.02)     # the approach replaces the wheel load
    pl = place_scene(sc)
    assert pl.z_first < pl.z_touch
    with pytest.raises(NoContactError, match="lifted off") as e:
        problems_from_wheel_rail(sc)
    gap = float(str(e.value).split(" is ")[1].split()[0])
    from scipy.spatial import cKDTree
    wheel = pl.pair.wheel(pl.z_first + 0.02)
    S, T = np.meshgrid(np.linspace(0, wheel.curve.length, 3001), np.linspace(-0.03, 0.03, 61), indexing="ij")
    P = wheel.point(S, T).reshape(-1, 3)
    _, rail_pts = pl.pair.rail.sample(0.005)
    dist, _ = cKDTree(rail_pts).query(P[:, 1:])
    assert 0 < gap < pl.z_touch - pl.z_first - 0.02                # closer than vertically
    assert gap == pytest.approx(dist.min(), abs=1e-3)


def test_shift_beyond_profile_range():
    sc = load_scene(SWEEP)
    with pytest.raises(InputError, match=r"\[geometry\] lateral_shift: .*end of a profile"):
        problems_from_wheel_rail(sc.with_(geometry__lateral_shift=-80.0, geometry__roll=0.0))
    with pytest.raises(InputError, match=r"\[geometry\] lateral_shift: .*does not lie over its rail"):
        problems_from_wheel_rail(sc.with_(geometry__lateral_shift=-200.0, geometry__roll=0.0))


def test_curved_grid_and_spin_along_the_profile():
    """Curved grid of a conformal gauge-corner patch: unit normals, delta(s) consistent with them,
    h >= 0 measured along the local normals, and the spin following the contact angle:
    phi(s) = -omega . n(s) / V with omega the wheelset's pitch about the axle (pure rolling, no yaw)."""
    sc = mbench_scene(5.5, theory="hertz", element_size=0.25, roll=-0.0004777)
    sc = sc.with_(geometry__yaw=0.0, kinematics__pitch_velocity=-2000.0 / 460.0)
    (grid, h, approach, info), = curved_problems_from_wheel_rail(sc)
    assert np.allclose(np.linalg.norm(grid.normal, axis=1), 1.0)
    assert np.allclose(grid.delta, np.arctan2(-grid.normal[:, 0], grid.normal[:, 1]), atol=1e-12)  # no cant
    assert h.min() == 0.0 and approach > 0 and grid.shape == h.shape
    assert np.ptp(grid.delta) > 0.05                       # the contact angle varies over the patch
    pl = place_scene(sc)
    a = pl.pair.frame(info["z_ws"]).a
    omega = -2000.0 / 460.0 * a
    n3 = np.c_[np.zeros(grid.ms), grid.normal]
    expected = -(n3 @ omega) / info["rolling_velocity_s"]
    assert np.allclose(info["phi_s"], expected, rtol=1e-9)
    assert np.all(np.diff(info["phi_s"]) * np.diff(-np.sin(grid.delta)) > 0)   # monotone with delta


def test_cli_sweep(tmp_path):
    out = tmp_path / "sw"
    assert main(["sweep", str(SWEEP), "--shift", "0:6:3", "--out", str(out)]) == 0
    rows = list(csv.DictReader((out / "sweep.csv").open()))
    assert [float(r["shift"]) for r in rows] == [0.0, 3.0, 6.0]
    dr = [float(r["delta_r"]) for r in rows]
    assert abs(dr[0]) < 1e-9 and 0 < dr[1] < dr[2]
    assert float(rows[0]["contact_angle_right"]) == pytest.approx(-float(rows[0]["contact_angle_left"]))
    assert (out / "sweep.png").stat().st_size > 10_000
    assert main(["sweep", str(SWEEP), "--shift", "3:1:1", "--out", str(out)]) == 2


def test_cli_solve_json(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(MBENCH.read_text().replace('theory = "exact"', 'theory = "hertz"')
                     .replace("element_size = 0.2", "element_size = 0.5"))
    assert main(["solve", str(scene), "--json", str(tmp_path / "o.json")]) == 0
    s = json.loads((tmp_path / "o.json").read_text())
    assert s["patches"][0]["contact_angle"] < -0.2 and "y_rail" in s["patches"][0]


def test_curved_grid_fields_rebuild_the_wheel():
    """The CurvedGrid fields are enough to rebuild the wheel (for meshing the FE bodies): the wheel
    surface point on each element's normal, rail point - (h - approach) n, lies on the surface of
    revolution given by wheel_centre, wheel_axle and wheel_profile (within the 1e-3 mm of linear
    interpolation in the sampled profile), in the rail-profile frame."""
    sc = mbench_scene(8.0, theory="hertz", element_size=0.4, roll=-0.008606)
    sc = sc.with_(geometry__rail_profile="UIC60", geometry__rail_cant=0.024995)
    (grid, h, approach, info), = curved_problems_from_wheel_rail(sc)
    X, S = grid.mesh()
    rail = np.stack([X, np.broadcast_to(grid.y, X.shape), np.broadcast_to(grid.z, X.shape)], axis=-1)
    n = np.concatenate([np.zeros((grid.ms, 1)), grid.normal], axis=1)
    W = rail - (h - approach)[..., None] * n
    d = W - grid.wheel_centre
    u = d @ grid.wheel_axle
    rho = np.linalg.norm(d - u[..., None] * grid.wheel_axle, axis=-1)
    zw = np.interp(u, grid.wheel_profile[:, 0], grid.wheel_profile[:, 1])
    assert np.abs(rho - (grid.wheel_radius + zw)).max() < 1e-3
    # the built-in UIC60 is uncanted: y_rail is in its own frame.  CONTACT's point at 8 mm,
    # (-40.701, 8.0092) in the canted file whose crown (0, 0) sits at (-7.50, 0.094), is
    # R(0.024995)^T ((-40.701, 8.0092) - (-7.50, 0.094)) = (-33.39, 7.08) in the uncanted frame
    assert grid.cant == 0.024995 and info["y_rail"] == pytest.approx(-33.39, abs=0.1)
    assert np.all(np.abs(grid.delta + 1.0) < 0.35)                 # flange contact, about 55 degrees
