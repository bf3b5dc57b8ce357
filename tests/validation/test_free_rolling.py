"""Free rolling in a deep conformal groove (issue 11, item 1): a 10 mm crowned wheel (rolling
radius 50 mm) in a 10.02 mm rail groove.  The rolling radius falls by 2.5 mm across the patch
(contact angles +-40 degrees), so every column of the curved strip has its own longitudinal
creepage xi(s) (Heathcote slip) and at FX = 0 the reference creepage balances the radius
variation.

Independent check: the full-slip limit.  As mu -> 0 the tangential displacements vanish with the
tractions (except the part the pressure itself causes through the rotated frames, A_tn p_n), the
slip is the rigid slip w = (xi(s) + dxi, eta(s) + phi(s) x) and the traction is mu p w/|w|; FX = 0
then fixes dxi from the pressure alone (a root of sum p dS w_x/|w|), with no tangential solver,
no upwind difference along x and no prescribed-force iteration.  Measured (24 / 40 elements):
the solved free-rolling creepage lies +1.4 / +1.1 % off this limit at mu = 0.003 (the
pressure-induced tangential displacements of the rotated half-space frames; +0.3 % at 40 elements
with the developed, unrolled kernel) and -1.9 / +3.7 % at mu = 0.3 (the elastic adhesion zone).
"""

import numpy as np
import pytest
from scipy.optimize import brentq

from conformal.cases.conformal import curved_problem_from_wheel_rail, solve_wheel_rail_conformal
from conformal.scene import load_scene, scene_from_dict
from conformal.solvers.conformal import solve_curved
from _paths import SCENES



def groove(mu=0.3, n=24, **kin):
    raw = load_scene(SCENES / "groove_conformal.toml").to_dict()
    raw["friction"] = {"mu": mu}
    raw["grid"] = {"n": n}
    k = {"speed": 1000.0, "pitch_velocity": -19.98}
    k.update(kin)
    raw["kinematics"] = {key: v for key, v in k.items() if v is not None}
    return scene_from_dict(raw, base_dir=SCENES, name="groove_free")


def full_slip_creepage(problem, pn):
    """The reference creepage at FX = 0 in the full-slip limit (module docstring)."""
    g = problem.grid
    X = g.x[:, None]
    ws = problem.eta_s[None, :] + problem.phi_s[None, :] * X
    w = pn * np.broadcast_to(g.area, g.shape)

    def fx(d):
        wx = problem.xi_s[None, :] + d
        return float((w * wx / np.hypot(wx, ws)).sum())

    d = brentq(fx, -0.2, 0.2, xtol=1e-14)
    return float(np.interp(g.s_ref, g.s, problem.xi_s)) + d


_FREE: dict = {}


def free(mu):
    if mu not in _FREE:
        _FREE[mu] = solve_wheel_rail_conformal(groove(mu, fx_rel=0.0))
    return _FREE[mu]


@pytest.mark.slow
@pytest.mark.parametrize("mu,tol", [pytest.param(0.003, 0.025, marks=pytest.mark.slow), (0.3, 0.06)])
def test_free_rolling_creepage_against_the_full_slip_limit(mu, tol):
    """The solved pitch creepage at FX = 0 against the full-slip limit of the same wheelset motion
    and pressure (module docstring): within 2.5 % at mu = 0.003 (measured +1.4 % on this grid,
    +1.1 % at 40 elements), and within 6 % at mu = 0.3 (measured -1.9 % here, +3.7 % at 40
    elements: the adhesion zone and the discretisation of the patch edges)."""
    r = free(mu)
    xi_free = r.extra["pitch_creepage_free"]
    # the same scene at the solved pitch velocity, without the prescribed force: FX ~ 0
    problem = curved_problem_from_wheel_rail(groove(mu, pitch_velocity=r.extra["pitch_velocity_solved"]))
    check = solve_curved(problem)
    assert abs(check.extra["FX_rel"]) < 2e-3
    assert np.interp(problem.grid.s_ref, problem.grid.s, problem.xi_s) == pytest.approx(xi_free, rel=1e-9)
    limit = full_slip_creepage(problem, check.field.side_frame("pn"))
    assert abs(xi_free / limit - 1.0) < tol
    # the groove lowers the rolling radius away from the crown: the free-rolling wheel turns faster
    # than V / R_ref, and xi_free is of the order of the pressure-weighted radius drop over R
    assert xi_free > 0.002 and r.extra["pitch_velocity_solved"] < -20.0


def test_free_rolling_json_fields():
    """The solved pitch is reported (added fields); the root search ends at FX = 0 within 1e-4 mu FN
    in a few solves; the reference radius is the crown's 50 mm."""
    r = free(0.3)
    d = r.to_dict()
    for key in ("pitch_creepage_free", "pitch_velocity_solved", "pitch_creepage_solved", "reference_rolling_radius"):
        assert key in d
    assert d["reference_rolling_radius"] == pytest.approx(50.0, abs=0.01)
    assert abs(r.FX) < 1e-4 * 0.3 * r.FN and d["pitch_solves"] < 20
    # the pitch creepage is the creepage of the reference column (the JSON xi) at the solved pitch
    V, R = 1000.0, d["reference_rolling_radius"]
    q = d["pitch_velocity_solved"] * R
    assert d["pitch_creepage_free"] == pytest.approx(-(V + q) / (0.5 * (V - q)), rel=1e-9)


@pytest.mark.slow
def test_prescribed_force_through_the_pitch():
    """fx_rel != 0 with the wheelset motion: the pitch is solved for FX/(mu FN) = -0.8 (near
    saturation, a creepage 20 times the free-rolling one), to 1e-6."""
    r = solve_wheel_rail_conformal(groove(0.3, fx_rel=-0.8))
    assert r.extra["FX_rel"] == pytest.approx(-0.8, abs=1e-6)
    assert "pitch_creepage_free" not in r.extra and r.extra["pitch_creepage_solved"] > 0.01
