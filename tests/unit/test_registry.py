"""The model registry (conformal.registry): declarations agree with the code that reads them, scene
validation and the CLI come from it, options nest by method with the flat keys still accepted, and
a model is added with its own module and one registry line (tests/unit/example_model.py)."""
from __future__ import annotations

import dataclasses
import math

import pytest

from conformal.errors import InputError
from conformal.registry import (CAPABILITIES, CURVED_STRIP, FE_BODIES, GRID, HISTORY, MODELS, Model, Option,
                                reference_markdown)
from conformal.scene import MODEL_OPTIONS, THEORIES, scene_from_dict

import example_model

QUADRATIC = {"geometry": {"kind": "quadratic", "A": 1.0 / 600.0, "B": 1.0 / 600.0}, "load": {"normal_force": 1e4}}


def _scene(model: dict, **sections):
    return scene_from_dict({**QUADRATIC, **sections, "model": model})


# ----------------------------------------------------------------------------- declarations
def test_every_registered_model_has_a_solve_function_and_the_scene_its_names():
    from conformal.models import SOLVE

    assert tuple(SOLVE) == MODELS.names == THEORIES
    assert set(MODEL_OPTIONS) == set(MODELS.options())
    for m in MODELS:
        assert m.capabilities <= set(CAPABILITIES)


def test_each_model_is_declared_once_and_its_solve_function_is_loaded_from_the_declaration():
    """Where each theory lives: its declaration (registry.py) names its module and function;
    conformal.models.SOLVE is loaded from those names (no theory name written in models.py), and
    every theory module with a solve function is declared."""
    import ast
    import importlib

    from _paths import ROOT

    from conformal.models import SOLVE

    where = {}
    for m in MODELS:
        module, _, name = m.solve.partition(":")
        assert SOLVE[m.name] is getattr(importlib.import_module(module), name), m.name
        where[m.name] = m.solve
    assert where == {
        "hertz": "conformal.theories.hertz:solve", "linear": "conformal.theories.linear:solve",
        "empirical": "conformal.theories.empirical:solve", "johnson_vermeulen": "conformal.theories.empirical:solve",
        "fastsim": "conformal.theories.fastsim:solve", "exact": "conformal.solvers.exact:solve",
        "conformal": "conformal.solvers.conformal:solve", "table": "conformal.tables.model:solve",
        "fe_contact": "conformal.fe_contact.problems:solve"}
    strings = {n.value for n in ast.walk(ast.parse((ROOT / "conformal" / "models.py").read_text()))
               if isinstance(n, ast.Constant) and isinstance(n.value, str)}
    assert not strings & set(MODELS.names), "models.py names theories: SOLVE must come from the declarations"
    theory_modules = {f"conformal.theories.{p.stem}" for p in (ROOT / "conformal" / "theories").glob("*.py")
                      if any(isinstance(n, ast.FunctionDef) and n.name == "solve"
                             for n in ast.parse(p.read_text()).body)}
    assert theory_modules and theory_modules <= {m.solve_module for m in MODELS}
    with pytest.raises(ValueError, match="not \"module:function\""):
        Model("x", "no function named", solve="conformal.theories.hertz")


def test_declared_defaults_are_the_defaults_the_code_uses():
    """The documented defaults (registry) against the dataclasses and constants the solvers read."""
    from conformal.fe_contact.bodies import ContactMesh
    from conformal.fe_contact.solver import FEContactSettings
    from conformal.influence.fe import FESettings
    from conformal.meshing.gmsh_body import MeshSpec
    from conformal.registry import COMMON
    from conformal.solvers.conformal import MAX_ELEMENTS
    from conformal.solvers.exact import MAXOUT
    from conformal.specs import ModelSpec

    code = {f.name: f.default for f in dataclasses.fields(MeshSpec)}
    code.update({f.name: f.default for f in dataclasses.fields(FESettings) if f.name != "mesh"})
    for o in MODELS.method("fe").options:
        assert o.default == code[o.name], o.key
    code = {f.name: f.default for f in dataclasses.fields(ContactMesh)}
    code.update({f.name: f.default for f in dataclasses.fields(FEContactSettings)})
    for o in MODELS.method("fe_contact").options:
        assert o.default == code[o.name], o.key
    spec = ModelSpec()
    for o in COMMON:
        assert o.default == getattr(spec, o.name), o.name
    assert MODELS.option("maxout").default == MAXOUT
    assert MODELS.option("max_mx").default == MODELS.option("max_ms").default == MAX_ELEMENTS


def test_memory_per_element_is_the_estimate_of_the_scene():
    from conformal.scene import grid_bytes

    assert grid_bytes(40, 30, "fastsim") == 40 * 30 * 240
    assert grid_bytes(40, 30, "exact") == 40 * 30 * 900
    # the conformal strips: dense 3 x 3 blocks along s, (2 mx) ms² complex numbers of 16 bytes
    assert grid_bytes(40, 30, "conformal") == 40 * 30 * 900 + 2.0 * 40 * 30**2 * 9 * 16


def test_capability_queries():
    assert MODELS.accepting(HISTORY) == ("exact",)
    assert MODELS.accepting(GRID) == ("exact", "conformal")
    assert MODELS.accepting(CURVED_STRIP) == ("conformal",)
    assert MODELS.accepting(FE_BODIES) == ("fe_contact",)
    assert [m.name for m in MODELS if m.normal_only] == ["hertz", "fe_contact"]
    with pytest.raises(ValueError, match="unknown capability"):
        MODELS["exact"].accepts("histroy")
    with pytest.raises(ValueError, match="named twice"):
        MODELS.with_model(Model("exact", "again"))


# ----------------------------------------------------------------------------- scene validation
def test_validation_messages_name_the_theories_that_accept_the_key(tmp_path):
    slip = tmp_path / "w.txt"
    slip.write_text("0 0\n")
    with pytest.raises(InputError, match=r'\[kinematics\] rigid_slip: only theory "exact" uses it'):
        _scene({"theory": "fastsim"}, kinematics={"rigid_slip": str(slip)})
    with pytest.raises(InputError, match=r'\[\[history\]\]: a load history is solved by theory "exact"'):
        scene_from_dict({**QUADRATIC, "model": {"theory": "fastsim"}, "history": [{"normal_force": 1e4}]})
    with pytest.raises(InputError, match=r'\[model\] n: must be a whole number >= 4, got 2.5 \(fastsim: number'):
        _scene({"theory": "fastsim", "n": 2.5})
    with pytest.raises(InputError, match=r"\[model\] creep_coefficients: must be one of 'kalker', 'elliptic'"):
        _scene({"theory": "empirical", "creep_coefficients": "johnson"})
    # CONTACT's rigid slip of the conformal strip: accepted when the scene is read (documented value)
    assert _scene({"theory": "fastsim", "creepage": "wheel_surface"}).model.options["creepage"] == "wheel_surface"


def test_nested_and_flat_model_keys_give_the_same_scene():
    from conformal.fe_contact.problems import settings_from_options as fec_settings
    from conformal.influence.fe import settings_from_options as fe_settings

    flat = _scene({"theory": "conformal", "fe_order": 2, "fe_h_patch": 1.5, "fec_n": 3, "maxout": 4})
    nested = _scene({"theory": "conformal", "maxout": 4, "fe": {"order": 2, "h_patch": 1.5},
                     "fe_contact": {"n": 3}})
    assert nested.model == flat.model and nested == flat
    assert fe_settings(nested.model.options) == fe_settings(flat.model.options)
    assert fe_settings(nested.model.options).mesh.order == 2
    assert fec_settings(nested.model.options)[0] == fec_settings(flat.model.options)[0]
    # the scene API takes the nested names too, and writes the flat ones
    assert flat.with_("model.fe.order", 1).model.options["fe_order"] == 1
    assert nested.to_dict()["model"]["fe_order"] == 2
    with pytest.raises(InputError, match=r"\[model.fe\] oder: unknown key \(did you mean 'order'\?\)"):
        _scene({"theory": "conformal", "fe": {"oder": 2}})
    with pytest.raises(InputError, match=r"\[model.fe\] order: given twice \(also as \[model\] fe_order\)"):
        _scene({"theory": "conformal", "fe_order": 1, "fe": {"order": 2}})


def test_nested_keys_from_a_toml_file(tmp_path):
    from conformal.scene import load_scene

    path = tmp_path / "s.toml"
    path.write_text('[geometry]\nkind = "quadratic"\nA = 0.001\nB = 0.001\n[load]\nnormal_force = 1e4\n'
                    '[model]\ntheory = "fe_contact"\n[model.fe_contact]\nn = 3\norder = 1\n', encoding="utf-8")
    assert dict(load_scene(path).model.options) == {"fec_n": 3, "fec_order": 1}


@pytest.mark.slow
def test_nested_and_flat_fe_contact_keys_give_identical_results():
    """The public interface: [model.fe_contact] n, order and the old fec_n, fec_order solve alike."""
    from conformal.dispatch import solve_scene

    base = {"geometry": {"kind": "quadratic", "A": 0.01, "B": 0.01}, "load": {"approach": 0.02}}
    flat = solve_scene(scene_from_dict({**base, "model": {"theory": "fe_contact", "fec_n": 2, "fec_order": 1}}))
    nested = solve_scene(scene_from_dict({**base, "model": {"theory": "fe_contact",
                                                            "fe_contact": {"n": 2, "order": 1}}}))
    for key in ("FN", "a", "b", "pmax", "approach"):
        assert getattr(nested, key) == getattr(flat, key), key
    assert flat.FN > 0


def test_cli_theory_help_and_reference_come_from_the_registry():
    from conformal.cli import build_parser

    help_text = build_parser().format_help() + "".join(
        a.format_help() for a in build_parser()._subparsers._group_actions[0].choices.values())
    for name in MODELS.names:
        assert name in help_text
    md = reference_markdown()
    assert "| `fe_order` |" not in md and "| `order` | whole number | 1 |" in md   # under [model.fe]
    assert "| `maxout` | whole number | 50 |" in md and "### [model.fe_contact]" in md
    for name in MODELS.names:
        assert f"### theory `{name}`" in md


# ----------------------------------------------------------------------------- adding a model
def test_a_model_is_added_with_its_module_and_one_registry_line():
    """tests/unit/example_model.py declares and solves Hertz's circular contact; one line adds it.  Its
    closed form (Johnson eqs. 4.22-4.23) agrees with the package's Hertz theory (elliptic integrals,
    conformal.theories.hertz) at A = B."""
    from conformal.models import solve_problem
    from conformal.problem import problems_from_scene

    models = MODELS.with_model(example_model.MODEL)          # the one registry line

    scene = scene_from_dict({**QUADRATIC, "model": {"theory": "circular_hertz", "max_ellipticity": 1e-6}},
                            models=models)
    r = solve_problem(problems_from_scene(scene)[0], models)
    hz = solve_problem(problems_from_scene(scene_from_dict({**QUADRATIC, "model": {"theory": "hertz"}}))[0])
    assert r.theory == "circular_hertz"
    for key in ("a", "pmax", "approach"):
        assert math.isclose(getattr(r, key), getattr(hz, key), rel_tol=1e-9), key
    # its option is validated from its declaration, its name is a theory, its keys are documented
    with pytest.raises(InputError, match=r"\[model\] max_ellipticity: must be a number"):
        scene_from_dict({**QUADRATIC, "model": {"theory": "circular_hertz", "max_ellipticity": "0"}},
                        models=models)
    with pytest.raises(InputError, match="must be one of"):
        scene_from_dict({**QUADRATIC, "model": {"theory": "circular_hertz"}})      # not in the package's
    assert "| `max_ellipticity` | number | 1e-09 |" in reference_markdown(models)
    assert "circular_hertz" in models.theory_help()
    # capabilities it does not declare are refused with the theories that have them
    with pytest.raises(InputError, match=r'\[\[history\]\]: a load history is solved by theory "exact"'):
        scene_from_dict({**QUADRATIC, "model": {"theory": "circular_hertz"}, "history": [{"normal_force": 1e4}]},
                        models=models)


def test_a_model_is_added_inside_the_package_with_its_module_and_one_registry_line(tmp_path):
    """The two touch points inside the package, in a copy of it: the model's module
    (conformal/theories/circular_hertz.py, the module of tests/unit/example_model.py) and one
    ``Model(...)`` line in registry.MODELS.  Nothing else changes, yet the theory is a scene's
    theory (validated, solved by conformal.solve), in the CLI's --theory help and in the reference."""
    import difflib
    import json
    import os
    import shutil
    import subprocess
    import sys

    from _paths import ROOT

    package = tmp_path / "conformal"
    shutil.copytree(ROOT / "conformal", package)                       # with __pycache__: no recompiling
    shutil.copy(ROOT / "tests" / "unit" / "example_model.py", package / "theories" / "circular_hertz.py")
    registry = package / "registry.py"
    before = registry.read_text(encoding="utf-8")
    end = "), methods=(FE, FE_CONTACT))"
    assert before.count(end) == 1
    line = ('    Model("circular_hertz", "Hertz\'s closed form for a circular contact", options=(Option('
            '"max_ellipticity", "float", 1e-9, "", "largest |A - B| / (A + B) accepted", minimum=0.0),), '
            'bytes_per_element=0.0, solve="conformal.theories.circular_hertz:solve"),\n')
    after = before.replace(end, line + end)
    registry.write_text(after, encoding="utf-8")
    changed = [d for d in difflib.ndiff(before.splitlines(True), after.splitlines(True)) if d[0] in "+-"]
    assert changed == ["+ " + line]

    script = """
import json
import conformal
from conformal.cli import build_parser
from conformal.errors import InputError
from conformal.registry import reference_markdown
q = {"geometry": {"kind": "quadratic", "A": 1 / 600, "B": 1 / 600}, "load": {"normal_force": 1e4}}
r = conformal.solve({**q, "model": {"theory": "circular_hertz", "max_ellipticity": 1e-6}})
hz = conformal.solve({**q, "model": {"theory": "hertz"}})
try:
    conformal.solve({**q, "model": {"theory": "circular_hertz", "max_ellipticity": "0"}})
    refused = ""
except InputError as e:
    refused = str(e)
sub = build_parser()._subparsers._group_actions[0].choices["solve"]
print(json.dumps({"file": conformal.__file__, "theory": r.theory, "refused": refused,
                  "new": [r.a, r.pmax, r.approach], "hertz": [hz.a, hz.pmax, hz.approach],
                  "help": "circular_hertz" in sub.format_help(),
                  "reference": "| `max_ellipticity` | number | 1e-09 |" in reference_markdown()}))
"""
    env = dict(os.environ, PYTHONPATH=str(tmp_path), OMP_NUM_THREADS="1")
    proc = subprocess.run([sys.executable, "-c", script], env=env, cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    d = json.loads(proc.stdout.strip().splitlines()[-1])
    assert d["file"] == str(package / "__init__.py")                   # the copy, not this checkout
    assert d["theory"] == "circular_hertz" and d["help"] and d["reference"]
    assert "[model] max_ellipticity: must be a number" in d["refused"]
    for new, hertz in zip(d["new"], d["hertz"]):                       # Johnson eqs. 4.22-4.23 = elliptic integrals
        assert math.isclose(new, hertz, rel_tol=1e-9)


def test_option_checks():
    o = Option("n", "int", 40, "", "strips", minimum=4)
    assert o.problem(40) is None and o.problem(3) == "must be >= 4, got 3" and "whole number" in o.problem(True)
    f = Option("L", "floats", None, "mm³/N", "flexibilities", length=3, minimum=0)
    assert f.problem([1.0, 2.0, 3.0]) is None and f.problem([1.0, 2.0]) and f.problem([1.0, -2.0, 3.0])


def test_scene_reference_lists_every_key_of_the_scene_sections():
    from conformal import scene as S
    from conformal.specs import Kinematics

    docs = S._KEY_DOCS
    assert set(docs["kinematics"]) == {f.name for f in dataclasses.fields(Kinematics)}
    assert set(docs["load"]) == {f.name for f in dataclasses.fields(S.Load)}
    assert set(docs["grid"]) == {f.name for f in dataclasses.fields(S.GridSpec)}
    geometry = set()
    for cls in (S.QuadraticGeometry, S.HertzGeometry, S.TableGeometry, S.WheelRailGeometry):
        geometry |= {f.name for f in dataclasses.fields(cls)}
    assert set(docs["geometry"]) == geometry
    md = S.reference_markdown()
    assert "| `rail_cant` | number | 0.0249948 | rad |" in md and "| `fec_n` |" not in md
    for name in MODELS.names:
        assert f"### theory `{name}`" in md
