"""Kalker's simplified theory and its algorithm FASTSIM (Kalker 1973, 1982; seed Eqs. 21-36).

Simplified theory: the tangential displacement difference is proportional to the local
traction, u = L p (seed Eq. 21), with three flexibilities chosen so that the no-slip forces equal
linear theory (seed Eqs. 25-27)::

    L1 = 8 a / (3 G C11),   L2 = 8 a / (3 G C22),   L3 = pi a sqrt(a/b) / (4 G C23)

and, for a contaminating surface layer of flexibility Lc (mm³/N = mm per N/mm²), in series:
L_i + Lc (seed Eqs. 34-36; Lc is added to all three).

Steady rolling in +x (material enters at the leading edge x = +x_l(y), seed Eq. 23): the slip
per unit rolling distance is s = w~ - L dp/dx with the "rigid slip over flexibility" (seed
Eq. 22, whose printed lateral spin term -phi y/L3 is a typo for +phi x/L3, cf. Eq. 24)::

    w~x / L1 = xi/L1 - phi y/L3,      w~y / L2 = eta/L2 + phi x/L3.

FASTSIM marches along each strip y = const from the leading edge: in adhesion
p(x) = -int_x^{x_l} (w~/L) dx' (seed Eq. 24 with D = 0); wherever the trial traction exceeds
the traction bound g = mu p_n it is scaled back onto it (slip), with the slip
s = L (p - p_trial) / h (opposite to p, Coulomb).  Traction bounds: parabolic
p_n = 2FN/(pi a b)(1 - x²/a² - y²/b²) (Kalker's choice for FASTSIM) or elliptic (Hertz)
p_n = 3FN/(2 pi a b) sqrt(1 - x²/a² - y²/b²).

Two discretisations of the same marching rule:

* :func:`fastsim_grid` on a :class:`~conformal.grid.PlanarGrid` (used by :func:`solve`; returns
  traction and slip maps).  Strips = grid columns; elements whose centre lies inside the
  ellipse are in contact; tractions live at element centres; by default the first step of each
  strip runs from the leading edge x_l(y) to the first centre, later steps are dx, with the
  midpoint rule for the rigid slip integral (exact for the linear-in-x w~).  The variant
  ``discretisation="contact"`` reproduces CONTACT's grid FASTSIM (to 4 printed digits).
* :func:`fastsim_batch`: Kalker's slices on the unit circle (seed Eqs. 28-32), ny strips
  (cosine-spaced by default, equal widths as in Kalker 1982 on request), nx equal cells per
  strip (cell centres, midpoint rule), vectorised over any number of contacts with numpy.
  :func:`fastsim_forces` is the single-contact form.

In full adhesion both reproduce seed Eqs. 25-26 (linear theory's FX, FY, with L from Eq. 27)
up to the discretisation of the ellipse boundary.  With spin the slip-zone update (the
projection onto the traction bound) is first order in the step, as in Kalker's algorithm.

>>> r = fastsim_forces(8.0, 4.0, 82000.0, 0.3, 0.0, -0.000625, 0.000625, G=82000.0, nu=0.28)
>>> round(r.FY / (0.3 * 82000.0), 2)
-0.65
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.errors import InputError
from conformal.grid import PlanarGrid
from conformal.result import ADHESION, EXTERIOR, SLIP
from conformal.theories import coefficients as coef

BOUNDS = ("parabolic", "elliptic")
DISCRETISATIONS = ("midpoint", "contact")


# ----------------------------------------------------------------------------- flexibilities
@dataclass(frozen=True)
class Flexibilities:
    """FASTSIM flexibilities L1 (xi), L2 (eta), L3 (phi), mm³/N, layer included."""

    L1: float
    L2: float
    L3: float


def flexibilities(a, b, G, nu, layer_flexibility=0.0):
    """L1, L2, L3 of seed Eq. 27 plus a layer flexibility Lc (seed Eq. 36); arrays broadcast.

    >>> f = flexibilities(8.0, 4.0, 82000.0, 0.25)      # C = 5.10, 4.90, 2.62 (table, b/a = 0.5)
    >>> round(f.L1 * 1e5, 4), round(f.L2 * 1e5, 4), round(f.L3 * 1e5, 4)
    (5.1012, 5.3094, 4.136)
    """
    a, b, G, nu, lc = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                            for v in (a, b, G, nu, layer_flexibility)))
    if np.any(lc < 0) or not np.all(np.isfinite(lc)):
        raise InputError(f"[model] layer_flexibility: must be >= 0, got {layer_flexibility}")
    c11, c22, c23 = coef.coefficient_arrays(a / b, nu)
    L1 = 8.0 * a / (3.0 * G * c11) + lc                                 # seed Eq. 27, 36
    L2 = 8.0 * a / (3.0 * G * c22) + lc
    L3 = np.pi * a * np.sqrt(a / b) / (4.0 * G * c23) + lc
    if L1.ndim == 0:
        return Flexibilities(float(L1), float(L2), float(L3))
    return Flexibilities(L1, L2, L3)


# ----------------------------------------------------------------------------- kernel
def _march(dpx, dpy, bound):
    """March along the last axis (leading -> trailing): p_k = project(p_{k-1} + dp_k, bound_k).

    dpx, dpy: traction increments of full adhesion over each step; bound: mu p_n at the cells
    (0 outside the contact).  Returns px, py, trial-minus-final (qx, qy) and the slip mask.
    """
    shape = dpx.shape
    px, py = np.zeros(shape), np.zeros(shape)
    qx, qy = np.zeros(shape), np.zeros(shape)
    slip = np.zeros(shape, dtype=bool)
    cx, cy = np.zeros(shape[:-1]), np.zeros(shape[:-1])
    for k in range(shape[-1]):
        tx, ty = cx + dpx[..., k], cy + dpy[..., k]
        t = np.hypot(tx, ty)
        g = bound[..., k]
        s = t > g
        f = np.where(s, g / np.where(s, t, 1.0), 1.0)
        cx, cy = tx * f, ty * f
        px[..., k], py[..., k] = cx, cy
        qx[..., k], qy[..., k] = cx - tx, cy - ty
        slip[..., k] = s
    return px, py, qx, qy, slip


def _bound_shape(r2, bound):
    """Traction bound shape (times p0 of the bound) for r² = x²/a² + y²/b²."""
    inside = np.clip(1.0 - r2, 0.0, None)
    return inside if bound == "parabolic" else np.sqrt(inside)


def _p0(FN, a, b, bound):
    return 2.0 * FN / (np.pi * a * b) if bound == "parabolic" else 1.5 * FN / (np.pi * a * b)


def _check_bound(bound):
    if bound not in BOUNDS:
        raise InputError(f"[model] bound: must be one of {', '.join(map(repr, BOUNDS))}, got {bound!r}")


# ----------------------------------------------------------------------------- grid version
@dataclass(frozen=True, eq=False)
class FastsimGridSolution:
    """FASTSIM on a planar grid: element arrays (mx, my) and totals (on body 1)."""

    grid: PlanarGrid
    pn: np.ndarray
    px: np.ndarray
    py: np.ndarray
    sx: np.ndarray
    sy: np.ndarray
    status: np.ndarray
    FX: float
    FY: float
    MZ: float
    FN_grid: float


def fastsim_grid(a: float, b: float, FN: float, mu: float, xi: float, eta: float, phi: float,
                 L: Flexibilities, grid: PlanarGrid, bound: str = "parabolic",
                 discretisation: str = "midpoint") -> FastsimGridSolution:
    """FASTSIM on the element centres of ``grid`` for the Hertz ellipse (a, b) centred at 0.

    Elements with centre strictly inside the ellipse are in contact.  Rolling in +x.  MZ is
    about the grid origin (x = y = 0, the ellipse centre).

    ``discretisation``:

    * ``"midpoint"`` (default): the first step of a strip starts at the ellipse's leading edge
      x_l(y); the rigid slip is integrated by the midpoint rule (exact for w~ linear in x).
    * ``"contact"``: CONTACT's grid FASTSIM (found by matching its printed results, see
      tests/validation/test_fastsim.py): every step is dx long, also the first one (the exterior element
      upstream carries p = 0, i.e. the leading edge is put one dx before the first centre), and
      the rigid slip of a step is dx (xi - phi y, eta + phi (x + dx/6)) (CONTACT's W_I with its
      delta q/6 term).  Both are first-order in dx at the edge; "midpoint" is closer to the
      converged result on coarse grids (measured in studies/fast_theories_benchmark.py).
    """
    _check_bound(bound)
    if discretisation not in DISCRETISATIONS:
        raise InputError(f"[model] discretisation: must be one of {', '.join(map(repr, DISCRETISATIONS))}, "
                         f"got {discretisation!r}")
    X, Y = grid.mesh()                                  # (mx, my)
    r2 = (X / a) ** 2 + (Y / b) ** 2
    inside = r2 < 1.0
    pn = _p0(FN, a, b, bound) * np.where(inside, _bound_shape(r2, bound), 0.0)
    # march along x from high to low: work on arrays (my, mx) with x descending
    xs = grid.x[::-1]
    ins = inside[::-1, :].T                             # (my, mx), k = 0 is the highest x
    y = grid.y[:, None]
    xl = a * np.sqrt(np.clip(1.0 - (grid.y / b) ** 2, 0.0, None))[:, None]   # leading edge
    prev_in = np.zeros_like(ins)
    prev_in[:, 1:] = ins[:, :-1]
    first = ins & ~prev_in
    if discretisation == "midpoint":
        x_prev = np.where(first, xl, xs[None, :] + grid.dx)  # upstream end of each step
        xmid = 0.5 * (x_prev + xs[None, :])
    else:  # "contact"
        x_prev = np.broadcast_to(xs[None, :] + grid.dx, ins.shape)
        xmid = np.broadcast_to(xs[None, :] + grid.dx / 6.0, ins.shape)
    h = np.where(ins, x_prev - xs[None, :], 0.0)
    dpx = -h * (xi / L.L1 - phi * y / L.L3)             # seed Eq. 24 (midpoint rule)
    dpy = -h * (eta / L.L2 + phi * xmid / L.L3)
    g = mu * pn[::-1, :].T
    px, py, qx, qy, slip = _march(dpx, dpy, g)
    hs = np.where(h > 0, h, 1.0)
    sx, sy = np.where(ins, L.L1 * qx / hs, 0.0), np.where(ins, L.L2 * qy / hs, 0.0)
    back = lambda v: v.T[::-1, :]                       # noqa: E731  (my, mx) desc -> (mx, my)
    px, py, sx, sy, slip = back(px), back(py), back(sx), back(sy), back(slip)
    status = np.where(inside, np.where(slip, SLIP, ADHESION), EXTERIOR).astype(np.int8)
    dA = grid.area
    return FastsimGridSolution(grid=grid, pn=pn, px=px, py=py, sx=sx, sy=sy, status=status,
                               FX=float(px.sum() * dA), FY=float(py.sum() * dA),
                               MZ=float((X * py - Y * px).sum() * dA), FN_grid=float(pn.sum() * dA))


# ----------------------------------------------------------------------------- batch version
@dataclass(frozen=True, eq=False)
class FastsimForces:
    """Totals from :func:`fastsim_batch` (arrays, one entry per contact; on body 1)."""

    FX: np.ndarray
    FY: np.ndarray
    MZ: np.ndarray
    slip_fraction: np.ndarray  # area fraction of the contact in slip


def _slices(nx: int, ny: int, spacing: str = "cosine"):
    """Unit-circle slices: strip centres y', strip widths dy', half lengths x'_l, cell step h'
    and cell centres x' (nx, ny).

    ``spacing="cosine"``: y' = cos(theta) with theta at the midpoints of ny equal steps in
    (0, pi), strip width sin(theta) pi/ny (the midpoint rule in theta: the integrand of the
    slice sum, x_l(y) times a smooth function, becomes smooth and periodic in theta, which
    removes the sqrt edge singularity of equal-width slices).  ``"uniform"``: Kalker's equal
    widths 2/ny.
    """
    if spacing == "cosine":
        th = (np.arange(ny) + 0.5) * (np.pi / ny)
        yc, dy = np.cos(th)[::-1].copy(), (np.sin(th) * (np.pi / ny))[::-1].copy()
    else:
        yc = -1.0 + (np.arange(ny) + 0.5) * (2.0 / ny)
        dy = np.full(ny, 2.0 / ny)
    xl = np.sqrt(1.0 - yc**2)
    hp = 2.0 * xl / nx
    xc = xl[None, :] - (np.arange(nx)[:, None] + 0.5) * hp[None, :]   # (nx, ny)
    return yc, dy, xl, hp, xc


def fastsim_batch(a, b, FN, mu, xi, eta, phi=0.0, *, G=None, nu=None, L=None,
                  layer_flexibility=0.0, bound: str = "parabolic", nx: int = 24,
                  ny: int = 24, spacing: str = "cosine") -> FastsimForces:
    """FASTSIM for many contacts at once (arrays broadcast to one shape; vectorised with numpy).

    Give either the combined constants (``G``, ``nu``: flexibilities from seed Eq. 27 with
    Kalker's coefficients) or ``L = (L1, L2, L3)`` directly; ``layer_flexibility`` is added to
    them in both cases (seed Eq. 36).  Forces on body 1 (N), MZ (N mm) about the ellipse centre.
    Discretisation: Kalker's slices on the unit circle, ``ny`` strips of ``nx`` cells (the
    default 24 x 24 gives forces within about 0.5 % of the converged values in the cases of
    tests/validation/test_fastsim.py).  Work is O(n_contacts nx ny); memory O(n_contacts ny).
    """
    _check_bound(bound)
    if L is None:
        if G is None or nu is None:
            raise InputError("fastsim_batch: give G and nu, or the flexibilities L = (L1, L2, L3)")
        f = flexibilities(a, b, G, nu, layer_flexibility)
        L1, L2, L3 = f.L1, f.L2, f.L3
    else:
        lc = np.asarray(layer_flexibility, dtype=float)
        if np.any(lc < 0):
            raise InputError(f"[model] layer_flexibility: must be >= 0, got {layer_flexibility}")
        L1, L2, L3 = (np.asarray(v, dtype=float) + lc for v in L)
    arrs = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                 for v in (a, b, FN, mu, xi, eta, phi, L1, L2, L3)))
    shape = arrs[0].shape
    a, b, FN, mu, xi, eta, phi, L1, L2, L3 = (v.reshape(-1, 1) for v in arrs)
    if not (np.all(a > 0) and np.all(b > 0) and np.all(FN > 0) and np.all(mu >= 0)
            and np.all(L1 > 0) and np.all(L2 > 0) and np.all(L3 > 0)):
        raise InputError("fastsim_batch: a, b, FN, L1, L2, L3 must be > 0 and mu >= 0")
    if not (np.all(np.isfinite(xi)) and np.all(np.isfinite(eta)) and np.all(np.isfinite(phi))):
        raise InputError("fastsim_batch: creepages xi, eta, phi must be finite")
    if spacing not in ("cosine", "uniform"):
        raise InputError(f"fastsim_batch: spacing must be 'cosine' or 'uniform', got {spacing!r}")
    if int(nx) < 1 or int(ny) < 1:
        raise InputError(f"fastsim_batch: nx, ny must be >= 1, got {nx}, {ny}")
    sl = _slices(int(nx), int(ny), spacing)
    out = np.empty((4, a.shape[0]))
    for i in range(0, a.shape[0], CHUNK):   # chunks that stay in cache: measured 1.3-1.5x faster
        c = slice(i, i + CHUNK)
        out[:, c] = _batch_chunk(a[c], b[c], FN[c], mu[c], xi[c], eta[c], phi[c], L1[c], L2[c],
                                 L3[c], sl, bound)
    return FastsimForces(*(v.reshape(shape) for v in out))


CHUNK = 1024


def _batch_chunk(a, b, FN, mu, xi, eta, phi, L1, L2, L3, slices, bound):
    """FX, FY, MZ, slip fraction for a chunk of contacts (all arguments (n, 1))."""
    yc, dyp, xlp, hp, xc = slices
    nx = xc.shape[0]
    shape_k = _bound_shape(xc**2 + yc[None, :] ** 2, bound)   # (nx, ny), same for all contacts
    g0 = mu * _p0(FN, a, b, bound)                            # (n, 1)
    h = a * hp[None, :]                                       # physical step (n, ny)
    y = b * yc[None, :]
    # full-adhesion traction increment over a step of length h: dpx = h (phi y/L3 - xi/L1),
    # dpy = -h (eta/L2 + phi x_mid/L3) (seed Eq. 24, midpoint rule, exact for w~ linear in x)
    dpx = h * (phi * y / L3 - xi / L1)
    dpy0 = -h * (eta / L2)
    dpy1 = -h * (phi / L3) * a
    xm = xc + 0.5 * hp[None, :]                               # step midpoints / a (nx, ny)
    xm[0] = xc[0] + 0.25 * hp                                 # first step: edge -> centre
    px, py = np.zeros(dpx.shape), np.zeros(dpx.shape)
    spx, spy, sxpy = np.zeros(dpx.shape), np.zeros(dpx.shape), np.zeros(dpx.shape)
    nslip = np.zeros(dpx.shape)
    for k in range(nx):
        w = 0.5 if k == 0 else 1.0
        tx = px + w * dpx
        ty = py + w * (dpy0 + dpy1 * xm[k])
        t = np.hypot(tx, ty)
        g = g0 * shape_k[k]
        nslip += t > g
        f = np.minimum(1.0, g / np.maximum(t, 1e-300))        # project onto |p| <= mu pn
        np.multiply(tx, f, out=px)
        np.multiply(ty, f, out=py)
        spx += px
        spy += py
        sxpy += xc[k] * py
    dA = h * (b * dyp[None, :])                               # cell areas (n, ny)
    FX = (spx * dA).sum(axis=1)
    FY = (spy * dA).sum(axis=1)
    MZ = ((a * sxpy - y * spx) * dA).sum(axis=1)
    frac = (nslip * dA).sum(axis=1) / (np.pi * a[:, 0] * b[:, 0])
    return FX, FY, MZ, frac


def fastsim_forces(a: float, b: float, FN: float, mu: float, xi: float, eta: float, phi: float = 0.0,
                   **kwargs) -> FastsimForces:
    """Single-contact FASTSIM (slice discretisation): :func:`fastsim_batch` for one contact,
    returning plain floats."""
    r = fastsim_batch(a, b, FN, mu, xi, eta, phi, **kwargs)
    return FastsimForces(float(r.FX), float(r.FY), float(r.MZ), float(r.slip_fraction))


# ----------------------------------------------------------------------------- model
def _grid_for(problem, a: float, b: float) -> tuple[PlanarGrid, str]:
    g = problem.grid
    if g is not None:
        xh, yh = g.xl + g.mx * g.dx, g.yl + g.my * g.dy
        if g.xl <= -a and xh >= a and g.yl <= -b and yh >= b:
            return g, "problem grid"
    n = problem.model.options.get("n", 40)
    if isinstance(n, bool) or not isinstance(n, int) or n < 4:
        raise InputError(f"[model] n: elements per axis of FASTSIM's own grid, a whole number >= 4, got {n!r}")
    return PlanarGrid.around_ellipse(a, b, n=n, scale=1.1), f"own {n}x{n} grid on 1.1 x the Hertz ellipse"


def problem_flexibilities(problem, a: float, b: float) -> tuple[Flexibilities, str]:
    """Flexibilities from Kalker's coefficients (seed Eq. 27) or ``[model] flexibilities =
    [L1, L2, L3]`` (mm³/N, e.g. CONTACT's printed values), plus ``[model] layer_flexibility``."""
    lc = problem.model.layer_flexibility
    given = problem.model.options.get("flexibilities")
    if given is None:
        return flexibilities(a, b, problem.material.G, problem.material.nu, lc), "kalker"
    ok = (isinstance(given, (list, tuple)) and len(given) == 3
          and all(isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 and math.isfinite(v)
                  for v in given))
    if not ok:
        raise InputError(f"[model] flexibilities: must be three numbers > 0 (L1, L2, L3 in mm³/N), got {given!r}")
    return Flexibilities(*(float(v) + lc for v in given)), "given"


def solve(problem):
    """FASTSIM as a model: traction and slip maps on the problem's grid (when it contains the
    Hertz ellipse; otherwise an own 40 x 40 grid, ``[model] n`` to change) and the totals.

    Scene keys: ``[model] bound`` ("parabolic" | "elliptic"), ``layer_flexibility`` (mm³/N),
    ``discretisation`` ("midpoint" | "contact", see :func:`fastsim_grid`), ``flexibilities``
    ([L1, L2, L3] in mm³/N instead of seed Eq. 27).

    FN, pmax and approach are Hertz's (pmax: the largest element-centre value of the traction
    bound's pressure, as CONTACT prints it); FX, FY, MZ are sums over the elements.
    """
    from conformal.result import Result, TractionField
    from conformal.theories.linear import material_notes, steady_hertz

    hz = steady_hertz(problem, "fastsim")
    kin, mu = problem.kinematics, problem.friction.mu
    if kin.fx_rel is not None or kin.fy_rel is not None:
        raise InputError("[kinematics] fx_rel: theory \"fastsim\" takes creepages (xi, eta); "
                         "prescribed forces are supported by theory \"linear\"")
    L, Lsource = problem_flexibilities(problem, hz.a, hz.b)
    grid, gsource = _grid_for(problem, hz.a, hz.b)
    disc = problem.model.options.get("discretisation", "midpoint")
    sol = fastsim_grid(hz.a, hz.b, hz.FN, mu, kin.xi, kin.eta, kin.phi, L, grid, problem.model.bound,
                       discretisation=disc)
    field = TractionField(grid=grid, pn=sol.pn, px=sol.px, py=sol.py, status=sol.status,
                          sx=sol.sx, sy=sol.sy)
    extra = {"bound": problem.model.bound, "discretisation": disc, "L1": L.L1, "L2": L.L2, "L3": L.L3,
             "flexibilities": Lsource, "layer_flexibility": problem.model.layer_flexibility,
             "grid": gsource, "FN_grid": sol.FN_grid,
             "FX_over_muFN": sol.FX / (mu * hz.FN), "FY_over_muFN": sol.FY / (mu * hz.FN),
             **material_notes(problem)}
    return Result(theory="fastsim", FN=hz.FN, FX=sol.FX, FY=sol.FY, MZ=sol.MZ, a=hz.a, b=hz.b,
                  pmax=float(sol.pn.max()), approach=hz.approach, xi=kin.xi, eta=kin.eta,
                  phi=kin.phi, field=field, extra=extra)
