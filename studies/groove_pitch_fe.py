"""The free-rolling pitch in the Li groove with FE influence numbers: which half-space formulation
the real elastic bodies support.

CONTACT's testbank deck ``groove_li`` cases 1-4 (tests/reference/contact_testbank, CONTACT open
source revision 2707, Apache-2.0): the R10 wheel (nominal radius 420 mm) rolling freely (FX = 0,
the pitch solved) in grooves of 10.25 / 10.10 / 10.05 / 10.02 mm, FZ = 10 kN, mu = 0.3, CONTACT's
grid DX = 0.095833 mm by DS = 0.25 mm.  Every formulation runs on the same grid (an element
centred on the reference point) with the same rigid slip (CONTACT's, ``[model] creepage =
"wheel_surface"``), so only the influence numbers differ.  The one patch is solved on the coupled
strip (``[grid] strips = "coupled"``; the deck's separate strip gives the same planar solution to
every printed digit, but its grid is rebuilt from each pitch step's contact, and a grid that moves
in its last bits is a new FE cache key: minutes of FE per step):

* ``planar``: ``influence = "halfspace_planar"`` (CONTACT's C3 = 2: planar half-space numbers on the
  developed grid);
* ``blanco3``: ``halfspace_blanco``, variant 3 (CONTACT's C3 = 4);
* ``blanco4``: ``halfspace_blanco``, variant 4 = the project's turned frames (``halfspace``, to 1e-16);
* ``fe``: ``influence = "fe"``, the converged defaults (split, P1, ``fe_body_size`` 16, closure
  ``"extend"``), the wheel and the rail meshed from the deck's profiles;
* ``fe_fine``: the FE mesh refined (``fe_h_patch`` 1, ``fe_h_load`` 0.25, half the default sizes;
  on the 10.25 mm groove at twice CONTACT's element sizes this run ends in a segmentation fault
  inside a compiled library); ``fe_fine_patch``: ``fe_h_patch`` 1 alone; ``fe_big``:
  ``fe_body_size`` 32.

Also ``default``: the project's default model (``influence = "halfspace"`` with its own creep
point and grid placement), as a user gets it; and the coupling decomposition (:data:`MIXED`,
:func:`mixed_kernel`): the FE kernel without its normal-tangential coupling (``fe_uncoupled``),
without the x-n terms alone (``fe_without_xn``: u_x due to p_n, u_n due to p_x) or the s-n terms
alone (``fe_without_sn``), with Blanco's variant 3 or 4 coupling in place of its own
(``fe_blanco3_coupling``, ``fe_blanco4_coupling``), and variant 4 with the FE coupling
(``blanco4_fe_coupling``).

Per row: the free-rolling pitch creepage omega R_nom / V - 1 (CONTACT's VPITCH), pmax, the
contact area, the developed normal force, elements in adhesion and the spin moment MZ at free
rolling; deviations against CONTACT's printed results and against the FE bodies.  The FE rows
carry the bodies really built (disc radius, margin asked and made, closure at each end).

Writes studies/out/groove_pitch_fe/ (or --out): groove_pitch_fe.csv, groove_pitch_fe.md, run.json.
Rows already in the CSV of the output folder are kept unless rerun (--grooves, --forms).

Run:  nice -n 5 python studies/groove_pitch_fe.py [--quick]
      (full: 4 grooves x 5 forms, FE numbers about 3-6 min per groove with an empty cache on the
       2-core machine, each solve about 1 min; --quick: the 10.25 mm groove on a grid of twice
       CONTACT's element sizes, QUICK_FORMS, about 70 s with an empty FE cache)
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import math
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from contact_conformal import GROOVE_LI, groove_scene, pct, read_csv, write_csv  # noqa: E402

from conformal.cases.conformal import solve_wheel_rail_conformal  # noqa: E402

CREEP = {"creepage": "wheel_surface"}
FORMS = {"planar": {"influence": "halfspace_planar", **CREEP},
         "blanco3": {"influence": "halfspace_blanco", "blanco_variant": 3, **CREEP},
         "blanco4": {"influence": "halfspace_blanco", "blanco_variant": 4, **CREEP},
         "fe": {"influence": "fe", **CREEP},
         "fe_fine": {"influence": "fe", "fe_h_patch": 1.0, "fe_h_load": 0.25, **CREEP},
         "fe_fine_patch": {"influence": "fe", "fe_h_patch": 1.0, **CREEP},
         "fe_big": {"influence": "fe", "fe_body_size": 32.0, **CREEP},
         "default": {"influence": "halfspace"},
         # the FE kernel with its normal-tangential coupling terms (u_n due to p_x, p_s and u_x, u_s due to
         # p_n) removed or replaced by the half-space variant's, and the other way round (:func:`mixed_kernel`)
         "fe_uncoupled": {"influence": "fe", **CREEP},
         "fe_blanco3_coupling": {"influence": "fe", **CREEP},
         "fe_blanco4_coupling": {"influence": "fe", **CREEP},
         "blanco4_fe_coupling": {"influence": "fe", **CREEP},
         "fe_without_xn": {"influence": "fe", **CREEP},
         "fe_without_sn": {"influence": "fe", **CREEP}}
#: mixed forms: (kernel, coupling terms from (None: zero), tangential components replaced: 0 = x, 1 = s)
MIXED = {"fe_uncoupled": ("fe", None, (0, 1)), "fe_blanco3_coupling": ("fe", 3, (0, 1)),
         "fe_blanco4_coupling": ("fe", 4, (0, 1)), "blanco4_fe_coupling": (4, "fe", (0, 1)),
         "fe_without_xn": ("fe", None, (0,)), "fe_without_sn": ("fe", None, (1,))}
MAIN_FORMS = ("planar", "blanco3", "blanco4", "fe", "default")
#: CONTACT's element sizes DX, DS of the deck (mm)
DX, DS = 0.095833, 0.25
#: --quick: twice CONTACT's element sizes (a quarter of the elements), the 10.25 mm groove
QUICK_SCALE = 2.0
QUICK_FORMS = ("fe", "planar", "blanco4", "fe_without_xn", "fe_blanco3_coupling")


@contextmanager
def mixed_kernel(form: str):
    """Within the block, ``influence = "fe"`` solves with the mixed kernel of ``form`` (:data:`MIXED`):
    the FE two-body kernel or Blanco's variant 3 / 4 of the planar half-space numbers on the same
    grid, its coupling terms K[..., n, t] and K[..., t, n] (t = x, s or both) replaced by another's
    (or zero).
    A study device: conformal.influence.fe.wheel_rail_kernel is wrapped for the block."""
    if form not in MIXED:
        yield
        return
    import conformal.influence.fe as fe
    from conformal.influence.blanco import blanco_kernel
    from conformal.influence.curved import curved_halfspace_kernel

    base, coupling, comps = MIXED[form]
    original = fe.wheel_rail_kernel

    def wrapped(grid, material, *args, **kw):
        k_fe, info = original(grid, material, *args, **kw)
        planar = curved_halfspace_kernel(grid.mx, grid.dx, grid.s - grid.s_ref, grid.ds, grid.delta, material,
                                         angle_correction=False)
        kernels = {"fe": k_fe, 3: blanco_kernel(planar, np.asarray(grid.delta, float), 3),
                   4: blanco_kernel(planar, np.asarray(grid.delta, float), 4)}
        k = kernels[base].copy()
        c = None if coupling is None else kernels[coupling]
        for t in comps:
            k[..., 2, t] = 0.0 if c is None else c[..., 2, t]
            k[..., t, 2] = 0.0 if c is None else c[..., t, 2]
        return k, info

    fe.wheel_rail_kernel = wrapped
    try:
        yield
    finally:
        fe.wheel_rail_kernel = original


def _body(fe: dict | None, which: str) -> dict:
    b = ((fe or {}).get(which) or {}).get("body") or {}
    return {f"{which}_{k}": b.get(k) for k in ("disc_radius_mm", "margin_mm", "margin_requested_mm",
                                                 "margin_limited_by", "closure_lo", "closure_hi")}


def row(radius: str, form: str, scale: float = 1.0) -> dict:
    """One free-rolling solve of groove ``radius`` with formulation ``form``."""
    scene = groove_scene(radius, FORMS[form]).with_("grid.strips", "coupled")
    if scale != 1.0:
        scene = scene.with_(geometry__element_size=DX * scale, geometry__element_size_s=DS * scale)
    t0 = time.perf_counter()
    with mixed_kernel(form):
        r = solve_wheel_rail_conformal(scene)
    e = r.extra
    vpitch, pmax, ncon, fn = GROOVE_LI[radius]
    xi = -e["pitch_velocity_solved"] - 1.0          # omega R_nom / V - 1, R_nom = V / (1 rad/s)
    xi_ref = -vpitch - 1.0
    out = {"groove": radius, "form": form, "scale": scale, "pitch_creepage": xi, "err_pitch_contact_pct": pct(xi, xi_ref),
           "pmax": r.pmax, "err_pmax_contact_pct": pct(r.pmax, pmax), "area": e["contact_area"],
           "err_area_contact_pct": pct(e["contact_area"], ncon * DX * DS), "FN": r.FN, "FX": r.FX,
           "MZ": e.get("MZ_3d"), "n_adhesion": e.get("n_adhesion"), "pitch_solves": e.get("pitch_solves"),
           "wall_s": time.perf_counter() - t0}
    if FORMS[form]["influence"] == "fe":
        out.update(_body(e.get("fe"), "rail"))
        out.update(_body(e.get("fe"), "wheel"))
    return out


def with_fe_deviation(rows: list[dict]) -> list[dict]:
    """Each row's deviation from the FE row (form ``fe``) of the same groove and scale."""
    ref = {(r["groove"], float(r["scale"])): r for r in rows if r["form"] == "fe"}
    for r in rows:
        f = ref.get((r["groove"], float(r["scale"])))
        for key in ("pitch_creepage", "pmax", "area"):
            r[f"dev_{key}_fe_pct"] = None if f is None else pct(float(r[key]), float(f[key]))
    return rows


def summary(rows: list[dict]) -> str:
    lines = ["# Free rolling in the Li groove with FE influence numbers (studies/groove_pitch_fe.py)", "",
             "CONTACT's groove_li (R10 wheel, 10 kN, mu = 0.3), its grid and rigid slip for every "
             "formulation but `default`.  Deviations in %.", "",
             "| groove | form | grid | pitch creepage | vs FE | vs CONTACT | pmax | vs FE | area (mm²) | vs FE | FN (N) "
             "| adhesion | MZ (N mm) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]

    def f(v, fmt):
        return "" if v is None or (isinstance(v, float) and math.isnan(v)) else format(float(v), fmt)

    for r in rows:
        grid = "CONTACT's" if float(r["scale"]) == 1.0 else f"{float(r['scale']):g} x CONTACT's"
        lines.append(f"| R {int(r['groove']) / 100:.2f} | {r['form']} | {grid} | {float(r['pitch_creepage']):.4e} | "
                     f"{f(r['dev_pitch_creepage_fe_pct'], '+.2f')} | {float(r['err_pitch_contact_pct']):+.2f} | "
                     f"{float(r['pmax']):.1f} | {f(r['dev_pmax_fe_pct'], '+.2f')} | {float(r['area']):.3f} | "
                     f"{f(r['dev_area_fe_pct'], '+.2f')} | {float(r['FN']):.0f} | {f(r['n_adhesion'], '.0f')} | "
                     f"{f(r['MZ'], '.1f')} |")
    bodies = [r for r in rows if str(r["form"]).startswith("fe")]
    if bodies:
        lines += ["", "FE bodies built (disc radius / margin made of asked, mm; closure at the two ends):", "",
                  "| groove | form | rail | wheel |", "|---|---|---|---|"]
        for r in bodies:
            def b(w):
                return (f"{f(r[w + '_disc_radius_mm'], '.1f')} / {f(r[w + '_margin_mm'], '.1f')} of "
                        f"{f(r[w + '_margin_requested_mm'], '.1f')} ({r[w + '_closure_lo']}, {r[w + '_closure_hi']}"
                        + (f"; limited by {r[w + '_margin_limited_by']}" if r.get(w + "_margin_limited_by") else "")
                        + ")")
            lines.append(f"| R {int(r['groove']) / 100:.2f} | {r['form']} | {b('rail')} | {b('wheel')} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=None,
                    help="output folder (default studies/out/groove_pitch_fe; with --quick a temporary folder)")
    ap.add_argument("--quick", action="store_true",
                    help="10.25 mm groove on twice CONTACT's element sizes: " + ", ".join(QUICK_FORMS))
    ap.add_argument("--grooves", default=",".join(GROOVE_LI), help="grooves to (re)run: 1025,1010,1005,1002")
    ap.add_argument("--forms", default=",".join(MAIN_FORMS),
                    help=f"formulations to (re)run, of {list(FORMS)}")
    ap.add_argument("--scale", type=float, default=None,
                    help=f"element sizes in units of CONTACT's DX, DS (default 1; --quick {QUICK_SCALE:g})")
    args = ap.parse_args(argv)
    out = output_dir("groove_pitch_fe", args)
    out.mkdir(parents=True, exist_ok=True)
    grooves = ("1025",) if args.quick else tuple(args.grooves.split(","))
    forms = QUICK_FORMS if args.quick else tuple(args.forms.split(","))
    bad = [g for g in grooves if g not in GROOVE_LI] + [f for f in forms if f not in FORMS]
    if bad:
        print(f"groove_pitch_fe: unknown groove or form {bad}; grooves {list(GROOVE_LI)}, forms {list(FORMS)}",
              file=sys.stderr)
        return 2
    scale = args.scale or (QUICK_SCALE if args.quick else 1.0)
    if not 0.5 <= scale <= 4.0:
        print(f"groove_pitch_fe: --scale must lie in [0.5, 4], got {scale:g}", file=sys.stderr)
        return 2
    path = out / "groove_pitch_fe.csv"
    rows = [r for r in read_csv(path) if not (r["groove"] in grooves and r["form"] in forms
                                              and float(r["scale"]) == scale)] \
        if path.is_file() and not args.quick else []
    order = list(FORMS)
    for g in grooves:
        for form in forms:
            rows.append(row(g, form, scale))
            print("row", rows[-1], flush=True)
            rows.sort(key=lambda r: (float(r["scale"]), -int(r["groove"]), order.index(r["form"])))
            write_csv(path, with_fe_deviation(rows))          # each row as it comes (FE rows take minutes)
    text = summary(rows)
    tmp = out / "groove_pitch_fe.md.tmp"
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, out / "groove_pitch_fe.md")
    write_sidecar(out, __file__, vars(args), extra={"summary": {
        f"{r['groove']}:{r['form']}:{float(r['scale']):g}": {"pitch_vs_fe_pct": None if r["dev_pitch_creepage_fe_pct"] is None
                                       else round(float(r["dev_pitch_creepage_fe_pct"]), 3),
                                       "pmax_vs_fe_pct": None if r["dev_pmax_fe_pct"] is None
                                       else round(float(r["dev_pmax_fe_pct"]), 3)} for r in rows}})
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
