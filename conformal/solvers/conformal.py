"""Conformal contact (Li 2002): the normal and tangential problems on the curved surface.

The potential contact area is a strip on the rail surface (:class:`~conformal.grid.CurvedGrid`):
mx elements along the rolling direction x times ms elements along the arc length s of the rail
profile, each with its own frame (x, s, n) and contact angle delta_I.  The influence numbers
(:class:`~conformal.influence.curved.CurvedInfluence`) come from the half-space formulas per
curved grid or from finite elements of the real wheel and rail (conformal.influence.fe); both are
invariant along x, so products use FFTs along x and dense blocks along s.

Normal stage (seed Eqs. 45-46).  The bodies approach rigidly by ``approach`` along a load
direction d (vertical for a wheel on its rail); element I sees it projected onto its normal,
w_I = d . n_I = cos(delta_I - delta_d).  Find p_n >= 0 with the deformed gap

    e_I = h_I - approach w_I + sum_J A_nn(I, J) p_n(J) + sum_J A_nt(I, J) p_t(J) >= 0,   p_n e = 0,

and the force along d prescribed (seed Eq. 46, with delta measured from d):

    sum_I p_n(I) cos(delta_I) dS_I = N - sum_I p_s(I) sin(delta_I) dS_I.

(The seed prints Eq. 46 with F_Iy for the lateral traction; on the curved surface that is p_s, the
traction along the profile, whose vertical component is p_s sin delta.)  The tangential share is
carried into the next normal stage as proportional to the normal force (exact in full slip); a
plain update by the last share diverges where mu tan(delta) > 1, and where the share outweighs the
pressure (the wheel climbs the flange, Nadal) the solver stops with ConvergenceError.

Tangential stage (seed Eqs. 47-49).  Steady rolling or transient shift with Coulomb friction; the
rigid slip varies over the patch: every column along s has its own creepages xi(s), eta(s),
phi(s) (the spin follows the contact angle, phi(s) = (omega_r - omega_w) . n(s) / V), and
within a column the lateral slip grows with x by the local spin, w_s = eta(s) + phi(s) x.
The tangential displacements include the coupling A_tn p_n.

Outer iteration.  On a curved surface the normal and tangential problems are coupled even for
identical materials (the frames turn with delta; FE bodies are not half-spaces): the two stages
alternate (Panagiotopoulos, CONTACT's MAXOUT loop) until the pressure and the traction both stop
changing, each stage starting from the previous solution.

Planar limit.  A flat strip (delta constant, ``load_angle`` = delta) with half-space numbers is
the planar problem: :func:`solve` of a planar ContactProblem (theory "conformal") runs this code on
the flat strip.  The stages are the planar solvers themselves (conformal.solvers.normal,
.tangential, and the alternation of conformal.solvers.exact), so it reproduces the exact theory:
the same contact and slip areas; forces and tractions equal up to the solvers' tolerance (the
operators agree to 2e-15; measured 1e-8 to 2e-7 in the forces at tol 1e-6,
tests/validation/test_conformal.py).

Wheel-rail scenes (``[model] theory = "conformal"``): one curved strip on the rail covers every
contact patch of the wheel (built by :mod:`conformal.cases.conformal`); ``[model]`` keys: influence
("halfspace" | "halfspace_planar" | "fe", FE keys fe_* of conformal.influence.fe), maxout, max_mx / max_ms (strip
size limits), creepage ("surface": from the wheelset motion at every point, or "reference": the
reference point's creepages spread as a rigid motion, the planar assumption).

Frames.  A curved grid is set up in the rail-profile frame of the pair's *side* (mirrored for a
left wheel, see conformal.geometry).  Totals are reported in the real frame: FN = sum p_n dS,
FX = sum p_x dS, FY = sum p_s dS (the developed, contact-frame sums), MZ = sum (x p_s - (s - s_ref)
p_x) dS (the developed spin moment), and in ``extra`` the track-frame forces on the rail
FX_track, FY_track, FZ_track (seed Eqs. 46, 48, 49) and the 3-D spin moment about the reference
normal, ``MZ_3d``.  Tractions act on the rail (body 1), as everywhere in this package.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any, Mapping

import numpy as np

from conformal.errors import ConvergenceError, InputError
from conformal.grid import CurvedGrid, PlanarGrid, connected_parts
from conformal.influence.operator import InfluenceOperator, build_operator
from conformal.materials import Material
from conformal.problem import ContactProblem
from conformal.result import Result, TractionField
from conformal.specs import Friction, Kinematics, ModelSpec
from conformal.solvers.exact import (Stages, patch_extent, alternate, convergence_warnings, maxout_option,
                                     solution_extra, tractions)
from conformal.solvers.normal import solve_normal

#: at most this many elements along x and along s of a strip ([model] max_mx, max_ms override):
#: a strip over patches far apart (tread and flange) gets coarser elements instead
MAX_ELEMENTS = 200
#: contact-angle spread over the contact area from which a planar (half-space) theory's result
#: warns that its simplification is questionable (degrees; conformal.cases.wheelrail; this theory
#: is the one that treats such patches and reports the spread as contact_angle_spread_deg)
DELTA_SPREAD_WARN = 10.0


# ----------------------------------------------------------------------------- the problem
@dataclass(frozen=True, eq=False)
class CurvedProblem:
    """One conformal contact problem on a curved grid (see the module docstring).

    h : (mx, ms) undeformed distance along the local normals at the reference position of the
        bodies (mm); may be < 0 where they overlap there.  The deformed gap is
        h - approach w + u_n with w = cos(delta - load_angle).
    normal_force, approach : exactly one: the force along the load direction (N), or the rigid
        approach along it from the reference position (mm).
    load_angle : the load direction delta_d, as a contact angle (rad; 0 = vertical, side frame).
    xi_s, eta_s, phi_s : (ms,) creepages per column in the grid's frame (steady rolling: -, -,
        rad/mm; shift: mm, mm, rad).
    kinematics : rolling ("steady" | "shift"), velocity, fx_rel, fy_rel of the scene.
    overlap_approach : report ``Result.approach`` as the largest rigid overlap along the local
        normals, max(approach w - h) (wheel-rail grids, where h is the signed distance at a
        reference height), instead of the approach itself (planar problems: h = 0 is where the
        undeformed surfaces first touch, as in the exact theory).
    rail_points, wheel_points : the whole rail and wheel profiles (rail-profile and wheel-profile
        coordinates), for the FE bodies (the grid's own curves reach only a few mm beyond it).
    """

    grid: CurvedGrid
    h: np.ndarray
    material: Material
    friction: Friction
    kinematics: Kinematics
    model: ModelSpec
    xi_s: np.ndarray
    eta_s: np.ndarray
    phi_s: np.ndarray
    normal_force: float | None = None
    approach: float | None = None
    load_angle: float = 0.0
    overlap_approach: bool = False
    label: str = "contact"
    info: Mapping[str, Any] = field(default_factory=dict)
    rail_points: np.ndarray | None = None
    wheel_points: np.ndarray | None = None

    def __post_init__(self):
        if (self.normal_force is None) == (self.approach is None):
            raise InputError("[load] normal_force: give exactly one of normal_force (N) or approach (mm)")
        if np.shape(self.h) != self.grid.shape:
            raise InputError(f"[geometry] undeformed distance: shape {np.shape(self.h)} does not match the "
                             f"curved grid {self.grid.shape}")
        for name in ("xi_s", "eta_s", "phi_s"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (self.grid.ms,) or not np.all(np.isfinite(v)):
                raise InputError(f"[kinematics] {name[:-2]}: need {self.grid.ms} finite creepages along s, "
                                 f"got shape {v.shape}")

    @property
    def mirror(self) -> float:
        """+1 for a right wheel (or a planar problem), -1 for a left wheel (frames mirrored)."""
        return 1.0 if self.grid.side == "right" else -1.0


# ----------------------------------------------------------------------------- grids
def flat_strip(grid: PlanarGrid, margin: float = 5.0) -> CurvedGrid:
    """A planar grid as a flat curved strip: s = y (up to a constant), delta = 0, normals along +z
    (into body 1); the bodies are half-spaces, drawn as flat blocks.  ``s_ref`` is the s of y = 0.

    >>> strip = flat_strip(PlanarGrid.centred(4, 3, 0.5, 1.0))
    >>> strip.shape, (strip.s - strip.s_ref).tolist(), strip.delta.tolist()
    ((4, 3), [-1.0, 0.0, 1.0], [0.0, 0.0, 0.0])
    """
    y_edges = grid.yl + np.arange(grid.my + 1) * grid.dy
    s0 = margin - grid.yl                   # s of y = 0
    y_curve = np.linspace(y_edges[0] - margin, y_edges[-1] + margin, 2 * grid.my + 3)
    x_half = 0.5 * grid.mx * grid.dx + margin
    radius = 1e6 * max(x_half, 1.0)         # a flat body: the 'wheel' is a half-space
    return CurvedGrid(mx=grid.mx, dx=grid.dx, xl=grid.xl, s_edges=y_edges + s0, y=grid.y.copy(),
                      z=np.zeros(grid.my), normal=np.tile([0.0, 1.0], (grid.my, 1)), delta=np.zeros(grid.my),
                      s_ref=s0, cant=0.0, rail_origin=(0.0, 0.0),
                      rail_curve=np.c_[y_curve, np.zeros_like(y_curve)], rail_curve_s=y_curve + s0,
                      wheel_profile=np.c_[y_curve, np.zeros_like(y_curve)],
                      wheel_centre=np.array([0.0, 0.0, -radius]), wheel_axle=np.array([0.0, 1.0, 0.0]),
                      wheel_down=np.array([0.0, 0.0, 1.0]), wheel_radius=radius, side="right")


def developed_grid(grid: CurvedGrid) -> PlanarGrid:
    """The curved grid unrolled onto the (x, s - s_ref) plane (for maps and totals).  Curved grids
    have equal widths along s (conformal.geometry.patches); others are refused."""
    ds = grid.ds
    if not np.allclose(ds, ds[0], rtol=1e-9, atol=0.0):
        raise InputError("[grid]: the curved grid's elements along s must have equal widths")
    return PlanarGrid(grid.mx, grid.ms, grid.dx, float(ds[0]), grid.xl, float(grid.s_edges[0] - grid.s_ref))


def reference_point(grid: CurvedGrid) -> tuple[np.ndarray, np.ndarray]:
    """(y, z) and the unit normal (n_y, n_z) at s = s_ref, rail-profile frame (interpolated)."""
    s = grid.s
    yz = np.array([np.interp(grid.s_ref, s, grid.y), np.interp(grid.s_ref, s, grid.z)])
    n = np.array([np.interp(grid.s_ref, s, grid.normal[:, 0]), np.interp(grid.s_ref, s, grid.normal[:, 1])])
    return yz, n / np.linalg.norm(n)


def approach_weights(grid: CurvedGrid, load_angle: float) -> np.ndarray:
    """w_I = d . n_I = cos(delta_I - delta_d), shape (mx, ms) (seed Eqs. 45-46)."""
    w = np.cos(grid.delta - load_angle)
    if np.any(w <= 0.0):
        bad = float(np.degrees(grid.delta[np.argmin(w)]))
        raise InputError(f"[geometry]: the curved grid reaches a contact angle of {bad:.1f} degrees, where "
                         f"the load direction ({math.degrees(load_angle):.1f} degrees) no longer presses the "
                         "surfaces together; shorten the grid along s")
    return np.broadcast_to(w, grid.shape)


# ----------------------------------------------------------------------------- kinematics
def column_creepages(grid: CurvedGrid, xi: float, eta: float, phi: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Creepages per column for a rigid relative motion given by the creepages (xi, eta, phi) at
    the reference point, the rotation being about the reference normal (the planar assumption):
    the velocity at an element is v_ref + Omega x dr with Omega = phi V n_ref, so

        xi(s) = xi + phi (n_ref x dr)_x,   eta(s) = eta t_ref . t(s),   phi(s) = phi n_ref . n(s).

    On a flat strip: xi(y) = xi - phi y, the planar rigid slip.  (With ``[kinematics] speed`` the
    wheelset's own rotation gives the creepages instead, conformal.cases.wheelrail.)"""
    (y0, z0), n0 = reference_point(grid)
    dy, dz = grid.y - y0, grid.z - z0
    cos_d = grid.normal @ n0
    return xi + phi * (n0[0] * dz - n0[1] * dy), eta * cos_d, phi * cos_d


# ----------------------------------------------------------------------------- influence numbers
def influence_operator(grid: CurvedGrid, material: Material, model: ModelSpec, *, planar: bool = False,
                       cache=None, rail_points=None, wheel_points=None) -> tuple[InfluenceOperator, dict]:
    """The curved grid's influence operator for ``model.influence`` (the factory
    :func:`conformal.influence.operator.build_operator`; ``planar``: a planar scene, no bodies'
    geometry for FE numbers; ``rail_points``, ``wheel_points``: the whole profiles the FE bodies
    are cut from).  Returns (operator, info with the timings and the FE statistics)."""
    return build_operator(grid, material, influence=model.influence, options=model.options, bodies=not planar,
                          cache=cache, rail_points=rail_points, wheel_points=wheel_points)


# ----------------------------------------------------------------------------- totals
@dataclass(frozen=True, eq=False)
class CurvedTractionField(TractionField):
    """A :class:`TractionField` on the developed curved grid (``grid``: x, s - s_ref; real frame,
    as every field in this package), plus the curved grid itself (``curved``, in the side frame:
    :meth:`side_frame` turns an array back for a left wheel) and per-element values of the curved
    problem: ``delta`` (the contact angle, rad), ``h`` (mm, at the reference position)."""

    curved: CurvedGrid | None = None
    delta: np.ndarray | None = None
    h: np.ndarray | None = None

    @property
    def mirror(self) -> float:
        return 1.0 if self.curved is None or self.curved.side == "right" else -1.0

    def side_frame(self, name: str) -> np.ndarray:
        """An array of the field in the curved grid's (side) frame: s axis and lateral sign mirrored
        back for a left wheel."""
        v = getattr(self, name)
        if self.mirror > 0:
            return v
        v = v[:, ::-1]
        return -v if name in ("py", "sy", "uy", "delta") else v


def curved_totals(grid: CurvedGrid, pn: np.ndarray, px: np.ndarray, ps: np.ndarray) -> dict:
    """Totals of a curved traction field in the side frame (seed Eqs. 46, 48, 49):

    FN = sum pn dS, FX = sum px dS, FS = sum ps dS (developed sums), the side-frame forces on the
    rail FY_side = sum (ps cos delta - pn sin delta) dS, FZ_side = sum (pn cos delta + ps sin delta)
    dS, the developed spin moment MZ = sum (x ps - (s - s_ref) px) dS and the 3-D moment about the
    reference normal through the reference point, MZ_3d."""
    dS = np.broadcast_to(grid.area, grid.shape)
    c, s = np.cos(grid.delta), np.sin(grid.delta)
    X, S = grid.mesh()
    out = {"FN": float((pn * dS).sum()), "FX": float((px * dS).sum()), "FS": float((ps * dS).sum()),
           "FY_side": float(((ps * c - pn * s) * dS).sum()), "FZ_side": float(((pn * c + ps * s) * dS).sum()),
           "MZ": float(((X * ps - (S - grid.s_ref) * px) * dS).sum())}
    # 3-D: element centres r = (x, y, z), traction px e_x + ps t_s + pn n (rail-profile frame)
    (y0, z0), n0 = reference_point(grid)
    ny, nz = grid.normal[:, 0], grid.normal[:, 1]
    ty, tz = nz, -ny                                  # t_s = n x e_x = (0, n_z, -n_y)
    Fy = (ps * ty + pn * ny) * dS
    Fz = (ps * tz + pn * nz) * dS
    Fx = px * dS
    ry, rz = (grid.y - y0)[None, :], (grid.z - z0)[None, :]
    my = rz * Fx - X * Fz
    mz = X * Fy - ry * Fx
    out["MZ_3d"] = float((my * n0[0] + mz * n0[1]).sum())   # (r x F) . n_ref
    return out


def _regions(grid: CurvedGrid, pn, px, ps, contact) -> list[dict]:
    """Connected contact regions (e.g. a tread and a flange patch on one strip), largest first:
    totals, contact-angle range and position along s of each."""
    labels, n = connected_parts(contact)
    out = []
    for k in range(1, n + 1):
        m = labels == k
        t = curved_totals(grid, np.where(m, pn, 0.0), np.where(m, px, 0.0), np.where(m, ps, 0.0))
        cols = np.flatnonzero(m.any(axis=0))
        d = grid.delta[cols]
        dS = np.broadcast_to(grid.area, grid.shape)
        out.append({"FN": t["FN"], "FX": t["FX"], "FS": t["FS"], "FY_side": t["FY_side"], "FZ_side": t["FZ_side"],
                    "area": float(dS[m].sum()), "pmax": float(pn[m].max()),
                    "s_min": float(grid.s_edges[cols[0]]), "s_max": float(grid.s_edges[cols[-1] + 1]),
                    "delta_min": float(d.min()), "delta_max": float(d.max()),
                    "contact_angle": float(np.sum(pn[m] * np.broadcast_to(grid.delta, grid.shape)[m])
                                           / max(pn[m].sum(), 1e-300))})
    out.sort(key=lambda r: -r["FN"])
    return out


def _region_real(r: dict, m: float) -> dict:
    """A region of :func:`_regions` in the real frame (left wheel: lateral signs mirrored)."""
    d = sorted((m * r["delta_min"], m * r["delta_max"]))
    return {"FN": r["FN"], "FX": r["FX"], "FS": m * r["FS"], "FY_track": m * r["FY_side"], "FZ_track": r["FZ_side"],
            "area": r["area"], "pmax": r["pmax"], "s_min": r["s_min"], "s_max": r["s_max"],
            "contact_angle": m * r["contact_angle"], "contact_angle_min": d[0], "contact_angle_max": d[1]}


# ----------------------------------------------------------------------------- the two stages
def _needs_tangential(problem: CurvedProblem, op) -> bool:
    k = problem.kinematics
    return (op.coupled or k.fx_rel is not None or k.fy_rel is not None
            or any(np.any(v != 0.0) for v in (problem.xi_s, problem.eta_s, problem.phi_s)))


def solve_stages(problem: CurvedProblem, op) -> Stages:
    """The normal and tangential stages on the curved grid, alternated until both converge
    (conformal.solvers.exact.alternate, shared with the planar theory).

    Raises ConvergenceError when the tangential tractions carry the whole load along the load
    direction (seed Eq. 46 leaves no normal force: the wheel climbs the flange)."""
    from conformal.solvers.tangential import column_rigid_slip, solve_tangential

    grid, h = problem.grid, np.asarray(problem.h, dtype=float)
    model, k, f = problem.model, problem.kinematics, problem.friction
    maxout = maxout_option(model)
    tol, maxit = model.tol, model.maxit
    w = approach_weights(grid, problem.load_angle)
    sin_w = np.broadcast_to(np.sin(grid.delta - problem.load_angle), grid.shape)
    dS = np.broadcast_to(grid.area, grid.shape)
    slip = column_rigid_slip(grid, problem.xi_s, problem.eta_s, problem.phi_s, k.rolling == "steady")
    extra_slip = problem.info.get("rigid_slip_extra")   # per element (conformal.cases.wheelrail.wheel_surface_slip)
    if extra_slip is not None:
        slip = slip + np.asarray(extra_slip, float)

    def normal_stage(extra_un, p_start, tang):
        if problem.normal_force is None:
            load = dict(approach=problem.approach)
        elif tang is None:
            load = dict(normal_force=problem.normal_force)
        else:  # seed Eq. 46: sum pn w dS = N - sum ps sin dS, the tangential share taken as
            # proportional to the normal force (exact in full slip): a plain update of the load by
            # the last share diverges where mu tan(delta) > 1 (measured on a 70-degree flank)
            FN = float((p_start * dS).sum())
            r = float((tang.py * sin_w * dS).sum()) / FN           # share per unit normal force
            c = float((p_start * w * dS).sum()) / FN                # load per unit normal force
            if not 1.0 + r / c > 1e-3:
                raise ConvergenceError(
                    f"[load] normal_force: the tangential tractions along the profile push the bodies apart "
                    f"as much as the normal pressure presses them together (per N of normal force "
                    f"{-r:.3f} N against {c:.3f} N along the load direction): the wheel climbs the flange "
                    "(Nadal's limit, mu tan(delta) > 1); no equilibrium at this load: lower mu or the creepages")
            load = dict(normal_force=problem.normal_force / (1.0 + r / c))
        return solve_normal(op, grid, h, weights=w, extra_un=extra_un, material=problem.material, tol=tol,
                            maxit=maxit, p_start=p_start, **load)

    # friction per element (``info["mu_scale"]``, [friction] angle_table): the bound mu p_n scaled
    scale = problem.info.get("mu_scale")

    def tangential_stage(pn, extra_u, p_start):
        if scale is not None:
            pn = pn * scale
        return solve_tangential(op, grid, pn, xi=0.0, eta=0.0, phi=0.0, mu_static=f.mu_static,
                                mu_kinetic=f.mu_kinetic, rolling=k.rolling, fx_rel=k.fx_rel, fy_rel=k.fy_rel,
                                extra_u=extra_u, tol=tol, maxit=maxit, p_start=p_start, rigid_slip=slip)

    # the load along d depends on the tangential tractions where the frames are inclined to d
    load_coupled = problem.normal_force is not None and bool(np.any(sin_w != 0.0))
    return alternate(op, normal_stage, tangential_stage, tangential=_needs_tangential(problem, op), tol=tol,
                     maxout=maxout, load_coupled=load_coupled)


# ----------------------------------------------------------------------------- results
def _real(v: np.ndarray, mirror: float, lateral: bool = False) -> np.ndarray:
    """A side-frame array on the curved grid in the real frame (left wheel: s axis reversed)."""
    if mirror > 0:
        return v
    v = v[:, ::-1]
    return -v if lateral else v


def _edge_warning(contact: np.ndarray) -> str | None:
    sides = [name for name, m in (("x = xl (trailing edge)", contact[0]), ("x = xh (leading edge)", contact[-1]),
                                  ("the first column along s", contact[:, 0]),
                                  ("the last column along s", contact[:, -1])) if m.any()]
    if not sides:
        return None
    return ("the contact area reaches the border of the potential contact area at " + ", ".join(sides)
            + ": the solution is truncated there; enlarge the grid ([grid] scale)")


def _result(problem: CurvedProblem, op, op_info: dict, stages: Stages) -> Result:
    grid = problem.grid
    m = problem.mirror
    dev = developed_grid(grid)
    if m < 0:  # real frame of a left wheel: s -> -s
        dev = PlanarGrid(dev.mx, dev.my, dev.dx, dev.dy, dev.xl, -(dev.yl + dev.my * dev.dy))
    normal = stages.normal
    tr = tractions(op, stages)
    pn, px, ps = normal.pn, tr.px, tr.py
    tot = curved_totals(grid, pn, px, ps)
    fld = CurvedTractionField(
        grid=dev, pn=_real(pn, m), px=_real(px, m), py=_real(ps, m, True), status=_real(tr.status, m),
        sx=_real(tr.sx, m), sy=_real(tr.sy, m, True), un=_real(tr.un, m), ux=_real(tr.ux, m),
        uy=_real(tr.uy, m, True), curved=grid, delta=_real(np.broadcast_to(grid.delta, grid.shape).copy(), m, True),
        h=_real(np.asarray(problem.h, float), m))
    a, b = patch_extent(dev, normal.contact)
    w = approach_weights(grid, problem.load_angle)
    approach = float(np.max(normal.approach * w - problem.h)) if problem.overlap_approach else normal.approach
    contact = normal.contact
    dS = np.broadcast_to(grid.area, grid.shape)
    d_c = m * np.broadcast_to(grid.delta, grid.shape)[contact]
    regions = _regions(grid, pn, px, ps, contact)
    spread = max((math.degrees(r["delta_max"] - r["delta_min"]) for r in regions), default=0.0)
    mu = problem.friction.mu_static
    extra: dict = {
        "label": problem.label,
        "FX_track": tot["FX"], "FY_track": m * tot["FY_side"], "FZ_track": tot["FZ_side"],
        "MZ_3d": m * tot["MZ_3d"],
        "approach_along_load": normal.approach, "load_angle": m * problem.load_angle,
        "contact_area": float(dS[contact].sum()),
        "contact_angle_min": float(d_c.min()) if d_c.size else None,
        "contact_angle_max": float(d_c.max()) if d_c.size else None,
        "contact_angle_spread_deg": spread,
        "regions": [_region_real(r, m) for r in regions],
        "FX_rel": tot["FX"] / (mu * tot["FN"]) if tot["FN"] > 0 else None,
        "FY_rel": m * tot["FS"] / (mu * tot["FN"]) if tot["FN"] > 0 else None,
        "outer_iterations": 1 + len(stages.outer), "outer": stages.outer,
        "grid": {"mx": grid.mx, "ms": grid.ms, "dx": grid.dx, "ds": float(grid.ds[0]), "xl": grid.xl,
                 "s_lo": float(grid.s_edges[0]), "s_hi": float(grid.s_edges[-1]), "s_ref": grid.s_ref},
    }
    extra.update(solution_extra(problem, stages, tr, dS))
    extra.update(op_info)
    extra.update({k: v for k, v in problem.info.items() if k not in extra and k not in ("rigid_slip_extra", "mu_scale")})
    warnings = list(problem.info.get("warnings", []))
    edge = _edge_warning(contact)
    if edge:
        warnings.append(edge)
    warnings += convergence_warnings(stages, tr, problem.model.tol, "curved frames, " + op_info.get("influence", ""))
    if warnings:
        extra["warnings"] = warnings
    tang = stages.tang
    xi_ref = float(np.interp(grid.s_ref, grid.s, problem.xi_s)) + (tang.xi if tang is not None else 0.0)
    eta_ref = float(np.interp(grid.s_ref, grid.s, problem.eta_s)) + (tang.eta if tang is not None else 0.0)
    return Result(theory="conformal", FN=tot["FN"], FX=tot["FX"], FY=m * tot["FS"], MZ=m * tot["MZ"], a=a, b=b,
                  pmax=float(pn.max()), approach=approach, xi=xi_ref, eta=m * eta_ref,
                  phi=m * float(np.interp(grid.s_ref, grid.s, problem.phi_s)),
                  converged=bool(normal.converged and tr.converged and stages.converged),
                  iterations=stages.normal_iterations + stages.tangential_iterations,
                  residual=max(normal.residual, tr.residual), field=fld, extra=extra)


def solve_curved(problem: CurvedProblem, op=None, op_info: dict | None = None) -> Result:
    """Solve a conformal contact problem (both stages and the outer iteration) on its curved grid.
    ``op``: a ready influence operator of the grid (else built from ``problem.model``)."""
    if op is None:
        op, op_info = influence_operator(problem.grid, problem.material, problem.model,
                                         rail_points=problem.rail_points, wheel_points=problem.wheel_points)
    if (op.mx, op.my) != problem.grid.shape:
        raise InputError(f"influence operator for a {op.mx} x {op.my} grid, the curved grid has "
                         f"{problem.grid.mx} x {problem.grid.ms} elements")
    t0 = time.perf_counter()
    stages = solve_stages(problem, op)
    info = dict(op_info or {})
    info["solve_s"] = time.perf_counter() - t0
    return _result(problem, op, info, stages)


# ----------------------------------------------------------------------------- entry points
def planar_as_curved(problem: ContactProblem) -> CurvedProblem:
    """A planar contact problem as a conformal problem on a flat strip (the planar limit)."""
    grid, h = problem.require_grid("theory \"conformal\"")
    strip = flat_strip(grid)
    k = problem.kinematics
    for key in ("xi", "eta", "phi"):
        if not math.isfinite(getattr(k, key)):
            raise InputError(f"[kinematics] {key}: must be a finite number, got {getattr(k, key)!r}")
    xi_s, eta_s, phi_s = column_creepages(strip, k.xi, k.eta, k.phi)
    return CurvedProblem(grid=strip, h=np.asarray(h, float), material=problem.material, friction=problem.friction,
                         kinematics=k, model=problem.model, xi_s=xi_s, eta_s=eta_s, phi_s=phi_s,
                         normal_force=problem.normal_force, approach=problem.approach, load_angle=0.0,
                         label=problem.label, info=dict(problem.info))


def solve(problem: ContactProblem) -> Result:
    """The model entry (conformal.models.SOLVE): a planar problem solved as a flat conformal strip.
    Wheel-rail scenes take conformal.cases.conformal.solve_wheel_rail_conformal (curved grids) instead."""
    cp = planar_as_curved(problem)
    op, info = influence_operator(cp.grid, cp.material, cp.model, planar=True)
    r = solve_curved(cp, op, info)
    if problem.hertz is not None:
        hz = problem.hertz
        r = replace(r, extra=dict(r.extra, hertz={"a": hz.a, "b": hz.b, "pmax": hz.pmax, "approach": hz.approach,
                                                  "FN": hz.FN}))
    return r
