"""Why the real-section ground truth differs from the contact models on the flange scene (issue 20,
item 3): defect checks, the structural deflection of the rail head and the wheel rim, the load
split, and the contact models placed where the truth's deformed bodies put the surfaces.

For each scene of :mod:`fe_ground_truth` (S1002 / UIC60 flange root at 6.2 and 6.25 mm, 10 kN)
the truth (``fec_body = "section"``: 60E1 rail clamped at the foot and the ends, wheel rim + web
clamped at the hub and the sector cuts, quadratic tetrahedra from a / 6) is solved once and then
its displacement field recovered (:meth:`conformal.fe_contact.solver.ContactModel.displacements`):

* **Defect checks** -- where the clamped nodes lie (foot / rail ends / hub / sector cuts, and how
  far from the contact); the vertical force carried (= the prescribed wheel load); the load
  direction and the 1:40 cant used by both models; the tread gap (a second patch?).
* **Structural deflection** -- the rigid-body motion (translation and rotation) that fits the
  displacement of the rail head's and the wheel rim's nodes in the cross-section through the
  contact (|x| < 6 mm), farther than R = 20 or 30 mm from the contact centre (beyond that the
  local contact deformation of a half-space decays as 1/r: at 20 mm about 1 µm).  Their
  difference, taken at the rail's gauge point (14 mm below the top, about which the package's
  placement turns the rail for a cant), is the relative pose change that the contact models
  do not contain: a lateral shift and a roll of the rail head against the wheel rim.
* **The contact models moved by that pose change** -- conformal contact with half-space numbers
  at ``lateral_shift + dy`` and ``rail_cant - dtheta``; if the difference is structural and not a
  defect, it meets the truth there.  This check shares no assumption with the truth: the pose
  change is measured on the truth's bodies away from the contact, the contact model is the
  half-space one.
* **Load split** -- there is no second (tread) patch at 6.2 or 6.25 mm (tread gap >= 0.26 mm), so
  the split is the share of FN on the flange flank: at rail contact angles steeper than 45 degrees
  (side frame), and the ratio of lateral to vertical force L/V = |FY| / FZ.

Outputs in studies/out/fe_truth_structure/: parts/<scene>.json, structure.json/.md, run.json.

    nice python studies/fe_truth_structure.py --scenes flange_y6.25      # ~10 min on the shared machine
    python studies/fe_truth_structure.py --quick                         # coarse truth at 6.25 mm (a test)
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "studies"))
import fe_ground_truth as gt  # noqa: E402
from _provenance import write_sidecar  # noqa: E402

OUT = ROOT / "studies" / "out" / "fe_truth_structure"
RADII = (20.0, 30.0)          # mm: nodes nearer the contact centre are left out of the rigid fits
SLICE = 6.0                   # mm: |x| of the cross-section slab of the fits
RAIL_HEAD_Z = 36.0            # mm below the rail top: the head (its underside starts at 39 mm)
RIM_DEPTH = 50.0              # mm below the tape circle: the rim (its inner face at 55 mm)
GAUGE_HEIGHT = 14.0           # mm: the gauge point below the top


def rigid_fit(P: np.ndarray, U: np.ndarray, c: np.ndarray) -> dict:
    """Least-squares rigid motion u = t + w x (p - c) of points P (n, 3) with displacements U:
    t (at c), w, the rms residual and the largest |U|."""
    r = P - c
    n = len(P)
    M = np.zeros((3 * n, 6))
    M[:, :3] = np.tile(np.eye(3), (n, 1))
    S = np.zeros((n, 3, 3))                 # -[r]x: w x r = -r x w
    S[:, 0, 1], S[:, 0, 2] = r[:, 2], -r[:, 1]
    S[:, 1, 0], S[:, 1, 2] = -r[:, 2], r[:, 0]
    S[:, 2, 0], S[:, 2, 1] = r[:, 1], -r[:, 0]
    M[:, 3:] = S.reshape(3 * n, 3)
    sol, *_ = np.linalg.lstsq(M, U.ravel(), rcond=None)
    res = U.ravel() - M @ sol
    return {"t": sol[:3].tolist(), "w": sol[3:].tolist(), "n": int(n),
            "rms_residual": float(np.sqrt(np.mean(res ** 2))), "max_u": float(np.abs(U).max())}


def _at(fit: dict, p: np.ndarray, c: np.ndarray) -> np.ndarray:
    return np.asarray(fit["t"]) + np.cross(np.asarray(fit["w"]), p - c)


def gauge_point(rail_yz: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The rail profile's gauge point (rail-profile frame): GAUGE_HEIGHT below the top along the
    load direction d, on the gauge side (the smallest lateral coordinate)."""
    depth = rail_yz @ d[1:]
    e_lat = np.array([d[2], -d[1]])
    top = depth.min()
    near = np.abs(depth - top - GAUGE_HEIGHT) < 0.5
    i = np.where(near)[0][np.argmin(rail_yz[near] @ e_lat)]
    return np.array([0.0, *rail_yz[i]])


def _clamp_report(body, kind: str, c: np.ndarray, sec_x: float) -> dict:
    """Where the clamped nodes of a body lie (its own frame) and how far from the contact."""
    from conformal.meshing.gmsh_body import cross_section_coordinates

    m = body.mesh
    nodes = np.unique(m.clamped_tris)
    x, yz = cross_section_coordinates(m.body, m.extent, m.points[nodes])
    ends = np.abs(np.abs(x) - sec_x) < 1e-3 * sec_x
    if kind == "rail":
        base = np.abs(yz[:, 1] - yz[:, 1].max()) < 1e-3          # the foot's lower face (largest z)
        base_name = "foot (z = %.1f mm)" % float(yz[:, 1].max())
    else:
        base = np.abs(yz[:, 1] - yz[:, 1].min()) < 1e-3          # the hub face (smallest z)
        base_name = "hub (z = %.1f mm)" % float(yz[:, 1].min())
    other = ~(ends | base)
    dist = np.linalg.norm(body.points[nodes] - c, axis=1)
    return {"clamped_nodes": int(nodes.size), "on_" + ("foot" if kind == "rail" else "hub"): int(base.sum()),
            "on_end_faces": int(ends.sum()), "elsewhere": int(other.sum()), "base": base_name,
            "end_faces_x": float(sec_x), "nearest_to_contact_mm": float(dist.min())}


def measure(scene, opts: dict) -> dict:
    """Solve the truth and measure its structural deflection (see the module docstring)."""
    from conformal.cases.fe_contact import load_direction, result_from_run, run_wheel_rail
    from conformal.meshing.gmsh_body import cross_section_coordinates

    sc = scene.with_model(theory="fe_contact", options=dict(scene.model.options, **opts))
    t0 = time.perf_counter()
    run, prob = run_wheel_rail(sc)
    res = result_from_run(run, prob, sc)
    sol = run.solution
    u1, u2 = run.model.displacements(sol)
    wall = time.perf_counter() - t0
    grid = prob.grid
    d = load_direction(grid)
    e_lat = np.array([0.0, d[2], -d[1]])
    act = sol.active
    f = sol.force[act]
    c = (sol.X[act] * f[:, None]).sum(axis=0) / f.sum()                # load centre, common frame
    # defect checks
    b1, b2 = run.body1, run.body2
    xr1 = float(b1.mesh.stats["x_range"][1])
    xr2 = float(b2.mesh.stats["x_range"][1])
    checks = {"F_load": sol.F_load, "wheel_load": scene.load.wheel_load,
              "load_direction": d.tolist(), "cant": float(grid.cant),
              "cant_from_direction": float(math.atan2(-d[1], d[2])),
              "rail": _clamp_report(b1, "rail", c, xr1), "wheel": _clamp_report(b2, "wheel", c, xr2),
              "rail_section": b1.mesh.stats.get("section"), "wheel_section": b2.mesh.stats.get("section"),
              "slave_edge": gt._slave_edge(run)}
    # rigid fits of the rail head and the wheel rim in the slab |x| < SLICE through the contact
    P1 = b1.points
    x1, yz1 = cross_section_coordinates(b1.mesh.body, b1.mesh.extent, b1.mesh.points)
    x2, yz2 = cross_section_coordinates(b2.mesh.body, b2.mesh.extent, b2.mesh.points)
    P2 = b2.points
    rail_yz = np.asarray(prob.rail_points, float)
    gp = gauge_point(np.column_stack([b1.mesh.body.profile.y, b1.mesh.body.profile.z]), d)
    fits = {}
    for R in RADII:
        head = (np.abs(x1) < SLICE) & (yz1[:, 1] < RAIL_HEAD_Z) & (np.linalg.norm(P1 - c, axis=1) > R)
        rim = (np.abs(x2) < SLICE) & (yz2[:, 1] > -RIM_DEPTH) & (np.linalg.norm(P2 - c, axis=1) > R)
        fr, fw = rigid_fit(P1[head], u1[head], c), rigid_fit(P2[rim], u2[rim], c)
        rel = _at(fw, gp, c) - _at(fr, gp, c)                    # wheel rim against rail head at the gauge point
        dtheta = fr["w"][0] - fw["w"][0]                          # roll of the rail head against the rim
        fits[f"R{R:g}"] = {"rail_head": fr, "wheel_rim": fw, "rel_at_gauge_point": rel.tolist(),
                           "dy_lateral": float(rel @ e_lat), "droll_rail": float(dtheta),
                           "rail_head_lateral": float(_at(fr, gp, c) @ e_lat),
                           "wheel_rim_lateral": float((_at(fw, gp, c) - sol.approach * d) @ e_lat)}
    s_grid = _grid_s(run, prob)
    rec = {"options": opts, "FN": res.FN, "pmax": res.pmax, "area": res.extra["contact_area"],
           "wall_s": wall, "n_unknowns": sol.n_unknowns, "h_contact": float(b1.mesh.patch.dx),
           "FY_side": res.extra["FY_side"], "FZ_side": res.extra["FZ_side"],
           "LV": abs(res.extra["FY_side"]) / res.extra["FZ_side"],
           "s_nodes": s_grid[act].tolist(), "f_nodes": f.tolist(),
           "contact_centre": c.tolist(), "gauge_point": gp.tolist(), "approach": sol.approach,
           "checks": checks, "fits": fits, "rail_points_n": int(len(rail_yz))}
    rec["s_flank"] = gt.flank_boundary(grid)
    rec["flank_share"] = gt.share(rec, rec["s_flank"])
    rec["LV_resultant"] = rec["LV"]
    rec["LV"] = gt.normal_lv(rec, grid)
    return rec


def _grid_s(run, prob) -> np.ndarray:
    """The slave nodes' arc length on the grid, from its reference point (mm)."""
    from conformal.influence.fe import rail_body_from_grid

    _, rpatch = rail_body_from_grid(prob.grid, prob.rail_points)
    return np.interp(run.solution.uv[:, 1], rpatch.edges, prob.grid.s_edges) - float(prob.grid.s_ref)


def conformal_at(scene, dy: float = 0.0, droll: float = 0.0) -> dict:
    """Conformal contact with half-space numbers, the wheelset moved by dy (lateral, mm) and the
    rail cant changed by -droll (rad): the contact model placed where the truth's bodies are."""
    from conformal.cases.conformal import curved_problem_from_wheel_rail

    g = scene.geometry
    sc = replace(scene, geometry=replace(g, lateral_shift=g.lateral_shift + dy, rail_cant=g.rail_cant - droll))
    r = gt._conformal(sc, "halfspace")
    grid = curved_problem_from_wheel_rail(sc).grid
    r["LV"] = gt.normal_lv(r, grid)
    r["s_flank"] = gt.flank_boundary(grid)
    r["flank_share"] = gt.share(r, r["s_flank"])
    r["lateral_shift"], r["rail_cant"] = sc.geometry.lateral_shift, sc.geometry.rail_cant
    for k in ("profile_s", "profile_p"):
        r.pop(k, None)
    return r


def match_lv(scene, target: float, lo: float = -0.06, hi: float = 0.02, tol: float = 2e-4,
             at=None) -> dict:
    """The conformal half-space model at the wheelset shift dy (mm) where its normal-force L/V
    equals ``target`` (regula falsi, Illinois; L/V grows with dy): compared at the same vertical
    AND lateral load, the lateral position is an output, as the approach is at a prescribed load.
    ``at(dy)`` (default: :func:`conformal_at` of the scene) gives the model's result dict with "LV"."""
    if at is None:
        def at(dy):
            return conformal_at(scene, dy)
    f_lo, f_hi = at(lo)["LV"] - target, at(hi)["LV"] - target
    if f_lo > 0 or f_hi < 0:
        raise ValueError(f"L/V {target:.3f} outside the bracket dy = {lo:g} .. {hi:g} mm")
    side = 0
    for _ in range(40):
        dy = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        r = at(dy)
        fm = r["LV"] - target
        if abs(fm) < tol or hi - lo < 1e-6:
            break
        if fm < 0:
            lo, f_lo = dy, fm
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = dy, fm
            if side == 1:
                f_lo *= 0.5
            side = 1
    r["dy"] = dy
    return r


def _errors(r: dict, t: dict) -> dict:
    e = {q: r[q] / t[q] - 1.0 for q in ("FN", "pmax", "area")}
    e["flank_share"] = r["flank_share"] - t["flank_share"]
    e["LV"] = r["LV"] - t["LV"]
    return e


def matched_existing(gt_parts: Path) -> list[dict]:
    """Every flange-scene truth of :mod:`fe_ground_truth` (reference, finer mesh, larger body, solid
    blocks) with its flank share and L/V, and the conformal half-space model at the same L/V."""
    from conformal.cases.conformal import curved_problem_from_wheel_rail

    scs = dict(gt.scenes(False))
    rows = []
    for path in sorted(gt_parts.glob("flange_*.json")):
        rec = json.loads(path.read_text())
        scene = scs[rec["scene"]]
        grid = curved_problem_from_wheel_rail(scene).grid
        s_b = gt.flank_boundary(grid)
        truths = [("truth (section, 20)", rec["truth"])] + [(k, v) for k, v in rec["variants"].items() if "FN" in v]
        for label, t in truths:
            t = dict(t, LV=gt.normal_lv(t, grid), flank_share=gt.share(t, s_b))
            r = match_lv(scene, t["LV"])
            rows.append({"scene": rec["scene"], "truth": label, "options": t.get("options"),
                         "truth_values": {q: t[q] for q in ("FN", "pmax", "area", "flank_share", "LV")},
                         "matched": {q: r[q] for q in ("FN", "pmax", "area", "flank_share", "LV", "dy")},
                         "err": _errors(r, t)})
            print(f"  {rec['scene']} {label:28s} L/V {t['LV']:.3f} dy {1e3 * r['dy']:+.2f} um  "
                  + "  ".join(f"{k} {100 * v:+.2f}" for k, v in rows[-1]["err"].items()), flush=True)
    return rows


def run_scene(name: str, scene, opts: dict, parts: Path) -> dict:
    path = parts / f"{name}.json"
    old = json.loads(path.read_text()) if path.exists() else {}
    if old.get("truth", {}).get("options") == opts:
        rec = old
    else:
        print(f"{name}: truth {opts}", flush=True)
        rec = {"scene": name, "measured_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
               "wheel_load": scene.load.wheel_load, "truth": measure(scene, opts)}
    t = rec["truth"]
    from conformal.cases.conformal import curved_problem_from_wheel_rail
    t["LV"] = gt.normal_lv(t, curved_problem_from_wheel_rail(scene).grid)
    models = {"conformal half-space": conformal_at(scene)}
    for key, fit in t["fits"].items():
        models[f"conformal half-space, moved as the truth ({key})"] = conformal_at(scene, fit["dy_lateral"],
                                                                                   fit["droll_rail"])
    m = match_lv(scene, t["LV"])
    models["conformal half-space, same L/V"] = m
    for label, r in models.items():
        r["err"] = _errors(r, t)
    rec["models"] = models
    gt._write_json(path, rec)
    return rec


def build(out: Path) -> dict:
    recs = [json.loads(p.read_text()) for p in sorted((out / "parts").glob("*.json"))]
    L = ["# The truth's structural deflection and the contact models moved by it", "",
         "Truth: fe_contact, `fec_body = \"section\"` (60E1 clamped at the foot and the ends, wheel rim + web "
         "clamped at the hub and the sector cuts). Rigid fits of the rail head and the wheel rim "
         f"(|x| < {SLICE:g} mm, nodes farther than R from the contact centre); dy: lateral motion of the "
         "rim against the head at the gauge point (track lateral, + = towards the field side: more "
         "flange), droll: roll of the head against the rim (+ = head top towards the field side). "
         f"Flank share: FN at rail contact angles above {gt.FLANK_ANGLE:g} degrees. Errors against the truth.", "",
         "| scene | model | lateral shift [mm] | FN [N] | pmax [N/mm²] | area [mm²] | flank share | L/V | "
         "FN err | pmax err | area err | flank diff | L/V diff |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for rec in recs:
        t = rec["truth"]
        L.append(f"| {rec['scene']} | truth (section, clamped) | | {t['FN']:.0f} | {t['pmax']:.1f} | {t['area']:.2f} | "
                 f"{100 * t['flank_share']:.1f} % | {t['LV']:.3f} | | | | | |")
        for label, r in rec["models"].items():
            e = r["err"]
            L.append(f"| {rec['scene']} | {label} | {r['lateral_shift']:.4f} | {r['FN']:.0f} | {r['pmax']:.1f} | "
                     f"{r['area']:.2f} | {100 * r['flank_share']:.1f} % | {r['LV']:.3f} | {100 * e['FN']:+.2f} % | "
                     f"{100 * e['pmax']:+.2f} % | {100 * e['area']:+.2f} % | {100 * e['flank_share']:+.2f} | "
                     f"{e['LV']:+.3f} |")
    L += ["", "Structural deflection of the truth (mm, mrad; rail-profile frame):", ""]
    for rec in recs:
        t = rec["truth"]
        ck = t["checks"]
        L.append(f"- {rec['scene']}: F_load {ck['F_load']:.1f} N (wheel load {ck['wheel_load']:.0f} N), cant "
                 f"{ck['cant']:.6f} = load direction's {ck['cant_from_direction']:.6f}; rail clamped nodes "
                 f"{ck['rail']['clamped_nodes']} ({ck['rail']['on_foot']} on the {ck['rail']['base']}, "
                 f"{ck['rail']['on_end_faces']} on the ends x = +-{ck['rail']['end_faces_x']:.0f} mm, "
                 f"{ck['rail']['elsewhere']} elsewhere; nearest {ck['rail']['nearest_to_contact_mm']:.0f} mm from the "
                 f"contact); wheel {ck['wheel']['clamped_nodes']} ({ck['wheel']['on_hub']} on the {ck['wheel']['base']}, "
                 f"{ck['wheel']['on_end_faces']} on the sector cuts, {ck['wheel']['elsewhere']} elsewhere; nearest "
                 f"{ck['wheel']['nearest_to_contact_mm']:.0f} mm); contact at the slave edge: {ck['slave_edge']}")
        for key, fit in t["fits"].items():
            fr, fw = fit["rail_head"], fit["wheel_rim"]
            L.append(f"  - {key}: rail head t = ({', '.join(f'{v:+.4f}' for v in fr['t'])}), roll "
                     f"{1e3 * fr['w'][0]:+.3f} mrad ({fr['n']} nodes, rms residual {fr['rms_residual']:.1e}); wheel rim "
                     f"t = ({', '.join(f'{v:+.4f}' for v in fw['t'])}) incl. approach {t['approach']:.4f}, roll "
                     f"{1e3 * fw['w'][0]:+.3f} mrad ({fw['n']} nodes, rms {fw['rms_residual']:.1e}); rail head lateral "
                     f"{fit['rail_head_lateral']:+.4f}, rim lateral {fit['wheel_rim_lateral']:+.4f}; relative dy "
                     f"{fit['dy_lateral']:+.4f} mm, droll {1e3 * fit['droll_rail']:+.3f} mrad")
    mpath = out / "matched.json"
    if mpath.exists():
        rows = json.loads(mpath.read_text())
        L += ["", "Every truth of studies/fe_ground_truth.py and the conformal half-space model at the SAME L/V "
              "(vertical AND lateral load prescribed; its wheelset shift dy is then an output, like the approach):", "",
              "| scene | truth | FN [N] | pmax [N/mm²] | area [mm²] | flank share | L/V | dy [µm] | FN err | pmax err | "
              "area err | flank diff |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for w in rows:
            t, m, e = w["truth_values"], w["matched"], w["err"]
            L.append(f"| {w['scene']} | {w['truth']} | {t['FN']:.0f} | {t['pmax']:.1f} | {t['area']:.2f} | "
                     f"{100 * t['flank_share']:.1f} % | {t['LV']:.3f} | {1e3 * m['dy']:+.1f} | {100 * e['FN']:+.2f} % | "
                     f"{100 * e['pmax']:+.2f} % | {100 * e['area']:+.2f} % | {100 * e['flank_share']:+.2f} |")
    md = "\n".join(L) + "\n"
    (out / "structure.md").write_text(md)
    gt._write_json(out / "structure.json", {"scenes": recs})
    return {"scenes": recs}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--scenes", nargs="*")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--matched", action="store_true",
                    help="also match the L/V of every flange truth of studies/out/fe_ground_truth (~7 min)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    opts = gt.QUICK_TRUTH if args.quick else gt.TRUTH
    todo = [(n, s) for n, s in gt.scenes(False) if n.startswith("flange")]
    if args.quick:
        todo = [t for t in todo if t[0] == "flange_y6.25"]
    for name, sc in todo:
        if args.scenes and name not in args.scenes:
            continue
        run_scene(name, sc, opts, args.out / "parts")
    if args.matched:
        gt._write_json(args.out / "matched.json", matched_existing(gt.OUT / "parts"))
    build(args.out)
    write_sidecar(args.out, __file__, vars(args) | {"out": str(args.out)}, {"wall_s": time.perf_counter() - t0})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
