"""FE bodies against half-spaces at a prescribed approach, over the size of the FE body.

The question a user asks of FE influence numbers: at the same approach, how much more or less
load does the real, curved wheel and rail carry than two half-spaces?  The FE bodies are finite
(a margin of ``fe_body_size`` patch sizes around the contact); this study shows how the answer
depends on that size at 0.5-4.

Superseded for the size question by studies/fe_far_field_limit.py (issue 20): its committed
outputs were made with FE_VERSION 4, where a profile ending inside the body was cut there (the
deep pair's bodies stopped growing beyond size 2, so the half-space series looked flat), and sizes
up to 4; the default body size is now 16 with profiles continued straight.  The sizes here are
explicit, so a rerun measures the same sizes with the new closure; it was not rerun for the
change (the new study covers sizes 1-16 with both far fields and extrapolates).

For each scene the conformal solver runs at the scene's prescribed approach with half-space
numbers (the reference FN_hs) and with FE numbers for body sizes 0.5, 1, 2, 4 (clamped: 0.5, 1, 2)
and both far-field conditions on the artificial boundaries:

* ``halfspace`` (default): the half-space field of the load is imposed there (the split method's
  correction vanishes on them): a flat block reproduces the half-space exactly.
* ``clamped`` (the earlier treatment): zero displacement; the body is too stiff by an offset that
  decays like 1/size and sums over the patch.

Scenes: the crowned wheel on a flat rail (Hertz: FN = 32847 N), the S1002/UIC60 flange root at
6.2 mm shift, the near-conformal groove (wheel R10 in a groove R10.02) and the deep conformal
pair (rail corner R10 against flange root R10.2).  Reported: the spread of FN_fe/FN_hs over the
body sizes with the half-space far field, and for the clamped series the decay rate of its
excess stiffness over the half-space far field's value at the largest size, fitted with
np.polyfit of log(excess) against log(size) (a truncation offset decays like 1/size).

    python studies/fe_body_size.py            # all scenes, sizes 0.5-4 (about 15 min on 2 cores)
    python studies/fe_body_size.py --quick    # the crowned wheel at sizes 0.5, 1 (a test runs it)

Output: studies/out/fe_body_size/fe_body_size.{csv,md,png} and run.json (commit, arguments,
package versions).
"""
from __future__ import annotations

import argparse
import csv
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "meshes" / "scenes"
OUT = ROOT / "studies" / "out" / "fe_body_size"

CASES = {   # scene file, prescribed approach (mm)
    "crowned wheel (Hertz)": ("hertz_crowned_wheel.toml", 0.05),
    "S1002/UIC60 flange 6.2 mm": ("flange_s1002_uic60_fe.toml", 0.03),
    "groove R10/R10.02": ("groove_conformal.toml", 0.006),
    "deep pair R10/R10.2": ("deep_conformal_pair.toml", 0.05),
}
SIZES = {"halfspace": (0.5, 1.0, 2.0, 4.0), "clamped": (0.5, 1.0, 2.0)}   # clamped at 4: minutes per body
FAR_FIELDS = ("halfspace", "clamped")
HERTZ_FN = 32847.0   # crowned wheel, Hertz (conformal.theories.hertz at A = 1/920, B = 1/600 per mm)


sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from conformal.errors import ConformalError  # noqa: E402


def solve_at(scene_file: str, approach: float, influence: str, **fe) -> dict:
    from conformal.scene import load_scene
    from conformal.dispatch import solve_scene

    scene = load_scene(SCENES / scene_file)
    options = dict(scene.model.options)
    options.update({f"fe_{k}": v for k, v in fe.items()})
    scene = scene.with_("load.approach", approach)
    scene = scene.with_model(theory="conformal", influence=influence, options=options)
    t0 = time.perf_counter()
    r = solve_scene(scene)
    return {"FN": r.FN, "pmax": r.pmax, "area": r.summary().get("contact_area", float("nan")),
            "wall_s": time.perf_counter() - t0}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the crowned wheel at sizes 0.5 and 1 only")
    ap.add_argument("--out", default=None,
                   help="output folder (default studies/out/fe_body_size; with --quick a temporary folder)")
    args = ap.parse_args(argv)
    out = output_dir("fe_body_size", args)
    out.mkdir(parents=True, exist_ok=True)
    cases = dict(list(CASES.items())[:1]) if args.quick else CASES
    sizes = {far: (0.5, 1.0) for far in FAR_FIELDS} if args.quick else SIZES
    os.environ.setdefault("CONFORMAL_CACHE", str(Path(tempfile.gettempdir()) / "conformal_fe_body_size"))
    rows = []
    for label, (scene_file, approach) in cases.items():
        hs = solve_at(scene_file, approach, "halfspace")
        rows.append({"case": label, "far_field": "-", "body_size": 0.0, "influence": "halfspace", **hs,
                     "ratio_FN": 1.0, "ratio_pmax": 1.0})
        print(f"{label}: half-space FN = {hs['FN']:.1f} N, pmax = {hs['pmax']:.1f}", flush=True)
        for far in FAR_FIELDS:
            for size in sizes[far]:
                try:
                    r = solve_at(scene_file, approach, "fe", body_size=size, far_field=far)
                except ConformalError as exc:      # e.g. a body larger than the 50 mm groove wheel
                    print(f"  {far:9s} size {size:3.1f}: not possible: {exc}", flush=True)
                    continue
                rows.append({"case": label, "far_field": far, "body_size": size, "influence": "fe", **r,
                             "ratio_FN": r["FN"] / hs["FN"], "ratio_pmax": r["pmax"] / hs["pmax"]})
                print(f"  {far:9s} size {size:3.1f}: FN/FN_hs = {r['FN'] / hs['FN']:.4f}, pmax/pmax_hs = "
                      f"{r['pmax'] / hs['pmax']:.4f} ({r['wall_s']:.1f} s)", flush=True)
    keys = ["case", "far_field", "body_size", "influence", "FN", "pmax", "area", "ratio_FN", "ratio_pmax", "wall_s"]
    with open(out / "fe_body_size.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{r[k]:.6g}" if isinstance(r[k], float) else r[k]) for k in keys})
    # summary per case: the half-space far field's spread over the sizes (it should be at the
    # level of the mesh noise), and the clamped series' excess stiffness over the half-space far
    # field's value at the largest size, with its fitted decay rate (np.polyfit, log-log)
    lines = ["| case | far field | FN_fe/FN_hs at body size " + " / ".join(f"{s:g}" for s in sizes["halfspace"])
             + " | spread (half-space) or fitted decay rate of the excess (clamped) | pmax ratio (largest size) |",
             "|---|---|---|---|---|"]
    summary = []
    for label in cases:
        ref = [r for r in rows if r["case"] == label and r["far_field"] == "halfspace"]
        for far in FAR_FIELDS:
            sel = [r for r in rows if r["case"] == label and r["far_field"] == far]
            if not sel:
                continue
            s = np.array([r["body_size"] for r in sel])
            q = np.array([r["ratio_FN"] for r in sel])
            if far == "halfspace":
                stat = float(q.max() - q.min())
                text = f"spread {100 * stat:.2f} %"
            else:
                excess = q / ref[-1]["ratio_FN"] - 1.0 if ref else q - 1.0
                stat = (float(-np.polyfit(np.log(s), np.log(excess), 1)[0])
                        if len(s) >= 2 and np.all(excess > 0) else float("nan"))
                text = f"rate {stat:.2f}"
            summary.append({"case": label, "far_field": far, "sizes": s.tolist(), "ratios": q.tolist(),
                            "spread_or_rate": stat, "pmax_ratio": sel[-1]["ratio_pmax"]})
            by_size = dict(zip(s.tolist(), q.tolist()))
            lines.append(f"| {label} | {far} | " + " / ".join(f"{by_size[z]:.4f}" if z in by_size else "-"
                                                           for z in sizes["halfspace"])
                         + f" | {text} | {sel[-1]['ratio_pmax']:.4f} |")
    hz = [r for r in rows if r["case"].startswith("crowned") and r["far_field"] == "halfspace"]
    if hz:
        lines.append("")
        lines.append("Crowned wheel against Hertz (FN = 32847 N): half-space "
                     + f"{rows[0]['FN'] / HERTZ_FN - 1:+.3%}, FE (half-space far field) "
                     + ", ".join(f"size {r['body_size']:g}: {r['FN'] / HERTZ_FN - 1:+.3%}" for r in hz))
    (out / "fe_body_size.md").write_text("\n".join(lines) + "\n")
    write_sidecar(out, __file__, args, extra={"summary": summary})
    _plot(rows, cases, out / "fe_body_size.png")
    print("\n".join(lines))
    return 0


def _plot(rows, cases, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    for k, label in enumerate(cases):
        for far, style in (("halfspace", "-o"), ("clamped", "--s")):
            sel = [r for r in rows if r["case"] == label and r["far_field"] == far]
            ax.plot([r["body_size"] for r in sel], [r["ratio_FN"] for r in sel], style, color=f"C{k}",
                    label=f"{label}, {far}")
    ax.axhline(1.0, color="0.5", lw=0.8)
    ax.set_xscale("log", base=2)
    ax.set_xlabel("FE body margin (patch sizes), fe_body_size")
    ax.set_ylabel("FN (FE) / FN (half-space) at equal approach")
    ax.set_title("FE bodies against half-spaces at a prescribed approach")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
