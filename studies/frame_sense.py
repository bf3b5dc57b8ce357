"""Which sense of the turn between element frames the FE bodies have (issue 21, frames21).

The curved half-space numbers with turned element frames (``influence = "halfspace"``,
conformal.influence.curved) and Blanco-Lorenzo's split correction (``halfspace_blanco``, variant
4: CONTACT's C3 = 4) are the same formula R(a/2) A R(a/2) with the angle a of opposite sign in the
project before frames21.  Identical materials make the half-space numbers A free of any
normal-tangential coupling, so the turn is the only source of the coupling terms A_ns (u_n at I
due to p_s at J) and A_sn; its sense decides their sign.  The FE numbers of the real bodies
(``influence = "fe"``, the default settings) carry the real geometry and serve as referee:

* the kernels: A_nn, A_ns, A_sn of element pairs at different contact angles (offset kx = 0);
* the solutions at the prescribed approach (FN, pmax, FX) and at a prescribed load (the FE FN:
  pmax, area, approach), each with the five kernels planar, turned (+: the project's sense before
  frames21; -: after, = Blanco 4), Blanco 3 and FE;
* the coupling alone: the FE kernel with its own coupling terms removed, and replaced by those of
  either turned kernel (FN with the FE A_nn, A_ss).

Cases: the deep pair (R10 rail corner against a R10.2 flange root, 0.05 mm) and a R10 wheel in a
R10.05 groove (0.01 mm) of studies/fe_far_field_limit.py, on an n x n grid (default 12).

    python studies/frame_sense.py            # both cases, n = 12 (about 3 min with an empty FE cache)
    python studies/frame_sense.py --quick    # the deep pair, n = 8 (about 30 s)

Output: studies/out/frame_sense/frame_sense.{md,json} and run.json.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402


def _kernels(case) -> dict:
    from conformal.influence.blanco import blanco_kernel
    from conformal.influence.curved import _rotate_pairs, curved_halfspace_kernel
    from conformal.influence.fe import FESettings

    g, m = case.problem.grid, case.material
    P = curved_halfspace_kernel(g.mx, g.dx, g.s - g.s_ref, g.ds, g.delta, m, angle_correction=False)
    a = 0.5 * (g.delta[None, :] - g.delta[:, None])            # [I, J]: (delta_J - delta_I) / 2
    kr, kw, _ = case.kernels(FESettings(), case.cache)
    return {"planar": P, "turned+ (before)": _rotate_pairs(P, -a), "turned- (now)": _rotate_pairs(P, a),
            "blanco3": blanco_kernel(P, g.delta, 3), "blanco4": blanco_kernel(P, g.delta, 4), "fe": kr + kw}


def _swap_coupling(K, C=None):
    K = K.copy()
    K[..., 2, :2] = 0.0 if C is None else C[..., 2, :2]
    K[..., :2, 2] = 0.0 if C is None else C[..., :2, 2]
    return K


def _solve(problem, K) -> dict:
    from conformal.influence.curved import CurvedInfluence
    from conformal.solvers.conformal import solve_curved

    r = solve_curved(problem, CurvedInfluence.from_kernel(K), {"influence": "study"})
    g = problem.grid
    area = float(((np.asarray(r.field.pn) > 0) * (g.dx * np.asarray(g.ds))[None, :]).sum())
    return {"FN": float(r.FN), "FX": float(r.FX), "pmax": float(r.pmax), "area": area,
            "approach": float(r.approach), "n_contact": int(r.n_contact or 0), "converged": bool(r.converged)}


def run_case(key: str, n: int, tmp: Path, cache) -> dict:
    import fe_far_field_limit as F

    case = F.Case(key, tmp, n)
    case.cache = cache
    g = case.problem.grid
    K = _kernels(case)
    k0 = g.mx - 1
    ms = g.ms
    pairs = [(ms // 2, ms // 2 + d) for d in (1, 2, 4) if ms // 2 + d < ms] + [(ms // 2 + ms // 4, ms // 2 - ms // 4)]
    kern = [{"I": I, "J": J, "dI_minus_dJ_deg": float(np.degrees(g.delta[I] - g.delta[J])),
             **{name: {"nn": float(A[k0, I, J, 2, 2]), "ns": float(A[k0, I, J, 2, 1]), "sn": float(A[k0, I, J, 1, 2])}
                for name, A in K.items()}} for I, J in pairs]
    at_approach = {name: _solve(case.problem, A) for name, A in K.items()}
    load = at_approach["fe"]["FN"]
    loaded = replace(case.problem, normal_force=load, approach=None)
    at_load = {name: _solve(loaded, A) for name, A in K.items()}
    coupling = {"fe": at_approach["fe"]["FN"],
                "fe uncoupled": _solve(case.problem, _swap_coupling(K["fe"]))["FN"],
                "fe + coupling of turned+": _solve(case.problem, _swap_coupling(K["fe"], K["turned+ (before)"]))["FN"],
                "fe + coupling of turned-": _solve(case.problem, _swap_coupling(K["fe"], K["turned- (now)"]))["FN"]}
    return {"key": key, "label": case.label, "n": n, "delta_deg": [float(v) for v in np.degrees(g.delta)],
            "kernel_pairs": kern, "at_approach": at_approach, "load": load, "at_load": at_load,
            "coupling_FN": coupling, "warning": case.warning}


def _pct(v, ref):
    return f"{100.0 * (v / ref - 1.0):+.2f} %"


def report(rows) -> str:
    out = ["# The sense of the turned element frames against the FE bodies", "",
           "Kernel entries at offset kx = 0 (mm/N per element load; u_n at I due to p_s at J = ns, "
           "u_s at I due to p_n at J = sn); identical materials.", ""]
    for r in rows:
        out += [f"## {r['label']} (n = {r['n']}, contact angles {r['delta_deg'][0]:.1f} .. {r['delta_deg'][-1]:.1f} deg)", "",
                "| I, J | dI - dJ (deg) | kernel | nn | ns | sn |", "|---|---|---|---|---|---|"]
        for p in r["kernel_pairs"]:
            for name in ("planar", "turned+ (before)", "turned- (now)", "blanco3", "fe"):
                e = p[name]
                out.append(f"| {p['I']}, {p['J']} | {p['dI_minus_dJ_deg']:+.1f} | {name} | {e['nn']:.3e} | {e['ns']:+.3e} | {e['sn']:+.3e} |")
        fe_a, fe_l = r["at_approach"]["fe"], r["at_load"]["fe"]
        out += ["", f"At the prescribed approach (FN against FE) and at the load FN = {r['load']:.0f} N (pmax, area, "
                "approach against FE):", "",
                "| kernel | FN | FN vs FE | FX | pmax @load | vs FE | area @load (mm2) | vs FE | approach @load | vs FE |",
                "|---|---|---|---|---|---|---|---|---|---|"]
        for name, a in r["at_approach"].items():
            b = r["at_load"][name]
            out.append(f"| {name} | {a['FN']:.0f} | {_pct(a['FN'], fe_a['FN'])} | {a['FX']:.0f} | {b['pmax']:.1f} | "
                       f"{_pct(b['pmax'], fe_l['pmax'])} | {b['area']:.3f} | {_pct(b['area'], fe_l['area'])} | "
                       f"{b['approach']:.5f} | {_pct(b['approach'], fe_l['approach'])} |")
        c = r["coupling_FN"]
        out += ["", "The coupling alone (FE A_nn, A_ss; coupling terms swapped), FN at the approach:", ""]
        out += [f"- {k}: {v:.1f} N ({_pct(v, c['fe'])})" for k, v in c.items()]
        if r["warning"]:
            out += ["", f"Warning: {r['warning']}."]
        out.append("")
    return "\n".join(out)


def main(argv=None) -> int:
    from conformal.influence.cache import Cache

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the deep pair, n = 8")
    ap.add_argument("--n", type=int, default=12)
    ap.add_argument("--cases", default="deep,groove")
    ap.add_argument("--cache", default=None, help="FE cache folder (default: a temporary one)")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    out = output_dir("frame_sense", args)
    cases, n = (["deep"], 8) if args.quick else (args.cases.split(","), args.n)
    with tempfile.TemporaryDirectory() as tmp:
        cache = Cache(args.cache or os.path.join(tmp, "cache"))
        rows = [run_case(k, n, Path(tmp), cache) for k in cases]
    md = report(rows)
    for name, text in (("frame_sense.md", md), ("frame_sense.json", json.dumps(rows, indent=1))):
        part = out / (name + ".part")
        part.write_text(text, encoding="utf-8")
        os.replace(part, out / name)
    write_sidecar(out, __file__, args, extra={"cases": cases, "n": n})
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
