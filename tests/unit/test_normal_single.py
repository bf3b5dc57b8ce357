"""The preconditioned force-prescribed normal iteration with single-precision products far from
its tolerance (conformal.solvers.normal: SINGLE_PRECISION, SINGLE_ABOVE;
HalfSpaceInfluence.normal_product32) against the same iteration in double precision throughout,
and the plain iteration, which stays in double precision."""
import numpy as np
import pytest

from conformal.grid import PlanarGrid
from conformal.influence.halfspace import HalfSpaceInfluence, Z
from conformal.influence.operator import build_operator
from conformal.materials import Material
from conformal.solvers import normal
from conformal.solvers.normal import solve_normal
from conformal.theories.hertz import hertz_from_semiaxes

STEEL = Material.steel()
FN = 1e5


def _hertz(n: int = 41):
    """A Hertz circle of radius 5 mm on an n x n grid of side 4 a."""
    hz = hertz_from_semiaxes(5.0, 5.0, STEEL, normal_force=FN)
    g = PlanarGrid.around_ellipse(5.0, 5.0, n=n, scale=2.0)
    X, Y = g.mesh()
    return hz, g, hz.A * X**2 + hz.B * Y**2


def _solve(monkeypatch, single: bool, tol: float, n: int = 41, above: float | None = None):
    monkeypatch.setattr(normal, "SINGLE_PRECISION", single)
    if above is not None:
        monkeypatch.setattr(normal, "SINGLE_ABOVE", above)
    hz, g, h = _hertz(n)
    op, _ = build_operator(g, STEEL)
    return op, solve_normal(op, g, h, normal_force=FN, tol=tol, material=STEEL, precondition=True)


def test_normal_product32_is_the_double_product_to_float32_rounding():
    op = HalfSpaceInfluence.for_grid(23, 17, 0.2, 0.3, STEEL)
    kh = op.kernel_hat(Z, Z)
    assert np.abs(kh.imag).max() <= 1e-12 * np.abs(kh.real).max()      # A_zz even: a real spectrum
    p = np.random.default_rng(3).random((23, 17))
    u64, u32 = op.apply_normal(p), op.normal_product32()(p)
    assert u32.dtype == np.float64 and u32.shape == u64.shape
    err = np.abs(u32 - u64).max() / np.abs(u64).max()
    assert 0.0 < err < 1e-6


@pytest.mark.parametrize("window", [True, False])
@pytest.mark.parametrize("tol", [1e-4, 1e-6])
def test_mixed_precision_agrees_with_double_within_the_tolerance(monkeypatch, tol, window):
    if not window:    # the iteration on the whole grid, whose u is returned
        monkeypatch.setattr(normal, "WINDOW_MARGIN", -1)
    op, ref = _solve(monkeypatch, False, tol)
    _, sol = _solve(monkeypatch, True, tol)
    assert sol.converged and ref.converged and sol.residual < tol
    assert np.abs(sol.pn - ref.pn).sum() / ref.pn.sum() < tol
    assert abs(sol.approach - ref.approach) < tol * abs(ref.approach)
    assert sol.FN == pytest.approx(ref.FN, rel=1e-12)
    # the returned displacement is a double-precision product of the returned pressure
    u = op.apply_normal(sol.pn)
    assert np.abs(sol.un - u).max() <= 1e-12 * np.abs(u).max()


def test_a_tight_solve_ends_in_double_precision(monkeypatch):
    """The float32 product's fixed point differs from the double one by about 5e-7 of the pressure:
    a solve to 1e-9 agrees with the double one only if it switches to double products (with the
    switch disabled, SINGLE_ABOVE = 0, it stops on single-precision products and does not)."""
    tol = 1e-9
    _, ref = _solve(monkeypatch, False, tol)
    _, sol = _solve(monkeypatch, True, tol)
    _, never = _solve(monkeypatch, True, tol, above=0.0)
    dev = lambda s: np.abs(s.pn - ref.pn).sum() / ref.pn.sum()   # noqa: E731
    assert sol.converged and sol.residual < tol
    assert dev(sol) < 1e-8
    assert dev(never) > 1e-7       # (this test's power: the switch is what makes the difference)


def test_single_products_only_far_from_the_tolerance(monkeypatch):
    """Products in float32 while the pressure changes by SINGLE_ABOVE or more, then double ones."""
    calls = []
    make = HalfSpaceInfluence.normal_product32

    def spy(self):
        f = make(self)
        return lambda p: calls.append("single") or f(p)

    monkeypatch.setattr(HalfSpaceInfluence, "normal_product32", spy)
    apply = HalfSpaceInfluence.apply_normal
    monkeypatch.setattr(HalfSpaceInfluence, "apply_normal", lambda self, p: calls.append("double") or apply(self, p))
    _, sol = _solve(monkeypatch, True, 1e-8)
    assert sol.converged
    first_double = calls.index("double")
    assert first_double > 0 and "single" not in calls[first_double:]


def test_the_plain_iteration_stays_in_double_precision(monkeypatch):
    """Without the preconditioner the planar grid keeps the arithmetic of the curved strips."""
    monkeypatch.setattr(HalfSpaceInfluence, "normal_product32", lambda self: pytest.fail("single product"))
    hz, g, h = _hertz()
    sol = solve_normal(None, g, h, normal_force=FN, tol=1e-6, material=STEEL, precondition=False)
    assert sol.converged and not sol.preconditioned
