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

import difflib
import math
import os
import tomllib
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Mapping

from conformal.errors import InputError
from conformal.materials import MAX_MODULUS, Material
from conformal.registry import (APPROACH_ALONG, CONFORMAL_GEOMETRY, CURVED_STRIP, HISTORY, INFLUENCE_FILE, LOAD_ANGLE, MODELS, MU_TABLE,
                                PLANAR_HALFSPACE, RIGID_SLIP, Registry, flatten_model_table)
from conformal.specs import Friction, HistoryStep, Kinematics, ModelSpec  # noqa: F401  (part of the scene API)

#: the theory names (conformal.registry.MODELS: each model's declaration)
THEORIES = MODELS.names
GEOMETRY_KINDS = ("quadratic", "hertz", "table", "wheel_rail")
#: ``[model] influence``: half-space numbers with the element frames turned by the contact angles (the
#: default), without that turn ("halfspace_planar": CONTACT's conformal approach, its D = 4 with
#: C3 = 2; theory conformal only), with Blanco-Lorenzo's angle correction ("halfspace_blanco": CONTACT's
#: C3 = 4, variant and method in [model] blanco_variant / blanco_method; conformal only) or the
#: finite-element numbers of the real wheel and rail
INFLUENCES = ("halfspace", "halfspace_planar", "halfspace_blanco", "fe")

#: model-specific ``[model]`` keys (besides theory, bound, influence, tol, maxit, layer_flexibility),
#: with the theories that read them, from the registry (conformal.registry).  Any other key is
#: rejected (a misspelt key would otherwise be ignored silently and the default model would run).
#: Keys of a method may also be nested: ``[model.fe] order`` is ``[model] fe_order``.
def model_options(models: Registry = MODELS) -> dict[str, str]:
    """The ``[model]`` keys of ``models`` (flat spelling) -> "readers: what it sets"."""
    return {key: f"{', '.join(models.readers(key)) or opt.group}: {opt.doc}" for key, opt in models.options().items()}


MODEL_OPTIONS = model_options()

#: the largest [model] tol: the iterations stop when the tractions change by less than tol (relative);
#: tol = 10 was reported converged with FX 35 % off (issue 22); the default is 1e-6
MAX_TOL = 1e-2
#: fewest grid elements across the contact patch along each axis of an automatic grid ([grid] n / scale)
MIN_ELEMENTS_ACROSS = 2.0
#: a computed contact area of fewer elements than this gets a resolution warning
MIN_CONTACT_ELEMENTS = 10
#: gauge - flange_back (mm) of a wheelset: twice the flange thickness (20-35 mm) plus play; 75 mm standard,
#: 81.2 mm the seed's wheelset, 87.7 mm a worn one
FLANGEWAY = (20.0, 140.0)
#: a wheelset yaw beyond this (rad, about 11 degrees) is outside the contact search's validity
MAX_YAW = 0.2
#: rail inclinations (cant, rad) beyond MAX_CANT are refused; beyond CANT_WARN (1:15) they warn
MAX_CANT = 0.2
CANT_WARN = 1.0 / 15.0


# ----------------------------------------------------------------------------- sections
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
    element_size_s: float | None = None  # mm, conformal strips: the element length along s (CONTACT DS; DX = element_size)
    patch_combine: float = 8.0           # mm, overlap regions closer than this form one patch
    wheel_z: str = "down"                # "up": the wheel file gives z positive upwards (negated on reading)
    rail_z: str = "down"                 # "up": the rail file gives z positive upwards (negated on reading)
    #: "auto" for wheel_z / rail_z: z mirrored where the side faces say so (CONTACT's MIRRORZ = 0)
    wheel_mirror_y: bool = False         # y negated on reading (CONTACT's MIRRORY = 1)
    rail_mirror_y: bool = False          # y negated on reading (CONTACT's MIRRORY = 1)
    wheel_smoothing: float | None = None  # mm, the wheel's own smoothing wavelength (None: smoothing)
    rail_smoothing: float | None = None   # mm, the rail's own smoothing wavelength (None: smoothing)
    max_smoothing_error: float = 0.1     # mm, the farthest a profile point may lie from its smoothed curve


Geometry = QuadraticGeometry | HertzGeometry | TableGeometry | WheelRailGeometry


@dataclass(frozen=True)
class Load:
    """Exactly one of normal_force (N), approach (mm) or wheel_load (N), and for wheel-rail scenes
    with the conformal theory the direction of the wheel load, ``load_angle`` (rad, as a contact
    angle in the JSON's convention: 0 = vertical; the wheel is pressed along that direction)."""

    normal_force: float | None = None
    approach: float | None = None
    wheel_load: float | None = None
    load_angle: float = 0.0
    approach_along: float | None = None   # mm along the load direction, from the height of ``approach``


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
    strips: str = "coupled"   # conformal wheel-rail: "coupled" (one strip) | "separate" (one per patch)

    @property
    def explicit(self) -> bool:
        return self.dx is not None


#: one ``[[history]]`` step (conformal.specs.HistoryStep: the load history with memory of
#: conformal.solvers.history), validated when built
HistoryStepSpec = HistoryStep


#: the most steps of a history (repeats counted)
MAX_HISTORY_STEPS = 10000


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
    history: tuple = ()        # HistoryStepSpec per [[history]] step (empty: one solve, no history)

    def with_model(self, **changes) -> "Scene":
        """The scene with other ``[model]`` values, e.g. ``scene.with_model(theory="exact")``,
        validated again as :meth:`with_`; ``options=`` replaces all model-specific keys.

        >>> s = scene_from_dict({"geometry": {"kind": "quadratic", "A": 0.001, "B": 0.001},
        ...                      "load": {"normal_force": 1e4}, "model": {"maxout": 3}})
        >>> s.with_model(theory="exact").model.options, s.with_model(options={"n": 20}).model.options
        ({'maxout': 3}, {'n': 20})
        """
        data = self.to_dict()
        if "options" in changes:
            core = {f.name for f in fields(ModelSpec)} - {"options"}
            data["model"] = {k: v for k, v in data["model"].items() if k in core}
            data["model"].update(dict(changes.pop("options") or {}))
        data["model"].update(changes)
        return scene_from_dict(data, base_dir=self.base_dir, name=self.name)

    def with_(self, key: str | None = None, value: Any = None, /, **changes) -> "Scene":
        """The scene with one or more keys changed, without nested :func:`dataclasses.replace`.

        Keys are dotted paths (``"model.theory"``, ``"geometry.lateral_shift"``) or, as keyword
        arguments, the same with a double underscore (``model__theory="exact"``).  A ``[model]``
        key that is not a field of :class:`ModelSpec` goes to ``model.options``.  The new scene is
        validated again (:func:`validate`).

        >>> s = scene_from_dict({"geometry": {"kind": "quadratic", "A": 0.001, "B": 0.001},
        ...                      "load": {"normal_force": 1e4}})
        >>> s.with_("model.theory", "exact").model.theory
        'exact'
        >>> s2 = s.with_(load__normal_force=2e4, model__maxout=5)
        >>> s2.load.normal_force, s2.model.options["maxout"], s.load.normal_force
        (20000.0, 5, 10000.0)
        >>> s.with_("load.approach", 0.01).load        # one load replaces the other
        Load(normal_force=None, approach=0.01, wheel_load=None, load_angle=0.0, approach_along=None)

        Keys are the TOML file's names: ``material.nu`` sets Poisson's ratio of body 1 and, where
        the scene has no ``[material.body2]``, of body 2 too (``material.body2.nu`` body 2 alone);
        ``friction.mu`` sets the static and the kinetic coefficient.  The fields' own names
        ``G1, nu1, G2, nu2`` set one body each.

        >>> s.with_("material.nu", 0.3).material
        Material(G1=82000.0, nu1=0.3, G2=82000.0, nu2=0.3)
        >>> f = s.with_(friction__mu=0.4).friction
        >>> f.mu_static, f.mu_kinetic
        (0.4, 0.4)
        """
        if key is not None:
            changes = {key: value, **changes}
        data, base_dir = self.to_dict(), self.base_dir
        for path, v in changes.items():
            path = path.replace("__", ".")
            if path == "base_dir":
                base_dir = Path(v)
                continue
            _set_toml_key(data, path, str(v) if isinstance(v, Path) else v)
        # the whole scene is checked again as if read from a file (ranges, combinations, memory)
        return scene_from_dict(data, base_dir=base_dir, name=str(data.get("name", self.name)))

    def to_dict(self) -> dict[str, Any]:
        """The scene as the mapping of its TOML file (``scene_from_dict(scene.to_dict())`` gives it
        back).

        >>> s = scene_from_dict({"geometry": {"kind": "quadratic", "A": 0.001, "B": 0.002},
        ...                      "load": {"normal_force": 1e4}})
        >>> d = s.to_dict()
        >>> d["geometry"], d["load"], scene_from_dict(d).geometry == s.geometry
        ({'kind': 'quadratic', 'A': 0.001, 'B': 0.002}, {'normal_force': 10000.0}, True)
        """
        def plain(obj) -> dict:
            return {f.name: getattr(obj, f.name) for f in fields(obj) if getattr(obj, f.name) is not None}

        m = self.material
        material: dict[str, Any] = {"G": m.G1, "nu": m.nu1}
        if (m.G2, m.nu2) != (m.G1, m.nu1):
            material["body2"] = {"G": m.G2, "nu": m.nu2}
        f = self.friction
        friction = {"mu": f.mu_kinetic} if f.mu_static == f.mu_kinetic else {"mu_static": f.mu_static,
                                                                                "mu_kinetic": f.mu_kinetic}
        if f.mu_table is not None:
            friction["mu_table"] = str(Path(f.mu_table).resolve())
        if f.angle_table:
            friction["angle_table"] = [list(r) for r in f.angle_table]
        geometry = plain(self.geometry)
        geometry = {"kind": geometry.pop("kind"), **geometry}
        if "file" in geometry:
            geometry["file"] = str(Path(geometry["file"]).resolve())
        model = plain(self.model)
        model.update(model.pop("options", {}))
        kinematics = plain(self.kinematics)
        if kinematics.get("direction") == 1:       # the default: not written (older readers)
            kinematics.pop("direction")
        for creep, force in (("xi", "fx_rel"), ("eta", "fy_rel")):   # a prescribed force, not both
            if force in kinematics:
                kinematics.pop(creep, None)
        if "rigid_slip" in kinematics:
            kinematics["rigid_slip"] = str(Path(kinematics["rigid_slip"]).resolve())
        out = {"name": self.name, "material": material, "friction": friction, "geometry": geometry,
               "load": {k: v for k, v in plain(self.load).items() if not (k == "load_angle" and v == 0.0)},
               "kinematics": kinematics, "grid": plain(self.grid),
               "model": model}
        if self.history:
            d0 = HistoryStepSpec()
            out["history"] = [{f.name: getattr(h, f.name) for f in fields(h)
                               if getattr(h, f.name) is not None and getattr(h, f.name) != getattr(d0, f.name)}
                              for h in self.history]
        return out


#: keys of which a TOML section holds at most one: setting one drops the others
_EXCLUSIVE = {"load": (("normal_force", "approach", "wheel_load"),),
              "kinematics": (("xi", "fx_rel"), ("eta", "fy_rel")),
              "material": (("G", "E"),)}


def _set_toml_key(data: dict, path: str, value: Any) -> None:
    """Set ``section.key`` (or ``material.body2.key``) in a scene's TOML mapping (``Scene.to_dict``),
    in place, as an edit of the file would; the caller validates the result."""
    parts = path.split(".")
    if len(parts) == 1:
        if parts[0] != "name":
            raise InputError(f"{path}: not a scene key; use section.key, e.g. \"model.theory\"")
        data["name"] = value
        return
    sec = parts[0]
    if sec not in SECTIONS[1:]:
        raise InputError(f"[{sec}]: unknown section{_did_you_mean(sec, SECTIONS[1:])}")
    table = data.setdefault(sec, {})
    if sec == "material":
        _set_material_key(table, parts[1:], value, path)
        return
    if sec == "model" and len(parts) == 3 and parts[1] in {me.name for me in MODELS.methods}:
        (flat,) = flatten_model_table({parts[1]: {parts[2]: value}})     # an unknown key: InputError
        parts = [sec, flat]
    if len(parts) != 2:
        raise InputError(f"{path}: expected section.key, e.g. \"model.theory\"")
    key = parts[1]
    if sec == "friction" and key in ("mu", "mu_static", "mu_kinetic"):
        if key == "mu":
            table.pop("mu_static", None), table.pop("mu_kinetic", None)
        elif "mu" in table:          # one of the two coefficients: the other keeps the old mu
            mu = table.pop("mu")
            table.update(mu_static=mu, mu_kinetic=mu)
    for group in _EXCLUSIVE.get(sec, ()):
        if key in group:
            for other in group:
                table.pop(other, None)
    if sec == "load" and key == "approach_along":       # an approach along the load direction: from
        table.pop("normal_force", None), table.pop("wheel_load", None)   # first touch or [load] approach
    elif sec == "load" and key in ("normal_force", "approach", "wheel_load"):
        table.pop("approach_along", None)
    if value is None:           # TOML has no null: None removes the key (its default applies)
        table.pop(key, None)
        return
    table[key] = value


def _set_material_key(table: dict, keys: list[str], value: Any, path: str) -> None:
    """``material.G|E|nu`` (body 1, and body 2 while the bodies are alike), ``material.body2.G|E|nu``,
    ``material.body2`` (the table) and the field names ``G1, nu1, G2, nu2`` (one body each)."""
    def body2() -> dict:
        if "body2" not in table:     # alike until now: body 2 keeps the current constants
            table["body2"] = {k: v for k, v in table.items() if k != "body2"}
        return table["body2"]

    def put(t: dict, key: str, v: Any) -> None:
        if key in ("G", "E"):
            t.pop("G", None), t.pop("E", None)
        t[key] = v

    legacy = {"G1": (False, "G"), "nu1": (False, "nu"), "G2": (True, "G"), "nu2": (True, "nu")}
    if len(keys) == 1 and keys[0] in legacy:
        second, key = legacy[keys[0]]
        target = body2()             # either way the bodies may differ from now on
        put(target if second else table, key, value)
    elif len(keys) == 1 and keys[0] in ("G", "E", "nu"):
        put(table, keys[0], value)
    elif len(keys) == 2 and keys[0] == "body2" and keys[1] in ("G", "E", "nu"):
        put(body2(), keys[1], value)
    elif keys == ["body2"]:          # the whole [material.body2] table (None: the bodies alike again)
        if value is None:
            table.pop("body2", None)
        else:
            table["body2"] = dict(value) if isinstance(value, Mapping) else value   # checked on validation
    else:
        key = ".".join(keys)
        raise InputError(f"[material] {key}: unknown key"
                         f"{_did_you_mean(key, ['G', 'E', 'nu', 'body2.G', 'body2.E', 'body2.nu'])}")


def _did_you_mean(key: str, known) -> str:
    """' (did you mean 'x'?)' for the closest known key (case-insensitive), else ''."""
    known = [str(k) for k in known]
    lower = {k.lower(): k for k in known}
    if str(key).lower() in lower:
        return f" (did you mean {lower[str(key).lower()]!r}?)"
    close = difflib.get_close_matches(str(key).lower(), list(lower), n=1, cutoff=0.6)
    return f" (did you mean {lower[close[0]]!r}?)" if close else ""


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
                raise InputError(f"[{name}] {unknown[0]}: unknown key{_did_you_mean(unknown[0], known)} "
                                 f"(known: {', '.join(sorted(known))})")

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
        key = "G" if sec.has("G") else "E"
        v = sec.number(key, positive=True)
        if v > MAX_MODULUS:       # the contact modulus and the Hertz sizes leave the float range (G = 1e308)
            raise sec.error(key, f"must be <= {MAX_MODULUS:g} N/mm² (a thousand times diamond's; rigid enough for a "
                                 f"rigid body), got {v:g}")
        return (v, nu) if key == "G" else (v / (2.0 * (1.0 + nu)), nu)

    if data is None:
        data = {"G": 82000.0, "nu": 0.28}
    if not isinstance(data, Mapping):
        raise InputError(f"[material] must be a table (G or E, nu), got {type(data).__name__} {data!r}")
    data = dict(data)
    body2 = data.pop("body2", None)
    G1, nu1 = constants(_Section("material", data, {"G", "E", "nu"}))
    G2, nu2 = (G1, nu1) if body2 is None else constants(_Section("material.body2", body2, {"G", "E", "nu"}))
    return Material(G1, nu1, G2, nu2)


def _input_file(sec: "_Section", key: str, base_dir: Path) -> Path | None:
    """An optional input file named by ``key``, relative to the scene's folder; must exist."""
    f = sec.string(key)
    if f is None:
        return None
    if not f:
        raise sec.error(key, "an empty file name")
    path = (base_dir / f) if not Path(f).is_absolute() else Path(f)
    if not path.is_file():
        raise sec.error(key, f"no such file: {path}")
    return path


def _friction(data: Any, base_dir: Path = Path(".")) -> Friction:
    data = dict(data) if isinstance(data, Mapping) else data
    table = None
    if isinstance(data, dict) and "mu_table" in data:   # friction varying over the profile: (s, mu) rows
        table = _input_file(_Section("friction", {"mu_table": data["mu_table"]}), "mu_table", base_dir)
        data.pop("mu_table")
    angles: tuple = ()
    if isinstance(data, dict) and "angle_table" in data:   # friction over the contact angle (wheel_rail)
        angles = _angle_table(data.pop("angle_table"))
        if not any(k in data for k in ("mu", "mu_static", "mu_kinetic")):
            data["mu_static"], data["mu_kinetic"] = angles[0][1], angles[0][2]
    fr = _friction_constant(data)
    if table is not None or angles:
        return Friction(fr.mu_static, fr.mu_kinetic, table, angles)
    return fr


def _angle_table(rows: Any) -> tuple:
    """``[friction] angle_table``: rows [alpha (rad), mu_static, mu_kinetic], alpha increasing,
    0 < mu_kinetic <= mu_static."""
    key = "[friction] angle_table"
    if not isinstance(rows, (list, tuple)) or not rows:
        raise InputError(f"{key}: a list of rows [alpha, mu_static, mu_kinetic], got {rows!r}")
    out = []
    for row in rows:
        if (not isinstance(row, (list, tuple)) or len(row) != 3
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in row)):
            raise InputError(f"{key}: each row is three numbers [alpha (rad), mu_static, mu_kinetic], got {row!r}")
        a, ms, mk = (float(v) for v in row)
        if abs(a) > math.pi:          # a contact angle lies within +-pi/2: 70 is degrees
            raise InputError(f"{key}: the angle alpha is in rad and must lie within +-pi, got {a:g} "
                             f"(degrees? {a:g} deg = {math.radians(a):.4g} rad)")
        if not 0.0 < mk <= ms:
            raise InputError(f"{key}: each row needs 0 < mu_kinetic <= mu_static, got {row!r}")
        out.append((a, ms, mk))
    if any(b[0] <= a[0] for a, b in zip(out, out[1:])):
        raise InputError(f"{key}: the angles must increase")
    return tuple(out)


def _friction_constant(data: Any) -> Friction:
    sec = _Section("friction", data if data is not None else {"mu": 0.3},
                   {"mu", "mu_static", "mu_kinetic", "mu_table", "angle_table"})
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
    if not isinstance(data, Mapping):
        raise InputError(f"[geometry] must be a table, got {type(data).__name__} {data!r}")
    raw = dict(data)
    kind = _Section("geometry", raw).choice("kind", GEOMETRY_KINDS)
    if kind == "quadratic":
        sec = _Section("geometry", raw, {"kind", "A", "B"})
        # B = 0: line contact (plane strain, conformal.solvers.line; the load is per mm of line)
        return QuadraticGeometry(sec.number("A", required=True, positive=True),
                                 sec.number("B", required=True, nonnegative=True))
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
    yaw = sec.number("yaw", d.yaw)
    if abs(yaw) > MAX_YAW:
        raise sec.error("yaw", f"the wheelset yaw must lie within +-{MAX_YAW:g} rad "
                               f"({math.degrees(MAX_YAW):.0f} degrees), got {yaw:g} rad")
    cant = sec.number("rail_cant", d.rail_cant)
    if abs(cant) > MAX_CANT:
        raise sec.error("rail_cant", f"the rail inclination must lie within +-{MAX_CANT:g} rad "
                                     f"(1:40 = 0.025, 1:20 = 0.05), got {cant:g} rad")
    gauge = sec.number("gauge", d.gauge, positive=True)
    flange_back = sec.number("flange_back", d.flange_back, positive=True)
    play = gauge - flange_back
    if placement == "wheelset" and not FLANGEWAY[0] <= play <= FLANGEWAY[1]:
        key = "gauge" if sec.has("gauge") and (gauge != d.gauge or not sec.has("flange_back")) else "flange_back"
        raise sec.error(key, f"gauge - flange_back = {gauge:g} - {flange_back:g} = {play:g} mm must lie within "
                        f"{FLANGEWAY[0]:g} to {FLANGEWAY[1]:g} mm (twice a flange's thickness and play; standard "
                        f"1435 - 1360 = 75 mm): otherwise the wheels do not lie over their rails")
    if roll is not None and abs(roll) > MAX_YAW:
        raise sec.error("roll", f"the wheelset roll must lie within +-{MAX_YAW:g} rad, got {roll:g} rad")
    shift = sec.number("lateral_shift", d.lateral_shift)
    if abs(shift) > gauge:    # 1e300: the contact search ran on inf and NaN before it gave up
        raise sec.error("lateral_shift", f"must lie within +-gauge = +-{gauge:g} mm (the wheels leave their rails "
                                         f"long before), got {shift:g} mm")
    return WheelRailGeometry(
        wheel_profile=sec.string("wheel_profile", d.wheel_profile),
        rail_profile=sec.string("rail_profile", d.rail_profile),
        side=side, placement=placement,
        lateral_shift=sec.number("lateral_shift", d.lateral_shift),
        yaw=yaw, roll=roll,
        rail_cant=cant,
        gauge=gauge,
        gauge_height=sec.number("gauge_height", d.gauge_height, nonnegative=True),
        flange_back=flange_back,
        wheel_radius=sec.number("wheel_radius", d.wheel_radius, positive=True),
        flange_back_pos=sec.number("flange_back_pos"),
        element_size_s=_element_size_s(sec),
        smoothing=sec.number("smoothing", d.smoothing, nonnegative=True),
        element_size=_element_size(sec),
        patch_combine=sec.number("patch_combine", d.patch_combine, nonnegative=True),
        wheel_z=sec.choice("wheel_z", ("down", "up", "auto"), d.wheel_z),
        rail_z=sec.choice("rail_z", ("down", "up", "auto"), d.rail_z),
        wheel_mirror_y=_flag(sec, "wheel_mirror_y"),
        rail_mirror_y=_flag(sec, "rail_mirror_y"),
        wheel_smoothing=sec.number("wheel_smoothing", nonnegative=True),
        rail_smoothing=sec.number("rail_smoothing", nonnegative=True),
        max_smoothing_error=sec.number("max_smoothing_error", d.max_smoothing_error, positive=True),
    )


def _flag(sec: "_Section", key: str) -> bool:
    """A true/false key of a table (default false)."""
    v = sec.data.get(key, False)
    if not isinstance(v, bool):
        raise sec.error(key, f"must be true or false, got {v!r}")
    return v


#: mm, the largest [geometry] element_size: one element then covers a whole contact patch (a larger one
#: reaches beyond the rail head: the grid's surface is not found)
MAX_ELEMENT_SIZE = 20.0


def _element_size(sec: "_Section") -> float | None:
    """``[geometry] element_size`` (mm): > 0 and at most MAX_ELEMENT_SIZE."""
    value = sec.number("element_size", positive=True)
    if value is not None and value > MAX_ELEMENT_SIZE:
        raise sec.error("element_size", f"must be <= {MAX_ELEMENT_SIZE:g} mm (one element then covers a whole "
                        f"contact patch; typical 0.1-1 mm), got {value:g}")
    return value


def _element_size_s(sec: "_Section") -> float | None:
    """``[geometry] element_size_s``: the element length along s of a conformal strip (CONTACT's DS),
    beside ``element_size`` (then the length along x, CONTACT's DX)."""
    value = sec.number("element_size_s", positive=True)
    if value is not None and not sec.has("element_size"):
        raise sec.error("element_size_s", "give element_size (the element length along x) with it")
    return value


def _load(data: Any, geometry: Geometry) -> Load:
    sec = _Section("load", data, {"normal_force", "approach", "wheel_load", "load_angle", "approach_along"})
    given = [k for k in ("normal_force", "approach", "wheel_load") if sec.has(k)]
    along = sec.number("approach_along")
    if along is not None:
        # the approach along the load direction (CONTACT's PEN along a direction), from the height
        # [load] approach (default 0: the first touch) below the first touch
        if geometry.kind != "wheel_rail":
            raise sec.error("approach_along", "only for [geometry] kind = \"wheel_rail\" (other scenes: approach)")
        if any(k in given for k in ("normal_force", "wheel_load")):
            raise sec.error("approach_along", "give either a load (wheel_load) or approach_along, not both")
        vertical = sec.number("approach", 0.0, nonnegative=True)
        if not (along > 0.0 or vertical > 0.0):
            raise sec.error("approach_along", f"must be > 0 from the first touch (without [load] approach), got {along:g}")
        return Load(approach=vertical, approach_along=along, load_angle=_load_angle(sec, geometry))
    if len(given) != 1:
        raise sec.error("normal_force", "give exactly one of normal_force (N), approach (mm) or wheel_load (N)")
    key = given[0]
    if key == "wheel_load" and geometry.kind != "wheel_rail":
        raise sec.error("wheel_load", "only for [geometry] kind = \"wheel_rail\"; use normal_force")
    if key == "approach" and geometry.kind == "table":
        # a gap table may already hold the approach (CONTACT's PEN = 0 with IBASE = 9): 0 is allowed
        value = sec.number(key, nonnegative=True)
    else:
        value = sec.number(key, positive=True)
    return Load(**{key: value}, load_angle=_load_angle(sec, geometry))


def _load_angle(sec: "_Section", geometry: Geometry) -> float:
    angle = sec.number("load_angle", 0.0)
    if angle != 0.0 and geometry.kind != "wheel_rail":
        raise sec.error("load_angle", "only for [geometry] kind = \"wheel_rail\" (the load of other scenes is "
                        "along the contact normal)")
    if not abs(angle) < 1.4:
        raise sec.error("load_angle", f"must lie within +-1.4 rad (80 degrees) of the vertical, got {angle!r}")
    return angle


def _kinematics(data: Any, base_dir: Path = Path(".")) -> Kinematics:
    known = {"xi", "eta", "phi", "rolling", "fx_rel", "fy_rel", "velocity",
             "speed", "pitch_velocity", "yaw_rate", "roll_rate", "lateral_velocity", "direction", "rigid_slip"}
    sec = _Section("kinematics", data, known)
    direction = sec.integer("direction", 1, minimum=-1)
    if direction not in (1, -1):
        raise sec.error("direction", f"the rolling direction must be 1 (+x) or -1 (-x), got {direction}")
    rigid_slip = _input_file(sec, "rigid_slip", base_dir)
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
                      lateral_velocity=sec.number("lateral_velocity", 0.0),
                      direction=direction, rigid_slip=rigid_slip)


def _history(data: Any) -> tuple:
    """The ``[[history]]`` steps (an array of tables), validated; () without."""
    if data is None:
        return ()
    if isinstance(data, Mapping):
        data = [data]
    if not isinstance(data, (list, tuple)) or not data or not all(isinstance(d, Mapping) for d in data):
        raise InputError("[[history]]: an array of tables, one [[history]] section per step")
    known = {f.name for f in fields(HistoryStepSpec)}
    steps, total = [], 0
    for k, d in enumerate(data, 1):
        sec = _Section(f"history {k}", d, known)
        if sec.has("normal_force") and sec.has("approach"):
            raise sec.error("normal_force", "give at most one of normal_force or approach per step")
        for creep, force in (("xi", "fx_rel"), ("eta", "fy_rel")):
            if sec.has(creep) and sec.has(force):
                raise sec.error(force, f"give either {creep} or {force}, not both")
        rolling = sec.choice("rolling", ("shift", "transient", "steady"), "shift")
        if sec.has("distance") and rolling != "transient":
            raise sec.error("distance", "only for rolling = \"transient\"")
        fx, fy = sec.number("fx_rel"), sec.number("fy_rel")
        for key, v in (("fx_rel", fx), ("fy_rel", fy)):
            if v is not None and abs(v) >= 1.0:
                raise sec.error(key, f"a force F/(mu FN) must lie in (-1, 1), got {v:g}")
        step = HistoryStepSpec(normal_force=sec.number("normal_force", positive=True),
                               approach=sec.number("approach", positive=True),
                               xi=sec.number("xi", 0.0), eta=sec.number("eta", 0.0), phi=sec.number("phi", 0.0),
                               rolling=rolling, distance=sec.number("distance", positive=True),
                               fx_rel=fx, fy_rel=fy, repeat=sec.integer("repeat", 1))
        total += step.repeat
        if total > MAX_HISTORY_STEPS:
            raise sec.error("repeat", f"at most {MAX_HISTORY_STEPS} steps in a history")
        steps.append(step)
    return tuple(steps)


def _grid(data: Any) -> GridSpec:
    sec = _Section("grid", data, {"mx", "my", "dx", "dy", "xl", "yl", "n", "scale", "strips"})
    explicit = [k for k in ("mx", "my", "dx", "dy") if sec.has(k)]
    if explicit and len(explicit) != 4:
        missing = sorted({"mx", "my", "dx", "dy"} - set(explicit))
        raise sec.error(missing[0], "an explicit grid needs all of mx, my, dx, dy")
    n, scale = sec.integer("n", 40, minimum=2), sec.number("scale", 1.1, positive=True)
    if not explicit and n / scale < MIN_ELEMENTS_ACROSS:
        key = "scale" if sec.has("scale") or not sec.has("n") else "n"
        raise sec.error(key, f"the grid of n = {n} elements spans scale = {scale:g} times the contact patch: "
                        f"{n / scale:.3g} elements across it, fewer than {MIN_ELEMENTS_ACROSS:g}; use "
                        f"scale <= n/{MIN_ELEMENTS_ACROSS:g} (the default scale is 1.1)")
    return GridSpec(mx=sec.integer("mx"), my=sec.integer("my"),
                    dx=sec.number("dx", positive=True), dy=sec.number("dy", positive=True),
                    xl=sec.number("xl"), yl=sec.number("yl"),
                    n=n, scale=scale,
                    strips=sec.choice("strips", ("coupled", "separate"), "coupled"))


def _model(data: Any, base_dir: Path = Path("."), models: Registry = MODELS) -> ModelSpec:
    if data is not None and not isinstance(data, Mapping):
        raise InputError(f"[model] must be a table, got {type(data).__name__} {data!r}")
    raw = flatten_model_table(dict(data or {}), models)     # [model.fe] order -> fe_order, ...
    core = {f.name for f in fields(ModelSpec)} - {"options"}
    _Section("model", raw, core | set(models.options()))      # unknown keys (with the closest known one)
    sec = _Section("model", {k: v for k, v in raw.items() if k in core})
    options = {k: v for k, v in raw.items() if k not in core}
    _check_model_options(sec, options, models)
    if options.get("table") not in (None, "default"):   # a creep-force table: relative to the scene's folder
        options["table"] = str(_input_file(_Section("model", options), "table", base_dir).resolve())
    tol = sec.number("tol", 1e-6, positive=True)
    if tol > MAX_TOL:
        raise sec.error("tol", f"the solvers' relative stopping tolerance must be <= {MAX_TOL:g}, got {tol:g} "
                        "(a larger one stops before the tractions are found; the default is 1e-6)")
    return ModelSpec(theory=sec.choice("theory", models.names, "fastsim"),
                     bound=sec.choice("bound", ("parabolic", "elliptic"), "parabolic"),
                     influence=sec.choice("influence", INFLUENCES, "halfspace"),
                     tol=tol,
                     maxit=sec.integer("maxit", 1000),
                     layer_flexibility=sec.number("layer_flexibility", 0.0, nonnegative=True),
                     options=options)


def _check_model_options(sec: "_Section", options: Mapping[str, Any], models: Registry = MODELS) -> None:
    """Refuse a bad value of a [model] option (InputError naming the key), checked against its
    declaration in the registry when the scene is read, so that a bad value is refused whatever the
    theory (it was ignored where the theory did not read it)."""
    declared = models.options()
    for key, v in options.items():
        problem = declared[key].problem(v) if key in declared else None
        if problem:
            raise sec.error(key, f"{problem} ({model_options(models)[key]})")


SECTIONS = ("name", "material", "friction", "geometry", "load", "kinematics", "grid", "model")


def available_memory() -> float | None:
    """Memory available to this process (bytes): /proc/meminfo MemAvailable, else the physical
    memory, else None."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def grid_bytes(mx: int, my: int, theory: str, models: Registry = MODELS) -> float:
    """An estimate of the memory (bytes) an mx x my grid needs with ``theory`` (its declaration in
    the registry: :meth:`conformal.registry.Model.grid_bytes`)."""
    return models.grid_bytes(mx, my, theory)


#: the most elements of any grid (planar n x n, mx x my, line grids, conformal strips, CONTACT decks):
#: 1000 x 1000, six times the largest grid the validation measures (400², docs/validation/halfspace.md);
#: a larger one fits the memory of a workstation but runs for many minutes (a line grid of 5.5 million
#: elements does) and resolves nothing a 1000-element row or a 400 x 400 grid does not
MAX_GRID_ELEMENTS = 1_000_000


#: grids needing less than this (bytes) are not checked against the available memory: reading
#: /proc/meminfo for every patch grid of a sweep cost 2 % of its time, and a machine with less than
#: 256 MiB free fails on the interpreter before such a grid
SMALL_GRID_BYTES = 2**28


def check_grid_memory(mx: int, my: int, theory: str, key: str, hint: str = "use a coarser grid",
                      models: Registry = MODELS) -> None:
    """Refuse (InputError naming ``key``) an mx x my grid of more than :data:`MAX_GRID_ELEMENTS`
    elements, or whose estimated memory with ``theory`` (:func:`grid_bytes`) exceeds 80 % of the
    memory available, before anything is allocated."""
    need = grid_bytes(mx, my, theory, models)
    avail = available_memory() if need > SMALL_GRID_BYTES else None
    if avail is not None and need > 0.8 * avail:
        raise InputError(f"{key}: a {mx} x {my} grid needs about {need / 2**30:.3g} GiB with theory "
                         f"{theory!r}, more than the {avail / 2**30:.3g} GiB available; {hint}")
    if float(mx) * float(my) > MAX_GRID_ELEMENTS:
        raise InputError(f"{key}: a {mx} x {my} grid has {float(mx) * float(my):.3g} elements, more than "
                         f"{MAX_GRID_ELEMENTS:.0e} (1000 x 1000; the largest measured grid is 400 x 400) and "
                         f"would run for many minutes; {hint}")


def grid_memory(scene: "Scene", models: Registry = MODELS) -> tuple[int, int, float]:
    """(mx, my, bytes): an estimate of the memory the scene's grid needs with its theory, before
    anything is allocated.  Wheel-rail grids sized by ``element_size`` are not known here: (0, 0, 0)
    (they are checked where their size becomes known: conformal.geometry.patches)."""
    g, theory = scene.grid, scene.model.theory
    if g.explicit:
        mx, my = int(g.mx), int(g.my)
    elif scene.geometry.kind == "wheel_rail" and scene.geometry.element_size is not None:
        return 0, 0, 0.0
    elif isinstance(scene.geometry, QuadraticGeometry) and scene.geometry.B == 0.0:
        mx, my = int(g.n), 1          # line contact: a row of n elements (conformal.problem)
    else:
        mx = my = int(g.n)
    return mx, my, grid_bytes(mx, my, theory, models)


def validate(scene: "Scene", models: Registry = MODELS) -> "Scene":
    """Checks that need several sections (a grid too large for the memory of this machine, the
    ranges of changed keys, what the theory accepts: its declaration in ``models``); raises
    :class:`InputError` naming the key.  Returns the scene."""
    theory = scene.model.theory
    if theory not in models:
        raise InputError(f"[model] theory: must be one of {', '.join(models.names)}, got {theory!r}"
                         f"{_did_you_mean(theory, models.names)}")
    model = models[theory]
    geo = scene.geometry
    kin, fr = scene.kinematics, scene.friction
    for key, given, cap in (("[kinematics] direction", kin.direction == -1, None),
                            ("[kinematics] rigid_slip", kin.rigid_slip is not None, RIGID_SLIP),
                            ("[friction] mu_table", fr.mu_table is not None, MU_TABLE),
                            ("[model] influence_file", "influence_file" in scene.model.options, INFLUENCE_FILE)):
        if given and isinstance(geo, WheelRailGeometry):
            raise InputError(f"{key}: for planar scenes (kind quadratic, hertz, table); not yet for wheel_rail scenes")
        if given and cap is not None and not model.accepts(cap):
            raise InputError(f"{key}: only theory {models.quoted(cap)} uses it (got theory {theory!r}); "
                             "other theories would ignore it")
    if fr.angle_table and (not isinstance(geo, WheelRailGeometry)
                           or (model.accepts(CONFORMAL_GEOMETRY) and not model.accepts(CURVED_STRIP))):
        raise InputError("[friction] angle_table: for wheel_rail scenes (one friction per patch at its contact angle, "
                         "per row on a conformal strip); not for planar scenes or theory fe_contact")
    if scene.history:
        if isinstance(geo, WheelRailGeometry):
            raise InputError("[[history]]: load histories are for planar scenes (kind quadratic, hertz, table)")
        if not model.accepts(HISTORY):
            raise InputError(f"[[history]]: a load history is solved by theory {models.quoted(HISTORY)}, got {theory!r}")
        if kin.direction == -1 or kin.rigid_slip is not None or fr.mu_table is not None \
                or "influence_file" in scene.model.options:
            raise InputError("[[history]]: not combined with direction = -1, rigid_slip, mu_table or influence_file")
    if scene.model.influence in ("halfspace_planar", "halfspace_blanco") and not model.accepts(PLANAR_HALFSPACE):
        raise InputError(f"[model] influence: \"{scene.model.influence}\" (CONTACT's conformal approach) is for theory "
                         f"{models.quoted(PLANAR_HALFSPACE)}, got theory {theory!r}")
    if scene.load.approach_along is not None and not model.accepts(APPROACH_ALONG):
        raise InputError(f"[load] approach_along: an approach along the load direction needs [model] theory = "
                         f"{models.quoted(APPROACH_ALONG)}, got {theory!r}")
    if scene.load.load_angle != 0.0 and not model.accepts(LOAD_ANGLE):
        raise InputError(f"[load] load_angle: a load direction other than vertical needs [model] theory = "
                         f"{models.quoted(LOAD_ANGLE)} (the {theory!r} model balances the vertical load)")
    if isinstance(geo, WheelRailGeometry):
        if abs(geo.yaw) > MAX_YAW:
            raise InputError(f"[geometry] yaw: the wheelset yaw must lie within +-{MAX_YAW:g} rad, got {geo.yaw:g}")
        if abs(geo.rail_cant) > MAX_CANT:
            raise InputError(f"[geometry] rail_cant: must lie within +-{MAX_CANT:g} rad, got {geo.rail_cant:g}")
    mx, my, _ = grid_memory(scene, models)
    if mx:
        check_grid_memory(mx, my, scene.model.theory, "[grid] mx" if scene.grid.explicit else "[grid] n",
                          models=models)
    return scene


def scene_warnings(scene: "Scene") -> list[str]:
    """Warnings about a valid but physically questionable scene (reported on stderr and in the JSON's
    ``warnings``): a rail inclination steeper than 1:15.  (Warnings about results, e.g. the linear
    theory beyond the friction bound, come from the models.)"""
    out = []
    geo = scene.geometry
    kin = scene.kinematics
    if scene.model.theory in MODELS and MODELS[scene.model.theory].normal_only:
        given = [k for k in ("xi", "eta", "phi") if getattr(kin, k) != 0.0]
        given += [k for k in ("fx_rel", "fy_rel", "speed") if getattr(kin, k) is not None]
        if given:
            out.append(f"[kinematics] {', '.join(given)}: theory {scene.model.theory!r} solves the normal problem "
                       "only; the creepages are not used (FX = FY = MZ = 0); a tangential theory (fastsim, "
                       "exact, conformal, ...) uses them")
    out += unread_model_options(scene)
    if isinstance(geo, WheelRailGeometry) and abs(geo.rail_cant) > CANT_WARN:
        out.append(f"[geometry] rail_cant = {geo.rail_cant:g} rad is steeper than 1:15 ({CANT_WARN:.4f} rad); "
                   "rails are inclined 1:20 (0.05) or 1:40 (0.025): is this the cant in rad?")
    return out


#: theories that do not iterate to ``[model] tol`` within ``maxit`` (closed forms, FASTSIM's one pass,
#: a table look-up)
NOT_ITERATED = ("hertz", "linear", "empirical", "johnson_vermeulen", "fastsim", "table")


def unread_model_options(scene: "Scene", models: Registry = MODELS) -> list[str]:
    """Warnings for ``[model]`` keys the scene's theory does not read (a key of another theory, or
    an FE key without ``influence = "fe"``; ``tol`` / ``maxit`` with a theory of
    :data:`NOT_ITERATED`, ``bound`` with a theory other than fastsim, fe_contact's section keys with
    another body), given with a value other than the default: valid, but without effect on this solve.

    >>> s = scene_from_dict({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
    ...                      "load": {"normal_force": 1e4}, "model": {"theory": "exact", "fec_n": 6}})
    >>> unread_model_options(s)[0][:64]
    "[model] fec_n: not read by theory 'exact' (read by fe_contact); "
    """
    theory = scene.model.theory
    if theory not in models:
        return []
    model = models[theory]
    own = {o.key for o in model.options} | {o.key for me in model.methods for o in models.method(me).options}
    fe_keys = {o.key for o in models.method("fe").options} if "fe" in {me.name for me in models.methods} else set()
    out = []
    spec, default = scene.model, ModelSpec()
    if theory in NOT_ITERATED:
        for key in ("tol", "maxit"):
            if getattr(spec, key) != getattr(default, key):
                out.append(f"[model] {key} = {getattr(spec, key):g}: theory {theory!r} does not iterate to a "
                           "tolerance (closed form or one pass); it has no effect here")
    if spec.bound != default.bound and theory != "fastsim":
        out.append(f"[model] bound = {spec.bound!r}: the traction bound of FASTSIM, read only by theory "
                   f"'fastsim' (this scene: {theory!r}); it has no effect here")
    body = spec.options.get("fec_body", "disc")
    for key in ("fec_section_size", "fec_section_h_max"):
        if key in spec.options and key in own and body != "section":
            out.append(f"[model] {key}: read only with [model] fec_body = \"section\", this scene has fec_body = "
                       f"{body!r}; it has no effect here")
    for key in scene.model.options:
        if key not in own:
            readers = ", ".join(models.readers(key)) or "no theory"
            out.append(f"[model] {key}: not read by theory {theory!r} (read by {readers}); it has no effect here")
        elif key in fe_keys and scene.model.influence != "fe":
            out.append(f"[model] {key}: read only with [model] influence = \"fe\" (FE influence numbers), this "
                       f"scene has influence = {scene.model.influence!r}; it has no effect here")
    return out


def scene_from_dict(data: Mapping[str, Any], base_dir: Path | str = ".", name: str = "scene",
                    models: Registry = MODELS) -> Scene:
    """Build a validated :class:`Scene` from a parsed TOML mapping.

    Every section is checked: unknown keys are refused with the closest known one, values are
    range-checked, and a grid that would not fit in memory is refused before anything is allocated.

    Parameters
    ----------
    data : mapping
        The parsed TOML: sections ``material``, ``friction``, ``geometry``, ``load``,
        ``kinematics``, ``grid``, ``model`` and an optional ``name``.
    base_dir : path, optional
        Folder that relative file names (profiles, tables) are taken from.
    name : str, optional
        Name of the scene when ``data`` has none.
    models : Registry, optional
        The models the scene may name (:data:`conformal.registry.MODELS`, or one extended by
        :meth:`~conformal.registry.Registry.with_model`).

    Returns
    -------
    Scene

    Raises
    ------
    InputError
        Naming the section and the key, e.g. ``[model] Theory: unknown key (did you mean 'theory'?)``.

    Examples
    --------
    >>> scene_from_dict({"geometry": {"kind": "quadratic", "A": 0.001, "B": 0.001},
    ...                  "load": {"normal_force": 1e4}, "model": {"thoery": "exact"}})
    Traceback (most recent call last):
    ...
    conformal.errors.InputError: [model] thoery: unknown key (did you mean 'theory'?) (known: ...)
    """
    if not isinstance(data, Mapping):
        raise InputError(f"a scene must be a table of sections, got {type(data).__name__}")
    unknown = sorted(set(data) - set(SECTIONS) - {"history"})
    if "vehicle" in unknown:          # a vehicle scene (conformal.dynamics.scene) given to solve
        raise InputError("[vehicle]: this is a vehicle scene (suspended wheelset); run it with `conformal "
                         "simulate` or `conformal stability`, a contact scene has [geometry] and [load]")
    if unknown:
        raise InputError(f"[{unknown[0]}]: unknown section{_did_you_mean(unknown[0], SECTIONS)} "
                         f"(known: {', '.join(SECTIONS[1:])})")
    for sec in SECTIONS[1:]:
        if sec in data and not isinstance(data[sec], Mapping):
            raise InputError(f"[{sec}] must be a table (a [{sec}] section), got {sec} = {data[sec]!r}")
    if "name" in data and (not isinstance(data["name"], str) or not data["name"].strip()):
        raise InputError(f"name: must be a non-empty string (it names the outputs), got {data['name']!r}")
    if "geometry" not in data:
        raise InputError("[geometry] kind: missing (one of " + ", ".join(GEOMETRY_KINDS) + ")")
    if "load" not in data:
        raise InputError("[load] normal_force: missing (give normal_force, approach or wheel_load)")
    base_dir = Path(base_dir)
    geometry = _geometry(data.get("geometry"), base_dir)
    scene = Scene(material=_material(data.get("material")), friction=_friction(data.get("friction"), base_dir),
                  geometry=geometry, load=_load(data.get("load"), geometry),
                  kinematics=_kinematics(data.get("kinematics"), base_dir), grid=_grid(data.get("grid")),
                  model=_model(data.get("model"), base_dir, models), name=str(data.get("name", name)), base_dir=base_dir,
                  history=_history(data.get("history")))
    return validate(scene, models)


def as_scene(source: "Scene | str | Path | Mapping[str, Any]", **overrides: Any) -> Scene:
    """A validated scene from a Scene, a TOML file path or a mapping, with ``section__key=value``
    overrides applied (:meth:`Scene.with_`); the API's :func:`conformal.load_scene`."""
    if isinstance(source, Scene):
        scene = source
    elif isinstance(source, (str, Path)):
        scene = load_scene(source)
    elif isinstance(source, Mapping):
        scene = scene_from_dict(source)
    else:
        raise InputError(f"scene: expected a Scene, a file path or a dict, got {type(source).__name__}")
    return scene.with_(**overrides) if overrides else scene


def read_scene_file(path: str | Path) -> dict:
    """The TOML mapping of a scene file (not yet validated); InputError if it is missing or not TOML."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"scene file not found: {path}")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: not a valid TOML file ({exc})") from None


def load_scene(path: str | Path) -> Scene:
    """Read and validate a TOML scene file."""
    path = Path(path)
    return scene_from_dict(read_scene_file(path), base_dir=path.parent, name=path.stem)


# ----------------------------------------------------------------------------- reference documentation
#: unit and meaning of the scene keys outside [model] (whose keys are declared in conformal.registry)
_KEY_DOCS: dict[str, dict[str, tuple[str, str]]] = {
    "material": {"G": ("N/mm²", "shear modulus (or E, Young's modulus); both bodies unless [material.body2]"),
                 "E": ("N/mm²", "Young's modulus, instead of G"), "nu": ("", "Poisson's ratio"),
                 "body2": ("", "a table with G (or E) and nu of body 2 (the wheel)")},
    "friction": {"mu": ("", "friction coefficient (static = kinetic)"), "mu_static": ("", "static coefficient"),
                 "mu_kinetic": ("", "kinetic coefficient (<= mu_static)"),
                 "mu_table": ("", "file of rows 's mu': mu along y (theory exact)"),
                 "angle_table": ("", "rows [alpha (rad), mu_static, mu_kinetic]: friction at each wheel-rail "
                                     "patch's contact angle, per row of a conformal strip (CONTACT's V = 1; "
                                     "linear between rows)")},
    "geometry": {"kind": ("", "quadratic | hertz | table | wheel_rail"),
                 "A": ("1/mm", "quadratic: h = A x² + B y² (B = 0: line contact)"), "B": ("1/mm", "quadratic"),
                 "a": ("mm", "hertz: semi-axis along x"), "b": ("mm", "hertz: semi-axis along y"),
                 "file": ("", "table: the undeformed distance on the grid (mx rows of my numbers)"),
                 "wheel_profile": ("", "built-in name or file"), "rail_profile": ("", "built-in name or file"),
                 "side": ("", "right | left"), "placement": ("", "wheelset | single"),
                 "lateral_shift": ("mm", "wheelset lateral displacement"), "yaw": ("rad", "wheelset yaw"),
                 "roll": ("rad", "wheelset roll (default: found so that both wheels touch)"),
                 "rail_cant": ("rad", "rail inclination"), "gauge": ("mm", "track gauge"),
                 "gauge_height": ("mm", "below the top of rail where the gauge is measured"),
                 "flange_back": ("mm", "distance of the flange backs"),
                 "wheel_radius": ("mm", "nominal rolling radius"),
                 "flange_back_pos": ("mm", "flange back in wheel-profile y (default: from the profile)"),
                 "smoothing": ("mm", "profile smoothing wavelength (0: interpolate)"),
                 "element_size": ("mm", "square grid elements per patch (CONTACT's DX = DS)"),
                 "element_size_s": ("mm", "conformal strips: element length along s"),
                 "patch_combine": ("mm", "overlap regions closer than this form one patch"),
                 "wheel_z": ("", "down | up (the wheel file gives z upwards) | auto (CONTACT's MIRRORZ = 0)"),
                 "rail_z": ("", "down | up (the rail file gives z upwards) | auto (CONTACT's MIRRORZ = 0)"),
                 "wheel_mirror_y": ("", "y of the wheel file negated on reading (CONTACT's MIRRORY = 1)"),
                 "rail_mirror_y": ("", "y of the rail file negated on reading (CONTACT's MIRRORY = 1)"),
                 "wheel_smoothing": ("mm", "the wheel's own smoothing wavelength (default: smoothing)"),
                 "rail_smoothing": ("mm", "the rail's own smoothing wavelength (default: smoothing)"),
                 "max_smoothing_error": ("mm", "the farthest a profile point may lie from its smoothed curve")},
    "load": {"normal_force": ("N", "normal force (per mm for line contact)"),
             "approach": ("mm", "approach (wheel-rail: lowering below first touch)"),
             "wheel_load": ("N", "wheel-rail: vertical load balanced by the contact"),
             "load_angle": ("rad", "wheel-rail, theory conformal: direction of the load, 0 = vertical"),
             "approach_along": ("mm", "wheel-rail, theory conformal: approach along the load direction")},
    "kinematics": {"xi": ("", "longitudinal creepage (rolling = shift: shift in mm)"),
                   "eta": ("", "lateral creepage (shift: mm)"), "phi": ("rad/mm", "spin creepage (shift: rad)"),
                   "rolling": ("", "steady | shift"), "fx_rel": ("", "prescribed FX / (mu FN) instead of xi"),
                   "fy_rel": ("", "prescribed FY / (mu FN) instead of eta"),
                   "velocity": ("mm/s", "rolling speed (frictional power)"),
                   "speed": ("mm/s", "wheel-rail: wheelset speed; the creepages follow per patch"),
                   "pitch_velocity": ("rad/s", "wheel-rail: about the axle (default: pure rolling)"),
                   "yaw_rate": ("rad/s", "wheel-rail"), "roll_rate": ("rad/s", "wheel-rail"),
                   "lateral_velocity": ("mm/s", "wheel-rail"), "direction": ("", "rolling direction +1 | -1"),
                   "rigid_slip": ("", "file: rigid slip per element (theory exact)")},
    "grid": {"mx": ("", "elements along x (explicit grid)"), "my": ("", "elements along y"),
             "dx": ("mm", "element size along x"), "dy": ("mm", "element size along y"),
             "xl": ("mm", "grid corner x (default: centred)"), "yl": ("mm", "grid corner y"),
             "n": ("", "automatic grid: elements along each axis"),
             "scale": ("", "automatic grid: extent over the Hertz patch"),
             "strips": ("", "conformal wheel-rail: coupled | separate")},
    "[history]": {"normal_force": ("N", "normal load of this step (none with approach: as the previous step)"),
                  "approach": ("mm", "prescribed approach of this step, instead of normal_force"),
                  "xi": ("", "shift: rigid shift increment (mm); transient/steady: longitudinal creepage"),
                  "eta": ("", "shift: rigid shift increment (mm); transient/steady: lateral creepage"),
                  "phi": ("rad/mm", "shift: rotation increment (rad); transient/steady: spin creepage"),
                  "rolling": ("", "shift | transient | steady"),
                  "distance": ("mm", "rolled distance of a transient step (default: one element)"),
                  "fx_rel": ("", "prescribed FX/(mu_static FN) instead of xi"),
                  "fy_rel": ("", "prescribed FY/(mu_static FN) instead of eta"),
                  "repeat": ("", "the step is applied this many times")},
}


def reference_markdown(models: Registry = MODELS) -> str:
    """Every scene key with its type, default, unit and meaning as markdown (for the documentation
    site): the sections from the scene's dataclasses, ``[model]`` and each theory from the registry
    (:func:`conformal.registry.reference_markdown`).

    >>> md = reference_markdown()
    >>> "| `wheel_load` | number | -- | N |" in md, "### theory `conformal`" in md
    (True, True)
    """
    from conformal.registry import reference_markdown as model_reference

    defaults = {"material": {"G": 82000.0, "nu": 0.28}, "friction": {"mu": 0.3}}
    for sec, cls in (("geometry", WheelRailGeometry), ("load", Load), ("kinematics", Kinematics), ("grid", GridSpec),
                     ("[history]", HistoryStep)):
        defaults[sec] = {f.name: f.default for f in fields(cls)}
    for cls in (QuadraticGeometry, HertzGeometry):
        defaults["geometry"].update({f.name: None for f in fields(cls) if f.name != "kind"})
    defaults["geometry"]["file"] = None

    types = {"mu_static": "number", "mu_kinetic": "number", "fx_rel": "number", "fy_rel": "number",
             "body2": "table", "file": "file", "mu_table": "file", "rigid_slip": "file", "mx": "whole number",
             "my": "whole number"}
    defaults["geometry"]["kind"] = None          # required

    def kind(v, key) -> str:
        if key in types:
            return types[key]
        if isinstance(v, bool):
            return "true \\| false"
        if isinstance(v, int) and not isinstance(v, bool):
            return "whole number"
        if isinstance(v, float) or (v is None and _KEY_DOCS[sec][key][0]):
            return "number"
        return "string"

    sections = {}
    for sec, docs in _KEY_DOCS.items():
        sections[sec] = [(k, kind(defaults.get(sec, {}).get(k), k), defaults.get(sec, {}).get(k), unit, doc)
                         for k, (unit, doc) in docs.items()]
    return model_reference(models, sections)
