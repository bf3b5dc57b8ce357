"""The cost of the tangential solver in counts, not times (the shared machine varies its wall and CPU
times by 2x): the single-precision product's column blocks, the reuse of the final product for the
displacements, CONTACT's own shift performance case (its contact and slip counts, our Newton steps
and products), and the growth of steady rolling from 200² to 400² in influence products
(studies/steady_rolling_speed.py measures the times)."""
from __future__ import annotations


import numpy as np
import pytest
from _studies import load_study

from conformal.grid import PlanarGrid
from conformal.influence.halfspace import HalfSpaceInfluence, TangentialProduct32
from conformal.materials import Material
from conformal.result import SLIP
from conformal.solvers.normal import solve_normal
from conformal.solvers.tangential import solve_tangential
from conformal.theories.hertz import hertz_from_curvatures

STEEL = Material.steel()


def _performance_study():
    return load_study("performance")


def circ(n: int):
    """Case circ of tests/reference/contact_performance.md with the Hertz pressure imposed."""
    hz = hertz_from_curvatures(0.001, 0.001, STEEL, normal_force=100e3)
    g = PlanarGrid.around_ellipse(hz.a, hz.b, n=n, scale=1.1)
    X, Y = g.mesh()
    return HalfSpaceInfluence.for_grid(n, n, g.dx, g.dy, STEEL), g, hz.pressure(X, Y)


def test_blocked_product_gives_the_unblocked_numbers():
    """Column blocks of the half-spectrum (large grids) change nothing: the transforms along x are
    per column; and both agree with the double-precision product to single precision."""
    op = HalfSpaceInfluence.for_grid(37, 29, 0.1, 0.12, STEEL, shared=False)
    p = np.random.default_rng(1).standard_normal((2, 37, 29)).astype(np.float32)
    whole = TangentialProduct32(op)
    blocked = TangentialProduct32(op)
    blocked.block = 4                     # 29 -> 30 padded columns: 8 blocks, the last one short
    assert whole.block >= op.padded_shape[1] // 2 + 1
    assert np.array_equal(blocked(p), whole(p))
    ref = np.stack(op.apply_tangential(*p.astype(float)))
    assert np.abs(whole(p) - ref).max() <= 1e-6 * np.abs(ref).max()


def test_displacements_of_the_solution_are_its_product():
    """The solution's (ux, uy) come from the last double-precision product of the solve: they are
    A p of the returned tractions."""
    op, g, pn = circ(60)
    sol = solve_tangential(op, g, pn, xi=1e-3, eta=2e-4, phi=0.0, mu_static=0.3, mu_kinetic=0.3)
    ux, uy = op.apply_tangential(sol.px, sol.py)
    scale = np.abs(ux).max()
    assert np.abs(sol.ux - ux).max() <= 1e-12 * scale and np.abs(sol.uy - uy).max() <= 1e-12 * scale


def test_contact_perfc_shift_case():
    """CONTACT's shift performance deck (perfc_test/tang_problm_1s.inp: Manchester right wheel at
    y = 6.2 mm, 71 x 81 elements, T = 1): the same 3 148 contact and 1 730 slip elements as CONTACT
    (perfc_test/get_times.ref_out), FN/G = 0.1220 as the deck states; the shift in at most 5 Newton
    steps and 34 products plus its nested start (4 and 28 + 7.2 measured)."""
    mod = _performance_study()
    c = mod.perfc_case()
    g = c["grid"]
    assert (g.mx, g.my, c["eps"], c["mu"]) == (71, 81, 1e-7, 0.3)
    op = HalfSpaceInfluence.for_grid(g.mx, g.my, g.dx, g.dy, c["material"])
    ns = solve_normal(op, g, c["h"], approach=c["approach"], tol=c["eps"])
    assert ns.converged and ns.n_contact == mod.CONTACT["perfc_ncon"] == 3148
    assert ns.FN / 82000.0 == pytest.approx(0.1220, abs=5e-5)
    ts = solve_tangential(op, g, ns.pn, xi=c["xi"], eta=c["eta"], phi=c["phi"], mu_static=c["mu"],
                          mu_kinetic=c["mu"], rolling="shift", tol=c["eps"])
    assert ts.converged and int(np.count_nonzero(ts.status == SLIP)) == mod.CONTACT["perfc_nslip"] == 1730
    assert ts.iterations <= 5 and ts.products <= 34 and ts.coarse_products <= 9


@pytest.mark.slow
def test_steady_rolling_products_grow_slowly_from_200_to_400():
    """Steady rolling of case circ (Hertz pressure, mu 0.3, xi 0.001): the influence products of the
    whole solve (fine grid, nested start and coarse-grid correction, in units of one fine product)
    grow as at most N^0.2 from 200² to 400² (measured N^0.17: 40 + 7.5 and 50 + 10.5), so the
    time grows as one product does, times N^0.2 at most; FX changes by the discretisation error of
    200² (0.17 %: -13931 and -13908 N; 1.3e-3 against 300² in docs/validation/halfspace.md)."""
    cost, fx = {}, {}
    for n in (200, 400):
        op, g, pn = circ(n)
        sol = solve_tangential(op, g, pn, xi=1e-3, eta=0.0, phi=0.0, mu_static=0.3, mu_kinetic=0.3)
        assert sol.converged
        cost[n] = sol.products + sol.coarse_products
        fx[n] = float(sol.px.sum() * g.area)
    assert np.log(cost[400] / cost[200]) / np.log(4.0) <= 0.2
    assert fx[400] == pytest.approx(fx[200], rel=2.5e-3)
