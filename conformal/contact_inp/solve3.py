"""Module-3 cases onto the project's exact half-space solver (conformal.solvers.exact) and load
histories (conformal.solvers.history).

CONTACT's piecewise-constant half-space influence numbers (C = 2) are the project's planar
half-space numbers (conformal.influence.halfspace: same closed forms, collocated at element
centres); C = 9 reads CONTACT's influence file (conformal.influence.contact_file).  Rigid slip:
user guide eq. ``eq:rig_shift_roll`` (steady rolling, dq/6 spin term as the project's solver)
and the shift formula of section "Tangential quantities in case of a shift"; a spin centre
(SPINXO, SPINYO) shifts the creepages: xi - phi (y - yo) = (xi + phi yo) - phi y.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from conformal.contact_inp.blocks import eps_tolerance
from conformal.contact_inp.module3 import Module3Case, chi_direction, exrhs_grid, grid_of, unsupported
from conformal.grid import PlanarGrid
from conformal.materials import Material
from conformal.problem import ContactProblem
from conformal.specs import Friction, HistoryStep, Kinematics, ModelSpec
from conformal.theories.hertz import aspect_from_curvatures, hertz_from_curvatures, hertz_from_semiaxes

ROLLING = {1: "shift", 2: "transient", 3: "steady"}


def material_of(case: Module3Case) -> Material:
    nu1, nu2, g1, g2 = case.material
    return Material(G1=g1, nu1=nu1, G2=g2, nu2=nu2)


def _hertz(case: Module3Case, mat: Material):
    _, ip, mx, my, v = case.grid_spec
    fn, pen = case.hertz_load          # the load of the case that set the grid (D = 2; kept with D = 0)
    load = dict(normal_force=fn, approach=pen)
    if ip == -1:
        hz = hertz_from_curvatures(v[0], v[1], mat, **load)
    elif ip == -2:
        A, aob = v[0], v[1]
        # B such that the Hertz ellipse has a/b = AOB (aspect_from_curvatures is monotone in B/A)
        f = lambda lb: aspect_from_curvatures(A, A * np.exp(lb)) - aob   # noqa: E731
        B = A * float(np.exp(brentq(f, -20.0, 20.0, xtol=1e-14)))
        hz = hertz_from_curvatures(A, B, mat, **load)
    else:
        hz = hertz_from_semiaxes(v[0], v[1], mat, **load)
    grid = PlanarGrid.around_ellipse(hz.a, hz.b, scale=v[2], mx=mx, my=my)
    X, Y = grid.mesh()
    return hz, grid, hz.A * X**2 + hz.B * Y**2


def problem_of(case: Module3Case, base_dir: Path) -> ContactProblem:
    """The project's ContactProblem of one module-3 case (theory "exact")."""
    mat = material_of(case)
    T = case.digits["T"]
    fstat, fkin = case.friction
    if T == 0 and not mat.quasi_identical:
        raise unsupported(case.deck, case.line, "frictionless compression (T = 0) of dissimilar bodies "
                                                "(the project's solver couples them through friction)")
    xo, yo = case.spin_centre
    direction = chi_direction(case) if T >= 2 else 1
    kin = Kinematics(
        xi=(case.cksi or 0.0) + case.cphi * yo if T else 0.0,
        eta=(case.ceta or 0.0) - case.cphi * xo if T else 0.0,
        phi=case.cphi if T else 0.0,
        rolling="shift" if T in (0, 1) else "steady",
        fx_rel=case.fxrel if T else None, fy_rel=case.fyrel if T else None,
        velocity=case.rolling[2] if (case.rolling and T >= 2) else 1000.0, direction=direction)
    tol = eps_tolerance(case.eps)
    opts = {} if case.maxout is None else {"maxout": max(int(case.maxout), 1) if mat.quasi_identical else 30}
    model = ModelSpec(theory="exact", influence="halfspace", tol=tol, maxit=1000, options=opts)
    info: dict = {}
    hz = None
    if case.grid_spec[0] == "hertz":
        hz, grid, h = _hertz(case, mat)
    else:
        grid, h = grid_of(case)
    ex = exrhs_grid(case)
    if ex is not None and T:
        info["rigid_slip"] = ex
    if case.inflcf == 9:
        path = Path(case.cfname)
        path = path if path.is_absolute() else base_dir / path
        if not path.is_file():
            raise unsupported(case.deck, case.line, f"the influence file (C = 9) {path.name} is missing")
        info["influence_file"] = path
    if case.friction_rows:
        info["mu_scale"] = _row_friction(case, grid)
    M, B = case.digits["M"], case.digits["B"]
    if M in (2, 3) or B in (2, 3):
        return _fastsim_problem(case, mat, kin, hz, grid, h, info)
    if T >= 2:
        dq = case.rolling[1]
        if T == 3 and case.cphi != 0.0 and abs(dq - grid.dx) > 1e-6 * grid.dx:
            raise unsupported(case.deck, case.line, f"steady rolling with spin and DQ = {dq:g} != DX = {grid.dx:g} "
                                                    "(the project's steady solver uses dq = dx)")
    return ContactProblem(material=mat, friction=Friction(fstat, fkin), kinematics=kin, model=model,
                          normal_force=case.fn, approach=case.pen, hertz=hz, grid=grid, h=h,
                          label=f"case {case.number}", info=info)


def _row_friction(case: Module3Case, grid) -> np.ndarray:
    """V = 3 (user guide, "friction varying per grid row"): the factor mu_j / mu_0 on both friction
    coefficients of every element of grid row j (the problem's friction is that of row 0), for
    the exact solver's per-element bound (conformal.solvers.exact, ``mu_scale``).  Rows whose
    FKIN / FSTAT differ from row 0's, and prescribed forces (relative to one mu), are refused."""
    rows = np.asarray(case.friction_rows, float)
    if rows.shape[0] != grid.my or np.any(rows <= 0.0):
        raise unsupported(case.deck, case.line, f"V = 3 with {rows.shape[0]} friction rows for {grid.my} grid rows "
                                                "or a friction coefficient <= 0")
    ratio = rows[:, 1] / rows[:, 0]
    if np.any(np.abs(ratio - ratio[0]) > 1e-12):
        raise unsupported(case.deck, case.line, "V = 3 with FKIN / FSTAT varying between the grid rows")
    if case.fxrel is not None or case.fyrel is not None:
        raise unsupported(case.deck, case.line, "V = 3 with prescribed tangential forces (F = 1, 2)")
    return np.broadcast_to(rows[:, 0] / rows[0, 0], grid.shape).copy()


def _fastsim_problem(case: Module3Case, mat: Material, kin: Kinematics, hz, grid, h, info) -> ContactProblem:
    """CONTACT's simplified theory (M = 2, 3) with a Hertzian traction bound (B = 2, 3): the project's
    FASTSIM on the same grid with CONTACT's flexibilities (conformal.contact_inp.fastsim3)."""
    from conformal.contact_inp.fastsim3 import contact_flexibilities

    d = case.digits
    M, B, T, F = d["M"], d["B"], d["T"], d["F"]
    if M not in (2, 3) or B not in (2, 3):
        raise unsupported(case.deck, case.line, f"control digits M = {M}, B = {B} (FASTSIM needs M = 2, 3 with "
                                                "an elliptic or parabolic traction bound B = 2, 3)")
    if hz is None or case.grid_spec[1] not in (-1, -2, -3):
        raise unsupported(case.deck, case.line, "FASTSIM on a non-Hertzian geometry")
    if T != 3 or F != 0 or case.spin_centre != (0.0, 0.0) or info:
        raise unsupported(case.deck, case.line, "FASTSIM other than steady rolling (T = 3) with creepages "
                                                "(F = 0)")
    if case.fn is None:
        raise unsupported(case.deck, case.line, "FASTSIM with a prescribed approach (N = 0)")
    par = case.mater_params
    k0, alpha = (par[1], par[2]) if M == 2 else (par[0], par[1])
    if alpha != 1.0 or not k0 > 0:
        raise unsupported(case.deck, case.line, f"modified FASTSIM with ALFAMF = {alpha:g} (only 1) or K0_MF = {k0:g}")
    if M == 2:
        L = (par[0],) * 3
    else:
        L = contact_flexibilities(hz.a, hz.b, mat.G, mat.nu, FN=case.fn, mu=case.friction[0],
                                  xi=kin.xi, eta=kin.eta, phi=kin.phi)
    L = [v / k0 for v in L]
    model = ModelSpec(theory="fastsim", bound="elliptic" if B == 2 else "parabolic",
                      options={"discretisation": "contact", "flexibilities": L})
    fstat, fkin = case.friction
    if fstat != fkin:
        raise unsupported(case.deck, case.line, "FASTSIM with FSTAT != FKIN")
    return ContactProblem(material=mat, friction=Friction(fstat, fkin), kinematics=kin, model=model,
                          normal_force=case.fn, hertz=hz, grid=grid, h=h, label=f"case {case.number}")


def history_step(case: Module3Case) -> HistoryStep:
    """One step of a load history (T = 1 shift, T = 2 transient rolling over DQ, T = 3 steady)."""
    T = case.digits["T"]
    xo, yo = case.spin_centre
    return HistoryStep(normal_force=case.fn, approach=case.pen,
                       xi=(case.cksi or 0.0) + case.cphi * yo, eta=(case.ceta or 0.0) - case.cphi * xo,
                       phi=case.cphi, rolling=ROLLING[T],
                       distance=case.rolling[1] if T == 2 else None,
                       fx_rel=case.fxrel, fy_rel=case.fyrel)


def same_geometry(a: ContactProblem, b: ContactProblem) -> bool:
    """The same grid, materials and friction (the undeformed distance may move: history ``undeformed``)."""
    return (a.grid == b.grid and a.material == b.material and a.friction == b.friction
            and not a.info and not b.info)


def summary(case: Module3Case, r) -> dict:
    """The JSON object of one solved case (CONTACT's sign conventions: forces on body 1)."""
    f = r.field
    out = {"case": case.number, "module": 3, "FN": r.FN, "FX": r.FX, "FY": r.FY, "MZ": r.MZ,
           "pmax": r.pmax, "approach": r.approach,
           "n_contact": f.n_contact, "n_adhesion": f.n_adhesion, "n_slip": f.n_slip}
    T, F = case.digits["T"], case.digits["F"]
    scale = case.rolling[1] if T == 2 else 1.0    # a transient step's shift / dq: the creepage
    if T and F >= 1:
        out["xi"] = r.xi / scale
    if T and F == 2:
        out["eta"] = r.eta / scale
    warnings = list(case.skipped) + list(r.extra.get("warnings", []))
    if not r.converged:
        warnings.append("not converged")
    out["converged"] = bool(r.converged)
    out["warnings"] = warnings
    return out
