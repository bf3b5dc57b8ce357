"""Inputs CONTACT users rely on (issue 11 item 5): rolling in -x, a rigid slip per element, friction
varying along the profile, influence numbers read from a file."""
from __future__ import annotations

import numpy as np
import pytest

import conformal
from conformal.errors import InputError
from conformal.result import ADHESION

BASE = {"material": {"G": 82000.0, "nu": 0.28}, "friction": {"mu": 0.3},
        "geometry": {"kind": "hertz", "a": 1.0, "b": 1.0}, "load": {"normal_force": 1000.0},
        "grid": {"n": 24}, "model": {"theory": "exact", "tol": 1e-9}}


def scene(**kin):
    d = {k: dict(v) if isinstance(v, dict) else v for k, v in BASE.items()}
    d["kinematics"] = kin
    return d


# ----------------------------------------------------------------------------- rolling in -x
def test_rolling_in_minus_x_mirrors_the_solution():
    """A geometry symmetric in x: the longitudinal creep force is the same in both directions, the
    traction field is mirrored (adhesion at the new leading edge x < 0), and the lateral force from
    spin changes sign."""
    plus = conformal.solve(scene(xi=1e-3))
    minus = conformal.solve(scene(xi=1e-3, direction=-1))
    assert minus.FX == pytest.approx(plus.FX, rel=1e-9) and plus.FX < 0
    assert np.allclose(minus.field.px, plus.field.px[::-1], rtol=0, atol=1e-9 * abs(plus.field.px).max())
    X, _ = plus.field.grid.mesh()
    stick_plus = X[plus.field.status == ADHESION].mean()
    stick_minus = X[minus.field.status == ADHESION].mean()
    assert stick_plus > 0.3 and stick_minus == pytest.approx(-stick_plus)
    assert minus.extra["direction"] == -1
    sp = conformal.solve(scene(phi=0.5))
    sm = conformal.solve(scene(phi=0.5, direction=-1))
    assert abs(sp.FY) > 5.0             # N: C23 couples spin into FY (7.1 N here)
    assert sm.FY == pytest.approx(-sp.FY, rel=1e-9)
    assert sm.MZ == pytest.approx(sp.MZ, rel=1e-9)   # the spin moment itself does not depend on it
    # any planar theory: FASTSIM likewise
    f = conformal.solve(scene(xi=1e-3, direction=-1), model__theory="fastsim")
    assert f.FX == pytest.approx(conformal.solve(scene(xi=1e-3), model__theory="fastsim").FX, rel=1e-9)


def test_direction_is_validated():
    with pytest.raises(InputError, match="direction"):
        conformal.solve(scene(xi=1e-3, direction=0))
    with pytest.raises(InputError, match="direction"):
        conformal.solve(scene(xi=1e-3, direction=2))
    from conformal.scene import scene_from_dict

    s = scene_from_dict(scene(xi=1e-3, direction=-1))
    assert s.with_("kinematics.xi", 2e-3).kinematics.direction == -1    # survives a change


# ----------------------------------------------------------------------------- rigid slip per element
def test_rigid_slip_file_equals_the_spin_it_describes(tmp_path):
    """The rigid slip of a spin phi written per element ((-phi y, phi (x + dx/6)), seed Eq. 47 in
    CONTACT's discretisation) and given as a file, with zero creepages, gives the solution of the
    spin itself; one uniform longitudinal slip equals xi."""
    phi = 0.4
    ref = conformal.solve(scene(phi=phi))
    g = ref.field.grid
    X, Y = g.mesh()
    w = np.stack([-phi * Y, phi * (X + g.dx / 6.0)])
    np.save(tmp_path / "w.npy", w)
    r = conformal.solve(scene(rigid_slip=str(tmp_path / "w.npy")))
    assert r.FY == pytest.approx(ref.FY, rel=1e-6) and r.MZ == pytest.approx(ref.MZ, rel=1e-6)
    # text form: mx rows of 2 my numbers
    np.savetxt(tmp_path / "w.txt", np.hstack([np.full(g.shape, 1e-3), np.zeros(g.shape)]))
    r2 = conformal.solve(scene(rigid_slip=str(tmp_path / "w.txt")))
    assert r2.FX == pytest.approx(conformal.solve(scene(xi=1e-3)).FX, rel=1e-6)
    np.savetxt(tmp_path / "bad.txt", np.zeros((3, 4)))
    with pytest.raises(InputError, match="rigid_slip"):
        conformal.solve(scene(rigid_slip=str(tmp_path / "bad.txt")))
    with pytest.raises(InputError, match="only theory"):
        conformal.solve(scene(rigid_slip=str(tmp_path / "w.npy")), model__theory="fastsim")
    with pytest.raises(InputError, match="no such file"):
        conformal.solve(scene(rigid_slip=str(tmp_path / "missing.npy")))


# ----------------------------------------------------------------------------- friction along the profile
def test_friction_table_full_slip_force(tmp_path):
    """mu varying across the patch (mu = 0.2 for y < 0, 0.5 for y > 0): in full slip the force is
    the integral of mu(y) p_n and the moment that of y mu(y) p_n (independent of the solver); a
    constant table equals plain mu."""
    f = tmp_path / "mu.csv"
    f.write_text("# s, mu\n-0.001, 0.2\n0.001, 0.5\n", encoding="utf-8")
    d = scene(xi=0.1)                     # far beyond saturation: full slip
    d["friction"] = {"mu": 0.3, "mu_table": str(f)}
    r = conformal.solve(d)
    g = r.field.grid
    _, Y = g.mesh()
    mu_y = np.interp(Y, [-0.001, 0.001], [0.2, 0.5])
    # the slip is along x up to the small lateral slip that nu couples in (relative 1e-6)
    assert r.FX == pytest.approx(-float((mu_y * r.field.pn).sum() * g.area), rel=1e-5)
    assert r.FX == pytest.approx(-0.35 * r.FN, rel=0.01)
    assert r.MZ == pytest.approx(float((Y * mu_y * r.field.pn).sum() * g.area), rel=1e-3)
    assert abs(r.FY) < 1e-4 * r.FN
    c = tmp_path / "const.csv"
    c.write_text("0, 0.25\n", encoding="utf-8")
    d2 = scene(xi=1e-3)
    d2["friction"] = {"mu": 0.3, "mu_table": str(c)}
    d3 = scene(xi=1e-3)
    d3["friction"] = {"mu": 0.25}
    assert conformal.solve(d2).FX == pytest.approx(conformal.solve(d3).FX, rel=1e-9)
    bad = tmp_path / "bad.csv"
    bad.write_text("0, 0.3\n-1, 0.3\n", encoding="utf-8")
    d4 = scene(xi=1e-3)
    d4["friction"] = {"mu": 0.3, "mu_table": str(bad)}
    with pytest.raises(InputError, match="increase"):
        conformal.solve(d4)
    d5 = scene(fx_rel=-0.5)
    d5["friction"] = {"mu": 0.3, "mu_table": str(c)}
    with pytest.raises(InputError, match="mu_table"):
        conformal.solve(d5)
    d6 = scene(xi=1e-3)
    d6["friction"] = {"mu": 0.3, "mu_tabel": str(c)}
    with pytest.raises(InputError, match="unknown key"):
        conformal.solve(d6)


# ----------------------------------------------------------------------------- influence numbers from a file
def test_influence_numbers_from_a_file(tmp_path):
    """The grid's half-space numbers written to an influence file and read back by the solver
    ([model] influence_file) give the same solution; numbers twice as large are a body half as
    stiff (the same as G/2)."""
    from conformal.influence.contact_file import read_influence_file, write_influence_file
    from conformal.influence.curved import curved_halfspace_kernel
    from conformal.materials import Material

    d = scene(xi=1e-3)
    d["load"], d["grid"] = {"approach": 0.004}, {"n": 16}
    ref = conformal.solve(d)
    g = ref.field.grid
    s_edges = g.yl + np.arange(g.my + 1) * g.dy
    K = curved_halfspace_kernel(g.mx, g.dx, g.y, np.full(g.my, g.dy), np.zeros(g.my), Material.identical(82000.0, 0.28))
    write_influence_file(tmp_path / "A.txt", K, dx=g.dx, s_edges=s_edges, comments=["half-space, flat strip"])
    assert np.array_equal(read_influence_file(tmp_path / "A.txt").kernel, K)     # round trip, to the bit
    d["model"] = dict(d["model"], influence_file=str(tmp_path / "A.txt"))
    r = conformal.solve(d)
    assert r.FN == pytest.approx(ref.FN, rel=1e-7) and r.FX == pytest.approx(ref.FX, rel=1e-5)
    write_influence_file(tmp_path / "A2.txt", 2.0 * K, dx=g.dx, s_edges=s_edges)
    d["model"]["influence_file"] = str(tmp_path / "A2.txt")
    soft = conformal.solve(d)
    d_half = scene(xi=1e-3)
    d_half["load"], d_half["material"], d_half["grid"] = {"approach": 0.004}, {"G": 41000.0, "nu": 0.28}, {"n": 16}
    assert soft.FN == pytest.approx(conformal.solve(d_half).FN, rel=1e-7)
    # a file for another grid is refused, naming the key
    write_influence_file(tmp_path / "small.txt", K[1:-1, :, :], dx=g.dx, s_edges=s_edges)
    d["model"]["influence_file"] = str(tmp_path / "small.txt")
    with pytest.raises(InputError, match="influence_file"):
        conformal.solve(d)
    with pytest.raises(InputError, match="only theory"):
        conformal.solve(d, model__theory="fastsim")
