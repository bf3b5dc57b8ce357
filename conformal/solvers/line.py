"""Line contact (B = 0): Kalker's exact theory in plane strain on a row of elements along x, with
the influence numbers of the elastic half-plane (2-D), not a long 3-D strip.

Two cylinders with parallel axes along y touch along a line; per unit length along y the problem
is two-dimensional: normal pressure and longitudinal traction in plane strain, lateral traction in
anti-plane shear.  A line load P on a half-plane displaces the surface by (Johnson 1985, eqs.
2.19, 2.25; both bodies, combined constants G, nu, E* = G/(1 - nu))

    u_n(x) = -(2/(pi E*)) P ln(|x|/L),    u_x(x) = -(2/(pi E*)) Q_x ln(|x|/L),
    u_y(x) = -(2/(pi G)) Q_y ln(|x|/L),

up to a rigid-body constant that 2-D elasticity leaves undetermined (the reference length L: the
depth of the datum).  Integrated over an element of width dx (F(t) = t ln|t| - t)::

    A(x) = -(2/(pi E*)) [F(x + dx/2) - F(x - dx/2) - dx ln L]        (A_nn = A_xx; A_yy with G)

Dissimilar bodies couple the normal and longitudinal problems (Johnson eqs. 2.19b, 2.25b): a
normal line load displaces the surfaces along x by -(K/G) P sgn(x) and a tangential one along the
normal by +(K/G) Q_x sgn(x), with Kalker's difference parameter K = (G/4)((1 - 2 nu1)/G1 -
(1 - 2 nu2)/G2), the limit b -> infinity of the half-space's K terms (the integral over y of
x/r^2 is pi sgn x).  Over an element (sgn integrated: 2 clip(x, -dx/2, dx/2))::

    A_xn(x) = -A_nx(x) = -(K/G) 2 clip(x, -dx/2, dx/2)

With the normal force prescribed (per unit length) the constant only shifts the approach, and in
steady rolling only differences of u enter, so forces, pressures, tractions and slip do not depend
on L; :data:`REFERENCE_FACTOR` sets L = that factor times the length of the grid, which keeps
the discrete operator positive definite (the logarithmic capacity of the grid, length/4, stays
below L).  The reported ``approach`` is relative to that datum: a prescribed approach is refused.

The grid is a row of mx elements of length dx and width dy = 1 mm, so that FN, FX, FY are per mm
of line length (N/mm) and MZ per mm (N).  The kernel is a :class:`CurvedInfluence` strip with one
element across (ms = 1), the operator the normal and tangential solvers take for curved strips.

Checks (tests/validation/test_line_contact.py): 2-D Hertz (half-width and peak pressure, Johnson eq. 4.45),
Carter's steady rolling (force, adhesion width and traction, conformal.reference), and for
dissimilar bodies the middle section of a long Hertzian contact (b = 20 a) of the 3-D exact theory.

The operator is :class:`conformal.influence.halfplane.LineInfluence` (built by the factory of
:mod:`conformal.influence.operator`).
"""
from __future__ import annotations

from dataclasses import replace

from conformal.errors import InputError
from conformal.grid import PlanarGrid
from conformal.influence.halfplane import REFERENCE_FACTOR, UNIT_WIDTH  # noqa: F401
from conformal.influence.operator import build_operator
from conformal.materials import Material
from conformal.problem import ContactProblem
from conformal.result import Result
from conformal.solvers import exact
from conformal.solvers.normal import solve_normal


def line_grid(A: float, FN: float, material: Material, n: int = 40, scale: float = 1.1) -> tuple[float, PlanarGrid]:
    """2-D Hertz half-width a (Johnson eq. 4.45, R = 1/(2A)) and a row of n elements over
    [-scale a, scale a], dy = UNIT_WIDTH."""
    from conformal.reference import hertz_2d

    a, _ = hertz_2d(FN, 1.0 / (2.0 * A), material.E_star)
    dx = 2.0 * scale * a / n
    return a, PlanarGrid(int(n), 1, dx, UNIT_WIDTH, -scale * a, -0.5 * UNIT_WIDTH)


def check_line_problem(problem: ContactProblem) -> None:
    if problem.normal_force is None:
        raise InputError("[load] approach: line contact (B = 0) needs normal_force (N per mm of line length): "
                         "the 2-D approach depends on an arbitrary datum")
    if problem.model.influence != "halfspace":
        raise InputError("[model] influence: line contact uses the half-plane influence numbers (\"halfspace\")")


def solve(problem: ContactProblem) -> Result:
    """Solve a line-contact problem (grid with my = 1, ``normal_force`` per mm) with the exact
    theory on the half-plane: normal problem, then steady rolling or shift as the kinematics say."""
    grid, h = problem.require_grid("line contact")
    check_line_problem(problem)
    exact.check_kinematics(problem)
    tol, maxit = problem.model.tol, problem.model.maxit
    op, _ = build_operator(grid, problem.material, line=True)
    FN = problem.normal_force * grid.dy  # N per mm times the unit width

    def normal_stage(extra_un, p_start, tang):
        return solve_normal(op, grid, h, normal_force=FN, material=problem.material, tol=tol, maxit=maxit,
                            extra_un=extra_un, p_start=p_start)

    def tangential_stage(pn, extra_u, p_start):
        return exact.solve_tangential_stage(op, grid, pn, problem, extra_u, tol, maxit, p_start)

    stages = exact.alternate(op, normal_stage, tangential_stage, tangential=exact.needs_tangential(problem, op),
                             tol=tol, maxout=exact.maxout_option(problem.model))
    res = exact.planar_result(problem, grid, h, op, stages)
    extra = dict(res.extra, line_contact=True, reference_length=op.ref_length,
                 per_unit_length="FN, FX, FY in N/mm, MZ in N (per mm of line length)")
    extra.pop("hertz", None)
    # no lateral extent: b is undefined (null in the JSON)
    return replace(res, b=float("nan"), extra=extra)
