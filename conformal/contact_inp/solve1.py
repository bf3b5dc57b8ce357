"""Module-1 (wheel-rail) cases onto the project's wheel-rail scene and its planar path
(conformal.cases.wheelrail, theory "exact": one tangent-plane half-space problem per patch).

The deck's inputs map onto scene keys: the profiles (``.prr``/``.prw`` beside the deck, read by
conformal.geometry.profiles), the track (GAUGHT, GAUGWD, CANT), the wheelset (FBDIST, FBPOS,
NOMRADW), its position (Y_WS, ROLL, YAW; the vertical force FZ) and velocity (VS_WS, VY_WS, VROLL,
VYAW, VPITCH), the element size DX (= DS), and the distance D_SEP above which patches are solved
separately (``patch_combine``).  The geometry processing is the project's own (smoothing spline,
contact search, patch reference point and angle), so the results agree with CONTACT's to the
accuracy of that processing (README, Manchester benchmark), not to its printed digits.
"""
from __future__ import annotations

from pathlib import Path

from conformal.contact_inp.module1 import Module1Case
from conformal.contact_inp.module3 import unsupported


def scene_of(case: Module1Case, base_dir: Path) -> dict:
    """The scene (as a dict for conformal.scene.scene_from_dict) of one module-1 case."""
    nu1, nu2, g1, g2 = case.material
    gaught, _, gaugwd, cant = case.track[:4]
    fbdist, fbpos, nomrad = case.wheelset[:3]
    s_ws, y_ws, fz, roll, yaw, _pitch = case.position
    dx = case.discretisation[0]
    d_sep = case.discretisation[4]
    files = {}
    for key, name in (("rail_profile", case.rail_file), ("wheel_profile", case.wheel_file)):
        path = Path(name) if Path(name).is_absolute() else base_dir / name
        if not path.is_file():
            raise unsupported(case.deck, case.line, f"the profile {name} is missing beside the deck")
        files[key] = str(path)
    kin: dict = {}
    if case.digits["T"] == 3:
        vs, vy, vz, vroll, vyaw, vpitch = case.velocity
        kin = {"speed": vs, "pitch_velocity": vpitch, "yaw_rate": vyaw, "roll_rate": vroll, "lateral_velocity": vy}
    return {
        "name": f"{case.deck} case {case.number}",
        "material": {"G": g1, "nu": nu1, "body2": {"G": g2, "nu": nu2}},
        "friction": {"mu_static": case.friction[0], "mu_kinetic": case.friction[1]},
        "geometry": {"kind": "wheel_rail", **files, "rail_cant": cant, "side": case.side, "placement": "wheelset",
                     "lateral_shift": y_ws, "yaw": yaw, "roll": roll, "gauge": gaugwd, "gauge_height": gaught,
                     "flange_back": fbdist, "flange_back_pos": fbpos, "wheel_radius": nomrad,
                     "element_size": dx, "patch_combine": d_sep, "smoothing": 0.0},
        "load": {"wheel_load": fz},
        "kinematics": kin,
        "model": {"theory": "exact"},
    }


def summary(case: Module1Case, r) -> dict:
    """The JSON object of one solved module-1 case: totals, the track-frame forces on the rail and
    one entry per patch (FN, FX, FS, MN, pmax, n_contact, contact_angle, y_rail)."""
    patches = []
    for p in r.patches or (r,):
        f = p.field
        patches.append({"FN": p.FN, "FX": p.FX, "FS": p.FY, "MN": p.MZ, "pmax": p.pmax,
                        "n_contact": f.n_contact if f is not None else None,
                        "n_adhesion": f.n_adhesion if f is not None else None,
                        "n_slip": f.n_slip if f is not None else None,
                        "contact_angle": p.extra.get("contact_angle"), "y_rail": p.extra.get("y_rail")})
    warnings = list(case.skipped) + list(r.extra.get("warnings", []))
    if not r.converged:
        warnings.append("not converged")
    return {"case": case.number, "module": 1, "FN": r.FN, "FX": r.FX, "FY": r.FY, "MZ": r.MZ, "pmax": r.pmax,
            "approach": r.approach, "n_contact": sum(p["n_contact"] or 0 for p in patches),
            "n_adhesion": sum(p["n_adhesion"] or 0 for p in patches), "n_slip": sum(p["n_slip"] or 0 for p in patches),
            "FX_track": r.extra.get("FX_track"), "FY_track": r.extra.get("FY_track"),
            "FZ_track": r.extra.get("FZ_track"), "z_ws": r.extra.get("z_ws"), "patches": patches,
            "warnings": warnings}
