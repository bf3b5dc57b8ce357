"""Issue 22: inputs that used to give a wrong answer without a word (the right number, or a
refusal naming the key, or a warning)."""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import conformal
from conformal.grid import PlanarGrid
from conformal.materials import Material
from conformal.solvers.normal import solve_normal

# ----------------------------------------------------------------------------- item 2
#: a soft sphere (G 0.5, nu 0) on a stiff flat (G 1e5): K = 0.5, the largest difference parameter
SOFT_ON_STIFF = {
    "material": {"G": 0.5, "nu": 0.0, "body2": {"G": 1e5, "nu": 0.0}}, "friction": {"mu": 0.2986},
    "geometry": {"kind": "quadratic", "A": 0.004116, "B": 0.004116}, "load": {"normal_force": 1e-5},
    "grid": {"mx": 45, "my": 45, "dx": 0.2, "dy": 0.2, "xl": -4.4999, "yl": -4.4999},
    "model": {"theory": "exact"},
    "history": [{"normal_force": 1e-5}, {"normal_force": 0.1}, {"normal_force": 0.47}],
}


def test_normal_solver_grows_the_contact_set_from_one_element():
    """A start from the one-element pressure of a tiny load (the previous history step) must give
    the same pressure as a start from nothing: the projected CG used to stop at once (the gap on a
    one-element set is trivially uniform) without letting the interpenetrating elements in."""
    g = PlanarGrid(45, 45, 0.2, 0.2, -4.4999, -4.4999)
    X, Y = g.mesh()
    h = 0.004116 * (X**2 + Y**2)
    mat = Material(0.5, 0.0, 1e5, 0.0)
    start = np.zeros(g.shape)
    start[np.unravel_index(np.argmin(h), h.shape)] = 1.0
    ref = solve_normal(None, g, h, normal_force=0.47, material=mat, tol=1e-8)
    warm = solve_normal(None, g, h, normal_force=0.47, material=mat, tol=1e-8, p_start=start)
    assert warm.converged and ref.n_contact > 900
    assert warm.n_contact == ref.n_contact
    assert np.abs(warm.pn - ref.pn).max() < 1e-6 * ref.pmax
    # and Hertz: pmax = 3 FN / (2 pi a²), a = (3 FN R / (4 E*))^(1/3), R = 1/(2A), E* = 1/(1/1 + 1e-5)
    E = 1.0 / (1.0 / 1.0 + 1.0 / 1e5)
    a = (3 * 0.47 / (2 * 0.004116) / (4 * E)) ** (1 / 3)
    assert ref.pmax == pytest.approx(3 * 0.47 / (2 * math.pi * a * a), rel=0.03)


def test_history_with_dissimilar_materials_does_not_freeze_the_contact_area():
    """The issue's reproducer: the last step's pmax was 11.75 N/mm² on one element.  The right
    answer is the same history started at 0.01 N (which never passed through one element): 917
    elements, pmax 0.024 N/mm²; a single step to 0.47 N differs by the history of the frictional
    coupling (Spence) but has the same size (944 elements, 0.021 N/mm²)."""
    r = conformal.solve(SOFT_ON_STIFF)
    last = r.extra["history"][-1]
    alt = copy.deepcopy(SOFT_ON_STIFF)
    alt["history"][0]["normal_force"] = 0.01
    r_alt = conformal.solve(alt)
    assert last["converged"]
    assert last["n_contact"] == r_alt.extra["history"][-1]["n_contact"] == 917
    assert r.pmax == pytest.approx(r_alt.pmax, rel=0.01)
    assert r.pmax == pytest.approx(0.024, rel=0.03)
    single = copy.deepcopy(SOFT_ON_STIFF)
    del single["history"]
    single["load"]["normal_force"] = 0.47
    one = conformal.solve(single)
    assert one.pmax == pytest.approx(r.pmax, rel=0.2)


# ----------------------------------------------------------------------------- item 4
CIRC = "meshes/scenes/circ.toml"


def _circ(**over):
    from conformal.scene import load_scene
    from _paths import SCENES

    return load_scene(SCENES / "circ.toml").with_(**over) if over else load_scene(SCENES / "circ.toml")


def test_a_grid_much_wider_than_the_patch_is_refused_naming_scale():
    """scale = 1000 put the whole Hertz patch (a = 6.9 mm) inside one element of a 13.8 m grid:
    pmax 0.12 instead of 1000 N/mm², without a word."""
    from conformal.errors import InputError

    with pytest.raises(InputError, match=r"^\[grid\] scale: .*0\.05 elements across"):
        _circ(grid__scale=1000)
    # a coarse but admissible grid solves and warns that the contact covers too few elements
    r = conformal.solve(_circ(grid__scale=20, model__theory="exact"))
    assert 0 < r.n_contact < 10
    assert any("[grid] scale" in w and "too few" in w for w in r.warnings)
    assert not any("too few" in w for w in conformal.solve(_circ(model__theory="exact")).warnings)


def test_tol_beyond_its_bound_is_refused():
    from conformal.errors import InputError

    for tol in (10.0, 0.5, 0.011):
        with pytest.raises(InputError, match=r"^\[model\] tol: .*<= 0\.01"):
            _circ(model__tol=tol)
    assert _circ(model__tol=1e-2).model.tol == 1e-2


def test_an_unconverged_solve_exits_3_unless_allowed(tmp_path, capsys):
    """maxit = 1 used to exit 0; now the JSON says "converged": false, stderr says so, exit 3."""
    import json

    from conformal.cli import main
    from _paths import SCENES

    scene = tmp_path / "m1.toml"
    text = (SCENES / "circ.toml").read_text(encoding="utf-8")
    scene.write_text(text.replace('theory = "fastsim"', 'theory = "exact"\nmaxit = 1'), encoding="utf-8")
    out = tmp_path / "m1.json"
    assert main(["solve", str(scene), "--json", str(out)]) == 3
    err = capsys.readouterr().err
    assert "did not converge" in err and "--allow-unconverged" in err
    d = json.loads(out.read_text(encoding="utf-8"))
    assert d["converged"] is False and any("not converged" in w for w in d["warnings"])
    assert main(["solve", str(scene), "--allow-unconverged"]) == 0
    assert main(["solve", str(SCENES / "circ.toml")]) == 0


# ----------------------------------------------------------------------------- item 8
def test_the_api_takes_the_toml_names():
    """friction.mu and material.nu as in the file: mu sets static = kinetic, nu both bodies where
    the scene has no [material.body2]; the field names G1 .. nu2 set one body."""
    r = conformal.solve(CIRC, friction__mu=0.4, model__theory="exact", grid__n=20)
    s = _circ()
    assert (r.FX, s.with_(friction__mu=0.4).friction.mu_static) == (pytest.approx(
        conformal.solve(s.with_(friction__mu_static=0.4, friction__mu_kinetic=0.4, model__theory="exact",
                                grid__n=20)).FX, rel=1e-12), 0.4)
    m = s.with_("material.nu", 0.3).material
    assert (m.nu1, m.nu2, m.K) == (0.3, 0.3, 0.0)
    m = s.with_("material.E", 210000.0).material
    assert m.G1 == m.G2 == pytest.approx(210000.0 / 2.56)
    d = s.with_("material.body2.G", 23000.0)
    assert (d.material.G1, d.material.G2) == (82000.0, 23000.0)
    assert d.with_("material.nu", 0.25).material.nu2 == 0.28          # body 2 given: kept
    assert s.with_("material.nu1", 0.3).material.nu2 == 0.28          # the field name: one body
    f = s.with_(friction__mu_kinetic=0.2).friction
    assert (f.mu_static, f.mu_kinetic) == (0.3, 0.2)
    from conformal.errors import InputError

    with pytest.raises(InputError, match=r"^\[material\] poisson: unknown key"):
        s.with_("material.poisson", 0.3)
    with pytest.raises(InputError, match=r"^\[friction\] mu: must be > 0"):
        s.with_(friction__mu=-1.0)


# ----------------------------------------------------------------------------- item 11
def test_prescribed_force_near_frictionless_dissimilar_rollers():
    """Bentall & Johnson's rollers (aluminium G 23000, nu 0.31 on steel, R 50/50 mm, 16.2 N/mm, line
    contact) at mu = 1e-4 with FX = 0: every creepage outside a narrow band gives full slip, the
    bordered Newton system stalls and the fallback root search on xi went the wrong way (xi = 0,
    converged false).  Now xi = -5.272e-4 rolling along +x; CONTACT's deck (examples/bentall.inp,
    aluminium body 1 as here) rolls along -x (CHI = 180 degrees) and reports +5.260e-4: the same
    scene with ``direction = -1`` gives +5.272e-4 (92 contact elements; 200 as in CONTACT's grid
    give 5.2606e-4).  Checked independently by two prescribed-xi solves either side of the root,
    whose forces have opposite signs."""
    mu = 1e-4
    d = {"material": {"G": 23000.0, "nu": 0.31, "body2": {"G": 82000.0, "nu": 0.28}}, "friction": {"mu": mu},
         "geometry": {"kind": "quadratic", "A": 0.02, "B": 0.0}, "load": {"normal_force": 16.2},
         "kinematics": {"fx_rel": 0.0}, "grid": {"n": 100}, "model": {"theory": "exact"}}
    r = conformal.solve(d)
    assert r.converged and not r.warnings
    assert abs(r.FX) < 1e-6 * mu * r.FN
    assert r.xi == pytest.approx(-5.260e-4, rel=0.005)
    # the force decreases with the creepage: positive below the root, negative above it
    below, above = (conformal.solve({**d, "kinematics": {"xi": r.xi + dxi}}).FX for dxi in (-1e-6, 1e-6))
    assert below > 0 > above
    chi180 = conformal.solve({**d, "kinematics": {"fx_rel": 0.0, "direction": -1}})   # CONTACT's CHI = 180 deg
    assert chi180.converged and chi180.xi == pytest.approx(-r.xi, rel=1e-6)


# ----------------------------------------------------------------------------- item 10
def test_planar_theories_warn_on_a_conformal_patch_and_the_conformal_theory_does_not():
    """The 16-degree flange patch: hertz (a half-space theory) says it is questionable there; the
    warning used to come from the conformal theory, the one made for such patches (that it no
    longer warns: tests/validation/test_conformal.py::test_wheel_rail_scene_runs_the_conformal_theory)."""
    from _paths import SCENES

    r = conformal.solve(SCENES / "flange_s1002_uic60.toml", model__theory="hertz")
    assert r.patches[0].extra["contact_angle_spread_deg"] > 10.0
    assert any("theory 'hertz' is questionable" in w for w in r.warnings)
    flat = conformal.solve(SCENES / "mbench_right_y5.toml", model__theory="hertz")   # a tread contact
    assert not any("questionable" in w for w in flat.warnings)
