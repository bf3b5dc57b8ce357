"""Issue 22: bad inputs as a new user types them, each expecting a clean refusal (exit code 2 and
ONE line on stderr naming the key; InputError naming it from the API) or the right answer.

The trials run in-process: API cases through :func:`conformal.solve`, CLI cases through
:func:`conformal.cli.main` with pytest's capsys (a few through a real subprocess at the end).  A
scene that gets past validation is solved with theory "hertz" or "fastsim" on a small grid, so the
whole file takes seconds.
"""
from __future__ import annotations

import copy
import json
import math
import re
import subprocess
import sys

import pytest

import conformal
from conformal.cli import main
from conformal.errors import ConformalError, InputError
from _paths import ROOT, SCENES

DELETE = object()

PLANAR = {
    "material": {"G": 82000.0, "nu": 0.28}, "friction": {"mu": 0.3},
    "geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3}, "load": {"normal_force": 1e4},
    "kinematics": {"xi": 1e-3}, "grid": {"n": 16}, "model": {"theory": "fastsim"},
}
WHEEL_RAIL = {
    "material": {"G": 82000.0, "nu": 0.28}, "friction": {"mu": 0.3},
    "geometry": {"kind": "wheel_rail", "wheel_profile": "S1002", "rail_profile": "UIC60",
                 "lateral_shift": 0.0}, "load": {"wheel_load": 1e4}, "grid": {"n": 16},
    "model": {"theory": "hertz"},
}


def edit(base: dict, changes: dict) -> dict:
    """The scene ``base`` with ``{"section.key": value}`` changes (DELETE removes; "section" alone
    replaces the section; "history" sets the [[history]] steps)."""
    d = copy.deepcopy(base)
    for path, v in changes.items():
        parts = path.split(".")
        node = d
        for p in parts[:-1]:
            node = node.setdefault(p, {})
        if v is DELETE:
            node.pop(parts[-1], None)
        else:
            node[parts[-1]] = v
    return d


# ----------------------------------------------------------------------------- the trials
NUMBER_KEYS = [  # (path, expected refusal of a negative value or None when negative is fine)
    ("material.G", "> 0"), ("material.nu", "(-1, 0.5)"), ("friction.mu", "> 0"), ("geometry.A", "> 0"),
    ("geometry.B", ">= 0"), ("load.normal_force", "> 0"), ("kinematics.xi", None), ("kinematics.eta", None),
    ("kinematics.phi", None), ("kinematics.velocity", "> 0"), ("grid.scale", "> 0"), ("model.tol", "> 0"),
    ("model.layer_flexibility", ">= 0"),
]
WHOLE_KEYS = [("grid.n", 2), ("model.maxit", 1), ("model.maxout", 1), ("model.n", 4), ("model.max_mx", 4),
              ("model.max_ms", 4)]


def _key(path: str) -> str:
    sec, key = path.rsplit(".", 1)
    return f"[{sec}] {key}"


def _cases():
    out = []
    for path, negative in NUMBER_KEYS:                         # 13 x 5 (+ negatives)
        for tag, v in (("text", "abc"), ("bool", True), ("nan", math.nan), ("inf", math.inf),
                       ("list", [1.0, 2.0])):
            out.append((f"{path}={tag}", PLANAR, {path: v}, _key(path)))
        if negative:
            out.append((f"{path}=-1", PLANAR, {path: -1.0}, _key(path)))
    for path, minimum in WHOLE_KEYS:                           # 6 x 4
        for tag, v in (("text", "abc"), ("float", 2.5), ("below", minimum - 1), ("bool", False)):
            out.append((f"{path}={tag}", PLANAR, {path: v}, _key(path)))
    for sec in ("material", "friction", "geometry", "load", "kinematics", "grid", "model"):   # 7 x 3
        out.append((f"[{sec}] unknown key", PLANAR, {f"{sec}.colour": 1}, f"[{sec}] colour: unknown key"))
        out.append((f"[{sec}] not a table", PLANAR, {sec: 5}, f"[{sec}]"))
        out.append((f"[{sec}] list", PLANAR, {sec: [1, 2]}, f"[{sec}]"))
    out += [
        ("unknown section", PLANAR, {"contact.mu": 0.3}, "[contact]: unknown section"),
        ("misspelt theory key", PLANAR, {"model.Theory": "exact"}, "did you mean 'theory'"),
        ("no geometry", PLANAR, {"geometry": DELETE}, "[geometry] kind"),
        ("no load", PLANAR, {"load": DELETE}, "[load] normal_force"),
        ("name not text", PLANAR, {"name": 5}, "name"),
        # material
        ("G and E", PLANAR, {"material.E": 2e5}, "[material] G"),
        ("neither G nor E", PLANAR, {"material.G": DELETE}, "[material] G"),
        ("nu 0.5", PLANAR, {"material.nu": 0.5}, "[material] nu"),
        ("nu missing", PLANAR, {"material.nu": DELETE}, "[material] nu"),
        ("body2 without nu", PLANAR, {"material.body2": {"G": 1e5}}, "[material.body2] nu"),
        ("body2 unknown key", PLANAR, {"material.body2": {"G": 1e5, "nu": 0.3, "K": 1}}, "[material.body2] K"),
        ("body2 not a table", PLANAR, {"material.body2": 3}, "[material.body2]"),
        # friction
        ("mu and mu_static", PLANAR, {"friction.mu_static": 0.4}, "[friction] mu"),
        ("mu_kinetic > mu_static", PLANAR, {"friction": {"mu_static": 0.2, "mu_kinetic": 0.3}},
         "[friction] mu_kinetic"),
        ("no mu", PLANAR, {"friction": {}}, "[friction] mu"),
        ("mu 0", PLANAR, {"friction.mu": 0.0}, "[friction] mu"),
        ("mu_table missing file", PLANAR, {"friction.mu_table": "nope.csv", "model.theory": "exact"},
         "[friction] mu_table"),
        # geometry
        ("kind unknown", PLANAR, {"geometry.kind": "sphere"}, "[geometry] kind"),
        ("kind missing", PLANAR, {"geometry.kind": DELETE}, "[geometry] kind"),
        ("A missing", PLANAR, {"geometry.A": DELETE}, "[geometry] A"),
        ("hertz b missing", PLANAR, {"geometry": {"kind": "hertz", "a": 5.0}}, "[geometry] b"),
        ("table file missing", PLANAR, {"geometry": {"kind": "table", "file": "nope.txt"}}, "[geometry] file"),
        ("table file empty name", PLANAR, {"geometry": {"kind": "table", "file": ""}}, "[geometry] file"),
        # load
        ("two loads", PLANAR, {"load.approach": 0.1}, "[load] normal_force"),
        ("no load value", PLANAR, {"load": {}}, "[load] normal_force"),
        ("approach 0", PLANAR, {"load": {"approach": 0.0}}, "[load] approach"),
        ("wheel_load planar", PLANAR, {"load": {"wheel_load": 1e4}}, "[load] wheel_load"),
        ("load_angle planar", PLANAR, {"load.load_angle": 0.1}, "[load] load_angle"),
        # kinematics
        ("xi and fx_rel", PLANAR, {"kinematics.fx_rel": 0.1}, "[kinematics] fx_rel"),
        ("fx_rel 1", PLANAR, {"kinematics": {"fx_rel": 1.0}}, "[kinematics] fx_rel"),
        ("fy_rel -2", PLANAR, {"kinematics": {"fy_rel": -2.0}}, "[kinematics] fy_rel"),
        ("rolling unknown", PLANAR, {"kinematics.rolling": "skid"}, "[kinematics] rolling"),
        ("direction 0", PLANAR, {"kinematics.direction": 0}, "[kinematics] direction"),
        ("direction 2", PLANAR, {"kinematics.direction": 2}, "[kinematics] direction"),
        ("rigid_slip missing", PLANAR, {"kinematics.rigid_slip": "nope.txt", "model.theory": "exact"},
         "[kinematics] rigid_slip"),
        ("fx_rel with fastsim", PLANAR, {"kinematics": {"fx_rel": 0.5}}, "fx_rel"),
        # grid
        ("mx without dx", PLANAR, {"grid": {"mx": 10, "my": 10}}, "[grid] dx"),
        ("strips unknown", PLANAR, {"grid.strips": "many"}, "[grid] strips"),
        ("scale 1000", PLANAR, {"grid.scale": 1000.0}, "[grid] scale"),
        ("grid too large", PLANAR, {"grid": {"n": 200000}, "model.theory": "exact"}, "[grid] n"),
        # model
        ("theory unknown", PLANAR, {"model.theory": "kalker"}, "[model] theory"),
        ("bound unknown", PLANAR, {"model.bound": "square"}, "[model] bound"),
        ("influence unknown", PLANAR, {"model.influence": "magic"}, "[model] influence"),
        ("tol 10", PLANAR, {"model.tol": 10.0}, "[model] tol"),
        ("tol 0.5", PLANAR, {"model.tol": 0.5}, "[model] tol"),
        ("discretisation unknown", PLANAR, {"model.discretisation": "fine"}, "[model] discretisation"),
        ("creepage unknown", PLANAR, {"model.creepage": "both"}, "[model] creepage"),
        ("creep_coefficients unknown", PLANAR, {"model.creep_coefficients": "x"}, "[model] creep_coefficients"),
        ("flexibilities two", PLANAR, {"model.flexibilities": [1e-5, 1e-5]}, "[model] flexibilities"),
        ("flexibilities negative", PLANAR, {"model.flexibilities": [1e-5, -1e-5, 1e-5]}, "[model] flexibilities"),
        ("require_c33 text", PLANAR, {"model.require_c33": "yes"}, "[model] require_c33"),
        ("table missing", PLANAR, {"model.table": "nope.npz", "model.theory": "table"}, "[model] table"),
        ("fe key unknown", PLANAR, {"model.fe_colour": 1}, "[model] fe_colour"),
        ("influence_file with fastsim", PLANAR, {"model.influence_file": "x.txt"}, "[model] influence_file"),
        # history
        ("history with fastsim", PLANAR, {"history": [{"normal_force": 1e4}]}, "[[history]]"),
        ("history force -1", PLANAR, {"history": [{"normal_force": -1.0}], "model.theory": "exact"},
         "[history 1] normal_force"),
        ("history rolling", PLANAR, {"history": [{"rolling": "skid"}], "model.theory": "exact"},
         "[history 1] rolling"),
        ("history distance with shift", PLANAR, {"history": [{"distance": 1.0}], "model.theory": "exact"},
         "[history 1] distance"),
        ("history fx_rel 1.5", PLANAR, {"history": [{"fx_rel": 1.5}], "model.theory": "exact"},
         "[history 1] fx_rel"),
        ("history repeat 0", PLANAR, {"history": [{"repeat": 0}], "model.theory": "exact"}, "[history 1] repeat"),
        ("history repeat huge", PLANAR, {"history": [{"repeat": 10 ** 6}], "model.theory": "exact"},
         "[history 1] repeat"),
        ("history unknown key", PLANAR, {"history": [{"force": 1.0}], "model.theory": "exact"},
         "[history 1] force"),
        ("history not tables", PLANAR, {"history": [1, 2], "model.theory": "exact"}, "[[history]]"),
        # wheel-rail geometry
        ("gauge 1000", WHEEL_RAIL, {"geometry.gauge": 1000.0}, "[geometry] gauge"),
        ("gauge 3000", WHEEL_RAIL, {"geometry.gauge": 3000.0}, "[geometry] gauge"),
        ("flange_back 1500", WHEEL_RAIL, {"geometry.flange_back": 1500.0}, "[geometry] flange_back"),
        ("flange_back 1000", WHEEL_RAIL, {"geometry.flange_back": 1000.0}, "[geometry] flange_back"),
        ("wheel_radius 1", WHEEL_RAIL, {"geometry.wheel_radius": 1.0}, "[geometry] wheel_radius"),
        ("wheel_radius 0", WHEEL_RAIL, {"geometry.wheel_radius": 0.0}, "[geometry] wheel_radius"),
        ("smoothing 100", WHEEL_RAIL, {"geometry.smoothing": 100.0}, "[geometry] smoothing"),
        ("smoothing 1000", WHEEL_RAIL, {"geometry.smoothing": 1000.0}, "[geometry] smoothing"),
        ("smoothing -1", WHEEL_RAIL, {"geometry.smoothing": -1.0}, "[geometry] smoothing"),
        ("yaw 1 rad", WHEEL_RAIL, {"geometry.yaw": 1.0}, "[geometry] yaw"),
        ("roll 1 rad", WHEEL_RAIL, {"geometry.roll": 1.0}, "[geometry] roll"),
        ("cant 0.5", WHEEL_RAIL, {"geometry.rail_cant": 0.5}, "[geometry] rail_cant"),
        ("side middle", WHEEL_RAIL, {"geometry.side": "middle"}, "[geometry] side"),
        ("placement unknown", WHEEL_RAIL, {"geometry.placement": "bogie"}, "[geometry] placement"),
        ("wheel_z sideways", WHEEL_RAIL, {"geometry.wheel_z": "sideways"}, "[geometry] wheel_z"),
        ("element_size -1", WHEEL_RAIL, {"geometry.element_size": -1.0}, "[geometry] element_size"),
        ("lateral_shift text", WHEEL_RAIL, {"geometry.lateral_shift": "6 mm"}, "[geometry] lateral_shift"),
        ("gauge_height 100", WHEEL_RAIL, {"geometry.gauge_height": 100.0}, "[geometry] gauge_height"),
        ("wheel profile unknown", WHEEL_RAIL, {"geometry.wheel_profile": "S9999"}, "[geometry] wheel_profile"),
        ("rail profile unknown", WHEEL_RAIL, {"geometry.rail_profile": "UIC99"}, "[geometry] rail_profile"),
        ("wheel profile a system file", WHEEL_RAIL, {"geometry.wheel_profile": "/etc/passwd"},
         "not a profile"),
        ("rail profile a binary file", WHEEL_RAIL, {"geometry.rail_profile": sys.executable}, "not a profile"),
        ("wheel profile a folder", WHEEL_RAIL, {"geometry.wheel_profile": "/tmp"}, "[geometry] wheel_profile"),
        ("wheel_rail without load", WHEEL_RAIL, {"load": {"normal_force": 1e4}}, "[load]"),
        ("load_angle 2 rad", WHEEL_RAIL, {"load.load_angle": 2.0, "model.theory": "conformal"},
         "[load] load_angle"),
        ("load_angle with hertz", WHEEL_RAIL, {"load.load_angle": 0.3}, "[load] load_angle"),
        ("history on wheel_rail", WHEEL_RAIL, {"history": [{"normal_force": 1.0}], "model.theory": "exact"},
         "[[history]]"),
        ("mu_table on wheel_rail", WHEEL_RAIL, {"friction.mu_table": "x.csv"}, "[friction] mu_table"),
        ("angle_table on a planar scene", PLANAR, {"friction.angle_table": [[0.0, 0.3, 0.3]]},
         "[friction] angle_table"),
        ("angle_table with FE contact", WHEEL_RAIL,
         {"friction.angle_table": [[0.0, 0.3, 0.3]], "model.theory": "fe_contact"}, "[friction] angle_table"),
        ("angle_table angles decreasing", WHEEL_RAIL, {"friction.angle_table": [[0.0, 0.3, 0.3], [-0.1, 0.2, 0.2]]},
         "[friction] angle_table"),
        ("angle_table kinetic above static", WHEEL_RAIL, {"friction.angle_table": [[0.0, 0.3, 0.4]]},
         "[friction] angle_table"),
        ("angle_table row of two", WHEEL_RAIL, {"friction.angle_table": [[0.0, 0.3]]}, "[friction] angle_table"),
        # huge numbers (fault trials): a traceback or a float overflow before
        ("G 1e308", PLANAR, {"material.G": 1e308}, "[material] G"),
        ("E 1e308", PLANAR, {"material.G": DELETE, "material.E": 1e308}, "[material] E"),
        ("body2 G 1e300", PLANAR, {"material.body2": {"G": 1e300, "nu": 0.3}}, "[material.body2] G"),
        ("A 1e300 (curvature ratio)", PLANAR, {"geometry.A": 1e300}, "curvature ratio"),
        ("B 1e-300 (curvature ratio)", PLANAR, {"geometry.B": 1e-300}, "curvature ratio"),
        ("wheel_load 1e300", WHEEL_RAIL, {"load.wheel_load": 1e300}, "[load] wheel_load"),
        ("lateral_shift 1e300", WHEEL_RAIL, {"geometry.lateral_shift": 1e300}, "[geometry] lateral_shift"),
        ("fe_contact h 1e-6 (the patch filled the memory)", PLANAR,
         {"model.theory": "fe_contact", "model.fe_contact": {"h": 1e-6}, "kinematics.xi": 0.0},
         "[model.fe_contact] n (or h)"),
    ]
    out += _newer_cases()
    return out


FE_CONTACT = {**WHEEL_RAIL, "model": {"theory": "fe_contact"}}
FE_INFLUENCE = {**WHEEL_RAIL, "model": {"theory": "conformal", "influence": "fe"}}


def _newer_cases():
    """Inputs of the features that came later (angle_table, fe_contact's and the FE influence
    numbers' options, registry options), units a new user gets wrong, misspelt keys."""
    nan, inf = math.nan, math.inf
    out = []
    for tag, v in (("nan angle", [[nan, .3, .3]]), ("text", "steep"), ("empty", []), ("mu negative", [[0., -.3, -.3]]),
                   ("inf mu", [[0., inf, .3]]), ("rows of 4", [[0., .3, .3, .1]]),
                   ("angles in degrees", [[0., .3, .3], [70., .2, .2]]), ("duplicate angles", [[0., .3, .3], [0., .2, .2]]),
                   ("mu zero", [[0., 0., 0.]]), ("not rows", [0.1, 0.3, 0.3]), ("row text", [["a", .3, .3]]),
                   ("bool", True)):
        out.append((f"angle_table {tag}", WHEEL_RAIL, {"friction.angle_table": v}, "[friction] angle_table"))
    for key, v in (("fec_n", 0), ("fec_n", "abc"), ("fec_n", 2.5), ("fec_h", -1.0), ("fec_h", 0.0), ("fec_order", 3),
                   ("fec_body", "cube"), ("fec_body", "Disc"), ("fec_body", True), ("fec_section_size", -1.0),
                   ("fec_section_size", 0.0), ("fec_growth", nan), ("fec_far_field", "free"), ("fec_solver", "mumps"),
                   ("fec_estimate", "guess"), ("fec_slave", 0.5), ("fec_patch", 0.0), ("fec_body_size", -2.0),
                   ("fec_h_max", inf), ("fec_section_h_max", -1.0)):
        out.append((f"fe_contact {key} = {v!r}", FE_CONTACT, {f"model.{key}": v}, f"[model] {key}"))
    out += [
        ("fe_contact fec_colour", FE_CONTACT, {"model.fec_colour": 1}, "[model] fec_colour: unknown key"),
        ("fe_contact fec_nn", FE_CONTACT, {"model.fec_nn": 4}, "did you mean 'fec_n'"),
        ("fe_contact nested n 0", FE_CONTACT, {"model.fe_contact": {"n": 0}}, "[model] fec_n"),
        ("fe_contact nested misspelt", FE_CONTACT, {"model.fe_contact": {"bodie": "disc"}}, "[model.fe_contact] bodie"),
        ("fe_contact section body on a quadratic scene", PLANAR,
         {"model.theory": "fe_contact", "model.fec_body": "section", "kinematics": DELETE}, "[model] fec_body"),
    ]
    for key, v in (("fe_closure", "open"), ("fe_order", 3), ("fe_solver", "mumps"), ("fe_h_patch", -1.0),
                   ("fe_conform", "some"), ("fe_growth", 0.0), ("fe_body_size", 0.0), ("fe_method", "splitt"),
                   ("fe_collocation", "corner"), ("fe_far_field", 3), ("fe_h_max", nan), ("fe_h_load", "abc")):
        out.append((f"fe {key} = {v!r}", FE_INFLUENCE, {f"model.{key}": v}, f"[model] {key}"))
    out += [
        ("fe nested closure 5", FE_INFLUENCE, {"model.fe": {"closure": 5}}, "[model] fe_closure"),
        ("blanco_variant 5", WHEEL_RAIL, {"model.theory": "conformal", "model.blanco_variant": 5},
         "[model] blanco_variant"),
        ("blanco_method quad", WHEEL_RAIL, {"model.theory": "conformal", "model.blanco_method": "quad"},
         "[model] blanco_method"),
        ("creepage capitalised", WHEEL_RAIL, {"model.theory": "conformal", "model.creepage": "Surface"},
         "[model] creepage"),
        ("theory capitalised", PLANAR, {"model.theory": "Exact"}, "[model] theory"),
        ("theory with a space", PLANAR, {"model.theory": " exact"}, "[model] theory"),
        ("tol 0", PLANAR, {"model.tol": 0.0}, "[model] tol"),
        ("flexibilities text", PLANAR, {"model.flexibilities": "abc"}, "[model] flexibilities"),
        ("influence fe with exact", PLANAR, {"model.theory": "exact", "model.influence": "fe"}, "[model] influence"),
        # units: metres or degrees for mm or rad
        ("wheel_radius in m", WHEEL_RAIL, {"geometry.wheel_radius": 0.46}, "[geometry] wheel_radius"),
        ("gauge in m", WHEEL_RAIL, {"geometry.gauge": 1.435}, "[geometry] gauge"),
        ("yaw in degrees", WHEEL_RAIL, {"geometry.yaw": 5.0}, "[geometry] yaw"),
        ("element_size 1 m", WHEEL_RAIL, {"geometry.element_size": 1e3}, "[geometry] element_size"),
        ("element_size nan", WHEEL_RAIL, {"geometry.element_size": nan}, "[geometry] element_size"),
        ("grid n 1e9", PLANAR, {"grid.n": 10 ** 9}, "[grid] n"),
        ("grid n 0", PLANAR, {"grid.n": 0}, "[grid] n"),
        # every grid bounded at 1000 x 1000 elements (scene.MAX_GRID_ELEMENTS), memory or not
        ("grid n 1001: more than 1e6 elements", PLANAR, {"grid.n": 1001, "model.theory": "exact"}, "[grid] n"),
        ("grid mx x my 2000 x 600", PLANAR, {"grid": {"mx": 2000, "my": 600, "dx": 0.01, "dy": 0.01},
                                             "model.theory": "exact"}, "[grid] mx"),
        ("line grid of 5.5 million elements", PLANAR,
         {"geometry.B": 0.0, "grid": {"mx": 5_500_000, "my": 1, "dx": 1e-6, "dy": 1.0, "xl": -2.75, "yl": -0.5},
          "model.theory": "exact"}, "[grid] mx"),
        ("automatic line grid of 2 million elements", PLANAR,
         {"geometry.B": 0.0, "grid.n": 2_000_000, "model.theory": "exact"}, "[grid] n"),
        ("grid dx -1", PLANAR, {"grid": {"mx": 10, "my": 10, "dx": -1.0, "dy": 1.0}, "model.theory": "exact"}, "[grid] dx"),
        ("grid dy nan", PLANAR, {"grid": {"mx": 10, "my": 10, "dx": 1.0, "dy": nan}, "model.theory": "exact"}, "[grid] dy"),
        ("grid mx 0", PLANAR, {"grid": {"mx": 0, "my": 10, "dx": 1.0, "dy": 1.0}, "model.theory": "exact"}, "[grid] mx"),
        ("grid xl nan", PLANAR, {"grid": {"mx": 10, "my": 10, "dx": 1.0, "dy": 1.0, "xl": nan},
                                 "model.theory": "exact"}, "[grid] xl"),
        ("nu below Kalker's table", PLANAR, {"material.nu": -0.99}, "[material] nu"),
        ("lateral_shift 1 km", WHEEL_RAIL, {"geometry.lateral_shift": 1e6}, "[geometry] lateral_shift"),
        ("lateral_shift nan", WHEEL_RAIL, {"geometry.lateral_shift": nan}, "[geometry] lateral_shift"),
        ("wheel_load negative", WHEEL_RAIL, {"load.wheel_load": -1e4}, "[load] wheel_load"),
        ("wheel_load nan", WHEEL_RAIL, {"load.wheel_load": nan}, "[load] wheel_load"),
        # misspelt keys, a key in the wrong section
        ("misspelt Nu", PLANAR, {"material.Nu": 0.3}, "did you mean 'nu'"),
        ("misspelt Mu", PLANAR, {"friction.Mu": 0.3}, "did you mean 'mu'"),
        ("misspelt a for A", PLANAR, {"geometry.a": 0.3}, "did you mean 'A'"),
        ("misspelt normal_froce", PLANAR, {"load.normal_froce": 1.0}, "did you mean 'normal_force'"),
        ("misspelt ksi", PLANAR, {"kinematics.ksi": 1e-3}, "[kinematics] ksi: unknown key"),
        ("misspelt N", PLANAR, {"grid.N": 10}, "did you mean 'n'"),
        ("misspelt tehory", PLANAR, {"model.tehory": "exact"}, "did you mean 'theory'"),
        ("xi in [load]", PLANAR, {"load.xi": 1e-3}, "[load] xi: unknown key"),
        ("misspelt lateral_shfit", WHEEL_RAIL, {"geometry.lateral_shfit": 1.0}, "did you mean 'lateral_shift'"),
        ("misspelt wheelprofile", WHEEL_RAIL, {"geometry.wheelprofile": "S1002"}, "did you mean 'wheel_profile'"),
        ("misspelt section materail", PLANAR, {"materail.G": 1.0}, "did you mean 'material'"),
        ("name empty", PLANAR, {"name": ""}, "name: must be a non-empty string"),
        ("a vehicle scene", PLANAR, {"vehicle.mass": 1000.0}, "[vehicle]: this is a vehicle scene"),
    ]
    return out


CASES = _cases()


def _one_line(text: str) -> str:
    lines = text.strip().splitlines()
    assert len(lines) == 1, text
    return lines[0]


def test_at_least_150_distinct_trials():
    assert len(CASES) >= 150 and len({c[0] for c in CASES}) == len(CASES)


@pytest.mark.parametrize("name, base, changes, key", CASES, ids=[c[0] for c in CASES])
def test_api_refuses_naming_the_key(tmp_path, name, base, changes, key):
    with pytest.raises(ConformalError) as info:
        conformal.solve(edit(base, changes))
    msg = str(info.value)
    assert key in msg and "\n" not in msg and isinstance(info.value, (InputError, ConformalError))
    assert "allow_pickle" not in msg and "Traceback" not in msg


# ----------------------------------------------------------------------------- the CLI, in-process
def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf else repr(v))
    if isinstance(v, (int,)):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(v)


def to_toml(d: dict) -> str:
    """A scene mapping as TOML text (enough for these trials: scalars, lists, inline tables)."""
    lines = [f"{k} = {_toml_value(v)}" for k, v in d.items() if not isinstance(v, dict)]  # before the tables
    for k, v in d.items():
        if isinstance(v, dict):
            lines.append(f"[{k}]")
            lines += [f"{kk} = {_toml_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


#: the CLI trials: every fifth scene trial (a spread over the sections) ...
CLI_SCENE_CASES = CASES[::5]


@pytest.mark.parametrize("name, base, changes, key", CLI_SCENE_CASES, ids=[c[0] for c in CLI_SCENE_CASES])
def test_cli_solve_exit_2_one_line(tmp_path, capsys, name, base, changes, key):
    f = tmp_path / "s.toml"
    f.write_text(to_toml(edit(base, changes)), encoding="utf-8")
    code = main(["solve", str(f)])
    out, err = capsys.readouterr()
    line = _one_line(err)
    assert code == 2 and out == "" and line.startswith("conformal: error:") and key in line


def _planar_file(tmp_path, **changes):
    f = tmp_path / f"p{len(list(tmp_path.glob('p*.toml')))}.toml"
    f.write_text(to_toml(edit(PLANAR, changes)), encoding="utf-8")
    return str(f)


# ... and the command line's own inputs
CLI_ARGS = [
    ("theory unknown", lambda t: ["solve", _planar_file(t), "--theory", "kalker"], "--theory"),
    ("json into a folder", lambda t: ["solve", _planar_file(t), "--json", str(t)], "--json"),
    ("plot suffix", lambda t: ["solve", _planar_file(t), "--plot", str(t / "x.xyz")], "--plot"),
    ("plot into a file's folder", lambda t: ["solve", _planar_file(t), "--plot", _planar_file(t) + "/x.png"],
     "--plot"),
    ("vtu with fastsim", lambda t: ["solve", _planar_file(t), "--vtu", str(t / "x.vtu")], "--vtu"),
    ("vtu suffix", lambda t: ["solve", _planar_file(t), "--vtu", str(t / "x.vtk")], "--vtu"),
    ("scene missing", lambda t: ["solve", str(t / "nope.toml")], "scene file not found"),
    ("scene a folder", lambda t: ["solve", str(t)], "scene file not found"),
    ("scene not TOML", lambda t: ["solve", _write(t, "x.toml", "mu = = 3")], "not a valid TOML file"),
    ("scene binary", lambda t: ["solve", _write(t, "x.toml", b"\x00\xff\xfe")], "not a valid TOML file"),
    ("scene empty", lambda t: ["solve", _write(t, "x.toml", "")], "[geometry] kind"),
    ("sweep on a planar scene", lambda t: ["sweep", _planar_file(t), "--out", str(t / "o")], "[geometry] kind"),
    ("precompute workers 0", lambda t: ["precompute", _planar_file(t), "--sweep", "shift=0:1:0.5",
                                        "--workers", "0"], "--workers"),
    ("table info: text file", lambda t: ["table", "info", _write(t, "t.npz", "hello")], "not a creep table"),
    ("table info: missing", lambda t: ["table", "info", str(t / "none.npz")], "not found"),
    ("simulate: scene missing", lambda t: ["simulate", str(t / "v.toml")], "v.toml"),
    # fault trials: a run reported for nothing, numbers beyond the float range, bytes echoed
    ("inp: empty deck", lambda t: ["inp", _write(t, "e.inp", "")], "no cases"),
    ("inp: only comments", lambda t: ["inp", _write(t, "c.inp", "% nothing\n 0  MODULE\n")], "no cases"),
    ("influence file an NPZ", lambda t: ["solve", _planar_file(t, **{"model.theory": "exact", "model.influence_file":
                                                                     _write(t, "k.npz", b"PK\x03\x04\x00\x00junk")})],
     "a binary file"),
    ("simulate: speed 1e300", lambda t: ["simulate", _vehicle(t, "speed = 65.0", "speed = 1e300"), "--out", str(t / "o")],
     "[simulation] speed"),
    ("simulate: initial_lateral 1e300", lambda t: ["simulate", _vehicle(t, "initial_lateral = 0.0", "initial_lateral = 1e300"), "--out",
                                                    str(t / "o")], "[simulation] initial_lateral"),
    ("stresses: depth 1e300", lambda t: ["stresses", _planar_file(t), "--depth", "1e300"], "--depth"),
    ("table build: rho_max 1e300", lambda t: ["table", "build", _spec(t, "rho_max = 5.0", "rho_max = 1e300"),
                                              "--out", str(t / "t.npz")], "[table] rho_max"),
    ("table build: spin_max 1e300", lambda t: ["table", "build", _spec(t, "spin_max = 2.0", "spin_max = 1e300"),
                                               "--out", str(t / "t.npz")], "[table] spin_max"),
    ("table build: ratio_max 1e300", lambda t: ["table", "build", _spec(t, "ratio_max = 4.0", "ratio_max = 1e300"),
                                                "--out", str(t / "t.npz")], "[table] ratio_max"),
    ("stability: creep table a text file", lambda t: ["stability", _vehicle_line(
        t, 'creep_model = "table"\ntable = "' + _write(t, "x.npz", "text") + '"'), "--out", str(t / "o")],
     "[contact] table"),
    ("stability: G 1e308", lambda t: ["stability", _vehicle_line(t, "G = 1e308"), "--out", str(t / "o")], "[material] G"),
    ("stability: scene missing", lambda t: ["stability", str(t / "v.toml")], "v.toml"),
]


def _vehicle(t, line: str) -> str:
    """The dynamics EXAMPLE scene with one ``key = value`` line replaced."""
    import re

    from conformal.dynamics.scene import EXAMPLE

    key = line.split("=")[0].strip()
    text = EXAMPLE if key != "G" else re.sub(r"(?m)^E = .*$", "G = 82000.0", EXAMPLE)
    return _write(t, "v.toml", re.sub(rf"(?m)^{key} = .*$", line, text, count=1))


def _spec(t, old: str, new: str) -> str:
    """The shipped creep-table spec with one line replaced."""
    text = (ROOT / "conformal" / "data" / "tables" / "creep_default.toml").read_text(encoding="utf-8")
    assert old in text
    return _write(t, "spec.toml", text.replace(old, new))


def _write(t, name, content) -> str:
    p = t / name
    (p.write_bytes if isinstance(content, bytes) else p.write_text)(content)
    return str(p)


# ... the commands that came later (sweep, inp, stresses, simulate, stability) and argparse's own
_DECK = (ROOT / "tests" / "reference" / "contact_decks" / "carter2d.inp").read_text(encoding="latin-1")
_VEHICLE = (SCENES / "seed_wheelset.toml").read_text(encoding="utf-8")


def _wheel_rail_file(t) -> str:
    return _write(t, "wr.toml", to_toml(WHEEL_RAIL))


def _deck(t, old: str = "", new: str = "", name: str = "d.inp") -> str:
    assert old in _DECK
    return _write(t, name, _DECK.replace(old, new, 1) if old else _DECK)


def _vehicle(t, old: str = "", new: str = "") -> str:
    assert old in _VEHICLE
    return _write(t, "v.toml", _VEHICLE.replace(old, new, 1) if old else _VEHICLE)


def _vehicle_line(t, line: str) -> str:
    """The dynamics EXAMPLE scene with one ``key = value`` line replaced."""
    import re

    from conformal.dynamics.scene import EXAMPLE

    key = line.split("=")[0].strip()
    text = EXAMPLE if key != "G" else re.sub(r"(?m)^E = .*$", "G = 82000.0", EXAMPLE)
    return _write(t, "v.toml", re.sub(rf"(?m)^{key} = .*$", line, text, count=1))


def _stresses(t, section: str = "") -> str:
    return _write(t, "st.toml", to_toml(edit(PLANAR, {"model.theory": "exact", "grid.n": 12})) + section)


CLI_ARGS += [(f"sweep --shift {tag}", lambda t, v=v: ["sweep", _wheel_rail_file(t), "--shift", v, "--out", str(t / "o")],
              "--shift") for tag, v in (("two parts", "0:10"), ("text", "a:b:c"), ("step 0", "0:10:0"),
                                        ("reversed", "10:0:1"), ("negative step", "0:10:-1"),
                                        ("huge count", "0:1e9:1e-3"), ("nan", "nan:1:0.5"), ("inf", "0:inf:1"),
                                        ("empty", ""))]
CLI_ARGS += [
    ("sweep --out a file", lambda t: ["sweep", _wheel_rail_file(t), "--out", _planar_file(t)], "--out"),
    ("sweep --solve --workers 0", lambda t: ["sweep", _wheel_rail_file(t), "--solve", "--workers", "0"], "--workers"),
    ("sweep --solve huge count", lambda t: ["sweep", _wheel_rail_file(t), "--solve", "--shift", "0:1e6:0.01"],
     "--shift"),
    ("sweep --workers without --solve", lambda t: ["sweep", _wheel_rail_file(t), "--workers", "3"], "--workers"),
    ("inp missing deck", lambda t: ["inp", str(t / "none.inp")], "none.inp"),
    ("inp deck a folder", lambda t: ["inp", str(t)], "no such file"),
    ("inp empty deck", lambda t: ["inp", _write(t, "e.inp", "")], "e.inp: no cases"),
    ("inp bad control digits", lambda t: ["inp", _deck(t, "203100", "2x3100")], "PBTNFS"),
    ("inp module 7", lambda t: ["inp", _deck(t, " 3  MODULE", " 7  MODULE")], "module 7"),
    ("inp truncated", lambda t: ["inp", _write(t, "tr.inp", _DECK[:_DECK.index("   999")])], "unexpected end of file"),
    ("inp --cases text", lambda t: ["inp", _deck(t), "--cases", "a"], "--cases"),
    ("inp --cases 0", lambda t: ["inp", _deck(t), "--cases", "0"], "--cases"),
    ("inp --cases beyond the deck", lambda t: ["inp", _deck(t), "--cases", "99"], "--cases"),
    ("inp --out a file", lambda t: ["inp", _deck(t), "--out", _planar_file(t)], "--out"),
    ("inp MX 5.5 million", lambda t: ["inp", _deck(t, "  55   1   -1.0500", "  5500000   1   -1.0500")],
     "line 23: MX, MY"),
    ("inp FN nan", lambda t: ["inp", _deck(t, "35780.   -0.00024", "nan   -0.00024")], "line 17"),
    ("inp G negative", lambda t: ["inp", _deck(t, "82000.   82000.", "-82000.   82000.")], "G1"),
    ("inp binary", lambda t: ["inp", _write(t, "b.inp", bytes(range(256)) * 4)], "b.inp"),
    ("inp digit out of range", lambda t: ["inp", _deck(t, "203100", "209100")], "control digit T = 9"),
    ("inp nu 0.5", lambda t: ["inp", _deck(t, "0.280    0.280    82000.", "0.500    0.280    82000.")], "nu1"),
    ("inp MX 0", lambda t: ["inp", _deck(t, "  55   1   -1.0500", "  0   1   -1.0500")], "mx, my"),
    ("inp DX 0", lambda t: ["inp", _deck(t, "0.0400   200.0", "0.0000   200.0")], "dx, dy"),
    ("stresses --depth -1", lambda t: ["stresses", _stresses(t), "--depth", "-1"], "--depth"),
    ("stresses --depth nan", lambda t: ["stresses", _stresses(t), "--depth", "nan"], "--depth"),
    ("stresses --depth 0", lambda t: ["stresses", _stresses(t), "--depth", "0"], "--depth"),
    ("stresses --k 0", lambda t: ["stresses", _stresses(t), "--k", "0"], "--k"),
    ("stresses --k -5", lambda t: ["stresses", _stresses(t), "--k", "-5"], "--k"),
    ("stresses --k inf", lambda t: ["stresses", _stresses(t), "--k", "inf"], "--k"),
    ("stresses --body 3", lambda t: ["stresses", _stresses(t), "--body", "3"], "--body"),
    ("stresses --depth text", lambda t: ["stresses", _stresses(t), "--depth", "abc"], "--depth"),
    ("stresses --plot suffix", lambda t: ["stresses", _stresses(t), "--plot", str(t / "x.xyz")], "--plot"),
    ("stresses --vtu under a file", lambda t: ["stresses", _stresses(t), "--vtu", _planar_file(t) + "/x.vtu"], "--vtu"),
    ("stresses on hertz", lambda t: ["stresses", _planar_file(t, **{"model.theory": "hertz"})], "'hertz'"),
]
CLI_ARGS += [(f"[stresses] {text.split(' = ')[0]} = {text.split(' = ')[1]}",
              lambda t, text=text: ["stresses", _stresses(t, f"[stresses]\n{text}\n")], key) for text, key in (
    ("n_depths = 0", "[stresses] n_depths"), ("n_depths = 1000000000", "[stresses] n_depths"),
    ("n_depths = 2.5", "[stresses] n_depths"), ("body = 3", "[stresses] body"), ('k = "abc"', "[stresses] k"),
    ("dept = 2.0", "[stresses] dept: unknown key"), ("k = -300.0", "[stresses] k"), ("alpha_dv = nan", "[stresses] alpha_dv"),
    ("tau_e = -1.0", "[stresses] tau_e"), ("depth = -2.0", "[stresses] depth"), ("fe_body = true", "[stresses] fe_body"))]
CLI_ARGS += [
    ("no command", lambda t: [], "command"),
    ("unknown command", lambda t: ["solv", _planar_file(t)], "'solv'"),
    ("unknown option", lambda t: ["solve", _planar_file(t), "--thoery", "exact"], "--thoery"),
    ("stability --method eig", lambda t: ["stability", _vehicle(t), "--method", "eig"], "--method"),
    ("table build without --out", lambda t: ["table", "build"], "--out"),
    ("cache purge", lambda t: ["cache", "purge"], "'purge'"),
    ("table info a folder", lambda t: ["table", "info", str(t)], "creep table"),
    ("table info empty", lambda t: ["table", "info", _write(t, "em.npz", b"")], "not a creep table"),
    ("precompute --sweep without range", lambda t: ["precompute", _wheel_rail_file(t), "--sweep", "shift",
                                                    "--dry-run"], "--sweep"),
    ("precompute --sweep speed", lambda t: ["precompute", _wheel_rail_file(t), "--sweep", "speed=0:1:0.5",
                                            "--dry-run"], "--sweep"),
    ("precompute --sweep step 0", lambda t: ["precompute", _wheel_rail_file(t), "--sweep", "shift=0:1:0",
                                             "--dry-run"], "--sweep"),
    ("precompute a planar scene", lambda t: ["precompute", _planar_file(t), "--sweep", "shift=0:1:0.5", "--dry-run"],
     "[geometry] kind"),
    ("simulate --speed -10", lambda t: ["simulate", _vehicle(t), "--speed", "-10"], "--speed"),
    ("simulate --speed nan", lambda t: ["simulate", _vehicle(t), "--speed", "nan"], "--speed"),
    ("simulate --speed in km/h", lambda t: ["simulate", _vehicle(t), "--speed", "5000"], "--speed"),
    ("simulate --out a file", lambda t: ["simulate", _vehicle(t), "--out", _planar_file(t)], "--out"),
    ("stability --v-max 0", lambda t: ["stability", _vehicle(t), "--v-max", "0"], "--v-max"),
    ("stability --tol nan", lambda t: ["stability", _vehicle(t), "--method", "nonlinear", "--tol", "nan"], "--tol"),
    ("a contact scene to simulate", lambda t: ["simulate", _planar_file(t)], "this is a contact scene"),
]
CLI_ARGS += [(f"vehicle {tag}", lambda t, cmd=cmd, old=old, new=new: [cmd, _vehicle(t, old, new)]
              + (["--out", str(t / "o")] if cmd != "solve" else []), key) for tag, cmd, old, new, key in (
    ("mass -1", "stability", "mass = 1568.0", "mass = -1.0", "[vehicle] mass"),
    ("mas misspelt", "stability", "mass = 1568.0", "mas = 1568.0", "did you mean 'mass'"),
    ("creep_model fast", "stability", 'creep_model = "fastsim"', 'creep_model = "fast"', "[contact] creep_model"),
    ("t_end 0", "simulate", "t_end = 2.0", "t_end = 0.0", "[simulation] t_end"),
    ("method Euler", "simulate", "t_end = 2.0", 't_end = 2.0\nmethod = "Euler"', "[simulation] method"),
    ("wheel_radius in m", "stability", "wheel_radius = 473.8", "wheel_radius = 0.4738", "[wheels] wheel_radius"),
    ("gauge in m", "stability", "gauge = 1435.0", "gauge = 1.435", "[track] gauge"),
    ("fastsim_n 0", "stability", "mu = 0.5", "mu = 0.5\nfastsim_n = 0", "[contact] fastsim_n"),
    ("wheel_load nan", "stability", "wheel_load = 49000.0", "wheel_load = nan", "[vehicle] wheel_load"),
    ("wavelength 0", "simulate", "wavelength = 11887.2", "wavelength = 0.0", "[track.irregularity] wavelength"),
    ("rail middle", "simulate", 'rail = "right"', 'rail = "middle"', "[track.irregularity] rail"),
    ("rtol 0", "simulate", "t_end = 2.0", "t_end = 2.0\nrtol = 0.0", "[simulation] rtol"),
    ("output_step -1", "simulate", "t_end = 2.0", "t_end = 2.0\noutput_step = -1.0", "[simulation] output_step"),
    ("speed in km/h", "simulate", "speed = 65.0", "speed = 234.0e1", "[simulation] speed"),
    ("to solve", "solve", "", "", "[vehicle]: this is a vehicle scene"))]


@pytest.mark.parametrize("name, argv, key", CLI_ARGS, ids=[c[0] for c in CLI_ARGS])
def test_cli_arguments_exit_2_one_line(tmp_path, capsys, name, argv, key):
    code = main(argv(tmp_path))
    out, err = capsys.readouterr()
    line = _one_line(err)
    assert code == 2 and line.startswith("conformal: error:") and key in line, (code, err)


# ----------------------------------------------------------------------------- files as a user gives them
_RAIL = ROOT / "conformal" / "data" / "profiles" / "uic60_head_r300w21_analytic.csv"


def _rail_rows() -> list[str]:
    return [ln for ln in _RAIL.read_text(encoding="utf-8").splitlines() if ln.strip() and not ln.startswith("#")]


def _profile(t, name, rows) -> dict:
    return edit(WHEEL_RAIL, {"geometry.rail_profile": _write(t, name, "\n".join(rows) + "\n")})


def _scaled(rows, fy, fz) -> list[str]:
    return [f"{float(y) * fy:.6f}, {float(z) * fz:.6f}" for y, z in (r.split(",") for r in rows)]


EXACT = edit(PLANAR, {"model.theory": "exact", "grid.n": 10})
FILE_CASES = [
    ("profile with NaN", lambda t: _profile(t, "nan.csv", _rail_rows()[:50] + ["nan, 1.0"] + _rail_rows()[50:]),
     "[geometry] rail_profile: profile nan.csv: line"),
    ("profile of one point", lambda t: _profile(t, "one.csv", _rail_rows()[:1]), "too few points"),
    ("profile empty", lambda t: _profile(t, "empty.csv", []), "[geometry] rail_profile"),
    ("profile in metres", lambda t: _profile(t, "m.csv", _scaled(_rail_rows(), 1e-3, 1e-3)), "span only"),
    ("profile in micrometres", lambda t: _profile(t, "um.csv", _scaled(_rail_rows(), 1e3, 1e3)),
     "at most 2000 mm long"),
    ("profile of three columns", lambda t: _profile(t, "c3.csv", [r + ", 0.0" for r in _rail_rows()]), "two columns"),
    ("profile zigzag", lambda t: _profile(t, "zig.csv", _rail_rows()[:100] + _rail_rows()[60:80] + _rail_rows()[100:]),
     "points out of order"),
    ("profile header only", lambda t: _profile(t, "hdr.csv", ["y,z"]), "too few points"),
    ("profile with decimal commas", lambda t: _profile(t, "dc.csv", [r.replace(".", ",").replace(", ", ";")
                                                                     for r in _rail_rows()]), "two columns"),
    ("profile shuffled", lambda t: _profile(t, "shuf.csv", _rail_rows()[::7] + _rail_rows()[3::7]),
     "the curve intersects itself"),
    ("profile binary", lambda t: edit(WHEEL_RAIL, {"geometry.rail_profile": _write(t, "b.csv", bytes(range(256)))}),
     "binary file"),
    ("profile .prr without points", lambda t: edit(WHEEL_RAIL, {"geometry.rail_profile": _write(
        t, "x.prr", "units.len.f = 1000\n")}), "point.begin"),
    ("mu_table empty", lambda t: edit(EXACT, {"friction.mu_table": _write(t, "mu.txt", "")}), "[friction] mu_table"),
    ("mu_table a folder", lambda t: edit(EXACT, {"friction.mu_table": str(t)}), "[friction] mu_table"),
    ("mu_table NaN", lambda t: edit(EXACT, {"friction.mu_table": _write(t, "mu.txt", "nan\n" * 100)}),
     "[friction] mu_table"),
    ("rigid_slip a folder", lambda t: edit(EXACT, {"kinematics.rigid_slip": str(t)}), "[kinematics] rigid_slip"),
    ("rigid_slip empty", lambda t: edit(EXACT, {"kinematics.rigid_slip": _write(t, "rs.txt", "")}),
     "[kinematics] rigid_slip"),
    ("influence_file a folder", lambda t: edit(EXACT, {"model.influence_file": str(t)}), "[model] influence_file"),
    ("influence_file empty", lambda t: edit(EXACT, {"model.influence_file": _write(t, "if.txt", "")}),
     "[model] influence_file"),
    ("influence_file text", lambda t: edit(EXACT, {"model.influence_file": _write(t, "if.txt", "hello\n")}),
     "[model] influence_file"),
    ("creep table empty", lambda t: edit(PLANAR, {"model.theory": "table", "model.table": _write(t, "e.npz", "")}),
     "[model] table"),
    ("creep table a folder", lambda t: edit(PLANAR, {"model.theory": "table", "model.table": str(t)}), "[model] table"),
    ("creep table text", lambda t: edit(PLANAR, {"model.theory": "table", "model.table": _write(t, "t.npz", "hi")}),
     "[model] table: creep table"),
    ("geometry file a folder", lambda t: edit(PLANAR, {"geometry": {"kind": "table", "file": str(t)}}),
     "[geometry] file"),
    ("geometry file NaN", lambda t: edit(EXACT, {"geometry": {"kind": "table", "file": _write(t, "g.txt", "nan " * 100)},
                                               "grid": {"mx": 10, "my": 10, "dx": .5, "dy": .5}}), "[geometry] file"),
]
SWEEP_API = [
    ("sweep shift empty list", dict(shift=[]), "--shift"),
    ("sweep shift nan", dict(shift=[math.nan]), "--shift"),
    ("sweep shift text", dict(shift="x"), "--shift"),
    ("sweep shift list of text", dict(shift=["a"]), "--shift"),
    ("sweep shift None", dict(shift=None), "--shift"),
    ("sweep shift bool", dict(shift=True), "--shift"),
    ("sweep shift list too long", dict(shift=[0.0] * 10001), "too many"),
    ("sweep workers 0", dict(shift=[0.0], workers=0), "--workers"),
    ("sweep unknown override", dict(shift=[0.0], model__colour=1), "[model] colour"),
]


@pytest.mark.parametrize("name, scene, key", FILE_CASES, ids=[c[0] for c in FILE_CASES])
def test_files_refused_naming_the_key(tmp_path, name, scene, key):
    with pytest.raises(ConformalError) as info:
        conformal.solve(scene(tmp_path))
    msg = str(info.value)
    assert key in msg and "\n" not in msg and "Traceback" not in msg


@pytest.mark.parametrize("name, kwargs, key", SWEEP_API, ids=[c[0] for c in SWEEP_API])
def test_sweep_api_refuses(name, kwargs, key):
    with pytest.raises(InputError, match=re.escape(key)):
        conformal.sweep(WHEEL_RAIL, **kwargs)
    with pytest.raises(InputError, match=r"\[geometry\] kind"):
        conformal.sweep(PLANAR, shift=[0.0])


# ----------------------------------------------------------------------------- the right answers
RIGHT = [
    ("tol at its bound", {"model.tol": 1e-2}, lambda r: r.FX < 0),
    ("nu of both bodies", {"material.nu": 0.3}, lambda r: r.extra.get("nu", 0.3) == 0.3),
    ("text numbers in a list are not needed: n as int", {"grid.n": 12}, lambda r: r.FN == pytest.approx(1e4)),
    ("fastsim n ignored on a covering grid, still checked", {"model.n": 10}, lambda r: r.FX < 0),
    ("hertz with creepages warns", {"model.theory": "hertz"},
     lambda r: any("creepages are not used" in w for w in r.warnings) and r.FX == 0.0),
    ("hertz without creepages is quiet", {"model.theory": "hertz", "kinematics.xi": 0.0},
     lambda r: r.warnings == []),
    ("E instead of G", {"material.G": DELETE, "material.E": 210000.0}, lambda r: r.FN == pytest.approx(1e4)),
]


@pytest.mark.parametrize("name, changes, check", RIGHT, ids=[c[0] for c in RIGHT])
def test_accepted_inputs_give_the_right_answer(name, changes, check):
    assert check(conformal.solve(edit(PLANAR, changes)))


HERTZ = edit(PLANAR, {"model.theory": "hertz", "kinematics.xi": 0.0})
#: valid values that a new user may mean otherwise (units): the right answer, checked against an
#: analytic scaling or a limit
RIGHT_AGAINST_THEORY = [
    ("xi 1e10: full slip, |FX| = mu FN", edit(PLANAR, {"kinematics.xi": 1e10}),
     lambda r: r.FX == pytest.approx(-0.3 * r.FN, rel=5e-3)),
    ("G 82 (GPa meant): Hertz a 10 times larger (a ~ G^(-1/3))", edit(HERTZ, {"material.G": 82.0}),
     lambda r: r.a == pytest.approx(10.0 * conformal.solve(HERTZ).a, rel=1e-9)),
    ("normal_force 1e12: pmax ~ FN^(1/3)", edit(HERTZ, {"load.normal_force": 1e12}),
     lambda r: r.pmax == pytest.approx(1e8 ** (1 / 3) * conformal.solve(HERTZ).pmax, rel=1e-9)),
    ("a key of another theory: same answer, a warning", edit(PLANAR, {"model.fec_n": 6}),
     lambda r: r.FX == conformal.solve(PLANAR).FX and r.warnings == [
         "[model] fec_n: not read by theory 'fastsim' (read by fe_contact); it has no effect here"]),
    ("bound given to exact is its default: no warning", edit(PLANAR, {"model.theory": "exact", "grid.n": 10}),
     lambda r: not any("not read" in w for w in r.warnings)),
]


@pytest.mark.parametrize("name, scene, check", RIGHT_AGAINST_THEORY, ids=[c[0] for c in RIGHT_AGAINST_THEORY])
def test_valid_surprising_inputs_give_the_right_answer(name, scene, check):
    assert check(conformal.solve(scene))


def test_fe_keys_without_fe_influence_warn():
    from conformal.scene import scene_from_dict, unread_model_options

    s = scene_from_dict(edit(WHEEL_RAIL, {"model.theory": "conformal", "model.fe_order": 2, "model.max_mx": 50}))
    assert unread_model_options(s) == ['[model] fe_order: read only with [model] influence = "fe" (FE influence '
                                       "numbers), this scene has influence = 'halfspace'; it has no effect here"]
    assert unread_model_options(s.with_("model.influence", "fe")) == []


def test_line_grid_bounded_by_its_elements_not_n_squared():
    """A line grid of n elements (one row) is bounded by n, not n x n: 2000 elements are accepted."""
    from conformal.scene import MAX_GRID_ELEMENTS, grid_memory, scene_from_dict

    s = scene_from_dict(edit(PLANAR, {"geometry.B": 0.0, "grid.n": 2000, "model.theory": "exact"}))
    assert grid_memory(s)[:2] == (2000, 1) and 2000 ** 2 > MAX_GRID_ELEMENTS


def test_keys_the_theory_does_not_read_warn_when_given():
    from conformal.scene import scene_from_dict, unread_model_options

    s = scene_from_dict(edit(PLANAR, {"model.tol": 1e-9, "model.maxit": 50}))
    assert unread_model_options(s) == [
        "[model] tol = 1e-09: theory 'fastsim' does not iterate to a tolerance (closed form or one pass); "
        "it has no effect here",
        "[model] maxit = 50: theory 'fastsim' does not iterate to a tolerance (closed form or one pass); "
        "it has no effect here"]
    assert unread_model_options(scene_from_dict(edit(PLANAR, {"model.tol": 1e-6, "model.maxit": 1000}))) == []
    assert unread_model_options(scene_from_dict(edit(PLANAR, {"model.theory": "exact", "model.tol": 1e-9}))) == []
    exact = scene_from_dict(edit(PLANAR, {"model.theory": "exact", "model.bound": "elliptic"}))
    assert unread_model_options(exact) == [
        "[model] bound = 'elliptic': the traction bound of FASTSIM, read only by theory 'fastsim' "
        "(this scene: 'exact'); it has no effect here"]
    assert unread_model_options(scene_from_dict(edit(PLANAR, {"model.bound": "elliptic"}))) == []
    disc = scene_from_dict(edit(FE_CONTACT, {"model.fec_section_size": 30.0}))
    assert unread_model_options(disc) == [
        "[model] fec_section_size: read only with [model] fec_body = \"section\", this scene has fec_body = "
        "'disc'; it has no effect here"]
    assert unread_model_options(disc.with_("model.fec_body", "section")) == []


def _inp_warnings(tmp_path, capsys, old: str, new: str) -> list:
    assert main(["inp", _deck(tmp_path, old, new)]) == 0
    return json.loads(capsys.readouterr().out.splitlines()[0])["warnings"]


def test_inp_eps_and_maxgs_not_silently_changed(tmp_path, capsys):
    """The deck's MAXGS is not used (a warning names it); a negative EPS warns with the tol used."""
    maxgs = ("MAXGS = 999 (CONTACT's Gauss-Seidel iteration limit) is not used: the solver here stops at its "
             "own limit, maxit = 1000")
    assert _inp_warnings(tmp_path, capsys, "", "") == [maxgs]
    assert _inp_warnings(tmp_path, capsys, "1     1e-5 ", "1    -1e-5 ") == [
        maxgs, "EPS = -1e-05 is not a tolerance (must be > 0): the solver uses tol = 1e-10"]


def test_profile_order_and_repeated_points_do_not_change_the_answer(tmp_path):
    rows = _rail_rows()
    ref = conformal.solve(_profile(tmp_path, "r.csv", rows))
    for name, r in (("rev.csv", rows[::-1]), ("dup.csv", rows[:50] + rows[49:])):
        got = conformal.solve(_profile(tmp_path, name, r))
        assert (got.FN, got.a, got.b) == pytest.approx((ref.FN, ref.a, ref.b), rel=1e-9)


def test_version_and_fortran_exponents(tmp_path, capsys):
    assert main(["--version"]) == 0 and capsys.readouterr().out.strip() == f"conformal {conformal.__version__}"
    assert main(["inp", _deck(tmp_path)]) == 0
    ref = json.loads(capsys.readouterr().out)
    assert main(["inp", _deck(tmp_path, "1e-5     MAXGS", "1d-5     MAXGS", name="f.inp")]) == 0   # Fortran's D
    assert json.loads(capsys.readouterr().out) == ref


def _documented_keys():
    """Every scene key the reference documents (scene._KEY_DOCS and the registry's [model] keys)."""
    from dataclasses import fields

    from conformal.registry import MODELS
    from conformal.scene import _KEY_DOCS, ModelSpec

    keys = [f"{sec}.{k}" for sec, docs in _KEY_DOCS.items() if sec != "[history]" for k in docs]
    keys += [f"model.{f.name}" for f in fields(ModelSpec) if f.name != "options"] + [f"model.{k}" for k in MODELS.options()]
    keys += [f"model.{me.name}.{o.name}" for me in MODELS.methods for o in me.options]      # [model.fe] order
    return keys


#: a valid value (and the scene it is valid in, and the keys it replaces) where the generic trials fail
_KEY_VALUES = {
    "material.E": (210000.0, PLANAR, {"material.G": DELETE}), "material.body2": ({"G": 23000.0, "nu": 0.31}, PLANAR, {}),
    "friction.mu_static": (0.4, PLANAR, {"friction": {"mu_static": 0.4, "mu_kinetic": 0.3}}),
    "friction.mu_kinetic": (0.2, PLANAR, {"friction": {"mu_static": 0.3, "mu_kinetic": 0.2}}),
    "friction.angle_table": ([[-1.0, 0.3, 0.3], [0.0, 0.2, 0.2]], WHEEL_RAIL, {}),
    "geometry.kind": ("quadratic", PLANAR, {}), "geometry.placement": ("single", WHEEL_RAIL, {}),
    "geometry.gauge": (1436.0, WHEEL_RAIL, {}), "geometry.flange_back": (1361.0, WHEEL_RAIL, {}),
    "geometry.element_size_s": (0.5, edit(WHEEL_RAIL, {"geometry.element_size": 0.5}), {}),
    "geometry.wheel_z": ("down", WHEEL_RAIL, {}), "geometry.rail_z": ("down", WHEEL_RAIL, {}),
    "load.approach": (0.01, PLANAR, {"load.normal_force": DELETE}),
    "load.approach_along": (0.01, WHEEL_RAIL, {"model.theory": "conformal", "load.wheel_load": DELETE}),
    "load.load_angle": (0.1, edit(WHEEL_RAIL, {"model.theory": "conformal"}), {}),
    **{f"grid.{k}": (v, edit(PLANAR, {"model.theory": "exact", "grid": {"mx": 10, "my": 10, "dx": 0.5, "dy": 0.5}}), {})
       for k, v in (("mx", 12), ("my", 12), ("dx", 0.6), ("dy", 0.6), ("xl", -3.0), ("yl", -3.0))},
    "grid.n": (12, PLANAR, {}), "grid.strips": ("coupled", WHEEL_RAIL, {}),
    "model.bound": ("elliptic", PLANAR, {}), "model.influence": ("halfspace", PLANAR, {}),
    "model.theory": ("exact", PLANAR, {}), "model.creep_coefficients": ("kalker", PLANAR, {}), "model.n": (12, PLANAR, {}),
    "model.flexibilities": ([1e-5, 1e-5, 1e-5], PLANAR, {}), "model.discretisation": ("contact", PLANAR, {}),
    "model.max_mx": (50, PLANAR, {}), "model.max_ms": (50, PLANAR, {}), "model.creepage": ("surface", PLANAR, {}),
    "model.blanco_method": ("linear", PLANAR, {}), "model.table": ("default", PLANAR, {}),
    "model.fe.method": ("direct", PLANAR, {}), "model.fe_method": ("direct", PLANAR, {}),
    "model.fe.conform": ("all", PLANAR, {}), "model.fe_conform": ("all", PLANAR, {}),
    "model.fe.solver": ("splu", PLANAR, {}), "model.fe_solver": ("splu", PLANAR, {}),
    "model.fe.collocation": ("average", PLANAR, {}), "model.fe_collocation": ("average", PLANAR, {}),
    "model.fe.far_field": ("clamped", PLANAR, {}), "model.fe_far_field": ("clamped", PLANAR, {}),
    "model.fe.closure": ("cut", PLANAR, {}), "model.fe_closure": ("cut", PLANAR, {}),
    "model.fe_contact.far_field": ("clamped", PLANAR, {}), "model.fec_far_field": ("clamped", PLANAR, {}),
    "model.fe_contact.solver": ("splu", PLANAR, {}), "model.fec_solver": ("splu", PLANAR, {}),
    "model.fe_contact.estimate": ("grid", PLANAR, {}), "model.fec_estimate": ("grid", PLANAR, {}),
    "model.fe_contact.body": ("block", PLANAR, {}), "model.fec_body": ("block", PLANAR, {}),
    # files: a missing one is refused naming the key (the spelling is taken)
    "friction.mu_table": ("none.txt", EXACT, {}),
    "kinematics.rigid_slip": ("none.txt", EXACT, {}),
    "geometry.a": (5.0, edit(PLANAR, {"geometry": {"kind": "hertz", "a": 4.0, "b": 4.0}}), {}),
    "geometry.b": (5.0, edit(PLANAR, {"geometry": {"kind": "hertz", "a": 4.0, "b": 4.0}}), {}),
    "model.influence_file": ("none.txt", EXACT, {}),
}


def _outcome(make):
    from conformal.scene import scene_from_dict  # noqa: F401 - the scene is built by make()

    try:
        return make().to_dict()
    except InputError as exc:
        return str(exc)


def test_with_takes_every_documented_toml_key(tmp_path):
    """Issue 22 item 8 for every key: ``scene.with_("section.key", v)`` (and ``section__key=v``, the
    spelling of ``conformal.solve(path, **overrides)``) gives what editing the file gives, for every
    key the reference documents; none is "unknown"."""
    from conformal.scene import scene_from_dict

    keys = _documented_keys()
    assert len(keys) > 120
    h = "\n".join(" ".join(f"{1e-3 * ((i - 4.5) ** 2 + (j - 4.5) ** 2) * 0.25:.6f}" for j in range(10)) for i in range(10))
    table = edit(PLANAR, {"geometry": {"kind": "table", "file": _write(tmp_path, "h.txt", h)}, "model.theory": "exact",
                          "load.normal_force": 100.0, "grid": {"mx": 10, "my": 10, "dx": 0.5, "dy": 0.5}})
    values = {**_KEY_VALUES, "geometry.file": (str(tmp_path / "h.txt"), table, {})}
    refused, untried = [], []
    for path in keys:
        value, base, extra = values.get(path, (None, None, {}))
        tries = [(value, base)] if base is not None else [(v, b) for b in (PLANAR, WHEEL_RAIL) for v in (
            0.5, 1, 2, 1e-5, "steady", True, "right")]
        for v, b in tries:
            sec, _, key = path.partition(".")
            nested = {f"{sec}.{key.split('.')[0]}": {key.split(".")[1]: v}} if "." in key else {path: v}
            file_scene = _outcome(lambda: scene_from_dict(edit(b, {**extra, **nested})))
            if isinstance(file_scene, str) and base is None:
                continue                                 # not valid here: the next value
            base_scene = scene_from_dict(edit(b, {k: x for k, x in extra.items() if k.split(".")[0] != sec}))
            api = _outcome(lambda: base_scene.with_(path, v)) if not extra or base is not None else file_scene
            assert "unknown key" not in str(api) and "not a scene key" not in str(api), (path, api)
            kw = _outcome(lambda: base_scene.with_(**{path.replace(".", "__"): v}))
            assert kw == api, path
            if not extra:
                assert api == file_scene, (path, api, file_scene)
            refused += [(path, api)] if isinstance(api, str) else []
            break
        else:
            untried.append(path)
    assert not untried, f"no valid value tried for {untried}"
    # every key gives a scene but the files that are missing on purpose (refused naming the key; the
    # influence file is read by the solve)
    assert sorted(p for p, _ in refused) == ["friction.mu_table", "kinematics.rigid_slip"], refused
    assert all(msg.startswith(f"[{p.split('.')[0]}] {p.split('.')[1]}: no such file") for p, msg in refused), refused


def test_api_overrides_with_toml_names_match_the_file(tmp_path):
    """conformal.solve(path, friction__mu=0.4) equals the file edited to mu = 0.4."""
    f = _planar_file(tmp_path, **{"friction.mu": 0.4})
    a = conformal.solve(_planar_file(tmp_path), friction__mu=0.4)
    b = conformal.solve(f)
    assert a.FX == pytest.approx(b.FX, rel=1e-12)
    c = conformal.solve(_planar_file(tmp_path), material__nu=0.3)
    d = conformal.solve(_planar_file(tmp_path, **{"material.nu": 0.3}))
    assert c.FX == pytest.approx(d.FX, rel=1e-12)


# ----------------------------------------------------------------------------- a few real processes
@pytest.mark.parametrize("argv, code, key", [
    (["solve", str(SCENES / "circ.toml"), "--theory", "nonsense"], 2, "--theory"),
    (["solve", "/etc/passwd"], 2, "not a valid TOML file"),
    (["table", "info", "/etc/hostname"], 2, "creep table"),
])
def test_subprocess_exit_code_and_one_line(argv, code, key):
    p = subprocess.run([sys.executable, "-m", "conformal.cli", *argv], capture_output=True, text=True,
                       cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "OMP_NUM_THREADS": "1"},
                       timeout=120)
    assert p.returncode == code and key in _one_line(p.stderr) and "Traceback" not in p.stderr
