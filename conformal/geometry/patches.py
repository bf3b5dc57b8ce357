"""Contact patches of a loaded wheel: interpenetration regions, reference points and grids.

At a wheelset height where the undeformed wheel overlaps the rail, the overlap along the wheel's
contact locus splits into connected regions (*lobes*).  Lobes closer than ``d_comb`` along the
rail profile form one patch (CONTACT's D_COMB); each patch is then solved on its own grid.

Contact reference point.  Per patch, the centroid of the interpenetration weighted by the
squared interpenetration, sum(s pen²) / sum(pen²) over the 2-D overlap region.  Integrated
across the rolling direction (the overlap of a strip is pen(s) - A x²) a strip carries the
weight pen(s)^2.5 / sqrt(A(s)).  This definition reproduces CONTACT's reference points of the
Manchester benchmark to about 0.01 mm, where the deepest point is up to 2.5 mm away on wide,
flat (nearly conformal) patches (studies/manchester_a22.py).

Grids.
* planar: the tangent plane of the rail at the reference point, (xi, eta) along (t1 = x, t2);
  the undeformed distance h is measured along the plane's normal between the *true* surfaces
  (Newton intersections of the normal lines with rail and wheel), not a quadratic fit;
* curved: x along the rail, s the arc length of the rail profile, the distance measured along
  the local inner normal of the rail at each element centre.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.errors import ConvergenceError, InputError, NoContactError
from conformal.geometry.search import ContactPoint, Locus, RailTop, _cross_x, newton_contact, wheel_locus
from conformal.geometry.spline import clip
from conformal.geometry.surfaces import RailSurface, WheelSurface
from conformal.grid import CurvedGrid, PlanarGrid
from conformal.scene import check_grid_memory

D_COMB = 8.0        # mm, lobes closer than this along the rail profile form one patch (CONTACT's D_SEP)
REF_EXPONENT = 2.0  # interpenetration weight exponent of the reference point (pen²)


@dataclass(frozen=True, eq=False)
class Patch:
    """One contact patch at a given wheelset height (side frame)."""

    s_ref: float                 # rail arc length of the reference point
    x_ref: float                 # x of the reference point
    point: np.ndarray            # (3,) reference point on the rail surface
    normal: np.ndarray           # (3,) inner rail normal at the reference point
    t2: np.ndarray               # (3,) lateral tangent, n x t1
    wheel_point: np.ndarray      # (3,) wheel surface point on the normal line through `point`
    wheel_s: float               # its wheel-profile arc length
    wheel_theta: float           # and rotation angle
    deepest: ContactPoint        # Newton-refined deepest point (seed Eqs. 54-56)
    penetration: float           # largest overlap along the locus (mm)
    s_range: tuple[float, float]   # rail arc lengths covered by the overlap
    x_range: tuple[float, float]   # rolling-direction extent of the overlap (absolute x)
    eta_range: tuple[float, float]  # lateral extent in the tangent plane (relative to point)
    n_lobes: int = 1
    #: d s_ref / dz (mm per mm of wheelset lowering): how fast the reference point moves along the
    #: rail profile as the wheel sinks (each locus sample's overlap grows by dz cos delta_i)
    s_ref_rate: float = 0.0

    @property
    def delta(self) -> float:
        """Contact angle (rad) of the reference normal (CONTACT's DELTCP, side frame)."""
        return float(math.atan2(-self.normal[1], self.normal[2]))

    @property
    def creep_point(self) -> np.ndarray:
        """The wheel material point whose velocity defines the patch's creepages: the reference
        point moved by the patch's penetration along the normal, i.e. the rail reference point as
        a point of the wheel in its just-touching position (the approach is the solver's rigid
        displacement).  This is CONTACT's convention: at CONTACT's wheelset heights it reproduces
        the Manchester benchmark's xi to 6e-8 at y_ws = 0 (-5.665e-5) and 3e-7 at 0.5 mm
        (4.948e-4), where the wheel surface point on the normal line (``wheel_point``, overlap
        pen(P) < penetration on wide patches) is 1.4e-6 and 1.5e-5 off; the latter made FX 3 %
        too small at 0.5 mm (tests/unit/test_wheelrail.py, studies/manchester_a22.py)."""
        return self.point + self.penetration * self.normal


# ----------------------------------------------------------------------------- lobes
#: locus samples higher than this (mm) above the rail top are not projected onto the rail profile
#: (their overlap is set to minus their vertical gap): an overlap needs a vertical gap < 0, and
#: neighbouring samples (0.05 mm apart) differ in gap by far less than this
NEAR_GAP = 2.0


def locus_penetration(wheel: WheelSurface, rail: RailSurface, top: RailTop, locus: Locus | None = None):
    """Locus samples with their rail arc length s_r, normal overlap pen (> 0 inside the rail) and
    the rolling-direction curvature A = (e_r . n) / (2 rho) of the gap.  ``locus``: the wheel's
    locus if known (:func:`~conformal.geometry.search.pair_locus`).  Samples more than NEAR_GAP
    above the rail top get pen = -gap and s_r = A = NaN (all samples are projected when none is
    that near)."""
    return _locus_penetration(wheel, rail, top, locus)[:4]


#: :func:`find_patches` first projects only the locus samples less than this (mm) above the rail
#: top and their neighbours: an overlapping sample (pen > 0) lies below the rail profile, and the
#: rail top envelope (RailTop, linear on a 0.01 mm grid of y) lies within 3e-4 mm of the profile
#: where it is inclined by less than 80 degrees (0.03 mm at 88); a patch needs the projections of
#: its samples and of the two next to them only.  All NEAR_GAP samples are projected where none of
#: these overlaps (test_overlap_samples_give_the_patches_of_all_samples)
OVERLAP_GAP = 0.05


def _locus_penetration(wheel: WheelSurface, rail: RailSurface, top: RailTop, locus: Locus | None,
                       overlap_only: bool = False):
    """:func:`locus_penetration` and the rail points (Y, Z) and inner normals (n_y, n_z) at s_r
    (NaN where s_r is).  ``overlap_only``: of the NEAR_GAP samples, only those less than
    OVERLAP_GAP above the rail top and their neighbours are projected (the others get pen = -gap,
    s_r = A = NaN; each projected sample has the values of projecting all), None where there are
    none."""
    loc = locus if locus is not None else wheel_locus(wheel, top)
    ok = np.isfinite(loc.theta) & np.isfinite(loc.gap)
    near = ok & (loc.gap < NEAR_GAP)
    if not near.any():
        if overlap_only:
            return None
        near = ok
    if overlap_only:
        close = ok & (loc.gap < OVERLAP_GAP)
        if not close.any():
            return None
        around = close.copy()
        around[1:] |= close[:-1]
        around[:-1] |= close[1:]
        near &= around
    k = np.nonzero(near)[0]
    pts = loc.points[k]
    s_k = rail.project(pts[:, 1:], top.s_near(pts[:, 1:]))     # closest rail point, from the nearest sample
    Y, Z, Y1, Z1 = rail.profile_slopes(s_k)
    g = np.hypot(Y1, Z1)
    ny, nz = -Z1 / g, Y1 / g
    pen_k = (pts[:, 1] - Y) * ny + (pts[:, 2] - Z) * nz
    er = wheel.e_r(np.nan_to_num(loc.theta[k])) if loc.e_r is None else loc.e_r[k]
    rho = wheel.rolling_radius(loc.s[k]) if loc.rho is None else loc.rho[k]
    A_k = np.maximum((er[:, 1] * ny + er[:, 2] * nz) / (2 * rho), 1e-6)     # np.clip(.., 1e-6, None)
    # points that project onto an end of the rail are not over the rail
    inside = (s_k > 1e-6) & (s_k < rail.curve.length - 1e-6)
    n = loc.s.size
    s_r, A = np.full(n, np.nan), np.full(n, np.nan)
    pen = np.where(ok, -loc.gap, np.nan)
    s_r[k], A[k], pen[k] = s_k, A_k, np.where(inside, pen_k, np.nan)
    rail_yzn = np.full((4, n), np.nan)
    rail_yzn[:, k] = (Y, Z, ny, nz)
    return loc, s_r, pen, A, rail_yzn


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Inclusive index ranges of the True runs of mask."""
    m = np.zeros(mask.size + 2, bool)
    m[1:-1] = mask
    starts = np.flatnonzero(m[1:] > m[:-1])            # False -> True
    ends = np.flatnonzero(m[:-1] > m[1:]) - 1          # True -> False
    return list(zip(starts.tolist(), ends.tolist()))


def find_patches(wheel: WheelSurface, rail: RailSurface, top: RailTop | None = None, *,
                 d_comb: float = D_COMB, locus: Locus | None = None) -> list[Patch]:
    """The contact patches of the wheel at its current height, most penetrating first
    (``locus``: the wheel's contact locus if known, :func:`~conformal.geometry.search.pair_locus`).

    Raises NoContactError (with the smallest gap) when the wheel does not touch the rail."""
    top = top or RailTop.of(rail)
    # the samples near the overlap first (the same patches); all NEAR_GAP samples where none overlaps
    found = _locus_penetration(wheel, rail, top, locus, overlap_only=True)
    if found is None or not np.nanmax(found[2], initial=-np.inf) > 0.0:
        found = _locus_penetration(wheel, rail, top, locus)
    loc, s_r, pen, A, rail_yzn = found
    if not np.isfinite(pen).any():
        raise NoContactError("wheel-rail contact: the wheel is not over the rail")
    pmax = float(np.nanmax(pen))
    if pmax <= 0.0:
        i = int(np.nanargmax(pen))
        gap = -pmax
        try:   # the exact smallest gap (seed Eq. 56) from the closest sample
            gap = -newton_contact(wheel, rail, (loc.s[i], loc.theta[i], loc.points[i, 0], s_r[i])).penetration
        except ConvergenceError:
            pass
        where = (f" (at rail y = {float(rail.curve.y(s_r[i])):.2f} mm)" if np.isfinite(s_r[i])
                 else f" (side-frame y = {loc.points[i, 1]:.2f} mm)")
        raise NoContactError(f"wheel lifted off: the smallest gap between wheel and rail is {gap:.4g} mm{where}")
    runs = _runs(pen > 0)                           # NaN: not overlapping
    valid = np.isfinite(pen)
    for a, b in runs:
        if a == 0 or b == pen.size - 1 or not (valid[a - 1] and valid[b + 1]):
            y_w = float(wheel.curve.y(loc.s[a if a == 0 or not valid[a - 1] else b]))
            raise InputError(f"the overlap of wheel and rail reaches the end of a profile (wheel y = "
                             f"{y_w:.2f} mm): the profiles do not cover this position")
    # combine runs that are close along the rail profile
    groups: list[list[tuple[int, int]]] = []
    for r in runs:
        if groups:
            prev = groups[-1][-1]
            gap = min(abs(s_r[r[0]] - s_r[prev[1]]), abs(s_r[r[1]] - s_r[prev[0]]))
            if gap < d_comb:
                groups[-1].append(r)
                continue
        groups.append([r])
    patches = []
    for grp in groups:
        idx = np.concatenate([np.arange(a, b + 1) for a, b in grp])
        patches.append(_patch(wheel, rail, loc, s_r[idx], pen[idx], A[idx], idx, len(grp), rail_yzn[:, idx]))
    patches.sort(key=lambda p: -p.penetration)
    return patches


def _patch(wheel: WheelSurface, rail: RailSurface, loc, s_r, pen, A, idx, n_lobes, rail_yzn) -> Patch:
    """The patch of the locus samples idx (``rail_yzn``: the rail points and normals at s_r)."""
    x = loc.points[idx, 0]
    k = int(np.argmax(pen))
    i = int(idx[k])
    # deepest point: Newton-Raphson from the deepest locus sample (seed Eqs. 54-55)
    deepest = newton_contact(wheel, rail, (loc.s[i], loc.theta[i], x[k], s_r[k]))
    w = pen ** (REF_EXPONENT + 0.5) / np.sqrt(A)
    sw = w.sum()                                  # (np.sum's: the same pairwise sum)
    s_ref = float((w * s_r).sum() / sw)
    x_ref = float((w * x).sum() / sw)
    Y, Z = (float(v) for v in rail.profile(s_ref)[:2])
    # the reference normal: weighted mean of the contact angles (equal to the normal at s_ref on
    # narrow patches; on wide ones it follows the mean inclination, as CONTACT's does)
    y_r, z_r, ny_r, nz_r = rail_yzn              # rail.point(s_r), rail.normal(s_r)
    angles = np.arctan2(-ny_r, nz_r)
    delta = float((w * angles).sum() / sw)
    # each sample's overlap grows by dz cos(delta_i) and its rail point moves by dz sin(delta_i)
    dw = (REF_EXPONENT + 0.5) * w / pen * np.cos(angles)           # pen > 0 on a patch
    s_ref_rate = float((dw * (s_r - s_ref) + w * np.sin(angles)).sum() / sw)
    n = np.array([0.0, -math.sin(delta), math.cos(delta)])
    t2 = _cross_x(n)
    P = np.array([x_ref, Y, Z])
    # the wheel point on the normal line through P (start from the deepest point)
    q = wheel_on_lines(wheel, P[None, :], n, np.array([deepest.s_w]), np.array([deepest.theta]))
    sw, th, t = (float(v[0]) for v in q)
    half = np.sqrt(np.maximum(pen, 0.0) / A)       # np.clip(pen, 0, None)
    eta = (y_r - Y) * t2[1] + (z_r - Z) * t2[2]
    return Patch(s_ref=s_ref, x_ref=x_ref, point=P, normal=n, t2=t2,
                 wheel_point=P + t * n, wheel_s=sw, wheel_theta=th, deepest=deepest,
                 penetration=float(pen.max()), s_range=(float(s_r.min()), float(s_r.max())),
                 x_range=(float((x - half).min()), float((x + half).max())),
                 eta_range=(float(eta.min()), float(eta.max())), n_lobes=n_lobes, s_ref_rate=s_ref_rate)


# ----------------------------------------------------------------------------- intersections
# The Newton steps below work on coordinate arrays (one per axis) instead of (N, 3) arrays: the
# same products and sums in the same order as numpy's cross and einsum("ij,ij->i") (which adds
# the three products as (p0 + p2) + p1), i.e. the same numbers, at a third of the cost; one line
# (a patch's reference point) takes Python floats.
def _cross(a, b):
    """a x b of 3-vectors given by their coordinates (arrays or floats), numpy.cross's arithmetic."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    """a . b of 3-vectors given by their coordinates, in the order of numpy.einsum("ij,ij->i")."""
    return (a[0] * b[0] + a[2] * b[2]) + a[1] * b[1]


def _cramer3(c0, c1, c2, b):
    """The solution (d0, d1, d2) of [c0 c1 c2] d = b by Cramer's rule, columns and b given by
    their coordinates (arrays of one shape, or floats); LinAlgError where singular."""
    k12, k20, k01 = _cross(c1, c2), _cross(c2, c0), _cross(c0, c1)
    det = _dot(c0, k12)
    if not np.all(np.abs(det) > 0.0):
        raise np.linalg.LinAlgError("singular matrix")
    return _dot(b, k12) / det, _dot(b, k20) / det, _dot(b, k01) / det


def _solve3(c0: np.ndarray, c1: np.ndarray, c2: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solutions d (N, 3) of the 3 x 3 systems [c0 c1 c2] d = b (columns and b (N, 3)), by
    Cramer's rule (a batched numpy.linalg.solve costs several times more at these sizes)."""
    return np.stack(_cramer3(c0.T, c1.T, c2.T, b.T), axis=1)


def _no_wheel(res) -> ConvergenceError:
    return ConvergenceError(f"wheel surface: the normal lines do not meet the wheel (residual "
                            f"{res:.2e} mm); the patch reaches beyond the wheel profile")


def wheel_on_lines(wheel: WheelSurface, Q: np.ndarray, n, s0: np.ndarray, th0: np.ndarray, *,
                   maxit: int = 30, tol: float = 1e-10):
    """Intersections of the lines Q + t n with the wheel surface: returns (s_w, theta, t).

    Q (N, 3), n (3,) or (N, 3); Newton on r_w(s_w, theta) - Q - t n = 0, vectorised."""
    Q = np.asarray(Q, float)
    N = Q.shape[0]
    n = np.asarray(n, float)
    if N == 1:
        return _wheel_on_line(wheel, Q[0], n.reshape(-1, 3)[0], s0, th0, maxit, tol)
    q0, q1, q2 = (np.ascontiguousarray(c) for c in Q.T)
    if n.ndim == 1:
        n0, n1, n2 = (float(c) for c in n)
    else:
        n0, n1, n2 = (np.ascontiguousarray(c) for c in np.broadcast_to(n, (N, 3)).T)
    m = (-n0, -n1, -n2)
    s = np.array(s0, float).reshape(N).copy()
    th = np.array(th0, float).reshape(N).copy()
    t = np.zeros(N)
    frame = _frame_floats(wheel)
    L = wheel.curve.length
    work = np.empty((_STEP_ARRAYS, N))
    for _ in range(maxit):
        F, (ds, dth, dt) = _wheel_lines_step(wheel.curve.stack(s, 1), wheel.offset, wheel.radius, th, t, frame,
                                             (q0, q1, q2), (n0, n1, n2), m, work)
        clip(ds, -2.0, 2.0, out=ds)
        ds += s
        s = clip(ds, 0.0, L)
        clip(dth, -0.05, 0.05, out=dth)
        th += dth
        t += dt
        res = np.max([np.max(np.abs(Fk, out=Fk)) for Fk in F])
        if res < tol:
            break
    if not res < 1e-7:
        raise _no_wheel(res)
    return s, th, t


def _frame_floats(wheel: WheelSurface) -> tuple:
    """The wheel frame's origin and axes (O, a, e_d, e_f) as tuples of Python floats."""
    return wheel.frame_floats


def _wheel_line_step(meridian, th, t, cos, sin, frame, q, n, m):
    """One Newton step of r_w(s_w, theta) - Q - t n = 0 for coordinate arrays or Python floats
    (``cos``, ``sin`` of numpy or math; the same operations in the same order either way): the
    residual F and the steps (ds, dtheta, dt)."""
    u, rho, u1, rho1, _, _ = meridian
    (O0, O1, O2), (a0, a1, a2), (d0, d1, d2), (e0, e1, e2) = frame
    (q0, q1, q2), (n0, n1, n2) = q, n
    c, sn = cos(th), sin(th)
    msn = -sn
    er = (c * d0 + sn * e0, c * d1 + sn * e1, c * d2 + sn * e2)
    et = (msn * d0 + c * e0, msn * d1 + c * e1, msn * d2 + c * e2)
    F = (((O0 + u * a0) + rho * er[0] - q0) - t * n0,
         ((O1 + u * a1) + rho * er[1] - q1) - t * n1,
         ((O2 + u * a2) + rho * er[2] - q2) - t * n2)
    c0 = (u1 * a0 + rho1 * er[0], u1 * a1 + rho1 * er[1], u1 * a2 + rho1 * er[2])
    c1 = (rho * et[0], rho * et[1], rho * et[2])
    return F, _cramer3(c0, c1, m, (-F[0], -F[1], -F[2]))


_STEP_ARRAYS = 34       # the work rows of _wheel_lines_step


def _wheel_lines_step(pieces, offset, radius, th, t, frame, q, n, m, work):
    """:func:`_wheel_line_step` for coordinate arrays, from the wheel profile's values and slopes
    (``pieces`` = ProfileCurve.stack(s, 1)), the same operations in the same order written into
    the rows of ``work`` (``_STEP_ARRAYS`` x N; the returned arrays are rows of it)."""
    (y, z), (y1, z1) = pieces
    (O0, O1, O2), (a0, a1, a2), (d0, d1, d2), (e0, e1, e2) = frame
    (q0, q1, q2), (n0, n1, n2) = q, n
    mul, w = np.multiply, work[20]
    u, rho = np.add(y, offset, out=work[0]), np.add(z, radius, out=work[1])     # the meridian u, rho
    c, sn = np.cos(th, out=work[2]), np.sin(th, out=work[3])
    msn = np.negative(sn, out=work[4])
    er, et, F, c0 = work[5:8], work[8:11], work[11:14], work[14:17]
    for k, (dk, ek, Ok, ak, qk, nk) in enumerate(((d0, e0, O0, a0, q0, n0), (d1, e1, O1, a1, q1, n1),
                                                  (d2, e2, O2, a2, q2, n2))):
        erk, etk, Fk, c0k = er[k], et[k], F[k], c0[k]
        mul(c, dk, out=erk)                       # er = c d + sn e
        erk += mul(sn, ek, out=w)
        mul(msn, dk, out=etk)                     # et = -sn d + c e
        etk += mul(c, ek, out=w)
        mul(u, ak, out=Fk)                        # F = ((O + u a) + rho er - q) - t n
        Fk += Ok
        Fk += mul(rho, erk, out=w)
        Fk -= qk
        Fk -= mul(t, nk, out=w)
        mul(y1, ak, out=c0k)                      # c0 = u' a + rho' er (u' = y', rho' = z')
        c0k += mul(z1, erk, out=w)
        etk *= rho                                # c1 = rho et
    return F, _cramer3_into(c0, et, m, F, work[17:20], work[21:34], w)


def _cross_into(a, b, out, w):
    """:func:`_cross` (a, b) written into the rows of ``out`` (``w`` a work row)."""
    np.multiply(a[1], b[2], out=out[0])
    out[0] -= np.multiply(a[2], b[1], out=w)
    np.multiply(a[2], b[0], out=out[1])
    out[1] -= np.multiply(a[0], b[2], out=w)
    np.multiply(a[0], b[1], out=out[2])
    out[2] -= np.multiply(a[1], b[0], out=w)
    return out


def _dot_into(a, b, out, w):
    """:func:`_dot` (a, b) written into ``out`` (``w`` a work row)."""
    np.multiply(a[0], b[0], out=out)
    out += np.multiply(a[2], b[2], out=w)
    out += np.multiply(a[1], b[1], out=w)
    return out


def _cramer3_into(c0, c1, m, F, out, rows, w):
    """:func:`_cramer3` (c0, c1, m, -F) for coordinate arrays, the same operations in the same
    order; the solution written into ``out`` (3 rows), ``rows`` 13 work rows, ``w`` one more."""
    k12, k20, k01 = _cross_into(c1, m, rows[0:3], w), _cross_into(m, c0, rows[3:6], w), _cross_into(c0, c1, rows[6:9], w)
    det = _dot_into(c0, k12, rows[9], w)
    if not np.all(np.abs(det, out=w) > 0.0):
        raise np.linalg.LinAlgError("singular matrix")
    b = np.negative(F, out=rows[10:13])
    for row, k in zip(out, (k12, k20, k01)):
        _dot_into(b, k, row, w)                   # ((b0 k0 + b2 k2) + b1 k1) / det
        row /= det
    return out


def _wheel_on_line(wheel: WheelSurface, Q, n, s0, th0, maxit: int, tol: float):
    """:func:`wheel_on_lines` for one line, in Python floats (the same arithmetic)."""
    q0, q1, q2 = (float(c) for c in Q)
    n0, n1, n2 = (float(c) for c in n)
    m = (-n0, -n1, -n2)
    s, th, t = float(np.reshape(s0, -1)[0]), float(np.reshape(th0, -1)[0]), 0.0
    frame = _frame_floats(wheel)
    L = wheel.curve.length
    for _ in range(maxit):
        F, (ds, dth, dt) = _wheel_line_step(wheel.meridian(s), th, t, math.cos, math.sin, frame, (q0, q1, q2),
                                            (n0, n1, n2), m)
        s = min(max(s + min(max(ds, -2.0), 2.0), 0.0), L)
        th += min(max(dth, -0.05), 0.05)
        t += dt
        res = max(abs(F[0]), abs(F[1]), abs(F[2]))
        if math.isnan(F[0] + F[1] + F[2]):
            res = math.nan                # as numpy's max: a NaN is the largest
        if res < tol:
            break
    if not res < 1e-7:
        raise _no_wheel(res)
    return np.array([s]), np.array([th]), np.array([t])


def rail_on_lines(rail: RailSurface, Q: np.ndarray, n: np.ndarray, s0: np.ndarray, *,
                  maxit: int = 30, tol: float = 1e-10):
    """Intersections of the (y, z) lines Q + t n with the rail profile: returns (s_r, t)."""
    Q = np.asarray(Q, float)
    N = Q.shape[0]
    n = np.asarray(n, float)
    if n.ndim == 1:
        n0, n1 = float(n[0]), float(n[1])
    else:
        n0, n1 = (np.ascontiguousarray(c) for c in np.broadcast_to(n, (N, 2)).T)
    mn0, mn1 = -n0, -n1
    q0, q1 = (np.ascontiguousarray(c) for c in Q.T)
    s = np.array(s0, float).reshape(N).copy()
    t = np.zeros(N)
    L = rail.curve.length
    cur = rail.curve._pieces.cursor()
    r00, r01, r10, r11, y0, z0 = rail._placement
    for _ in range(maxit):
        c = cur.stack1(s)              # rail.profile_slopes(s): the same expressions
        y, z = c[:, 0], c[:, 1]
        Yd, Zd = r00 * y + r01 * z, r10 * y + r11 * z
        Y, Z, Y1, Z1 = Yd[0] + y0, Zd[0] + z0, Yd[1], Zd[1]
        F0, F1 = (Y - q0) - t * n0, (Z - q1) - t * n1
        mF0, mF1 = -F0, -F1
        det = Y1 * mn1 - mn0 * Z1
        ds = (mF0 * mn1 + n0 * mF1) / det
        dt = (Y1 * mF1 - Z1 * mF0) / det
        s = clip(s + clip(ds, -2.0, 2.0), 0.0, L)
        t += dt
        res = np.maximum(np.abs(F0).max(), np.abs(F1).max())     # NaN if any
        if res < tol:
            break
    if not res < 1e-7:
        raise ConvergenceError(f"rail surface: the normal lines do not meet the rail profile (residual "
                               f"{res:.2e} mm); the patch reaches beyond the rail profile")
    return s, t


def _unique(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``numpy.unique(v.ravel(), return_inverse=True)``; without sorting for a 2-D v whose rows are
    one increasing row (a grid's lateral coordinate)."""
    if v.ndim == 2 and v.shape[0] > 0 and v.shape[1] > 0:
        row = v[0]
        if np.all(row[1:] > row[:-1]):
            bits = np.ascontiguousarray(v).view(np.uint64)
            if np.array_equal(bits, np.broadcast_to(bits[0], bits.shape)):
                return row.copy(), np.tile(np.arange(v.shape[1]), v.shape[0])
    return np.unique(v.ravel(), return_inverse=True)


# ----------------------------------------------------------------------------- planar grid
def planar_distance(wheel: WheelSurface, rail: RailSurface, patch: Patch, xi: np.ndarray,
                    eta: np.ndarray) -> np.ndarray:
    """Undeformed distance (mm, < 0 = overlap) between rail and wheel along the patch normal at
    tangent-plane points (xi, eta) (arrays of one shape), from the true surfaces."""
    xi, eta = np.broadcast_arrays(np.asarray(xi, float), np.asarray(eta, float))
    P, n, t2 = patch.point, patch.normal, patch.t2
    e1 = np.array([1.0, 0.0, 0.0])
    # rail: depends on eta only
    eta_u, inv = _unique(eta)
    Qr = P[1:][None, :] + eta_u[:, None] * t2[1:][None, :]
    s_r, t_r = rail_on_lines(rail, Qr, n[1:], patch.s_ref + eta_u)
    # wheel: start from the linear prediction at the reference wheel point; the points
    # P + xi e1 + eta t2 one coordinate at a time (rows of a (3, N) array, Q its transpose)
    Qc = np.empty((3, xi.size))
    for k in range(3):
        np.multiply(xi.reshape(-1), e1[k], out=Qc[k])
        Qc[k] += P[k]
        Qc[k] += eta.reshape(-1) * t2[k]
    t_w = _wheel_on_grid_lines(wheel, patch, Qc, n)
    return (t_r[inv] - t_w).reshape(xi.shape)


def _wheel_on_grid_lines(wheel: WheelSurface, patch: Patch, q: np.ndarray, n: np.ndarray, *,
                         maxit: int = 30, tol: float = 1e-10) -> np.ndarray:
    """The distances t at which the lines q + t n (q: (3, N) coordinate rows, n the patch normal)
    meet the wheel surface, as :func:`wheel_on_lines` (the same root), in two unknowns.

    A point w (from the wheelset centre O) lies on the surface of revolution where its axial
    position w . a and its distance from the axle |w - (w . a) a| are those of a profile point,
    (u(s), rho(s)) (seed Eq. 52).  Along a line both are known in closed form: the axial position
    alpha(t) = alpha_0 + t n.a and the squared radius r(t)^2 = |v_0 + t m|^2 (v_0 the radial
    part of q - O, m = n - (n.a) a), so Newton-Raphson runs on the two equations
    y(s) = alpha(t) - L and z(s) = r(t) - R0 (L the axial offset, R0 the radius of the profile
    origin) in (s, t), without the rotation angle; starts from the linear prediction at the
    patch's wheel point (:func:`_wheel_start`'s).  Steps limited as there (|ds| <= 2 mm, s on
    the profile); the residual (mm) below ``tol``."""
    f = wheel.frame
    (O0, O1, O2), (a0, a1, a2), _, _ = wheel.frame_floats
    n0, n1, n2 = (float(c) for c in n)
    w0, w1, w2 = q[0] - O0, q[1] - O1, q[2] - O2
    al = (w0 * a0 + w1 * a1) + w2 * a2                      # axial position at t = 0
    v0, v1, v2 = w0 - al * a0, w1 - al * a1, w2 - al * a2   # radial part at t = 0
    al1 = (n0 * a0 + n1 * a1) + n2 * a2
    m0, m1, m2 = n0 - al1 * a0, n1 - al1 * a1, n2 - al1 * a2
    c0 = (v0 * v0 + v1 * v1) + v2 * v2                       # r(t)^2 = c0 + t (2 c1 + t c2)
    c1 = (v0 * m0 + v1 * m1) + v2 * m2
    c2 = (m0 * m0 + m1 * m1) + m2 * m2
    b = al - wheel.offset                                   # the profile's y at t = 0
    R0 = wheel.radius
    # start: the linear prediction of (s, t) at the patch's wheel point (rows 0 and 2 of the
    # inverse Jacobian of r_w(s, theta) - q - t n, by Cramer's rule)
    u, rho, u1, rho1, _, _ = (float(v) for v in wheel.meridian(patch.wheel_s))
    er, et = wheel.e_r(patch.wheel_theta), wheel.e_t(patch.wheel_theta)
    J0, J1, J2 = (tuple(float(c) for c in v) for v in (u1 * f.a + rho1 * er, rho * et, -patch.normal))
    k12, k01 = _cross(J1, J2), _cross(J0, J1)
    det = _dot(J0, k12)
    wp0, wp1, wp2 = (float(c) for c in patch.wheel_point)
    d0, d1, d2 = q[0] - wp0, q[1] - wp1, q[2] - wp2
    s = (d0 * (k12[0] / det) + d1 * (k12[1] / det)) + d2 * (k12[2] / det)
    s += patch.wheel_s
    t = (d0 * (k01[0] / det) + d1 * (k01[1] / det)) + d2 * (k01[2] / det)
    cur = wheel.curve._pieces.cursor()
    L = wheel.curve.length
    c1x2 = 2.0 * c1
    G = np.empty((2, s.size))                 # the residuals (axial, radial)
    G1, G2 = G
    r, rp, det, w = np.empty((4, s.size))
    mul = np.multiply
    for _ in range(maxit):
        (y, z), (y1, z1) = cur.stack1(s)       # a new array: its rows serve as work rows below
        tc2 = mul(t, c2, out=rp)
        np.add(tc2, c1x2, out=r)               # r = sqrt(c0 + t (2 c1 + t c2))
        r *= t
        r += c0
        np.sqrt(r, out=r)
        np.subtract(y, b, out=G1)              # G1 = (y - b) - al1 t
        G1 -= mul(t, al1, out=w)
        np.add(z, R0, out=G2)                  # G2 = (z + R0) - r
        G2 -= r
        rp += c1                               # dr/dt = (c1 + t c2) / r
        rp /= r
        mul(z1, al1, out=det)                  # det = al1 z1 - y1 dr/dt
        det -= mul(y1, rp, out=w)
        ds = mul(G1, rp, out=y)                # ds = (G1 dr/dt - al1 G2) / det
        ds -= mul(G2, al1, out=w)
        ds /= det
        dt = mul(z1, G1, out=z)                # dt = (z1 G1 - y1 G2) / det
        dt -= mul(y1, G2, out=w)
        dt /= det
        clip(ds, -2.0, 2.0, out=ds)
        ds += s
        clip(ds, 0.0, L, out=s)
        t += dt
        res = float(np.abs(G, out=G).max())   # NaN if any
        if res < tol:
            break
    if not res < 1e-7:
        raise _no_wheel(res)
    return t


def _wheel_start(wheel: WheelSurface, patch: Patch, Q: np.ndarray):
    u, rho, u1, rho1, _, _ = (float(v) for v in wheel.meridian(patch.wheel_s))
    f = wheel.frame
    er, et = wheel.e_r(patch.wheel_theta), wheel.e_t(patch.wheel_theta)
    J = np.column_stack([u1 * f.a + rho1 * er, rho * et, -patch.normal])
    d = np.linalg.solve(J, (Q - patch.wheel_point).T)
    return patch.wheel_s + d[0], patch.wheel_theta + d[1]


def _check_size(mx: int, my: int, theory: str, by_element_size: bool, by_sizes: bool = False) -> None:
    """The memory check of a grid whose size is known only now (scene.check_grid_memory), naming
    the key that sized it."""
    if by_element_size:
        key, hint = "[geometry] element_size", "use larger elements"
    elif by_sizes:
        key, hint = "[model] max_mx / max_ms", "use fewer elements"
    else:
        key, hint = "[grid] n", "use a coarser grid"
    check_grid_memory(mx, my, theory, key, hint)


def planar_grid_for_patch(wheel: WheelSurface, rail: RailSurface, patch: Patch, *,
                          element_size: float | None = None, n: int = 40, scale: float = 1.1,
                          explicit: tuple | None = None, theory: str = "exact"
                          ) -> tuple[PlanarGrid, np.ndarray, float]:
    """Planar potential contact grid on the patch's tangent plane, the undeformed distance h on it
    (min 0) and the approach (largest overlap on the grid).

    The grid covers the overlap region (x_range, eta_range) times ``scale``: with square elements
    of ``element_size`` mm (CONTACT's DX = DS), or n x n elements; ``explicit`` = (mx, my, dx, dy,
    xl, yl) fixes it (xl, yl relative to the reference point, None = centred).  A grid too large
    for the memory with ``theory`` is refused before it is allocated (InputError naming the key that
    sized it)."""
    if explicit is not None:
        mx, my, dx, dy, xl, yl = explicit
        grid = PlanarGrid(mx, my, dx, dy, -0.5 * mx * dx if xl is None else xl,
                          -0.5 * my * dy if yl is None else yl)
    else:
        x0, x1 = (v - patch.x_ref for v in patch.x_range)
        e0, e1 = patch.eta_range
        # at least a couple of elements' worth of margin around the overlap
        cx, cy = 0.5 * (x0 + x1), 0.5 * (e0 + e1)
        hx, hy = 0.5 * (x1 - x0) * scale, 0.5 * (e1 - e0) * scale
        if element_size is not None:
            hx, hy = hx + element_size, hy + element_size
            mx = max(1, int(math.ceil(2 * hx / element_size)))
            my = max(1, int(math.ceil(2 * hy / element_size)))
            dx = dy = element_size
        else:
            hy = max(hy, 1e-3)
            mx = my = n
            dx, dy = 2 * hx / n, 2 * hy / n
        _check_size(mx, my, theory, element_size is not None)
        grid = PlanarGrid(mx, my, dx, dy, cx - 0.5 * mx * dx, cy - 0.5 * my * dy)
    d = _grid_distance(wheel, rail, patch, grid)
    approach = float(-d.min())
    return grid, d + approach, approach


def _grid_distance(wheel: WheelSurface, rail: RailSurface, patch: Patch, grid: PlanarGrid) -> np.ndarray:
    """:func:`planar_distance` at the element centres of ``grid`` (``grid.mesh()``), the same
    numbers: the rail lines are the grid's columns (its lateral coordinates), the points
    P + xi e1 + eta t2 formed from the two coordinate vectors by broadcasting."""
    x, eta = grid.x, grid.y
    P, n, t2 = patch.point, patch.normal, patch.t2
    Qr = P[1:][None, :] + eta[:, None] * t2[1:][None, :]
    _, t_r = rail_on_lines(rail, Qr, n[1:], patch.s_ref + eta)
    Qc = np.empty((3, x.size, eta.size))
    xc = x[:, None]
    for k, e1k in enumerate((1.0, 0.0, 0.0)):
        np.multiply(xc, e1k, out=Qc[k])
        Qc[k] += P[k]
        Qc[k] += eta * t2[k]
    t_w = _wheel_on_grid_lines(wheel, patch, Qc.reshape(3, -1), n)
    return t_r - t_w.reshape(x.size, eta.size)


# ----------------------------------------------------------------------------- curved grid
def curved_distance(wheel: WheelSurface, rail: RailSurface, patch: Patch, x: np.ndarray,
                    s: np.ndarray) -> np.ndarray:
    """Undeformed distance (mm, < 0 = overlap) along the local inner rail normal at rail surface
    points (x, s) (x absolute, side frame; arrays of one shape)."""
    x, s = np.broadcast_arrays(np.asarray(x, float), np.asarray(s, float))
    Y, Z, Y1, Z1, _, _ = rail.profile(s.ravel())
    g = np.hypot(Y1, Z1)
    nrm = np.stack([np.zeros_like(g), -Z1 / g, Y1 / g], axis=1)
    R = np.stack([x.ravel(), Y, Z], axis=1)
    s_w, th_w = _wheel_start(wheel, patch, R)
    _, _, t = wheel_on_lines(wheel, R, nrm, s_w, th_w)
    return (-t).reshape(x.shape)


def curved_grid_for_patch(wheel: WheelSurface, rail: RailSurface, patch: Patch, *,
                          element_size: float | None = None, n: int = 40, scale: float = 1.1,
                          side: str = "right", margin: float = 5.0, sizes: tuple[float, float] | None = None,
                          centred: bool = False, theory: str = "conformal") -> tuple[CurvedGrid, np.ndarray, float]:
    """Curved potential contact grid (x, s) for the patch, h along the local normals (min 0) and
    the approach.  Uniform elements in x and in s (``element_size``, ``sizes`` = (dx, ds), or n x n).
    ``centred``: an element centred on the reference point (x_ref, s_ref), as CONTACT's grids; else
    the grid is centred on the overlap region.  A grid too large for the memory with ``theory`` is
    refused before it is allocated."""
    x0, x1 = (v - patch.x_ref for v in patch.x_range)
    s0, s1 = patch.s_range
    cx, cs = 0.5 * (x0 + x1), 0.5 * (s0 + s1)
    hx, hs = 0.5 * (x1 - x0) * scale, max(0.5 * (s1 - s0) * scale, 1e-3)
    if element_size is not None:
        sizes = (element_size, element_size)
    if sizes is not None:
        dx, ds = sizes
        hx, hs = hx + dx, hs + ds
        mx = max(1, int(math.ceil(2 * hx / dx)))
        ms = max(1, int(math.ceil(2 * hs / ds)))
    else:
        mx = ms = n
        dx, ds = 2 * hx / n, 2 * hs / n
    _check_size(mx, ms, theory, element_size is not None, sizes is not None and element_size is None)
    xl = cx - 0.5 * mx * dx
    s_start = cs - 0.5 * ms * ds
    if centred:   # shift by less than an element so that the reference point is an element centre
        xl = -(round(-xl / dx - 0.5) + 0.5) * dx
        s_start = patch.s_ref - (round((patch.s_ref - s_start) / ds - 0.5) + 0.5) * ds
    s_lo = max(s_start, 0.0)
    s_hi = min(s_lo + ms * ds, rail.curve.length)
    s_edges = np.linspace(s_lo, s_hi, ms + 1)
    sc = 0.5 * (s_edges[:-1] + s_edges[1:])
    xc = xl + (np.arange(mx) + 0.5) * dx
    X, S = np.meshgrid(xc + patch.x_ref, sc, indexing="ij")
    d = curved_distance(wheel, rail, patch, X, S)
    approach = float(-d.min())
    own = rail.curve.point(sc)
    nrm_own = rail.curve.normal(sc)
    nrm_side = nrm_own @ rail.rotation.T
    delta = np.arctan2(-nrm_side[:, 0], nrm_side[:, 1])
    # local curves for meshing the bodies
    sr = np.linspace(max(s_lo - margin, 0.0), min(s_hi + margin, rail.curve.length), 400)
    rail_curve = rail.curve.point(sr)
    Rm = rail.rotation
    f = wheel.frame

    def to_own3(v, is_point=True):
        v = np.asarray(v, float)
        yz = v[1:] - (np.asarray(rail.origin) if is_point else 0.0)
        return np.r_[v[0] - (patch.x_ref if is_point else 0.0), yz @ Rm]

    centre = f.O + wheel.offset * f.a
    sw = np.linspace(max(patch.wheel_s - (s_hi - s_lo) - margin, 0.0),
                     min(patch.wheel_s + (s_hi - s_lo) + margin, wheel.curve.length), 400)
    grid = CurvedGrid(mx=mx, dx=dx, xl=xl, s_edges=s_edges, y=own[:, 0], z=own[:, 1], normal=nrm_own,
                      delta=delta, s_ref=patch.s_ref, cant=rail.cant, rail_origin=tuple(rail.origin),
                      rail_curve=rail_curve, rail_curve_s=sr, wheel_profile=wheel.curve.point(sw),
                      wheel_centre=to_own3(centre), wheel_axle=to_own3(f.a, False),
                      wheel_down=to_own3(f.e_d, False), wheel_radius=wheel.radius, side=side)
    return grid, d + approach, approach
