"""Kalker's creepage and spin coefficients C11, C22, C23, C33 computed with the exact half-space
theory at vanishing creepage (seed Eq. 13; Kalker 1967, Kalker 1990 ch. 2), i.e. in full adhesion,
where the steady rolling problem is linear.

For a Hertzian contact with semi-axes a (rolling direction x) and b, scaled so that ab = 1, and
G = 1, the exact normal problem gives the contact set C on an element grid (conformal.solvers.
normal).  With full adhesion the discrete slip vanishes on C (steady rolling in +x, CONTACT's
scheme with the time step dq = dx: the particle at element I was at I+1 one step earlier)::

    s_I = w_I + (u_I - u_{I+1}) / dx = 0,     u = A_tt p_t,     p_t = 0 outside C,

with the rigid slip w = (xi - phi y, eta + phi (x + dx/2)).  The term dx/2 evaluates the spin's
lateral creepage at the middle of the step, which makes the difference quotient exact for the
linear-in-x rigid slip (measured: C33 at a/b = 10 then changes by < 2 % from 16 to 96 elements
across b, against a factor 2 without it; the uniform-creepage coefficients do not depend on it).
The forces give (seed Eq. 13, signs of the csv header)::

    C11 = -FX/(G ab xi),  C22 = -FY/(G ab eta),  C23 = MZ/(G (ab)^1.5 eta),  C33 = -MZ/(G (ab)² phi)

Discretisation: the discrete contact area n_C dxdy fluctuates about pi ab as elements enter the
set, so ab is replaced by the discrete n_C dxdy / pi (removes most of the grid-to-grid scatter);
the remaining error is first order in the element size.  studies/creep_coefficients.py fits
C(n) = C_inf + c/n over n = 32, 48, 64, 96 elements across the short axis (the tables in
conformal/data); :func:`extrapolated_coefficients` is the two-grid Richardson version.
The grid-convergence study (studies/c33_convergence.py, issue 11 item 6) averages each element
size over grid offsets (:func:`averaged_coefficients`; the contact-set scatter is not a smooth
function of n) and extrapolates with a fitted rate and an error estimate (:func:`richardson`).  Measured
against Kalker's table: C11, C22, C23 within 1.1 % at every node except b/a = 0.1 (1.3-1.8 %); on
the finest grid alone within 1.2 %.  The same discrete equations solved by the general tangential
solver with a huge friction coefficient give the same forces to 7 digits (tests/validation/test_exact.py).

The linear system (non-symmetric) is solved by GMRES with a right preconditioner: the upwind
difference is inverted by a cumulative sum along x and A_tt by its Fourier symbol
|k| (I + nu/(1-nu) k k^T/|k|²) G/2 (Cerruti), applied with the zero-padded FFTs of the product.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from conformal.errors import ConvergenceError, InputError
from conformal.files import write_text
from conformal.grid import PlanarGrid
from conformal.influence.halfspace import HalfSpaceInfluence
from conformal.solvers.krylov import gmres as krylov_gmres
from conformal.solvers.normal import solve_normal
from conformal.theories.hertz import hertz_from_semiaxes

DATA_DIR = Path(__file__).resolve().parent.parent / "data"
C33_FILE = DATA_DIR / "kalker_c33.csv"
FULL_FILE = DATA_DIR / "kalker_coefficients_computed.csv"
REFERENCE_FILE = DATA_DIR / "kalker_coefficients.csv"


@dataclass(frozen=True)
class _Elastic:
    """Combined constants (G, nu, K = 0) without Material's nu < 0.5 check: Kalker's table goes to
    the incompressible nu = 0.5, where the half-space formulas stay valid."""

    G: float
    nu: float
    K: float = 0.0

    @property
    def E_star(self) -> float:
        return self.G / (1.0 - self.nu)


# ----------------------------------------------------------------------------- GMRES
def gmres(matvec: Callable[[np.ndarray], np.ndarray], b: np.ndarray, *,
          precond: Callable[[np.ndarray], np.ndarray] | None = None, tol: float = 1e-10,
          restart: int = 60, maxit: int = 600) -> tuple[np.ndarray, int, float]:
    """:func:`conformal.solvers.krylov.gmres` (the package's one Krylov solver) returning the true
    relative residual |b - A x| / |b|: (x, iterations, residual)."""
    return krylov_gmres(matvec, b, precond=precond, tol=tol, restart=restart, maxit=maxit, true_residual=True)


# ----------------------------------------------------------------------------- full-stick rolling
@dataclass(frozen=True, eq=False)
class StickSolution:
    """Full-adhesion steady rolling: tractions (mx, my) and totals (FX, FY, MZ about the origin)."""

    px: np.ndarray
    py: np.ndarray
    FX: float
    FY: float
    MZ: float
    iterations: int
    residual: float


class StickRolling:
    """The linear full-adhesion steady-rolling problem on a contact set of a grid.

    The influence operator is built on a grid one column longer at the leading edge, so that the
    upstream displacement u_{I+1} of the leading contact elements is always defined.
    """

    def __init__(self, grid: PlanarGrid, contact: np.ndarray, material, *, spin_shift: float = 0.5):
        self.grid, self.contact = grid, np.asarray(contact, dtype=bool)
        if self.contact.shape != grid.shape or not self.contact.any():
            raise InputError("StickRolling: the contact set must be a non-empty (mx, my) mask")
        self.spin_shift = spin_shift
        mx, my = grid.shape
        self.op = HalfSpaceInfluence.for_grid(mx + 1, my, grid.dx, grid.dy, material)
        Mx, My = self.op.padded_shape
        kx = 2.0 * np.sin(np.pi * np.fft.fftfreq(Mx))[:, None] / grid.dx
        ky = 2.0 * np.sin(np.pi * np.fft.rfftfreq(My))[None, :] / grid.dy
        k = np.hypot(kx, ky)
        k[0, 0] = k[k > 0].min() if (k > 0).any() else 1.0
        nx, ny = kx / k, ky / k
        c = material.nu / (1.0 - material.nu)
        # inverse Cerruti symbol (up to the constant G/2, which GMRES does not need)
        self._inv = (k * (1 + c * nx * nx), k * c * nx * ny, k * (1 + c * ny * ny))
        self.nc = int(self.contact.sum())

    def _scatter(self, v: np.ndarray) -> np.ndarray:
        P = np.zeros((2, self.grid.mx + 1, self.grid.my))
        P[0, :-1][self.contact] = v[: self.nc]
        P[1, :-1][self.contact] = v[self.nc:]
        return P

    def _gather(self, F: np.ndarray) -> np.ndarray:
        return np.concatenate([F[0, :-1][self.contact], F[1, :-1][self.contact]])

    def matvec(self, v: np.ndarray) -> np.ndarray:
        """(u_I - u_{I+1}) / dx on the contact set for tractions v on it."""
        P = self._scatter(v)
        ux, uy = self.op.apply_tangential(P[0], P[1])
        return np.concatenate([((ux[:-1] - ux[1:]) / self.grid.dx)[self.contact],
                               ((uy[:-1] - uy[1:]) / self.grid.dx)[self.contact]])

    def precond(self, v: np.ndarray) -> np.ndarray:
        """Approximate inverse: upwind difference inverted by a cumulative sum from the leading
        edge, then A_tt^-1 through its Fourier symbol."""
        S = self._scatter(v)
        U = np.cumsum(S[:, ::-1], axis=1)[:, ::-1] * self.grid.dx
        Uh = self.op._forward(U)
        ixx, ixy, iyy = self._inv
        P = self.op._back(np.stack([ixx * Uh[0] + ixy * Uh[1], ixy * Uh[0] + iyy * Uh[1]]))
        return self._gather(P)

    def solve(self, xi: float = 0.0, eta: float = 0.0, phi: float = 0.0, *, tol: float = 1e-9,
              maxit: int = 600) -> StickSolution:
        g = self.grid
        X, Y = g.mesh()
        wx = xi - phi * Y
        wy = eta + phi * (X + self.spin_shift * g.dx)
        rhs = -np.concatenate([wx[self.contact], wy[self.contact]])
        sol, its, res = gmres(self.matvec, rhs, precond=self.precond, tol=tol, maxit=maxit)
        if not res <= 10 * tol:
            raise ConvergenceError(f"full-stick rolling: GMRES residual {res:.3g} after {its} iterations")
        P = self._scatter(sol)[:, :-1]
        dA = g.area
        return StickSolution(px=P[0], py=P[1], FX=float(P[0].sum() * dA), FY=float(P[1].sum() * dA),
                             MZ=float((X * P[1] - Y * P[0]).sum() * dA), iterations=its, residual=res)


# ----------------------------------------------------------------------------- coefficients
@dataclass(frozen=True)
class ExactCoefficients:
    """C11, C22, C23 (from the spin moment under eta), C23_phi (from FY under phi), C33 at one
    (a/b, nu) on one grid (or extrapolated: n_short = 0), with the discrete contact data."""

    a_over_b: float
    nu: float
    C11: float
    C22: float
    C23: float
    C23_phi: float
    C33: float
    n_short: int
    mx: int
    my: int
    n_contact: int
    iterations: int


def grid_for(a_over_b: float, n: int, scale: float = 1.1) -> tuple[float, float, PlanarGrid]:
    """Semi-axes (a, b) with ab = 1 and a grid of about n elements across the short axis of the
    box [-scale a, scale a] x [-scale b, scale b], elements no more elongated than sqrt(a/b)."""
    r = float(a_over_b)
    a, b = math.sqrt(r), 1.0 / math.sqrt(r)
    mx = int(round(n * max(1.0, math.sqrt(r))))
    my = int(round(n * max(1.0, math.sqrt(1.0 / r))))
    return a, b, PlanarGrid.around_ellipse(a, b, scale=scale, mx=mx, my=my)


def exact_coefficients(a_over_b: float, nu: float, n: int = 48, *, spin_shift: float = 0.5,
                       tol: float = 1e-9, offset: tuple[float, float] = (0.0, 0.0),
                       elements: tuple[int, int] | None = None) -> ExactCoefficients:
    """Creep coefficients of the exact theory on one grid (n elements across the short axis).

    ``offset`` = (ox, oy) in [0, 1) shifts the grid against the ellipse by that fraction of an
    element (the grid gets one more element per axis so that it still covers the box); (0, 0) is
    the centred grid of :func:`grid_for`.  Averaging over offsets removes the scatter from
    elements entering the contact set (:func:`averaged_coefficients`).  ``elements`` = (mx, my)
    overrides the element counts on the same box (CONTACT's usual n x n grids, elements a/b times
    longer along x than across); ``n`` is then only recorded.
    """
    if not (a_over_b > 0 and math.isfinite(a_over_b)):
        raise InputError(f"a/b must be > 0, got {a_over_b!r}")
    if not (0.0 <= nu <= 0.5):
        raise InputError(f"nu must lie in [0, 0.5], got {nu!r}")
    ox, oy = (float(v) for v in offset)
    if not (0.0 <= ox < 1.0 and 0.0 <= oy < 1.0):
        raise InputError(f"offset: fractions of an element in [0, 1), got {offset!r}")
    mat = _Elastic(1.0, float(nu))
    a, b, grid = grid_for(a_over_b, n)
    if elements is not None:
        mx, my = (int(v) for v in elements)
        if mx < 2 or my < 2:
            raise InputError(f"elements: at least 2 x 2, got {elements!r}")
        grid = PlanarGrid.around_ellipse(a, b, scale=1.1, mx=mx, my=my)
    if ox or oy:
        grid = PlanarGrid(grid.mx + 1, grid.my + 1, grid.dx, grid.dy, grid.xl - ox * grid.dx,
                          grid.yl - oy * grid.dy)
    hz = hertz_from_semiaxes(a, b, mat, normal_force=1.0)
    X, Y = grid.mesh()
    normal = solve_normal(None, grid, hz.A * X**2 + hz.B * Y**2, normal_force=1.0, material=mat,
                          tol=1e-10, maxit=5000)
    if not normal.converged:
        raise ConvergenceError(f"normal problem at a/b = {a_over_b}, nu = {nu}: residual {normal.residual:.3g}")
    stick = StickRolling(grid, normal.contact, mat, spin_shift=spin_shift)
    sx = stick.solve(xi=1.0, tol=tol)
    se = stick.solve(eta=1.0, tol=tol)
    sp = stick.solve(phi=1.0, tol=tol)
    ab = normal.n_contact * grid.area / math.pi  # discrete contact area / pi (exact: ab = 1)
    G = mat.G
    return ExactCoefficients(a_over_b=float(a_over_b), nu=float(nu), C11=-sx.FX / (G * ab),
                             C22=-se.FY / (G * ab), C23=se.MZ / (G * ab**1.5), C23_phi=-sp.FY / (G * ab**1.5),
                             C33=-sp.MZ / (G * ab**2), n_short=n, mx=grid.mx, my=grid.my,
                             n_contact=normal.n_contact, iterations=sx.iterations + se.iterations + sp.iterations)


def extrapolated_coefficients(a_over_b: float, nu: float, n: int = 48) -> tuple[ExactCoefficients, ...]:
    """Richardson extrapolation (first order) from n and 2n elements across the short axis.
    Returns (extrapolated, coarse, fine)."""
    c1 = exact_coefficients(a_over_b, nu, n)
    c2 = exact_coefficients(a_over_b, nu, 2 * n)
    ext = {k: 2 * getattr(c2, k) - getattr(c1, k) for k in ("C11", "C22", "C23", "C23_phi", "C33")}
    e = ExactCoefficients(a_over_b=float(a_over_b), nu=float(nu), n_short=0, mx=c2.mx, my=c2.my,
                          n_contact=c2.n_contact, iterations=c1.iterations + c2.iterations, **ext)
    return e, c1, c2


# ----------------------------------------------------------------------------- tables
def reference_nodes(path: Path = REFERENCE_FILE) -> list[tuple[str, float, float, dict]]:
    """(branch, g, nu, {C11, C22, C23}) of Kalker's table, in file order."""
    lines = [ln for ln in path.read_text(encoding="utf-8").splitlines()
             if ln.strip() and not ln.lstrip().startswith("#")]
    out = []
    for r in csv.DictReader(lines):
        out.append((r["branch"].strip(), float(r["g"]), float(r["nu"]),
                    {k: float(r[k]) for k in ("C11", "C22", "C23")}))
    return out


def a_over_b(branch: str, g: float) -> float:
    """a/b of a table node: g for branch 'a<=b', 1/g for 'a>b'."""
    return g if branch == "a<=b" else 1.0 / g


#: prefix of the header lines that studies/c33_convergence.py writes into the C33 table
CONVERGENCE_PREFIX = "# C33 convergence"


def _convergence_lines(path: Path) -> list[str]:
    if not Path(path).is_file():
        return []
    return [ln if ln.endswith("\n") else ln + "\n" for ln in Path(path).read_text(encoding="utf-8").splitlines()
            if ln.startswith(CONVERGENCE_PREFIX)]


def set_convergence_header(lines: list[str], path: Path = C33_FILE) -> None:
    """Replace the "# C33 convergence ..." comment lines of the C33 table by ``lines`` (each must
    start with "C33 convergence"); the other header lines and the values stay as they are."""
    if not all(ln.startswith(CONVERGENCE_PREFIX[2:]) for ln in lines):
        raise InputError("set_convergence_header: every line must start with 'C33 convergence'")
    text = Path(path).read_text(encoding="utf-8").splitlines()
    head = [ln for ln in text if ln.startswith("#") and not ln.startswith(CONVERGENCE_PREFIX)]
    body = [ln for ln in text if not ln.startswith("#")]
    new = head + [f"# {ln}" for ln in lines] + body
    write_text(path, "\n".join(new) + "\n")


def write_tables(rows: Iterable[tuple[str, float, float, ExactCoefficients]], header: list[str],
                 c33_path: Path = C33_FILE, full_path: Path = FULL_FILE) -> None:
    """Write the C33 table (branch,g,nu,C33) and the full computed table (branch,g,nu,C11..C33)."""
    rows = list(rows)
    kept = _convergence_lines(c33_path)  # the convergence study's header lines survive a rewrite
    comments = "".join(f"# {h}\n" for h in header) + "".join(kept)
    write_text(c33_path, comments + "branch,g,nu,C33\n"
               + "".join(f"{branch},{g:g},{nu:g},{c.C33:.4g}\n" for branch, g, nu, c in rows))
    write_text(full_path, comments + "branch,g,nu,C11,C22,C23,C33\n"
               + "".join(f"{branch},{g:g},{nu:g},{c.C11:.4g},{c.C22:.4g},{c.C23:.4g},{c.C33:.4g}\n"
                         for branch, g, nu, c in rows))


# ----------------------------------------------------------------------------- grid convergence
#: grid offsets (fractions of an element along x, y) averaged over by :func:`averaged_coefficients`;
#: the first k are used, so every prefix is spread over the element (a rank-1 lattice order)
OFFSETS = ((0.0, 0.0), (0.5, 0.5), (0.5, 0.0), (0.0, 0.5), (0.25, 0.25), (0.75, 0.75), (0.25, 0.75),
           (0.75, 0.25))
NAMES = ("C11", "C22", "C23", "C23_phi", "C33")


def averaged_coefficients(a_over_b: float, nu: float, n: int, n_offsets: int = 4, **kw
                          ) -> tuple[ExactCoefficients, dict[str, float]]:
    """Coefficients on one element size averaged over ``n_offsets`` grid offsets (:data:`OFFSETS`).

    On one grid the discrete contact set gains or loses elements at its edge as the grid moves
    against the ellipse: a scatter of about +-1 % in C33 (a/b = 1, n = 32) that is not a smooth
    function of the element size and spoils any convergence fit.  The mean over offsets keeps the
    smooth discretisation error and divides the scatter by about sqrt(n_offsets).

    Keywords (``spin_shift``, ``elements``, ``tol``) go to :func:`exact_coefficients`.

    Returns
    -------
    (mean, std): the mean as ExactCoefficients (``n_short`` = n, the centred grid's mx, my, the
    mean contact count), and the standard deviation over the offsets of each coefficient.
    """
    if not 1 <= int(n_offsets) <= len(OFFSETS):
        raise InputError(f"n_offsets: 1 ... {len(OFFSETS)}, got {n_offsets!r}")
    runs = [exact_coefficients(a_over_b, nu, n, offset=o, **kw) for o in OFFSETS[: int(n_offsets)]]
    mean = {k: float(np.mean([getattr(c, k) for c in runs])) for k in NAMES}
    std = {k: float(np.std([getattr(c, k) for c in runs])) for k in NAMES}
    c0 = runs[0]
    return ExactCoefficients(a_over_b=float(a_over_b), nu=float(nu), n_short=int(n), mx=c0.mx, my=c0.my,
                             n_contact=int(round(np.mean([c.n_contact for c in runs]))),
                             iterations=sum(c.iterations for c in runs), **mean), std


@dataclass(frozen=True)
class Extrapolation:
    """Richardson extrapolation of a grid sequence with a fitted rate.

    value : the extrapolated value C_inf of the model C(n) = C_inf + c n^-rate.
    rate : the fitted order in the element size (the slope of log|C(n_k+1) - C(n_k)| against
        log n, np.polyfit); rate_std : its standard error (NaN with fewer than 4 differences).
    error : the estimated error of ``value``: the root sum of squares of (1) the change of the
        extrapolation when the rate moves by one standard error (by -20/+25 % with fewer than 4
        differences, where no standard error exists), (2) its change when the coarsest
        grid is left out (rate refitted), (3) the standard error of the weighted value fit
        (from ``noise``; 0 without it).
    c : the coefficient of n^-rate; ns, values : the data.
    """

    value: float
    rate: float
    rate_std: float
    error: float
    c: float
    ns: tuple
    values: tuple


def _fit_given_rate(ns: np.ndarray, v: np.ndarray, rate: float, w: np.ndarray) -> tuple[float, float, float]:
    """Weighted least squares C_inf, c of C = C_inf + c n^-rate (weights w = 1/sigma), and the
    standard error of C_inf (from the weights; 0 when they are all equal, i.e. unknown noise)."""
    A = np.vstack([np.ones(ns.size), ns ** -rate]).T
    sol = np.linalg.lstsq(A * w[:, None], v * w, rcond=None)[0]
    se = 0.0
    if np.ptp(w) > 0 or w[0] != 1.0:
        cov = np.linalg.inv((A * w[:, None]).T @ (A * w[:, None]))
        se = float(np.sqrt(cov[0, 0]))
    return float(sol[0]), float(sol[1]), se


def _fitted_rate(ns: np.ndarray, v: np.ndarray, sig: np.ndarray) -> tuple[float, float]:
    """Order p from log|d_k| = const - p log n_k (d_k = C(n_k+1) - C(n_k); exact for a geometric
    sequence of n), np.polyfit weighted by |d_k|/sigma(d_k) (the inverse standard error of log|d_k|)
    when the noise sigma of the values is known; its standard error (NaN with < 4 differences).
    Clipped to [0.25, 4]."""
    d = np.abs(np.diff(v))
    d = np.where(d > 0, d, np.finfo(float).tiny)
    sd = np.hypot(sig[:-1], sig[1:])
    w = d / sd if np.all(sd > 0) else np.ones_like(d)
    x = np.log(np.sqrt(ns[:-1] * ns[1:]))
    p = 1.0
    for _ in range(8):  # abscissa x_k = -log(n_k^-p - n_k+1^-p)/p: exact also for a non-geometric sequence
        if d.size >= 4:
            coef, cov = np.polyfit(x, np.log(d), 1, w=w, cov="unscaled" if np.all(sd > 0) else True)
            sp = float(np.sqrt(cov[0, 0]))
        else:
            coef, sp = np.polyfit(x, np.log(d), 1, w=w), float("nan")
        p = float(np.clip(-coef[0], 0.25, 4.0))
        x = -np.log(ns[:-1] ** -p - ns[1:] ** -p) / p
    return p, sp


def richardson(ns, values, noise=0.0) -> Extrapolation:
    """Extrapolate C(n) to n -> infinity with a fitted rate (see :class:`Extrapolation`).

    Parameters
    ----------
    ns : element counts across the short axis (at least 3, increasing; best a geometric sequence).
    values : the coefficient on each grid (averaged over offsets, :func:`averaged_coefficients`).
    noise : the standard error of each value (its offset scatter / sqrt(number of offsets)), a
        scalar or one per grid; 0: unknown (unweighted fits).  With it the rate fit weights each
        difference by its significance and the value fit each grid by 1/noise.

    >>> ns = [16, 32, 64, 128]
    >>> e = richardson(ns, [2.0 + 3.0 / n**1.5 for n in ns])
    >>> round(e.value, 9), round(e.rate, 6)
    (2.0, 1.5)
    """
    ns = np.asarray(ns, dtype=float)
    v = np.asarray(values, dtype=float)
    if ns.ndim != 1 or ns.size < 3 or ns.size != v.size or np.any(np.diff(ns) <= 0):
        raise InputError("richardson: at least 3 increasing element counts with one value each")
    sig = np.broadcast_to(np.asarray(noise, dtype=float), ns.shape).copy()
    if np.any(sig < 0) or not np.all(np.isfinite(sig)):
        raise InputError("richardson: noise must be finite and >= 0")
    w = 1.0 / sig if np.all(sig > 0) else np.ones_like(sig)
    p, sp = _fitted_rate(ns, v, sig)
    value, c, se = _fit_given_rate(ns, v, p, w)
    qs = (p - sp, p + sp) if math.isfinite(sp) else (0.8 * p, 1.25 * p)  # nominal +-25 % without a std
    e1 = max(abs(_fit_given_rate(ns, v, float(np.clip(q, 0.25, 4.0)), w)[0] - value) for q in qs)
    e2 = 0.0
    if ns.size >= 4:
        p2, _ = _fitted_rate(ns[1:], v[1:], sig[1:])
        e2 = abs(_fit_given_rate(ns[1:], v[1:], p2, w[1:])[0] - value)
    err = math.sqrt(e1 * e1 + e2 * e2 + se * se)
    return Extrapolation(value=value, rate=p, rate_std=sp, error=err, c=c, ns=tuple(int(n) for n in ns),
                         values=tuple(float(x) for x in v))
