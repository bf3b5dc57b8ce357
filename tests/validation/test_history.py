"""Load histories with memory of the previous tractions (conformal.solvers.history, seed Eqs. 39-40):
Cattaneo's growing tangential force, Mindlin-Deresiewicz unloading, the onset of rolling."""
from __future__ import annotations

import math

import numpy as np
import pytest

from conformal import reference as ref
from conformal.errors import InputError
from conformal.problem import problems_from_scene
from conformal.result import ADHESION, SLIP
from conformal.scene import scene_from_dict
from conformal.solvers.history import HistoryStep, solve_history
from conformal.solvers.tangential import solve_tangential

MU, FN, A_ = 0.3, 1000.0, 1.0


def problem(n=30, nu=0.28):
    s = scene_from_dict({"material": {"G": 82000.0, "nu": nu}, "friction": {"mu": MU},
                         "geometry": {"kind": "hertz", "a": A_, "b": A_}, "load": {"normal_force": FN},
                         "grid": {"n": n}, "model": {"theory": "exact", "tol": 1e-8}})
    return problems_from_scene(s)[0]


def stick_radius(res) -> float:
    """Radius of the adhesion area from its element count (c = sqrt(n dA / pi))."""
    f = res.field
    return math.sqrt(np.count_nonzero(f.status == ADHESION) * f.grid.area / math.pi)


def contact_radius(res) -> float:
    f = res.field
    return math.sqrt(np.count_nonzero(f.pn > 0) * f.grid.area / math.pi)


def test_cattaneo_loading_in_steps():
    """FX grows at constant FN in three steps: the stick radius follows (1 - Q/(mu P))^(1/3) and the
    accumulated shift Johnson's eq. 7.42 (Cattaneo); the last step equals one shift to the same force
    (monotone loading does not depend on the path)."""
    p = problem()
    qs = (-0.25, -0.5, -0.75)
    h = solve_history(p, [HistoryStep(fx_rel=q) for q in qs])
    G, nu = p.material.G, p.material.nu
    for q, r, sh in zip(qs, h.steps, h.shift):
        assert r.converged
        assert r.FX / (MU * r.FN) == pytest.approx(q, abs=1e-7)
        a = contact_radius(r)
        # discrete radii: within about half an element (dx = 0.073 a)
        assert stick_radius(r) / a == pytest.approx(ref.cattaneo_stick_ratio(q), abs=0.04)
        w = ref.cattaneo_shift(q, mu=MU, FN=r.FN, a=r.extra["hertz"]["a"], G=G, nu=nu)
        assert sh[0] == pytest.approx(w, rel=0.02)
    one = solve_history(p, [HistoryStep(fx_rel=qs[-1])]).steps[0]
    # the same up to round-off of the tolerance and the tiny py that nu != 0 couples in (2e-4 measured)
    assert np.abs(one.field.px - h.steps[-1].field.px).max() < 1e-3 * MU * h.steps[-1].pmax
    assert h.steps[-1].n_slip == one.n_slip


def test_mindlin_unloading_reverse_slip_annulus():
    """Loading to Q* = 0.9 mu P, then unloading to Q = 0.1 mu P (Mindlin & Deresiewicz 1953; Johnson
    1985 §7.2): the slip reverses in the annulus c' < r < a with c'/a = (1 - (Q* - Q)/(2 mu P))^(1/3),
    and the traction is q(Q*) - 2 q((Q* - Q)/2) (Cattaneo distributions)."""
    p = problem(n=36)
    qstar, q = -0.9, -0.1
    h = solve_history(p, [HistoryStep(fx_rel=qstar), HistoryStep(fx_rel=q)])
    load, unload = h.steps
    assert unload.converged and unload.FX / (MU * unload.FN) == pytest.approx(q, abs=1e-7)
    f = unload.field
    a = contact_radius(unload)
    # the reverse-slip annulus
    rev = unload.extra["n_reversed"]
    assert rev > 0 and rev == np.count_nonzero(f.status == SLIP)    # every slipping element slips back
    c_rev = math.sqrt(max(np.count_nonzero(f.pn > 0) - rev, 0) * f.grid.area / math.pi)
    expected = (1.0 - abs(qstar - q) / 2.0) ** (1.0 / 3.0)
    assert c_rev / a == pytest.approx(expected, abs=0.04)
    # the traction along the x axis against Mindlin-Deresiewicz
    hz = unload.extra["hertz"]
    x = f.grid.x
    j = f.grid.my // 2
    r = np.abs(np.hypot(x, f.grid.y[j]))
    md = (ref.cattaneo_traction(r, qstar, mu=MU, a=hz["a"], p0=hz["pmax"])
          - 2.0 * ref.cattaneo_traction(r, (qstar - q) / 2.0, mu=MU, a=hz["a"], p0=hz["pmax"]))
    # away from the two kinks of the distribution (the stick and reverse-slip edges), where the
    # piecewise-constant elements smear a square-root corner
    dx = f.grid.dx
    c_star = ref.cattaneo_stick_ratio(qstar) * hz["a"]
    away = (r < hz["a"] - dx) & (np.abs(r - expected * hz["a"]) > 1.5 * dx) & (np.abs(r - c_star) > 1.5 * dx)
    assert np.abs(f.px[:, j] - md)[away].max() < 0.02 * MU * hz["pmax"]
    # the shift on unloading: W(Q*) - 2 W((Q* - Q)/2) (the same Cattaneo compliance)
    G, nu = p.material.G, p.material.nu
    W = (ref.cattaneo_shift(qstar, mu=MU, FN=FN, a=hz["a"], G=G, nu=nu)
         - 2.0 * ref.cattaneo_shift((qstar - q) / 2.0, mu=MU, FN=FN, a=hz["a"], G=G, nu=nu))
    assert h.shift[-1][0] == pytest.approx(W, rel=0.03)
    # hysteresis: at the same force Q the unloading shift differs from the loading one
    w_load = ref.cattaneo_shift(q, mu=MU, FN=FN, a=hz["a"], G=G, nu=nu)
    assert h.shift[-1][0] > 2 * w_load


def test_onset_of_rolling_converges_to_steady_rolling():
    """From the Cattaneo state (a tangential shift at rest), the wheel starts to roll with creepage
    xi in steps of one element: after the contact has rolled over more than its length the tractions
    equal the steady-rolling solution of the same grid (Carter's regime in 3-D)."""
    p = problem(n=24)
    xi = 1.5e-3
    nroll = 60   # 5 contact lengths; the transient decays by about 0.85 per element rolled
    h = solve_history(p, [HistoryStep(fx_rel=-0.4), HistoryStep(rolling="transient", xi=xi, repeat=nroll)])
    last = h.steps[-1]
    pn = last.field.pn
    st = solve_tangential(_op(p), p.grid, pn, xi=xi, eta=0.0, phi=0.0, mu_static=MU, mu_kinetic=MU,
                          rolling="steady", tol=1e-9)
    scale = MU * float(pn.max())
    assert np.abs(last.field.px - st.px).max() < 1e-3 * scale
    assert last.FX == pytest.approx(float(st.px.sum() * p.grid.area), rel=1e-4)
    # the first rolling steps differ from it (the transient): the memory matters
    first = h.steps[1]
    assert abs(first.FX - last.FX) > 0.05 * MU * last.FN


def _op(p):
    from conformal.influence.halfspace import HalfSpaceInfluence

    g = p.grid
    return HalfSpaceInfluence.for_grid(g.mx, g.my, g.dx, g.dy, p.material)


def test_bad_steps_rejected():
    with pytest.raises(InputError, match="rolling"):
        HistoryStep(rolling="sideways")
    with pytest.raises(InputError, match="fx_rel"):
        HistoryStep(fx_rel=1.2)
    with pytest.raises(InputError, match="distance"):
        HistoryStep(distance=0.1)
    p = problem(n=12)
    with pytest.raises(InputError, match="whole number of elements"):
        solve_history(p, [HistoryStep(rolling="transient", xi=1e-3, distance=0.37 * p.grid.dx)])
    with pytest.raises(InputError, match="at least one step"):
        solve_history(p, [])


def test_history_scene_section(tmp_path):
    """[[history]] in a scene file: the steps are solved in order, the JSON's ``history`` lists
    one summary per applied step, the totals are the last step's; bad steps name the key."""
    import json

    import conformal

    text = """
[material]
G = 82000.0
nu = 0.28
[friction]
mu = 0.3
[geometry]
kind = "hertz"
a = 1.0
b = 1.0
[load]
normal_force = 1000.0
[grid]
n = 20
[model]
theory = "exact"

[[history]]
fx_rel = -0.5

[[history]]
fx_rel = -0.875

[[history]]
rolling = "transient"
xi = 0.0015
repeat = 3
"""
    f = tmp_path / "hist.toml"
    f.write_text(text, encoding="utf-8")
    r = conformal.solve(f)
    hist = r.to_dict()["history"]
    assert [h["step"] for h in hist] == [1, 2, 3, 4, 5]
    assert [h["rolling"] for h in hist][:3] == ["shift", "shift", "transient"]
    assert hist[1]["FX"] / (0.3 * hist[1]["FN"]) == pytest.approx(-0.875, abs=1e-6)
    assert r.FX == hist[-1]["FX"]
    # Cattaneo's shift for 7/8 of mu FN (the total of the two shift steps)
    s = conformal.load_scene(f)
    assert len(s.history) == 3 and s.with_("grid.n", 20).history == s.history   # survives with_
    G, nu = 82000.0, 0.28
    assert hist[1]["shift_x"] == pytest.approx(
        ref.cattaneo_shift(-0.875, mu=0.3, FN=1000.0, a=r.extra["hertz"]["a"], G=G, nu=nu), rel=0.03)
    # the command line writes the same history
    from conformal.cli import main

    out = tmp_path / "h.json"
    assert main(["solve", str(f), "--json", str(out)]) == 0
    assert len(json.loads(out.read_text())["history"]) == 5
    # bad steps
    bad = text.replace("fx_rel = -0.5", "fx_rell = -0.5")
    with pytest.raises(InputError, match=r"\[history 1\] fx_rell: unknown key \(did you mean 'fx_rel'\?\)"):
        conformal.solve(_write(tmp_path, bad))
    with pytest.raises(InputError, match="distance"):
        conformal.solve(_write(tmp_path, text.replace("fx_rel = -0.5", "fx_rel = -0.5\ndistance = 0.1")))
    with pytest.raises(InputError, match="theory"):
        conformal.solve(f, model__theory="fastsim")


def _write(tmp_path, text):
    f = tmp_path / "bad.toml"
    f.write_text(text, encoding="utf-8")
    return f


def test_onset_of_rolling_in_2d_from_cattaneo_to_carter():
    """Line contact (B = 0, half-plane): a tangential shift at rest to Q = 0.4 mu P (2-D Cattaneo:
    stick half-width c/a = (1 - Q/(mu P))^(1/2)), then rolling with xi in steps of one element: the
    force reaches Carter's (1 - (a'/a)^2) mu FN and the tractions the steady 2-D solution."""
    import test_line_contact as tl

    from conformal.solvers import line

    _, p = tl.line_problem(n=60)
    xi = 0.00024                          # Carter: a' = 0.6 a, FX = -0.64 mu FN
    h = solve_history(p, [HistoryStep(fx_rel=-0.4), HistoryStep(rolling="transient", xi=xi, repeat=300)])
    first, last = h.steps[0], h.steps[-1]
    dx = p.grid.dx
    c = np.count_nonzero(first.field.status[:, 0] == ADHESION) * dx / 2
    assert c == pytest.approx(math.sqrt(0.6) * 1.0, abs=dx)
    assert last.extra["line_contact"] is True
    assert last.FX / (MU * last.FN) == pytest.approx(ref.carter_force(xi, mu=MU, a=1.0, R=tl.R), abs=0.005)
    steady = line.solve(tl.line_problem(xi=xi, n=60)[1])
    assert np.abs(last.field.px - steady.field.px).max() < 1e-3 * MU * steady.pmax


@pytest.mark.slow
def test_spence_growing_normal_load_is_self_similar():
    """Spence (1975): a sphere pressed on dissimilar material (K != 0) with finite friction, the
    normal load growing monotonically, keeps a stick radius in a constant ratio c/a to the contact
    radius (the solution is self-similar), different from the one-stage (Panagiotopoulos) solution;
    the slip is radial.  35 load stages from FN/8 to FN (CONTACT's spence35 loading)."""
    s = scene_from_dict({"material": {"G": 82000.0, "nu": 0.3, "body2": {"G": 26000.0, "nu": 0.33}},
                         "friction": {"mu": 0.1}, "geometry": {"kind": "hertz", "a": 1.0, "b": 1.0},
                         "load": {"normal_force": 1000.0}, "grid": {"n": 40, "scale": 1.15},
                         "model": {"theory": "exact", "tol": 1e-7}})
    p = problems_from_scene(s)[0]
    assert p.material.K != 0.0
    loads = 1000.0 * (1.0 / 8.0) ** (1.0 - np.arange(1, 36) / 35.0)
    h = solve_history(p, [HistoryStep(normal_force=float(f)) for f in loads])

    def ratio(r):
        nc = np.count_nonzero(r.field.pn > 0)
        return math.sqrt((nc - np.count_nonzero(r.field.status == SLIP)) / nc)

    ratios = [ratio(r) for r in h.steps[9:]]           # after the first stages (start from zero traction)
    assert all(r.converged for r in h.steps)
    # constant within the discreteness of the slip ring (an element is 0.06-0.09 a wide here)
    assert max(ratios) - min(ratios) < 0.04
    one = ratio(solve_history(p, [HistoryStep(normal_force=1000.0)]).steps[0])
    assert one < np.mean(ratios) - 0.2                  # the loading path matters
    f = h.steps[-1].field
    X, Y = f.grid.mesh()
    slip = f.status == SLIP
    cosang = (f.px * X + f.py * Y)[slip] / (np.hypot(f.px, f.py) * np.hypot(X, Y))[slip]
    assert np.mean(np.abs(cosang)) > 0.95               # radial tractions in the slip annulus
    assert abs(h.steps[-1].FX) < 1e-6 * h.steps[-1].FN and abs(h.steps[-1].FY) < 1e-6 * h.steps[-1].FN
