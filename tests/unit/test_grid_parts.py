"""conformal.grid.connected_parts: the parts of a contact mask by runs along the rows, checked
element by element against scipy.ndimage.label (an independent implementation) on structured and
random masks, through each of its three routes (one convex part; union-find in Python; union-find
in numpy calls) and the graph route of arrays with more axes; and what a planar result takes from
the parts and the grid (patch forces, extent, edge warning, the moment MZ)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

import conformal.grid as grid_module
from conformal.grid import connected_parts


def _ellipse(mx, my, cx=0.0, cy=0.0, r=1.0):
    X, Y = np.meshgrid(np.linspace(-1.2, 1.2, mx), np.linspace(-1.2, 1.2, my), indexing="ij")
    return (X - cx) ** 2 + (Y - cy) ** 2 < r * r


def _spiral(n):
    m = np.zeros((n, n), bool)
    t, l, b, r = 0, 0, n - 1, n - 1
    while t <= b and l <= r:
        m[t, l:r + 1] = True
        m[t:b + 1, r] = True
        m[b, l:r + 1] = True
        m[t + 2:b + 1, l] = True
        t, l, b, r = t + 2, l + 2, b - 2, r - 2
    return m


def _serpentine(n):
    m = np.zeros((n, n), bool)
    m[::2] = True
    m[1::4, -1] = True
    m[3::4, 0] = True
    return m


def _structured():
    ring = _ellipse(41, 37) & ~_ellipse(41, 37, r=0.6)
    two = _ellipse(55, 33, cy=-0.6, r=0.5) | _ellipse(55, 33, cy=0.6, r=0.5)   # two patches side by side
    checker = (np.add.outer(np.arange(9), np.arange(7)) % 2).astype(bool)
    u = np.zeros((6, 9), bool)
    u[:, 0] = u[:, -1] = u[-1] = True                   # one part whose arms join only in the last row
    stairs = np.eye(8, dtype=bool) | np.eye(8, k=1, dtype=bool)
    return {
        "ellipse 55 x 33": _ellipse(55, 33), "ellipse 110 x 11": _ellipse(110, 11), "ring": ring, "two": two,
        "spiral": _spiral(51), "serpentine": _serpentine(41), "serpentine across": _serpentine(41).T,
        "checker": checker, "u": u, "stairs": stairs, "diagonal": np.eye(7, dtype=bool),
        "full": np.ones((5, 4), bool), "one element": np.ones((1, 1), bool), "row": np.ones((1, 9), bool),
        "column": np.ones((9, 1), bool), "two rows apart": np.array([[1, 1], [0, 0], [1, 1]], bool),
    }


@pytest.mark.parametrize("join_max", [grid_module.PYTHON_JOIN_MAX, 0, 10 ** 9])
def test_structured_masks_equal_ndimage_label(monkeypatch, join_max):
    """Convex patches (one part), two patches, a ring, a spiral, serpentines, a checkerboard (every
    element its own part), U and stair shapes, single rows and columns: labels and count equal
    scipy.ndimage.label's, whichever way the runs are joined."""
    monkeypatch.setattr(grid_module, "PYTHON_JOIN_MAX", join_max)
    for name, m in _structured().items():
        labels, n = connected_parts(m)
        ref, n_ref = ndimage.label(m)
        assert n == n_ref, name
        assert labels.dtype == np.int32 and labels.shape == m.shape, name
        np.testing.assert_array_equal(labels, ref, err_msg=name)


def test_known_counts():
    """Counts that follow from the shapes: a 9 x 7 checkerboard has 31 parts (its elements of odd i + j),
    two separated ellipses two, a ring and a U one each, a diagonal of 7 elements (corners only)
    7, an empty mask none."""
    s = _structured()
    assert connected_parts(s["checker"])[1] == 31
    assert connected_parts(s["two"])[1] == 2
    assert connected_parts(s["ring"])[1] == 1
    assert connected_parts(s["u"])[1] == 1
    assert connected_parts(s["diagonal"])[1] == 7
    assert connected_parts(np.zeros((4, 3), bool))[1] == 0
    assert connected_parts(np.zeros((0, 3), bool))[1] == 0


@pytest.mark.parametrize("join_max", [grid_module.PYTHON_JOIN_MAX, 0, 10 ** 9])
def test_random_masks_equal_ndimage_label(monkeypatch, join_max):
    """300 random masks (1 x 1 to 39 x 39, densities 0..1) and 100 random 1-D masks: labels and
    count equal scipy.ndimage.label's through each join."""
    monkeypatch.setattr(grid_module, "PYTHON_JOIN_MAX", join_max)
    rng = np.random.default_rng(7)
    for _ in range(300):
        m = rng.random(tuple(rng.integers(1, 40, size=2))) < rng.random()
        labels, n = connected_parts(m)
        ref, n_ref = ndimage.label(m)
        assert n == n_ref
        np.testing.assert_array_equal(labels, ref)
    for _ in range(100):
        m = rng.random(int(rng.integers(1, 60))) < rng.random()
        labels, n = connected_parts(m)
        ref, n_ref = ndimage.label(m)
        assert n == n_ref and labels.shape == m.shape
        np.testing.assert_array_equal(labels, ref)


def test_views_integers_and_more_axes():
    """A transposed (non-contiguous) view and an integer array label as the boolean copy; a 3-D
    array goes through the graph of neighbours and still equals ndimage.label (6-neighbourhood)."""
    rng = np.random.default_rng(3)
    m = rng.random((23, 17)) < 0.55
    for view in (m.T, m[::2, ::-1], m.astype(int)):
        labels, n = connected_parts(view)
        ref, n_ref = ndimage.label(np.asarray(view, bool))
        assert n == n_ref
        np.testing.assert_array_equal(labels, ref)
    cube = rng.random((7, 8, 9)) < 0.4
    labels, n = connected_parts(cube)
    ref, n_ref = ndimage.label(cube)
    assert n == n_ref
    np.testing.assert_array_equal(labels, ref)


def test_many_parts_on_a_large_grid():
    """A 300 x 300 random mask (thousands of parts, the numpy join) equals ndimage.label."""
    m = np.random.default_rng(11).random((300, 300)) < 0.55
    labels, n = connected_parts(m)
    ref, n_ref = ndimage.label(m)
    assert n == n_ref > 1000
    np.testing.assert_array_equal(labels, ref)


def test_totals_moment_is_the_sum_over_the_element_centres():
    """TractionField.totals on an offset planar grid: FN, FX, FY the sums p dA, and MZ the sum of
    (x p_y - y p_x) dA over the element centres of PlanarGrid.mesh, to the last bit (the same
    products and the same summation)."""
    from conformal.grid import PlanarGrid
    from conformal.result import TractionField

    rng = np.random.default_rng(5)
    g = PlanarGrid(mx=23, my=17, dx=0.21, dy=0.37, xl=-1.9, yl=0.4)
    pn, px, py = rng.random((3, 23, 17))
    f = TractionField(grid=g, pn=pn, px=px, py=py, status=np.ones((23, 17), np.int8))
    X, Y = g.mesh()
    FN, FX, FY, MZ = f.totals()
    assert (FN, FX, FY) == (float(pn.sum() * g.area), float(px.sum() * g.area), float(py.sum() * g.area))
    assert MZ == float((X * py - Y * px).sum() * g.area)


def test_planar_result_patches_extent_and_edges():
    """Two pressure patches on a planar grid, the second touching the grid's y = yh side: patch_FN
    holds each patch's sum p dA (largest first, parts from ndimage.label), a and b half the extent of
    the contact rows and columns, and the one edge warning names y = yh only."""
    from conformal.grid import PlanarGrid
    from conformal.solvers.exact import _edge_warning, _patches, patch_extent

    g = PlanarGrid(mx=30, my=20, dx=0.5, dy=0.25, xl=-7.5, yl=-2.5)
    X, Y = g.mesh()
    pn = np.maximum(0.0, 1.0 - ((X + 2.0) / 3.0) ** 2 - ((Y + 0.5) / 1.2) ** 2)
    pn += 2.0 * np.maximum(0.0, 1.0 - ((X - 3.0) / 1.5) ** 2 - ((Y - 2.4) / 0.6) ** 2)
    contact = pn > 0
    labels, n = ndimage.label(contact)
    assert n == 2
    expected = sorted((float(pn[labels == k].sum() * g.area) for k in (1, 2)), reverse=True)
    np.testing.assert_allclose(_patches(g, pn, contact), expected, rtol=1e-14)
    ix, iy = np.flatnonzero(contact.any(axis=1)), np.flatnonzero(contact.any(axis=0))
    a, b = patch_extent(g, contact)
    assert (a, b) == (0.5 * (ix[-1] - ix[0] + 1) * g.dx, 0.5 * (iy[-1] - iy[0] + 1) * g.dy)
    assert patch_extent(g, np.zeros_like(contact)) == (0.0, 0.0)
    warning = _edge_warning(g, contact)
    assert "y = yh" in warning and "y = yl" not in warning and "x = x" not in warning
    assert _edge_warning(g, contact, contact.any(axis=1), contact.any(axis=0)) == warning
    assert _edge_warning(g, np.zeros_like(contact)) is None
