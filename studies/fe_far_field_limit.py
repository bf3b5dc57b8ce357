"""FE bodies converged in size: per-body compliance and pair FN over the body size, extrapolated.

The FE influence numbers of a body (conformal.influence.fe) come from a finite model: a disc of
``fe_body_size`` patch sizes around the contact in the cross-section (a profile that ends inside
it is continued straight, conformal.meshing.bodies.grow_profile), with the half-space field of the
load (``fe_far_field = "halfspace"``) or zero displacement (``"clamped"``) on the artificial
boundary.  Both series converge to the same large-body limit, the clamped one from the stiff
side: the error of a finite body decays like 1/size (a truncated Boussinesq field), so the limit
follows by Richardson extrapolation in 1/size,

    R2 = 2 C(2s) - C(s),    R3 = (8 C(4s) - 6 C(2s) + C(s)) / 3,

from the last two or three sizes of a doubling series, and the successive-difference ratio
(C(4s) - C(2s)) / (C(2s) - C(s)) is 0.5 in that regime.

Measured per case (idealised long profiles: the scene profiles continued straight):

* per body: the compliance ``C`` = mean normal displacement under the half-space solution's
  pressure at the prescribed approach, weighted by that pressure (sum p u_n / sum p u_n,hs), over
  the same with the single-body half-space numbers in turned element frames (the influence model
  ``influence = "halfspace"``);
* per pair: FN with FE numbers over FN with half-space numbers at the same prescribed approach
  and the same curved grid (conformal.solvers.conformal.solve_curved); also with one body's FE
  numbers and the other's half-space numbers (``FN_rail_only``, ``FN_wheel_only``).

Cases: the flat block (a 9 x 9 patch of 1 mm elements, elliptic Hertz-like pressure: the exact
limit is 1), the deep pair (rail corner R10 against flange root R10.2, 0.05 mm), a R10 wheel in a
R10.05 groove (rolling radius 460 mm so that the wheel body can grow; 0.01 mm) and the R13 gauge
corner of UIC60 against the S1002 flange root (6.2 mm shift, 0.03 mm), all on grids of n = 16
(GRID_N).  Series: the half-space far field at sizes 1-16 (the default 16 among them), clamped at
2-16, the half-space far field with every element size halved at 8 and 16, and where a body's
section is a slab (the UIC60 head) the unlimited straight continuation at 4-16
(``fe_closure = "straight"``: its compliance grows without bound, the default limits it); with
quadratic tetrahedra (``p2``: the default grading, sizes 4-32); and for the real S1002/UIC60 pair
the whole sections (``section``, ``section_clamped``: ``fe_closure = "section"``, the 60E1 rail's
head, web and foot and the wheel's rim and web cut by the body's disc, sizes 1-64 and 2-64, their
meshes capped at ``fe_h_wall`` of the local wall thickness, conformal.meshing.wall;
``section_fine`` / ``section_coarse``: every element size, the walls' cap included, halved /
doubled, sizes 16 and 32; ``section_p2``: quadratic tetrahedra on the doubled mesh;
``--section-sizes`` picks other sizes for all of them).
Besides the quantities at the prescribed approach, each row has pmax, the contact area and the
approach at a prescribed load (the half-space solution's FN along the load direction) over those
of the half-space numbers at that load (``pmax_load``, ``area_load``, ``approach_load``).  The
report gives, per case and quantity, the limit (R3 of the half-space series), an error bar (the
largest of |R2 - R3|, the clamped R3 and the refined R2 against it) and the default's distance
from it.

    python studies/fe_far_field_limit.py            # everything (about 75 min on 2 busy cores)
    python studies/fe_far_field_limit.py --cases gauge --series halfspace,straight --append
                                                    # rerun one case, keep the others' rows
    python studies/fe_far_field_limit.py --quick    # the flat block, clamped, sizes 4-16 (< 60 s; a test)

Output: studies/out/fe_far_field_limit/fe_far_field_limit.{md,json,png} and run.json.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "meshes" / "scenes"

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from conformal.errors import ConformalError  # noqa: E402

G, NU = 82000.0, 0.28
SIZES = (1.0, 2.0, 4.0, 8.0, 16.0)
CLAMPED_SIZES = (2.0, 4.0, 8.0, 16.0)
FINE_SIZES = (8.0, 16.0)
STRAIGHT_SIZES = (4.0, 8.0, 16.0)
P2_SIZES = (4.0, 8.0, 16.0, 32.0)
#: series name -> (far field, grading label) of its rows
SERIES = {"halfspace": ("halfspace", "default"), "clamped": ("clamped", "default"), "fine": ("halfspace", "fine"),
          "straight": ("halfspace", "straight"), "p2": ("halfspace", "p2"), "section": ("halfspace", "section"),
          "section_clamped": ("clamped", "section"), "section_fine": ("halfspace", "section_fine"),
          "section_coarse": ("halfspace", "section_coarse"), "section_p2": ("halfspace", "section_p2")}
SECTION_SIZES = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0)
SECTION_FINE_SIZES = (16.0, 32.0)
QUICK_SIZES = (4.0, 8.0, 16.0)
GRID_N = 16          # elements across the overlap (the scenes' 30-40 cost 2-3 min per pair here)


# ----------------------------------------------------------------------------- extrapolation
def richardson(sizes, values) -> dict:
    """Limits of a doubling series in 1/size: R2 from the last two sizes, R3 from the last
    three (error a/s + b/s^2), the successive-difference ratio of the last three, and an error
    bar: |R2 - R3| (the size of the term R2 neglects)."""
    s = np.asarray(sizes, float)
    v = np.asarray(values, float)
    if len(s) < 2 or not np.allclose(s[1:] / s[:-1], 2.0):
        raise ValueError(f"richardson: need a doubling series of sizes, got {s.tolist()}")
    r2 = 2 * v[-1] - v[-2]
    out = {"R2": float(r2), "last": float(v[-1])}
    if len(s) >= 3:
        r3 = (8 * v[-1] - 6 * v[-2] + v[-3]) / 3
        d1, d2 = v[-2] - v[-3], v[-1] - v[-2]
        out.update(R3=float(r3), ratio=float(d2 / d1) if d1 != 0 else float("nan"), err=float(abs(r2 - r3)))
    return out


# ----------------------------------------------------------------------------- cases
def _groove_scene(tmp: Path, r_groove: float = 10.05, r_wheel: float = 10.0):
    """A R10 wheel crown in a R10.05 rail groove, rolling radius 460 mm (the 50 mm wheel of
    meshes/scenes/groove_conformal.toml cannot hold a body beyond 2 patch sizes): two circular
    arcs, continued straight by the FE bodies (as every profile here)."""
    from conformal.scene import load_scene

    t = np.linspace(-math.asin(9.5 / r_groove), math.asin(9.5 / r_groove), 381)
    rail = np.column_stack([r_groove * np.sin(t), -r_groove * (1 - np.cos(t))])        # z down: bottom z = 0
    t = np.linspace(-math.asin(9.0 / r_wheel), math.asin(9.0 / r_wheel), 361)
    wheel = np.column_stack([r_wheel * np.sin(t), -r_wheel * (1 - np.cos(t))])
    np.savetxt(tmp / "groove_rail.csv", rail, delimiter=",", fmt="%.10f",
               header=f"groove rail: concave arc R{r_groove:g}, bottom at (0, 0), z down (mm)")
    np.savetxt(tmp / "groove_wheel.csv", wheel, delimiter=",", fmt="%.10f",
               header=f"groove wheel: convex arc R{r_wheel:g}, crown at (0, 0), z = increase of radius (mm)")
    text = (SCENES / "groove_conformal.toml").read_text()
    text = (text.replace("groove_wheel_r10.csv", "groove_wheel.csv").replace("groove_rail_r10p02.csv", "groove_rail.csv")
            .replace("wheel_radius = 50.0", "wheel_radius = 460.0").replace("pitch_velocity = -19.98", "pitch_velocity = -2.17"))
    (tmp / "groove.toml").write_text(text)
    return load_scene(tmp / "groove.toml")


CASES = {   # label, scene (file or builder), prescribed approach (mm)
    "deep": ("deep pair R10/R10.2", "deep_conformal_pair.toml", 0.05),
    "groove": ("R10 wheel in R10.05 groove", _groove_scene, 0.01),
    "gauge": ("R13 gauge corner / S1002 root", "flange_s1002_uic60_fe.toml", 0.03),
}


class Case:
    """One wheel-rail case at its prescribed approach: the curved problem, the half-space
    solution's pressure, and the two bodies with their patches."""

    def __init__(self, key: str, tmp: Path, n: int | None = GRID_N):
        from conformal.cases.conformal import curved_problem_from_wheel_rail
        from conformal.influence.curved import curved_halfspace_kernel
        from conformal.influence.fe import rail_body_from_grid, wheel_body_from_grid
        from conformal.scene import load_scene
        from conformal.solvers.conformal import influence_operator, solve_curved

        self.key = key
        label, scene, approach = CASES[key]
        self.label = label
        sc = scene(tmp) if callable(scene) else load_scene(SCENES / scene)
        sc = sc.with_("load.approach", approach).with_model(theory="conformal", influence="halfspace")
        if n is not None:
            sc = sc.with_("grid.n", n)
        self.problem = curved_problem_from_wheel_rail(sc)
        grid = self.problem.grid
        op, info = influence_operator(grid, sc.material, sc.model)
        self.hs = solve_curved(self.problem, op, info)
        self.p = np.asarray(self.hs.field.pn, float)
        self.material = sc.material
        m = sc.material
        self.rail, self.rpatch = rail_body_from_grid(grid, self.problem.rail_points)
        self.wheel, self.wpatch, self.rot = wheel_body_from_grid(grid, self.problem.wheel_points)
        # single-body half-space numbers in the turned element frames (the "halfspace" model)
        self.hs_body = {b: curved_halfspace_kernel(grid.mx, grid.dx, grid.s - grid.s_ref, grid.ds, grid.delta,
                                                   _identical(m, b)) / 2.0 for b in ("rail", "wheel")}
        edge = self.p[[0, -1], :].any() or self.p[:, [0, -1]].any()
        self.warning = "the half-space contact reaches the strip's edge" if edge else ""

    def sections(self):
        """The real rail and wheel as whole sections (``fe_closure = "section"``): the 60E1 section
        below a UIC60 head, the wheel's rim and web below an S1002 profile
        (conformal.geometry.sections), each opened at its support edge (the rail's foot, the
        wheel's hub: bodies.section_profile); None where the profiles are not those."""
        from conformal.errors import InputError
        from conformal.geometry.sections import uic60_section, wheel_rim_section
        from conformal.meshing.bodies import BodyModel, section_profile

        rp, wp = self.rail.profile, self.wheel.profile
        try:
            rs = uic60_section(np.column_stack([rp.y, rp.z]))
            ws = wheel_rim_section(np.column_stack([wp.y, wp.z]), -self.wheel.axle_z)
        except InputError:
            return None
        return (BodyModel("rail", section_profile(rs.points, rs.n_profile, rs.clamped[0], rs.name)),
                BodyModel("wheel", section_profile(ws.points, ws.n_profile, ws.clamped[0], ws.name),
                          axle_z=self.wheel.axle_z))

    def kernels(self, settings, cache):
        """(rail kernel, wheel kernel in the rail's element frames, stats) for FE settings (with
        the closure "section": the bodies of :meth:`sections`)."""
        from conformal.influence.fe import body_influences, rotate_kernel

        m = self.material
        rail, wheel = self.sections() if settings.mesh.closure == "section" else (self.rail, self.wheel)
        kr, kw = body_influences([(rail, self.rpatch, m.G1, m.nu1, settings),
                                  (wheel, self.wpatch, m.G2, m.nu2, settings)], cache)
        return kr.kernel, rotate_kernel(kw.kernel, self.rot), {"rail": kr.stats, "wheel": kw.stats}

    def slab(self) -> bool:
        """Whether a body's section is a slab (its ends point the same way, bodies.grow_profile):
        the default limits its margin to the section's width."""
        from conformal.meshing.bodies import grow_profile

        return any(grow_profile(b, p, max(SIZES))[1].slab_width > 0
                   for b, p in ((self.rail, self.rpatch), (self.wheel, self.wpatch)))

    def compliance(self, kernel, body: str) -> float:
        return _compliance(kernel, self.hs_body[body], self.p)

    def fn_ratio(self, kernel) -> float:
        from conformal.influence.curved import CurvedInfluence
        from conformal.solvers.conformal import solve_curved

        r = solve_curved(self.problem, CurvedInfluence.from_kernel(kernel), {"influence": "fe"})
        return float(r.FN / self.hs.FN)

    def at_load(self, kernel) -> dict:
        """At a prescribed load (the half-space solution's FN along the load direction) instead of
        its approach: pmax, the contact area and the approach with the FE numbers over those with
        the half-space numbers at the same load (what a real rail and wheel, which have no
        approach relative to infinity, compare at)."""
        if not hasattr(self, "_hs_load"):
            self._hs_load = self._load_solution(self.hs_body["rail"] + self.hs_body["wheel"])
        fe, hs = self._load_solution(kernel), self._hs_load
        return {f"{k}_load": fe[k] / hs[k] for k in fe}

    def _load_solution(self, kernel) -> dict:
        from conformal.influence.curved import CurvedInfluence
        from conformal.solvers.conformal import solve_curved

        prob = replace(self.problem, approach=None, normal_force=float(self.hs.FN))
        r = solve_curved(prob, CurvedInfluence.from_kernel(kernel), {"influence": "fe"})
        p = np.asarray(r.field.pn, float)
        g = self.problem.grid
        dA = g.dx * np.broadcast_to(np.asarray(g.ds, float)[None, :], p.shape)
        return {"pmax": float(p.max()), "area": float(((p > 0) * dA).sum()), "approach": float(r.approach)}


def _identical(m, body: str):
    from conformal.materials import Material

    return Material.identical(m.G1, m.nu1) if body == "rail" else Material.identical(m.G2, m.nu2)


def _compliance(kernel: np.ndarray, reference: np.ndarray, p: np.ndarray) -> float:
    """sum p (K_nn * p) / sum p (K_ref,nn * p): the pressure-weighted mean normal displacement."""
    from conformal.influence.curved import CurvedInfluence

    u = CurvedInfluence.from_kernel(kernel).apply_normal(p)
    u0 = CurvedInfluence.from_kernel(reference).apply_normal(p)
    return float((p * u).sum() / (p * u0).sum())


class FlatBlock:
    """The flat block: a 9 x 9 patch of 1 mm elements under an elliptic (Hertz-like) pressure;
    its exact large-body compliance is the half-space's (1)."""

    key, label, warning = "flat", "flat block (exact 1)", ""

    def __init__(self, n: int = 9, d: float = 1.0):
        from conformal.influence.curved import curved_halfspace_kernel
        from conformal.meshing.bodies import BodyModel, StripPatch, flat_profile

        self.body = BodyModel("block", flat_profile(-40.0, 40.0))
        self.patch = StripPatch.uniform(n, d, n, d, 40.0)
        c = (np.arange(n) - 0.5 * (n - 1)) * d
        X, S = np.meshgrid(c, c, indexing="ij")
        a = 0.5 * n * d
        self.p = np.sqrt(np.clip(1 - (X / a) ** 2 - (S / (0.8 * a)) ** 2, 0, None))
        self.hs = curved_halfspace_kernel(n, d, c, np.full(n, d), np.zeros(n), _identical_steel()) / 2.0

    def compliance(self, settings, cache) -> tuple[float, dict]:
        from conformal.influence.fe import cached_body_influence

        r = cached_body_influence(self.body, self.patch, G, NU, settings, cache=cache)
        return _compliance(r.kernel, self.hs, self.p), r.stats


def _identical_steel():
    from conformal.materials import Material

    return Material.identical(G, NU)


# ----------------------------------------------------------------------------- settings
def fe_settings(size: float, far: str = "halfspace", refine: float = 1.0, **mesh):
    """FE settings of the series: the production defaults, the body size and far field given,
    every element size (h_patch, h_load, h_max, and h_wall, which only the closure "section"
    uses) times ``refine``."""
    from conformal.influence.fe import FESettings
    from conformal.meshing.gmsh_body import MeshSpec

    base = MeshSpec()
    # every element size: with the closure "section" also the walls' cap (a fraction of the local
    # wall thickness, conformal.meshing.wall)
    mesh.setdefault("h_wall", base.h_wall * refine)
    spec = replace(base, body_size=size, h_patch=base.h_patch * refine, h_load=base.h_load * refine,
                   h_max=base.h_max * refine, **mesh)
    return FESettings(far_field=far, mesh=spec)


# ----------------------------------------------------------------------------- runs
def run_flat(sizes, far: str, cache) -> list[dict]:
    blk = FlatBlock()
    rows = []
    for s in sizes:
        t0 = time.perf_counter()
        c, st = blk.compliance(fe_settings(s, far), cache)
        rows.append({"case": "flat", "far_field": far, "grading": "default", "size": s, "C_block": c,
                     "time_s": time.perf_counter() - t0, "dofs": st.get("dofs")})
        print(f"flat block {far:9s} size {s:4g}: C = {c:.5f}", flush=True)
    return rows


def run_case(case, sizes, far: str, refine: float, cache, grading: str, **mesh) -> list[dict]:
    rows = []
    for s in sizes:
        t0 = time.perf_counter()
        settings = fe_settings(s, far, refine, **mesh)
        try:
            kr, kw, st = case.kernels(settings, cache)
        except ConformalError as exc:      # e.g. gmsh leaving flat tetrahedra in a small body
            print(f"{case.label}: {far} {grading} size {s:g}: not possible: {exc}", flush=True)
            rows.append({"case": case.key, "far_field": far, "grading": grading, "size": s, "error": str(exc)})
            continue
        row = {"case": case.key, "far_field": far, "grading": grading, "size": s,
               "C_rail": case.compliance(kr, "rail"), "C_wheel": case.compliance(kw, "wheel"),
               "FN_ratio": case.fn_ratio(kr + kw),
               # one FE body against the other's half-space numbers: what each body's shape does
               "FN_rail_only": case.fn_ratio(kr + case.hs_body["wheel"]),
               "FN_wheel_only": case.fn_ratio(case.hs_body["rail"] + kw), **case.at_load(kr + kw),
               "time_s": time.perf_counter() - t0,
               "fe_s": sum(float(v.get("total_s", 0.0)) for v in st.values()),
               "fe_body_s": [v.get("total_s") for v in st.values()],
               "peak_rss_gib": max(float(v.get("peak_rss_gib", 0.0)) for v in st.values()),
               "dofs": [v.get("dofs") for v in st.values()],
               "h_wall": settings.mesh.h_wall if settings.mesh.closure == "section" else None,
               "body": {b: v.get("body") for b, v in st.items()}}
        rows.append(row)
        print(f"{case.label}: {far:9s} {grading:7s} size {s:4g}: C_rail {row['C_rail']:.5f} C_wheel "
              f"{row['C_wheel']:.5f} FN/FN_hs {row['FN_ratio']:.5f} (FE {row['fe_s']:.1f} s, dofs {row['dofs']})",
              flush=True)
    return rows


def limits(rows, case: str, far: str, grading: str, key: str) -> dict:
    sel = sorted((r for r in rows if r["case"] == case and r["far_field"] == far and r["grading"] == grading
                  and key in r), key=lambda r: r["size"])
    if len(sel) < 2:
        return {}
    return richardson([r["size"] for r in sel], [r[key] for r in sel])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the flat block, clamped, sizes 4, 8, 16 only")
    ap.add_argument("--cases", default="deep,groove,gauge", help="comma-separated: deep, groove, gauge")
    ap.add_argument("--out", default=None, help="output folder (default studies/out/fe_far_field_limit)")
    ap.add_argument("--series", default="halfspace,clamped,fine,straight,p2,section,section_clamped",
                    help="comma-separated: halfspace, clamped, fine (refined grading), straight (slabs not "
                         "limited), p2 (quadratic tetrahedra, default grading, sizes 4-16), section, "
                         "section_clamped, section_fine, section_coarse (real rail and wheel sections, closure "
                         "\"section\"; fine / coarse: every element size halved / doubled, sizes 16 and 32), "
                         "section_p2 (quadratic tetrahedra, every element size doubled)")
    ap.add_argument("--section-sizes", default=None,
                    help="comma-separated body sizes of the section series (default 1-64; clamped 2-64) "
                         "and of section_fine (default 16,32), e.g. 16,32")
    ap.add_argument("--report", action="store_true",
                    help="only rebuild the report (md, png) from the existing JSON")
    ap.add_argument("--append", action="store_true",
                    help="keep the rows of other cases and series from the existing JSON (rerun some only)")
    args = ap.parse_args(argv)
    out = output_dir("fe_far_field_limit", args)
    out.mkdir(parents=True, exist_ok=True)
    os.environ.setdefault("CONFORMAL_CACHE", str(Path(tempfile.gettempdir()) / "conformal_fe_far_field_limit"))
    from conformal.influence.cache import Cache

    cache = Cache(None)
    rows: list[dict] = []
    series = set(args.series.split(","))
    keys = [k for k in args.cases.split(",") if k]
    if args.report:
        rows = json.loads((out / "fe_far_field_limit.json").read_text())["rows"]
        summary = summarise(rows)
        _dump(out, rows, summary, converged(rows, summary))
        (out / "fe_far_field_limit.md").write_text(report(rows, summary))
        _plot(rows, summary, out / "fe_far_field_limit.png")
        return 0
    if args.append and (out / "fe_far_field_limit.json").exists():
        old = json.loads((out / "fe_far_field_limit.json").read_text())["rows"]
        rerun = {SERIES[s] for s in series if s in SERIES}
        only = None if args.section_sizes is None else {float(v) for v in args.section_sizes.split(",")}

        def kept(r):        # with --section-sizes only those sizes of the section series are rerun
            if r["case"] in keys and r["grading"].startswith("section") and r.get("h_wall") is None:
                return False    # a section row from before the walls' cap (conformal.meshing.wall)
            if r["case"] not in keys or (r["far_field"], r["grading"]) not in rerun:
                return True
            return only is not None and r["grading"].startswith("section") and r["size"] not in only

        rows = [r for r in old if kept(r) and (r["case"] != "flat" or args.quick)]
    if args.quick:
        rows += run_flat(QUICK_SIZES, "clamped", cache)
    else:
        rows += run_flat((0.5,) + SIZES, "clamped", cache)
        tmp = Path(tempfile.mkdtemp(prefix="fe_far_field_limit_"))
        for key in keys:
            case = Case(key, tmp)
            print(f"{case.label}: half-space FN = {case.hs.FN:.1f} N {case.warning}", flush=True)
            if "halfspace" in series:
                rows += run_case(case, SIZES, "halfspace", 1.0, cache, "default")
                _dump(out, rows)
            if "clamped" in series:
                rows += run_case(case, CLAMPED_SIZES, "clamped", 1.0, cache, "default")
                _dump(out, rows)
            if "fine" in series:
                rows += run_case(case, FINE_SIZES, "halfspace", 0.5, cache, "fine")
                _dump(out, rows)
            if "straight" in series and case.slab():
                rows += run_case(case, STRAIGHT_SIZES, "halfspace", 1.0, cache, "straight", closure="straight")
                _dump(out, rows)
            sec_sizes = SECTION_SIZES if args.section_sizes is None else tuple(
                float(v) for v in args.section_sizes.split(","))
            if "section" in series and case.sections() is not None:
                rows += run_case(case, sec_sizes, "halfspace", 1.0, cache, "section", closure="section")
                _dump(out, rows)
            if "section_clamped" in series and case.sections() is not None:
                rows += run_case(case, tuple(v for v in sec_sizes if v >= 2.0), "clamped", 1.0, cache, "section",
                                 closure="section")
                _dump(out, rows)
            if "section_coarse" in series and case.sections() is not None:
                rows += run_case(case, SECTION_FINE_SIZES if args.section_sizes is None else sec_sizes, "halfspace",
                                 2.0, cache, "section_coarse", closure="section")
                _dump(out, rows)
            if "section_p2" in series and case.sections() is not None:
                rows += run_case(case, SECTION_FINE_SIZES if args.section_sizes is None else sec_sizes, "halfspace",
                                 2.0, cache, "section_p2", closure="section", order=2)
                _dump(out, rows)
            if "section_fine" in series and case.sections() is not None:
                rows += run_case(case, SECTION_FINE_SIZES if args.section_sizes is None else sec_sizes, "halfspace",
                                 0.5, cache, "section_fine", closure="section")
                _dump(out, rows)
            if "p2" in series:
                rows += run_case(case, P2_SIZES, "halfspace", 1.0, cache, "p2", order=2)
                _dump(out, rows)
    summary = summarise(rows)
    _dump(out, rows, summary, converged(rows, summary))
    (out / "fe_far_field_limit.md").write_text(report(rows, summary))
    _plot(rows, summary, out / "fe_far_field_limit.png")
    write_sidecar(out, __file__, args, extra={"converged": converged(rows, summary)})
    print(report(rows, summary))
    return 0


def summarise(rows) -> dict:
    out = {}
    for case in dict.fromkeys(r["case"] for r in rows):
        keys = ["C_block"] if case == "flat" else ["C_rail", "C_wheel", "FN_ratio", "FN_rail_only", "FN_wheel_only",
                                                   "pmax_load", "area_load", "approach_load"]
        for far, grading in SERIES.values():
            for k in keys:
                lim = limits(rows, case, far, grading, k)
                if lim:
                    out.setdefault(case, {}).setdefault(f"{far}/{grading}", {})[k] = lim
    return out


def converged(rows, summary) -> list[dict]:
    """Per case and quantity: the limit (R3 of the half-space far field's series), its error bar
    (the largest of |R2 - R3|, the clamped series' R3 and the refined grading's R2 against it),
    and the production default's value and distance from it (the default's size is one of the
    series' sizes)."""
    from conformal.meshing.gmsh_body import MeshSpec

    size = MeshSpec().body_size
    out = []
    for case, per in summary.items():
        hs = per.get("halfspace/default", {})
        for k, lim in hs.items():
            if "R3" not in lim:
                continue
            others = [abs(lim["R2"] - lim["R3"])]
            cl = per.get("clamped/default", {}).get(k, {})
            fine = per.get("halfspace/fine", {}).get(k, {})
            if "R3" in cl:
                others.append(abs(cl["R3"] - lim["R3"]))
            if "R2" in fine:
                others.append(abs(fine["R2"] - lim["R2"]))
            at = [r[k] for r in rows if r["case"] == case and r["far_field"] == "halfspace"
                  and r["grading"] == "default" and r["size"] == size and k in r]
            p2 = per.get("halfspace/p2", {}).get(k, {})
            row = {"case": case, "quantity": k, "limit": lim["R3"], "err": max(others), "ratio": lim.get("ratio"),
                   "clamped_R3": cl.get("R3"), "fine_R2": fine.get("R2"), "p2_R3": p2.get("R3"),
                   "p2_ratio": p2.get("ratio")}
            if at:
                row.update(default=at[0], default_off=at[0] / lim["R3"] - 1.0)
            out.append(row)
    return out


def section_limits(rows, summary) -> list[dict]:
    """Per case with a section series and quantity: the value at its largest size as the limit
    (the series leaves the 1/size regime: the real bodies' structure, not the contact, changes
    with the size until the disc holds the section and the wheel's disc reaches its cap), the
    change from the size before as its error bar, the clamped section series' value at its
    largest size, and the production default's value (closure "extend", half-space far field,
    the default size) and distance from that limit."""
    from conformal.meshing.gmsh_body import MeshSpec

    size = MeshSpec().body_size
    out = []
    for case, per in summary.items():
        for k in per.get("halfspace/section", {}):
            sel = sorted((r["size"], r[k]) for r in rows if r["case"] == case and r["grading"] == "section"
                         and r["far_field"] == "halfspace" and k in r)
            cl = sorted((r["size"], r[k]) for r in rows if r["case"] == case and r["grading"] == "section"
                        and r["far_field"] == "clamped" and k in r)
            fine = sorted((r["size"], r[k]) for r in rows if r["case"] == case and r["grading"] == "section_fine"
                          and k in r)
            coarse = sorted((r["size"], r[k]) for r in rows if r["case"] == case and r["grading"] == "section_coarse"
                            and k in r)
            p2 = sorted((r["size"], r[k]) for r in rows if r["case"] == case and r["grading"] == "section_p2"
                        and k in r)
            at = [r[k] for r in rows if r["case"] == case and r["far_field"] == "halfspace"
                  and r["grading"] == "default" and r["size"] == size and k in r]
            lim = sel[-1][1]
            row = {"case": case, "quantity": k, "limit": lim, "err": abs(sel[-1][1] - sel[-2][1]),
                   "values": " / ".join(f"{v:.4f}" for _, v in sel[-3:]),
                   "sizes": " / ".join(f"{s:g}" for s, _ in sel[-3:]),
                   "clamped_last": cl[-1][1] if cl else None,
                   "fine": " / ".join(f"{v:.4f} ({s:g})" for s, v in fine) or "-",
                   "coarse": " / ".join(f"{v:.4f} ({s:g})" for s, v in coarse) or "-",
                   "p2": " / ".join(f"{v:.4f} ({s:g})" for s, v in p2) or "-"}
            if at:
                row.update(default=at[0], default_off=at[0] / lim - 1.0)
            out.append(row)
    return out


def _dump(out: Path, rows, summary=None, conv=None) -> None:
    tmp = out / "fe_far_field_limit.json.tmp"
    tmp.write_text(json.dumps({"rows": rows, "summary": summary or {}, "converged": conv or []}, indent=1,
                              default=float))
    os.replace(tmp, out / "fe_far_field_limit.json")


def report(rows, summary) -> str:
    from conformal.meshing.gmsh_body import MeshSpec

    conv = converged(rows, summary)
    head = ["| case | quantity | limit (R3, half-space far field) | error bar | ratio of differences 4-8-16 "
            f"| clamped R3 | refined R2 | P2 R3 (ratio) | default (size {MeshSpec().body_size:g}) | default - limit |",
            "|---|---|---|---|---|---|---|---|---|---|"]

    def f(v, fmt="{:.4f}"):
        return "-" if v is None else fmt.format(v)

    for c in conv:
        r = c.get("ratio")
        regime = f(r, "{:.2f}") + ("" if r is not None and 0.4 <= r <= 0.7 else " (not 1/size)")
        p2 = f(c.get("p2_R3")) + ("" if c.get("p2_ratio") is None else f" ({c['p2_ratio']:.2f})")
        head.append(f"| {c['case']} | {c['quantity']} | {c['limit']:.4f} | {c['err']:.4f} | {regime} | "
                    f"{f(c['clamped_R3'])} | {f(c['fine_R2'])} | "
                    f"{p2} | {f(c.get('default'))} | "
                    f"{f(c.get('default_off'), '{:+.2%}')} |")
    slabs = sorted({(r["case"], b, r["size"]) for r in rows for b, v in (r.get("body") or {}).items()
                    if v and v.get("margin_limited_by") == "section width" and r["grading"] == "default"})
    for case in dict.fromkeys(c for c, _, _ in slabs):
        first = min((z, b) for c, b, z in slabs if c == case)
        head.append("")
        head.append(f"{case}: the {first[1]} section is a slab (its profile's ends point the same way); from size "
                    f"{first[0]:g} on its margin is limited to the section's width, so its 'limit' is that of the "
                    "limited body, not of a large one: the series 'straight' (not limited) grows without bound.")
    sec = section_limits(rows, summary)
    if sec:
        head += ["", "Real sections (``fe_closure = \"section\"``: the 60E1 rail and the wheel's rim and web, "
                 "conformal.geometry.sections): the value at the largest size as the limit, with the change "
                 "from the size before, and the production default's (closure \"extend\") distance from it.",
                 "", "| case | quantity | sizes | section series | limit (largest size) | clamped section, "
                 "largest size | every element doubled | every element halved | P2, every element doubled | "
                 "default (extend) | default - limit |",
                 "|---|---|---|---|---|---|---|---|---|---|---|"]
        for c in sec:
            head.append(f"| {c['case']} | {c['quantity']} | {c['sizes']} | {c['values']} | {c['limit']:.4f} +- "
                        f"{c['err']:.4f} | {f(c.get('clamped_last'))} | {c['coarse']} | {c['fine']} | {c['p2']} | "
                        f"{f(c.get('default'))} | "
                        f"{f(c.get('default_off'), '{:+.2%}')} |")
    sizes = sorted({r["size"] for r in rows if "size" in r and r["case"] != "flat"} | set(SIZES))
    lines = head + ["", "| case | quantity | far field / grading | value at size " + " / ".join(f"{s:g}" for s in sizes)
             + " | R2 | R3 | ratio of differences |", "|---|---|---|---|---|---|---|"]
    for case, per in summary.items():
        for series, d in per.items():
            far, grading = series.split("/")
            for k, lim in d.items():
                by = {r["size"]: r[k] for r in rows if r["case"] == case and r["far_field"] == far
                      and r["grading"] == grading and k in r}
                vals = " / ".join(f"{by[s]:.4f}" if s in by else "-" for s in sizes)
                lines.append(f"| {case} | {k} | {series} | {vals} | {lim['R2']:.4f} | "
                             f"{lim.get('R3', float('nan')):.4f} | {lim.get('ratio', float('nan')):.2f} |")
    return "\n".join(lines) + "\n"


def _plot(rows, summary, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = [c for c in summary if c != "flat"] or ["flat"]
    styles = (("halfspace", "default", "-o"), ("clamped", "default", "--s"), ("halfspace", "fine", ":^"),
              ("halfspace", "straight", "-.x"), ("halfspace", "p2", ":D"), ("halfspace", "section", "-P"),
              ("clamped", "section", "--P"), ("halfspace", "section_fine", ":P"),
              ("halfspace", "section_coarse", "-.P"), ("halfspace", "section_p2", ":X"))
    # the real sections (30-100 % more compliant than the half-space) get a panel of their own, so
    # that the few-per-cent differences of the continued profiles stay readable
    panels = []
    for case in cases:
        for real in (False, True):
            own = [st for st in styles if st[1].startswith("section") == real]
            if any(r["case"] == case and (r["grading"], r["far_field"]) in {(g, f) for f, g, _ in own} for r in rows):
                panels.append((case, real, own))
    fig, axes = plt.subplots(1, len(panels), figsize=(4.6 * len(panels), 4.0), squeeze=False)
    for ax, (case, real, own) in zip(axes[0], panels):
        keys = ["C_block"] if case == "flat" else ["C_rail", "C_wheel", "FN_ratio"]
        vals = []
        for k, key in enumerate(keys):
            for far, grading, style in own:
                sel = sorted((r for r in rows if r["case"] == case and r["far_field"] == far
                              and r["grading"] == grading and key in r), key=lambda r: r["size"])
                if sel:
                    ax.plot([1 / r["size"] for r in sel], [r[key] for r in sel], style, color=f"C{k}", ms=4,
                            label=f"{key}, {far}, {grading}")
                    vals += [r[key] for r in sel]
            lim = summary.get(case, {}).get("halfspace/default", {}).get(key)
            if lim and not real:
                ax.plot([0], [lim.get("R3", lim["R2"])], "*", color=f"C{k}", ms=10)
        ax.axhline(1.0, color="0.6", lw=0.8)
        ax.set_xlabel("1 / fe_body_size (patch sizes)")
        if ax is axes[0][0]:
            ax.set_ylabel("FE / half-space")
        ax.set_title(f"{case}: real rail and wheel sections" if real else case, fontsize=10)
        ax.set_ylim(min(0.85, min(vals, default=1) - 0.02), max(1.2, max(vals, default=1) + 0.02))
        if real:
            ax.set_xlim(left=0.0)
    handles = {}
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    fig.legend(list(handles.values()), list(handles.keys()), loc="lower center", ncol=4, fontsize=7)
    fig.suptitle("Compliance per body (C_rail, C_wheel) and FN per pair at a prescribed approach, FE over "
                 "half-space;\nstars: Richardson limits (R3) of the half-space far field's series", fontsize=10)
    fig.set_figheight(4.0 + 0.22 * math.ceil(len(handles) / 4))
    fig.tight_layout(rect=(0, 0.04 + 0.034 * math.ceil(len(handles) / 4), 1, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
