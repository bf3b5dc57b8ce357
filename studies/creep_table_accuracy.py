"""Accuracy of a creep-force table against direct exact solves, with FASTSIM beside it.

    python studies/creep_table_accuracy.py [--table TABLE.npz] [--n 300] [--fine 20] [--holdout 4000]
                                           [--out DIR] [--quick]

Random points, uniform in the table's own coordinates (ln a/b, nu, s = rho/(1+rho), theta over
the full circle, q = nphi/(1+|nphi|); Eqs. T1-T4 of conformal/tables/spec.py), so none lies on a
node, inside the tabulated ranges.  Reference: :func:`conformal.solvers.exact.solve` from a cold
start at each point with the table's solver settings (grid_n, tol): the error measured is the
table's own (interpolation) error.  Reported per point: |F_table - F_exact| / (mu FN) (the vector
norm over FX, FY) and |MZ error| / (mu FN sqrt(ab)); FASTSIM (conformal.theories.fastsim.
fastsim_batch, parabolic bound, 24 x 24 slices, Kalker's flexibilities) at the same points against
the same reference.  ``--fine`` points are also solved on a grid 2.5x finer to show the exact
solver's own discretisation error at the table's grid_n (what the table inherits).

``--holdout`` more points from another seed (``--holdout-seed``, default 18) are checked the same
way.  Every earlier sample shaped the shipped table, so only a fresh seed is the unbiased measure
of its error: the evaluator's interpolation (Eq. T5 of conformal/tables/table.py: Akima along the
spin axis, cubic Hermite along ln a/b) was chosen on the first ``--n`` points (seed 2026); the
earlier tables (7 a/b x 9 theta x 23 q nodes) were refined in boxes where the samples of seeds 7
and 8 found errors above 0.01; seed 9 (600 points) then found the largest errors between the a/b
nodes (13 a/b nodes instead of 7), and seeds 11-14 (1000-4000 points, each a new box, each
followed by a few new points above 0.01, along q and theta) led to the shipped table's uniformly
denser nodes, 13 theta x 45 q without boxes, sampled as finely as before (:func:`conformal.tables.
table.refine`); seed 15 (4000 points) found one point above 0.01, where the spline along s
overshot the knee of the force at full slip (PCHIP along s since); seed 16 (4000 points) found two,
in the last cell along s (rho 4-5), where the force still bends: 32 nodes along s instead of 22;
seed 17 (4000 points) found one, along q for a long contact (a/b = 3.7, small creepage, spin
against the lateral creepage): one refinement box, the q cell midpoints in [-0.5, 0.5] for a/b >=
1.6 and s < 0.35 (``conformal table refine ... --box 8:13,0:14,0:13 --q -0.5:0.5``).  ``--quick``: 20 points, 2 on
the finer grid, 20 hold-out points (a smoke run, not a measurement).

Writes OUT/accuracy.json, OUT/accuracy_points.csv (every point), OUT/accuracy_holdout_points.csv,
OUT/accuracy.png and the sidecar OUT/run.json (default OUT = studies/out/creep_table).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from threadpoolctl import threadpool_limits  # noqa: E402

from conformal.tables import evaluate, load_table  # noqa: E402
from conformal.tables.table import refine  # noqa: E402
from conformal.tables.build import solve_points  # noqa: E402
from conformal.tables.spec import saturation_scales  # noqa: E402
from conformal.theories.coefficients import coefficient_arrays  # noqa: E402
from conformal.theories.fastsim import fastsim_batch  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _provenance import write_sidecar  # noqa: E402

G, MU, FN, C = 82000.0, 0.3, 1.0e5, 6.0   # any values: the errors are in units of mu FN


def sample(spec, n: int, rng) -> dict:
    t = rng.uniform(math.log(spec.ratio_min), math.log(spec.ratio_max), n)
    nu = rng.uniform(spec.nu_min, spec.nu_max, n)
    # 0.2 % inside the rho edge: the table normalises with its own interpolated C11, C22 (Eq. T1)
    s = rng.uniform(0.0, 0.998 * spec.s_max, n)
    th = rng.uniform(0.0, 2 * math.pi, n)
    q = rng.uniform(-0.998 * spec.q_max, 0.998 * spec.q_max, n)
    rho = s / (1 - s)
    return {"ratio": np.exp(t), "nu": nu, "nx": rho * np.cos(th), "ny": rho * np.sin(th),
            "nphi": q / (1 - np.abs(q)), "rho": rho}


def summary(err: np.ndarray) -> dict:
    return {"max": float(err.max()), "mean": float(err.mean()), "p99": float(np.percentile(err, 99)),
            "p90": float(np.percentile(err, 90))}


def check(table, p: dict) -> dict:
    """Exact solves at the points ``p`` (:func:`sample`), the table and FASTSIM against them."""
    spec = table.spec
    n = p["ratio"].size
    t0 = time.perf_counter()
    ref = solve_points(p["ratio"], p["nu"], p["nx"], p["ny"], p["nphi"], grid_n=spec.grid_n, tol=spec.tol)
    t_exact = time.perf_counter() - t0
    a, b = C * np.sqrt(p["ratio"]), C / np.sqrt(p["ratio"])
    kx, ky, kp = saturation_scales(a, b, FN, MU, G, *coefficient_arrays(p["ratio"], p["nu"]))
    xi, eta, phi = p["nx"] / kx, p["ny"] / ky, p["nphi"] / kp
    evaluate(table, a[:1], b[:1], FN, MU, G, p["nu"][:1], xi[:1], eta[:1], phi[:1])   # evaluation grid
    with threadpool_limits(1):
        t0 = time.perf_counter()
        FX, FY, MZ = evaluate(table, a, b, FN, MU, G, p["nu"], xi, eta, phi)
        t_table = time.perf_counter() - t0
    muFN = MU * FN
    fs = fastsim_batch(a, b, FN, MU, xi, eta, phi, G=G, nu=p["nu"])
    return {"ref": ref, "a": a, "b": b, "FX": FX, "FY": FY, "fs": fs,
            "e_tab": np.hypot(FX / muFN - ref[:, 0], FY / muFN - ref[:, 1]),
            "e_tab_mz": np.abs(MZ / (muFN * np.sqrt(a * b)) - ref[:, 2]),
            "e_fs": np.hypot(fs.FX / muFN - ref[:, 0], fs.FY / muFN - ref[:, 1]),
            "e_fs_mz": np.abs(fs.MZ / (muFN * np.sqrt(a * b)) - ref[:, 2]),
            "t_exact": t_exact / n, "t_table": t_table / n}


def write_points(path: Path, p: dict, r: dict) -> None:
    cols = {"a_over_b": p["ratio"], "nu": p["nu"], "nx": p["nx"], "ny": p["ny"], "nphi": p["nphi"],
            "fx_exact": r["ref"][:, 0], "fy_exact": r["ref"][:, 1], "mz_exact": r["ref"][:, 2],
            "err_table": r["e_tab"], "err_table_mz": r["e_tab_mz"], "err_fastsim": r["e_fs"]}
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="",
               fmt="%.6g")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--table", default=None, help="table file (default: the shipped table)")
    ap.add_argument("--n", type=int, default=300, help="random points")
    ap.add_argument("--fine", type=int, default=20, help="points also solved on a finer grid")
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--holdout", type=int, default=4000, help="hold-out points (another seed)")
    ap.add_argument("--holdout-seed", type=int, default=18,
                    help="seeds 7, 8, 9 and 11-17 shaped the shipped table: not hold-out sets")
    ap.add_argument("--quick", action="store_true", help="20 points (a smoke run)")
    ap.add_argument("--out", default=str(ROOT / "studies" / "out" / "creep_table"))
    args = ap.parse_args(argv)
    if args.quick:
        args.n, args.fine, args.holdout = min(args.n, 20), min(args.fine, 2), min(args.holdout, 20)
    table = load_table(args.table)
    spec = table.spec
    p = sample(spec, args.n, np.random.default_rng(args.seed))
    r = check(table, p)
    ref, FX, FY, fs = r["ref"], r["FX"], r["FY"], r["fs"]
    e_tab, e_fs = r["e_tab"], r["e_fs"]
    muFN = MU * FN
    core = p["rho"] <= 1.5
    res = {
        "table": table.path, "content_hash": table.content_hash, "points": args.n, "seed": args.seed,
        "quick": args.quick, "ranges": table.ranges(), "grid_n": spec.grid_n, "tol": spec.tol,
        "evaluator": "Eq. T5 of conformal/tables/table.py: Akima along q, cubic Hermite along ln a/b, "
                     f"splines along s, theta sampled on a grid refine() = {list(refine(spec))} finer, linear in nu",
        "table_F": summary(e_tab), "table_MZ": summary(r["e_tab_mz"]),
        "table_F_rho_le_1.5": summary(e_tab[core]), "table_F_rho_gt_1.5": summary(e_tab[~core]),
        "fastsim_F": summary(e_fs), "fastsim_MZ": summary(r["e_fs_mz"]),
        "fastsim_F_rho_le_1.5": summary(e_fs[core]),
        "time_exact_s_per_point": r["t_exact"], "time_table_s_per_point": r["t_table"],
    }
    if args.fine > 0:
        k = np.arange(min(args.fine, args.n))
        fine_n = int(round(2.5 * spec.grid_n))
        ref_f = solve_points(p["ratio"][k], p["nu"][k], p["nx"][k], p["ny"][k], p["nphi"][k], grid_n=fine_n, tol=spec.tol)
        d = np.hypot(*(ref_f[:, :2] - ref[k, :2]).T)
        res["exact_grid_n_vs_fine"] = {"fine_grid_n": fine_n, "points": int(k.size), **summary(d)}
        res["table_vs_fine_F"] = summary(np.hypot(FX[k] / muFN - ref_f[:, 0], FY[k] / muFN - ref_f[:, 1]))
        res["fastsim_vs_fine_F"] = summary(np.hypot(fs.FX[k] / muFN - ref_f[:, 0], fs.FY[k] / muFN - ref_f[:, 1]))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    ph, rh = None, None
    if args.holdout > 0:
        ph = sample(spec, args.holdout, np.random.default_rng(args.holdout_seed))
        rh = check(table, ph)
        res["holdout"] = {"points": args.holdout, "seed": args.holdout_seed, "table_F": summary(rh["e_tab"]),
                          "table_F_above_0.01": int((rh["e_tab"] > 0.01).sum()),
                          "table_MZ": summary(rh["e_tab_mz"]), "fastsim_F": summary(rh["e_fs"])}
        write_points(out / "accuracy_holdout_points.csv", ph, rh)
    all_err = np.concatenate([e_tab] + ([rh["e_tab"]] if rh is not None else []))
    res["all_points_table_F"] = {"points": int(all_err.size), **summary(all_err),
                                 "above_0.01": int((all_err > 0.01).sum())}
    (out / "accuracy.json").write_text(json.dumps(res, indent=2) + "\n")
    write_points(out / "accuracy_points.csv", p, r)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(1, 2, figsize=(11, 4))
        ax[0].semilogy(p["rho"], np.maximum(e_fs, 1e-6), ".", color="tab:red", ms=4, label="FASTSIM")
        ax[0].semilogy(p["rho"], np.maximum(e_tab, 1e-6), ".", color="tab:blue", ms=4, label="table")
        if rh is not None:
            ax[0].semilogy(ph["rho"], np.maximum(rh["e_tab"], 1e-6), "x", color="tab:cyan", ms=3,
                           label=f"table, {args.holdout} hold-out points")
            ax[1].semilogy(np.abs(ph["nphi"]), np.maximum(rh["e_tab"], 1e-6), "x", color="tab:cyan", ms=3)
        ax[0].axhline(0.01, color="k", lw=0.8, ls="--")
        ax[0].set_xscale("symlog", linthresh=1.0)
        ax[0].set_xlabel("rho = hypot(nx, ny) (1 = saturation)")
        ax[0].set_ylabel("|F - F_exact| / (mu FN)")
        ax[0].legend()
        ax[1].semilogy(np.abs(p["nphi"]), np.maximum(e_fs, 1e-6), ".", color="tab:red", ms=4, label="FASTSIM")
        ax[1].semilogy(np.abs(p["nphi"]), np.maximum(e_tab, 1e-6), ".", color="tab:blue", ms=4, label="table")
        ax[1].axhline(0.01, color="k", lw=0.8, ls="--")
        ax[1].set_xlabel("|nphi| (normalised spin)")
        fig.suptitle(f"creep table vs exact solves at {args.n} random points (grid_n = {spec.grid_n})")
        fig.tight_layout()
        fig.savefig(out / "accuracy.png", dpi=110)
    except ImportError:
        pass
    write_sidecar(out, __file__, args, extra={"summary": {"table_F": res["table_F"], "fastsim_F": res["fastsim_F"],
                                                          "holdout": res.get("holdout"),
                                                          "all_points_table_F": res["all_points_table_F"]}})
    print(json.dumps({k: v for k, v in res.items() if k not in ("ranges",)}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
