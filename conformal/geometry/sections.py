"""Whole cross-sections of real bodies: the rail (head, web, foot) and the wheel (rim and web).

The FE contact ground truth (``[model] fec_body = "section"``, :mod:`conformal.meshing.section_body`)
sweeps these closed sections along the track (rail) or about the axle (wheel) and clamps them
far from the contact (the rail's foot and end faces, the wheel's hub and sector cuts), so that
no half-space assumption enters anywhere.  A section is a closed polygon (y, z) in the frame of
its profile (z down: the rail-profile frame, or the wheel frame with z the radius increase over
the nominal radius) whose first ``n_profile`` points are the contact profile itself, in its own
order; the remaining points close it on the material side.  ``clamped`` names the closing edges
(by the index of their first point) that are held.

Sections:

* :func:`uic60_section` -- 60E1 (UIC 60) rail, EN 13674-1: height 172 mm, foot width 150 mm, web
  16.5 mm, head width 72 mm.  The head is the scene's head profile (the package's UIC 60 head,
  1:20 flanks to 35 mm below the top); below it the simplified standard shape: the 1:20 flanks
  continue to the head's underside, which falls at the standard's fishing inclination 1:2.75 to
  the web; a straight web of 16.5 mm; the foot's upper face one straight slope (1:5) down to a
  foot edge 11.5 mm thick; a flat 150 mm foot.  Simplifications: no fillets (the R3/R7 corners
  of the head, the R35/R120 web fillets), one slope for the foot's upper face instead of the
  standard's compound curve.  Two free dimensions (head underside depth at the flank, 39.2 mm,
  and the foot slope) are set so that the section's area, centroid height and second moment
  match the values the standard publishes for 60E1 (76.70 cm², 80.9 mm above the foot,
  3038.3 cm⁴) within 1 % (:func:`section_properties`, tests/validation/test_fe_truth.py).
* :func:`wheel_rim_section` -- a monobloc wheel's rim and straight web: the S1002 (or any) tread
  and flange profile from the flange back (y = -70) to the field side, a 5 x 5 mm chamfer to the
  field face of a 135 mm wide rim (y = +65), the rim's inner face ``rim_depth`` = 55 mm below
  the tape circle, a straight web ``web_thickness`` = 30 mm thick centred on the rim, down to
  the hub radius ``hub_radius`` = 125 mm (where it is clamped).  Simplifications: a flat plate
  web (real webs are curved or S-shaped, which changes the wheel's lateral compliance, not the
  contact), no fillets, no hub.
* :func:`block_section` -- a generic large body for idealised profiles (the deep pair): both
  profile ends continued straight along their end tangents by ``extension`` and the section
  closed by a rectangle on the material side; the closing edges are clamped.

>>> import numpy as np
>>> from conformal.geometry.profiles import load_profile
>>> sec = uic60_section(load_profile("UIC60", "rail").points)
>>> A, zc, I = section_properties(sec.points)
>>> round(A / 7670.0, 3), round((172.0 - zc) / 80.9, 3), round(I / 3.0383e7, 3)
(0.996, 1.002, 1.009)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.errors import InputError

#: 60E1 (EN 13674-1) published properties: area (mm²), centroid height above the foot (mm),
#: second moment about the horizontal axis (mm⁴)
UIC60_AREA = 7670.0
UIC60_CENTROID = 80.9
UIC60_I = 3.0383e7
UIC60_HEIGHT = 172.0
UIC60_FOOT = 150.0
UIC60_WEB = 16.5
#: simplified-shape parameters (see the module docstring): head underside depth at the flank,
#: fishing inclination of the head underside, foot edge thickness, foot slope
UIC60_UNDERSIDE_Z = 39.2
UIC60_FISHING = 1.0 / 2.75
UIC60_FOOT_EDGE = 11.5
UIC60_FOOT_SLOPE = 1.0 / 5.0


@dataclass(frozen=True, eq=False)
class Section:
    """A closed cross-section: ``points`` (n, 2) (y, z), the first ``n_profile`` of them the contact
    profile; ``clamped``: indices i of the closing edges (points i -> i + 1, cyclic) that are held;
    ``kind``: "rail" (swept along x) or "wheel" (revolved about the axle); ``hub_z``: wheel, the z of
    the clamped hub face; ``name`` and ``note`` (what was simplified)."""

    points: np.ndarray
    n_profile: int
    clamped: tuple[int, ...]
    kind: str
    name: str
    note: str = ""
    hub_z: float | None = None

    @property
    def profile(self) -> np.ndarray:
        return self.points[:self.n_profile]

    @property
    def closure(self) -> np.ndarray:
        """The closing points after the profile (the last profile point and the first one not included)."""
        return self.points[self.n_profile:]


def section_properties(points: np.ndarray) -> tuple[float, float, float]:
    """Area, centroid z and second moment about the horizontal centroidal axis (int (z - zc)² dA)
    of a simple polygon (y, z), by the shoelace formulas."""
    P = np.asarray(points, dtype=float)
    y, z = P[:, 0], P[:, 1]
    y2, z2 = np.roll(y, -1), np.roll(z, -1)
    c = y * z2 - y2 * z
    A = 0.5 * c.sum()
    zc = ((z + z2) * c).sum() / (6.0 * A)
    Izz = ((z * z + z * z2 + z2 * z2) * c).sum() / 12.0 - A * zc * zc
    return abs(float(A)), float(zc), abs(float(Izz))


def _simple(P: np.ndarray) -> bool:
    """No two non-adjacent edges of the closed polygon cross."""
    Q = np.vstack([P, P[:1]])
    a, b = Q[:-1], Q[1:]
    n = len(a)

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    A, B = a[:, None], b[:, None]
    C, D = a[None, :], b[None, :]
    cross = (orient(A, B, C) * orient(A, B, D) < -1e-12) & (orient(C, D, A) * orient(C, D, B) < -1e-12)
    i, j = np.nonzero(cross)
    far = (np.abs(i - j) > 1) & (np.abs(i - j) < n - 1)
    return not bool(np.any(far))


def _finish(points: np.ndarray, n_profile: int, clamped, kind: str, name: str, note: str,
            hub_z: float | None = None) -> Section:
    P = np.asarray(points, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(P, axis=0).T) > 1e-9])
    if not keep[:n_profile].all():
        raise InputError(f"section {name}: repeated points in the profile")
    if not _simple(P):
        raise InputError(f"section {name}: the closed cross-section crosses itself (profile and closure overlap)")
    return Section(P, n_profile, tuple(int(i) for i in clamped), kind, name, note, hub_z)


def uic60_section(head: np.ndarray, *, underside_z: float = UIC60_UNDERSIDE_Z) -> Section:
    """The 60E1 rail section below a head profile (rail-profile frame, z down from the top, y from
    the rail's centre line; the head from one flank end to the other, both at the same depth, as
    the package's UIC60 and 60E1 heads).  The foot's lower face (z = 172) is clamped."""
    H = np.asarray(head, dtype=float)
    if H.ndim != 2 or H.shape[1] != 2 or len(H) < 10:
        raise InputError("uic60_section: need the head profile as (n, 2) points")
    if H[0, 0] > H[-1, 0]:
        raise InputError("uic60_section: the head profile must run from -y to +y")
    y_end, z_end = float(H[-1, 0]), float(H[-1, 1])
    if abs(H[0, 1] - z_end) > 1e-6 or abs(H[0, 0] + y_end) > 1e-3 or not (30.0 < y_end < 40.0):
        raise InputError("uic60_section: the head profile must be symmetric and end on both 1:20 flanks "
                         f"(got ends {H[0]} and {H[-1]})")
    if not z_end < underside_z < 50.0:
        raise InputError(f"uic60_section: the head profile ends at z = {z_end:g}, below the head's underside")
    w = 0.5 * UIC60_WEB
    yc = y_end + (underside_z - z_end) / 20.0                 # the 1:20 flank continued
    z_web_top = underside_z + (yc - w) * UIC60_FISHING
    z_foot_edge = UIC60_HEIGHT - UIC60_FOOT_EDGE
    z_web_bottom = z_foot_edge - (0.5 * UIC60_FOOT - w) * UIC60_FOOT_SLOPE
    right = [(yc, underside_z), (w, z_web_top), (w, z_web_bottom), (0.5 * UIC60_FOOT, z_foot_edge),
             (0.5 * UIC60_FOOT, UIC60_HEIGHT)]
    left = [(-y, z) for y, z in reversed(right)]
    P = np.vstack([H, right, left])
    n = len(H)
    foot = n + len(right) - 1                                  # edge (75, 172) -> (-75, 172)
    return _finish(P, n, (foot,), "rail", "60E1 section",
                   "EN 13674-1 60E1, simplified: no fillets, one foot slope (see conformal.geometry.sections)")


def wheel_rim_section(profile: np.ndarray, wheel_radius: float, *, rim_width: float = 135.0,
                      flange_back: float = -70.0, rim_depth: float = 55.0, web_thickness: float = 30.0,
                      hub_radius: float = 125.0, chamfer: float = 5.0) -> Section:
    """A wheel's rim and straight web under a tread/flange profile (wheel frame: y along the
    axle, flange at -y, z = radius increase over ``wheel_radius``, the axle at z = -wheel_radius).
    The profile runs from the flange back (y = ``flange_back``) to the field side; the rim ends at
    y = flange_back + rim_width.  The hub face (radius ``hub_radius``) is clamped."""
    P0 = np.asarray(profile, dtype=float)
    R = float(wheel_radius)
    if not (R > 0 and math.isfinite(R)):
        raise InputError(f"wheel_rim_section: wheel radius must be > 0, got {wheel_radius!r}")
    if abs(P0[0, 0] - flange_back) > 0.5 or P0[-1, 0] <= P0[0, 0]:
        raise InputError(f"wheel_rim_section: the profile must start at the flange back y = {flange_back:g} "
                         f"and run to the field side (got {P0[0]} .. {P0[-1]})")
    y_field = flange_back + rim_width
    z_rim = -float(rim_depth)
    if P0[-1, 0] > y_field - 1e-6 or np.min(P0[:, 1]) <= z_rim + 5.0:
        raise InputError("wheel_rim_section: the profile does not fit on the rim (width or depth)")
    if not (0 < hub_radius < R - rim_depth - 20.0):
        raise InputError(f"wheel_rim_section: hub radius {hub_radius:g} must lie inside the rim")
    y_mid = 0.5 * (flange_back + y_field)
    w = 0.5 * float(web_thickness)
    z_hub = float(hub_radius) - R
    closure = []
    y_last, z_last = P0[-1]
    if y_field - y_last > 1e-6:
        c = min(chamfer, y_field - y_last)
        closure.append((y_field, z_last - c))                    # chamfer to the field face
    closure += [(y_field, z_rim), (y_mid + w, z_rim), (y_mid + w, z_hub), (y_mid - w, z_hub),
                (y_mid - w, z_rim), (flange_back, z_rim)]
    P = np.vstack([P0, closure])
    n = len(P0)
    hub = n + len(closure) - 4                                  # edge (y_mid + w, z_hub) -> (y_mid - w, z_hub)
    return _finish(P, n, (hub,), "wheel", "wheel rim and web",
                   f"rim {rim_width:g} x {rim_depth:g} mm, straight web {web_thickness:g} mm to the hub "
                   f"radius {hub_radius:g} mm, no fillets", hub_z=z_hub)


def block_section(profile: np.ndarray, kind: str, extension: float) -> Section:
    """A generic large body around an idealised profile: both ends continued straight along their
    end tangents by ``extension`` (mm), closed by a rectangle on the material side (below the
    profile for a rail, above it, towards the axle, for a wheel); every closing edge is clamped.

    The profile must start at its lower-left end as seen from the material: for a rail (material
    below, larger z) the first point is the deeper end (a gauge face going up), the last one the
    far end of the top; for a wheel (material above) the first point is the flange tip end, the
    last the field end of the tread (the deep pair's profiles)."""
    P0 = np.asarray(profile, dtype=float)
    L = float(extension)
    if not (L > 0 and math.isfinite(L)):
        raise InputError(f"block_section: extension must be > 0, got {extension!r}")
    if kind not in ("rail", "wheel"):
        raise InputError(f"block_section: kind must be \"rail\" or \"wheel\", got {kind!r}")
    t0 = P0[0] - P0[1]
    t1 = P0[-1] - P0[-2]
    a = P0[0] + L * t0 / np.linalg.norm(t0)
    b = P0[-1] + L * t1 / np.linalg.norm(t1)
    if kind == "rail":
        z_far = max(a[1], b[1], float(P0[:, 1].max()) + L)
        closure = [b, (b[0], z_far), (a[0], z_far), a]
    else:
        z_far = min(a[1], b[1], float(P0[:, 1].min()) - L)
        y_far = min(a[0], float(P0[:, 0].min())) - L
        closure = [b, (b[0], z_far), (y_far, z_far), (y_far, a[1]), a]
    closure = np.asarray(closure, dtype=float)
    closure = closure[np.concatenate([[True], np.hypot(*np.diff(closure, axis=0).T) > 1e-9])]
    P = np.vstack([P0, closure])
    n = len(P0)
    # the extensions (profile end -> b, a -> profile start) are free surface; the rest is clamped
    clamped = tuple(range(n, len(P) - 1))
    return _finish(P, n, clamped, kind, f"block around {kind} profile",
                   f"profile ends continued straight by {L:g} mm, closed by a clamped rectangle",
                   hub_z=z_far if kind == "wheel" else None)
