"""Element sizes tied to the local wall thickness of a cross-section.

A whole rail or wheel section (``fe_closure = "section"``) has thin walls far from the contact:
the 60E1 rail's 16.5 mm web and its foot (11.5 mm at the edge), the wheel's 30 mm web.  There the
head and rim bend and turn on the web, and linear tetrahedra several wall thicknesses long are
far too stiff in bending (shear locking), whatever the grading at the contact does.  This module
gives the cap that keeps every element in a wall at a fraction of that wall's thickness:

* the *local thickness* t(p) at a point p of the section is the thickness across the wall at the
  nearest point of the section's wall mid-lines (its medial axis, pruned to the points whose
  nearest boundary points lie on opposite faces): in a straight wall between parallel or
  slightly tapered faces it is the wall's thickness, in the rail head its height or width,
  whichever is smaller.  Unlike the diameter of the largest disc that contains p (Hildebrand and
  Rüegsegger, J. Microscopy 185 (1997) 67-75), it does not vanish at a convex corner;
* the cap is h(p) = min over q of (f t(q) + g |p - q|) (f: the fraction, g: the growth rate of the
  body's grading), so that it varies gradually from a thin wall to a thicker part.

Both are computed on a raster of the cross-section (:data:`MAX_CELLS` cells along its larger
side: 0.43 mm on the 172 mm rail section): the distance to the boundary and the nearest
mid-line cell by scipy's exact Euclidean distance transform, the mid-lines' thickness exactly
from the polygon's edges, the graded cap by repeated 8-neighbour minimum passes (a chamfer
metric, at most 8 % longer than the Euclidean distance).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.errors import InputError

#: raster cells along the section's larger side
MAX_CELLS = 400
#: a re-entrant corner: the boundary turns into the material by more than this at one vertex (rad)
REENTRANT_TURN = math.radians(20.0)
#: mid-line cells: their neighbourhood's nearest boundary points at least this fraction of the
#: distance across apart (see _local_thickness)
OPPOSITE = 0.8


@dataclass(frozen=True, eq=False)
class WallCap:
    """The wall-thickness cap of a cross-section on a raster.

    ``y0``, ``z0``: centre of the first cell (mm); ``spacing``: cell size (mm); ``inside``
    (ny, nz): cells whose centre lies in the section; ``thickness`` (ny, nz): local wall
    thickness (mm, NaN outside); ``cap`` (ny, nz): the graded cap (mm, also outside, near the
    boundary, from the nearest inside cells)."""

    y0: float
    z0: float
    spacing: float
    inside: np.ndarray
    thickness: np.ndarray
    cap: np.ndarray

    def _cells(self, y, z) -> tuple[np.ndarray, np.ndarray]:
        i = np.clip(np.rint((np.asarray(y, float) - self.y0) / self.spacing), 0, self.cap.shape[0] - 1)
        j = np.clip(np.rint((np.asarray(z, float) - self.z0) / self.spacing), 0, self.cap.shape[1] - 1)
        return i.astype(np.int64), j.astype(np.int64)

    def at(self, y, z) -> np.ndarray:
        """The cap (mm) at points (y, z) of the cross-section (the nearest cell's; points beyond
        the raster get its edge's)."""
        i, j = self._cells(y, z)
        return self.cap[i, j]

    def thickness_at(self, y, z) -> np.ndarray:
        """The local wall thickness (mm) at points (y, z) of the section (NaN outside)."""
        i, j = self._cells(y, z)
        return self.thickness[i, j]


def _inside(P: np.ndarray, yc: np.ndarray, zc: np.ndarray) -> np.ndarray:
    """Cells (yc x zc centres) inside the closed polygon P, by the even-odd rule along each
    raster line z = zc[j] (edges crossing it, half-open in z so that a vertex counts once)."""
    a, b = P, np.roll(P, -1, axis=0)
    out = np.zeros((len(yc), len(zc)), dtype=bool)
    lo, hi = np.minimum(a[:, 1], b[:, 1]), np.maximum(a[:, 1], b[:, 1])
    for j, z in enumerate(zc):
        k = (lo <= z) & (z < hi)
        if not k.any():
            continue
        t = (z - a[k, 1]) / (b[k, 1] - a[k, 1])
        yx = np.sort(a[k, 0] + t * (b[k, 0] - a[k, 0]))
        # cells with an odd number of crossings to their left are inside
        out[:, j] = (np.searchsorted(yx, yc) % 2) == 1
    return out


def _across(q: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Thickness across the section at its mid-line points q (m, 2), exactly from the closed
    polygon P (n, 2): the distance to the nearest boundary point plus the distance to the nearest
    one on the other side (beyond the plane through q normal to the first); in a wall between
    parallel faces that sum is the wall's thickness wherever q lies in it."""
    a, b = P, np.roll(P, -1, axis=0)
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    out = np.empty(len(q))
    for k in range(0, len(q), 256):
        d = a[None] - q[k:k + 256, None, :]                                   # (m, n, 2) q -> a
        t = np.clip(-np.einsum("mnj,nj->mn", d, ab) / L2, 0.0, 1.0)
        f = d + t[..., None] * ab                                            # q -> the edge's nearest point
        r = np.linalg.norm(f, axis=-1)
        i = np.argmin(r, axis=1)
        m = np.arange(len(i))
        f1, r1 = f[m, i], r[m, i]
        other = np.einsum("mnj,mj->mn", f, f1) < 0.0
        r2 = np.where(other, r, np.inf).min(axis=1)
        out[k:k + 256] = r1 + np.where(np.isfinite(r2), r2, r1)
    return out


def _local_thickness(P: np.ndarray, inside: np.ndarray, y0: float, z0: float, h: float) -> np.ndarray:
    """Local wall thickness of every inside cell (mm; NaN outside): the thickness across the wall
    (:func:`_across`) at the nearest cell of the section's wall mid-lines.

    The mid-lines are the ridge of the distance to the boundary (cells whose distance no
    neighbour exceeds) where the nearest boundary points of the cell's neighbourhood lie on
    opposite faces: at least :data:`OPPOSITE` times the distance across (a wall between nearly
    parallel faces gives 1, the bisector of a 90-degree corner 0.71).  Without that pruning a
    convex corner, where the largest disc shrinks to nothing, would look like a vanishing wall.
    The thickness at the mid-line cells is computed exactly from the polygon's edges."""
    from scipy import ndimage

    d, (fi, fj) = ndimage.distance_transform_edt(np.pad(inside, 1), return_indices=True)
    d, fi, fj = d[1:-1, 1:-1] * h, fi[1:-1, 1:-1] - 1, fj[1:-1, 1:-1] - 1      # nearest outside cell
    ridge = inside & (d >= ndimage.maximum_filter(d, size=3, mode="constant"))
    ny, nz = d.shape
    sep = np.zeros_like(d)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if not (di or dj):
                continue
            a = (slice(max(-di, 0), ny - max(di, 0)), slice(max(-dj, 0), nz - max(dj, 0)))
            b = (slice(max(di, 0), ny - max(-di, 0)), slice(max(dj, 0), nz - max(-dj, 0)))
            s = np.hypot(fi[a] - fi[b], fj[a] - fj[b]) * h
            sep[b] = np.maximum(sep[b], np.where(inside[a], s, 0.0))
    mid = ridge & (sep >= OPPOSITE * 2.0 * d)
    if not mid.any():
        mid = ridge
    ci, cj = np.nonzero(mid)
    t_mid = _across(np.column_stack([y0 + h * ci, z0 + h * cj]), P)
    t_cell = np.zeros_like(d)
    t_cell[ci, cj] = t_mid
    _, (ni, nj) = ndimage.distance_transform_edt(~mid, return_indices=True)
    return np.where(inside, t_cell[ni, nj], np.nan)


def _graded(cap: np.ndarray, h: float, growth: float) -> np.ndarray:
    """min over q of (cap(q) + growth |p - q|) on the raster (8-neighbour passes until nothing
    changes; at most one pass per cell along the raster's diagonal)."""
    c = cap.copy()
    steps = [((di, dj), growth * h * math.hypot(di, dj)) for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj]
    for _ in range(sum(c.shape)):
        new = c.copy()
        for (di, dj), w in steps:
            src = c[max(-di, 0):c.shape[0] - max(di, 0), max(-dj, 0):c.shape[1] - max(dj, 0)]
            dst = new[max(di, 0):c.shape[0] - max(-di, 0), max(dj, 0):c.shape[1] - max(-dj, 0)]
            np.minimum(dst, src + w, out=dst)
        if np.array_equal(new, c):
            break
        c = new
    return c


def wall_cap(points: np.ndarray, fraction: float, growth: float, *, corner: float | None = None,
             cells: int = MAX_CELLS) -> WallCap:
    """The element-size cap of a closed cross-section: ``fraction`` of the local wall thickness,
    graded at ``growth`` (mm per mm) towards thicker parts.

    Parameters
    ----------
    points : ndarray (n, 2)
        The closed polygon (y, z) of the section (mm; the last point joins the first).
    fraction : float
        The cap as a fraction of the local wall thickness (> 0; 1/3: three elements across a wall).
    growth : float
        Largest increase of the cap per mm (> 0), as the body's grading (``MeshSpec.growth``).
    corner : float, optional
        At the re-entrant corners (:func:`reentrant_corners`: where a web meets a head, foot or
        rim without a fillet, and the stress is singular) the cap falls to ``corner`` times the
        wall's cap there, graded at ``growth`` away from it; None: no corner refinement.
    cells : int
        Raster cells along the section's larger side.

    Returns
    -------
    WallCap

    Examples
    --------
    A plate 10 mm thick and 100 mm wide has walls 10 mm thick; its cap is a third of that:

    >>> cap = wall_cap(np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 10.0], [0.0, 10.0]]), 1 / 3, 0.35)
    >>> round(float(cap.thickness_at(50.0, 5.0)), 1), round(float(cap.at(50.0, 2.0)), 2)
    (10.0, 3.33)
    """
    P = np.asarray(points, dtype=float)
    if P.ndim != 2 or P.shape[1] != 2 or len(P) < 3:
        raise InputError("wall_cap: need a closed polygon of at least 3 points (y, z)")
    if not (fraction > 0 and math.isfinite(fraction)) or not (growth > 0 and math.isfinite(growth)):
        raise InputError(f"wall_cap: fraction and growth must be > 0, got {fraction!r}, {growth!r}")
    lo, hi = P.min(axis=0), P.max(axis=0)
    h = float(np.max(hi - lo)) / int(cells)
    n = np.ceil((hi - lo) / h).astype(int) + 3
    y0, z0 = float(lo[0] - h), float(lo[1] - h)
    yc = y0 + h * np.arange(n[0])
    zc = z0 + h * np.arange(n[1])
    inside = _inside(P, yc, zc)
    if not inside.any():
        raise InputError("wall_cap: the section holds no raster cell (degenerate polygon)")
    t = _local_thickness(P, inside, y0, z0, h)
    cap = np.where(inside, fraction * t, np.inf)
    if corner is not None:
        for v in reentrant_corners(P):
            i, j = (int(round(c)) for c in ((v - (y0, z0)) / h))
            blk = (slice(max(i - 1, 0), i + 2), slice(max(j - 1, 0), j + 2))
            tv = np.nanmax(np.where(inside[blk], t[blk], np.nan)) if inside[blk].any() else np.nan
            if np.isfinite(tv):
                cap[blk] = np.minimum(cap[blk], corner * fraction * tv)
    cap = _graded(cap, h, growth)
    return WallCap(y0, z0, h, inside, t, cap)


def reentrant_corners(points: np.ndarray, min_turn: float = REENTRANT_TURN) -> np.ndarray:
    """The re-entrant (concave) corners of a closed polygon (y, z): vertices where the boundary
    turns into the material by more than ``min_turn`` (rad) at once (a sampled smooth concave
    curve, such as a flange root, turns by a fraction of a degree per point and is no corner)."""
    P = np.asarray(points, dtype=float)
    e1 = P - np.roll(P, 1, axis=0)
    e2 = np.roll(P, -1, axis=0) - P
    cross = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    turn = np.arctan2(cross, np.einsum("ij,ij->i", e1, e2))
    area = 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    return P[np.sign(area) * turn < -min_turn]
