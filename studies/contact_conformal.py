"""CONTACT's conformal formulation against the project's own, on CONTACT's testbank decks built
from their profiles (issue 21, item 1).

Cases (tests/reference/contact_testbank, CONTACT open source revision 2707, Apache-2.0):

* ``groove_li`` cases 1-4: the R10 wheel (nominal radius 420 mm) rolling freely (FX = 0, the pitch
  solved) in grooves of 10.25 / 10.10 / 10.05 / 10.02 mm, FZ = 10 kN, mu = 0.3, DX = 0.095833 mm,
  DS = 0.25 mm.  Compared: pmax, contact area (elements x DX DS), the free-rolling pitch creepage
  omega R_nom / V - 1 (from CONTACT's VPITCH) and the developed normal force (CONTACT's TILDE_FN).
* ``mbench_conf`` case 1: S1002 on UIC 60 at y = 6.25 mm, yaw 24 mrad, Z_WS = 0.1720 mm prescribed,
  two patches (gauge corner -24 degrees, flange -70 degrees), DX = DS = 0.2 mm, full slip.  Compared
  per patch: overlap, FN, FX, FS (in CONTACT's "bar" frame: the patch forces rotated by CONTACT's
  reference angle), pmax, area; totals FX, FY, FZ on the rail in the track frame.

Variants ([model] keys): ``contact`` = influence "halfspace_planar" (CONTACT's conformal approach:
planar half-space numbers on the developed grid, CONTACT's rigid slip at the wheel's own surface
projected on the mid-plane, grids centred on the reference point); ``planar_surface_creep`` = the
same with the project's creep point (creepage "surface"); ``turned_contact_creep`` = the project's
turned frames with CONTACT's rigid slip; ``project`` = the project's default (influence "halfspace",
creepage "surface").  mbench_conf adds ``project_coupled`` (one strip over both patches, with their
elastic interaction).

Writes studies/out/contact_conformal/ (or --out): groove.csv, mbench.csv, summary.md, run.json
(``--cases mbench`` reruns one deck and keeps the other's CSV).

Run:  nice -n 5 python studies/contact_conformal.py [--quick]
      (full: 4 grooves x 4 variants + mbench x 4, about 20 min on the 2-core machine;
       --quick: groove 10.25 mm in CONTACT's formulation, about 20 s)
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import csv
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402

from conformal.cases.conformal import solve_wheel_rail_conformal  # noqa: E402
from conformal.contact_inp.deck import deck_scene  # noqa: E402
from conformal.scene import scene_from_dict  # noqa: E402

TB = ROOT / "tests" / "reference" / "contact_testbank"
NOMRAD = 420.0
#: groove_li.ref_out: VPITCH (rad/s), PMAX (N/mm2), NCON, TILDE_FN (N)
GROOVE_LI = {"1025": (-1.0002301, 530.2, 1187, 9915.0), "1010": (-1.0004411, 409.3, 1559, 9931.0),
             "1005": (-1.0006495, 348.7, 1843, 1.001e4), "1002": (-1.0009761, 296.8, 2265, 1.026e4)}
DX, DS = 0.095833, 0.25
#: mbench_conf.ref_out per patch: BAR_FN, BAR_FX, BAR_FS (N), PMAX, NCON, DELTCP (deg), APPROACH (mm)
MBENCH = [(8677.0, -573.0, -1669.0, 1075.0, 321, -24.25, 2.476e-2),
          (3310.0, -220.4, -626.1, 1195.0, 129, -70.01, 1.182e-2)]
MBENCH_TRACK = (-793.4, 4939.0, 1.032e4)
VARIANTS = {"contact": {"influence": "halfspace_planar"},
            "project": {"influence": "halfspace"},
            "planar_surface_creep": {"influence": "halfspace_planar", "creepage": "surface"},
            "turned_contact_creep": {"influence": "halfspace", "creepage": "wheel_surface"}}


GROOVE_CASE = {"1025": 1, "1010": 2, "1005": 3, "1002": 4}          # groove_li.inp, cases 1-4 (C3 = 2)


def groove_scene(radius: str, model: dict):
    """groove_li case of that groove, read from CONTACT's deck by ``conformal inp``'s reader
    (conformal.contact_inp.deck.deck_scene), the [model] keys replaced by ``model``."""
    raw = deck_scene(TB / "groove_li.inp", GROOVE_CASE[radius], **model)
    return scene_from_dict(raw, base_dir=TB, name=f"groove_li_{radius}")


def mbench_scene(model: dict, strips: str = "separate"):
    """mbench_conf case 1 from CONTACT's deck (Z_WS = 0.1720 mm prescribed: the approach from the
    first touch; friction 0.2, constant over both patches' angles), ``model`` and ``strips`` set."""
    raw = deck_scene(TB / "mbench_conf.inp", 1, **model)
    raw["grid"] = {**raw.get("grid", {}), "strips": strips}
    return scene_from_dict(raw, base_dir=TB, name="mbench_conf")


def pct(a: float, b: float) -> float:
    return 100.0 * (a / b - 1.0)


def groove_row(radius: str, variant: str) -> dict:
    vpitch, pmax, ncon, fn = GROOVE_LI[radius]
    t0 = time.perf_counter()
    r = solve_wheel_rail_conformal(groove_scene(radius, VARIANTS[variant]))
    e = r.extra
    xi = -e["pitch_velocity_solved"] - 1.0            # omega R_nom / V - 1 with R_nom = V / 1 rad/s
    xi_ref = -vpitch - 1.0
    return {"groove": radius, "variant": variant, "pitch_creepage": xi, "ref_pitch_creepage": xi_ref,
            "err_pitch_pct": pct(xi, xi_ref), "pmax": r.pmax, "ref_pmax": pmax, "err_pmax_pct": pct(r.pmax, pmax),
            "area": e["contact_area"], "ref_area": ncon * DX * DS, "err_area_pct": pct(e["contact_area"], ncon * DX * DS),
            "FN": r.FN, "ref_FN": fn, "err_FN_pct": pct(r.FN, fn), "wall_s": time.perf_counter() - t0}


def mbench_rows(variant: str, model: dict, strips: str) -> list[dict]:
    t0 = time.perf_counter()
    r = solve_wheel_rail_conformal(mbench_scene(model, strips))
    wall = time.perf_counter() - t0
    rows = []
    if strips == "separate":
        for k, (p, ref) in enumerate(zip(sorted(r.patches, key=lambda q: -q.FN), MBENCH)):
            fn, fx, fs, pmax, ncon, dref, pen = ref
            d = math.radians(dref)
            FY, FZ = p.extra["FY_track"], p.extra["FZ_track"]
            bar_fn, bar_fs = FZ * math.cos(d) - FY * math.sin(d), FY * math.cos(d) + FZ * math.sin(d)
            mid = 0.5 * (p.extra["contact_angle_min"] + p.extra["contact_angle_max"])
            rows.append({"variant": variant, "item": f"patch {k + 1}", "overlap": p.extra["overlap_max"],
                         "dx": p.extra["grid"]["dx"], "ds": p.extra["grid"]["ds"],
                         "err_overlap_pct": pct(p.extra["overlap_max"], pen), "angle_deg": math.degrees(mid),
                         "ref_angle_deg": dref, "FN": bar_fn, "err_FN_pct": pct(bar_fn, fn), "FX": p.FX,
                         "err_FX_pct": pct(p.FX, fx), "FS": bar_fs, "err_FS_pct": pct(bar_fs, fs), "pmax": p.pmax,
                         "err_pmax_pct": pct(p.pmax, pmax),
                         "n_contact": round(p.extra["contact_area"] / (p.extra["grid"]["dx"] * p.extra["grid"]["ds"])),
                         "ref_n_contact": ncon, "wall_s": wall})
    for key, ref in zip(("FX_track", "FY_track", "FZ_track"), MBENCH_TRACK):
        rows.append({"variant": variant, "item": key, "FN": r.extra[key], "err_FN_pct": pct(r.extra[key], ref),
                     "wall_s": wall})
    return rows


def write_csv(path: Path, rows: list[dict]) -> None:
    keys = list(dict.fromkeys(k for row in rows for k in row))
    tmp = path.with_suffix(".tmp")
    with tmp.open("w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, path)


def read_csv(path: Path) -> list[dict]:
    """Rows of a CSV written by :func:`write_csv`, numbers as floats (empty cells as None)."""
    def value(v: str):
        if v == "":
            return None
        try:
            return float(v)
        except ValueError:
            return v

    with path.open(newline="", encoding="utf-8") as fh:
        rows = [{k: value(v) for k, v in row.items()} for row in csv.DictReader(fh)]
    for row in rows:        # identifiers stay text
        for key in ("groove", "variant", "item"):
            if key in row and isinstance(row[key], float):
                row[key] = str(int(row[key]))
    return rows


def summary(groove: list[dict], mbench: list[dict]) -> str:
    lines = ["# CONTACT's conformal formulation against the project's (studies/contact_conformal.py)", "",
             "Deviation from CONTACT's printed results (%), geometry built from the profiles by this project.", "",
             "## groove_li (free rolling, FX = 0)", "",
             "| groove | variant | pitch creepage | err % | pmax err % | area err % | FN err % |", "|---|---|---|---|---|---|---|"]
    for r in groove:
        lines.append(f"| R {int(r['groove']) / 100:.2f} | {r['variant']} | {float(r['pitch_creepage']):.4e} | "
                     f"{r['err_pitch_pct']:+.2f} | {r['err_pmax_pct']:+.2f} | {r['err_area_pct']:+.2f} | "
                     f"{r['err_FN_pct']:+.2f} |")
    if mbench:
        lines += ["", "## mbench_conf case 1 (two patches, separate strips; FN, FS in CONTACT's bar frame)", "",
                  "| variant | item | FN / force | err % | FX err % | FS err % | pmax err % | elements (CONTACT) | overlap err % |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for r in mbench:
            if r["item"].startswith("patch"):
                lines.append(f"| {r['variant']} | {r['item']} | {r['FN']:.1f} | {r['err_FN_pct']:+.2f} | "
                             f"{r['err_FX_pct']:+.2f} | {r['err_FS_pct']:+.2f} | {r['err_pmax_pct']:+.2f} | "
                             f"{int(r['n_contact'])} ({int(r['ref_n_contact'])}) | {r['err_overlap_pct']:+.2f} |")
            else:
                lines.append(f"| {r['variant']} | {r['item']} | {r['FN']:.1f} | {r['err_FN_pct']:+.2f} | | | | | |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=None,
                    help="output folder (default studies/out/contact_conformal; with --quick a temporary folder)")
    ap.add_argument("--quick", action="store_true", help="groove 10.25 mm in CONTACT's formulation only")
    ap.add_argument("--cases", default="groove,mbench",
                    help="which decks to run (groove, mbench); the other's CSV in the output folder is kept")
    ap.add_argument("--variants", default=None,
                    help="comma-separated variants to rerun (e.g. project,turned_contact_creep,project_coupled); "
                         "the other variants' rows are kept from the CSVs in the output folder")
    args = ap.parse_args(argv)
    cases = set(args.cases.split(","))
    out = output_dir("contact_conformal", args)
    out.mkdir(parents=True, exist_ok=True)
    grooves = ("1025",) if args.quick else tuple(GROOVE_LI)
    variants = ("contact",) if args.quick else tuple(VARIANTS)
    rerun = set(args.variants.split(",")) if args.variants else None
    if rerun is not None:
        unknown = rerun - set(VARIANTS) - {"project_coupled"}
        if unknown:
            ap.error(f"unknown variants {sorted(unknown)}; known: {list(VARIANTS) + ['project_coupled']}")
        variants = tuple(v for v in variants if v in rerun)

    def kept(name):
        if rerun is None or not (out / name).is_file():
            return []
        return [r for r in read_csv(out / name) if r["variant"] not in rerun]

    groove = []
    if "groove" in cases:
        groove = kept("groove.csv")
        for v in variants:
            for radius in grooves:
                groove.append(groove_row(radius, v))
                print("groove", groove[-1], flush=True)
        groove.sort(key=lambda r: (-int(r["groove"]), list(VARIANTS).index(r["variant"])))
        write_csv(out / "groove.csv", groove)
    elif (out / "groove.csv").is_file():
        groove = read_csv(out / "groove.csv")
    mbench = []
    if not args.quick and "mbench" not in cases and (out / "mbench.csv").is_file():
        mbench = read_csv(out / "mbench.csv")
    elif not args.quick:
        mbench = kept("mbench.csv")
        for v in variants:
            mbench += mbench_rows(v, VARIANTS[v], "separate")
            print("mbench", mbench[-5:], flush=True)
        if rerun is None or "project_coupled" in rerun:
            mbench += mbench_rows("project_coupled", VARIANTS["project"], "coupled")
        order = list(VARIANTS) + ["project_coupled"]
        mbench.sort(key=lambda r: order.index(r["variant"]))
        write_csv(out / "mbench.csv", mbench)
    text = summary(groove, mbench)
    tmp = out / "summary.md.tmp"
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, out / "summary.md")
    write_sidecar(out, __file__, vars(args), extra={"summary": {
        "groove_pitch_err_pct": {f"{r['groove']}:{r['variant']}": round(float(r["err_pitch_pct"]), 3) for r in groove}}})
    print(text)


if __name__ == "__main__":
    main()
