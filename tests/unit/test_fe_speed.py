"""Speed-ups of the FE influence numbers keep the numbers (issue 13): the swept pieces of a body
share their faces without a boolean (a conforming mesh), and the two bodies computed in two
processes give exactly the kernels of one process."""
from __future__ import annotations


import numpy as np
import pytest

from conformal.influence.fe import FESettings, body_influence, body_influences
from conformal.meshing.bodies import BodyModel, Profile2D, StripPatch
from conformal.meshing.gmsh_body import MeshSpec, mesh_body
from _paths import PROFILES

G, NU = 82000.0, 0.28


def _bodies():
    rail = BodyModel("rail", Profile2D.from_points(np.loadtxt(PROFILES / "uic60_head_r300w21_analytic.csv",
                                                              delimiter=","), "uic60"))
    wheel = BodyModel("wheel", Profile2D.from_points(np.loadtxt(PROFILES / "s1002_analytic.csv", delimiter=","),
                                                     "s1002"), axle_z=-460.0)
    rp = StripPatch.uniform(4, 0.8, 5, 0.8, float(rail.profile.project(np.array([0.0, 0.0]))))
    wp = StripPatch.uniform(4, 0.8, 5, 0.8, float(wheel.profile.project(np.array([0.0, 0.0]))))
    return (rail, rp), (wheel, wp)


def _faces(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    f = np.concatenate([tets[:, [0, 1, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 3]], tets[:, [1, 2, 3]]])
    return np.unique(np.sort(f, axis=1), axis=0, return_counts=True)


def _groups(tris: np.ndarray) -> list[np.ndarray]:
    """Node sets of the groups of triangles connected through shared nodes."""
    groups: list[set] = []
    for t in tris:
        hit = [g for g in groups if g & set(t)]
        merged = set(t).union(*hit)
        groups = [g for g in groups if not (g & set(t))] + [merged]
    return [np.array(sorted(g)) for g in groups]


def test_swept_pieces_form_one_conforming_mesh():
    """Each piece is swept from the end face of the one before: every interior triangle belongs to
    exactly two tetrahedra (no duplicated nodes on the cuts between pieces), and the triangles of
    one tetrahedron only are exactly the free and clamped surface triangles."""
    for body, patch in _bodies():
        for conform in ("column", "all"):
            m = mesh_body(body, patch, MeshSpec(conform=conform, body_size=1.0))
            faces, count = _faces(m.tets)
            assert count.max() == 2
            boundary = faces[count == 1]
            surface = np.unique(np.sort(np.concatenate([m.free_tris, m.clamped_tris]), axis=1), axis=0)
            is_surface = (boundary[:, None, :] == surface[None, :, :]).all(-1).any(1)
            assert is_surface.sum() == len(surface)
            # the only other exposed triangles are the faces of flat tetrahedra that were dropped
            # (gmsh_body._drop_flat): groups of coplanar nodes, nothing to do with the pieces
            extra = boundary[~is_surface]
            for nodes in _groups(extra):
                X = m.points[nodes] - m.points[nodes].mean(axis=0)
                sv = np.linalg.svd(X, compute_uv=False)
                assert sv[-1] < 1e-6 * sv[0]
            # no two nodes at the same place (pieces glued by shared faces, not by coincident copies)
            q = np.round(m.points / 1e-9).astype(np.int64)
            assert len(np.unique(q, axis=0)) == len(m.points)


@pytest.mark.slow
def test_two_processes_give_the_same_kernels_as_one():
    (rail, rp), (wheel, wp) = _bodies()
    st = FESettings(mesh=MeshSpec(body_size=1.0))
    jobs = [(rail, rp, G, NU, st), (wheel, wp, G, NU, st)]
    par = body_influences(jobs, cache=False, workers=2)
    seq = body_influences(jobs, cache=False, workers=1)
    assert par[1].stats.get("process") == "child"
    for a, b in zip(par, seq):
        assert a.kernel.shape == (7, 5, 5, 3, 3)
        assert np.array_equal(a.kernel, b.kernel)
    assert np.array_equal(seq[0].kernel, body_influence(rail, rp, G, NU, st).kernel)


def test_two_processes_through_the_cache(tmp_path):
    """Computed in two processes into an empty cache, then both read back from it."""
    (rail, rp), (wheel, wp) = _bodies()
    st = FESettings(mesh=MeshSpec(body_size=1.0))
    jobs = [(rail, rp, G, NU, st), (wheel, wp, G, NU, st)]
    first = body_influences(jobs, cache=tmp_path, workers=2)
    again = body_influences(jobs, cache=tmp_path, workers=2)
    assert all(r.stats.get("cache_hit") for r in again)
    for a, b in zip(first, again):
        assert np.array_equal(a.kernel, b.kernel)
