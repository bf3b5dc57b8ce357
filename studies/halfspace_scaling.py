"""Wall time and iterations of the exact (half-space) solver against the number of elements, on
CONTACT's performance case "circ" (reference/contact_performance.md), next to CONTACT's times.

Case: quasi-identical steel, G = 82 000 N/mm², nu = 0.28, A = B = 0.001 1/mm, FN = 100 kN
prescribed, potential area 1.1 x the Hertz circle in n x n elements; mu = 0.3, xi = 0.001 (steady
rolling, +x), tol 1e-6.

Measured per n: the normal problem (kernel set-up included: HalfSpaceInfluence.for_grid and the
A_zz transform count), with and without the FFT preconditioner; and, when the tangential solver
(conformal.solvers.tangential) is present, steady rolling (its own time, after the normal
problem, plus the tangential kernel set-up).  Times are the minimum over several repeats of
time.perf_counter() around the calls (imports excluded).  Errors are relative to the finest grid
(pmax, approach, FX) and to Hertz (pmax, approach).

Writes halfspace_scaling.csv, halfspace_scaling.png and the sidecar run.json (commit, arguments,
package versions) to --out (default studies/out/halfspace_scaling).

    python studies/halfspace_scaling.py [--max-n 316] [--repeats 5]
    python studies/halfspace_scaling.py --quick --out /tmp/hs   # n = 25, 32, 50, one repeat (seconds)
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from conformal.grid import PlanarGrid  # noqa: E402
from conformal.influence.halfspace import HalfSpaceInfluence  # noqa: E402
from conformal.materials import Material  # noqa: E402
from conformal.solvers.normal import solve_normal  # noqa: E402
from conformal.theories.hertz import hertz_from_curvatures  # noqa: E402

# CONTACT (revision 2707, 1 thread, same kind of machine): n -> (normal, SteadyGS, GDsteady, FX)
CONTACT = {25: (0.007, 0.025, None, -14330.0), 50: (0.012, 0.40, 0.29, -14110.0),
           100: (0.046, 6.8, 1.17, -13990.0), 150: (0.071, 44.0, 2.87, -13950.0),
           200: (0.14, 211.0, 6.80, -13940.0)}
MAT = Material.steel()
FN, A, MU, XI, TOL = 1.0e5, 0.001, 0.3, 0.001, 1e-6


def circ(n: int):
    hz = hertz_from_curvatures(A, A, MAT, normal_force=FN)
    grid = PlanarGrid.around_ellipse(hz.a, hz.b, n=n, scale=1.1)
    X, Y = grid.mesh()
    return hz, grid, A * X**2 + A * Y**2


def time_normal(n: int, precondition: bool, repeats: int, uniform_start: bool = False):
    """uniform_start: start from a uniform pressure instead of the Hertz-like guess of
    conformal.solvers.normal.initial_pressure (which is nearly exact for this Hertzian case)."""
    hz, grid, h = circ(n)
    best, sol = np.inf, None
    p0 = np.full(grid.shape, FN / (grid.area * grid.size)) if uniform_start else None
    for _ in range(repeats):
        t0 = time.perf_counter()
        op = HalfSpaceInfluence.for_grid(grid.mx, grid.my, grid.dx, grid.dy, MAT, shared=False)
        sol = solve_normal(op, grid, h, normal_force=FN, tol=TOL, precondition=precondition, p_start=p0)
        best = min(best, time.perf_counter() - t0)
    return best, sol


def time_rolling(n: int, normal, repeats: int):
    try:
        from conformal.solvers.tangential import solve_tangential
    except ImportError:
        return None
    hz, grid, h = circ(n)
    best, tang = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        op = HalfSpaceInfluence.for_grid(grid.mx, grid.my, grid.dx, grid.dy, MAT, shared=False)
        tang = solve_tangential(op, grid, normal.pn, xi=XI, eta=0.0, phi=0.0, mu_static=MU, mu_kinetic=MU,
                                rolling="steady", tol=TOL)
        best = min(best, time.perf_counter() - t0)
    return best, tang


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-n", type=int, default=316, help="largest n (n x n elements), default 316 (1e5)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-rolling", action="store_true", help="skip steady rolling")
    ap.add_argument("--quick", action="store_true", help="n = 25, 32, 50 with one repeat (seconds; a test runs it)")
    ap.add_argument("--out", default=None,
                   help="output folder (default studies/out/halfspace_scaling; with --quick a temporary folder)")
    args = ap.parse_args(argv)
    if args.quick:
        args.max_n, args.repeats = min(args.max_n, 50), 1
    ns = [n for n in (25, 32, 50, 71, 100, 141, 150, 200, 250, 316) if n <= args.max_n]
    rows = []
    print(f"{'n':>4} {'N':>7} {'ncon':>6} | {'normal pc [s]':>13} {'it':>3} | {'plain [s]':>9} {'it':>3} | "
          f"{'unif. start':>11} {'it':>3} | "
          f"{'CONTACT':>7} | {'pmax':>8} {'approach':>9} | {'rolling [s]':>11} {'it':>5} {'FX':>9} | "
          f"{'GDsteady':>8} {'CONTACT FX':>10}")
    for n in ns:
        reps = args.repeats if n <= 200 else max(2, args.repeats // 2)
        t_pc, s_pc = time_normal(n, True, reps)
        t_pl, s_pl = time_normal(n, False, reps)
        t_un, s_un = time_normal(n, True, reps, uniform_start=True)
        roll = None if args.no_rolling else time_rolling(n, s_pc, 1 if n > 150 else 2)
        c = CONTACT.get(n)
        row = dict(n=n, N=n * n, n_contact=s_pc.n_contact, t_normal_pc=t_pc, it_normal_pc=s_pc.iterations,
                   t_normal_plain=t_pl, it_normal_plain=s_pl.iterations,
                   t_normal_pc_uniform_start=t_un, it_normal_pc_uniform_start=s_un.iterations, pmax=s_pc.pmax, approach=s_pc.approach,
                   t_contact_normal=c[0] if c else np.nan,
                   t_rolling=roll[0] if roll else np.nan, it_rolling=roll[1].iterations if roll else -1,
                   FX=float(roll[1].px.sum() * circ(n)[1].area) if roll else np.nan,
                   n_slip=int((roll[1].status == 2).sum()) if roll else -1,
                   t_contact_gdsteady=c[2] if c and c[2] else np.nan, FX_contact=c[3] if c else np.nan)
        rows.append(row)
        print(f"{n:4d} {n*n:7d} {s_pc.n_contact:6d} | {t_pc:13.4f} {s_pc.iterations:3d} | {t_pl:9.4f} "
              f"{s_pl.iterations:3d} | {t_un:11.4f} {s_un.iterations:3d} | {row['t_contact_normal']:7.3f} | {s_pc.pmax:8.2f} {s_pc.approach:9.6f} | "
              f"{row['t_rolling']:11.3f} {row['it_rolling']:5d} {row['FX']:9.1f} | "
              f"{row['t_contact_gdsteady']:8.2f} {row['FX_contact']:10.0f}", flush=True)
    hz = circ(ns[0])[0]
    fin = rows[-1]
    for r in rows:
        r["pmax_err_finest"] = r["pmax"] / fin["pmax"] - 1
        r["approach_err_finest"] = r["approach"] / fin["approach"] - 1
        r["pmax_err_hertz"] = r["pmax"] / hz.pmax - 1
        r["approach_err_hertz"] = r["approach"] / hz.approach - 1
        r["FX_err_finest"] = r["FX"] / fin["FX"] - 1 if np.isfinite(fin["FX"]) else np.nan
    out = output_dir("halfspace_scaling", args)
    out.mkdir(parents=True, exist_ok=True)
    keys = list(rows[0])
    with open(out / "halfspace_scaling.csv", "w", encoding="utf-8") as f:
        f.write(",".join(keys) + "\n")
        for r in rows:
            f.write(",".join(f"{r[k]:.6g}" for k in keys) + "\n")
    print("\nerror against the finest grid (n = %d) and against Hertz (pmax %.2f, approach %.6f):" %
          (fin["n"], hz.pmax, hz.approach))
    for r in rows:
        print(f"  n = {r['n']:3d}: pmax {100*r['pmax_err_finest']:+.3f} % (Hertz {100*r['pmax_err_hertz']:+.3f} %), "
              f"approach {100*r['approach_err_finest']:+.4f} % (Hertz {100*r['approach_err_hertz']:+.4f} %), "
              f"FX {100*r['FX_err_finest']:+.3f} %")
    _plot(rows, out / "halfspace_scaling.png")
    write_sidecar(out, __file__, args, extra={"hertz": {"pmax": hz.pmax, "approach": hz.approach}})
    print(f"wrote {out / 'halfspace_scaling.csv'}, {out / 'halfspace_scaling.png'} and run.json")
    return 0


def _plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    N = np.array([r["N"] for r in rows], float)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax.loglog(N, [r["t_normal_pc"] for r in rows], "o-", label="normal, preconditioned PCG (ours)")
    ax.loglog(N, [r["t_normal_plain"] for r in rows], "s--", label="normal, plain Polonsky-Keer (ours)")
    ax.loglog(N, [r["t_normal_pc_uniform_start"] for r in rows], "d:", label="normal, PCG from uniform start (ours)")
    cN = np.array([n * n for n in CONTACT], float)
    ax.loglog(cN, [v[0] for v in CONTACT.values()], "k^", label="normal, CONTACT")
    if np.isfinite([r["t_rolling"] for r in rows]).any():
        ax.loglog(N, [r["t_rolling"] for r in rows], "o-", label="steady rolling (ours)")
    gd = [(n * n, v[2]) for n, v in CONTACT.items() if v[2]]
    ax.loglog([g[0] for g in gd], [g[1] for g in gd], "kv", label="steady rolling, CONTACT GDsteady")
    ax.set_xlabel("number of elements N")
    ax.set_ylabel("wall time [s]")
    ax.set_title("case circ: time against grid size")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    err = [(r["N"], abs(r["pmax_err_finest"]), abs(r["approach_err_finest"]), abs(r["FX_err_finest"]))
           for r in rows[:-1]]
    ax2.loglog([e[0] for e in err], [e[1] for e in err], "o-", label="|pmax - finest| / finest")
    ax2.loglog([e[0] for e in err], [e[2] for e in err], "s-", label="|approach - finest| / finest")
    if np.isfinite([e[3] for e in err]).any():
        ax2.loglog([e[0] for e in err], [e[3] for e in err], "^-", label="|FX - finest| / finest")
    ax2.set_xlabel("number of elements N")
    ax2.set_ylabel("relative difference")
    ax2.set_title(f"error against the finest grid (N = {rows[-1]['N']})")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
