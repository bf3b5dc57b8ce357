"""Wheel-rail geometry of a scene: profile curves, the pair of a side placed on the track, and the
heights at which the wheels touch (no contact mechanics here; the wheel-rail cases that balance
loads and solve contact problems are :mod:`conformal.cases.wheelrail`).

1. profiles -> smoothing splines (``smoothing``), rail placed on the track (gauge, cant),
   wheelset placed (lateral shift, yaw, roll; the roll found so that both wheels touch when it
   is not given), see :mod:`conformal.geometry.placement`;
2. the height at which the wheel of ``side`` first touches its rail (contact search, the seed
   paper's Eqs. 54-56).
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from scipy.optimize import brentq

from conformal.errors import ConvergenceError, InputError, NoContactError
from conformal.geometry.placement import WheelRailPair, make_pair
from conformal.geometry.profiles import builtin_flange_back, load_profile
from conformal.geometry.search import TOUCH_STEP, RailTop, touch_bounds, touch_height, touch_point
from conformal.geometry.spline import ProfileCurve, fit_curve
from conformal.scene import WheelRailGeometry


#: the largest distance (mm) of a profile's points from its smoothing spline: 0.1 mm is twice a
#: typical elastic approach of a wheel on a rail; measured profiles need 0.01-0.05 mm (smoothing 1-20
#: mm on S1002/UIC60), smoothing = 100 mm moves them by 0.5-1.3 mm and 1000 mm by 11-24 mm
MAX_SMOOTHING_ERROR = 0.1


# ----------------------------------------------------------------------------- set-up
@lru_cache(maxsize=32)
def _curve(spec: str, kind: str, base_dir: str, smoothing: float, z_up: bool | None = False,
           mirror_y: bool = False) -> ProfileCurve:
    prof = load_profile(spec, kind, base_dir, z_up=z_up, mirror_y=mirror_y)
    return fit_curve(prof.points, smoothing, prof.name)


def _z_up(value: str) -> bool | None:
    """``[geometry] wheel_z`` / ``rail_z``: "up" True, "down" False, "auto" None (CONTACT's MIRRORZ = 0)."""
    return None if value == "auto" else value == "up"


def _smoothing(geo, kind: str) -> float:
    own = getattr(geo, f"{kind}_smoothing", None)
    return float(geo.smoothing if own is None else own)


def profile_curves(geo: WheelRailGeometry, base_dir: str | Path = ".") -> tuple[ProfileCurve, ProfileCurve]:
    """(wheel, rail) smoothing-spline curves of a scene's profiles (cached)."""
    try:
        w = _curve(geo.wheel_profile, "wheel", str(base_dir), _smoothing(geo, "wheel"),
                   _z_up(getattr(geo, "wheel_z", "down")), bool(getattr(geo, "wheel_mirror_y", False)))
    except InputError as exc:
        raise InputError(f"[geometry] wheel_profile: {exc}") from None
    try:
        r = _curve(geo.rail_profile, "rail", str(base_dir), _smoothing(geo, "rail"),
                   _z_up(getattr(geo, "rail_z", "down")), bool(getattr(geo, "rail_mirror_y", False)))
    except InputError as exc:
        raise InputError(f"[geometry] rail_profile: {exc}") from None
    limit = float(getattr(geo, "max_smoothing_error", MAX_SMOOTHING_ERROR))
    for c, what in ((w, "wheel"), (r, "rail")):
        if c.smoothing_error > limit:
            key = f"{what}_smoothing" if getattr(geo, f"{what}_smoothing", None) is not None else "smoothing"
            raise InputError(f"[geometry] {key}: a wavelength of {_smoothing(geo, what):g} mm moves the {what} profile "
                             f"{c.name} up to {c.smoothing_error:.3g} mm from its points (at most "
                             f"{limit:g} mm, [geometry] max_smoothing_error): it is no longer that profile; the "
                             "default is 1 mm")
    # the radius at each wheel-profile point, wheel_radius + z (z down), must be positive
    rho_min = float(geo.wheel_radius) + float(w.points[:, 1].min())
    if rho_min <= 0.0:
        raise InputError(f"[geometry] wheel_radius: {geo.wheel_radius:g} mm leaves the wheel profile {w.name} a "
                         f"radius of {rho_min:.3g} mm at its highest point (z = {w.points[:, 1].min():.3g} mm); "
                         "the nominal rolling radius must exceed the profile's height")
    return w, r


def build_pair(geo: WheelRailGeometry, base_dir: str | Path = ".", *, side: str | None = None,
               roll: float | None = None, lateral_shift: float | None = None) -> WheelRailPair:
    wc, rc = profile_curves(geo, base_dir)
    return make_pair(wc, rc, side=side or geo.side, placement=geo.placement,
                     lateral_shift=geo.lateral_shift if lateral_shift is None else lateral_shift,
                     roll=(geo.roll or 0.0) if roll is None else roll, yaw=geo.yaw,
                     rail_cant=geo.rail_cant, gauge=geo.gauge, gauge_height=geo.gauge_height,
                     flange_back=geo.flange_back,
                     flange_back_pos=(geo.flange_back_pos if geo.flange_back_pos is not None
                                      else builtin_flange_back(geo.wheel_profile)),
                     wheel_radius=geo.wheel_radius)


def _position_key(pair: WheelRailPair) -> str:
    """The scene key to blame when no contact is found: the yaw when it is the larger cause."""
    yaw = abs(pair.pose.yaw)
    return "yaw" if yaw > 0.02 else "lateral_shift"


def first_touch(pair: WheelRailPair, top: RailTop | None = None, *, step: float | None = None) -> float:
    """Wheelset height (side frame, z down, mm) at which the wheel of ``pair`` first touches its rail.

    ``step``: None searches the wheel's contact locus sampled as the later contact searches of the
    pair sample it, with a global search per trial height
    (:func:`~conformal.geometry.search.touch_height`, the locus kept with the pair; Newton-Raphson
    only from the locus minimum that can touch first, ``deepest_only``); a step (mm of wheel
    profile) samples it that finely and searches it once
    (:func:`~conformal.geometry.search.touch_point`: the same height to rounding, measured within
    3.4e-13 mm).  :data:`~conformal.geometry.search.LOCUS_STEP` is the locus the later contact
    searches use (kept with the pair: :func:`~conformal.cases.wheelrail.place_scene`),
    :data:`~conformal.geometry.search.TOUCH_STEP` a coarser one for a pair whose contacts are not
    searched further.
    """
    key = _position_key(pair)
    try:
        if step is None:
            z, sr = touch_height(pair, top, deepest_only=True)
            c = sr.contacts[0]
        else:
            z, c = touch_point(pair, top, step=step)
    except NoContactError as exc:
        raise InputError(f"[geometry] {key}: the {pair.side} wheel does not lie over its rail "
                         f"at this position ({exc})") from None
    except (InputError, ConvergenceError) as exc:
        raise InputError(f"[geometry] {key}: no contact point for the {pair.side} wheel at this "
                         f"position ({exc})") from None
    if c.at_end:
        raise InputError(f"[geometry] {key}: the {pair.side} wheel would touch the rail at the end "
                         f"of a profile (rail y = {float(pair.rail.to_own(c.rail_point[1:])[0]):.2f} mm, "
                         f"wheel y = {c.y_wheel:.2f} mm): the profiles do not cover this position")
    return z


#: mm of wheel profile between the locus samples of the first look of :func:`touches_after`: where
#: the bounds of that coarse locus already show the wheel touching after z, the finer one is not
#: sampled (a fifth of its samples).  Its bounds hold the searched height on the Manchester A-2.2
#: positions of both wheels, the tread -> flange sweep and the flange-climbing jump
#: (tests/unit/test_touch_shortcuts.py), the lower one at most 0.046 mm below it (flange: the rail
#: top's chords) and 2e-4 .. 9e-4 mm on the other wheel's treads, which touch 0.0017 mm and more
#: after the right wheel at 0.5 .. 10 mm: all decided here
AFTER_STEP = 0.5


def touches_after(pair: WheelRailPair, z: float, top: RailTop | None = None, *, step: float = TOUCH_STEP) -> bool:
    """Whether the wheel of ``pair`` provably first touches its rail below the height z (side frame,
    z down, mm), i.e. after a wheel that touches at z, from its contact locus sampled every ``step``
    mm alone (:func:`~conformal.geometry.search.touch_bounds`: the lower bound of its touching height
    more than 1e-9 mm beyond z, and the touch away from the profiles' ends, where
    :func:`first_touch` would refuse the position).  The locus is first sampled every AFTER_STEP mm
    (where ``step`` is finer): its bounds decide where they show the touch after z, else those of
    ``step``.  False where it cannot tell: then :func:`first_touch` gives the height (a wheelset's
    first touch is min(z, that height))."""
    for st in (AFTER_STEP, step) if step < AFTER_STEP else (step,):
        try:
            z_low, _, clear = touch_bounds(pair, top, step=st)
        except (InputError, NoContactError, ConvergenceError):
            continue
        if clear and z_low > z + 1e-9:
            return True
    return False


def wheelset_roll(geo: WheelRailGeometry, base_dir: str | Path = ".", lateral_shift: float | None = None,
                  ) -> tuple[float, float]:
    """Roll angle (rad, track frame) and height z at which both wheels of the wheelset touch their
    rails (rigid profiles, the given lateral shift and yaw)."""
    seen: dict[float, tuple[float, float]] = {}    # the root search asks again for rolls of the bracket

    def f(roll):
        key = float(roll)
        if key not in seen:
            zr = first_touch(build_pair(geo, base_dir, side="right", roll=roll, lateral_shift=lateral_shift))
            zl = first_touch(build_pair(geo, base_dir, side="left", roll=roll, lateral_shift=lateral_shift))
            seen[key] = (zr - zl, zr)
        return seen[key]

    arm = max(geo.flange_back / 2.0 + 70.0, 1.0)
    f0, _ = f(0.0)
    r0 = f0 / (2 * arm)                        # positive roll lowers the right wheel
    # the root NEAREST to this estimate: with a flange at its rail, zr - zl has several roots
    # (the wheelset on its treads and flange flank, and the flange tip lifted onto the rail, 10 mm
    # higher); a wide bracket let Brent's method pick either, and the height jumped by 11 mm
    # between two shifts 0.005 mm apart (issue 11).  Steps double from 1e-5 rad on both sides.
    fr0 = f(r0)[0]
    if fr0 == 0.0:
        return float(r0), float(f(r0)[1])
    h = 1e-5
    left, right = (r0, fr0), (r0, fr0)
    for _ in range(40):
        h *= 2.0
        found = []
        for side, prev in ((-1.0, left), (1.0, right)):
            r = r0 + side * h
            fr = f(r)[0]
            if fr == 0.0 or (fr > 0) != (prev[1] > 0):
                found.append((min(prev[0], r), max(prev[0], r)))
            if side < 0:
                left = (r, fr)
            else:
                right = (r, fr)
        if found:
            lo, hi = found[0]
            break
    else:
        raise ConvergenceError("[geometry] roll: no roll angle makes both wheels touch their rails")
    roll = brentq(lambda r: f(r)[0], lo, hi, xtol=1e-12, rtol=1e-12)
    return float(roll), float(f(roll)[1])
