"""The inputs of one contact problem that do not depend on a scene file: friction, kinematics and
the model settings, as frozen dataclasses.

They live below the scenes (conformal.scene builds them from TOML and re-exports them) so that the
solvers, which take a :class:`~conformal.problem.ContactProblem`, never import the scene layer.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

from conformal.errors import InputError


@dataclass(frozen=True)
class Friction:
    """Coulomb friction.  ``mu_static`` bounds adhesion, ``mu_kinetic`` acts in slip."""

    mu_static: float
    mu_kinetic: float
    #: friction varying over the profile: a file of (s, mu) rows (s = y on a planar grid), mu_static
    #: and mu_kinetic scaled by mu(s)/mu_static along s (conformal.problem, theory "exact")
    mu_table: Any = None
    #: friction over the surface inclination (CONTACT's V = 1): rows (alpha, mu_static, mu_kinetic),
    #: alpha (rad) the contact angle, increasing; linear between the rows, constant beyond; each
    #: patch of a wheel-rail scene takes the values at its contact angle (conformal.cases.wheelrail),
    #: each row of a conformal strip those at its own angle (conformal.cases.conformal)
    angle_table: tuple = ()

    @property
    def mu(self) -> float:
        return self.mu_kinetic

    def at_angle(self, alpha: float) -> "Friction":
        """The constant friction at contact angle ``alpha`` (rad) from ``angle_table`` (this
        friction where there is none).

        >>> Friction(0.3, 0.3, angle_table=((-0.5, 0.2, 0.2), (-0.3, 0.3, 0.25))).at_angle(-0.4)
        Friction(mu_static=0.25, mu_kinetic=0.225, mu_table=None, angle_table=())
        """
        if not self.angle_table:
            return self
        a, ms, mk = (list(col) for col in zip(*self.angle_table))
        return Friction(_interp(alpha, a, ms), _interp(alpha, a, mk))


def _interp(x: float, xs: list, ys: list) -> float:
    """Piecewise-linear interpolation, constant beyond the ends (xs increasing)."""
    if x <= xs[0]:
        return float(ys[0])
    for k in range(1, len(xs)):
        if x <= xs[k]:
            t = (x - xs[k - 1]) / (xs[k] - xs[k - 1])
            return float(ys[k - 1] + t * (ys[k] - ys[k - 1]))
    return float(ys[-1])


@dataclass(frozen=True)
class Kinematics:
    """Creepages (steady rolling) or shift distances (rolling = "shift", as CONTACT's T = 1:
    xi, eta are rigid shifts in mm and phi a rotation in rad).  fx_rel, fy_rel = F/(mu FN)
    prescribe the tangential forces instead of xi, eta."""

    xi: float = 0.0
    eta: float = 0.0
    phi: float = 0.0
    rolling: str = "steady"
    fx_rel: float | None = None
    fy_rel: float | None = None
    velocity: float = 1000.0  # mm/s, rolling speed (for frictional power)
    # wheel-rail only: wheelset velocities; with `speed` set the creepages follow per contact patch
    speed: float | None = None          # mm/s, forward velocity of the wheelset
    pitch_velocity: float | None = None  # rad/s about the axle (None: pure rolling at wheel_radius)
    yaw_rate: float = 0.0               # rad/s
    roll_rate: float = 0.0              # rad/s
    lateral_velocity: float = 0.0       # mm/s
    direction: int = 1                  # rolling direction: +1 (+x, CONTACT's default) or -1 (-x)
    rigid_slip: Any = None              # file with a rigid slip per element added to w (theory "exact")


@dataclass(frozen=True)
class ModelSpec:
    theory: str = "fastsim"
    bound: str = "parabolic"          # fastsim traction bound: "parabolic" | "elliptic"
    influence: str = "halfspace"      # "halfspace" | "halfspace_planar" (conformal: CONTACT's D = 4, C3 = 2) | "fe"
    tol: float = 1e-6
    maxit: int = 1000
    layer_flexibility: float = 0.0    # mm/(N/mm²), FASTSIM contamination layer (seed Eqs. 34-36)
    options: Mapping[str, Any] = field(default_factory=dict)  # other model-specific keys


#: the kinds of [[history]] steps
HISTORY_ROLLING = ("shift", "transient", "steady")


@dataclass(frozen=True)
class HistoryStep:
    """One step of a load history.

    normal_force, approach : the normal load of this step (N, mm); both None: as the previous step
        (the problem's load for the first step).
    xi, eta, phi : ``shift``: the rigid shift increment of this step (mm, mm, rad);
        ``transient``/``steady``: creepages (-, -, rad/mm).
    rolling : "shift" (no rolling, dq = 0), "transient" (rolling over ``distance``) or "steady".
    distance : rolled distance dq of a transient step (mm), a whole number of elements dx;
        None: one element.
    fx_rel, fy_rel : prescribed FX/(mu_static FN), FY/(mu_static FN) instead of xi, eta.
    repeat : the step is applied this many times (e.g. 40 transient steps of one element).
    """

    normal_force: float | None = None
    approach: float | None = None
    xi: float = 0.0
    eta: float = 0.0
    phi: float = 0.0
    rolling: str = "shift"
    distance: float | None = None
    fx_rel: float | None = None
    fy_rel: float | None = None
    repeat: int = 1

    def __post_init__(self):
        if self.rolling not in HISTORY_ROLLING:
            raise InputError(f"[[history]] rolling: must be one of {', '.join(HISTORY_ROLLING)}, got {self.rolling!r}")
        if self.normal_force is not None and self.approach is not None:
            raise InputError("[[history]] normal_force: give at most one of normal_force or approach per step")
        for key in ("normal_force", "approach", "distance"):
            v = getattr(self, key)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise InputError(f"[[history]] {key}: must be a finite number > 0, got {v!r}")
        for key in ("xi", "eta", "phi"):
            if not math.isfinite(getattr(self, key)):
                raise InputError(f"[[history]] {key}: must be a finite number, got {getattr(self, key)!r}")
        for key in ("fx_rel", "fy_rel"):
            v = getattr(self, key)
            if v is not None and not (math.isfinite(v) and abs(v) < 1.0):
                raise InputError(f"[[history]] {key}: a force F/(mu FN) must lie in (-1, 1), got {v!r}")
        if self.rolling != "transient" and self.distance is not None:
            raise InputError("[[history]] distance: only for rolling = \"transient\"")
        if isinstance(self.repeat, bool) or not isinstance(self.repeat, int) or self.repeat < 1:
            raise InputError(f"[[history]] repeat: must be a whole number >= 1, got {self.repeat!r}")
