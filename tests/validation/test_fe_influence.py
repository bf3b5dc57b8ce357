"""FE influence numbers (conformal.influence.fe): validation against the half-space, reciprocity,
invariance along x, convergence, wheel-rail combination, bad input.  Coarse meshes throughout.

References: the single-body half-space numbers (conformal.influence.halfspace, checked there
against the tabulated closed forms of Love 1929 and Kalker 1990) and the closed forms themselves for the 3-D field.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest


from conformal.errors import InputError
from conformal.influence import fe
from conformal.influence.fe import FESettings, FESolveError, body_influence, settings_from_options
from conformal.influence.fe_halfspace3d import (_point_displacement_local, _point_stress_local,
                                                _stress_from, point_displacement, rectangle_displacement,
                                                rectangle_stress)
from conformal.influence.halfspace import single_body_influence
from conformal.meshing.bodies import BodyModel, Profile2D, StripPatch, flat_profile
from conformal.meshing.gmsh_body import MeshSpec, mesh_body
from _paths import PROFILES, SCENES

G, NU = 82000.0, 0.28


def _halfspace(patch: StripPatch) -> np.ndarray:
    """Single-body half-space kernel on a flat strip, same layout as the FE kernel."""
    kx = patch.x_centres[:, None, None]
    ds = (patch.s_centres[:, None] - patch.s_centres[None, :])[None]
    return single_body_influence(kx + 0 * ds, ds + 0 * kx, patch.dx, float(patch.s_widths[0]), G=G, nu=NU)


def _rail() -> BodyModel:
    yz = np.loadtxt(PROFILES / "uic60_head_r300w21_analytic.csv", delimiter=",")
    return BodyModel("rail", Profile2D.from_points(yz, "uic60"))


def _wheel() -> BodyModel:
    yz = np.loadtxt(PROFILES / "s1002_analytic.csv", delimiter=",")
    return BodyModel("wheel", Profile2D.from_points(yz, "s1002"), axle_z=-460.0)


def _patch_at(body: BodyModel, y: float, z: float, mx=4, ms=3, d=1.0) -> StripPatch:
    return StripPatch.uniform(mx, d, ms, d, float(body.profile.project(np.array([y, z]))))


# ----------------------------------------------------------------------------- 3-D half-space field
def test_field_surface_limit_equals_closed_form():
    """At z -> 0 the interior field equals Love/Kalker's surface numbers (independent formulas)."""
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-3, 3, 40), rng.uniform(-3, 3, 40)
    u = rectangle_displacement(np.stack([x, y, np.full(40, 1e-13)], -1), 0.6, 1.5, G=2.5, nu=0.3, near=None)
    A = single_body_influence(x, y, 0.6, 1.5, G=2.5, nu=0.3)
    assert np.abs(u - A).max() < 1e-12 * np.abs(A).max()  # both closed forms: round-off only


def test_field_matches_reference_table1():
    """Two identical bodies (K = 0): A = 2 x single body; reference Table 1 (G = 1, nu = 0.28),
    components not involving K."""
    table = {(0.0, 0.0): (9.650917460234e-01, 0.0, 9.650917460234e-01, 8.079837873684e-01),
             (1.0, 0.0): (3.214217517720e-01, 0.0, 2.469032166850e-01, 2.379034751680e-01),
             (2.0, 3.0): (7.146187404728e-02, 1.129965903671e-02, 8.088288085438e-02, 6.377222298209e-02),
             (10.0, 0.0): (3.183679228905e-02, 0.0, 2.293530035971e-02, 2.292785273669e-02)}
    pts = np.array([[x, y, 1e-14] for (x, y) in table])
    u = 2 * rectangle_displacement(pts, 1.0, 1.0, G=1.0, nu=0.28)
    for k, (xx, xy, yy, zz) in enumerate(table.values()):
        got = u[k][[0, 0, 1, 2], [0, 1, 1, 2]]
        # 12 digits in the table; the far point (10, 0) uses the 3 x 3 Gauss far field (error < 1e-7)
        assert got == pytest.approx([xx, xy, yy, zz], rel=1e-7, abs=1e-9)


def test_field_equilibrium_and_surface_traction():
    """div sigma = 0 inside; on z = 0 the traction sigma . (-e_z) is p on the rectangle, 0 outside."""
    rng = np.random.default_rng(2)
    P = np.stack([rng.uniform(-2, 2, 12), rng.uniform(-2, 2, 12), rng.uniform(0.2, 2, 12)], -1)
    h = 1e-4
    div = 0.0
    for l in range(3):
        e = np.zeros(3)
        e[l] = h
        div = div + (rectangle_stress(P + e, 0.6, 1.5, G=G, nu=NU, near=None)[:, :, l, :]
                     - rectangle_stress(P - e, 0.6, 1.5, G=G, nu=NU, near=None)[:, :, l, :]) / (2 * h)
    scale = np.abs(rectangle_stress(P, 0.6, 1.5, G=G, nu=NU, near=None)).max()
    assert np.abs(div).max() < 1e-5 * scale / 0.1  # central differences, O(h^2) with h = 1e-4
    pts = np.array([[0.1, 0.2, 1e-10], [0.25, -0.7, 1e-10], [0.5, 0.3, 1e-10], [-1.0, 2.0, 1e-10]])
    t = -rectangle_stress(pts, 0.6, 1.5, G=G, nu=NU, near=None)[:, :, 2, :]
    inside = np.array([1, 1, 0, 0])
    for k in range(4):
        assert np.allclose(t[k], inside[k] * np.eye(3), atol=1e-6)


def test_point_force_stress_and_far_field():
    rng = np.random.default_rng(3)
    P = rng.uniform(-3, 3, (30, 3))
    P[:, 2] = np.abs(P[:, 2]) + 0.1
    a = _point_stress_local(P[:, 0], P[:, 1], P[:, 2], NU)
    b = _stress_from(lambda x, y, z: _point_displacement_local(x, y, z, G, NU), P[:, 0], P[:, 1], P[:, 2], G, NU, 1.0)
    assert np.abs(a - b).max() < 1e-12 * np.abs(b).max()
    # far from the rectangle it acts as a point force of size dx dy (reference §4.2: 7.4e-4 at r = 10)
    far = np.array([[10.0, 0.0, 0.0], [0.0, 10.0, 3.0]])
    u_rect = rectangle_displacement(far, 1.0, 1.0, G=G, nu=NU, near=None)
    u_pt = point_displacement(far + [0, 0, 1e-14], G=G, nu=NU)
    assert np.abs(u_rect - u_pt).max() < 1e-3 * np.abs(u_pt).max()


# ----------------------------------------------------------------------------- flat limit
def test_flat_block_reproduces_halfspace():
    """With the half-space field on the artificial boundaries (default) the split method's
    correction on a flat block has no load and no boundary value: the FE kernel IS the half-space
    kernel, whatever the body size (the observation adds the closed form once)."""
    body = BodyModel("block", flat_profile(-60, 60))
    patch = StripPatch.uniform(5, 1.0, 5, 1.0, 60.0)
    A = _halfspace(patch)
    s = A[4, 0, 0, 2, 2]
    for size in (0.5, 2.0):
        r = body_influence(body, patch, G, NU, FESettings(mesh=MeshSpec(body_size=size)))
        assert np.abs(r.kernel - A).max() < 1e-10 * s     # two closed forms (depth 0+ and z = 0): round-off
        assert r.stats["corrected"] is False                # nothing to solve (no factorisation)


def test_clamped_block_is_stiff_by_an_offset_that_shrinks_with_size():
    """The earlier far field (clamped artificial boundaries): every number carries a negative
    offset that scales like 1/size; summed over a patch it made FE bodies 20-40 % too stiff."""
    body = BodyModel("block", flat_profile(-60, 60))
    patch = StripPatch.uniform(3, 1.0, 3, 1.0, 60.0)
    A = _halfspace(patch)
    offs = []
    for size in (1.0, 2.0):
        r = body_influence(body, patch, G, NU, FESettings(far_field="clamped", mesh=MeshSpec(body_size=size)))
        offs.append(np.median((r.kernel - A)[..., 2, 2]) / A[2, 0, 0, 2, 2])
    assert offs[0] < offs[1] < 0
    # disc radius 1.5 + 3 -> 1.5 + 6 element sizes, body length 11 -> 17: ratio 0.6-0.65 for 1/size
    assert 0.45 < offs[1] / offs[0] < 0.75


@pytest.mark.slow
def test_direct_method_converges_to_split():
    """Plain FE (P2, unit loads on conforming elements, the half-space field on the artificial
    boundaries) approaches the split result (= the half-space) as the loaded column is refined;
    the far numbers agree already on the coarse mesh."""
    body = BodyModel("block", flat_profile(-60, 60))
    patch = StripPatch.uniform(3, 1.0, 3, 1.0, 60.0)
    ref = _halfspace(patch)
    s = ref[2, 1, 1, 2, 2]
    errs = []
    for h_load in (0.5, 0.25):
        st = FESettings(method="direct", mesh=MeshSpec(order=2, h_patch=1.0, h_load=h_load, body_size=1.0))
        d = (body_influence(body, patch, G, NU, st).kernel - ref) / s
        errs.append((abs(d[2, 1, 1, 2, 2]), np.abs(d).max(), np.abs(d[[0, 4]]).max()))
    # measured: self 2.1 % -> 0.85 %, max 5.2 % -> 2.4 %, far (|kx| = 2) 0.82 % -> 0.27 %
    assert errs[1][0] < 0.5 * errs[0][0] and errs[1][1] < 0.5 * errs[0][1]
    assert errs[0][2] < 0.012 and errs[1][2] < 0.005


# ----------------------------------------------------------------------------- curved bodies
def test_reciprocity_direct_exact_on_curved_rail():
    """A_IiJj = A_JjIi on the same element pair (load column 0 / observe column 1 and back):
    exact for element-averaged numbers, whose observation is the transposed load operator."""
    rail = _rail()
    patch = _patch_at(rail, -20.0, 1.0, mx=3, ms=3)
    st = FESettings(method="direct", collocation="average", far_field="clamped",
                    mesh=MeshSpec(h_patch=0.5, conform="all", body_size=0.5))
    bm = mesh_body(rail, patch, st.mesh)
    k0 = body_influence(rail, patch, G, NU, st, mesh=bm).kernel
    k1 = body_influence(rail, patch, G, NU, st, mesh=bm, load_column=1).kernel
    A01, A10 = k0[3], k1[1]                    # observe col 1 / load col 0, and the reverse
    s = k0[2, 1, 1, 2, 2]
    # equal element areas up to the facets' chord error (1e-7 here); solver round-off 1e-12
    assert np.abs(A01 - A10.transpose(1, 0, 3, 2)).max() < 1e-6 * s
    # the half-space far field is not the FE operator's own boundary condition: reciprocity then
    # holds up to the truncation of the body (measured 0.24 % of the self term at this size)
    st = replace(st, far_field="halfspace")
    k0 = body_influence(rail, patch, G, NU, st, mesh=bm).kernel
    k1 = body_influence(rail, patch, G, NU, st, mesh=bm, load_column=1).kernel
    assert np.abs(k0[3] - k1[1].transpose(1, 0, 3, 2)).max() < 0.005 * s


def test_invariance_along_x_rail_and_wheel():
    """Loading another column gives the same kernel (extrusion; revolution in rolling frames);
    split P1 h = d.  Measured 0.25 % of the self term (mesh differences)."""
    for body, y in ((_rail(), 0.0), (_wheel(), 0.0)):
        patch = _patch_at(body, y, 0.0, mx=4, ms=3)
        st = FESettings(mesh=MeshSpec(conform="all", h_patch=1.0, h_load=None, body_size=1.0))
        bm = mesh_body(body, patch, st.mesh)
        a = body_influence(body, patch, G, NU, st, mesh=bm).kernel
        b = body_influence(body, patch, G, NU, st, mesh=bm, load_column=1).kernel
        s = a[3, 1, 1, 2, 2]
        assert np.abs(a[:-1] - b[:-1]).max() < 0.006 * s, body.kind


def test_wheel_and_rail_couplings_and_combination():
    """Rail (normal into it) matches the half-space couplings A_zx; the wheel (normal out of it)
    the mirrored ones (S g S, reference §2.2); for identical materials the two-body couplings
    cancel (K = 0) while the diagonal terms add."""
    rail, wheel = _rail(), _wheel()
    rp, wp = _patch_at(rail, 0.0, 0.0), _patch_at(wheel, 0.0, 0.0)
    st = FESettings(mesh=MeshSpec(body_size=1.0))
    kr = body_influence(rail, rp, G, NU, st)
    kw = body_influence(wheel, wp, G, NU, st)
    A = _halfspace(rp)
    s = A[3, 1, 1, 2, 2]
    S = np.diag([1.0, 1.0, -1.0])
    Am = np.einsum("ab,...bc,cd->...ad", S, A, S)
    # measured: 1.8 % (truncation of these small bodies), against 18 % for the wrong sign
    assert np.abs(kr.kernel[..., 2, 0] - A[..., 2, 0]).max() < 0.03 * s
    assert np.abs(kw.kernel[..., 2, 0] - Am[..., 2, 0]).max() < 0.03 * s
    both = fe.combine(kr, kw)
    assert np.abs(both[..., 2, :2]).max() < 0.005 * s          # single body: 8.7 % of the self term
    assert both[3, 1, 1, 2, 2] == pytest.approx(kr.kernel[3, 1, 1, 2, 2] + kw.kernel[3, 1, 1, 2, 2])


def test_split_mesh_convergence_on_rail_crown():
    """Refining the mesh (h = d -> d/2, P1) changes the crown kernel by < 0.2 % of the self term
    (measured 0.04 % at 0.4 mm elements): the split method's correction is smooth."""
    rail = _rail()
    patch = _patch_at(rail, 0.0, 0.0, mx=4, ms=3, d=0.4)
    ks = [body_influence(rail, patch, G, NU, FESettings(mesh=MeshSpec(h_patch=h, h_load=None, body_size=1.0))).kernel
          for h in (1.0, 0.5)]
    s = ks[1][3, 1, 1, 2, 2]
    assert np.abs(ks[0] - ks[1]).max() < 0.002 * s


# ----------------------------------------------------------------------------- bad input
def test_bad_input_messages():
    rail = _rail()
    with pytest.raises(InputError, match="too short for the requested patch"):
        body_influence(rail, StripPatch.uniform(3, 1.0, 3, 1.0, rail.profile.length - 0.5), G, NU)
    with pytest.raises(InputError, match="needs a mesh that conforms"):
        body_influence(rail, _patch_at(rail, 0, 0), G, NU, FESettings(mesh=MeshSpec(conform="none")))
    with pytest.raises(InputError, match="fe_method"):
        FESettings(method="magic")
    with pytest.raises(InputError, match="fe_order"):
        MeshSpec(order=3)
    with pytest.raises(InputError, match="larger than the wheel"):
        w = _wheel()
        body_influence(w, StripPatch.uniform(400, 5.0, 3, 1.0, 70.0), G, NU)
    with pytest.raises(FESolveError, match="max_dofs"):
        body = BodyModel("block", flat_profile(-10, 10))
        body_influence(body, StripPatch.uniform(2, 1.0, 2, 1.0, 10.0), G, NU, FESettings(max_dofs=100))


def test_out_of_memory_is_a_clear_error(monkeypatch):
    body = BodyModel("block", flat_profile(-10, 10))
    monkeypatch.setattr(fe, "_available_memory", lambda: 1e6)   # 1 MB left
    with pytest.raises(FESolveError, match="GiB are available"):
        body_influence(body, StripPatch.uniform(2, 1.0, 2, 1.0, 10.0), G, NU)
    monkeypatch.setattr(fe, "_available_memory", lambda: None)

    def boom(*a, **k):
        raise MemoryError

    monkeypatch.setattr(fe._Factor, "__init__", boom)
    with pytest.raises(FESolveError, match="out of memory"):
        body_influence(body, StripPatch.uniform(2, 1.0, 2, 1.0, 10.0), G, NU, FESettings(far_field="clamped"))


def test_solver_choice_and_missing_pardiso(monkeypatch):
    body = BodyModel("block", flat_profile(-20, 20))
    patch = StripPatch.uniform(2, 1.0, 2, 1.0, 20.0)
    bm = mesh_body(body, patch, MeshSpec())
    from conformal.influence import fe_toolkit
    from conformal.influence.factor import amg_available, pardiso_available

    solvers = ["splu"] + (["amg"] if amg_available() else []) + (["pardiso"] if pardiso_available() else [])
    ks = {s: body_influence(body, patch, G, NU, FESettings(solver=s, far_field="clamped"), mesh=bm).kernel
          for s in solvers}
    for s in solvers:   # AMG-CG to a relative residual of 1e-10; direct solvers to round-off
        assert np.abs(ks["splu"] - ks[s]).max() < 1e-7 * ks["splu"][1, 0, 0, 2, 2], s
    monkeypatch.setattr(fe_toolkit, "pardiso_available", lambda: False)
    with pytest.raises(InputError, match="pypardiso is not installed"):
        body_influence(body, patch, G, NU, FESettings(solver="pardiso", far_field="clamped"), mesh=bm)
    r = body_influence(body, patch, G, NU, FESettings(solver="auto", far_field="clamped"), mesh=bm)
    assert r.stats["solver"] == "splu"


def test_settings_from_scene_options():
    st = settings_from_options({"fe_order": 2, "fe_h_patch": 2.0, "fe_solver": "splu", "other": 1})
    assert st.mesh.order == 2 and st.mesh.h_patch == 2.0 and st.solver == "splu" and st.method == "split"
    with pytest.raises(InputError, match="fe_typo"):
        settings_from_options({"fe_typo": 1})
    with pytest.raises(InputError, match="fe_growth"):
        settings_from_options({"fe_growth": "fast"})


def test_worn_wheel_slender_strip_free_surface_is_whole():
    """Worn wheel (measured profile, digitised curvature up to 0.6 /mm at the flange root) under a
    slender strip (ds = 0.02 mm): gmsh's spline departs from the profile polyline by about 1e-3 mm
    there, more than the old free-surface tolerance 1e-2 ds, so parts of the free surface were
    taken for clamped faces and observation points fell into the holes (flange_worn.toml at a
    17 mm shift: "observation point lies outside the meshed surface").  Now the free surface is
    the whole revolved surface: its area equals (theta_hi - theta_lo) * int r ds (flat facets
    are chords of the curved surface: relative error of order (h / R)^2 < 1e-4; 1e-3 allows for
    that), and the influence numbers of the strip come out (the self normal term is positive)."""
    from conformal.scene import load_scene

    sc = load_scene(SCENES / "flange_worn.toml")
    from conformal.cases.conformal import scene_profiles

    _, wheel_pts = scene_profiles(sc)
    wheel = BodyModel("wheel", Profile2D.from_points(wheel_pts, "worn"), axle_z=-444.0)
    patch = StripPatch.uniform(3, 0.4, 3, 0.02, 21.2)
    st = FESettings(mesh=MeshSpec(h_patch=4.0, body_size=1.0))
    bm = mesh_body(wheel, patch, st.mesh)
    ext = bm.extent
    X = bm.points[bm.free_tris]
    area = 0.5 * np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), axis=1).sum()
    s = np.linspace(ext.s_lo, ext.s_hi, 4001)
    r = wheel.radius_at(s)
    exact = (ext.theta_hi - ext.theta_lo) * np.sum(0.5 * (r[1:] + r[:-1]) * np.diff(s))
    assert area == pytest.approx(exact, rel=1e-3)
    k = body_influence(wheel, patch, G, NU, st, mesh=bm).kernel
    assert np.all(np.isfinite(k)) and k[patch.mx - 1, 1, 1, 2, 2] > 0


def test_trace_interpolation_survives_degenerate_surface_triangles():
    """gmsh leaves slivers on the free surface whose three nodes lie on one circle of revolution
    (a patch edge s = const of a wheel): zero area in the (x, s) parametrisation.  matplotlib's
    trifinder rejected such a surface ("Triangulation is invalid": flange flank at 70 degrees,
    n = 48; the worn pair); the point location now skips them.  P1 interpolation of a linear
    field must then be exact (to round-off) everywhere in the square, edges and nodes included."""
    from types import SimpleNamespace

    # F(0.5,2) above; A(0,1) B(0.5,1) C(1,1) on the patch edge; D(0,0) E(1,0) below.  Below the
    # edge the triangles use B, above it (A, C, F) spans over B, and (A, C, B) is the collinear
    # sliver between them (this configuration made matplotlib's trifinder raise).
    nodes = np.array([[0.0, 1.0], [0.5, 1.0], [1.0, 1.0], [0.0, 0.0], [1.0, 0.0], [0.5, 2.0]])
    tris = np.array([[3, 4, 2], [3, 2, 1], [3, 1, 0], [0, 2, 1], [0, 2, 5]])
    surf = SimpleNamespace(tris=tris, tri_uv=nodes[tris])
    from conformal.influence.fe_toolkit import VectorSpace

    space = VectorSpace(None, None, len(nodes), np.zeros(0, np.int64), np.zeros(0, np.int64), len(nodes), 1)
    rng = np.random.default_rng(3)
    top = rng.random((30, 2))
    top = top[top.sum(axis=1) < 1.0]                     # in the upper triangle (A, C, F)
    top = nodes[0] + top[:, :1] * (nodes[2] - nodes[0]) + top[:, 1:] * (nodes[5] - nodes[0])
    pts = np.vstack([rng.random((50, 2)), top, nodes, [[0.5, 0.5], [0.25, 1.0], [0.75, 1.0], [1.0, 0.3]]])
    Q = fe._trace_interpolation(surf, space, pts)

    def lin(p):
        return 2.0 * p[:, 0] - 3.0 * p[:, 1] + 1.0

    np.testing.assert_allclose(Q @ lin(nodes), lin(pts), rtol=0, atol=1e-12)
    with pytest.raises(FESolveError, match="outside the meshed surface"):
        fe._trace_interpolation(surf, space, np.array([[0.9, 1.5]]))
