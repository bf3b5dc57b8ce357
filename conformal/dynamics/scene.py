"""The vehicle scene: a suspended wheelset on tangent track (TOML, SI units for the vehicle).

Sections and keys (the names are a public interface; unknown keys are rejected naming the
closest known key)::

    [vehicle]     kind = "suspended_wheelset", mass (kg), Ixx, Iyy, Izz (kg m^2; y = axle),
                  wheel_load (N, total vertical load per wheel), kx, ky (N/m, each spring),
                  cx, cy (N s/m, each damper), spring_spacing (m, 2b)
    [track]       gauge (mm), rail_profile, rail_cant (rad), gauge_height (mm, default 14)
    [track.irregularity]  kind = "alignment", rail = "right" | "left", amplitude (mm),
                  wavelength (mm), start (m)
    [wheels]      wheel_profile, wheel_radius (mm, radius at the wheel-profile origin),
                  flange_back (mm, distance between the flange backs), flange_back_pos (mm, optional)
    [contact]     creep_model = "linear" | "empirical" | "fastsim" | "table" | "none",
                  damping (Eq. 57's C, N s/mm^2),
                  mu (or [friction] mu), table_step (mm), table_range (mm), fastsim_n (slices), table (creep table file)
    [material]    E or G (N/mm^2), nu  (as in the other scenes)
    [simulation]  speed (m/s), t_end (s), initial_lateral (mm), initial_yaw (rad),
                  method (scipy solve_ivp method, default "RK45"), rtol (default 1e-3),
                  atol (default 1e-7, for m and rad; x10 for velocities), output_step (s)

>>> import tomllib
>>> s = scene_from_dict(tomllib.loads(EXAMPLE))
>>> s.vehicle.mass, s.track.irregularity.amplitude, s.contact.creep_model
(1568.0, 7.62, 'fastsim')
"""
from __future__ import annotations

import difflib
import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from conformal.dynamics.contact import check_table_size
from conformal.errors import InputError
from conformal.materials import MAX_MODULUS, Material

#: the largest speed (m/s) of a scene and of a stability scan (conformal.dynamics.stability)
MAX_SPEED = 1000.0

CREEP_MODELS = ("linear", "empirical", "fastsim", "none", "table")

EXAMPLE = """
[vehicle]
kind = "suspended_wheelset"
mass = 1568.0
Ixx = 656.0
Iyy = 168.0
Izz = 656.0
wheel_load = 49000.0
kx = 1.35e5
ky = 2.5e5
cx = 0.0
cy = 0.0
spring_spacing = 1.8
[track]
gauge = 1435.0
rail_profile = "UIC60"
rail_cant = 0.025
gauge_height = 15.875
[track.irregularity]
kind = "alignment"
rail = "right"
amplitude = 7.62
wavelength = 11887.2
start = 5.0
[wheels]
wheel_profile = "APTA140"
wheel_radius = 473.8
flange_back = 1353.8
[contact]
creep_model = "fastsim"
damping = 1500.0
mu = 0.5
[material]
E = 210000.0
nu = 0.28
[simulation]
speed = 65.0
t_end = 2.0
initial_lateral = 0.0
initial_yaw = 0.0
"""


# ----------------------------------------------------------------------------- dataclasses
@dataclass(frozen=True)
class Vehicle:
    """Suspended wheelset (seed Table 1), SI units."""

    mass: float
    Ixx: float
    Iyy: float
    Izz: float
    wheel_load: float
    kx: float
    ky: float
    cx: float = 0.0
    cy: float = 0.0
    spring_spacing: float = 1.8
    kind: str = "suspended_wheelset"


@dataclass(frozen=True)
class Irregularity:
    """One full cosine wave of lateral alignment of one rail: the rail moves towards its field side
    by amplitude/2 (1 - cos(2 pi (x - start)/wavelength)) for start <= x <= start + wavelength
    (peak = amplitude; value and slope zero at both ends)."""

    kind: str = "alignment"
    rail: str = "right"
    amplitude: float = 0.0      # mm
    wavelength: float = 1.0     # mm
    start: float = 0.0          # m


@dataclass(frozen=True)
class Track:
    gauge: float
    rail_profile: str
    rail_cant: float
    gauge_height: float = 14.0
    irregularity: Irregularity = field(default_factory=Irregularity)


@dataclass(frozen=True)
class Wheels:
    wheel_profile: str
    wheel_radius: float
    flange_back: float
    flange_back_pos: float | None = None


@dataclass(frozen=True)
class ContactSettings:
    creep_model: str
    damping: float              # Eq. 57's C, N s/mm^2 (F_d = C pdot p with p in mm, pdot in mm/s)
    mu: float
    table_step: float = 0.1     # mm, lateral step of the contact-geometry table
    table_range: float = 14.0   # mm, the table covers -range..+range of lateral shift per wheel
    fastsim_n: int = 12         # FASTSIM slices per axis (batch form)
    table: str | None = None    # creep-force table file for creep_model = "table" (None: the default)


@dataclass(frozen=True)
class Simulation:
    speed: float                # m/s
    t_end: float                # s
    initial_lateral: float = 0.0   # mm
    initial_yaw: float = 0.0       # rad
    method: str = "RK45"
    rtol: float = 1e-3
    atol: float = 1e-7
    output_step: float = 1e-3      # s


@dataclass(frozen=True)
class VehicleScene:
    """A complete vehicle scene (frozen); ``base_dir`` resolves relative profile paths."""

    name: str
    vehicle: Vehicle
    track: Track
    wheels: Wheels
    contact: ContactSettings
    material: Material
    simulation: Simulation
    base_dir: str = "."

    def with_speed(self, speed: float) -> "VehicleScene":
        _positive_or_zero("simulation", "speed", speed)
        check_speed("[simulation] speed", float(speed))
        return replace(self, simulation=replace(self.simulation, speed=float(speed)))


# ----------------------------------------------------------------------------- parsing helpers
def _closest(key: str, known) -> str:
    m = difflib.get_close_matches(str(key).lower(), [k.lower() for k in known], n=1, cutoff=0.5)
    if not m:
        return ""
    name = next(k for k in known if k.lower() == m[0])
    return f" (did you mean {name!r}?)"


class _Sec:
    def __init__(self, name: str, data: Any, known: set[str], nested: set[str] = frozenset()):
        if data is None:
            data = {}
        if not isinstance(data, dict):
            raise InputError(f"[{name}]: must be a table")
        self.name, self.data = name, data
        for k in data:
            if k not in known and k not in nested:
                raise InputError(f"[{name}] {k}: unknown key{_closest(k, sorted(known | set(nested)))}")

    def has(self, key: str) -> bool:
        return key in self.data

    def error(self, key: str, msg: str) -> InputError:
        return InputError(f"[{self.name}] {key}: {msg}")

    def number(self, key: str, default: float | None = None, *, positive=False, nonneg=False) -> float:
        if key not in self.data:
            if default is None:
                raise self.error(key, "missing")
            return float(default)
        v = self.data[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.error(key, f"must be a number, got {v!r}")
        v = float(v)
        if not math.isfinite(v):
            raise self.error(key, f"must be finite, got {v!r}")
        if positive and not v > 0:
            raise self.error(key, f"must be > 0, got {v!r}")
        if nonneg and not v >= 0:
            raise self.error(key, f"must be >= 0, got {v!r}")
        return v

    def string(self, key: str, default: str | None = None, choices=None) -> str:
        if key not in self.data:
            if default is None:
                raise self.error(key, "missing")
            return default
        v = self.data[key]
        if not isinstance(v, str):
            raise self.error(key, f"must be a string, got {v!r}")
        if choices is not None and v not in choices:
            raise self.error(key, f"must be one of {', '.join(choices)}, got {v!r}{_closest(v, choices)}")
        return v


def _positive_or_zero(sec: str, key: str, v) -> None:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
        raise InputError(f"[{sec}] {key}: must be a number >= 0, got {v!r}")


def check_speed(key: str, v: float) -> float:
    """A vehicle speed in m/s: finite, >= 0 and at most MAX_SPEED (a value in km/h or mm/s is refused)."""
    if v > MAX_SPEED:
        raise InputError(f"{key}: must be <= {MAX_SPEED:g} m/s, got {v:g} (the speed is in m/s, not km/h or mm/s)")
    return v


SECTIONS = ("vehicle", "track", "wheels", "contact", "material", "simulation", "friction", "name")


def scene_from_dict(data: dict, base_dir: str | Path = ".", name: str = "scene") -> VehicleScene:
    """Check a parsed TOML dictionary and build a :class:`VehicleScene` (InputError on bad input).

    >>> import tomllib
    >>> d = tomllib.loads(EXAMPLE.replace("mass = 1568.0", "mas = 1568.0"))
    >>> try:
    ...     scene_from_dict(d)
    ... except InputError as e:
    ...     print(e)
    [vehicle] mas: unknown key (did you mean 'mass'?)
    """
    if "vehicle" not in data and any(k in data for k in ("geometry", "load", "kinematics")):
        raise InputError("[vehicle]: missing; this is a contact scene ([geometry], [load]): solve it with "
                         "`conformal solve`, a vehicle scene has [vehicle], [track], [wheels], [contact]")
    for k in data:
        if k not in SECTIONS:
            raise InputError(f"[{k}]: unknown section{_closest(k, SECTIONS)}")
    for k in ("vehicle", "track", "wheels", "contact", "material", "simulation"):
        if k not in data:
            raise InputError(f"[{k}]: missing section")
    v = _Sec("vehicle", data["vehicle"], {"kind", "mass", "Ixx", "Iyy", "Izz", "wheel_load", "kx", "ky",
                                          "cx", "cy", "spring_spacing"})
    kind = v.string("kind", choices=("suspended_wheelset",))
    vehicle = Vehicle(mass=v.number("mass", positive=True), Ixx=v.number("Ixx", positive=True),
                      Iyy=v.number("Iyy", positive=True), Izz=v.number("Izz", positive=True),
                      wheel_load=v.number("wheel_load", positive=True), kx=v.number("kx", nonneg=True),
                      ky=v.number("ky", nonneg=True), cx=v.number("cx", 0.0, nonneg=True),
                      cy=v.number("cy", 0.0, nonneg=True),
                      spring_spacing=v.number("spring_spacing", positive=True), kind=kind)

    t = _Sec("track", data["track"], {"gauge", "rail_profile", "rail_cant", "gauge_height"}, {"irregularity"})
    irr_data = t.data.get("irregularity")
    if irr_data is None:
        irr = Irregularity()
    else:
        i = _Sec("track.irregularity", irr_data, {"kind", "rail", "amplitude", "wavelength", "start"})
        irr = Irregularity(kind=i.string("kind", choices=("alignment",)),
                           rail=i.string("rail", choices=("right", "left")),
                           amplitude=i.number("amplitude"), wavelength=i.number("wavelength", positive=True),
                           start=i.number("start", 0.0, nonneg=True))
    track = Track(gauge=t.number("gauge", positive=True), rail_profile=t.string("rail_profile"),
                  rail_cant=t.number("rail_cant", 0.025), gauge_height=t.number("gauge_height", 14.0, positive=True),
                  irregularity=irr)
    if abs(track.rail_cant) > 0.2:
        raise t.error("rail_cant", f"must be a small angle in rad (|cant| <= 0.2), got {track.rail_cant!r}")

    w = _Sec("wheels", data["wheels"], {"wheel_profile", "wheel_radius", "flange_back", "flange_back_pos"})
    wheels = Wheels(wheel_profile=w.string("wheel_profile"), wheel_radius=w.number("wheel_radius", positive=True),
                    flange_back=w.number("flange_back", positive=True),
                    flange_back_pos=w.number("flange_back_pos") if w.has("flange_back_pos") else None)

    c = _Sec("contact", data["contact"], {"creep_model", "damping", "mu", "table_step", "table_range",
                                          "fastsim_n", "table"})
    if "friction" in data:
        f = _Sec("friction", data["friction"], {"mu"})
        if c.has("mu"):
            raise c.error("mu", "give mu in [contact] or in [friction], not both")
        mu = f.number("mu", positive=True)
    else:
        mu = c.number("mu", positive=True)
    n = c.number("fastsim_n", 12, positive=True)
    if n != int(n):
        raise c.error("fastsim_n", f"must be an integer, got {n!r}")
    contact = ContactSettings(creep_model=c.string("creep_model", choices=CREEP_MODELS),
                              damping=c.number("damping", nonneg=True), mu=mu,
                              table_step=c.number("table_step", 0.1, positive=True),
                              table_range=c.number("table_range", 14.0, positive=True), fastsim_n=int(n),
                              table=c.string("table") if c.has("table") else None)
    if contact.table is not None and not Path(contact.table).is_absolute() and contact.table != "default":
        contact = replace(contact, table=str(Path(base_dir) / contact.table))
    if contact.table_step > 1.0:
        raise c.error("table_step", f"must be <= 1 mm (the table is interpolated), got {contact.table_step!r}")
    check_table_size(contact.table_step, contact.table_range)

    m = _Sec("material", data["material"], {"G", "E", "nu"})
    nu = m.number("nu")
    if m.has("G") == m.has("E"):
        raise m.error("G", "give exactly one of G (shear modulus) or E (Young's modulus), N/mm²")
    key = "G" if m.has("G") else "E"
    if m.number(key, positive=True) > MAX_MODULUS:
        raise m.error(key, f"must be <= {MAX_MODULUS:g} N/mm², got {m.number(key):g}")
    G = m.number("G", positive=True) if m.has("G") else m.number("E", positive=True) / (2.0 * (1.0 + nu))
    material = Material.identical(G, nu)

    s = _Sec("simulation", data["simulation"], {"speed", "t_end", "initial_lateral", "initial_yaw", "method",
                                                "rtol", "atol", "output_step"})
    sim = Simulation(speed=check_speed("[simulation] speed", s.number("speed", nonneg=True)), t_end=s.number("t_end", positive=True),
                     initial_lateral=s.number("initial_lateral", 0.0), initial_yaw=s.number("initial_yaw", 0.0),
                     method=s.string("method", "RK45", choices=("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")),
                     rtol=s.number("rtol", 1e-3, positive=True), atol=s.number("atol", 1e-7, positive=True),
                     output_step=s.number("output_step", 1e-3, positive=True))
    if abs(sim.initial_lateral) > contact.table_range:
        raise s.error("initial_lateral", f"{sim.initial_lateral:g} mm lies outside the contact table's "
                                         f"+-{contact.table_range:g} mm ([contact] table_range)")
    if sim.speed == 0 and contact.creep_model != "none":
        raise s.error("speed", "must be > 0 with creep forces (creepages divide by the speed); "
                               "use creep_model = \"none\" for a wheelset at rest")
    nm = data.get("name", name)
    if not isinstance(nm, str):
        raise InputError(f"name: must be a string, got {nm!r}")
    return VehicleScene(nm, vehicle, track, wheels, contact, material, sim, str(base_dir))


def load_vehicle_scene(path: str | Path) -> VehicleScene:
    """Read and check a vehicle scene file.

    Parameters
    ----------
    path : str or Path
        TOML file with the sections of the module docstring; relative profile paths are taken
        from its folder.

    Returns
    -------
    VehicleScene

    Raises
    ------
    InputError
        Missing file, invalid TOML, unknown section or key (naming the closest known one),
        missing or invalid value.

    Examples
    --------
    >>> from pathlib import Path
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "w.toml"
    >>> _ = p.write_text(EXAMPLE)
    >>> load_vehicle_scene(p).vehicle.wheel_load
    49000.0
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"scene file not found: {p}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{p.name}: not valid TOML: {exc}") from None
    return scene_from_dict(data, base_dir=p.parent, name=p.stem)
