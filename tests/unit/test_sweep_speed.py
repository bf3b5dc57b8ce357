"""Issue 23, faster sweeps: every shortcut of the solved sweep against the path it replaces.

Geometry (same answers to rounding): the cubic pieces against the B-spline, the wheel locus moved
with the height against the locus sampled at that height, the projections of the near locus
samples against all samples, Cramer's 3 x 3 solves against numpy.linalg.solve, the wheel's
line intersections on its surface, the contact point's Newton system in floats against numpy's,
the contact parts against scipy.ndimage.  Balance: the one-patch passes of a warm-started
Manchester sweep against the general balance with tight tolerances (an independent path) and
against the forces of the code before (stored values).
"""
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from conformal.cases import wheelrail as wr
from conformal.geometry import patches as gp
from conformal.geometry.search import pair_locus, wheel_locus
from conformal.geometry.wheelrail import profile_curves
from conformal.grid import PlanarGrid
from _paths import CONTACT_CASES, REFERENCE, ROOT
from _scenes import MBENCH, mbench_case_scene, tight_general_balance

CASES = json.loads((CONTACT_CASES).read_text())["cases"]["mbench_a22"]["right"]
BEFORE = json.loads((REFERENCE / "mbench_a22_right_sweep_before.json").read_text())["cases"]


def mbench_case(y, element_size=0.2):
    """The Manchester A-2.2 right-wheel case at lateral shift y with CONTACT's yaw, roll and pitch
    velocity (studies/manchester_a22.scene_for)."""
    return mbench_case_scene(next(c["inputs"] for c in CASES if c["inputs"]["Y_WS_mm"] == y),
                             element_size=element_size)


def test_cubic_pieces_equal_the_bspline():
    """Profile coordinates and their first two derivatives from the cubic pieces equal scipy's
    B-spline along both Manchester profiles to rounding: on the profile within 1e-12 mm, 1e-11
    and 1e-9 1/mm (the Taylor coefficients of 0.025 mm pieces, measured 3e-14, 1e-12, 9e-11),
    extrapolated 1 mm beyond its ends within 1e-9, 1e-9 and 1e-8 (measured 2e-10, 7e-10,
    1.4e-9); for arrays and single points (floats)."""
    for curve in profile_curves(mbench_case(0.0).geometry, MBENCH.parent):
        L = curve.length
        for s, tol in ((np.r_[np.linspace(0.0, L, 4001), 0.37 * L], (1e-12, 1e-11, 1e-9)),
                       (np.r_[np.linspace(-1.0, 0.0, 51), np.linspace(L, L + 1.0, 51)], (1e-9, 1e-9, 1e-8))):
            got = curve.derivatives(s)
            for k in range(6):
                np.testing.assert_allclose(got[k], curve._c(s, k // 2)[:, k % 2], rtol=0, atol=tol[k // 2])
        for sk in (0.0, 0.37 * L, L):
            one = curve.derivatives(float(sk))
            assert all(isinstance(v, float) for v in one)
            np.testing.assert_allclose(one, [curve._c(sk, k // 2)[k % 2] for k in range(6)], rtol=0, atol=1e-9)


def test_locus_moved_with_height_equals_locus_sampled_there():
    """The contact locus sampled once per position and moved with the wheelset height equals the
    locus sampled at that height (points to 1e-9 mm, gaps likewise, same NaNs)."""
    sc = mbench_case(3.0)
    pl = wr.place_scene(sc)
    for z in (pl.z_touch, pl.z_touch + 0.037, pl.z_touch - 2.0):
        a = pair_locus(pl.pair, pl.top, z)
        b = wheel_locus(pl.pair.wheel(z), pl.top)
        np.testing.assert_array_equal(np.isnan(a.theta), np.isnan(b.theta))
        np.testing.assert_allclose(a.points, b.points, rtol=0, atol=1e-9)
        np.testing.assert_allclose(a.gap, b.gap, rtol=0, atol=1e-9)


@pytest.mark.parametrize("y", [0.0, 5.0, 7.0])
def test_near_samples_give_the_patches_of_all_samples(y, monkeypatch):
    """Projecting only the locus samples less than NEAR_GAP above the rail gives the patches of
    projecting all of them (tread, the jump at 5 mm, flange): reference points, penetrations and
    extents equal to 1e-12 mm."""
    sc = mbench_case(y)
    pl = wr.place_scene(sc)
    wheel = pl.pair.wheel(pl.z_touch + 0.03)
    near = gp.find_patches(wheel, pl.pair.rail, pl.top)
    monkeypatch.setattr(gp, "NEAR_GAP", math.inf)
    every = gp.find_patches(wheel, pl.pair.rail, pl.top)
    assert len(near) == len(every) >= 1
    for p, q in zip(near, every):
        assert p.s_ref == pytest.approx(q.s_ref, abs=1e-12)
        assert p.penetration == pytest.approx(q.penetration, abs=1e-12)
        np.testing.assert_allclose(p.x_range + p.eta_range + p.s_range, q.x_range + q.eta_range + q.s_range,
                                   rtol=0, atol=1e-12)


def test_cramer_solves_equal_numpy_solve():
    rng = np.random.default_rng(3)
    c0, c1, c2, b = (rng.normal(size=(50, 3)) for _ in range(4))
    ref = np.linalg.solve(np.stack([c0, c1, c2], axis=2), b[..., None])[..., 0]
    np.testing.assert_allclose(gp._solve3(c0, c1, c2, b), ref, rtol=1e-10, atol=1e-12)
    with pytest.raises(np.linalg.LinAlgError):
        gp._solve3(c0, c0, c2, b)


@pytest.mark.parametrize("y", [0.0, 7.0])
def test_wheel_on_lines_meets_the_wheel_surface(y):
    """The intersections of lines with the wheel lie on the revolved wheel surface,
    r_w(s_w, theta) = Q + t n within 1e-9 mm, for the lines of a planar grid (one direction: tread at 0 mm, flange at 7 mm) and for lines of
    their own directions (a curved grid's local normals); theta within pi of its start."""
    sc = mbench_case(y)
    pl = wr.place_scene(sc)
    wheel = pl.pair.wheel(pl.z_touch + 0.05)
    patch = gp.find_patches(wheel, pl.pair.rail, pl.top)[0]
    X, Y = np.meshgrid(np.linspace(-6.0, 6.0, 25), np.linspace(-4.0, 4.0, 17), indexing="ij")
    Q = patch.point + X.reshape(-1, 1) * np.array([1.0, 0.0, 0.0]) + Y.reshape(-1, 1) * patch.t2
    s0, th0 = gp._wheel_start(wheel, patch, Q)
    rng = np.random.default_rng(5)
    tilt = patch.normal + 0.05 * rng.normal(size=Q.shape)
    for n in (patch.normal, tilt / np.linalg.norm(tilt, axis=1, keepdims=True)):
        s_w, th, t = gp.wheel_on_lines(wheel, Q, n, s0, th0)
        np.testing.assert_allclose(wheel.point(s_w, th), Q + t[:, None] * n, rtol=0, atol=1e-9)
        assert np.all(np.abs(th - th0) < math.pi) and np.all(np.abs(t) < 1.0)


@pytest.mark.parametrize("y", [0.0, 5.0, 7.0])
def test_float_newton_system_equals_the_numpy_one(y):
    """The contact point's Newton system in Python floats (the steps of newton_contact) equals
    the numpy one (residual, Jacobian) to 1e-12 of its largest entry, at the contact point and
    away from it (tread, the jump at 5 mm, flange)."""
    from conformal.geometry.search import _newton_system, _residual_and_jacobian, find_contacts

    sc = mbench_case(y)
    pl = wr.place_scene(sc)
    wheel = pl.pair.wheel(pl.z_touch + 0.03)
    f = wheel.frame
    frame = tuple(tuple(float(c) for c in v) for v in (f.O, f.a, f.e_d, f.e_f))
    c = find_contacts(wheel, pl.pair.rail, pl.top).contacts[0]
    for dq in ((0.0, 0.0, 0.0, 0.0), (0.3, 0.01, 0.5, -0.2)):
        q = np.array([c.s_w, c.theta, c.x, c.s_r]) + dq
        F, J, _ = _residual_and_jacobian(wheel, pl.pair.rail, q)
        F2, J2 = _newton_system(wheel, pl.pair.rail, q, frame)
        scale = np.abs(J).max()
        np.testing.assert_allclose(F2, F, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(J2, J, rtol=0, atol=1e-12 * scale)


def test_connected_parts_equal_ndimage_label():
    """The edge-connected parts of random masks (1 x 1 to 29 x 29, densities 0..1: single
    elements, stripes, one part spanning the grid) equal scipy.ndimage.label's labels and count,
    numbering included; an empty mask has none."""
    from scipy import ndimage

    from conformal.grid import connected_parts

    rng = np.random.default_rng(0)
    for _ in range(200):
        m = rng.random(tuple(rng.integers(1, 30, size=2))) < rng.random()
        labels, n = connected_parts(m)
        ref, n_ref = ndimage.label(m)
        assert n == n_ref
        np.testing.assert_array_equal(labels, ref)
    assert connected_parts(np.zeros((3, 4), bool))[1] == 0


def test_resample_is_bilinear_and_exact_on_the_same_grid():
    """A field resampled onto its own grid is itself; onto a finer grid inside the source a linear
    field is reproduced exactly (bilinear interpolation); beyond the source it is 0."""
    g = PlanarGrid(8, 6, 0.5, 0.4, -2.0, -1.2)
    X, Y = g.mesh()
    f = 3.0 + 0.7 * X - 1.1 * Y
    np.testing.assert_allclose(wr.resample(g, f, g), f, rtol=0, atol=1e-12)
    fine = PlanarGrid(10, 8, 0.25, 0.2, -1.5, -0.8)
    Xf, Yf = fine.mesh()
    np.testing.assert_allclose(wr.resample(g, f, fine), 3.0 + 0.7 * Xf - 1.1 * Yf, rtol=0, atol=1e-12)
    far = PlanarGrid(2, 2, 0.5, 0.4, 10.0, 10.0)
    assert not wr.resample(g, f, far).any()


def test_warm_start_extrapolates_along_the_sweep():
    """WarmStart.at moves the lowering and the ratios along their slopes to the next shift, and
    leaves them where the step reverses or grows more than 1.5 times (a jump, a new sweep)."""
    w = wr.WarmStart(lowering=0.02, ratios=((50.0, -0.3),), shift=2.0, step=0.5, lowering_slope=-0.001,
                     ratio_slopes=(0.01,))
    a = w.at(2.5)
    assert a.lowering == pytest.approx(0.0195) and a.ratios[0][1] == pytest.approx(-0.295)
    assert w.at(1.5) is w and w.at(3.5) is w and wr.WarmStart(lowering=0.02).at(1.0).lowering == 0.02


def test_core_command_parser_leaves_out_the_other_modules():
    """``conformal solve`` builds only the parsers of cli.py: the table, stresses, dynamics and
    inp modules (numpy, the table build machinery) are not imported to declare their options."""
    code = ("import sys; from conformal.cli import build_parser; build_parser('solve'); "
            "print(sorted(m for m in sys.modules if m.startswith(('conformal.tables', 'conformal.stresses', "
            "'conformal.dynamics', 'conformal.contact_inp', 'numpy', 'dask'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}, check=True).stdout
    assert out.strip() == "[]"
    from conformal.cli import build_parser

    full = build_parser().format_help()
    assert "stresses" in full and "table" in full


def test_planar_wheel_rail_imports_no_other_model():
    """A planar wheel-rail solve imports the modules of its own theory only: importing the case
    leaves the other models' modules (FE contact and its meshing, the tables, the curved-strip
    case) unloaded, and ``conformal.models.SOLVE`` imports a model's module when its function is
    first asked for."""
    code = ("import sys; import conformal.cases.wheelrail; from conformal.models import SOLVE; "
            "other = ('conformal.fe_contact', 'conformal.meshing', 'conformal.tables', 'conformal.cases.conformal', "
            "'conformal.theories.fastsim'); print(sorted(m for m in sys.modules if m.startswith(other))); "
            "SOLVE['fastsim']; print('conformal.theories.fastsim' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "OPENBLAS_NUM_THREADS": "1"},
                         check=True).stdout.split("\n")
    assert out[0] == "[]" and out[1] == "True"


@pytest.mark.slow
def test_warm_sweep_equals_independent_balance_and_before():
    """The Manchester A-2.2 right-wheel sequence (0.2 mm elements, 10 kN, CONTACT's yaw, roll and
    pitch velocity) solved as a sweep (one-patch passes, warm starts, extrapolated lowering) over
    two stretches (tread 2-3 mm; the flange from 6 mm, its jump at 6.5 mm) against

    * the general balance (normal problems, then contact solves with FS/FN fed back), each case
      cold, with the force and height tolerances 1e-8 W and 1e-7 mm, its geometry searched at the
      balanced height: FN and FS within 5e-5 W, FX within 1e-4 W, the height within 5e-5 mm
      (measured 1.6e-5 W, 0.2e-5 W and 8.5e-6 mm at 7 mm).  The sweep keeps a searched geometry
      lowered by up to GEOMETRY_KEEP = 2e-3 mm (each element's distance moved at its own rate), so
      its grid samples the patch at other points: over all 21 positions of the sequence the
      differences are at most 3.9e-5 W in FN and 2.1e-4 mm in the height (9 mm, flange: the grid's
      element centres sample the overlap peak, (dy/2)^2 / 2R ~ 3e-4 mm on 0.2 mm elements);
      the balance itself within 2e-5 W (the passes take it to ONE_PATCH_TOL = 1e-5 W);
    * the forces before issue 23's speed-up (stored, balanced to 1e-4 W): within 3e-4 W."""
    W = 10000.0
    for stretch in ((2.0, 2.5, 3.0), (6.0, 6.5, 7.0)):
        warm = None
        for y in stretch:
            sc = mbench_case(y)
            r = wr.solve_wheel_rail(sc, warm=warm)
            warm = wr.WarmStart.from_result(r, warm)
            assert r.extra["balance"]["one_patch_passes"] and len(r.patches) == 1
            assert abs(r.extra["FZ_track"] - W) <= 2e-5 * W
            ref, z = tight_general_balance(sc)
            assert abs(r.FN - ref.FN) <= 5e-5 * W, y
            assert abs(r.FY - ref.FY) <= 5e-5 * W, y
            assert abs(r.FX - ref.FX) <= 1e-4 * W, y
            assert abs(r.extra["z_ws"] - z) <= 5e-5, y
            before = next(c for c in BEFORE if c["y_ws"] == y)
            for k in ("FN", "FX", "FY"):
                assert abs(getattr(r, k) - before[k]) <= 3e-4 * W, (y, k)
            assert abs(r.extra["FY_track"] - before["FY_track"]) <= 3e-4 * W


def test_contact_solve_from_its_converged_solution_stops_at_once():
    """A contact solve (Manchester A-2.2 at 3 mm, 0.4 mm elements, steady rolling) started from
    its own converged tractions, handed over as a sweep does (a PatchField resampled onto the
    problem's grid), stops after one normal iteration and one tangential Newton step (the
    residual check of the start), with the forces of the first solve to the tolerance 1e-6."""
    from dataclasses import replace

    from conformal.models import solve_problem

    sc = mbench_case(3.0, element_size=0.4)
    pl = wr.place_scene(sc)
    st = wr.state_at(pl.pair, pl.top, pl.z_touch + 0.06, pl.roll, sc)
    pg = st.patches[0]
    problem = wr.problems_at(sc, pl, st, [9800.0])[0]
    first = solve_problem(problem)
    assert first.converged and first.extra["normal_iterations"] > 2 and first.extra["tangential_iterations"] >= 1
    f = first.field
    fields = [wr.PatchField(pg.patch.s_ref, f.grid, f.pn, f.px, f.py)]
    again = solve_problem(replace(problem, start=wr._contact_start(fields, pg, problem, pl.pair.side)))
    assert again.converged
    assert again.extra["normal_iterations"] <= 2 and again.extra["tangential_iterations"] <= 2
    for k in ("FN", "FX", "FY"):
        assert abs(getattr(again, k) - getattr(first, k)) <= 1e-5 * first.FN, k


def test_resample_onto_the_same_grid_keeps_the_contact_edge():
    """A pressure resampled onto its own grid (offsets that rounding does not keep exactly: xl
    -2.3 mm, 0.2 mm elements) is bitwise itself, and so onto a larger grid whose centres fall on
    the source's: no tiny pressures beyond the contact edge, which would enter the starting
    contact set of the next normal solve."""
    g = PlanarGrid(23, 17, 0.2, 0.2, -2.3, -1.7)
    X, Y = g.mesh()
    p = np.sqrt(np.maximum(1.0 - (X / 1.9) ** 2 - (Y / 1.3) ** 2, 0.0))
    out = wr.resample(g, p, g)
    np.testing.assert_array_equal(out, p)
    # a larger grid of the same spacing whose centres fall on the source's (a neighbour's grid)
    big = PlanarGrid(27, 19, 0.2, 0.2, -2.3 - 0.4, -1.7 - 0.2)
    out = wr.resample(g, p, big)
    np.testing.assert_array_equal(out[2:25, 1:18], p)
    assert np.count_nonzero(out) == np.count_nonzero(p)
    shifted = PlanarGrid(23, 17, 0.2, 0.2, -2.3 + 0.1, -1.7)      # half an element: interpolated
    assert np.count_nonzero(wr.resample(g, p, shifted)) > np.count_nonzero(p) - 40


def test_shared_halfspace_operator_equals_a_fresh_one():
    """Grids of equal shape, spacing and material share one half-space operator in the process;
    its kernels, transforms, preconditioner and products equal those of a fresh operator bitwise;
    another spacing or material gives another operator; the cache is bounded."""
    from conformal.influence import halfspace as hs
    from conformal.materials import Material

    mat = Material.identical(82000.0, 0.28)
    a = hs.HalfSpaceInfluence.for_grid(21, 13, 0.2, 0.15, mat)
    b = hs.HalfSpaceInfluence.for_grid(21, 13, 0.2, 0.15, mat)
    fresh = hs.HalfSpaceInfluence.for_grid(21, 13, 0.2, 0.15, mat, shared=False)
    assert a is b and fresh is not a
    assert hs.HalfSpaceInfluence.for_grid(21, 13, 0.2, 0.2, mat) is not a
    assert hs.HalfSpaceInfluence.for_grid(21, 13, 0.2, 0.15, Material.identical(70000.0, 0.3)) is not a
    for i, j in ((2, 2), (0, 0), (0, 1), (1, 1)):
        np.testing.assert_array_equal(a.kernel_hat(i, j), fresh.kernel_hat(i, j))
    np.testing.assert_array_equal(a.self_influence(), fresh.self_influence())
    p = np.random.default_rng(1).random((2, 21, 13))
    np.testing.assert_array_equal(a.tangential_product32()(p), fresh.tangential_product32()(p))
    assert a.tangential_product32() is a.tangential_product32()
    np.testing.assert_array_equal(a.normal_preconditioner()(p[0]), fresh.normal_preconditioner()(p[0]))
    big = int(hs.CACHE_ELEMENTS ** 0.5) + 1
    assert hs.HalfSpaceInfluence.for_grid(big, big, 0.2, 0.2, mat) is not hs.HalfSpaceInfluence.for_grid(
        big, big, 0.2, 0.2, mat)


def test_shared_operator_cache_is_bounded_by_entries_and_elements():
    """The shared operators are dropped least recently used first once more than ``max_entries``
    are kept or their grids exceed ``max_elements`` in all; one that is asked for again moves to
    the end; the process-wide cache has the documented bounds."""
    from conformal.influence import halfspace as hs

    assert (hs._shared_operator.max_entries, hs._shared_operator.max_elements) == (hs.CACHE_OPERATORS,
                                                                                   hs.CACHE_TOTAL_ELEMENTS)
    cache = hs._OperatorCache(max_entries=3, max_elements=1000)
    key = (0.2, 0.2, 82000.0, 0.28, 0.0)
    a, b = cache(10, 10, *key), cache(20, 20, *key)             # 100 + 400 elements
    assert cache(10, 10, *key) is a and len(cache) == 2 and cache.elements == 500
    c = cache(20, 30, *key)                                      # 1100 in all: b (least recently used) goes
    assert len(cache) == 2 and cache.elements == 700 and cache(10, 10, *key) is a
    assert cache(20, 20, *key) is not b                          # built anew: c goes (a was just used)
    assert cache(10, 10, *key) is a and cache.elements == 500
    assert cache(20, 30, *key) is not c and cache.elements == 700       # the 20 x 20 went
    for n in range(1, 6):                                        # at most 3 entries
        cache(n, 1, *key)
    assert len(cache) == 3 and cache.elements == 3 + 4 + 5


def test_corner_lattice_slices_equal_own_evaluations():
    """The corner primitives of a grid taken from its element size's lattice (grown by larger grids,
    restarted beyond its bound) equal those the grid evaluates itself, bitwise, and the kernels of
    a shared operator those of a fresh one."""
    from conformal.influence import halfspace as hs
    from conformal.materials import Material

    lat = hs.CornerLattice(0.2, 0.15, max_elements=3000)
    for mx, my in ((7, 5), (30, 4), (12, 40), (3, 3), (55, 50), (31, 41)):
        own = hs._primitives(((np.arange(mx) + 0.5) * 0.2)[:, None], ((np.arange(my) + 0.5) * 0.15)[None, :])
        for f, g in zip(lat.primitives(mx, my), own):
            np.testing.assert_array_equal(f, g)
    assert lat.shape == (55, 50)     # 40 x 40 held all before; 55 x 50 beyond 3000 corners started anew
    # the corner differences at the offsets of a grid: a slice of the lattice's, bitwise the grid's own
    for mx, my in ((7, 5), (55, 50), (1, 1), (20, 33)):
        own = hs._primitives(((np.arange(mx) + 0.5) * 0.2)[:, None], ((np.arange(my) + 0.5) * 0.15)[None, :])
        for name, k in hs._PRIM_INDEX.items():
            D = lat.differences(name, mx, my)
            assert D.shape == (2 * mx - 1, 2 * my - 1)
            np.testing.assert_array_equal(D, hs._differences(own[k], name))
    grow = hs.CornerLattice(0.2, 0.2, max_elements=10000)      # a growing side grows by half
    grow.primitives(40, 30)
    grow.primitives(42, 30)
    assert grow.shape == (60, 30) and grow.primitives(59, 29)[0].shape == (59, 29)
    grow.primitives(61, 100)
    assert grow.shape == (90, 100)
    grow.primitives(91, 105)              # half as many rows more would pass the bound: those asked for
    assert grow.shape == (91, 105)
    mat = Material(82000.0, 0.28, 26000.0, 0.33)                 # coupled: T1, T2 used too
    for mx, my in ((23, 9), (41, 17), (17, 30)):
        a = hs.HalfSpaceInfluence.for_grid(mx, my, 0.2, 0.15, mat)
        b = hs.HalfSpaceInfluence.for_grid(mx, my, 0.2, 0.15, mat, shared=False)
        for i in range(3):
            np.testing.assert_array_equal(a.self_influence(), b.self_influence())
            for j in range(3):
                np.testing.assert_array_equal(a._component(i, j), b._component(i, j))
                np.testing.assert_array_equal(a.kernel_hat(i, j), b.kernel_hat(i, j))
    assert len(hs._corner_lattice(0.2, 0.15)._derived) <= hs.LATTICE_DERIVED
