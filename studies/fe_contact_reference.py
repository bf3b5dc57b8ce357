"""Direct FE contact (theory "fe_contact") as the reference for conformal contact.

Two parts:

1. ``--convergence``: Hertz verification and mesh convergence.  A sphere (R = 50 mm) on a flat
   block and two crossed cylinders (R = 40 mm along x, 80 mm along y), steel, at a prescribed
   approach: FN, pmax and the contact area against Hertz (conformal.theories.hertz) for a series
   of meshes (fec_n = n elements per contact semi-axis and fec_growth = 1.2 / n: the whole mesh
   is refined; the default is n = 4; quadratic and linear tetrahedra); the rate is
   fitted by np.polyfit on log(error) against log(h / a).  Also the effect of the boundary
   condition on the cut faces (half-space field against clamped) and of the body size.
2. ``--comparison``: the S1002/UIC60 flange scenes (meshes/scenes/flange_s1002_uic60.toml at 0,
   6.2 and 6.25 mm shift) and the deep groove (meshes/scenes/groove_conformal.toml), frictionless
   (no creepage), at the scene's wheel load and at a prescribed approach (the wheelset height the
   conformal half-space model reaches at that load): FN, pmax, contact area, the pressure along the
   profile, wall times, from fe_contact, conformal with FE influence numbers, conformal with
   half-space numbers and the tangent-plane exact theory; errors against fe_contact.

   Each scene's rows go to parts/<scene>.json (``--scenes`` runs a subset, the other parts are
   kept); comparison.* are built from all parts.
3. ``--mesh-study SCENE``: fe_contact on one comparison scene for a list of meshes (``--fec-list``,
   JSON list of fec_* key sets: element size, order, body size) and conformal with half-space and
   FE numbers for a list of grid sizes (``--grid-list``, [grid] n), at the wheel load and at the
   prescribed approach: mesh_study_<scene>.json/.md (appended run by run).

Outputs in --out (default studies/out/fe_contact): convergence.json/.md/.png,
comparison.json/.md/.png, parts/*.json, mesh_study_*.json/.md, fe_contact_<scene>.vtu (rail
surface with the pressure), and run.json (studies/_provenance.py).

    nice python studies/fe_contact_reference.py --convergence      # ~10 minutes
    nice python studies/fe_contact_reference.py --comparison       # ~40 minutes on a busy 2-core machine
    nice python studies/fe_contact_reference.py --comparison --scenes groove
    nice python studies/fe_contact_reference.py --mesh-study groove --fec-list '[{"fec_h": 0.38}]' --grid-list '[20, 40, 80]'
    python studies/fe_contact_reference.py --quick                 # coarse, one scene (the test)
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from conformal.fe_contact.bodies import STEEL, ContactMesh, crossed_cylinders, sphere_on_block  # noqa: E402
from conformal.fe_contact.solver import FEContactSettings, solve_contact  # noqa: E402
from conformal.theories.hertz import hertz_from_curvatures  # noqa: E402

sys.path.insert(0, str(ROOT / "studies"))
from _provenance import write_sidecar  # noqa: E402

SPHERE_R, SPHERE_DELTA = 50.0, 0.08
CYL_R1, CYL_R2, CYL_DELTA = 40.0, 80.0, 0.06


# ----------------------------------------------------------------------------- part 1
def hertz_case(case: str, n: int, order: int, far_field: str = "halfspace", body_size: float = 1.0) -> dict:
    # the whole mesh is refined: surface size a / n and growth 1.2 / n (the default: n = 4, 0.3)
    mesh = ContactMesh(n=n, growth=1.2 / n, body_size=body_size)
    if case == "sphere":
        A = B = 1.0 / (2.0 * SPHERE_R)
        delta = SPHERE_DELTA
    else:
        A, B, delta = 1.0 / (2.0 * CYL_R2), 1.0 / (2.0 * CYL_R1), CYL_DELTA
    hz = hertz_from_curvatures(A, B, STEEL, approach=delta)
    t0 = time.perf_counter()
    if case == "sphere":
        b1, b2 = sphere_on_block(SPHERE_R, (hz.a, hz.b), mesh=mesh)
    else:
        b1, b2 = crossed_cylinders(CYL_R1, CYL_R2, (hz.a, hz.b), mesh=mesh)
    sol = solve_contact(b1, b2, approach=delta, settings=FEContactSettings(order=order, far_field=far_field))
    wall = time.perf_counter() - t0
    return {"case": case, "n": n, "order": order, "far_field": far_field, "body_size": body_size,
            "h_over_a": 1.0 / n, "dofs": sol.n_unknowns, "wall_s": wall,
            "growth": mesh.growth, "FN": sol.FN, "FN_hertz": hz.FN, "pmax": sol.pmax, "pmax_nodal": sol.pmax_nodal,
            "pmax_hertz": hz.pmax,
            "area": sol.contact_area, "area_hertz": hz.area,
            "err_FN": sol.FN / hz.FN - 1.0, "err_pmax": sol.pmax / hz.pmax - 1.0,
            "err_area": sol.contact_area / hz.area - 1.0}


def convergence(out: Path, quick: bool) -> dict:
    runs = []
    series = [("sphere", 2, [2] if quick else [2, 3, 4, 5]), ("sphere", 1, [2] if quick else [2, 4, 6, 8]),
              ("cylinders", 2, [] if quick else [2, 3, 4])]
    for case, order, ns in series:
        for n in ns:
            r = hertz_case(case, n, order)
            runs.append(r)
            print(f"{case:9s} P{order} n={n}: dofs {r['dofs']:6d}  FN {100 * r['err_FN']:+.2f} %  pmax "
                  f"{100 * r['err_pmax']:+.2f} %  area {100 * r['err_area']:+.2f} %  {r['wall_s']:.1f} s", flush=True)
    extra = [] if quick else [("sphere", 3, 2, "clamped", 1.0), ("sphere", 3, 2, "halfspace", 2.0),
                              ("sphere", 3, 2, "clamped", 2.0)]
    for case, n, order, ff, bs in extra:
        r = hertz_case(case, n, order, ff, bs)
        runs.append(r)
        print(f"{case} P{order} n={n} {ff} body {bs}: FN {100 * r['err_FN']:+.2f} %  pmax {100 * r['err_pmax']:+.2f} %",
              flush=True)
    fits = {}
    for case, order, _ in series:
        rs = [r for r in runs if r["case"] == case and r["order"] == order and r["far_field"] == "halfspace"
              and r["body_size"] == 1.0]
        if len(rs) >= 2:
            h = np.log([r["h_over_a"] for r in rs])
            for q in ("FN", "pmax"):
                e = np.abs([r[f"err_{q}"] for r in rs])
                if np.all(e > 0):
                    fits[f"{case}_P{order}_{q}"] = float(np.polyfit(h, np.log(e), 1)[0])
    data = {"runs": runs, "rates": fits}
    (out / "convergence.json").write_text(json.dumps(data, indent=1))
    lines = ["| case | order | n (elements per semi-axis) | far field | body size | unknowns | FN error | pmax error | "
             "area error | wall [s] |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        lines.append(f"| {r['case']} | P{r['order']} | {r['n']} | {r['far_field']} | {r['body_size']:g} | {r['dofs']} | "
                     f"{100 * r['err_FN']:+.2f} % | {100 * r['err_pmax']:+.2f} % | {100 * r['err_area']:+.1f} % | "
                     f"{r['wall_s']:.1f} |")
    lines.append("")
    lines.append("Fitted rates (slope of log|error| against log(h/a)): "
                 + ", ".join(f"{k} {v:.2f}" for k, v in fits.items()))
    (out / "convergence.md").write_text("\n".join(lines) + "\n")
    _plot_convergence(runs, fits, out / "convergence.png")
    return data


def _plot_convergence(runs, fits, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, q in zip(axes, ("FN", "pmax")):
        for case, order, marker in (("sphere", 2, "o"), ("sphere", 1, "s"), ("cylinders", 2, "^")):
            rs = [r for r in runs if r["case"] == case and r["order"] == order and r["far_field"] == "halfspace"
                  and r["body_size"] == 1.0]
            if not rs:
                continue
            rate = fits.get(f"{case}_P{order}_{q}")
            label = f"{case} P{order}" + (f" (rate {rate:.2f})" if rate is not None else "")
            ax.loglog([r["h_over_a"] for r in rs], [abs(r[f"err_{q}"]) * 100 for r in rs], marker + "-", label=label)
        ax.axhline(1.0 if q == "FN" else 2.0, color="grey", lw=0.8, ls="--")
        ax.set_xlabel("h / a (element size over the smaller semi-axis)")
        ax.set_ylabel(f"|{q} error| vs Hertz [%]")
        ax.legend(fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle("fe_contact against Hertz at a prescribed approach")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------- part 2
def _scenes(quick: bool):
    from conformal.scene import load_scene

    flange = load_scene(ROOT / "meshes/scenes/flange_s1002_uic60.toml")
    groove = load_scene(ROOT / "meshes/scenes/groove_conformal.toml")
    out = []
    for shift in ([6.2] if quick else [0.0, 6.2, 6.25]):
        out.append((f"flange_y{shift:g}", flange.with_("geometry.lateral_shift", shift)))
    if not quick:
        out.append(("groove", groove))
    # frictionless comparison: no creepage, so that every model solves the normal problem alone
    return [(name, sc.with_(kinematics__speed=None, kinematics__xi=0.0, kinematics__eta=0.0,
                                 kinematics__phi=0.0, kinematics__fx_rel=None, kinematics__fy_rel=None)) for name, sc in out]


def _area(r) -> float:
    if "contact_area" in r.extra:
        return float(r.extra["contact_area"])
    parts = r.patches or (r,)
    return float(sum(p.field.n_contact * p.field.grid.area for p in parts if p.field is not None))


def _profile(r):
    """(s - s_ref, p) along the profile at x = 0 (conformal: the strip; exact: the main patch's y)."""
    if r.theory == "fe_contact":
        s = np.asarray(r.extra["profile_s"]) - r.extra["profile_s_ref"]
        return s, np.asarray(r.extra["profile_p"])
    parts = r.patches or (r,)
    main = max(parts, key=lambda p: p.FN)
    f = main.field
    if f is None:
        return np.zeros(0), np.zeros(0)
    ix = int(np.argmin(np.abs(f.grid.x)))
    if getattr(f, "curved", None) is not None:
        return np.asarray(f.curved.s) - f.curved.s_ref, f.pn[ix]
    return f.grid.y, f.pn[ix]


def _solve(scene, theory: str, options: dict, influence: str = "halfspace"):
    from conformal.dispatch import solve_scene

    opts = dict(scene.model.options)
    opts.update(options)
    sc = scene.with_model(theory=theory, influence=influence, options=opts)
    t0 = time.perf_counter()
    r = solve_scene(sc)
    return r, time.perf_counter() - t0


#: fe_contact meshes of the comparison.  The flange scenes: fec_h = 0.8 mm (2.3 to 4.5 elements
#: per contact semi-axis; at 6.25 mm shift, prescribed approach, FN changes by -0.12 % and pmax
#: by -0.9 % from 0.8 to 0.55 mm, measured 2026-11-24).  The deep groove: its contact is 0.75 mm
#: wide (a = 0.37 mm) and 12 mm long; the automatic default (h = a / 4 = 0.09 mm) is beyond this
#: machine, so fec_h = 0.27 mm (40 minutes of a loaded 2-core machine), with the groove mesh
#: study (--mesh-study groove: 0.38, 0.27, 0.19 mm) for its convergence
FE_MESH = {"groove": {"fec_h": 0.27}}
FE_MESH_FLANGE = {"fec_h": 0.8}
FE_MESH_QUICK = {"fec_n": 2, "fec_order": 1}


def fe_options(name: str, quick: bool, override: dict | None = None) -> dict:
    """[model] fec_* keys of the fe_contact run of a comparison scene."""
    if override is not None:
        return dict(override)
    if quick:
        return dict(FE_MESH_QUICK)
    return dict(FE_MESH.get(name, FE_MESH_FLANGE))


def compare_scene(name: str, scene, out: Path, fec_opts: dict, fe_influence: bool) -> tuple[list, dict]:
    """Rows (one per load mode and model) and pressure profiles of one comparison scene."""
    from conformal.cases.fe_contact import result_from_run, run_wheel_rail
    from conformal.fe_contact.problems import write_vtu

    rows, profiles = [], {}
    run = prob = s2 = fe_prep = None
    # prescribed approach: the overlap the conformal half-space model reaches at the wheel load
    ref, _ = _solve(scene, "conformal", {})
    for mode in ("load", "approach"):
        # [load] approach counts the wheelset height from first touch: the height the conformal
        # half-space model finds for the wheel load, so that every model sees the same overlap
        sc = scene if mode == "load" else scene.with_("load.approach", float(ref.approach))
        models = [("fe_contact", "fe_contact", fec_opts, "halfspace"),
                  ("conformal_fe", "conformal", {}, "fe"),
                  ("conformal_hs", "conformal", {}, "halfspace"),
                  ("exact", "exact", {}, "halfspace")]
        if not fe_influence:
            models = [m for m in models if m[0] != "conformal_fe"]
        for label, theory, opts, infl in models:
            try:
                if label == "fe_contact" and mode == "load":
                    t0 = time.perf_counter()
                    s2 = sc.with_model(theory="fe_contact", options=dict(sc.model.options, **opts))
                    run, prob = run_wheel_rail(s2)
                    r = result_from_run(run, prob, s2)
                    wall = time.perf_counter() - t0
                    fe_prep = wall - run.solution.stats["active_set_s"]     # meshing, pairing, factorising
                    write_vtu(run, out / f"fe_contact_{name}.vtu")
                elif label == "fe_contact":
                    if run is None:
                        raise RuntimeError("the fe_contact run at the wheel load failed (above)")
                    # the same meshes, the wheel moved to the prescribed height: one more solve
                    # (its wall time counts the shared meshing and factorisation once more)
                    delta = float(ref.approach) - (prob.info["z_ws_reference"] - prob.info["z_first_touch"])
                    sol2 = run.model.solve(approach=delta)
                    r = result_from_run(replace(run, solution=sol2), prob, s2)
                    wall = fe_prep + sol2.stats["active_set_s"]
                else:
                    r, wall = _solve(sc, theory, opts, infl)
                    if label == "conformal_fe":      # second call: FE numbers from the cache
                        r, wall = _solve(sc, theory, opts, infl)
            except Exception as exc:  # a model that fails is reported, not hidden
                print(f"{name} {mode} {label}: FAILED {type(exc).__name__}: {exc}", flush=True)
                rows.append({"scene": name, "mode": mode, "model": label, "error": f"{type(exc).__name__}: {exc}"})
                continue
            row = {"scene": name, "mode": mode, "model": label, "FN": r.FN, "pmax": r.pmax,
                   "area": _area(r), "approach": r.approach, "wall_s": wall,
                   "n_unknowns": r.extra.get("n_unknowns"), "fe_contact": r.extra.get("fe_contact")}
            rows.append(row)
            s, p = _profile(r)
            profiles[f"{name}|{mode}|{label}"] = {"s": np.asarray(s).tolist(), "p": np.asarray(p).tolist()}
            print(f"{name:12s} {mode:8s} {label:13s} FN {r.FN:9.1f}  pmax {r.pmax:7.1f}  area {row['area']:6.2f}  "
                  f"approach {r.approach:.4f}  {wall:6.1f} s", flush=True)
        ref_row = next((x for x in rows if x["mode"] == mode and x["model"] == "fe_contact" and "FN" in x), None)
        if ref_row:
            for x in rows:
                if x["mode"] == mode and "FN" in x:
                    for q in ("FN", "pmax", "area"):
                        x[f"err_{q}"] = x[q] / ref_row[q] - 1.0
                    x["time_ratio"] = x["wall_s"] / ref_row["wall_s"]
    return rows, profiles


def comparison(out: Path, quick: bool, fe_influence: bool, only: list | None = None,
               fec_override: dict | None = None) -> dict:
    """Run the comparison scenes (``only``: a subset by name) and write each one's rows to
    ``parts/<scene>.json``; then build comparison.{json,md,png} from every part present (so that
    scenes can be run, or rerun, one at a time)."""
    parts = out / "parts"
    parts.mkdir(parents=True, exist_ok=True)
    for name, scene in _scenes(quick):
        if only and name not in only:
            continue
        opts = fe_options(name, quick, fec_override)
        rows, profiles = compare_scene(name, scene, out, opts, fe_influence)
        (parts / f"{name}.json").write_text(json.dumps(
            {"rows": rows, "profiles": profiles, "fe_options": opts,
             "measured_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime())}, indent=1))
    return build_comparison(out)


def build_comparison(out: Path) -> dict:
    """comparison.{json,md,png} from the parts in ``out/parts`` (scene order of the study)."""
    order = ["flange_y0", "flange_y6.2", "flange_y6.25", "groove"]
    found = sorted((out / "parts").glob("*.json"), key=lambda p: (order.index(p.stem) if p.stem in order else 99, p.stem))
    rows, profiles, meta = [], {}, {}
    for p in found:
        d = json.loads(p.read_text())
        rows += d["rows"]
        profiles.update(d["profiles"])
        meta[p.stem] = {"fe_options": d["fe_options"], "measured_utc": d["measured_utc"]}
    data = {"rows": rows, "profiles": profiles, "scenes": meta}
    (out / "comparison.json").write_text(json.dumps(data, indent=1))
    lines = ["| scene | load | model | FN [N] | pmax [N/mm²] | area [mm²] | FN err | pmax err | area err | wall [s] | "
             "time / fe_contact |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for x in rows:
        if "FN" not in x:
            lines.append(f"| {x['scene']} | {x['mode']} | {x['model']} | failed: {x['error'][:60]} | | | | | | | |")
            continue
        e = (lambda q: f"{100 * x[f'err_{q}']:+.1f} %" if f"err_{q}" in x else "")
        lines.append(f"| {x['scene']} | {x['mode']} | {x['model']} | {x['FN']:.0f} | {x['pmax']:.0f} | {x['area']:.1f} | "
                     f"{e('FN')} | {e('pmax')} | {e('area')} | {x['wall_s']:.2f} | {x.get('time_ratio', float('nan')):.3f} |")
    lines.append("")
    lines.append("fe_contact meshes: " + "; ".join(f"{k}: {', '.join(f'{a} = {b}' for a, b in v['fe_options'].items())} "
                                                   f"(measured {v['measured_utc']} UTC)" for k, v in meta.items()))
    (out / "comparison.md").write_text("\n".join(lines) + "\n")
    if rows:
        _plot_comparison(rows, profiles, out / "comparison.png")
    return data


def _plot_comparison(rows, profiles, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(x["scene"] for x in rows))
    fig, axes = plt.subplots(2, len(scenes), figsize=(4.2 * len(scenes), 7.5), squeeze=False)
    styles = {"fe_contact": ("k", "-"), "conformal_fe": ("C0", "--"), "conformal_hs": ("C1", "-."),
              "exact": ("C2", ":")}
    for j, sc in enumerate(scenes):
        ax = axes[0, j]
        for key, v in profiles.items():
            name, mode, label = key.split("|")
            if name == sc and mode == "load":
                c, ls = styles[label]
                ax.plot(v["s"], v["p"], color=c, ls=ls, label=label)
        ax.set_title(f"{sc}, wheel load")
        ax.set_xlabel("s - s_ref (exact: y) [mm]")
        ax.set_ylabel("p at x = 0 [N/mm²]")
        ax.legend(fontsize=7)
        ax = axes[1, j]
        labels = [m for m in styles if m != "fe_contact"]
        width = 0.2
        for k, q in enumerate(("FN", "pmax", "area")):
            vals = []
            for m in labels:
                x = next((x for x in rows if x["scene"] == sc and x["mode"] == "approach" and x["model"] == m
                          and f"err_{q}" in x), None)
                vals.append(100 * x[f"err_{q}"] if x else np.nan)
            ax.bar(np.arange(len(labels)) + (k - 1) * width, vals, width, label=q)
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xticks(np.arange(len(labels)))
        ax.set_xticklabels(labels, fontsize=8)
        ax.set_ylabel("error vs fe_contact at prescribed approach [%]")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def mesh_study(out: Path, name: str, fec_list: list, grid_list: list, fe_influence: bool = True) -> dict:
    """fe_contact on one comparison scene for each set of fec_* keys, and conformal (half-space
    and FE numbers) for each grid size [grid] n, at the wheel load and at the prescribed approach
    of the comparison.  Appends to ``mesh_study_<name>.json`` (one run at a time: a long study
    survives an interruption) and writes ``mesh_study_<name>.md``."""
    from conformal.cases.fe_contact import result_from_run, run_wheel_rail

    scene = dict(_scenes(False))[name]
    path = out / f"mesh_study_{name}.json"
    data = json.loads(path.read_text()) if path.exists() else {"runs": []}
    ref, _ = _solve(scene, "conformal", {})
    app_scene = scene.with_("load.approach", float(ref.approach))

    def record(run: dict) -> None:
        nonlocal data      # read again: another mesh study of the same scene may have appended meanwhile
        data = json.loads(path.read_text()) if path.exists() else {"runs": []}
        data["runs"].append(run)
        path.write_text(json.dumps(data, indent=1))
        print(json.dumps({k: v for k, v in run.items() if k != "estimate"}), flush=True)

    for opts in fec_list:
        t0 = time.perf_counter()
        s2 = scene.with_model(theory="fe_contact", options=dict(scene.model.options, **opts))
        run, prob = run_wheel_rail(s2)
        r = result_from_run(run, prob, s2)
        wall = time.perf_counter() - t0
        delta = float(ref.approach) - (prob.info["z_ws_reference"] - prob.info["z_first_touch"])
        sol2 = run.model.solve(approach=delta)
        r2 = result_from_run(replace(run, solution=sol2), prob, s2)
        fc = r.extra["fe_contact"]
        # force on the rail outside the conformal grid's strip (e.g. the groove's edges)
        from conformal.influence.fe import rail_body_from_grid

        _, rp = rail_body_from_grid(prob.grid, prob.rail_points)
        s_fe = sol2.uv[:, 1]
        outside = sol2.active & ((s_fe < rp.edges[0]) | (s_fe > rp.edges[-1]))
        record({"model": "fe_contact", "options": opts, "h": fc["h_contact"], "order": fc["order"],
                "FN_outside_strip_approach": float(sol2.force[outside].sum()),
                "body_size": fc["body_size"], "n_unknowns": r.extra["n_unknowns"], "wall_s": wall,
                "load": {"FN": r.FN, "pmax": r.pmax, "area": r.extra["contact_area"],
                         "area_bounds": r.extra["contact_area_bounds"], "a": r.a, "b": r.b},
                "approach": {"FN": r2.FN, "pmax": r2.pmax, "area": r2.extra["contact_area"],
                             "area_bounds": r2.extra["contact_area_bounds"], "a": r2.a, "b": r2.b},
                "estimate": fc.get("estimate")})
    for n in grid_list:
        for label, infl in (("conformal_hs", "halfspace"), ("conformal_fe", "fe")):
            if infl == "fe" and not fe_influence:
                continue
            res = {}
            for mode, sc in (("load", scene), ("approach", app_scene)):
                sc = sc.with_("grid.n", int(n))
                r, wall = _solve(sc, "conformal", {}, infl)
                res[mode] = {"FN": r.FN, "pmax": r.pmax, "area": _area(r), "wall_s": wall}
            record({"model": label, "grid_n": int(n), **res})
    lines = ["| model | mesh | unknowns | FN load [N] | pmax load | area load | FN approach [N] | pmax approach | "
             "area approach |", "|---|---|---|---|---|---|---|---|---|"]
    for x in data["runs"]:
        mesh = (f"h = {x['h']:.3g} mm, P{x['order']}, body {x['body_size']:g}" if x["model"] == "fe_contact"
                else f"grid n = {x['grid_n']}")
        if "FN_outside_strip_approach" in x:
            mesh += f" (outside the strip: {x['FN_outside_strip_approach']:.1f} N)"
        lo, ap = x["load"], x["approach"]
        lines.append(f"| {x['model']} | {mesh} | {x.get('n_unknowns', '')} | {lo['FN']:.0f} | {lo['pmax']:.0f} | "
                     f"{lo['area']:.2f} | {ap['FN']:.0f} | {ap['pmax']:.0f} | {ap['area']:.2f} |")
    (out / f"mesh_study_{name}.md").write_text("\n".join(lines) + "\n")
    return data


def _error_summary(data: dict) -> dict:
    return {f"{x['scene']}|{x['mode']}|{x['model']}": {q: x.get(f"err_{q}") for q in ("FN", "pmax", "area")}
            for x in data["rows"] if "FN" in x}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--convergence", action="store_true")
    ap.add_argument("--comparison", action="store_true")
    ap.add_argument("--quick", action="store_true", help="coarse meshes, one scene, no FE influence numbers")
    ap.add_argument("--no-fe", action="store_true", help="skip conformal with FE influence numbers")
    ap.add_argument("--scenes", default="", help="comparison: these scenes only (comma-separated: flange_y0, "
                    "flange_y6.2, flange_y6.25, groove); the others' parts are kept")
    ap.add_argument("--fec", default=None, help="comparison: fec_* keys as JSON for every scene (default: FE_MESH)")
    ap.add_argument("--mesh-study", default="", help="mesh study of one comparison scene (e.g. groove): "
                    "fe_contact meshes --fec-list and conformal grids --grid-list")
    ap.add_argument("--fec-list", default='[{"fec_h": 0.38}, {"fec_h": 0.27}, {"fec_h": 0.19}]',
                    help="mesh study: JSON list of fec_* key sets")
    ap.add_argument("--grid-list", default="[20, 40, 80]", help="mesh study: JSON list of [grid] n")
    ap.add_argument("--build", action="store_true", help="only rebuild comparison.* and run.json from the parts")
    ap.add_argument("--out", default=str(ROOT / "studies/out/fe_contact"))
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if a.build:
        data = build_comparison(out)
        write_sidecar(out, __file__, a, extra={"comparison_errors": _error_summary(data), "parts": data["scenes"]})
        return 0
    if a.mesh_study:
        mesh_study(out, a.mesh_study, json.loads(a.fec_list), json.loads(a.grid_list), fe_influence=not a.no_fe)
    elif not (a.convergence or a.comparison):
        a.convergence = a.comparison = True
    if a.convergence:
        convergence(out, a.quick)
    if a.comparison:
        only = [v.strip() for v in a.scenes.split(",") if v.strip()] or None
        data = comparison(out, a.quick, fe_influence=not (a.quick or a.no_fe), only=only,
                          fec_override=json.loads(a.fec) if a.fec else None)
        write_sidecar(out, __file__, a, extra={"comparison_errors": _error_summary(data), "parts": data["scenes"]})
    elif a.convergence or a.mesh_study:
        write_sidecar(out, __file__, a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
