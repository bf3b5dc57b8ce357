"""Track and wheelset placement: where the rail and the wheel sit in the side frame.

Track (``placement = "wheelset"``, CONTACT module 1): the rail profile is rotated by the cant (top
towards the track centre), lowered until its highest point touches the track plane z = 0, and
moved sideways until its gauge face, ``gauge_height`` below the track plane, lies at gauge/2
from the track centre.  The wheel-profile origin lies ``flange_back/2 - flange_back_pos`` from the
wheelset centre along the axle (``flange_back_pos`` = the flange back in wheel-profile
coordinates, -70 mm for S1002), and ``wheel_radius`` (the radius at the wheel-profile origin)
below the axle: a wheelset height z = 0 puts the axle wheel_radius above the track plane.

Single wheel (``placement = "single"``): both profiles keep their own origins; the rail is only
rotated by the cant about its origin; the wheel-profile origin lies ``lateral_shift`` to the
side of the rail-profile origin and ``wheel_radius`` below the wheel centre.

A left pair is solved as the mirror image (y -> -y) of a right pair: lateral shift, roll and yaw
change sign.

>>> from conformal.geometry.profiles import load_profile
>>> from conformal.geometry.spline import fit_curve
>>> rail = place_rail(fit_curve(load_profile("UIC60_MBENCH_1IN40", "rail").points), cant=0.0,
...                   placement="wheelset", gauge=1435.0, gauge_height=14.0)
>>> round(rail.origin[0], 2)   # CONTACT's Manchester set-up: 760.53 mm
760.53
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from conformal.errors import InputError
from conformal.geometry.spline import ProfileCurve
from conformal.geometry.surfaces import RailSurface, WheelFrame, WheelSurface, cant_matrix


def gauge_point(rail: RailSurface, depth: float) -> tuple[float, float]:
    """(y, s) of the gauge point: where the placed rail profile, walking from its highest point
    towards the gauge side (smaller y), first reaches ``depth`` below the track plane."""
    s, p = rail.sample(0.02)
    i_top = int(np.argmin(p[:, 1]))
    z = p[: i_top + 1, 1][::-1]
    below = np.nonzero(z >= depth)[0]
    if below.size == 0:
        raise InputError(f"[geometry] gauge_height: the rail profile {rail.curve.name} does not reach "
                         f"{depth:g} mm below its top on the gauge side (it goes to {z.max():.2f} mm)")
    k = int(below[0])
    i1, i0 = i_top - k, i_top - k + 1          # indices in the original order, i1 < i0
    z0, z1 = p[i0, 1], p[i1, 1]
    w = (depth - z0) / (z1 - z0) if z1 != z0 else 0.0
    return float(p[i0, 0] + w * (p[i1, 0] - p[i0, 0])), float(s[i0] + w * (s[i1] - s[i0]))


def place_rail(curve: ProfileCurve, *, cant: float, placement: str, gauge: float,
               gauge_height: float) -> RailSurface:
    """The rail of a right-side pair in the side frame (see module docstring)."""
    if placement == "single":
        return RailSurface(curve, cant, (0.0, 0.0))
    rotated = RailSurface(curve, cant, (0.0, 0.0))
    _, p = rotated.sample(0.01)
    z_top = float(p[:, 1].min())
    lowered = RailSurface(curve, cant, (0.0, -z_top))
    y_gauge, _ = gauge_point(lowered, gauge_height)
    return RailSurface(curve, cant, (0.5 * gauge - y_gauge, -z_top))


_place_rail_cached = lru_cache(maxsize=64)(place_rail)   # curves are compared by identity


@dataclass(frozen=True)
class SidePose:
    """Wheelset lateral shift, roll and yaw of one pair in its side frame (mirrored for left)."""

    y: float
    roll: float
    yaw: float

    @classmethod
    def from_track(cls, side: str, y: float, roll: float, yaw: float) -> "SidePose":
        m = 1.0 if side == "right" else -1.0
        return cls(m * y, m * roll, m * yaw)


def _as_range(k: np.ndarray) -> np.ndarray | slice:
    """Ascending indices k as a slice where they are one contiguous range (the samples of a locus
    that can lie over a rail usually are): the same elements, read and written through views
    instead of gathered and scattered copies."""
    if k.size and int(k[-1]) - int(k[0]) + 1 == k.size:
        return slice(int(k[0]), int(k[-1]) + 1)
    return k


@dataclass(frozen=True, eq=False)
class WheelRailPair:
    """One wheel on one rail in the side frame; the wheelset height z is the only free coordinate."""

    wheel_curve: ProfileCurve
    rail: RailSurface
    radius: float          # radius at the wheel-profile origin (mm)
    offset: float          # axial position of the wheel-profile origin from the wheelset centre
    pose: SidePose
    side: str = "right"
    #: the contact locus samples at z = 0 by sampling step (filled on first use, see locus_samples)
    _loci: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    #: the rail top under the locus samples by step (see rail_top_under_locus)
    _tops: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    #: the wheelset axes (a, e_d, e_f) of the pose (filled on first use, see frame)
    _axes: tuple | None = field(default=None, init=False, repr=False, compare=False)

    def frame(self, z: float) -> WheelFrame:
        """The wheelset frame at height z: the axes of the pose (the same at every height, computed
        once per pair, read-only) and the centre at (0, y, z - radius)."""
        axes = self._axes
        if axes is None:
            f = WheelFrame.from_pose(self.pose.y, 0.0, self.pose.roll, self.pose.yaw, self.radius)
            for v in (f.a, f.e_d, f.e_f):
                v.flags.writeable = False
            axes = (f.a, f.e_d, f.e_f)
            object.__setattr__(self, "_axes", axes)
        return WheelFrame(np.array([0.0, self.pose.y, z - self.radius]), *axes)

    def wheel(self, z: float) -> WheelSurface:
        return WheelSurface(self.wheel_curve, self.radius, self.offset, self.frame(z))

    def locus_samples(self, z: float, step: float, span: tuple[float, float] | None = None
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(s_w, theta, points (n, 3)) of the wheel's contact locus (:meth:`WheelSurface.locus_theta`)
        sampled every ``step`` mm of wheel profile, at wheelset height z.  The locus is rigid under
        a vertical translation of the wheelset (theta depends on the orientation only), so it is
        computed once per pair at z = 0 and moved by z: a contact search at many trial heights of
        one position samples the wheel once.  ``span``: the side-frame lateral range of a rail
        (y_min, y_max); theta is NaN at the samples that cannot lie over it
        (:meth:`WheelSurface.locus_reach`), whose gap to that rail is NaN in any case."""
        s, th, pts = self._locus_at_zero(step, span)[:3]
        moved = np.empty_like(pts)
        for k, dz in enumerate((0.0, 0.0, z)):      # pts + (0, 0, z), one coordinate at a time
            np.add(pts[:, k], dz, out=moved[:, k])
        return s, th, moved

    def locus_radial(self, step: float, span: tuple[float, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(e_r (n, 3), rho (n,)) at the locus samples of :meth:`locus_samples`: the radial
        direction at the locus angle (0 where there is none) and the wheel radius, both independent
        of the height."""
        return self._locus_at_zero(step, span)[3:5]

    def _locus_at_zero(self, step: float, span: tuple[float, float] | None = None) -> tuple[np.ndarray, ...]:
        """(s, theta, points, e_r, rho, reach) of the locus at z = 0 (:meth:`locus_samples`), kept."""
        key = (step, span)
        hit = self._loci.get(key)
        if hit is None:
            wheel = self.wheel(0.0)
            s, y, z, y1, z1, _, _ = wheel.curve.sampled(step)     # the meridian of WheelSurface
            u, rho = wheel.offset + y, wheel.radius + z
            reach = np.ones(s.shape, bool) if span is None else wheel.locus_reach(u, rho, *span)
            th = np.full(s.shape, np.nan)
            er = np.empty((s.size, 3))
            f = wheel.frame                          # e_r(nan_to_num(theta)) where theta is NaN: e_r(0.0),
            er[:] = [1.0 * d + 0.0 * e for d, e in zip(f.e_d.tolist(), f.e_f.tolist())]   # its arithmetic
            todo = reach
            shared = self._loci.get(("shared",) + key)
            if shared is not None:                   # the same wheel and orientation (share_locus)
                sth, ser, sreach = shared
                both = reach & sreach
                th[both], er[both] = sth[both], ser[both]
                todo = reach & ~sreach
            if todo.any():
                k = _as_range(np.nonzero(todo)[0])
                th[k] = wheel.locus_theta_of(y1[k], z1[k])
                tk = th[k]
                er[k] = wheel.e_r(np.where(np.isnan(tk), 0.0, tk))   # nan_to_num (theta is finite or NaN)
            hit = (s, th, wheel.point_of(u, rho, e_r=er), er, rho, reach)
            self._loci[key] = hit
        return hit

    def share_locus(self, other: "WheelRailPair") -> None:
        """Take the contact locus angles and radial directions of ``other`` (what
        :meth:`locus_samples` computes once per pair) where they are this pair's: the same wheel
        profile, radius, axial offset and orientation (roll and yaw), i.e. another lateral shift
        of the same wheelset; the locus points follow from this pair's centre.  Otherwise
        nothing is taken."""
        same = (float(a).hex() == float(b).hex() for a, b in ((other.radius, self.radius),
                (other.offset, self.offset), (other.pose.roll, self.pose.roll), (other.pose.yaw, self.pose.yaw)))
        if other.wheel_curve is not self.wheel_curve or not all(same):      # bitwise, signed zeros apart
            return
        for key, hit in list(other._loci.items()):
            if key[0] != "shared" and key not in self._loci:
                self._loci[("shared",) + key] = hit[1], hit[3], hit[5]

    def rail_top_under_locus(self, top, step: float, span: tuple[float, float] | None = None) -> np.ndarray:
        """``top.z_at`` (a :class:`~conformal.geometry.search.RailTop`) at the lateral positions of
        the locus samples of :meth:`locus_samples` (NaN where they cannot reach ``span``): they do
        not change with the height z, so it is computed once per rail top and step."""
        key = (step, span)
        hit = self._tops.get(key)
        if hit is None or hit[0] is not top:
            pts, reach = (self._locus_at_zero(step, span)[i] for i in (2, 5))
            z_top = np.full(reach.shape, np.nan)
            k = _as_range(np.nonzero(reach)[0])
            z_top[k] = top.z_at(pts[k, 1])
            hit = (top, z_top)
            self._tops[key] = hit
        return hit[1]

    @property
    def mirror(self) -> float:
        """+1 for a right pair, -1 for a left pair (side frame y = mirror * track y)."""
        return 1.0 if self.side == "right" else -1.0


def wheel_offset(wheel_curve: ProfileCurve, *, placement: str, flange_back: float,
                 flange_back_pos: float | None, lateral_shift: float) -> tuple[float, float]:
    """(axial offset of the wheel-profile origin from the wheelset centre, wheelset lateral
    position in the side frame before mirroring) for the placement."""
    if placement == "single":
        return 0.0, lateral_shift
    fb = float(wheel_curve.points[:, 0].min()) if flange_back_pos is None else flange_back_pos
    return 0.5 * flange_back - fb, lateral_shift


def make_pair(wheel_curve: ProfileCurve, rail_curve: ProfileCurve, *, side: str, placement: str,
              lateral_shift: float, roll: float, yaw: float, rail_cant: float, gauge: float,
              gauge_height: float, flange_back: float, flange_back_pos: float | None,
              wheel_radius: float) -> WheelRailPair:
    """Assemble the pair of ``side`` (track-frame shift, roll, yaw are mirrored for a left pair)."""
    if side not in ("left", "right"):
        raise InputError(f"[geometry] side: must be 'left' or 'right', got {side!r}")
    rail = _place_rail_cached(rail_curve, cant=rail_cant, placement=placement, gauge=gauge,
                              gauge_height=gauge_height)
    offset, y = wheel_offset(wheel_curve, placement=placement, flange_back=flange_back,
                             flange_back_pos=flange_back_pos, lateral_shift=lateral_shift)
    # single: the roll and yaw turn the wheel about its own centre, offset = 0
    return WheelRailPair(wheel_curve, rail, wheel_radius, offset, SidePose.from_track(side, y, roll, yaw), side)


__all__ = ["gauge_point", "place_rail", "SidePose", "WheelRailPair", "wheel_offset", "make_pair", "cant_matrix"]
