"""The contact solves' leaner array handling, each against the expression it replaces (bitwise):
the cross products of the creepages, the rigid slip and rotated tangents of the tangential
solver, the half-space tangential product, the normal preconditioner's kept padded field, the
slip rows' weights of the Newton preconditioner and the Newton loop's last residual."""
import numpy as np
import pytest

from conformal.geometry.kinematics import _cross
from conformal.grid import PlanarGrid
from conformal.influence import fft as ffts
from conformal.influence.halfspace import HalfSpaceInfluence, X, Y
from conformal.materials import Material
from conformal.solvers import tangential as tang
from conformal.theories.hertz import hertz_from_semiaxes

STEEL = Material.steel()
MU = 0.3


@pytest.mark.parametrize("shape_a, shape_b", [((3,), (3,)), ((5, 3), (3,)), ((3,), (4, 3)), ((2, 6, 3), (2, 6, 3))])
def test_cross_is_numpy_cross(shape_a, shape_b):
    rng = np.random.default_rng(7)
    for _ in range(200):
        a = rng.standard_normal(shape_a) * 10.0 ** rng.integers(-6, 6)
        b = rng.standard_normal(shape_b) * 10.0 ** rng.integers(-6, 6)
        ref, got = np.cross(a, b), _cross(a, b)
        assert got.shape == ref.shape and got.tobytes() == ref.tobytes()


def test_column_rigid_slip_is_the_stacked_broadcasts():
    g = PlanarGrid.centred(7, 5, 0.2, 0.3)
    Y_ = g.y[None, :]
    for steady in (True, False):
        for xi, eta, phi in ((1e-3 - 2e-4 * Y_, 3e-3, 2e-4), (np.linspace(0, 1e-3, 5), np.full(5, 2e-3), 1e-4)):
            X_ = g.x[:, None]
            dq6 = g.dx / 6.0 if steady else 0.0
            ref = np.stack([np.broadcast_to(xi, g.shape), np.broadcast_to(eta + phi * (X_ + dq6), g.shape)])
            got = tang.column_rigid_slip(g, xi, eta, phi, steady)
            assert got.shape == ref.shape and got.tobytes() == ref.tobytes()


def test_rotated_tangent_is_the_stacked_one():
    n = np.random.default_rng(2).standard_normal((2, 11))
    assert tang._rotated(n).tobytes() == np.stack([-n[1], n[0]]).tobytes()


def test_tangential_product_is_the_stacked_complex_product():
    """(u_x, u_y) with the fields padded in one array and the kernel products into their result:
    the numbers of the stacked fields, the rfft/fft of the padded half-spectrum, fxx h0 + fxy h1,
    fxy h0 + fyy h1 and the transforms back."""
    op = HalfSpaceInfluence.for_grid(9, 6, 0.2, 0.3, STEEL, shared=False)
    rng = np.random.default_rng(5)
    px, py = rng.standard_normal((2, 9, 6))
    Mx, My = op.padded_shape
    spec = np.zeros((2, Mx, My // 2 + 1), dtype=complex)
    ffts.rfft(np.stack([px, py]), My, axis=-1, out=spec[:, :9])
    h = ffts.fft(spec, axis=-2, overwrite=True)
    fxx, fxy, fyy = op.kernel_hat(X, X), op.kernel_hat(X, Y), op.kernel_hat(Y, Y)
    acc = np.stack([fxx * h[0] + fxy * h[1], fxy * h[0] + fyy * h[1]])
    ref = ffts.irfft(ffts.ifft(acc, axis=-2, overwrite=True)[:, :9], My, axis=-1)[:, :, :6]
    ux, uy = op.apply_tangential(px, py)
    assert np.array_equal(ux, ref[0]) and np.array_equal(uy, ref[1])


def test_normal_preconditioner_keeps_its_padded_field():
    """One preconditioner applied to several fields gives each field's own answer (its padding
    stays zero), as a fresh preconditioner per field."""
    op = HalfSpaceInfluence.for_grid(13, 7, 0.2, 0.2, STEEL, shared=False)
    rng = np.random.default_rng(4)
    fields = rng.standard_normal((3, 13, 7))
    pc = op.normal_preconditioner()
    for f in fields:
        assert np.array_equal(pc(f), op.normal_preconditioner()(f))


def _newton_state(xi=2e-4, phi=2e-4):
    """A Newton state of a partly slipping Hertz patch off its solution, with its slip operator."""
    hz = hertz_from_semiaxes(6.0, 4.0, STEEL, normal_force=10e3)
    g = PlanarGrid.around_ellipse(hz.a, hz.b, n=24, scale=1.3)
    X_, Y_ = g.mesh()
    pn = hz.pressure(X_, Y_)
    op = HalfSpaceInfluence.for_grid(g.mx, g.my, g.dx, g.dy, STEEL)
    L = tang._SlipOperator(op, g, pn > 0, True)
    idx = L.idx
    gk = (MU * pn).ravel()[idx]
    w = tang.column_rigid_slip(g, xi - phi * g.y[None, :], 0.0, phi, True).reshape(2, -1)[:, idx].copy()
    newton = tang._Newton(L, w, gk, gk, np.full(idx.size, g.area), [], MU * pn.sum() * g.area)
    newton.creep0 = np.zeros(2)
    p = np.zeros((2, idx.size))
    return newton, tang._State(p, w + L.apply(p), np.zeros(2), np.zeros(idx.size, bool))


def test_slip_weights_only_where_used():
    """The preconditioner's slip rows with sigma above STIFF_RATIO diag get weight 0 without the
    power: its answer is that of the weights np.where(sigma > 3 diag, 0, (diag/(diag+sigma))^1.5)."""
    newton, st = _newton_state()
    nc, diag = newton.nc, newton.L.diag
    t = np.stack([np.ones(nc), np.zeros(nc)])
    sigma = np.geomspace(0.1, 30.0, nc) * diag            # both kinds of rows
    empty, isl = np.zeros(0, dtype=np.intp), np.arange(nc)
    r = np.random.default_rng(3).standard_normal(nc)
    got = newton.preconditioner(empty, isl, empty, np.concatenate([isl, nc + isl]), t, sigma)(r)
    w = np.where(sigma > tang.STIFF_RATIO * diag, 0.0, (diag / (diag + sigma)) ** tang.SLIP_WEIGHT_POWER)
    q = newton.L.precondition((r * w) * t)
    ref = w * (t[0] * q[0] + t[1] * q[1]) + (1.0 - w) / (sigma + diag) * r
    assert np.array_equal(got, ref)


def test_newton_loop_returns_the_residual_of_its_state():
    """The residual the Newton loop hands back with its final state is that state's residual."""
    newton, st = _newton_state()
    st, its, res, msg, last = newton.solve(st, 1e-6, 50)
    assert its > 0 and res <= 1e-6 and not msg
    F, ferr, slip = newton.residual(st.p, st.s, st.slipping)
    if last is not None:
        assert np.array_equal(last[0], F) and last[1] == ferr and np.array_equal(last[2], slip)
    assert newton.measure(st.p, F, ferr) == res
    assert 0 < np.count_nonzero(slip) < newton.nc       # partial slip


def _resample_reference(src, values, dst):
    """The bilinear resampling with numpy.pad and fancy indexing (the expression resample replaces)."""
    def axis(n_src, lo_src, d_src, n_dst, lo_dst, d_dst):
        f = (lo_dst + (np.arange(n_dst) + 0.5) * d_dst - lo_src) / d_src - 0.5
        near = np.rint(f)
        f = np.where(np.abs(f - near) <= 1e-9, near, f)
        i0 = np.floor(f).astype(int)
        w = f - i0
        return np.clip(i0, -1, n_src) + 1, np.clip(i0 + 1, -1, n_src) + 1, w

    values = np.asarray(values, float)
    v = np.pad(values, [(0, 0)] * (values.ndim - 2) + [(1, 1), (1, 1)])
    ia, ib, wi = axis(src.mx, src.xl, src.dx, dst.mx, dst.xl, dst.dx)
    ja, jb, wj = axis(src.my, src.yl, src.dy, dst.my, dst.yl, dst.dy)
    rows = (1.0 - wi)[:, None] * v[..., ia, :] + wi[:, None] * v[..., ib, :]
    return (1.0 - wj)[None, :] * rows[..., ja] + wj[None, :] * rows[..., jb]


@pytest.mark.parametrize("stack", [False, True])
def test_resample_is_the_padded_bilinear_interpolation(stack):
    from conformal.cases.wheelrail import resample

    rng = np.random.default_rng(11)
    src = PlanarGrid(12, 9, 0.2, 0.25, -1.3, -1.1)
    values = rng.random((3, 12, 9) if stack else (12, 9))
    for dst in (PlanarGrid(15, 7, 0.2, 0.25, -1.5, -0.9), PlanarGrid(10, 12, 0.17, 0.3, -0.7, -2.0),
                PlanarGrid(12, 9, 0.2, 0.25, -1.1, -1.1)):
        ref, got = _resample_reference(src, values, dst), resample(src, values, dst)
        assert got.shape == ref.shape and got.tobytes() == ref.tobytes()
