"""Contact search: all local minima of the gap, refined by Newton-Raphson (seed Eqs. 54-56).

1. *Global search.*  Because the rail is an extrusion along x, a contact point on the wheel must
   lie on the wheel's *contact locus*: on each wheel circle, the point whose surface normal is
   perpendicular to x (:meth:`WheelSurface.locus_theta`).  Sampling the locus every 0.05 mm of
   wheel profile gives a curve that is compared with the rail profile in the (y, z) plane: the
   vertical gap of every locus point to the top of the rail.  Every local minimum of that gap is a
   candidate contact (tread and flange patches, two-point contact); minima shallower than 0.1 um
   are merged with their neighbour.
2. *Local refinement.*  Each candidate is refined by Newton-Raphson on the four conditions of seed
   Eq. 54 in the surface parameters q = (s_w, theta, x, s_r), with the analytic Jacobian (seed
   Eq. 55, built from the splines' first and second derivatives):

       F1 = t1_r . d = 0,  F2 = t2_r . d = 0,  F3 = t1_w . n_r = 0,  F4 = e_t . n_r = 0,

   d = r_w - r_r.  (F4 uses the unit tangent e_t = t2_w / rho instead of t2_w: the same equation,
   better scaled.  The seed prints Eq. 55 with a column of its Jacobian misplaced; this Jacobian
   is derived afresh.)
3. *Penetration* (seed Eq. 56) delta = d . n_r with n_r the inner normal of the rail: delta > 0
   is an overlap of the undeformed surfaces (the seed uses the outer normal, so its sign is the
   opposite).

Principal relative curvatures for Hertz follow from the second fundamental forms of both
surfaces expressed in the contact frame (t1 = x, t2 = lateral tangent, n into the rail).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np
from scipy.spatial import cKDTree

from conformal.errors import ConvergenceError, InputError, NoContactError
from conformal.geometry.spline import clip
from conformal.geometry.surfaces import LOCUS_REACH_MARGIN, RailSurface, WheelSurface

LOCUS_STEP = 0.05      # mm of wheel profile between locus samples
MERGE_DEPTH = 1e-4     # mm: minima separated by a smaller bump are one minimum
#: :meth:`RailTop.s_near` looks for the nearest rail sample among this many samples either side of
#: the envelope's (0.02 mm apart; on the Manchester sequence the nearest lies at most 5 away)
NEAR_WINDOW = 6


# ----------------------------------------------------------------------------- rail top
@dataclass(frozen=True, eq=False)
class RailTop:
    """The upper envelope z_top(y) of a placed rail profile (what a falling wheel meets first)."""

    y0: float
    hy: float
    z: np.ndarray
    s: np.ndarray          # arc length of the envelope point
    tree: cKDTree
    s_samples: np.ndarray
    y_min: float
    y_max: float

    @classmethod
    def of(cls, rail: RailSurface, step: float = 0.02) -> "RailTop":
        return _rail_top(rail, step)

    @classmethod
    def build(cls, rail: RailSurface, step: float = 0.02) -> "RailTop":
        s, p = rail.sample(step)
        y, z = p[:, 0], p[:, 1]
        hy = 0.5 * step
        y0 = float(y.min())
        n = int(math.ceil((y.max() - y0) / hy)) + 1
        ya, yb, za, zb = y[:-1], y[1:], z[:-1], z[1:]
        sa, sb = s[:-1], s[1:]
        lo, hi = np.minimum(ya, yb), np.maximum(ya, yb)
        i_lo = np.ceil((lo - y0) / hy - 1e-9).astype(int)
        i_hi = np.floor((hi - y0) / hy + 1e-9).astype(int)
        count = np.maximum(i_hi - i_lo + 1, 0)
        seg = np.repeat(np.arange(ya.size), count)
        idx = np.repeat(i_lo, count) + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
        yg = y0 + idx * hy
        dy = yb[seg] - ya[seg]
        w = np.where(np.abs(dy) > 1e-12, (yg - ya[seg]) / np.where(np.abs(dy) > 1e-12, dy, 1.0), 0.0)
        w = np.clip(w, 0.0, 1.0)
        zg = za[seg] + w * (zb[seg] - za[seg])
        sg = sa[seg] + w * (sb[seg] - sa[seg])
        order = np.lexsort((zg, idx))          # per grid index, smallest z first
        idx, zg, sg = idx[order], zg[order], sg[order]
        first = np.r_[True, idx[1:] != idx[:-1]]
        ztop = np.full(n, np.nan)
        stop = np.full(n, np.nan)
        ztop[idx[first]] = zg[first]
        stop[idx[first]] = sg[first]
        return cls(y0, hy, ztop, stop, cKDTree(p), s, float(y.min()), float(y.max()))

    def z_at(self, y: np.ndarray) -> np.ndarray:
        """Envelope height at y (NaN outside the rail)."""
        t = (np.asarray(y) - self.y0) / self.hy
        i = np.clip(np.floor(t).astype(int), 0, self.z.size - 2)
        w = t - i.astype(float)          # t - i (the same numbers, without a mixed-type loop)
        z = (1 - w) * self.z[i] + w * self.z[i + 1]
        return np.where((y >= self.y_min) & (y <= self.y_max), z, np.nan)

    def s_near(self, yz: np.ndarray) -> np.ndarray:
        """Arc length of the rail sample nearest to points yz (..., 2).

        Points given as an (N, 2) array are first looked for among the NEAR_WINDOW samples either
        side of the envelope's sample at their y (a point near the top of the rail lies within a
        few samples of it): where the nearest of those is not at the window's edge, the sample
        distances fall towards it and rise after it, and it is the k-d tree's answer unless
        another stretch of the profile, more than NEAR_WINDOW samples away along it, came closer
        (not for the points within a few hundredths of a millimetre of the top that the patch
        search projects); the others (and points off the envelope) ask the tree."""
        yz = np.asarray(yz, float)
        if yz.ndim != 2 or yz.shape[0] < 8 or self.s_samples.size < 4 * NEAR_WINDOW:
            _, k = self.tree.query(yz)
            return self.s_samples[k]
        return self.s_samples[self._near_index(yz)]

    @cached_property
    def _sample_yz(self) -> tuple[np.ndarray, np.ndarray]:
        """The samples' y and z (contiguous copies of the tree's points)."""
        p = self.tree.data
        return np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1])

    def _near_index(self, yz: np.ndarray) -> np.ndarray:
        """The index of the sample nearest to each point of yz (N, 2) (:meth:`s_near`)."""
        (py, pz), ss, W = self._sample_yz, self.s_samples, NEAR_WINDOW
        n = ss.size
        qy, qz = yz[:, 0], yz[:, 1]
        i = clip(np.rint((qy - self.y0) / self.hy), 0.0, self.z.size - 1.0).astype(np.intp)
        guess = self.s.take(i) * ((n - 1) / ss[-1])                  # the envelope's sample index
        ok = np.isfinite(guess)
        j = clip(np.rint(np.where(ok, guess, 0.0)), W, n - 1.0 - W).astype(np.intp)
        cand = j[:, None] + np.arange(-W, W + 1)
        dy = py.take(cand)
        dy -= qy[:, None]
        dz = pz.take(cand)
        dz -= qz[:, None]
        dy *= dy
        dz *= dz
        dy += dz                                                     # the squared distances
        m = dy.argmin(axis=1)
        k = cand[np.arange(m.size), m]
        redo = ~ok | (m == 0) | (m == 2 * W) | ~np.isfinite(dy.min(axis=1))
        if redo.any():
            k[redo] = self.tree.query(yz[redo])[1]
        return k


@lru_cache(maxsize=64)
def _rail_top(rail: RailSurface, step: float) -> RailTop:   # rails are compared by identity
    return RailTop.build(rail, step)


# ----------------------------------------------------------------------------- locus and gap
@dataclass(frozen=True, eq=False)
class Locus:
    """The wheel's contact locus sampled along the wheel profile."""

    s: np.ndarray          # wheel-profile arc length
    theta: np.ndarray      # rotation angle (NaN: no locus point, or none that can lie over the rail)
    points: np.ndarray     # (n, 3) side frame
    gap: np.ndarray        # vertical gap to the rail top (NaN outside the rail / no locus)
    e_r: np.ndarray | None = None   # (n, 3) radial direction at theta (NaN theta: 0), if known
    rho: np.ndarray | None = None   # wheel radius at s, if known


def wheel_locus(wheel: WheelSurface, top: RailTop, step: float = LOCUS_STEP) -> Locus:
    """The wheel's contact locus sampled every ``step`` mm of wheel profile, theta NaN where there is
    none or where the sample cannot lie over the rail (:meth:`WheelSurface.locus_reach`)."""
    s, _ = wheel.curve.sample(step)
    u, rho = wheel.meridian(s)[:2]
    reach = wheel.locus_reach(u, rho, top.y_min, top.y_max)
    th = np.full(s.shape, np.nan)
    th[reach] = wheel.locus_theta(s[reach])
    pts = wheel.point(s, np.nan_to_num(th))
    return _locus(s, th, pts, top)


def pair_locus(pair, top: RailTop, z: float, step: float = LOCUS_STEP) -> Locus:
    """The contact locus of the wheel of ``pair`` (a :class:`~conformal.geometry.placement.WheelRailPair`)
    at wheelset height z: the pair's locus sampled once and moved by z
    (:meth:`~conformal.geometry.placement.WheelRailPair.locus_samples`), equal to
    ``wheel_locus(pair.wheel(z), top)`` to rounding."""
    span = (top.y_min, top.y_max)
    s, th, pts = pair.locus_samples(z, step, span)
    loc = _locus(s, th, pts, top, pair.rail_top_under_locus(top, step, span))
    er, rho = pair.locus_radial(step, span)
    return Locus(loc.s, loc.theta, loc.points, loc.gap, er, rho)


def _locus(s: np.ndarray, th: np.ndarray, pts: np.ndarray, top: RailTop, z_top: np.ndarray | None = None) -> Locus:
    """The locus with its vertical gap; ``z_top``: the rail top at the points' y if known."""
    gap = (top.z_at(pts[:, 1]) if z_top is None else z_top) - pts[:, 2]
    gap = np.where(np.isnan(th), np.nan, gap)
    return Locus(s, th, pts, gap)


def local_minima(g: np.ndarray, merge: float = MERGE_DEPTH) -> list[int]:
    """Indices of the local minima of g (NaN = no data), merging minima separated by a bump
    smaller than ``merge``; sorted by increasing g."""
    valid = np.isfinite(g)
    if not valid.any():
        return []
    return _local_minima(np.where(valid, g, np.inf), valid, merge)


def _local_minima(gg: np.ndarray, valid: np.ndarray, merge: float) -> list[int]:
    """:func:`local_minima` of gg = g with inf for NaN (``valid``: where g is finite, at least once)."""
    inf = np.array([np.inf])
    left = np.concatenate((inf, gg[:-1]))
    right = np.concatenate((gg[1:], inf))
    cand = np.nonzero(valid & (gg <= left) & (gg < right))[0]
    # plateaus that end with an equal value on the right
    cand = list(cand)
    if not cand:
        return []
    # merge neighbours whose separating maximum is less than `merge` above the higher minimum
    merged = [cand[0]]
    for i in cand[1:]:
        j = merged[-1]
        between = gg[j:i + 1]
        bump = np.max(between[np.isfinite(between)]) if np.isfinite(between).any() else np.inf
        if not np.all(np.isfinite(between)):
            merged.append(i)          # a stretch without data separates the minima
        elif bump - max(gg[i], gg[j]) < merge:
            if gg[i] < gg[j]:
                merged[-1] = i
        else:
            merged.append(i)
    return sorted(merged, key=lambda k: gg[k])


#: mm: the sampled vertical gap of a locus lies above the continuous gap by at most the sampling's
#: terms (:func:`_gap_floor`) plus this (rounding, the envelope's crossing segments)
SAMPLE_GAP_TOL = 1e-5
#: mm: a sampled local minimum of the gap is left out of the search for the touching contact only
#: where the continuous gap in its basin lies provably this much above the smallest sampled gap
TOUCH_CLEAR = 1e-6
#: mm of profile arc length: a touching contact sampled this far from the ends of both profiles is
#: not at an end (its Newton-Raphson solution lies within 3 mm of its start, :func:`find_contacts`)
END_CLEAR = 3.0


def _gap_floor(gg: np.ndarray, valid: np.ndarray, y: np.ndarray, top: RailTop, j: int, h: float) -> float:
    """A lower bound (mm) of the continuous vertical gap between the neighbours of the sampled local
    minimum j of gg (the locus gap with inf for NaN; ``y``: the samples' lateral positions, ``h``:
    the sampling step along the wheel profile), -inf at the end of a stretch of samples.

    The continuous minimum lies within one sample of j; a quadratic through the three samples dips
    below gg[j] by at most d2/8 (d2 = gg[j-1] - 2 gg[j] + gg[j+1]), taken 4 times; the rail top
    (:class:`RailTop`: chords of the rail samples regridded linearly every hy) lies above the
    profile by at most 5/8 of its largest second difference near y[j] (the chords' 0.02 mm of arc
    length project onto at most two grid steps), taken as the whole second difference."""
    n = gg.size
    if j <= 0 or j >= n - 1 or not (valid[j - 1] and valid[j + 1]):
        return -math.inf
    d2 = float(gg[j - 1] - 2.0 * gg[j] + gg[j + 1])
    k = int((float(y[j]) - top.y0) / top.hy)
    reach = int(math.ceil(h / top.hy)) + 2
    z = top.z[max(k - reach, 0): k + reach + 2]
    if z.size < 3:
        return -math.inf
    d2r = float(np.max(np.abs(z[:-2] - 2.0 * z[1:-1] + z[2:])))
    if not math.isfinite(d2r):
        return -math.inf
    return float(gg[j]) - 0.5 * abs(d2) - d2r - SAMPLE_GAP_TOL


def touch_candidates(loc: Locus, top: RailTop) -> tuple[int, float, float, list[int]]:
    """The sampled local minima of a locus's vertical gap that can hold its smallest continuous gap.

    Returns
    -------
    i_min : int
        The sample of the smallest gap (the first, numpy's argmin of the gap with NaN as inf).
    g_min : float
        That gap (mm): an upper bound of the continuous minimum.
    g_low : float
        A lower bound (mm) of the continuous minimum: the smallest :func:`_gap_floor` of the local
        minima (-inf where one ends a stretch of samples).
    contenders : list of int
        The local minima (not merged, :func:`local_minima`'s candidates) whose floor lies less
        than TOUCH_CLEAR above g_min, ascending: the others touch later than the sample i_min
        when the wheel is lowered vertically.
    """
    valid = np.isfinite(loc.gap)
    if not valid.any():
        raise NoContactError("contact search: the wheel does not lie over the rail")
    gg = np.where(valid, loc.gap, np.inf)
    i_min = int(np.argmin(gg))
    g_min = float(gg[i_min])
    inf = np.array([np.inf])
    raw = np.nonzero(valid & (gg <= np.concatenate((inf, gg[:-1]))) & (gg < np.concatenate((gg[1:], inf))))[0]
    h = float(loc.s[1] - loc.s[0]) if loc.s.size > 1 else 0.0
    y = loc.points[:, 1]
    g_low, contenders = math.inf, []
    for j in raw.tolist():
        f = _gap_floor(gg, valid, y, top, j, h)
        g_low = min(g_low, f)
        if f <= g_min + TOUCH_CLEAR:
            contenders.append(j)
    return i_min, g_min, min(g_low, g_min), contenders


# ----------------------------------------------------------------------------- Newton (Eqs. 54-55)
@dataclass(frozen=True, eq=False)
class ContactPoint:
    """A refined contact point of one wheel on one rail (side frame)."""

    s_w: float
    theta: float
    x: float
    s_r: float
    rail_point: np.ndarray       # (3,) on the rail surface
    wheel_point: np.ndarray      # (3,) on the wheel surface
    normal: np.ndarray           # (3,) unit inner normal of the rail
    t2: np.ndarray               # (3,) lateral unit tangent, t2 = n x t1
    penetration: float           # mm, d . n_r > 0 = overlap (seed Eq. 56, sign flipped)
    rolling_radius: float        # distance of the wheel point from the axle (mm)
    y_wheel: float               # wheel-profile coordinates of the wheel point
    z_wheel: float
    iterations: int
    residual: float
    at_end: bool = False         # the solution sits on an end of a profile
    #: (wheel, rail, vectors at the point) for the curvatures, computed when first asked for (a
    #: search for the touching height needs none of them)
    surfaces: tuple = field(default=(), repr=False)

    @cached_property
    def _curvature_parts(self) -> tuple[np.ndarray, float, float]:
        return _curvatures(*self.surfaces)

    @property
    def curvature(self) -> np.ndarray:
        """(2, 2) relative curvature K = K_rail - K_wheel (1/mm) in (t1, t2)."""
        return self._curvature_parts[0]

    @property
    def kappa_rail(self) -> float:
        """Lateral curvature of the rail profile (1/mm)."""
        return self._curvature_parts[1]

    @property
    def kappa_wheel(self) -> float:
        """Lateral curvature of the wheel profile (1/mm)."""
        return self._curvature_parts[2]

    @property
    def delta(self) -> float:
        """Contact angle (rad): rotation about x from the z axis to the inner normal (CONTACT's DELTCP)."""
        return float(math.atan2(-self.normal[1], self.normal[2]))

    @property
    def gap(self) -> float:
        return -self.penetration

    def principal(self) -> tuple[float, float, float]:
        """A, B (1/mm; h = A x'^2 + B y'^2 in principal axes) and the angle (rad) of the x' axis
        from the rolling direction."""
        K = 0.5 * (self.curvature + self.curvature.T)
        w, v = _eigh(0.5 * K)
        # the eigenvector closest to the rolling direction is x'
        k = int(np.argmax(np.abs(v[0, :])))
        A, B = float(w[k]), float(w[1 - k])
        vx = v[:, k] * np.sign(v[0, k])
        return A, B, float(math.atan2(vx[1], vx[0]))


def _residual_and_jacobian(wheel: WheelSurface, rail: RailSurface, q: np.ndarray):
    s_w, th, x, s_r = q
    u, rho, u1, rho1, u2, rho2 = (float(v) for v in wheel.meridian(s_w))
    f = wheel.frame
    er, et = wheel.e_r(th), wheel.e_t(th)
    rw = f.O + u * f.a + rho * er
    t1w = u1 * f.a + rho1 * er
    t2w = rho * et
    Y, Z, Y1, Z1, Y2, Z2 = (float(v) for v in rail.profile(s_r))
    rr = np.array([x, Y, Z])
    g = math.hypot(Y1, Z1)
    t2r = np.array([0.0, Y1, Z1])
    m = np.array([0.0, -Z1, Y1])
    n = m / g
    dm = np.array([0.0, -Z2, Y2])
    dn = (dm - n * (n @ dm)) / g
    dt2r = np.array([0.0, Y2, Z2])
    d = rw - rr
    F = np.array([d[0], t2r @ d, t1w @ n, et @ n])
    J = np.array([
        [t1w[0], t2w[0], -1.0, 0.0],
        [t2r @ t1w, t2r @ t2w, 0.0, dt2r @ d - t2r @ t2r],
        [(u2 * f.a + rho2 * er) @ n, rho1 * (et @ n), 0.0, t1w @ dn],
        [0.0, -(er @ n), 0.0, et @ dn],
    ])
    return F, J, dict(rw=rw, rr=rr, n=n, t1w=t1w, t2w=t2w, er=er, et=et, u1=u1, rho1=rho1,
                      u2=u2, rho2=rho2, rho=rho, t2r=t2r / g, d=d, Y1=Y1, Z1=Z1, Y2=Y2, Z2=Z2)


def _newton_system(wheel: WheelSurface, rail: RailSurface, q, frame: tuple) -> tuple[list, list]:
    """F and J of :func:`_residual_and_jacobian` (the same expressions) in Python floats, for the
    Newton steps (four unknowns: numpy's per-call cost exceeds the arithmetic); ``frame`` = the
    wheel frame's (O, a, e_d, e_f) as tuples."""
    s_w, th, x, s_r = (float(v) for v in q)
    u, rho, u1, rho1, u2, rho2 = (float(v) for v in wheel.meridian(s_w))
    (O0, O1, O2), (a0, a1, a2), (d0, d1, d2), (f0, f1, f2) = frame
    c, sn = math.cos(th), math.sin(th)
    er = (c * d0 + sn * f0, c * d1 + sn * f1, c * d2 + sn * f2)
    et = (-sn * d0 + c * f0, -sn * d1 + c * f1, -sn * d2 + c * f2)
    rw = (O0 + u * a0 + rho * er[0], O1 + u * a1 + rho * er[1], O2 + u * a2 + rho * er[2])
    t1w = (u1 * a0 + rho1 * er[0], u1 * a1 + rho1 * er[1], u1 * a2 + rho1 * er[2])
    t2w = (rho * et[0], rho * et[1], rho * et[2])
    Y, Z, Y1, Z1, Y2, Z2 = (float(v) for v in rail.profile(s_r))
    g = math.hypot(Y1, Z1)
    n1, n2 = -Z1 / g, Y1 / g                      # n = (0, n1, n2)
    ndm = n1 * -Z2 + n2 * Y2
    dn1, dn2 = (-Z2 - n1 * ndm) / g, (Y2 - n2 * ndm) / g
    e0, e1, e2 = rw[0] - x, rw[1] - Y, rw[2] - Z
    a_ss = (u2 * a1 + rho2 * er[1], u2 * a2 + rho2 * er[2])
    etn = et[1] * n1 + et[2] * n2
    F = [e0, Y1 * e1 + Z1 * e2, t1w[1] * n1 + t1w[2] * n2, etn]
    J = [[t1w[0], t2w[0], -1.0, 0.0],
         [Y1 * t1w[1] + Z1 * t1w[2], Y1 * t2w[1] + Z1 * t2w[2], 0.0, (Y2 * e1 + Z2 * e2) - (Y1 * Y1 + Z1 * Z1)],
         [a_ss[0] * n1 + a_ss[1] * n2, rho1 * etn, 0.0, t1w[1] * dn1 + t1w[2] * dn2],
         [0.0, -(er[1] * n1 + er[2] * n2), 0.0, et[1] * dn1 + et[2] * dn2]]
    return F, J


def _dot3(a, b) -> float:
    """a . b of 3-tuples with the arithmetic of numpy's ``@`` on 3-vectors ((p0 + p1) + p2)."""
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]


def _contact_values(wheel: WheelSurface, rail: RailSurface, q) -> tuple[list, dict]:
    """The residual F and the vectors ``v`` of :func:`_residual_and_jacobian` at a converged q, the
    same expressions in Python floats (numpy arrays in ``v``, as there)."""
    s_w, th, x, s_r = (float(c) for c in q)
    u, rho, u1, rho1, u2, rho2 = wheel.meridian(s_w)
    O, a, ed, ef = wheel.frame_floats
    c, sn = math.cos(th), math.sin(th)
    msn = -sn
    er = tuple(c * ed[k] + sn * ef[k] for k in range(3))
    et = tuple(msn * ed[k] + c * ef[k] for k in range(3))
    rw = tuple((O[k] + u * a[k]) + rho * er[k] for k in range(3))
    t1w = tuple(u1 * a[k] + rho1 * er[k] for k in range(3))
    t2w = tuple(rho * et[k] for k in range(3))
    Y, Z, Y1, Z1, Y2, Z2 = rail.profile(s_r)
    rr = (x, Y, Z)
    g = math.hypot(Y1, Z1)
    t2r = (0.0, Y1, Z1)
    n = (0.0 / g, -Z1 / g, Y1 / g)
    d = tuple(rw[k] - rr[k] for k in range(3))
    F = [d[0], _dot3(t2r, d), _dot3(t1w, n), _dot3(et, n)]
    arr = np.array
    v = dict(rw=arr(rw), rr=arr(rr), n=arr(n), t1w=arr(t1w), t2w=arr(t2w), er=arr(er), et=arr(et), u1=u1,
             rho1=rho1, u2=u2, rho2=rho2, rho=rho, t2r=arr((0.0 / g, Y1 / g, Z1 / g)), d=arr(d),
             Y1=Y1, Z1=Z1, Y2=Y2, Z2=Z2)
    return F, v


def _curvatures(wheel: WheelSurface, rail: RailSurface, v: dict) -> tuple[np.ndarray, float, float]:
    """Relative curvature matrix in (t1 = e_x, t2) and the lateral profile curvatures."""
    n, f = v["n"], wheel.frame
    # wheel second fundamental form in its parameters (s_w, theta), w.r.t. n (into the rail)
    r_ss = v["u2"] * f.a + v["rho2"] * v["er"]
    r_st = v["rho1"] * v["et"]
    r_tt = -v["rho"] * v["er"]
    II = np.array([[r_ss @ n, r_st @ n], [r_st @ n, r_tt @ n]])
    Jw = np.column_stack([v["t1w"], v["t2w"]])
    e1, e2 = np.array([1.0, 0.0, 0.0]), v["t2r"]
    C = _lstsq(Jw, np.column_stack([e1, e2]))   # tangent vectors in (s_w, theta)
    Kw = C.T @ II @ C
    Y1, Z1, Y2, Z2 = v["Y1"], v["Z1"], v["Y2"], v["Z2"]
    kr = (Y1 * Z2 - Z1 * Y2) / (Y1 * Y1 + Z1 * Z1) ** 1.5
    Kr = np.array([[0.0, 0.0], [0.0, kr]])
    return Kr - Kw, float(kr), float(Kw[1, 1])


def _cross_x(n: np.ndarray) -> np.ndarray:
    """n x e_x, with numpy.cross's arithmetic (signed zeros included), without its per-call cost."""
    n0, n1, n2 = (float(c) for c in n)
    return np.array([n1 * 0.0 - n2 * 0.0, n2 * 1.0 - n0 * 0.0, n0 * 0.0 - n1 * 1.0])


def _raise_singular(err, flag):
    raise np.linalg.LinAlgError("Singular matrix")


#: the floating-point error state numpy.linalg.solve sets around its LAPACK call (a singular matrix
#: raises LinAlgError)
_SOLVE_ERRSTATE = dict(call=_raise_singular, invalid="call", over="ignore", divide="ignore", under="ignore")


def _raise_eigh(err, flag):
    raise np.linalg.LinAlgError("Eigenvalues did not converge")


def _raise_lstsq(err, flag):
    raise np.linalg.LinAlgError("SVD did not converge in Linear Least Squares")

try:   # the gufuncs numpy.linalg.solve (one right-hand side), eigh and lstsq call (the same numbers),
    from numpy.linalg import _umath_linalg    # without their per-call argument handling

    def _solve1(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """numpy.linalg.solve(a, b) of float arrays, b a vector; under _SOLVE_ERRSTATE."""
        return _umath_linalg.solve1(a, b, signature="dd->d")

    def _eigh(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """numpy.linalg.eigh(a) of a real symmetric float array (its lower triangle)."""
        with np.errstate(**{**_SOLVE_ERRSTATE, "call": _raise_eigh}):
            return _umath_linalg.eigh_lo(a, signature="d->dd")

    def _lstsq(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """numpy.linalg.lstsq(a, b, rcond=None)[0] of float arrays a (m, n), b (m, k), k > 0."""
        rcond = np.finfo(np.float64).eps * max(a.shape)
        with np.errstate(**{**_SOLVE_ERRSTATE, "call": _raise_lstsq}):
            return _umath_linalg.lstsq(a, b, rcond, signature="ddd->ddid")[0]
except ImportError:                     # pragma: no cover - other numpy layouts
    def _solve1(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.linalg.solve(a, b)

    def _eigh(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.linalg.eigh(a)

    def _lstsq(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.linalg.lstsq(a, b, rcond=None)[0]


def newton_contact(wheel: WheelSurface, rail: RailSurface, q0, *, tol: float = 1e-11,
                   maxit: int = 40) -> ContactPoint:
    """Refine a contact point from the start q0 = (s_w, theta, x, s_r) (seed Eqs. 54-55)."""
    q = [float(v) for v in q0]            # Python floats: the arithmetic of numpy's, per entry
    Lw, Lr = wheel.curve.length, rail.curve.length
    res = np.inf
    frame = wheel.frame_floats
    array = np.array
    with np.errstate(**_SOLVE_ERRSTATE):  # numpy.linalg.solve's, once for the loop
        for it in range(1, maxit + 1):
            F, J = _newton_system(wheel, rail, q, frame)
            try:
                dq = _solve1(array(J), -array(F)).tolist()
            except np.linalg.LinAlgError:
                raise ConvergenceError("contact search: singular Jacobian (seed Eq. 55) at "
                                       f"s_w = {q[0]:.3f}, s_r = {q[3]:.3f} mm") from None
            # limit the step (a Newton step may jump across the profile where curvatures change fast)
            scale = max(1.0, abs(dq[0]) / 2.0, abs(dq[3]) / 2.0, abs(dq[1]) / 0.05)
            dq = [v / scale for v in dq]
            q = [a + b for a, b in zip(q, dq)]
            q[0] = min(max(q[0], 0.0), Lw)
            q[3] = min(max(q[3], 0.0), Lr)
            if (abs(dq[0]) < 1e-9 and abs(dq[2]) < 1e-9 and abs(dq[3]) < 1e-9 and abs(dq[1]) < 1e-12
                    and scale == 1.0):
                break
    q = np.array(q)
    F, v = _contact_values(wheel, rail, q)
    Fa = np.array(F)
    res = math.sqrt(Fa.dot(Fa))           # numpy.linalg.norm's arithmetic (a dot product, sqrt)
    if not res < max(tol, 1e-8):
        raise ConvergenceError(f"contact search: Newton-Raphson (seed Eq. 55) did not converge "
                               f"in {maxit} iterations (residual {res:.2e})")
    n = v["n"]
    t2 = _cross_x(n)
    y_w, z_w = wheel.curve.derivatives(float(q[0]))[:2]
    at_end = q[0] <= 1e-9 or q[0] >= Lw - 1e-9 or q[3] <= 1e-9 or q[3] >= Lr - 1e-9
    return ContactPoint(s_w=float(q[0]), theta=float(q[1]), x=float(q[2]), s_r=float(q[3]),
                        rail_point=v["rr"], wheel_point=v["rw"], normal=n, t2=t2,
                        penetration=float(v["d"] @ n),
                        rolling_radius=float(v["rho"]), y_wheel=y_w, z_wheel=z_w, iterations=it,
                        residual=res, at_end=bool(at_end), surfaces=(wheel, rail, v))


# ----------------------------------------------------------------------------- global search
@dataclass(frozen=True, eq=False)
class SearchResult:
    contacts: list[ContactPoint]            # distinct local minima, deepest first
    locus: Locus
    candidates: list[int] = field(default_factory=list)


def find_contacts(wheel: WheelSurface, rail: RailSurface, top: RailTop | None = None, *,
                  window: float = 1.0, locus: Locus | None = None, deepest_only: bool = False) -> SearchResult:
    """All distinct contact candidates whose vertical gap is within ``window`` mm of the smallest,
    refined by Newton-Raphson; deepest (largest penetration) first.  ``locus``: the wheel's locus
    if known (:func:`pair_locus`).  ``deepest_only``: where the sampled gap shows that only the
    candidate of the smallest sampled gap can be the deepest (:func:`touch_candidates`: every other
    local minimum's floor lies TOUCH_CLEAR above it, so its contact overlaps less, or not at all,
    at every height where the wheel touches), only that one is refined and returned (the same
    contact, the same numbers; ``candidates`` holds it alone); all of them where it does not
    converge."""
    top = top or RailTop.of(rail)
    loc = locus if locus is not None else wheel_locus(wheel, top)
    valid = np.isfinite(loc.gap)
    if not valid.any():
        raise NoContactError("contact search: the wheel does not lie over the rail "
                             "(no part of the wheel profile is above the rail profile)")
    gg = np.where(valid, loc.gap, np.inf)      # numpy.nanmin / nanargmin's values, NaN as inf
    i_min = int(np.argmin(gg))
    gmin = float(gg[i_min])
    if i_min == 0 or i_min == valid.size - 1 or not (valid[i_min - 1] and valid[i_min + 1]):
        y_w = float(wheel.curve.y(loc.s[i_min]))
        raise InputError(f"the wheel would touch the rail at the end of a profile (wheel y = {y_w:.2f} mm, "
                         f"side-frame y = {loc.points[i_min, 1]:.2f} mm): the profiles do not cover "
                         "this position")
    contacts: list[ContactPoint] = []
    if deepest_only and touch_candidates(loc, top)[3] == [i_min]:
        # i_min is then the first of the merged candidates (a strict local minimum below all others)
        contacts = _refine(wheel, rail, top, loc, [i_min])
        cands = [i_min]
    if not contacts:
        cands = [i for i in _local_minima(gg, valid, MERGE_DEPTH) if loc.gap[i] <= gmin + window]
        contacts = _refine(wheel, rail, top, loc, cands)
    if not contacts:
        raise ConvergenceError("contact search: no candidate converged (seed Eq. 55)")
    contacts.sort(key=lambda c: -c.penetration)
    return SearchResult(contacts, loc, cands)


def _refine(wheel: WheelSurface, rail: RailSurface, top: RailTop, loc: Locus, cands: list[int]) -> list[ContactPoint]:
    """The contact points refined from the locus samples ``cands`` (:func:`find_contacts`), distinct,
    in the order of ``cands``."""
    contacts: list[ContactPoint] = []
    for i in cands:
        p = loc.points[i]
        s_r0 = float(top.s_near(np.array([p[1], p[2] + loc.gap[i]])))
        try:
            c = newton_contact(wheel, rail, (loc.s[i], loc.theta[i], p[0], s_r0))
        except ConvergenceError:
            continue
        # a solution far from its start belongs to another minimum (or is a saddle)
        if abs(c.s_w - loc.s[i]) > 3.0:
            continue
        if any(abs(c.s_w - o.s_w) < 0.05 and abs(c.s_r - o.s_r) < 0.05 for o in contacts):
            continue
        # keep minima of the distance only: the relative lateral curvature must not be strongly negative
        contacts.append(c)
    return contacts


def touch_height(pair, top: RailTop | None = None, z0: float = 0.0, *, tol: float = 1e-9,
                 maxit: int = 20, deepest_only: bool = False) -> tuple[float, SearchResult]:
    """Wheelset height z (side frame, z down) at which the wheel of ``pair`` first touches its
    rail, and the contact search there (the deepest contact has zero penetration).

    The locus is rigid under vertical translation, so the vertical gap gives the height to the
    envelope's resolution in one step; Newton-Raphson contact points then correct it
    (a vertical move dz changes the penetration by dz n_z).  ``deepest_only``: the searches refine
    only the candidate that can be the deepest where the sampled gap shows it
    (:func:`find_contacts`): the same height and contact, the search's other contacts left out."""
    top = top or RailTop.of(pair.rail)
    loc = pair_locus(pair, top, z0)
    if not np.isfinite(loc.gap).any():
        raise NoContactError("contact search: the wheel does not lie over the rail")
    z = z0 + float(np.nanmin(loc.gap))
    for _ in range(maxit):
        sr = find_contacts(pair.wheel(z), pair.rail, top, locus=pair_locus(pair, top, z), deepest_only=deepest_only)
        c = sr.contacts[0]
        dz = -c.penetration / c.normal[2]
        z += dz
        if abs(c.penetration) < tol:
            return z, sr
    raise ConvergenceError(f"contact search: the touching height did not converge (penetration "
                           f"{c.penetration:.2e} mm after {maxit} corrections)")



#: mm of wheel profile between the locus samples of :func:`touch_point` when only the touching
#: height is wanted (the wheel's later contact searches, if any, sample it every LOCUS_STEP): the
#: sampled minimum only starts the Newton-Raphson refinement, whose height does not depend on it
#: to rounding; 2.5 times cheaper than LOCUS_STEP's 3000 samples of a 150 mm profile
TOUCH_STEP = 0.1
#: :func:`touch_point` follows every candidate whose first-order touching height lies within this
#: (mm) of the lowest one, plus half its own distance (the first-order estimate's error is of the
#: order of the squared distance times the relative curvature)
TOUCH_FOLLOW = 1e-6


def touch_point(pair, top: RailTop | None = None, z0: float = 0.0, *, step: float = LOCUS_STEP,
                tol: float = 1e-9, maxit: int = 20) -> tuple[float, ContactPoint]:
    """The touching height of :func:`touch_height` and its contact point, with one global search.

    A vertical move dz of the wheelset translates its contact locus rigidly (every vertical gap
    changes by exactly dz), so one locus evaluation (sampled every ``step`` mm of wheel profile)
    gives the height to the sampling's resolution and one search there (:func:`find_contacts`)
    every candidate's penetration p and normal n; where the floors of the sampled gap
    (:func:`touch_candidates`) leave one candidate that can touch first, only it is refined (from
    its locus sample, as the search would: the same contact and numbers).  A candidate
    touches at z - p / n_z to first order in p; only those that can touch first (within
    TOUCH_FOLLOW of the lowest estimate) are
    followed, each by corrections of the height dz = -p / n_z (seed Eq. 56) with Newton-Raphson
    (seed Eq. 55) started from the previous contact point (it moves by O(dz)), instead of a new
    global search per trial height.  The height is that of :func:`touch_height` to rounding (the
    deepest contact has zero penetration); the other candidates are not refined at that height.

    Returns
    -------
    z : float
        Wheelset height (side frame, z down, mm) at which the wheel first touches its rail.
    contact : ContactPoint
        The touching contact point (at the height before the last correction, as in
        :func:`touch_height`).
    """
    top = top or RailTop.of(pair.rail)
    loc = pair_locus(pair, top, z0, step)
    i, g_min, _, contenders = touch_candidates(loc, top)     # NoContactError: no sample over the rail
    z1 = z0 + g_min
    contacts = None
    if contenders == [i] and _inside(loc.gap, i):
        # the one candidate that can touch first, refined from where it lies as find_contacts would at
        # z1 (the same start: the locus samples' wheel parameters and the rail top under them do not
        # depend on the height)
        contacts = _refine(pair.wheel(z1), pair.rail, top, pair_locus(pair, top, z1, step), [i]) or None
    if contacts is None:
        contacts = find_contacts(pair.wheel(z1), pair.rail, top, locus=pair_locus(pair, top, z1, step),
                                 deepest_only=True).contacts
    est = [-c.penetration / c.normal[2] for c in contacts]
    low = min(est)
    best: tuple[float, ContactPoint] | None = None
    for c, e in zip(contacts, est):
        if e > low + TOUCH_FOLLOW + 0.5 * abs(e):
            continue
        z = z1
        for it in range(maxit):
            if it:
                c = newton_contact(pair.wheel(z), pair.rail, (c.s_w, c.theta, c.x, c.s_r))
            z += -c.penetration / c.normal[2]
            if abs(c.penetration) < tol:
                break
        else:
            raise ConvergenceError(f"contact search: the touching height did not converge (penetration "
                                   f"{c.penetration:.2e} mm after {maxit} corrections)")
        if best is None or z < best[0]:
            best = (z, c)
    return best


def _inside(gap: np.ndarray, i: int) -> bool:
    """Whether sample i of a locus gap has sampled neighbours on both sides (else the touch would lie
    at the end of a profile: :func:`find_contacts` refuses it)."""
    return 0 < i < gap.size - 1 and bool(np.isfinite(gap[i - 1]) and np.isfinite(gap[i + 1]))


def touch_bounds(pair, top: RailTop | None = None, z0: float = 0.0, *, step: float = LOCUS_STEP,
                 dy: float = 0.0) -> tuple[float, float, bool]:
    """Bounds of the touching height of :func:`touch_height` from the sampled locus alone (no
    Newton-Raphson): the locus is rigid under a vertical move of the wheelset, so the wheel first
    touches at z0 plus the smallest continuous vertical gap of its locus, which lies between the
    smallest sampled gap and the floor of :func:`touch_candidates`.

    ``dy``: the bounds of the wheel moved by dy (mm, side frame, less than LOCUS_REACH_MARGIN)
    along y, its orientation kept: its locus is the pair's moved by dy (the same samples to
    rounding: a sample that cannot lie over the rail lies LOCUS_REACH_MARGIN outside it).

    Returns
    -------
    z_low, z_high : float
        The touching height (side frame, z down, mm) lies in [z_low, z_high] (z_low = -inf where
        a local minimum of the sampled gap ends a stretch of samples).
    clear : bool
        The smallest sampled gap lies inside its stretch of samples and END_CLEAR mm from the ends
        of both profiles: the search of the height itself would not stop at a profile's end (an
        InputError of :func:`find_contacts` or an ``at_end`` contact).
    """
    top = top or RailTop.of(pair.rail)
    loc = pair_locus(pair, top, z0, step)
    if dy:
        if not abs(dy) < LOCUS_REACH_MARGIN:
            raise ValueError(f"touch_bounds: dy = {dy:g} mm must be smaller than {LOCUS_REACH_MARGIN:g} mm")
        pts = loc.points.copy()
        pts[:, 1] += dy
        loc = Locus(loc.s, loc.theta, pts, np.where(np.isnan(loc.theta), np.nan, top.z_at(pts[:, 1]) - pts[:, 2]))
    i, g_min, g_low, _ = touch_candidates(loc, top)
    clear = _inside(loc.gap, i)
    if clear:
        s_w = float(loc.s[i])
        k = min(max(int(round((float(loc.points[i, 1]) - top.y0) / top.hy)), 0), top.s.size - 1)
        s_r = float(top.s[k])
        clear = (END_CLEAR <= s_w <= pair.wheel_curve.length - END_CLEAR
                 and END_CLEAR <= s_r <= pair.rail.curve.length - END_CLEAR)
    return z0 + g_low, z0 + g_min, clear
