"""Wheel-rail cases: from ``[geometry] kind = "wheel_rail"`` to contact problems and one result.

Stages (the seed paper's geometry, kinematic and dynamic stages; "seed" is the review cited in
docs/references.md):

1. the wheelset placed and the height where the wheel of ``side`` first touches its rail
   (:mod:`conformal.geometry.wheelrail`);
2. the height under load: ``[load] wheel_load`` (vertical, N) is balanced by the
   vertical components of all patch forces (normal and tangential, as CONTACT's FZ(TR)), with
   the height as the unknown of the normal problem (seed Eq. 46): the geometry is searched once
   per trial height and a vertical step dz changes each patch's approach by dz cos(delta)
   (:func:`linear_balance`; one patch: FN = W / (cos d + (FS/FN) sin d) and one force-prescribed
   normal solve give the height), a few searches in all (:func:`balance_height`; a sweep starts
   from its neighbour's height and ratios extrapolated along the shift, :class:`WarmStart`).
   A one-patch wheel with the exact theory takes the contact solve itself as the normal solve of
   the balance (:func:`one_patch_passes`, about two contact solves per position of a sweep);
   ``[load] approach`` lowers the wheelset by that many mm below the height where its first wheel
   touches (a wheel that then still has a gap is lifted off: NoContactError).  The reported
   ``approach`` of a wheel-load solve is the same quantity, so that solving at it gives the load
   back (the largest overlap of a patch along its normal is ``penetration``);
3. per patch a planar grid on the tangent plane with the undeformed distance of the true
   profiles, Hertz curvatures, and creepages from the wheelset velocities (seed Eq. 61) when
   ``[kinematics] speed`` is given (else the scene's xi, eta, phi for every patch).

Forces are those on the rail (body 1, the normal points into the rail), CONTACT's module 1
convention.  A left wheel is computed as a mirrored right wheel and reported in its own frame:
y_rail > 0 towards the track centre, contact angle > 0 on the tread (as CONTACT prints).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

from conformal.errors import ConvergenceError, InputError, NoContactError
from conformal.geometry.kinematics import Creepages, WheelsetMotion, creepages
from conformal.geometry.patches import (Patch, curved_grid_for_patch, find_patches, planar_grid_for_patch,
                                        rail_on_lines)
from conformal.geometry.placement import WheelRailPair
from conformal.geometry.profiles import rail_orientation_warning
from conformal.geometry.search import LOCUS_STEP, TOUCH_STEP, RailTop, pair_locus, touch_bounds
from conformal.geometry.surfaces import LOCUS_REACH_MARGIN
from conformal.geometry.wheelrail import build_pair, first_touch, profile_curves, touches_after, wheelset_roll
from conformal.grid import PlanarGrid
from conformal.models import solve_problem
from conformal.problem import ContactProblem
from conformal.registry import CONFORMAL_GEOMETRY, CURVED_STRIP, GRID, MODELS, WARM_START
from conformal.result import Result
from conformal.scene import Scene, WheelRailGeometry
from conformal.solvers.conformal import DELTA_SPREAD_WARN
from conformal.solvers.exact import border_sides
from conformal.solvers.normal import solve_normal, warm_precondition
from conformal.theories.hertz import hertz_from_curvatures

BALANCE_TOL = 1e-4                       # relative tolerance of the vertical force balance


def wheelset_motion(scene: Scene) -> WheelsetMotion | None:
    """The wheelset's velocities of ``[kinematics]`` (None without ``speed``): forward speed, the
    pitch velocity (default: pure rolling at ``wheel_radius``), yaw, roll and lateral velocities."""
    k = scene.kinematics
    if k.speed is None:
        return None
    pitch = k.pitch_velocity if k.pitch_velocity is not None else -k.speed / scene.geometry.wheel_radius
    return WheelsetMotion(k.speed, pitch, k.yaw_rate, k.roll_rate, k.lateral_velocity)


# ----------------------------------------------------------------------------- per height
def gap_rate(pair: WheelRailPair, pg: PatchGeometry) -> np.ndarray:
    """The rate d(distance)/dz (per mm of wheelset lowering, side frame) of the undeformed distance
    of every element of the patch grid, the patch frame (point P, normal n, lateral tangent t2)
    kept: the wheel moves by dz along the vertical, dz cos(delta) along n and dz sin(delta) along
    t2, so its surface distance t_w(x, eta) from the tangent plane becomes
    t_w(x, eta - dz sin d) + dz cos d, and the distance d = t_r - t_w changes at the rate
    -cos d + sin d dt_w/deta (t_r: the rail's, which does not move).  Exact to first order in dz
    where the contact angle varies over the patch (checked against distances searched at two
    heights: 2e-4 of the rate on a two-lobe patch, against 5 % for the uniform -cos d)."""
    p, grid = pg.patch, pg.grid
    c, s = math.cos(p.delta), math.sin(p.delta)
    if grid.my < 2 or s == 0.0:
        return np.full(grid.shape, -c)
    eta = grid.y
    Q = p.point[1:][None, :] + eta[:, None] * p.t2[1:][None, :]
    _, t_r = rail_on_lines(pair.rail, Q, p.normal[1:], p.s_ref + eta)
    t_w = t_r[None, :] - (pg.h - pg.approach)
    return -c + s * np.gradient(t_w, grid.dy, axis=1)


@dataclass(frozen=True, eq=False)
class PatchGeometry:
    """One patch at a wheelset height with its planar grid (side frame)."""

    patch: Patch
    grid: PlanarGrid
    h: np.ndarray
    approach: float
    A: float
    B: float
    hertz_angle: float
    #: the approach the vertical balance uses for a Hertz patch (the locus penetration of the
    #: overlap search; ``approach`` is then the largest overlap on the grid), None: ``approach``
    balance_approach: float | None = None
    #: d(distance)/dz per grid element (:func:`gap_rate`), kept from the searched geometry by
    #: :meth:`PairState.lowered` (None: not yet needed)
    rate: np.ndarray | None = None

    @property
    def hertz_approach(self) -> float:
        return self.approach if self.balance_approach is None else self.balance_approach

    @property
    def hertzian(self) -> bool:
        return self.A > 0 and self.B > 0


@dataclass(frozen=True, eq=False)
class PairState:
    pair: WheelRailPair
    z: float
    roll: float                   # track frame
    patches: list[PatchGeometry]
    warnings: tuple[str, ...] = ()            # of the vertical balance (non-convergence)
    placement_warnings: tuple[str, ...] = ()  # of the placement (flange tip, profile ends, lift)
    z_geometry: float | None = None           # the height where the patches were searched (None: z)

    def lowered(self, dz: float) -> "PairState":
        """This state lowered by dz (mm) with its searched geometry kept (seed Eq. 46, the height as
        the unknown): each element's undeformed distance changes by dz times its own rate
        (:func:`gap_rate`, first order in dz; the patch approach by dz cos(delta)) and the patch's
        penetration with it, so that the creepages are those of the wheel at the new height."""
        moved = []
        for pg in self.patches:
            ck = math.cos(pg.patch.delta)
            pg = pg if pg.h is None or pg.rate is not None else replace(pg, rate=gap_rate(self.pair, pg))
            h, approach = pg.h, pg.approach + dz * ck
            if h is not None:
                h = h - dz * (pg.rate + ck)              # the part of the rate the approach leaves out
                low = float(h.min())
                h, approach = h - low, approach - low    # h >= 0 with the approach at its minimum
            moved.append(replace(pg, h=h, approach=approach,
                                 patch=replace(pg.patch, penetration=pg.patch.penetration + dz * ck),
                                 balance_approach=None if pg.balance_approach is None
                                 else pg.balance_approach + dz * ck))
        zg = self.z if self.z_geometry is None else self.z_geometry
        return replace(self, z=self.z + dz, patches=moved, z_geometry=zg)

    @property
    def geometry_offset(self) -> float:
        """|z - z_geometry| (mm): how far the balanced height lies from the searched geometry."""
        return 0.0 if self.z_geometry is None else abs(self.z - self.z_geometry)


#: warn when a contact lies within this radial distance (mm) of the wheel's flange tip
FLANGE_TIP_WARN = 2.0
#: warn when a contact lies within this arc length (mm) of an end of a profile
PROFILE_END_WARN = 1.0
#: a wheelset standing more than this (mm) above its nominal height (tape circle on the rail top)
LIFT_WARN = 3.0
#: ... whose height changes by more than this (mm) for 0.1 mm of lateral shift: a jump
JUMP_WARN = 1.0


def placement_warnings(scene: Scene, pl: "Placement", st: PairState) -> list[str]:
    """Warnings about a placement that a careful user must see (issue 11): a contact at the flange
    tip (within FLANGE_TIP_WARN mm of the tip's radius) or at an end of a profile (within
    PROFILE_END_WARN mm of arc length), where the result depends on data the profile does not have;
    and a wheelset lifted more than LIFT_WARN mm above its nominal height (the tape circle on the
    rail top, z = 0), checked for a jump of the height within 0.1 mm of lateral shift (the flange
    climbing onto the rail: the vertical placement at a prescribed shift then finds a state the
    wheelset cannot reach by rolling)."""
    out: list[str] = []
    concave = rail_orientation_warning(pl.pair.rail.curve.points, pl.pair.rail.curve.name)
    if concave and scene.geometry.rail_z == "down":
        out.append("placement: " + concave)
    wc = pl.pair.wheel_curve
    z_w_samples = wc.sampled(0.05)[2]      # the z of wc.sample(0.05), kept with the curve
    z_tip = float(z_w_samples[int(np.argmax(z_w_samples))])
    flanged = z_tip > 10.0            # a flange more than 10 mm above the tape circle
    rail_len = pl.pair.rail.curve.length
    for pg in st.patches:
        p = pg.patch
        z_w = float(wc.point(p.wheel_s)[1])
        if flanged and z_tip - z_w < FLANGE_TIP_WARN:
            out.append(f"placement: contact {z_tip - z_w:.2f} mm (radially) from the flange tip of the wheel "
                       f"(contact angle {math.degrees(pl.pair.mirror * p.delta):.1f} degrees): the wheel rides on its "
                       "flange; check [geometry] lateral_shift")
        if p.wheel_s < PROFILE_END_WARN or p.wheel_s > wc.length - PROFILE_END_WARN:
            out.append("placement: contact at an end of the wheel profile: the profile does not cover it")
        if p.s_range[0] < PROFILE_END_WARN or p.s_range[1] > rail_len - PROFILE_END_WARN:
            out.append(f"placement: contact at an end of the rail profile (rail arc length {p.s_range[0]:.2f} .. "
                       f"{p.s_range[1]:.2f} of {rail_len:.2f} mm): the profile does not cover it")
    lift = -pl.z_touch
    if lift > LIFT_WARN:
        msg = (f"placement: the wheelset stands {lift:.2f} mm above its nominal height (tape circle on the "
               "rail top)")
        try:
            jump = _height_jump(scene, pl, -0.1)
            if jump is not None and abs(jump) > JUMP_WARN:
                msg += (f", and {abs(jump):.2f} mm {'higher' if jump < 0 else 'lower'} than at 0.1 mm less "
                        "lateral shift: the height jumps (flange climbing onto the rail), a state the rolling "
                        "wheelset does not reach; check [geometry] lateral_shift")
        except (InputError, NoContactError, ConvergenceError):
            pass
        out.append(msg)
    return out


def _height_jump(scene: Scene, pl: "Placement", dy: float) -> float | None:
    """pl.z_touch less the touching height of the scene's wheel at ``dy`` mm more lateral shift (the
    lift check of :func:`placement_warnings`), or None where that height provably lies within
    JUMP_WARN of pl.z_touch.  With a given roll (or a single wheel) the wheelset keeps pl's
    orientation and its contact locus moves by dy: for |dy| < LOCUS_REACH_MARGIN the bounds of that locus
    (:func:`~conformal.geometry.search.touch_bounds`) decide without a contact search where they can;
    otherwise the touching height of :func:`first_touch` (the shifted pair taking pl's locus angles,
    :meth:`WheelRailPair.share_locus`).  Without a roll the wheelset's roll is that of the shifted
    scene (:func:`place_scene`)."""
    geo = scene.geometry
    shift = geo.lateral_shift + dy
    if geo.roll is None and geo.placement == "wheelset":
        return pl.z_touch - place_scene(scene.with_("geometry.lateral_shift", shift), touch_only=True,
                                        like=pl).z_touch
    if abs(dy) < LOCUS_REACH_MARGIN:
        z_low, z_high, _ = touch_bounds(pl.pair, pl.top, step=LOCUS_STEP, dy=pl.pair.mirror * dy)
        if abs(pl.z_touch - z_low) <= JUMP_WARN and abs(pl.z_touch - z_high) <= JUMP_WARN:
            return None
    pair = build_pair(geo, scene.base_dir, roll=pl.roll, lateral_shift=shift)
    pair.share_locus(pl.pair)
    return pl.z_touch - first_touch(pair, pl.top, step=LOCUS_STEP)


def _grid_options(scene: Scene) -> dict:
    geo, g = scene.geometry, scene.grid
    if g.explicit:
        return dict(explicit=(g.mx, g.my, g.dx, g.dy, g.xl, g.yl), theory=scene.model.theory)
    return dict(element_size=geo.element_size, n=g.n, scale=g.scale, theory=scene.model.theory)


def state_at(pair: WheelRailPair, top: RailTop, z: float, roll: float, scene: Scene, *,
             grids: bool = True) -> PairState:
    """Patches of the wheel at height z; without ``grids`` only the patches and their overlap
    (for Hertz-based balances, where the grid is not needed)."""
    wheel = pair.wheel(z)
    out = []
    try:
        patches = find_patches(wheel, pair.rail, top, d_comb=scene.geometry.patch_combine,
                               locus=pair_locus(pair, top, z))
    except InputError as exc:
        raise InputError(f"[geometry] lateral_shift: {exc}") from None
    for p in patches:
        if grids:
            grid, h, approach = planar_grid_for_patch(wheel, pair.rail, p, **_grid_options(scene))
        else:
            grid, h, approach = None, None, p.penetration
        if approach <= 0:
            continue
        A, B, ang = p.deepest.principal()
        out.append(PatchGeometry(p, grid, h, approach, A, B, ang))
    if not out:
        raise NoContactError("wheel lifted off: no grid element overlaps the rail")
    return PairState(pair, z, roll, out)


def _check_normal(sol, pg: PatchGeometry, warnings: list | None) -> None:
    """A warning when a normal solve of the balance did not converge."""
    if not sol.converged and warnings is not None:
        warnings.append(f"vertical balance: the normal problem of the patch at contact angle "
                        f"{pg.patch.delta:.3f} rad did not converge ({sol.iterations} iterations, "
                        f"residual {sol.residual:.2g})")


def _normal_field(fields, pg: PatchGeometry, side: str, pn: np.ndarray) -> PatchField:
    """The field of a balance's normal solution on patch ``pg`` (side frame) in the problem frame,
    with the tangential tractions of the field it started from (resampled), if any."""
    grid = _mirror_grid(pg.grid, None, side)[0]
    pn = pn if side == "right" else pn[:, ::-1]
    old = _nearest_field(fields, pg.patch.s_ref)
    if old is None or old.px is None:
        return PatchField(pg.patch.s_ref, grid, pn, here=True)
    px, py = resample(_moved_grid(old, pg.patch.s_ref, side), np.stack([old.px, old.py]), grid)
    return PatchField(pg.patch.s_ref, grid, pn, px, py, here=True)


# ----------------------------------------------------------------------------- placement of a scene
@dataclass(frozen=True, eq=False)
class Placement:
    pair: WheelRailPair
    top: RailTop
    roll: float          # track frame
    z_touch: float       # this wheel touches
    z_first: float       # the first wheel of the wheelset touches: [load] approach counts from here

    def approach(self, z: float) -> float:
        """The wheelset approach (mm) at height z: its vertical lowering below the height where its
        first wheel touches, the meaning of ``[load] approach`` (and of the reported ``approach``)."""
        return float(z - self.z_first)


def placed_pair(scene: Scene) -> tuple[WheelRailPair, RailTop, float, float | None]:
    """The scene's wheel over its rail before any height is searched: (the pair, its rail top, the
    wheelset roll (rad, track frame), the height where both wheels touch where the roll was found
    from it (:func:`~conformal.geometry.wheelrail.wheelset_roll`; None for a given roll)).
    :func:`place_scene` adds the touching heights; the surfaces at a known height need only this
    (conformal.contact_inp.combine)."""
    geo = scene.geometry
    if not isinstance(geo, WheelRailGeometry):
        raise InputError("[geometry] kind: not a wheel_rail scene")
    roll, z_both = geo.roll, None
    if roll is None and geo.placement == "wheelset":
        roll, z_both = wheelset_roll(geo, scene.base_dir)
    roll = 0.0 if roll is None else roll
    pair = build_pair(geo, scene.base_dir, roll=roll)
    return pair, RailTop.of(pair.rail), roll, z_both


def place_scene(scene: Scene, *, touch_only: bool = False, like: Placement | None = None) -> Placement:
    """The wheelset placed (roll, the wheel-rail pair) and the heights where this wheel and the first
    wheel of the wheelset touch; ``touch_only``: z_first is left equal to z_touch (the other wheel
    is not searched).  ``like``: a placement of the same scene at another lateral shift, whose
    wheel's contact locus this pair takes where its orientation is the same
    (:meth:`~conformal.geometry.placement.WheelRailPair.share_locus`).  The other wheel of a
    wheelset is searched only where its sampled locus does not show that it touches after this one
    (:func:`~conformal.geometry.wheelrail.touches_after`): z_first is then z_touch."""
    geo = scene.geometry
    base = scene.base_dir
    pair, top, roll, z_other = placed_pair(scene)
    if like is not None:
        pair.share_locus(like.pair)
    # the pair of a touch_only placement is not searched further: its locus is sampled for the height
    # alone (as finely as like's, whose locus angles it takes, where like is given); this wheel's height
    # from the search per trial height on the locus its contact searches use (bitwise the height that
    # keys a cache of FE influence numbers), refining only the candidate that can touch first
    step = None if not touch_only else LOCUS_STEP if like is not None else TOUCH_STEP
    z_touch = first_touch(pair, top, step=step)
    z_first = z_touch
    # the other wheel sets the height from which [load] approach (and the reported approach) counts
    if geo.placement == "wheelset" and not touch_only:
        if z_other is None:
            other = build_pair(geo, base, side="left" if pair.side == "right" else "right", roll=roll)
            # only its height is needed, and only where it touches first
            if not touches_after(other, z_touch, step=TOUCH_STEP):
                z_other = first_touch(other, step=TOUCH_STEP)
        if z_other is not None:
            z_first = min(z_touch, z_other)
    return Placement(pair, top, roll, z_touch, z_first)


#: the wheelset height is balanced when the linearised balance on the geometry of the last search
#: moves it by at most this (mm): the geometry (tangent plane, curvatures, grid extents) changes
#: by the lateral part dz sin(delta) of a lowering dz, far below the element size
BALANCE_ZTOL = 1e-4
#: at most this many geometry searches per balance before the bracketing search takes over
#: the largest approach (mm) of the vertical balance: the seed's steel wheels stay below 0.1 mm
MAX_APPROACH = 10.0
MAX_SEARCHES = 8
#: the one-patch passes keep a searched geometry while the height lies within this (mm) of it
#: (:func:`gap_rate` moves each element's distance to first order: 2e-7 mm of error at 2e-3 mm on a
#: flange patch; the creepages follow the height)
GEOMETRY_KEEP = 2e-3
#: ... and while its reference point moves by at most this (mm) along the rail profile
#: (Patch.s_ref_rate): the creepages and the contact angle are those of the reference point, which
#: on a wide tread patch moves 100-230 mm per mm of lowering (Manchester A-2.2 at 0-0.5 mm and
#: 5 mm; FX moves about 27 N per mm of it at 0.5 mm)
REFERENCE_KEEP = 5e-3
#: ... and where that range is shorter than this (mm; the error of a neighbour's extrapolated
#: height is 1e-4 to 5e-3 mm), the height is first set by force-prescribed normal solves
SETTLE_BELOW = 1e-3
#: the general balance of several patches keeps a searched geometry while the height moves at most
#: this (mm) from it (PairState.lowered: each element's distance at its own rate)
GEOMETRY_REUSE = 1e-2
#: the one-patch passes (:func:`one_patch_passes`) end when the height at which the contact solve's
#: normal force acts (from its approach) lies within this (mm) of the height its geometry and
#: creepages were taken at: the creep point follows the lowering (Patch.creep_point), so a creepage
#: changes by dz sin^2(delta) / R, 2e-7 for 1e-4 mm on a flange (measured: forces within 0.07 N of
#: passes taken to 1e-8 mm and 1e-8 W over the Manchester A-2.2 sequence)
DZ_FINAL = 1e-4
#: relative tolerance of the vertical force balance of the one-patch passes (a pass on a kept
#: geometry costs a contact solve started from the previous one: 10 times tighter than BALANCE_TOL)
ONE_PATCH_TOL = 1e-5
#: the solver tolerance of a pass whose normal force comes from the ratio FS/FN of another geometry
#: (the neighbour's, or one more than GEOMETRY_KEEP away), where ``[model] tol`` is tighter: it
#: seldom balances, its tractions only start the next pass and give it the ratio and the height,
#: and it is never taken as the answer (the Manchester A-2.2 sequence: 6-7 instead of 9-10 normal
#: and 1-2 instead of 2-3 tangential iterations in the first pass, the answers within 0.04 N of
#: passes all at 1e-6)
FIRST_PASS_TOL = 1e-4
#: the solver tolerance of the force-prescribed normal solve that settles the height before the
#: first contact solve of :func:`one_patch_passes` (cold or after a jump): it sets only the height
#: of the next search and the start of the first contact solve, which is solved to FIRST_PASS_TOL
#: and checks that height; never the answer (the Manchester A-2.2 sequence: 20-22 instead of
#: 27-28 iterations from the same start, forces within 0.02 N and heights within 1e-7 mm of
#: settle solves to 1e-6)
SETTLE_TOL = FIRST_PASS_TOL


@dataclass(frozen=True)
class BalanceCounts:
    """Work of one vertical balance: geometry (contact) searches and normal solves."""

    searches: int
    normal_solves: int
    bracketing: bool = False


def _fn_at(pg: PatchGeometry, scene: Scene, approach: float, warnings: list, counts: list,
           p_start: dict | None = None, key=None) -> float:
    """Normal force of a patch when its rigid approach along its normal is ``approach`` (mm), on the
    grid and undeformed distance of the patch's geometry (0 when it no longer touches)."""
    if approach <= 0:
        return 0.0
    if MODELS.accepts(scene.model.theory, GRID):
        counts[0] += 1
        start = None if p_start is None else p_start.get(key)
        try:
            sol = solve_normal(None, pg.grid, pg.h, approach=approach, material=scene.material,
                               tol=min(scene.model.tol, 1e-6), maxit=scene.model.maxit, p_start=start,
                               precondition=warm_precondition(pg.grid, start))
        except NoContactError:
            return 0.0
        if p_start is not None:
            p_start[key] = sol.pn
        _check_normal(sol, pg, warnings)
        return float(sol.FN)
    if not pg.hertzian:
        _raise_not_hertzian(pg)
    return hertz_from_curvatures(pg.A, pg.B, scene.material, approach=approach).FN


def linear_balance(st: PairState, scene: Scene, ratios=None, *, counts: list | None = None,
                   warnings: list | None = None, fields: list | None = None,
                   normal_force: float | None = None, settle: bool = False) -> tuple[float, list[float]]:
    """The lowering dz (mm, vertical) from the height of ``st`` at which the patches carry the wheel
    load, and their normal forces there (seed Eq. 46 with the height as the unknown):
    sum_i FN_i(a_i + dz cos d_i) (cos d_i + r_i sin d_i) = wheel_load, a_i the approach of patch i
    along its normal at the height of ``st``, r_i = FS_i/FN_i (:func:`_ratio`).

    The geometry of ``st`` is reused for every trial height: a vertical step dz moves the wheel by
    dz cos d_i along the normal of patch i (and by dz sin d_i in its tangent plane, which is left
    out: the caller searches the geometry again at the new height until the step is small).  One
    patch: FN = W / (cos d + r sin d) directly, one force-prescribed normal problem for its
    approach.  Several: secant steps on (F/W)^(2/3), nearly linear in dz for Hertz-like growth.
    Grid theories solve the half-space normal problem on the patch grids, the others use Hertz
    from the patch curvatures.  ``counts`` = [normal solves] is incremented; ``fields`` (a list of
    :class:`PatchField`, changed in place) starts the normal solves (resampled onto the patch
    grids) and receives the one-patch normal solution (with the tangential tractions of the field
    it started from: the start of the next contact solve).  ``normal_force``: one patch carries this (N) instead of W / (cos d + r sin d)
    (a secant step of the caller on the vertical force of the contact solves).  ``settle``: the
    one-patch solve only sets the height of the next geometry search and the start of a loose
    first contact solve (:func:`one_patch_passes`), never the answer: solved to SETTLE_TOL,
    and without a known field started from the patch's rigid overlap (:func:`_overlap_start`)."""
    W = scene.load.wheel_load
    counts = counts if counts is not None else [0]
    warnings = warnings if warnings is not None else []
    pgs = st.patches
    c = [math.cos(pg.patch.delta) for pg in pgs]
    w = [ci + _ratio(ratios, pg) * math.sin(pg.patch.delta) for ci, pg in zip(c, pgs)]
    on_grid = MODELS.accepts(scene.model.theory, GRID)
    if len(pgs) == 1 and w[0] > 0:
        pg, fn = pgs[0], (normal_force if normal_force is not None and normal_force > 0 else W / w[0])
        if on_grid:
            counts[0] += 1
            side = st.pair.side
            start = _normal_start(fields, pg, side)
            if settle and start is None:
                start = _overlap_start(pg)
            sol = solve_normal(None, pg.grid, pg.h, normal_force=fn, material=scene.material,
                               tol=SETTLE_TOL if settle else min(scene.model.tol, 1e-6),
                               maxit=scene.model.maxit, p_start=start, precondition=warm_precondition(pg.grid, start))
            _check_normal(sol, pg, warnings)
            a = float(sol.approach)
            if fields is not None:
                fields[:] = [_normal_field(fields, pg, side, sol.pn)]
        else:
            a = hertz_from_curvatures(pg.A, pg.B, scene.material, normal_force=fn).approach if pg.hertzian \
                else _raise_not_hertzian(pg)
            return (a - pg.hertz_approach) / c[0], [fn]
        return (a - pg.approach) / c[0], [fn]
    p_start: dict = {k: _normal_start(fields, pg, st.pair.side) for k, pg in enumerate(pgs)} if on_grid else {}
    cache: dict[float, list[float]] = {}

    def fns_at(dz: float) -> list[float]:
        if dz not in cache:
            out = []
            for k, pg in enumerate(pgs):
                a = (pg.approach if on_grid else pg.hertz_approach) + dz * c[k]
                out.append(_fn_at(pg, scene, a, warnings, counts, p_start, k))
            cache[dz] = out
        return cache[dz]

    def f(dz: float) -> float:
        return sum(fn * wk for fn, wk in zip(fns_at(dz), w)) - W

    main = max(range(len(pgs)), key=lambda k: pgs[k].approach)
    a_m, c_m = pgs[main].approach, c[main]
    # grid theories: the first trial height from Hertz on the patch curvatures (no grid solves),
    # where every patch is Hertzian and Hertz carries the load there
    x0 = _hertz_lowering(pgs, scene, c, w) if on_grid else None
    F0 = f(x0) + W if x0 is not None else 0.0
    if not F0 > 0:
        x0 = 0.0
        F0 = f(0.0) + W
    a0 = a_m + x0 * c_m
    x1 = x0 + ((a0 * ((W / F0) ** (2.0 / 3.0) - 1.0) / c_m) if F0 > 0 and a0 > 0 else a_m / c_m)
    x = secant_on_hertz_growth(f, W, x0, x1, tol=1e-7, maxit=12, xtol=1e-10, rtol=1e-12,
                               message="[load] wheel_load: the linearised vertical balance did not settle")
    return x, fns_at(x)


def _hertz_lowering(pgs: list, scene: Scene, c: list, w: list) -> float | None:
    """The lowering dz at which Hertz on the patch curvatures carries the wheel load,
    sum_i FN_i^Hertz(a_i + dz cos d_i) w_i = W (the start of a grid balance of several patches), or
    None where a patch is not Hertzian or the secant does not settle."""
    if not all(pg.hertzian for pg in pgs):
        return None
    W = scene.load.wheel_load

    def f(dz: float) -> float:
        total = 0.0
        for pg, ck, wk in zip(pgs, c, w):
            a = pg.approach + dz * ck
            if a > 0:
                total += hertz_from_curvatures(pg.A, pg.B, scene.material, approach=a).FN * wk
        return total - W

    main = max(range(len(pgs)), key=lambda k: pgs[k].approach)
    a_m, c_m = pgs[main].approach, c[main]
    F0 = f(0.0) + W
    x1 = (a_m * ((W / F0) ** (2.0 / 3.0) - 1.0) / c_m) if F0 > 0 else a_m / c_m
    try:
        return secant_on_hertz_growth(f, W, 0.0, x1, tol=1e-6, maxit=20, xtol=1e-10, rtol=1e-12, message="")
    except (ConvergenceError, ValueError, ZeroDivisionError):
        return None


def _raise_not_hertzian(pg: PatchGeometry):
    raise InputError(f"[model] theory: patch at contact angle {pg.patch.delta:.3f} rad is not Hertzian "
                     f"(relative curvatures A = {pg.A:.3g}, B = {pg.B:.3g} 1/mm); use theory = \"exact\"")


def balance_height(pl: Placement, scene: Scene, ratios=None, *, lowering: float | None = None,
                   start: PairState | None = None, counts_out: list | None = None, fields: list | None = None,
                   normal_force: float | None = None) -> tuple[float, PairState, list[float]]:
    """Height z at which sum_i FN_i (cos d_i + r_i sin d_i) = wheel_load, with r_i = FS_i/FN_i
    (side frame) the tangential-to-normal ratios of the patches (0: normal forces only).

    Newton-like on the height with the geometry searched once per trial height
    (:func:`linear_balance` on the patches found there gives the next height) until the step is
    below BALANCE_ZTOL; the state returned is that of the last search, at the balanced height.
    Start: ``start`` (a state of the same placement, e.g. the previous outer iteration), else
    ``lowering`` (mm below the touching height, e.g. the neighbour's in a sweep), else a Hertz
    estimate from the overlap at a small trial lowering.  Falls back to the bracketing root
    search on the vertical force (:func:`balance_height_bracketing`) when the searches do not
    settle in MAX_SEARCHES.  ``counts_out`` receives a :class:`BalanceCounts`."""
    on_grid = MODELS.accepts(scene.model.theory, GRID)
    warnings: list[str] = []
    counts = [0]
    searches = 0

    def search(z):
        nonlocal searches
        searches += 1
        return state_at(pl.pair, pl.top, z, pl.roll, scene, grids=on_grid)

    def overlap(z):
        nonlocal searches
        searches += 1
        return state_at(pl.pair, pl.top, z, pl.roll, scene, grids=False)

    st = start
    if st is None and lowering is not None and lowering > 0:
        try:
            st = search(pl.z_touch + lowering)
        except NoContactError:
            st = None
    if st is None:
        st = search(pl.z_touch + _estimated_lowering(pl, scene, search, overlap, warnings, counts))
    for _ in range(MAX_SEARCHES):
        del warnings[:]
        dz, fns = linear_balance(st, scene, ratios, counts=counts, warnings=warnings, fields=fields,
                                 normal_force=normal_force if len(st.patches) == 1 else None)
        z = st.z + dz
        if abs(dz) <= BALANCE_ZTOL and all(fn > 0 for fn in fns):
            if counts_out is not None:
                counts_out.append(BalanceCounts(searches, counts[0]))
            # the state at the balanced height: its approaches moved by dz cos d (first order)
            st = replace(st.lowered(dz), warnings=tuple(warnings))
            if not on_grid:     # the grids, keeping the approaches the balance used (locus penetration)
                balanced = st
                st = replace(state_at(pl.pair, pl.top, z, pl.roll, scene), warnings=tuple(warnings))
                if len(st.patches) != len(fns):
                    raise ConvergenceError("vertical balance: the patches on the grid differ from those of the "
                                           "overlap")
                st = replace(st, patches=[replace(pg, balance_approach=b.hertz_approach)
                                          for pg, b in zip(st.patches, balanced.patches)])
            return z, st, fns
        try:
            st = search(z)
        except NoContactError:
            break
    z, st, fns = balance_height_bracketing(pl, scene, ratios)
    if counts_out is not None:
        counts_out.append(BalanceCounts(searches, counts[0], bracketing=True))
    return z, st, fns


def _estimated_lowering(pl: Placement, scene: Scene, search, overlap, warnings: list, counts: list) -> float:
    """A Hertz-like estimate of the lowering (mm below the touching height) that carries the wheel
    load, from the force at a small trial lowering (doubled until it overlaps): the approach grows
    as FN^(2/3).  ``overlap(z)`` / ``search(z)``: the patches at height z without / with their
    grids (the grids where a patch is not Hertzian: its grid normal problem, counted in ``counts``)."""
    W = scene.load.wheel_load
    on_grid = MODELS.accepts(scene.model.theory, GRID)
    trial, F1 = 0.01, 0.0
    for _ in range(12):
        try:
            st0 = overlap(pl.z_touch + trial)
            if on_grid and not all(pg.hertzian for pg in st0.patches):
                st0 = search(pl.z_touch + trial)
            F1 = sum(_trial_force(pg, scene, warnings, counts) * math.cos(pg.patch.delta) for pg in st0.patches)
        except NoContactError:
            F1 = 0.0
        if F1 > 0:
            break
        trial *= 2.0
    else:
        raise ConvergenceError("[load] wheel_load: the vertical force does not grow when the wheel is lowered")
    lowering = trial * (W / F1) ** (2.0 / 3.0)       # Hertz: the approach grows as FN^(2/3)
    if not lowering <= MAX_APPROACH:      # beyond the profiles (wheel_load = 1e300: a search outside the rail)
        raise InputError(f"[load] wheel_load: {W:g} N would press the wheel about {lowering:.3g} mm into the rail "
                         f"(Hertz estimate), more than {MAX_APPROACH:g} mm: far beyond elastic contact "
                         f"(the seed's wheels: below 0.1 mm)")
    return lowering


def _trial_force(pg: PatchGeometry, scene: Scene, warnings: list, counts: list) -> float:
    """Normal force of a patch at its own approach for the first height estimate: Hertz where the
    patch is Hertzian, else its grid normal problem."""
    if pg.hertzian:
        return hertz_from_curvatures(pg.A, pg.B, scene.material, approach=pg.approach).FN
    if pg.grid is None:
        return _raise_not_hertzian(pg)
    return _fn_at(pg, scene, pg.approach, warnings, counts)


def balance_height_bracketing(pl: Placement, scene: Scene, ratios=None) -> tuple[float, PairState, list[float]]:
    """The reference balance (before issue 23): a bracketing root search on the vertical force
    FZ(z), every trial height with its own geometry search and normal solves (about 28 force
    evaluations per balance).  Kept as the fallback of :func:`balance_height` and for tests."""
    W = scene.load.wheel_load
    cache: dict[float, tuple[PairState, list[float]]] = {}
    warnings: list[str] = []
    on_grid = MODELS.accepts(scene.model.theory, GRID)

    def fz(z):
        if z not in cache:
            try:
                st = state_at(pl.pair, pl.top, z, pl.roll, scene, grids=on_grid) if z > pl.z_touch else None
            except NoContactError:      # just above the touching height no element overlaps yet
                st = None
            fns = [_fn_at(pg, scene, pg.approach, warnings, [0]) for pg in st.patches] if st else []
            cache[z] = (st, fns)
        st, fns = cache[z]
        if st is None:
            return -W
        total = 0.0
        for k, (pg, fn) in enumerate(zip(st.patches, fns)):
            r = _ratio(ratios, pg)
            d = pg.patch.delta
            total += fn * (math.cos(d) + r * math.sin(d))
        return total - W

    # first guess: Hertz-like growth FZ ~ dz^1.5 from a small trial lowering (doubled until the
    # overlap covers a grid element)
    trial = 0.01
    for _ in range(12):
        f1 = fz(pl.z_touch + trial) + W
        if f1 > 0:
            break
        trial *= 2.0
    else:
        raise ConvergenceError("[load] wheel_load: the vertical force does not grow when the wheel is lowered")
    dz = trial * (W / f1) ** (2.0 / 3.0)
    hi = pl.z_touch + 1.2 * dz
    for _ in range(30):
        if fz(hi) > 0:
            break
        hi = pl.z_touch + 2.0 * (hi - pl.z_touch)
    else:
        raise ConvergenceError("wheel_load: could not bracket the wheelset height")
    lo = max((z for z in cache if z > pl.z_touch and fz(z) < 0), default=pl.z_touch)
    z = brentq(fz, lo, hi, xtol=1e-9, rtol=1e-12, maxiter=100)
    del warnings[:]
    cache.pop(z, None)
    fz(z)
    st, fns = cache[z]
    if not on_grid:
        st = state_at(pl.pair, pl.top, z, pl.roll, scene)
        if len(st.patches) != len(fns):
            raise ConvergenceError("vertical balance: the patches on the grid differ from those of the overlap")
    return z, replace(st, warnings=tuple(warnings)), fns


def _ratio(ratios, pg: PatchGeometry) -> float:
    """Tangential-to-normal ratio of the nearest patch of a previous solve (by rail position)."""
    return _ratio_near(ratios, pg.patch.s_ref)


def _ratio_near(ratios, s: float) -> float:
    """The ratio of the (s_ref, FS/FN) entry nearest to rail arc length s (within 5 mm), else 0."""
    if not ratios:
        return 0.0
    best = min(ratios, key=lambda item: abs(item[0] - s))
    return best[1] if abs(best[0] - s) < 5.0 else 0.0


# ----------------------------------------------------------------------------- starting fields
@dataclass(frozen=True, eq=False)
class PatchField:
    """A solved patch's tractions as the start of a later solve of the same contact on another
    grid (a later height of the balance, the next position of a sweep): the rail arc length of its
    reference point and the tractions on its grid, in the problem frame (mirrored for a left
    wheel, as the contact problems); px, py None for a normal solve.  ``here``: solved at this
    position (the wheel's lateral place) by the one-patch passes: on a geometry searched again at
    another height it moves with its reference point along the rail (:func:`_moved_grid`); a
    neighbour's field is resampled where it lies."""

    s_ref: float
    grid: PlanarGrid
    pn: np.ndarray
    px: np.ndarray | None = None
    py: np.ndarray | None = None
    here: bool = False


def resample(src: PlanarGrid, values: np.ndarray, dst: PlanarGrid) -> np.ndarray:
    """``values`` (src's shape, per element; or a stack of such arrays, shape (k, mx, my), each
    resampled alike) bilinearly interpolated at the element centres of ``dst`` (both grids in
    their patch's tangent-plane coordinates about the reference point), 0 beyond src; equal to
    ``values`` where dst is src (and where a dst centre lies within 1e-9 elements of a src centre,
    the src value exactly)."""
    def axis(n_src, lo_src, d_src, n_dst, lo_dst, d_dst):
        f = (lo_dst + (np.arange(n_dst) + 0.5) * d_dst - lo_src) / d_src - 0.5   # src index coordinate
        # an element centre on a source centre takes its value alone: rounding of f (1e-15) would
        # otherwise leave a tiny pressure on the neighbours beyond the contact edge, which puts them
        # in the starting contact set (a converged start then took 8 iterations instead of 1)
        near = np.rint(f)
        f = np.where(np.abs(f - near) <= 1e-9, near, f)
        i0 = np.floor(f).astype(int)
        w = f - i0
        return np.clip(i0, -1, n_src) + 1, np.clip(i0 + 1, -1, n_src) + 1, w   # indices into the padded array

    if (src.mx, src.my, src.dx, src.dy, src.xl, src.yl) == (dst.mx, dst.my, dst.dx, dst.dy, dst.xl, dst.yl):
        return np.array(values, dtype=float)      # the same grid (the passes of a position)
    values = np.asarray(values, float)
    v = np.zeros(values.shape[:-2] + (values.shape[-2] + 2, values.shape[-1] + 2))   # (np.pad's zero border)
    v[..., 1:-1, 1:-1] = values
    ia, ib, wi = axis(src.mx, src.xl, src.dx, dst.mx, dst.xl, dst.dx)
    ja, jb, wj = axis(src.my, src.yl, src.dy, dst.my, dst.yl, dst.dy)
    # (the gathers by np.take: the values of v[..., ia, :] and rows[..., ja] at less cost)
    rows = (1.0 - wi)[:, None] * v.take(ia, axis=-2) + wi[:, None] * v.take(ib, axis=-2)
    return (1.0 - wj)[None, :] * rows.take(ja, axis=-1) + wj[None, :] * rows.take(jb, axis=-1)


def _nearest_field(fields, s_ref: float) -> PatchField | None:
    """The field of the patch nearest to rail arc length ``s_ref`` (within 5 mm), or None."""
    best = min(fields or (), key=lambda f: abs(f.s_ref - s_ref), default=None)
    return best if best is not None and abs(best.s_ref - s_ref) < 5.0 else None


def _moved_grid(f: PatchField, s_ref: float, side: str) -> PlanarGrid:
    """The grid of field ``f`` (problem frame) in the tangent-plane coordinates of a patch whose
    reference point lies at rail arc length ``s_ref``: a point of the rail at arc length s lies
    at eta = s - s_ref across the tangent plane (to the profile's curvature over the shift), so
    the field moves by its reference point's shift along the rail (mirrored for a left wheel).
    Only a field of this position (``f.here``): the pressure of a solve at the new height on the
    kept geometry lies where the new search puts it (0.5 mm of the Manchester A-2.2 sequence: the
    wide patch's reference point moves 1 mm between the searches; the first contact solve took 6
    instead of 19 iterations); a neighbour's patch is centred on its own reference point (moved,
    the neighbours' starts of 2-10 mm took 322 -> 376 normal iterations in all)."""
    shift = f.s_ref - s_ref if f.here else 0.0
    if shift == 0.0:
        return f.grid
    g = f.grid
    return PlanarGrid(g.mx, g.my, g.dx, g.dy, g.xl, g.yl + (shift if side == "right" else -shift))


def _normal_start(fields, pg: PatchGeometry, side: str) -> np.ndarray | None:
    """A starting pressure for the normal problem of patch ``pg`` (side frame) from the nearest
    known field, or None."""
    f = _nearest_field(fields, pg.patch.s_ref)
    if f is None:
        return None
    pn = resample(_moved_grid(f, pg.patch.s_ref, side), f.pn, _mirror_grid(pg.grid, None, side)[0])
    pn = pn if side == "right" else pn[:, ::-1]
    return pn if np.any(pn > 0) else None


def _overlap_start(pg: PatchGeometry) -> np.ndarray | None:
    """A starting pressure for a cold force-prescribed normal problem of patch ``pg`` (side frame):
    the square root of the rigid overlap, sqrt(approach - h) where > 0 (the solver scales it to
    the force).  Its support is the whole overlap, wider than the contact (Hertz: twice its area),
    which the iteration shrinks in fewer steps than it grows a narrower one: on the wide tread and
    gauge-corner patches of the Manchester A-2.2 sequence 10-12 instead of 20-22 iterations of the
    Hertz-like circular start at FIRST_PASS_TOL.  None where the patch does not overlap."""
    if pg.h is None or not pg.approach > 0:
        return None
    p = np.sqrt(np.maximum(pg.approach - pg.h, 0.0))
    return p if np.any(p > 0) else None


def _contact_start(fields, pg: PatchGeometry, problem: ContactProblem, side: str):
    """(pn, px, py) on the problem's grid from the nearest known field (px, py None from a normal
    solve), or None; ``side``: the wheel's (a field of this position moves mirrored on a left wheel,
    :func:`_moved_grid`)."""
    f = _nearest_field(fields, pg.patch.s_ref)
    if f is None:
        return None
    src = _moved_grid(f, pg.patch.s_ref, side)
    if f.px is None:
        pn = resample(src, f.pn, problem.grid)
        return (pn, None, None) if np.any(pn > 0) else None
    pn, px, py = resample(src, np.stack([f.pn, f.px, f.py]), problem.grid)   # one interpolation for all three
    return (pn, px, py) if np.any(pn > 0) else None


# ----------------------------------------------------------------------------- problems
def _mirror_grid(grid: PlanarGrid, h: np.ndarray | None, side: str) -> tuple[PlanarGrid, np.ndarray | None]:
    if side == "right":
        return grid, h
    g = PlanarGrid(grid.mx, grid.my, grid.dx, grid.dy, grid.xl, -(grid.yl + grid.my * grid.dy))
    return g, None if h is None else h[:, ::-1].copy()


def _kinematics_for(scene: Scene, pair: WheelRailPair, z: float, patch: Patch):
    """The patch's Kinematics (real frame) and the creepages (or None when given directly)."""
    k = scene.kinematics
    motion = wheelset_motion(scene)
    if motion is None:
        return k, None
    motion = motion.mirrored(pair.side)
    # the wheel material point: the reference point in the just-touching wheel (CONTACT's convention)
    c = creepages(pair.frame(z), motion, patch.creep_point, patch.normal)
    m = pair.mirror
    kin = replace(k, xi=float(c.xi), eta=float(m * c.eta), phi=float(m * c.phi), velocity=float(c.velocity))
    return kin, c


def patch_info(pair: WheelRailPair, st: PairState, pg: PatchGeometry, index: int) -> dict:
    """Positions and geometry of a patch in CONTACT's printed conventions (see module docstring)."""
    p, m = pg.patch, pair.mirror
    own = pair.rail.to_own(p.point[1:])
    wheel = pair.wheel(st.z)
    y_w, z_w = (float(v) for v in wheel.curve.point(p.wheel_s))
    return {
        "patch": index,
        "side": pair.side,
        "contact_angle": m * p.delta,
        "y_rail": float(m * own[0]),
        "z_rail": float(own[1]),
        "x_track": float(p.x_ref),
        "y_track": float(m * p.point[1]),
        "z_track": float(p.point[2]),
        "y_wheel": m * y_w,
        "z_wheel": z_w,
        "rolling_radius": float(wheel.rolling_radius(p.wheel_s)),
        "penetration": pg.approach,
        "n_lobes": p.n_lobes,
        "curvature_A": pg.A,
        "curvature_B": pg.B,
        "hertz_angle": m * pg.hertz_angle,
        "z_ws": st.z,
        "roll": st.roll,
        "s_rail": float(p.s_ref),
    }


def contact_angle_spread(pair: WheelRailPair, s_ref: float, half_width: float, samples: int = 41) -> float:
    """How much the rail's contact angle varies over a contact of lateral semi-axis ``half_width``
    (mm) about the rail arc length ``s_ref`` (degrees): the largest minus the smallest angle of the
    rail normal over [s_ref - half_width, s_ref + half_width] (the tangent-plane width taken as arc
    length along the profile)."""
    lo, hi = 0.0, pair.rail.curve.length
    s = np.clip(np.linspace(s_ref - half_width, s_ref + half_width, samples), lo, hi)
    n = pair.rail.normal(s)
    delta = np.arctan2(-n[:, 0], n[:, 1])
    return float(np.degrees(delta.max() - delta.min()))


def planar_theory_warning(theory: str, spread: float) -> str | None:
    """The warning of a planar (half-space, tangent-plane) theory on a patch whose contact angle
    varies by more than DELTA_SPREAD_WARN degrees: a conformal contact, for theory "conformal"."""
    if MODELS.accepts(theory, CONFORMAL_GEOMETRY) or not spread > DELTA_SPREAD_WARN:
        return None
    return (f"the contact angle varies by {spread:.1f} degrees over a contact patch: the half-space "
            f"(planar) theory {theory!r} is questionable here; this is a conformal contact "
            "([model] theory = \"conformal\")")


def _problem(scene: Scene, pair: WheelRailPair, st: PairState, pg: PatchGeometry, index: int, *,
             normal_force: float | None = None, approach: float | None = None) -> ContactProblem:
    grid, h = _mirror_grid(pg.grid, pg.h, pair.side)
    kin, c = _kinematics_for(scene, pair, st.z, pg.patch)
    hz = None
    if pg.hertzian:
        hz = hertz_from_curvatures(pg.A, pg.B, scene.material, normal_force=normal_force,
                                   approach=None if normal_force is not None else approach)
    info = patch_info(pair, st, pg, index)
    if c is not None:
        info.update(rolling_velocity=float(c.velocity))
    if hz is not None:
        info.update(hertz_a=hz.a, hertz_b=hz.b, hertz_pmax=hz.pmax)
    if st.warnings:
        info.update(balance_warnings=list(st.warnings))
    # [friction] angle_table: the friction at this patch's contact angle (CONTACT's V = 1, one value per patch)
    friction = scene.friction.at_angle(info["contact_angle"])
    return ContactProblem(material=scene.material, friction=friction, kinematics=kin, model=scene.model,
                          normal_force=normal_force, approach=None if normal_force is not None else approach,
                          hertz=hz, grid=grid, h=h, label=f"{scene.name}:{pair.side}:{index}", info=info)


def problems_at(scene: Scene, pl: Placement, st: PairState, fns: list[float] | None) -> list[ContactProblem]:
    out = []
    for i, pg in enumerate(st.patches):
        if fns is not None:
            out.append(_problem(scene, pl.pair, st, pg, i, normal_force=fns[i]))
        else:
            out.append(_problem(scene, pl.pair, st, pg, i, approach=pg.approach))
    return out


@dataclass(frozen=True)
class WarmStart:
    """What a neighbouring solve (the previous position of a sweep) knows: its wheelset lowering
    below the height where the wheel touches (mm), the tangential-to-normal ratios of its
    patches ((rail arc length s_ref, FS/FN) pairs, side frame) and their traction fields
    (:class:`PatchField`), the starting point of the next vertical balance and of its normal and
    contact solves.  With the neighbour's own neighbour (``from_result(..., previous)``) it also
    knows the slopes of the lowering and the ratios against the lateral shift and extrapolates
    them (:meth:`at`): the ratio of a patch with its own earlier value, the lowering where no
    patch jumped along the rail and none changed its number of lobes."""

    lowering: float | None = None
    ratios: tuple[tuple[float, float], ...] = ()
    fields: tuple[PatchField, ...] = ()
    shift: float | None = None                 # the neighbour's lateral shift (mm)
    step: float | None = None                  # its distance from its own neighbour (mm)
    lowering_slope: float = 0.0                # d lowering / d shift
    ratio_slopes: tuple[float, ...] = ()       # d (FS/FN) / d shift per entry of ratios
    lobes: tuple[int, ...] = ()                # the lobes of each patch (the contact's shape)

    @classmethod
    def from_result(cls, result: Result, previous: "WarmStart | None" = None) -> "WarmStart":
        """The warm start a result gives its next position; ``previous``: the warm start this result
        was solved from (the position before it), for the slopes."""
        b = result.extra.get("balance") or {}
        fields = tuple(PatchField(float(p.extra["s_rail"]), p.field.grid, p.field.pn, p.field.px, p.field.py)
                       for p in result.patches if p.field is not None and "s_rail" in p.extra)
        ratios = tuple((float(s), float(r)) for s, r in b.get("ratios", ()))
        shift, lowering = b.get("lateral_shift"), b.get("lowering")
        lobes = tuple(int(p.extra.get("n_lobes", 1)) for p in result.patches)
        out = cls(lowering, ratios, fields, shift, lobes=lobes)
        p = previous
        if (p is None or p.shift is None or shift is None or p.lowering is None or lowering is None
                or p.shift == shift or len(p.ratios) != len(ratios)):
            return out
        h = shift - p.shift
        slopes, same = [], []
        for s_ref, r in ratios:
            same.append(any(abs(s_ref - s0) < 5.0 for s0, _ in p.ratios))
            slopes.append((r - _ratio_near(p.ratios, s_ref)) / h if same[-1] else 0.0)
        # the contact jumped (no patch near one of the neighbour's) or changed its shape (lobes): no
        # slope of the lowering either (5 -> 5.5 mm, two lobes to one: the slope put the first
        # search at 6 mm 2.9e-3 mm off, the lowering alone 1.2e-3 mm)
        slope = (lowering - p.lowering) / h if all(same) and p.lobes == lobes else 0.0
        return replace(out, step=h, lowering_slope=slope, ratio_slopes=tuple(slopes))

    def at(self, shift: float) -> "WarmStart":
        """This warm start extrapolated linearly to the lateral shift ``shift`` (mm): the lowering and
        the ratios along their slopes, when the new step goes the same way as the last and is at
        most 1.5 times as long (unchanged otherwise, e.g. across a jump in the sequence)."""
        if self.step is None or self.shift is None or self.lowering is None:
            return self
        h = shift - self.shift
        if h == 0.0 or h / self.step < 0 or abs(h) > 1.5 * abs(self.step):
            return self
        lowering = self.lowering + self.lowering_slope * h
        if not lowering > 0:
            return self
        ratios = tuple((s, r + k * h) for (s, r), k in zip(self.ratios, self.ratio_slopes))
        return replace(self, lowering=lowering, ratios=ratios)


def loaded_state(scene: Scene, pl: Placement | None = None, *, ratios=None, grids: bool = True,
                 lowering: float | None = None, start: PairState | None = None, counts_out: list | None = None,
                 warn: bool = True, fields: list | None = None, normal_force: float | None = None
                 ) -> tuple[Placement, PairState, list[float] | None]:
    """The one wheel-rail sequence "place, then balance the wheel load or lower by the approach":
    (placement, the patches at the loaded height, the balanced normal forces or None).

    ``[load] wheel_load``: the height where the vertical forces balance it (:func:`balance_height`,
    with the tangential-to-normal ``ratios`` of a previous solve, starting from the state ``start``
    or the ``lowering`` below the touching height); ``[load] approach``: the height that far below
    the first touch of the wheelset.  ``grids=False`` skips the planar grids where only the patches
    are needed (conformal strips are built afterwards from the patches searched at the balanced
    height itself).  ``warn=False`` leaves out the placement
    warnings (added once by the caller)."""
    pl = pl or place_scene(scene)
    load = scene.load
    if load.wheel_load is not None:
        _, st, fns = balance_height(pl, scene, ratios, lowering=lowering, start=start, counts_out=counts_out,
                                    fields=fields, normal_force=normal_force)
        if not grids and st.geometry_offset > 0:   # the patches themselves (curved strips): at the height
            st = replace(state_at(pl.pair, pl.top, st.z, pl.roll, scene, grids=False), warnings=st.warnings)
    elif load.approach is None:
        raise InputError("[load] wheel_load: a wheel_rail scene needs wheel_load (N) or approach (mm)")
    else:
        lowering = load.approach
        if getattr(load, "approach_along", None) is not None and lowering == 0.0:
            # from the first touch: the patches where the wheel overlaps after the approach along the load
            # direction are found at the height of its vertical part (conformal.cases.conformal.StripBuilder
            # takes h back to the first touch)
            lowering += load.approach_along * math.cos(load.load_angle)
        st, fns = state_at(pl.pair, pl.top, pl.z_first + lowering, pl.roll, scene, grids=grids), None
    if warn:
        st = replace(st, placement_warnings=tuple(placement_warnings(scene, pl, st)))
    return pl, st, fns


def problems_from_wheel_rail(scene: Scene) -> list[ContactProblem]:
    """One planar ContactProblem per contact patch of the scene's wheel.

    With ``[load] wheel_load`` the normal forces balance the vertical load with normal forces only
    (Hertz, or the half-space normal problem for grid theories); :func:`solve_wheel_rail` adds the
    vertical components of the tangential forces.  With ``[load] approach`` each patch gets its own
    approach (the overlap at that wheelset height)."""
    pl, st, fns = loaded_state(scene)
    return problems_at(scene, pl, st, fns)


# ----------------------------------------------------------------------------- solving
def track_forces(result: Result, delta: float) -> np.ndarray:
    """(FX, FY, FZ) on the rail in the track frame of a patch result (real frame, delta = its
    contact angle): F = FN n + FX t1 + FY t2, n = (0, -sin d, cos d), t2 = (0, cos d, sin d)."""
    c, s = math.cos(delta), math.sin(delta)
    return np.array([result.FX, -result.FN * s + result.FY * c, result.FN * c + result.FY * s])


def _with_patch_extra(r: Result, problem: ContactProblem, pair: WheelRailPair | None = None) -> Result:
    F = track_forces(r, problem.info["contact_angle"])
    extra = dict(r.extra)
    extra.update(problem.info)
    if pair is not None and math.isfinite(r.b) and r.b > 0 and "s_rail" in problem.info:
        spread = contact_angle_spread(pair, problem.info["s_rail"], r.b)
        extra["contact_angle_spread_deg"] = spread
        planar = planar_theory_warning(r.theory, spread)
        if planar:
            extra["warnings"] = list(r.extra.get("warnings", ())) + [planar]
    extra.update(FX_track=float(F[0]), FY_track=float(F[1]), FZ_track=float(F[2]),
                 xi_patch=problem.kinematics.xi, eta_patch=problem.kinematics.eta,
                 phi_patch=problem.kinematics.phi)
    return replace(r, extra=extra)


def combine_patches(results: list[Result], problems: list[ContactProblem], theory: str, extra: dict,
                    pair: WheelRailPair | None = None) -> Result:
    """One Result for a wheel: FN, FX, FY, MZ the sums of the patch values (contact frames), the
    track-frame forces on the rail FX_track, FY_track, FZ_track in ``extra``; ``patches`` lists every
    patch with its contact_angle and y_rail."""
    patches = [_with_patch_extra(r, p, pair) for r, p in zip(results, problems)]
    main = max(patches, key=lambda r: r.FN)
    F = sum(track_forces(r, p.info["contact_angle"]) for r, p in zip(results, problems))
    ext = dict(extra)
    ext.update(FX_track=float(F[0]), FY_track=float(F[1]), FZ_track=float(F[2]), n_patches=len(patches),
               contact_angle=main.extra["contact_angle"], y_rail=main.extra["y_rail"],
               penetration=main.approach)
    return Result.combined(patches, theory, ext)


def _geometry_extra(scene: Scene, pl: Placement) -> dict:
    w, r = profile_curves(scene.geometry, scene.base_dir)
    return {"roll": pl.roll, "side": pl.pair.side, "smoothing_error_wheel": w.smoothing_error,
            "smoothing_error_rail": r.smoothing_error}


def _keep_range(st: PairState) -> float:
    """How far (mm) the height may move from the searched geometry of a one-patch state before it is
    searched again: GEOMETRY_KEEP, less where the reference point would move more than
    REFERENCE_KEEP along the rail profile (Patch.s_ref_rate)."""
    rate = abs(st.patches[0].patch.s_ref_rate)
    return GEOMETRY_KEEP if rate * GEOMETRY_KEEP <= REFERENCE_KEEP else REFERENCE_KEEP / rate


def one_patch_passes(scene: Scene, pl: Placement, st: PairState, fn: float, fields: list, ratios, *,
                     max_outer: int = 12, search=None, settle: bool = False):
    """The vertical balance of a one-patch wheel with the contact solve as its normal solve (seed
    Eq. 46, the height as the unknown; grid theory "exact"): each pass solves the contact problem
    on the patch geometry of ``st`` with the normal force ``fn`` prescribed; its approach a gives
    the height at which fn acts, z + (a - a_st) / cos(delta), and its FZ = FN cos d + FS sin d the
    next normal force (the fixed point W / (cos d + (FS/FN) sin d), then secant steps on FZ(FN)
    over the passes on one geometry).  The next pass keeps the searched geometry lowered to the
    predicted height (each element's distance moved at its own rate, :func:`gap_rate`, the
    creepages taken at the new height) while that height lies within :func:`_keep_range` of the
    searched one (GEOMETRY_KEEP, less where the reference point moves fast) and the contact stays
    off the grid's outermost elements; else the geometry is searched again there (``search(z)``).
    Where that range is below SETTLE_BELOW (or with ``settle``: a height estimated without a
    neighbour), a force-prescribed normal solve sets the height of a fresh search before the first
    contact solve (solved to SETTLE_TOL, cold from the patch's rigid overlap; its pressure, moved
    along the rail with the reference point, starts that contact solve).  Done when |FZ - W| <= ONE_PATCH_TOL W and the
    approach agrees with the height within DZ_FINAL.  A pass costs one contact solve, started from
    the latest tractions of the patch (``fields``); a pass whose normal force comes from another
    geometry's ratio (the first, one after a search more than GEOMETRY_KEEP away) is solved to
    FIRST_PASS_TOL and never the answer (a lean solve, ``ContactProblem.lean``: the forces, the
    approach and the tractions it passes on).

    Returns (state, results, problems, ratios, passes, fields, normal solves), or None when the contact leaves
    the one-patch case (another patch appears, the wheel lifts off, no convergence in
    ``max_outer`` passes): the caller then balances with :func:`loaded_state`."""
    W = scene.load.wheel_load
    mirror = pl.pair.mirror
    passes: list[tuple[float, float]] = []
    normal_solves = [0]
    # a geometry whose reference point moves fast with the height is kept over a short range only:
    # a force-prescribed normal solve (cheaper than a contact solve) finds the height first and the
    # geometry is searched there once (the linearised step lands within 2.2e-6 mm over 3.7e-3 mm on
    # the wide tread patches at 0-1.5 mm; the first contact solve checks it)
    if st is not None and len(st.patches) == 1 and st.z_geometry is None and (settle or _keep_range(st) < SETTLE_BELOW):
        warn: list[str] = []
        dz, _ = linear_balance(st, scene, None, counts=normal_solves, warnings=warn, fields=fields,
                               normal_force=fn, settle=True)
        try:
            st = st.lowered(dz) if abs(dz) <= _keep_range(st) else search(st.z + dz)
        except NoContactError:
            return None
        st = replace(st, warnings=tuple(warn))
    far = True          # the ratio FS/FN of this pass's normal force comes from another geometry
    for k in range(1, max_outer + 1):
        if st is None or len(st.patches) != 1:
            return None
        pg = st.patches[0]
        c = math.cos(pg.patch.delta)
        problem = problems_at(scene, pl, st, [fn])[0]
        loose = far and FIRST_PASS_TOL > problem.model.tol
        # a loose pass is never the answer: its forces, approach and tractions alone (lean)
        settings = dict(model=replace(problem.model, tol=FIRST_PASS_TOL), lean=True) if loose else {}
        problem = replace(problem, start=_contact_start(fields, pg, problem, pl.pair.side), **settings)
        r = solve_problem(problem)
        if r.field is not None:
            fields = [PatchField(pg.patch.s_ref, r.field.grid, r.field.pn, r.field.px, r.field.py, here=True)]
        if not (r.FN > 0 and r.approach > 0):
            return None
        dz = (r.approach - pg.approach) / c
        FZ = float(track_forces(r, problem.info["contact_angle"])[2])
        ratio = mirror * r.FY / r.FN
        ratios = [(pg.patch.s_ref, ratio)]
        balanced = abs(FZ - W) <= ONE_PATCH_TOL * W
        edge = r.field is not None and bool(border_sides(r.field.grid, np.asarray(r.field.pn) > 0))
        if balanced and abs(dz) <= DZ_FINAL and not edge and not loose:
            return st, [r], [problem], ratios, k, fields, normal_solves[0]
        passes.append((fn, FZ))
        fn_next = fn
        if not balanced:
            w = c + ratio * math.sin(pg.patch.delta)
            fn_next = W / w if w > 0 else fn
            if len(passes) >= 2 and passes[-1][1] != passes[-2][1] and passes[-1][0] != passes[-2][0]:
                (f0, F0), (f1, F1) = passes[-2], passes[-1]
                sec = f1 + (W - F1) * (f1 - f0) / (F1 - F0)
                fn_next = sec if 0.5 * f1 < sec < 2.0 * f1 else fn_next
        z_next = st.z + dz + r.approach * ((fn_next / fn) ** (2.0 / 3.0) - 1.0) / c
        z_geo = st.z if st.z_geometry is None else st.z_geometry
        warn_n: list[str] = []
        if not edge and fn_next != fn and abs(z_next - z_geo) > _keep_range(st) and _keep_range(st) < SETTLE_BELOW:
            # a fast-moving reference point (kept over less than SETTLE_BELOW): the height for the next
            # normal force from a force-prescribed normal solve on this geometry (Hertz's FN^(2/3) was
            # 4e-5 mm off on the wide patch at 0.5 mm, twice the range it is kept over)
            dz_n, _ = linear_balance(st, scene, None, counts=normal_solves, warnings=warn_n, fields=fields,
                                     normal_force=fn_next)
            z_next = st.z + dz_n
        far = abs(z_next - z_geo) > GEOMETRY_KEEP
        if abs(z_next - z_geo) > _keep_range(st) or edge:
            try:   # (a little deeper when the grid was too small: it then covers the patch)
                st = search(z_next + (GEOMETRY_KEEP / 2 if edge else 0.0))
            except NoContactError:
                return None
            passes = []
            if not balanced and len(st.patches) == 1:
                # the next normal force for the contact angle d of the geometry just searched, which
                # the next pass solves on: the fixed point W / (cos d + r sin d) (or the secant step)
                # scaled from the previous geometry's angle to it (that angle left the FZ of the pass
                # after the search 2.1e-5 W off at 0.5 mm, a third pass; with the new one 2.0e-6 W)
                d = st.patches[0].patch.delta
                w_new, w_old = math.cos(d) + ratio * math.sin(d), c + ratio * math.sin(pg.patch.delta)
                fn_next = fn_next * w_old / w_new if w_new > 0 and w_old > 0 else fn_next
        else:
            st = st.lowered(z_next - st.z)
        if warn_n:    # a normal solve that set this height did not converge
            st = replace(st, warnings=st.warnings + tuple(warn_n))
        fn = fn_next
    return None


def _general_passes(scene: Scene, pl: Placement, ratios, lowering, fields: list, counts: list, max_outer: int):
    """The vertical balance of any wheel: :func:`loaded_state` (the height from the normal
    problems, :func:`balance_height`), a contact solve per patch, the ratios FS/FN back into the
    balance on the kept geometry (a secant step on FZ(FN) for one patch) until the vertical force
    of the contact solves carries the wheel load.  Returns (state, height, results, problems,
    ratios, passes, extra normal solves)."""
    W = scene.load.wheel_load
    history = []
    _, st, fns = loaded_state(scene, pl, ratios=ratios, lowering=lowering, counts_out=counts, warn=False,
                              fields=fields)
    extra_normal = 0
    passes: list[tuple[float, float]] = []      # (FN, FZ) of the passes of a one-patch wheel
    for outer in range(1, max_outer + 1):
        z = st.z
        problems = problems_at(scene, pl, st, fns)
        if MODELS.accepts(scene.model.theory, WARM_START):   # the latest tractions of this patch start the iterations
            problems = [replace(p, start=_contact_start(fields, pg, p, pl.pair.side)) for p, pg in zip(problems, st.patches)]
        results = [solve_problem(p) for p in problems]
        fields = [PatchField(pg.patch.s_ref, r.field.grid, r.field.pn, r.field.px, r.field.py)
                  for pg, r in zip(st.patches, results) if r.field is not None]
        FZ = sum(track_forces(r, p.info["contact_angle"])[2] for r, p in zip(results, problems))
        history.append({"z_ws": z, "FZ_track": float(FZ)})
        # side-frame ratio FS/FN (mirroring flips both FS and the angle: the product is invariant)
        ratios = [(pg.patch.s_ref, pl.pair.mirror * r.FY / r.FN if r.FN > 0 else 0.0)
                  for pg, r in zip(st.patches, results)]
        balanced = abs(FZ - W) <= BALANCE_TOL * W
        if balanced and st.geometry_offset <= BALANCE_ZTOL:
            break
        # one patch: a secant step on FZ(FN) over the passes (the fixed point FN = W / (cos d + r sin d)
        # converges slowly in flange contact, where FS sin d carries a third of the load)
        fn_next = None
        if len(st.patches) == 1:
            passes.append((fns[0], FZ))
            if len(passes) >= 2 and passes[-1][1] != passes[-2][1] and passes[-1][0] != passes[-2][0]:
                (f0, F0), (f1, F1) = passes[-2], passes[-1]
                fn_next = f1 + (W - F1) * (f1 - f0) / (F1 - F0)
                fn_next = fn_next if 0.5 * f1 < fn_next < 2.0 * f1 else None
        if balanced:      # the ratios have settled on the kept geometry: search it at the balanced height
            _, st, fns = loaded_state(scene, pl, ratios=ratios, lowering=st.z - pl.z_touch, counts_out=counts,
                                      warn=False, fields=fields, normal_force=fns[0] if len(fns) == 1 else None)
            passes = []   # a secant step spans passes on one geometry
            continue
        # the ratios changed: balance again on the same geometry (seed Eq. 46, linearised in the height)
        n = [0]
        warn: list[str] = []
        dz, fns2 = linear_balance(st, scene, ratios, counts=n, warnings=warn, fields=fields,
                                  normal_force=fn_next)
        extra_normal += n[0]
        if all(fn > 0 for fn in fns2) and len(fns2) == len(st.patches):
            st, fns = replace(st.lowered(dz), warnings=tuple(warn)), fns2
            if st.geometry_offset > GEOMETRY_REUSE:   # too far from the searched geometry: search again
                _, st, fns = loaded_state(scene, pl, ratios=ratios, lowering=st.z - pl.z_touch, counts_out=counts,
                                          warn=False, fields=fields, normal_force=fn_next)
                passes = []
        else:
            _, st, fns = loaded_state(scene, pl, ratios=ratios, lowering=st.z - pl.z_touch, counts_out=counts,
                                      warn=False)
    else:
        raise ConvergenceError(f"[load] wheel_load: the vertical balance did not converge in {max_outer} "
                               f"iterations (FZ = {FZ:.1f} N for {W:g} N)")
    return st, z, results, problems, ratios, len(history), extra_normal


def _one_patch_start(scene: Scene, pl: Placement, warm: "WarmStart", fields: list, counts: list, max_outer: int):
    """The start of :func:`one_patch_passes` and the passes: the patches searched at the
    neighbour's lowering with FN = W / (cos d + r sin d) from its ratio, or without a neighbour the
    normal-problem balance (:func:`loaded_state`); None (and the general balance) when that gives
    other than one patch or the passes leave the one-patch case.  Returns (state, results, problems,
    ratios, passes, searches) with the searches of the passes (those of a balance are in ``counts``)."""
    W = scene.load.wheel_load
    ratios = list(warm.ratios) or None
    searches = [0]

    def search(z):
        searches[0] += 1
        return state_at(pl.pair, pl.top, z, pl.roll, scene)

    st, fn, settle = None, None, False
    if warm.lowering is not None and warm.lowering > 0:
        try:
            st = search(pl.z_touch + warm.lowering)
        except NoContactError:
            st = None
    else:       # no neighbour: the Hertz-like estimate, its height then set by one normal solve
        def overlap(z):
            searches[0] += 1
            return state_at(pl.pair, pl.top, z, pl.roll, scene, grids=False)

        trial = [0]
        st = search(pl.z_touch + _estimated_lowering(pl, scene, search, overlap, [], trial))
        counts.append(BalanceCounts(0, trial[0]))
        settle = True
    # a one-patch neighbour's FS/FN starts every patch found, also one that jumped more than 5 mm
    # along the rail (5 mm, 6.5 mm: FS/FN -0.30 -> -0.28 and -0.29 -> -0.27, where 0 gave FN 8 %
    # and 60 % off): the wheelset's lateral creepage sets it on either
    one_ratio = ratios[0][1] if ratios is not None and len(ratios) == 1 else None
    if st is not None and one_ratio is not None:
        ratios = [(pg.patch.s_ref, one_ratio) for pg in st.patches]
    if st is not None and len(st.patches) > 1 and one_ratio is not None:
        # a one-patch neighbour and several patches here (5 mm: the two lobes of the coming two-lobe
        # patch): the height where Hertz on their curvatures carries the load, searched before any
        # normal solve, often joins them into one patch
        c = [math.cos(pg.patch.delta) for pg in st.patches]
        w = [ci + _ratio(ratios, pg) * math.sin(pg.patch.delta) for ci, pg in zip(c, st.patches)]
        dz = _hertz_lowering(st.patches, scene, c, w)
        if dz is not None and abs(dz) > GEOMETRY_KEEP:
            try:
                st = search(st.z + dz)
            except NoContactError:
                pass
            ratios = [(pg.patch.s_ref, one_ratio) for pg in st.patches]
    if st is None or len(st.patches) != 1:   # no neighbour, or the contact changed: the normal balance
        _, st, fns = loaded_state(scene, pl, ratios=ratios, counts_out=counts, warn=False, fields=fields,
                                  lowering=warm.lowering, start=st)
        fn = fns[0] if len(fns) == 1 else None
    if len(st.patches) != 1:
        return None
    if fn is None:
        d = st.patches[0].patch.delta
        w = math.cos(d) + _ratio(ratios, st.patches[0]) * math.sin(d)
        if not w > 0:
            return None
        fn = W / w
    out = one_patch_passes(scene, pl, st, fn, list(fields), ratios, max_outer=max_outer, search=search,
                           settle=settle)
    if out is None:
        return None
    st, results, problems, ratios, n, _, n_normal = out
    return st, results, problems, ratios, n, searches[0], n_normal


def solve_wheel_rail(scene: Scene, *, max_outer: int = 12, warm: WarmStart | None = None) -> Result:
    """Solve a wheel-rail scene with a planar model (one tangent-plane problem per patch): patches,
    vertical balance including the tangential forces (iterated), and the combined result with
    track-frame totals.  (Any model: :func:`conformal.cases.solve_wheel_rail`.)  ``warm``: the
    :class:`WarmStart` of a neighbouring solve (a sweep's previous position); ``extra["balance"]``
    counts the geometry searches, normal and tangential solves of the balance and carries the
    next position's warm start."""
    if MODELS.accepts(scene.model.theory, CURVED_STRIP):   # one curved grid per wheel: conformal.cases.conformal
        raise InputError("[model] theory: the conformal theory solves a wheel on ONE curved strip: "
                         "conformal.cases.solve_wheel_rail (or conformal.solve) dispatches it")
    pl = place_scene(scene)
    theory = scene.model.theory
    geo_extra = _geometry_extra(scene, pl)
    if scene.load.wheel_load is None:
        _, st, _ = loaded_state(scene, pl)
        problems = problems_at(scene, pl, st, None)
        results = [solve_problem(p) for p in problems]
        ext = {"z_ws": st.z, **geo_extra}
        if st.placement_warnings:
            ext["warnings"] = list(st.placement_warnings)
        out = combine_patches(results, problems, theory, ext, pl.pair)
        return replace(out, approach=pl.approach(st.z))
    W = scene.load.wheel_load
    warm = (warm or WarmStart()).at(scene.geometry.lateral_shift)
    ratios = list(warm.ratios) or None
    counts: list[BalanceCounts] = []
    # the latest tractions per patch (the neighbour's, then the balance's normal solutions and the
    # contact solves): resampled onto each new grid, they start the normal and contact solves
    fields: list[PatchField] = list(warm.fields)
    one = _one_patch_start(scene, pl, warm, fields, counts, max_outer) if MODELS.accepts(theory, WARM_START) else None
    if one is not None:
        st, results, problems, ratios, n_passes, searches, extra_normal = one
        z = st.z
        counts.append(BalanceCounts(searches, 0))
    else:
        st, z, results, problems, ratios, n_passes, extra_normal = _general_passes(
            scene, pl, ratios, warm.lowering, fields, counts, max_outer)
    st = replace(st, placement_warnings=tuple(placement_warnings(scene, pl, st)))
    balance = {"searches": sum(c.searches for c in counts),
               "normal_solves": sum(c.normal_solves for c in counts) + extra_normal,
               "tangential_solves": n_passes * len(problems), "bracketing": any(c.bracketing for c in counts),
               "lowering": float(z - pl.z_touch), "ratios": [[float(a), float(b)] for a, b in ratios],
               "one_patch_passes": one is not None, "lateral_shift": float(scene.geometry.lateral_shift)}
    extra = {"z_ws": z, **geo_extra, "wheel_load": W, "balance_iterations": n_passes, "balance": balance}
    if st.warnings or st.placement_warnings:
        extra["warnings"] = list(st.warnings) + list(st.placement_warnings)
    out = combine_patches(results, problems, theory, extra, pl.pair)
    return replace(out, approach=pl.approach(z), converged=out.converged and not st.warnings)


def curved_creepages(pair: WheelRailPair, z: float, motion: WheelsetMotion, grid, patch: Patch) -> Creepages:
    """Creepages along the profile of a curved grid (one value per element column js, real frame):
    the spin phi(s) = (omega_r - omega_w) . n(s) / V follows the contact angle delta(s) across the
    patch (seed Eq. 61 at every element centre).

    The wheel material point of column s is the rule of :attr:`Patch.creep_point` (CONTACT's)
    applied per column: the rail point R(s) moved by the patch's penetration along the local
    normal n(s), i.e. the point that lies on the rail in the just-touching wheel; the conformal
    solver's own just-touching gap is h(s) - approach along the same normals.  At the reference
    column this is the planar path's point, so both give the same creepages there.  (The wheel
    surface point on the local normal, used before, sits at the local overlap instead: an offset
    of (penetration - overlap(s)) |omega| / V in the creepages, 1e-5 .. 1e-4.)"""
    wheel = pair.wheel(z)
    side_yz = np.c_[grid.y, grid.z] @ pair.rail.rotation.T + np.asarray(pair.rail.origin)
    n_side = grid.normal @ pair.rail.rotation.T
    R = np.c_[np.full(grid.ms, patch.x_ref), side_yz]
    nrm = np.c_[np.zeros(grid.ms), n_side]
    c = creepages(wheel.frame, motion.mirrored(pair.side), R + patch.penetration * nrm, nrm)
    m = pair.mirror
    return Creepages(xi=c.xi, eta=m * c.eta, phi=m * c.phi, velocity=c.velocity)


def wheel_surface_slip(pair: WheelRailPair, z: float, motion: WheelsetMotion, grid, x_ref: float,
                       h: np.ndarray, penetration: float) -> np.ndarray:
    """Per-element change of the rigid slip (2, mx, ms; side frame, creepage units) for CONTACT's
    conformal rigid slip (module 1, D = 4; its m_wr_rigslip): the wheel's velocity taken at its own
    undeformed surface point of each element, R(x, s) - h(x, s) n(s) (h: the signed distance along
    the local normal, < 0 in the overlap), the rail's at R(x, s), and both projected on their mean
    direction in the (x, n) plane (the "mid-plane", equal materials: the average of the two
    velocities relative to the moving contact frame) before the x components are subtracted;
    instead of the x components of the velocities at the point of :func:`curved_creepages`,
    R(s) + penetration n(s).  Both change the creepage by the order of the overlap over the wheel
    radius, (x / R)^2 along x and (penetration + h) / R across."""
    wheel = pair.wheel(z)
    side_yz = np.c_[grid.y, grid.z] @ pair.rail.rotation.T + np.asarray(pair.rail.origin)
    n_side = grid.normal @ pair.rail.rotation.T
    mx, ms = grid.mx, grid.ms
    R = np.empty((mx, ms, 3))
    R[..., 0] = x_ref + grid.x[:, None]
    R[..., 1:] = side_yz[None, :, :]
    nrm = np.zeros((mx, ms, 3))
    nrm[..., 1:] = n_side[None, :, :]
    own = motion.mirrored(pair.side)
    frame = wheel.frame
    at_touch = creepages(frame, own, R + penetration * nrm, nrm)
    p = R - np.asarray(h, float)[..., None] * nrm
    at_wheel = creepages(frame, own, p, nrm)
    # velocities relative to the contact frame that moves with the wheelset (conformal.geometry.kinematics)
    omega = own.roll_rate * np.array([1.0, 0.0, 0.0]) + own.yaw_rate * frame.e_d + own.pitch_velocity * frame.a
    v_w = np.cross(omega, p - frame.O)
    v_r = -np.array([own.speed, own.lateral_velocity, own.vertical_velocity])
    vwx, vwn = v_w[..., 0], np.einsum("...i,...i->...", v_w, nrm)
    vrx, vrn = v_r[0] + 0.0 * vwx, np.einsum("...i,...i->...", np.broadcast_to(v_r, nrm.shape), nrm)
    mx_, mn_ = 0.5 * (vrx + vwx), 0.5 * (vrn + vwn)
    length = np.hypot(mx_, mn_) * np.sign(-mx_)          # rolling in +x: the mean points to -x
    rail_x = -(vrx * mx_ + vrn * mn_) / length
    wheel_x = -(vwx * mx_ + vwn * mn_) / length
    xi = (rail_x - wheel_x) / at_wheel.velocity
    return np.stack([xi - at_touch.xi, at_wheel.eta - at_touch.eta])


def curved_problems_from_wheel_rail(scene: Scene):
    """Curved-grid versions of the patches: a list of (CurvedGrid, h, approach, info) per patch at the
    height found by :func:`problems_from_wheel_rail`'s normal balance (for the conformal theory).
    With ``[kinematics] speed`` the info holds the creepages per element column (xi_s, eta_s, phi_s)."""
    pl, st, _ = loaded_state(scene)
    wheel = pl.pair.wheel(st.z)
    out = []
    geo, g = scene.geometry, scene.grid
    for i, pg in enumerate(st.patches):
        grid, h, approach = curved_grid_for_patch(wheel, pl.pair.rail, pg.patch, element_size=geo.element_size,
                                                  n=g.n, scale=g.scale, side=pl.pair.side, theory=scene.model.theory)
        info = patch_info(pl.pair, st, pg, i)
        motion = wheelset_motion(scene)
        if motion is not None:
            c = curved_creepages(pl.pair, st.z, motion, grid, pg.patch)
            info.update(xi_s=c.xi, eta_s=c.eta, phi_s=c.phi, rolling_velocity_s=c.velocity)
        out.append((grid, h, approach, info))
    return out


def secant_on_hertz_growth(f, W: float, x0: float, x1: float, *, tol: float, maxit: int, xtol: float,
                           rtol: float, message: str) -> float:
    """The lowering dz with f(dz) = 0, f = F(dz) - W increasing (a total force against its target W):
    secant steps on (F/W)^(2/3) - 1, nearly linear in dz for Hertz-like growth, from x0, x1 until
    |f| <= tol W; Brent's method on the bracket the steps found if they do not settle in ``maxit``
    steps; ConvergenceError(``message``) without a bracket."""
    def g(dz: float) -> float:
        v = f(dz) / W + 1.0
        return math.copysign(abs(v) ** (2.0 / 3.0), v) - 1.0

    g0, g1 = g(x0), g(x1)
    pts = [(x0, g0), (x1, g1)]
    for _ in range(maxit):
        if abs(f(x1)) <= tol * W:
            return x1
        if g1 == g0:
            break
        x0, g0, x1 = x1, g1, x1 - g1 * (x1 - x0) / (g1 - g0)
        g1 = g(x1)
        pts.append((x1, g1))
    neg = [x for x, v in pts if v < 0]
    pos = [x for x, v in pts if v > 0]
    if not (neg and pos):
        raise ConvergenceError(message)
    return brentq(f, max(neg), min(pos), xtol=xtol, rtol=rtol)
