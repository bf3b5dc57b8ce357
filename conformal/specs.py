"""The inputs of one contact problem that do not depend on a scene file: friction, kinematics and
the model settings, as frozen dataclasses.

They live below the scenes (conformal.scene builds them from TOML and re-exports them) so that the
solvers, which take a :class:`~conformal.problem.ContactProblem`, never import the scene layer.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping


@dataclass(frozen=True)
class Friction:
    """Coulomb friction.  ``mu_static`` bounds adhesion, ``mu_kinetic`` acts in slip."""

    mu_static: float
    mu_kinetic: float

    @property
    def mu(self) -> float:
        return self.mu_kinetic


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


@dataclass(frozen=True)
class ModelSpec:
    theory: str = "fastsim"
    bound: str = "parabolic"          # fastsim traction bound: "parabolic" | "elliptic"
    influence: str = "halfspace"      # "halfspace" | "fe"
    tol: float = 1e-6
    maxit: int = 1000
    layer_flexibility: float = 0.0    # mm/(N/mm²), FASTSIM contamination layer (seed Eqs. 34-36)
    options: Mapping[str, Any] = field(default_factory=dict)  # other model-specific keys
