"""``conformal stresses SCENE.toml``: solve a scene, then the half-space subsurface stresses of
every contact patch (body 1, the rail), their maxima and the fatigue indices (issue 24, item 4).

The scene may carry a ``[stresses]`` section (read here, not by the scene loader):

    [stresses]
    k = 300.0          # yield stress in shear (N/mm²), shakedown map (FI_surf)
    alpha_dv = 0.333   # Dang Van hydrostatic sensitivity
    tau_e = 300.0      # shear endurance limit (N/mm²)
    depth = 2.0        # deepest plane (mm); default twice the smaller semi-axis of each patch
    n_depths = 40      # planes from the surface to depth
    body = 1           # 1: the rail (body 1), 2: the wheel
    fe_body = true     # theory "conformal" with influence "fe": also the stresses inside the FE body
                       # (one FE solve with the final load) on the cross-section through the
                       # half-space maximum (default: true for influence = "fe", else false);
                       # true: the stressed body (`body`), or "rail", "wheel", "both"; with
                       # --vtu OUT.vtu the FE body's stresses go to OUT_fe_rail.vtu / OUT_fe_wheel.vtu
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from conformal.errors import InputError
from conformal.files import write_text
from conformal.registry import FE_INFLUENCE, MODELS
from conformal.result import _jsonable
from conformal.scene import read_scene_file, scene_from_dict
from conformal.stresses.fatigue import (ALPHA_DV, K_SHEAR, TAU_E, FatigueParameters, dang_van, surface_index,
                                       surface_index_area)
from conformal.stresses.field import N_DEPTHS, default_depths, stress_field

_KEYS = {"k", "alpha_dv", "tau_e", "depth", "n_depths", "body", "fe_body"}


def read_scene_with_stresses(path: str | Path):
    """(scene, options) of a TOML scene with an optional ``[stresses]`` section."""
    path = Path(path)
    data = read_scene_file(path)
    opts = data.pop("stresses", {})
    if not isinstance(opts, dict):
        raise InputError(f"[stresses] must be a table, got stresses = {opts!r}")
    bad = sorted(set(opts) - _KEYS)
    if bad:
        raise InputError(f"[stresses] {bad[0]}: unknown key (known: {', '.join(sorted(_KEYS))})")
    check_options(opts)
    return scene_from_dict(data, base_dir=path.parent, name=path.stem), dict(opts)


def check_options(opts: dict) -> None:
    """Check the ``[stresses]`` values before anything is solved (InputError naming the key)."""
    FatigueParameters(k=_number(opts, "k", K_SHEAR), alpha_dv=_number(opts, "alpha_dv", ALPHA_DV),
                      tau_e=_number(opts, "tau_e", TAU_E))
    depth = _number(opts, "depth", None)
    if depth is not None and not depth > 0:
        raise InputError(f"[stresses] depth: must be a positive number of mm, got {depth!r}")
    if opts.get("body", 1) not in (1, 2) or isinstance(opts.get("body"), bool):
        raise InputError(f"[stresses] body: must be 1 or 2, got {opts.get('body')!r}")
    n = opts.get("n_depths", N_DEPTHS)
    if isinstance(n, bool) or not isinstance(n, int) or not 2 <= n <= 2000:
        raise InputError(f"[stresses] n_depths: must be an integer in [2, 2000], got {n!r}")


def _positive_option(value, option: str, unit: str):
    """A command-line number that must be finite and > 0 (InputError naming the option)."""
    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(f"{option}: must be a positive number of {unit}, got {value!r}")
    return value


def _number(opts: dict, key: str, default):
    v = opts.get(key, default)
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(f"[stresses] {key}: must be a number, got {v!r}")
    return float(v)


def _finite_max(values) -> float:
    vals = [v for v in values if math.isfinite(v)]
    return max(vals) if vals else float("nan")


def patch_stresses(result, scene, opts: dict, vtu=None) -> tuple[dict, list]:
    """The JSON summary of the stresses of every patch of ``result`` and the StressFields;
    ``vtu`` (the --vtu path): the FE bodies' stresses go beside it as ``<stem>_fe_rail.vtu`` and
    ``<stem>_fe_wheel.vtu`` (``_patch<k>`` added when there are several patches)."""
    params = FatigueParameters(k=_number(opts, "k", K_SHEAR), alpha_dv=_number(opts, "alpha_dv", ALPHA_DV),
                               tau_e=_number(opts, "tau_e", TAU_E))
    body = opts.get("body", 1)
    if body not in (1, 2):
        raise InputError(f"[stresses] body: must be 1 or 2, got {body!r}")
    n_depths = opts.get("n_depths", N_DEPTHS)
    if isinstance(n_depths, bool) or not isinstance(n_depths, int):
        raise InputError(f"[stresses] n_depths: must be an integer, got {n_depths!r}")
    depth = _number(opts, "depth", None)
    nu = scene.material.nu1 if body == 1 else scene.material.nu2
    patches = [p for p in (result.patches or (result,)) if p.field is not None]
    if not patches:
        raise InputError(f"stresses: the {result.theory!r} result has no traction field; use a theory with a grid "
                         "(exact, conformal, fastsim, ...)")
    fields, rows = [], []
    for k, p in enumerate(patches):
        if not p.FN > 0:
            continue
        depths = default_depths(p.a, p.b, depth, n_depths)
        sf = stress_field(p.field, depths, nu=nu, body=body)
        row = {"patch": k, "FN": p.FN, "FX": p.FX, "FY": p.FY, "a": p.a, "b": p.b, "pmax": p.pmax}
        row.update(sf.summary(params))
        row["FI_surf"] = surface_index(p.FN, p.FX, p.FY, p.a, p.b, params.k)
        area = float(p.field.n_contact * np.mean(p.field.grid.area))
        row["contact_area"] = area
        row["FI_surf_equivalent"] = surface_index_area(p.FN, p.FX, p.FY, area, params.k)
        row["mu_eff"] = math.hypot(p.FX, p.FY) / p.FN
        fe_bodies = _fe_bodies(scene, result, opts, body)
        if fe_bodies:
            row["fe_bodies"] = {}
            for b in fe_bodies:
                who = "rail" if b == 1 else "wheel"
                sfb = sf if b == body else stress_field(p.field, depths, nu=scene.material.nu1 if b == 1
                                                        else scene.material.nu2, body=b)
                vp = None
                if vtu is not None:
                    vtu = Path(vtu)
                    vp = vtu.with_name(f"{vtu.stem}_fe_{who}" + (f"_patch{k}" if len(patches) > 1 else "") + ".vtu")
                row["fe_bodies"][who] = fe_body_section(p, scene, sfb, params, vtu=vp)
            row["fe_body"] = row["fe_bodies"]["rail" if fe_bodies[0] == 1 else "wheel"]   # the stressed body
        rows.append(row)
        fields.append(sf)
    if not rows:
        raise InputError("stresses: no patch carries a normal force")
    out: dict[str, Any] = {"scene": scene.name, "theory": result.theory, "FN": result.FN, "FX": result.FX,
                           "FY": result.FY, "nu": nu, "body": body, "units": {"stress": "N/mm²", "length": "mm"},
                           "model": "half-space (superposed closed-form rectangle fields, FFT per depth plane)"}
    for key in ("max_von_mises", "max_shear", "max_orthogonal_shear", "max_principal"):
        best = max(rows, key=lambda r: r[key])
        out[key] = best[key]
        if key + "_depth" in best:
            out[key + "_depth"] = best[key + "_depth"]
        out[key + "_position"] = best[key + "_position"]
        out[key + "_patch"] = best["patch"]
    dv = max(rows, key=lambda r: r["dang_van"]["tau_dv_max"])["dang_van"]
    out["fatigue"] = {"k": params.k, "alpha_dv": params.alpha_dv, "tau_e": params.tau_e,
                      "FI_surf": _finite_max(r["FI_surf"] for r in rows),
                      "FI_surf_equivalent": _finite_max(r["FI_surf_equivalent"] for r in rows),
                      "tau_dv_max": dv["tau_dv_max"], "tau_dv_depth": dv["depth"], "FI_sub": dv["FI_sub"]}
    fe_rows = [r for r in rows if "fe_body" in r]
    if fe_rows:
        best_fe = max(fe_rows, key=lambda r: r["max_von_mises"])
        out["fe_body"] = best_fe["fe_body"]
        out["fe_bodies"] = best_fe["fe_bodies"]
        # Dang Van in the FE bodies (the rolling pass through the FE rail / wheel), per body: the
        # patch with the largest tau_DV
        out["fatigue"]["fe_bodies"] = {
            who: max((r["fe_bodies"][who]["dang_van"]["fe"] for r in fe_rows if who in r["fe_bodies"]),
                     key=lambda d: d["tau_dv_max"])
            for who in sorted({w for r in fe_rows for w in r["fe_bodies"]})}
    out["frame"] = rows[0]["frame"]
    out["converged"] = bool(result.converged)     # the contact solve under the stresses
    out["patches"] = rows
    warnings = list(result.warnings)
    for r in rows:
        if not math.isfinite(r["FI_surf"]):
            warnings.append(f"patch {r['patch']}: FI_surf needs the semi-axes a and b of a 3-D patch")
        elif abs(math.pi * r["a"] * r["b"] - r["contact_area"]) > 0.1 * r["contact_area"]:
            warnings.append(f"patch {r['patch']}: the contact area {r['contact_area']:.3g} mm² differs from pi a b = "
                            f"{math.pi * r['a'] * r['b']:.3g} mm² of the extents: the patch is not elliptic; "
                            "FI_surf_equivalent uses the ellipse of equal area")
        if r["max_von_mises_depth"] >= r["depths"]["max"] * 0.999:
            warnings.append(f"patch {r['patch']}: the von Mises maximum lies at the deepest plane "
                            f"({r['depths']['max']:.3g} mm): give a larger --depth")
    out["warnings"] = list(dict.fromkeys(warnings))
    return _jsonable(out), fields


def _fe_bodies(scene, result, opts, body: int) -> tuple[int, ...]:
    """The FE bodies to compute: ``[stresses] fe_body`` true (the stressed body ``body``), false,
    "rail", "wheel" or "both"; default: the stressed body for influence = "fe", else none."""
    want = opts.get("fe_body", None)
    choices = {True: (body,), False: (), "rail": (1,), "wheel": (2,), "both": (1, 2)}
    if want is not None and (not isinstance(want, (bool, str)) or want not in choices):
        raise InputError(f"[stresses] fe_body: must be true, false, \"rail\", \"wheel\" or \"both\", got {want!r}")
    fe = MODELS.accepts(result.theory, FE_INFLUENCE) and scene.model.influence == "fe"
    if want not in (None, False) and not fe:
        raise InputError("[stresses] fe_body: needs [model] theory = \"conformal\" with influence = \"fe\"")
    if want is None:
        return (body,) if fe else ()
    bodies = choices[want]
    return tuple(sorted(bodies, key=lambda b: b != body))      # the stressed body first


def _section_maxima(sf) -> dict:
    out = {}
    for key, vals, use_abs in (("max_von_mises", sf.von_mises, False), ("max_shear", sf.principal_shear, False),
                               ("max_orthogonal_shear", sf.orthogonal_shear, True)):
        v = np.abs(vals) if use_abs else vals
        i = np.unravel_index(int(np.nanargmax(v)), v.shape)
        out[key] = float(v[i])
        out[key + "_depth"] = float(sf.depths[i[0]])
        out[key + "_position"] = [float(c) for c in sf.points[i]]
    return out


def fe_body_stress_section(result, scene, sf, body: int | None = None, vtu=None, block: bool = False):
    """(points, BodyStresses) inside the FE body (1: rail, 2: wheel; default the body of ``sf``;
    conformal.stresses.bodies): on the cross-section of the strip through the half-space von Mises
    maximum of ``sf`` (the StressField of that body; points (nd, 1, nc, 3)), or with ``block`` on
    the whole block of ``sf`` (the rolling pass, for Dang Van: the rail at the points of ``sf``,
    whose half-space part is ``sf.sigma``; the wheel on circles about its axle); ``vtu``: also write
    the FE body's stresses around the patch there (conformal.stresses.bodies.write_body_vtu)."""
    from conformal.cases.conformal import scene_profiles
    from conformal.influence.fe import settings_from_options
    from conformal.stresses.bodies import body_stresses

    body = sf.body if body is None else body
    if block:
        pts = sf.points
    else:
        x_i = int(np.unravel_index(int(np.nanargmax(sf.von_mises)), sf.von_mises.shape)[1])
        pts = sf.points[:, x_i:x_i + 1]
    rail_pts, wheel_pts = scene_profiles(scene)
    settings = settings_from_options(scene.model.options)
    field = result.field if result.field is not None else result.patches[0].field
    G, nu = (scene.material.G1, scene.material.nu1) if body == 1 else (scene.material.G2, scene.material.nu2)
    bs = body_stresses(field, pts, body=body, G=G, nu=nu, settings=settings,
                       profile_points=rail_pts if body == 1 else wheel_pts, vtu=vtu, rolling_block=block,
                       sigma_hs=sf.sigma if (block and body == 1 and sf.body == 1) else None)
    return pts, bs


def fe_body_section(result, scene, sf, params=None, figure=None, vtu=None) -> dict:
    """The maxima inside the FE body of ``sf`` (rail or wheel) on the cross-section through the
    half-space maximum and over the whole block with the Dang Van index of the rolling pass
    (:func:`fe_body_section_data`), against the half-space stresses of ``sf``; ``figure``: also
    write the comparison figure there and its 3-D view (pyvista) beside it as ``<stem>_3d.png``
    (:func:`fe_section_figures`); ``vtu``: the FE body's stresses around the patch for ParaView."""
    out, pts, bs, hs_sigma = fe_body_section_data(result, scene, sf, vtu=vtu, params=params)
    if figure is not None:
        fe_section_figures(result, scene, sf, pts, bs, hs_sigma, figure)
    return out


def fe_body_section_data(result, scene, sf, vtu=None, params=None):
    """(summary, section points, section BodyStresses, half-space sigma at the section points) of
    :func:`fe_body_section` without the figures (a study meshes every body before it draws with
    VTK: gmsh meshing after a VTK render in the same process has crashed the heap).

    One FE solve gives the FE body's stresses on the whole block of ``sf`` (the rolling pass):
    ``fe`` / ``halfspace`` are the maxima on the section through the half-space von Mises maximum,
    ``block`` the maxima of both over the whole block and ``dang_van`` the Dang Van index of both
    (tau_DV, its depth and position, FI_sub; ``params``: the FatigueParameters, default ones)."""
    from dataclasses import replace as _replace

    from conformal.stresses.bodies import BodyStresses
    from conformal.stresses.field import StressField

    params = params or FatigueParameters()
    pts_b, bb = fe_body_stress_section(result, scene, sf, vtu=vtu, block=True)
    x_i = int(np.unravel_index(int(np.nanargmax(sf.von_mises)), sf.von_mises.shape)[1])
    pts = pts_b[:, x_i:x_i + 1]
    bs = BodyStresses(pts, bb.sigma_hs[:, x_i:x_i + 1], bb.sigma_c[:, x_i:x_i + 1], bb.stats)
    who = "rail" if sf.body == 1 else "wheel"
    fe = StressField(bs.sigma, pts, sf.depths, sf.normal, sf.frame, sf.body)
    hs = _replace(fe, sigma=sf.sigma[:, x_i:x_i + 1])
    fe_block = StressField(bb.sigma, pts_b, sf.depths, sf.normal, sf.frame, sf.body)
    dv = {}
    for key, f in (("fe", fe_block), ("halfspace", sf)):
        sm = f.summary(params)
        d = sm["dang_van"]
        tau, at = dang_van(f.sigma, params.alpha_dv, axis=1)
        i = np.unravel_index(int(np.nanargmax(tau)), tau.shape)
        dv[key] = {"tau_dv_max": d["tau_dv_max"], "depth": d["depth"], "FI_sub": d["FI_sub"],
                   "position": [float(c) for c in f.points[i[0], int(at[i]), i[1]]]}
    out = {"body": who, "section_x": float(pts[0, 0, 0, 0]), "fe": _section_maxima(fe),
           "halfspace": _section_maxima(hs), "block": {"fe": _section_maxima(fe_block), "halfspace": _section_maxima(sf)},
           "dang_van": {"alpha_dv": params.alpha_dv, "tau_e": params.tau_e, **dv},
           "max_correction": float(np.abs(bs.sigma_c).max()),
           "max_correction_block": float(np.abs(bb.sigma_c).max()), "stats": bb.stats,
           "note": "sigma = half-space field of the elements on the body's tangent planes + FE correction of "
                   "the real body (split method, one FE solve with the final load), on the whole block of the "
                   "half-space field (the rolling pass; the wheel on circles about its axle, each line in its "
                   "co-rotating frame)"}
    return out, pts, bs, hs.sigma


def fe_section_figures(result, scene, sf, pts, bs, hs_sigma, figure) -> None:
    """The section figure (matplotlib: half-space, FE body, difference) at ``figure`` and its 3-D
    view (pyvista) at ``<stem>_3d.png``."""
    from pathlib import Path as _Path

    from conformal.stresses.invariants import von_mises
    from conformal.stresses.plots import plot_section_3d, plot_section_comparison

    who = "rail" if sf.body == 1 else "wheel"
    plot_section_comparison(pts[:, 0], hs_sigma[:, 0], bs.sigma[:, 0], figure,
                            title=f"{scene.name}: stresses in the {who} at x = {pts[0, 0, 0, 0]:.2f} mm",
                            surface=surface_curve(result), body_label=f"FE {who}")
    fig3d = _Path(figure).with_name(_Path(figure).stem + "_3d.png")   # the same section in 3-D (pyvista)
    plot_section_3d(result, pts[:, 0], von_mises(bs.sigma[:, 0]), fig3d,
                    title=f"{scene.name}: von Mises in the FE {who}, section x = {pts[0, 0, 0, 0]:.2f} mm",
                    body=who)


def surface_curve(result) -> np.ndarray | None:
    """The rail profile (y, z) around a conformal strip, for the cross-section figure."""
    f = result.field if result.field is not None else (result.patches[0].field if result.patches else None)
    g = getattr(f, "curved", None)
    return None if g is None else np.asarray(g.rail_curve, float)


# ----------------------------------------------------------------------------- the command
def cmd_stresses(args) -> int:
    """``conformal stresses SCENE.toml [--depth D] [--k K] [--vtu OUT.vtu] [--plot OUT.png] [--json OUT.json]``."""
    import json
    import sys

    from conformal.dispatch import solve_scene

    args.check_output(args.json, "--json", (".json",))
    args.check_output(args.plot, "--plot", args.plot_suffixes)
    args.check_output(args.vtu, "--vtu", (".vtu",))
    _positive_option(args.depth, "--depth", "mm")
    _positive_option(args.k, "--k", "N/mm²")
    scene, opts = read_scene_with_stresses(args.scene)
    if args.depth is not None:
        opts["depth"] = args.depth
    if args.k is not None:
        opts["k"] = args.k
    if args.body is not None:
        opts["body"] = args.body
    result = solve_scene(scene)
    summary, fields = patch_stresses(result, scene, opts, vtu=args.vtu)
    for w in summary["warnings"]:
        print(f"conformal: warning: {w}", file=sys.stderr)
    text = json.dumps(summary, indent=2)
    print(text)
    if args.json:
        write_text(args.json, text + "\n")
    best = int(np.argmax([r["max_von_mises"] for r in summary["patches"]]))
    code = 0
    if args.vtu:
        from conformal.stresses.plots import write_stress_vtu

        try:
            write_stress_vtu(fields[best], args.vtu)
        except (OSError, ValueError, RuntimeError) as exc:
            print(f"conformal: error: --vtu: {exc} (the JSON summary was written)", file=sys.stderr)
            code = 1
    if args.plot:
        from conformal.stresses.plots import plot_stress_field

        try:
            plot_stress_field(fields[best], args.plot, title=f"{scene.name}: half-space stresses in body "
                              f"{summary['body']} (patch {summary['patches'][best]['patch']})",
                              dang_van_alpha=summary["fatigue"]["alpha_dv"], surface=surface_curve(result))
        except Exception as exc:  # noqa: BLE001 - any plotting failure: the JSON is already out
            print(f"conformal: error: --plot: {type(exc).__name__}: {exc} (the JSON summary was written)",
                  file=sys.stderr)
            code = 1
    if not summary["converged"] and code == 0:
        from conformal.errors import unconverged_exit

        code = unconverged_exit("the contact solve", args.allow_unconverged)
    return code


def add_parsers(sub, check_output, plot_suffixes) -> None:
    """The ``stresses`` sub-command of :mod:`conformal.cli`; ``check_output(path, option, suffixes)``
    refuses an output path before any work (conformal.cli.check_output_path)."""
    st = sub.add_parser("stresses", help="solve a scene, then the subsurface stresses and fatigue indices (JSON)")
    st.add_argument("scene", help="scene file (TOML); optional [stresses] section (k, alpha_dv, tau_e, depth, "
                    "n_depths, body)")
    st.add_argument("--depth", type=float, help="deepest plane in mm (default: twice the smaller semi-axis)")
    st.add_argument("--k", type=float, help="yield stress in shear, N/mm² (FI_surf; default 300)")
    st.add_argument("--body", type=int, choices=(1, 2), help="1: rail (body 1, default), 2: wheel")
    st.add_argument("--json", metavar="OUT.json", help="also write the JSON to this file")
    st.add_argument("--vtu", metavar="OUT.vtu", help="the stress block of the most stressed patch for ParaView")
    st.add_argument("--plot", metavar="OUT.png", help="slices of von Mises and orthogonal shear, Dang Van per depth")
    st.add_argument("--allow-unconverged", action="store_true",
                    help="exit 0 also when the contact solve did not converge (default: exit status 3)")
    st.set_defaults(func=cmd_stresses, check_output=check_output, plot_suffixes=tuple(plot_suffixes))
