"""Quasi-quarter-space bodies for FE influence numbers: what to mesh, and how large.

A body is a cross-section swept along the rolling direction x: extruded (rail, flat block) or
revolved about the axle (wheel ring sector).  Everything is written in the common contact frame
of the patch: x rolling, y lateral, z DOWN (into the rail, body 1).  The rail's and the block's
material lies below their surface curve (larger z), the wheel's above it (smaller z).

The contact grid the body must carry is a :class:`StripPatch`: ``mx`` elements of length ``dx``
along x and ``ms`` elements along the arc length s of this body's profile, between the edges
``s_edges``.  By the invariance along x (DESIGN.md §4) only ONE column of elements is loaded, the
one centred on x = 0; the displacements are observed on the 2 mx - 1 columns around it, which
gives every offset ix - jx of the (2mx-1, ms, ms, 3, 3) kernel.

The body size follows from the patch (:func:`body_extent`): a margin of ``size`` times the patch
size beyond the observed region in x, beyond the patch along the profile (clipped to the
profile's ends) and below the deepest surface point.  The far faces are clamped; a clamped body is
stiffer than a half-space by an almost constant offset that shrinks like 1/size (DESIGN.md §5).

>>> import numpy as np
>>> prof = flat_profile(-20.0, 20.0)
>>> patch = StripPatch.uniform(mx=5, dx=0.5, ms=4, ds=0.5, s_centre=20.0)
>>> ext = body_extent(BodyModel("block", prof), patch, size=2.0)
>>> ext.x_lo, ext.s_lo, ext.s_hi, ext.depth
(-7.25, 14.0, 26.0, 5.0)
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from conformal.errors import InputError

BODY_KINDS = ("block", "rail", "wheel")


@dataclass(frozen=True, eq=False)
class Profile2D:
    """A cross-section surface curve as a polyline of points (y, z) ordered by arc length s.

    ``s`` starts at 0 on the first point.  ``y`` must increase along the curve within any body
    extent (a graph over y), so that vertical cuts close the cross-section.
    """

    y: np.ndarray
    z: np.ndarray
    name: str = "profile"
    s: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        y = np.asarray(self.y, dtype=float)
        z = np.asarray(self.z, dtype=float)
        if y.ndim != 1 or y.shape != z.shape or y.size < 2:
            raise InputError(f"profile {self.name}: need matching 1-D arrays y, z with >= 2 points")
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(z))):
            raise InputError(f"profile {self.name}: NaN or infinite coordinates")
        seg = np.hypot(np.diff(y), np.diff(z))
        keep = np.concatenate([[True], seg > 1e-9])
        y, z = y[keep], z[keep]
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "s", np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(y), np.diff(z)))]))

    @classmethod
    def from_points(cls, points: np.ndarray, name: str = "profile") -> "Profile2D":
        p = np.asarray(points, dtype=float)
        return cls(p[:, 0], p[:, 1], name)

    @property
    def length(self) -> float:
        return float(self.s[-1])

    def point(self, s) -> np.ndarray:
        """(y, z) at arc length s (linear along the polyline), shape s.shape + (2,)."""
        s = np.asarray(s, dtype=float)
        return np.stack([np.interp(s, self.s, self.y), np.interp(s, self.s, self.z)], axis=-1)

    def tangent(self, s) -> np.ndarray:
        """Unit tangent (dy/ds, dz/ds) at s, from the segment containing s (centre of a short
        symmetric chord, so that a point on a vertex gets the mean direction)."""
        s = np.asarray(s, dtype=float)
        h = 0.05
        a = self.point(np.clip(s - h, 0.0, self.length))
        b = self.point(np.clip(s + h, 0.0, self.length))
        t = b - a
        return t / np.linalg.norm(t, axis=-1, keepdims=True)

    def pieces(self, s_breaks: np.ndarray) -> list[np.ndarray]:
        """Points of the curve between consecutive s_breaks (both ends included exactly)."""
        out = []
        for s0, s1 in zip(s_breaks[:-1], s_breaks[1:]):
            tol = 1e-3 * (s1 - s0)
            inner = (self.s > s0 + tol) & (self.s < s1 - tol)
            ss = np.concatenate([[s0], self.s[inner], [s1]])
            out.append(self.point(ss))
        return out

    def project(self, yz: np.ndarray) -> np.ndarray:
        """Arc length of the closest point of the polyline to each point (..., 2)."""
        from scipy.spatial import cKDTree

        q = np.asarray(yz, dtype=float).reshape(-1, 2)
        P = np.stack([self.y, self.z], axis=1)
        tree = cKDTree(P)
        _, k = tree.query(q)
        best_s = self.s[k].copy()
        best_d = np.full(len(q), np.inf)
        for seg in (k - 1, k):
            valid = (seg >= 0) & (seg < len(P) - 1)
            i = np.where(valid, seg, 0)
            a, b = P[i], P[i + 1]
            ab = b - a
            t = np.clip(np.einsum("ij,ij->i", q - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
            d = np.linalg.norm(a + t[:, None] * ab - q, axis=1)
            better = valid & (d < best_d)
            best_d = np.where(better, d, best_d)
            best_s = np.where(better, self.s[i] + t * (self.s[i + 1] - self.s[i]), best_s)
        return best_s.reshape(np.shape(yz)[:-1])


def flat_profile(y0: float, y1: float, n: int = 2) -> Profile2D:
    """A straight surface z = 0 from y0 to y1 (the flat block, the half-space limit)."""
    return Profile2D(np.linspace(y0, y1, n), np.zeros(n), "flat")


@dataclass(frozen=True, eq=False)
class BodyModel:
    """One body: its kind, its surface curve in the common frame (z down) and, for a wheel, the
    axle height ``axle_z`` (z of the axle, above the surface: axle_z < z)."""

    kind: str
    profile: Profile2D
    axle_z: float | None = None

    def __post_init__(self):
        if self.kind not in BODY_KINDS:
            raise InputError(f"body kind: must be one of {', '.join(BODY_KINDS)}, got {self.kind!r}")
        if self.kind == "wheel":
            if self.axle_z is None or not math.isfinite(self.axle_z):
                raise InputError("wheel body: axle_z (height of the axle, mm) is required")
            if self.axle_z >= float(np.min(self.profile.z)):
                raise InputError(f"wheel body: the axle (z = {self.axle_z:g}) must lie above the "
                                 f"profile (z down; smallest profile z = {np.min(self.profile.z):g})")

    @property
    def below(self) -> bool:
        """True where the material lies below the surface curve (larger z): rail and block."""
        return self.kind != "wheel"

    @property
    def revolved(self) -> bool:
        return self.kind == "wheel"

    def radius_at(self, s) -> np.ndarray:
        """Wheel: radius of the surface at arc length s."""
        return self.profile.point(s)[..., 1] - self.axle_z

    def key(self) -> dict:
        """Everything that defines the body, for cache keys."""
        return {"kind": self.kind, "axle_z": self.axle_z,
                "y": self.profile.y.round(12).tolist(), "z": self.profile.z.round(12).tolist()}


@dataclass(frozen=True)
class StripPatch:
    """The contact grid as one body sees it: mx x ms elements; dx along x, s_edges along its profile.

    ``x_ref_radius`` (wheels only) is the radius at which the rolling length dx is measured; the
    wheel's columns are then equal angles dx / x_ref_radius (invariance by revolution).
    """

    mx: int
    dx: float
    s_edges: tuple[float, ...]

    def __post_init__(self):
        if self.mx < 1:
            raise InputError(f"[grid] mx: need at least one element, got {self.mx}")
        if not (self.dx > 0 and math.isfinite(self.dx)):
            raise InputError(f"[grid] dx: must be > 0, got {self.dx}")
        e = np.asarray(self.s_edges, dtype=float)
        if e.ndim != 1 or e.size < 2 or not np.all(np.diff(e) > 0):
            raise InputError("[grid] s_edges: need >= 2 increasing arc-length positions")

    @classmethod
    def uniform(cls, mx: int, dx: float, ms: int, ds: float, s_centre: float) -> "StripPatch":
        edges = s_centre + (np.arange(ms + 1) - 0.5 * ms) * ds
        return cls(mx, dx, tuple(float(v) for v in edges))

    @property
    def ms(self) -> int:
        return len(self.s_edges) - 1

    @property
    def edges(self) -> np.ndarray:
        return np.asarray(self.s_edges, dtype=float)

    @property
    def s_centres(self) -> np.ndarray:
        e = self.edges
        return 0.5 * (e[1:] + e[:-1])

    @property
    def s_widths(self) -> np.ndarray:
        return np.diff(self.edges)

    @property
    def n_columns(self) -> int:
        """Observed columns: every offset -(mx-1) .. mx-1 of the loaded column."""
        return 2 * self.mx - 1

    @property
    def x_edges(self) -> np.ndarray:
        """Edges of the observed columns; the loaded column is [-dx/2, dx/2]."""
        return (np.arange(self.n_columns + 1) - 0.5 * self.n_columns) * self.dx

    @property
    def x_centres(self) -> np.ndarray:
        return (np.arange(self.n_columns) - (self.mx - 1)) * self.dx

    @property
    def size(self) -> float:
        """Reference size of the patch: the larger of its extents along x and s."""
        return max(self.mx * self.dx, float(self.edges[-1] - self.edges[0]))

    def key(self) -> dict:
        return {"mx": self.mx, "dx": self.dx, "s_edges": [round(v, 12) for v in self.s_edges]}


@dataclass(frozen=True)
class BodyExtent:
    """Where the body ends: x (rolling length at the reference radius), s along the profile, and
    the depth of the bottom face below the deepest (rail) or above the highest (wheel) surface
    point of the cross-section."""

    x_lo: float
    x_hi: float
    s_lo: float
    s_hi: float
    depth: float
    z_bottom: float
    x_ref_radius: float | None = None  # wheel: radius at which x is arc length

    @property
    def theta_lo(self) -> float:
        return self.x_lo / self.x_ref_radius

    @property
    def theta_hi(self) -> float:
        return self.x_hi / self.x_ref_radius


def body_extent(body: BodyModel, patch: StripPatch, size: float = 2.0) -> BodyExtent:
    """Body limits for a patch: a margin of ``size`` x patch size around it (clipped to the profile).

    Raises InputError when the patch does not fit on the profile, when the profile is not a
    graph over y within the body, or when a wheel sector would exceed the wheel.
    """
    if not (size > 0 and math.isfinite(size)):
        raise InputError(f"[model] fe_body_size: must be > 0, got {size}")
    prof = body.profile
    e = patch.edges
    if e[0] < prof.s[0] - 1e-9 or e[-1] > prof.s[-1] + 1e-9:
        raise InputError(f"profile {prof.name}: too short for the requested patch: the grid spans "
                         f"s = {e[0]:.3f} .. {e[-1]:.3f} mm along the profile, the profile "
                         f"0 .. {prof.length:.3f} mm")
    margin = size * patch.size
    s_lo = max(prof.s[0], e[0] - margin)
    s_hi = min(prof.s[-1], e[-1] + margin)
    depth = margin
    half = patch.n_columns * 0.5 * patch.dx + margin
    if not body.below:
        r_ref = float(body.radius_at(0.5 * (e[0] + e[-1])))
        if depth >= 0.8 * r_ref or 2 * half / r_ref > 1.5 * math.pi:
            raise InputError(f"wheel body: the grid is larger than the wheel: the FE body would be "
                             f"{depth:.1f} mm deep and {2 * half:.1f} mm long at radius {r_ref:.1f} mm; "
                             "reduce mx, dx or [model] fe_body_size")
    inside = (prof.s > s_lo + 1e-9) & (prof.s < s_hi - 1e-9)
    yy = np.concatenate([[prof.point(s_lo)[0]], prof.y[inside], [prof.point(s_hi)[0]]])
    if np.any(np.diff(yy) <= 0):
        raise InputError(f"profile {prof.name}: y must increase along the profile within the body "
                         f"(s = {s_lo:.2f} .. {s_hi:.2f} mm); the FE body needs a surface that is a "
                         "graph over y")
    zz = np.concatenate([[prof.point(s_lo)[1]], prof.z[inside], [prof.point(s_hi)[1]]])
    if body.below:
        z_bottom = float(zz.max()) + depth
        return BodyExtent(-half, half, float(s_lo), float(s_hi), depth, z_bottom)
    # wheel: the bottom (inner) face lies towards the axle
    z_bottom = float(zz.min()) - depth
    if z_bottom <= body.axle_z:
        raise InputError(f"wheel body: the FE body ({depth:.1f} mm deep) would reach the axle; "
                         "the grid is larger than the wheel (reduce the grid or [model] fe_body_size)")
    return BodyExtent(-half, half, float(s_lo), float(s_hi), depth, z_bottom, r_ref)
