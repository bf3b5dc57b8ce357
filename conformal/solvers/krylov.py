"""One Krylov solver for the package: right-preconditioned restarted GMRES (Saad and Schultz 1986,
modified Gram-Schmidt, Givens rotations).

Written with elementwise numpy sums instead of BLAS calls: scipy's gmres spends its time in
threaded BLAS, measured 5-100x slower on a busy 2-core machine.  Used by the semismooth Newton
steps of the tangential solver (:mod:`conformal.solvers.tangential`) and by the full-stick rolling
problem behind C33 (:mod:`conformal.theories.c33`).
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np


def dot(a: np.ndarray, b: np.ndarray) -> float:
    """a . b of 1-D vectors (BLAS ddot: 4x faster than sum(a * b); the callers run under
    :func:`conformal._threads.single_threaded_blas` or a user's thread setting)."""
    return float(np.dot(a, b))


def gmres(matvec: Callable, b: np.ndarray, *, precond: Callable | None = None, tol: float = 1e-10,
          restart: int = 60, maxit: int = 600, extra: bool = False, true_residual: bool = False):
    """Solve A x = b by right-preconditioned restarted GMRES.

    Parameters
    ----------
    matvec : callable
        ``matvec(z)`` returns A z, or with ``extra`` a pair (A z, e(z)) where e is any by-product
        linear in z (summed with the same coefficients as x, e.g. another operator's product).
    b : ndarray
        Right-hand side (1-D).
    precond : callable, optional
        The right preconditioner z = P v (identity when omitted).
    tol : float
        Relative residual |b - A x| / |b| to reach.
    restart, maxit : int
        Krylov vectors per cycle and in total.
    extra : bool
        ``matvec`` returns (A z, e(z)); the result then includes e(x).
    true_residual : bool
        Check the true residual after the last cycle too (one more product) and return it.

    Returns
    -------
    (x, iterations, relres), or (x, e(x), iterations, relres) with ``extra``.

    Examples
    --------
    >>> A = np.array([[4.0, 1.0], [2.0, 3.0]])
    >>> x, its, res = gmres(lambda z: A @ z, np.array([1.0, 2.0]), tol=1e-12)
    >>> np.allclose(A @ x, [1.0, 2.0]), its
    (True, 2)
    """
    M = precond or (lambda v: v)
    op = matvec if extra else (lambda z: (matvec(z), None))
    beta0 = math.sqrt(dot(b, b))
    x = np.zeros_like(b)
    ext = None
    if beta0 == 0.0:
        return (x, ext, 0, 0.0) if extra else (x, 0, 0.0)
    r = b          # (never written to: the restarts form a new residual)
    total = 0
    relres = 1.0
    beta = beta0   # the first cycle's residual is b
    while total < maxit:
        m_max = min(restart, maxit - total)
        # the Hessenberg column, the rotations and the residual vector as Python floats (the same
        # IEEE operations as on numpy scalars, without their overhead); the columns are kept as
        # lists and written into H for the back substitution
        V = [r / beta]
        Z, E, cols = [], [], []
        cs, sn = [0.0] * m_max, [0.0] * m_max
        g = [0.0] * (m_max + 1)
        g[0] = beta
        m = 0
        for k in range(m_max):
            z = M(V[k])
            w, e = op(z)
            Z.append(z)
            E.append(e)
            h = [0.0] * (k + 2)
            for i in range(k + 1):  # modified Gram-Schmidt
                h[i] = hi = dot(w, V[i])
                w = w - hi * V[i]
            h[k + 1] = hk1 = math.sqrt(dot(w, w))
            V.append(w / hk1 if hk1 > 0 else w)
            for i in range(k):  # previous Givens rotations
                t = cs[i] * h[i] + sn[i] * h[i + 1]
                h[i + 1] = -sn[i] * h[i] + cs[i] * h[i + 1]
                h[i] = t
            rho = math.hypot(h[k], h[k + 1])
            cs[k], sn[k] = (h[k] / rho, h[k + 1] / rho) if rho > 0 else (1.0, 0.0)
            h[k], h[k + 1] = rho, 0.0
            cols.append(h)
            g[k + 1] = -sn[k] * g[k]
            g[k] = cs[k] * g[k]
            m = k + 1
            relres = abs(g[k + 1]) / beta0
            if relres <= tol or h[k] == 0.0:
                break
        H = np.zeros((m + 1, m))
        for k, h in enumerate(cols):
            H[:k + 2, k] = h
        y = np.zeros(m)  # back substitution (no LAPACK: see dot)
        for i in range(m - 1, -1, -1):
            y[i] = (g[i] - dot(H[i, i + 1:m], y[i + 1:])) / H[i, i] if H[i, i] != 0 else 0.0
        x = x + sum(yi * zi for yi, zi in zip(y, Z))
        if extra:
            de = sum(yi * ei for yi, ei in zip(y, E))
            ext = de if ext is None else ext + de
        total += m
        if (relres <= tol and not true_residual) or total >= maxit and not true_residual:
            break
        Mx, _ = op(x)  # true residual for the restart (one product)
        r = b - Mx
        beta = math.sqrt(dot(r, r))
        relres = beta / beta0
        if relres <= tol or total >= maxit:
            break
    return (x, ext, total, relres) if extra else (x, total, relres)
