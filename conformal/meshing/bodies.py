"""Quasi-quarter-space bodies for FE influence numbers: what to mesh, and how large.

A body is a cross-section swept along the rolling direction x: extruded (rail, flat block) or
revolved about the axle (wheel ring sector).  Everything is written in the common contact frame
of the patch: x rolling, y lateral, z DOWN (into the rail, body 1).  The rail's and the block's
material lies on the +n side of their surface curve, the wheel's on the other side; the curve is
parametrised by its arc length s, so it may be any simple curve (grooves, a gauge face turning
past vertical, a flange flank at any angle).

The contact grid the body must carry is a :class:`StripPatch`: ``mx`` elements of length ``dx``
along x and ``ms`` elements along the arc length s of this body's profile, between the edges
``s_edges``.  By the invariance along x only ONE column of elements is loaded, the one centred
on x = 0; the displacements are observed on the 2 mx - 1 columns around it, which gives every
offset ix - jx of the (2mx-1, ms, ms, 3, 3) kernel.

The body size follows from the patch (:func:`body_extent`): a margin of ``size`` times the patch
size beyond the observed region in x, and in the cross-section a disc around the patch whose
radius reaches ``size`` patch sizes beyond it.  On these artificial boundaries
:mod:`conformal.influence.fe` imposes the half-space field, so that the body behaves like a large
one (see there).

>>> import numpy as np
>>> prof = flat_profile(-20.0, 20.0)
>>> patch = StripPatch.uniform(mx=5, dx=0.5, ms=4, ds=0.5, s_centre=20.0)
>>> ext = body_extent(BodyModel("block", prof), patch, size=2.0)
>>> ext.x_lo, ext.s_lo, ext.s_hi, ext.depth, ext.radius
(-7.25, 14.0, 26.0, 5.0, 6.0)
>>> np.round(ext.arc_mid, 12) + 0.0       # the arc runs through the material, below the surface
array([0., 6.])
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

    ``s`` starts at ``s_start`` (default 0) on the first point.  Any simple curve will do (it need
    not be a graph over y); the body's material lies on one side of it (:func:`inward_normal`).
    A profile continued before its first point (:func:`grow_profile`) keeps the arc lengths of
    its original points: its new first point has s < 0.
    """

    y: np.ndarray
    z: np.ndarray
    name: str = "profile"
    s_start: float = 0.0
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
        s0 = float(self.s_start)
        if not math.isfinite(s0):
            raise InputError(f"profile {self.name}: s_start must be finite, got {self.s_start!r}")
        object.__setattr__(self, "s", s0 + np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(y), np.diff(z)))]))

    @classmethod
    def from_points(cls, points: np.ndarray, name: str = "profile") -> "Profile2D":
        p = np.asarray(points, dtype=float)
        return cls(p[:, 0], p[:, 1], name)

    @property
    def length(self) -> float:
        return float(self.s[-1] - self.s[0])

    def point(self, s) -> np.ndarray:
        """(y, z) at arc length s (linear along the polyline), shape s.shape + (2,)."""
        s = np.asarray(s, dtype=float)
        return np.stack([np.interp(s, self.s, self.y), np.interp(s, self.s, self.z)], axis=-1)

    def tangent(self, s) -> np.ndarray:
        """Unit tangent (dy/ds, dz/ds) at s, from the segment containing s (centre of a short
        symmetric chord, so that a point on a vertex gets the mean direction)."""
        s = np.asarray(s, dtype=float)
        h = 0.05
        a = self.point(np.clip(s - h, self.s[0], self.s[-1]))
        b = self.point(np.clip(s + h, self.s[0], self.s[-1]))
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

    def project(self, yz: np.ndarray, s_lo: float | None = None, s_hi: float | None = None) -> np.ndarray:
        """Arc length of the closest point of the polyline to each point (..., 2); with ``s_lo``,
        ``s_hi`` the closest point of that part of it (a body's part of the profile, whose tail
        may curl back close to it).  Assumes points a few segment lengths apart at most (the
        closest point lies on a segment next to the nearest vertex), as sampled profiles are."""
        from scipy.spatial import cKDTree

        q = np.asarray(yz, dtype=float).reshape(-1, 2)
        if s_lo is None and s_hi is None:
            P, S = np.stack([self.y, self.z], axis=1), self.s
        else:
            lo = self.s[0] if s_lo is None else s_lo
            hi = self.s[-1] if s_hi is None else s_hi
            S = np.concatenate([[lo], self.s[(self.s > lo) & (self.s < hi)], [hi]])
            P = self.point(S)
        tree = cKDTree(P)
        _, k = tree.query(q)
        best_s = S[k].copy()
        best_d = np.full(len(q), np.inf)
        # segments much longer than the sampling (a straight continuation, grow_profile; a
        # section's web or foot) are tried for every point: beside the middle of one, the nearest
        # vertex may be the far end of another (an S1002 wheel continued 350 mm along its flange
        # back and its tread: its flange-back face was taken for a clamped one)
        seg_len = np.diff(S)
        long = np.flatnonzero(seg_len > 10.0 * np.median(seg_len)) if len(seg_len) > 2 else np.zeros(0, int)
        for seg in [k - 1, k] + [np.full(len(q), i) for i in long]:
            valid = (seg >= 0) & (seg < len(P) - 1)
            i = np.where(valid, seg, 0)
            a, b = P[i], P[i + 1]
            ab = b - a
            t = np.clip(np.einsum("ij,ij->i", q - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
            d = np.linalg.norm(a + t[:, None] * ab - q, axis=1)
            better = valid & (d < best_d)
            best_d = np.where(better, d, best_d)
            best_s = np.where(better, S[i] + t * (S[i + 1] - S[i]), best_s)
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
        # every bit (not rounded): gmsh's mesh changes with the last bits of its input (a rail body
        # of 1 648 nodes got 1 645 .. 1 650 when its points moved by one unit in the last place), so
        # a key rounded to 12 decimals held different meshes and numbers (issue 22: 15 732, 15 744
        # and 15 750 unknowns under one key); -0.0 is written as 0.0
        return {"kind": self.kind, "axle_z": self.axle_z,
                "y": (self.profile.y + 0.0).tolist(), "z": (self.profile.z + 0.0).tolist()}


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
        return {"mx": self.mx, "dx": self.dx, "s_edges": [float(v) + 0.0 for v in self.s_edges]}   # every bit


@dataclass(frozen=True)
class BodyExtent:
    """Where the body ends.

    Along x: ``x_lo .. x_hi`` (rolling length at the reference radius ``x_ref_radius`` for a
    wheel).  In the cross-section: a disc of radius ``radius`` about ``centre`` (the profile point
    at the middle of the patch), ``depth`` (the margin) beyond the farthest patch point.  The body's
    part of the profile runs from ``s_lo`` to ``s_hi`` (where it leaves the disc, or where the
    profile ends: then a straight cut, ``cut_lo``/``cut_hi``, along the inward normal or the
    nearest direction that does not cross the profile, reaches the circle at ``q_lo``/``q_hi``).  The artificial boundary closes the section from ``q_hi`` through
    ``arc_mid`` to ``q_lo`` along the circle, on the material side.  The disc works for any profile
    shape (grooves, gauge faces past vertical, any contact angle): it never needs the profile to be
    a graph over y, and it meets the profile at a steep angle.
    """

    x_lo: float
    x_hi: float
    s_lo: float
    s_hi: float
    depth: float
    centre: tuple[float, float]
    radius: float
    q_lo: tuple[float, float]
    q_hi: tuple[float, float]
    arc_mid: tuple[float, float]
    cut_lo: bool = False
    cut_hi: bool = False
    x_ref_radius: float | None = None  # wheel: radius at which x is arc length
    wheel_limited: bool = False        # the margin was cut to fit the wheel (bodies._disc)
    closed: bool = False               # a whole section: the profile's ends joined straight, cut by the disc

    @property
    def theta_lo(self) -> float:
        return self.x_lo / self.x_ref_radius

    @property
    def theta_hi(self) -> float:
        return self.x_hi / self.x_ref_radius

    def closure(self, n_arc: int = 64) -> np.ndarray:
        """Points (y, z) of the artificial boundary of the cross-section, from q_hi to q_lo."""
        c = np.asarray(self.centre)
        a0, am, a1 = (math.atan2(q[1] - c[1], q[0] - c[0]) for q in (self.q_hi, self.arc_mid, self.q_lo))
        d1 = (am - a0) % (2 * math.pi)
        d2 = (a1 - am) % (2 * math.pi)
        if (a1 - a0) % (2 * math.pi) < d1:          # the arc turns clockwise
            d1, d2 = d1 - 2 * math.pi, d2 - 2 * math.pi
        t = a0 + np.linspace(0.0, d1 + d2, n_arc + 1)
        return c + self.radius * np.column_stack([np.cos(t), np.sin(t)])


def inward_normal(body: BodyModel, s) -> np.ndarray:
    """Unit normal (y, z) of the cross-section pointing into the body's material at arc length s."""
    t = body.profile.tangent(s)
    n = np.stack([-t[..., 1], t[..., 0]], axis=-1)   # common normal: into body 1 (rail, block)
    return n if body.below else -n


def _leave_disc(prof: Profile2D, c: np.ndarray, R: float, s_start: float, step: int) -> tuple[float, bool]:
    """Arc length where the profile, followed from s_start in direction ``step`` (+1 or -1), first
    leaves the disc |p - c| <= R; (profile end, True) if it ends inside."""
    P = np.stack([prof.y, prof.z], axis=1)
    dist = np.linalg.norm(P - c, axis=1)
    idx = np.arange(len(P))
    cand = idx[(prof.s > s_start) & (dist > R)] if step > 0 else idx[(prof.s < s_start) & (dist > R)][::-1]
    if cand.size == 0:
        return float(prof.s[-1] if step > 0 else prof.s[0]), True
    k = int(cand[0])
    j = k - step                                   # the vertex before it (inside, or s_start's segment)
    a = prof.point(s_start) if (prof.s[j] < s_start) == (step > 0) else P[j]
    sa = s_start if (prof.s[j] < s_start) == (step > 0) else prof.s[j]
    b = P[k]
    d = b - a
    f = a - c
    qa, qb, qc = d @ d, 2 * f @ d, f @ f - R * R
    t = (-qb + math.sqrt(max(qb * qb - 4 * qa * qc, 0.0))) / (2 * qa)
    return float(sa + np.clip(t, 0.0, 1.0) * (prof.s[k] - sa)), False


def _to_circle(p: np.ndarray, n: np.ndarray, c: np.ndarray, R: float) -> np.ndarray:
    """The point p + t n (t > 0) on the circle |q - c| = R (p inside)."""
    f = p - c
    b = f @ n
    t = -b + math.sqrt(max(b * b - (f @ f - R * R), 0.0))
    return p + t * n


def _end_cut(p: np.ndarray, n_in: np.ndarray, c: np.ndarray, R: float, curve: np.ndarray,
             gap: float) -> np.ndarray | None:
    """End of a straight cut from a profile end p (inside the disc) to the circle: along the inward
    normal n_in where that does not cross the profile, else along the direction closest to it that
    does not (a worn gauge face curling back under the head), at most 60 degrees away (a cut
    nearly along the profile would leave a sliver), ending at least ``gap`` from the profile;
    None if there is none."""
    ang0 = math.atan2(n_in[1], n_in[0])
    for da in sorted(np.radians(np.arange(-60.0, 61.0, 5.0)), key=abs):
        d = np.array([math.cos(ang0 + da), math.sin(ang0 + da)])
        q = _to_circle(p, d, c, R)
        if (np.min(np.linalg.norm(curve - q, axis=1)) >= gap
                and not _segments_intersect(np.array([p + 1e-6 * (q - p), q]), curve)):
            return q
    return None


def _inside(poly: np.ndarray, q: np.ndarray) -> bool:
    """Point in polygon (even-odd rule)."""
    y, z = poly[:, 0], poly[:, 1]
    y2, z2 = np.roll(y, -1), np.roll(z, -1)
    cross = (z > q[1]) != (z2 > q[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        yi = y + (q[1] - z) * (y2 - y) / (z2 - z)
    return bool(np.count_nonzero(cross & (yi > q[0])) % 2)


def _segments_intersect(P: np.ndarray, Q: np.ndarray) -> bool:
    """Whether any segment of polyline P properly crosses any segment of polyline Q."""
    a, b = P[:-1, None, :], P[1:, None, :]
    c, d = Q[None, :-1, :], Q[None, 1:, :]

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    o1, o2, o3, o4 = orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b)
    return bool(np.any((o1 * o2 < -1e-18) & (o3 * o4 < -1e-18)))


#: a wheel body's disc reaches at most this fraction of the wheel's radius towards the axle, and
#: its sector at most this angle (rad): larger sizes are limited to them (and say so)
WHEEL_REACH = 0.75
WHEEL_SECTOR = 1.4 * math.pi


def _disc(body: BodyModel, patch: StripPatch, size: float) -> tuple[np.ndarray, float, float, float, bool]:
    """Centre (the profile point at the middle of the patch), radius of the patch about it, the
    radius of the body's disc (``size`` patch sizes beyond the patch), that margin, and whether a
    wheel limited it (a disc beyond WHEEL_REACH of the wheel's radius or a sector beyond
    WHEEL_SECTOR: the margin is cut to fit; a wheel too small for a quarter patch size raises)."""
    prof = body.profile
    e = patch.edges
    s_mid = 0.5 * (e[0] + e[-1])
    c = prof.point(s_mid)
    inner = (prof.s > e[0]) & (prof.s < e[-1])
    r_patch = float(np.max(np.linalg.norm(prof.point(np.concatenate([[e[0]], prof.s[inner], [e[-1]]])) - c, axis=1)))
    margin = size * patch.size
    limited = False
    if not body.below:
        r_ref = float(body.radius_at(s_mid))
        cap = min(WHEEL_REACH * r_ref - r_patch, 0.5 * WHEEL_SECTOR * r_ref - patch.n_columns * 0.5 * patch.dx)
        if cap < min(margin, 0.25 * patch.size):
            raise InputError(f"wheel body: the grid is larger than the wheel: the FE body would reach "
                             f"{r_patch + margin:.1f} mm into the wheel and be "
                             f"{patch.n_columns * patch.dx + 2 * margin:.1f} mm long at radius {r_ref:.1f} mm; "
                             "reduce mx, dx or [model] fe_body_size")
        if margin > cap:
            margin, limited = cap, True
    return c, r_patch, r_patch + margin, margin, limited


#: arc length (mm) over which the end tangent of a profile is taken (a chord: on a 0.1 mm
#: sampled profile the last two segments; on an R10 arc it turns 0.6 degrees from the tangent)
END_CHORD = 0.2


@dataclass(frozen=True)
class Closure:
    """How a body's profile was closed at its two ends (low s, high s): the straight continuation
    added there (``extension_lo``, ``extension_hi``, mm of new profile beyond the original end,
    0 where none was needed or possible) and the disc radius it was made for."""

    extension_lo: float = 0.0
    extension_hi: float = 0.0
    radius: float = 0.0
    size: float = 0.0            # the body size made (patch sizes): below the one asked for on a slab
    slab_width: float = 0.0      # width of the section between parallel continued ends (0: none)


#: end directions within this angle (rad) of each other make the continued section a slab
SLAB_ANGLE = math.radians(30.0)


def grow_profile(body: BodyModel, patch: StripPatch, size: float, *, limit_slab: bool = True
                 ) -> tuple[BodyModel, Closure]:
    """The body with its profile continued straight along its end tangents where it ends inside
    the disc of ``size`` patch sizes (:func:`body_extent`), so that the disc, and the FE body, has
    the size it names.

    Why a straight continuation along the end tangent: the profiles given to the workbench
    describe the running surface near the contact (a rail head, a wheel tread and flange), and
    end where the drawing or the measurement ends, not where the body does.  Cutting the body
    there (the earlier closure: a straight cut to the disc's arc) makes it smaller than
    ``fe_body_size`` says, by an amount that depends on where the profile file happens to end
    (the deep pair's rail was the same 36 mm body at sizes 2 and 4), and a finite-body error
    that does not decrease with the size the user asked for.  The tangent continuation is the
    C1 extension with no curvature: it adds no geometry the profile does not state (no invented
    curvature, which would change the compliance near the contact), it keeps the surface smooth
    where it joins (no kink, whose stress concentration would belong to neither body), and far
    from the contact only the amount of material matters, which then grows with the size.  The
    far field imposed beyond the disc (``fe_far_field``) is the half-space tangent to the loaded
    element, so a straight continuation is also the shape that field assumes.  It is not the
    real body: a UIC60 head profile ends 35 mm down, where the real rail turns into its web, and
    an S1002 profile ends at the flange back and the field side of the tread, where the real
    rim turns into its faces.  On idealised long profiles (a rail corner, a flange root, a
    groove) the continued bodies converge with the size (studies/fe_far_field_limit.py); on real
    profiles the full section (head, web and foot; rim and web) is the answer, the domain of the
    direct FE contact's ground truth (conformal.fe_contact), not of this closure.

    A continuation that would cross the profile itself or run close beside a part of it ahead of
    the end (a worn gauge face curling back under the head, a concave profile whose end tangents
    meet) is not made: that end keeps the straight cut of :func:`body_extent`.

    Where the two ends point the same way (within SLAB_ANGLE: the sides of a rail head profile),
    a straight continuation makes a slab as
    wide as the section, and an edge-loaded slab has no size-converged compliance (it grows like
    the logarithm of its depth, studies/fe_far_field_limit.py: the UIC60 head continued straight
    went 1.026, 1.037, 1.076 x the half-space at sizes 4, 8, 16).  The real section below a rail
    head or a wheel rim is narrower still (web), so neither the slab nor the half-space is the
    real body there; the body is then limited to a margin of the section's width (at least one
    patch size): the half-space far field takes over about one head width from the patch, and
    ``Closure.size`` (and the FE statistics' ``margin_limited_by = "section width"``) say so
    (``limit_slab = False``, the closure ``"straight"``: the slab as deep as the size asks).

    The arc lengths of the original points do not change (a continuation before the first point
    gets s < 0), so a patch given on the original profile is on the grown one at the same s.
    """
    if not (size > 0 and math.isfinite(size)):
        raise InputError(f"[model] fe_body_size: must be > 0, got {size}")
    prof = body.profile
    e = patch.edges
    if e[0] < prof.s[0] - 1e-9 or e[-1] > prof.s[-1] + 1e-9:
        return body, Closure(size=size)             # body_extent reports it
    P = np.stack([prof.y, prof.z], axis=1)
    chord = min(END_CHORD, 0.25 * prof.length)
    # outward end directions; where they are nearly parallel the continued section is a slab of
    # the section's width (a rail head's sides, a wheel rim's faces) whose compliance grows
    # without bound with its depth (an edge-loaded plate): the margin is limited to that width
    dirs = {}
    for side, s_end, s_in in (("lo", prof.s[0], prof.s[0] + chord), ("hi", prof.s[-1], prof.s[-1] - chord)):
        d = prof.point(s_end) - prof.point(s_in)
        n = float(np.linalg.norm(d))
        dirs[side] = d / n if n > 0 else None
    width = 0.0
    if dirs["lo"] is not None and dirs["hi"] is not None and dirs["lo"] @ dirs["hi"] > math.cos(SLAB_ANGLE):
        m = dirs["lo"] + dirs["hi"]
        m /= np.linalg.norm(m)
        gap = P[-1] - P[0]
        width = abs(float(gap[0] * m[1] - gap[1] * m[0]))
        if limit_slab:
            size = min(size, max(width, patch.size) / patch.size)
    c, _, R, _, _ = _disc(body, patch, size)
    ends = {}
    for side, s_end in (("lo", prof.s[0]), ("hi", prof.s[-1])):
        p = prof.point(s_end)
        d = dirs[side]
        if d is None or np.linalg.norm(p - c) >= R:
            continue
        f = p - c
        b = float(f @ d)
        t_exit = -b + math.sqrt(max(b * b - (f @ f - R * R), 0.0))
        L = t_exit + 0.05 * R
        q = p + L * d                               # beyond the circle: the body cuts it at R
        # the continuation must not cross the profile, nor run close beside a part of it in the
        # disc that lies ahead of the end, within 45 degrees of its direction (a hook curling back
        # under the running surface: a continuation there would slit the material; that end
        # keeps the cut, which shrinks the disc to the hook)
        seg = np.array([p + 1e-6 * (q - p), q])
        if _segments_intersect(seg, P):
            continue
        t = (P - p) @ d
        off = np.abs((P - p) @ np.array([-d[1], d[0]]))
        ahead = (t > 1e-9 * R) & (np.linalg.norm(P - c, axis=1) <= R)     # in a 45-degree cone
        if np.any(ahead & (off < t)):
            continue
        ends[side] = q
    if "lo" in ends and "hi" in ends and _segments_intersect(
            np.array([P[0], ends["lo"]]), np.array([P[-1], ends["hi"]])):
        ends.pop("lo"), ends.pop("hi")              # the two continuations would meet: cut both
    if not ends:
        return body, Closure(radius=R, size=size, slab_width=width)
    pts = [ends["lo"][None]] if "lo" in ends else []
    pts += [P] + ([ends["hi"][None]] if "hi" in ends else [])
    Q = np.concatenate(pts)
    ext_lo = float(np.linalg.norm(ends["lo"] - P[0])) if "lo" in ends else 0.0
    ext_hi = float(np.linalg.norm(ends["hi"] - P[-1])) if "hi" in ends else 0.0
    grown = Profile2D(Q[:, 0], Q[:, 1], prof.name, s_start=float(prof.s[0]) - ext_lo)
    return BodyModel(body.kind, grown, body.axle_z), Closure(ext_lo, ext_hi, R, size, width)


def body_extent(body: BodyModel, patch: StripPatch, size: float = 1.0) -> BodyExtent:
    """Body limits for a patch: a margin of ``size`` x patch size around it (see BodyExtent).

    Raises InputError when the patch does not fit on the profile, when the profile ends too close
    to the patch, or when a wheel sector would exceed the wheel.
    """
    if not (size > 0 and math.isfinite(size)):
        raise InputError(f"[model] fe_body_size: must be > 0, got {size}")
    prof = body.profile
    e = patch.edges
    if e[0] < prof.s[0] - 1e-9 or e[-1] > prof.s[-1] + 1e-9:
        raise InputError(f"profile {prof.name}: too short for the requested patch: the grid spans "
                         f"s = {e[0]:.3f} .. {e[-1]:.3f} mm along the profile, the profile "
                         f"{prof.s[0]:.3f} .. {prof.s[-1]:.3f} mm")
    s_mid = 0.5 * (e[0] + e[-1])
    c, r_patch, R, margin, wheel_limited = _disc(body, patch, size)
    half = patch.n_columns * 0.5 * patch.dx + margin
    r_ref = None if body.below else float(body.radius_at(s_mid))
    # A profile end inside the disc is closed by a straight cut to the circle (along the inward
    # normal, or the nearest direction that does not cross the profile).  Where that cut would be
    # a sliver (the end lies just inside) or cannot be made, the disc shrinks to pass through
    # that end instead.
    for _ in range(6):
        s_lo, cut_lo = _leave_disc(prof, c, R, e[0], -1)
        s_hi, cut_hi = _leave_disc(prof, c, R, e[-1], +1)
        ss = np.concatenate([[s_lo], prof.s[(prof.s > s_lo) & (prof.s < s_hi)], [s_hi]])
        curve = prof.point(ss)
        shrink, q_end = [], {}
        for s_end, cut in ((s_lo, cut_lo), (s_hi, cut_hi)):
            if not cut:
                continue
            p = prof.point(s_end)
            d = float(np.linalg.norm(p - c))
            q_end[s_end] = _end_cut(p, inward_normal(body, s_end), c, R, curve, 0.3 * margin)
            if d > R - 0.3 * margin or q_end[s_end] is None:
                shrink.append(d)
        if len(q_end) == 2 and not shrink and _segments_intersect(
                np.array([prof.point(s_lo), q_end[s_lo]]), np.array([prof.point(s_hi), q_end[s_hi]])):
            shrink.append(max(float(np.linalg.norm(prof.point(s) - c)) for s in q_end))
        if not shrink:
            break
        R = min(shrink) * (1 - 1e-9)
    else:
        raise InputError(f"profile {prof.name}: cannot close the {body.kind} body's cross-section around the "
                         "patch (the profile ends close to it); extend the profile or reduce [model] fe_body_size")
    if R < r_patch + 0.2 * margin:
        raise InputError(f"profile {prof.name}: too short for an FE body around the patch: it ends "
                         f"{R - r_patch:.2f} mm beyond the patch; extend the profile or reduce [model] fe_body_size")
    p_lo, p_hi = prof.point(s_lo), prof.point(s_hi)
    q_lo = q_end[s_lo] if cut_lo else p_lo
    q_hi = q_end[s_hi] if cut_hi else p_hi
    # the arc from q_hi to q_lo on the material side: the one whose closed section contains a
    # point just inside the material at the patch centre
    probe = c + 1e-4 * R * inward_normal(body, s_mid)
    a0 = math.atan2(q_hi[1] - c[1], q_hi[0] - c[0])
    a1 = math.atan2(q_lo[1] - c[1], q_lo[0] - c[0])
    ccw = (a1 - a0) % (2 * math.pi)
    for sweep in (ccw, ccw - 2 * math.pi):
        t = a0 + np.linspace(0.0, sweep, 129)
        arc = c + R * np.column_stack([np.cos(t), np.sin(t)])
        closing = np.vstack([[p_hi]] * cut_hi + [arc] + [[p_lo]] * cut_lo)
        if _inside(np.vstack([curve, closing]), probe):
            break
    else:
        raise InputError(f"profile {prof.name}: cannot close the FE body's cross-section around the patch")
    mid = arc[64]
    return BodyExtent(-half, half, float(s_lo), float(s_hi), float(R - r_patch), (float(c[0]), float(c[1])),
                      float(R), (float(q_lo[0]), float(q_lo[1])), (float(q_hi[0]), float(q_hi[1])),
                      (float(mid[0]), float(mid[1])), bool(cut_lo), bool(cut_hi), r_ref, wheel_limited)


def section_profile(points: np.ndarray, n_profile: int, support_edge: int, name: str = "section") -> Profile2D:
    """The boundary of a whole cross-section as one open profile: the closed polygon ``points``
    (its first ``n_profile`` points the contact profile, then the closure on the material side,
    as :mod:`conformal.geometry.sections` builds them) opened at its support edge
    ``support_edge`` (points i -> i + 1, cyclic: the rail's foot, the wheel's hub face), so that it
    runs from that edge's end round the section to its start.  The contact profile's points keep
    their arc lengths (the part before them gets s < 0), so a patch given on the contact profile
    is on the section profile at the same s; :func:`closed_section_extent` joins the two ends
    again by the straight support edge.

    >>> sq = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    >>> p = section_profile(sq, 2, 2)          # open at the edge (1, 1) -> (0, 1)
    >>> p.y.tolist(), p.z.tolist(), p.s.tolist()
    ([0.0, 0.0, 1.0, 1.0], [1.0, 0.0, 0.0, 1.0], [-1.0, 0.0, 1.0, 2.0])
    """
    P = np.asarray(points, dtype=float)
    k = int(support_edge) % len(P)
    if not 0 < n_profile <= len(P) or k < n_profile - 1:
        raise InputError(f"section {name}: the support edge {support_edge} must not be part of the profile")
    Q = np.concatenate([P[k + 1:], P[:k + 1]])
    before = len(P) - (k + 1)
    seg = np.hypot(*np.diff(Q[:before + 1], axis=0).T) if before else np.zeros(0)
    return Profile2D(Q[:, 0], Q[:, 1], name, s_start=-float(seg.sum()))


def closed_section_extent(body: BodyModel, patch: StripPatch, size: float) -> BodyExtent:
    """Body limits of a whole section (``fe_closure = "section"``): the body's profile is the
    section's boundary less its support edge (:func:`section_profile`), the section the polygon
    closed by that straight edge, and the body that section cut by the disc of ``size`` patch
    sizes around the patch (:func:`_disc`; a wheel's disc limited as there).  Where the disc
    contains the whole section only the length along x grows with the size.  ``s_lo .. s_hi``
    span the parts of the profile inside the disc (the free surface: the profile, the web, the
    foot's upper face, the rim faces); the disc's arcs, the support edge and the end faces are
    the artificial boundary."""
    if not (size > 0 and math.isfinite(size)):
        raise InputError(f"[model] fe_body_size: must be > 0, got {size}")
    prof = body.profile
    e = patch.edges
    if e[0] < prof.s[0] - 1e-9 or e[-1] > prof.s[-1] + 1e-9:
        raise InputError(f"profile {prof.name}: the grid spans s = {e[0]:.3f} .. {e[-1]:.3f} mm, beyond the section")
    P = np.stack([prof.y, prof.z], axis=1)
    if _segments_intersect(np.array([P[-1], P[0]]), P[1:-1]):
        raise InputError(f"profile {prof.name}: the support edge between its ends crosses the section")
    c, r_patch, R, margin, limited = _disc(body, patch, size)
    dist = np.linalg.norm(P - c, axis=1)
    inside = dist <= R
    s_in = list(prof.s[inside])
    for i in np.flatnonzero(inside[:-1] != inside[1:]):        # where a segment crosses the circle
        a, b = P[i], P[i + 1]
        d = b - a
        f = a - c
        A, B, C = d @ d, 2 * (f @ d), f @ f - R * R
        disc = max(B * B - 4 * A * C, 0.0)
        for t in ((-B - math.sqrt(disc)) / (2 * A), (-B + math.sqrt(disc)) / (2 * A)):
            if 0.0 <= t <= 1.0:
                s_in.append(prof.s[i] + t * (prof.s[i + 1] - prof.s[i]))
    s_lo, s_hi = float(min(s_in)), float(max(s_in))
    half = patch.n_columns * 0.5 * patch.dx + margin
    s_mid = 0.5 * (e[0] + e[-1])
    r_ref = None if body.below else float(body.radius_at(s_mid))
    q = (float(c[0]), float(c[1]))
    return BodyExtent(-half, half, s_lo, s_hi, float(margin), q, float(R), q, q, q, False, False, r_ref,
                      limited, closed=True)
