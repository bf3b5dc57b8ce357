"""Meshed bodies for the direct FE contact solve: Hertzian pairs and the wheel and rail of a
curved (conformal) contact problem.

Everything is in the common contact frame of :mod:`conformal.meshing.bodies` (x rolling, y
lateral, z DOWN into body 1).  Body 1 (block or rail) lies below its surface, body 2 (a wheel:
a body of revolution about an axle along y) above it.  The surfaces are meshed with a uniform
size ``h`` on the potential contact area (a :class:`~conformal.meshing.bodies.StripPatch` of
square cells of size h whose row edges drive gmsh's size field) that grows linearly away from
it (``growth``) up to ``h_max`` times the body depth; the bodies reach ``body_size`` patch
sizes beyond the patch.

Mesh refinement (the scene's ``[model]`` keys, see :class:`ContactMesh`): ``fec_n`` elements per
contact semi-axis (default 4, with quadratic elements), or ``fec_h`` in mm; ``fec_growth`` (0.3),
``fec_h_max`` (0.25), ``fec_body_size`` (1.0), ``fec_patch`` (1.3: the fine patch reaches 1.3
semi-axes).

>>> b1, b2 = sphere_on_block(50.0, (2.0, 2.0), n=2)
>>> b1.mesh.body.kind, b2.mesh.body.kind
('block', 'wheel')
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from conformal.errors import InputError
from conformal.fe_contact.solver import ContactBody
from conformal.materials import Material
from conformal.meshing.bodies import BodyModel, Profile2D, StripPatch, flat_profile
from conformal.meshing.gmsh_body import MAX_PATCH_NODES, MeshSpec, mesh_body

STEEL = Material(82000.0, 0.28, 82000.0, 0.28)


#: the largest [model] fec_n (elements per contact semi-axis): 50 already meshes millions of elements
MAX_N = 50


@dataclass(frozen=True)
class ContactMesh:
    """Mesh refinement of the FE contact bodies.

    n : elements per contact semi-axis (the smaller one) on the contact surface, used when ``h``
        is None.
    h : element size on the potential contact area (mm), overrides ``n``.
    growth : increase of the element size per mm of distance from the patch.
    h_max : largest element, relative to the body depth.
    body_size : margin of each body beyond the patch, in patch sizes.
    patch : the finely meshed patch reaches ``patch`` contact semi-axes from the centre (Hertz;
        wheel-rail: ``patch`` times the half extents of the half-space estimate of the contact).
    estimate : wheel-rail scenes: "halfspace" (contact semi-axis and fine patch from a half-space
        solve on the same grid, :func:`conformal.cases.fe_contact.contact_estimate`) or "grid"
        (the whole grid; semi-axis: half its smaller extent / 1.1).
    body : wheel-rail scenes: "disc" (the profile inside a disc around the patch, cut faces with the
        half-space field or clamped) or "section" (the ground truth: the whole rail section and the
        wheel's rim and web, clamped far away, :func:`section_pair`) or "block" (solid blocks around
        both profiles, their ends continued straight, clamped far away: large bodies without the
        thin web, :func:`~conformal.geometry.sections.block_section`).
    section_size : "section" bodies: the rail's ends and the wheel's sector cuts lie this many
        patch sizes beyond the patch (on each side).
    section_h_max : "section" bodies: the largest element (mm).
    slave : wheel-rail bodies ("disc" and "section"): the contact candidate surface is the patch
        enlarged by this factor (its half extents; :func:`slave_region`).
    """

    n: int = 4
    h: float | None = None
    growth: float = 0.3
    h_max: float = 0.25
    body_size: float = 1.0
    patch: float = 1.3
    estimate: str = "halfspace"
    body: str = "disc"
    section_size: float = 20.0
    section_h_max: float = 12.0
    slave: float = 1.6

    def __post_init__(self):
        if self.body not in ("disc", "section", "block"):
            raise InputError(f"[model] fec_body: must be \"disc\", \"section\" or \"block\", got {self.body!r}")
        if self.estimate not in ("halfspace", "grid"):
            raise InputError(f"[model] fec_estimate: must be \"halfspace\" or \"grid\", got {self.estimate!r}")
        if isinstance(self.n, bool) or not isinstance(self.n, int) or not 1 <= self.n <= MAX_N:
            raise InputError(f"[model] fec_n: must be a whole number from 1 to {MAX_N} (elements per contact "
                             f"semi-axis; 4-8 are usual), got {self.n!r}")
        for name in ("growth", "h_max", "body_size", "patch", "section_size", "section_h_max", "slave") + (
                ("h",) if self.h is not None else ()):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v > 0):
                raise InputError(f"[model] fec_{name}: must be a number > 0, got {v!r}")
        if self.slave < 1.0:
            raise InputError(f"[model] fec_slave: must be >= 1 (the contact candidates cover the patch enlarged by "
                             f"this factor), got {self.slave!r}")

    def size(self, semi_axis: float) -> float:
        """Element size on the contact patch for a contact of this (smaller) semi-axis."""
        return float(self.h) if self.h is not None else semi_axis / self.n

    def spec(self) -> MeshSpec:
        """gmsh parameters (sizes relative to h; the element order is the solver's)."""
        return MeshSpec(order=1, h_patch=1.0, h_load=None, growth=self.growth, h_max=self.h_max,
                        conform="none", body_size=self.body_size)


def strip_patch(x_half: float, s_lo: float, s_hi: float, h: float) -> StripPatch:
    """A patch of cells of about h x h covering |x| <= x_half and s_lo <= s <= s_hi."""
    if not (h > 0 and x_half > 0 and s_hi > s_lo):
        raise InputError(f"contact patch: need h > 0 and a non-empty patch, got h = {h}, x_half = {x_half}, "
                         f"s = {s_lo} .. {s_hi}")
    cells = (2.0 * x_half / h) * ((s_hi - s_lo) / h)
    if not cells <= MAX_PATCH_NODES:         # fec_h = 1e-6: the patch's edges alone filled the memory
        raise InputError(f"[model.fe_contact] n (or h): elements of {h:.3g} mm put about {cells:.3g} cells on the "
                         f"contact patch, more than {MAX_PATCH_NODES:,}; use larger elements (at least "
                         f"{math.sqrt(2.0 * x_half * (s_hi - s_lo) / MAX_PATCH_NODES):.3g} mm)")
    mx = max(1, math.ceil((2.0 * x_half / h + 1.0) / 2.0))
    ms = max(1, math.ceil((s_hi - s_lo) / h))
    return StripPatch(mx, h, tuple(float(v) for v in np.linspace(s_lo, s_hi, ms + 1)))


def _arc_profile(radius: float, half_width: float, sign: float, name: str, n: int = 241) -> Profile2D:
    """z = sign (R - sqrt(R² - y²)) for |y| <= half_width (sign -1: a crown facing down, +1: up)."""
    y = np.linspace(-half_width, half_width, n)
    return Profile2D(y, sign * (radius - np.sqrt(radius * radius - y * y)), name)


def _check_radius(name: str, R: float) -> float:
    if not (isinstance(R, (int, float)) and math.isfinite(R) and R > 0):
        raise InputError(f"{name}: must be a radius > 0 (mm), got {R!r}")
    return float(R)


def _semi_axes(semi_axes) -> tuple[float, float]:
    a, b = (float(v) for v in semi_axes)
    if not (a > 0 and b > 0 and math.isfinite(a) and math.isfinite(b)):
        raise InputError(f"contact semi-axes: must be > 0 (mm), got {semi_axes!r}")
    return a, b


def quadratic_pair(A: float, B: float, semi_axes: tuple[float, float], material: Material = STEEL,
                   mesh: ContactMesh = ContactMesh()) -> tuple[ContactBody, ContactBody]:
    """A flat block (body 1) and a crowned wheel (body 2, rolling radius 1/(2A), transverse radius
    1/(2B)) touching at the origin: the undeformed distance is A x² + B y² + O(r⁴/R³).  The patch
    is sized from the expected contact semi-axes (a along x, b along y; e.g. Hertz's)."""
    a, b = _semi_axes(semi_axes)
    Rx = _check_radius("rolling radius 1/(2A)", 1.0 / (2.0 * A) if A > 0 else -1.0)
    Ry = _check_radius("transverse radius 1/(2B)", 1.0 / (2.0 * B) if B > 0 else -1.0)
    h = mesh.size(min(a, b))
    Lx, Ly = mesh.patch * a, mesh.patch * b
    patch = strip_patch(Lx, -Ly, Ly, h)
    margin = mesh.body_size * patch.size
    Y = Ly + 1.5 * margin
    if Y >= 0.7 * Ry or margin >= 0.5 * Rx:
        raise InputError(f"quadratic pair: the contact (a = {a:.3g}, b = {b:.3g} mm) is too large for "
                         f"the radii {Rx:.3g}, {Ry:.3g} mm; reduce the load or [model] fec_body_size")
    block = BodyModel("block", flat_profile(-2 * Y, 2 * Y))
    wheel = BodyModel("wheel", _arc_profile(Ry, Y, -1.0, "crown"), axle_z=-Rx)
    return _pair(block, _shift(patch, 2 * Y), wheel, _arc_patch(patch, wheel.profile), material, mesh)


def _shift(patch: StripPatch, s0: float) -> StripPatch:
    """The same patch with its arc lengths measured from a profile start s0 earlier."""
    return StripPatch(patch.mx, patch.dx, tuple(v + s0 for v in patch.s_edges))


def _arc_patch(patch: StripPatch, prof: Profile2D) -> StripPatch:
    """Patch given in y (centred on y = 0) mapped to the arc length of ``prof``."""
    yz = np.column_stack([np.asarray(patch.s_edges), np.interp(patch.s_edges, prof.y, prof.z)])
    return StripPatch(patch.mx, patch.dx, tuple(float(v) for v in prof.project(yz)))


def _pair(b1: BodyModel, p1: StripPatch, b2: BodyModel, p2: StripPatch, material: Material, mesh: ContactMesh,
          rotation2=None, origin2=None) -> tuple[ContactBody, ContactBody]:
    key = "[model.fe_contact] n (or h)"       # the contact-surface element size of these meshes
    m1 = mesh_body(b1, p1, mesh.spec(), size_key=key)
    m2 = mesh_body(b2, p2, mesh.spec(), size_key=key)
    kw = {} if rotation2 is None else {"rotation": rotation2, "origin": origin2}
    return (ContactBody(m1, material.G1, material.nu1),
            ContactBody(m2, material.G2, material.nu2, **kw))


def sphere_on_block(radius: float, semi_axes: tuple[float, float], *, material: Material = STEEL,
                    mesh: ContactMesh | None = None, n: int | None = None) -> tuple[ContactBody, ContactBody]:
    """A sphere of ``radius`` (body 2) on a flat block (body 1), meshed for a contact of the given
    semi-axes (mm, e.g. Hertz's: a = sqrt(R delta)).  ``n`` overrides ``mesh.n``.

    >>> b1, b2 = sphere_on_block(50.0, (2.0, 2.0), n=2)
    >>> b2.mesh.body.axle_z
    -50.0
    """
    R = _check_radius("radius", radius)
    mesh = mesh or ContactMesh()
    if n is not None:
        mesh = replace(mesh, n=n)
    A = 1.0 / (2.0 * R)
    return quadratic_pair(A, A, semi_axes, material, mesh)


def crossed_cylinders(r1: float, r2: float, semi_axes: tuple[float, float], *, material: Material = STEEL,
                      mesh: ContactMesh | None = None, n: int | None = None) -> tuple[ContactBody, ContactBody]:
    """Two cylinders crossed at right angles: body 1 with its axis along x (transverse radius
    r1, a 'rail'), body 2 with its axis along y (radius r2, a wheel with a flat profile); the
    undeformed distance is x²/(2 r2) + y²/(2 r1), an elliptic Hertz contact of semi-axes
    ``semi_axes`` = (a along x, b along y) (mm).

    >>> b1, b2 = crossed_cylinders(40.0, 80.0, (2.3, 1.5), n=2)
    >>> b1.mesh.body.kind, b2.mesh.body.kind
    ('rail', 'wheel')
    """
    r1 = _check_radius("r1", r1)
    r2 = _check_radius("r2", r2)
    a, b = _semi_axes(semi_axes)
    mesh = mesh or ContactMesh()
    if n is not None:
        mesh = replace(mesh, n=n)
    h = mesh.size(min(a, b))
    Lx, Ly = mesh.patch * a, mesh.patch * b
    patch = strip_patch(Lx, -Ly, Ly, h)
    margin = mesh.body_size * patch.size
    Y = Ly + 1.5 * margin
    if Y >= 0.7 * r1 or margin >= 0.5 * r2:
        raise InputError(f"crossed cylinders: the contact is too large for the radii {r1:g}, {r2:g} mm")
    rail = BodyModel("rail", _arc_profile(r1, Y, 1.0, "cylinder"))
    wheel = BodyModel("wheel", flat_profile(-Y, Y), axle_z=-r2)
    return _pair(rail, _arc_patch(patch, rail.profile), wheel, _shift(patch, Y), material, mesh)


def wheel_rail_pair(grid, rail_points: np.ndarray, wheel_points: np.ndarray, material: Material,
                    mesh: ContactMesh = ContactMesh(), *, semi_axis: float | None = None,
                    box: tuple[float, float, float] | None = None) -> tuple[ContactBody, ContactBody]:
    """Rail (body 1, rail-profile frame) and wheel (body 2, placed by the grid's wheel position)
    around the potential contact area of a :class:`~conformal.grid.CurvedGrid`.

    ``semi_axis``: the smaller contact semi-axis (mm) that sets the element size with ``mesh.n``;
    default: half the smaller extent of the grid divided by 1.1 (the grid's usual margin).
    ``box`` = (x_half, s_lo, s_hi): the finely meshed patch, |x| <= x_half and s_lo <= s <= s_hi in
    the grid's arc length (e.g. an estimated contact area enlarged by ``mesh.patch``), clipped to
    the grid; default: the whole grid.
    """
    from conformal.influence.fe import wheel_axes, rail_body_from_grid, wheel_body_from_grid

    rail, rpatch = rail_body_from_grid(grid, rail_points)
    wheel, wpatch, _ = wheel_body_from_grid(grid, wheel_points)
    x_lo, x_hi = grid.xl, grid.xl + grid.mx * grid.dx
    x_half = max(abs(x_lo), abs(x_hi))
    if semi_axis is None:
        semi_axis = 0.5 * min(x_hi - x_lo, float(rpatch.edges[-1] - rpatch.edges[0])) / 1.1
    h = mesh.size(semi_axis)
    s_grid = np.asarray(grid.s_edges, dtype=float)
    s_lo, s_hi = float(s_grid[0]), float(s_grid[-1])
    if box is not None:
        bx, bs_lo, bs_hi = (float(v) for v in box)
        if not (bx > 0 and bs_hi > bs_lo):
            raise InputError(f"fe_contact patch: need x_half > 0 and s_lo < s_hi, got {box!r}")
        x_half = min(x_half, bx)
        s_lo, s_hi = max(s_lo, bs_lo), min(s_hi, bs_hi)
        if s_hi <= s_lo:
            raise InputError(f"fe_contact patch: s = {bs_lo:.3f} .. {bs_hi:.3f} mm lies outside the grid")
    # grid arc length -> arc length of each FE profile
    r_lo, r_hi = np.interp([s_lo, s_hi], s_grid, rpatch.edges)
    w_lo, w_hi = np.interp([s_lo, s_hi], s_grid, wpatch.edges)
    p1 = strip_patch(x_half, float(r_lo), float(r_hi), h)
    p2 = strip_patch(x_half, float(w_lo), float(w_hi), h)
    M = wheel_axes(grid)
    origin = np.asarray(grid.wheel_centre, dtype=float) + float(grid.wheel_radius) * M[:, 2]
    if mesh.body in ("section", "block"):
        return section_pair(rail, p1, wheel, p2, material, mesh, rotation2=M, origin2=origin)
    return _pair(rail, p1, wheel, p2, material, mesh, rotation2=M, origin2=origin)


def slave_box(patch: StripPatch, factor: float, x_half: float = 0.0) -> tuple[float, float, float]:
    """The contact candidates of a body around its finely meshed patch: (x_half, s_lo, s_hi), the
    patch's half extents (along x at least ``x_half``) times ``factor`` about its centre
    (``[model] fec_slave``)."""
    e = patch.edges
    c, half = 0.5 * (e[0] + e[-1]), 0.5 * (e[-1] - e[0])
    xp = max(0.5 * patch.mx * patch.dx, float(x_half))
    return factor * xp, c - factor * half, c + factor * half


def slave_region(patch: StripPatch, factor: float, x_half: float = 0.0):
    """The mask uv (n, 2) -> bool of the points inside :func:`slave_box` (the ``region`` of
    :func:`conformal.fe_contact.solver.prepare_contact`).

    Why a disc body needs it: its free surface reaches ``fec_body_size`` patch sizes from the
    contact, where the elements grow to tens of mm.  The dual multipliers (psi = 4 phi - 1) are not
    positive, so the weighted gap of a node on such a coarse triangle is not bounded by the gaps
    at its points and can come out negative where the surfaces stand apart; on the deep pair at
    16 patch sizes that put spurious contact (six times the real load) on nodes 100 mm away.
    The contact candidates, like those of the section bodies, are therefore the patch enlarged by
    ``fec_slave``.

    >>> inside = slave_region(StripPatch(4, 1.0, (0.0, 1.0, 2.0)), 1.5)
    >>> inside(np.array([[0.0, 1.0], [2.9, 1.0], [3.1, 1.0], [0.0, 2.6]])).tolist()
    [True, True, False, False]
    """
    xs, s_lo, s_hi = slave_box(patch, factor, x_half)

    def inside(uv: np.ndarray) -> np.ndarray:
        uv = np.asarray(uv, dtype=float)
        return (np.abs(uv[:, 0]) <= xs) & (uv[:, 1] >= s_lo) & (uv[:, 1] <= s_hi)

    return inside


def body_section(body: BodyModel, extension: float, block: bool = False):
    """The whole cross-section of a wheel-rail body (:mod:`conformal.geometry.sections`): the 60E1
    rail section under a symmetric UIC 60 / 60E1 head (ends on both flanks at the same depth,
    35 mm), the rim and web under a wheel profile that starts at its flange back (y = -70, as
    S1002 and the EN 13715 profiles); any other profile gets a clamped block (its ends continued
    straight by ``extension``, :func:`~conformal.geometry.sections.block_section`)."""
    from conformal.geometry.sections import block_section, uic60_section, wheel_rim_section

    P = np.column_stack([body.profile.y, body.profile.z])
    if block:
        return block_section(P, body.kind, extension)
    if body.kind == "rail":
        head = abs(P[0, 1] - P[-1, 1]) < 1e-6 and abs(P[0, 0] + P[-1, 0]) < 1e-3 and 30 < P[-1, 0] < 40
        if head and 30.0 <= P[-1, 1] < 39.0 and np.min(P[:, 1]) > -1e-3:
            return uic60_section(P)
        return block_section(P, "rail", extension)
    if abs(P[0, 0] + 70.0) < 0.5 and P[-1, 0] > P[0, 0] and P[-1, 0] < 65.0:
        return wheel_rim_section(P, -float(body.axle_z))
    return block_section(P, "wheel", extension)


def section_pair(rail: BodyModel, p1: StripPatch, wheel: BodyModel, p2: StripPatch, material: Material,
                 mesh: ContactMesh, rotation2=None, origin2=None) -> tuple[ContactBody, ContactBody]:
    """The ground-truth bodies: whole sections (:func:`body_section`) swept over ``mesh.section_size``
    patch sizes beyond the patch on each side (the rail's ends, the wheel sector's cuts), clamped
    there and at the foot / hub, graded from the patch element size with ``mesh.growth`` up to
    ``mesh.section_h_max`` (mm).  The contact candidates: the patch enlarged by ``mesh.slave``."""
    from conformal.meshing.section_body import mesh_section_body

    bodies = []
    for body, patch in ((rail, p1), (wheel, p2)):
        size = patch.size
        margin = mesh.section_size * size
        sec = body_section(body, margin, block=mesh.body == "block")
        if sec.n_profile != len(body.profile.y):
            raise InputError(f"{body.kind} section: profile mismatch")
        if body.revolved and float(sec.points[:, 1].min()) <= float(body.axle_z) + 10.0:
            raise InputError(f"wheel {sec.name}: reaches {-float(sec.points[:, 1].min()):.0f} mm towards the axle, "
                             f"beyond the wheel radius {-float(body.axle_z):.0f} mm; reduce [model] fec_section_size")
        xp = 0.5 * patch.mx * patch.dx
        slave = slave_box(patch, mesh.slave)
        xr = xp + margin
        # a solid block (no thin web) takes elements up to a tenth of its margin far away
        h_max = mesh.section_h_max if not sec.name.startswith("block") else max(mesh.section_h_max, 0.2 * margin)
        m = mesh_section_body(body, sec, patch, slave, (-xr, xr), h0=patch.dx, growth=mesh.growth,
                              h_max=max(h_max, patch.dx), reach=4.0 * size)
        m.stats["section_note"] = sec.note
        m.stats["margin_mm"] = margin
        bodies.append(m)
    kw = {} if rotation2 is None else {"rotation": rotation2, "origin": origin2}
    return (ContactBody(bodies[0], material.G1, material.nu1),
            ContactBody(bodies[1], material.G2, material.nu2, **kw))
