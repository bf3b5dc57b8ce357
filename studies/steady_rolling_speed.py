"""Time and accuracy of the steady-rolling and shift solvers (conformal.solvers.tangential)
against the grid, next to CONTACT's GDsteady on the same case (reference/contact_performance.md,
case "circ").

Case: quasi-identical steel, G = 82 000 N/mm², nu = 0.28, A = B = 0.001 1/mm, FN = 100 kN, potential
area 1.1 x the Hertz circle in n x n square elements, mu = 0.3, xi = 0.001 (steady rolling in +x),
tol 1e-6.  The normal problem is solved first (conformal.solvers.normal, as CONTACT does), and its
time is not counted: the tangential time is the one compared with CONTACT's "steady rolling" column
minus its "normal only" column.  The shift case (CONTACT's T = 1) shifts the same contact by
0.008 mm (about half the shift of full sliding) from zero tractions.

The cost is given in three ways, because wall times on a shared 2-core machine vary by up to 2x:

* ``wall_s``: the minimum over ``--repeats`` runs of perf_counter;
* ``fft_pairs``: the wall time in units of one FFT pair of the padded grid (rfft2 + irfft2 of the
  2-component field on the 2n x 2n grid, double precision, one thread), timed in the same process
  right before: the cost of one plain influence product, the unit of the issue's target (<= 150
  at n = 200);
* ``products``: the influence products actually spent on the n x n grid, and
  ``coarse_products`` those of the nested start on coarser grids, weighted by the element count.

Also per n: Newton iterations, FX, the adhesion/slip counts and the error of FX and of the
traction field against the finest grid, and the growth exponent of the time with the number of
elements N = n^2 (np.polyfit of log wall against log N over the sizes run).

Writes studies/out/steady_rolling_speed/{steady_rolling_speed.csv, steady_rolling_speed.md,
run.json}.  Run: python studies/steady_rolling_speed.py [--sizes 50 100 150 200 300 400]
[--repeats 3] [--quick] [--out DIR]
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

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _provenance import write_sidecar  # noqa: E402

# CONTACT (revision 2707, 1 thread, this kind of machine): n -> (normal only, GDsteady, FX)
CONTACT = {25: (0.007, None, -14330.0), 50: (0.012, 0.29, -14110.0), 100: (0.046, 1.17, -13990.0),
           150: (0.071, 2.87, -13950.0), 200: (0.14, 6.80, -13940.0)}
MAT = Material.steel()
FN, CURV, MU, XI, TOL = 1.0e5, 0.001, 0.3, 0.001, 1e-6
VARIANTS = {"plain": dict(NESTED_FROM=10**12, SINGLE_PRECISION=False),
            "+coarse": dict(NESTED_FROM=1500, SINGLE_PRECISION=False),
            "one-level": dict(COARSE_FROM=0),
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
        walls, cpus, sol = [], [], None
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            sol = tang.solve_tangential(op, grid, pn, xi=XI, eta=0.0, phi=0.0, mu_static=MU, mu_kinetic=MU,
                                        tol=TOL)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
    finally:
        for k, v in saved.items():
            setattr(tang, k, v)
    MEDIANS[n, variant] = float(np.median(walls))
    CPU_MEDIANS[n, variant] = float(np.median(cpus))
    return grid, pn, sol, min(walls), min(cpus)


def field_error(grid, sol, fine_grid, fine_sol) -> float:
    """max |px - px_fine| / max |px_fine|, the fine traction sampled at the coarse element centres."""
    fx = (grid.x - fine_grid.xl) / fine_grid.dx - 0.5
    fy = (grid.y - fine_grid.yl) / fine_grid.dy - 0.5
    from scipy.ndimage import map_coordinates
    FX, FY = np.meshgrid(fx, fy, indexing="ij")
    ref = map_coordinates(fine_sol.px, [FX, FY], order=1, mode="nearest")
    return float(np.abs(sol.px - ref).max() / np.abs(fine_sol.px).max())


#: median wall times (s) of the repeats, by (n, variant): the machine is shared, so the growth of
#: the median is reported beside that of the minimum
MEDIANS: dict = {}
#: the same for the CPU time (process_time), less sensitive to other jobs on the machine
CPU_MEDIANS: dict = {}

SHIFT = 0.008  # mm: the shift case (about half of the full-sliding shift of this contact)


def fft_pair_time(op, repeats: int = 20) -> float:
    """Seconds of one FFT pair of the padded grid: rfft2 + irfft2 of a (2, Mx, My) double field."""
    from scipy import fft as sfft

    Mx, My = op.padded_shape
    x = np.random.default_rng(0).random((2, op.mx, op.my))
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        sfft.irfft2(sfft.rfft2(x, s=(Mx, My)), s=(Mx, My))
        best = min(best, time.perf_counter() - t0)
    return best


def run_shift(n: int, repeats: int):
    grid, op, pn = problem(n)
    wall, sol = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = tang.solve_tangential(op, grid, pn, xi=SHIFT, eta=0.0, phi=0.0, mu_static=MU, mu_kinetic=MU,
                                    rolling="shift", tol=TOL)
        wall = min(wall, time.perf_counter() - t0)
    return grid, pn, sol, wall


def growth(sizes, values) -> float:
    """Exponent q of value ~ N^q (N = n^2), fitted over the sizes given."""
    return float(np.polyfit(np.log(np.asarray(sizes, float) ** 2), np.log(values), 1)[0])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[25, 50, 100, 150, 200, 300, 400])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--variant-sizes", type=int, nargs="*", default=[200])
    ap.add_argument("--quick", action="store_true", help="sizes 25 50 100, one repeat, no variants")
    ap.add_argument("--out", type=Path, default=ROOT / "studies" / "out" / "steady_rolling_speed")
    args = ap.parse_args(argv)
    if args.quick:
        args.sizes, args.repeats, args.variant_sizes = [25, 50, 100], 1, []
    sizes = sorted(args.sizes)
    rows = []
    results = {}
    for n in sizes:
        grid, op, pn = problem(n)
        unit = fft_pair_time(op)
        results[n] = run(n, args.repeats) + (unit,)
    fine_grid, fine_pn, fine, *_ = results[sizes[-1]]
    FX_fine = float(fine.px.sum() * fine_grid.area)
    print(f"steady rolling, case circ (mu {MU}, xi {XI}, tol {TOL:g}); finest grid {sizes[-1]}^2: FX = {FX_fine:.1f} N")
    head = (f"{'n':>4} {'contact':>7} {'slip%':>6} {'its':>4} {'prods':>5} {'coarse':>6} {'wall s':>7} "
            f"{'FFT pairs':>9} {'CONTACT s':>9} {'ratio':>6} {'FX':>9} {'FX CONTACT':>10} {'dFX/FX':>8} {'dpx/max':>8}")
    print(head)
    for n in sizes:
        grid, pn, sol, wall, cpu, unit = results[n]
        FX = float(sol.px.sum() * grid.area)
        nc = int(np.count_nonzero(sol.status))
        nslip = int(np.count_nonzero(sol.status == SLIP))
        c_norm, c_steady, c_fx = CONTACT.get(n, (None, None, None))
        c_tang = c_steady - c_norm if c_steady is not None else None
        ratio = wall / c_steady if c_steady else None
        err_fx = abs(FX - FX_fine) / abs(FX_fine)
        err_p = field_error(grid, sol, fine_grid, fine) if n != sizes[-1] else 0.0
        row = dict(n=n, case="steady", variant="final", n_contact=nc, n_slip=nslip,
                   n_adhesion=int(np.count_nonzero(sol.status == ADHESION)), newton_iterations=sol.iterations,
                   products=sol.products, coarse_products=round(sol.coarse_products, 1), residual=sol.residual,
                   converged=sol.converged, wall_s=wall, cpu_s=cpu, fft_pair_s=unit, fft_pairs=wall / unit,
                   wall_median_s=MEDIANS[n, "final"], cpu_median_s=CPU_MEDIANS[n, "final"], contact_gdsteady_s=c_steady, contact_tangential_s=c_tang, ratio_to_contact=ratio, FX=FX,
                   FX_contact=c_fx, FX_error_vs_finest=err_fx, px_error_vs_finest=err_p)
        rows.append(row)
        print(f"{n:>4} {nc:>7} {100 * nslip / nc:>6.1f} {sol.iterations:>4} {sol.products:>5} {sol.coarse_products:>6.1f} "
              f"{wall:>7.3f} {wall / unit:>9.0f} {(f'{c_steady:.2f}' if c_steady else '-'):>9} "
              f"{(f'{ratio:.3f}' if ratio else '-'):>6} {FX:>9.1f} {(f'{c_fx:.0f}' if c_fx else '-'):>10} "
              f"{err_fx:>8.2e} {err_p:>8.2e}")
    print("\nshift (T = 1), the same contact shifted by", SHIFT, "mm:")
    for n in sizes:
        grid, pn, sol, wall = run_shift(n, args.repeats)
        unit = results[n][-1]
        FX = float(sol.px.sum() * grid.area)
        rows.append(dict(n=n, case="shift", variant="final", newton_iterations=sol.iterations, products=sol.products,
                         coarse_products=round(sol.coarse_products, 1), residual=sol.residual,
                         converged=sol.converged, wall_s=wall, fft_pair_s=unit, fft_pairs=wall / unit, FX=FX,
                         n_slip=int(np.count_nonzero(sol.status == SLIP)), n_contact=int(np.count_nonzero(sol.status))))
        print(f"{n:>4} its {sol.iterations} products {sol.products} + {sol.coarse_products:.1f} wall {wall:.3f} s "
              f"= {wall / unit:.0f} FFT pairs, FX {FX:.1f}")
    big = [n for n in sizes if n >= 50]
    fits = {}
    for case in ("steady", "shift"):
        rs = [r for r in rows if r["case"] == case and r["n"] in big]
        if len(rs) >= 2:
            fits[case] = dict(wall=growth([r["n"] for r in rs], [r["wall_s"] for r in rs]),
                              wall_median=(growth([r["n"] for r in rs], [r["wall_median_s"] for r in rs])
                                           if all("wall_median_s" in r for r in rs) else None),
                              fft_pair=growth([r["n"] for r in rs], [r["fft_pair_s"] for r in rs]),
                              products=growth([r["n"] for r in rs], [r["products"] + r["coarse_products"] for r in rs]))
    for case, f in fits.items():
        print(f"growth {case} (n = {big[0]}..{big[-1]}): wall ~ N^{f['wall']:.2f}, products ~ N^{f['products']:.2f}, "
              f"one FFT pair ~ N^{f['fft_pair']:.2f}")
    steady = {r["n"]: r for r in rows if r["case"] == "steady"}
    for lo, hi in zip(big, big[1:]):   # the growth between neighbouring sizes (issue 23: 200 -> 400)
        a, b = steady[lo], steady[hi]
        fits.setdefault("steady_pairs", {})[f"{lo}-{hi}"] = dict(
            wall_min=growth([lo, hi], [a["wall_s"], b["wall_s"]]),
            wall_median=growth([lo, hi], [a["wall_median_s"], b["wall_median_s"]]),
            cpu_median=growth([lo, hi], [a["cpu_median_s"], b["cpu_median_s"]]),
            products=growth([lo, hi], [a["products"] + a["coarse_products"], b["products"] + b["coarse_products"]]))
        g = fits["steady_pairs"][f"{lo}-{hi}"]
        print(f"growth steady {lo}^2 -> {hi}^2: wall (min) ~ N^{g['wall_min']:.2f}, wall (median) ~ N^{g['wall_median']:.2f}, "
              f"CPU (median) ~ N^{g['cpu_median']:.2f}, "
              f"products ~ N^{g['products']:.2f}")
    if args.variant_sizes:
        print("\nvariants (what was tried), same case:")
        print(f"{'n':>4} {'variant':>8} {'its':>4} {'prods':>5} {'wall s':>7} {'cpu s':>7} {'FX':>9}")
        for n in args.variant_sizes:
            for v in VARIANTS:
                grid, pn, sol, wall, cpu = run(n, args.repeats, v)
                FX = float(sol.px.sum() * grid.area)
                rows.append(dict(n=n, case="steady", variant=v, newton_iterations=sol.iterations, products=sol.products,
                                 coarse_products=round(sol.coarse_products, 1), residual=sol.residual,
                                 converged=sol.converged, wall_s=wall, cpu_s=cpu, FX=FX,
                                 wall_median_s=MEDIANS[n, v], cpu_median_s=CPU_MEDIANS[n, v],
                                 contact_gdsteady_s=CONTACT.get(n, (None, None))[1]))
                print(f"{n:>4} {v:>8} {sol.iterations:>4} {sol.products:>5} {wall:>7.3f} {cpu:>7.3f} {FX:>9.1f}")
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(out / "steady_rolling_speed.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    md = ["| n x n | case | Newton its | products (+ coarse) | wall [s] | FFT pairs | CONTACT GDsteady [s] | FX [N] | FX CONTACT [N] | FX error vs finest |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["variant"] != "final" or "fft_pairs" not in r:
            continue
        cs = r.get("contact_gdsteady_s") or "-"
        err = r.get("FX_error_vs_finest")
        err = f"{err:.1e}" if err is not None else "-"
        md.append(f"| {r['n']} | {r['case']} | {r['newton_iterations']} | {r['products']} (+{r['coarse_products']:.0f}) | "
                  f"{r['wall_s']:.3f} | {r['fft_pairs']:.0f} | {cs} | {r['FX']:.0f} | {r.get('FX_contact') or '-'} | {err} |")
    for case, f in fits.items():
        if case == "steady_pairs":
            for pair, g in f.items():
                md.append(f"\nGrowth (steady, {pair.replace('-', '² -> ')}²): wall ~ N^{g['wall_min']:.2f} (minimum of the "
                          f"repeats), N^{g['wall_median']:.2f} (median), CPU ~ N^{g['cpu_median']:.2f} (median), "
                          f"products ~ N^{g['products']:.2f}.")
            continue
        md.append(f"\nGrowth ({case}, n = {big[0]}..{big[-1]}): wall ~ N^{f['wall']:.2f}, products ~ N^{f['products']:.2f}, "
                  f"one FFT pair of the padded grid ~ N^{f['fft_pair']:.2f}.")
    var = [r for r in rows if r["variant"] != "final" or ("fft_pairs" not in r and r["case"] == "steady")]
    if var:
        md += ["", "Variants (steady, the same process; medians of the repeats; final = the default solver, "
               "one-level = without the coarse-grid correction):", "",
               "| n x n | variant | Newton its | products (+ coarse) | wall median [s] | CPU median [s] | FX [N] |",
               "|---|---|---|---|---|---|---|"]
        md += [f"| {r['n']} | {r['variant']} | {r['newton_iterations']} | {r['products']} (+{r['coarse_products']:.0f}) | "
               f"{r['wall_median_s']:.3f} | {r['cpu_median_s']:.3f} | {r['FX']:.1f} |" for r in var]
        for v in VARIANTS:
            vs = sorted(r["n"] for r in var if r["variant"] == v)
            cpu = {r["n"]: r["cpu_median_s"] for r in var if r["variant"] == v}
            for lo, hi in zip(vs, vs[1:]):
                md.append(f"\nGrowth of the variant {v} ({lo}² -> {hi}²): CPU ~ N^{growth([lo, hi], [cpu[lo], cpu[hi]]):.2f}.")
    (out / "steady_rolling_speed.md").write_text("\n".join(md) + "\n")
    write_sidecar(out, __file__, args, extra={"growth": fits, "load_average": os.getloadavg()})
    print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
