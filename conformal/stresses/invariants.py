"""Invariants and equivalent stresses of stress tensors sigma[..., 3, 3] (N/mm², tension positive).

>>> s = np.diag([-100.0, -50.0, -20.0])
>>> float(von_mises(s)), float(principal_shear(s)), float(max_principal(s))
(70.0, 40.0, -20.0)
"""
from __future__ import annotations

import numpy as np


def principal(sigma: np.ndarray) -> np.ndarray:
    """Principal stresses s1 >= s2 >= s3, shape (..., 3)."""
    return np.linalg.eigvalsh(np.asarray(sigma, float))[..., ::-1]


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """sqrt(3 J2) = sqrt(3/2 s:s) with s the deviator."""
    s = np.asarray(sigma, float)
    tr = np.trace(s, axis1=-2, axis2=-1) / 3.0
    dev = s - tr[..., None, None] * np.eye(3)
    return np.sqrt(1.5 * np.einsum("...ij,...ij->...", dev, dev))


def principal_shear(sigma: np.ndarray) -> np.ndarray:
    """Tresca's maximum shear (s1 - s3) / 2."""
    p = principal(sigma)
    return 0.5 * (p[..., 0] - p[..., 2])


def max_principal(sigma: np.ndarray) -> np.ndarray:
    """The largest principal stress s1 (tension positive)."""
    return principal(sigma)[..., 0]


def hydrostatic(sigma: np.ndarray) -> np.ndarray:
    """sigma_h = tr(sigma) / 3 (tension positive)."""
    return np.trace(np.asarray(sigma, float), axis1=-2, axis2=-1) / 3.0


def orthogonal_shear(sigma: np.ndarray, rolling=(1.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0)) -> np.ndarray:
    """The orthogonal shear stress tau = rolling . sigma . normal (sigma_xz of the rolling frame:
    x the rolling direction, z the depth axis); ``rolling`` and ``normal`` may be arrays (..., 3)."""
    r = np.asarray(rolling, float)
    n = np.asarray(normal, float)
    return np.einsum("...i,...ij,...j->...", np.broadcast_to(r, np.shape(sigma)[:-1]), sigma,
                     np.broadcast_to(n, np.shape(sigma)[:-1]))
