"""Kalker's exact theory on a planar grid (half-space influence numbers): the model "exact".

The normal problem (seed Eqs. 45-46, :mod:`conformal.solvers.normal`) and the tangential problem
(seed Eqs. 47-49, :mod:`conformal.solvers.tangential`) on one potential contact grid.

* Quasi-identical bodies (K = 0): the two problems decouple; the normal problem is solved first,
  then the tangential problem with that pressure ("Johnson's process", one pass).
* Dissimilar bodies (K != 0): the pressure causes tangential displacements (A_tn p_n) and the
  tangential tractions cause normal ones (A_nt p_t).  The two problems are solved alternately,
  each with the other's coupling displacement, until both stop changing (the Panagiotopoulos
  process, as CONTACT's MAXOUT loop).  The history of changes is in ``Result.extra["outer"]``.

Totals as CONTACT prints them (reference/contact_cases.md, "What the printed totals mean"):
elastic energy dxdy/2000 sum p.u (J); frictional power V/1000 dxdy sum p_t.s_t (W, steady
rolling, s = relative slip) or frictional work dxdy/1000 sum p_t.S_t (J, shift, S = slip distance).
"""
from __future__ import annotations

import math

import numpy as np

from conformal.errors import InputError
from conformal.grid import PlanarGrid
from conformal.influence.halfspace import HalfSpaceInfluence
from conformal.problem import ContactProblem
from conformal.result import ADHESION, EXTERIOR, Result, TractionField
from conformal.solvers.normal import NormalSolution, solve_normal

#: at most this many normal/tangential alternations for K != 0 ([model] maxout overrides)
MAXOUT = 50


def _needs_tangential(problem: ContactProblem, op: HalfSpaceInfluence) -> bool:
    k = problem.kinematics
    return (op.coupled or k.fx_rel is not None or k.fy_rel is not None
            or any(v != 0.0 for v in (k.xi, k.eta, k.phi)))


def _check_kinematics(problem: ContactProblem) -> None:
    k = problem.kinematics
    for key in ("xi", "eta", "phi"):
        v = getattr(k, key)
        if not math.isfinite(v):
            raise InputError(f"[kinematics] {key}: must be a finite number, got {v!r}")
    for key in ("fx_rel", "fy_rel"):
        v = getattr(k, key)
        if v is not None and not (math.isfinite(v) and abs(v) < 1.0):
            raise InputError(f"[kinematics] {key}: a force F/(mu FN) must lie in (-1, 1), got {v!r}")


def _patch_extent(grid: PlanarGrid, contact: np.ndarray) -> tuple[float, float]:
    """Half the extent (mm) of the contact elements in x and y, element widths included."""
    if not contact.any():
        return 0.0, 0.0
    ix = np.flatnonzero(contact.any(axis=1))
    iy = np.flatnonzero(contact.any(axis=0))
    return 0.5 * (ix[-1] - ix[0] + 1) * grid.dx, 0.5 * (iy[-1] - iy[0] + 1) * grid.dy


def _edge_warning(grid: PlanarGrid, contact: np.ndarray) -> str | None:
    """A warning when the contact reaches the border of the potential contact area."""
    sides = []
    if contact[0].any():
        sides.append("x = xl (trailing edge)")
    if contact[-1].any():
        sides.append("x = xh (leading edge)")
    if grid.my > 1 and contact[:, 0].any():
        sides.append("y = yl")
    if grid.my > 1 and contact[:, -1].any():
        sides.append("y = yh")
    if not sides:
        return None
    return ("the contact area reaches the border of the potential contact area at " + ", ".join(sides)
            + ": the solution is truncated there; enlarge the grid ([grid] scale, or xl/yl/mx/my)")


def _patches(grid: PlanarGrid, pn: np.ndarray, contact: np.ndarray) -> list[float]:
    """Normal force of each connected contact patch (edge-connected elements), largest first."""
    from scipy import ndimage

    labels, n = ndimage.label(contact)
    if n == 0:
        return []
    forces = ndimage.sum_labels(pn, labels, index=np.arange(1, n + 1)) * grid.area
    return sorted((float(f) for f in np.atleast_1d(forces)), reverse=True)


def _relative_change(new: np.ndarray, old: np.ndarray, scale: float) -> float:
    return float(np.abs(new - old).sum()) / max(scale, 1e-300)


def _tangential(op, grid, pn, problem, extra_u, tol, maxit, p_start):
    from conformal.solvers.tangential import solve_tangential

    k, f = problem.kinematics, problem.friction
    return solve_tangential(op, grid, pn, xi=k.xi, eta=k.eta, phi=k.phi, mu_static=f.mu_static,
                            mu_kinetic=f.mu_kinetic, rolling=k.rolling, fx_rel=k.fx_rel, fy_rel=k.fy_rel,
                            extra_u=extra_u, tol=tol, maxit=maxit, p_start=p_start)


def solve(problem: ContactProblem) -> Result:
    """Solve one contact problem with the exact half-space theory."""
    grid, h = problem.require_grid("theory \"exact\"")
    if problem.model.influence != "halfspace":
        raise InputError(f"[model] influence: theory \"exact\" uses half-space influence numbers, got "
                         f"{problem.model.influence!r} (finite-element influence numbers: theory \"conformal\")")
    _check_kinematics(problem)
    opts = dict(problem.model.options)
    maxout = opts.get("maxout", MAXOUT)
    if isinstance(maxout, bool) or not isinstance(maxout, int) or maxout < 1:
        raise InputError(f"[model] maxout: must be a whole number >= 1, got {maxout!r}")
    tol, maxit = problem.model.tol, problem.model.maxit
    mat = problem.material
    op = HalfSpaceInfluence.for_grid(grid.mx, grid.my, grid.dx, grid.dy, mat)
    load = dict(normal_force=problem.normal_force, approach=problem.approach)

    normal = solve_normal(op, grid, h, tol=tol, maxit=maxit, **load)
    tang = None
    outer: list[dict] = []
    n_iter, t_iter = normal.iterations, 0
    outer_converged = True
    if _needs_tangential(problem, op):
        extra_u = op.apply_coupling_tn(normal.pn) if op.coupled else None
        tang = _tangential(op, grid, normal.pn, problem, extra_u, tol, maxit, None)
        t_iter += tang.iterations
        if op.coupled:  # Panagiotopoulos: alternate until the pressure and the traction settle
            outer_converged = False
            for it in range(2, maxout + 1):
                pn_old, px_old, py_old = normal.pn, tang.px, tang.py
                extra_un = op.apply_coupling_nt(tang.px, tang.py)
                normal = solve_normal(op, grid, h, tol=tol, maxit=maxit, extra_un=extra_un,
                                      p_start=pn_old, **load)
                extra_u = op.apply_coupling_tn(normal.pn)
                tang = _tangential(op, grid, normal.pn, problem, extra_u, tol, maxit,
                                   np.stack([px_old, py_old]))
                n_iter += normal.iterations
                t_iter += tang.iterations
                scale = float(np.abs(normal.pn).sum())
                dn = _relative_change(normal.pn, pn_old, scale)
                dt = _relative_change(np.stack([tang.px, tang.py]), np.stack([px_old, py_old]), scale)
                outer.append({"iteration": it, "pressure_change": dn, "traction_change": dt,
                              "normal_iterations": normal.iterations, "tangential_iterations": tang.iterations})
                if max(dn, dt) < tol:
                    outer_converged = True
                    break
    return _result(problem, grid, h, op, normal, tang, outer, outer_converged, n_iter, t_iter)


def _result(problem, grid, h, op, normal: NormalSolution, tang, outer, outer_converged, n_iter, t_iter) -> Result:
    dA = grid.area
    kin = problem.kinematics
    zeros = np.zeros(grid.shape)
    if tang is None:  # frictionless / no creepage and K = 0: no tangential traction, no slip
        px, py, sx, sy, ux, uy = zeros, zeros, zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy()
        status = np.where(normal.contact, ADHESION, EXTERIOR).astype(np.int8)
        xi, eta = kin.xi, kin.eta
        t_res, t_conv = 0.0, True
    else:
        px, py, sx, sy, ux, uy = tang.px, tang.py, tang.sx, tang.sy, tang.ux, tang.uy
        status = np.where(normal.contact, tang.status, EXTERIOR).astype(np.int8)
        xi, eta = tang.xi, tang.eta
        t_res, t_conv = float(tang.residual), bool(tang.converged)
    un = normal.un
    if op.coupled and tang is not None:  # the coupling A_nt p_t of the final tangential traction
        un = op.apply_normal(normal.pn) + op.apply_coupling_nt(px, py)
    field = TractionField(grid=grid, pn=normal.pn, px=px, py=py, status=status, sx=sx, sy=sy,
                          un=un, ux=ux, uy=uy)
    FN, FX, FY, MZ = field.totals()
    a, b = _patch_extent(grid, normal.contact)
    patch_fn = _patches(grid, normal.pn, normal.contact)
    energy = dA / 2000.0 * float((normal.pn * un + px * ux + py * uy).sum())   # J
    dissipation = dA * float((px * sx + py * sy).sum())                        # N mm per unit rolled / per shift
    extra: dict = {
        "elastic_energy": energy,
        "normal_iterations": n_iter,
        "tangential_iterations": t_iter,
        "normal_residual": normal.residual,
        "tangential_residual": t_res,
        "gap_residual": normal.gap_residual,
        "n_adhesion": field.n_adhesion,
        "n_potential": grid.size,
        "n_patches": len(patch_fn),
        "patch_FN": patch_fn,
        "FX_rel": FX / (problem.friction.mu_static * FN) if FN > 0 else None,
        "FY_rel": FY / (problem.friction.mu_static * FN) if FN > 0 else None,
        "FN_over_G": FN / problem.material.G,
        "grid": {"mx": grid.mx, "my": grid.my, "dx": grid.dx, "dy": grid.dy, "xl": grid.xl, "yl": grid.yl},
    }
    if kin.rolling == "shift":
        extra["frictional_work"] = dissipation / 1000.0                              # J
    else:
        extra["frictional_power"] = kin.velocity / 1000.0 * dissipation              # W
    if op.coupled:
        extra["outer_iterations"] = 1 + len(outer)
        extra["outer"] = outer
    warnings = []
    edge = _edge_warning(grid, normal.contact)
    if edge:
        warnings.append(edge)
    if not normal.converged:
        warnings.append(f"normal problem: not converged after {normal.iterations} iterations "
                        f"(relative change {normal.residual:.3g} > tol {problem.model.tol:g})")
    if not t_conv:
        warnings.append(f"tangential problem: not converged (residual {t_res:.3g})")
    if not outer_converged:
        warnings.append(f"normal-tangential coupling (K = {op.K:.4g}): not converged after "
                        f"{1 + len(outer)} alternations; raise [model] maxout")
    if warnings:
        extra["warnings"] = warnings
    if problem.hertz is not None:
        hz = problem.hertz
        extra["hertz"] = {"a": hz.a, "b": hz.b, "pmax": hz.pmax, "approach": hz.approach, "FN": hz.FN}
    return Result(theory="exact", FN=FN, FX=FX, FY=FY, MZ=MZ, a=a, b=b, pmax=normal.pmax,
                  approach=normal.approach, xi=xi, eta=eta, phi=kin.phi,
                  converged=bool(normal.converged and t_conv and outer_converged),
                  iterations=n_iter + t_iter, residual=max(normal.residual, t_res), field=field, extra=extra)
