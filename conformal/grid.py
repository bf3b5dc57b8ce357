"""Potential contact grids.

A planar grid is a rectangle [xl, xl + mx dx] x [yl, yl + my dy] of mx x my equal elements.
Arrays on the grid have shape (mx, my) and are indexed [ix, iy] (x = rolling direction first);
element (ix, iy) has its centre at x = xl + (ix + 1/2) dx, y = yl + (iy + 1/2) dy (CONTACT's
convention with 0-based indices).  Rolling is in +x: material enters at the leading edge x = xh.

>>> g = PlanarGrid(mx=4, my=2, dx=0.5, dy=1.0, xl=-1.0, yl=-1.0)
>>> g.x.tolist(), g.y.tolist(), g.shape, g.area
([-0.75, -0.25, 0.25, 0.75], [-0.5, 0.5], (4, 2), 0.5)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from conformal.errors import InputError


@dataclass(frozen=True)
class PlanarGrid:
    mx: int
    my: int
    dx: float
    dy: float
    xl: float
    yl: float

    def __post_init__(self):
        if self.mx < 1 or self.my < 1:
            raise InputError(f"[grid] mx, my: need at least one element, got {self.mx} x {self.my}")
        if not (self.dx > 0 and self.dy > 0):
            raise InputError(f"[grid] dx, dy: must be > 0, got {self.dx}, {self.dy}")

    @classmethod
    def centred(cls, mx: int, my: int, dx: float, dy: float) -> "PlanarGrid":
        return cls(mx, my, dx, dy, -0.5 * mx * dx, -0.5 * my * dy)

    @classmethod
    def around_ellipse(cls, a: float, b: float, n: int = 40, scale: float = 1.1,
                       mx: int | None = None, my: int | None = None) -> "PlanarGrid":
        """n x n elements (or mx x my) on [-scale a, scale a] x [-scale b, scale b]."""
        mx, my = mx or n, my or n
        return cls.centred(mx, my, 2 * scale * a / mx, 2 * scale * b / my)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.mx, self.my)

    @property
    def size(self) -> int:
        return self.mx * self.my

    @property
    def area(self) -> float:
        """Area of one element, mm²."""
        return self.dx * self.dy

    @property
    def x(self) -> np.ndarray:
        return self.xl + (np.arange(self.mx) + 0.5) * self.dx

    @property
    def y(self) -> np.ndarray:
        return self.yl + (np.arange(self.my) + 0.5) * self.dy

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Element centres as two (mx, my) arrays."""
        return np.meshgrid(self.x, self.y, indexing="ij")


@dataclass(frozen=True, eq=False)
class CurvedGrid:
    """Potential contact area on the curved rail surface (conformal contact, Li 2002).

    mx uniform elements along the rolling direction x (as in :class:`PlanarGrid`: edges
    ``xl + i dx``) times ms elements along s, the arc length of the rail profile.  Arrays on the
    grid have shape (mx, ms), indexed [ix, js].  The rail is an extrusion along x, so everything
    that depends on the cross-section (centres, normals, contact angle) is given per js.

    Frames.  The *rail-profile frame* is the rail profile's own coordinate system (the profile
    file, right-side form: y towards this rail's field side, z downwards, before the cant); x is
    the rolling direction.  The pair's *side frame* (track axes, mirrored for a left wheel) follows
    by ``side = R(cant) @ (y, z) + rail_origin`` with R(c) = [[cos c, sin c], [-sin c, cos c]].

    Fields
    ------
    mx, dx, xl : elements, element length (mm) and lower edge (mm) along x (x = 0 at the
        contact reference point, rolling in +x).
    s_edges : (ms + 1,) element edges along the rail profile (mm of arc length from the first
        point of the rail profile); element js spans [s_edges[js], s_edges[js + 1]].
    y, z : (ms,) element centres (at the centre arc length) in the rail-profile frame, on the
        rail surface.
    normal : (ms, 2) unit inner normals (n_y, n_z) of the rail (body 1) at the centres, in the
        rail-profile frame.
    delta : (ms,) contact angle (rad) at the centres: rotation about x from the side frame's
        z axis to the inner normal (CONTACT's DELTCP; negative at a right gauge corner).
    s_ref : arc length of the contact reference point (where x = 0, s = s_ref).
    cant, rail_origin : the rail-profile frame inside the side frame (see above).
    rail_curve : (n, 2) points (y, z) of the rail profile (rail-profile frame) from some mm
        before the first to some mm after the last element: the local curve to mesh the rail.
    rail_curve_s : (n,) their arc lengths.
    wheel_profile : (k, 2) points (y_w, z_w) of the wheel profile (wheel-profile coordinates:
        y_w along the axle towards the field side, z_w = increase of radius) over the part that
        faces the grid.
    wheel_centre : (3,) the point of the axle at the wheel-profile origin (y_w = 0), in the
        rail-profile frame (x, y, z).
    wheel_axle, wheel_down : (3,) unit axle direction (towards +y_w) and the wheel's 'down'
        direction (theta = 0), rail-profile frame.  A wheel surface point is
        ``wheel_centre + y_w wheel_axle + (wheel_radius + z_w) (cos(t) wheel_down + sin(t) f)``
        with f = wheel_axle x wheel_down (forward).
    wheel_radius : radius at the wheel-profile origin (mm).
    side : "left" | "right" (a left pair is the mirror image of a right pair).
    """

    mx: int
    dx: float
    xl: float
    s_edges: np.ndarray
    y: np.ndarray
    z: np.ndarray
    normal: np.ndarray
    delta: np.ndarray
    s_ref: float
    cant: float
    rail_origin: tuple[float, float]
    rail_curve: np.ndarray
    rail_curve_s: np.ndarray
    wheel_profile: np.ndarray
    wheel_centre: np.ndarray
    wheel_axle: np.ndarray
    wheel_down: np.ndarray
    wheel_radius: float
    side: str = "right"

    def __post_init__(self):
        if self.mx < 1 or len(self.s_edges) < 2:
            raise InputError(f"[grid]: a curved grid needs at least one element, got {self.mx} x {len(self.s_edges) - 1}")
        if not self.dx > 0 or np.any(np.diff(self.s_edges) <= 0):
            raise InputError("[grid]: curved grid element sizes must be > 0")

    @property
    def ms(self) -> int:
        return len(self.s_edges) - 1

    @property
    def shape(self) -> tuple[int, int]:
        return (self.mx, self.ms)

    @property
    def size(self) -> int:
        return self.mx * self.ms

    @property
    def ds(self) -> np.ndarray:
        """(ms,) element widths along s (mm)."""
        return np.diff(self.s_edges)

    @property
    def area(self) -> np.ndarray:
        """(ms,) element areas dx ds_j (mm²), the same for every ix."""
        return self.dx * self.ds

    @property
    def x(self) -> np.ndarray:
        return self.xl + (np.arange(self.mx) + 0.5) * self.dx

    @property
    def s(self) -> np.ndarray:
        """(ms,) element-centre arc lengths."""
        return 0.5 * (self.s_edges[:-1] + self.s_edges[1:])

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Element centres (x, s) as two (mx, ms) arrays."""
        return np.meshgrid(self.x, self.s, indexing="ij")


#: at most this many runs and run contacts are joined one by one in Python (:func:`_join_runs`);
#: more go to the array form (:func:`_join_runs_arrays`), whose few dozen numpy calls cost less there
PYTHON_JOIN_MAX = 600


def connected_parts(mask: np.ndarray) -> tuple[np.ndarray, int]:
    """The edge-connected parts of a boolean grid array (e.g. the contact elements): labels of the
    array's shape, 0 outside ``mask`` and 1..n numbered in the raster order of each part's first
    element, and n (what ``scipy.ndimage.label`` gives with its default structure, without
    importing scipy.ndimage, whose import costs about 0.3 s of CPU).

    1-D and 2-D arrays are labelled by runs: the runs of ``mask`` along each row, joined where
    runs of neighbouring rows share a column (union-find, the root of a part its first run);
    a contact patch of m rows has about m runs, so a patch costs a few numpy calls whatever the
    grid.  Arrays of more axes go through a graph of neighbouring elements
    (``scipy.sparse.csgraph.connected_components``).

    Parameters
    ----------
    mask : boolean array (any number of axes); neighbours share a face (2-D: an edge).

    Returns
    -------
    (labels, n): int32 labels of ``mask``'s shape and the number of parts.

    >>> connected_parts(np.array([[1, 0, 1], [1, 0, 0], [0, 1, 1]], bool))[0].tolist()
    [[1, 0, 2], [1, 0, 0], [0, 3, 3]]
    """
    m = np.asarray(mask, bool)
    if m.ndim == 1:
        labels, n = connected_parts(m.reshape(1, -1))
        return labels.reshape(m.shape), n
    if m.ndim != 2 or m.size == 0:
        return _connected_parts_graph(m)
    start = m.copy()                  # the first element of each run along a row
    start[:, 1:] &= ~m[:, :-1]
    nrun = int(np.count_nonzero(start))
    if nrun == 0:
        return np.zeros(m.shape, dtype=np.int32), 0
    shared = m[:-1] & m[1:]           # elements whose neighbour in the next row is in the mask too
    first = shared.copy()             # one per pair of runs of neighbouring rows that share columns
    first[:, 1:] &= ~shared[:, :-1]
    if int(np.count_nonzero(first)) == nrun - 1 and nrun == int(np.count_nonzero(m.any(axis=1))):
        # one run per row in nrun rows, each sharing columns with the next: one part (a convex patch)
        return m.astype(np.int32), 1
    run = np.cumsum(start, dtype=np.int32).reshape(m.shape)   # run k = 1..nrun (raster order)
    upper, lower = run[:-1][first], run[1:][first]
    labels = np.zeros(m.shape, dtype=np.int32)
    if nrun + upper.size <= PYTHON_JOIN_MAX:
        part, n = _join_runs(nrun, upper.tolist(), lower.tolist())
    else:
        part, n = _join_runs_arrays(nrun, upper, lower)
    labels[m] = part[run[m]]
    return labels, n


def _join_runs(nrun: int, upper: list, lower: list) -> tuple[np.ndarray, int]:
    """Union-find of runs 1..nrun joined by the pairs (upper, lower): the part (1..n, in the order
    of each part's first run) of every run, index 0 (outside) part 0, and n."""
    parent = list(range(nrun + 1))
    for a, b in zip(upper, lower):
        while parent[a] != a:                    # roots, halving the paths on the way
            parent[a] = a = parent[parent[a]]
        while parent[b] != b:
            parent[b] = b = parent[parent[b]]
        if a < b:                                # the smaller run is the root: a part's first run
            parent[b] = a
        elif b < a:
            parent[a] = b
    part = [0] * (nrun + 1)
    n = 0
    for k in range(1, nrun + 1):                 # a run's root comes before it: numbered already
        r = parent[k]
        if r == k:
            n += 1
            part[k] = n
        else:
            part[k] = part[r]
    return np.array(part, dtype=np.int32), n


def _join_runs_arrays(nrun: int, upper: np.ndarray, lower: np.ndarray) -> tuple[np.ndarray, int]:
    """:func:`_join_runs` in numpy calls: every root hooks onto the smallest root it touches, then
    the trees are shortcut to their roots; the number of trees of a part at least halves in each
    pass, so a part of k runs takes at most log2(k) + 1 passes."""
    parent = np.arange(nrun + 1, dtype=np.int32)
    a, b = upper, lower
    while a.size:
        pa, pb = parent[a], parent[b]
        np.minimum.at(parent, np.maximum(pa, pb), np.minimum(pa, pb))
        while True:
            grand = parent[parent]
            if np.array_equal(grand, parent):
                break
            parent = grand
        open_ = parent[a] != parent[b]
        a, b = a[open_], b[open_]
    root = parent == np.arange(nrun + 1, dtype=np.int32)     # a part's root is its smallest run
    number = np.cumsum(root, dtype=np.int32) - 1             # run 0 is a root of number 0
    return number[parent], int(number[-1])


def _connected_parts_graph(m: np.ndarray) -> tuple[np.ndarray, int]:
    """:func:`connected_parts` of a boolean array of any number of axes by a graph of
    neighbouring elements (``scipy.sparse.csgraph.connected_components``)."""
    labels = np.zeros(m.shape, dtype=np.int32)
    idx = np.flatnonzero(m)
    if idx.size == 0:
        return labels, 0
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    node = np.full(m.size, -1, dtype=np.int64)
    node[idx] = np.arange(idx.size)
    node = node.reshape(m.shape)
    a, b = [], []
    for axis in range(m.ndim):        # neighbours along each axis
        lo = tuple(slice(None, -1) if k == axis else slice(None) for k in range(m.ndim))
        hi = tuple(slice(1, None) if k == axis else slice(None) for k in range(m.ndim))
        both = m[lo] & m[hi]
        a.append(node[lo][both])
        b.append(node[hi][both])
    a, b = np.concatenate(a), np.concatenate(b)
    graph = coo_matrix((np.ones(a.size), (a, b)), shape=(idx.size, idx.size))
    n, comp = connected_components(graph, directed=False)
    _, first = np.unique(comp, return_index=True)       # each part's first element (raster order)
    rank = np.empty(n, dtype=np.int32)
    rank[np.argsort(first)] = np.arange(1, n + 1, dtype=np.int32)
    labels.reshape(-1)[idx] = rank[comp]
    return labels, int(n)
