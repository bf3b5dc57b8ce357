"""``conformal simulate`` and ``conformal stability`` (registered by :func:`add_parsers`).

    conformal simulate SCENE.toml [--out DIR] [--speed V]
    conformal stability SCENE.toml [--method linear|nonlinear] [--out DIR]
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from conformal.errors import InputError
from conformal.files import check_output_path


def _default_out(scene_path: str) -> Path:
    return Path("out") / Path(scene_path).stem


def cmd_simulate(args) -> int:
    from conformal.dynamics.contact import interpolation_error
    from conformal.dynamics.model import build_model
    from conformal.dynamics.plots import plot_history
    from conformal.dynamics.scene import check_speed, load_vehicle_scene
    from conformal.dynamics.simulate import check_history_memory, simulate, write_outputs

    scene = load_vehicle_scene(args.scene)
    if args.speed is not None:
        if not args.speed > 0:
            raise InputError(f"--speed: must be > 0 m/s, got {args.speed}")
        check_speed("--speed", args.speed)
        scene = scene.with_speed(args.speed)
    out = Path(args.out) if args.out else _default_out(args.scene)
    check_output_path(str(out / "history.csv"), "--out")       # before the run, not after it
    check_history_memory(scene.simulation.t_end, scene.simulation.output_step)   # before the table is built
    model = build_model(scene)
    result = simulate(scene, progress=True, model=model)
    err = interpolation_error(model.table, n_points=12)
    summary = dict(result.summary, table_interpolation_error=err.as_dict())
    result = type(result)(result.history, summary, result.final_state)
    paths = write_outputs(result, out)
    paths += plot_history(result.history, out, title=scene.name)
    print(json.dumps(summary, indent=2))
    print("wrote " + ", ".join(str(p) for p in paths), file=sys.stderr)
    return 0


def cmd_stability(args) -> int:
    from conformal.dynamics.plots import plot_damping
    from conformal.dynamics.scene import MAX_SPEED, load_vehicle_scene
    from conformal.dynamics.stability import (check_bisection, damping_curve, linear_critical_speed,
                                              linear_inputs, nonlinear_critical_speed)

    scene = load_vehicle_scene(args.scene)
    if not 0 < args.v_max <= MAX_SPEED:      # the linear scan takes one eigenproblem per m/s
        raise InputError(f"--v-max: must lie in (0, {MAX_SPEED:g}] m/s, got {args.v_max}")
    out = Path(args.out) if args.out else _default_out(args.scene)
    check_output_path(str(out / "stability.png"), "--out")
    if scene.contact.creep_model == "table":     # the linear scan does not read it: check it is a table all the same
        from conformal.tables import load_table

        try:
            load_table(scene.contact.table or "default")
        except InputError as exc:
            raise InputError(f"[contact] table: {exc}") from None
    if args.method == "nonlinear":
        check_bisection(0.5 * args.v_max, args.v_max, args.tol)
    lin = linear_inputs(scene)
    vc = linear_critical_speed(lin, v_max=args.v_max)
    report = {"method": args.method, "critical_speed": vc, "linear_critical_speed": vc}
    report.update({k: getattr(lin, k) for k in ("f11", "f22", "f23", "f33", "equivalent_conicity",
                                                 "rolling_radius", "contact_half_distance")})
    nl = None
    if args.method == "nonlinear":
        hi = args.v_max if vc is None else min(args.v_max, 1.3 * vc)
        lo = 0.5 * hi
        nl, tried = nonlinear_critical_speed(scene, lo, hi, tol=args.tol,
                                             log=lambda m: print(m, file=sys.stderr))
        report["critical_speed"] = nl
        report["nonlinear_runs"] = [{"speed": v, "decays": d, "decay_rate": r} for v, d, r in tried]
        report["creep_model"] = scene.contact.creep_model
    speeds = np.linspace(1.0, args.v_max, 300)
    sp, zeta, freq = damping_curve(lin, speeds)
    png = plot_damping(sp, zeta, freq, out / "stability.png", critical=vc, nonlinear=nl, title=scene.name)
    report["plot"] = str(png)
    print(json.dumps(report, indent=2))
    return 0


def add_parsers(sub) -> None:
    """Register ``simulate`` and ``stability`` on the argparse sub-parser collection ``sub``."""
    s = sub.add_parser("simulate", help="simulate a vehicle scene (suspended wheelset): CSV, JSON, PNGs")
    s.add_argument("scene", help="vehicle scene file (TOML)")
    s.add_argument("--out", metavar="DIR", help="output folder (default: out/SCENE-NAME)")
    s.add_argument("--speed", type=float, metavar="V", help="override [simulation] speed (m/s)")
    s.set_defaults(func=cmd_simulate)

    st = sub.add_parser("stability", help="critical hunting speed of a vehicle scene: JSON and a damping plot")
    st.add_argument("scene", help="vehicle scene file (TOML)")
    st.add_argument("--method", choices=("linear", "nonlinear"), default="linear",
                    help="linear: eigenvalues about centred running; nonlinear: time-domain onset (bisection)")
    st.add_argument("--out", metavar="DIR", help="folder of stability.png (default: out/SCENE-NAME)")
    st.add_argument("--v-max", type=float, default=150.0, help="largest speed considered (m/s, default 150)")
    st.add_argument("--tol", type=float, default=0.5, help="nonlinear bisection tolerance (m/s, default 0.5)")
    st.set_defaults(func=cmd_stability)
