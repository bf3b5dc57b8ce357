"""The exact model (conformal.solvers.exact) end to end: CONTACT's reference cases (normal parts),
explicit undeformed-distance tables, the result fields, and the creep coefficients computed by
the exact theory (conformal.theories.c33) against Kalker's table."""
import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from conformal.cli import main
from conformal.materials import Material
from conformal.result import ADHESION, EXTERIOR
from conformal.scene import load_scene, scene_from_dict
from conformal.dispatch import solve_scene
from conformal.theories import c33 as c33mod
from conformal.theories.hertz import hertz_from_curvatures
from _paths import ROOT



def exact_scene(geometry, load, grid, material=None, friction=None, kinematics=None, base_dir="."):
    return scene_from_dict({"material": material or {"G": 82000.0, "nu": 0.28},
                            "friction": friction or {"mu": 0.3}, "geometry": geometry, "load": load,
                            "kinematics": kinematics or {}, "grid": grid, "model": {"theory": "exact"}},
                           base_dir=base_dir)


# CONTACT prints 4 significant digits (pmax, approach, energy) and exact element counts
def test_cattaneo_normal_part():
    r = solve_scene(exact_scene({"kind": "hertz", "a": 1.0, "b": 1.0}, {"normal_force": 9.1954},
                                {"mx": 19, "my": 19, "dx": 2 * 1.26667 / 19, "dy": 2 * 1.26667 / 19},
                                material={"G": 200.0, "nu": 0.42}, friction={"mu": 0.4}))
    s = r.summary()
    assert r.converged and r.FN == pytest.approx(9.1954, rel=1e-10)
    assert round(r.pmax, 3) == 4.393 and r.n_contact == 177 and round(r.approach, 5) == 0.01998
    assert s["elastic_energy"] == pytest.approx(7.35e-5, rel=1e-3)
    assert s["FN_over_G"] == pytest.approx(0.04598, rel=1e-3)
    assert s["n_adhesion"] == 177 and r.n_slip == 0 and r.FX == 0 and r.FY == 0
    assert s["frictional_power"] == 0.0 and s["n_patches"] == 1


def test_carter2d_normal_part_from_a_table(tmp_path):
    """carter2d: one row of 55 elements, dy = 200 mm, h = 0.001 x² given as a table (kind = "table";
    B = 0 is not a quadratic Hertz geometry): pmax 113.9, 50 contact elements, approach 0.006492."""
    x = -1.05 + 0.04 * np.arange(55)
    np.savetxt(tmp_path / "h.txt", (0.001 * x**2)[:, None])
    r = solve_scene(exact_scene({"kind": "table", "file": "h.txt"}, {"normal_force": 35780.0},
                                {"mx": 55, "my": 1, "dx": 0.04, "dy": 200.0, "xl": -1.07, "yl": -100.0},
                                base_dir=tmp_path))
    assert round(r.pmax, 1) == 113.9 and r.n_contact == 50
    assert r.approach == pytest.approx(0.006492, abs=5e-7)
    assert r.summary()["FN_over_G"] == pytest.approx(0.4363, rel=1e-3)


def test_tractcurv_normal_part():
    """tractcurv (A = 0.0008, B = 2.814e-4, FN = 106.7 kN, 48 x 44, SCALE 1.1): pmax 640.7, 1384
    contact elements, approach 0.07651, elastic energy 3.265 J (case 1, xi = 1e-5, whose tangential
    part adds < 1e-3)."""
    hz = hertz_from_curvatures(0.0008, 2.814e-4, Material.steel(), normal_force=106700.0)
    r = solve_scene(exact_scene({"kind": "quadratic", "A": 0.0008, "B": 2.814e-4}, {"normal_force": 106700.0},
                                {"mx": 48, "my": 44, "dx": 2.2 * hz.a / 48, "dy": 2.2 * hz.b / 44}))
    assert round(r.pmax, 1) == 640.7 and r.n_contact == 1384
    assert round(r.approach, 5) == 0.07651
    assert r.summary()["elastic_energy"] == pytest.approx(3.265, rel=1e-3)


def test_fastsim_case_exact_normal_part():
    """fastsim case 1 (a = 8, b = 4, FN = 82 kN, 44 x 44, SCALE 1.1): pmax 1223, 1276 contact
    elements, approach 0.09266."""
    r = solve_scene(exact_scene({"kind": "hertz", "a": 8.0, "b": 4.0}, {"normal_force": 82000.0},
                                {"mx": 44, "my": 44, "dx": 0.4, "dy": 0.2}))
    assert round(r.pmax) == 1223 and r.n_contact == 1276
    assert round(r.approach, 5) == 0.09266


def test_two_bump_table_scene(tmp_path):
    """meshes/scenes/two_bumps.toml: two patches; the load split follows from Hertz for each bump
    with the far-field displacement of the other one (independent estimate, 1 %)."""
    scene = load_scene(ROOT / "meshes" / "scenes" / "two_bumps.toml")
    r = solve_scene(scene)
    s = r.summary()
    assert r.converged and s["n_patches"] == 2
    F1, F2 = s["patch_FN"]
    assert F1 + F2 == pytest.approx(20.0, rel=1e-9)
    m, d, A = scene.material, 6.0, 0.01
    far = (1 - m.nu) / (math.pi * m.G) / d

    def mismatch(f1):  # equal approach of both patches; the second bump is 0.002 mm further away
        d1 = hertz_from_curvatures(A, A, m, normal_force=f1).approach + far * (20.0 - f1)
        d2 = hertz_from_curvatures(A, A, m, normal_force=20.0 - f1).approach + 0.002 + far * f1
        return d1 - d2

    f1 = brentq(mismatch, 10.0, 19.99)
    assert F1 == pytest.approx(f1, rel=0.01)


def test_result_field_and_plot(tmp_path):
    """The exact result carries every field array (for --plot and VTU export); the CLI writes the PNG."""
    scene = tmp_path / "s.toml"
    scene.write_text("""
[material]
G = 200.0
nu = 0.42
[friction]
mu = 0.4
[geometry]
kind = "hertz"
a = 1.0
b = 1.0
[load]
normal_force = 9.1954
[grid]
n = 15
scale = 1.3
[model]
theory = "exact"
""")
    png, js = tmp_path / "out.png", tmp_path / "out.json"
    assert main(["solve", str(scene), "--plot", str(png), "--json", str(js)]) == 0
    assert png.stat().st_size > 10_000
    summary = json.loads(js.read_text())
    for key in ("iterations", "residual", "elastic_energy", "frictional_power", "normal_residual", "n_patches"):
        assert key in summary
    r = solve_scene(load_scene(scene))
    f = r.field
    for name in ("pn", "px", "py", "status", "sx", "sy", "un", "ux", "uy"):
        assert getattr(f, name).shape == (15, 15), name
    assert set(np.unique(f.status)) == {EXTERIOR, ADHESION}
    # un closes the gap on the contact set: h - approach + un = 0 there (h = A x² + B y², A = B = 0.01)
    X, Y = f.grid.mesh()
    h = 0.01 * X**2 + 0.01 * Y**2
    gap = h - r.approach + f.un
    assert np.abs(gap[f.pn > 0]).max() < 1e-5 * r.approach and gap[f.pn == 0].min() > -1e-5 * r.approach


# ----------------------------------------------------------------------------- creep coefficients
@pytest.mark.parametrize("a_over_b,nu,C11,C22,C23", [(1.0, 0.25, 4.12, 3.67, 1.47), (0.3, 0.25, 3.44, 2.75, 0.715)])
def test_creep_coefficients_on_a_coarse_grid(a_over_b, nu, C11, C22, C23):
    """Full-adhesion steady rolling with the exact theory on 32 elements across the short axis:
    within 3 % of Kalker's table (measured +0.8, +1.2, -2.2 % at a/b = 1; the error is first order
    in the element size, studies/creep_coefficients.py).  C23 from the spin moment under eta and
    from FY under spin agree to the discretisation error."""
    c = c33mod.exact_coefficients(a_over_b, nu, 32)
    assert c.C11 == pytest.approx(C11, rel=0.03)
    assert c.C22 == pytest.approx(C22, rel=0.03)
    assert c.C23 == pytest.approx(C23, rel=0.03)
    assert c.C23_phi == pytest.approx(C23, rel=0.08)


def test_c33_table_is_complete_and_meets_the_slender_asymptote():
    """conformal/data/kalker_c33.csv covers every (branch, g, nu) node of Kalker's table; the linear
    theory reads it; at a/b = 0.1 it is within 6 % of Kalker's a/b -> 0 asymptote
    pi²/(16(1-nu) g) (an O(g) remainder: Kalker's own C11, C22 differ from their asymptotes by up to
    4.3 % there)."""
    from conformal.theories import coefficients as coef

    rows = [ln.split(",") for ln in c33mod.C33_FILE.read_text().splitlines()
            if ln and not ln.startswith("#")][1:]
    nodes = {(b, float(g), float(nu)) for b, g, nu, _ in rows}
    ref = {(b, g, nu) for b, g, nu, _ in c33mod.reference_nodes()}
    assert nodes == ref
    for nu in (0.0, 0.25, 0.5):
        assert coef.c33(0.1, nu) == pytest.approx(float(coef.asymptotic_c33(0.1, nu)), rel=0.06)
    # a fresh coarse computation agrees with the tabulated (extrapolated) value within 3 %
    assert c33mod.exact_coefficients(1.0, 0.25, 32).C33 == pytest.approx(coef.c33(1.0, 0.25), rel=0.03)


# ----------------------------------------------------------------------------- normal + tangential
def test_cattaneo_shift_end_to_end():
    """CONTACT cattaneo case 2 through the model: FX/(mu FN) = -0.875 prescribed in a shift; CONTACT:
    FX -3.218, shift 0.008155 mm (analytic 0.008172), 45 adhesion / 132 slip elements, elastic
    energy 8.525e-5 J, frictional work -2.75e-6 J."""
    d = 2 * 1.26667 / 19
    r = solve_scene(exact_scene({"kind": "hertz", "a": 1.0, "b": 1.0}, {"normal_force": 9.1954},
                                {"mx": 19, "my": 19, "dx": d, "dy": d}, material={"G": 200.0, "nu": 0.42},
                                friction={"mu": 0.4}, kinematics={"rolling": "shift", "fx_rel": -0.875, "fy_rel": 0.0}))
    s = r.summary()
    assert r.converged and round(r.FX, 3) == -3.218 and round(r.xi, 6) == 0.008155
    assert s["n_adhesion"] == 45 and r.n_slip == 132
    assert s["elastic_energy"] == pytest.approx(8.525e-5, rel=1e-3)
    assert s["frictional_work"] == pytest.approx(-2.75e-6, rel=2e-3) and "frictional_power" not in s


def test_carter2d_end_to_end(tmp_path):
    """carter2d: FX 6955 N (FX/(mu FN) 0.648), 30 adhesion / 20 slip, elastic energy 0.1162 J,
    frictional power -47.62 W at V = 30 m/s."""
    x = -1.05 + 0.04 * np.arange(55)
    np.savetxt(tmp_path / "h.txt", (0.001 * x**2)[:, None])
    r = solve_scene(exact_scene({"kind": "table", "file": "h.txt"}, {"normal_force": 35780.0},
                                {"mx": 55, "my": 1, "dx": 0.04, "dy": 200.0, "xl": -1.07, "yl": -100.0},
                                kinematics={"xi": -0.00024, "velocity": 30000.0}, base_dir=tmp_path))
    s = r.summary()
    assert round(r.FX) == 6955 and round(s["FX_rel"], 3) == 0.648
    assert s["n_adhesion"] == 30 and r.n_slip == 20
    assert s["elastic_energy"] == pytest.approx(0.1162, rel=1e-3)
    assert s["frictional_power"] == pytest.approx(-47.62, rel=1e-3)


def test_fastsim_case_exact_end_to_end():
    """fastsim case 1 (exact theory, eta = -0.000625, phi = 0.000625 rad/mm, V = 30 m/s):
    FY -14940, FY/(mu FN) -0.6074, MZ -48210, 356 adhesion / 920 slip, frictional power -540.4 W,
    elastic energy 3.231 J."""
    r = solve_scene(exact_scene({"kind": "hertz", "a": 8.0, "b": 4.0}, {"normal_force": 82000.0},
                                {"mx": 44, "my": 44, "dx": 0.4, "dy": 0.2},
                                kinematics={"eta": -0.000625, "phi": 0.000625, "velocity": 30000.0}))
    s = r.summary()
    assert r.converged and round(r.FY, -1) == -14940 and round(s["FY_rel"], 4) == -0.6074
    assert round(r.MZ, -1) == -48210 and abs(r.FX) < 1e-3
    assert s["n_adhesion"] == 356 and r.n_slip == 920
    assert s["frictional_power"] == pytest.approx(-540.4, rel=1e-3)
    assert s["elastic_energy"] == pytest.approx(3.231, rel=1e-3)


def test_dissimilar_bodies_panagiotopoulos():
    """K != 0 (aluminium on steel, K = 0.076): the normal and tangential problems alternate until
    both settle (history in extra["outer"]); exchanging the bodies (K -> -K) in a compression
    without shift gives the same pressure and the mirrored tangential traction (the z -> -z mirror
    of the problem), and the final pressure solves the normal problem with the final coupling."""
    def run(material):
        return solve_scene(exact_scene({"kind": "quadratic", "A": 0.01, "B": 0.01}, {"normal_force": 1000.0},
                                       {"n": 24}, material=material, kinematics={"rolling": "shift"}))
    al = {"G": 26000.0, "nu": 0.33, "body2": {"G": 82000.0, "nu": 0.28}}
    st = {"G": 82000.0, "nu": 0.28, "body2": {"G": 26000.0, "nu": 0.33}}
    a, b = run(al), run(st)
    for r in (a, b):
        s = r.summary()
        assert r.converged and 2 <= s["outer_iterations"] <= 20
        last = s["outer"][-1]
        assert max(last["pressure_change"], last["traction_change"]) < 1e-6
    fa, fb = a.field, b.field
    assert fa.px.any() and a.n_slip > 0   # the coupling alone makes tractions and slip at the edge
    np.testing.assert_allclose(fa.pn, fb.pn, atol=1e-6 * a.pmax)
    np.testing.assert_allclose(fa.px, -fb.px, atol=1e-6 * a.pmax)
    np.testing.assert_allclose(fa.py, -fb.py, atol=1e-6 * a.pmax)
    # consistency: with the final tangential traction's normal displacement the gap closes on the contact set
    from conformal.influence.halfspace import HalfSpaceInfluence
    g = fa.grid
    m = Material(26000.0, 0.33, 82000.0, 0.28)
    op = HalfSpaceInfluence.for_grid(g.mx, g.my, g.dx, g.dy, m)
    X, Y = g.mesh()
    un = op.apply_normal(fa.pn) + op.apply_coupling_nt(fa.px, fa.py)
    gap = 0.01 * (X**2 + Y**2) - a.approach + un
    assert np.abs(gap[fa.pn > 0]).max() < 1e-5 * a.approach


def test_full_stick_solver_equals_the_tangential_solver_at_tiny_creepage():
    """The creep-coefficient module's linear full-stick solver (GMRES) and the general tangential
    solver (semismooth Newton, mu huge so nothing slips) solve the same discrete equations with
    CONTACT's rigid slip (spin term at x + dx/6): forces and moment agree to 1e-6."""
    from conformal.influence.halfspace import HalfSpaceInfluence
    from conformal.solvers.normal import solve_normal
    from conformal.solvers.tangential import solve_tangential
    from conformal.theories.hertz import hertz_from_semiaxes

    mat = Material.identical(1.0, 0.25)
    a, b, g = c33mod.grid_for(3.0, 16)
    hz = hertz_from_semiaxes(a, b, mat, normal_force=1.0)
    X, Y = g.mesh()
    pn = solve_normal(None, g, hz.A * X**2 + hz.B * Y**2, normal_force=1.0, material=mat, tol=1e-10).pn
    stick = c33mod.StickRolling(g, pn > 0, mat, spin_shift=1 / 6)
    op = HalfSpaceInfluence.for_grid(g.mx, g.my, g.dx, g.dy, mat)
    for kw in (dict(xi=1.0, eta=0.0, phi=0.0), dict(xi=0.0, eta=1.0, phi=0.0), dict(xi=0.0, eta=0.0, phi=1.0)):
        mine = stick.solve(**kw)
        t = solve_tangential(op, g, pn, mu_static=1e3, mu_kinetic=1e3, tol=1e-10,
                             **{k: 1e-9 * v for k, v in kw.items()})
        assert np.all(t.status[pn > 0] == ADHESION)
        theirs = np.array([t.px.sum(), t.py.sum(), (X * t.py - Y * t.px).sum()]) * g.area * 1e9
        np.testing.assert_allclose(theirs, [mine.FX, mine.FY, mine.MZ], rtol=0,
                                   atol=1e-6 * max(abs(mine.FX), abs(mine.FY), abs(mine.MZ)))
