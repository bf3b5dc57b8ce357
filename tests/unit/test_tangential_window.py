"""The tangential solver's cheaper paths (conformal.solvers.tangential): the products on a window
around the contact elements, the lean Newton step and preconditioner of full slip, and the start
rescaled from a neighbouring solution.  Each is checked against the path it replaces: the whole
grid, the general Newton step, the unscaled start."""
import numpy as np
import pytest

from conformal.grid import PlanarGrid
from conformal.influence.halfspace import HalfSpaceInfluence
from conformal.materials import Material
from conformal.solvers import tangential as tang
from conformal.theories.hertz import hertz_from_semiaxes

STEEL = Material.steel()
MU = 0.3


def patch(n: int = 48, scale: float = 2.2):
    """A Hertz pressure (a = 6, b = 4 mm, 10 kN) in the middle of a grid ``scale`` times its size:
    the window of the products is a quarter of the grid."""
    hz = hertz_from_semiaxes(6.0, 4.0, STEEL, normal_force=10e3)
    g = PlanarGrid.around_ellipse(hz.a, hz.b, n=n, scale=scale)
    X, Y = g.mesh()
    return HalfSpaceInfluence.for_grid(g.mx, g.my, g.dx, g.dy, STEEL), g, hz.pressure(X, Y)


def solve(op, g, pn, **kw):
    args = dict(xi=0.0, eta=0.0, phi=0.0, mu_static=MU, mu_kinetic=MU)
    args.update(kw)
    return tang.solve_tangential(op, g, pn, **args)


def test_window_operator_is_the_block_of_the_whole_grid():
    """``window(mx, my)``: the matrix between the elements of any mx x my window of the grid."""
    from conformal.influence.curved import CurvedInfluence

    mat = Material(82000.0, 0.28, 40000.0, 0.3)              # dissimilar: the coupling terms too
    op = HalfSpaceInfluence.for_grid(6, 5, 0.3, 0.2, mat)
    D = op.dense()
    win = op.window(3, 4)
    assert (win.mx, win.my) == (3, 4)
    W = win.dense()
    for r0, c0 in ((0, 0), (2, 1), (3, 1)):
        cells = np.array([(r0 + i) * 5 + c0 + j for i in range(3) for j in range(4)])
        rows = np.concatenate([cells + k * 30 for k in range(3)])
        assert np.array_equal(W, D[np.ix_(rows, rows)])
    assert CurvedInfluence.window(None, 3, 4) is None         # strips: no window


@pytest.mark.parametrize("rolling, kin", [("steady", dict(xi=5e-5, phi=5e-5)), ("shift", dict(xi=1e-3, eta=5e-4))])
def test_window_gives_the_whole_grid_solution(monkeypatch, rolling, kin):
    op, g, pn = patch()
    assert tang._window(pn > 0, rolling == "steady") is not None      # the window is used here
    win = solve(op, g, pn, rolling=rolling, **kin)
    monkeypatch.setattr(tang, "WINDOW_STEP", 0)
    whole = solve(op, g, pn, rolling=rolling, **kin)
    assert win.converged and whole.converged
    FN = pn.sum() * g.area
    # both within the solver's tolerance (1e-6 on the friction law) of the same solution
    for a, b in ((win.px, whole.px), (win.py, whole.py)):
        assert abs(a.sum() - b.sum()) * g.area <= 1e-5 * MU * FN
        assert np.abs(a - b).max() <= 1e-5 * MU * pn.max()
    assert np.count_nonzero(win.status != whole.status) <= 2
    assert 0 < np.count_nonzero(whole.status == 2) < np.count_nonzero(pn > 0)   # partial slip
    # the displacements on the whole grid, inside and outside the window
    scale = np.abs(whole.ux).max()
    assert np.abs(win.ux - whole.ux).max() <= 1e-5 * scale
    assert np.abs(win.uy - whole.uy).max() <= 1e-5 * scale
    # about as many products as on the whole grid, each on a quarter of it
    assert win.products <= whole.products + 4


def _full_slip_state():
    """A Newton state of a full-slip problem (large creepage), off the solution by a rotation of
    the tractions, on the grid of the window-free solver."""
    op, g, pn = patch(n=30, scale=1.1)
    sol = solve(op, g, pn, xi=0.01, eta=0.004)
    assert np.all(sol.status[pn > 0] == 2)
    L = tang._SlipOperator(op, g, pn > 0, True)
    idx = L.idx
    gk = (MU * pn).ravel()[idx]
    X, Y = g.mesh()
    w = tang.column_rigid_slip(g, 0.01 - 0.0 * Y, 0.004, 0.0, True).reshape(2, -1)[:, idx].copy()
    newton = tang._Newton(L, w, gk, gk, np.full(idx.size, g.area), [], MU * pn.sum() * g.area)
    newton.creep0 = np.zeros(2)
    c, s = np.cos(0.05), np.sin(0.05)
    p = np.stack([sol.px.ravel()[idx], sol.py.ravel()[idx]])
    p = np.stack([c * p[0] - s * p[1], s * p[0] + c * p[1]])
    st = tang._State(p, w + L.apply(p), np.zeros(2), np.ones(idx.size, bool))
    return newton, st


def test_full_slip_step_is_the_general_step():
    newton, st = _full_slip_state()
    F, ferr, slip = newton.residual(st.p, st.s, st.slipping)
    assert slip.all()
    dp, ds, dc, its = newton.step(st, F, ferr, slip, 1e-3)
    dp2, ds2, dc2, its2 = newton.step_full_slip(st, 1e-3)
    assert its == its2 > 0
    assert np.array_equal(dp, dp2) and np.array_equal(ds, ds2) and np.array_equal(dc, dc2)


def test_diagonal_preconditioner_is_the_general_one():
    newton, st = _full_slip_state()
    nc = newton.nc
    z = st.p - newton.c * st.s
    n = z / np.hypot(*z)
    t = np.stack([-n[1], n[0]])
    sigma = np.full(nc, 10.0 * newton.L.diag)      # every row stiffer than STIFF_RATIO diag
    empty, isl = np.zeros(0, dtype=np.intp), np.arange(nc)
    args = (empty, isl, empty, np.concatenate([isl, nc + isl]), t, sigma)
    r = np.random.default_rng(3).standard_normal(nc)
    lean = newton.preconditioner(*args)(r)
    general = newton.preconditioner(*args, lean=False)(r)
    assert np.array_equal(lean, general)
    assert not np.array_equal(lean, r)


@pytest.mark.parametrize("kin, fewer", [(dict(xi=2e-4, phi=2e-4), True), (dict(xi=0.01, eta=0.004), True),
                                        (dict(xi=5e-5, phi=5e-5), False)])
def test_rescaled_start_of_a_heavier_load(kin, fewer):
    """The solution under 5 % more pressure from the last one, carried over relative to the
    pressure: it converges to the same tractions as the plain start, and where (nearly) every
    element slips (a wheel-rail sweep) it starts on the new bound and needs a Newton step less.
    With a large adhesion area (a fifth slipping, the last case) the scaled tractions are no better
    a start than the plain ones."""
    op, g, pn = patch()
    first = solve(op, g, pn, **kin)
    p0 = np.stack([first.px, first.py])
    pn2 = 1.05 * pn
    plain = solve(op, g, pn2, p_start=p0, **kin)
    scaled = solve(op, g, pn2, p_start=tang.rescaled_start(p0, pn, pn2), **kin)
    assert plain.converged and scaled.converged
    FN = pn2.sum() * g.area
    assert abs(plain.px.sum() - scaled.px.sum()) * g.area <= 1e-5 * MU * FN
    assert abs(plain.py.sum() - scaled.py.sum()) * g.area <= 1e-5 * MU * FN
    slipping = np.count_nonzero(first.status == 2) / np.count_nonzero(pn > 0)
    assert (slipping > 0.9) == fewer
    if fewer:
        assert scaled.iterations < plain.iterations, (scaled.iterations, plain.iterations)


def test_centred_kernel_is_numpy_roll():
    """The preconditioner's probe, centred by block copies (tangential._centred_at), is
    numpy.roll(k, (-cx, -cy), axis=(0, 1)) for every centre of grids of 1 to 7 rows and columns."""
    from conformal.solvers.tangential import _centred_at

    rng = np.random.default_rng(0)
    for mx in range(1, 8):
        for my in range(1, 8):
            k = rng.random((mx, my))
            for cx in range(mx):
                for cy in range(my):
                    np.testing.assert_array_equal(_centred_at(k, cx, cy), np.roll(k, (-cx, -cy), axis=(0, 1)))
