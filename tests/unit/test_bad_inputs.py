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
    ("simulate: speed 1e300", lambda t: ["simulate", _vehicle(t, "speed = 1e300"), "--out", str(t / "o")],
     "[simulation] speed"),
    ("simulate: initial_lateral 1e300", lambda t: ["simulate", _vehicle(t, "initial_lateral = 1e300"), "--out",
                                                    str(t / "o")], "[simulation] initial_lateral"),
    ("stresses: depth 1e300", lambda t: ["stresses", _planar_file(t), "--depth", "1e300"], "--depth"),
    ("table build: rho_max 1e300", lambda t: ["table", "build", _spec(t, "rho_max = 5.0", "rho_max = 1e300"),
                                              "--out", str(t / "t.npz")], "[table] rho_max"),
    ("table build: spin_max 1e300", lambda t: ["table", "build", _spec(t, "spin_max = 2.0", "spin_max = 1e300"),
                                               "--out", str(t / "t.npz")], "[table] spin_max"),
    ("table build: ratio_max 1e300", lambda t: ["table", "build", _spec(t, "ratio_max = 4.0", "ratio_max = 1e300"),
                                                "--out", str(t / "t.npz")], "[table] ratio_max"),
    ("stability: creep table a text file", lambda t: ["stability", _vehicle(
        t, 'creep_model = "table"\ntable = "' + _write(t, "x.npz", "text") + '"'), "--out", str(t / "o")],
     "[contact] table"),
    ("stability: G 1e308", lambda t: ["stability", _vehicle(t, "G = 1e308"), "--out", str(t / "o")], "[material] G"),
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


@pytest.mark.parametrize("name, argv, key", CLI_ARGS, ids=[c[0] for c in CLI_ARGS])
def test_cli_arguments_exit_2_one_line(tmp_path, capsys, name, argv, key):
    code = main(argv(tmp_path))
    out, err = capsys.readouterr()
    line = _one_line(err)
    assert code == 2 and line.startswith("conformal: error:") and key in line, (code, err)


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
