"""Grid convergence of Kalker's spin coefficient C33 (and C11, C22, C23) from the exact half-space
solver, extrapolated to zero element size with a fitted rate (issue 11, item 6: C33 for long
contacts a > b).

Why: CONTACT's C33 at a/b = 5 moves by 19 % between 40 x 40 and 80 x 80 elements, and our table
value (conformal/data/kalker_c33.csv, fit C_inf + c/n over n = 32 ... 96) was 19 % below CONTACT's
80 x 80 value.  A single grid settles nothing; this study measures the convergence.

Method (conformal.theories.c33): Hertz contact with ab = 1, G = 1, full-adhesion steady rolling
(vanishing creepage).  Grids of n elements across the short axis of the box 1.1 x the Hertz
ellipse (elements elongated at most sqrt(a/b) along the long axis), n a geometric sequence with
ratio about sqrt(2).  On each n the coefficients are averaged over grid offsets (fractions of an
element; c33.OFFSETS), which removes the scatter of elements entering the contact set.  The
sequence is extrapolated by Richardson with a fitted rate: p from np.polyfit of
log|C(n_k+1) - C(n_k)| against log n, then C(n) = C_inf + c n^-p by least squares; the
uncertainty combines the change under p +- its standard error, the change when the coarsest grid is
dropped and the offset noise of the finest grid (c33.richardson).

Writes studies/out/c33_convergence/ (or --out; --quick: a temporary folder): grids.csv (every n,
mean and offset std of each coefficient),
summary.csv and summary.md (per a/b and nu: extrapolated value, rate, uncertainty, Kalker's table,
the current C33 table), run.json.  A full run into studies/out/c33_convergence also puts the result
into the header of conformal/data/kalker_c33.csv and kalker_coefficients_computed.csv (comment
lines "# C33 convergence ..."; the values are unchanged).

Run:  nice -n 5 python studies/c33_convergence.py [--quick]
      (full: a/b = 1, 2, 5, 10, 0.2, 0.1; nu = 0.25, 0.3; n = 16 ... 128; 8 offsets; minutes)
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import math
import sys
import time
from pathlib import Path


ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from conformal.theories import coefficients as coef  # noqa: E402
from conformal.theories.c33 import (C33_FILE, FULL_FILE, NAMES, averaged_coefficients,  # noqa: E402
                                    reference_nodes, richardson, set_convergence_header)

FULL = dict(ratios=(1.0, 2.0, 5.0, 10.0, 0.2, 0.1), nus=(0.25, 0.3), ns=(16, 23, 32, 45, 64, 90, 128), offsets=8,
            contact_ratios=(2.0, 5.0, 10.0), contact_ns=(20, 40, 80, 160, 320))
QUICK = dict(ratios=(1.0, 5.0), nus=(0.25,), ns=(16, 23, 32, 45), offsets=4,
             contact_ratios=(5.0,), contact_ns=(20, 40, 80))
#: CONTACT's discretisation of the spin's lateral creepage: eta + phi (x + dx/6) (CONTACT's W/dq with
#: chi = 0, as conformal.solvers.tangential), on n x n grids over the box (elements a/b longer in x)
CONTACT_SPIN_SHIFT = 1.0 / 6.0


def contact_like(cfg) -> list[dict]:
    """C33 on CONTACT-like n x n grids with the dx/6 spin shift: how it converges, and where to."""
    rows = []
    for r in cfg["contact_ratios"]:
        vals = []
        for n in cfg["contact_ns"]:
            c = averaged_coefficients(r, 0.25, n, 1, spin_shift=CONTACT_SPIN_SHIFT, elements=(n, n))[0]
            vals.append(c.C33)
            print(f"CONTACT-like a/b {r:g} nu 0.25 {n} x {n}: C33 {c.C33:.4f}", flush=True)
        e = richardson(cfg["contact_ns"], vals)
        rows.append(dict(a_over_b=r, nu=0.25, ns=list(cfg["contact_ns"]), C33=vals,
                         change_40_80_pct=(100.0 * (vals[1] / vals[2] - 1.0) if len(vals) > 2 else None),
                         C33_inf=e.value, C33_err=e.error, rate=e.rate))
        print(f"  -> extrapolated {e.value:.4f} +- {e.error:.4f} (rate {e.rate:.2f})", flush=True)
    return rows


def kalker_table(r: float, nu: float) -> dict | None:
    """Kalker's C11, C22, C23 at a table node (a/b = r, nu), or None."""
    for branch, g, n, ref in reference_nodes():
        rr = g if branch == "a<=b" else 1.0 / g
        if abs(rr - r) < 1e-9 and abs(n - nu) < 1e-12:
            return ref
    return None


def read_grids(path: Path) -> list[dict]:
    """The rows of a previous run's grids.csv (for --refit)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    keys = lines[0].split(",")
    return [dict(zip(keys, (float(v) for v in ln.split(",")))) for ln in lines[1:] if ln.strip()]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a/b = 1, 5; nu = 0.25; n <= 45; 4 offsets; "
                    "does not touch conformal/data")
    ap.add_argument("--refit", action="store_true", help="redo the extrapolation from the grids.csv of a "
                    "previous run (same mode) instead of solving again")
    ap.add_argument("--out", default=None, help="output folder (default studies/out/c33_convergence; with "
                    "--quick a temporary folder)")
    args = ap.parse_args(argv)
    cfg = QUICK if args.quick else FULL
    from _provenance import output_dir

    out = output_dir("c33_convergence", args)   # a quick run never overwrites the full outputs
    t0 = time.perf_counter()
    if args.refit:
        grid_rows = read_grids(out / "grids.csv")
    else:
        grid_rows = []
        for r in cfg["ratios"]:
            for nu in cfg["nus"]:
                for n in cfg["ns"]:
                    t1 = time.perf_counter()
                    mean, std = averaged_coefficients(r, nu, n, cfg["offsets"])
                    grid_rows.append(dict(a_over_b=r, nu=nu, n=n, mx=mean.mx, my=mean.my, n_contact=mean.n_contact,
                                          **{k: getattr(mean, k) for k in NAMES},
                                          **{f"{k}_std": std[k] for k in NAMES}, wall_s=time.perf_counter() - t1))
                    print(f"a/b {r:5g} nu {nu:4g} n {n:4d} ({mean.mx} x {mean.my}): C33 {mean.C33:.5f} "
                          f"+- {std['C33']:.5f}  C11 {mean.C11:.4f}  ({time.perf_counter() - t1:.1f} s)", flush=True)
    summary = []
    for r in cfg["ratios"]:
        for nu in cfg["nus"]:
            rows = [g for g in grid_rows if g["a_over_b"] == r and g["nu"] == nu]
            ns = [int(g["n"]) for g in rows]
            ref = kalker_table(r, nu)
            rec = dict(a_over_b=r, nu=nu, n_min=ns[0], n_max=ns[-1], offsets=cfg["offsets"])
            for k in NAMES:
                noise = [g[f"{k}_std"] / math.sqrt(cfg["offsets"]) for g in rows]
                e = richardson(ns, [g[k] for g in rows], noise=noise)
                rec[f"{k}_inf"], rec[f"{k}_err"], rec[f"{k}_rate"], rec[f"{k}_rate_std"] = (
                    e.value, e.error, e.rate, e.rate_std)
                rec[f"{k}_finest"] = e.values[-1]
                if ref is not None and k in ref:
                    rec[f"{k}_kalker"] = ref[k]
            try:
                rec["C33_table"] = float(coef.c33(r, nu))
            except Exception:  # noqa: BLE001 - outside the computed table: reported as missing
                rec["C33_table"] = float("nan")
            summary.append(rec)
            print(f"a/b {r:g} nu {nu:g} -> C33 = {rec['C33_inf']:.4f} +- {rec['C33_err']:.4f} (rate {rec['C33_rate']:.2f}), "
                  f"table {rec['C33_table']:.4f}; C11 = {rec['C11_inf']:.4f} +- {rec['C11_err']:.4f}", flush=True)
    keys = list(grid_rows[0])
    with open(out / "grids.csv", "w", encoding="utf-8") as f:
        f.write(",".join(keys) + "\n")
        for row in grid_rows:
            f.write(",".join(f"{row[k]:.7g}" for k in keys) + "\n")
    skeys = sorted({k for rec in summary for k in rec}, key=lambda k: (k not in ("a_over_b", "nu"), k))
    with open(out / "summary.csv", "w", encoding="utf-8") as f:
        f.write(",".join(skeys) + "\n")
        for rec in summary:
            f.write(",".join(f"{rec.get(k, float('nan')):.7g}" for k in skeys) + "\n")
    md = ["| a/b | nu | C33 extrapolated | rate | finest grid (n) | C33 table (before) | C11 extrap. / Kalker | "
          "C22 extrap. / Kalker | C23 extrap. / Kalker |", "|---|---|---|---|---|---|---|---|---|"]
    for rec in summary:
        def kal(k):
            v = rec.get(f"{k}_kalker")
            return f"{rec[f'{k}_inf']:.3f} +- {rec[f'{k}_err']:.3f} / " + (f"{v:g}" if v is not None else "-")
        md.append(f"| {rec['a_over_b']:g} | {rec['nu']:g} | **{rec['C33_inf']:.4f} +- {rec['C33_err']:.4f}** | "
                  f"{rec['C33_rate']:.2f} | {rec['C33_finest']:.4f} ({rec['n_max']}) | {rec['C33_table']:.4f} | "
                  f"{kal('C11')} | {kal('C22')} | {kal('C23')} |")
    (out / "summary.md").write_text("\n".join(md) + "\n", encoding="utf-8")
    clike = contact_like(cfg)
    md += ["", "CONTACT-like grids (n x n over the box, spin creepage at x + dx/6), nu = 0.25:", "",
           "| a/b | C33 on " + " / ".join(f"{n}x{n}" for n in cfg["contact_ns"]) + " | change 40 -> 80 | extrapolated |",
           "|---|---|---|---|"]
    for row in clike:
        ch = row["change_40_80_pct"]
        md.append(f"| {row['a_over_b']:g} | " + " / ".join(f"{v:.4f}" for v in row["C33"])
                  + f" | {'' if ch is None else f'{ch:+.1f} %'} | {row['C33_inf']:.4f} +- {row['C33_err']:.4f} "
                  f"(rate {row['rate']:.2f}) |")
    (out / "summary.md").write_text("\n".join(md) + "\n", encoding="utf-8")
    print("\n".join(md))
    wall = time.perf_counter() - t0
    if not args.quick and Path(args.out).resolve() == (ROOT / "studies" / "out" / "c33_convergence").resolve():
        lines = [f"C33 convergence (studies/c33_convergence.py; n = {cfg['ns'][0]}...{cfg['ns'][-1]} across the short "
                 f"axis, {cfg['offsets']} grid offsets, Richardson with fitted rate):"]
        lines.append("C33 convergence: CONTACT's n x n grids with the spin creepage at x + dx/6 converge to the same "
                     "values at first order (a/b = 5: " + ", ".join(f"{v:.3f}" for v in clike[1]["C33"][:3])
                     + f" on 20/40/80; extrapolated {clike[1]['C33_inf']:.3f}):")
        def worst(recs):
            dev = [(abs(rec["C33_table"] / rec["C33_inf"] - 1.0), rec) for rec in recs if math.isfinite(rec["C33_table"])]
            return max(dev, key=lambda t: t[0]) if dev else (float("nan"), None)

        w_node, r_node = worst([rec for rec in summary if rec["nu"] in (0.0, 0.25, 0.5)])
        w_int, r_int = worst([rec for rec in summary if rec["nu"] not in (0.0, 0.25, 0.5)])
        if r_node is not None:
            lines.append(f"C33 convergence: the values below in this file (fit C_inf + c/n) differ from these extrapolations by "
                         f"at most {100 * w_node:.1f} % at the nodes (a/b = {r_node['a_over_b']:g}, nu = {r_node['nu']:g})"
                         + (f", {100 * w_int:.1f} % interpolated to nu = {r_int['nu']:g} (a/b = {r_int['a_over_b']:g})"
                            if r_int is not None else "") + "; they stay the interpolation nodes")
        for rec in summary:
            lines.append(f"C33 convergence  a/b = {rec['a_over_b']:g}, nu = {rec['nu']:g}: C33 = {rec['C33_inf']:.4f} "
                         f"+- {rec['C33_err']:.4f} (rate {rec['C33_rate']:.2f}; table value {rec['C33_table']:.4f})")
        set_convergence_header(lines)
        if FULL_FILE.is_file():   # the full computed table carries the same lines (write_tables keeps them)
            set_convergence_header(lines, FULL_FILE)
        print(f"wrote the header of {C33_FILE} and {FULL_FILE}")
    from _provenance import write_sidecar
    write_sidecar(out, __file__, args, extra={"wall_s": round(wall, 1), "config": {k: list(v) if isinstance(v, tuple)
                                                                                  else v for k, v in cfg.items()},
                                               "summary": summary, "contact_like": clike,
                                               "grids": (f"read from grids.csv of an earlier run (--refit); its grid "
                                                         f"solves took {sum(g['wall_s'] for g in grid_rows):.0f} s "
                                                         "wall") if args.refit else "solved in this run"})
    print(f"wrote {out}; {wall:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
