"""Wheelset dynamics: independent checks of the suspended-wheelset model.

Short simulated times and coarse contact tables keep this file fast.  References are analytic
(Klingel, Hertz, energy) or an independent numerical route (time integration against eigenvalues).
"""
from __future__ import annotations

import json
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from conformal.dynamics.contact import C, interpolation_error, normal_force
from conformal.dynamics.model import build_model, equilibrium
from conformal.dynamics.scene import EXAMPLE, load_vehicle_scene, scene_from_dict
from conformal.dynamics.simulate import integrate_model, simulate
from conformal.dynamics.stability import (hunting_mode, linear_critical_speed, linear_inputs,
                                          linear_onset_time_domain)
from conformal.errors import InputError
from conformal.theories.hertz import hertz_from_curvatures
from _paths import ROOT

STEP, RANGE = 0.5, 12.0          # coarse table: about 0.5 s to build


def scene(**changes):
    d = tomllib.loads(EXAMPLE)
    d["contact"].update(table_step=STEP, table_range=RANGE)
    for key, value in changes.items():
        sec, k = key.split("__")
        if sec == "irregularity":
            d["track"]["irregularity"][k] = value
        else:
            d[sec][k] = value
    return scene_from_dict(d)


# ----------------------------------------------------------------------------- Eq. 57
def test_eq57_force_is_zero_at_zero_penetration():
    for pdot in (-50.0, 0.0, 50.0):                   # approaching, at rest, separating (mm/s)
        assert normal_force(3.0e6, 0.0, pdot, 3000.0) == 0.0
    # continuous through zero and Hertz's p^1.5 law without damping
    assert normal_force(3.0e6, 1e-9, 100.0, 3000.0) < 1e-3
    assert normal_force(3.0e6, 0.065, 0.0, 3000.0) == pytest.approx(3.0e6 * 0.065**1.5, rel=1e-14)
    # damping adds C pdot p; never a pulling force
    assert normal_force(3.0e6, 0.01, 10.0, 3000.0) == pytest.approx(3.0e6 * 0.01**1.5 + 3000.0 * 10.0 * 0.01)
    assert normal_force(3.0e6, 0.001, -1e6, 3000.0) == 0.0


# ----------------------------------------------------------------------------- at rest
def test_each_wheel_carries_W_at_rest():
    s = scene(contact__creep_model="none", simulation__speed=0.0, irregularity__amplitude=0.0)
    m = build_model(s)
    X0 = equilibrium(m)
    # independent: the static overlap is Hertz's approach under FN = W / n_z (curvatures of the search)
    row = m.table.data[int(round(-m.table.y0 / m.table.step)), 0]
    assert row[C["Kh"]] > 0
    from conformal.geometry.search import touch_height
    from conformal.geometry.placement import make_pair
    from conformal.dynamics import contact as dc
    wc, rc, fbp = dc._curves(m.table.geometry)
    g = m.table.geometry
    pair = make_pair(wc, rc, side="right", placement="wheelset", lateral_shift=0.0, roll=0.0, yaw=0.0,
                     rail_cant=g.rail_cant, gauge=g.gauge, gauge_height=g.gauge_height,
                     flange_back=g.flange_back, flange_back_pos=fbp, wheel_radius=g.wheel_radius)
    z_touch, sr = touch_height(pair)
    c = sr.contacts[0]
    A, B, _ = c.principal()
    hz = hertz_from_curvatures(A, B, s.material, normal_force=s.vehicle.wheel_load / c.normal[2])
    assert 1000 * X0[1] == pytest.approx(z_touch + hz.approach / c.normal[2], abs=2e-4)   # mm
    # disturb vertically and in roll, let Eq. 57's damping settle it: each wheel carries W
    X = X0.copy()
    X[1] += 20e-6
    X[2] += 2e-5
    t, states, steps, _ = integrate_model(m, X, 0.3, output_step=0.05)
    out = m.outputs(t[-1], states[-1])
    W = s.vehicle.wheel_load
    assert out["right_FZ"] == pytest.approx(W, rel=1e-4)
    assert out["left_FZ"] == pytest.approx(W, rel=1e-4)
    first = m.outputs(0.0, X)
    assert abs(first["right_FZ"] - W) > 0.05 * W          # the disturbance was real


# ----------------------------------------------------------------------------- energy
@pytest.mark.slow
def test_energy_conserved_without_creep_and_damping():
    s = scene(contact__creep_model="none", contact__damping=0.0, vehicle__cx=0.0, vehicle__cy=0.0,
              irregularity__amplitude=0.0, simulation__speed=30.0)
    m = build_model(s)
    X0 = equilibrium(m, 0.004, 0.0)
    X0[7] = 0.02                      # yaw rate: gyroscopic coupling active (30 m/s spin)
    X0[6] = 0.002                     # roll rate: excites the contact (vertical/roll) modes
    E0 = m.energy(0.0, X0)
    scale = 0.5 * m.Izz * 0.02**2 + 0.5 * m.Ixx * 0.002**2 + m.ky * 0.004**2
    t, states, steps, _ = integrate_model(m, X0, 0.08, method="DOP853", rtol=1e-10, atol=1e-13,
                                          output_step=0.01)
    drift = max(abs(m.energy(tt, X) - E0) for tt, X in zip(t, states))
    assert drift < 1e-6 * scale
    # the motion was not trivial: lateral and yaw exchanged energy with the springs and contacts
    assert np.ptp(states[:, 3]) > 1e-3 and np.ptp(states[:, 1]) > 1e-7
    # control: Eq. 57's damping dissipates
    m2 = build_model(scene(contact__creep_model="none", contact__damping=3000.0, vehicle__cx=0.0,
                           vehicle__cy=0.0, irregularity__amplitude=0.0, simulation__speed=30.0))
    t2, st2, _, _ = integrate_model(m2, X0, 0.08, method="DOP853", rtol=1e-8, atol=1e-11, output_step=0.08)
    assert m2.energy(t2[-1], st2[-1]) < E0 - 100 * drift


# ----------------------------------------------------------------------------- Klingel
def test_klingel_wavelength_of_a_free_wheelset_on_a_cone():
    """APTA 140 (straight 1:40 tread) on a 1:40-canted R300 crown: the contact stays at the crown
    centre, so the wheelset runs as a pure cone of conicity 1/40 up to the flange."""
    V = 20.0
    s = scene(vehicle__kx=0.0, vehicle__ky=0.0, contact__creep_model="linear", irregularity__amplitude=0.0,
              simulation__speed=V, simulation__initial_lateral=2.0, simulation__t_end=0.95,
              simulation__output_step=2e-3)
    m = build_model(s)
    val, _ = m.table.evaluate(np.array([-4.0, 0.0, 4.0]))
    lam = (val[2, 0, C["R"]] - val[0, 0, C["R"]]) / 8.0
    assert lam == pytest.approx(1 / 40, rel=2e-3)                    # a pure cone
    r0, l0 = val[1, 0, C["R"]] / 1000, val[1, 0, C["L"]] / 1000
    klingel = 2 * math.pi * math.sqrt(r0 * l0 / lam)                  # m
    r = simulate(s, model=m)
    t, y = r.history["t"], r.history["y"]
    k = np.nonzero(np.sign(y[1:]) != np.sign(y[:-1]))[0]
    assert k.size >= 2
    tc = [t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i]) for i in k[:2]]
    wavelength = 2 * V * (tc[1] - tc[0])
    assert wavelength == pytest.approx(klingel, rel=0.02)
    assert abs(wavelength / klingel - 1) < 0.02


# ----------------------------------------------------------------------------- critical speed
@pytest.mark.slow
def test_linear_critical_speed_equals_time_domain_onset():
    p = linear_inputs(scene())
    vc = linear_critical_speed(p)
    assert vc is not None and 30 < vc < 150
    assert hunting_mode(p, 0.99 * vc)[0] < 0 < hunting_mode(p, 1.01 * vc)[0]
    onset = linear_onset_time_domain(p, 0.85 * vc, 1.15 * vc, tol=0.2)
    assert onset == pytest.approx(vc, rel=0.02)


@pytest.mark.slow
def test_full_model_linearises_to_the_linear_model():
    """Small-amplitude hunting of the full model (creep model "linear", roll and vertical
    dynamics, contact table) against the eigenvalues of the 2-DOF linear model at 65 m/s."""
    V = 65.0
    s = scene(contact__creep_model="linear", irregularity__amplitude=0.0, simulation__speed=V,
              simulation__initial_lateral=1.0, simulation__t_end=1.3, simulation__output_step=2e-3)
    r = simulate(s)
    re, f_lin, _ = hunting_mode(linear_inputs(s), V)
    t, y = r.history["t"], r.history["y"]
    zc = np.nonzero(np.sign(y[1:]) != np.sign(y[:-1]))[0]
    f_full = (zc.size - 1) / 2 / (t[zc[-1]] - t[zc[0]])
    assert f_full == pytest.approx(f_lin, rel=0.02)
    assert r.summary["decay_rate"] == pytest.approx(-re, rel=0.15)      # 0.28 vs 0.27 1/s measured


@pytest.mark.slow
def test_linear_inputs_against_hertz_and_kalker():
    s = scene()
    p = linear_inputs(s)
    # f11 = G a b C11 with a, b Hertz's semi-axes under the wheel load (independent Hertz solve)
    m = build_model(s)
    row = m.table.data[int(round(-m.table.y0 / m.table.step)), 0]
    hz = hertz_from_curvatures(*_curvatures_at_centre(m), s.material, normal_force=49000.0 / row[C["nz"]])
    # the table smooths the Hertz columns over +-0.5 mm (the single search's transverse curvature,
    # a second derivative of the profile splines, scatters by 1-2 % from row to row)
    assert p.a * 1000 == pytest.approx(hz.a, rel=3e-3)
    assert p.b * 1000 == pytest.approx(hz.b, rel=1e-2)
    from conformal.theories.coefficients import kalker_coefficients
    k = kalker_coefficients(hz.a / hz.b, 0.28)
    G = s.material.G * 1e6
    assert p.f11 == pytest.approx(G * hz.a * hz.b * 1e-6 * k.C11, rel=1e-2)
    assert p.f22 == pytest.approx(G * hz.a * hz.b * 1e-6 * k.C22, rel=1e-2)
    assert p.rolling_radius == pytest.approx(0.4572, abs=2e-4)


def _curvatures_at_centre(m):
    from conformal.dynamics import contact as dc
    from conformal.geometry.placement import make_pair
    from conformal.geometry.search import touch_height
    g = m.table.geometry
    wc, rc, fbp = dc._curves(g)
    pair = make_pair(wc, rc, side="right", placement="wheelset", lateral_shift=0.0, roll=0.0, yaw=0.0,
                     rail_cant=g.rail_cant, gauge=g.gauge, gauge_height=g.gauge_height,
                     flange_back=g.flange_back, flange_back_pos=fbp, wheel_radius=g.wheel_radius)
    _, sr = touch_height(pair)
    A, B, _ = sr.contacts[0].principal()
    return A, B


# ----------------------------------------------------------------------------- table
@pytest.mark.slow
def test_contact_table_interpolation_error_is_small():
    m = build_model(scene())
    e = interpolation_error(m.table, n_points=6)
    assert e.Z_mm[0] < 1e-3          # 1 um on the touching height (the overlap is ~65 um)
    assert e.R_mm[0] < 1e-3


# ----------------------------------------------------------------------------- scene and CLI
def test_scene_rejects_unknown_keys_with_the_closest_name():
    d = tomllib.loads(EXAMPLE)
    d["vehicle"]["spring_spacng"] = d["vehicle"].pop("spring_spacing")
    with pytest.raises(InputError, match=r"\[vehicle\] spring_spacng: unknown key \(did you mean 'spring_spacing'\?\)"):
        scene_from_dict(d)
    d = tomllib.loads(EXAMPLE)
    d["contact"]["creep_model"] = "fastsimm"
    with pytest.raises(InputError, match="did you mean 'fastsim'"):
        scene_from_dict(d)
    d = tomllib.loads(EXAMPLE)
    d["vehicle"]["mass"] = -1.0
    with pytest.raises(InputError, match=r"\[vehicle\] mass: must be > 0"):
        scene_from_dict(d)
    d = tomllib.loads(EXAMPLE)
    d["track"]["irregularity"]["wavelenght"] = 1.0
    with pytest.raises(InputError, match="did you mean 'wavelength'"):
        scene_from_dict(d)


def test_creep_model_table_needs_a_table_file(tmp_path):
    d = tomllib.loads(EXAMPLE)
    d["contact"].update(creep_model="table", table="no_such_table.npz", table_step=STEP, table_range=RANGE)
    s = scene_from_dict(d, base_dir=tmp_path)
    with pytest.raises(InputError, match="no_such_table.npz"):
        build_model(s)


@pytest.mark.slow
def test_creep_table_model_follows_linear_theory_at_small_creepage():
    """The creep table of conformal.tables (exact theory) against Kalker's linear theory: at the
    seed's creepages (< 3e-4) both give the same wheelset motion."""
    kw = dict(irregularity__start=0.0, simulation__t_end=0.15)
    r_tab = simulate(scene(contact__creep_model="table", **kw))
    r_lin = simulate(scene(contact__creep_model="linear", **kw))
    assert r_tab.summary["max_lateral_displacement"] == pytest.approx(r_lin.summary["max_lateral_displacement"],
                                                                      rel=2e-3)   # 0.06 % measured
    # the longitudinal creep force of the right wheel during the excitation
    i = int(np.argmax(np.abs(r_lin.history["right_FX"])))
    assert abs(r_lin.history["right_FX"][i]) > 500.0
    assert r_tab.history["right_FX"][i] == pytest.approx(r_lin.history["right_FX"][i], rel=0.01)   # 0.07 %


def _write_scene(tmp_path, **changes) -> Path:
    text = (ROOT / "meshes" / "scenes" / "seed_wheelset.toml").read_text()
    text = text.replace("table_step = 0.1", f"table_step = {STEP}").replace("table_range = 14.0", f"table_range = {RANGE}")
    for old, new in changes.items():
        assert old in text
        text = text.replace(old, new)
    p = tmp_path / "wheelset.toml"
    p.write_text(text)
    return p


@pytest.mark.slow
def test_cli_simulate_and_stability(tmp_path, capsys):
    from conformal.cli import main
    p = _write_scene(tmp_path, **{"t_end = 2.0": "t_end = 0.03", "start = 5.0": "start = 0.0",
                                   'creep_model = "fastsim"': 'creep_model = "linear"'})
    assert main(["simulate", str(p), "--out", str(tmp_path / "o"), "--speed", "60"]) == 0
    summary = json.loads(capsys.readouterr().out)
    for key in ("max_lateral_displacement", "decay_rate", "wall_s", "steps"):
        assert key in summary
    assert summary["speed"] == 60.0
    header = (tmp_path / "o" / "history.csv").read_text().splitlines()[0].split(",")
    wanted = ["t", "y", "yaw"] + [f"{s}_{q}" for s in ("left", "right") for q in
                                  ("xi", "eta", "phi", "a", "b", "FN", "FX", "FY", "FZ", "y_contact")]
    assert set(wanted) <= set(header) and header[:3] == ["t", "y", "yaw"]
    for n in (11, 12, 13, 14, 15):
        assert list((tmp_path / "o").glob(f"fig{n}_*.png"))
    assert main(["stability", str(p), "--out", str(tmp_path / "s")]) == 0
    rep = json.loads(capsys.readouterr().out)
    for key in ("critical_speed", "method", "f11", "f22", "f23", "f33", "equivalent_conicity",
                "rolling_radius", "contact_half_distance"):
        assert key in rep
    assert rep["method"] == "linear" and rep["equivalent_conicity"] == pytest.approx(0.025, rel=5e-3)
    assert (tmp_path / "s" / "stability.png").is_file()
    # bad input: exit code 2 and one line naming the key
    bad = _write_scene(tmp_path, **{"mass = 1568.0": "mas = 1568.0"})
    assert main(["simulate", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "mas" in err[0] and "mass" in err[0]


def test_seed_scene_is_table_1():
    s = load_vehicle_scene(ROOT / "meshes" / "scenes" / "seed_wheelset.toml")
    v = s.vehicle
    assert (v.mass, v.Ixx, v.Iyy, v.Izz, v.wheel_load, v.kx, v.ky, v.cx, v.cy, v.spring_spacing) == \
        (1568.0, 656.0, 168.0, 656.0, 49000.0, 1.35e5, 2.5e5, 0.0, 0.0, 1.8)
    assert s.track.gauge == 1435.0 and s.contact.mu == 0.5 and s.simulation.speed == 65.0
    assert s.track.irregularity.amplitude == pytest.approx(0.3 * 25.4)
    assert s.track.irregularity.wavelength == pytest.approx(39 * 304.8)
    assert s.material.G == pytest.approx(2.1e5 / (2 * 1.28))


@pytest.mark.slow
def test_study_quick(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "studies" / "seed_wheelset.py"), "--quick", "--out",
                        str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    res = json.loads((tmp_path / "seed_wheelset.json").read_text())
    assert res["linear_critical_speed"] == pytest.approx(71.3, abs=3.0)
    assert res["speed"]["fastsim"]["wall_per_simulated_s"] > 0
