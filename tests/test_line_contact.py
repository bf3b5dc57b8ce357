"""Line contact (B = 0, plane strain) with the half-plane influence numbers (conformal.solvers.line):
2-D Hertz and Carter's steady rolling (conformal.reference), from the API and from a scene."""
from __future__ import annotations

import numpy as np
import pytest

import conformal
from conformal import reference as ref
from conformal.errors import InputError
from conformal.materials import Material
from conformal.problem import ContactProblem
from conformal.result import ADHESION
from conformal.solvers import line
from conformal.specs import Friction, Kinematics, ModelSpec

G, NU, MU, R, FN = 82000.0, 0.28, 0.3, 500.0, 178.9   # a = 1.0 mm (reference.py's Carter example)


def line_problem(xi=0.0, n=100, rolling="steady", **kin):
    mat = Material.identical(G, NU)
    a, grid = line.line_grid(1.0 / (2 * R), FN, mat, n=n, scale=1.1)
    X, _ = grid.mesh()
    return a, ContactProblem(material=mat, friction=Friction(MU, MU), kinematics=Kinematics(xi=xi, rolling=rolling, **kin),
                             model=ModelSpec(theory="exact", tol=1e-9), normal_force=FN, grid=grid,
                             h=X ** 2 / (2 * R), info={"line_contact": True})


def test_hertz_2d():
    a, p = line_problem()
    r = line.solve(p)
    a_ref, p0 = ref.hertz_2d(FN, R, Material.identical(G, NU).E_star)
    assert a == pytest.approx(a_ref) and a_ref == pytest.approx(1.0, rel=1e-3)
    assert r.FN == pytest.approx(FN, rel=1e-9)
    assert r.pmax == pytest.approx(p0, rel=0.003)
    x = p.grid.x
    pn = r.field.pn[:, 0]
    # the elliptic pressure: away from the edges within 1 % of p0
    inner = np.abs(x) < 0.9 * a_ref
    assert np.abs(pn - p0 * np.sqrt(np.clip(1 - (x / a_ref) ** 2, 0, None)))[inner].max() < 0.01 * p0
    assert r.a == pytest.approx(a_ref, abs=p.grid.dx)
    assert r.extra["line_contact"] is True and r.to_dict()["b"] is None


def test_carter_steady_rolling():
    xi = -0.00024                       # Carter: a' = 0.6 a, FX = +0.64 mu FN
    a, p = line_problem(xi=xi)
    r = line.solve(p)
    assert r.converged
    assert r.FX / (MU * r.FN) == pytest.approx(ref.carter_force(xi, mu=MU, a=1.0, R=R), abs=0.01)
    stick = np.count_nonzero(r.field.status[:, 0] == ADHESION) * p.grid.dx
    assert stick / 2 == pytest.approx(ref.carter_adhesion_width(xi, mu=MU, a=1.0, R=R), abs=p.grid.dx)
    x = p.grid.x
    _, p0 = ref.hertz_2d(FN, R, Material.identical(G, NU).E_star)
    carter = ref.carter_traction(x, xi, mu=MU, a=1.0, R=R, p0=p0)
    away = (np.abs(x) < 0.95) & (np.abs(x - (1.0 - 2 * 0.6)) > 2 * p.grid.dx)
    assert np.abs(r.field.px[:, 0] - carter)[away].max() < 0.02 * MU * p0
    # the reference length of the logarithm does not change the forces (only the approach)
    op2 = line.LineInfluence.for_grid(p.grid, p.material, ref_length=50.0)
    assert op2.ref_length == 50.0


def test_line_contact_from_a_scene():
    """[geometry] kind = "quadratic" with B = 0 is line contact; the load is per mm of line."""
    r = conformal.solve({"material": {"G": G, "nu": NU}, "friction": {"mu": MU},
                         "geometry": {"kind": "quadratic", "A": 1.0 / (2 * R), "B": 0.0},
                         "load": {"normal_force": FN}, "kinematics": {"xi": -0.00024},
                         "grid": {"n": 80}, "model": {"theory": "exact"}})
    assert r.extra["line_contact"] is True
    assert r.FX / (MU * r.FN) == pytest.approx(0.64, abs=0.015)
    with pytest.raises(InputError, match="B = 0"):
        conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 0.0},
                         "load": {"normal_force": FN}, "model": {"theory": "fastsim"}})
    with pytest.raises(InputError, match="approach"):
        conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 0.0},
                         "load": {"approach": 0.01}, "model": {"theory": "exact"}})


def test_dissimilar_line_contact_refused():
    from dataclasses import replace

    _, p = line_problem()
    with pytest.raises(InputError, match="quasi-identical"):
        line.solve(replace(p, material=Material(G1=82000.0, nu1=0.28, G2=40000.0, nu2=0.4)))
