"""Kalker's exact theory on a planar grid (half-space influence numbers; Kalker 1990): the model "exact".

The normal problem (seed Eqs. 45-46, :mod:`conformal.solvers.normal`) and the tangential problem
(seed Eqs. 47-49, :mod:`conformal.solvers.tangential`) on one potential contact grid.

* Quasi-identical bodies (K = 0): the two problems decouple; the normal problem is solved first,
  then the tangential problem with that pressure ("Johnson's process", one pass).
* Dissimilar bodies (K != 0): the pressure causes tangential displacements (A_tn p_n) and the
  tangential tractions cause normal ones (A_nt p_t).  The two problems are solved alternately,
  each with the other's coupling displacement, until both stop changing (the Panagiotopoulos
  process, as CONTACT's MAXOUT loop).  The history of changes is in ``Result.extra["outer"]``.

Totals as CONTACT prints them (the CONTACT cases of tests/reference/contact_cases.json):
elastic energy dxdy/2000 sum p.u (J); frictional power V/1000 dxdy sum p_t.s_t (W, steady
rolling, s = relative slip) or frictional work dxdy/1000 sum p_t.S_t (J, shift, S = slip distance).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from conformal.errors import InputError
from conformal.grid import PlanarGrid, connected_parts
from conformal.influence.operator import InfluenceOperator, build_operator
from conformal.problem import ContactProblem
from conformal.result import ADHESION, EXTERIOR, Result, TractionField
from conformal.solvers.normal import NormalSolution, solve_normal, warm_precondition

#: at most this many normal/tangential alternations for K != 0 ([model] maxout overrides)
MAXOUT = 50


def needs_tangential(problem: ContactProblem, op: InfluenceOperator) -> bool:
    """Whether the problem has a tangential part: coupling, creepages, prescribed forces or rigid slip."""
    k = problem.kinematics
    return (op.coupled or k.fx_rel is not None or k.fy_rel is not None
            or any(v != 0.0 for v in (k.xi, k.eta, k.phi)) or problem.info.get("rigid_slip") is not None)


def check_kinematics(problem: ContactProblem) -> None:
    """Finite creepages and prescribed forces |F|/(mu FN) < 1 (InputError otherwise)."""
    k = problem.kinematics
    for key in ("xi", "eta", "phi"):
        v = getattr(k, key)
        if not math.isfinite(v):
            raise InputError(f"[kinematics] {key}: must be a finite number, got {v!r}")
    for key in ("fx_rel", "fy_rel"):
        v = getattr(k, key)
        if v is not None and not (math.isfinite(v) and abs(v) < 1.0):
            raise InputError(f"[kinematics] {key}: a force F/(mu FN) must lie in (-1, 1), got {v!r}")


def patch_extent(grid: PlanarGrid, contact: np.ndarray) -> tuple[float, float]:
    """Half the extent (mm) of the contact elements in x and y, element widths included."""
    return _extent(grid, contact.any(axis=1), contact.any(axis=0))


def _extent(grid, rows: np.ndarray, cols: np.ndarray) -> tuple[float, float]:
    """:func:`patch_extent` from the rows (ix) and the columns (iy) that hold contact elements."""
    ix = np.flatnonzero(rows)
    if ix.size == 0:
        return 0.0, 0.0
    iy = np.flatnonzero(cols)
    return 0.5 * (ix[-1] - ix[0] + 1) * grid.dx, 0.5 * (iy[-1] - iy[0] + 1) * grid.dy


def border_sides(grid: PlanarGrid, contact: np.ndarray, rows: np.ndarray | None = None,
                 cols: np.ndarray | None = None) -> list[str]:
    """The borders of the potential contact area that contact elements reach (``rows``, ``cols``:
    ``contact.any(axis=1)`` and ``contact.any(axis=0)`` where the caller has them)."""
    rows = contact.any(axis=1) if rows is None else rows
    cols = contact.any(axis=0) if cols is None else cols
    sides = []
    if rows[0]:
        sides.append("x = xl (trailing edge)")
    if rows[-1]:
        sides.append("x = xh (leading edge)")
    if grid.my > 1 and cols[0]:
        sides.append("y = yl")
    if grid.my > 1 and cols[-1]:
        sides.append("y = yh")
    return sides


def _edge_warning(grid: PlanarGrid, contact: np.ndarray, rows: np.ndarray | None = None,
                  cols: np.ndarray | None = None) -> str | None:
    """A warning when the contact reaches the border of the potential contact area
    (:func:`border_sides`)."""
    sides = border_sides(grid, contact, rows, cols)
    if not sides:
        return None
    return ("the contact area reaches the border of the potential contact area at " + ", ".join(sides)
            + ": the solution is truncated there; enlarge the grid ([grid] scale, or xl/yl/mx/my)")


def _patches(grid: PlanarGrid, pn: np.ndarray, contact: np.ndarray) -> list[float]:
    """Normal force of each connected contact patch (edge-connected elements), largest first."""
    labels, n = connected_parts(contact)
    if n == 0:
        return []
    forces = np.bincount(labels.ravel(), weights=np.asarray(pn, float).ravel(), minlength=n + 1)[1:] * grid.area
    return sorted((float(f) for f in np.atleast_1d(forces)), reverse=True)


def _relative_change(new: np.ndarray, old: np.ndarray, scale: float) -> float:
    return float(np.abs(new - old).sum()) / max(scale, 1e-300)


def maxout_option(model) -> int:
    """[model] maxout: the most normal/tangential alternations (default MAXOUT)."""
    maxout = dict(model.options).get("maxout", MAXOUT)
    if isinstance(maxout, bool) or not isinstance(maxout, int) or maxout < 1:
        raise InputError(f"[model] maxout: must be a whole number >= 1, got {maxout!r}")
    return maxout


def solve_tangential_stage(op, grid, pn, problem, extra_u, tol, maxit, p_start):
    """The tangential problem of a planar contact problem for the pressure ``pn`` (one stage of
    :func:`alternate`), with the problem's kinematics and friction (without the displacements
    u_x, u_y for a lean problem, ``ContactProblem.lean``)."""
    from conformal.solvers.tangential import solve_tangential

    k, f = problem.kinematics, problem.friction
    # per-element inputs (conformal.problem._with_inputs): friction along the profile enters as the
    # bound mu(s) p_n = mu_static (p_n mu(s)/mu_static); a rigid slip per element adds to w
    scale = problem.info.get("mu_scale")
    pn_bound = pn if scale is None else pn * scale
    return solve_tangential(op, grid, pn_bound, xi=k.xi, eta=k.eta, phi=k.phi, mu_static=f.mu_static,
                            mu_kinetic=f.mu_kinetic, rolling=k.rolling, fx_rel=k.fx_rel, fy_rel=k.fy_rel,
                            extra_u=extra_u, tol=tol, maxit=maxit, p_start=p_start,
                            rigid_slip=problem.info.get("rigid_slip"), displacements=not problem.lean)


@dataclass(frozen=True, eq=False)
class Stages:
    """The outcome of :func:`alternate`: the last normal and tangential solutions (``tang`` None
    when no tangential problem was solved), the history of the alternations (``outer``: relative
    changes and inner iteration counts), whether they converged, and the inner iterations spent."""

    normal: NormalSolution
    tang: Any
    outer: list
    converged: bool
    normal_iterations: int
    tangential_iterations: int


def alternate(op, normal_stage: Callable, tangential_stage: Callable, *, tangential: bool, tol: float,
              maxout: int, load_coupled: bool = False) -> Stages:
    """The normal and the tangential problem, alternated until both stop changing (Panagiotopoulos).

    ``normal_stage(extra_un, p_start, tang)`` solves the normal problem with the coupling
    displacement A_nt p_t (None at first), a starting pressure, and the current tangential solution
    (None at first; a curved grid's load balance, seed Eq. 46, depends on it);
    ``tangential_stage(pn, extra_u, p_start)`` the tangential problem with A_tn p_n.  One pass
    (Johnson's process) where the problems decouple: op.coupled False (quasi-identical bodies on a
    planar grid) and ``load_coupled`` False.  Shared by the exact (planar) and the conformal
    (curved) theories."""
    normal = normal_stage(None, None, None)
    tang = None
    outer: list[dict] = []
    n_iter, t_iter = normal.iterations, 0
    converged = True
    if tangential:
        extra_u = op.apply_coupling_tn(normal.pn) if op.coupled else None
        tang = tangential_stage(normal.pn, extra_u, None)
        t_iter += tang.iterations
        if op.coupled or load_coupled:  # Panagiotopoulos: alternate until pressure and traction settle
            converged = False
            for it in range(2, maxout + 1):
                pn_old, px_old, py_old = normal.pn, tang.px, tang.py
                extra_un = op.apply_coupling_nt(tang.px, tang.py) if op.coupled else None
                normal = normal_stage(extra_un, pn_old, tang)
                extra_u = op.apply_coupling_tn(normal.pn) if op.coupled else None
                tang = tangential_stage(normal.pn, extra_u, np.stack([px_old, py_old]))
                n_iter += normal.iterations
                t_iter += tang.iterations
                scale = float(np.abs(normal.pn).sum())
                dn = _relative_change(normal.pn, pn_old, scale)
                dt = _relative_change(np.stack([tang.px, tang.py]), np.stack([px_old, py_old]), scale)
                outer.append({"iteration": it, "pressure_change": dn, "traction_change": dt,
                              "normal_iterations": normal.iterations, "tangential_iterations": tang.iterations})
                if max(dn, dt) < tol:
                    converged = True
                    break
    return Stages(normal, tang, outer, converged, n_iter, t_iter)


def solve(problem: ContactProblem) -> Result:
    """Solve one contact problem with the exact half-space theory."""
    grid, h = problem.require_grid("theory \"exact\"")
    if problem.model.influence != "halfspace":
        raise InputError(f"[model] influence: theory \"exact\" uses half-space influence numbers, got "
                         f"{problem.model.influence!r} (finite-element influence numbers: theory \"conformal\")")
    check_kinematics(problem)
    maxout = maxout_option(problem.model)
    tol, maxit = problem.model.tol, problem.model.maxit
    mat = problem.material
    # [model] influence_file: the file's numbers
    op, _ = build_operator(grid, mat, influence_file=problem.info.get("influence_file"))
    load = dict(normal_force=problem.normal_force, approach=problem.approach)

    start = problem.start    # a neighbouring solution on this grid: the iterations start there

    def normal_stage(extra_un, p_start, tang):
        pre = None
        if p_start is None and start is not None:   # a neighbouring solution: preconditioned from 400 elements
            p_start = start[0]
            pre = warm_precondition(grid, p_start)
        return solve_normal(op, grid, h, tol=tol, maxit=maxit, extra_un=extra_un, p_start=p_start,
                            precondition=pre, **load)

    def tangential_stage(pn, extra_u, p_start):
        if p_start is None and start is not None and start[1] is not None:
            # the neighbour's tractions relative to its pressure (on the bound where it slipped)
            from conformal.solvers.tangential import rescaled_start
            p_start = rescaled_start(np.stack([start[1], start[2]]), start[0], pn)
        return solve_tangential_stage(op, grid, pn, problem, extra_u, tol, maxit, p_start)

    stages = alternate(op, normal_stage, tangential_stage, tangential=needs_tangential(problem, op), tol=tol,
                       maxout=maxout)
    return planar_result(problem, grid, h, op, stages)


@dataclass(frozen=True, eq=False)
class Tractions:
    """Per-element arrays of a solved problem (grid shape): tractions, slip, displacement
    differences (u_n with the coupling A_nt p_t of the final traction), status, and the tangential
    residual and convergence (0 and True without a tangential problem).  Lean (``ContactProblem.lean``):
    ux, uy None where the tangential solve skipped them, un without the coupling A_nt p_t."""

    px: np.ndarray
    py: np.ndarray
    sx: np.ndarray
    sy: np.ndarray
    un: np.ndarray
    ux: np.ndarray | None
    uy: np.ndarray | None
    status: np.ndarray
    residual: float
    converged: bool


def tractions(op, stages: Stages, lean: bool = False) -> Tractions:
    normal, tang = stages.normal, stages.tang
    if tang is None:  # frictionless / no creepage and no coupling: no tangential traction, no slip
        zeros = np.zeros(normal.pn.shape)
        px, py, sx, sy, ux, uy = zeros, zeros, zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy()
        status = np.where(normal.contact, ADHESION, EXTERIOR).astype(np.int8)
        t_res, t_conv = 0.0, True
    else:
        px, py, sx, sy, ux, uy = tang.px, tang.py, tang.sx, tang.sy, tang.ux, tang.uy
        status = np.where(normal.contact, tang.status, EXTERIOR).astype(np.int8)
        t_res, t_conv = float(tang.residual), bool(tang.converged)
    un = normal.un
    if op.coupled and tang is not None and not lean:  # the coupling A_nt p_t of the final tangential traction
        un = op.apply_normal(normal.pn) + op.apply_coupling_nt(px, py)
    return Tractions(px, py, sx, sy, un, ux, uy, status, t_res, t_conv)


def _area_sum(values: np.ndarray, dA) -> float:
    """sum values dA with dA one area (planar) or per column (curved)."""
    return dA * float(values.sum()) if np.ndim(dA) == 0 else float((values * dA).sum())


def solution_extra(problem, stages: Stages, tr: Tractions, dA) -> dict:
    """Result.extra entries common to the grid theories: CONTACT's totals (elastic energy,
    frictional power or work), iterations, residuals, element counts."""
    normal, kin = stages.normal, problem.kinematics
    extra = {
        "elastic_energy": _area_sum(normal.pn * tr.un + tr.px * tr.ux + tr.py * tr.uy, dA) / 2000.0,   # J
        "normal_iterations": stages.normal_iterations,
        "tangential_iterations": stages.tangential_iterations,
        "normal_residual": normal.residual,
        "tangential_residual": tr.residual,
        "gap_residual": normal.gap_residual,
        "n_adhesion": int(np.count_nonzero(tr.status == ADHESION)),
        "n_potential": int(normal.pn.size),
    }
    dissipation = _area_sum(tr.px * tr.sx + tr.py * tr.sy, dA)   # N mm per unit rolled / per shift
    if kin.rolling == "shift":
        extra["frictional_work"] = dissipation / 1000.0                              # J
    else:
        extra["frictional_power"] = kin.velocity / 1000.0 * dissipation              # W
    return extra


def convergence_warnings(stages: Stages, tr: Tractions, tol: float, coupling: str) -> list[str]:
    """Warnings for the parts that did not converge (``coupling``: what couples the problems)."""
    normal, warnings = stages.normal, []
    if not normal.converged:
        warnings.append(f"normal problem: not converged after {normal.iterations} iterations "
                        f"(relative change {normal.residual:.3g} > tol {tol:g})")
    if not tr.converged:
        warnings.append(f"tangential problem: not converged (residual {tr.residual:.3g})")
    if not stages.converged:
        warnings.append(f"normal-tangential coupling ({coupling}): not converged after "
                        f"{1 + len(stages.outer)} alternations; raise [model] maxout")
    return warnings


def planar_result(problem, grid, h, op, stages: Stages) -> Result:
    """The :class:`Result` of a planar contact problem from its solved stages (totals as CONTACT
    prints them, module docstring).  A lean problem (``ContactProblem.lean``, a solve that is never
    the answer) gets the totals and the field (pn, px, py, status, slip) alone: an empty ``extra``
    (no patches, totals of energy, iteration counts or warnings)."""
    dA = grid.area
    kin = problem.kinematics
    normal, tang = stages.normal, stages.tang
    tr = tractions(op, stages, lean=problem.lean)
    xi, eta = (kin.xi, kin.eta) if tang is None else (tang.xi, tang.eta)
    field = TractionField(grid=grid, pn=normal.pn, px=tr.px, py=tr.py, status=tr.status, sx=tr.sx, sy=tr.sy,
                          un=tr.un, ux=tr.ux, uy=tr.uy)
    FN, FX, FY, MZ = field.totals()
    rows, cols = normal.contact.any(axis=1), normal.contact.any(axis=0)   # for the extent and the edges
    a, b = _extent(grid, rows, cols)
    common = dict(theory="exact", FN=FN, FX=FX, FY=FY, MZ=MZ, a=a, b=b, pmax=normal.pmax, approach=normal.approach,
                  xi=xi, eta=eta, phi=kin.phi, converged=bool(normal.converged and tr.converged and stages.converged),
                  iterations=stages.normal_iterations + stages.tangential_iterations,
                  residual=max(normal.residual, tr.residual), field=field)
    if problem.lean:
        return Result(**common)
    patch_fn = _patches(grid, normal.pn, normal.contact)
    extra = solution_extra(problem, stages, tr, dA)
    extra.update({
        "n_patches": len(patch_fn),
        "patch_FN": patch_fn,
        "FX_rel": FX / (problem.friction.mu_static * FN) if FN > 0 else None,
        "FY_rel": FY / (problem.friction.mu_static * FN) if FN > 0 else None,
        "FN_over_G": FN / problem.material.G,
        "grid": {"mx": grid.mx, "my": grid.my, "dx": grid.dx, "dy": grid.dy, "xl": grid.xl, "yl": grid.yl},
    })
    if op.coupled:
        extra["outer_iterations"] = 1 + len(stages.outer)
        extra["outer"] = stages.outer
    warnings = []
    edge = _edge_warning(grid, normal.contact, rows, cols)
    if edge:
        warnings.append(edge)
    warnings += convergence_warnings(stages, tr, problem.model.tol, f"K = {op.K:.4g}")
    if warnings:
        extra["warnings"] = warnings
    if problem.hertz is not None:
        hz = problem.hertz
        extra["hertz"] = {"a": hz.a, "b": hz.b, "pmax": hz.pmax, "approach": hz.approach, "FN": hz.FN}
    return Result(extra=extra, **common)
