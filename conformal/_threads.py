"""Single-threaded BLAS for the solvers, without touching the process environment.

The solvers' inner loops are FFTs and small dense products: a threaded BLAS only adds contention
(measured up to 1000x slower on a busy 2-core machine).  :func:`single_threaded_blas` limits the
BLAS pools with threadpoolctl for the duration of a solve and restores them afterwards; a user who
sets ``OPENBLAS_NUM_THREADS``, ``MKL_NUM_THREADS`` or ``OMP_NUM_THREADS`` keeps that setting.
"""
from __future__ import annotations

import contextlib
import os

_USER_KEYS = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS", "BLIS_NUM_THREADS")


def single_threaded_blas():
    """Context manager: BLAS limited to one thread inside (unless the user chose a number).

    >>> with single_threaded_blas():
    ...     pass
    """
    if any(k in os.environ for k in _USER_KEYS):
        return contextlib.nullcontext()
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:          # pragma: no cover - a dependency; without it BLAS keeps its threads
        return contextlib.nullcontext()
    return threadpool_limits(limits=1, user_api="blas")
