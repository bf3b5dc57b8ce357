"""Wheel-rail cases with the conformal theory: ONE curved strip on the rail over every contact
patch of the wheel, its creepages from the wheelset motion, and its FE or half-space influence
numbers (the body shapes handed to :mod:`conformal.influence.fe`).

The solver itself (Li's conformal contact, Li 2002; seed Eqs. 45-49) is
:mod:`conformal.solvers.conformal`; this module builds its
:class:`~conformal.solvers.conformal.CurvedProblem` from a scene, and (issue 11)

* extends a strip wherever its contact reaches an end (:func:`_solve_extending`): never cut;
* with ``[grid] strips = "separate"`` solves every contact patch on a strip of its own, without
  elastic interaction, at a common wheelset height (:func:`_solve_separate`);
* with ``[kinematics] fx_rel`` and ``speed`` solves the wheelset's pitch velocity for that force
  (free rolling at fx_rel = 0, :func:`_solve_pitch`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.optimize import brentq

from conformal.cases.wheelrail import (curved_creepages, loaded_state, patch_info, secant_on_hertz_growth,
                                       wheel_surface_slip, wheelset_motion)
from conformal.errors import ConvergenceError, InputError
from conformal.geometry.patches import Patch, curved_grid_for_patch
from conformal.geometry.wheelrail import profile_curves
from conformal.grid import connected_parts
from conformal.result import EXTERIOR, Result
from conformal.specs import Friction
from conformal.solvers.conformal import (MAX_ELEMENTS, CurvedProblem, approach_weights, column_creepages,
                                        solve_curved)


def scene_profiles(scene) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Whole rail and wheel profiles (points, 0.1 mm apart) of a wheel-rail scene, so that the FE
    bodies get room beyond the grid's local curves; (None, None) if they cannot be had."""
    try:
        wc, rc = profile_curves(scene.geometry, scene.base_dir)
    except (AttributeError, TypeError):
        return None, None
    return rc.sample(0.1)[1], wc.sample(0.1)[1]


def fe_profiles(scene) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The profiles the FE bodies are built from: :func:`scene_profiles`, or with ``[model]
    fe_closure = "section"`` the boundaries of the real cross-sections (the 60E1 rail under a
    UIC 60 / 60E1 head, the wheel's rim and web under a profile from its flange back at
    y = -70: :mod:`conformal.geometry.sections`), each less its support edge (the rail's foot,
    the wheel's hub face: :func:`conformal.meshing.bodies.section_profile`), which the FE body
    closes again and cuts by its disc.  Raises InputError where a profile has no known section."""
    rail, wheel = scene_profiles(scene)
    if dict(scene.model.options).get("fe_closure") != "section":
        return rail, wheel
    from conformal.geometry.sections import uic60_section, wheel_rim_section
    from conformal.meshing.bodies import section_profile

    if rail is None or wheel is None:
        raise InputError("[model] fe_closure = \"section\": needs a wheel_rail scene with rail and wheel profiles")
    geo = scene.geometry
    try:
        rs = uic60_section(rail)
    except InputError as exc:
        raise InputError(f"[model] fe_closure = \"section\": rail profile {geo.rail_profile}: no known section "
                         f"(a symmetric UIC 60 / 60E1 head is needed: {exc})") from None
    try:
        ws = wheel_rim_section(wheel, float(geo.wheel_radius))
    except InputError as exc:
        raise InputError(f"[model] fe_closure = \"section\": wheel profile {geo.wheel_profile}: no known section "
                         f"(a profile from its flange back at y = -70 is needed: {exc})") from None
    out = []
    for s in (rs, ws):
        p = section_profile(s.points, s.n_profile, s.clamped[0], s.name)
        out.append(np.column_stack([p.y, p.z]))
    return out[0], out[1]


CREEPAGES = ("surface", "reference", "wheel_surface")


def creepage_option(model) -> str:
    """``[model] creepage`` of the conformal theory: "surface" (the creepages of each column from the
    wheelset motion, the wheel's material point on the rail surface of the just-touching wheel; the
    default), "reference" (the reference point's creepages spread as a rigid motion: the planar
    theories' assumption) or "wheel_surface" (CONTACT's conformal rigid slip: the wheel's velocity at
    its own undeformed surface point of every element; the default of influence =
    "halfspace_planar")."""
    default = "wheel_surface" if model.influence in ("halfspace_planar", "halfspace_blanco") else "surface"
    creep = dict(model.options).get("creepage", default)
    if creep not in CREEPAGES:
        raise InputError(f"[model] creepage: must be one of {', '.join(CREEPAGES)}, got {creep!r}")
    return creep


# ----------------------------------------------------------------------------- wheel and rail
def _element_sizes(scene, patches, merged, scale: float) -> tuple[float, float, list[str]]:
    """(dx, ds, warnings) of a strip over several patches: [geometry] element_size (square
    elements, CONTACT's DX = DS), else the extents of the most penetrating patch along x and s
    times [grid] scale over [grid] n elements (the strip gets more elements along s).  At most
    MAX_ELEMENTS ([model] max_mx, max_ms) along each axis: larger strips get coarser elements."""
    es = scene.geometry.element_size
    p, g = patches[0], scene.grid
    if es is not None:
        dx = float(es)
        ds = float(getattr(scene.geometry, "element_size_s", None) or es)
    else:
        dx = (p.x_range[1] - p.x_range[0]) * g.scale / g.n
        ds = max(p.s_range[1] - p.s_range[0], 1e-3) * g.scale / g.n
    warnings = []
    opts = scene.model.options
    for axis, lo_hi, key in (("x", merged.x_range, "max_mx"), ("s", merged.s_range, "max_ms")):
        limit = int(opts.get(key, MAX_ELEMENTS))
        if limit < 2:
            raise InputError(f"[model] {key}: must be >= 2, got {limit}")
        need = (lo_hi[1] - lo_hi[0]) * scale
        size = dx if axis == "x" else ds
        if need / size > limit:
            size = need / limit
            warnings.append(f"the strip over {len(patches)} patch(es) needs more than {limit} elements along "
                            f"{axis}: element size {size:.3g} mm instead (raise [model] {key} for a finer grid)")
            dx, ds = (size, ds) if axis == "x" else (dx, size)
    return dx, ds, warnings


def curved_problem_from_wheel_rail(scene, *, scale: float | None = None) -> CurvedProblem:
    """The conformal problem of a wheel-rail scene: ONE curved grid on the rail that covers every
    contact patch of the wheel (tread and flange at once share the strip, and their elastic
    interaction is included), at the wheelset height of the planar half-space balance.

    h is the signed distance along the local normals at that height; the load is ``[load]
    wheel_load`` along the load direction (vertical, or ``[load] load_angle`` from it, the wheel
    pressed along that direction from the height of the vertical balance: w = cos(delta - load
    angle), seed Eqs. 45-46) or, with
    ``[load] approach``, the height itself (approach 0 from there).  Creepages per column: from the
    wheelset velocities with ``[kinematics] speed`` (the spin follows the contact angle), else from
    the scene's xi, eta, phi at the reference point (:func:`column_creepages`).  ``[model] creepage
    = "reference"`` takes the reference point's creepages with the speed too (the assumption of the
    planar theories; for studies that separate the effect of the geometry from that of the
    kinematics)."""
    pl, st, _ = loaded_state(scene, grids=False)
    return StripBuilder.for_scene(scene, pl, st).problem(scale=scale)


@dataclass(frozen=True, eq=False)
class StripBuilder:
    """Builds the curved strip problems of a wheel at one loaded state: the strip over every patch
    (``patch`` merged), or a strip fitted to one part of it, and the same strip extended along x
    or s with its element sizes kept (:meth:`extended`)."""

    scene: Any
    pl: Any
    st: Any
    patch: Patch                 # merged over all patches of the wheel
    n_patches: int

    @classmethod
    def for_scene(cls, scene, pl, st) -> "StripBuilder":
        patches = [pg.patch for pg in st.patches]
        main = patches[0]
        merged = main if len(patches) == 1 else replace(
            main, s_range=(min(p.s_range[0] for p in patches), max(p.s_range[1] for p in patches)),
            x_range=(min(p.x_range[0] for p in patches), max(p.x_range[1] for p in patches)))
        return cls(scene, pl, st, merged, len(patches))

    def problem(self, *, scale: float | None = None, patch: Patch | None = None,
                sizes: tuple[float, float] | None = None, n: int | None = None,
                approach: float | None = None, label: str = "") -> CurvedProblem:
        """The strip problem: over ``patch`` (default: all patches), ``sizes`` = (dx, ds) or ``n``
        elements per axis or the scene's element size; loaded by the wheel load, or, with
        ``approach``, moved that far (mm) along the load direction (vertical unless ``[load]
        load_angle``) from the reference height."""
        scene, pl, st = self.scene, self.pl, self.st
        load = scene.load
        wheel = pl.pair.wheel(st.z)
        g = scene.grid
        scale = scale or g.scale
        size_warnings: list[str] = []
        target = patch or self.patch
        # CONTACT's formulation (its kernel or its rigid slip): its grids put an element centre on the
        # reference point
        centred = scene.model.influence in ("halfspace_planar", "halfspace_blanco") or creepage_option(scene.model) == "wheel_surface"
        if sizes is not None:
            grid, h, approach0 = curved_grid_for_patch(wheel, pl.pair.rail, target, sizes=sizes, scale=scale,
                                                       side=pl.pair.side, centred=centred, theory=scene.model.theory)
        elif (self.n_patches == 1 or patch is not None) and n is None \
                and getattr(scene.geometry, "element_size_s", None) is not None:   # CONTACT's DX, DS
            grid, h, approach0 = curved_grid_for_patch(
                wheel, pl.pair.rail, target, sizes=(scene.geometry.element_size, scene.geometry.element_size_s),
                scale=scale, side=pl.pair.side, centred=centred, theory=scene.model.theory)
        elif self.n_patches == 1 or patch is not None:   # the grid of conformal.geometry (and of precompute)
            grid, h, approach0 = curved_grid_for_patch(
                wheel, pl.pair.rail, target, element_size=None if n is not None else scene.geometry.element_size,
                n=n or g.n, scale=scale, side=pl.pair.side, centred=centred, theory=scene.model.theory)
        else:
            patches = [pg.patch for pg in st.patches]
            dx, ds, size_warnings = _element_sizes(scene, patches, target, scale)
            grid, h, approach0 = curved_grid_for_patch(wheel, pl.pair.rail, target, sizes=(dx, ds), scale=scale,
                                                       side=pl.pair.side, theory=scene.model.theory)
        merged = self.patch
        m = pl.pair.mirror
        k = scene.kinematics
        creep = creepage_option(scene.model)
        motion = wheelset_motion(scene)
        if motion is not None:
            c = curved_creepages(pl.pair, st.z, motion, grid, merged)
            xi_s, eta_s, phi_s = c.xi, m * c.eta, m * c.phi        # back to the side frame of the grid
            if creep == "reference":   # the planar theories' assumption: the reference point's creepages
                xi_s, eta_s, phi_s = column_creepages(grid, *(float(np.interp(grid.s_ref, grid.s, v))
                                                              for v in (xi_s, eta_s, phi_s)))
            kin = replace(k, velocity=float(np.interp(grid.s_ref, grid.s, c.velocity)))
        else:
            xi_s, eta_s, phi_s = column_creepages(grid, k.xi, m * k.eta, m * k.phi)
            kin = k
        info = patch_info(pl.pair, st, st.patches[0], 0)
        if patch is not None:     # a strip of its own: its reference point on the rail (CONTACT's YCP(R), ZCP(R))
            y_own, z_own = (float(v) for v in pl.pair.rail.curve.point(target.s_ref))
            info.update(s_rail=float(target.s_ref), y_rail=m * y_own, z_rail=z_own)
        info.update(n_geometric_patches=self.n_patches, z_ws_reference=st.z, z_first_touch=pl.z_first,
                    side=pl.pair.side)
        if st.warnings or size_warnings or st.placement_warnings:
            info["warnings"] = list(st.warnings) + size_warnings + list(st.placement_warnings)
        h_strip = h - approach0          # the signed distance along the local normals at the height st.z
        if motion is not None and creep == "wheel_surface":
            # CONTACT's D = 4 rigid slip: the wheel's velocity at its own surface point of each element
            info["rigid_slip_extra"] = wheel_surface_slip(pl.pair, st.z, motion, grid, target.x_ref, h_strip,
                                                          merged.penetration)
        if getattr(load, "approach_along", None) is not None:
            # [load] approach_along: from the height of [load] approach (below the first touch) the wheel
            # moves that far along the load direction; the strip was found at a height st.z, so h is taken
            # back to the reference height by the vertical motion's projection on the normals (first
            # order, as the motion along the load direction itself; seed Eq. 45)
            z_ref = pl.z_first + load.approach
            h_strip = h_strip + (st.z - z_ref) * approach_weights(grid, 0.0)
            info["z_ws_reference"] = z_ref
            normal = dict(approach=float(load.approach_along if approach is None else approach))
        elif approach is not None:
            normal = dict(approach=float(approach))
        else:
            normal = dict(normal_force=load.wheel_load) if load.wheel_load is not None else dict(approach=0.0)
        rail_points, wheel_points = fe_profiles(scene)   # whole profiles (or sections) for the FE bodies
        profiles = dict(rail_points=rail_points, wheel_points=wheel_points)
        friction = scene.friction
        if friction.angle_table:   # [friction] angle_table: each row s of the strip at its own angle
            friction, info["mu_scale"] = _friction_per_row(friction, m * np.asarray(grid.delta, float), grid.shape,
                                                           k)
        return CurvedProblem(grid=grid, h=h_strip, material=scene.material, friction=friction,
                             kinematics=kin, model=scene.model, xi_s=np.asarray(xi_s, float),
                             eta_s=np.asarray(eta_s, float), phi_s=np.asarray(phi_s, float),
                             load_angle=m * load.load_angle,     # the side frame (left wheel mirrored)
                             overlap_approach=True,
                             label=f"{scene.name}:{pl.pair.side}{label}", info=info, **normal, **profiles)

    def extended(self, problem: CurvedProblem, sides: set[str], *, patch: Patch | None = None,
                 fraction: float = 0.5, label: str = "") -> CurvedProblem | None:
        """The strip of ``problem`` extended on ``sides`` ("x_lo", "x_hi", "s_lo", "s_hi") by
        ``fraction`` of its length along that axis (at least 3 elements), with the same element
        sizes; None where it cannot grow (an end of the rail profile, or more than the element
        limits [model] max_mx / max_ms)."""
        g = problem.grid
        ref = patch or self.patch
        dx, ds = g.dx, float(g.ds[0])
        x_lo = ref.x_ref + g.xl
        x_hi = x_lo + g.mx * dx
        s_lo, s_hi = float(g.s_edges[0]), float(g.s_edges[-1])
        ex = max(fraction * (x_hi - x_lo), 3 * dx)
        es = max(fraction * (s_hi - s_lo), 3 * ds)
        length = self.pl.pair.rail.curve.length
        if ("s_lo" in sides and s_lo <= 1e-9) or ("s_hi" in sides and s_hi >= length - 1e-9):
            return None
        x_lo -= ex if "x_lo" in sides else 0.0
        x_hi += ex if "x_hi" in sides else 0.0
        s_lo = max(s_lo - es, 0.0) if "s_lo" in sides else s_lo
        s_hi = min(s_hi + es, length) if "s_hi" in sides else s_hi
        opts = self.scene.model.options
        if ((x_hi - x_lo) / dx > int(opts.get("max_mx", MAX_ELEMENTS))
                or (s_hi - s_lo) / ds > int(opts.get("max_ms", MAX_ELEMENTS))):
            return None
        # curved_grid_for_patch adds one element on each side of the range at scale 1
        target = replace(ref, x_range=(x_lo + dx, x_hi - dx), s_range=(s_lo + ds, s_hi - ds))
        kw = dict(approach=problem.approach) if problem.normal_force is None else {}
        return self.problem(scale=1.0, patch=target, sizes=(dx, ds), label=label, **kw)


def _edge_sides(problem: CurvedProblem, result: Result) -> set[str]:
    """The strip ends (side frame) where the contact area of ``result`` reaches the border."""
    contact = result.field.side_frame("status") != EXTERIOR
    sides = set()
    for name, m in (("x_lo", contact[0]), ("x_hi", contact[-1]), ("s_lo", contact[:, 0]), ("s_hi", contact[:, -1])):
        if m.any():
            sides.add(name)
    return sides


def _solve_extending(builder: StripBuilder, problem: CurvedProblem, max_extend: int, *, patch=None,
                     label: str = "") -> tuple[Result, CurvedProblem, int, list[str]]:
    """Solve ``problem`` and, while its contact area reaches an end of the strip, extend the strip
    there (same element sizes) and solve again: contact is never cut by the strip.  Returns (result,
    problem, number of extensions, warnings)."""
    warnings: list[str] = []
    for attempt in range(max_extend + 1):
        result = solve_curved(problem)
        sides = _edge_sides(problem, result)
        if not sides:
            return result, problem, attempt, warnings
        if attempt == max_extend:
            break
        bigger = builder.extended(problem, sides, patch=patch, label=label)
        if bigger is None:
            warnings.append(f"the contact reaches the strip's end ({', '.join(sorted(sides))}) where the strip "
                            "cannot grow (an end of the rail profile, or [model] max_mx / max_ms elements)")
            return result, problem, attempt, warnings
        problem = bigger
    warnings.append(f"the contact still reaches the strip's end ({', '.join(sorted(sides))}) after {max_extend} "
                    "extensions")
    return result, problem, max_extend, warnings


def _pitch_for_reference_creepage(problem: CurvedProblem, motion, xi_target: float) -> tuple[float, float]:
    """(pitch velocity, reference rolling radius): the wheelset pitch velocity (rad/s) at which the
    reference column of ``problem`` has the longitudinal creepage ``xi_target``.

    At the reference point the wheel material moves with v_w = V + pitch R_ref along x (R_ref: the
    distance of the point below the axle, the reference rolling radius) and the rolling velocity is
    the mean V_r = (V - pitch R_ref)/2 (conformal.geometry.kinematics), so that
    xi = -(V + pitch R_ref)/V_r, i.e. pitch R_ref = -V (1 + xi/2)/(1 - xi/2).  R_ref follows from
    the creepage the problem was built with at its own pitch velocity."""
    g = problem.grid
    V = motion.speed
    xi0 = float(np.interp(g.s_ref, g.s, problem.xi_s))
    q0 = -V * (1.0 + 0.5 * xi0) / (1.0 - 0.5 * xi0)
    if motion.pitch_velocity == 0.0:
        raise InputError("[kinematics] pitch_velocity: a prescribed FX needs a rolling wheel (pitch velocity != 0)")
    r_ref = q0 / motion.pitch_velocity
    q = -V * (1.0 + 0.5 * xi_target) / (1.0 - 0.5 * xi_target)
    return float(q / r_ref), float(r_ref)


def solve_wheel_rail_conformal(scene, *, max_enlarge: int = 2, max_pitch: int = 8, warm=None) -> Result:
    """Solve a wheel-rail scene with the conformal theory; with ``[kinematics] speed`` and ``fx_rel``
    (e.g. ``fx_rel = 0``: free rolling) the wheelset's pitch velocity is solved so that FX/(mu FN)
    takes that value (:func:`_solve_pitch`), else :func:`_solve_conformal` at the scene's motion.
    ``warm``: a neighbour's WarmStart (its lowering starts the planar balance the strip is built at)."""
    k = scene.kinematics
    if k.fx_rel is None or k.speed is None:
        state = None
        if warm is not None and warm.lowering is not None and scene.load.wheel_load is not None:
            state = loaded_state(scene, grids=False, lowering=warm.lowering)[:2]
        return _solve_conformal(scene, max_enlarge=max_enlarge, state=state)
    return _solve_pitch(scene, max_enlarge=max_enlarge, max_pitch=max_pitch)


def _solve_pitch(scene, *, max_enlarge: int, max_pitch: int) -> Result:
    """Prescribed FX with the wheelset motion: the pitch velocity that gives FX = fx_rel mu FN.

    The tangential solver can meet a prescribed FX by itself, by adding one longitudinal creepage
    dxi to every column; a change of the pitch velocity instead changes the creepage of column s
    in proportion to its own rolling radius r(s), which differs across a deep groove by several
    per cent, and near saturation or at a small mu the force is a steep function of the creepage.
    So the pitch is found here, in the case layer, by a root search on solves at a given motion:
    f(xi) = FX/(mu FN) - fx_rel as a function of the reference column's creepage xi (monotone,
    decreasing), each xi turned into a pitch velocity (:func:`_pitch_for_reference_creepage`)
    and the column creepages rebuilt from the wheelset motion.  The first guess is the creepage
    the prescribed-force solve finds (its uniform shift dxi); the bracket widens from there until
    f changes sign, then Brent's method (xtol 1e-7 of the creepage, at most ``max_pitch`` + 20
    solves).  The result is the solve at the root's motion: ``pitch_velocity_solved`` (rad/s),
    ``pitch_creepage_solved`` (the reference column's xi, the JSON ``xi``),
    ``reference_rolling_radius`` and, for fx_rel = 0, ``pitch_creepage_free``."""
    target = float(scene.kinematics.fx_rel)
    plain = scene.with_("kinematics.fx_rel", None)
    state = loaded_state(scene, grids=False)[:2]       # the pitch does not move the planar balance
    motion0 = wheelset_motion(scene)
    solves: dict[float, tuple] = {}
    ref: dict = {}

    def at(xi: float):
        if xi not in solves:
            if ref:
                pitch, _ = _pitch_for_reference_creepage(ref["problem"], ref["motion"], xi)
                sc = plain.with_("kinematics.pitch_velocity", pitch)
            else:
                sc = plain
            res, prob = _solve_conformal(sc, max_enlarge=max_enlarge, with_problem=True, state=state)
            solves[xi] = (res, prob, wheelset_motion(sc))
        return solves[xi]

    # the scene's own motion, and the prescribed-force solve for a first guess
    res0, problem = _solve_conformal(plain, max_enlarge=max_enlarge, with_problem=True, state=state)
    g = problem.grid
    xi0 = float(np.interp(g.s_ref, g.s, problem.xi_s))
    ref.update(problem=problem, motion=motion0)
    solves[xi0] = (res0, problem, motion0)
    try:
        guess = float(_solve_conformal(scene, max_enlarge=max_enlarge, state=state).xi)
    except ConvergenceError:
        guess = math.nan

    def f(xi: float) -> float:
        r = at(xi)[0]
        return float(r.extra["FX_rel"]) - target

    f0 = f(xi0)
    # FX falls as xi grows (a positive xi gives FX < 0): the root lies at a larger xi where f0 > 0
    step = abs(guess - xi0) if math.isfinite(guess) and guess != xi0 else 1e-3
    step = math.copysign(max(step, 1e-7), f0)
    lo, flo = xi0, f0
    hi = xi0 + step
    for _ in range(max_pitch + 12):
        fhi = f(hi)
        if fhi == 0.0 or (fhi > 0) != (flo > 0):
            break
        lo, flo = hi, fhi
        step *= 2.0
        hi = lo + step
    else:
        raise ConvergenceError(f"[kinematics] fx_rel: no pitch velocity gives FX/(mu FN) = {target:g} "
                               f"(creepage bracket up to {hi:.3g})")
    if fhi != 0.0:
        xtol = 1e-7 * max(abs(lo), abs(hi), 1e-6)
        root = brentq(f, min(lo, hi), max(lo, hi), xtol=xtol, rtol=1e-10, maxiter=max_pitch + 20)
    else:
        root = hi
    result, prob, motion = at(root)
    xi_ref = float(np.interp(prob.grid.s_ref, prob.grid.s, prob.xi_s))
    _, r_ref = _pitch_for_reference_creepage(prob, motion, xi_ref)
    extra = dict(result.extra, pitch_velocity_solved=float(motion.pitch_velocity), pitch_creepage_solved=xi_ref,
                 reference_rolling_radius=r_ref, pitch_solves=len(solves) + 1,
                 pitch_creepage_guess=guess, fx_rel_target=target)
    if target == 0.0:
        extra["pitch_creepage_free"] = xi_ref
    return replace(result, extra=extra)


def _solve_conformal(scene, *, max_enlarge: int = 6, with_problem: bool = False, state=None):
    """Solve a wheel-rail scene with the conformal theory (see :func:`curved_problem_from_wheel_rail`).

    With a prescribed wheel load the grid is built around the overlap at the planar balance height;
    where the conformal solution needs more room (its contact reaches an end of the strip, along x
    or s) the strip is extended on that side by half its length, with the same elements, at most
    ``max_enlarge`` times (:func:`_solve_extending`): the contact is never cut by the strip.
    ``[grid] strips = "separate"`` solves every contact patch on its own strip instead
    (:func:`_solve_separate`).  ``state`` = (placement, loaded state) of an earlier solve of the same
    scene with other creepages (they do not move the planar balance the strip is built at)."""
    pl, st = state if state is not None else loaded_state(scene, grids=False)[:2]
    builder = StripBuilder.for_scene(scene, pl, st)
    problem = builder.problem()
    result, problem, attempt, ext_warn = _solve_extending(builder, problem, max_enlarge)
    out = _finish(scene, problem, result, attempt, ext_warn)
    # the next position of a sweep starts its planar balance from this lowering (WarmStart)
    out = replace(out, extra=dict(out.extra, balance={"lowering": float(st.z - pl.z_touch)}))
    if getattr(scene.grid, "strips", "coupled") == "separate":
        out, problem = _solve_separate(scene, builder, problem, out, max_enlarge)
    return (out, problem) if with_problem else out


def _finish(scene, problem: CurvedProblem, result: Result, attempt: int, ext_warn: list[str]) -> Result:
    along = result.extra["approach_along_load"] if problem.normal_force is not None else (problem.approach or 0.0)
    z_ws = problem.info["z_ws_reference"] + along * math.cos(problem.load_angle)   # its vertical part
    # ``approach`` means what [load] approach means: the wheelset's lowering below the height where
    # its first wheel touches; the largest overlap along the local normals is ``overlap_max``
    extra = dict(result.extra, z_ws=z_ws, grid_scale=scene.grid.scale, enlargements=attempt,
                 # the lowering below the first touch from which the wheel moves along the load direction:
                 # [load] approach = approach_reference with approach_along = approach_along_load gives
                 # this solve back
                 approach_reference=float(problem.info["z_ws_reference"] - problem.info["z_first_touch"]),
                 wheel_load=scene.load.wheel_load, overlap_max=result.approach,
                 strips=getattr(scene.grid, "strips", "coupled"))
    if ext_warn:
        extra["warnings"] = list(extra.get("warnings", [])) + ext_warn
    return replace(result, approach=float(z_ws - problem.info["z_first_touch"]), extra=extra)


#: a contact region of the coupled strip carrying less than this share of the normal force is not
#: given a strip of its own in ``[grid] strips = "separate"`` (its load moves to the others)
MIN_PART_SHARE = 0.005


def _contact_parts(problem: CurvedProblem, result: Result, builder: StripBuilder) -> list[Patch]:
    """The contact regions of a coupled strip solution (connected sets of contact elements, side
    frame) as patches for strips of their own: x and s ranges of the region, reference point at
    its pressure centroid along s; regions under MIN_PART_SHARE of FN are dropped."""
    g = problem.grid
    pn = result.field.side_frame("pn")
    contact = result.field.side_frame("status") != EXTERIOR
    labels, n = connected_parts(contact)
    dS = np.broadcast_to(g.area, g.shape)
    total = float((pn * dS).sum())
    parts = []
    x_edges = builder.patch.x_ref + g.xl + np.arange(g.mx + 1) * g.dx
    for k in range(1, n + 1):
        mask = labels == k
        fn = float((pn * dS)[mask].sum())
        if fn < MIN_PART_SHARE * total:
            continue
        rows = np.flatnonzero(mask.any(axis=1))
        cols = np.flatnonzero(mask.any(axis=0))
        w = (pn * dS * mask).sum(axis=0)
        s_ref = float((w * g.s).sum() / w.sum())
        parts.append((fn, replace(builder.patch, s_range=(float(g.s_edges[cols[0]]), float(g.s_edges[cols[-1] + 1])),
                                  x_range=(float(x_edges[rows[0]]), float(x_edges[rows[-1] + 1])), s_ref=s_ref)))
    parts.sort(key=lambda item: -item[0])
    return [p for _, p in parts]


def _solve_separate(scene, builder: StripBuilder, coupled_problem: CurvedProblem, coupled: Result,
                    max_extend: int, *, sizes: tuple[float, float] | None = None) -> tuple[Result, CurvedProblem]:
    """``[grid] strips = "separate"``: every contact patch of the coupled solution on a strip of
    its own, without elastic interaction between the strips (as CONTACT solves the patches of a
    wheel), each with ``[grid] n`` elements per axis over ``[grid] scale`` times its patch (its
    own element size; with ``[geometry] element_size`` (and ``element_size_s``) those elements,
    CONTACT's DX and DS), extended where its contact reaches an end.  The strips share the wheelset
    height: with ``[load] wheel_load`` the common lowering dz along the load direction below the
    reference height is found by Brent's method on sum_k F_k(dz) = wheel_load (F_k: the force along
    the load direction, :func:`force_along_load`, with the tangential tractions, seed Eq. 46); with ``[load] approach`` the height is the scene's.  ``sizes`` = (dx, ds)
    gives every strip those elements instead (a comparison with the coupled strip at its own sizes).

    The result sums the strips (FN, FX, FY, MZ; FX_track, FY_track, FZ_track in ``extra``) and lists
    them in ``patches`` and in ``extra["strips"]`` (FN, area, pmax, FY_track, contact angle per
    strip); ``extra["coupled"]`` keeps the same per-patch values of the coupled strip."""
    parts = _contact_parts(coupled_problem, coupled, builder)
    g = scene.grid
    W = scene.load.wheel_load
    dz0 = (float(coupled.extra["approach_along_load"]) if coupled_problem.normal_force is not None
           else float(coupled_problem.approach or 0.0))
    # the coupled strip's contact regions are coarse: each strip spans 1.5 times its region
    scale = max(g.scale, 1.5)
    geo = scene.geometry
    if sizes is None and getattr(geo, "element_size", None) is not None:   # CONTACT's DX, DS on every strip
        sizes = (float(geo.element_size), float(getattr(geo, "element_size_s", None) or geo.element_size))
    problems = [builder.problem(patch=p, n=g.n, scale=scale, approach=dz0, label=f":strip{k}", sizes=sizes)
                for k, p in enumerate(parts)]
    warnings: list[str] = []
    results: list[Result] = []
    n_ext = [0] * len(parts)
    for outer in range(4):
        results = []
        for k, (p, prob) in enumerate(zip(parts, problems)):
            r, prob2, ext, w = _solve_extending(builder, prob, max_extend, patch=p, label=f":strip{k}")
            n_ext[k] += ext
            problems[k] = prob2
            results.append(r)
            if outer == 3:
                warnings += w
        if W is None:
            break
        cache: dict[float, list[Result]] = {dz0: results}

        def fz(dz: float) -> float:    # the force along the load direction, less the wheel load
            if dz not in cache:
                cache[dz] = [solve_curved(replace(pr, approach=dz)) for pr in problems]
            return sum(force_along_load(r.extra, scene.load.load_angle) for r in cache[dz]) - W

        dz = _common_lowering(fz, dz0, W)
        fz(dz)
        problems = [replace(pr, approach=dz) for pr in problems]
        results = cache[dz]
        dz0 = dz
        if not any(_edge_sides(pr, r) for pr, r in zip(problems, results)):
            break
    finished = [_finish(scene, pr, r, e, []) for pr, r, e in zip(problems, results, n_ext)]
    tot = {key: sum(r.extra[key] for r in finished) for key in ("FX_track", "FY_track", "FZ_track")}
    strips = [_part_summary(r, k) for k, r in enumerate(finished)]
    main = max(finished, key=lambda r: r.FN)
    extra = {k: v for k, v in main.extra.items() if k not in ("regions", "outer", "grid", "warnings")}
    extra.update(tot, strips="separate", n_strips=len(finished), separate_strips=strips,
                 coupled_strip={"FN": coupled.FN, "FX": coupled.FX, "FY": coupled.FY, "pmax": coupled.pmax,
                          **{k: coupled.extra[k] for k in ("FX_track", "FY_track", "FZ_track")},
                          "regions": coupled.extra["regions"]},
                 contact_area=sum(r.extra["contact_area"] for r in finished),
                 FX_rel=sum(r.FX for r in finished) / (scene.friction.mu_static * sum(r.FN for r in finished)))
    all_warn = warnings + [w for r in finished for w in r.extra.get("warnings", [])]
    if all_warn:
        extra["warnings"] = list(dict.fromkeys(all_warn))
    out = Result.combined(finished, "conformal", extra)
    return out, problems[int(np.argmax([r.FN for r in finished]))]


def force_along_load(extra: dict, load_angle: float) -> float:
    """The force on the rail along the load direction (seed Eq. 46): FZ_track cos(angle) - FY_track
    sin(angle), ``load_angle`` as in ``[load]`` (the JSON's convention; the track frame)."""
    return extra["FZ_track"] * math.cos(load_angle) - extra["FY_track"] * math.sin(load_angle)


def _common_lowering(fz, dz0: float, W: float, tol: float = 1e-5) -> float:
    """The lowering dz with fz(dz) = 0 (fz = FZ(dz) - W, increasing): secant steps on
    (FZ/W)^(2/3), nearly linear in dz for Hertz-like growth, until |fz| <= tol W; Brent's method on
    the bracket found if the secant steps do not settle in 8 solves."""
    return secant_on_hertz_growth(fz, W, dz0, dz0 * 1.02 + 1e-6, tol=tol, maxit=8, xtol=1e-12, rtol=1e-10,
                                  message="[grid] strips: could not find the common wheelset height of the "
                                          "separate strips")


def _part_summary(r: Result, k: int) -> dict:
    """Per-strip values of a separate-strips result (real frame)."""
    g = r.extra["grid"]
    return {"strip": k, "FN": r.FN, "FX": r.FX, "FS": r.FY, "FY_track": r.extra["FY_track"],
            "FZ_track": r.extra["FZ_track"], "area": r.extra["contact_area"], "pmax": r.pmax,
            "contact_angle_min": r.extra["contact_angle_min"], "contact_angle_max": r.extra["contact_angle_max"],
            "dx": g["dx"], "ds": g["ds"], "mx": g["mx"], "ms": g["ms"], "enlargements": r.extra.get("enlargements", 0)}


def _friction_per_row(friction, angles: np.ndarray, shape: tuple, kin) -> tuple:
    """``[friction] angle_table`` on a conformal strip: the friction of every row s at its contact
    angle (``angles``, the real frame), as CONTACT's V = 1 interpolates it per grid row; returned
    as the largest coefficients and the (mx, ms) factor on both (the solver's per-element bound,
    conformal.solvers.conformal).  A table whose mu_kinetic / mu_static changes over the strip, and
    prescribed forces (relative to one mu) with a friction that changes, are refused."""
    rows = [friction.at_angle(float(a)) for a in angles]
    ms = np.array([r.mu_static for r in rows])
    mk = np.array([r.mu_kinetic for r in rows])
    ratio = mk / ms
    if np.ptp(ratio) > 1e-12 * ratio.max():
        raise InputError("[friction] angle_table: on a conformal strip mu_kinetic / mu_static must be the same at "
                         "every contact angle it spans")
    top = int(np.argmax(ms))
    if np.ptp(ms) > 1e-12 * ms[top] and (kin.fx_rel is not None or kin.fy_rel is not None):
        raise InputError("[friction] angle_table: prescribed forces (fx_rel, fy_rel) are relative to one mu; the "
                         "friction changes over this strip")
    scale = np.broadcast_to(ms / ms[top], shape).copy()
    return Friction(float(ms[top]), float(mk[top])), scale
