"""Blanco-Lorenzo's angle correction of half-space influence numbers (CONTACT's C3 = 4).

Blanco-Lorenzo et al. (2016, 2021) correct the planar half-space numbers A of a conformal strip
to first order in the change of surface inclination between the loaded element J and the
element I where the displacement is taken, alpha = alpha_J - alpha_I (CONTACT user guide,
"Influence coefficients for conformal contact", option C3 = 4; its four variants).  With the
components (x, s, n), c = cos alpha, s = sin alpha, and the rotation about x

    R(a) = [[1, 0, 0], [0, cos a, -sin a], [0, sin a, cos a]],

the corrected numbers B are

1. Blanco's proposal, decomposing the tractions at J: B[:, s] = A[:, s] c + A[:, n] s,
   B[:, n] = A[:, n] c - A[:, s] s (columns turned, x column kept);
2. the same without the correction of B_xn (B_xn = A_xn);
3. the half-space at J with its displacements turned into I's frame: B = R(alpha) A;
4. the split form B = R(alpha / 2) A R(alpha / 2) (for A_ns = -A_sn, as for the half-space,
   this is the project's own turned-frame numbers, conformal.influence.curved, with alpha = delta).

``alpha`` is the surface inclination per element along s; CONTACT's "fast" method (IF_METH = 0)
replaces it by its least-squares straight line over s (a constant radius of curvature),
:func:`linear_fit`.

>>> import numpy as np
>>> K = np.random.default_rng(0).normal(size=(3, 4, 4, 3, 3))
>>> bool(np.array_equal(blanco_kernel(K, np.zeros(4), 3), K))
True
"""
from __future__ import annotations

import numpy as np

from conformal.errors import InputError

VARIANTS = (1, 2, 3, 4)


def linear_fit(s: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """The least-squares straight line through (s, alpha), evaluated at s (CONTACT's IF_METH = 0)."""
    s, alpha = np.asarray(s, float), np.asarray(alpha, float)
    c1, c0 = np.polyfit(s, alpha, 1)
    return c0 + c1 * s


def blanco_kernel(K: np.ndarray, alpha: np.ndarray, variant: int) -> np.ndarray:
    """The corrected kernel B[kx, I, J, i, j] of a planar (untuned) curved-strip kernel K of shape
    (2 mx - 1, ms, ms, 3, 3) (conformal.influence.curved: load at J, displacement at I, components
    x, s, n), with ``alpha`` (ms,) the surface inclination (rad) of each element along s and
    ``variant`` 1-4 (module docstring)."""
    if variant not in VARIANTS:
        raise InputError(f"Blanco's influence correction: variant must be one of 1-4, got {variant!r}")
    K = np.asarray(K, float)
    alpha = np.asarray(alpha, float)
    a = alpha[None, :] - alpha[:, None]            # [I, J]: alpha_J - alpha_I
    c, s = np.cos(a), np.sin(a)
    A = K.transpose(3, 4, 0, 1, 2)                 # [i, j, kx, I, J]
    B = A.copy()
    X, S, N = 0, 1, 2
    if variant in (1, 2):
        for i in (X, S, N):
            B[i, S] = A[i, S] * c + A[i, N] * s
            B[i, N] = A[i, N] * c - A[i, S] * s
        if variant == 2:
            B[X, N] = A[X, N]
    elif variant == 3:
        for j in (X, S, N):
            B[S, j] = A[S, j] * c - A[N, j] * s
            B[N, j] = A[S, j] * s + A[N, j] * c
    else:
        cb, sb = np.cos(0.5 * a), np.sin(0.5 * a)
        aspn = 0.5 * (A[S, S] + A[N, N])
        asmn = 0.5 * (A[S, S] - A[N, N])
        B[X, S] = A[X, S] * cb + A[X, N] * sb
        B[X, N] = A[X, N] * cb - A[X, S] * sb
        B[S, X] = A[X, S] * cb + A[X, N] * sb
        B[S, S] = asmn + aspn * c + A[S, N] * s
        B[S, N] = A[S, N] * c - aspn * s
        B[N, X] = A[X, S] * sb - A[X, N] * cb
        B[N, S] = aspn * s - A[S, N] * c
        B[N, N] = -asmn + aspn * c + A[S, N] * s
    return np.ascontiguousarray(B.transpose(2, 3, 4, 0, 1))
