"""Element sizes of the whole-section FE bodies (``fe_closure = "section"``) tied to the local wall
thickness (conformal.meshing.wall): the local thickness of analytic sections, the cap gmsh really
builds in a thin web (measured on the tetrahedra, not the key), and the cache keys of the other
closures unchanged."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from conformal.errors import InputError
from conformal.meshing.bodies import BodyModel, StripPatch, section_profile
from conformal.meshing.gmsh_body import WALL_CORNER, MeshSpec, mesh_body
from conformal.meshing.wall import reentrant_corners, wall_cap

#: a T-shaped "rail": head 30 mm wide and 10 mm deep (its top the contact profile, sampled at
#: 0.5 mm), a web 8 mm thick down to z = 40 mm, whose lower end is the support edge
HEAD_W, HEAD_D, WEB_T, WEB_Z = 30.0, 10.0, 8.0, 40.0


def _t_section() -> tuple[np.ndarray, int, int]:
    top = np.column_stack([np.linspace(-15.0, 15.0, 61), np.zeros(61)])
    w = 0.5 * WEB_T
    rest = [(15.0, HEAD_D), (w, HEAD_D), (w, WEB_Z), (-w, WEB_Z), (-w, HEAD_D), (-15.0, HEAD_D)]
    P = np.vstack([top, rest])
    return P, len(top), len(top) + 2                     # support edge: (w, 40) -> (-w, 40)


def test_local_thickness_of_a_t_section_and_of_a_tapered_plate():
    P, _, _ = _t_section()
    cap = wall_cap(P, 1 / 3, 0.35)
    # the web and the head: their thickness, exactly on the mid-lines and across the wall
    np.testing.assert_allclose(cap.thickness_at([0.0, 3.5, -3.5, 0.0], [25.0, 25.0, 30.0, 38.0]), WEB_T, rtol=1e-9)
    np.testing.assert_allclose(cap.thickness_at([-12.0, 12.0, 8.0], [5.0, 1.0, 3.0]), HEAD_D, rtol=0.02)
    # the convex corners keep their wall's thickness (no vanishing disc at a corner)
    np.testing.assert_allclose(cap.thickness_at([14.8, -3.9], [0.2, 39.8]), [HEAD_D, WEB_T], rtol=0.02)
    # the cap: a third of the thickness in the web, graded (at most 0.35 per mm, chamfer metric
    # 8 % longer) towards the thicker part, never above the part's own third
    assert float(cap.at(0.0, 25.0)) == pytest.approx(WEB_T / 3, rel=1e-9)
    assert float(cap.at(-12.0, 5.0)) == pytest.approx(HEAD_D / 3, rel=1e-9)
    # a plate tapering from 10 to 20 mm over 100 mm: the thickness across it, within a cell
    taper = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 20.0], [0.0, 10.0]])
    c2 = wall_cap(taper, 0.25, 0.35)
    x = np.array([20.0, 50.0, 80.0])
    across = (10.0 + 0.1 * x) / np.sqrt(1 + 0.1 ** 2) ** 0           # the plate's height at x
    np.testing.assert_allclose(c2.thickness_at(x, 0.5 * across), across, rtol=0.02)
    with pytest.raises(InputError):
        wall_cap(P, 0.0, 0.35)


def test_reentrant_corners_are_refined():
    """The T section's two re-entrant corners (web into head, no fillet: a singular stress) and
    no others (the head's top is sampled, its convex corners are not re-entrant); the cap there
    falls to ``corner`` x the web's cap and grows at the growth rate away from them."""
    P, _, _ = _t_section()
    np.testing.assert_allclose(reentrant_corners(P), [[0.5 * WEB_T, HEAD_D], [-0.5 * WEB_T, HEAD_D]])
    np.testing.assert_allclose(reentrant_corners(P[::-1]), [[-0.5 * WEB_T, HEAD_D], [0.5 * WEB_T, HEAD_D]])
    cap = wall_cap(P, 0.25, 0.35, corner=0.25)
    at = float(cap.at(0.5 * WEB_T - 0.2, HEAD_D + 0.2))
    assert at == pytest.approx(0.25 * 0.25 * WEB_T, abs=0.35 * 1.5 * cap.spacing)
    # 5 mm down the web, away from the corner: the growth (chamfer metric, at most 8 % longer)
    far = float(cap.at(0.0, HEAD_D + 5.0))
    r = float(np.hypot(0.5 * WEB_T, 5.0))
    assert min(0.25 * WEB_T, 0.25 * 0.25 * WEB_T + 0.35 * r) <= far + 0.02 <= 0.25 * WEB_T + 0.02


def _web_edges(bm) -> np.ndarray:
    """Edge lengths of the tetrahedra whose four nodes lie in the web (clear of the head and of
    the support edge by 3 mm)."""
    p = bm.points
    y, z = p[:, 1], p[:, 2]
    in_web = (np.abs(y) <= 0.5 * WEB_T + 1e-9) & (z > HEAD_D + 3.0) & (z < WEB_Z - 3.0)
    t = bm.tets[np.all(in_web[bm.tets], axis=1)]
    e = np.concatenate([p[t[:, a]] - p[t[:, b]] for a, b in ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))])
    return np.linalg.norm(e, axis=1)


def test_section_mesh_obeys_the_web_cap():
    """What gmsh built in the web of a T section, against the cap (a third of the 8 mm web): the
    median tetrahedron edge within 1.3 x the cap and 95 % of them within 2 x (gmsh realises a
    size h with a median edge of 1.15-1.25 h and 95 % within 1.7-1.9 h: a box meshed at a constant
    2.67 mm, HXT and Delaunay, gmsh 4.15.2), while the same body without the cap (the contact
    grading and h_max alone) has a median edge over 2 x the cap there, as long as the web is
    thick."""
    P, n, support = _t_section()
    body = BodyModel("rail", section_profile(P, n, support, "T section"))
    patch = StripPatch.uniform(3, 1.0, 3, 1.0, 15.0)          # on the head's top at y = 0
    spec = replace(MeshSpec(), body_size=14.0, closure="section", h_wall=1 / 3)
    bm = mesh_body(body, patch, spec)
    assert bm.points[:, 2].max() == pytest.approx(WEB_Z)      # the disc holds the whole section
    cap = WEB_T / 3
    e = _web_edges(bm)
    assert e.size > 1000 and np.median(e) <= 1.3 * cap and np.percentile(e, 95) <= 2.0 * cap
    assert bm.stats["wall_fraction"] == pytest.approx(1 / 3)
    free = mesh_body(body, patch, replace(spec, h_wall=100.0))   # a cap that never binds
    assert np.median(_web_edges(free)) > 2.0 * cap


def test_wall_cap_enters_the_key_of_section_bodies_only():
    """The mesh of the other closures does not use the wall cap: their key (and so the cache of
    every default body) is the same dict as before it existed; a section body's key has it."""
    old = {"order": 1, "h_patch": 2.0, "h_load": 0.5, "growth": 0.35, "h_max": 0.2, "conform": "column",
           "body_size": 16.0, "optimize": True}
    for closure in ("extend", "straight", "cut"):
        assert MeshSpec(closure=closure).key() == {**old, "closure": closure}
        assert MeshSpec(closure=closure).key() == replace(MeshSpec(closure=closure), h_wall=0.1).key()
    sec = MeshSpec(closure="section")
    assert sec.key() == {**old, "closure": "section", "h_wall": sec.h_wall, "wall_corner": WALL_CORNER}
    assert replace(sec, h_wall=0.1).key() != sec.key()
    with pytest.raises(InputError, match="fe_h_wall"):
        MeshSpec(h_wall=0.0)
