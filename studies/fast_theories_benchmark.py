"""Kalker's fast theories: speed and error against CONTACT's reference cases.

    python studies/fast_theories_benchmark.py [--n 100000] [--out studies/out/fast_theories_benchmark]
    python studies/fast_theories_benchmark.py --quick --out DIR   # batch of 2000, no 880 grid (seconds)

Prints (1) FASTSIM throughput: single calls (slices and grid) and the vectorised batch, with
the other vectorised fast theories for comparison; (2) the error of each fast theory (Hertz,
linear, Kalker 1968 empirical, Johnson-Vermeulen, FASTSIM) against CONTACT's exact half-space
results in tests/reference/contact_cases.json (cases `cattaneo`, `fastsim`, `tractcurv`
series 1), and FASTSIM against CONTACT's FASTSIM (same variant); (3) FASTSIM's grid
convergence.  The error table is written to OUT/fast_theories.csv, the convergence table to
OUT/fastsim_convergence.csv and the sidecar (commit, arguments, package versions, throughput) to
OUT/run.json.

Timings: wall clock and CPU time (the machine's 2 cores may be shared with other jobs).
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from conformal.grid import PlanarGrid  # noqa: E402
from conformal.materials import Material  # noqa: E402
from conformal.theories import empirical as emp  # noqa: E402
from conformal.theories import fastsim as fs  # noqa: E402
from conformal.theories import linear  # noqa: E402
from conformal.theories.hertz import hertz_from_curvatures, hertz_from_semiaxes  # noqa: E402

REF = ROOT / "tests" / "reference" / "contact_cases.json"
G, NU = 82000.0, 0.28


def best_time(fn, repeat=3):
    """Smallest wall and CPU (process) time of ``repeat`` runs.  On a shared machine the wall
    time includes waiting for a core; the CPU time is the intrinsic cost (numpy here is single
    threaded)."""
    wall = cpu = math.inf
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall = min(wall, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return wall, cpu


# ----------------------------------------------------------------------------- throughput
def throughput(n: int) -> list[tuple[str, float, float]]:
    rng = np.random.default_rng(2024)
    a, b = rng.uniform(3.0, 10.0, n), rng.uniform(3.0, 10.0, n)
    FN, mu = rng.uniform(2e4, 1.2e5, n), np.full(n, 0.3)
    xi, eta, phi = rng.uniform(-2e-3, 2e-3, n), rng.uniform(-2e-3, 2e-3, n), rng.uniform(-1e-3, 1e-3, n)
    rows = []
    m = 300
    t = best_time(lambda: [fs.fastsim_forces(a[i], b[i], FN[i], 0.3, xi[i], eta[i], phi[i], G=G, nu=NU)
                           for i in range(m)], repeat=2)
    rows.append(("FASTSIM single call, slices 24x24 (fastsim_forces)", m / t[0], m / t[1]))
    grid = PlanarGrid.around_ellipse(8.0, 4.0, n=40)
    L = fs.flexibilities(8.0, 4.0, G, NU)
    t = best_time(lambda: [fs.fastsim_grid(8.0, 4.0, 82000.0, 0.3, xi[i], eta[i], phi[i], L, grid)
                           for i in range(100)], repeat=2)
    rows.append(("FASTSIM single call, 40x40 grid with traction maps (fastsim_grid)", 100 / t[0], 100 / t[1]))
    f = fs.flexibilities(a, b, G, NU)
    t = best_time(lambda: fs.fastsim_batch(a, b, FN, mu, xi, eta, phi, L=(f.L1, f.L2, f.L3)), repeat=2)
    rows.append((f"FASTSIM batch of {n} contacts, slices 24x24, flexibilities given", n / t[0], n / t[1]))
    t = best_time(lambda: fs.fastsim_batch(a, b, FN, mu, xi, eta, phi, G=G, nu=NU), repeat=2)
    rows.append((f"FASTSIM batch of {n} contacts, slices 24x24, incl. Kalker coefficients", n / t[0], n / t[1]))
    t = best_time(lambda: fs.fastsim_batch(a, b, FN, mu, xi, eta, phi, L=(f.L1, f.L2, f.L3), nx=12, ny=12), repeat=2)
    rows.append((f"FASTSIM batch of {n} contacts, slices 12x12, flexibilities given", n / t[0], n / t[1]))
    t = best_time(lambda: linear.linear_force_arrays(a, b, G, NU, xi, eta, phi))
    rows.append((f"linear theory, vectorised, {n} contacts", n / t[0], n / t[1]))
    for law, cc in (("kalker", "kalker"), ("johnson_vermeulen", "elliptic")):
        t = best_time(lambda: emp.empirical_forces(a, b, FN, mu, G, NU, xi, eta, law=law, coefficients=cc))
        rows.append((f"empirical {law} ({cc} coefficients), vectorised, {n} contacts", n / t[0], n / t[1]))
    return rows


# ----------------------------------------------------------------------------- errors
def error_rows() -> list[dict]:
    cases = json.loads(REF.read_text())["cases"]
    rows: list[dict] = []
    steel = Material.identical(G, NU)

    def add(case, theory, variant, quantity, ref, value, wall=None):
        err = value - ref
        rows.append(dict(case=case, theory=theory, variant=variant, quantity=quantity, reference=ref,
                         value=value, abs_error=err, rel_error=err / ref if ref else math.nan,
                         wall_s=wall))

    # Hertz against CONTACT's exact normal solutions (element-centre pmax, as printed)
    cat = cases["cattaneo"]["steps"][0]["outputs"]
    hz = hertz_from_semiaxes(1.0, 1.0, Material.identical(200.0, 0.42), normal_force=9.1954)
    add("cattaneo", "hertz", "", "approach_mm", cat["approach_mm"], hz.approach)
    add("cattaneo", "hertz", "", "pmax_Nmm2", cat["pmax_Nmm2"], hz.pmax)
    ex = cases["fastsim"]["steps"][0]["outputs"]
    hz = hertz_from_semiaxes(8.0, 4.0, steel, normal_force=82000.0)
    add("fastsim#1 exact", "hertz", "", "approach_mm", ex["approach_mm"], hz.approach)
    add("fastsim#1 exact", "hertz", "", "pmax_Nmm2", ex["pmax_Nmm2"], hz.pmax)
    add("fastsim#1 exact", "hertz", "", "n_contact (pi a b/(dx dy))", ex["n_contact"], math.pi * 32 / 0.08)
    tc1 = [s for s in cases["tractcurv"]["steps"] if s.get("series") == 1]
    hz = hertz_from_curvatures(0.0008, 0.2814e-3, steel, normal_force=106700.0)
    add("tractcurv s1 exact", "hertz", "", "approach_mm", tc1[0]["outputs"]["approach_mm"], hz.approach)
    add("tractcurv s1 exact", "hertz", "", "pmax_Nmm2", tc1[0]["outputs"]["pmax_Nmm2"], hz.pmax)

    # fastsim case 1 (exact theory): lateral creepage + large spin
    a, b, FN, mu, eta, phi = 8.0, 4.0, 82000.0, 0.3, -0.000625, 0.000625
    muFN = mu * FN
    lf = linear.linear_forces(a, b, G, NU, 0.0, eta, phi, need_c33=False)
    add("fastsim#1 exact", "linear", "", "FY/(mu FN)", ex["FY_over_muFN"], lf.FY / muFN)
    for law, cc in (("kalker", "kalker"), ("kalker", "elliptic"), ("johnson_vermeulen", "elliptic"),
                    ("johnson_vermeulen", "kalker")):
        fx, fy, _ = emp.empirical_forces(a, b, FN, mu, G, NU, 0.0, eta, law=law, coefficients=cc)
        add("fastsim#1 exact", "empirical" if law == "kalker" else law, f"{cc} coefficients (spin ignored)",
            "FY/(mu FN)", ex["FY_over_muFN"], fy / muFN)
    Lk = fs.flexibilities(a, b, G, NU)
    for bound in fs.BOUNDS:
        for n in (44, 220):
            grid = PlanarGrid(n, n, 17.6 / n, 8.8 / n, -8.8, -4.4)
            t0 = time.perf_counter()
            s = fs.fastsim_grid(a, b, FN, mu, 0.0, eta, phi, Lk, grid, bound)
            wall = time.perf_counter() - t0
            add("fastsim#1 exact", "fastsim", f"{bound}, grid {n}x{n}, midpoint, Kalker L", "FY/(mu FN)",
                ex["FY_over_muFN"], s.FY / muFN, wall)
            add("fastsim#1 exact", "fastsim", f"{bound}, grid {n}x{n}, midpoint, Kalker L", "MZ_Nmm",
                ex["MZ_Nmm"], s.MZ, wall)
        r = fs.fastsim_forces(a, b, FN, mu, 0.0, eta, phi, G=G, nu=NU, bound=bound)
        add("fastsim#1 exact", "fastsim", f"{bound}, slices 24x24", "FY/(mu FN)", ex["FY_over_muFN"], r.FY / muFN)
        add("fastsim#1 exact", "fastsim", f"{bound}, slices 24x24", "MZ_Nmm", ex["MZ_Nmm"], r.MZ)

    # FASTSIM against CONTACT's FASTSIM (cases 2, 3, 5, 6), same variant and flexibilities
    Lc = fs.Flexibilities(4.937e-5, 5.152e-5, 4.090e-5)
    for case, (bound, n) in {2: ("parabolic", 44), 3: ("elliptic", 44), 5: ("parabolic", 220),
                             6: ("elliptic", 220)}.items():
        out = cases["fastsim"]["steps"][case - 1]["outputs"]
        grid = PlanarGrid(n, n, 17.6 / n, 8.8 / n, -8.8, -4.4)
        for disc in ("contact", "midpoint"):
            s = fs.fastsim_grid(a, b, FN, mu, 0.0, eta, phi, Lc, grid, bound, discretisation=disc)
            v = f"{bound}, grid {n}x{n}, {disc}, CONTACT's L"
            add(f"fastsim#{case} CONTACT-FASTSIM", "fastsim", v, "FY/(mu FN)", out["FY_over_muFN"], s.FY / muFN)
            add(f"fastsim#{case} CONTACT-FASTSIM", "fastsim", v, "MZ_Nmm", out["MZ_Nmm"], s.MZ)
            add(f"fastsim#{case} CONTACT-FASTSIM", "fastsim", v, "n_adhesion", out["n_adhesion"],
                float(np.count_nonzero(s.status == 1)))

    # tractcurv series 1 (exact, pure xi, 30 creepages): max |error| of FX/(mu FN) over the curve
    a, b, FN, mu = 6.3036, 12.6072, 106700.0, 0.33
    muFN = mu * FN
    xi = np.array([s["inputs"]["loading"]["CKSI_xi"] for s in tc1])
    ref = np.array([s["outputs"]["FX_over_muFN"] for s in tc1])

    def curve(name, variant, vals, wall=None):
        k = int(np.argmax(np.abs(vals - ref)))
        add("tractcurv s1 exact", name, variant + f" (max over 30 xi, at xi={xi[k]:g})", "FX/(mu FN)",
            ref[k], vals[k], wall)
        add("tractcurv s1 exact", name, variant + " (xi=1e-5, slope)", "FX/(mu FN)", ref[0], vals[0], wall)

    t0 = time.perf_counter()
    fl, _ = linear.linear_force_arrays(a, b, G, NU, xi, 0.0)
    curve("linear", "", fl / muFN, (time.perf_counter() - t0) / 30)
    for law, cc in (("kalker", "kalker"), ("kalker", "elliptic"), ("johnson_vermeulen", "elliptic"),
                    ("johnson_vermeulen", "kalker")):
        t0 = time.perf_counter()
        fx, _, _ = emp.empirical_forces(a, b, FN, mu, G, NU, xi, 0.0, law=law, coefficients=cc)
        curve("empirical" if law == "kalker" else law, f"{cc} coefficients", fx / muFN,
              (time.perf_counter() - t0) / 30)
    grid = PlanarGrid.around_ellipse(a, b, mx=48, my=44)
    Lk = fs.flexibilities(a, b, G, NU)
    for bound in fs.BOUNDS:
        t0 = time.perf_counter()
        vals = np.array([fs.fastsim_grid(a, b, FN, mu, x, 0.0, 0.0, Lk, grid, bound).FX for x in xi]) / muFN
        curve("fastsim", f"{bound}, grid 48x44", vals, (time.perf_counter() - t0) / 30)
        t0 = time.perf_counter()
        r = fs.fastsim_batch(a, b, FN, mu, xi, 0.0, 0.0, G=G, nu=NU, bound=bound)
        curve("fastsim", f"{bound}, batch slices 24x24", r.FX / muFN, (time.perf_counter() - t0) / 30)
    # tractcurv series 3: CONTACT's FASTSIM, same variant
    tc3 = [s for s in cases["tractcurv"]["steps"] if s.get("series") == 3]
    Lc = fs.Flexibilities(5.491e-5, 6.773e-5, 4.526e-5)
    ref3 = np.array([s["outputs"]["FX_over_muFN"] for s in tc3])
    for disc in ("contact", "midpoint"):
        vals = np.array([fs.fastsim_grid(a, b, FN, mu, x, 0.0, 0.0, Lc, grid, "parabolic",
                                         discretisation=disc).FX for x in xi]) / muFN
        k = int(np.argmax(np.abs(vals - ref3)))
        add("tractcurv s3 CONTACT-FASTSIM", "fastsim", f"parabolic, grid 48x44, {disc}, CONTACT's L "
            f"(max over 30 xi, at xi={xi[k]:g})", "FX/(mu FN)", ref3[k], vals[k])
    return rows


def convergence_rows(quick: bool = False) -> list[tuple]:
    """FASTSIM fastsim case (parabolic, CONTACT's L): FY/(mu FN) and MZ against grid size."""
    Lc = fs.Flexibilities(4.937e-5, 5.152e-5, 4.090e-5)
    out = []
    for n in ((44, 220) if quick else (44, 220, 880)):
        grid = PlanarGrid(n, n, 17.6 / n, 8.8 / n, -8.8, -4.4)
        for disc in ("midpoint", "contact"):
            s = fs.fastsim_grid(8.0, 4.0, 82000.0, 0.3, 0.0, -0.000625, 0.000625, Lc, grid, "parabolic",
                                discretisation=disc)
            out.append((n, disc, s.FY / 24600.0, s.MZ))
    for nxy in (12, 24, 48, 96):
        r = fs.fastsim_forces(8.0, 4.0, 82000.0, 0.3, 0.0, -0.000625, 0.000625, L=(Lc.L1, Lc.L2, Lc.L3),
                              nx=nxy, ny=nxy)
        out.append((nxy, "slices", r.FY / 24600.0, r.MZ))
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=100_000, help="contacts in the batch timing")
    p.add_argument("--out", default=None,
                  help="output folder (default studies/out/fast_theories_benchmark; with --quick a temporary folder)")
    p.add_argument("--quick", action="store_true", help="batch of 2000 contacts, grids up to 220 (seconds)")
    args = p.parse_args(argv)
    if args.quick:
        args.n = min(args.n, 2000)

    print("== throughput (contacts per second, best of 2-3 runs: wall clock | CPU time) ==")
    if hasattr(os, "getloadavg"):
        print(f"  (load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    rates = throughput(args.n)
    for name, rate, rate_cpu in rates:
        print(f"  {rate:12,.0f} /s | {rate_cpu:12,.0f} /s CPU   {name}")

    print("\n== error against CONTACT reference cases ==")
    rows = error_rows()
    fmt = "  {case:<28} {theory:<18} {quantity:<26} ref {reference:>11.5g}  got {value:>11.5g}  rel {rel:>8}  {variant}"
    for r in rows:
        rel = "" if not math.isfinite(r["rel_error"]) else f"{100 * r['rel_error']:+.2f}%"
        print(fmt.format(rel=rel, **r))
    out = output_dir("fast_theories_benchmark", args)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "fast_theories.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"\nwrote {out / 'fast_theories.csv'} ({len(rows)} rows)")

    print("\n== FASTSIM convergence, fastsim case, parabolic, CONTACT's L ==")
    conv = convergence_rows(args.quick)
    for n, disc, fy, mz in conv:
        print(f"  {disc:<9} n = {n:4d}   FY/(mu FN) = {fy:.5f}   MZ = {mz:9.0f} N mm")
    print("  (CONTACT exact: FY/(mu FN) = -0.6074, MZ = -48210; CONTACT FASTSIM 44: -0.6118, 220: -0.6359)")
    with open(out / "fastsim_convergence.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(("n", "discretisation", "FY_over_muFN", "MZ_Nmm"))
        w.writerows((n, disc, f"{fy:.6g}", f"{mz:.6g}") for n, disc, fy, mz in conv)
    write_sidecar(out, __file__, args, extra={
        "throughput_per_s": [{"what": name, "wall": rate, "cpu": rate_cpu} for name, rate, rate_cpu in rates]})
    print(f"wrote {out / 'fastsim_convergence.csv'} and {out / 'run.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
