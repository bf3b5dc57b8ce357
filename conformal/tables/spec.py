"""Creep-force table definition: axes, normalisation, and the SPEC.toml that describes a build.

Normalisation (after Kalker's USETAB idea)
------------------------------------------
For a Hertzian contact (semi-axes a along the rolling direction x and b, quasi-identical bodies
with combined G, nu; seed Eqs. 16-17), Coulomb friction mu and steady rolling, the exact theory's
tangential problem depends on the data only through (dimensional analysis of the slip equation
s = w + du/dx with u = O(p sqrt(ab)/G) and |p| <= mu p_n, p_n = O(FN/(ab)))::

    a/b,  nu,  G ab xi/(mu FN),  G ab eta/(mu FN),  G (ab)^1.5 phi/(mu FN).

The table scales the creepages with Kalker's linear theory (seed Eq. 13; C11, C22, C23 from
:mod:`conformal.theories.coefficients`) so that 1 means saturation (Eq. T1)::

    nx = G ab C11 xi / (3 mu FN),   ny = G ab C22 eta / (3 mu FN),
    nphi = G (ab)^1.5 C23 phi / (3 mu FN)                                               (T1)

(linear theory's force reaches 3 mu FN, where a Hertzian contact under pure creepage saturates
(Johnson-Vermeulen), at n = 1) and tabulates the dimensionless outputs (Eq. T2)::

    fx = FX/(mu FN),   fy = FY/(mu FN),   mz = MZ/(mu FN sqrt(ab))                        (T2)

MZ is the spin moment about the centre of the ellipse.  Two exact symmetries halve the table
twice (Eq. T3): reversing every creepage reverses every traction, (nx, ny, nphi) ->
-(nx, ny, nphi) gives (fx, fy, mz) -> -(fx, fy, mz); mirroring y gives (nx, ny, nphi) ->
(nx, -ny, -nphi) and (fx, fy, mz) -> (fx, -fy, -mz).  The table stores nx >= 0, ny >= 0 in polar
form and maps the unbounded magnitudes onto bounded coordinates (Eq. T4)::

    rho = hypot(nx, ny),  theta = atan2(ny, nx) in [0, pi/2],
    s = rho/(1 + rho) in [0, rho_max/(1 + rho_max)],   q = nphi/(1 + |nphi|)           (T4)

with nodes uniform in ln(a/b), nu, s, theta and q.  The map s(rho) puts half the nodes below
saturation, where the forces bend most.

Limits (what the table cannot represent): non-Hertzian contacts (several patches, conformal or
non-elliptic geometry), dissimilar materials (K != 0: the normal-tangential coupling is neglected,
the combined G, nu are used), friction that differs between static and kinetic or depends on the
slip velocity, transient rolling and shifts, prescribed forces, creepages beyond rho_max or spin
beyond spin_max, and a/b, nu outside the tabulated ranges.  The exact solver's own discretisation
error (n elements across the short semi-axis box, see ``[solver] n``) is in every node value.

>>> spec = spec_from_dict({"table": {"n_ratio": 3, "n_rho": 3, "n_theta": 2, "n_spin": 3}})
>>> spec.shape, spec.n_nodes
((3, 2, 3, 2, 3), 108)
>>> spec_from_dict({"table": {"rho_mx": 3}})
Traceback (most recent call last):
...
conformal.errors.InputError: SPEC [table] rho_mx: unknown key (did you mean 'rho_max'?)
"""
from __future__ import annotations

import difflib
import hashlib
import json
import math
import tomllib
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from conformal.errors import InputError

#: the saturation factor of Eq. T1 (linear theory's force at saturation, in units of mu FN)
SATURATION = 3.0
#: number of outputs per node (fx, fy, mz of Eq. T2)
N_OUT = 3
#: most nodes of a table (each is an exact solve; the node values alone take 24 bytes each, the plan
#: of a build one task per ``chunk`` nodes): the shipped table has 486 720
MAX_NODES = 10_000_000
#: the largest rho_max and spin_max (normalised: 1 = saturation, Eq. T1)
MAX_NORMALISED = 1000.0
#: the most elements along the long axis of one node's grid (grid_n across the short one)
MAX_LONG_AXIS = 20_000
#: most elements across the short axis of an exact solve's box (its memory and time grow as grid_n^4)
MAX_GRID_N = 400


@dataclass(frozen=True)
class TableSpec:
    """What a table covers, how densely, and how each node is solved.

    Parameters
    ----------
    ratio_min, ratio_max : float
        Range of a/b (a along the rolling direction); nodes uniform in ln(a/b).
    n_ratio : int
        Number of a/b nodes.
    nu_min, nu_max : float
        Range of the combined Poisson's ratio; n_nu nodes uniform in nu (one node: nu_min only).
    rho_max : float
        Largest tabulated hypot(nx, ny) of Eq. T1 (1 = saturation).
    n_rho, n_theta : int
        Nodes in s = rho/(1 + rho) on [0, rho_max/(1 + rho_max)] and in theta on [0, pi/2].
    spin_max : float
        Largest tabulated |nphi|; n_spin nodes in q = nphi/(1 + |nphi|), symmetric about 0.
    grid_n : int
        Exact solver: elements across the short axis of the box 1.1 a x 1.1 b
        (:func:`conformal.theories.c33.grid_for`).
    tol : float
        Exact solver tolerance ([model] tol).
    chunk : int
        Nodes per task of a build.
    """

    ratio_min: float = 0.2
    ratio_max: float = 5.0
    n_ratio: int = 7
    nu_min: float = 0.25
    nu_max: float = 0.30
    n_nu: int = 2
    rho_max: float = 10.0
    n_rho: int = 16
    n_theta: int = 9
    spin_max: float = 5.0
    n_spin: int = 17
    grid_n: int = 30
    tol: float = 1e-6
    chunk: int = 200

    def __post_init__(self):
        def bad(key, why):
            raise InputError(f"SPEC {_SECTION_OF[key]} {key}: {why}")

        for key in ("ratio_min", "ratio_max", "nu_min", "nu_max", "rho_max", "spin_max", "tol"):
            v = getattr(self, key)
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                bad(key, f"must be a finite number, got {v!r}")
        for key in INT_KEYS:
            v = getattr(self, key)
            if not isinstance(v, int) or isinstance(v, bool) or v < 1:
                bad(key, f"must be a positive integer, got {v!r}")
        if not 0 < self.ratio_min <= self.ratio_max:
            bad("ratio_min", f"need 0 < ratio_min <= ratio_max, got {self.ratio_min}, {self.ratio_max}")
        if not -1.0 < self.nu_min <= self.nu_max < 0.5:
            bad("nu_min", f"need -1 < nu_min <= nu_max < 0.5, got {self.nu_min}, {self.nu_max}")
        if not (self.rho_max > 0 and self.spin_max >= 0):
            bad("rho_max", f"need rho_max > 0 and spin_max >= 0, got {self.rho_max}, {self.spin_max}")
        for key in ("rho_max", "spin_max"):        # 1 = saturation (Eq. T1): far beyond, the forces no longer change
            if getattr(self, key) > MAX_NORMALISED:
                bad(key, f"must be <= {MAX_NORMALISED:g} (1 = saturation, Eq. T1), got {getattr(self, key):g}")
        for key, lo in (("n_rho", 2), ("n_theta", 2)):
            if getattr(self, key) < lo:
                bad(key, f"must be >= {lo}, got {getattr(self, key)}")
        if self.n_spin % 2 == 0 or (self.spin_max > 0) != (self.n_spin > 1):
            bad("n_spin", f"must be odd (a node at zero spin), and 1 exactly when spin_max = 0; got "
                          f"{self.n_spin} with spin_max = {self.spin_max}")
        for lo, hi, n in (("ratio_min", "ratio_max", "n_ratio"), ("nu_min", "nu_max", "n_nu")):
            if (getattr(self, lo) == getattr(self, hi)) != (getattr(self, n) == 1):
                bad(n, f"must be 1 exactly when {lo} = {hi}")
        if not 4 <= self.grid_n <= MAX_GRID_N:
            bad("grid_n", f"must lie in 4 .. {MAX_GRID_N}, got {self.grid_n}")
        if self.grid_n * max(self.ratio_max, 1.0 / self.ratio_min) > MAX_LONG_AXIS:
            key = "ratio_max" if self.ratio_max >= 1.0 / self.ratio_min else "ratio_min"
            bad(key, f"an a/b of {getattr(self, key):g} with grid_n = {self.grid_n} needs "
                     f"{self.grid_n * max(self.ratio_max, 1.0 / self.ratio_min):.3g} elements along the long axis, "
                     f"more than {MAX_LONG_AXIS:,}")
        n = math.prod(self.shape)
        if n > MAX_NODES:
            raise InputError(f"SPEC [table] n_ratio x n_nu x n_rho x n_theta x n_spin: "
                             f"{' x '.join(str(k) for k in self.shape)} = {n:.3g} nodes, more than "
                             f"{MAX_NODES:,}; use fewer nodes")
        if not 0 < self.tol < 0.1:
            bad("tol", f"must lie in (0, 0.1), got {self.tol}")

    # ------------------------------------------------------------------ axes
    @property
    def shape(self) -> tuple[int, int, int, int, int]:
        """Node counts along (ln a/b, nu, s, theta, q)."""
        return (self.n_ratio, self.n_nu, self.n_rho, self.n_theta, self.n_spin)

    @property
    def n_nodes(self) -> int:
        return int(np.prod(self.shape))

    @property
    def s_max(self) -> float:
        return self.rho_max / (1.0 + self.rho_max)

    @property
    def q_max(self) -> float:
        return self.spin_max / (1.0 + self.spin_max)

    def axes(self) -> tuple[np.ndarray, ...]:
        """Node coordinates of the five axes (ln a/b, nu, s, theta, q) of Eq. T4."""
        return (np.linspace(math.log(self.ratio_min), math.log(self.ratio_max), self.n_ratio),
                np.linspace(self.nu_min, self.nu_max, self.n_nu),
                np.linspace(0.0, self.s_max, self.n_rho),
                np.linspace(0.0, 0.5 * math.pi, self.n_theta),
                np.linspace(-self.q_max, self.q_max, self.n_spin))

    def to_dict(self) -> dict:
        return asdict(self)

    def digest(self) -> str:
        """sha256 of the spec (what changes the node values), for chunk files of a build."""
        d = self.to_dict()
        d.pop("chunk")
        return hashlib.sha256(json.dumps(d, sort_keys=True).encode()).hexdigest()


# SPEC.toml sections -> keys
SPEC_KEYS: dict[str, tuple[str, ...]] = {
    "table": ("ratio_min", "ratio_max", "n_ratio", "nu_min", "nu_max", "n_nu", "rho_max", "n_rho",
              "n_theta", "spin_max", "n_spin"),
    "solver": ("grid_n", "tol"),
    "build": ("chunk",),
}
_SECTION_OF = {k: f"[{sec}]" for sec, keys in SPEC_KEYS.items() for k in keys}
INT_KEYS = ("n_ratio", "n_nu", "n_rho", "n_theta", "n_spin", "grid_n", "chunk")


def _closest(word: str, options) -> str:
    m = difflib.get_close_matches(word, list(options), n=1, cutoff=0.5)
    return f" (did you mean {m[0]!r}?)" if m else f" (known: {', '.join(options)})"


def spec_from_dict(data: Mapping[str, Any]) -> TableSpec:
    """A validated :class:`TableSpec` from a parsed SPEC.toml; unknown sections or keys raise
    :class:`~conformal.errors.InputError` naming the closest known one."""
    if not isinstance(data, Mapping):
        raise InputError("SPEC: expected a TOML table")
    values: dict[str, Any] = {}
    for sec, body in data.items():
        if sec not in SPEC_KEYS:
            raise InputError(f"SPEC [{sec}]: unknown section{_closest(sec, SPEC_KEYS)}")
        if not isinstance(body, Mapping):
            raise InputError(f"SPEC [{sec}]: expected a table of keys")
        for key, v in body.items():
            if key not in SPEC_KEYS[sec]:
                raise InputError(f"SPEC [{sec}] {key}: unknown key{_closest(key, SPEC_KEYS[sec])}")
            is_int = isinstance(v, int) and not isinstance(v, bool)
            values[key] = float(v) if is_int and key not in INT_KEYS else v   # 3 means 3.0 for a range
    return TableSpec(**values)


def load_spec(path: str | Path) -> TableSpec:
    """Read SPEC.toml (see :func:`spec_from_dict`)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"SPEC: file not found: {path}") from None
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise InputError(f"SPEC: cannot read {path}: {exc}") from None
    return spec_from_dict(data)


# ----------------------------------------------------------------------------- normalisation
def saturation_scales(a, b, FN, mu, G, c11, c22, c23):
    """Factors k such that nx = kx xi, ny = ky eta, nphi = kphi phi (Eq. T1); arrays broadcast.

    >>> kx, ky, kp = saturation_scales(6.0, 6.0, 1e5, 0.3, 82000.0, 4.12, 3.67, 1.47)
    >>> round(float(kx), 1), round(float(ky), 1), round(float(kp), 1)
    (135.1, 120.4, 289.3)
    """
    ab = np.asarray(a, dtype=float) * b
    base = G * ab / (SATURATION * mu * np.asarray(FN, dtype=float))
    return base * c11, base * c22, base * np.sqrt(ab) * c23


def polar(nx, ny, nphi):
    """The symmetry-reduced coordinates of Eqs. T3-T4.

    Returns (s, theta, q, sign_all, sign_y): the table is read at (s, theta, q) and its
    (fx, fy, mz) multiplied by (sign_all, sign_all sign_y, sign_all sign_y).

    >>> s, th, q, sa, sy = polar(-1.0, 1.0, 0.5)    # reversed: (1, -1, -0.5), mirrored: (1, 1, 0.5)
    >>> round(float(s), 4), round(float(th), 4), round(float(q), 4), float(sa), float(sy)
    (0.5858, 0.7854, 0.3333, -1.0, -1.0)
    """
    nx, ny, nphi = (np.asarray(v, dtype=float) for v in (nx, ny, nphi))
    sign_all = np.where(nx < 0, -1.0, 1.0)
    nx, ny, nphi = nx * sign_all, ny * sign_all, nphi * sign_all
    sign_y = np.where(ny < 0, -1.0, 1.0)
    ny, nphi = ny * sign_y, nphi * sign_y
    rho = np.hypot(nx, ny)
    return rho / (1.0 + rho), np.arctan2(ny, nx), nphi / (1.0 + np.abs(nphi)), sign_all, sign_y


def creepages_of_node(s: float, theta: float, q: float) -> tuple[float, float, float]:
    """(nx, ny, nphi) of a node: the inverse of Eq. T4."""
    rho = s / (1.0 - s)
    return rho * math.cos(theta), rho * math.sin(theta), q / (1.0 - abs(q))
