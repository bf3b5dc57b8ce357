"""Load histories and transient rolling: a sequence of steps with memory of the previous tractions
(seed Eqs. 39-40; Kalker 1990 ch. 5, CONTACT's T = 1 and T = 2 over several cases).

Between two steps the bodies shift rigidly by W_k (mm) and the material moves by dq along x
(dq = 0 for a shift).  The slip distance of the particle that is now at element I is (seed Eq. 40)

    S_I = W_I + u_k(x_I) - u_{k-1}(x_I + dq),        u = A_tt p_t + A_tn p_n,

the rigid shift plus the change of the elastic displacement difference of the same particle: in a
shift the particle stays (u_{k-1} at x_I), in rolling (+x) it was dq further downstream one step
earlier.  Coulomb's law holds for S as in a shift from zero tractions, so each step is the
shift problem of :func:`conformal.solvers.tangential.solve_tangential` with the memory term

    extra_u = A_tn p_n,k - u_{k-1}(x + dq)       and      p_start = p_{k-1},

and rigid shift W = (xi - phi y, eta + phi x) per step (``rolling = "shift"``), or the creepages
times the rolled distance, W = dq (xi - phi y, eta + phi (x + dx/6)) (``rolling = "transient"``,
dq a whole number of elements so that x + dq is a grid point; the spin's dx/6 as in the steady
solver, so that a long transient roll converges to the steady-rolling solution of the same grid).
A ``rolling = "steady"`` step solves steady rolling (memory only as the start) and sets the state
that the next steps continue from.  The normal problem of each step is solved first (from the
previous pressure); dissimilar bodies (K != 0) alternate normal and tangential problems within the
step (Panagiotopoulos, :func:`conformal.solvers.exact.alternate`).

A step may prescribe FX/(mu FN) (``fx_rel``) and/or FY/(mu FN) (``fy_rel``) instead of the shift
(CONTACT's F = 1, 2): the step's rigid shift increment is then the unknown.

Line contact (B = 0, conformal.solvers.line) works alike on the half-plane; there the tangential
displacement is defined only up to a constant times the force (2-D elasticity), so transient steps
that change the force carry a uniform slip that depends on the datum, which vanishes as the force
settles (steady state, Carter) and in shifts at constant force.

Checks (tests/validation/test_history.py): Cattaneo's growing tangential force (stick radius
c/a = (1 - Q/(mu P))^(1/3) and the shift), Mindlin-Deresiewicz unloading (the reverse-slip
annulus), the onset of rolling from the Cattaneo state, which converges to the steady solution
of the same grid, in 2-D from Cattaneo (c/a = (1 - Q/(mu P))^(1/2)) to Carter, and Spence's
growing normal load on dissimilar bodies (35 stages: the stick ratio c/a stays constant).

>>> import numpy as np
>>> from conformal.problem import problems_from_scene
>>> from conformal.scene import scene_from_dict
>>> p = problems_from_scene(scene_from_dict({"geometry": {"kind": "hertz", "a": 1.0, "b": 1.0},
...     "load": {"normal_force": 1000.0}, "grid": {"n": 20}, "model": {"theory": "exact"}}))[0]
>>> h = solve_history(p, [HistoryStep(fx_rel=-0.5), HistoryStep(fx_rel=-0.875)])
>>> [round(s.FX / (0.3 * s.FN), 4) for s in h.steps]
[-0.5, -0.875]
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from conformal.errors import InputError
from conformal.influence.operator import build_operator
from conformal.problem import ContactProblem
from conformal.solvers import exact, line
from conformal.solvers.normal import solve_normal
from conformal.solvers.tangential import solve_tangential

from conformal.specs import HISTORY_ROLLING as ROLLING, HistoryStep  # noqa: E402,F401  (one definition)


@dataclass(frozen=True, eq=False)
class HistoryResult:
    """The solved history: one :class:`~conformal.result.Result` per applied step (repeats
    expanded), in order; ``shift`` the accumulated rigid shift (x, y) of the shift and transient
    steps (mm), per step."""

    steps: tuple
    shift: tuple

    def to_dict(self) -> dict:
        """Per-step summaries (the JSON's ``history`` list)."""
        out = []
        for k, (r, sh) in enumerate(zip(self.steps, self.shift)):
            d = {key: v for key, v in r.to_dict().items() if not isinstance(v, (dict, list))}
            d.update(step=k + 1, rolling=r.extra.get("history_rolling"), shift_x=sh[0], shift_y=sh[1],
                     n_reversed=r.extra.get("n_reversed"))
            out.append(d)
        return {"history": out}


def _shifted(u: np.ndarray, ncol: int) -> np.ndarray:
    """u(x + ncol dx) on the grid for u (2, mx + ncol, my) on the grid extended downstream."""
    return u[:, ncol:]


def leading_edge_factor(contact: np.ndarray, ncol: int) -> np.ndarray:
    """The fraction of a transient step of ``ncol`` elements (dq = ncol dx, rolling in +x) that each
    element of ``contact`` (mx, my) spent inside the contact area: the leading edge of a run of
    contact elements along x lies one element beyond its last element, and an element at distance
    d from it entered the contact d / dq of the step ago, f = min(1, d / dq) (CONTACT's
    leading-edge correction of the rigid slip, its ``sxbnd`` with a fixed edge position; 1 for
    dq = dx).  Exterior elements get 0."""
    c = np.asarray(contact, bool)
    mx = c.shape[0]
    f = np.zeros(c.shape)
    d = np.zeros(c.shape[1])                  # elements from the next leading edge, scanning from +x
    for ix in range(mx - 1, -1, -1):
        d = np.where(c[ix], d + 1.0, 0.0)
        # the last two columns of the grid: no room to place an edge, the whole step (as CONTACT)
        f[ix] = 1.0 if ix >= mx - 2 else np.minimum(1.0, d / ncol)
    return np.where(c, f, 0.0)


def solve_history(problem: ContactProblem, steps, *, maxout: int | None = None,
                  undeformed=None) -> HistoryResult:
    """Solve the steps one after the other, each with the memory of the previous tractions.

    Parameters
    ----------
    problem : a planar ContactProblem (theory "exact": grid, h, material, friction; line contact,
        ``info["line_contact"]``, with the half-plane numbers of conformal.solvers.line); its load
        is the load of the first step unless that step gives one; its kinematics are not used.
    steps : sequence of :class:`HistoryStep` (at least one).
    maxout : most normal/tangential alternations per step for dissimilar bodies ([model] maxout).
    undeformed : optional, one undeformed distance per applied step (grid shape, mm) instead of
        the problem's h: the bodies' profiles moving over the grid between the steps (CONTACT's
        Z = 2 inside a sequence, e.g. a shift that moves the indenter by one element).

    Returns
    -------
    HistoryResult
    """
    steps = list(steps)
    if not steps:
        raise InputError("[[history]]: at least one step")
    if not all(isinstance(s, HistoryStep) for s in steps):
        raise InputError("[[history]]: steps must be HistoryStep")
    grid, h = problem.require_grid("a load history")
    if problem.model.influence != "halfspace":
        raise InputError("[model] influence: load histories use half-space influence numbers")
    maxout = exact.maxout_option(problem.model) if maxout is None else int(maxout)
    tol, maxit = problem.model.tol, problem.model.maxit
    mat, fr = problem.material, problem.friction
    mx, my = grid.shape
    # the largest downstream extension a transient step needs
    ncols = {}
    for s in steps:
        if s.rolling == "transient":
            dq = grid.dx if s.distance is None else s.distance
            n = dq / grid.dx
            if abs(n - round(n)) > 1e-6 or round(n) < 1:
                raise InputError(f"[[history]] distance: a transient step rolls a whole number of elements "
                                 f"(dx = {grid.dx:g} mm), got {dq:g} mm")
            ncols[s] = int(round(n))
    ext = max(ncols.values(), default=0)
    line_contact = bool(problem.info.get("line_contact"))
    if line_contact:   # B = 0: the half-plane operator (conformal.solvers.line), one datum for both grids
        line.check_line_problem(problem)
        if any(s.approach is not None for s in steps):
            raise InputError("[[history]] approach: line contact (B = 0) needs normal_force per step")
    op, _ = build_operator(grid, mat, line=line_contact)
    op_ext = op.extended(ext) if ext else op
    load = dict(normal_force=problem.normal_force, approach=problem.approach)
    pn_prev = None
    p_prev = np.zeros((2, mx, my))
    total = np.zeros(2)
    results, shifts = [], []
    X, Y = grid.mesh()

    def u_total(op_, px, py, pn):
        """(2, m, my) tangential displacement difference of tractions padded to op_'s grid."""
        pad = op_.mx - mx
        z = np.zeros((pad, my))
        PX, PY, PN = (np.concatenate([a, z]) for a in (px, py, pn))
        ux, uy = op_.apply_tangential(PX, PY)
        u = np.stack([ux, uy])
        if op_.coupled:
            u = u + op_.apply_coupling_tn(PN)
        return u

    applied = [s for s in steps for _ in range(s.repeat)]
    if undeformed is not None:
        undeformed = [np.asarray(u, dtype=float) for u in undeformed]
        if len(undeformed) != len(applied) or any(u.shape != grid.shape for u in undeformed):
            raise InputError(f"[[history]]: need one undeformed distance of shape {grid.shape} per applied step "
                             f"({len(applied)})")
    h0 = h
    for k_step, step in enumerate(applied):
        h = h0 if undeformed is None else undeformed[k_step]
        if step.normal_force is not None or step.approach is not None:
            load = dict(normal_force=step.normal_force, approach=step.approach)
        ncol = ncols.get(step, 0)
        if step.rolling == "steady":
            memory = None
        elif pn_prev is None:
            memory = np.zeros((2, mx, my))
        else:
            memory = _shifted(u_total(op_ext if ncol else op, p_prev[0], p_prev[1], pn_prev), ncol) if ncol \
                else u_total(op, p_prev[0], p_prev[1], pn_prev)
        if step.rolling == "transient":
            dq = ncol * grid.dx
            xi, eta, phi = step.xi * dq, step.eta * dq, step.phi * dq
            rigid = np.stack([np.zeros((mx, my)), np.full((mx, my), phi * grid.dx / 6.0)])
            kind = "shift"
        else:
            xi, eta, phi = step.xi, step.eta, step.phi
            rigid = None
            kind = "shift" if step.rolling == "shift" else "steady"

        def normal_stage(extra_un, p_start, tang, _load=load, _h=h):
            start = p_start if p_start is not None else pn_prev
            return solve_normal(op, grid, _h, tol=tol, maxit=maxit, extra_un=extra_un, p_start=start, material=mat,
                                **_load)

        def tangential_stage(pn, extra_u, p_start, _mem=memory, _rigid=rigid, _xi=xi, _eta=eta, _phi=phi,
                             _kind=kind, _step=step, _ncol=ncol if step.rolling == "transient" else 0):
            eu = extra_u
            if _mem is not None:
                eu = -_mem if eu is None else eu - _mem
            start = p_start if p_start is not None else p_prev
            weight = leading_edge_factor(pn > 0, _ncol) if _ncol > 1 else None
            return solve_tangential(op, grid, pn, xi=_xi, eta=_eta, phi=_phi, mu_static=fr.mu_static,
                                    mu_kinetic=fr.mu_kinetic, rolling=_kind, fx_rel=_step.fx_rel,
                                    fy_rel=_step.fy_rel, extra_u=eu, tol=tol, maxit=maxit, p_start=start,
                                    rigid_slip=_rigid, creep_weight=weight)

        stages = exact.alternate(op, normal_stage, tangential_stage, tangential=True, tol=tol, maxout=maxout)
        tang = stages.tang
        kin = replace(problem.kinematics, xi=xi, eta=eta, phi=phi, rolling="shift" if kind == "shift" else "steady",
                      fx_rel=step.fx_rel, fy_rel=step.fy_rel)
        res = exact.planar_result(replace(problem, kinematics=kin, normal_force=load["normal_force"],
                                    approach=load["approach"]), grid, h, op, stages)
        # the tangential displacement of this step's tractions (the solver's ux includes the memory)
        u_now = u_total(op, tang.px, tang.py, stages.normal.pn)
        field = replace(res.field, ux=u_now[0], uy=u_now[1])
        if step.rolling != "steady":
            total = total + np.array([tang.xi, tang.eta])
        # slip against the previous traction direction: elements whose slip reversed
        dot = tang.sx * p_prev[0] + tang.sy * p_prev[1]
        n_rev = int(np.count_nonzero(dot > 0))  # slip along p_prev: traction pushed back (p opposes slip)
        extra = dict(res.extra, history_rolling=step.rolling, n_reversed=n_rev,
                     shift_total=[float(total[0]), float(total[1])])
        if line_contact:
            extra.update(line_contact=True, reference_length=op.ref_length)
            extra.pop("hertz", None)
        res = replace(res, field=field, extra=extra, theory="exact", b=float("nan") if line_contact else res.b)
        results.append(res)
        shifts.append((float(total[0]), float(total[1])))
        p_prev = np.stack([tang.px, tang.py])
        pn_prev = stages.normal.pn
    return HistoryResult(steps=tuple(results), shift=tuple(shifts))
