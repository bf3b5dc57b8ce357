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

Outputs in --out (default studies/out/fe_contact): convergence.json/.md/.png,
comparison.json/.md/.png, and fe_contact_<scene>.vtu (rail surface with the pressure).

    nice python studies/fe_contact_reference.py --convergence      # ~10 minutes
    nice python studies/fe_contact_reference.py --comparison       # ~15 minutes (FE numbers cached)
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
        out.append((f"flange_y{shift:g}", replace(flange, geometry=replace(flange.geometry, lateral_shift=shift))))
    if not quick:
        out.append(("groove", groove))
    # frictionless comparison: no creepage, so that every model solves the normal problem alone
    return [(name, replace(sc, kinematics=replace(sc.kinematics, speed=None, xi=0.0, eta=0.0, phi=0.0,
                                                  fx_rel=None, fy_rel=None))) for name, sc in out]


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
    from conformal.solve import solve_scene

    opts = dict(scene.model.options)
    opts.update(options)
    sc = scene.with_model(theory=theory, influence=influence, options=opts)
    t0 = time.perf_counter()
    r = solve_scene(sc)
    return r, time.perf_counter() - t0


def comparison(out: Path, quick: bool, fe_influence: bool) -> dict:
    from conformal.cases.fe_contact import result_from_run, run_wheel_rail
    from conformal.fe_contact.problems import write_vtu

    rows, profiles = [], {}
    for name, scene in _scenes(quick):
        # mesh: the default fec_n = 4 takes its size from the whole strip, 1.27 mm at 6.25 mm shift,
        # too coarse for the root + flank contact (FN 5 % off h = 0.8 mm, which agrees with
        # h = 0.6 mm within 0.2 %): fec_h = 0.8 mm on the flange scenes.  The deep groove's slender
        # strip (15 mm along s, 1.7 mm along x) at fec_n = 4 needs more than 10 minutes and
        # 3.4 GiB here: fec_n = 2 (h = 0.38 mm) for it
        fec_opts = {"fec_n": 2, "fec_order": 1} if quick else ({"fec_n": 2} if name == "groove" else {"fec_h": 0.8})
        # prescribed approach: the overlap the conformal half-space model reaches at the wheel load
        ref, _ = _solve(scene, "conformal", {})
        for mode in ("load", "approach"):
            # [load] approach counts the wheelset height from first touch: the height the conformal
            # half-space model finds for the wheel load, so that every model sees the same overlap
            sc = scene if mode == "load" else replace(scene, load=replace(scene.load, wheel_load=None,
                                                                            approach=float(ref.approach)))
            models = [("fe_contact", "fe_contact", fec_opts, "halfspace"),
                      ("conformal_fe", "conformal", {}, "fe"),
                      ("conformal_hs", "conformal", {}, "halfspace"),
                      ("exact", "exact", {}, "halfspace")]
            if not fe_influence:
                models = [m for m in models if m[0] != "conformal_fe"]
            res = {}
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
                res[label] = r
                row = {"scene": name, "mode": mode, "model": label, "FN": r.FN, "pmax": r.pmax,
                       "area": _area(r), "approach": r.approach, "wall_s": wall,
                       "n_unknowns": r.extra.get("n_unknowns"), "fe_contact": r.extra.get("fe_contact")}
                rows.append(row)
                s, p = _profile(r)
                profiles[f"{name}|{mode}|{label}"] = {"s": np.asarray(s).tolist(), "p": np.asarray(p).tolist()}
                print(f"{name:12s} {mode:8s} {label:13s} FN {r.FN:9.1f}  pmax {r.pmax:7.1f}  area {row['area']:6.2f}  "
                      f"approach {r.approach:.4f}  {wall:6.1f} s", flush=True)
            ref_row = next((x for x in rows if x["scene"] == name and x["mode"] == mode and x["model"] == "fe_contact"
                            and "FN" in x), None)
            if ref_row:
                for x in rows:
                    if x["scene"] == name and x["mode"] == mode and "FN" in x:
                        for q in ("FN", "pmax", "area"):
                            x[f"err_{q}"] = x[q] / ref_row[q] - 1.0
                        x["time_ratio"] = x["wall_s"] / ref_row["wall_s"]
    data = {"rows": rows, "profiles": profiles,
            "measured_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime())}
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
    (out / "comparison.md").write_text("\n".join(lines) + "\n")
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--convergence", action="store_true")
    ap.add_argument("--comparison", action="store_true")
    ap.add_argument("--quick", action="store_true", help="coarse meshes, one scene, no FE influence numbers")
    ap.add_argument("--no-fe", action="store_true", help="skip conformal with FE influence numbers")
    ap.add_argument("--out", default=str(ROOT / "studies/out/fe_contact"))
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if not (a.convergence or a.comparison):
        a.convergence = a.comparison = True
    if a.convergence:
        convergence(out, a.quick)
    if a.comparison:
        comparison(out, a.quick, fe_influence=not (a.quick or a.no_fe))
    return 0


if __name__ == "__main__":
    sys.exit(main())
