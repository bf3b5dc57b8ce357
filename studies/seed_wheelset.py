"""The seed's suspended wheelset (seed Table 1, Figs. 11-15) at 65 m/s: response, critical speeds,
speed of the creep models.

    python studies/seed_wheelset.py            # full study (~15-25 min on the 2-core machine)
    python studies/seed_wheelset.py --quick    # coarse table, 0.1 s of fastsim (~15 s; run by the tests)

Writes ``studies/out/seed_wheelset/`` (or ``--out DIR``): ``seed_wheelset.json`` (all numbers),
``seed_wheelset.md`` (the tables), the seed-like figures of the fastsim run (fig11..fig15),
``lateral_by_model.png``, ``stability.png`` and the sidecar ``run.json`` (commit, arguments,
package versions).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar                                         # noqa: E402
from conformal.dynamics.contact import interpolation_error                    # noqa: E402
from conformal.dynamics.model import build_model                              # noqa: E402
from conformal.dynamics.plots import SEED_CRITICAL_SPEED, plot_damping, plot_history  # noqa: E402
from conformal.dynamics.scene import load_vehicle_scene                       # noqa: E402
from conformal.dynamics.simulate import simulate                              # noqa: E402
from conformal.dynamics.stability import (damping_curve, linear_critical_speed, linear_inputs,  # noqa: E402
                                          linear_onset_time_domain, nonlinear_critical_speed)

SEED_CRITICAL = 69.0      # m/s, Valtorta et al. (2001) as quoted by the seed


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def with_contact(scene, **kw):
    return replace(scene, contact=replace(scene.contact, **kw))


def with_sim(scene, **kw):
    return replace(scene, simulation=replace(scene.simulation, **kw))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="coarse table, short runs")
    ap.add_argument("--out", default=None,
                   help="output folder (default studies/out/seed_wheelset; with --quick a temporary folder)")
    args = ap.parse_args(argv)
    out = output_dir("seed_wheelset", args)
    out.mkdir(parents=True, exist_ok=True)
    scene = load_vehicle_scene(ROOT / "meshes" / "scenes" / "seed_wheelset.toml")
    if args.quick:
        scene = with_contact(scene, table_step=0.5, table_range=12.0)
        scene = with_sim(scene, t_end=0.1)
        scene = replace(scene, track=replace(scene.track, irregularity=replace(scene.track.irregularity, start=0.0)))
    res: dict = {"scene": "meshes/scenes/seed_wheelset.toml", "quick": args.quick,
                 "seed_critical_speed": SEED_CRITICAL}

    # ------------------------------------------------------------------ contact table
    model = build_model(scene)
    err = interpolation_error(model.table, n_points=4 if args.quick else 40)
    res["table"] = {"step_mm": model.table.step, "rows": int(model.table.data.shape[0]),
                    "build_s": model.table.build_s, "interpolation_error": err.as_dict(),
                    "flange_from_mm": float(model.table.y[model.table.flange_valid][0])
                    if model.table.flange_valid.any() else None}
    log(f"table: {res['table']}")

    # ------------------------------------------------------------------ linear stability
    lin = linear_inputs(scene)
    vc = linear_critical_speed(lin, v_max=200.0)
    onset = linear_onset_time_domain(lin, 0.85 * vc, 1.15 * vc, tol=0.05 if not args.quick else 1.0)
    res["linear_inputs"] = lin.as_dict()
    res["linear_critical_speed"] = vc
    res["linear_time_domain_onset"] = onset
    log(f"linear critical speed {vc:.2f} m/s, time-domain onset of the linear model {onset:.2f} m/s")

    # ------------------------------------------------------------------ what the rail stand-in changes
    res["crown_sensitivity"] = [{"crown_radius_mm": R, **_crown(lin, scene, R)} for R in (300.0, 254.0)]
    log(f"crown sensitivity: {res['crown_sensitivity']}")
    res["sensitivity"] = [
        {"change": label, "linear_critical_speed": linear_critical_speed(replace(lin, **kw), v_max=200.0)}
        for label, kw in (("none (this scene)", {}),
                          ("contact half-distance = gauge/2 = 0.7175 m (Table 1's 2a)", {"contact_half_distance": 0.7175}),
                          ("rolling radius 17 in (0.4318 m)", {"rolling_radius": 0.4318}),
                          ("conicity 0.03", {"equivalent_conicity": 0.03}),
                          ("conicity 0.02", {"equivalent_conicity": 0.02}),
                          ("no gyroscopic coupling (Iyy = 0)", {"Iyy": 0.0}),
                          ("creep coefficients f11, f22 x 0.9", {"f11": 0.9 * lin.f11, "f22": 0.9 * lin.f22}))]
    log(f"sensitivity: {res['sensitivity']}")

    # ------------------------------------------------------------------ 65 m/s, each creep model
    models = ("fastsim",) if args.quick else ("linear", "empirical", "fastsim", "table")
    res["response"], res["speed"] = {}, {}
    runs = {}
    for name in models:
        s = with_contact(scene, creep_model=name)
        r = simulate(s, progress=not args.quick)
        runs[name] = r
        sm = r.summary
        res["response"][name] = {k: sm[k] for k in ("max_lateral_displacement", "max_yaw", "decay_rate",
                                                    "final_lateral_displacement", "max_right_FZ",
                                                    "max_right_FY", "flange_contact_time")}
        res["speed"][name] = {k: sm[k] for k in ("wall_per_simulated_s", "cpu_per_simulated_s", "steps",
                                                 "rhs_evaluations", "t_end", "method", "rtol")}
        log(f"{name}: {res['response'][name]} | {res['speed'][name]}")
    plot_history(runs["fastsim"].history, out, title="seed wheelset, 65 m/s, fastsim:")
    _plot_models(runs, out / "lateral_by_model.png")

    # ------------------------------------------------------------------ integrator tolerance (fastsim)
    if not args.quick:
        ref = None
        res["tolerance"] = []
        for rtol in (1e-6, 1e-5, 1e-4, 1e-3):
            s = with_sim(with_contact(scene, creep_model="fastsim"), rtol=rtol, atol=rtol * 1e-3, t_end=1.0)
            r = simulate(s)
            y = r.history["y"]
            if ref is None:
                ref = y
            res["tolerance"].append({"rtol": rtol, "steps": r.summary["steps"],
                                     "wall_per_simulated_s": r.summary["wall_per_simulated_s"],
                                     "cpu_per_simulated_s": r.summary["cpu_per_simulated_s"],
                                     "max_abs_y_difference_mm": float(np.max(np.abs(y - ref)))})
            log(f"tolerance {res['tolerance'][-1]}")

    # ------------------------------------------------------------------ nonlinear onset
    nl = {}
    if not args.quick:
        for name in ("fastsim", "linear"):
            s = with_sim(with_contact(scene, creep_model=name), initial_lateral=3.0)
            v, tried = nonlinear_critical_speed(s, 55.0, 85.0, tol=0.5, t_end=3.0, log=log)
            nl[name] = {"critical_speed": v, "runs": [{"speed": a, "decays": b, "decay_rate": c}
                                                      for a, b, c in tried]}
    res["nonlinear_critical_speed"] = nl
    sp, zeta, freq = damping_curve(lin, np.linspace(1.0, 120.0, 240))
    plot_damping(sp, zeta, freq, out / "stability.png", critical=vc, reference=SEED_CRITICAL_SPEED,
                 nonlinear=nl.get("fastsim", {}).get("critical_speed"), title="seed wheelset:")
    (out / "seed_wheelset.json").write_text(json.dumps(res, indent=2) + "\n", encoding="utf-8")
    (out / "seed_wheelset.md").write_text(_markdown(res), encoding="utf-8")
    write_sidecar(out, __file__, args, extra={"linear_critical_speed": vc})
    log(f"wrote {out}")
    return 0


def _crown(lin, scene, crown: float) -> dict:
    """Linear critical speed with the contact ellipse of a straight 1:40 cone on a rail crown of
    radius ``crown`` (mm): A = 1/(2 r0), B = 1/(2 crown) (Hertz under W), Kalker's coefficients."""
    from conformal.theories.coefficients import c33, coefficient_arrays
    from conformal.theories.hertz import hertz_from_curvatures

    r0 = lin.rolling_radius * 1000.0
    h = hertz_from_curvatures(1 / (2 * r0), 1 / (2 * crown), scene.material, normal_force=lin.W)
    c11, c22, c23 = (float(v) for v in coefficient_arrays(h.a / h.b, scene.material.nu))
    k33 = float(c33(h.a / h.b, scene.material.nu))
    G, ab = scene.material.G * 1e6, h.a * h.b * 1e-6
    p = replace(lin, f11=G * ab * c11, f22=G * ab * c22, f23=G * ab**1.5 * c23, f33=G * ab**2 * k33,
                a=h.a / 1000, b=h.b / 1000)
    return {"a_mm": h.a, "b_mm": h.b, "f11": p.f11, "f22": p.f22,
            "linear_critical_speed": linear_critical_speed(p, v_max=200.0)}


def _plot_models(runs, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.2))
    for name, r in runs.items():
        ax.plot(r.history["t"], r.history["y"], label=name)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("lateral displacement y [mm]")
    ax.set_title("seed wheelset at 65 m/s: lateral displacement by creep model")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _fmt(v, f="{:.3g}"):
    return "-" if v is None else f.format(v)


def _markdown(res) -> str:
    L = ["# Seed wheelset (Table 1) at 65 m/s", ""]
    t = res["table"]
    e = t["interpolation_error"]
    L += [f"Contact table: {t['rows']} rows of {t['step_mm']} mm, built in {t['build_s']:.1f} s; "
          f"interpolation error (table vs fresh search at midpoints): touching height "
          f"{e['Z_mm_tread'] * 1000:.3g} um (tread) / {e['Z_mm_flange'] * 1000:.3g} um (flange), rolling radius "
          f"{e['R_mm_tread'] * 1000:.3g} um / {e['R_mm_flange'] * 1000:.3g} um; flange contact from "
          f"{_fmt(t['flange_from_mm'])} mm lateral shift.", ""]
    li = res["linear_inputs"]
    L += ["| critical speed | m/s |", "|---|---|",
          f"| seed (Valtorta et al. 2001) | {res['seed_critical_speed']:.1f} |",
          f"| linear model, eigenvalues | {res['linear_critical_speed']:.2f} |",
          f"| linear model, time-domain onset | {res['linear_time_domain_onset']:.2f} |"]
    for k, v in res["nonlinear_critical_speed"].items():
        L.append(f"| nonlinear model ({k}), 3 mm disturbance | {_fmt(v['critical_speed'], '{:.1f}')} |")
    L += ["", f"Linear model inputs: f11 = {li['f11']:.4g} N, f22 = {li['f22']:.4g} N, f23 = {li['f23']:.4g} N m, "
          f"f33 = {li['f33']:.4g} N m², conicity {li['equivalent_conicity']:.4f}, r0 = {li['rolling_radius']:.4f} m, "
          f"l0 = {li['contact_half_distance']:.4f} m, a = {li['a'] * 1000:.2f} mm, b = {li['b'] * 1000:.2f} mm.", ""]
    L += ["| creep model | max y [mm] | max yaw [mrad] | decay rate [1/s] | max right FZ [kN] | max right FY [kN] "
          "| flange contact [s] | wall s / simulated s | CPU s / simulated s | steps |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for k, r in res["response"].items():
        sp = res["speed"][k]
        L.append(f"| {k} | {r['max_lateral_displacement']:.3f} | {r['max_yaw'] * 1000:.3f} | {_fmt(r['decay_rate'])} | "
                 f"{r['max_right_FZ'] / 1000:.2f} | {r['max_right_FY'] / 1000:.2f} | {r['flange_contact_time']:.3f} | "
                 f"{sp['wall_per_simulated_s']:.2f} | {sp['cpu_per_simulated_s']:.2f} | {sp['steps']} |")
    if res.get("tolerance"):
        L += ["", "| rtol (fastsim, 1 s) | steps | wall s / simulated s | CPU s / simulated s "
              "| max abs y difference to rtol 1e-6 [mm] |", "|---|---|---|---|---|"]
        for r in res["tolerance"]:
            L.append(f"| {r['rtol']:g} | {r['steps']} | {r['wall_per_simulated_s']:.2f} | "
                     f"{r['cpu_per_simulated_s']:.2f} | {r['max_abs_y_difference_mm']:.2e} |")
    if res.get("crown_sensitivity"):
        L += ["", "What the rail stand-in changes (linear model; 1:40 cone on a crown of radius R, Hertz under W):", "",
              "| crown radius [mm] | a [mm] | b [mm] | f11 [MN] | f22 [MN] | linear critical speed [m/s] |",
              "|---|---|---|---|---|---|"]
        for r in res["crown_sensitivity"]:
            L.append(f"| {r['crown_radius_mm']:.0f} | {r['a_mm']:.2f} | {r['b_mm']:.2f} | {r['f11'] / 1e6:.3f} | "
                     f"{r['f22'] / 1e6:.3f} | {_fmt(r['linear_critical_speed'], '{:.2f}')} |")
    if res.get("sensitivity"):
        L += ["", "Sensitivity of the linear critical speed (one input changed at a time):", "",
              "| change | linear critical speed [m/s] |", "|---|---|"]
        for r in res["sensitivity"]:
            L.append(f"| {r['change']} | {_fmt(r['linear_critical_speed'], '{:.2f}')} |")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    sys.exit(main())
