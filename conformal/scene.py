"""Scene files: what the user asks, as frozen dataclasses, loaded from TOML and validated.

A scene names the materials, friction, geometry, load, kinematics, grid and model.  Every
problem with the input is raised as :class:`~conformal.errors.InputError` naming the key, e.g.
``[load] normal_force: must be > 0, got -5``.  Units: mm, N, N/mm², rad; spin in rad/mm.

The keys below are a public interface (other tools write scene files): add, never rename.

>>> s = scene_from_dict({"material": {"G": 82000, "nu": 0.28}, "friction": {"mu": 0.3},
...     "geometry": {"kind": "quadratic", "A": 0.001, "B": 0.001}, "load": {"normal_force": 1e5},
...     "kinematics": {"xi": 0.001}, "model": {"theory": "hertz"}})
>>> s.geometry.kind, s.load.normal_force, s.kinematics.xi, s.model.theory
('quadratic', 100000.0, 0.001, 'hertz')
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping

from conformal.errors import InputError
from conformal.materials import Material

THEORIES = ("hertz", "linear", "empirical", "johnson_vermeulen", "fastsim", "exact", "conformal")
GEOMETRY_KINDS = ("quadratic", "hertz", "table", "wheel_rail")


# ----------------------------------------------------------------------------- sections
@dataclass(frozen=True)
class Friction:
    """Coulomb friction.  ``mu_static`` bounds adhesion, ``mu_kinetic`` acts in slip."""

    mu_static: float
    mu_kinetic: float

    @property
    def mu(self) -> float:
        return self.mu_kinetic


@dataclass(frozen=True)
class QuadraticGeometry:
    """Undeformed distance h = A x² + B y² (1/mm)."""

    A: float
    B: float
    kind: str = "quadratic"


@dataclass(frozen=True)
class HertzGeometry:
    """Hertzian contact given by its semi-axes a (x, rolling) and b (y) in mm; curvatures follow
    from the load (CONTACT's IPOTCN = -3)."""

    a: float
    b: float
    kind: str = "hertz"


@dataclass(frozen=True)
class TableGeometry:
    """Explicit undeformed distance on the grid, read from ``file`` (see conformal.problem)."""

    file: Path
    kind: str = "table"


@dataclass(frozen=True)
class WheelRailGeometry:
    """A wheel profile on a rail profile (see conformal.geometry)."""

    wheel_profile: str = "S1002"
    rail_profile: str = "UIC60"
    side: str = "right"
    placement: str = "wheelset"          # "wheelset" | "single"
    lateral_shift: float = 0.0           # mm
    yaw: float = 0.0                     # rad
    roll: float | None = None            # rad; None = found so that both wheels touch
    rail_cant: float = math.atan(1 / 40)  # rad
    gauge: float = 1435.0                # mm
    gauge_height: float = 14.0           # mm below the top of rail where the gauge is measured
    flange_back: float = 1360.0          # mm
    wheel_radius: float = 460.0          # mm, nominal rolling radius
    kind: str = "wheel_rail"
    flange_back_pos: float | None = None  # mm, flange back in wheel-profile y (None: from the profile)
    smoothing: float = 1.0               # mm, profile smoothing-spline wavelength (0 = interpolate)
    element_size: float | None = None    # mm, square grid elements covering each patch (CONTACT DX = DS)
    patch_combine: float = 8.0           # mm, overlap regions closer than this form one patch


Geometry = QuadraticGeometry | HertzGeometry | TableGeometry | WheelRailGeometry


@dataclass(frozen=True)
class Load:
    """Exactly one of normal_force (N), approach (mm) or wheel_load (vertical, N)."""

    normal_force: float | None = None
    approach: float | None = None
    wheel_load: float | None = None


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
class GridSpec:
    """Potential contact area.  Either explicit (mx, my, dx, dy and optional corner xl, yl) or
    automatic: ``n`` elements along each axis of ``scale`` times the Hertz patch."""

    mx: int | None = None
    my: int | None = None
    dx: float | None = None
    dy: float | None = None
    xl: float | None = None
    yl: float | None = None
    n: int = 40
    scale: float = 1.1

    @property
    def explicit(self) -> bool:
        return self.dx is not None


@dataclass(frozen=True)
class ModelSpec:
    theory: str = "fastsim"
    bound: str = "parabolic"          # fastsim traction bound: "parabolic" | "elliptic"
    influence: str = "halfspace"      # "halfspace" | "fe"
    tol: float = 1e-6
    maxit: int = 1000
    layer_flexibility: float = 0.0    # mm/(N/mm²), FASTSIM contamination layer (seed Eqs. 34-36)
    options: Mapping[str, Any] = field(default_factory=dict)  # other model-specific keys


@dataclass(frozen=True)
class Scene:
    material: Material
    friction: Friction
    geometry: Geometry
    load: Load
    kinematics: Kinematics
    grid: GridSpec
    model: ModelSpec
    name: str = "scene"
    base_dir: Path = Path(".")

    def with_model(self, **changes) -> "Scene":
        return replace(self, model=replace(self.model, **changes))


# ----------------------------------------------------------------------------- reading
class _Section:
    """Typed access to one TOML table; every error names the table and the key."""

    def __init__(self, name: str, data: Any, known: set[str] | None = None):
        if data is None:
            data = {}
        if not isinstance(data, Mapping):
            raise InputError(f"[{name}] must be a table, got {type(data).__name__}")
        self.name, self.data = name, dict(data)
        if known is not None:
            unknown = sorted(set(self.data) - known)
            if unknown:
                raise InputError(f"[{name}] {unknown[0]}: unknown key (known: {', '.join(sorted(known))})")

    def has(self, key: str) -> bool:
        return key in self.data

    def error(self, key: str, problem: str) -> InputError:
        return InputError(f"[{self.name}] {key}: {problem}")

    def number(self, key: str, default: float | None = None, *, positive: bool = False,
               nonnegative: bool = False, required: bool = False) -> float | None:
        if key not in self.data:
            if required:
                raise self.error(key, "missing")
            return default
        v = self.data[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.error(key, f"must be a number, got {v!r}")
        v = float(v)
        if not math.isfinite(v):
            raise self.error(key, f"must be a finite number, got {v!r}")
        if positive and v <= 0:
            raise self.error(key, f"must be > 0, got {v:g}")
        if nonnegative and v < 0:
            raise self.error(key, f"must be >= 0, got {v:g}")
        return v

    def integer(self, key: str, default: int | None = None, *, minimum: int = 1) -> int | None:
        if key not in self.data:
            return default
        v = self.data[key]
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(key, f"must be a whole number, got {v!r}")
        if v < minimum:
            raise self.error(key, f"must be >= {minimum}, got {v}")
        return v

    def choice(self, key: str, choices: tuple[str, ...], default: str | None = None) -> str:
        v = self.data.get(key, default)
        if v is None:
            raise self.error(key, f"missing (one of {', '.join(choices)})")
        if v not in choices:
            raise self.error(key, f"must be one of {', '.join(repr(c) for c in choices)}, got {v!r}")
        return v

    def string(self, key: str, default: str | None = None) -> str | None:
        v = self.data.get(key, default)
        if v is not None and not isinstance(v, str):
            raise self.error(key, f"must be a string, got {v!r}")
        return v


def _material(data: Any) -> Material:
    def constants(sec: _Section) -> tuple[float, float]:
        nu = sec.number("nu", required=True)
        if not -1.0 < nu < 0.5:
            raise sec.error("nu", f"Poisson's ratio must lie in (-1, 0.5), got {nu:g}")
        if sec.has("G") == sec.has("E"):
            raise sec.error("G", "give exactly one of G (shear modulus) or E (Young's modulus), N/mm²")
        if sec.has("G"):
            return sec.number("G", positive=True), nu
        return sec.number("E", positive=True) / (2.0 * (1.0 + nu)), nu

    data = dict(data or {"G": 82000.0, "nu": 0.28})
    body2 = data.pop("body2", None)
    G1, nu1 = constants(_Section("material", data, {"G", "E", "nu"}))
    G2, nu2 = (G1, nu1) if body2 is None else constants(_Section("material.body2", body2, {"G", "E", "nu"}))
    return Material(G1, nu1, G2, nu2)


def _friction(data: Any) -> Friction:
    sec = _Section("friction", data if data is not None else {"mu": 0.3}, {"mu", "mu_static", "mu_kinetic"})
    if sec.has("mu"):
        if sec.has("mu_static") or sec.has("mu_kinetic"):
            raise sec.error("mu", "give either mu or mu_static/mu_kinetic, not both")
        mu = sec.number("mu", positive=True)
        return Friction(mu, mu)
    ms = sec.number("mu_static", positive=True)
    mk = sec.number("mu_kinetic", positive=True)
    if ms is None and mk is None:
        raise sec.error("mu", "missing (the friction coefficient, > 0)")
    ms = mk if ms is None else ms
    mk = ms if mk is None else mk
    if mk > ms:
        raise sec.error("mu_kinetic", f"must not exceed mu_static ({mk:g} > {ms:g})")
    return Friction(ms, mk)


def _geometry(data: Any, base_dir: Path) -> Geometry:
    raw = dict(data or {})
    kind = _Section("geometry", raw).choice("kind", GEOMETRY_KINDS)
    if kind == "quadratic":
        sec = _Section("geometry", raw, {"kind", "A", "B"})
        return QuadraticGeometry(sec.number("A", required=True, positive=True),
                                 sec.number("B", required=True, positive=True))
    if kind == "hertz":
        sec = _Section("geometry", raw, {"kind", "a", "b"})
        return HertzGeometry(sec.number("a", required=True, positive=True),
                             sec.number("b", required=True, positive=True))
    if kind == "table":
        sec = _Section("geometry", raw, {"kind", "file"})
        f = sec.string("file")
        if not f:
            raise sec.error("file", "missing (path of the undeformed-distance table)")
        path = (base_dir / f) if not Path(f).is_absolute() else Path(f)
        if not path.is_file():
            raise sec.error("file", f"no such file: {path}")
        return TableGeometry(path)
    # wheel_rail
    d = WheelRailGeometry()
    known = {k for k in WheelRailGeometry.__dataclass_fields__}
    sec = _Section("geometry", raw, known)
    side = sec.choice("side", ("left", "right"), d.side)
    placement = sec.choice("placement", ("wheelset", "single"), d.placement)
    roll = sec.number("roll")
    return WheelRailGeometry(
        wheel_profile=sec.string("wheel_profile", d.wheel_profile),
        rail_profile=sec.string("rail_profile", d.rail_profile),
        side=side, placement=placement,
        lateral_shift=sec.number("lateral_shift", d.lateral_shift),
        yaw=sec.number("yaw", d.yaw), roll=roll,
        rail_cant=sec.number("rail_cant", d.rail_cant),
        gauge=sec.number("gauge", d.gauge, positive=True),
        gauge_height=sec.number("gauge_height", d.gauge_height, nonnegative=True),
        flange_back=sec.number("flange_back", d.flange_back, positive=True),
        wheel_radius=sec.number("wheel_radius", d.wheel_radius, positive=True),
        flange_back_pos=sec.number("flange_back_pos"),
        smoothing=sec.number("smoothing", d.smoothing, nonnegative=True),
        element_size=sec.number("element_size", positive=True),
        patch_combine=sec.number("patch_combine", d.patch_combine, nonnegative=True),
    )


def _load(data: Any, geometry: Geometry) -> Load:
    sec = _Section("load", data, {"normal_force", "approach", "wheel_load"})
    given = [k for k in ("normal_force", "approach", "wheel_load") if sec.has(k)]
    if len(given) != 1:
        raise sec.error("normal_force", "give exactly one of normal_force (N), approach (mm) or wheel_load (N)")
    key = given[0]
    if key == "wheel_load" and geometry.kind != "wheel_rail":
        raise sec.error("wheel_load", "only for [geometry] kind = \"wheel_rail\"; use normal_force")
    value = sec.number(key, positive=True)
    return Load(**{key: value})


def _kinematics(data: Any) -> Kinematics:
    known = {"xi", "eta", "phi", "rolling", "fx_rel", "fy_rel", "velocity",
             "speed", "pitch_velocity", "yaw_rate", "roll_rate", "lateral_velocity"}
    sec = _Section("kinematics", data, known)
    rolling = sec.choice("rolling", ("steady", "shift"), "steady")
    for creep, force in (("xi", "fx_rel"), ("eta", "fy_rel")):
        if sec.has(creep) and sec.has(force):
            raise sec.error(force, f"give either {creep} or {force}, not both")
    fx, fy = sec.number("fx_rel"), sec.number("fy_rel")
    for key, v in (("fx_rel", fx), ("fy_rel", fy)):
        if v is not None and abs(v) >= 1.0:
            raise sec.error(key, f"a force F/(mu FN) must lie in (-1, 1), got {v:g}")
    return Kinematics(xi=sec.number("xi", 0.0), eta=sec.number("eta", 0.0), phi=sec.number("phi", 0.0),
                      rolling=rolling, fx_rel=fx, fy_rel=fy,
                      velocity=sec.number("velocity", 1000.0, positive=True),
                      speed=sec.number("speed", positive=True), pitch_velocity=sec.number("pitch_velocity"),
                      yaw_rate=sec.number("yaw_rate", 0.0), roll_rate=sec.number("roll_rate", 0.0),
                      lateral_velocity=sec.number("lateral_velocity", 0.0))


def _grid(data: Any) -> GridSpec:
    sec = _Section("grid", data, {"mx", "my", "dx", "dy", "xl", "yl", "n", "scale"})
    explicit = [k for k in ("mx", "my", "dx", "dy") if sec.has(k)]
    if explicit and len(explicit) != 4:
        missing = sorted({"mx", "my", "dx", "dy"} - set(explicit))
        raise sec.error(missing[0], "an explicit grid needs all of mx, my, dx, dy")
    return GridSpec(mx=sec.integer("mx"), my=sec.integer("my"),
                    dx=sec.number("dx", positive=True), dy=sec.number("dy", positive=True),
                    xl=sec.number("xl"), yl=sec.number("yl"),
                    n=sec.integer("n", 40, minimum=2), scale=sec.number("scale", 1.1, positive=True))


def _model(data: Any) -> ModelSpec:
    raw = dict(data or {})
    core = {"theory", "bound", "influence", "tol", "maxit", "layer_flexibility"}
    sec = _Section("model", {k: v for k, v in raw.items() if k in core})
    options = {k: v for k, v in raw.items() if k not in core}
    return ModelSpec(theory=sec.choice("theory", THEORIES, "fastsim"),
                     bound=sec.choice("bound", ("parabolic", "elliptic"), "parabolic"),
                     influence=sec.choice("influence", ("halfspace", "fe"), "halfspace"),
                     tol=sec.number("tol", 1e-6, positive=True),
                     maxit=sec.integer("maxit", 1000),
                     layer_flexibility=sec.number("layer_flexibility", 0.0, nonnegative=True),
                     options=options)


SECTIONS = ("name", "material", "friction", "geometry", "load", "kinematics", "grid", "model")


def scene_from_dict(data: Mapping[str, Any], base_dir: Path | str = ".", name: str = "scene") -> Scene:
    """Build a validated :class:`Scene` from a parsed TOML mapping."""
    unknown = sorted(set(data) - set(SECTIONS))
    if unknown:
        raise InputError(f"[{unknown[0]}]: unknown section (known: {', '.join(SECTIONS[1:])})")
    if "geometry" not in data:
        raise InputError("[geometry] kind: missing (one of " + ", ".join(GEOMETRY_KINDS) + ")")
    if "load" not in data:
        raise InputError("[load] normal_force: missing (give normal_force, approach or wheel_load)")
    base_dir = Path(base_dir)
    geometry = _geometry(data.get("geometry"), base_dir)
    return Scene(material=_material(data.get("material")), friction=_friction(data.get("friction")),
                 geometry=geometry, load=_load(data.get("load"), geometry),
                 kinematics=_kinematics(data.get("kinematics")), grid=_grid(data.get("grid")),
                 model=_model(data.get("model")), name=str(data.get("name", name)), base_dir=base_dir)


def load_scene(path: str | Path) -> Scene:
    """Read and validate a TOML scene file."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"scene file not found: {path}")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: not a valid TOML file ({exc})") from None
    return scene_from_dict(data, base_dir=path.parent, name=path.stem)
