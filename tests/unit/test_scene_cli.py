"""Scene validation (every error names its key) and the `conformal solve` command line."""
import json
import math

import pytest

from conformal.cli import main
from conformal.errors import InputError
from conformal.scene import load_scene

GOOD = """\
name = "circle"
[material]
G = 82000.0
nu = 0.28
[friction]
mu = 0.3
[geometry]
kind = "quadratic"
A = 0.001
B = 0.0015
[load]
normal_force = 50000.0
[kinematics]
xi = 0.0005
eta = -0.0002
phi = 0.0
[grid]
n = 30
[model]
theory = "fastsim"
"""


def scene_file(tmp_path, text=GOOD, replace=None):
    if replace:
        old, new = replace
        assert old in text
        text = text.replace(old, new)
    f = tmp_path / "scene.toml"
    f.write_text(text, encoding="utf-8")
    return f


BAD = [  # (change to the good scene, text the one-line error must contain)
    (("normal_force = 50000.0", "normal_force = -5"), "[load] normal_force: must be > 0, got -5"),
    (("mu = 0.3", "mu = 0.0"), "[friction] mu: must be > 0"),
    (("mu = 0.3", "mu = -0.1"), "[friction] mu: must be > 0"),
    (("xi = 0.0005", "xi = nan"), "[kinematics] xi: must be a finite number"),
    (("eta = -0.0002", "eta = inf"), "[kinematics] eta: must be a finite number"),
    (("phi = 0.0", "phi = 0.0\nomega = 1.0"), "[kinematics] omega: unknown key"),
    (("A = 0.001", "A = 0.001\nC = 2.0"), "[geometry] C: unknown key"),
    (("[load]\nnormal_force = 50000.0\n", ""), "[load] normal_force: missing"),
    (('kind = "quadratic"\nA = 0.001\nB = 0.0015\n', 'kind = "quadratic"\nA = 0.001\n'), "[geometry] B: missing"),
    (("nu = 0.28", "nu = 0.6"), "[material] nu:"),
    (('theory = "fastsim"', 'theory = "magic"'), "[model] theory: must be one of"),
    (('theory = "fastsim"', 'theory = "fastsim"\nbound = "square"'), "[model] bound: must be one of"),
    (("n = 30", "n = 30\nmx = 10"), "[grid] dx: an explicit grid needs all of mx, my, dx, dy"),
    (("[grid]", "[gird]"), "[gird]: unknown section"),
    (("G = 82000.0", 'G = "steel"'), "[material] G: must be a number"),
]


@pytest.mark.parametrize("change, message", BAD)
def test_scene_validation_names_the_key(tmp_path, change, message):
    with pytest.raises(InputError) as exc:
        load_scene(scene_file(tmp_path, replace=change))
    assert message in str(exc.value)


def test_bad_toml_and_missing_file(tmp_path):
    with pytest.raises(InputError, match="not a valid TOML file"):
        load_scene(scene_file(tmp_path, replace=("mu = 0.3", "mu = = 0.3")))
    with pytest.raises(InputError, match="scene file not found"):
        load_scene(tmp_path / "nope.toml")


@pytest.mark.parametrize("change, message", BAD[:4] + [(("mu = 0.3", "mu = = 0.3"), "not a valid TOML file")])
def test_cli_bad_scene_exit_2_one_line(tmp_path, capsys, change, message):
    code = main(["solve", str(scene_file(tmp_path, replace=change))])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("conformal: error:") and message in lines[0]
    assert "Traceback" not in err


def test_cli_bad_option_value_is_one_line(tmp_path, capsys):
    # model-specific keys are checked by the model: still one line, exit 2
    code = main(["solve", str(scene_file(tmp_path, replace=('theory = "fastsim"',
                                                            'theory = "fastsim"\ndiscretisation = "x"')))])
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1 and "[model] discretisation" in err
    code = main(["solve", str(scene_file(tmp_path)), "--theory", "nonsense"])
    _, err = capsys.readouterr()
    assert code == 2 and "--theory" in err and len(err.strip().splitlines()) == 1


KEYS = ("FN", "FX", "FY", "MZ", "a", "b", "pmax", "approach", "n_contact", "n_slip", "theory",
        "converged", "wall_s")


@pytest.mark.parametrize("theory", ["fastsim", "hertz", "linear", "empirical", "johnson_vermeulen"])
def test_cli_good_scene_prints_json(tmp_path, capsys, theory):
    out_json = tmp_path / "out" / "r.json"
    code = main(["solve", str(scene_file(tmp_path)), "--theory", theory, "--json", str(out_json)])
    out, err = capsys.readouterr()
    # hertz solves the normal problem only: the scene's creepages are not used, and it says so
    assert code == 0 and err == ("" if theory != "hertz" else err.splitlines()[0] + "\n")
    assert theory != "hertz" or "creepages are not used" in err
    d = json.loads(out)
    assert all(k in d for k in KEYS)
    assert d["theory"] == theory and d["converged"] is True and d["wall_s"] >= 0
    assert d["FN"] == pytest.approx(50000.0) and d["a"] > 0 and d["b"] > 0
    assert json.loads(out_json.read_text()) == d
    if theory == "fastsim":
        assert d["n_contact"] > 0 and 0 < d["n_slip"] < d["n_contact"]
        assert d["FX"] < 0 and d["FY"] > 0            # xi > 0, eta < 0 (forces on body 1)
    elif theory in ("empirical", "johnson_vermeulen"):
        assert d["MZ"] is None and d["FX"] < 0
    else:
        assert d["n_contact"] is None and math.isfinite(d["MZ"])


def test_demo_solves_the_flange_scene_and_balances_the_wheel_load(tmp_path, capsys):
    """`conformal demo` (README command 1, docs/getting-started.md): conformal contact of S1002 on UIC60 at the flange root.
    The vertical force on the rail must equal the prescribed 10 kN wheel load (seed Eq. 46) and
    the patch must lie on the curved gauge corner (contact angles spread over more than 10 deg)."""
    import json

    from conformal.cli import main

    assert main(["demo", "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "demo.json").read_text())
    assert summary["theory"] == "conformal" and summary["converged"]
    assert summary["FZ_track"] == pytest.approx(10000.0, rel=1e-4)
    assert summary["contact_angle_spread_deg"] > 10.0
    assert (tmp_path / "demo.png").stat().st_size > 10_000
