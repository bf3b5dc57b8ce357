"""Line contact (B = 0, plane strain) with the half-plane influence numbers (conformal.solvers.line):
2-D Hertz and Carter's steady rolling (conformal.reference), from the API and from a scene."""
from __future__ import annotations

import numpy as np
import pytest

import conformal
from conformal import reference as ref
from conformal.errors import InputError
from conformal.influence.halfplane import LineInfluence
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
    op2 = LineInfluence.for_grid(p.grid, p.material, ref_length=50.0)
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


def long_contact_section(rolling: str, ratio: float, mx: int = 60, my: int = 41):
    """The middle row (y = 0) of a long Hertzian contact of the 3-D exact theory (A / B = ratio, so
    b >> a), steel on aluminium, mu = 0.1, no creepage; and the 2-D line contact with the same line
    load and half-width.  Returns (3-D pressure, 3-D traction px, 2-D pressure, 2-D px, status 3-D,
    status 2-D, p0)."""
    mu, A, FN3 = 0.1, 1.0 / 1000.0, 20000.0
    scene = {"material": {"G": 82000.0, "nu": 0.28, "body2": {"G": 26000.0, "nu": 0.33}}, "friction": {"mu": mu},
             "geometry": {"kind": "quadratic", "A": A, "B": A / ratio}, "load": {"normal_force": FN3},
             "kinematics": {"rolling": rolling}, "model": {"theory": "hertz"}}
    hz = conformal.solve(scene)
    a, b = hz.a, hz.b
    scene.update(grid={"mx": mx, "my": my, "dx": 2.2 * a / mx, "dy": 2.2 * b / my, "xl": -1.1 * a, "yl": -1.1 * b},
                 model={"theory": "exact", "tol": 1e-8})
    r3 = conformal.solve(scene)
    j = my // 2                                        # the row through y = 0
    p3, q3 = r3.field.pn[:, j], r3.field.px[:, j]
    mat = Material(G1=82000.0, nu1=0.28, G2=26000.0, nu2=0.33)
    P = float(p3.sum()) * 2.2 * a / mx                 # the same line load (N/mm)
    R2 = np.pi * a * a * mat.E_star / (4 * P)          # and the same 2-D Hertz half-width a
    _, grid = line.line_grid(1 / (2 * R2), P, mat, n=mx, scale=1.1)
    X, _ = grid.mesh()
    prob = ContactProblem(material=mat, friction=Friction(mu, mu), kinematics=Kinematics(rolling=rolling),
                          model=ModelSpec(theory="exact", tol=1e-9), normal_force=P, grid=grid, h=X ** 2 / (2 * R2),
                          info={"line_contact": True})
    r2 = line.solve(prob)
    assert r3.converged and r2.converged
    return p3, q3, r2.field.pn[:, 0], r2.field.px[:, 0], r3.field.status[:, j], r2.field.status[:, 0], mu * hz.pmax


@pytest.mark.parametrize("rolling", ["steady", "shift"])
def test_dissimilar_line_contact_is_the_limit_of_long_contacts(rolling):
    """Dissimilar bodies (steel on aluminium) with no creepage: the normal-tangential coupling alone
    makes the tangential tractions (free rolling of dissimilar rollers; compression, Spence's
    problem in one step).  The independent value: the 3-D exact theory's middle section of a
    Hertzian contact with b >> a tends to the 2-D half-plane solution.  Measured (60 elements along
    x): the largest traction difference over the row falls from 0.29 / 0.15 mu p0 (steady / shift)
    at b/a = 18 to 0.145 / 0.071 at b/a = 40 and 0.057 / 0.022 at b/a = 147, as (a/b)^0.78 / ^0.93;
    the pressures agree within 0.5 % of p0 and the adhesion zones to the element at b/a = 147 (15 /
    14 elements).  A wrong sign of the
    coupling would put the adhesion zone at the other edge (steady) and reverse the tractions."""
    diffs = []
    for ratio in (100.0, 400.0, 4000.0):
        p3, q3, p2, q2, st3, st2, mu_p0 = long_contact_section(rolling, ratio)
        diffs.append(float(np.abs(q3 - q2).max() / mu_p0))
        assert np.abs(p3 - p2).max() < 0.006 * mu_p0 / 0.1      # pressures within 0.6 % of p0
    assert diffs[0] > diffs[1] > diffs[2]
    rate = -np.polyfit(np.log([18.2, 40.5, 146.6]), np.log(diffs), 1)[0]   # b/a of the three
    assert 0.5 < rate < 1.2
    assert diffs[2] < (0.07 if rolling == "steady" else 0.03)
    # the same adhesion zone, at the same edge
    assert abs(int((st3 == ADHESION).sum()) - int((st2 == ADHESION).sum())) <= 1
    assert np.flatnonzero(st3 == ADHESION).mean() == pytest.approx(np.flatnonzero(st2 == ADHESION).mean(), abs=1.0)
    assert np.sign(q2[np.argmax(np.abs(q2))]) == np.sign(q3[np.argmax(np.abs(q2))])
