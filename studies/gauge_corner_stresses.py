"""Gauge-corner stresses: where the rail head and the wheel flange root are loaded hardest.

S1002 wheelset on UIC 60 rails (1:40), 10 kN per wheel, the flange root against the gauge corner
at lateral shifts 6.2 and 6.25 mm (meshes/scenes/flange_s1002_uic60.toml), and the deep conformal
pair (meshes/scenes/deep_conformal_pair.toml: rail corner R 10 against flange root R 10.2).  Each
is solved with the conformal theory (curved strip), with half-space and with FE influence numbers
of the real bodies; then the subsurface stresses of both bodies follow from the solved tractions
(conformal.stresses: the closed-form field of each element in its own frame, summed; FFT along x):

* "strip": every element in its own frame (tangent, profile tangent, inner normal) on the curved
  surface; the stresses along the normals of the element centres;
* "tangent plane": the same tractions on the developed (flat) strip, as a planar half-space
  theory would place them.

Per case, influence model, body and frame: the maxima of von Mises, the principal shear
(s1 - s3)/2 and the orthogonal shear sigma_xn with their depths and positions (rail-profile frame,
mm), the surface fatigue index FI_surf (shakedown map, k = 300 N/mm²) and the Dang Van index
(alpha = 1/3, tau_e = 300 N/mm²).  Then the stresses inside the FE rail (conformal.stresses.bodies:
half-space field of the elements on their tangent planes plus the FE correction of the real rail,
one FE solve with the final load) and inside the FE wheel (the opposite tractions in the wheel's
element frames), each on the cross-section through that body's half-space von Mises maximum,
against the half-space stresses at the same points ("FE body, section" and "half-space, same
section"), and over the whole block of the half-space field with the Dang Van index of the rolling
pass ("FE body, whole block" and "half-space, whole block"; the wheel's block on circles about its
axle, conformal.stresses.bodies).

Writes to --out (default studies/out/gauge_corner_stresses): gauge_corner_stresses.csv, .md, and
<case>_<influence>_rail.png / _wheel.png (slices, von Mises and orthogonal shear, per-depth maxima),
<case>_<influence>_fe_section.png / _fe_section_wheel.png (von Mises in the half-space and in the
FE rail / wheel on the section; _3d.png: the section in 3-D), and with --vtu
<case>_<influence>_fe_rail.vtu / _fe_wheel.vtu (the FE bodies around the patch, for ParaView).

    python studies/gauge_corner_stresses.py             # all cases, half-space and FE (minutes: FE)
    python studies/gauge_corner_stresses.py --no-fe     # half-space influence numbers only
    python studies/gauge_corner_stresses.py --no-fe --n 24   # coarser strips, FE bodies (the committed outputs)
    python studies/gauge_corner_stresses.py --quick --out DIR   # 6.2 mm, coarse grid, half-space (seconds)
"""
from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from conformal.errors import ConformalError  # noqa: E402
from conformal.result import TractionField  # noqa: E402
from conformal.scene import load_scene  # noqa: E402
from conformal.dispatch import solve_scene  # noqa: E402
from conformal.stresses.fatigue import FatigueParameters, surface_index  # noqa: E402
from conformal.stresses.field import StressField, default_depths, stress_field  # noqa: E402
from conformal.stresses.halfspace import planar_planes  # noqa: E402
from conformal.stresses.plots import plot_stress_field  # noqa: E402

FLANGE = ROOT / "meshes" / "scenes" / "flange_s1002_uic60.toml"
DEEP = ROOT / "meshes" / "scenes" / "deep_conformal_pair.toml"
CASES = (("flange_6.2", FLANGE, 6.2), ("flange_6.25", FLANGE, 6.25), ("deep_pair", DEEP, None))
PARAMS = FatigueParameters()


def tangent_plane(result, depths, nu, body) -> StressField:
    """The strip's tractions on its developed (flat) grid: the planar half-space estimate."""
    f = result.field
    flat = TractionField(f.grid, pn=f.pn, px=f.px, py=f.py, status=f.status)
    sig = planar_planes(flat, depths, nu=nu, body=body)
    X, Y = f.grid.mesh()
    pts = np.empty(sig.shape[:-1])
    pts[..., 0], pts[..., 1] = X[None], Y[None]
    pts[..., 2] = depths[:, None, None] * (1 if body == 1 else -1)
    return StressField(sig, pts, np.asarray(depths), np.broadcast_to([0.0, 0.0, 1.0 if body == 1 else -1.0],
                       (f.grid.my, 3)).copy(), "planar", body)


def run_case(name, path, shift, influence, args):
    scene = load_scene(path)
    over = {"model": {"influence": influence}}
    if shift is not None:
        over["geometry"] = {"lateral_shift": shift}
    if args.quick:
        over["grid"] = {"n": 16}
    elif args.n:
        over["grid"] = {"n": args.n}
    scene = scene.with_(**{f"{s}__{k}": v for s, kv in over.items() for k, v in kv.items()})
    if args.fe_h_load is not None:      # the FE body meshes (and FE influence numbers) at the loaded column
        scene = scene.with_model(options=dict(scene.model.options, fe_h_load=args.fe_h_load))
    t0 = time.perf_counter()
    result = solve_scene(scene)
    t_solve = time.perf_counter() - t0
    rows, fields = [], {}
    depths = default_depths(result.a, result.b, None, 20 if args.quick else 40)
    fi = surface_index(result.FN, result.FX, result.FY, result.a, result.b, PARAMS.k)
    for body, who in ((1, "rail"), (2, "wheel")):
        nu = scene.material.nu1 if body == 1 else scene.material.nu2
        t1 = time.perf_counter()
        sf = stress_field(result.field, depths, nu=nu, body=body)
        t_st = time.perf_counter() - t1
        fields[who] = sf
        for frame, s in (("strip", sf), ("tangent plane", tangent_plane(result, depths, nu, body))):
            sm = s.summary(PARAMS)
            rows.append({"case": name, "influence": influence, "body": who, "frame": frame,
                         "FN": result.FN, "FX": result.FX, "FY": result.FY, "pmax": result.pmax,
                         "a": result.a, "b": result.b,
                         "max_von_mises": sm["max_von_mises"], "vm_depth": sm["max_von_mises_depth"],
                         "vm_y": sm["max_von_mises_position"][1], "vm_z": sm["max_von_mises_position"][2],
                         "max_shear": sm["max_shear"], "shear_depth": sm["max_shear_depth"],
                         "max_orthogonal_shear": sm["max_orthogonal_shear"],
                         "orth_depth": sm["max_orthogonal_shear_depth"],
                         "FI_surf": fi, "tau_dv": sm["dang_van"]["tau_dv_max"], "dv_depth": sm["dang_van"]["depth"],
                         "FI_sub": sm["dang_van"]["FI_sub"], "solve_s": t_solve, "stress_s": t_st,
                         "surface_check": surface_check(result, sf) if frame == "strip" else ""})
    if not args.quick and not args.no_fe_body:
        from conformal.stresses.run import fe_body_section_data, fe_section_figures

        figures = []                                   # drawn after both bodies are meshed (gmsh before VTK)
        for who in ("rail", "wheel"):
            t1 = time.perf_counter()
            stem = f"{name}_{influence}_fe_section" + ("" if who == "rail" else "_wheel")
            vtu = Path(args.out) / f"{name}_{influence}_fe_{who}.vtu" if args.vtu else None
            sec, pts, bs, hs_sigma = fe_body_section_data(result, scene, fields[who], vtu=vtu, params=PARAMS)
            figures.append((fields[who], pts, bs, hs_sigma, Path(args.out) / f"{stem}.png"))
            base = next(r for r in rows if r["body"] == who and r["frame"] == "strip")
            for frame, m, dv in (("FE body, section", sec["fe"], None),
                                 ("half-space, same section", sec["halfspace"], None),
                                 ("FE body, whole block", sec["block"]["fe"], sec["dang_van"]["fe"]),
                                 ("half-space, whole block", sec["block"]["halfspace"], sec["dang_van"]["halfspace"])):
                nan = float("nan")
                rows.append({**{k: base[k] for k in ("case", "influence", "FN", "FX", "FY", "pmax", "a", "b", "FI_surf")},
                             "body": who, "frame": frame, "max_von_mises": m["max_von_mises"],
                             "vm_depth": m["max_von_mises_depth"], "vm_y": m["max_von_mises_position"][1],
                             "vm_z": m["max_von_mises_position"][2], "max_shear": m["max_shear"],
                             "shear_depth": m["max_shear_depth"], "max_orthogonal_shear": m["max_orthogonal_shear"],
                             "orth_depth": m["max_orthogonal_shear_depth"],
                             "tau_dv": dv["tau_dv_max"] if dv else nan, "dv_depth": dv["depth"] if dv else nan,
                             "FI_sub": dv["FI_sub"] if dv else nan, "solve_s": t_solve,
                             "stress_s": time.perf_counter() - t1,
                             "surface_check": f"x = {sec['section_x']:.2f} mm, max |sigma_c| "
                                              f"{sec['max_correction'] if dv is None else sec['max_correction_block']:.1f}, "
                                              f"{sec['stats']['dofs']} unknowns"})
            print(f"  FE {who}: {sec['stats']['dofs']} unknowns, {time.perf_counter() - t1:.0f} s", flush=True)
        for sf, pts, bs, hs_sigma, fig in figures:
            fe_section_figures(result, scene, sf, pts, bs, hs_sigma, fig)
    return result, rows, fields


def surface_check(result, sf) -> float:
    """max |sigma_nn + pn| / pmax on the surface (depth 0) at the element centres: how well the
    superposed field meets the traction boundary condition sigma_nn = -p on the curved surface.
    Each element meets it exactly on its own tangent plane; its neighbours' planes pass the point
    at a small height (d²/2R), so a strip on a curved surface misses it by a fraction of pmax
    (zero on a flat strip)."""
    f = result.field
    cols = np.flatnonzero(np.any(np.asarray(f.side_frame("pn")) > 0, axis=0))
    lo = max(int(cols[0]) - 1, 0)
    n = sf.normal                                               # (nc, 3)
    snn = np.einsum("xci,xcij,xcj->xc", np.broadcast_to(n, sf.sigma.shape[1:3] + (3,)), sf.sigma[0],
                    np.broadcast_to(n, sf.sigma.shape[1:3] + (3,)))
    pn = np.asarray(f.side_frame("pn"))[:, lo:lo + snn.shape[1]]
    sgn = 1.0
    return float(np.abs(snn + sgn * pn).max() / result.pmax)


def write_md(rows, path: Path) -> None:
    head = ("| case | influence | body | frame | FN (N) | pmax | max von Mises (depth) | max (s1-s3)/2 (depth) | "
            "max orth. shear (depth) | FI_surf | Dang Van tau (depth) | FI_sub |")
    lines = ["Stresses in N/mm², depths in mm (below the surface along the normal of the element).", "",
             head, "|" + "---|" * 12]
    for r in rows:
        lines.append(f"| {r['case']} | {r['influence']} | {r['body']} | {r['frame']} | {r['FN']:.0f} | {r['pmax']:.0f} | "
                     f"{r['max_von_mises']:.0f} ({r['vm_depth']:.2f}) | {r['max_shear']:.0f} ({r['shear_depth']:.2f}) | "
                     f"{r['max_orthogonal_shear']:.0f} ({r['orth_depth']:.2f}) | {r['FI_surf']:.3f} | "
                     + (f"{r['tau_dv']:.0f} ({r['dv_depth']:.2f}) | {r['FI_sub']:.0f} |" if r["tau_dv"] == r["tau_dv"]
                        else "- | - |"))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="6.2 mm only, coarse grid, half-space, no FE")
    ap.add_argument("--no-fe", action="store_true", help="half-space influence numbers only")
    ap.add_argument("--no-fe-body", action="store_true", help="no FE body stresses (conformal.stresses.bodies)")
    ap.add_argument("--cases", help="comma-separated subset of " + ", ".join(c[0] for c in CASES))
    ap.add_argument("--fe-h-load", type=float, help="[model] fe_h_load of the FE bodies (default: the scene's)")
    ap.add_argument("--vtu", action="store_true", help="also write the FE bodies' stresses as VTU (ParaView)")
    ap.add_argument("--n", type=int, help="[grid] n of every scene (default: the scenes' 40 and 30)")
    ap.add_argument("--out", help="output folder")
    args = ap.parse_args(argv)
    out = output_dir("gauge_corner_stresses", args)
    cases = CASES[:1] if args.quick else CASES
    if args.cases:
        want = args.cases.split(",")
        bad = sorted(set(want) - {c[0] for c in CASES})
        if bad:
            ap.error(f"--cases: unknown case {bad[0]!r}")
        cases = tuple(c for c in CASES if c[0] in want)
    models = ("halfspace",) if (args.quick or args.no_fe) else ("halfspace", "fe")
    rows, notes = [], []
    for name, path, shift in cases:
        for influence in models:
            try:
                result, rr, fields = run_case(name, path, shift, influence, args)
            except ConformalError as exc:
                notes.append(f"{name} / {influence}: {exc}")
                print(f"{name} / {influence}: FAILED {exc}", file=sys.stderr)
                continue
            rows += rr
            for who, sf in fields.items():
                surf = result.field.curved.rail_curve
                plot_stress_field(sf, out / f"{name}_{influence}_{who}.png",
                                  title=f"{name}, {influence} influence numbers: half-space stresses in the {who} "
                                        f"(rail-profile frame; FN {result.FN:.0f} N, pmax {result.pmax:.0f} N/mm²)",
                                  dang_van_alpha=PARAMS.alpha_dv, surface=surf)
            print(f"{name} / {influence}: FN {result.FN:.0f} N, rail max von Mises {rr[0]['max_von_mises']:.0f} "
                  f"N/mm² at {rr[0]['vm_depth']:.2f} mm", flush=True)
    if rows:
        with (out / "gauge_corner_stresses.csv").open("w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
        write_md(rows, out / "gauge_corner_stresses.md")
    write_sidecar(out, __file__, args, extra={"notes": notes, "params": {"k": PARAMS.k, "alpha_dv": PARAMS.alpha_dv,
                                                                          "tau_e": PARAMS.tau_e}})
    return 0 if rows else 1


if __name__ == "__main__":
    sys.exit(main())
