"""Single-threaded BLAS for the solvers, without touching the process environment.

The solvers' inner loops are FFTs and small dense products: a threaded BLAS only adds contention
(measured up to 1000x slower on a busy 2-core machine).  :func:`single_threaded_blas` limits the
BLAS pools with threadpoolctl for the duration of a solve and restores them afterwards; a user who
sets ``OPENBLAS_NUM_THREADS``, ``MKL_NUM_THREADS`` or ``OMP_NUM_THREADS`` keeps that setting.

Inside a limit already set (a command that solves many cases wraps them all once), the inner calls
do nothing: each limit costs threadpoolctl a scan of the loaded libraries, about 3 ms (1.3 % of
``conformal inp`` on CONTACT's 21-case Manchester deck when every case set its own).
"""
from __future__ import annotations

import contextlib
import contextvars
import os

_USER_KEYS = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS", "BLIS_NUM_THREADS")
#: True inside a :func:`single_threaded_blas` block of this thread (context)
_LIMITED = contextvars.ContextVar("conformal_single_threaded_blas", default=False)


@contextlib.contextmanager
def _limit_blas(threadpool_limits):
    token = _LIMITED.set(True)
    try:
        with threadpool_limits(limits=1, user_api="blas"):
            yield
    finally:
        _LIMITED.reset(token)


def single_threaded_blas():
    """Context manager: BLAS limited to one thread inside (unless the user chose a number).

    >>> with single_threaded_blas():
    ...     with single_threaded_blas():     # nested: nothing more to do
    ...         pass
    """
    if _LIMITED.get() or any(k in os.environ for k in _USER_KEYS):
        return contextlib.nullcontext()
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:          # pragma: no cover - a dependency; without it BLAS keeps its threads
        return contextlib.nullcontext()
    return _limit_blas(threadpool_limits)
