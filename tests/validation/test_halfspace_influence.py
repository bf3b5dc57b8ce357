"""Half-space influence numbers against the verified reference values (closed forms of Love 1929 and Kalker 1990, tabulated values)."""
import math

import numpy as np
import pytest

from conformal.influence.halfspace import HalfSpaceInfluence, rectangle_influence, single_body_influence
from conformal.materials import Material

IDX = {"x": 0, "y": 1, "z": 2}

# Table 1: G = 1, dx = dy = 1, nu = 0.28, K = 0.1
OFFSETS_1 = [(0, 0), (1, 0), (0, 1), (2, 3), (10, 0)]
TABLE_1 = {
    "xx": [9.650917460234e-01, 3.214217517720e-01, 2.469032166850e-01, 7.146187404728e-02, 3.183679228905e-02],
    "xy": [0, 0, 0, 1.129965903671e-02, 0],
    "xz": [0, -3.133991464121e-02, 0, -4.896900494678e-03, -3.183093556717e-03],
    "yx": [0, 0, 0, 1.129965903671e-02, 0],
    "yy": [9.650917460234e-01, 2.469032166850e-01, 3.214217517720e-01, 8.088288085438e-02, 2.293530035971e-02],
    "yz": [0, 0, -3.133991464121e-02, -7.346466007728e-03, 0],
    "zx": [0, 3.133991464121e-02, 0, 4.896900494678e-03, 3.183093556717e-03],
    "zy": [0, 0, 3.133991464121e-02, 7.346466007728e-03, 0],
    "zz": [8.079837873684e-01, 2.379034751680e-01, 2.379034751680e-01, 6.377222298209e-02, 2.292785273669e-02],
}
# Table 2: G = 2.5, dx = 0.6, dy = 1.5, nu = 0.3, K = -0.05 (catches dx/dy mix-ups and K sign errors)
OFFSETS_2 = [(0, 0), (0.3, 0), (1.0, 0.5), (-0.5, 2.0), (4.0, -6.0)]
TABLE_2 = {
    "xx": [3.251573840225e-01, 2.519716249568e-01, 9.416643556406e-02, 4.178167598079e-02, 1.262985250764e-02],
    "xy": [0, 0, 8.010056569904e-03, -4.256914282870e-03, -2.202919292576e-03],
    "xz": [0, 9.207359465971e-03, 4.406711340814e-03, -7.476634148988e-04, 4.431003803225e-04],
    "yy": [3.559661427103e-01, 2.580109527200e-01, 7.716107508712e-02, 5.644767241626e-02, 1.443674362185e-02],
    "yz": [0, 0, 1.734828948425e-03, 2.774323016756e-03, -6.606340863259e-04],
    "zx": [0, -9.207359465971e-03, -4.406711340814e-03, 7.476634148988e-04, -4.431003803225e-04],
    "zy": [0, 0, -1.734828948425e-03, -2.774323016756e-03, 6.606340863259e-04],
    "zz": [2.804626286547e-01, 2.099928261022e-01, 7.054662203284e-02, 4.044737875173e-02, 1.114506899450e-02],
}


@pytest.mark.parametrize("offsets,table,args", [
    (OFFSETS_1, TABLE_1, dict(dx=1.0, dy=1.0, G=1.0, nu=0.28, K=0.1)),
    (OFFSETS_2, TABLE_2, dict(dx=0.6, dy=1.5, G=2.5, nu=0.3, K=-0.05)),
])
def test_reference_tables(offsets, table, args):
    x = np.array([o[0] for o in offsets], float)
    y = np.array([o[1] for o in offsets], float)
    A = rectangle_influence(x, y, args.pop("dx"), args.pop("dy"), **args)
    for key, ref in table.items():
        got = A[:, IDX[key[0]], IDX[key[1]]]
        ref = np.array(ref)
        # the reference is exact to 12 digits; float64 double differences at r <= 10 dx lose < 1e-12
        np.testing.assert_allclose(got[ref != 0], ref[ref != 0], rtol=1e-11, err_msg=key)
        assert np.all(np.abs(got[ref == 0]) < 1e-15), key


def test_self_term_closed_form():
    dx, dy, G, nu = 0.3, 0.7, 82000.0, 0.28
    A = rectangle_influence(np.array(0.0), np.array(0.0), dx, dy, G=G, nu=nu)
    zz = 2 * (1 - nu) / (math.pi * G) * (dx * math.asinh(dy / dx) + dy * math.asinh(dx / dy))
    xx = 2 / (math.pi * G) * ((1 - nu) * dx * math.asinh(dy / dx) + dy * math.asinh(dx / dy))
    assert A[2, 2] == pytest.approx(zz, rel=1e-14)
    assert A[0, 0] == pytest.approx(xx, rel=1e-14)


def test_two_identical_bodies_are_twice_one_body_without_coupling():
    x, y = np.array([0.0, 1.0, -2.0, 3.5]), np.array([0.0, 0.5, 1.0, -4.0])
    one = single_body_influence(x, y, 1.0, 0.8, G=50.0, nu=0.3)
    two = rectangle_influence(x, y, 1.0, 0.8, G=50.0, nu=0.3, K=0.0)
    # body 2 mirrored: same normal/tangential parts, coupling terms cancel (reference §2.2)
    for i, j in [(0, 0), (1, 1), (2, 2), (0, 1)]:
        np.testing.assert_allclose(two[:, i, j], 2 * one[:, i, j], rtol=1e-13)
    assert np.all(two[:, 2, 0] == 0) and np.any(one[:, 2, 0] != 0)


def test_far_field_is_point_load():
    # reference §4.2: point-load term alone is off by 7.4e-4 at r = 10 dx, 5e-5 at r = 50 dx
    G, nu = 1.0, 0.28
    for r, tol in [(10.0, 1e-3), (50.0, 1e-4)]:
        A = rectangle_influence(np.array(r), np.array(0.0), 1.0, 1.0, G=G, nu=nu)
        assert A[2, 2] == pytest.approx((1 - nu) / (math.pi * G) / r, rel=tol)


def test_fft_product_equals_dense_matrix_and_is_symmetric():
    m = Material(0.6875, 0.28, 1.833333, 0.28)  # K = 0.1
    op = HalfSpaceInfluence.for_grid(9, 6, 0.7, 1.3, m)
    D = op.dense()
    assert np.abs(D - D.T).max() < 1e-15 * np.abs(D).max()
    p = np.random.default_rng(1).random((3, 9, 6))
    u = op.apply(p)
    np.testing.assert_allclose(u.ravel(), D @ p.ravel(), rtol=0, atol=1e-14 * np.abs(u).max())
    N = 54
    np.testing.assert_allclose(op.apply_normal(p[2]).ravel(), D[2 * N:, 2 * N:] @ p[2].ravel(), atol=1e-14)
    ux, uy = op.apply_tangential(p[0], p[1])
    np.testing.assert_allclose(np.concatenate([ux.ravel(), uy.ravel()]), D[:2 * N, :2 * N] @ p[:2].ravel(),
                               atol=1e-14)


# ----------------------------------------------------------------------------- the operator protocol
def test_extended_and_coarsened_operators_equal_the_ones_built_for_those_grids():
    from conformal.grid import PlanarGrid
    from conformal.influence.operator import build_operator

    mat = Material(82000.0, 0.28, 40000.0, 0.3)              # dissimilar: K != 0 is kept
    op, info = build_operator(PlanarGrid.centred(5, 4, 0.3, 0.2), mat)
    assert info["influence"] == "halfspace" and op.coupled
    longer = HalfSpaceInfluence.for_grid(7, 4, 0.3, 0.2, mat)
    assert np.array_equal(op.extended(2).dense(), longer.dense())
    coarse = HalfSpaceInfluence.for_grid(3, 2, 0.6, 0.4, mat)   # ceil(5/2) x 4/2 merged elements
    assert np.array_equal(op.coarsened(2, 2).dense(), coarse.dense())
    assert op.contact_modulus() == pytest.approx(mat.E_star, rel=1e-15)


def test_single_precision_tangential_product_and_normal_preconditioner():
    from conformal.grid import PlanarGrid
    from conformal.influence.operator import build_operator

    op, _ = build_operator(PlanarGrid.centred(9, 7, 0.2, 0.3), Material.steel())
    p = np.random.default_rng(1).standard_normal((2, 9, 7))
    u = np.stack(op.apply_tangential(*p))
    u32 = op.tangential_product32()(p.astype(np.float32))
    assert u32.dtype == np.float32
    assert np.abs(u32 - u).max() < 1e-6 * np.abs(u).max()
    # the preconditioner multiplies by |k| (module docstring of conformal.solvers.normal): positive definite
    P = op.normal_preconditioner()
    g = p[0]
    assert float((g * P(g)).sum()) > 0.0


def test_line_and_strip_operators_through_the_factory():
    from conformal.grid import PlanarGrid
    from conformal.influence.halfplane import LineInfluence
    from conformal.errors import InputError
    from conformal.influence.operator import build_operator

    mat = Material.identical(80000.0, 0.3)
    grid = PlanarGrid(10, 1, 0.1, 1.0, -0.5, -0.5)
    op, info = build_operator(grid, mat, line=True)
    assert info["influence"] == "halfplane"
    ext = op.extended(3)
    ref = LineInfluence.for_grid(PlanarGrid(13, 1, 0.1, 1.0, -0.5, -0.5), mat, ref_length=op.ref_length)
    assert ext.ref_length == op.ref_length and np.array_equal(ext.dense(), ref.dense())
    # strips offer no preconditioner, no single precision and no coarsening: None, not an error
    assert op.normal_preconditioner() is None and op.tangential_product32() is None
    assert op.coarsened(2, 1) is None and op.contact_modulus() == pytest.approx(mat.E_star)
    with pytest.raises(InputError, match="influence"):
        build_operator(grid, mat, influence="fe")
