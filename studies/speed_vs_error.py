"""Speed against error: every model on the same wheel-rail scenes.

Scenes: S1002 on UIC 60 (1:40), 10 kN, 2 m/s, at three lateral shifts: the tread (0 mm), the flange
root against the gauge corner (6.2 mm, contact angles -25 to -42 degrees) and the flange flank
(6.3 mm, about -70 degrees).  Models: Hertz (normal only), Kalker's linear theory, the empirical
theory, FASTSIM, the exact half-space theory on the tangent plane and the conformal theory with
half-space and with FE influence numbers, the grid models at several grid sizes ([grid] n).

Reference: the conformal theory with FE influence numbers on the finest grid.  Errors:
* force: |F - F_ref| / |F_ref| with F = (FX, FY, FZ) the total force on the rail, track frame;
* pmax: |pmax - pmax_ref| / pmax_ref.
Wall time: the solve as `conformal solve` runs it; for the FE model with the FE influence numbers
read from the cache, and (hollow markers) including their computation.

Writes to --out (default studies/out/speed_vs_error): speed_vs_error.csv, speed_vs_error.md,
speed_vs_error.png and the sidecar run.json (commit, arguments, package versions).

    python studies/speed_vs_error.py            # ~15 minutes the first time (FE), then ~2
    python studies/speed_vs_error.py --quick --out DIR   # flange root only, n = 12, 16, no FE; the
                                                         # reference is conformal HS n = 24 (< 1 min)
    python studies/speed_vs_error.py --only 6.3 "conformal FE n=24"   # one cell again, against the
                                                         # stored reference row; merged into the CSV
"""
from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from conformal.errors import ConformalError  # noqa: E402
from conformal.scene import load_scene  # noqa: E402
from conformal.dispatch import solve_scene  # noqa: E402

SCENE = ROOT / "meshes" / "scenes" / "flange_s1002_uic60.toml"
SCENES = (("tread, y = 0", 0.0), ("flange root, y = 6.2", 6.2), ("flange flank, y = 6.3", 6.3))
FAST = (("hertz", None), ("linear", None), ("empirical", None), ("fastsim", None))
FIELDS = ("scene", "model", "n", "FX_track", "FY_track", "FZ_track", "pmax", "force_error", "pmax_error", "wall_s", "wall_cold_s", "note")


def configs(quick: bool):
    """(label, theory, influence, n) of every model run, and the reference run.  Quick: no FE
    (the FE numbers take minutes to compute cold); the reference is the finer half-space one."""
    ns = (12, 16) if quick else (16, 24, 32, 48)
    out = [(t, t, "halfspace", None) for t, _ in FAST]
    out += [(f"exact n={n}", "exact", "halfspace", n) for n in ns]
    out += [(f"conformal HS n={n}", "conformal", "halfspace", n) for n in ns]
    if quick:
        return out, ("conformal HS n=24 (reference)", "conformal", "halfspace", 24)
    out += [(f"conformal FE n={n}", "conformal", "fe", n) for n in (16, 24, 32)]
    return out, ("conformal FE n=48 (reference)", "conformal", "fe", 48)


def run(scene, theory, influence, n) -> dict:
    sc = scene.with_model(theory=theory, influence=influence)
    if n is not None:
        sc = sc.with_("grid.n", n)
    t0 = time.perf_counter()
    r = solve_scene(sc)
    wall = time.perf_counter() - t0
    ex = r.extra
    row = {"FX_track": ex.get("FX_track", r.FX), "FY_track": ex.get("FY_track", r.FY), "FZ_track": ex.get("FZ_track", r.FN),
           "pmax": r.pmax, "wall_s": wall, "wall_cold_s": wall, "converged": r.converged}
    if influence == "fe":
        fe = ex.get("fe", {})
        built = sum(float(v.get("total_s", 0.0)) for v in fe.values())
        hit = bool(fe) and all(v.get("cache_hit") for v in fe.values())
        row["wall_cold_s"] = wall + built if hit else wall
        row["wall_s"] = wall if hit else wall - ex.get("influence_s", 0.0)
        row["note"] = "FE from cache" if hit else "FE computed"
    if theory == "hertz":
        row["note"] = "normal problem only (no creep forces)"
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=None,
                   help="output folder (default studies/out/speed_vs_error; with --quick a temporary folder)")
    ap.add_argument("--only", nargs=2, metavar=("SHIFT", "MODEL"), default=None,
                    help="rerun one cell (lateral shift in mm, one of the scenes', and a model label such as "
                         "'conformal FE n=24') against the stored reference row of that scene; the row replaces "
                         "the stored one and md/png are rewritten")
    args = ap.parse_args(argv)
    out = output_dir("speed_vs_error", args)
    out.mkdir(parents=True, exist_ok=True)
    if args.only:
        return rerun_cell(out, float(args.only[0]), args.only[1], args)
    base = load_scene(SCENE)
    runs, ref_cfg = configs(args.quick)
    rows = []
    for scene_label, y in (SCENES[1:2] if args.quick else SCENES):
        sc = base.with_("geometry.lateral_shift", y)
        ref_label = ref_cfg[0]
        try:
            ref = run(sc, *ref_cfg[1:])
        except ConformalError as exc:   # the FE reference failed: the finest half-space grid instead
            print(f"{scene_label}: reference {ref_label} failed ({exc}); using the half-space one", flush=True)
            ref_label = ref_cfg[0].replace("FE", "HS")
            ref = run(sc, "conformal", "halfspace", ref_cfg[3])
        F_ref = np.array([ref["FX_track"], ref["FY_track"], ref["FZ_track"]])
        print(f"{scene_label}: reference {ref_label}: F = {np.round(F_ref, 1)}, pmax {ref['pmax']:.1f}, "
              f"{ref['wall_s']:.1f} s", flush=True)
        for label, theory, influence, n in runs:
            try:
                row = run(sc, theory, influence, n)
            except ConformalError as exc:
                row = {"note": f"{type(exc).__name__}: {exc}"[:160]}
            else:
                F = np.array([row["FX_track"], row["FY_track"], row["FZ_track"]])
                row["force_error"] = float(np.linalg.norm(F - F_ref) / np.linalg.norm(F_ref))
                row["pmax_error"] = abs(row["pmax"] - ref["pmax"]) / ref["pmax"]
            row.update(scene=scene_label, model=label, n=n)
            rows.append(row)
            print(f"  {label:26s} " + "  ".join(f"{k}={row[k]:.3g}" for k in ("force_error", "pmax_error", "wall_s")
                                                 if row.get(k) is not None) + f"  {row.get('note', '')}", flush=True)
        rows.append(dict(ref, scene=scene_label, model=ref_cfg[0], n=ref_cfg[3], force_error=0.0, pmax_error=0.0,
                         note=("" if ref_label == ref_cfg[0] else f"FE failed: reference {ref_label}")))
    with (out / "speed_vs_error.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    write_markdown(rows, out / "speed_vs_error.md")
    plot(rows, out / "speed_vs_error.png", ref_cfg[0])   # per-scene fallbacks are noted in the table
    write_sidecar(out, __file__, args, extra={"reference": ref_cfg[0]})
    print(f"wrote {out}")
    return 0


def read_rows(path: Path) -> list[dict]:
    """The rows of a stored speed_vs_error.csv (numbers as floats, empty cells as absent)."""
    rows = []
    with path.open(newline="") as fh:
        for r in csv.DictReader(fh):
            row = {}
            for k, v in r.items():
                if v in ("", None):
                    continue
                row[k] = v if k in ("scene", "model", "note") else int(float(v)) if k == "n" else float(v)
            rows.append(row)
    return rows


def write_outputs(rows, out: Path, ref_label: str) -> None:
    """CSV (atomic), markdown and plot of ``rows``."""
    tmp = out / "speed_vs_error.csv.tmp"
    with tmp.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    tmp.replace(out / "speed_vs_error.csv")
    write_markdown(rows, out / "speed_vs_error.md")
    plot(rows, out / "speed_vs_error.png", ref_label)


def rerun_cell(out: Path, shift: float, label: str, args) -> int:
    """Run one model at one scene again and merge it into the stored outputs (its errors against
    the stored reference row of that scene)."""
    scene_label = next((lab for lab, y in SCENES if abs(y - shift) < 1e-9), None)
    runs, ref_cfg = configs(False)
    cfg = next((c for c in runs if c[0] == label), None)
    if scene_label is None or cfg is None:
        print(f"speed_vs_error: --only: no scene at {shift:g} mm or no model {label!r} (scenes at "
              f"{', '.join(f'{y:g}' for _, y in SCENES)}; models {', '.join(c[0] for c in runs)})", file=sys.stderr)
        return 2
    rows = read_rows(out / "speed_vs_error.csv")
    ref = next((r for r in rows if r["scene"] == scene_label and "(reference)" in r["model"]), None)
    if ref is None:
        print(f"speed_vs_error: --only: no stored reference row for {scene_label!r}", file=sys.stderr)
        return 2
    sc = load_scene(SCENE).with_("geometry.lateral_shift", shift)
    try:
        row = run(sc, *cfg[1:])
    except ConformalError as exc:
        row = {"note": f"{type(exc).__name__}: {exc}"[:160]}
    else:
        F = np.array([row["FX_track"], row["FY_track"], row["FZ_track"]])
        F_ref = np.array([ref["FX_track"], ref["FY_track"], ref["FZ_track"]])
        row["force_error"] = float(np.linalg.norm(F - F_ref) / np.linalg.norm(F_ref))
        row["pmax_error"] = abs(row["pmax"] - ref["pmax"]) / ref["pmax"]
    row.update(scene=scene_label, model=label, n=cfg[3])
    print(f"{scene_label}: {label}: " + "  ".join(f"{k}={row[k]:.4g}" for k in ("force_error", "pmax_error", "wall_s",
                                                                              "wall_cold_s") if k in row)
          + f"  {row.get('note', '')}", flush=True)
    i = next((i for i, r in enumerate(rows) if r["scene"] == scene_label and r["model"] == label), None)
    if i is None:
        rows.append(row)
    else:
        rows[i] = row
    write_outputs(rows, out, ref_cfg[0])
    # the full run's provenance stays with the rows it made; this run's describes the one cell
    side = out / "run.json"
    before = json.loads(side.read_text()) if side.exists() else {}
    earlier = before.pop("earlier_runs", [])
    write_sidecar(out, __file__, args, extra={"reference": ref_cfg[0], "rerun_cell": [scene_label, label],
                                              "earlier_runs": earlier + ([before] if before else [])})
    return 0


def write_markdown(rows, path: Path) -> None:
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    models = list(dict.fromkeys(r["model"] for r in rows))
    head = "| model | " + " | ".join(f"{s}: force err / pmax err / wall [s]" for s in scenes) + " |"
    lines = [head, "|---|" + "---|" * len(scenes)]
    for m in models:
        cells = []
        for s in scenes:
            r = next((r for r in rows if r["scene"] == s and r["model"] == m), None)
            if r is None or r.get("force_error") is None:
                cells.append(r.get("note", "") if r else "")
            else:
                cold = f" ({r['wall_cold_s']:.1f} with FE)" if r.get("wall_cold_s", r["wall_s"]) > r["wall_s"] + 1e-9 else ""
                note = f" ({r['note']})" if str(r.get("note", "")).startswith("FE failed") else ""
                cells.append(f"{100 * r['force_error']:.2f} % / {100 * r['pmax_error']:.1f} % / {r['wall_s']:.2f}{cold}"
                             + note)
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    path.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def plot(rows, path: Path, ref_label: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fams = {"hertz": "C7", "linear": "C5", "empirical": "C6", "fastsim": "C4", "exact": "C0",
            "conformal HS": "C1", "conformal FE": "C3"}
    marks = {s: m for s, m in zip(dict.fromkeys(r["scene"] for r in rows), "o^s")}
    fig, axes = plt.subplots(1, 2, figsize=(14, 6))
    for ax, key, name in ((axes[0], "force_error", "force error |F - F_ref| / |F_ref|"),
                          (axes[1], "pmax_error", "pmax error")):
        seen = set()
        for r in rows:
            if r.get(key) is None or "(reference)" in r["model"] or r[key] <= 0:
                continue
            fam = next(f for f in sorted(fams, key=len, reverse=True) if r["model"].startswith(f))
            lab = fam if fam not in seen else None
            seen.add(fam)
            ax.loglog(r["wall_s"], r[key], marks[r["scene"]], color=fams[fam], label=lab, ms=7)
            if r.get("wall_cold_s", r["wall_s"]) > r["wall_s"] + 1e-9:
                ax.loglog(r["wall_cold_s"], r[key], marks[r["scene"]], mfc="none", color=fams[fam], ms=7)
                ax.plot([r["wall_s"], r["wall_cold_s"]], [r[key]] * 2, color=fams[fam], lw=0.6, alpha=0.5)
        ax.set_xlabel("wall time [s] (hollow: including the FE influence numbers)")
        ax.set_ylabel(name)
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=8, loc="lower left")
    for s, m in marks.items():
        axes[1].plot([], [], m, color="k", label=s)
    axes[1].legend(fontsize=8, loc="lower left")
    fig.suptitle(f"S1002/UIC60, 10 kN, 2 m/s: error against {ref_label}")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
