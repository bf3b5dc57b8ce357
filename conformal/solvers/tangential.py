"""The tangential problem of Kalker's exact theory: steady rolling and transient shift with Coulomb
friction (seed Eqs. 47-49; Kalker 1990 ch. 2 and 5; CONTACT's T = 3 and T = 1).

Given the pressure p_n on the potential contact grid, find the tangential tractions p = (p_x, p_y) on
body 1 such that in every element I with p_n > 0 (conventions: the CONTACT cases (tests/reference/contact_cases.json))

    s_I = w_I + (L p)_I                                          slip (per unit rolled / per shift)
    adhesion:  s_I = 0,                    |p_I| <= mu_static  p_n,I
    slip:      p_I = -mu_kinetic p_n,I s_I/|s_I|,   s_I != 0

and p = 0 outside (exterior).  Steady rolling in +x (material enters at the leading edge x = xh):
L p = (u - u')/dx with u = A p the tangential displacement difference and u' its value one element
upstream (x + dx): CONTACT's discretisation with the time step dq replaced by dx.  Rigid slip
w = (xi - phi y, eta + phi (x + dx/6)) (CONTACT's W_I/dq for chi = 0).  Shift (CONTACT T = 1,
starting from zero tangential tractions): L p = A p, W = (xi - phi y, eta + phi x) with xi, eta
rigid shift distances (mm) and phi a rotation (rad); the slip is then a distance (mm).
A coupling displacement ``extra_u`` (A_tn p_n for dissimilar bodies) enters u.

When FX/(mu_static FN) and/or FY/(mu_static FN) are prescribed (``fx_rel``, ``fy_rel``), xi and/or
eta become unknowns, with one force equation each (CONTACT's F = 1, 2), and are returned.

Method: a semismooth Newton method on Alart-Curnier's projection form of the friction law,

    F(p) = p - Proj_{|q| <= g}(p - c s(p)) = 0,        c = 1/diag(L),

whose Jacobian in adhesion is c L and in slip
``I - kappa (I - n n^T)(I - c L)`` (n = direction of p - c s, kappa = g/|p - c s| < 1).  The step
fixes |p| = g in slip along n (a local update) and leaves one unknown per slip element along the
tangent t, whose row reads ``(|s|/g) dp_t + t.(L dp) = ...``; with the adhesion rows
``(L dp) = -s`` this reduced linear system is solved by GMRES (right preconditioned), each
iteration one FFT product L v.  Prescribed forces add one unknown and one row each (a bordered
system in the same GMRES).  A line search on ||F||^2 costs no products: s is linear in p, so
s(p + a dp) = s + a L dp with L dp assembled from the GMRES basis.

Preconditioner (the key to speed).  Steady rolling: L = D A / dx with D the upwind difference
along x, so L^-1 = A^-1 D^-1 dx, where D^-1 is a cumulative sum from the leading edge (exact, cheap)
and A^-1 is approximated by the inverse of the circulant (Strang) approximation of A on the
unpadded mx x my grid, a 2 x 2 matrix per Fourier mode; the kernel is probed from the operator
itself (two products), so any x-invariant operator works (half-space, curved strips).  Shift:
A^-1 alone.  A slip element's row adds |s|/g to the diagonal of L: its tangent unknown gets the
weighted blend of that inverse and the diagonal, weight w = (diag / (diag + |s|/g))^1.5, and the
diagonal alone where |s|/g exceeds STIFF_RATIO diag (:meth:`_Newton.preconditioner`).  The
preconditioner costs one unpadded FFT pair, about a quarter of a padded product.  The start on a
coarser grid and the extension by one column come from the operator (``coarsened``,
``extended``, :mod:`conformal.influence.operator`).  Steady rolling from COARSE_FROM (50 000)
contact elements on adds a coarse-grid correction of the adhesion rows (:class:`_CoarseCorrection`): on
a grid of 8 x 8 merged elements the cells mostly in adhesion get L's coarse version, solved by 3
GMRES iterations, which replaces the smooth part of P's answer; the outer GMRES is flexible (it
keeps the preconditioned vectors), so an inner iteration may serve as preconditioner.

Start.  Large problems (>= NESTED_FROM contact elements, planar half-space) start from the same
problem on a grid of 2 x 2 merged elements (block means of pressure and rigid slip), solved to
NESTED_TOL and interpolated (nested iteration, recursive): the fine grid then needs 3-4 Newton
steps instead of 8-17.  Inside GMRES the products use single-precision FFTs (2.5x faster, relative
error 1e-7); the slip is recomputed in double precision before convergence is declared.

What was measured (case "circ" of reference/contact_performance.md: steel, A = B = 0.001,
FN = 100 kN, normal problem solved, mu = 0.3, xi = 0.001, tol 1e-6; this shared 2-core machine,
best of 3; studies/steady_rolling_speed.py, CONTACT's GDsteady times in brackets):

* GMRES iterations for one Newton system (dense experiments at 30 x 30 and 50 x 50, rtol 1e-8):
  no preconditioner 99 / 154; Jacobi 99 / 152; exact inverse of the 5 x 5 near field 22 / 28 (no
  cheap way to apply it); 1-3 Gauss-Seidel sweeps of the near field 57-800 (diverging);
  cumsum + circulant A^-1: 20 / 21 on the all-adhesion operator, 26-35 with slip elements.  The
  padded (DC-FFT) circulant inverse needed 40 iterations where the unpadded Strang one needed 22,
  at a quarter of the cost.
* Whole tangential solve, before the work on the overheads: 50^2 0.06 s (0.29); 100^2 0.10-0.16 s
  (1.17); 200^2 0.73-1.1 s (6.8), i.e. about 360 FFT pairs of the padded grid at 200^2, of which
  only a quarter in the FFTs: the rest was array handling.  Variants at 100^2 / 200^2:
  Newton-GMRES from zero, double precision 0.17 / 1.47 s (8 / 17 Newton steps); + coarse start
  0.12 / 0.90 s (3 / 4 steps); + single-precision products 0.10 / 0.73 s.
* Now (studies/steady_rolling_speed.py, studies/performance.py): 200^2 0.34 s = 80 FFT pairs (65
  products on the fine grid + 10 of the nested start), growth N^1.08 in wall time from 50^2 to
  400^2 with products growing as N^0.16, FX unchanged to 1e-7.  What it took: scatter and gather
  of the contact elements by ``put``/``take`` on flat offsets into preallocated buffers (5-8x
  faster than 2-D fancy indexing), L p gathered at the elements and their upstream neighbours
  instead of differencing the whole grid, the half-space kernel symbols stored real (float32: they
  are even-even or odd-odd), ddot in GMRES, and forcing terms (:func:`forcing`) that are loose
  while the slip set settles (0.1 min(1, res) x 10) and stop at what the tolerance needs on the
  last step (a last step used to solve to 1e-3 to go from 1.2e-6 to below 1e-6).
* FX agrees with CONTACT's printed FX on every grid (-14332 / -14114 / -13987 / -13948 / -13935
  against -14330 / -14110 / -13990 / -13950 / -13940); relative to 300^2 the error of FX is
  5.0e-3 at 100^2 and 1.3e-3 at 200^2.
* Slip rows weighted (issue 23 item 4; w above, replacing "the diagonal where |s|/g > diag, else
  P unweighted"): GMRES iterations of the last Newton system to 1e-3 went from 20 / 30 / 38 to
  14 / 18 / 21 at 100^2 / 200^2 / 400^2, products of the whole solve from 60 / 65 / 95 to
  43 / 41 / 58 (+ 7-8 coarse), FX unchanged to 1e-7.  Tried and not kept: an unweighted input
  with a weighted output (16 / 23 iterations at 100^2 / 200^2), no diagonal at all (50 / 78),
  the diagonal projected on the tangent (no change), a periodic circulant of L + mean(|s|/g)
  for the slip rows (17 / 22), a downstream sweep of the upwind coupling between slip elements
  (no change), cubic prolongation of the nested start (one Newton step more), other forcing
  terms and a tighter nested start (no change).
* Coarse-grid correction of the adhesion rows (issue 23 item 4, :class:`_CoarseCorrection`):
  GMRES iterations of the last Newton system to 1e-3 (the solver's own solution, the normal
  problem solved) 13 / 17 / 21 -> 11 / 11 / 12 at 100^2 / 200^2 / 400^2; fine-grid products of
  the whole solve 43 / 41 / 58 -> 33 / 37 / 47 (+ 8-9 coarse, nested start and correction), FX
  unchanged to 1e-7.  CPU time: the correction (3 inner iterations on the 8x coarser grid, a
  restriction and a prolongation) costs 10-20 % of a fine iteration, so the time gained is smaller
  than the products gained: median CPU of 7 interleaved runs (loaded 2-core machine) 0.130 /
  0.425 / 2.68 s without, 0.148 / 0.471 / 2.44 s with it at 100^2 / 200^2 / 400^2 (growth from
  200^2 to 400^2 N^1.33 -> N^1.19 had it been used everywhere); hence COARSE_FROM
  (studies/steady_rolling_speed.py, variant "one-level").  Tried: 4 x 4
  cells (11 / 11 / 12 with 4 inner iterations, dearer; 10 / 11 / 14 with 2), 8 x 8 cells with 2
  inner iterations (11 / 12 / 15), cells taken from a quarter or 90 % adhesion (4 x 4, 2 inner
  iterations: 11 / 11 / 13 and 12 / 14 / 16), the correction in shifts too (more products: P
  alone is good there).
* Fewer double-precision products: the preconditioner's kernel probes use the single-precision
  product from PROBE32_FROM elements on, and the solution's (ux, uy) reuse the field of the last
  (double-precision) slip computation: three double products fewer per solve, about 3 % of a
  400^2 steady-rolling solve.  Near the tolerance (res < FRESH_BELOW tol) the slip is recomputed in
  double precision before the next step: the slip updated by single-precision products drifts by
  about 1e-7 of the early steps' size, which cost CONTACT's shift performance case
  (tests/reference/contact_perfc, tol 1e-7) an eighth Newton step.
* Shift start: the coarse solution is prolonged as the ratio of the traction to its bound
  mu p_n (interpolated over the coarse contact elements only, normalised) times the fine bound,
  so that slipping elements start on their bound: Newton steps on the fine grid of CONTACT's
  shift performance case (71 x 81, 3 148 contact elements) 6 -> 4, products 33 -> 28 (+ 7 on the
  coarse grid); case circ (shift 0.008 mm) 28 / 33 / 34 -> 23 / 23 / 26 products at 100^2 / 200^2 /
  400^2.  Steady rolling keeps the linear interpolation of the tractions (with the ratio: 40 -> 47
  products at 200^2, 46 -> 49 at 400^2).
* Element-wise Gauss-Seidel (CONTACT's SteadyGS) costs O(N^2) per sweep and O(mx) sweeps
  (6.8 s / 211 s in CONTACT); not pursued.
* The contact solves of a wheel-rail sweep (the Manchester A-2.2 sequence of
  studies/performance.py: 51 solves on grids of 190-1290 contact elements, most in full slip,
  replayed, interleaved with the previous code on a 2-core machine at load 3-5): median CPU
  0.43 -> 0.26 s (0.60) in one process, 0.35 -> 0.26 s (0.74, best 0.66) in separate processes;
  forces within 0.001 N, FN unchanged to 1.5e-8.  What it took: the products
  and the preconditioner on a window around the contact elements (:data:`WINDOW_FRACTION`; the
  patch grids have margins of 8-10 elements on each side, so the windows hold a quarter to a half
  of the grid's elements; the padded FFTs of the whole grid remain for (u_x, u_y) once per
  solve), the diagonal preconditioner alone where every row slips above STIFF_RATIO diag (66 of
  105 Newton steps: 331 -> 161 FFT preconditioner applications), a Newton step without the
  scatter and gather of adhesion rows in full slip (:meth:`_Newton.step_full_slip`), the
  spectral products on float32 views, and the start from the neighbour's tractions relative to
  its pressure (:func:`rescaled_start`: 106 -> 95 Newton steps).  The last three give bitwise
  the numbers they replace; the window changes the rounding (the preconditioner's circulant is
  the window's), the rescaled start the path: both within the solver's tolerance.  Tried and not
  kept: the nested start from 300 or 1000 contact elements (fewer Newton steps, more CPU), the
  initial slip in single precision (99 Newton steps instead of 95), double-precision products
  through the single-precision product's real kernels (in float64: 5e-16 from the reference
  product, but the changed rounding moved a preconditioner test's iteration counts).

Static and kinetic friction (mu_static > mu_kinetic): an element leaves adhesion when the traction
it needs exceeds mu_static p_n and then slips with mu_kinetic p_n; it re-adheres when its slip
would reverse.  The classification keeps this memory between Newton iterations (a hysteresis),
so the solution found satisfies both conditions; it is one of possibly several (the law is not
monotone) and is reached from zero tractions (or ``p_start``).

>>> import numpy as np
>>> from conformal.grid import PlanarGrid
>>> from conformal.influence.operator import build_operator
>>> from conformal.materials import Material
>>> g = PlanarGrid.centred(20, 20, 0.1, 0.1)
>>> X, Y = g.mesh()
>>> pn = 1000.0 * np.sqrt(np.clip(1 - (X**2 + Y**2) / 0.9**2, 0, None))
>>> op, _ = build_operator(g, Material.steel())
>>> sol = solve_tangential(op, g, pn, xi=1.0, eta=0.0, phi=0.0, mu_static=0.3, mu_kinetic=0.3)
>>> sol.converged, bool(np.all(sol.status[pn > 0] == 2))     # huge creepage: full slip
(True, True)
>>> round(float(-sol.px.sum() / (0.3 * pn.sum())), 3)       # |FX| = mu FN
1.0
"""
from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from conformal.influence import fft as ffts
from conformal.solvers import checks
from conformal.solvers.krylov import gmres
from conformal.errors import InputError
from conformal.grid import PlanarGrid
from conformal.result import ADHESION, EXTERIOR, SLIP

#: GMRES restart length and the most GMRES iterations for one Newton step
GMRES_RESTART = 60
GMRES_MAXIT = 240
#: slip elements with |s|/g larger than this times diag(L) get a diagonal preconditioner alone
STIFF_RATIO = 3.0
#: the weight of the long-range preconditioner in a slip row: (diag / (diag + |s|/g)) ** this
SLIP_WEIGHT_POWER = 1.5
#: Krylov products in single precision where the operator allows (studies switch it off to compare)
SINGLE_PRECISION = True
#: the kernel probes of the preconditioner use the single-precision product from this many grid
#: elements on (two double products of a 400 x 400 grid cost about 3 % of its steady-rolling
#: solve; on small grids the double ones cost little and keep the last digits of c = 1/diag)
PROBE32_FROM = 2500


@dataclass(frozen=True, eq=False)
class TangentialSolution:
    """Solution of the tangential problem; arrays have the grid's shape (mx, my).

    px, py : tangential tractions on body 1 (N/mm²); zero outside the contact (p_n = 0).
    sx, sy : slip in contact elements (steady rolling: relative slip velocity s/V, -; shift: slip
        distance, mm); zero in adhesion and outside.
    ux, uy : tangential displacement difference A p (+ extra_u) at the element centres (mm); None
        where the solve was asked for no displacements.
    status : EXTERIOR / ADHESION / SLIP (conformal.result).
    xi, eta : the creepages (shifts) used: solved where fx_rel / fy_rel were prescribed.
    iterations : Newton iterations; residual : max |F| (the friction-law residual in traction
        units) relative to the largest traction, and the relative force errors; converged :
        residual <= tol; message : why not, when not converged.
    products : number of influence products (FFT pairs) spent on this grid, for studies.
    coarse_products : the products of the nested start on coarser grids, in units of one product
        on this grid (weighted by the element count); ``products + coarse_products`` is the cost.
    """

    px: np.ndarray
    py: np.ndarray
    sx: np.ndarray
    sy: np.ndarray
    ux: np.ndarray | None
    uy: np.ndarray | None
    status: np.ndarray
    xi: float
    eta: float
    iterations: int
    residual: float
    converged: bool
    message: str = ""
    products: int = 0
    coarse_products: float = 0.0


# ----------------------------------------------------------------------------- input checks


# ----------------------------------------------------------------------------- the operator L
#: what the slip operators of one influence operator share across solves (its longer version, the
#: single-precision product, the preconditioner's symbols, the coarse levels), per rolling kind and
#: element length; held while the influence operator lives (the planar half-space operators are
#: themselves shared per grid shape, so the contact solves of a sweep's position and of the
#: balance passes on one grid build the preconditioner once).  Pure functions of the operator:
#: the same numbers as a fresh build.
_PER_OPERATOR: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _operator_shared(op, steady: bool, dx: float) -> dict:
    """The dict of :data:`_PER_OPERATOR` for ``op`` (a fresh one where the operator cannot be
    referenced weakly or hashed)."""
    try:
        per = _PER_OPERATOR.setdefault(op, {})
    except TypeError:
        return {}
    return per.setdefault((bool(steady), float(dx)), {})


#: the products of a contact solve run on a window of the grid around the contact elements (their
#: bounding rows and columns, in steady rolling one row more downstream for the upstream
#: neighbours) where the operator has one (``window``: the planar half-space) and the window has
#: at most WINDOW_FRACTION of the grid's elements; its sides are rounded up to multiples of
#: WINDOW_STEP elements, so that the contact sets of neighbouring positions share its operator,
#: single-precision product and preconditioner (0: no windows)
WINDOW_FRACTION = 0.7
WINDOW_STEP = 4


def _window(contact: np.ndarray, steady: bool):
    """(first row, first column, rows, columns) of the window of the products around ``contact``
    (:data:`WINDOW_FRACTION`), or None where the whole grid is used."""
    if not WINDOW_STEP:
        return None
    mx, my = contact.shape
    rows, cols = np.flatnonzero(contact.any(axis=1)), np.flatnonzero(contact.any(axis=0))
    if rows.size == 0:
        return None
    r0, c0 = int(rows[0]), int(cols[0])
    nx = min(int(rows[-1]) + (2 if steady else 1), mx) - r0
    ny = int(cols[-1]) + 1 - c0
    q = WINDOW_STEP
    nx, ny = min(mx, -(-nx // q) * q), min(my, -(-ny // q) * q)
    if nx * ny > WINDOW_FRACTION * mx * my:
        return None
    return min(r0, mx - nx), min(c0, my - ny), nx, ny


def _centred_at(k: np.ndarray, cx: int, cy: int) -> np.ndarray:
    """k (mx, my) rolled so that its entry (cx, cy) comes first: ``numpy.roll(k, (-cx, -cy),
    axis=(0, 1))``, the same array by four block copies."""
    mx, my = k.shape
    out = np.empty_like(k)
    out[:mx - cx, :my - cy] = k[cx:, cy:]
    out[:mx - cx, my - cy:] = k[cx:, :cy]
    out[mx - cx:, :my - cy] = k[:cx, cy:]
    out[mx - cx:, my - cy:] = k[:cx, :cy]
    return out


class _SlipOperator:
    """L p on the contact elements (steady: upwind difference of A p over dx; shift: A p) and its
    approximate inverse (the preconditioner), see the module docstring.

    The products work on the contact elements: p is scattered into a preallocated grid buffer
    (the same positions every time, so the rest stays zero), and L p is gathered from A p at the
    elements and at their upstream neighbours (x + dx), without forming the difference on the
    whole grid."""

    def __init__(self, op, grid, contact: np.ndarray, steady: bool, shared: dict | None = None):
        self.steady = steady
        self.dx = float(grid.dx)
        #: the contact elements as flat offsets into the grid (the callers' numbering)
        self.idx = np.flatnonzero(contact.ravel())
        self.products = 0
        self.coarse_products = 0.0  # products on coarser grids (nested start, coarse-grid correction),
        #                             in this grid's units
        self._full_op, self._full_shared = op, shared
        self.window = None
        if shared is None:
            shared = self._full_shared = _operator_shared(op, steady, grid.dx)
            win = _window(contact, steady)
            if win is not None:
                key = ("window",) + win[2:]
                if key not in shared:
                    shared[key] = op.window(*win[2:])
                if shared[key] is not None:
                    self.window = (slice(win[0], win[0] + win[2]), slice(win[1], win[1] + win[3]))
                    op, contact = shared[key], contact[self.window]
                    shared = _operator_shared(op, steady, grid.dx)
        # below: the grid of the products (the window where there is one), its contact elements
        # ``widx`` and its operator ``op``
        self.op = op
        self.mx, self.my = contact.shape
        self.widx = np.flatnonzero(contact.ravel()) if self.window is not None else self.idx
        # what depends on the operator alone (longer operator, single-precision product, the
        # preconditioner's symbols), shared by the operators of other contact sets on this grid
        self._shared = shared
        self._ext = None
        if steady and contact[-1].any():  # u' of the leading column lies outside the grid; operators
            if "ext" not in shared:       # without a longer version fall back to u' = u there
                shared["ext"] = op.extended(1)
            self._ext = shared["ext"]
        pop = self._ext if self._ext is not None else op
        rows = pop.mx if self._ext is not None else self.mx
        self._rows = rows
        # L p = wgt (u[idx] - u[up]) with u = A p on the (possibly extended) grid, flattened
        if steady:
            has_up = self.widx // self.my + 1 < rows  # without an extended grid the leading column
            self._up = np.where(has_up, self.widx + self.my, self.widx)  # gets L p = 0 (u' = u)
            self._wgt = has_up / self.dx
        key = ("fast", self._ext is not None)
        if key not in shared:
            shared[key] = pop.tangential_product32() if SINGLE_PRECISION else None
        self._fast = shared[key]
        # flat offsets of the contact elements (and their upstream neighbours) in a (2, rows*my) buffer
        self._off = np.concatenate([self.widx, rows * self.my + self.widx])
        if steady:
            self._off_up = np.concatenate([self._up, rows * self.my + self._up])
            self._wgt2 = np.concatenate([self._wgt, self._wgt])
        # the same positions as boolean masks of the grid buffers: scatter and gather by a mask
        # are 3-6x faster than put/take on flat offsets (the offsets are sorted, so the order agrees)
        self._m = np.zeros((2, rows, self.my), bool)
        self._m.reshape(-1)[self._off] = True
        self._pm = self._m[:, :self.mx]
        # upstream neighbours by the mask shifted one row, where every element has one
        self._m_up = self._m[:, :-1] if steady and rows > 1 and bool(has_up.all()) else None
        self._buf32 = np.zeros((2, rows * self.my), dtype=np.float32)
        self._buf64 = np.zeros((2, rows * self.my))
        self._pbuf = np.zeros((2, self.mx * self.my), dtype=np.float32)
        self._last = None   # (tractions, field) of the last double-precision product
        if "inv" not in shared:
            self._build_preconditioner()
            shared["inv"], shared["diag"] = self._inv, self.diag
            real = all(v.dtype == np.float32 for v in self._inv)
            shared["inv2"] = tuple(ffts.doubled(v) for v in self._inv) if real else None
        self._inv, self.diag, self._inv2 = shared["inv"], shared["diag"], shared["inv2"]
        self._cbuf = np.empty((2, self.mx, self.my), dtype=np.float32) if steady else None

    # --- products
    def grid_u(self, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(u_x, u_y) = A p on the grid for tractions (px, py) given on the grid (zero outside the
        contact elements): the field of the last double-precision :meth:`apply` when that was
        for the same tractions (the final slip of a solve is computed from them), else one
        product.  With a window (:data:`WINDOW_FRACTION`) that field covers the window only: the
        rest of the grid, away from the contact, comes from the single-precision product of the
        whole grid where the operator has one (relative error about 1e-7)."""
        last = self._last
        same = last is not None and np.array_equal(last[0][0], px.reshape(-1).take(self.idx)) \
            and np.array_equal(last[0][1], py.reshape(-1).take(self.idx))
        if self.window is None:
            if same:
                return last[1][0, :self.mx], last[1][1, :self.mx]
            self.products += 1
            return self._full_op.apply_tangential(px, py)
        if "fast" not in self._full_shared:
            self._full_shared["fast"] = self._full_op.tangential_product32() if SINGLE_PRECISION else None
        fast = self._full_shared["fast"]
        self.products += 1
        if fast is None:
            return self._full_op.apply_tangential(px, py)
        p32 = np.empty((2,) + px.shape, dtype=np.float32)   # (the float32 values of np.stack([px, py]))
        p32[0], p32[1] = px, py
        u = fast(p32).astype(float)
        if same:
            u[(slice(None),) + self.window] = last[1][:, :self.mx]
        else:
            self.products += 1
            u[(slice(None),) + self.window] = self.op.apply_tangential(px[self.window], py[self.window])
        return u[0], u[1]

    def apply(self, pc: np.ndarray, fast: bool = False) -> np.ndarray:
        """L p for p given on the contact elements (2, nc); returns (2, nc).  ``fast``: single
        precision FFTs (Krylov products, where 1e-7 relative is ample), when available."""
        self.products += 1
        shape = (2, self._rows, self.my)
        if fast and self._fast is not None:
            buf = self._buf32.reshape(shape)
            buf[self._m] = pc.reshape(-1)
            u = self._fast(buf)
        else:
            buf = self._buf64.reshape(shape)
            buf[self._m] = pc.reshape(-1)
            pop = self._ext if self._ext is not None else self.op
            u = np.stack(pop.apply_tangential(*buf))
            self._last = (pc.reshape(2, -1).copy(), u)   # for grid_u
        if not self.steady:
            return u[self._m].astype(float).reshape(2, -1)
        if self._m_up is not None:   # (u - u') at the elements: one gather of the difference of the rows
            return (np.subtract(u[:, :-1], u[:, 1:])[self._m_up] * self._wgt2).reshape(2, -1)
        u = u.reshape(-1)
        return ((u.take(self._off) - u.take(self._off_up)) * self._wgt2).reshape(2, -1)

    def coarse_level(self, fx: int, fy: int):
        """(operator or None, shared dict) of the grid of fx x fy merged elements, built once."""
        key = ("coarse", fx, fy)
        if key not in self._shared:
            self._shared[key] = (self.op.coarsened(fx, fy), {})
        return self._shared[key]

    # --- preconditioner
    def _probe(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(u_x, u_y) on the grid of a unit traction in component k at the centre element: by the
        single-precision product where the operator has one and the grid has at least
        :data:`PROBE32_FROM` elements (the preconditioner need not be accurate: relative error about
        1e-7), else in double precision."""
        mx, my = self.mx, self.my
        if self._fast is None or mx * my < PROBE32_FROM:
            e = np.zeros((2, mx, my))
            e[k, mx // 2, my // 2] = 1.0
            self.products += 1
            return self.op.apply_tangential(*e)
        self.products += 1
        e = np.zeros((2, self._rows, my), dtype=np.float32)
        e[k, mx // 2, my // 2] = 1.0
        u = self._fast(e)
        return u[0, :mx].astype(float), u[1, :mx].astype(float)

    def _build_preconditioner(self) -> None:
        """Probe the kernel at the centre element (two products), fold it onto the unpadded
        periodic grid (Strang circulant) and invert its 2 x 2 symbol per Fourier mode."""
        mx, my = self.mx, self.my
        cx, cy = mx // 2, my // 2
        kxx, kyx = self._probe(0)
        kxy, kyy = self._probe(1)
        # diagonal of L per component (scalars): self term, minus the upstream neighbour if steady
        dxx, dyy = kxx[cx, cy], kyy[cx, cy]
        if self.steady:
            if mx > 1:
                up = cx + 1 if cx + 1 < mx else cx - 1  # kernel even in x
                dxx, dyy = (dxx - kxx[up, cy]) / self.dx, (dyy - kyy[up, cy]) / self.dx
            else:
                dxx, dyy = dxx / self.dx, dyy / self.dx
        self.diag = 0.5 * (dxx + dyy)
        # A_xy = A_yx (reciprocity): the two probes give the coupling bitwise alike (measured on every
        # preconditioner of the Manchester sequence), and then its transform and inverse entry are
        # taken once (the same numbers); otherwise each from its own probe
        sym_xy = np.array_equal(kxy, kyx) and np.array_equal(np.signbit(kxy), np.signbit(kyx))
        a, b, d = (ffts.rfft2(_centred_at(k, cx, cy)) for k in (kxx, kxy, kyy))
        c = b if sym_xy else ffts.rfft2(_centred_at(kyx, cx, cy))
        det = a * d - b * c
        floor = 1e-8 * np.abs(det).max()
        det = np.where(np.abs(det) < floor, floor, det)
        # single precision: the preconditioner need not be accurate
        inv = [d / det, -b / det]
        inv += [inv[1] if sym_xy else -c / det, a / det]
        distinct = list({id(v): v for v in inv}.values())
        real = all(ffts.imag_negligible(v, 1e-6) for v in distinct)
        single = {id(v): v.real.astype(np.float32) if real else v.astype(np.complex64) for v in distinct}
        self._inv = tuple(single[id(v)] for v in inv)

    def precondition(self, rc: np.ndarray) -> np.ndarray:
        """Approximately L^-1 r for r on the contact elements (2, nc); returns (2, nc)."""
        full = self._pbuf.reshape(2, self.mx, self.my)
        full[self._pm] = rc.reshape(-1)
        if self.steady:  # D^-1: sum from the leading edge downstream
            np.cumsum(full[:, ::-1], axis=1, out=self._cbuf[:, ::-1])
            full = self._cbuf
            full *= np.float32(self.dx)
        h = ffts.rfft2(full)
        if self._inv2 is not None and h.flags.c_contiguous:
            # real symbols: the products on float32 views (the numbers of the complex product)
            i00, i01, i10, i11 = self._inv2
            h, q = h.view(np.float32), np.empty_like(h)
            qf = q.view(np.float32)
        else:
            i00, i01, i10, i11 = self._inv
            q = qf = np.empty_like(h)
        qf[0] = i00 * h[0]
        qf[0] += i01 * h[1]
        qf[1] = i10 * h[0]
        qf[1] += i11 * h[1]
        q = ffts.irfft2(q, (self.mx, self.my))
        return q[self._pm].astype(float).reshape(2, -1)


#: coarse-grid correction of the adhesion rows (:class:`_CoarseCorrection`): cells of COARSE_FACTOR x
#: COARSE_FACTOR elements, from COARSE_FROM contact elements on (0: never; below about 50 000 the
#: correction costs more CPU time than the iterations it saves: 100² and 200² of case circ were 12 %
#: and 10 % slower with it, 400² 10 % faster, interleaved runs); a cell takes part where at
#: least COARSE_STICK of its elements are adhesion rows; COARSE_ITS GMRES iterations (to COARSE_TOL) on
#: the coarse grid per application
COARSE_FACTOR = 8
COARSE_FROM = 50000
COARSE_STICK = 0.5
COARSE_ITS = 3
COARSE_TOL = 0.1


class _CoarseCorrection:
    """Coarse-grid correction of the adhesion rows of the Newton system: ``Pr (Lc^-1 - Pc) R``.

    The one-level preconditioner P (cumulative sum and circulant A^-1 of the whole periodic grid)
    misjudges the smooth part of the answer, which depends on the shape of the adhesion area: its
    GMRES iterations grow with the grid (13 / 17 / 21 at 100² / 200² / 400² on the circ case).  On
    a grid of f x f merged elements (the operator's ``coarsened``), the cells mostly in adhesion
    form the coarse problem Lc pc = rc: L of the coarse grid with the tractions of all other cells
    held at zero (slip elements are held in their direction by their own rows).  R is the mean over
    a cell's adhesion elements (slips are intensive), Pr the injection of the cell's traction into
    them.  Lc^-1 is approximated by a few GMRES iterations preconditioned by the coarse grid's own P
    (Pc); subtracting Pc R r leaves P in charge of what the coarse grid cannot see and replaces its
    smooth part by the coarse solution.  The product is not linear in r (inner GMRES), so the outer
    GMRES must keep its preconditioned vectors (:func:`conformal.solvers.krylov.gmres` does:
    flexible GMRES).  Measured in :meth:`_Newton.preconditioner`."""

    def __init__(self, L: "_SlipOperator", ia: np.ndarray, f: int):
        from types import SimpleNamespace

        self.L, self.ok = L, False
        mx, my = L.mx, L.my
        fy = f if my >= 4 * f else 1
        g = L.widx[ia]
        mxc, myc = -(-mx // f), -(-my // fy)
        cell = ((g // my) // f) * myc + (g % my) // fy
        stick = np.bincount(cell, minlength=mxc * myc) >= COARSE_STICK * f * fy
        if stick.sum() < 4:
            return
        cop, shared = L.coarse_level(f, fy)
        if cop is None:
            return
        self.ok = True
        self.Lc = Lc = _SlipOperator(cop, SimpleNamespace(mx=mxc, dx=f * L.dx), stick.reshape(mxc, myc), L.steady,
                                     shared)
        Lc.products = 0
        self.scale = (mxc * myc) / (mx * my)   # a coarse product in units of a fine one
        self.sel = np.flatnonzero(stick[cell])  # the adhesion rows (positions in ia) that have a cell
        self.pos = np.searchsorted(Lc.widx, cell[self.sel])
        self.ncc = ncc = Lc.widx.size
        self.wmean = 1.0 / np.bincount(self.pos, minlength=ncc)
        # prolongation by one take: adhesion row j of component k reads entry k (ncc + 1) + pos of
        # the coarse field padded with a zero per component (rows without a cell read the zero)
        pmap = np.full(ia.size, ncc)
        pmap[self.sel] = self.pos
        self.pmap = np.concatenate([pmap, pmap + ncc + 1])
        self._pad = np.zeros((2, ncc + 1))

    def restrict(self, ra: np.ndarray) -> np.ndarray:
        """R: (2, nA) adhesion residual -> (2, ncc), the mean over each cell's adhesion rows."""
        return np.stack([np.bincount(self.pos, weights=ra[k, self.sel], minlength=self.ncc) * self.wmean
                         for k in (0, 1)])

    def prolong(self, ec: np.ndarray) -> np.ndarray:
        """Pr: (2, ncc) -> (2 nA,) flat, each adhesion row the value of its cell (0 without one)."""
        self._pad[:, :self.ncc] = ec
        return self._pad.reshape(-1).take(self.pmap)

    def __call__(self, ra: np.ndarray) -> np.ndarray:
        """Pr (Lc^-1 - Pc) R ra for the adhesion part ra (2, nA) of a residual; flat (2 nA,)."""
        Lc = self.Lc
        rc = self.restrict(ra)
        x, _, _ = gmres(lambda v: Lc.apply(v.reshape(2, -1), fast=True).reshape(-1), rc.reshape(-1),
                        precond=lambda v: Lc.precondition(v.reshape(2, -1)).reshape(-1), tol=COARSE_TOL,
                        maxit=COARSE_ITS, restart=COARSE_ITS)
        self.L.coarse_products += Lc.products * self.scale
        Lc.products = 0
        return self.prolong(x.reshape(2, -1) - Lc.precondition(rc))


# ----------------------------------------------------------------------------- the Newton method
#: the slip is recomputed in double precision (:meth:`_Newton.fresh`) before a Newton step taken
#: at a residual below this times the tolerance: the shift of CONTACT's performance case
#: (tests/reference/contact_perfc) at tol 1e-7 then takes 7 Newton steps instead of 8
FRESH_BELOW = 10.0
#: forcing-term parameters of the inexact Newton method (see forcing)
FORCING = dict(cap=0.1, floor=3e-3, quad=1.0, last=0.5)


def forcing(res: float, tol: float) -> float:
    """GMRES tolerance of one Newton step at residual measure ``res`` (inexact Newton): ``quad``
    x res (superlinear convergence near the solution) between ``floor`` and ``cap``, but never
    tighter than ``last`` x tol/res, what the last step needs to reach the tolerance.  Measured on
    the circ case (studies/steady_rolling_speed.py): 117 -> 75 products at 200^2, FX to 1e-7.

    >>> forcing(1e-2, 1e-6), forcing(1.2e-6, 1e-6)
    (0.01, 0.1)
    """
    f = FORCING
    eta = max(f["floor"], f["quad"] * res)
    if f["last"]:
        eta = max(eta, f["last"] * tol / res)
    return min(f["cap"], eta)


def _rotated(n: np.ndarray) -> np.ndarray:
    """(-n_y, n_x) of unit vectors n (2, k): ``np.stack([-n[1], n[0]])`` without its copies."""
    t = np.empty_like(n)
    np.negative(n[1], out=t[0])
    t[1] = n[0]
    return t


@dataclass
class _State:
    p: np.ndarray       # (2, nc) traction on the contact elements
    s: np.ndarray       # (2, nc) slip
    creep: np.ndarray   # (2,) the unknown creepages' current values (xi, eta)
    slipping: np.ndarray  # (nc,) bool, classification memory (static/kinetic hysteresis)


class _Newton:
    def __init__(self, L: _SlipOperator, w: np.ndarray, gs: np.ndarray, gk: np.ndarray, area: np.ndarray,
                 force_rows: list[tuple[int, float]], FN_mu: float):
        self.L, self.w, self.gs, self.gk = L, w, gs, gk
        self.area = area
        self.c = 1.0 / L.diag
        self.force_rows = force_rows          # [(component, target force)]
        self.FN_mu = FN_mu                    # mu_static FN: scale of the force errors
        self.A_tot = float(area.sum())
        self.nc = gs.size
        self.gmax = float(gk.max())
        self.one_mu = bool(np.array_equal(gs, gk))   # mu_static = mu_kinetic: one bound

    def classify(self, p, s, slipping):
        z = p - self.c * s
        nz = np.hypot(z[0], z[1])
        slip = nz > (self.gk if self.one_mu else np.where(slipping, self.gk, self.gs))
        return z, nz, slip

    def residual(self, p, s, slipping):
        """F (2, nc) and the force errors (N) at (p, s)."""
        z, nz, slip = self.classify(p, s, slipping)
        if slip.all():    # the same numbers without the selections
            F = p - (self.gk / nz) * z
        else:
            scale = np.where(slip, self.gk / np.where(slip, nz, 1.0), 0.0)
            F = np.where(slip, p - scale * z, self.c * s)
        ferr = [float((self.area * p[k]).sum()) - target for k, target in self.force_rows]
        return F, ferr, slip

    def merit(self, F, ferr) -> float:
        m = float((F * F).sum())
        for e in ferr:
            m += self.nc * (e / self.A_tot) ** 2
        return m

    def measure(self, p, F, ferr) -> float:
        """The convergence measure: max |F| relative to the largest traction, and the force errors
        relative to the largest of the prescribed and the current tangential force (relative, so
        tiny creepages are solved as accurately as large ones)."""
        pscale = max(float(np.sqrt((p * p).sum(axis=0)).max()), 1e-12 * self.gmax)
        r = float(np.abs(F).max()) / pscale if F.size else 0.0
        if ferr:
            fscale = max([abs(t) for _, t in self.force_rows]
                         + [float((self.area * np.hypot(p[0], p[1])).sum()), 1e-12 * self.FN_mu])
            for e in ferr:
                r = max(r, abs(e) / fscale)
        return r

    def step(self, st: _State, F, ferr, slip, rtol: float):
        """One semismooth Newton direction: returns (dp, L dp + creepage part, dcreep, gmres its)."""
        L, c = self.L, self.c
        p, s = st.p, st.s
        z = p - c * s
        nz = np.hypot(z[0], z[1])
        ia, isl = np.flatnonzero(~slip), np.flatnonzero(slip)
        nA, nS = ia.size, isl.size
        n = z[:, isl] / nz[isl]
        t = _rotated(n)
        kap = self.gk[isl] / nz[isl]
        sigma = (1.0 - kap) / (kap * c)   # = |s|/g at a solution
        # known part: |p| = g along n in slip
        nc = self.nc
        ia2 = np.concatenate([ia, nc + ia])       # flat offsets in (2, nc) arrays (put/take: fast)
        isl2 = np.concatenate([isl, nc + isl])
        D0 = np.zeros((2, nc))
        D0.reshape(-1).put(isl2, ((self.gk[isl] - (n[0] * p[0, isl] + n[1] * p[1, isl])) * n).ravel())
        LD0 = L.apply(D0, fast=True)
        tp = t[0] * p[0, isl] + t[1] * p[1, isl]
        rhs = np.concatenate([-s.reshape(-1).take(ia2) - LD0.reshape(-1).take(ia2),
                              -tp / (kap * c) - (t[0] * LD0[0].take(isl) + t[1] * LD0[1].take(isl)),
                              [-self.L.diag * (e + float((self.area * D0[k]).sum())) / self.A_tot
                               for e, (k, _) in zip(ferr, self.force_rows)]])
        nf = len(self.force_rows)

        def expand(x):
            d = np.zeros(2 * nc)
            d.put(ia2, x[:2 * nA])
            xs = x[2 * nA:2 * nA + nS]
            d.put(isl2, (xs * t).ravel())
            return d.reshape(2, nc)

        def matvec(x):
            d = expand(x)
            Ld = L.apply(d, fast=True)
            for j, (k, _) in enumerate(self.force_rows):  # creepage columns: ds = dcreep e_k
                Ld[k] += x[2 * nA + nS + j]
            out = np.empty(2 * nA + nS + nf)
            out[:2 * nA] = Ld.reshape(-1).take(ia2)
            out[2 * nA:2 * nA + nS] = (sigma * x[2 * nA:2 * nA + nS] + t[0] * Ld[0].take(isl)
                                       + t[1] * Ld[1].take(isl))
            for j, (k, _) in enumerate(self.force_rows):
                out[2 * nA + nS + j] = self.L.diag * float((self.area * d[k]).sum()) / self.A_tot
            return out, Ld

        prec = self.preconditioner(ia, isl, ia2, isl2, t, sigma)

        x, Ldx, its, _ = gmres(matvec, rhs, precond=prec, tol=rtol, maxit=GMRES_MAXIT, restart=GMRES_RESTART,
                               extra=True)
        dp = D0 + expand(x)
        ds = LD0 + (Ldx if Ldx is not None else 0.0)
        dcreep = np.zeros(2)
        for j, (k, _) in enumerate(self.force_rows):
            dcreep[k] = x[2 * nA + nS + j]
        return dp, ds, dcreep, its

    def step_full_slip(self, st: _State, rtol: float):
        """:meth:`step` where every element slips and no force is prescribed (most contact solves
        of a wheel-rail sweep): the same system and the same numbers, without the scatter and
        gather of the adhesion rows."""
        L, c, gk = self.L, self.c, self.gk
        p, s = st.p, st.s
        z = p - c * s
        nz = np.hypot(z[0], z[1])
        n = z / nz
        t = _rotated(n)
        kap = gk / nz
        sigma = (1.0 - kap) / (kap * c)
        D0 = (gk - (n[0] * p[0] + n[1] * p[1])) * n
        LD0 = L.apply(D0, fast=True)
        tp = t[0] * p[0] + t[1] * p[1]
        rhs = -tp / (kap * c) - (t[0] * LD0[0] + t[1] * LD0[1])

        def matvec(x):
            Ld = L.apply(x * t, fast=True)
            return sigma * x + t[0] * Ld[0] + t[1] * Ld[1], Ld

        empty = np.zeros(0, dtype=np.intp)
        prec = self.preconditioner(empty, np.arange(self.nc), empty, np.arange(2 * self.nc), t, sigma)
        x, Ldx, its, _ = gmres(matvec, rhs, precond=prec, tol=rtol, maxit=GMRES_MAXIT, restart=GMRES_RESTART,
                               extra=True)
        return D0 + x * t, LD0 + (Ldx if Ldx is not None else 0.0), np.zeros(2), its

    def preconditioner(self, ia, isl, ia2, isl2, t, sigma, lean: bool = True):
        """The right preconditioner of the reduced Newton system (module docstring, "Preconditioner").

        Adhesion rows: P = L^-1 (cumulative sum and circulant A^-1, :meth:`_SlipOperator.precondition`).
        A slip row reads ``sigma x_t + t.(L d)`` (sigma = |s|/g), whose local stiffness is
        diag(L) + sigma instead of diag(L).  With the weight w = (diag / (diag + sigma))^p
        (p = :data:`SLIP_WEIGHT_POWER`) its tangent unknown gets
        ``w t.P(w t r) + (1 - w) r / (diag + sigma)``: the long-range inverse where sigma is small
        (near the stick-slip boundary), the diagonal where it dominates, and the diagonal alone
        above :data:`STIFF_RATIO` diag.  Measured (circ case, last Newton system, GMRES iterations
        to 1e-3): 20 / 30 / 38 at 100² / 200² / 400² with P unweighted (and the diagonal above
        diag), 13 / 18 / 26 with w (p = 1, diagonal above 2 diag), 14 / 18 / 21 with p = 1.5 and
        the diagonal above 3 diag.  Where every row slips above that (``lean``, the default), the
        diagonal is applied alone, without P's product of zeros (the same numbers)."""
        L, nc = self.L, self.nc
        nA, nS = ia.size, isl.size
        diag = L.diag
        soft = ~(sigma > STIFF_RATIO * diag)    # (the rows with a weight: the power only where it is used)
        if soft.all():
            w = (diag / (diag + sigma)) ** SLIP_WEIGHT_POWER
        else:
            w = np.zeros(sigma.shape)
            if soft.any():
                w[soft] = (diag / (diag + sigma[soft])) ** SLIP_WEIGHT_POWER
        local = (1.0 - w) / (sigma + diag)
        cc = None
        if L.steady and COARSE_FACTOR and COARSE_FROM and self.nc >= COARSE_FROM and nA:
            cc = _CoarseCorrection(L, ia, COARSE_FACTOR)
            cc = cc if cc.ok else None

        if lean and not nA and cc is None and not w.any():
            # every row slips with sigma above STIFF_RATIO diag (full slip at large creepage, most of
            # a wheel-rail sweep): the preconditioner is the diagonal alone, and P's product, which
            # would act on zeros, is skipped (the same numbers)
            def diagonal(r):
                out = np.empty_like(r)
                out[:nS] = local * r[:nS]
                out[nS:] = r[nS:]
                return out

            return diagonal

        def prec(r):
            d = np.zeros(2 * nc)
            d.put(ia2, r[:2 * nA])
            rt = r[2 * nA:2 * nA + nS]
            d.put(isl2, ((rt * w) * t).ravel())
            q = L.precondition(d.reshape(2, nc))
            out = np.empty_like(r)
            out[:2 * nA] = q.reshape(-1).take(ia2)
            if cc is not None:
                out[:2 * nA] += cc(r[:2 * nA].reshape(2, nA))
            out[2 * nA:2 * nA + nS] = w * (t[0] * q[0].take(isl) + t[1] * q[1].take(isl)) + local * rt
            out[2 * nA + nS:] = r[2 * nA + nS:]
            return out

        return prec

    def fresh(self, st: _State) -> _State:
        """The slip recomputed from the tractions in double precision (the iteration updates it
        incrementally with single-precision products)."""
        s = self.w + (st.creep - self.creep0)[:, None] + self.L.apply(st.p)
        return _State(st.p, s, st.creep, st.slipping)

    def solve(self, st: _State, tol: float, maxit: int):
        """Newton iterations until the residual measure <= tol (checked with a fresh slip).
        Returns (state with fresh slip, its, res, msg, last): ``last`` the residual
        (F, force errors, slip classification) of the returned state where the iteration ended on
        it, else None (:meth:`residual` of the state gives it)."""
        F, ferr, slip = self.residual(st.p, st.s, st.slipping)
        res = self.measure(st.p, F, ferr)
        best, stall, it = res, 0, 0
        msg, is_fresh = "", True
        while True:
            if res <= tol:
                if is_fresh:
                    break
                st, is_fresh = self.fresh(st), True
                F, ferr, slip = self.residual(st.p, st.s, st.slipping)
                res = self.measure(st.p, F, ferr)
                if res <= tol:
                    break
            elif not is_fresh and res < FRESH_BELOW * tol:
                # close to the tolerance: the slip updated by single-precision products has drifted
                # by about 1e-7 of the early steps' size, which the last step would have to undo
                st, is_fresh = self.fresh(st), True
                F, ferr, slip = self.residual(st.p, st.s, st.slipping)
                res = self.measure(st.p, F, ferr)
            if it >= maxit:
                msg = f"no convergence in {maxit} Newton iterations (residual {res:.3g} > tol {tol:g})"
                break
            it += 1
            rtol = forcing(res, tol)
            if not self.force_rows and slip.all():
                dp, ds, dcreep, _ = self.step_full_slip(st, rtol)
            else:
                dp, ds, dcreep, _ = self.step(st, F, ferr, slip, rtol)
            m0 = self.merit(F, ferr)
            memory = slip  # thresholds for the trial points: g_k where slipping now, g_s in adhesion
            alpha, tried = 1.0, []
            while True:
                p_t, s_t = st.p + alpha * dp, st.s + alpha * ds
                F_t, ferr_t, slip_t = self.residual(p_t, s_t, memory)
                m_t = self.merit(F_t, ferr_t)
                tried.append((m_t, alpha, p_t, s_t, F_t, ferr_t, slip_t))
                if m_t <= (1.0 - 1e-4 * alpha) * m0:
                    break
                if alpha < 1.0 / 64:  # no decrease: take the best step tried (non-monotone)
                    break
                alpha *= 0.5
            m_t, alpha, p_t, s_t, F_t, ferr_t, slip_t = min(tried, key=lambda r: r[0])
            st, is_fresh = _State(p_t, s_t, st.creep + alpha * dcreep, slip_t), False
            F, ferr, slip = F_t, ferr_t, slip_t
            res = self.measure(st.p, F, ferr)
            if res < 0.9 * best:
                best, stall = res, 0
            else:
                stall += 1
                if stall >= 25:
                    msg = f"Newton stalled at residual {res:.3g} (tol {tol:g}) after {it} iterations"
                    break
        if not is_fresh:
            return self.fresh(st), it, res, msg, None
        return st, it, res, msg, (F, ferr, slip)


# ----------------------------------------------------------------------------- entry point
def column_rigid_slip(grid, xi, eta, phi, steady: bool) -> np.ndarray:
    """Rigid slip (2, mx, my) from the creepages of the columns at x = 0 (seed Eq. 47; CONTACT's
    W/dq with chi = 0): w = (xi, eta + phi (x + dx/6)) in steady rolling, (xi, eta + phi x) for a
    shift.  xi, eta, phi broadcast against the grid: scalars, one value per column along y (or s),
    or per element.  On a planar grid the column value of xi is xi - phi y (the spin turns the
    longitudinal slip across the patch); on a curved grid every column has its own creepages, from
    the wheelset motion with the local contact angle (conformal.solvers.conformal)."""
    X = grid.x[:, None]
    dq6 = grid.dx / 6.0 if steady else 0.0
    w = np.empty((2,) + tuple(grid.shape))   # (the numbers of np.stack of the two broadcasts)
    w[0] = xi
    w[1] = eta + phi * (X + dq6)
    return w


def rescaled_start(p_start: np.ndarray, pn_start: np.ndarray, pn: np.ndarray) -> np.ndarray:
    """Starting tractions for the pressure ``pn`` from a neighbouring solution (tractions
    ``p_start`` (2, mx, my) under the pressure ``pn_start``, both on this grid, e.g. resampled):
    each element keeps its traction relative to the pressure, ``p_start pn / pn_start`` (zero where
    ``pn_start`` is zero).  Where the neighbour slipped, the start then lies on the new bound
    mu p_n: the contact solves of a wheel-rail sweep, mostly in full slip, need fewer Newton steps
    (the Manchester sequence: 106 -> 95; the second solve of a position, after the height
    correction, often none).

    >>> pn0, pn1 = np.array([[1.0, 2.0, 0.0]]), np.array([[1.5, 2.0, 1.0]])
    >>> rescaled_start(np.array([[[0.3, 0.6, 0.0]], [[0.0, 0.0, 0.0]]]), pn0, pn1)[0].tolist()
    [[0.44999999999999996, 0.6, 0.0]]
    """
    pn_start = np.asarray(pn_start, dtype=float)
    ratio = np.where(pn_start > 0, np.asarray(pn, dtype=float) / np.where(pn_start > 0, pn_start, 1.0), 0.0)
    return np.asarray(p_start, dtype=float) * ratio


def solve_tangential(op, grid, pn: np.ndarray, *, xi: float, eta: float, phi: float,
                     mu_static: float, mu_kinetic: float, rolling: str = "steady",
                     fx_rel: float | None = None, fy_rel: float | None = None,
                     extra_u: np.ndarray | None = None, tol: float = 1e-6, maxit: int = 100,
                     p_start: np.ndarray | None = None,
                     rigid_slip: np.ndarray | None = None,
                     creep_weight: np.ndarray | None = None,
                     displacements: bool = True) -> TangentialSolution:
    """Solve the tangential problem (module docstring) for the pressure ``pn`` on ``grid``.

    Parameters
    ----------
    op : the influence operator of the grid (:class:`conformal.influence.operator.InfluenceOperator`,
        x-invariant: the planar half-space, curved strips, ...).
    grid : PlanarGrid (or CurvedGrid: x along the rolling direction, ``mesh()`` and ``area``).
    pn : (mx, my) pressure (N/mm²); elements with pn = 0 are exterior (zero traction).
    xi, eta, phi : creepages (steady: -, -, rad/mm) or rigid shifts (shift: mm, mm, rad).  With
        fx_rel (fy_rel) prescribed, xi (eta) is the starting value of the unknown.
    mu_static, mu_kinetic : friction coefficients, mu_static >= mu_kinetic >= 0.
    rolling : "steady" (steady rolling in +x) or "shift" (transient shift from zero traction).
    fx_rel, fy_rel : prescribed FX/(mu_static FN), FY/(mu_static FN), or None.
    extra_u : (2, mx, my) tangential displacement difference from other loads (A_tn pn), or None.
    tol : on the friction-law residual relative to the largest traction, and on the relative
        force errors.
    maxit : most Newton iterations.
    p_start : (2, mx, my) starting tractions (e.g. the previous solution), or None (zero).
    rigid_slip : (2, mx, my) rigid slip per element added to the creepage part (curved grids with
        creepages varying over the patch), or None.
    creep_weight : (mx, my) factor on each element's rigid slip, the unknown creepages' part
        included (the fraction of a transient step an element spent in contact, CONTACT's
        leading-edge correction: conformal.solvers.history.leading_edge_factor), or None (1).  A
        prescribed force is then found by the root search on the creepage (one force at a time).
    displacements : False: ux, uy are left None (a solve whose answer is not reported, e.g. a loose
        pass of a wheel-rail balance, skips the influence products of the final displacements).

    Returns
    -------
    TangentialSolution; ``converged`` False with a ``message`` when the tolerance was not met.
    """
    shape = tuple(grid.shape)
    pn = checks.field("pn", pn, shape)
    if np.any(pn < 0):
        raise InputError("pn: the pressure must be >= 0")
    if (op.mx, op.my) != shape:
        raise InputError(f"op: influence operator is for {op.mx} x {op.my} elements, the grid has {shape}")
    if rolling not in ("steady", "shift"):
        raise InputError(f"[kinematics] rolling: must be \"steady\" or \"shift\", got {rolling!r}")
    xi, eta, phi = (checks.number(f"[kinematics] {k}", v) for k, v in (("xi", xi), ("eta", eta), ("phi", phi)))
    mu_s = checks.number("[friction] mu_static", mu_static, nonneg=True)
    mu_k = checks.number("[friction] mu_kinetic", mu_kinetic, nonneg=True)
    if mu_k > mu_s:
        raise InputError(f"[friction] mu_kinetic: must not exceed mu_static ({mu_k} > {mu_s})")
    tol = checks.number("[model] tol", tol, positive=True)
    if int(maxit) < 1:
        raise InputError(f"[model] maxit: must be >= 1, got {maxit}")
    targets = {}
    for key, v, k in (("fx_rel", fx_rel, 0), ("fy_rel", fy_rel, 1)):
        if v is not None:
            targets[k] = checks.number(f"[kinematics] {key}", v)
    if targets and mu_k == 0.0:
        raise InputError("[kinematics] fx_rel, fy_rel: a prescribed tangential force needs friction (mu > 0)")
    if targets:
        fmag = math.hypot(*targets.values())
        limit = mu_k / mu_s
        if not fmag < limit:
            raise InputError(f"[kinematics] fx_rel, fy_rel: the prescribed force |F|/(mu_static FN) = {fmag:.6g} "
                             f"must be < mu_kinetic/mu_static = {limit:.6g}, the force in full slip (with "
                             "mu_static > mu_kinetic larger forces lie on a falling branch of the creep-force "
                             "curve and are not unique)")
    steady = rolling == "steady"
    mx, my = shape
    area = np.broadcast_to(np.asarray(grid.area, dtype=float), shape)
    contact = pn > 0

    # rigid slip (seed Eq. 47; CONTACT's W/dq with chi = 0)
    # the y of the element centres: one row broadcast along x on a planar grid (the numbers of its
    # mesh(), without forming the (mx, my) copies), the mesh elsewhere
    Y = grid.y[None, :] if isinstance(grid, PlanarGrid) else grid.mesh()[1]
    w = column_rigid_slip(grid, xi - phi * Y, eta, phi, steady)
    if rigid_slip is not None:
        w = w + checks.field("rigid_slip", np.asarray(rigid_slip, dtype=float), (2,) + shape)
    weight = None
    if creep_weight is not None:
        weight = checks.field("creep_weight", np.asarray(creep_weight, dtype=float), shape)
        w = w * weight
        if len(targets) > 1:
            raise InputError("[kinematics] fx_rel, fy_rel: both forces prescribed with a weighted rigid slip "
                             "(a transient step over more than one element) are not supported")
    if extra_u is not None:
        eu = checks.field("extra_u", extra_u, (2,) + shape)
        if steady:  # (u - u')/dx of the extra displacement; u' of the leading column: u there
            w = w + np.stack([np.concatenate([eu[k, :-1] - eu[k, 1:], np.zeros((1, my))]) for k in (0, 1)]) / grid.dx
        else:
            w = w + eu

    def finish(px, py, sx, sy, status, xi_, eta_, its, res, conv, msg, nprod, L=None):
        if not displacements:
            ux = uy = None
        elif L is None:
            (ux, uy), nprod = op.apply_tangential(px, py), nprod + 1
        else:
            before = L.products
            ux, uy = L.grid_u(px, py)
            nprod += L.products - before
        if extra_u is not None and displacements:
            ux, uy = ux + extra_u[0], uy + extra_u[1]
        return TangentialSolution(px=px, py=py, sx=sx, sy=sy, ux=ux, uy=uy, status=status.astype(np.int8),
                                  xi=float(xi_), eta=float(eta_), iterations=its, residual=float(res),
                                  converged=conv, message=msg, products=nprod,
                                  coarse_products=float(getattr(L, "coarse_products", 0.0)))

    if not contact.any():
        zeros = np.zeros(shape)
        return finish(zeros, zeros.copy(), zeros.copy(), zeros.copy(), np.full(shape, EXTERIOR), xi, eta,
                      0, 0.0, True, "", 0)
    FN = float((pn * area).sum())
    if mu_k == 0.0:  # frictionless: no traction, every element with rigid slip slips
        zeros = np.zeros(shape)
        ws = np.where(contact, w, 0.0)
        status = np.where(contact, np.where(np.hypot(ws[0], ws[1]) > 0, SLIP, ADHESION), EXTERIOR)
        return finish(zeros, zeros.copy(), ws[0], ws[1], status, xi, eta, 0, 0.0, True, "", 0)

    force_rows = [(k, targets[k] * mu_s * FN) for k in sorted(targets)]
    if p_start is not None:
        p_start = checks.field("p_start", p_start, (2,) + shape)
    if weight is not None and force_rows:    # the creepage acts with a weight: fixed-creepage solves
        st = slip = its = L = msg = None
        res, nprod = np.inf, 0
    else:
        st, slip, its, res, msg, L = _solve_grid(op, grid, pn, w, area, steady, mu_s, mu_k, force_rows,
                                                 np.array([xi, eta]), tol, int(maxit), p_start)
        nprod = L.products
    if res > tol and len(force_rows) == 1:
        # the bordered Newton system failed (e.g. near saturation with a strong normal-tangential
        # coupling): a bracketing root search on the creepage, each step a fixed-creepage solve
        k, target = force_rows[0]
        found = _bracketed_force(op, grid, pn, w, area, steady, mu_s, mu_k, k, target,
                                 np.array([xi, eta]), float(st.creep[k]) if st is not None else (xi, eta)[k], tol,
                                 int(maxit), weight)
        nprod += found[-1]
        if found[3] <= tol or st is None:
            st, slip, its, res, msg, L = found[:-1]
            msg = "" if res <= tol else msg
        else:
            msg = f"{msg}; the bracketing search on the creepage failed too: {found[4]}"
    idx = L.idx
    conv = res <= tol
    if conv:
        msg = ""
    elif not msg:
        msg = f"residual {res:.3g} > tol {tol:g} after {its} Newton iterations"
    px, py, sx, sy = (np.zeros(mx * my) for _ in range(4))
    px[idx], py[idx] = st.p
    status = np.full(mx * my, EXTERIOR)
    if slip.all():   # (full slip: np.where's numbers without its selections)
        sx[idx], sy[idx] = st.s
        status[idx] = SLIP
    else:
        sx[idx], sy[idx] = np.where(slip, st.s, 0.0)
        status[idx] = np.where(slip, SLIP, ADHESION)
    r = lambda a: a.reshape(shape)
    return finish(r(px), r(py), r(sx), r(sy), r(status), st.creep[0], st.creep[1], its, res, conv, msg,
                  nprod, L)


def _bracketed_force(op, grid, pn, w, area, steady, mu_s, mu_k, k, target, creep0, guess, tol, maxit, weight=None):
    """Prescribed force component k (N) by a root search on creepage k: expand a bracket from
    ``guess`` (factor 4 steps), then Illinois regula falsi.  Each evaluation solves the problem at
    a fixed creepage (no bordered system), warm started from the nearest solution.  The force is a
    continuous, monotone function of the creepage, so the bracket always exists for |F| < mu_k FN.
    ``weight``: the creepage's rigid slip per element is weighted by it (``creep_weight``).

    Returns (state, slip, iterations, residual, message, L, products); residual combines the
    friction-law residual and the relative force error, as the Newton measure does."""
    shape = pn.shape
    FN_mu = mu_s * float((pn * area).sum())
    products, its_total = 0, 0
    memo: dict[float, tuple] = {}
    last = [None]

    def evaluate(c: float):
        nonlocal products, its_total
        wc = w.copy()
        wc[k] += (c - creep0[k]) * (1.0 if weight is None else weight)
        creep = creep0.copy()
        creep[k] = c
        p0 = None
        if last[0] is not None:  # warm start from the previous solution
            st0, L0 = last[0]
            p0 = np.zeros((2, shape[0] * shape[1]))
            p0[:, L0.idx] = st0.p
            p0 = p0.reshape((2,) + shape)
        st, slip, its, res, msg, L = _solve_grid(op, grid, pn, wc, area, steady, mu_s, mu_k, [], creep,
                                                 tol, maxit, p0)
        products += L.products
        its_total += its
        last[0] = (st, L)
        F = float((area.ravel()[L.idx] * st.p[k]).sum())
        fscale = max(abs(target), float((area.ravel()[L.idx] * np.hypot(*st.p)).sum()), 1e-12 * FN_mu)
        g = (F - target) / FN_mu
        memo[c] = (st, slip, its, max(res, abs(F - target) / fscale), msg, L)
        return g, abs(F - target) / fscale, res

    def done(c):
        st, slip, its, res, msg, L = memo[c]
        return st, slip, its_total, res, msg, L, products

    # a creepage scale: the slip of one element carrying mu pmax (L's diagonal), or the guess
    scale = max(abs(guess), 1e-3 * abs(guess) + mu_s * float(pn.max()) * 1e-6)
    c0 = guess
    g0, e0, r0 = evaluate(c0)
    if e0 <= tol and r0 <= tol:
        return done(c0)
    h = max(abs(c0), scale, 1e-300)
    c1 = c0 + h
    g1, e1, r1 = evaluate(c1)
    same = np.sign(g1) == np.sign(g0)
    flat = same and abs(g1 - g0) <= 1e-9 * max(abs(g0), 1e-300)
    # wrong way: |g| grew; or no slope at all (full slip on both sides: the force is mu_k FN in
    # magnitude and does not change), where the force, which decreases with the creepage (a positive
    # creepage gives a negative force), says which way: g < 0 (force too small) to smaller creepage.
    # (Near frictionless dissimilar rollers every creepage but a narrow band saturates: the search
    # went the wrong way for ever, issue 22.)
    if same and (abs(g1) > abs(g0) or (flat and np.sign(h) != np.sign(g0))):
        h, c1 = -h, c0 - h
        g1, e1, r1 = evaluate(c1)
    n = 0
    while np.sign(g1) == np.sign(g0) and g1 != 0.0:
        n += 1
        if n > 60:
            return (*memo[c1][:4], f"no bracket of the prescribed force found up to creepage {c1:.6g}",
                    memo[c1][5], products)
        c0, g0 = c1, g1
        h *= 4.0
        c1 = c0 + h
        g1, e1, r1 = evaluate(c1)
    if e1 <= tol and r1 <= tol:
        return done(c1)
    a, ga, b, gb = c0, g0, c1, g1
    side = 0
    for _ in range(100):
        c = b - gb * (b - a) / (gb - ga) if gb != ga else 0.5 * (a + b)
        if not (min(a, b) < c < max(a, b)):
            c = 0.5 * (a + b)
        g, e, r = evaluate(c)
        if e <= tol and r <= tol:
            return done(c)
        if np.sign(g) == np.sign(gb):   # Illinois: halve the retained end's value
            b, gb = c, g
            if side == -1:
                ga *= 0.5
            side = -1
        else:
            a, ga = c, g
            if side == +1:
                gb *= 0.5
            side = +1
        if abs(b - a) <= 1e-14 * max(abs(a), abs(b)):
            break
    c = min(memo, key=lambda v: memo[v][3])
    st, slip, its, res, msg, L = memo[c]
    return st, slip, its_total, res, f"the creepage search stopped at residual {res:.3g}", L, products



# ----------------------------------------------------------------------------- one grid (+ nested start)
#: solve a 2x coarser problem first (nested iteration) from this many contact elements on
NESTED_FROM = 1500
#: tolerance of the coarse solve that gives the starting tractions
NESTED_TOL = 1e-3
PROLONG_LINEAR = True
PROLONG_RATIO = True


def _solve_grid(op, grid, pn, w, area, steady, mu_s, mu_k, force_rows, creep0, tol, maxit, p_start):
    """Newton on one grid; returns (state, slip classification, iterations, residual, message, L).
    Without ``p_start`` on a large planar half-space problem the start comes from the same problem
    on a 2x coarser grid (nested iteration), prolonged element-wise."""
    contact = pn > 0
    L = _SlipOperator(op, grid, contact, steady)
    idx = L.idx
    gk = (mu_k * pn).ravel()[idx]
    gs = (mu_s * pn).ravel()[idx]
    wc = w.reshape(2, -1)[:, idx].copy()
    FN = float((pn * area).sum())
    newton = _Newton(L, wc, gs, gk, area[contact], force_rows, mu_s * FN)   # (area.ravel()[idx] without the copy)
    newton.creep0 = creep0
    creep = creep0.copy()
    if p_start is None and idx.size >= NESTED_FROM:
        p_start, creep, L.coarse_products = _coarse_start(op, grid, pn, w, area, steady, mu_s, mu_k, force_rows,
                                                          creep0, maxit)
    if p_start is not None:
        p0 = p_start.reshape(2, -1)[:, idx].copy()
        mag = np.hypot(p0[0], p0[1])
        p0 *= np.where(mag > gs, gs / np.where(mag > 0, mag, 1.0), 1.0)
        slipping = mag >= gk * (1.0 - 1e-9)
    else:
        p0, slipping = np.zeros((2, idx.size)), np.zeros(idx.size, bool)
    s0 = wc + (creep - creep0)[:, None] + L.apply(p0)
    st, its, res, msg, last = newton.solve(_State(p0, s0, creep, slipping), tol, maxit)
    if last is None:   # (a fresh state's residual, where the iteration ended on it: the same arguments)
        F, ferr, slip = newton.residual(st.p, st.s, st.slipping)
        res = newton.measure(st.p, F, ferr)
    else:
        F, ferr, slip = last
    return st, slip, its, res, msg, L


def _coarse_start(op, grid, pn, w, area, steady, mu_s, mu_k, force_rows, creep0, maxit):
    """Starting tractions from the problem on a grid of 2 x 2 merged elements (block means of the
    pressure and the rigid slip) and their cost in products of the fine grid, or (None, creep0, 0)
    where that is not possible."""
    from conformal.grid import PlanarGrid

    mx, my = pn.shape
    fy = 2 if my >= 8 else 1
    cop = op.coarsened(2, fy)
    if cop is None or not isinstance(grid, PlanarGrid):
        return None, creep0, 0.0
    mxc, myc = cop.mx, cop.my

    def block_mean(a):
        pad = np.zeros(a.shape[:-2] + (2 * mxc, fy * myc))
        pad[..., :mx, :my] = a
        return pad.reshape(a.shape[:-2] + (mxc, 2, myc, fy)).mean(axis=(-3, -1))

    cgrid = PlanarGrid(mxc, myc, 2 * grid.dx, fy * grid.dy, grid.xl, grid.yl)
    pnc, wc = block_mean(pn), block_mean(w)
    carea = np.full(cgrid.shape, cgrid.area)
    FNc = float((pnc * carea).sum())
    FN = float((pn * area).sum())
    rows = [(k, f * FNc / FN) for k, f in force_rows]
    st, slip, *_ , L = _solve_grid(cop, cgrid, pnc, wc, carea, steady, mu_s, mu_k, rows, creep0,
                                   max(NESTED_TOL, 0.0), maxit, None)
    pc = np.zeros((2, mxc * myc))
    pc[:, L.idx] = st.p
    pc = pc.reshape(2, mxc, myc)
    if PROLONG_LINEAR:
        from scipy.ndimage import map_coordinates
        cx = (np.arange(mx) + 0.5) / 2 - 0.5
        cy = (np.arange(my) + 0.5) / fy - 0.5
        CX, CY = np.meshgrid(cx, cy, indexing="ij")
        if PROLONG_RATIO and not steady:
            # the traction relative to its bound mu p_n, interpolated over the coarse contact elements
            # only (normalised), times the fine bound
            gc = mu_k * pnc
            inside = (gc > 0).astype(float)
            q = np.where(gc > 0, pc / np.where(gc > 0, gc, 1.0), 0.0)
            wgt = map_coordinates(inside, [CX, CY], order=1, mode="nearest")
            wgt = np.where(wgt > 0, wgt, 1.0)
            pf = np.stack([map_coordinates(q[k], [CX, CY], order=1, mode="nearest") / wgt for k in (0, 1)]) * (mu_k * pn)
        else:
            pf = np.stack([map_coordinates(pc[k], [CX, CY], order=1, mode="nearest") for k in (0, 1)])
    else:
        pf = np.repeat(np.repeat(pc, 2, axis=1), fy, axis=2)[:, :mx, :my]
    cost = (L.products + L.coarse_products) * (mxc * myc) / (mx * my)
    return np.where(pn > 0, pf, 0.0), st.creep, cost
