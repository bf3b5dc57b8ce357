"""Creepages at a wheel-rail contact from the wheelset's velocities (seed Eqs. 58-61).

The rail is fixed.  A wheel material point at r moves with (seed Eq. 60)

    v_w = V_ws + omega_w x (r - O),      omega_w = roll_rate e_x + yaw_rate e_d + pitch_velocity a

(roll about the track x axis, yaw about the wheelset's vertical axis e_d, pitch about the axle a:
the derivatives of CONTACT's Euler angles).  In the contact frame (t1 = e_x, t2, n into the rail)
the creepages are those of body 1 (the rail) relative to body 2 (the wheel), CONTACT's
convention (a braking wheel has xi > 0 and FX < 0 on the rail):

    xi = (v_r - v_w) . t1 / V,   eta = (v_r - v_w) . t2 / V,   phi = (omega_r - omega_w) . n / V

Seed Eq. 61 writes the wheel relative to the rail (the opposite sign) and divides by the forward
speed; here V is the rolling velocity, the mean speed at which the two surfaces move through the
contact point (which travels with the wheelset): V = -(v_r - v_c + v_w - v_c) . t1 / 2, as
CONTACT's VELOC.

All vectors are in the side frame (mirrored for a left wheel, see placement); the returned
creepages are in the side frame too (mirror eta and phi for a left wheel's real frame).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.errors import InputError
from conformal.geometry.surfaces import WheelFrame


@dataclass(frozen=True)
class WheelsetMotion:
    """Wheelset velocities in the track frame (mm/s, rad/s)."""

    speed: float                    # forward, along the track
    pitch_velocity: float           # about the axle; negative for forward rolling (x fwd, z down)
    yaw_rate: float = 0.0
    roll_rate: float = 0.0
    lateral_velocity: float = 0.0
    vertical_velocity: float = 0.0

    def __post_init__(self):
        if not (self.speed > 0 and math.isfinite(self.speed)):
            raise InputError(f"[kinematics] speed: must be > 0 mm/s, got {self.speed!r}")

    @classmethod
    def rolling(cls, speed: float, radius: float, **rates) -> "WheelsetMotion":
        """Pure rolling at ``radius``: pitch velocity -speed/radius."""
        return cls(speed=speed, pitch_velocity=-speed / radius, **rates)

    def mirrored(self, side: str) -> "WheelsetMotion":
        """The motion in the side frame: y -> -y for a left wheel.  Angular velocity is a
        pseudo-vector, so roll and yaw rates change sign and the pitch velocity does not."""
        if side == "right":
            return self
        return WheelsetMotion(self.speed, self.pitch_velocity, -self.yaw_rate, -self.roll_rate,
                              -self.lateral_velocity, self.vertical_velocity)


@dataclass(frozen=True)
class Creepages:
    xi: np.ndarray | float
    eta: np.ndarray | float
    phi: np.ndarray | float
    velocity: np.ndarray | float   # rolling velocity V (mm/s)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``numpy.cross(a, b)`` of float 3-vectors (..., 3): its products and differences,
    (a1 b2 - a2 b1, a2 b0 - a0 b2, a0 b1 - a1 b0), without its axis handling (on single vectors,
    as Python floats: the same IEEE operations at a twentieth of its cost)."""
    if a.ndim == 1 and b.ndim == 1:
        a0, a1, a2 = (float(v) for v in a)
        b0, b1, b2 = (float(v) for v in b)
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out


def creepages(frame: WheelFrame, motion: WheelsetMotion, point, normal) -> Creepages:
    """Creepages (seed Eq. 61, body 1 = rail) at contact point(s) ``point`` (..., 3) with inner rail
    normal(s) ``normal`` (..., 3) (normal must have zero x component: the rail is an extrusion)."""
    p = np.asarray(point, float)
    n = np.broadcast_to(np.asarray(normal, float), p.shape)
    t1 = np.array([1.0, 0.0, 0.0])
    t2 = _cross(n, t1)
    Vws = np.array([motion.speed, motion.lateral_velocity, motion.vertical_velocity])
    omega = (motion.roll_rate * t1 + motion.yaw_rate * frame.e_d + motion.pitch_velocity * frame.a)
    rel_w = _cross(omega, p - frame.O)           # wheel material relative to the contact point
    v_w = Vws + rel_w                            # seed Eq. 60 (the rail is at rest)
    rel_r = -Vws                                 # rail material relative to the contact point
    V = -0.5 * ((rel_r + rel_w) @ t1)
    if np.any(V <= 0):
        raise InputError("[kinematics] speed: the wheel must roll forwards (rolling velocity <= 0)")
    dv = -v_w                                    # v_rail - v_wheel
    xi = (dv @ t1) / V
    eta = np.einsum("...i,...i->...", dv, t2) / V
    phi = -np.einsum("...i,...i->...", np.broadcast_to(omega, p.shape), n) / V
    return Creepages(xi=xi, eta=eta, phi=phi, velocity=V)
