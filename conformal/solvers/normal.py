"""The normal contact problem of the exact (half-space) theory: seed Eqs. 45-46 on a planar grid.

Find the pressure p_n >= 0 on the potential contact grid such that the deformed gap

    e_I = h_I - approach w_I + sum_J A_zz(I, J) p_n(J) + extra_I  >= 0,    p_n(I) e_I = 0,

with either the load sum_I w_I p_n(I) dA_I (seed Eq. 46) or the approach prescribed.  ``extra`` is
an additional normal displacement difference, e.g. the coupling term A_zt p_t of dissimilar bodies
(K != 0) in the Panagiotopoulos process.

The same code serves planar and curved grids.  On a planar grid every element has the area dxdy
and w_I = 1, so the load is the normal force FN = dxdy sum p_n (the seed's cos delta = 1).  On a
curved grid (conformal contact, conformal.solvers.conformal) the rigid approach acts along a load
direction d and projects onto the normal of element I as w_I = d . n_I = cos(delta_I - delta_d);
the load is the force along d, sum_I p_n(I) cos(delta_I - delta_d) dA_I (seed Eq. 46, whose
tangential part the caller subtracts from the prescribed force).  The approach is the Lagrange
multiplier of that load, so the same weights w enter the gap and the load (an energy-conjugate
pair), and inner products carry the element areas.

Solver: projected conjugate gradients of Polonsky & Keer (1999), i.e. CG on the current contact
set, restarted when the set grows, with the pressure projected onto p >= 0 (and rescaled to FN when
the force is prescribed), plus an optional FFT preconditioner in the spirit of CONTACT's NormCG
(Vollebregt 2014): the operator's ``normal_preconditioner``, for the half-space a multiplication by
|k| (the inverse of the Boussinesq symbol) by FFTs of the periodic grid of the elements, restricted
to the contact set.  Each product A p costs two FFTs of the zero-padded grid
(conformal.influence.halfspace), the preconditioner two of a quarter of its size.  Iterations stop when the pressure changes by less than
``tol`` (relative, sum |dp| / sum p) from one iteration to the next, as in Polonsky & Keer.
With the force prescribed on a planar half-space grid the iteration runs on a window around the
starting pressure's support (:data:`WINDOW_MARGIN`), the same discrete problem while the contact
stays inside it, which one product on the whole grid checks (else the whole grid is solved).

>>> import numpy as np
>>> from conformal.grid import PlanarGrid
>>> from conformal.materials import Material
>>> g = PlanarGrid.centred(20, 20, 0.1, 0.1)
>>> X, Y = g.mesh()
>>> sol = solve_normal(None, g, 0.01 * (X**2 + Y**2), normal_force=9.1954, material=Material.identical(200, 0.42))
>>> sol.converged, round(sol.FN, 4)
(True, 9.1954)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.solvers import checks
from conformal.errors import InputError, NoContactError
from conformal.grid import PlanarGrid
from conformal.influence.halfspace import Z
from conformal.influence.operator import InfluenceOperator, build_operator
from conformal.materials import Material

#: use the FFT preconditioner from this many grid elements on (the break-even measured with the
#: preconditioner on the zero-padded grid, studies/halfspace_scaling.py: at 50 x 50 both variants
#: took about the same time, from 100 x 100 on the preconditioned iteration is faster and its
#: iteration count grows much more slowly).  On the periodic grid (the operator's
#: ``normal_preconditioner``) the preconditioned iteration of a cold Hertz circle is already faster
#: from 15 x 15 on (0.6-0.85 of the plain time at 15² to 50², best of 7, loaded 2-core machine);
#: the default stays, so that the planar grids of these sizes keep the arithmetic of the curved
#: strips, whose operators have no preconditioner (the planar limit of the conformal theory)
PRECONDITION_FROM = 2500
#: ... and from this many on where a caller starts the iteration from a neighbouring solution (a
#: sweep, a balance, the passes of a contact solve: :func:`warm_precondition`), where the
#: preconditioned iteration needs fewer products: measured on the Manchester A-2.2 sweep's
#: 55 x 33 patch grids, 9 instead of 21 iterations (3-4 ms instead of 9 ms a solve)
PRECONDITION_WARM_FROM = 400
#: prescribed approach (:func:`_solve_for_approach`): each inner force-prescribed solve stops at this
#: times the last relative mismatch of the approach (at most 1e-3, at least 0.1 tol) until the
#: mismatch is below 10 tol, then the same force is solved to 0.1 tol; 0 solves every inner
#: problem to 0.1 tol.  CONTACT's shift performance case (71 x 81, tests/reference/contact_perfc,
#: tol 1e-7): 34 instead of 49 iterations, FN the same to 1e-8
INEXACT_SECANT = 0.01

#: the preconditioned force-prescribed iteration's products A p in single precision where the
#: operator has them (``normal_product32``, the planar half-space; :func:`_product32`; studies
#: switch it off to compare) ...
SINGLE_PRECISION = True
#: ... while the pressure changes by at least this much per iteration (sum |dp| / sum p), and to
#: the end of a solve whose tolerance is at least this (it stops on single-precision products);
#: below it the products are in double precision, from u = A p computed anew.  The float32
#: product's relative error is about 3e-7 (padded patch grids of 24 x 16 to 56 x 36); the pressure
#: of an iteration run to 1e-13 on it differs from the double one by 5e-7 (40 x 28, 60 x 40) to
#: 1.6e-6 (100 x 100) in sum |dp| / sum p, with the same contact set: 1/60 of this threshold or less
SINGLE_ABOVE = 1e-4


def warm_precondition(grid, p_start) -> bool | None:
    """The ``precondition`` argument of :func:`solve_normal` for a start from a neighbouring
    solution: True from PRECONDITION_WARM_FROM elements on when ``p_start`` has a positive
    pressure, else None (the default rule).  Callers opt in, so that the alternations of the
    exact and the conformal theories keep the same arithmetic (their planar limit)."""
    warm = p_start is not None and bool(np.any(np.asarray(p_start) > 0))
    return True if warm and grid.size >= PRECONDITION_WARM_FROM else None


@dataclass(frozen=True, eq=False)
class NormalSolution:
    """Solution of the normal problem on a grid; arrays have the grid's shape (mx, my).

    pn : pressure on body 1 (N/mm²), >= 0.
    un : normal displacement difference at the element centres (mm), A_zz pn plus ``extra_un``.
    approach : the approach (mm), prescribed or solved (along the load direction, see the module).
    FN : sum pn dA (N), the sum of the normal tractions.
    contact : the elements in contact (pn > 0).
    iterations, residual, converged : the projected-CG iteration count, the final relative change
        of the pressure (the stopping criterion) and whether it fell below the tolerance.
    gap_residual : max |e| over the contact set and max(-e) outside it, relative to the approach
        (the discrete Signorini conditions; small when converged).
    """

    pn: np.ndarray
    un: np.ndarray
    approach: float
    FN: float
    contact: np.ndarray
    iterations: int
    residual: float
    converged: bool
    gap_residual: float = 0.0
    preconditioned: bool = False
    load: float | None = None     # sum w pn dA (N), the force along the load direction (= FN if planar)

    @property
    def n_contact(self) -> int:
        return int(np.count_nonzero(self.contact))

    @property
    def pmax(self) -> float:
        return float(self.pn.max())

    def gap(self, h: np.ndarray, weights: np.ndarray | float = 1.0) -> np.ndarray:
        """Deformed gap e = h - approach w + un (mm)."""
        return h - self.approach * np.asarray(weights) + self.un


def _positive_weights(name: str, w, shape) -> np.ndarray | float:
    """Per-element weights as an array of the grid's shape, or the scalar 1.0 where they are all
    one (planar grids keep exactly the arithmetic of the planar solver)."""
    if w is None:
        return 1.0
    w = np.broadcast_to(np.asarray(w, dtype=float), shape)
    if not (np.all(np.isfinite(w)) and np.all(w > 0)):
        raise InputError(f"{name}: must be finite and > 0 on every element")
    return 1.0 if np.all(w == 1.0) else np.array(w)


def element_areas(grid) -> tuple[float, np.ndarray | float]:
    """(dA_ref, a): a reference element area (mm²) and the relative areas a = dA / dA_ref (the
    scalar 1.0 on a planar grid; per element on a curved grid, whose areas dx ds_j may vary)."""
    area = np.asarray(grid.area, dtype=float)
    if area.ndim == 0:
        return float(area), 1.0
    full = np.broadcast_to(area, grid.shape)
    ref = float(full.mean())
    if np.allclose(full, ref, rtol=1e-12, atol=0.0):  # equal areas: the planar arithmetic
        return ref, 1.0
    return ref, _positive_weights("[grid] element areas", full / ref, grid.shape)


def _self_zz(op, shape) -> np.ndarray | float:
    """A_zz of each element on itself: a scalar (planar) or an array of the grid's shape (curved
    strips: one value per column along s)."""
    S = np.asarray(op.self_influence())
    return float(S[Z, Z]) if S.ndim == 2 else np.broadcast_to(S[:, Z, Z], shape)


def _e_star(op: InfluenceOperator, material: Material | None, dA: float, a_self) -> float:
    """Contact modulus for the starting guesses: the operator's, the material's, or from the self
    term of a square element, A_zz = 4 asinh(1) d / (pi E*) (only a first guess)."""
    E_star = op.contact_modulus()
    if E_star is not None:
        return E_star
    if material is not None:
        return material.E_star
    return 4.0 * math.asinh(1.0) * math.sqrt(dA) / (math.pi * float(np.max(a_self)))


class _Weighted:
    """Inner products and projections of the weighted problem: <x, y> = sum a x y (a: relative
    element areas), the load sum a w p, and the approach as the weighted least-squares multiplier
    of the gap on the contact set, <g, w>_act / <w, w>_act.  With a = w = 1 (planar grids) these
    are the plain sums and the mean over the contact set."""

    def __init__(self, a=1.0, w=1.0):
        self.a, self.w = a, w
        self.aw = a * w
        self.unit = np.isscalar(a) and np.isscalar(w) and a == 1.0 and w == 1.0

    def load(self, p: np.ndarray) -> float:
        if self.unit:   # (the sum of p * 1.0 without the product)
            return float(_sum(p))
        return float(np.multiply(p, self.aw).sum())

    def norm(self, p: np.ndarray) -> float:
        """sum a |p|."""
        return float(np.multiply(np.abs(p), self.a).sum())

    def on(self, actf: np.ndarray) -> tuple[np.ndarray, float]:
        """(a w on the contact set, <w, w>_act)."""
        wa = actf * self.aw
        return wa, float(np.multiply(wa, self.w).sum())

    def approach(self, g: np.ndarray, act: np.ndarray) -> float:
        if self.unit:   # np.mean(g[act]): its sum and division, without the wrapper
            ga = g[act]
            return float(np.add.reduce(ga)) / ga.size if ga.size else math.nan
        wa, ww = self.on(act.astype(float))
        return _dot(g, wa) / ww

    def first_touch(self, h: np.ndarray) -> float:
        """The approach at which the first element touches: min h / w."""
        return float(np.min(h / self.w))


def solve_normal(op: InfluenceOperator | None, grid: PlanarGrid, h: np.ndarray, *,
                 normal_force: float | None = None, approach: float | None = None,
                 extra_un: np.ndarray | None = None, material: Material | None = None,
                 tol: float = 1e-6, maxit: int = 1000, p_start: np.ndarray | None = None,
                 precondition: bool | None = None, weights: np.ndarray | None = None) -> NormalSolution:
    """Solve the normal contact problem on ``grid`` for the undeformed distance ``h``.

    Parameters
    ----------
    op : the influence operator of the grid (:class:`conformal.influence.operator.InfluenceOperator`),
        or None to build the half-space one from ``material``.
    grid : the potential contact grid, planar or curved (``grid.area``: element area, a scalar or
        one per column); ``h`` has its shape (mm, before the approach; on a curved grid it may be
        < 0: the signed distance at a reference position of the bodies).
    normal_force, approach : exactly one of them (N, mm): the load sum w pn dA, or the approach.
    extra_un : additional normal displacement difference (mm), e.g. A_zt p_t for K != 0.
    tol, maxit : stop when sum|dp| / sum p < tol; at most maxit iterations.
    p_start : a starting pressure (e.g. the previous outer iteration), optional.
    precondition : use the operator's preconditioner where it has one (the FFT one of the planar
        half-space; default: from PRECONDITION_FROM elements on; :func:`warm_precondition` for a
        start from a neighbouring solution).
    weights : w, the projection of the approach direction onto each element's normal (module
        docstring), > 0; default 1 (planar).

    Raises
    ------
    InputError for bad input (negative or NaN values, wrong shapes), NoContactError when the
    prescribed approach does not exceed the smallest undeformed distance.
    """
    if (normal_force is None) == (approach is None):
        raise InputError("[load] normal_force: give exactly one of normal_force (N) or approach (mm)")
    h = checks.field("[geometry] undeformed distance h", h, grid.shape)
    if op is None:
        if material is None:
            raise InputError("solve_normal: give the influence operator or the material")
        op, _ = build_operator(grid, material)
    if (op.mx, op.my) != grid.shape:
        raise InputError(f"solve_normal: the influence operator is for a {op.mx} x {op.my} grid, "
                         f"the grid has {grid.mx} x {grid.my} elements")
    if not (tol > 0 and math.isfinite(tol)):
        raise InputError(f"[model] tol: must be > 0, got {tol!r}")
    if int(maxit) < 1:
        raise InputError(f"[model] maxit: must be >= 1, got {maxit!r}")
    h_eff = h if extra_un is None else h + checks.field("extra_un", extra_un, grid.shape)
    if precondition is None:
        precondition = grid.size >= PRECONDITION_FROM
    dA, a = element_areas(grid)
    w = _positive_weights("[model] load direction: weights w", weights, grid.shape)
    weighted = _Weighted(a, w)
    a_self = _self_zz(op, grid.shape)
    E_star = _e_star(op, material, dA, a_self)

    if normal_force is not None:
        FN = checks.number("[load] normal_force", normal_force, positive=True)
        if p_start is not None and np.any(np.asarray(p_start) > 0):
            p0 = np.maximum(checks.field("p_start", p_start, grid.shape), 0.0)
        else:
            p0 = initial_pressure(h_eff, FN, E_star, dA)
        p0 = p0 * (FN / (weighted.load(p0) * dA))
        win = _window(op, p0) if weighted.unit and np.isscalar(a_self) else None
        p, u, k, eps, pc, delta = None, None, 0, math.inf, None, math.nan
        if win is not None:   # the iteration on a window around the start's support (WINDOW_FRACTION)
            sl, wop = win
            pw, _, k, eps, pcw = _force(wop, precondition, a_self, h_eff[sl], FN / dA, p0[sl], tol,
                                        int(maxit), weighted, u_exact=False)
            p = np.zeros(grid.shape)
            p[sl] = pw
            u = op.apply_normal(p)     # one product on the whole grid: the gap outside the window
            act = p > 0
            delta = weighted.approach(u + h_eff, act)
            e = u + h_eff
            e -= delta
            e[sl] = 1.0
            if bool(np.all(e > 0.0)):
                pc = pcw
            else:   # the contact leaves the window: the whole grid, from the window's pressure
                p0, win = p, None
        if win is None:
            p, u, k2, eps, pc = _force(op, precondition, a_self, h_eff, FN / dA, p0, tol, int(maxit),
                                       weighted, u=u)
            k += k2
            act = p > 0
            delta = weighted.approach(u + h_eff, act)
    else:
        delta = float(approach)
        if not math.isfinite(delta):
            raise InputError(f"[load] approach: must be a finite number, got {approach!r}")
        hmin = weighted.first_touch(h_eff)
        if delta <= hmin:
            raise NoContactError(f"no contact: the approach {delta:.6g} mm does not exceed the smallest "
                                 f"undeformed distance {hmin:.6g} mm (gap {hmin - delta:.6g} mm)")
        args = (a_self, E_star, h_eff, delta, dA, tol, int(maxit), p_start, weighted)
        pc = op.normal_preconditioner() if precondition else None
        p, u, k, eps = _solve_for_approach(op, pc, *args)
        if pc is not None and not eps < tol:  # safety net: the plain Polonsky-Keer iteration
            pc = None
            p, u, k2, eps = _solve_for_approach(op, None, *args)
            k += k2
        act = p > 0
    un = u if extra_un is None else u + extra_un
    e = h - delta * w + un
    # the Signorini residuals, max |e| on the contact set and max(-e, 0) outside it (masked reductions:
    # the values of max and min over the selected elements, without copying them out)
    spread = float(np.max(h_eff, where=act, initial=-np.inf) - np.min(h_eff, where=act, initial=np.inf)) \
        if act.any() else 0.0
    scale = max(abs(delta), spread, 1e-300)
    gap_res = max(float(np.max(np.abs(e), where=act, initial=0.0)),
                  float(np.max(-e, where=~act, initial=0.0))) / scale
    FN = float(np.multiply(p, a).sum() * dA) if not weighted.unit else weighted.load(p) * dA
    return NormalSolution(pn=p, un=un, approach=delta, FN=FN, contact=act,
                          iterations=k, residual=eps, converged=bool(eps < tol), gap_residual=gap_res,
                          preconditioned=pc is not None, load=FN if weighted.unit else weighted.load(p) * dA)


#: the force-prescribed iteration on a planar grid runs on a window around the start's support
#: (p_start > 0, else that of :func:`initial_pressure`), grown by WINDOW_MARGIN elements on each
#: side, its sides rounded up to multiples of WINDOW_STEP elements (so that the window shapes,
#: and with them the operators and kernels built, stay few), where the operator has one
#: (``window``: the half-space, invariant to translations) and the window holds at most
#: WINDOW_FRACTION of the grid's elements; one product on the whole grid then checks the gap
#: outside the window, and a contact that leaves it is solved again on the whole grid, started
#: from the window's pressure (WINDOW_MARGIN < 0: no windows).  Measured on the Manchester A-2.2
#: sequence (54 normal solves, callgrind instructions of the whole sequence's second run against
#: whole-grid solves, windows at the support's first row and column): margin 3 / fraction 0.7
#: -1.4 %, 2 / 0.8 -2.8 %, 2 / 0.9 -2.9 %, 1 / 0.9 -3.8 %, 0 / 0.9 -3.0 % (more fallbacks); with
#: the windows centred and nearly whole sides taken whole (as now), 1 / 0.9: -2.7 % (first run
#: -2.5 %; 52 solves on windows, 6 fallbacks)
WINDOW_MARGIN = 1
WINDOW_STEP = 4
WINDOW_FRACTION = 0.9


def _window(op, p0: np.ndarray):
    """(slices of the window, its operator) around the support of ``p0`` (:data:`WINDOW_MARGIN`),
    or None where the whole grid is used."""
    if WINDOW_MARGIN < 0:
        return None
    mx, my = p0.shape
    pos = p0 > 0
    rows, cols = np.flatnonzero(pos.any(axis=1)), np.flatnonzero(pos.any(axis=0))
    if rows.size == 0:
        return None
    m, q = WINDOW_MARGIN, WINDOW_STEP
    sx, sy = int(rows[-1]) + 1 - int(rows[0]) + 2 * m, int(cols[-1]) + 1 - int(cols[0]) + 2 * m
    nx, ny = -(-sx // q) * q, -(-sy // q) * q
    # a side that would save less than one step takes the grid's (e.g. a window of 44 of 45
    # columns would only break the symmetry of a problem symmetric in y)
    nx, ny = (mx if nx > mx - q else nx), (my if ny > my - q else ny)
    if nx * ny > WINDOW_FRACTION * mx * my:
        return None
    wop = op.window(nx, ny)
    if wop is None:
        return None
    # centred on the support (the rounding's extra elements split over both sides), so that a
    # symmetric problem keeps a symmetric window where the grid allows
    r0 = min(max(int(rows[0]) - m - (nx - sx) // 2, 0), mx - nx)
    c0 = min(max(int(cols[0]) - m - (ny - sy) // 2, 0), my - ny)
    return (slice(r0, r0 + nx), slice(c0, c0 + ny)), wop


def _product32(op, pc):
    """``op``'s single-precision normal product for the preconditioned iteration (``pc`` not None)
    where the operator has one and :data:`SINGLE_PRECISION`, else None.  Operators without
    ``normal_product32`` (e.g. those of curved grids) run in double, and so does the plain
    iteration, so that planar grids keep the arithmetic of the curved strips without a
    preconditioner (the planar limit of the conformal theory, as for :data:`PRECONDITION_FROM`)."""
    make = getattr(op, "normal_product32", None) if SINGLE_PRECISION and pc is not None else None
    return make() if make is not None else None


def _force(op, precondition: bool, a_self, h, load, p0, tol, maxit, weighted, u=None, u_exact=True):
    """:func:`_pk_force` with ``op``'s preconditioner where ``precondition``, and the plain
    Polonsky-Keer iteration as the safety net where the preconditioned one does not converge;
    ``u_exact``: see :func:`_pk_force`.
    Returns (p, u, iterations, last relative change, the preconditioner used or None)."""
    pc = op.normal_preconditioner() if precondition else None
    p, u1, k, eps = _pk_force(op.apply_normal, pc, a_self, h, load, p0, tol, maxit, weighted, u=u,
                              A32=_product32(op, pc), u_exact=u_exact)
    if pc is not None and not eps < tol:
        pc = None
        p, u1, k2, eps = _pk_force(op.apply_normal, None, a_self, h, load, p0, tol, maxit, weighted, u=u,
                                   u_exact=u_exact)
        k += k2
    return p, u1, k, eps, pc


def initial_pressure(h: np.ndarray, FN: float, E_star: float, dA: float) -> np.ndarray:
    """A Hertz-like starting pressure for the force-prescribed iteration.

    The area below a level t of a paraboloid h - min h = r²/(2R) is 2 pi R t, which gives an
    effective radius R; Hertz then gives the approach d = (9 FN² / (16 E*² R))^(1/3), and the
    start is proportional to sqrt(d/2 - (h - min h)) (the Hertz pressure of a circle; for other
    shapes the iteration corrects it).  Measured on case circ: 6 iterations instead of 16 at
    200 x 200; two bumps: 8 instead of 27; elongated ellipses unchanged (15-20).  Falls back to a
    uniform pressure when h has no usable minimum (e.g. a flat punch)."""
    t = h - h.min()
    level = float(np.quantile(t, 0.2))
    area = np.count_nonzero(t < level) * dA
    if level > 0 and area > 0:
        R = area / (2 * math.pi * level)
        d = (9 * FN**2 / (16 * E_star**2 * R)) ** (1 / 3)
        p0 = np.sqrt(np.maximum(0.5 * d - t, 0.0))
        if np.count_nonzero(p0) >= 1:
            return p0 * (FN / (p0.sum() * dA))
    return np.full(h.shape, FN / (dA * h.size))


def _solve_for_approach(op, pc, a_self, E_star, h, delta, dA, tol, maxit, p_start, weighted):
    """Prescribed approach: the force-prescribed iteration inside a secant iteration on FN.

    The approach above first contact, d = approach - min h, grows monotonically with FN (as
    FN^(2/3) for Hertz, FN for a flat punch), so the secant runs on log FN against log d; each
    inner solve starts from the previous pressure.  A direct projected CG with the approach
    prescribed was measured to oscillate for many iterations from a poor first guess.  The inner
    solves are loose while the secant is far from the approach (:data:`INEXACT_SECANT`).
    Returns (p, u, total inner iterations, relative approach mismatch)."""
    hmin = weighted.first_touch(h)
    d_target = delta - hmin
    if p_start is not None and np.any(np.asarray(p_start) > 0):
        p = np.maximum(np.asarray(p_start, dtype=float), 0.0)
        FN = weighted.load(p) * dA
    else:  # E* r d, between flat punch (2 E* a d) and Hertz (4/3 E* a d, a = r / sqrt 2)
        r = math.sqrt(np.count_nonzero(h < delta * weighted.w) * dA / math.pi)
        FN = max(E_star * r * d_target, d_target / float(np.max(a_self)) * dA)
        p = None
    history: list[tuple[float, float]] = []
    total, mismatch = 0, math.inf
    inner_tol = 0.1 * tol
    u = None      # A p of the last inner solve: the next one starts from both, rescaled (A is linear)
    A32 = _product32(op, pc)
    for _ in range(60):
        if p is None or p.sum() <= 0:
            p, u = np.full(h.shape, FN / (dA * h.size)), None
        c = FN / (weighted.load(p) * dA)
        p = p * c
        loose = max(inner_tol, min(INEXACT_SECANT * mismatch, 1e-3)) if INEXACT_SECANT else inner_tol
        p, u, k, eps = _pk_force(op.apply_normal, pc, a_self, h, FN / dA, p, loose, maxit, weighted,
                                 u=None if u is None else u * c, A32=A32)
        total += k
        act = p > 0
        d = weighted.approach(u + h, act) - hmin
        mismatch = abs(d - d_target) / d_target
        if loose > inner_tol and mismatch < 10 * tol:   # nearly there: solve the same force tightly
            p, u, k, eps = _pk_force(op.apply_normal, pc, a_self, h, FN / dA, p, inner_tol, maxit, weighted, u=u,
                                     A32=A32)
            total += k
            d = weighted.approach(u + h, p > 0) - hmin
            mismatch = abs(d - d_target) / d_target
        if mismatch < tol or total >= maxit:
            break
        history.append((math.log(FN), math.log(max(d, 1e-300))))
        slope = 1.5  # Hertz: FN ~ d^(3/2)
        if len(history) >= 2:
            (f0, d0), (f1, d1) = history[-2], history[-1]
            if abs(d1 - d0) > 1e-14:
                slope = min(max((f1 - f0) / (d1 - d0), 0.5), 3.0)
        FN = math.exp(history[-1][0] + slope * (math.log(d_target) - history[-1][1]))
    return p, u, total, mismatch


def _sum(a: np.ndarray):
    """``a.sum()`` (numpy's pairwise sum over all elements) without the method's Python wrapper."""
    return np.add.reduce(a, axis=None)


def _dot(a: np.ndarray, b: np.ndarray) -> float:
    """Sum of a*b without BLAS: a threaded BLAS dot on a busy 2-core machine was measured 1000x
    slower (ms instead of µs) than this elementwise product."""
    return float(_sum(np.multiply(a, b)))


def _direction(ga, act, actf, wa, ww, weighted, pc):
    """Preconditioned steepest-descent direction z on the contact set (zero elsewhere)."""
    if pc is None:
        return ga
    z = np.multiply(pc(ga), actf)
    # keep the load: <z, w>_act = 0 (planar: zero sum over the contact set, where the sum of z,
    # already zero outside it, is its masked sum)
    if weighted.unit:
        np.subtract(z, float(_sum(z)) / ww, out=z, where=act)
    else:
        z -= (actf * weighted.w) * (_dot(z, wa) / ww)
    return z


def _pk_force(A, pc, a_self, h, load, p, tol, maxit, weighted=None, u=None, A32=None, u_exact=True):
    """Polonsky-Keer with the load sum(a w p) = load prescribed (load = FN / dA_ref; planar:
    sum(p) = FN / dxdy).  On the contact set the gap is g - lambda w with lambda the weighted mean
    of g (:class:`_Weighted`); inner products carry the relative areas a.

    ``u``: A p where the caller has it (a start rescaled from an earlier solve), else computed.
    Returns (p, u = A p, iterations, last relative change).

    With a = w = 1 (planar grids) the products with a and w are left out, which changes no bit:
    multiplying by 1.0 is exact, the sum of the 0/1 contact indicator is the element count, and
    a sum over a field that is already zero outside the contact set equals its masked sum.  The
    displacement u is kept up to date by the step (u - tau r) s where the contact set keeps its
    elements and the pressure stays positive, and recomputed (A p) where it changes; it is returned
    as it is (it differs from a product A p of the final pressure by rounding only).

    ``A32``: A in single precision (float64 in and out), used for the products while the pressure
    changes by at least :data:`SINGLE_ABOVE` per iteration; then u = A p is computed anew in double
    and the iteration goes on in double precision, so that a solve to a tolerance below
    SINGLE_ABOVE stops on double-precision products only.  A solve to a tolerance of at least
    SINGLE_ABOVE stops on the single-precision ones (their error, about 1e-6 of the pressure, is a
    hundredth of its tolerance); its u is then computed anew in double where ``u_exact`` (a
    caller that computes A p itself passes False and gets the single-precision u)."""
    weighted = weighted or _Weighted()
    a, w = weighted.a, weighted.w
    plain = weighted.unit
    single = A32 is not None
    prod = A32 if single else A     # the products of this iteration
    u = prod(p) if u is None else u
    t = None
    G_old, restart = 1.0, True
    eps, k = math.inf, 0
    na, kept = 0, False   # kept: the last step changed no element of the contact set
    for k in range(1, maxit + 1):
        act = p > 0
        n = int(np.count_nonzero(act))
        kept, na = kept and n == na, n   # (a step without clipping only removes elements whose pressure is 0)
        if na == 0:  # cannot happen with a positive load; guard anyway
            hw = h / w
            p = np.where(hw == hw.min(), 1.0, 0.0)
            p *= load / weighted.load(p)
            u = prod(p)
            continue
        g = u + h
        actf = act.astype(float)
        # the gap is g - lam w with lam the (weighted) mean of g over the contact set = the approach;
        # ga: the gap on the contact set, zero elsewhere
        if plain:
            wa, ww = actf, float(na)
            ga = np.multiply(g, actf)
            lam = float(_sum(ga)) / ww
            np.subtract(ga, lam, out=ga, where=act)
        else:
            wa, ww = weighted.on(actf)
            g -= w * (_dot(g, wa) / ww)
            ga, lam = g * actf, 0.0
        z = _direction(ga, act, actf, wa, ww, weighted, pc)
        gaa = ga if plain else ga * a
        G = _dot(gaa, z)
        if restart:
            t = z if pc is not None else z.copy()   # with the preconditioner z is a new array
        else:
            t *= G / G_old
            t += z
            if not kept:
                t *= actf
        G_old = G
        r = prod(t)
        if plain:
            rt = _dot(r, t) - _dot(r, actf) / ww * float(_sum(t))
        else:
            rt = float(_dot(r * a, t)) - float(_dot(r, wa)) / ww * weighted.load(t)
        overlap = g < lam     # the gap g - lam < 0 ...
        np.greater(overlap, act, out=overlap)  # ... outside the contact set: interpenetrating, enter it
        if not rt > 0.0:   # t = 0: the gap is already uniform on the contact set
            if overlap.any():
                # ... but elements outside it interpenetrate (e.g. a start from the one-element
                # pressure of a much smaller load): let them in, as in the step below, and go on.
                # Stopping here would freeze the contact set (a history's later steps kept one
                # element, pmax 490 times too large).
                p = p.copy()
                p[overlap] = -(g[overlap] - lam) / (a_self if np.isscalar(a_self) else a_self[overlap])
                p *= load / weighted.load(p)
                u = prod(p)
                restart, eps = True, math.inf
                continue
            eps = 0.0 if G == 0.0 else eps
            break
        tau = (G if restart else _dot(gaa, t)) / rt   # restart: t = z
        p_new = p - tau * t
        neg = p_new < 0.0
        changed = bool(neg.any())
        if changed:
            p_new[neg] = 0.0
        if overlap.any():
            # Polonsky-Keer's -tau g; with the preconditioner tau is no longer a compliance, so
            # close each gap as if the element were alone: -g / A_zz(0, 0)
            p_new[overlap] = -(g[overlap] - lam) * (tau if pc is None else 1.0 / (a_self if np.isscalar(a_self)
                                                                                     else a_self[overlap]))
            changed, restart = True, True
        else:
            restart = False
        kept = not changed
        s = load / (float(_sum(p_new)) if plain else weighted.load(p_new))
        p_new *= s
        if changed:
            u = prod(p_new)
        else:
            ur = np.multiply(r, tau)
            np.subtract(u, ur, out=ur)    # (u - tau r) s
            ur *= s
            u = ur
        dp = p_new - p
        np.abs(dp, out=dp)
        eps = (float(_sum(dp)) / load) if plain else weighted.norm(dp) / weighted.norm(p_new)
        p = p_new
        if eps < tol and not (single and tol < SINGLE_ABOVE):
            break
        if single and eps < SINGLE_ABOVE:   # near the answer: double-precision products from here on
            single, prod = False, A
            u = A(p)
    if single and u_exact:   # stopped on single-precision products: u = A p in double
        u = A(p)
    return p, u, k, eps
