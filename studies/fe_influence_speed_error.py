"""Speed against error of FE influence numbers: method, element order, mesh size near
the contact, body size and linear solver.

Target: the influence numbers of a 51 x 39 grid of 0.4 mm elements (wheel and rail) within 1 % of
the self-influence number of the flat-limit reference (truncation offset accounted for) in under
60 s on this machine, in under 8 GiB.

1. Flat limit.  A block (the flat body of the same size rules as the rail) carries the 51 x 39
   patch; its FE kernel is compared with the single-body half-space numbers
   (conformal.influence.halfspace.single_body_influence; element-averaged numbers for the
   direct method, whose natural observation is the element average).  With the default
   half-space far field the split method is exact here; the split rows with clamped artificial
   boundaries show the FE part: a clamped finite body is stiffer than a half-space by an almost
   constant offset, separated as the median of the difference per component.  Errors are
   relative to the self term A_zz(0, 0):
     e_raw  = max |K - A|,   e_off = max |K - A - offset|,   offset = median(K - A) (zz).
2. Wheel and rail.  The chosen settings on a UIC 60 crown patch and an S1002 tread patch
   (51 x 39, 0.4 mm): wall time and peak memory of both bodies.
3. Curvature.  On the R13 gauge corner of the rail (11 x 9 patch) the cheap settings are compared
   with P2 at h = d/2 (no analytic reference there).

Every configuration runs in its own process (peak memory = that process's max RSS).  Output in
--out (default studies/out/fe_influence_speed_error/; --quick: a temporary folder):
fe_influence_speed_error.{json,md,png}, the kernels compared in part 3 (fe_kernel_*.npy) and the
sidecar run.json (commit, arguments, package versions).

    python studies/fe_influence_speed_error.py            # all (about 15-25 min on 2 cores)
    python studies/fe_influence_speed_error.py --quick    # a few configurations
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _provenance import output_dir, write_sidecar  # noqa: E402
OUT = ROOT / "studies" / "out" / "fe_influence_speed_error"  # set by main (--out)
PROFILES = ROOT / "conformal" / "data" / "profiles"
G, NU, D = 82000.0, 0.28, 0.4


def _profile(name):
    from conformal.meshing.bodies import Profile2D

    yz = np.loadtxt(PROFILES / name, delimiter=",")
    return Profile2D.from_points(yz, name.split("_")[0])


def body_and_patch(kind: str, mx: int, ms: int, d: float):
    from conformal.meshing.bodies import BodyModel, StripPatch, flat_profile

    if kind == "block":
        return BodyModel("block", flat_profile(-200.0, 200.0)), StripPatch.uniform(mx, d, ms, d, 200.0)
    if kind in ("rail", "gauge"):
        prof = _profile("uic60_head_r300w21_analytic.csv")
        y0, z0 = (0.0, 0.0) if kind == "rail" else (-30.0, 5.0)
        sc = float(prof.project(np.array([y0, z0])))
        return BodyModel("rail", prof), StripPatch.uniform(mx, d, ms, d, sc)
    prof = _profile("s1002_analytic.csv")
    sc = float(prof.project(np.array([0.0, 0.0])))
    return BodyModel("wheel", prof, axle_z=-460.0), StripPatch.uniform(mx, d, ms, d, sc)


def averaged_halfspace(patch, n: int = 8):
    from conformal.influence.halfspace import single_body_influence

    kx = patch.x_centres[:, None, None]
    ds = (patch.s_centres[:, None] - patch.s_centres[None, :])[None]
    g, w = np.polynomial.legendre.leggauss(n)
    A = 0.0
    for gi, wi in zip(g, w):
        for gj, wj in zip(g, w):
            A = A + 0.25 * wi * wj * single_body_influence(kx + 0 * ds + 0.5 * gi * patch.dx,
                                                           ds + 0 * kx + 0.5 * gj * D, patch.dx, D, G=G, nu=NU)
    return A


def run_one(cfg: dict) -> dict:
    """One configuration (in this process): the kernel, its errors (block) and its costs."""
    from conformal.influence.fe import FESettings, body_influence
    from conformal.influence.halfspace import single_body_influence
    from conformal.meshing.gmsh_body import MeshSpec

    body, patch = body_and_patch(cfg["kind"], cfg["mx"], cfg["ms"], cfg.get("d", D))
    mesh = MeshSpec(order=cfg["order"], h_patch=cfg["h_patch"], h_load=cfg.get("h_load"),
                    growth=cfg.get("growth", 0.35), body_size=cfg["body_size"], conform=cfg.get("conform", "column"))
    st = FESettings(method=cfg["method"], mesh=mesh, solver=cfg.get("solver", "auto"),
                    collocation="average" if cfg["method"] == "direct" else "centre",
                    far_field=cfg.get("far_field", "halfspace"))
    t0 = time.perf_counter()
    r = body_influence(body, patch, G, NU, st)
    wall = time.perf_counter() - t0
    out = dict(cfg, wall_s=wall, dofs=r.stats["dofs"], peak_gib=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20,
               **{k: r.stats[k] for k in ("mesh_s", "assemble_s", "rhs_s", "factor_s", "solve_s", "observe_s")})
    K = r.kernel
    if cfg.get("save"):
        np.save(Path(cfg.get("out", OUT)) / f"fe_kernel_{cfg['save']}.npy", K)
    if cfg["kind"] == "block":
        mx = patch.mx
        kx = patch.x_centres[:, None, None]
        ds = (patch.s_centres[:, None] - patch.s_centres[None, :])[None]
        A = (averaged_halfspace(patch) if st.collocation == "average"
             else single_body_influence(kx + 0 * ds, ds + 0 * kx, patch.dx, D, G=G, nu=NU))
        s = float(A[mx - 1, 0, 0, 2, 2])
        diff = K - A
        off = np.median(diff.reshape(-1, 3, 3), axis=0)
        idx = np.arange(patch.ms)
        out.update(e_raw=float(np.abs(diff).max() / s), e_off=float(np.abs(diff - off).max() / s),
                   offset_zz=float(off[2, 2] / s),
                   e_self_zz=float(np.mean(diff[mx - 1, idx, idx, 2, 2] - off[2, 2]) / s),
                   e_off_by_comp={f"{i}{j}": float(np.abs(diff[..., i, j] - off[i, j]).max() / s)
                                  for i in range(3) for j in range(3)})
    return out


def spawn(cfg: dict, timeout: float = 600.0) -> dict:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--one", json.dumps(cfg)]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return dict(cfg, error=f"timeout after {timeout:.0f} s")
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
    if p.returncode != 0 or not lines:
        return dict(cfg, error=(p.stderr.strip().splitlines() or ["failed"])[-1])
    return json.loads(lines[-1])


def configurations(quick: bool):
    base = dict(kind="block", mx=51, ms=39, d=D, method="split", order=1, h_patch=1.0, body_size=1.0)
    default = dict(base, h_patch=2.0, h_load=0.5)
    # the split rows below use clamped artificial boundaries: with the default half-space far
    # field the flat block's correction vanishes (first row: exact, nothing to solve), so only the
    # clamped variants show what mesh, order and body size do to the FE part of the numbers
    clamped = dict(base, far_field="clamped")
    cfgs = [
        dict(default, name="split P1 default (half-space far field)"),
        dict(default, far_field="clamped", name="split P1 h=2d, column h=d/2, clamped"),
        dict(default, far_field="clamped", name="split P1 h=2d, column h=d/2, body 2, clamped", body_size=2.0),
        dict(clamped, name="split P1 h=d, clamped"),
        dict(clamped, name="split P1 h=2d, column h=d, clamped", h_patch=2.0, h_load=1.0),
        dict(clamped, name="split P1 h=3d, column h=d, clamped", h_patch=3.0, h_load=1.0),
        dict(clamped, name="split P1 h=d, body 0.5, clamped", body_size=0.5),
        dict(clamped, name="split P1 h=d, body 2, clamped", body_size=2.0),
        dict(clamped, name="split P1 h=d, growth 0.6, clamped", growth=0.6),
        dict(clamped, name="split P2 h=2d, column h=d, clamped", order=2, h_patch=2.0, h_load=1.0),
        dict(clamped, name="split P1 h=d, splu, clamped", solver="splu"),
        dict(clamped, name="split P1 h=d, AMG-CG, clamped", solver="amg"),
        dict(base, name="direct P1 h=d, column h=d/2", method="direct", h_load=0.5),
        dict(base, name="direct P2 h=2d, column h=d/2", method="direct", order=2, h_patch=2.0, h_load=0.5),
        dict(base, name="direct P2 h=2d, column h=d/4", method="direct", order=2, h_patch=2.0, h_load=0.25),
    ]
    if quick:
        cfgs = [cfgs[0], cfgs[3], cfgs[12]]
    bodies = []
    for h in ((2.0, 0.5), (1.0, None), (2.0, 1.0)):
        for kind in ("rail", "wheel"):
            bodies.append(dict(base, kind=kind, h_patch=h[0], h_load=h[1],
                               name=f"{kind} split P1 h_patch={h[0]:g}d" + (f", column h={h[1]:g}d" if h[1] else "")
                               + (" (default)" if h == (2.0, 0.5) else "")))
    curv = [dict(kind="gauge", mx=11, ms=9, d=D, method="split", order=o, h_patch=h, h_load=hl, body_size=1.0,
                 name=f"gauge split P{o} h={h:g}d" + (f" col {hl:g}d" if hl else ""), save=f"gauge_P{o}_{h:g}_{hl}")
            for o, h, hl in ((2, 0.5, None), (1, 2.0, 0.5), (1, 1.0, None), (1, 2.0, 1.0), (1, 1.0, 0.5),
                             (1, 1.0, 0.25), (2, 1.0, None))]
    if quick:
        bodies, curv = bodies[:2], curv[:2]
    return cfgs, bodies, curv


def pareto(points):
    """Indices of the Pareto-optimal points (min time, min error)."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], np.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def report(flat, bodies, curv):
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "fe_influence_speed_error.json").write_text(json.dumps({"flat": flat, "bodies": bodies, "curvature": curv},
                                                                  indent=1))
    lines = ["# FE influence numbers: speed against error (studies/fe_influence_speed_error.py)", "",
             "## 1. Flat limit, 51 x 39 grid of 0.4 mm elements (one body, block)", "",
             "| configuration | unknowns | wall s | peak GiB | mesh s | factor+solve s | rhs s | offset_zz | e_raw | e_off | self zz |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in flat:
        if "error" in r:
            lines.append(f"| {r['name']} | failed: {r['error']} |")
            continue
        lines.append(f"| {r['name']} | {r['dofs']} | {r['wall_s']:.1f} | {r['peak_gib']:.2f} | {r['mesh_s']:.1f} | "
                     f"{r['factor_s'] + r['solve_s']:.1f} | {r['rhs_s']:.1f} | {100 * r['offset_zz']:.2f} % | "
                     f"{100 * r['e_raw']:.2f} % | {100 * r['e_off']:.2f} % | {100 * r['e_self_zz']:+.2f} % |")
    lines += ["", "Errors relative to the half-space self term A_zz(0,0); offset = median of K - A (truncation of the "
              "clamped body: summed over a contact patch it makes the body far too stiff, see "
              "studies/fe_body_size.py); e_off = max |K - A - offset| over all 9 components and offsets; self zz = "
              "mean self-term error after the offset.  Direct method (half-space far field): element-averaged "
              "numbers against the averaged half-space.  The default (half-space far field) is exact on the flat "
              "block (drawn at 0.001 % in the plot).", "",
              "## 2. Wheel and rail, 51 x 39 grid of 0.4 mm elements", "",
              "| body / configuration | unknowns | wall s | peak GiB | mesh s | rhs s | factor+solve s |", "|---|---:|---:|---:|---:|---:|---:|"]
    for r in bodies:
        if "error" in r:
            lines.append(f"| {r['name']} | failed: {r['error']} |")
            continue
        lines.append(f"| {r['name']} | {r['dofs']} | {r['wall_s']:.1f} | {r['peak_gib']:.2f} | {r['mesh_s']:.1f} | "
                     f"{r['rhs_s']:.1f} | {r['factor_s'] + r['solve_s']:.1f} |")
    pairs = {}
    for r in bodies:
        if "error" not in r:
            key = r["name"].split(" ", 1)[1]
            pairs.setdefault(key, []).append(r)
    for key, rs in pairs.items():
        if len(rs) == 2:
            lines.append(f"| **wheel + rail, {key}** | {rs[0]['dofs'] + rs[1]['dofs']} | "
                         f"**{rs[0]['wall_s'] + rs[1]['wall_s']:.1f}** | {max(r['peak_gib'] for r in rs):.2f} | | | |")
    lines += ["", "## 3. Curvature: R13 gauge corner of UIC 60, 11 x 9 grid of 0.4 mm (against split P2 h = d/2)", "",
              "| configuration | unknowns | wall s | max diff / self | xx | ss | nn |", "|---|---:|---:|---:|---:|---:|---:|"]
    ref = next((r for r in curv if "error" not in r and r["order"] == 2 and r["h_patch"] == 0.5), None)
    if ref is not None:
        Kr = np.load(OUT / f"fe_kernel_{ref['save']}.npy")
        s = Kr[ref["mx"] - 1, ref["ms"] // 2, ref["ms"] // 2, 2, 2]
        for r in curv:
            if "error" in r or r is ref:
                continue
            Kc = np.load(OUT / f"fe_kernel_{r['save']}.npy")
            dd = np.abs(Kc - Kr) / s
            lines.append(f"| {r['name']} | {r['dofs']} | {r['wall_s']:.1f} | {100 * dd.max():.2f} % | "
                         f"{100 * dd[..., 0, 0].max():.2f} % | {100 * dd[..., 1, 1].max():.2f} % | {100 * dd[..., 2, 2].max():.2f} % |")
    (OUT / "fe_influence_speed_error.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    # Pareto plot
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in flat if "error" not in r]
    floor = 1e-5   # exact rows (the default split with the half-space far field) are drawn here
    pts = [(r["wall_s"], max(r["e_off"], floor)) for r in ok]
    fig, (ax, tx) = plt.subplots(1, 2, figsize=(12, 5.5), gridspec_kw={"width_ratios": [3, 2]})
    for n, (r, (t, e)) in enumerate(zip(ok, pts), 1):
        marker = "o" if r["method"] == "split" else "s"
        color = "C0" if r["order"] == 1 else "C1"
        ax.scatter(t, 100 * e, marker=marker, color=color, s=25 + 60 * r["peak_gib"] / 8, zorder=3)
        ax.annotate(str(n), (t, 100 * e), fontsize=8, xytext=(3, 3 + 7 * (n % 2)), textcoords="offset points")
    tx.axis("off")
    tx.text(0, 1, "\n".join(f"{n:2d}  {r['name']}  ({r['dofs'] // 1000}k dofs, {r['peak_gib']:.1f} GiB)"
                            for n, r in enumerate(ok, 1)), va="top", family="monospace", fontsize=7.5)
    front = pareto(pts)
    fx = [pts[i][0] for i in front]
    fy = [100 * pts[i][1] for i in front]
    ax.step(fx, fy, where="post", color="k", lw=0.8, label="Pareto front")
    ax.axhline(1.0, color="r", ls="--", lw=0.8, label="target 1 %")
    ax.axvline(60.0, color="r", ls=":", lw=0.8, label="target 60 s")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time, one body (s)")
    ax.set_ylabel("max error after truncation offset / self term (%)\n(exact rows drawn at 0.001 %)")
    ax.set_title("FE influence numbers, 51 x 39 grid of 0.4 mm (flat limit)\n"
                 "o split, s direct; blue P1, orange P2; marker size ~ peak memory")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "fe_influence_speed_error.png", dpi=130)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--one", help="run one configuration (JSON) and print its result")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", help="output folder (default studies/out/fe_influence_speed_error)")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    if args.one:
        print(json.dumps(run_one(json.loads(args.one))))
        return
    global OUT
    OUT = output_dir("fe_influence_speed_error", args)
    flat, bodies, curv = configurations(args.quick)
    results = {}
    for group, cfgs in (("flat", flat), ("bodies", bodies), ("curvature", curv)):
        results[group] = []
        for cfg in cfgs:
            r = spawn(dict(cfg, out=str(OUT)))
            results[group].append(r)
            msg = r.get("error") or (f"{r['wall_s']:.1f} s, {r['dofs']} unknowns, {r['peak_gib']:.2f} GiB"
                                     + (f", e_off {100 * r['e_off']:.2f} %" if "e_off" in r else ""))
            print(f"[{group}] {cfg['name']}: {msg}", flush=True)
    report(results["flat"], results["bodies"], results["curvature"])
    write_sidecar(OUT, __file__, args)


if __name__ == "__main__":
    main()
