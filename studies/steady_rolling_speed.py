"""Time and accuracy of the steady-rolling solver (conformal.solvers.tangential) against the grid,
next to CONTACT's GDsteady on the same case (reference/contact_performance.md, case "circ").

Case: quasi-identical steel, G = 82 000 N/mm², nu = 0.28, A = B = 0.001 1/mm, FN = 100 kN, potential
area 1.1 x the Hertz circle in n x n square elements, mu = 0.3, xi = 0.001 (steady rolling in +x),
tol 1e-6.  The normal problem is solved first (conformal.solvers.normal, as CONTACT does), and its
time is not counted: the tangential time is the one compared with CONTACT's "steady rolling" column
minus its "normal only" column.  (CONTACT's times are whole-program wall times; its normal part is
0.05 s at 100 x 100 and 0.14 s at 200 x 200.)

Per n: the tangential solve, timed as the minimum over ``--repeats`` runs of perf_counter (and of
process_time: this 2-core machine is shared, wall times vary by up to 2x), Newton iterations,
FFT products, FX, the adhesion/slip counts and the error of FX and of the traction field against
the finest grid.  At two sizes also the variants that led to the final method:

* ``plain``: semismooth Newton + GMRES with the cumsum/circulant preconditioner, double precision,
  started from zero;
* ``+coarse``: started from the solution on a 2x coarser grid (nested iteration, recursively);
* ``final``: + single-precision FFT products inside GMRES.

Writes studies/out/steady_rolling_speed.csv.  Run: python studies/steady_rolling_speed.py
[--sizes 25 50 100 150 200 300] [--repeats 3]
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from conformal.grid import PlanarGrid  # noqa: E402
from conformal.influence.halfspace import HalfSpaceInfluence  # noqa: E402
from conformal.materials import Material  # noqa: E402
from conformal.result import ADHESION, SLIP  # noqa: E402
from conformal.solvers import tangential as tang  # noqa: E402
from conformal.solvers.normal import solve_normal  # noqa: E402
from conformal.theories.hertz import hertz_from_curvatures  # noqa: E402

# CONTACT (revision 2707, 1 thread, this kind of machine): n -> (normal only, GDsteady, FX)
CONTACT = {25: (0.007, None, -14330.0), 50: (0.012, 0.29, -14110.0), 100: (0.046, 1.17, -13990.0),
           150: (0.071, 2.87, -13950.0), 200: (0.14, 6.80, -13940.0)}
MAT = Material.steel()
FN, CURV, MU, XI, TOL = 1.0e5, 0.001, 0.3, 0.001, 1e-6
VARIANTS = {"plain": dict(NESTED_FROM=10**12, SINGLE_PRECISION=False),
            "+coarse": dict(NESTED_FROM=1500, SINGLE_PRECISION=False),
            "final": dict(NESTED_FROM=1500, SINGLE_PRECISION=True)}


def problem(n: int):
    hz = hertz_from_curvatures(CURV, CURV, MAT, normal_force=FN)
    grid = PlanarGrid.around_ellipse(hz.a, hz.b, n=n, scale=1.1)
    X, Y = grid.mesh()
    op = HalfSpaceInfluence.for_grid(n, n, grid.dx, grid.dy, MAT)
    pn = solve_normal(op, grid, CURV * (X**2 + Y**2), normal_force=FN, tol=TOL).pn
    return grid, op, pn


def run(n: int, repeats: int, variant: str = "final"):
    grid, op, pn = problem(n)
    saved = {k: getattr(tang, k) for k in VARIANTS[variant]}
    for k, v in VARIANTS[variant].items():
        setattr(tang, k, v)
    try:
        wall, cpu, sol = np.inf, np.inf, None
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            sol = tang.solve_tangential(op, grid, pn, xi=XI, eta=0.0, phi=0.0, mu_static=MU, mu_kinetic=MU,
                                        tol=TOL)
            wall, cpu = min(wall, time.perf_counter() - t0), min(cpu, time.process_time() - c0)
    finally:
        for k, v in saved.items():
            setattr(tang, k, v)
    return grid, pn, sol, wall, cpu


def field_error(grid, sol, fine_grid, fine_sol) -> float:
    """max |px - px_fine| / max |px_fine|, the fine traction sampled at the coarse element centres."""
    fx = (grid.x - fine_grid.xl) / fine_grid.dx - 0.5
    fy = (grid.y - fine_grid.yl) / fine_grid.dy - 0.5
    from scipy.ndimage import map_coordinates
    FX, FY = np.meshgrid(fx, fy, indexing="ij")
    ref = map_coordinates(fine_sol.px, [FX, FY], order=1, mode="nearest")
    return float(np.abs(sol.px - ref).max() / np.abs(fine_sol.px).max())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[25, 50, 100, 150, 200, 300])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--variant-sizes", type=int, nargs="*", default=[100, 200])
    args = ap.parse_args(argv)
    sizes = sorted(args.sizes)
    results = {n: run(n, args.repeats) for n in sizes}
    fine_grid, fine_pn, fine, *_ = results[sizes[-1]]
    FX_fine = float(fine.px.sum() * fine_grid.area)
    rows = []
    print(f"steady rolling, case circ (mu {MU}, xi {XI}, tol {TOL:g}); finest grid {sizes[-1]}^2: FX = {FX_fine:.1f} N")
    print(f"{'n':>4} {'contact':>7} {'slip%':>6} {'its':>4} {'prods':>5} {'wall s':>7} {'cpu s':>7} "
          f"{'CONTACT s':>9} {'ratio':>6} {'FX':>9} {'FX CONTACT':>10} {'dFX/FX':>8} {'dpx/max':>8}")
    for n in sizes:
        grid, pn, sol, wall, cpu = results[n]
        FX = float(sol.px.sum() * grid.area)
        nc = int(np.count_nonzero(sol.status))
        nslip = int(np.count_nonzero(sol.status == SLIP))
        c_norm, c_steady, c_fx = CONTACT.get(n, (None, None, None))
        c_tang = c_steady - c_norm if c_steady is not None else None
        ratio = wall / c_steady if c_steady else None
        err_fx = abs(FX - FX_fine) / abs(FX_fine)
        err_p = field_error(grid, sol, fine_grid, fine) if n != sizes[-1] else 0.0
        row = dict(n=n, variant="final", n_contact=nc, n_slip=nslip, n_adhesion=int(np.count_nonzero(sol.status == ADHESION)),
                   newton_iterations=sol.iterations, products=sol.products, residual=sol.residual,
                   converged=sol.converged, wall_s=wall, cpu_s=cpu, contact_gdsteady_s=c_steady,
                   contact_tangential_s=c_tang, ratio_to_contact=ratio, FX=FX, FX_contact=c_fx,
                   FX_error_vs_finest=err_fx, px_error_vs_finest=err_p)
        rows.append(row)
        print(f"{n:>4} {nc:>7} {100 * nslip / nc:>6.1f} {sol.iterations:>4} {sol.products:>5} {wall:>7.3f} {cpu:>7.3f} "
              f"{(f'{c_steady:.2f}' if c_steady else '-'):>9} {(f'{ratio:.2f}' if ratio else '-'):>6} {FX:>9.1f} "
              f"{(f'{c_fx:.0f}' if c_fx else '-'):>10} {err_fx:>8.2e} {err_p:>8.2e}")
    if args.variant_sizes:
        print("\nvariants (what was tried), same case:")
        print(f"{'n':>4} {'variant':>8} {'its':>4} {'prods':>5} {'wall s':>7} {'cpu s':>7} {'FX':>9}")
        for n in args.variant_sizes:
            for v in VARIANTS:
                grid, pn, sol, wall, cpu = run(n, args.repeats, v)
                FX = float(sol.px.sum() * grid.area)
                rows.append(dict(n=n, variant=v, newton_iterations=sol.iterations, products=sol.products,
                                 residual=sol.residual, converged=sol.converged, wall_s=wall, cpu_s=cpu, FX=FX,
                                 contact_gdsteady_s=CONTACT.get(n, (None, None))[1]))
                print(f"{n:>4} {v:>8} {sol.iterations:>4} {sol.products:>5} {wall:>7.3f} {cpu:>7.3f} {FX:>9.1f}")
    out = ROOT / "studies" / "out"
    out.mkdir(parents=True, exist_ok=True)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(out / "steady_rolling_speed.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    print(f"\nwrote {out / 'steady_rolling_speed.csv'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
