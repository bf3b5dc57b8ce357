"""Tetrahedral meshes of quasi-quarter-space bodies with gmsh (OpenCASCADE kernel).

The cross-section (surface curve between s_lo and s_hi, closed on the material side by an arc of
the disc around the patch, see :class:`~conformal.meshing.bodies.BodyExtent`) is extruded along x
(rail, block) or revolved about the axle (wheel), piece by piece between the column edges the mesh
must follow (``conform``).  The surface curve is split at every grid edge s_l, so the swept
surface falls apart into one strip per grid row and one piece per swept section:

* ``"all"``: every column edge of the observed region: each contact element is a face of its own
  and the surface mesh conforms to the grid (needed for exact element loads and averages);
* ``"column"``: only the edges of the loaded column and of the observed region;
* ``"none"``: only the edges of the observed region (enough for the split method, whose loads are
  analytic).

The mesh size is ``h_patch`` on the observed patch (``h_load`` on the loaded column, if given) and
grows linearly with the distance from it (gradient ``growth``) up to ``h_max``; gmsh's Distance
field from the grid's row edges drives it.  gmsh is not thread-safe: one model per process, always
finalised (also on errors).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from conformal.errors import ConformalError, InputError
from conformal.meshing.bodies import (BodyExtent, BodyModel, StripPatch, body_extent, closed_section_extent,
                                      grow_profile, inward_normal)

SAMPLING = 0
#: a wheel's strips whose surface meshes gmsh could not make are meshed again with the element
#: edges along the sweep short enough that their chords depart from the arc, within the surface,
#: by at most this fraction of the strip's width (sagitta_sizes)
SAGITTA_FRACTION = 0.5
CONFORM = ("all", "column", "none")
CLOSURES = ("extend", "straight", "cut", "section")
#: closure "section": at the section's re-entrant corners (a web meeting a head, foot or rim
#: without a fillet: a singular stress) the walls' cap falls to this fraction of its value
#: (conformal.meshing.wall.wall_cap); halving it with every element keeps the corners graded
WALL_CORNER = 0.25


class MeshingError(ConformalError):
    """gmsh could not build or mesh the body (the message says which step and why)."""


@dataclass(frozen=True)
class MeshSpec:
    """Mesh parameters.  Sizes are relative to the contact element size h_e = min(dx, ds).

    order: 1 (linear) or 2 (quadratic tetrahedra) -- used by the FE solve, stored here so that one
    spec describes the whole discretisation.
    """

    # defaults chosen from studies/fe_influence_speed_error.py (split method): P1 with h = 2 d on
    # the observed patch and d/2 at the loaded column; see the study's report for the numbers
    order: int = 1
    h_patch: float = 2.0
    h_load: float | None = 0.5
    growth: float = 0.35
    h_max: float = 0.2          # largest element, relative to the body margin (depth)
    conform: str = "column"
    # margin around the patch, in patch sizes (see body_extent): 16, chosen from
    # studies/fe_far_field_limit.py: within 0.3 % (rail corner), 0.1 % (flange root) and 0.2 %
    # (pair FN) of the size-converged limit of the deep pair, at the unknowns of size 1 (the
    # grading keeps them nearly constant; size 1, the earlier default, was 2.6 % off on the rail)
    body_size: float = 16.0
    optimize: bool = True
    # a profile that ends inside the body's disc: continued straight along its end tangent
    # ("extend", bodies.grow_profile; a section whose ends point the same way, a slab, is
    # limited to a margin of its width; "straight": not limited), or cut straight to the disc's
    # arc ("cut", the earlier closure, which leaves the body smaller than body_size says); or the
    # profile is a whole section's boundary less its support edge ("section", bodies.section_profile:
    # the body is that section cut by the disc)
    closure: str = "extend"
    # closure "section" only: the largest element in a wall of the section (the rail's web and
    # foot, the wheel's rim and web), as a fraction of its local thickness (conformal.meshing.wall):
    # P1 tetrahedra much longer than a wall is thick are too stiff in bending there
    h_wall: float = 0.25

    def __post_init__(self):
        if self.order not in (1, 2):
            raise InputError(f"[model] fe_order: must be 1 or 2, got {self.order}")
        if self.closure not in CLOSURES:
            raise InputError(f"[model] fe_closure: must be one of {', '.join(CLOSURES)}, got {self.closure!r}")
        if self.conform not in CONFORM:
            raise InputError(f"[model] fe_conform: must be one of {', '.join(CONFORM)}, got {self.conform!r}")
        for name in ("h_patch", "growth", "h_max", "body_size", "h_wall"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"[model] fe_{name}: must be > 0, got {v!r}")
        if self.h_load is not None and not (math.isfinite(self.h_load) and self.h_load > 0):
            raise InputError(f"[model] fe_h_load: must be > 0, got {self.h_load!r}")

    def key(self) -> dict:
        key = {"order": self.order, "h_patch": self.h_patch, "h_load": self.h_load, "growth": self.growth,
               "h_max": self.h_max, "conform": self.conform, "body_size": self.body_size,
               "optimize": self.optimize, "closure": self.closure}
        if self.closure == "section":          # the other closures' meshes (and keys) do not use it
            key.update(h_wall=self.h_wall, wall_corner=WALL_CORNER)
        return key


@dataclass(frozen=True, eq=False)
class BodyMesh:
    """A linear tetrahedral mesh of one body and what the FE solve needs to know about it.

    points (N, 3) mm, tets (T, 4) node indices; free_tris (F, 3): triangles of the free (profile)
    surface; clamped_tris (C, 3): triangles of the cut faces (clamped); uv (N, 2): rolling coordinate x and
    arc length s of the nodes on the free surface (NaN elsewhere).
    """

    body: BodyModel
    patch: StripPatch
    extent: BodyExtent
    spec: MeshSpec
    points: np.ndarray
    tets: np.ndarray
    free_tris: np.ndarray
    clamped_tris: np.ndarray
    uv: np.ndarray
    stats: dict = field(default_factory=dict)

    @property
    def n_nodes(self) -> int:
        return len(self.points)

    @property
    def clamped_nodes(self) -> np.ndarray:
        return np.unique(self.clamped_tris)

    def to_meshio(self):
        """The mesh as a meshio.Mesh (tetra + free-surface triangles) for inspection."""
        import meshio

        return meshio.Mesh(self.points, [("tetra", self.tets), ("triangle", self.free_tris)])

    def write(self, path) -> None:
        """Write the mesh with meshio (format from the suffix, e.g. .vtu, .msh, .xdmf)."""
        from conformal.files import atomic_path

        with atomic_path(path, keep_suffix=True) as tmp:
            self.to_meshio().write(str(tmp))


# ----------------------------------------------------------------------------- coordinates
def cross_section_coordinates(body: BodyModel, extent: BodyExtent, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rolling coordinate x (arc length at the reference radius for a wheel) and the point
    (y, z) in the cross-section plane, for points p (..., 3) of the body."""
    p = np.asarray(p, dtype=float)
    if not body.revolved:
        return p[..., 0], p[..., 1:3]
    dz = p[..., 2] - body.axle_z
    theta = np.arctan2(p[..., 0], dz)
    r = np.hypot(p[..., 0], dz)
    yz = np.stack([p[..., 1], body.axle_z + r], axis=-1)
    return theta * extent.x_ref_radius, yz


def surface_point(body: BodyModel, extent: BodyExtent, x, s) -> np.ndarray:
    """3-D point of the surface at rolling coordinate x and arc length s."""
    yz = body.profile.point(s)
    x = np.asarray(x, dtype=float)
    if not body.revolved:
        return np.stack(np.broadcast_arrays(x, yz[..., 0], yz[..., 1]), axis=-1)
    theta = x / extent.x_ref_radius
    r = yz[..., 1] - body.axle_z
    return np.stack(np.broadcast_arrays(r * np.sin(theta), yz[..., 0], body.axle_z + r * np.cos(theta)), axis=-1)


def surface_frame(body: BodyModel, extent: BodyExtent, x, s) -> np.ndarray:
    """Contact frame (t_x, t_s, n) of the surface at (x, s), rows of shape (..., 3, 3).

    n is the common normal: it points into body 1 (down, z > 0 side of the rail surface), i.e.
    into a rail or block body and out of a wheel; t_s = n x t_x along increasing s.
    """
    t = body.profile.tangent(s)                    # (..., 2) = (dy/ds, dz/ds)
    x = np.asarray(x, dtype=float)
    shape = np.broadcast(x, t[..., 0]).shape
    F = np.zeros(shape + (3, 3))
    if not body.revolved:
        theta = np.zeros(shape)
    else:
        theta = np.broadcast_to(x / extent.x_ref_radius, shape)
    c, si = np.cos(theta), np.sin(theta)
    ty, tz = np.broadcast_to(t[..., 0], shape), np.broadcast_to(t[..., 1], shape)
    # cross-section vectors at theta = 0: t_s = (0, ty, tz), n = (0, -tz, ty); rotate about y
    F[..., 0, :] = np.stack([c, np.zeros(shape), -si], axis=-1)
    F[..., 1, :] = np.stack([tz * si, ty, tz * c], axis=-1)
    F[..., 2, :] = np.stack([ty * si, -tz, ty * c], axis=-1)
    return F


# ----------------------------------------------------------------------------- gmsh model
def _cut_positions(patch: StripPatch, conform: str) -> np.ndarray:
    xe = patch.x_edges
    if conform == "all":
        return xe
    cuts = [xe[0], xe[-1]]
    if conform == "column":
        cuts += [-0.5 * patch.dx, 0.5 * patch.dx]
    return np.unique(np.array(cuts))


# ----------------------------------------------------------------------------- gmsh helpers
# (shared with conformal.meshing.section_body)
def profile_curves(occ, pieces: list[np.ndarray], pt) -> tuple[list[int], list[int]]:
    """OpenCASCADE curves through consecutive profile pieces (arrays of (y, z) points, each
    starting where the one before ends; ``pt(y, z)`` adds a point and returns its tag): a spline
    through smooth parts, split at kinks (turns over 10 degrees, where a spline through the
    corner would overshoot the polyline), a line where two points remain.  Returns the curve
    tags in order and the point tags of the pieces' ends (the first piece's start included)."""
    corner = [pt(*pieces[0][0])]
    curves = []
    for piece in pieces:
        inner = [pt(*q) for q in piece[1:-1]]
        end = pt(*piece[-1])
        tags = [corner[-1]] + inner + [end]
        seg = np.diff(piece, axis=0)
        seg /= np.linalg.norm(seg, axis=1, keepdims=True)
        kinks = 1 + np.flatnonzero(np.einsum("ij,ij->i", seg[:-1], seg[1:]) < math.cos(math.radians(10.0)))
        for a, b in zip(np.concatenate([[0], kinks]), np.concatenate([kinks, [len(tags) - 1]])):
            part = tags[a:b + 1]
            curves.append(occ.addLine(part[0], part[1]) if len(part) == 2 else occ.addSpline(part))
        corner.append(end)
    return curves, corner


def sweep_pieces(occ, face: int, body: BodyModel, xs: np.ndarray, x0: float, r_ref: float | None) -> None:
    """Sweep a cross-section face (drawn at x = ``x0``, or at angle 0 for a wheel) from xs[0] to
    xs[-1] piece by piece between the positions ``xs`` (along x, or arc length at the radius
    ``r_ref`` about the axle for a wheel): each piece is swept from the end face of the one
    before, so neighbouring pieces share that face (OpenCASCADE keeps it as one shape) and the
    volumes are conforming without a boolean; then synchronise."""
    f = [(2, face)]
    if body.revolved:
        occ.rotate(f, 0, 0, body.axle_z, 0, 1, 0, xs[0] / r_ref)
    else:
        occ.translate(f, xs[0] - x0, 0, 0)
    for xa, xb in zip(xs[:-1], xs[1:]):
        if body.revolved:
            out = occ.revolve(f, 0, 0, body.axle_z, 0, 1, 0, (xb - xa) / r_ref)
        else:
            out = occ.extrude(f, xb - xa, 0, 0)
        f = [out[0]]                       # the end face of this piece starts the next one
    occ.synchronize()


def graded_size(field, tag: int, entities: list[int], where: str, sampling: int, h0: float, h_max: float,
                growth: float) -> int:
    """Mesh size graded from ``entities`` (gmsh tags; ``where``: "CurvesList" or "SurfacesList"):
    a Distance field ``tag`` from them (``sampling`` points per entity) and a linear Threshold
    field ``tag + 1``, h = min(h_max, h0 + growth * distance) (native, fast).  Returns the
    Threshold's tag."""
    field.add("Distance", tag)
    field.setNumbers(tag, where, entities)
    field.setNumber(tag, "Sampling", sampling)
    _threshold(field, tag + 1, tag, h0, h_max, growth)
    return tag + 1


#: gmsh options of every body mesh: the size from the background field only, 2-D Frontal-Delaunay
#: ("Mesh.Algorithm" 6), no optimiser inside generate, linear elements
MESH_OPTIONS = (("Mesh.MeshSizeFromPoints", 0), ("Mesh.MeshSizeFromCurvature", 0),
                ("Mesh.MeshSizeExtendFromBoundary", 0), ("Mesh.Algorithm", 6), ("Mesh.Optimize", 0),
                ("Mesh.ElementOrder", 1))


def set_mesh_options(gmsh, algorithm3d: int, *extra: tuple[str, float]) -> None:
    """MESH_OPTIONS, the 3-D algorithm (10: HXT, 1: Delaunay) and ``extra`` (name, value) pairs."""
    for name, value in MESH_OPTIONS + (("Mesh.Algorithm3D", algorithm3d),) + extra:
        gmsh.option.setNumber(name, value)


def _breaks(body: BodyModel, patch: StripPatch, ext: BodyExtent, joints=()) -> np.ndarray:
    """Arc lengths at which the surface curve is split: its ends, the grid's row edges and the
    joints of a straight continuation (grow_profile: the continuation is one straight line, not
    the last span of a spline through 0.1 mm points, which would bulge)."""
    prof = body.profile
    e = patch.edges
    tol = 1e-6 * max(1.0, patch.size)
    s0, s1 = (prof.s[0], prof.s[-1]) if ext.closed else (ext.s_lo, ext.s_hi)
    lo = [s0] + [j for j in joints if s0 + tol < j < e[0] - tol]
    hi = [j for j in joints if e[-1] + tol < j < s1 - tol] + [s1]
    return np.array(([v for v in lo if v < e[0] - 1e-9]) + list(e) + [v for v in hi if v > e[-1] + 1e-9])


def sagitta_sizes(body: BodyModel, breaks: np.ndarray, fraction: float = SAGITTA_FRACTION) -> np.ndarray:
    """Largest element edge along the sweep on each strip of a wheel (the surface between
    consecutive ``breaks`` revolved about the axle) for which the edge's chord departs from its
    arc, within the surface, by at most ``fraction`` of the strip's width.

    A parallel circle of radius r on a surface of revolution whose profile has the unit tangent
    (t_y, t_z) has the geodesic curvature kappa_g = |t_z| / r (the part of its curvature 1/r that
    lies in the surface); a chord of length h departs from it in the surface by h^2 kappa_g / 8.
    With the strip's width w (arc length along the profile): h = sqrt(8 fraction w / kappa_g).
    Where the chord departs by more than the width, the triangles spanning the strip fold over:
    on a flange flank (profile at 70 degrees to the axle, |t_z| = 0.94) with 0.1 mm grid rows
    and a sweep element of 70 mm at r = 473 mm the chord departs by 1.2 mm.  Returns
    one size per strip (inf where the strip is not curved in the surface, and for a body that is
    not revolved).
    """
    breaks = np.asarray(breaks, dtype=float)
    if not body.revolved:
        return np.full(len(breaks) - 1, np.inf)
    u = np.linspace(0.0, 1.0, 5)
    s = breaks[:-1, None] + (breaks[1:] - breaks[:-1])[:, None] * u[None, :]
    kappa = np.max(np.abs(body.profile.tangent(s)[..., 1]) / body.radius_at(s), axis=1)
    w = np.diff(breaks)
    with np.errstate(divide="ignore"):
        return np.where(kappa > 0, np.sqrt(8.0 * fraction * w / np.where(kappa > 0, kappa, 1.0)), np.inf)


def _build(gmsh, body: BodyModel, patch: StripPatch, ext: BodyExtent, spec: MeshSpec, joints=()):
    occ = gmsh.model.occ
    prof = body.profile
    pieces = prof.pieces(_breaks(body, patch, ext, joints))
    x0 = 0.0 if body.revolved else ext.x_lo

    def pt(y, z):
        return occ.addPoint(x0, float(y), float(z))

    curves, corner = profile_curves(occ, pieces, pt)
    if ext.closed:
        face = _closed_section_face(gmsh, body, patch, ext, curves, corner, x0)
    else:
        face = _disc_section_face(occ, ext, curves, corner, pt)
    _sweep(gmsh, body, patch, ext, spec, face, x0)


def _closed_section_face(gmsh, body, patch, ext, curves, corner, x0) -> int:
    """A whole section (closure "section"): the profile closed by the straight support edge, cut
    by the disc; of the pieces the cut leaves, the one holding the patch."""
    occ = gmsh.model.occ
    curves.append(occ.addLine(corner[-1], corner[0]))
    face = occ.addPlaneSurface([occ.addCurveLoop(curves)])
    disk = occ.addDisk(x0, ext.centre[0], ext.centre[1], ext.radius, ext.radius, zAxis=[1, 0, 0], xAxis=[0, 1, 0])
    out, _ = occ.intersect([(2, face)], [(2, disk)])
    faces = [t for d, t in out if d == 2]
    if not faces:
        raise MeshingError(f"the {body.kind} section and the body's disc do not overlap")
    if len(faces) == 1:
        return faces[0]
    occ.synchronize()
    s_mid = 0.5 * (patch.edges[0] + patch.edges[-1])
    yz = body.profile.point(s_mid) + 1e-3 * patch.size * inward_normal(body, s_mid)
    probe = [x0, float(yz[0]), float(yz[1])]
    gap = [np.linalg.norm(np.array(gmsh.model.getClosestPoint(2, f, probe)[0]) - probe) for f in faces]
    keep = faces[int(np.argmin(gap))]
    occ.remove([(2, f) for f in faces if f != keep], recursive=True)
    return keep


def _disc_section_face(occ, ext, curves, corner, pt) -> int:
    """The profile between s_lo and s_hi closed by the disc's arc (and end cuts)."""
    # artificial boundary: end cut (profile end inside the disc), two arcs (< pi each), end cut
    cen = pt(*ext.centre)
    q_hi = pt(*ext.q_hi) if ext.cut_hi else corner[-1]
    if ext.cut_hi:
        curves.append(occ.addLine(corner[-1], q_hi))
    q_lo = pt(*ext.q_lo) if ext.cut_lo else corner[0]
    mid = pt(*ext.arc_mid)
    curves += [occ.addCircleArc(q_hi, cen, mid), occ.addCircleArc(mid, cen, q_lo)]
    if ext.cut_lo:
        curves.append(occ.addLine(q_lo, corner[0]))
    loop = occ.addCurveLoop(curves)
    return occ.addPlaneSurface([loop])


def _sweep(gmsh, body, patch, ext, spec, face, x0) -> None:
    """Sweep the section face along x (extrusion) or about the axle (revolution)."""
    # sweep the section piece by piece between the cut positions (x_lo, the cuts, x_hi), so that
    # the column edges are edges of the pieces: each piece is swept from the end face of the one
    # before, so neighbouring pieces share that face (OpenCASCADE keeps it as one shape) and the
    # volumes are conforming without a boolean.  Gluing separately swept copies by a fragment
    # took 3-4.5 s CPU of a 51 x 39 body (more than the 3-D mesher); imprinting copies of the
    # profile curves on one swept volume made OpenCASCADE fail ("Fragments failed") on a
    # measured worn wheel with a 202 x 83 strip.
    xs = np.concatenate([[ext.x_lo], _cut_positions(patch, spec.conform), [ext.x_hi]])
    xs = np.unique(xs[(xs >= ext.x_lo) & (xs <= ext.x_hi)])
    sweep_pieces(gmsh.model.occ, face, body, xs, x0, ext.x_ref_radius)


def _curve_midpoint(gmsh, tag: int) -> np.ndarray:
    lo, hi = gmsh.model.getParametrizationBounds(1, tag)
    return np.array(gmsh.model.getValue(1, tag, [0.5 * (lo[0] + hi[0])]))


def _threshold(f, tag: int, distance: int, h0: float, h_max: float, growth: float) -> None:
    """h = min(h_max, h0 + growth * distance): a linear Threshold field (native, fast)."""
    f.add("Threshold", tag)
    f.setNumber(tag, "InField", distance)
    f.setNumber(tag, "SizeMin", h0)
    f.setNumber(tag, "SizeMax", h_max)
    f.setNumber(tag, "DistMin", 0.0)
    f.setNumber(tag, "DistMax", max((h_max - h0) / growth, 1e-9))
    f.setNumber(tag, "Sigmoid", 0)


def _surface_midpoint(gmsh, tag: int) -> np.ndarray:
    lo, hi = gmsh.model.getParametrizationBounds(2, tag)
    return np.array(gmsh.model.getValue(2, tag, [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]))


def _sagitta_field(gmsh, body, ext, breaks, h_max: float, last: int, tag: int, tol: float) -> tuple[int, int]:
    """Cap the mesh size on every swept strip of a wheel at its :func:`sagitta_sizes` (a
    Constant field on the strip and its boundary curves), combined with the field ``last`` by a
    Min field.  Returns the background field's tag and the number of strips capped."""
    caps = sagitta_sizes(body, breaks)
    if not np.any(caps < h_max):
        return last, 0
    tags = [t for _, t in gmsh.model.getEntities(2)]
    _, yz = cross_section_coordinates(body, ext, np.array([_surface_midpoint(gmsh, t) for t in tags]))
    s = body.profile.project(yz, ext.s_lo, ext.s_hi)
    on = np.linalg.norm(body.profile.point(s) - yz, axis=-1) < tol
    strip = np.clip(np.searchsorted(breaks, s) - 1, 0, len(caps) - 1)
    f = gmsh.model.mesh.field
    fields = [last]
    for j in np.unique(strip[on]):
        if caps[j] >= h_max:
            continue
        f.add("Constant", tag)
        f.setNumbers(tag, "SurfacesList", [t for t, k, o in zip(tags, strip, on) if o and k == j])
        f.setNumber(tag, "IncludeBoundary", 1)
        f.setNumber(tag, "VIn", float(caps[j]))
        f.setNumber(tag, "VOut", 1e22)
        fields.append(tag)
        tag += 1
    f.add("Min", tag)
    f.setNumbers(tag, "FieldsList", fields)
    return tag, len(fields) - 1


def _size_field(gmsh, body, patch, ext, spec, h_e, breaks=None):
    """Distance fields from the row edges of the observed patch and of the loaded column; with
    ``breaks`` (the splits of the surface curve) also the sagitta bound of a wheel's strips
    (:func:`_sagitta_field`).  Returns the numbers of observed and loaded curves and of capped
    strips."""
    x_obs = 0.5 * patch.n_columns * patch.dx
    e = patch.edges
    tol = 1e-6 * max(1.0, patch.size)
    tags = [c for _, c in gmsh.model.getEntities(1)]
    # all curve midpoints projected on the profile at once (one projection per curve took 0.4 s
    # of a 51 x 39 body)
    x, yz = cross_section_coordinates(body, ext, np.array([_curve_midpoint(gmsh, c) for c in tags]))
    s = body.profile.project(yz, ext.s_lo, ext.s_hi)
    on_surface = np.linalg.norm(body.profile.point(s) - yz, axis=-1) < tol
    obs = on_surface & (s >= e[0] - tol) & (s <= e[-1] + tol) & (np.abs(x) <= x_obs + tol)
    obs_curves = [c for c, k in zip(tags, obs) if k]
    col_curves = [c for c, k, xc in zip(tags, obs, x) if k and abs(xc) < 0.5 * patch.dx + tol]
    h_patch = spec.h_patch * h_e
    h_max = max(spec.h_max * ext.depth, h_patch)
    f = gmsh.model.mesh.field
    length = max(patch.n_columns * patch.dx, e[-1] - e[0])
    last = graded_size(f, 1, obs_curves, "CurvesList", SAMPLING or int(min(2000, max(20, 2 * length / h_patch))),
                       h_patch, h_max, spec.growth)
    if spec.h_load is not None and col_curves:
        h_load = spec.h_load * h_e
        graded_size(f, 3, col_curves, "CurvesList", int(min(2000, max(20, 4 * (e[-1] - e[0]) / h_load))),
                    h_load, h_max, spec.growth)
        f.add("Min", 5)
        f.setNumbers(5, "FieldsList", [2, 4])
        last = 5
    capped = 0
    if breaks is not None:
        last, capped = _sagitta_field(gmsh, body, ext, breaks, h_max, last, 10, tol=max(1e-3, 1e-2 * h_e))
    f.setAsBackgroundMesh(last)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h_max)
    gmsh.option.setNumber("Mesh.MeshSizeMin", min(h_patch, spec.h_load * h_e if spec.h_load else h_patch))
    return len(obs_curves), len(col_curves), capped


def _has_tetrahedra(gmsh) -> bool:
    types, _, conn = gmsh.model.mesh.getElements(3)
    return any(len(c) for c in conn)


def _unmeshed(gmsh, min_area: float) -> tuple[list[int], list[int]]:
    """Surfaces of area over ``min_area`` that gmsh left without triangles, and volumes it left
    without tetrahedra (gmsh only warns "No elements in surface ..." / "... in volume ...", and
    meshes the other volumes: a body with a hole in its mesh).  OpenCASCADE's degenerate
    slivers, without area, are not counted."""
    def empty(dim, tag):
        return not any(len(c) for c in gmsh.model.mesh.getElements(dim, tag)[2])

    faces = [t for _, t in gmsh.model.getEntities(2) if empty(2, t) and gmsh.model.occ.getMass(2, t) > min_area]
    volumes = [t for _, t in gmsh.model.getEntities(3) if empty(3, t)]
    return faces, volumes


def _extract(gmsh, body: BodyModel, ext: BodyExtent, h_element: float):
    tags, coords, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(tags)
    tags = tags[order]
    pts = coords.reshape(-1, 3)[order]
    types, _, conn = gmsh.model.mesh.getElements(3)
    if not any(len(c) for c in conn):
        raise MeshingError(f"gmsh produced no tetrahedra for the {body.kind} body (its surface mesh "
                           "could not be filled; a finer fe_h_patch or a smaller fe_body_size may help)")
    tets = []
    for t, c in zip(types, conn):
        if t != 4:
            raise MeshingError(f"gmsh returned volume elements of type {t}, expected linear tetrahedra")
        tets.append(c.reshape(-1, 4))
    tets = np.searchsorted(tags, np.concatenate(tets))
    used = np.unique(tets)
    # surface entities: free (every node on the surface curve) or clamped.  gmsh's spline through
    # the profile points departs from the polyline by up to about h_p^2 / (8 R) (1e-4 mm for 0.1 mm
    # points on R13, but 1e-3 mm on a measured worn profile whose digitised curvature reaches
    # 1/R = 0.6 /mm: a tolerance tied to the contact element size (1e-2 h_e = 2e-4 mm on a
    # 0.02 mm strip) then called parts of the free surface clamped and left holes in it).  Every
    # clamped face (the x-end cuts, the s-end cuts and the bottom) reaches the bottom face, so it
    # has nodes at least the body depth away from the body's part of the profile (s_lo .. s_hi; the
    # profile beyond it, e.g. a gauge face, may run close to an s-end cut): a tenth of the depth
    # separates the two kinds with a wide margin on either side.
    tol = max(1e-2 * h_element, 0.1 * ext.depth)
    if ext.closed:
        # a whole section: the disc's arcs may cross a web 16.5 mm thick (8 mm from its faces) and
        # the support edge lies 15-20 mm from the nearest profile point, whatever the body size
        tol = max(1e-2 * h_element, min(tol, 0.5))
    free, clamped = [], []
    for _, s in gmsh.model.getBoundary(gmsh.model.getEntities(3), oriented=False):
        types, _, conn = gmsh.model.mesh.getElements(2, s)
        conn = [c for t, c in zip(types, conn) if t == 2]
        if not conn:                       # a degenerate face without triangles (a sliver of OCC's)
            continue
        tri = np.searchsorted(tags, np.concatenate(conn).reshape(-1, 3))
        nodes = np.unique(tri)
        _, yz = cross_section_coordinates(body, ext, pts[nodes])
        sp = body.profile.project(yz, ext.s_lo, ext.s_hi)             # the body's part of the profile only
        dist = np.linalg.norm(body.profile.point(sp) - yz, axis=-1)
        (free if dist.max() < tol else clamped).append(tri)
    if not free:
        raise MeshingError("no free surface found in the body mesh")
    # compact numbering (gmsh keeps geometry points that carry no tetrahedron)
    new = -np.ones(len(pts), dtype=np.int64)
    new[used] = np.arange(used.size)
    pts = pts[used]
    tets = new[tets]
    free = new[np.concatenate(free)]
    clamped = new[np.concatenate(clamped)] if clamped else np.zeros((0, 3), dtype=np.int64)
    return pts, tets, free, clamped


def _drop_flat(points: np.ndarray, tets: np.ndarray, body: BodyModel) -> np.ndarray:
    """Tetrahedra without the flat ones (four nodes in one plane: HXT left 487 of them on the
    internal faces between the swept pieces of a worn wheel, whose singular element matrices
    made the stiffness matrix singular).  They carry no material; every node must keep a
    tetrahedron of volume."""
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    vol = np.abs(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a))
    keep = vol > 1e-9 * np.median(vol)
    if keep.all():
        return tets
    if np.unique(tets[keep]).size != len(points):
        raise MeshingError(f"gmsh left flat tetrahedra in the {body.kind} body that cannot be removed "
                           "(a node would lose its volume); try other [model] fe_h_patch or fe_body_size")
    return tets[keep]


def _orient(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Tetrahedra with positive volume (node order swapped where needed)."""
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    vol = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)
    tets = tets.copy()
    neg = vol < 0
    tets[neg, 0], tets[neg, 1] = tets[neg, 1], tets[neg, 0].copy()
    return tets


class _NoTetrahedra(Exception):
    """gmsh's 3-D mesher left the volume empty (try another algorithm)."""


class _Unmeshed(Exception):
    """gmsh's surface mesher left surfaces without triangles (so their volumes without
    tetrahedra): another 3-D algorithm cannot help."""

    def __init__(self, faces, volumes):
        super().__init__(f"no elements in surfaces {faces}, volumes {volumes}")
        self.faces, self.volumes = faces, volumes


def _wall_size(body: BodyModel, cap):
    """gmsh's mesh size callback that caps the size at ``cap`` (a :class:`~conformal.meshing.wall.WallCap`
    of the cross-section) at the point's cross-section coordinates (about the axle for a wheel)."""
    y0, z0, h, table = cap.y0, cap.z0, cap.spacing, cap.cap
    ni, nj = table.shape[0] - 1, table.shape[1] - 1
    axle = body.axle_z if body.revolved else None

    def size(dim, tag, x, y, z, lc):
        zz = z if axle is None else axle + math.hypot(x, z - axle)
        i = min(max(int(round((y - y0) / h)), 0), ni)
        j = min(max(int(round((zz - z0) / h)), 0), nj)
        return min(lc, float(table[i, j]))

    return size


def _generate(gmsh, body, patch, ext, spec, h_e, threads, algorithm3d, joints=(), wall=None, sagitta=False):
    """One gmsh session: geometry, size field, mesh (Mesh.Algorithm3D = algorithm3d), extraction;
    ``wall``: a wall-thickness cap of the cross-section (closure "section") on top of the size field;
    ``sagitta``: bound the element size along the sweep on a wheel's strips (sagitta_sizes).
    Returns (points, tets, free, clamped, t1, t2, capped strips)."""
    if gmsh.isInitialized():
        gmsh.finalize()
    # interruptible=False: no SIGINT handler, so that meshing also works in worker threads (Dask)
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", threads)
        gmsh.model.add("conformal_body")
        step = "building the geometry"
        try:
            _build(gmsh, body, patch, ext, spec, joints)
            step = "setting the mesh size"
            breaks = _breaks(body, patch, ext, joints) if sagitta else None
            n_obs, n_col, capped = _size_field(gmsh, body, patch, ext, spec, h_e, breaks)
            if n_obs == 0:
                raise MeshingError("the patch edges were not found on the body surface")
            if wall is not None:
                gmsh.model.mesh.setSizeCallback(_wall_size(body, wall))
            # measured on a 51 x 39 patch: HXT without gmsh's full optimiser meshes in 3-4 s
            # (Delaunay 4-6 s, HXT + optimiser 10-20 s); a cheap pass on tets with quality
            # gamma < 0.2 then removes the slivers (min gamma 0.07 instead of 1e-24).
            set_mesh_options(gmsh, algorithm3d, ("Mesh.LcIntegrationPrecision", 1e-3))
            t1 = time.perf_counter()
            step = "meshing"
            min_area = (1e-2 * h_e) ** 2
            try:
                gmsh.model.mesh.generate(3)
            except Exception:
                if _unmeshed(gmsh, min_area)[0]:
                    raise _Unmeshed(*_unmeshed(gmsh, min_area)) from None
                raise
            if not _has_tetrahedra(gmsh):
                raise _NoTetrahedra()
            faces, volumes = _unmeshed(gmsh, min_area)
            if faces or volumes:
                raise _Unmeshed(faces, volumes)
            if spec.optimize:
                gmsh.option.setNumber("Mesh.OptimizeThreshold", 0.2)
                gmsh.model.mesh.optimize("")
            t2 = time.perf_counter()
            step = "reading the mesh"
            pts, tets, free, clamped = _extract(gmsh, body, ext, h_e)
        except (MeshingError, _NoTetrahedra, _Unmeshed):
            raise
        except Exception as exc:  # gmsh raises plain Exceptions with its last error message
            if step == "meshing" and algorithm3d != 1:
                raise _NoTetrahedra() from None
            raise MeshingError(f"gmsh failed while {step} ({body.kind} body, {patch.ms} x "
                               f"{patch.n_columns} patch): {exc}") from None
    finally:
        gmsh.finalize()
        _restore_sigpipe()
    return pts, tets, free, clamped, t1, t2, capped


def _restore_sigpipe() -> None:
    """gmsh.initialize() resets SIGPIPE to its default action (terminate the process) behind
    Python's back, which ignores it (a write to a closed pipe then raises BrokenPipeError): a
    later write to a pipe whose reader has gone (a helper process that finished) would kill the
    whole process silently (exit 141).  Put back what Python has set (main thread only: the
    signal disposition can only be set there)."""
    import signal
    import threading

    if hasattr(signal, "SIGPIPE") and threading.current_thread() is threading.main_thread():
        handler = signal.getsignal(signal.SIGPIPE)
        if handler is not None:
            signal.signal(signal.SIGPIPE, handler)


def closure_report(original, body: BodyModel, patch: StripPatch, ext: BodyExtent, size: float,
                   points: np.ndarray | None = None, slab: bool = False) -> dict:
    """What the body is, for the FE statistics and the solve's JSON: the disc radius it has
    (``disc_radius_mm``) and its margin beyond the patch (``margin_mm``) against the
    ``size`` patch sizes asked for (``margin_requested_mm``); at each end of the ``original``
    profile the closure: ``"profile"`` (the profile reaches the disc), ``"extended"`` (continued
    straight along its end tangent, ``extension_lo_mm`` / ``extension_hi_mm`` of it inside the
    body) or ``"cut"`` (a straight cut from the profile's end to the disc's arc); what limited
    the margin where it is smaller than asked for (``margin_limited_by``: ``"wheel radius"``,
    ``"section width"`` (``slab``: a section whose ends point the same way, see
    bodies.grow_profile), ``"profile end"`` or ``""``).  With ``points`` (the mesh nodes) also what the mesher built: ``mesh_reach_mm``,
    the largest distance of a node from the disc's centre in the cross-section."""
    lo = max(0.0, float(original.s[0] - ext.s_lo))
    hi = max(0.0, float(ext.s_hi - original.s[-1]))
    out = {"disc_radius_mm": float(ext.radius), "margin_mm": float(ext.depth),
           "margin_requested_mm": float(size * patch.size),
           "closure_lo": "section" if ext.closed else "cut" if ext.cut_lo else ("extended" if lo > 0 else "profile"),
           "closure_hi": "section" if ext.closed else "cut" if ext.cut_hi else ("extended" if hi > 0 else "profile"),
           "extension_lo_mm": lo, "extension_hi_mm": hi,
           "margin_limited_by": ("wheel radius" if ext.wheel_limited else "section width" if slab else
                                 "profile end" if ext.depth < size * patch.size * (1 - 1e-9) else "")}
    if points is not None:
        _, yz = cross_section_coordinates(body, ext, points)
        out["mesh_reach_mm"] = float(np.max(np.linalg.norm(yz - np.asarray(ext.centre), axis=1)))
    return out


#: the most mesh nodes on the contact patch's surface alone (the FE solve's memory check, about
#: 25 kB per unknown, refuses far fewer; this bound stops gmsh before it meshes for hours)
MAX_PATCH_NODES = 1_000_000


def check_patch_nodes(patch: StripPatch, spec: MeshSpec, h_e: float, size_key: str | None = None) -> None:
    """Refuse (InputError naming ``[model] fe_h_patch`` / ``fe_h_load``, or ``size_key``: the key
    that set the element size, e.g. the direct FE contact's ``[model.fe_contact] n``) element sizes
    that put more than MAX_PATCH_NODES nodes on the patch's surface (its area over the element size
    squared), before gmsh is started: ``fe_h_patch = 1e-6`` meshed without end."""
    area = patch.mx * patch.dx * float(patch.s_edges[-1] - patch.s_edges[0])
    for name, rel, what in (("fe_h_patch", spec.h_patch, area),
                            ("fe_h_load", spec.h_load, patch.dx * float(patch.s_edges[-1] - patch.s_edges[0]))):
        if rel is None:
            continue
        n = what / (rel * h_e) ** 2
        if n <= MAX_PATCH_NODES:
            continue
        if size_key is not None:
            raise InputError(f"{size_key}: elements of {rel * h_e:.3g} mm put about {n:.3g} mesh nodes on the "
                             f"patch, more than {MAX_PATCH_NODES:,}; use larger elements (at least "
                             f"{math.sqrt(what / MAX_PATCH_NODES):.3g} mm)")
        least = math.sqrt(what / MAX_PATCH_NODES) / h_e
        raise InputError(f"[model] {name}: {rel:g} contact elements ({rel * h_e:.3g} mm) puts about {n:.3g} "
                         f"mesh nodes on the patch, more than {MAX_PATCH_NODES:,}; use {name} >= {least:.3g}")


def mesh_body(body: BodyModel, patch: StripPatch, spec: MeshSpec = MeshSpec(),
              extent: BodyExtent | None = None, *, threads: int = 1, algorithm3d: int | None = None,
              size_key: str | None = None) -> BodyMesh:
    """Build and mesh one body for a patch (gmsh, OpenCASCADE).  Raises MeshingError on failure.

    ``algorithm3d``: gmsh's 3-D mesher; None (default) HXT (10), and gmsh's Delaunay (1) where HXT
    leaves the volume empty; 1: Delaunay only.  With ``conform = "all"`` the body is swept in
    slabs one column (dx) thick that span the whole cross-section, whose faces carry triangles
    up to h_max (tens of dx) far from the patch; HXT's boundary recovery then inserts Steiner
    points on the surface mesh ("Steiner point inserted that splits an existing edge (boundary
    mesh has changed ...)", an unfinished path of gmsh 4.15's HXT) and aborts the process
    (heap corruption / SIGSEGV, deterministic; S1002/UIC60 at 6.2 and 6.25 mm and the deep pair,
    n = 24): such bodies need ``algorithm3d = 1``, which recovers them.

    ``threads = 1`` (default) makes the mesh reproducible: gmsh's HXT mesher with 2 threads gave a
    different mesh on every run (node counts differing by one or two, influence numbers by up to
    5e-4 of the kernel maximum) and now and then aborted the process; single-threaded it gives
    the same mesh every time and was no slower here (2.4-3.1 s against 3.3-5.5 s on a 16 x 16
    wheel patch on a busy 2-core machine).
    """
    import gmsh

    original = body.profile
    joints: tuple[float, ...] = ()
    size = spec.body_size
    wall = None
    if spec.closure == "section":
        from conformal.meshing.wall import wall_cap

        # the section is the profile closed by its straight support edge (bodies.section_profile)
        wall = wall_cap(np.column_stack([original.y, original.z]), spec.h_wall, spec.growth, corner=WALL_CORNER)
    if extent is None:
        if spec.closure == "section":
            ext = closed_section_extent(body, patch, spec.body_size)
            # the section's straight edges (web, foot, rim faces) stay lines: split the curve at
            # the ends of every segment much longer than the profile's sampling
            seg = np.diff(original.s)
            long = np.flatnonzero(seg > 10.0 * np.median(seg))
            joints = tuple(sorted({float(v) for v in np.concatenate([original.s[long], original.s[long + 1]])}))
        elif spec.closure in ("extend", "straight"):
            body, closure = grow_profile(body, patch, spec.body_size, limit_slab=spec.closure == "extend")
            joints = tuple(float(v) for v in (original.s[0], original.s[-1]))
            size = closure.size
        if spec.closure != "section":
            ext = body_extent(body, patch, size)
    else:
        ext = extent
    h_e = min(patch.dx, float(patch.s_widths.min()))
    check_patch_nodes(patch, spec, h_e, size_key)       # size_key: the key that set the sizes (default fe_h_*)
    t0 = time.perf_counter()
    # HXT (fast) first; where it cannot recover the surface mesh ("failed to recover constrained
    # triangles", S1002 at a 5 mm shift) it leaves gmsh unusable ("I'm busy"), so the whole model
    # is built again for gmsh's Delaunay mesher (slower, more tolerant)
    if algorithm3d not in (None, 1):
        raise InputError(f"mesh_body: algorithm3d must be None (HXT, Delaunay fallback) or 1, got {algorithm3d!r}")

    def attempt(sagitta):
        try:
            if algorithm3d == 1:
                raise _NoTetrahedra()
            return _generate(gmsh, body, patch, ext, spec, h_e, threads, 10, joints, wall, sagitta)
        except _NoTetrahedra:
            return _generate(gmsh, body, patch, ext, spec, h_e, threads, 1, joints, wall, sagitta)

    # a surface gmsh cannot mesh: on a wheel, a strip (a grid row) of a steep flank revolved with
    # elements so long that their chords cross the strip (sagitta_sizes); the body is meshed
    # again with the sweep's elements bounded there.  Bodies meshed at the first try keep their
    # mesh (and the cached influence numbers theirs).
    h_max = max(spec.h_max * ext.depth, spec.h_patch * h_e)
    try:
        pts, tets, free, clamped, t1, t2, capped = attempt(False)
    except _Unmeshed as first:
        bounded = bool(np.any(sagitta_sizes(body, _breaks(body, patch, ext, joints)) < h_max))
        try:
            if not bounded:
                raise first
            pts, tets, free, clamped, t1, t2, capped = attempt(True)
        except _Unmeshed as exc:
            raise MeshingError(f"gmsh could not mesh the {body.kind} body: no elements in {len(exc.faces)} "
                               f"surface(s) and {len(exc.volumes)} volume(s)"
                               + (" (also with the sweep's elements bounded by their sagitta)" if bounded else "")
                               + "; try other [model] fe_h_max, fe_growth or fe_body_size") from None
    if len(tets) == 0:
        raise MeshingError(f"gmsh produced no tetrahedra for the {body.kind} body")
    tets = _drop_flat(pts, tets, body)
    tets = _orient(pts, tets)
    uv = np.full((len(pts), 2), np.nan)
    fn = np.unique(free)
    x, yz = cross_section_coordinates(body, ext, pts[fn])
    uv[fn, 0] = x
    uv[fn, 1] = body.profile.project(yz, ext.s_lo, ext.s_hi)
    # the free surface must cover the whole body surface x_lo..x_hi, s_lo..s_hi (else observation
    # points may fall into holes); a misclassified face shows up here, not as a failed point location
    span = np.array([[ext.x_lo, ext.s_lo], [ext.x_hi, ext.s_hi]])
    got = np.array([np.min(uv[fn], axis=0), np.max(uv[fn], axis=0)])
    if np.max(np.abs(got - span)) > 1e-3 * max(1.0, ext.depth):
        raise MeshingError(f"the free surface of the {body.kind} body covers x = {got[0, 0]:.3f} .. {got[1, 0]:.3f}, "
                           f"s = {got[0, 1]:.3f} .. {got[1, 1]:.3f} mm instead of x = {ext.x_lo:.3f} .. "
                           f"{ext.x_hi:.3f}, s = {ext.s_lo:.3f} .. {ext.s_hi:.3f} mm")
    stats = {"geometry_s": t1 - t0, "mesh_s": t2 - t1, "nodes": len(pts), "tets": len(tets),
             "free_tris": len(free), "clamped_tris": len(clamped), "h_element": h_e, "sagitta_strips": capped,
             **closure_report(original, body, patch, ext, spec.body_size, pts, slab=size < spec.body_size)}
    if wall is not None:
        stats.update(wall_fraction=float(spec.h_wall), wall_thickness_min_mm=float(np.nanmin(wall.thickness)))
    return BodyMesh(body, patch, ext, spec, pts, tets, free, clamped, uv, stats)
