"""Input checks shared by the solvers: every failure is an InputError naming the quantity."""
from __future__ import annotations

import math

import numpy as np

from conformal.errors import InputError


def number(name: str, v, *, positive: bool = False, nonneg: bool = False) -> float:
    """A finite float (optionally > 0 or >= 0)."""
    try:
        v = float(v)
    except (TypeError, ValueError):
        raise InputError(f"{name}: must be a number, got {v!r}") from None
    if positive and not v > 0:  # also catches NaN
        raise InputError(f"{name}: must be > 0, got {v!r}")
    if nonneg and v < 0:
        raise InputError(f"{name}: must be >= 0, got {v!r}")
    if not math.isfinite(v):
        raise InputError(f"{name}: must be finite, got {v!r}")
    return v


def field(name: str, a, shape) -> np.ndarray:
    """A finite float array of the given shape (a quantity on the grid)."""
    a = np.asarray(a, dtype=float)
    if a.shape != tuple(shape):
        raise InputError(f"{name}: expected an array of shape {tuple(shape)}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: contains NaN or infinite values")
    return a
