"""The ground truth's own convergence at prescribed loads, and the production model against it.

The truth (``theory = "fe_contact"``, ``fec_body = "section"``: the 60E1 rail section clamped at
the foot and the ends, the wheel rim + web clamped at the hub and the sector cuts; the deep pair:
both profiles continued straight and closed by clamped blocks; quadratic tetrahedra graded from
h = a / ``fec_n`` at the contact; see :mod:`fe_ground_truth`) is solved on each scene of
:mod:`fe_ground_truth` on a series of meshes (fec_n = 6, 8, 10) and two body sizes
(``fec_section_size`` = 20 and 40 patch sizes beyond the patch).

Each truth mesh is solved twice with the same factorisation
(:meth:`conformal.fe_contact.solver.ContactModel.solve`):

* **at the nominal position** (the scene's lateral shift, the prescribed wheel load): the
  lateral position of the wheel against the rail head then depends on the bending of the rail
  web and the wheel web, micrometres that decide a flange-root contact (studies/fe_truth_structure.py),
  and on the body size (a longer clamped rail, a larger wheel sector bend more);
* **at prescribed vertical AND lateral load**: the wheel load along the load direction d and the
  lateral force along e = (0, d_z, -d_y) equal to the REFERENCE mesh's lateral force at the
  nominal position; the wheel moves rigidly by delta d + s e, both unknown.  A real rail has no
  lateral position relative to infinity any more than an approach: the contact is compared at
  the same loads.  This is where the reference's convergence is judged, and where the production
  model is compared (the same L/V, its wheelset shift an output).

The reference is gt.TRUTH (fec_n = 6, 20 patch sizes) except where ``SCENE_REFERENCE`` says
otherwise: at 6.25 mm a / 8 of the half-space estimate (about a / 6 of the truth's own patch) with
the contact candidates enlarged 2.0 times; its series (``SCENE_VARIANTS``) is a / 11 and 40 patch
sizes.  A part file stored on other reference options is kept under "superseded" (its
production rows are taken over where their L/V lies within the match tolerance ``LV_TOL`` of the
new reference's).  Each solution also records the structural pose (:func:`pose`: the rail head's
and the wheel rim's roll and lateral motion from rigid fits away from the contact).

Convergence in the mesh: Richardson extrapolation in h ~ 1 / fec_n through the three meshes where
the differences have one sign and the observed order lies in 0.5 .. 4; the contact area's
resolution is reported as the mean triangle area in contact over the area (the element-counting
definition moves by about one row of elements) and the half width of its bounds.

Production model: theory conformal, influence "fe" (the package's default FE influence numbers)
and "halfspace", at the truth's L/V (as studies/fe_truth_structure.py matches it), on the scene's grid
and on finer grids ([grid] n), to show whether a difference is the production grid's.

Outputs in studies/out/fe_truth_convergence/: parts/<scene>.json (one per scene and variant,
``--scenes`` / ``--variants`` run a subset), convergence.json/.md, run.json.

    nice python studies/fe_truth_convergence.py --scenes deep_pair     # ~10 min on the shared machine
    nice python studies/fe_truth_convergence.py --models-only           # production side only
    python studies/fe_truth_convergence.py --quick                      # coarse, flange 6.2 mm (a test)
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "studies"))
import fe_ground_truth as gt  # noqa: E402
import fe_truth_structure as ts  # noqa: E402
from _provenance import write_sidecar  # noqa: E402

OUT = ROOT / "studies" / "out" / "fe_truth_convergence"
#: the truth series: the reference (gt.TRUTH), two finer meshes, a larger body
VARIANTS = {"reference": {}, "finer mesh": {"fec_n": 8}, "finest mesh": {"fec_n": 10},
            "larger body": {"fec_section_size": 40.0}}
MESH_SERIES = ("reference", "finer mesh", "finest mesh")
#: per-scene reference options over gt.TRUTH.  At 6.25 mm (root + flank) h = a / fec_n takes a
#: from the half-space estimate, whose patch is about 60 % larger than the truth's, so fec_n = 6
#: meshes the real patch at about a / 4: the reference there is fec_n = 8 (h = 0.453 mm, about
#: a / 6 of the truth's own patch), with the contact candidates enlarged 2.0 times (``fec_slave``;
#: at 1.6 the a / 8 contact reaches the candidate box's edge along x, whose half width
#: 1.6 * mx * h / 2 shrinks with h)
SCENE_REFERENCE = {"flange_y6.25": {"fec_n": 8, "fec_slave": 2.0}}
#: per-scene truth series (over the scene's reference options) where it differs from VARIANTS
SCENE_VARIANTS = {"flange_y6.25": {"reference": {}, "finer mesh": {"fec_n": 11},
                                   "larger body": {"fec_section_size": 40.0}}}
QUICK_VARIANTS = {"reference": {}, "finer mesh": {"fec_n": 4}}
#: production grids ([grid] n) besides the scene's own
GRID_N = (60, 80)


def lateral_direction(d: np.ndarray) -> np.ndarray:
    """The lateral unit vector e = (0, d_z, -d_y) across the load direction d (rail-profile frame;
    + towards the field side: more flange)."""
    return np.array([0.0, d[2], -d[1]])


def state(sol, run, prob, e: np.ndarray) -> dict:
    """FN, pmax, the contact area (with its bounds and resolution), the flank share and L/V of the
    normal forces, the lateral force and the rigid motions of one solution."""
    grid = prob.grid
    from conformal.influence.fe import rail_body_from_grid

    _, rpatch = rail_body_from_grid(grid, prob.rail_points)
    s = np.interp(sol.uv[:, 1], rpatch.edges, grid.s_edges) - float(grid.s_ref)
    act = sol.active
    rec = {"FN": sol.FN, "pmax": sol.pmax, "pmax_nodal": sol.pmax_nodal, "area": sol.contact_area,
           "area_bounds": list(sol.contact_area_bounds), "F_load": sol.F_load,
           "F_lat": float(sol.force_vector @ e), "approach": sol.approach, "shift": sol.shift,
           "s_nodes": s[act].tolist(), "f_nodes": sol.force[act].tolist(), "edge": _edge(sol, run)}
    full = sol.active[sol.tris].all(axis=1)
    rec["area_resolution"] = float(np.mean(sol.tri_area[full]) / rec["area"]) if full.any() else None
    rec["flank_share"] = gt.share(rec, gt.flank_boundary(grid))
    rec["LV"] = gt.normal_lv(rec, grid)
    return rec


def _edge(sol, run) -> bool:
    tol = 0.51 * float(run.body1.mesh.patch.dx)
    uv = sol.uv
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    a = uv[sol.active]
    return bool(np.any((a - lo < tol) | (hi - a < tol)))


def spread_share(s_nodes, f_nodes, widths, s_b: float) -> float:
    """Share of the force at s < s_b with each nodal force spread uniformly over [s - w/2, s + w/2]
    (w its element's width along s): the flank share without the one-element jumps of counting
    whole elements on one side of the boundary (the 45-degree line of the deep pair runs through
    the middle of the patch, where one column of elements carries 3-5 % of FN)."""
    s, f = np.asarray(s_nodes, float), np.asarray(f_nodes, float)
    w = np.broadcast_to(np.asarray(widths, float), s.shape)
    frac = np.clip((s_b - (s - 0.5 * w)) / w, 0.0, 1.0)
    return float((f * frac).sum() / f.sum())


def grid_widths(s_nodes) -> np.ndarray:
    """Widths along s of the elements whose centres are ``s_nodes`` (a grid's columns: half the
    distance to the neighbouring centres on each side)."""
    s = np.asarray(s_nodes, float)
    u = np.unique(np.round(s, 9))
    if u.size < 2:
        return np.ones_like(s)
    mid = 0.5 * (u[1:] + u[:-1])
    edges = np.concatenate([[u[0] - (mid[0] - u[0])], mid, [u[-1] + (u[-1] - mid[-1])]])
    k = np.searchsorted(u, np.round(s, 9))
    return (edges[k + 1] - edges[k])


def pose(run, prob, sol, R: float = ts.RADII[0]) -> dict:
    """The structural pose change of one solution (:func:`fe_truth_structure.measure`'s rigid fits
    of the rail head and the wheel rim in the slab |x| < SLICE through the contact, nodes farther
    than R from the load centre): the rail head's roll (rad, about x) and its lateral displacement
    at the gauge point (mm), the wheel rim's likewise, and their differences (rim against head;
    the roll of the head against the rim is what the rigid wheel of the loaded solve cannot follow)."""
    from conformal.cases.fe_contact import load_direction
    from conformal.meshing.gmsh_body import cross_section_coordinates

    u1, u2 = run.model.displacements(sol)
    d = load_direction(prob.grid)
    e_lat = lateral_direction(d)
    act = sol.active
    f = sol.force[act]
    c = (sol.X[act] * f[:, None]).sum(axis=0) / f.sum()
    b1, b2 = run.body1, run.body2
    x1, yz1 = cross_section_coordinates(b1.mesh.body, b1.mesh.extent, b1.mesh.points)
    x2, yz2 = cross_section_coordinates(b2.mesh.body, b2.mesh.extent, b2.mesh.points)
    P1, P2 = b1.points, b2.points
    gp = ts.gauge_point(np.column_stack([b1.mesh.body.profile.y, b1.mesh.body.profile.z]), d)
    head = (np.abs(x1) < ts.SLICE) & (yz1[:, 1] < ts.RAIL_HEAD_Z) & (np.linalg.norm(P1 - c, axis=1) > R)
    rim = (np.abs(x2) < ts.SLICE) & (yz2[:, 1] > -ts.RIM_DEPTH) & (np.linalg.norm(P2 - c, axis=1) > R)
    fr, fw = ts.rigid_fit(P1[head], u1[head], c), ts.rigid_fit(P2[rim], u2[rim], c)
    head_lat = float(ts._at(fr, gp, c) @ e_lat)
    rim_lat = float(ts._at(fw, gp, c) @ e_lat)
    return {"R": R, "rail_head_roll": fr["w"][0], "wheel_rim_roll": fw["w"][0],
            "droll_rail": fr["w"][0] - fw["w"][0], "rail_head_lateral": head_lat, "wheel_rim_lateral": rim_lat,
            "dy_lateral": rim_lat - head_lat, "rms_residual": [fr["rms_residual"], fw["rms_residual"]]}


def truth_run(scene, opts: dict, f_lat: float | None) -> dict:
    """One truth mesh: solved at the nominal position and at the prescribed vertical and lateral
    load (lateral force ``f_lat``, or this mesh's own at the nominal position when None)."""
    from conformal.cases.fe_contact import load_direction, run_wheel_rail

    sc = scene.with_model(theory="fe_contact", options=dict(scene.model.options, **opts))
    t0 = time.perf_counter()
    run, prob = run_wheel_rail(sc)
    t1 = time.perf_counter()
    e = lateral_direction(load_direction(prob.grid))
    nominal = state(run.solution, run, prob, e)
    target = nominal["F_lat"] if f_lat is None else float(f_lat)
    sol = run.model.solve(normal_force=prob.normal_force, shift_direction=e, shift_force=target,
                          approach_guess=run.solution.approach)
    loaded = state(sol, run, prob, e)
    for rec, so in ((nominal, run.solution), (loaded, sol)):
        try:
            rec["pose"] = pose(run, prob, so)
        except Exception as exc:   # reported, not hidden
            rec["pose"] = {"error": f"{type(exc).__name__}: {exc}"}
    st = run.solution.stats
    return {"options": opts, "nominal": nominal, "loaded": loaded, "F_lat_target": target,
            "n_unknowns": run.solution.n_unknowns, "dofs_body1": st["dofs_body1"], "dofs_body2": st["dofs_body2"],
            "h_contact": float(run.body1.mesh.patch.dx),
            "x_range_rail": list(run.body1.mesh.stats["x_range"]), "wall_s": time.perf_counter() - t0,
            "mesh_solve_s": t1 - t0, "rss_gib": gt._rss_gib()}


def richardson(hs, fs) -> dict | None:
    """f(h) = f0 + C h^p through three (h, f): the observed order p and the limit f0, or None when
    the differences change sign or p falls outside 0.5 .. 4 (not in the asymptotic regime)."""
    from scipy.optimize import brentq

    (h1, h2, h3), (f1, f2, f3) = hs, fs
    d1, d2 = f1 - f2, f2 - f3
    if d1 == 0 or d2 == 0 or d1 * d2 < 0:
        return None
    r = d1 / d2

    def g(p):
        return (h1 ** p - h2 ** p) / (h2 ** p - h3 ** p) - r

    try:
        p = brentq(g, 0.5, 4.0)
    except ValueError:
        return None
    C = d2 / (h2 ** p - h3 ** p)
    return {"p": float(p), "limit": float(f3 - C * h3 ** p)}


def production(scene, target_lv: float, grid_n=None, influence: str = "fe", lo=-0.06, hi=0.02,
               start: dict | None = None) -> dict:
    """The conformal model at the truth's normal-force L/V (its wheelset shift dy an output).
    With ``start`` (the half-space model's match: its dy and dL/V / dy), two Newton steps from
    there instead of the bracketing search (FE influence numbers are recomputed at every shift)."""
    sc = scene if grid_n is None else scene.with_("grid.n", grid_n)
    sc = sc.with_model(theory="conformal", influence=influence, options=dict(scene.model.options))
    t0 = time.perf_counter()
    if start is None:
        m = match_lv(sc, target_lv, influence, lo, hi)
    else:
        at = _at(sc, influence)
        dy, slope = start["dy"], start["slope"]
        for _ in range(2):
            m = at(dy)
            dy = dy - (m["LV"] - target_lv) / slope
        m["newton"] = True
    m["wall_s"] = time.perf_counter() - t0
    m["grid_n"] = sc.grid.n
    m["influence"] = influence
    return m


def _at(scene, influence):
    """The conformal model with the wheelset moved by dy (mm): FN, pmax, area, flank share, L/V."""
    from dataclasses import replace

    from conformal.cases.conformal import curved_problem_from_wheel_rail

    def at(dy):
        g = scene.geometry
        sc = replace(scene, geometry=replace(g, lateral_shift=g.lateral_shift + dy))
        r = gt._conformal(sc, influence)
        grid = curved_problem_from_wheel_rail(sc).grid
        r["LV"] = gt.normal_lv(r, grid)
        s_b = gt.flank_boundary(grid)
        r["flank_share"] = gt.share(r, s_b)
        r["flank_share_spread"] = spread_share(r["s_nodes"], r["f_nodes"], grid_widths(r["s_nodes"]), s_b)
        r["dy"] = dy
        for k in ("profile_s", "profile_p", "s_nodes", "f_nodes"):
            r.pop(k, None)
        return r
    return at


def match_lv(scene, target, influence, lo, hi, tol=2e-4) -> dict:
    """The wheelset shift dy (mm) where the normal-force L/V equals ``target``, for either influence
    (:func:`fe_truth_structure.match_lv`), with the slope dL/V / dy at the match (1/mm)."""
    at = _at(scene, influence)
    r = ts.match_lv(scene, target, lo, hi, tol, at=at)
    r["slope"] = (at(r["dy"] + 1e-3)["LV"] - r["LV"]) / 1e-3
    return r


def _load(path: Path, fresh: dict) -> dict:
    """The part file of a scene for these reference options (``fresh``: scene, base_options,
    wheel_load).  A stored record of other reference options is kept under "superseded" (its
    truths and models, for the record; they enter no comparison)."""
    rec = json.loads(path.read_text()) if path.exists() else {}
    if rec.get("base_options") != fresh["base_options"] or rec.get("wheel_load") != fresh["wheel_load"]:
        old = {k: rec[k] for k in ("base_options", "wheel_load", "truths", "models") if k in rec}
        sup = rec.get("superseded", [])
        rec = dict(fresh, truths={}, models={}, superseded=sup + ([old] if old.get("truths") else []))
    return rec


def _update(path: Path, fresh: dict, key: str, label: str, value: dict) -> dict:
    """Read the part file again, set rec[key][label] = value and write it back (truths and
    models are run by separate processes; each keeps the other's entries)."""
    rec = _load(path, fresh)
    rec.setdefault(key, {})[label] = value
    gt._write_json(path, rec)
    return rec


def seed_from_ground_truth(name: str, parts: Path) -> None:
    """Take the reference truth of studies/out/fe_ground_truth/parts/<name>.json (the same options,
    solved at the nominal position, where the loaded state is the same solution: s = 0) as this
    study's reference when it has none (its lateral force, contact-area bounds and resolution
    were not stored there)."""
    path = parts / f"{name}.json"
    src = gt.OUT / "parts" / f"{name}.json"
    if (path.exists() and "reference" in json.loads(path.read_text()).get("truths", {})) or not src.exists():
        return
    old = json.loads(src.read_text())
    t = old["truth"]
    if t["options"] != gt.TRUTH:
        return
    st = {"FN": t["FN"], "pmax": t["pmax"], "area": t["area"], "area_bounds": None,
          "area_resolution": None, "F_lat": None, "shift": 0.0, "s_nodes": t["s_nodes"], "f_nodes": t["f_nodes"],
          "edge": t["edge"], "flank_share": t["flank_share"], "LV": t["LV"]}
    rec = {"options": t["options"], "nominal": st, "loaded": dict(st), "F_lat_target": None,
           "n_unknowns": t["n_unknowns"], "dofs_body1": t["stats"]["dofs_body1"], "dofs_body2": t["stats"]["dofs_body2"],
           "h_contact": t["h_contact"], "x_range_rail": t["mesh1"]["x_range"], "wall_s": t["wall_s"],
           "rss_gib": t["rss_gib"], "from": str(src.relative_to(ROOT))}
    _update(path, {"scene": name, "base_options": gt.TRUTH, "wheel_load": old["wheel_load"]}, "truths", "reference", rec)


def reference_options(name: str) -> dict:
    """The reference truth's ``[model]`` options of a scene: gt.TRUTH with SCENE_REFERENCE."""
    return dict(gt.TRUTH, **SCENE_REFERENCE.get(name, {}))


def run_scene(name, scene, variants: dict, parts: Path, only=None, models=True, quick=False) -> dict:
    path = parts / f"{name}.json"
    base = gt.QUICK_TRUTH if quick else reference_options(name)
    fresh = {"scene": name, "base_options": base, "wheel_load": scene.load.wheel_load}
    rec = _load(path, fresh)
    for label, extra in variants.items():
        if only is not None and label not in only:
            continue
        opts = dict(base, **extra)
        old = rec["truths"].get(label)
        if old is not None and old.get("options") == opts and "from" not in old:
            continue
        f_lat = None if label == "reference" else rec["truths"]["reference"]["F_lat_target"]
        print(f"{name}: {label} {opts}", flush=True)
        r = truth_run(scene, opts, f_lat)
        _say(name, label, r)
        rec = _update(path, fresh, "truths", label, r)
    if models and "reference" in rec["truths"]:
        t = rec["truths"]["reference"]["loaded"]
        todo = [("conformal half-space", None, "halfspace"), ("conformal FE", None, "fe")]
        if not quick:
            todo += [(f"conformal half-space, grid n = {n}", n, "halfspace") for n in GRID_N]
        for label, n, infl in (todo[:1] if quick else todo):
            old = rec["models"].get(label)
            if old is not None and abs(old.get("target_LV", -1) - t["LV"]) < 1e-9 and "flank_share_spread" in old:
                continue
            kept = _kept_model(rec, label, t["LV"])
            if kept is not None:
                print(f"{name}: {label} kept (matched to L/V {kept['target_LV']:.5f})", flush=True)
                rec = _update(path, fresh, "models", label, kept)
                continue
            print(f"{name}: {label}", flush=True)
            hs = rec["models"].get("conformal half-space" if n is None else f"conformal half-space, grid n = {n}", {})
            start = {"dy": hs["dy"], "slope": hs["slope"]} if infl == "fe" and "slope" in hs else None
            try:
                m = production(scene, t["LV"], n, infl, start=start)
            except Exception as exc:   # reported, not hidden
                m = {"error": f"{type(exc).__name__}: {exc}"}
            m["target_LV"] = t["LV"]
            print(f"  {name} {label}: " + ("FAILED " + m["error"] if "error" in m else
                  f"dy {1e3 * m['dy']:+.2f} um FN {m['FN']:.1f} pmax {m['pmax']:.2f} area {m['area']:.2f} "
                  f"flank {100 * m['flank_share']:.2f} % L/V {m['LV']:.4f} ({m['wall_s']:.0f} s)"), flush=True)
            rec = _update(path, fresh, "models", label, m)
    return rec


#: L/V: the production model's match tolerance (:func:`fe_truth_structure.match_lv`)
LV_TOL = 2e-4


def _kept_model(rec: dict, label: str, target_lv: float) -> dict | None:
    """A production row of a superseded reference whose L/V target lies within the match
    tolerance LV_TOL of the new reference's (a rerun would match no closer), marked with the
    reference it was matched to; None where there is none."""
    for old in reversed(rec.get("superseded", [])):
        m = old.get("models", {}).get(label)
        if m is not None and "FN" in m and "flank_share_spread" in m and abs(m["target_LV"] - target_lv) < LV_TOL:
            return dict(m, matched_to=old["base_options"])
    return None


def _say(name, label, r):
    for k in ("nominal", "loaded"):
        s = r[k]
        print(f"  {name} {label:12s} {k:8s} FN {s['FN']:8.1f} pmax {s['pmax']:7.2f} area {s['area']:6.2f} "
              f"flank {100 * s['flank_share']:5.1f} % L/V {s['LV']:.4f} shift {1e3 * s['shift']:+.2f} um",
              flush=True)
    print(f"  {r['n_unknowns']} unknowns, h {r['h_contact']:.3f} mm, {r['wall_s']:.0f} s, rss {r['rss_gib']:.2f} GiB",
          flush=True)


def summarise(rec: dict, s_b: float) -> dict:
    """Differences of every truth against the reference (nominal and loaded), the Richardson
    limits of the mesh series, and every production model's errors against the reference
    (``s_b``: the flank boundary's arc length; the truths' spread flank share is added here, each
    node's force spread over its element size h)."""
    T = rec["truths"]
    ref = T.get("reference")
    out: dict = {"convergence": {}, "richardson": {}, "errors": {}}
    if ref is None:
        return out
    for r in T.values():
        for k in ("nominal", "loaded"):
            r[k]["flank_share_spread"] = spread_share(r[k]["s_nodes"], r[k]["f_nodes"], r["h_contact"], s_b)
    for label, r in T.items():
        if label == "reference":
            continue
        out["convergence"][label] = {k: {q: r[k][q] / ref[k][q] - 1.0 for q in ("FN", "pmax", "area")}
                                     | {q: r[k][q] - ref[k][q] for q in ("flank_share", "flank_share_spread")}
                                     for k in ("nominal", "loaded")}
    if all(m in T for m in MESH_SERIES):
        hs = [T[m]["h_contact"] for m in MESH_SERIES]
        for q in ("FN", "pmax", "area", "flank_share_spread"):
            rr = richardson(hs, [T[m]["loaded"][q] for m in MESH_SERIES])
            if rr is not None:
                rr["limit_vs_reference"] = (rr["limit"] - ref["loaded"][q]) if q.startswith("flank") else \
                    rr["limit"] / ref["loaded"][q] - 1.0
            out["richardson"][q] = rr
    t = ref["loaded"]
    for label, m in rec.get("models", {}).items():
        if "FN" not in m:
            continue
        out["errors"][label] = {q: m[q] / t[q] - 1.0 for q in ("FN", "pmax", "area")} | \
            {"flank_share": m["flank_share"] - t["flank_share"], "LV": m["LV"] - t["LV"]}
        if "flank_share_spread" in m:
            out["errors"][label]["flank_share_spread"] = m["flank_share_spread"] - t["flank_share_spread"]
    return out


def build(out: Path) -> dict:
    recs = [json.loads(p.read_text()) for p in sorted((out / "parts").glob("*.json"))]
    L = ["# The ground truth's convergence at prescribed loads, and the production model against it", "",
         "Truth: fe_contact, `fec_body = \"section\"` (deep pair: clamped blocks), quadratic tetrahedra from "
         "h = a / fec_n; each mesh solved at the nominal position (the scene's lateral shift, the wheel load) "
         "and at the prescribed vertical AND lateral load (the reference mesh's lateral force at the nominal "
         "position; the wheel's lateral shift s is then an output). Differences against the reference mesh "
         "(fec_n = 6, 20 patch sizes). Area resolution: mean triangle area in contact / area. Flank share: FN "
         f"at rail contact angles above {gt.FLANK_ANGLE:g} degrees (differences in percentage points; 'counted / spread': each node's or element's force counted on the side of its centre, or spread uniformly over its width along s).", ""]
    L += ["| scene | truth | fec_n | size | unknowns | h [mm] | state | FN [N] | pmax [N/mm²] | area [mm²] | "
          "area bounds | area resolution | flank share | L/V | shift [µm] | FN diff | pmax diff | area diff | "
          "flank diff |", "|" + "---|" * 19]
    from conformal.cases.conformal import curved_problem_from_wheel_rail

    scs = dict(gt.scenes(False)) | dict(gt.scenes(True))
    for rec in recs:
        S = summarise(rec, gt.flank_boundary(curved_problem_from_wheel_rail(scs[rec["scene"]]).grid))
        rec["summary"] = S
        for label, r in rec["truths"].items():
            for k in ("nominal", "loaded"):
                s = r[k]
                c = S["convergence"].get(label, {}).get(k)
                dif = ("| | | | " if c is None else
                       f"| {100 * c['FN']:+.2f} % | {100 * c['pmax']:+.2f} % | {100 * c['area']:+.2f} % | "
                       f"{100 * c['flank_share']:+.2f} / {100 * c['flank_share_spread']:+.2f} ")
                L.append(f"| {rec['scene']} | {label} | {r['options']['fec_n']} | {r['options']['fec_section_size']:g} | "
                         f"{r['n_unknowns']} | {r['h_contact']:.3f} | {k} | {s['FN']:.1f} | {s['pmax']:.1f} | "
                         f"{s['area']:.2f} | {'' if s['area_bounds'] is None else '%.2f .. %.2f' % tuple(s['area_bounds'])} | "
                         f"{'' if s['area_resolution'] is None else '%.2f %%' % (100 * s['area_resolution'])} | {100 * s['flank_share']:.2f} / "
                         f"{100 * s['flank_share_spread']:.2f} % | "
                         f"{s['LV']:.4f} | {1e3 * s['shift']:+.2f} {dif}|"
                         + (" slave edge" if s["edge"] else ""))
    L += ["", "Richardson extrapolation of the mesh series (loaded state; f = f0 + C h^p through fec_n = 6, 8, 10; "
          "none where the differences change sign or p is outside 0.5 .. 4):", ""]
    for rec in recs:
        for q, rr in rec["summary"]["richardson"].items():
            L.append(f"- {rec['scene']}, {q}: " + ("not in the asymptotic regime" if rr is None else
                     f"p = {rr['p']:.2f}, limit {rr['limit']:.4g} ({'%+.2f points' % (100 * rr['limit_vs_reference'])}"
                     f" against the reference)" if q == "flank_share" else
                     f"p = {rr['p']:.2f}, limit {rr['limit']:.4g} ({100 * rr['limit_vs_reference']:+.2f} % against the reference)"))
    L += ["", "Production model (theory conformal) at the truth reference's L/V (loaded state); errors against "
          "the reference truth:", "",
          "| scene | model | grid n | dy [µm] | FN [N] | pmax [N/mm²] | area [mm²] | area resolution | flank share | "
          "L/V | FN err | pmax err | area err | flank diff | wall [s] |", "|" + "---|" * 15]
    for rec in recs:
        for label, m in rec.get("models", {}).items():
            if "FN" not in m:
                L.append(f"| {rec['scene']} | {label} | failed: {m.get('error', '')} |" + "|" * 12)
                continue
            e = rec["summary"]["errors"][label]
            L.append(f"| {rec['scene']} | {label} | {m['grid_n']} | {1e3 * m['dy']:+.1f} | {m['FN']:.1f} | "
                     f"{m['pmax']:.1f} | {m['area']:.2f} | "
                     f"{'' if m.get('area_resolution') is None else '%.2f %%' % (100 * m['area_resolution'])} | "
                     f"{100 * m['flank_share']:.2f} / {100 * m.get('flank_share_spread', float('nan')):.2f} % | "
                     f"{m['LV']:.4f} | "
                     f"{100 * e['FN']:+.2f} % | {100 * e['pmax']:+.2f} % | {100 * e['area']:+.2f} % | "
                     f"{100 * e['flank_share']:+.2f} / {100 * e.get('flank_share_spread', float('nan')):+.2f} | "
                     f"{m['wall_s']:.0f} |" + ("" if "matched_to" not in m else
                                               f" matched to L/V {m['target_LV']:.5f} (reference {m['matched_to']})"))
    L += ["", "Truth runs:", ""]
    for rec in recs:
        for label, r in rec["truths"].items():
            L.append(f"- {rec['scene']}, {label}: {r['options']}, {r['n_unknowns']} unknowns ({r['dofs_body1']} rail, "
                     f"{r['dofs_body2']} wheel), rail x = {r['x_range_rail'][0]:.0f} .. {r['x_range_rail'][1]:.0f} mm, "
                     + ("" if r["F_lat_target"] is None else f"lateral force {r['F_lat_target']:.1f} N, ")
                     + f"wall {r['wall_s']:.0f} s, process peak RSS {r['rss_gib']:.2f} GiB"
                     + (f"; the stored reference of {r['from']}" if "from" in r else "")
                     + _pose_text(r["loaded"].get("pose")))
        for old in rec.get("superseded", []):
            L.append(f"- {rec['scene']}: earlier series on the reference {old['base_options']} "
                     f"({', '.join(old['truths'])}), kept in parts/{rec['scene']}.json under \"superseded\"")
    md = "\n".join(L) + "\n"
    out.mkdir(parents=True, exist_ok=True)
    (out / "convergence.md").write_text(md)
    gt._write_json(out / "convergence.json", {"scenes": recs})
    return {"scenes": recs}


def _pose_text(p: dict | None) -> str:
    if not p or "error" in p:
        return "" if not p else f"; pose: {p['error']}"
    return (f"; at the prescribed loads the rail head rolls {1e3 * p['rail_head_roll']:+.3f} mrad, the wheel rim "
            f"{1e3 * p['wheel_rim_roll']:+.3f} mrad (head against rim {1e3 * p['droll_rail']:+.3f} mrad), lateral at "
            f"the gauge point head {1e3 * p['rail_head_lateral']:+.1f} µm, rim {1e3 * p['wheel_rim_lateral']:+.1f} µm "
            f"(rigid fits beyond R = {p['R']:g} mm)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--scenes", nargs="*")
    ap.add_argument("--variants", nargs="*", help="truth variants to run (default: all)")
    ap.add_argument("--no-models", action="store_true", help="truths only")
    ap.add_argument("--models-only", action="store_true", help="production models only (truths stored)")
    ap.add_argument("--seed", action="store_true",
                    help="a scene without a reference takes the stored one of studies/out/fe_ground_truth")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    todo = gt.scenes(args.quick)
    variants = QUICK_VARIANTS if args.quick else VARIANTS
    for name, sc in todo:
        if args.scenes and name not in args.scenes:
            continue
        only = [] if args.models_only else args.variants
        if args.seed:
            seed_from_ground_truth(name, args.out / "parts")
        run_scene(name, sc, SCENE_VARIANTS.get(name, variants) if not args.quick else variants, args.out / "parts", only, models=not args.no_models, quick=args.quick)
    build(args.out)
    write_sidecar(args.out, __file__, vars(args) | {"out": str(args.out)}, {"wall_s": time.perf_counter() - t0})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
