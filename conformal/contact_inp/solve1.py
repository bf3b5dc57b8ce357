"""Module-1 (wheel-rail) cases onto the project's wheel-rail scene and its planar path
(conformal.cases.wheelrail, theory "exact": one tangent-plane half-space problem per patch).

The deck's inputs map onto scene keys: the profiles (SIMPACK ``.prr``/``.prw`` or Miniprof
``.ban``/``.whl`` beside the deck, read by conformal.geometry.profiles, with MIRRORY, MIRRORZ and
SMOOTH as ``*_mirror_y``, ``*_z``, ``*_smoothing``: :func:`_profile_keys`), the track (GAUGHT,
GAUGWD, CANT), the wheelset (FBDIST, FBPOS, NOMRADW), its position (Y_WS, ROLL, YAW; the vertical
force FZ) and velocity (VS_WS, VY_WS, VROLL, VYAW, VPITCH), the element size DX (= DS), and the
distance D_SEP above which patches are solved separately (``patch_combine``), the wheelset height
Z_WS where the deck prescribes it (N = 0: ``[load] approach`` from the first touch).  Friction
varying with the surface inclination (V = 1) takes, as CONTACT, one coefficient per patch at its
contact angle (``[friction] angle_table``).

Cases with CONTACT's conformal approach (D = 4) map onto theory ``conformal`` with influence
``halfspace_planar`` (CONTACT's conformal half-space numbers, C3 = 2; ``halfspace_blanco`` with
Blanco's angle correction, C3 = 4, conformal.influence.blanco) and its rigid slip (creepage
``wheel_surface``), element sizes DX and DS (``element_size``, ``element_size_s``), every patch on
its own strip (``[grid] strips = "separate"``); there the deck may prescribe the wheelset height
Z_WS (N = 0: ``[load] approach`` from the first touch), the longitudinal force FX_WS with the pitch
velocity solved (F = 1: ``fx_rel``), one wheel over one rail (GAUGHT <= 0 with the rail and wheel
origins together: placement "single") and friction varying with the surface inclination (V = 1),
every row of a strip at its own contact angle (``[friction] angle_table``).  The geometry processing is the project's own (smoothing spline,
contact search, patch reference point and angle), so the results agree with CONTACT's to the
accuracy of that processing (docs/validation/halfspace.md, Manchester benchmark), not to its printed digits.

CONTACT's combination of nearby contact regions (D_COMB, blending up to D_SEP, turning up to
D_TURN) is not applied; every case where that rule treats the regions at the solved height
differently from the patches solved here carries a ``patch combination:`` warning naming the
parameter and the distance (conformal.contact_inp.combine).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from conformal.contact_inp.module1 import Module1Case
from conformal.contact_inp.module3 import unsupported


def _profile_path(case: Module1Case, name: str, base_dir: Path) -> Path:
    """The profile as the deck names it, else the file of that name beside the deck."""
    for path in (Path(name) if Path(name).is_absolute() else base_dir / name, base_dir / Path(name).name):
        if path.is_file():
            return path.resolve()
    raise unsupported(case.deck, case.line, f"the profile {name} is missing beside the deck")


#: mm, how far the smoothing may move a deck's profile points (``[geometry] max_smoothing_error``;
#: a scene's default is 0.1 mm): CONTACT sets no limit, and its lambda = 10 on the measured profiles
#: of its testbank moves them up to 1.0 mm at their corners, where CONTACT keeps a kink
DECK_SMOOTHING_ERROR = 2.0


def _profile_keys(case: Module1Case, base_dir: Path) -> dict:
    """``[geometry]`` keys of both profiles: the files, CONTACT's MIRRORY / MIRRORZ (``*_mirror_y``,
    ``*_z``; MIRRORZ = 0 detects the orientation of Miniprof files, SIMPACK files are taken as they
    are, as CONTACT does) and SMOOTH (``*_smoothing``): the wavelength L_filt where ISMOOTH = 1,
    and where ISMOOTH = 0 (CONTACT's unweighted spline with parameter lambda) the wavelength that
    gives the project's spline (conformal.geometry.spline.fit_curve) that same lambda, L = 2 pi
    (lambda / dt)**(1/4) with dt the mean chord between the points."""
    from conformal.geometry.miniprof import SUFFIXES
    from conformal.geometry.profiles import check_points, load_profile

    out = {}
    for kind, prof in (("rail", case.rail), ("wheel", case.wheel)):
        path = _profile_path(case, prof[0], base_dir)
        mirror_y, smooth, mirror_z, ismooth = prof[1] >= 1, prof[3], prof[4], prof[6]
        z = {1: "up", -1: "down"}.get(mirror_z, "auto" if path.suffix.lower() in SUFFIXES else "down")
        out.update({f"{kind}_profile": str(path), f"{kind}_z": z, f"{kind}_mirror_y": mirror_y})
        if smooth > 0 and ismooth == 0:
            p = load_profile(str(path), kind, z_up=None if z == "auto" else z == "up", mirror_y=mirror_y).points
            dt = float(np.hypot(*np.diff(check_points(p, kind, path.name), axis=0).T).mean())
            smooth = 2.0 * np.pi * (smooth / dt) ** 0.25
        out[f"{kind}_smoothing"] = float(max(smooth, 0.0))
    out["max_smoothing_error"] = DECK_SMOOTHING_ERROR
    return out


def scene_of(case: Module1Case, base_dir: Path, memo: dict | None = None) -> dict:
    """The scene (as a dict for conformal.scene.scene_from_dict) of one module-1 case; ``memo``: a
    dict that keeps the first-touch heights of cases with Z_WS prescribed (N = 0) between calls."""
    if case.conformal:
        return _conformal_scene(case, base_dir, memo)
    nu1, nu2, g1, g2 = case.material
    gaught, _, gaugwd, cant = case.track[:4]
    fbdist, fbpos, nomrad = case.wheelset[:3]
    s_ws, y_ws, fz, roll, yaw, _pitch = case.position
    dx = case.discretisation[0]
    d_sep = case.discretisation[4]
    files = _profile_keys(case, base_dir)
    kin: dict = {}
    if case.digits["T"] == 3:
        vs, vy, vz, vroll, vyaw, vpitch = case.velocity
        kin = {"speed": vs, "pitch_velocity": vpitch, "yaw_rate": vyaw, "roll_rate": vroll, "lateral_velocity": vy}
    if case.friction_table:                # V = 1: one friction per patch at its contact angle
        friction = {"angle_table": [list(r) for r in case.friction_table]}
    else:
        friction = {"mu_static": case.friction[0], "mu_kinetic": case.friction[1]}
    raw = {
        "name": f"{case.deck} case {case.number}",
        "material": {"G": g1, "nu": nu1, "body2": {"G": g2, "nu": nu2}},
        "friction": friction,
        "geometry": {"kind": "wheel_rail", **files, "rail_cant": cant, "side": case.side, "placement": "wheelset",
                     "lateral_shift": y_ws, "yaw": yaw, "roll": roll, "gauge": gaugwd, "gauge_height": gaught,
                     "flange_back": fbdist, "flange_back_pos": fbpos, "wheel_radius": nomrad,
                     "element_size": dx, "patch_combine": d_sep},
        "load": {"wheel_load": fz},
        "kinematics": kin,
        "model": {"theory": "exact"},
    }
    return _height_prescribed(case, raw, base_dir, memo)


def _conformal_scene(case: Module1Case, base_dir: Path, memo: dict | None = None) -> dict:
    """A D = 4 case: theory conformal with CONTACT's formulation (module docstring)."""
    nu1, nu2, g1, g2 = case.material
    gaught, _, gaugwd, cant = case.track[:4]
    fbdist, fbpos, nomrad = case.wheelset[:3]
    s_ws, y_ws, z_inp, roll, yaw, _pitch = case.position
    dx, ds = case.discretisation[:2]
    files = _profile_keys(case, base_dir)
    if case.friction_table:                # V = 1: per row of each strip at its contact angle
        friction = {"angle_table": [list(r) for r in case.friction_table]}
    else:
        friction = {"mu_static": case.friction[0], "mu_kinetic": case.friction[1]}
    if gaught > 0:
        place = {"placement": "wheelset", "gauge": gaugwd, "gauge_height": gaught, "flange_back": fbdist,
                 "flange_back_pos": fbpos}
    else:                                  # one wheel over one rail, origins together (module1)
        place = {"placement": "single"}
    vs, vy, _vz, vroll, vyaw, v6 = case.velocity
    kin = {"speed": vs, "yaw_rate": vyaw, "roll_rate": vroll, "lateral_velocity": vy}
    if case.digits["F"] == 1:              # FX_WS prescribed, the pitch velocity solved
        if case.digits["N"] != 1:
            raise unsupported(case.deck, case.line, "module 1, F = 1 with N = 0 (force with the height prescribed)")
        if case.friction_table:
            raise unsupported(case.deck, case.line, "module 1, F = 1 with friction over the profile (V = 1; FX_WS is "
                                                    "relative to one mu)")
        kin.update(fx_rel=v6 / (friction["mu_static"] * z_inp), pitch_velocity=-vs / nomrad)
    else:
        kin["pitch_velocity"] = v6
    raw = {
        "name": f"{case.deck} case {case.number}",
        "material": {"G": g1, "nu": nu1, "body2": {"G": g2, "nu": nu2}},
        "friction": friction,
        "geometry": {"kind": "wheel_rail", **files, "rail_cant": cant, "side": case.side, **place,
                     "lateral_shift": y_ws, "yaw": yaw, "roll": roll, "wheel_radius": nomrad,
                     "element_size": dx, "element_size_s": ds},
        "load": {"wheel_load": z_inp},
        "kinematics": {k: v for k, v in kin.items() if v != 0.0 or k in ("pitch_velocity", "fx_rel")},
        "grid": {"strips": "separate"},
        "model": {"theory": "conformal", "influence": "halfspace_planar"},
    }
    if case.blanco is not None:            # C = 4: Blanco's angle correction (conformal.influence.blanco)
        raw["model"] = {"theory": "conformal", "influence": "halfspace_blanco",
                        "blanco_method": "full" if case.blanco[0] == 1 else "linear", "blanco_variant": case.blanco[1]}
    return _height_prescribed(case, raw, base_dir, memo)


def _height_prescribed(case: Module1Case, raw: dict, base_dir: Path, memo: dict | None = None) -> dict:
    """N = 0 (Z_WS prescribed, CONTACT's wheelset height, positive downwards): ``[load] approach``,
    the lowering below the height where the wheelset first touches (conformal.cases.wheelrail,
    :class:`~conformal.cases.wheelrail.Placement`), so that the solve puts the wheelset at Z_WS.
    ``memo``: first-touch heights already found, by geometry (a deck's cases often share it)."""
    import json

    from conformal.cases.wheelrail import place_scene
    from conformal.scene import scene_from_dict

    if case.digits["N"] != 0:
        return raw
    z_inp = case.position[2]
    key = json.dumps([raw["geometry"], raw["model"], str(base_dir)], sort_keys=True)
    if memo is None or key not in memo:
        z = place_scene(scene_from_dict(raw, base_dir=base_dir)).z_first
        if memo is None:
            memo = {}
        memo[key] = z
    z_first = memo[key]
    if z_inp - z_first <= 0.0:
        raise unsupported(case.deck, case.line, f"module 1, Z_WS = {z_inp:g} mm leaves the wheel off the rail")
    raw["load"] = {"approach": z_inp - z_first}
    return raw


#: the scene keys in which consecutive module-1 cases of a deck may differ and still form one
#: sequence of wheelset positions (CONTACT starts every case from the one before): the position
#: (``[geometry]`` lateral_shift, yaw, roll) and the velocities (``[kinematics]``); profiles, track,
#: grid, material, friction, load and model must be the same
SEQUENCE_POSITION = ("lateral_shift", "yaw", "roll")


def sequence_key(raw: dict) -> str | None:
    """What a module-1 case's scene shares with its neighbours in a sequence of wheelset positions
    (the scene less its name, position and velocities, :data:`SEQUENCE_POSITION`): consecutive cases
    with the same key start each from the one before (:func:`solve_case`, ``warm``).  None for a
    case with the wheelset height prescribed (N = 0, ``[load] approach``), which has no vertical
    balance to start."""
    import json

    if raw["load"].get("wheel_load") is None:
        return None
    geometry = {k: v for k, v in raw["geometry"].items() if k not in SEQUENCE_POSITION}
    rest = {k: v for k, v in raw.items() if k not in ("name", "geometry", "kinematics")}
    return json.dumps([geometry, rest], sort_keys=True)


def solve_case(case: Module1Case, raw: dict, base_dir: Path, warm=None):
    """Solve one case's scene; ``warm``: the :class:`~conformal.cases.wheelrail.WarmStart` of the
    case before it in the same sequence (:func:`sequence_key`), where the vertical balance and the
    contact solves start.  The answer is then the same balance to its tolerances as a cold solve,
    not bitwise: the passes keep a geometry searched near the neighbour's height (within
    GEOMETRY_KEEP of the final one, conformal.cases.wheelrail), where a cold solve searches at its
    settled height (Manchester A-2.2 deck, 21 cases: FN, FX, FY within 0.41, 0.35, 0.17 N = 4e-5 of
    the wheel load of the cold solves, the same as the study's warm-started sequence against cold
    solves of its positions, with FZ balanced to 6e-6 of the load).

    A case the project's wheel-rail set-up cannot place (no contact point within the profiles,
    normals that miss a profile, a ``[geometry]`` check) is refused naming that, as an unsupported
    case (one line, exit 2)."""
    from conformal.contact_inp.module3 import Unsupported
    from conformal.errors import ConvergenceError, InputError, NoContactError
    from conformal.scene import scene_from_dict
    from conformal.dispatch import solve_scene

    try:
        scene = scene_from_dict(raw, base_dir=base_dir, name=raw["name"])
        r = solve_scene(scene, warm=warm)
    except (InputError, NoContactError, ConvergenceError) as exc:
        text = str(exc)
        if isinstance(exc, InputError) and not text.startswith("[geometry]"):
            raise
        if isinstance(exc, ConvergenceError) and not text.startswith(("wheel surface", "rail surface")):
            raise
        raise Unsupported(f"{case.deck}, line {case.line} (case {case.number}): not supported: module 1, "
                          f"the project's wheel-rail set-up fails here ({text})") from None
    extra = dict(r.extra)
    extra["warnings"] = list(extra.get("warnings", [])) + _combination_warnings(case, scene, r)
    return replace(r, extra=extra)


def _combination_warnings(case: Module1Case, scene, r) -> list[str]:
    """The warnings of conformal.contact_inp.combine: where CONTACT would combine, blend or turn
    the contact regions at the solved wheelset height differently from the patches solved here."""
    from conformal.contact_inp.combine import combination_warnings, reader_gap, regions_at, strip_count_warning
    from conformal.errors import ConvergenceError, InputError, NoContactError

    z = r.extra.get("z_ws")
    if z is None:
        return []
    try:
        regions = regions_at(scene, float(z))
    except (InputError, NoContactError, ConvergenceError):
        return []
    out = combination_warnings(regions, reader_gap(scene), *thresholds(case))
    if case.conformal and not out:         # one region whose contact splits into strips, or the reverse
        out = strip_count_warning(regions, len(r.patches or (r,)), *thresholds(case))
    return out


def thresholds(case: Module1Case) -> tuple[float, float, float, float]:
    """The deck's (D_COMB, D_SEP, D_TURN, A_SEP); D_TURN defaults to 2 D_SEP - D_COMB as in CONTACT."""
    a_sep, d_sep, d_comb = case.discretisation[3:6]
    d_turn = case.discretisation[6] if len(case.discretisation) > 6 else 2.0 * d_sep - d_comb
    return d_comb, d_sep, d_turn, a_sep


def summary(case: Module1Case, r) -> dict:
    """The JSON object of one solved module-1 case: totals, the track-frame forces on the rail and
    one entry per patch (FN, FX, FS, MN, pmax, n_contact, contact_angle, y_rail)."""
    patches = []
    for p in r.patches or (r,):
        f = p.field
        g = p.extra.get("grid")
        if f is None and g is not None:        # conformal strips: elements from the area
            ncon = int(round(p.extra["contact_area"] / (g["dx"] * g["ds"])))
        else:
            ncon = f.n_contact if f is not None else None
        angle, y_rail = p.extra.get("contact_angle"), p.extra.get("y_rail")
        if "contact_angle_min" in p.extra:     # a conformal strip: the middle of its band of angles
            angle = 0.5 * (p.extra["contact_angle_min"] + p.extra["contact_angle_max"])
            y_rail = p.extra.get("y_rail")     # the strip's reference point on the rail (YCP(R))
        patches.append({"FN": p.FN, "FX": p.FX, "FS": p.FY, "MN": p.MZ, "pmax": p.pmax,
                        "n_contact": ncon,
                        "n_adhesion": f.n_adhesion if f is not None else None,
                        "n_slip": f.n_slip if f is not None else None,
                        "contact_angle": angle, "y_rail": y_rail,
                        **({"FY_track": p.extra["FY_track"], "FZ_track": p.extra["FZ_track"]}
                           if "FY_track" in p.extra else {})})
    warnings = list(case.skipped) + list(r.extra.get("warnings", []))
    if not r.converged:
        warnings.append("not converged")
    return {"case": case.number, "module": 1, "FN": r.FN, "FX": r.FX, "FY": r.FY, "MZ": r.MZ, "pmax": r.pmax,
            "approach": r.approach, "n_contact": sum(p["n_contact"] or 0 for p in patches),
            "n_adhesion": sum(p["n_adhesion"] or 0 for p in patches), "n_slip": sum(p["n_slip"] or 0 for p in patches),
            "FX_track": r.extra.get("FX_track"), "FY_track": r.extra.get("FY_track"),
            "FZ_track": r.extra.get("FZ_track"), "z_ws": r.extra.get("z_ws"), "patches": patches,
            **({"pitch_velocity": r.extra["pitch_velocity_solved"]} if "pitch_velocity_solved" in r.extra else {}),
            "converged": bool(r.converged), "warnings": warnings}
