"""Kalker's creep coefficients C11, C22, C23, C33 from the exact half-space solver at vanishing
creepage (full adhesion), on the (g, nu) nodes of Kalker's table; validation against the table and
the grid convergence.

Writes
  conformal/data/kalker_c33.csv                   branch,g,nu,C33 (read by the linear theory)
  conformal/data/kalker_coefficients_computed.csv branch,g,nu,C11,C22,C23,C33
  OUT/creep_coefficients.csv              per node: Kalker, every grid, extrapolated, error
  OUT/creep_coefficients_convergence.csv  convergence at three nodes on finer grids
  OUT/run.json                            sidecar: commit, arguments, package versions
with OUT = --out (default studies/out/creep_coefficients).

Method (conformal.theories.c33): Hertz contact with ab = 1, G = 1; exact normal problem; linear
full-stick steady rolling for xi, eta, phi; the coefficients from seed Eq. 13 with the discrete
contact area; the grids have n = 32, 48, 64, 96 elements across the short semi-axis box
(2.2 x the short semi-axis), and the value at n -> infinity is the least-squares fit
C(n) = C_inf + c / n over them (the discretisation error is first order in the element size; the
scatter of +-0.5 % from elements entering the contact set averages out in the fit).

Run:  python studies/creep_coefficients.py                    (about 3 min on 2 cores)
      python studies/creep_coefficients.py --quick --out DIR    (g = 0.5 and 1 only, n = 16, 24, 32;
                                                                 seconds; conformal/data untouched)
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # threaded BLAS is slower on a busy 2-core box

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from conformal.theories.c33 import (C33_FILE, FULL_FILE, ExactCoefficients, a_over_b,  # noqa: E402
                                    exact_coefficients, reference_nodes, write_tables)

NAMES = ("C11", "C22", "C23", "C33")


def fit_inf(ns, values) -> float:
    """C_inf of the least-squares line C = C_inf + c/n."""
    A = np.vstack([np.ones(len(ns)), 1.0 / np.asarray(ns, float)]).T
    return float(np.linalg.lstsq(A, np.asarray(values, float), rcond=None)[0][0])


def node(r: float, nu: float, ns) -> tuple[ExactCoefficients, list[ExactCoefficients]]:
    runs = [exact_coefficients(r, nu, n) for n in ns]
    vals = {k: fit_inf(ns, [getattr(c, k) for c in runs]) for k in NAMES + ("C23_phi",)}
    ext = ExactCoefficients(a_over_b=r, nu=nu, n_short=0, mx=runs[-1].mx, my=runs[-1].my,
                            n_contact=runs[-1].n_contact, iterations=sum(c.iterations for c in runs), **vals)
    return ext, runs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="nodes g = 0.5 and 1 only, grids n = 16, 24, 32 (not written to conformal/data)")
    ap.add_argument("--out", default=None,
                   help="output folder (default studies/out/creep_coefficients; with --quick a temporary folder)")
    args = ap.parse_args(argv)
    ns = (16, 24, 32) if args.quick else (32, 48, 64, 96)
    out = output_dir("creep_coefficients", args)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    done: dict[tuple[float, float], tuple[ExactCoefficients, list]] = {}
    rows, report = [], []
    print(f"grids: n = {ns} elements across the short axis (fit C_inf + c/n)")
    print(f"{'branch':6} {'g':>4} {'nu':>5} | " + " | ".join(f"{k}: Kalker  ours   err%" for k in ("C11", "C22", "C23"))
          + " | C33 ours")
    worst = {k: 0.0 for k in ("C11", "C22", "C23")}
    for branch, g, nu, ref in reference_nodes():
        if args.quick and g not in (0.5, 1.0):
            continue
        r = a_over_b(branch, g)
        key = (round(r, 12), nu)
        if key not in done:
            done[key] = node(r, nu, ns)
        ext, runs = done[key]
        rows.append((branch, g, nu, ext))
        errs = {k: 100.0 * (getattr(ext, k) / ref[k] - 1.0) for k in ("C11", "C22", "C23")}
        for k in worst:
            worst[k] = max(worst[k], abs(errs[k]))
        print(f"{branch:6} {g:4.1f} {nu:5.2f} | " + " | ".join(
            f"{ref[k]:7.3f} {getattr(ext, k):7.3f} {errs[k]:+5.2f}" for k in ("C11", "C22", "C23"))
            + f" | {ext.C33:7.4f}", flush=True)
        rec = {"branch": branch, "g": g, "nu": nu}
        for k in ("C11", "C22", "C23"):
            rec[f"{k}_kalker"] = ref[k]
        for c in runs:
            for k in NAMES + ("C23_phi",):
                rec[f"{k}_n{c.n_short}"] = getattr(c, k)
        for k in NAMES + ("C23_phi",):
            rec[f"{k}_inf"] = getattr(ext, k)
        for k in ("C11", "C22", "C23"):
            rec[f"{k}_err_pct"] = errs[k]
            rec[f"{k}_err_finest_pct"] = 100.0 * (getattr(runs[-1], k) / ref[k] - 1.0)
        report.append(rec)
    keys = list(report[0])
    with open(out / "creep_coefficients.csv", "w", encoding="utf-8") as f:
        f.write(",".join(keys) + "\n")
        for rec in report:
            f.write(",".join(str(rec[k]) if isinstance(rec[k], str) else f"{rec[k]:.6g}" for k in keys) + "\n")
    finest = {k: max(abs(rec[f"{k}_err_finest_pct"]) for rec in report) for k in ("C11", "C22", "C23")}
    print("largest deviation from Kalker's table, extrapolated: " + ", ".join(f"{k} {v:.2f} %" for k, v in worst.items()))
    print(f"largest deviation from Kalker's table, finest grid n = {ns[-1]}: "
          + ", ".join(f"{k} {v:.2f} %" for k, v in finest.items()))
    if not args.quick:
        header = [
            "Kalker's creep coefficients computed by conformal's exact half-space solver at vanishing creepage",
            "(full adhesion, steady rolling; studies/creep_coefficients.py, conformal/theories/c33.py).",
            f"Grids n = {ns} elements across the short axis of 1.1x the Hertz ellipse; value = fit C_inf + c/n.",
            "branch 'a<=b': g = a/b; 'a>b': g = b/a; a = semi-axis in the rolling direction x.",
            "Force law (seed Eq. 13): Fx = -G a b C11 xi; Fy = -G a b C22 eta - G (ab)^1.5 C23 phi; "
            "Mz = G (ab)^1.5 C23 eta - G (ab)^2 C33 phi",
            "C11, C22, C23: within " + ", ".join(f"{k} {v:.1f} %" for k, v in worst.items())
            + " of Kalker's table (Kalker 1990, Table E.3).",
        ]
        write_tables(rows, header)
        print(f"wrote {C33_FILE} and {FULL_FILE}")
    # convergence on finer grids at three nodes
    conv_ns = (16, 24, 32, 48, 64, 96, 128) if not args.quick else (16, 24, 32)
    with open(out / "creep_coefficients_convergence.csv", "w", encoding="utf-8") as f:
        f.write("a_over_b,nu,n,mx,my,n_contact,C11,C22,C23,C23_phi,C33,gmres_iterations\n")
        for r in (1.0, 0.1, 10.0):
            for n in conv_ns:
                c = exact_coefficients(r, 0.25, n)
                f.write(f"{r:g},0.25,{n},{c.mx},{c.my},{c.n_contact},{c.C11:.6g},{c.C22:.6g},{c.C23:.6g},"
                        f"{c.C23_phi:.6g},{c.C33:.6g},{c.iterations}\n")
    write_sidecar(out, __file__, args, extra={
        "grids": list(ns), "convergence_grids": list(conv_ns), "wall_s": time.perf_counter() - t0,
        "max_error_pct_extrapolated": worst, "max_error_pct_finest": finest})
    print(f"wrote {out / 'creep_coefficients.csv'}, {out / 'creep_coefficients_convergence.csv'} and run.json; "
          f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
