"""Hard cases of the exact model, end to end through `conformal solve`: they converge to the
right answer or stop with one clear line (exit code 2)."""
import json
import math

import numpy as np
import pytest

from conformal.cli import main
from conformal.materials import Material
from conformal.theories.hertz import hertz_from_semiaxes

BASE = """\
[material]
G = 82000.0
nu = 0.28
[friction]
{friction}
{geometry}
[load]
{load}
[grid]
{grid}
[kinematics]
{kinematics}
[model]
theory = "exact"
"""


def run(tmp_path, capsys, geometry, load="normal_force = 10000.0", grid="n = 31", kinematics="", files=None,
        friction="mu = 0.3"):
    for name, text in (files or {}).items():
        (tmp_path / name).write_text(text)
    f = tmp_path / "scene.toml"
    f.write_text(BASE.format(geometry=geometry, load=load, grid=grid, kinematics=kinematics, friction=friction))
    code = main(["solve", str(f)])
    out, err = capsys.readouterr()
    return code, (json.loads(out) if code == 0 else None), err


@pytest.mark.parametrize("a_over_b", [0.05, 20.0])
def test_very_elongated_ellipses(tmp_path, capsys, a_over_b):
    """a/b = 0.05 and 20 (elements 20:1): converged, pmax within 0.2 % of Hertz (measured 0.04 %)."""
    a, b = 4.0 * math.sqrt(a_over_b), 4.0 / math.sqrt(a_over_b)
    code, s, _ = run(tmp_path, capsys, f'[geometry]\nkind = "hertz"\na = {a}\nb = {b}')
    assert code == 0 and s["converged"]
    hz = hertz_from_semiaxes(a, b, Material.steel(), normal_force=10000.0)
    assert s["pmax"] == pytest.approx(hz.pmax, rel=2e-3)
    assert s["FN"] == pytest.approx(10000.0, rel=1e-10)


def test_load_so_small_the_patch_covers_three_elements(tmp_path, capsys):
    """A = B = 0.001, FN = 0.5 N: the Hertz radius (0.066 mm) is about one element (0.1 mm) wide,
    so the patch is a handful of elements; the iteration still converges and keeps FN."""
    code, s, _ = run(tmp_path, capsys, '[geometry]\nkind = "quadratic"\nA = 0.001\nB = 0.001',
                     load="normal_force = 0.5", grid="mx = 21\nmy = 21\ndx = 0.1\ndy = 0.1")
    assert code == 0 and s["converged"]
    assert 1 <= s["n_contact"] <= 5
    assert s["FN"] == pytest.approx(0.5, rel=1e-10)
    # the single central element carries most of the load: its pressure FN/dA bounds pmax
    assert s["pmax"] <= 0.5 / 0.01 + 1e-9


def test_two_patches(tmp_path, capsys):
    x = (np.arange(40) - 19.5) * 0.25
    y = (np.arange(16) - 7.5) * 0.25
    X, Y = np.meshgrid(x, y, indexing="ij")
    h = np.minimum(0.001 * (X - 3) ** 2, 0.001 * (X + 3) ** 2) + 0.001 * Y**2
    code, s, _ = run(tmp_path, capsys, '[geometry]\nkind = "table"\nfile = "h.txt"', load="normal_force = 2000.0",
                     grid="mx = 40\nmy = 16\ndx = 0.25\ndy = 0.25",
                     files={"h.txt": "\n".join(" ".join(f"{v:.8e}" for v in r) for r in h)})
    assert code == 0 and s["converged"] and s["n_patches"] == 2
    assert s["patch_FN"] == pytest.approx([1000.0, 1000.0], rel=1e-6)  # symmetric bumps


def test_no_contact_names_the_gap(tmp_path, capsys):
    code, s, err = run(tmp_path, capsys, '[geometry]\nkind = "table"\nfile = "h.txt"', load="approach = 0.01",
                       grid="mx = 2\nmy = 2\ndx = 1.0\ndy = 1.0", files={"h.txt": "0.03 0.05\n0.04 0.06\n"})
    assert code == 2
    assert "no contact" in err and "gap 0.02 mm" in err and err.count("\n") == 1


@pytest.mark.parametrize("load,match", [
    ("normal_force = -5.0", "[load] normal_force: must be > 0"),
    ("normal_force = nan", "[load] normal_force: must be a finite number"),
    ("approach = -0.01", "[load] approach: must be > 0"),
])
def test_bad_loads(tmp_path, capsys, load, match):
    code, _, err = run(tmp_path, capsys, '[geometry]\nkind = "quadratic"\nA = 0.001\nB = 0.001', load=load)
    assert code == 2 and match in err


def test_nan_in_the_table(tmp_path, capsys):
    code, _, err = run(tmp_path, capsys, '[geometry]\nkind = "table"\nfile = "h.txt"',
                       grid="mx = 2\nmy = 2\ndx = 1.0\ndy = 1.0", files={"h.txt": "0.0 nan\n0.1 0.2\n"})
    assert code == 2 and "NaN" in err


def test_patch_reaching_the_grid_edge_is_reported(tmp_path, capsys):
    """A potential area smaller than the contact: solved, with a warning naming the edges."""
    code, s, _ = run(tmp_path, capsys, '[geometry]\nkind = "quadratic"\nA = 0.001\nB = 0.001', grid="n = 20\nscale = 0.8")
    assert code == 0
    assert any("border of the potential contact area" in w for w in s["warnings"])


# ----------------------------------------------------------------------------- with friction
CIRCLE = '[geometry]\nkind = "hertz"\na = 1.0\nb = 1.0'


def test_full_slip(tmp_path, capsys):
    """xi = 0.05 (100x the saturation creepage): every contact element slips, |FX| = mu FN, and the
    frictional power tends to its rigid-slip value V/1000 xi FX (elastic slip is O(creepage at
    saturation) = 1 % of xi here)."""
    code, s, _ = run(tmp_path, capsys, CIRCLE, kinematics="xi = 0.05\nvelocity = 1000.0", grid="n = 24")
    assert code == 0 and s["converged"]
    assert s["n_slip"] == s["n_contact"]
    # |p_t| = mu pn everywhere; the slip direction deviates from x by the elastic part (~1 % of xi
    # at the edges), which shortens FX by ~1e-4
    assert s["FX"] == pytest.approx(-0.3 * s["FN"], rel=1e-3)
    assert s["frictional_power"] == pytest.approx(1.0 * 0.05 * s["FX"], rel=0.02)


def test_pure_spin_at_large_spin(tmp_path, capsys):
    """phi = 1 rad/mm on a 1 mm circle (rigid slip >> elastic): the slip circles the centre, so
    MZ -> -mu sum(pn r) dA.  The limit is computed from the pressure field of the same result (an
    independent check of the traction directions), 1 %.  FX = 0 by symmetry; FY does not vanish:
    CONTACT's discrete rigid slip (followed by conformal.solvers.tangential) evaluates phi x at
    x + dx/6, a pole offset that acts like a lateral creepage phi dx/6."""
    f = tmp_path / "scene.toml"
    f.write_text(BASE.format(geometry=CIRCLE, load="normal_force = 10000.0", grid="n = 24",
                             kinematics="phi = 1.0", friction="mu = 0.3"))
    from conformal.scene import load_scene
    from conformal.dispatch import solve_scene

    r = solve_scene(load_scene(f))
    assert r.converged and r.n_slip == r.n_contact
    X, Y = r.field.grid.mesh()
    limit = -0.3 * float((r.field.pn * np.hypot(X, Y)).sum() * r.field.grid.area)
    assert r.MZ == pytest.approx(limit, rel=0.01)
    assert abs(r.FX) < 1e-6 * 0.3 * r.FN
    # and the analytic Hertz value -(3 pi/16) mu FN a, 2 % (the element sum of pn r)
    assert r.MZ == pytest.approx(-3 * math.pi / 16 * 0.3 * r.FN * 1.0, rel=0.02)


def test_mu_one_small_creepage_is_linear_theory(tmp_path, capsys):
    """mu = 1 and xi = 1e-5: almost full adhesion, so FX = -G a b C11 xi with Kalker's C11 (linear
    theory, seed Eq. 13); 24 x 24 elements make the exact solution about 2 % stiffer (first-order
    discretisation error, studies/creep_coefficients.py); allow 4 %."""
    from conformal.theories.coefficients import kalker_coefficients

    code, s, _ = run(tmp_path, capsys, CIRCLE, kinematics="xi = 1e-5", grid="n = 24", friction="mu = 1.0")
    assert code == 0 and s["converged"]
    c11 = kalker_coefficients(1.0, 0.28).C11
    assert s["FX"] == pytest.approx(-82000.0 * 1.0 * 1.0 * c11 * 1e-5, rel=0.04)
    assert s["n_slip"] < 0.1 * s["n_contact"]
