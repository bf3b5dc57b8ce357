"""Wheel and rail surfaces (seed Eqs. 50-53): the rail an extrusion, the wheel a surface of revolution.

Everything is expressed in the *side frame* of one wheel-rail pair: the track frame (x forward
along the track, y lateral, z down; CONTACT module 1) mirrored for a left wheel, so that y always
points to the field side of this rail.  A left pair is solved as the mirror image of a right
pair, as CONTACT does.

Rail (extrusion along x), parameters (x, s_r) (seed: s_1^r along the rail, s_2^r across)::

    r_r(x, s_r) = (x, Y(s_r), Z(s_r)),   t1_r = e_x,  t2_r = (0, Y', Z'),  n_r = t1_r x t2_r

with (Y, Z) the rail profile rotated by the cant and placed; n_r points into the rail (+z on top).

Wheel (revolution about the axle), parameters (s_w, theta) (seed: s_1^w the profile, s_2^w the
rotation)::

    r_w(s_w, theta) = O + u(s_w) a + rho(s_w) e_r(theta),   e_r = cos(theta) e_d + sin(theta) e_f

with O the wheelset centre, a the axle direction (towards the field side), e_d the wheelset's
downward axis, e_f = a x e_d its forward axis, u = L + y_w(s_w) the axial position and
rho = R0 + z_w(s_w) the radius (z_w = radius increase of the wheel profile).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from conformal.geometry.spline import ProfileCurve


def cant_matrix(cant: float) -> np.ndarray:
    """Rotation of a right-side rail profile by its cant, top leaning towards the track centre (-y)."""
    c, s = math.cos(cant), math.sin(cant)
    return np.array([[c, s], [-s, c]])


@dataclass(frozen=True, eq=False)
class RailSurface:
    """A rail profile curve (own coordinates) rotated by ``cant`` and moved to ``origin`` (side frame)."""

    curve: ProfileCurve
    cant: float = 0.0
    origin: tuple[float, float] = (0.0, 0.0)

    @property
    def rotation(self) -> np.ndarray:
        return cant_matrix(self.cant)

    @cached_property
    def _placement(self) -> tuple[float, ...]:
        """The rotation's entries and the origin as Python floats (r00, r01, r10, r11, y0, z0)."""
        R = self.rotation
        return (float(R[0, 0]), float(R[0, 1]), float(R[1, 0]), float(R[1, 1]),
                float(self.origin[0]), float(self.origin[1]))

    def profile(self, s) -> tuple[np.ndarray, ...]:
        """Y, Z, Y', Z', Y'', Z'' of the placed profile at arc length s (side frame; floats for a
        scalar s)."""
        r00, r01, r10, r11, y0, z0 = self._placement
        if isinstance(s, (float, int)) or (isinstance(s, np.ndarray) and s.ndim == 0):
            y, z, y1, z1, y2, z2 = self.curve.derivatives(s)
            Y = r00 * y + r01 * z + y0
            Z = r10 * y + r11 * z + z0
            return (Y, Z, r00 * y1 + r01 * z1, r10 * y1 + r11 * z1,
                    r00 * y2 + r01 * z2, r10 * y2 + r11 * z2)
        c = self.curve.stack(s)          # (3, 2, ...): the value and two derivatives of (y, z)
        y, z = c[:, 0], c[:, 1]
        Yd, Zd = r00 * y + r01 * z, r10 * y + r11 * z    # the same expressions, three rows at once
        return (Yd[0] + y0, Zd[0] + z0, Yd[1], Zd[1], Yd[2], Zd[2])

    def profile_slopes(self, s: np.ndarray) -> tuple[np.ndarray, ...]:
        """Y, Z, Y', Z' of :meth:`profile` at the arc lengths s (an array): the same values, without
        the second derivatives."""
        r00, r01, r10, r11, y0, z0 = self._placement
        c = self.curve.stack(s, 1)
        y, z = c[:, 0], c[:, 1]
        Yd, Zd = r00 * y + r01 * z, r10 * y + r11 * z
        return (Yd[0] + y0, Zd[0] + z0, Yd[1], Zd[1])

    def point(self, s) -> np.ndarray:
        Y, Z = self.profile(s)[:2]
        return np.stack([Y, Z], axis=-1)

    def normal(self, s) -> np.ndarray:
        """Unit inner normal (n_y, n_z) in the side frame (seed Eq. 53, n = t1 x t2)."""
        _, _, Y1, Z1, _, _ = self.profile(s)
        g = np.hypot(Y1, Z1)
        return np.stack([-Z1 / g, Y1 / g], axis=-1)

    def project(self, yz: np.ndarray, s0: np.ndarray) -> np.ndarray:
        """Arc lengths of the closest rail points to side-frame points yz (..., 2), Newton from s0."""
        own = self.to_own(yz)
        return self.curve.project(own, s0)

    def to_own(self, yz: np.ndarray) -> np.ndarray:
        """Side-frame (y, z) -> the rail profile's own coordinates."""
        return (np.asarray(yz) - np.asarray(self.origin)) @ self.rotation

    def sample(self, step: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
        s, _ = self.curve.sample(step)
        return s, self.point(s)


@dataclass(frozen=True)
class WheelFrame:
    """Position and axes of a wheelset in the side frame."""

    O: np.ndarray     # wheelset centre (3,)
    a: np.ndarray     # axle direction, towards this wheel's field side
    e_d: np.ndarray   # wheelset 'down' axis
    e_f: np.ndarray   # wheelset 'forward' axis, a x e_d

    @classmethod
    def from_pose(cls, y: float, z: float, roll: float, yaw: float, radius: float) -> "WheelFrame":
        """CONTACT's wheelset orientation: roll about x, then yaw about the new vertical axis
        (z down); the centre at (0, y, z - radius), i.e. z = 0 puts the axle ``radius`` above
        the track plane and z > 0 lowers the wheelset."""
        cr, sr, cy, sy = math.cos(roll), math.sin(roll), math.cos(yaw), math.sin(yaw)
        Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
        Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
        R = Rx @ Rz
        return cls(O=np.array([0.0, y, z - radius]), a=R[:, 1].copy(), e_d=R[:, 2].copy(), e_f=R[:, 0].copy())

    def shifted(self, dz: float) -> "WheelFrame":
        return WheelFrame(self.O + np.array([0.0, 0.0, dz]), self.a, self.e_d, self.e_f)


def _combine(c: np.ndarray, v: np.ndarray, d: np.ndarray, w: np.ndarray) -> np.ndarray:
    """c[..., None] * v + d[..., None] * w for 3-vectors v, w, one coordinate at a time (the same
    numbers as the broadcast expression, without its buffered iteration over rows of three)."""
    out = np.empty(np.broadcast_shapes(c.shape, d.shape) + (3,))
    for k in range(3):
        col = out[..., k]
        np.multiply(c, v[k], out=col)
        col += d * w[k]
    return out


#: mm: :meth:`WheelSurface.locus_reach` keeps the samples up to this far outside a rail's lateral range
LOCUS_REACH_MARGIN = 1.0


def _wrap(th: np.ndarray) -> np.ndarray:
    """(th + pi) % (2 pi) - pi, the remainder taken only where th + pi lies outside (0, 2 pi) (inside,
    numpy's remainder returns its argument: the same numbers)."""
    x = th + np.pi
    if np.ndim(x) == 0:
        return x % (2 * np.pi) - np.pi
    out = ~((x > 0.0) & (x < 2 * np.pi))
    if out.any():
        x[out] = x[out] % (2 * np.pi)
    return x - np.pi


@dataclass(frozen=True, eq=False)
class WheelSurface:
    """A wheel profile curve revolved about the axle of ``frame``.

    ``offset`` is the axial position of the wheel-profile origin from the wheelset centre and
    ``radius`` the radius at the profile origin (z_w = 0).
    """

    curve: ProfileCurve
    radius: float
    offset: float
    frame: WheelFrame

    @cached_property
    def frame_floats(self) -> tuple[tuple[float, float, float], ...]:
        """The frame's origin and axes (O, a, e_d, e_f) as tuples of Python floats (for the
        per-point Newton iterations of the contact search, computed once per wheel)."""
        f = self.frame
        return tuple(tuple(float(c) for c in v) for v in (f.O, f.a, f.e_d, f.e_f))

    def meridian(self, s) -> tuple[np.ndarray, ...]:
        """u, rho, u', rho', u'', rho'' (axial position and radius along the profile)."""
        y, z, y1, z1, y2, z2 = self.curve.derivatives(s)
        return self.offset + y, self.radius + z, y1, z1, y2, z2

    def e_r(self, theta) -> np.ndarray:
        """Radial direction cos(theta) e_d + sin(theta) e_f, shape theta.shape + (3,)."""
        th = np.asarray(theta)
        return _combine(np.cos(th), self.frame.e_d, np.sin(th), self.frame.e_f)

    def e_t(self, theta) -> np.ndarray:
        """Circumferential direction -sin(theta) e_d + cos(theta) e_f, shape theta.shape + (3,)."""
        th = np.asarray(theta)
        return _combine(-np.sin(th), self.frame.e_d, np.cos(th), self.frame.e_f)

    def point(self, s, theta) -> np.ndarray:
        u, rho = self.meridian(s)[:2]
        return self.point_of(u, rho, theta)

    def point_of(self, u, rho, theta=None, *, e_r=None) -> np.ndarray:
        """The surface point of axial position u, radius rho (the meridian's values) and rotation
        theta (or its radial direction ``e_r`` = :meth:`e_r` (theta))."""
        er = self.e_r(theta) if e_r is None else np.asarray(e_r)
        u, rho, f = np.asarray(u), np.asarray(rho), self.frame
        out = np.empty(np.broadcast_shapes(u.shape, rho.shape, er.shape[:-1]) + (3,))
        for k in range(3):              # (O + u a) + rho e_r, one coordinate at a time
            col = out[..., k]
            np.multiply(u, f.a[k], out=col)
            col += f.O[k]
            col += rho * er[..., k]
        return out

    def locus_reach(self, u: np.ndarray, rho: np.ndarray, y_min: float, y_max: float) -> np.ndarray:
        """Where the profile samples of axial positions u and radii rho (the meridian's values) can
        have their locus point at a side-frame lateral position in [y_min, y_max] (a rail's range),
        with LOCUS_REACH_MARGIN mm to spare: the point's y = O_y + u a_y + rho e_r,y and
        |e_r,y| <= hypot(e_d,y, e_f,y) at every rotation."""
        f = self.frame
        c = float(f.O[1]) + u * float(f.a[1])
        r = rho * math.hypot(float(f.e_d[1]), float(f.e_f[1])) + LOCUS_REACH_MARGIN
        return (c + r >= y_min) & (c - r <= y_max)

    def locus_theta(self, s) -> np.ndarray:
        """Rotation angle theta(s_w) of the contact locus: the point of each wheel circle where the
        surface normal is perpendicular to the rail direction e_x (the rail normal has no x
        component, so a contact point must lie there).  NaN where no such point exists near the
        bottom (a wheel flank parallel to the wheel's plane)."""
        _, _, u1, rho1, _, _ = self.meridian(s)
        return self.locus_theta_of(u1, rho1)

    def locus_theta_of(self, u1, rho1) -> np.ndarray:
        """:meth:`locus_theta` from the meridian's slopes u', rho' at the profile points."""
        f = self.frame
        # meridian normal N = rho' a - u' e_r;  N . e_x = 0  <=>  A cos + B sin = C
        A, B, C = u1 * f.e_d[0], u1 * f.e_f[0], rho1 * f.a[0]
        Rn = np.hypot(A, B)
        with np.errstate(invalid="ignore", divide="ignore"):
            phase = np.arctan2(B, A)
            ratio = np.where(Rn > 0, C / np.where(Rn > 0, Rn, 1.0), np.nan)
            dev = np.arccos(np.clip(ratio, -1.0, 1.0))
        th1, th2 = _wrap(phase + dev), _wrap(phase - dev)
        th = np.where(np.abs(th1) < np.abs(th2), th1, th2)
        bad = ~(np.abs(ratio) <= 1.0) | (np.abs(th) > 0.5)
        return np.where(bad, np.nan, th)

    def rolling_radius(self, s) -> np.ndarray:
        return self.meridian(s)[1]
