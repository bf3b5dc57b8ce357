"""Tetrahedral meshes of whole-section bodies (the rail with head, web and foot; the wheel's rim and
web) for the FE contact ground truth (``[model] fec_body = "section"``).

A closed cross-section (:class:`conformal.geometry.sections.Section`) is extruded along x (rail,
``x_lo .. x_hi``) or revolved about the axle over a sector (wheel, ``x_lo .. x_hi`` of arc length at
the reference radius), in pieces between the cuts at the slave box and the fine patch, so that the
finely meshed patch and the slave surface are faces of their own.  The mesh size is ``h0`` on the
patch face and grows linearly with the distance from it (``growth`` per mm) up to ``h_max`` (mm):
gmsh's Distance field from the patch surface and a Threshold field.

Boundary faces: ``clamped_tris`` are the section's clamped edges swept (the rail's foot, the
wheel's hub face) and the two end faces (rail ends, sector cuts); ``free_tris`` are the profile
faces inside the slave box (the contact candidates, with (x, s) coordinates in ``uv``); every
other face (the rest of the profile, the web, the foot's upper face, the rim faces) is free of
traction and carries no contact.  gmsh is not thread-safe: one model per process, always finalised.
"""
from __future__ import annotations

import math
import time

import numpy as np

from conformal.errors import InputError
from conformal.geometry.sections import Section
from conformal.meshing.bodies import BodyExtent, BodyModel, StripPatch
from conformal.meshing.gmsh_body import (BodyMesh, MeshingError, MeshSpec, _drop_flat, _orient,
                                         _restore_sigpipe, cross_section_coordinates, graded_size,
                                         profile_curves, set_mesh_options, sweep_pieces)


def _segment_distance(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip((q - a) @ ab / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(a + t[:, None] * ab - q, axis=1)


def section_extent(body: BodyModel, patch: StripPatch, x_lo: float, x_hi: float, margin: float) -> BodyExtent:
    """The :class:`BodyExtent` of a section body: x range, the whole profile, ``depth`` = a measure of
    the contact region (the pairing reach is a quarter of it), the wheel's reference radius."""
    prof = body.profile
    s_mid = 0.5 * (patch.edges[0] + patch.edges[-1])
    c = prof.point(s_mid)
    r_ref = float(body.radius_at(s_mid)) if body.revolved else None
    p0, p1 = prof.point(0.0), prof.point(prof.length)
    return BodyExtent(float(x_lo), float(x_hi), 0.0, float(prof.length), float(margin), (float(c[0]), float(c[1])),
                      float(margin), (float(p0[0]), float(p0[1])), (float(p1[0]), float(p1[1])),
                      (float(c[0]), float(c[1])), False, False, r_ref)


def mesh_section_body(body: BodyModel, section: Section, patch: StripPatch, slave: tuple[float, float, float],
                      x_range: tuple[float, float], *, h0: float, growth: float, h_max: float,
                      reach: float) -> BodyMesh:
    """Mesh a whole-section body.

    Parameters
    ----------
    body : the body (its profile must be ``section.profile``: the same arc length s).
    section : the closed cross-section.
    patch : the finely meshed patch (|x| <= its half length, s between its edges).
    slave : (x_half, s_lo, s_hi), the contact candidate surface (contains the patch).
    x_range : (x_lo, x_hi) of the body (rail length; wheel sector as arc length at the patch radius).
    h0, growth, h_max : element size on the patch (mm), its growth per mm of distance, the largest
        element (mm).
    reach : the pairing reach is reach / 4 (``BodyExtent.depth``).
    """
    import gmsh

    prof = body.profile
    P = section.profile
    if len(P) != len(prof.y) or not np.allclose(np.column_stack([prof.y, prof.z]), P, atol=1e-9):
        raise InputError(f"{body.kind} section: its profile is not the body's profile")
    x_lo, x_hi = (float(v) for v in x_range)
    xp = 0.5 * patch.mx * patch.dx
    xs, ss_lo, ss_hi = (float(v) for v in slave)
    sp_lo, sp_hi = float(patch.edges[0]), float(patch.edges[-1])
    ss_lo, ss_hi = max(ss_lo, 1e-6 * prof.length), min(ss_hi, prof.length * (1 - 1e-6))
    if not (x_lo < -xs <= -xp < 0 < xp <= xs < x_hi and ss_lo <= sp_lo < sp_hi <= ss_hi):
        raise InputError(f"{body.kind} section body: need x_lo < slave < patch and the patch inside the slave "
                         f"surface (x: {x_lo:g} / {xs:g} / {xp:g}, s: {ss_lo:g} / {sp_lo:g} .. {sp_hi:g} / {ss_hi:g})")
    ext = section_extent(body, patch, x_lo, x_hi, reach)
    r_ref = ext.x_ref_radius
    if body.revolved and (x_hi - x_lo) / r_ref > 1.9 * math.pi:
        raise InputError("wheel section body: the sector exceeds the wheel; reduce [model] fec_section_size")
    t0 = time.perf_counter()
    if gmsh.isInitialized():
        gmsh.finalize()
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.add("section_body")
        occ = gmsh.model.occ
        x0 = 0.0 if body.revolved else x_lo

        def pt(y, z):
            return occ.addPoint(x0, float(y), float(z))

        breaks = np.unique(np.array([0.0, ss_lo, sp_lo, sp_hi, ss_hi, prof.length]))
        pieces = prof.pieces(breaks)
        curves, corner = profile_curves(occ, pieces, pt)
        first, last = corner[0], corner[-1]
        for q in section.closure:
            nxt = pt(*q)
            curves.append(occ.addLine(last, nxt))
            last = nxt
        curves.append(occ.addLine(last, first))
        face = occ.addPlaneSurface([occ.addCurveLoop(curves)])
        xs_cuts = np.array([x_lo, -xs, -xp, xp, xs, x_hi])
        xs_cuts = np.unique(xs_cuts)
        sweep_pieces(occ, face, body, xs_cuts, x0, r_ref)
        # the patch faces: a point of each surface (mid-parameter) on the profile inside the patch
        tol = 1e-3 * max(1.0, h0)
        patch_faces = []
        for _, s in gmsh.model.getEntities(2):
            lo, hi = gmsh.model.getParametrizationBounds(2, s)
            q = np.array(gmsh.model.getValue(2, s, [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]))
            xq, yz = cross_section_coordinates(body, ext, q[None, :])
            sq = prof.project(yz)
            on = np.linalg.norm(prof.point(sq) - yz, axis=-1) < 0.05 * h0 + 1e-3
            if on[0] and sp_lo - tol < sq[0] < sp_hi + tol and abs(xq[0]) < xp + tol:
                patch_faces.append(s)
        if not patch_faces:
            raise MeshingError(f"{body.kind} section body: the patch faces were not found")
        fld = gmsh.model.mesh.field
        size = max(2 * xp, sp_hi - sp_lo)
        fld.setAsBackgroundMesh(graded_size(fld, 1, patch_faces, "SurfacesList",
                                            int(min(300, max(20, 3 * size / h0))), h0, h_max, growth))
        set_mesh_options(gmsh, 10, ("Mesh.MeshSizeMax", h_max), ("Mesh.MeshSizeMin", h0))
        t1 = time.perf_counter()
        try:
            gmsh.model.mesh.generate(3)
        except Exception:                   # HXT failed to recover the surface: Delaunay instead
            gmsh.option.setNumber("Mesh.Algorithm3D", 1)
            gmsh.model.mesh.clear()
            gmsh.model.mesh.generate(3)
        gmsh.option.setNumber("Mesh.OptimizeThreshold", 0.2)
        gmsh.model.mesh.optimize("")
        t2 = time.perf_counter()
        pts, tets, free, clamped = _extract(gmsh, body, section, ext, (xs, ss_lo, ss_hi), h0)
    except (MeshingError, InputError):
        raise
    except Exception as exc:
        raise MeshingError(f"gmsh failed on the {body.kind} section body: {exc}") from None
    finally:
        gmsh.finalize()
        _restore_sigpipe()
    tets = _orient(pts, _drop_flat(pts, tets, body))
    uv = np.full((len(pts), 2), np.nan)
    fn = np.unique(free)
    x, yz = cross_section_coordinates(body, ext, pts[fn])
    uv[fn, 0] = x
    uv[fn, 1] = prof.project(yz, ss_lo, ss_hi)
    stats = {"geometry_s": t1 - t0, "mesh_s": t2 - t1, "nodes": len(pts), "tets": len(tets),
             "free_tris": len(free), "clamped_tris": len(clamped), "h_element": h0,
             "section": section.name, "x_range": [x_lo, x_hi], "slave": [xs, ss_lo, ss_hi]}
    spec = MeshSpec(order=1, h_patch=1.0, h_load=None, growth=growth, h_max=1.0, conform="none",
                    body_size=1.0)
    return BodyMesh(body, patch, ext, spec, pts, tets, free, clamped, uv, stats)


def _extract(gmsh, body: BodyModel, section: Section, ext: BodyExtent, slave, h0: float):
    """Nodes, tetrahedra and the classified boundary triangles (see the module docstring)."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(tags)
    tags = tags[order]
    pts = coords.reshape(-1, 3)[order]
    types, _, conn = gmsh.model.mesh.getElements(3)
    tets = [c.reshape(-1, 4) for t, c in zip(types, conn) if t == 4]
    if not tets:
        raise MeshingError(f"gmsh produced no tetrahedra for the {body.kind} section body")
    tets = np.searchsorted(tags, np.concatenate(tets))
    used = np.unique(tets)
    xs, ss_lo, ss_hi = slave
    prof = body.profile
    tol_x = 1e-6 * max(1.0, ext.x_hi - ext.x_lo)
    tol = max(1e-3, 0.02 * h0)
    P = section.points
    clamped_segs = [(P[i], P[(i + 1) % len(P)]) for i in section.clamped]
    free, clamped = [], []
    for _, s in gmsh.model.getBoundary(gmsh.model.getEntities(3), oriented=False):
        types, _, conn = gmsh.model.mesh.getElements(2, s)
        conn = [c for t, c in zip(types, conn) if t == 2]
        if not conn:
            continue
        tri = np.searchsorted(tags, np.concatenate(conn).reshape(-1, 3))
        nodes = np.unique(tri)
        x, yz = cross_section_coordinates(body, ext, pts[nodes])
        if np.all(np.abs(x - ext.x_lo) < tol_x) or np.all(np.abs(x - ext.x_hi) < tol_x):
            clamped.append(tri)
            continue
        if any(np.all(_segment_distance(yz, a, b) < tol) for a, b in clamped_segs):
            clamped.append(tri)
            continue
        sq = prof.project(yz)
        on = np.linalg.norm(prof.point(sq) - yz, axis=-1) < tol
        if on.all() and np.all(np.abs(x) < xs + tol) and np.all((sq > ss_lo - tol) & (sq < ss_hi + tol)):
            free.append(tri)
    if not free or not clamped:
        raise MeshingError(f"{body.kind} section body: no {'slave' if not free else 'clamped'} faces found")
    new = -np.ones(len(pts), dtype=np.int64)
    new[used] = np.arange(used.size)
    return pts[used], new[tets], new[np.concatenate(free)], new[np.concatenate(clamped)]
