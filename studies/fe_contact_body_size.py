"""The direct FE contact (theory "fe_contact") converged in body size: FN, pmax, area, approach over
``fec_body_size``, extrapolated in 1/size.

The FE contact meshes each body in a disc of ``fec_body_size`` patch sizes around the contact (a
profile that ends inside it is continued straight, conformal.meshing.bodies.grow_profile) and
imposes on the disc's cut faces either the half-space field of the contact forces
(``fec_far_field = "halfspace"``, the default) or zero displacement (``"clamped"``).  As for the
FE influence numbers (studies/fe_far_field_limit.py), the error of a finite body decays like
1/size, so the large-body limit follows by Richardson extrapolation of a doubling series,

    R2 = 2 v(2s) - v(s),    R3 = (8 v(4s) - 6 v(2s) + v(s)) / 3,

and the successive-difference ratio (v(4s) - v(2s)) / (v(2s) - v(s)) is 0.5 in that regime
(the ``richardson`` function of studies/fe_far_field_limit.py, reused here).

Case: the deep pair (meshes/scenes/deep_conformal_pair.toml: the rail corner R10 against the
flange root R10.2 at 45 degrees, long idealised profiles continued straight), the production
mesh (``fec_n`` 4, quadratic tetrahedra), sizes 1-16, both far fields; per size one meshing and
factorisation, solved at the prescribed approach 0.05 mm (FN) and at a prescribed load (the
half-space estimate's FN: pmax, contact area, approach).  Every row records what was built: each
body's disc radius, margin, profile closure and node count (the key asked for is not evidence).

    python studies/fe_contact_body_size.py            # the deep pair (about 20 min on a busy core)
    python studies/fe_contact_body_size.py --quick    # the deep pair, coarse, 4 solves (about 1 min; a test)

``--quick``: the deep pair on a coarser mesh (quadratic elements as the production mesh, 2 per
semi-axis instead of 4), clamped at sizes 4, 8, 16 and the half-space far field at 16: the
clamped series' limit against the half-space far field's value (two routes to the same large
body).  Its clamped FN lies within 1.2 % of the production mesh's at each size and its
successive-difference ratio is 0.50 (production: 0.47); linear elements on that mesh gave 0.30
(1.22, 0.53, 0.30 over sizes 1-16: each remeshing moved FN by about 1 %, the scale of the
differences at the larger sizes).

Output: studies/out/fe_contact_body_size/fe_contact_body_size.{md,json,png} and run.json.
"""
from __future__ import annotations

import argparse
import json
import os
import runpy
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "meshes" / "scenes"

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402

richardson = runpy.run_path(str(Path(__file__).resolve().parent / "fe_far_field_limit.py"))["richardson"]

SIZES = (1.0, 2.0, 4.0, 8.0, 16.0)
FARS = ("halfspace", "clamped")
QUICK_SIZES = (4.0, 8.0, 16.0)
DEEP_APPROACH = 0.05
KEYS = ("FN", "pmax_load", "area_load", "approach_load")
#: successive-difference ratios taken as the 1/size regime (0.5 there; the issue's band 0.5 +- 0.1,
#: widened to 0.3-0.8 before an R3 is trusted at all)
REGIME = (0.3, 0.8)
#: the acceptance of the default (issue: pair FN within 0.5 % of the size-converged limit)
FN_TOL = 0.005


# ----------------------------------------------------------------------------- runs
def deep_scene(size: float, far: str, coarse: bool = False):
    """The deep pair at the prescribed approach; ``coarse``: 2 (quadratic) elements per semi-axis."""
    from conformal.scene import load_scene

    sc = load_scene(SCENES / "deep_conformal_pair.toml").with_model(theory="fe_contact")
    sc = (sc.with_("load.approach", DEEP_APPROACH).with_("model.fec_body_size", float(size))
          .with_("model.fec_far_field", far))
    return sc.with_("model.fec_n", 2).with_("model.fec_order", 2) if coarse else sc


def run_deep(size: float, far: str, coarse: bool = False) -> dict:
    """One size and far field of the deep pair: FN at the approach; pmax, area and approach at the
    half-space estimate's FN taken as the load along the load direction (vertical; the same load
    at every size)."""
    from conformal.cases.fe_contact import edge_warning, run_wheel_rail

    t0 = time.perf_counter()
    run, _ = run_wheel_rail(deep_scene(size, far, coarse))
    t1 = time.perf_counter()
    load = float(run.info["estimate"]["FN"])
    at_load = run.model.solve(normal_force=load)
    sol = run.solution
    return {"case": "deep_coarse" if coarse else "deep", "far_field": far, "size": size, "FN": sol.FN,
            "pmax": sol.pmax, "F_load": sol.F_load,
            "area": sol.contact_area, "load": load, "pmax_load": at_load.pmax, "area_load": at_load.contact_area,
            "approach_load": at_load.approach, "n_unknowns": sol.n_unknowns, "columns": sol.stats.get("columns"),
            "solve_s": t1 - t0, "load_s": time.perf_counter() - t1, "bodies": run.info["bodies"],
            "warning": edge_warning(run)}


# ----------------------------------------------------------------------------- summary
def summarise(rows) -> dict:
    """Per case, far field and quantity: the Richardson limits of the doubling series."""
    out: dict = {}
    for case in dict.fromkeys(r["case"] for r in rows):
        for far in FARS:
            sel = sorted((r for r in rows if r["case"] == case and r["far_field"] == far), key=lambda r: r["size"])
            # the longest doubling run that ends at the largest size
            while len(sel) >= 2 and not np.allclose([b["size"] / a["size"] for a, b in zip(sel, sel[1:])], 2.0):
                sel = sel[1:]
            if len(sel) < 2:
                continue
            for k in KEYS:
                if all(k in r for r in sel):
                    out.setdefault(case, {}).setdefault(far, {})[k] = richardson([r["size"] for r in sel],
                                                                                   [r[k] for r in sel])
    return out


def converged(rows, summary) -> list[dict]:
    """Per case and quantity: the limit (R3 of the half-space far field's series, else R2), its
    error bar (|R2 - R3| and the clamped series' limit against it), the clamped series' limits
    and ratio, the half-space far field's value at its largest size, and every half-space size's
    distance from the limit."""
    out = []
    for case, per in summary.items():
        hs, cl = per.get("halfspace", {}), per.get("clamped", {})
        for k in dict.fromkeys(list(hs) + list(cl)):
            h, c = hs.get(k, {}), cl.get(k, {})
            hs_rows = sorted((r for r in rows if r["case"] == case and r["far_field"] == "halfspace" and k in r),
                             key=lambda r: r["size"])
            row = {"case": case, "quantity": k, "clamped_R2": c.get("R2"), "clamped_R3": c.get("R3"),
                   "clamped_ratio": c.get("ratio"),
                   "halfspace_largest": hs_rows[-1][k] if hs_rows else None,
                   "halfspace_largest_size": hs_rows[-1]["size"] if hs_rows else None}
            if h:
                vals = [r[k] for r in hs_rows]
                if "R3" in h and REGIME[0] <= h["ratio"] <= REGIME[1]:
                    best, how = h["R3"], "R3"
                    bars = [abs(h["R2"] - best)]
                else:
                    # no 1/size trend above the mesh scatter: the mean of the two largest sizes,
                    # with the scatter of the whole series about it as its error bar
                    best, how = 0.5 * (vals[-1] + vals[-2]), "mean of the two largest sizes"
                    bars = [0.5 * abs(vals[-1] - vals[-2]), float(np.std(vals))]
                bars += [abs(c.get("R3", c["R2"]) - best)] if c and (c.get("ratio") is None
                                                                    or REGIME[0] <= c["ratio"] <= REGIME[1]) else []
                row.update(limit=best, how=how, R2=h["R2"], R3=h.get("R3"), ratio=h.get("ratio"), err=max(bars),
                           off={f"{r['size']:g}": r[k] / best - 1.0 for r in hs_rows})
            out.append(row)
    return out


def choose_default(rows, conv, tol: float = FN_TOL) -> dict:
    """The smallest size of the half-space series whose FN at the approach is within ``tol`` of
    the limit (and stays so at every larger size), with its time against size 1's."""
    fn = next((c for c in conv if c["case"] == "deep" and c["quantity"] == "FN"), None)
    if fn is None:
        return {}
    hs = sorted((r for r in rows if r["case"] == "deep" and r["far_field"] == "halfspace"), key=lambda r: r["size"])
    if "off" not in fn:
        return {}
    ok = [abs(fn["off"][f"{r['size']:g}"]) <= tol for r in hs]
    pick = next((r for i, r in enumerate(hs) if all(ok[i:])), None)
    base = next((r for r in hs if r["size"] == 1.0), None)
    if pick is None:
        return {"size": None, "tol": tol}
    cost = lambda r: r["solve_s"]  # noqa: E731
    return {"size": pick["size"], "tol": tol, "FN_off": fn["off"][f"{pick['size']:g}"],
            "time_ratio": cost(pick) / cost(base) if base else None,
            "unknowns_ratio": pick["n_unknowns"] / base["n_unknowns"] if base else None}


# ----------------------------------------------------------------------------- report
def report(rows, summary, conv, pick) -> str:
    lines = ["| case | far field | size | disc radius rail / wheel (mm) | nodes rail / wheel | unknowns | FN at "
             "approach (N) | pmax at load | area at load (mm²) | approach at load (mm) | time (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r["case"], r["far_field"], r["size"])):
        b = r.get("bodies", {})
        rad = " / ".join(f"{v.get('disc_radius_mm', v.get('depth_mm', float('nan'))):.1f}" for v in b.values())
        nodes = " / ".join(str(v.get("nodes")) for v in b.values())
        lines.append(f"| {r['case']} | {r['far_field']} | {r['size']:g} | {rad} | {nodes} | {r['n_unknowns']} | "
                     f"{r['FN']:.1f} | {r.get('pmax_load', r['pmax']):.1f} | {r.get('area_load', r['area']):.2f} | "
                     f"{r.get('approach_load', float('nan')):.5f} | {r['solve_s']:.0f} |")
    lines += ["", "| case | quantity | half-space: limit | how | R3 | R2 | ratio of differences | error bar | "
              "clamped: R3 | R2 | ratio | half-space at the largest size | distance of each half-space size from "
              "the limit |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]

    def f(v, fmt="{:.5g}"):
        return "-" if v is None else fmt.format(v)

    for c in conv:
        offs = ", ".join(f"{s}: {v:+.2%}" for s, v in c.get("off", {}).items()) or "-"
        lines.append(f"| {c['case']} | {c['quantity']} | {f(c.get('limit'))} | {c.get('how', '-')} | "
                     f"{f(c.get('R3'))} | {f(c.get('R2'))} | "
                     f"{f(c.get('ratio'), '{:.2f}')} | {f(c.get('err'), '{:.3g}')} | {f(c['clamped_R3'])} | "
                     f"{f(c['clamped_R2'])} | {f(c['clamped_ratio'], '{:.2f}')} | {f(c['halfspace_largest'])} "
                     f"({f(c['halfspace_largest_size'], '{:g}')}) | {offs} |")
    if pick:
        lines += ["", f"Smallest size with FN at the approach within {pick['tol']:.1%} of the limit at it and every "
                  f"larger size: {pick['size']}" + ("" if pick.get("size") is None else
                                                   f" ({pick['FN_off']:+.2%}; time {pick['time_ratio']:.2f} x, "
                                                   f"unknowns {pick['unknowns_ratio']:.2f} x size 1's)")]
    warn = sorted({r["warning"] for r in rows if r.get("warning")})
    if warn:
        lines += [""] + [f"Warning: {w}" for w in warn]
    return "\n".join(lines) + "\n"


def plot(rows, summary, conv, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = list(dict.fromkeys(r["case"] for r in rows))
    keys = [k for k in KEYS if any(k in r for r in rows)]
    fig, axes = plt.subplots(len(cases), len(keys), figsize=(3.6 * len(keys), 3.3 * len(cases)), squeeze=False)
    for i, case in enumerate(cases):
        for j, k in enumerate(keys):
            ax = axes[i][j]
            for far, style in (("halfspace", "-o"), ("clamped", "--s")):
                sel = sorted((r for r in rows if r["case"] == case and r["far_field"] == far and k in r),
                             key=lambda r: r["size"])
                if not sel:
                    continue
                ax.plot([1 / r["size"] for r in sel], [r[k] for r in sel], style, ms=4, label=far)
                lim = summary.get(case, {}).get(far, {}).get(k)
                star = None
                if far == "halfspace":
                    star = next((c.get("limit") for c in conv if c["case"] == case and c["quantity"] == k), None)
                elif lim and "R3" in lim and REGIME[0] <= lim["ratio"] <= REGIME[1]:
                    star = lim["R3"]
                if star is not None:
                    ax.plot([0], [star], "*", ms=10, color=ax.lines[-1].get_color())
            ax.set_xlabel("1 / fec_body_size")
            unit = {"FN": "N", "pmax_load": "N/mm²", "area_load": "mm²", "approach_load": "mm"}[k]
            ax.set_title(f"{case}: {k} ({unit})", fontsize=9)
            ax.tick_params(labelsize=8)
            ax.legend(fontsize=7)
    fig.suptitle("fe_contact (deep pair R10/R10.2) over the body size; stars: the limits (half-space far field: "
                 "R3 in the 1/size regime, else the mean of the two largest sizes; clamped: R3 in that regime)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _dump(out: Path, payload: dict) -> None:
    tmp = out / "fe_contact_body_size.json.tmp"
    tmp.write_text(json.dumps(payload, indent=1, default=float))
    os.replace(tmp, out / "fe_contact_body_size.json")


def finish(out: Path, rows, args=None) -> dict:
    summary = summarise(rows)
    conv = converged(rows, summary)
    pick = choose_default(rows, conv)
    payload = {"rows": rows, "summary": summary, "converged": conv, "default_choice": pick}
    _dump(out, payload)
    text = report(rows, summary, conv, pick)
    tmp = out / "fe_contact_body_size.md.tmp"
    tmp.write_text(text)
    os.replace(tmp, out / "fe_contact_body_size.md")
    plot(rows, summary, conv, out / "fe_contact_body_size.png")
    if args is not None:
        write_sidecar(out, __file__, args, extra={"default_choice": pick})
    print(text)
    return payload


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the deep pair, coarser mesh, clamped 4-16 and half-space 16")
    ap.add_argument("--out", default=None, help="output folder (default studies/out/fe_contact_body_size)")
    ap.add_argument("--sizes", default=",".join(f"{s:g}" for s in SIZES), help="comma-separated body sizes")
    ap.add_argument("--far", default=",".join(FARS), help="comma-separated far fields: halfspace, clamped")
    ap.add_argument("--append", action="store_true", help="keep the existing JSON's other rows")
    ap.add_argument("--report", action="store_true", help="only rebuild md and png from the JSON")
    args = ap.parse_args(argv)
    out = output_dir("fe_contact_body_size", args)
    out.mkdir(parents=True, exist_ok=True)
    rows: list[dict] = []
    if args.report:
        finish(out, json.loads((out / "fe_contact_body_size.json").read_text())["rows"])
        return 0
    if args.quick:
        for s in QUICK_SIZES:
            rows.append(run_deep(s, "clamped", coarse=True))
        rows.append(run_deep(QUICK_SIZES[-1], "halfspace", coarse=True))
        finish(out, rows, args)
        return 0
    sizes = [float(v) for v in args.sizes.split(",") if v]
    fars = [v for v in args.far.split(",") if v]
    if args.append and (out / "fe_contact_body_size.json").exists():
        old = json.loads((out / "fe_contact_body_size.json").read_text())["rows"]
        rows = [r for r in old if not (r["far_field"] in fars and r["size"] in sizes)]
    for far in fars:
        for s in sizes:
            r = run_deep(s, far)
            rows.append(r)
            print(f"deep {far:9s} size {s:4g}: FN {r['FN']:.1f} N, pmax@load {r['pmax_load']:.1f}, area@load "
                  f"{r['area_load']:.2f}, approach@load {r['approach_load']:.5f}, {r['n_unknowns']} unknowns, "
                  f"{r['solve_s']:.0f} s; discs {[v['disc_radius_mm'] for v in r['bodies'].values()]}", flush=True)
            _dump(out, {"rows": rows})
    finish(out, rows, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
