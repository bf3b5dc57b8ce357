"""Rigid wheel-rail geometry versus lateral shift for the project's profile pairs.

For each pair: rolling-radius difference r_R - r_L, contact angles and contact positions for
wheelset shifts -10 .. 10 mm (roll found so that both wheels touch, no yaw), CSV + PNG per pair
and one overview PNG.  Also printed: the secant conicity dr(y)/(2y) at y = 3 mm (a plain secant,
not the EN 15302 harmonic linearisation) and the measured time per shift.

    python studies/profile_sweep.py [--out studies/out/profile_sweep] [--step 0.5]
    python studies/profile_sweep.py --quick --out DIR   # S1002/UIC60 only, -4 .. 4 mm in 1 mm steps

The sidecar OUT/run.json records the commit, the arguments, the package versions and the secant
conicities.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from conformal.geometry.sweep import plot, sweep, write_csv  # noqa: E402
from conformal.scene import WheelRailGeometry  # noqa: E402

PAIRS = {
    # name: geometry (track gauge 1435, flange-back spacing 1360, radius 460 unless stated)
    "S1002_UIC60_1in40": WheelRailGeometry(wheel_profile="S1002", rail_profile="UIC60", rail_cant=0.024995),
    "S1002_60E1_1in40": WheelRailGeometry(wheel_profile="S1002", rail_profile="60E1", rail_cant=0.024995),
    "EN15302_A_railA": WheelRailGeometry(wheel_profile="EN15302_WHEEL_A", rail_profile="EN15302_RAIL_A_1IN20",
                                         rail_cant=0.0),
    "EN15302_B_railA": WheelRailGeometry(wheel_profile="EN15302_WHEEL_B", rail_profile="EN15302_RAIL_A_1IN20",
                                         rail_cant=0.0),
    "EN13715_1in40_UIC60_1in40": WheelRailGeometry(wheel_profile="EN13715_1IN40", rail_profile="UIC60",
                                                   rail_cant=0.024995),
    # CONTACT testbank worn pair: GAUGHT 15.875, GAUGWD 1435.1, FBDIST 1347.4, NOMRAD 444, no cant
    "worn_pair_site_b": WheelRailGeometry(wheel_profile="WORN_WHEEL_HM", rail_profile="WORN_RAIL_SITE_B",
                                          rail_cant=0.0, gauge=1435.1, gauge_height=15.875,
                                          flange_back=1347.4, wheel_radius=444.0, smoothing=2.0),
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=None,
                   help="output folder (default studies/out/profile_sweep; with --quick a temporary folder)")
    ap.add_argument("--step", type=float, default=0.5)
    ap.add_argument("--max-shift", type=float, default=10.0)
    ap.add_argument("--pairs", default=",".join(PAIRS), help="profile pairs, comma separated")
    ap.add_argument("--quick", action="store_true",
                    help="S1002_UIC60_1in40 only, -4 .. 4 mm in 1 mm steps (seconds; a test runs it)")
    args = ap.parse_args(argv)
    if args.quick:
        args.pairs, args.step, args.max_shift = "S1002_UIC60_1in40", 1.0, 4.0
    unknown = [p for p in args.pairs.split(",") if p not in PAIRS]
    if unknown:
        ap.error(f"--pairs: unknown {', '.join(unknown)}; known: {', '.join(PAIRS)}")
    out = output_dir("profile_sweep", args)
    n = int(round(2 * args.max_shift / args.step)) + 1
    shifts = np.linspace(-args.max_shift, args.max_shift, n)
    results, summary = {}, {}
    failed = []
    for name in args.pairs.split(","):
        geo = PAIRS[name]
        t0 = time.perf_counter()
        try:
            rows = sweep(geo, shifts)
        except Exception as exc:   # noqa: BLE001 - report and go on with the other pairs
            print(f"{name}: failed: {exc}")
            failed.append(name)
            continue
        dt = time.perf_counter() - t0
        results[name] = rows
        write_csv(rows, out / f"{name}.csv")
        plot(rows, out / f"{name}.png", title=name)
        dr = {r["shift"]: r["delta_r"] for r in rows}
        conicity = dr.get(3.0, np.nan) / 6.0
        flange = [r["shift"] for r in rows if r["contact_angle_right"] < -0.9]
        jumps = [rows[i + 1]["shift"] for i in range(len(rows) - 1)
                 if abs(rows[i + 1]["y_rail_right"] - rows[i]["y_rail_right"]) > 3.0]
        summary[name] = {"secant_conicity_3mm": conicity, "flange_from_mm": min(flange) if flange else None,
                         "contact_jumps_before_mm": jumps, "ms_per_shift": dt / len(rows) * 1000}
        print(f"{name:28s} secant conicity dr(3)/6 = {conicity:.4f}  flange contact from y = "
              f"{(min(flange) if flange else float('nan')):5.1f} mm  contact jumps before y = {jumps}  "
              f"({dt / len(rows) * 1000:.0f} ms per shift)")
    _overview(results, out / "overview.png")
    write_sidecar(out, __file__, args, extra={"summary": summary, "failed": failed})
    print(f"wrote CSV and PNG per pair, {out / 'overview.png'} and run.json")
    return 1 if failed else 0


def _overview(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
    for name, rows in results.items():
        y = [r["shift"] for r in rows]
        ax[0].plot(y, [r["delta_r"] for r in rows], label=name)
        ax[1].plot(y, [r["y_rail_right"] for r in rows], label=name)
    ax[0].set_ylabel("r_R - r_L [mm]")
    ax[0].set_ylim(-25, 25)
    ax[1].set_ylabel("right contact position on the rail [mm]")
    for a in ax:
        a.set_xlabel("lateral shift [mm]")
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=7)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
