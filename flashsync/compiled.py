"""Compiled kernels: numba's ``njit``, cached on disk where numba can write a cache, else
compiled in memory.

numba caches a compiled kernel beside its source (``__pycache__``) or in the user's cache
folder (``$NUMBA_CACHE_DIR``, ``~/.cache``). Where neither can be written (a package
installed read-only and run by a service account without a writable home), asking for the
cache fails at import; the kernels are then compiled in memory on first use in each process
(a few seconds once) instead.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numba
import numpy as np


def njit(function: Callable | None = None, **options) -> Callable:
    """``numba.njit(cache=True, nogil=True, error_model="numpy", **options)(function)``, or
    without the on-disk cache where numba has no writable place for it; ``@njit`` or
    ``@njit(inline="always")``. numpy's error model: a division by zero gives inf or NaN
    and never raises, so a degenerate band cannot stop a run."""
    if function is None:
        return lambda function: njit(function, **options)
    try:
        return numba.njit(cache=True, nogil=True, error_model="numpy", **options)(function)
    except RuntimeError:  # "cannot cache function ...: no locator available for file ..."
        return numba.njit(nogil=True, error_model="numpy", **options)(function)


@njit
def cholesky_solve(a, b):  # pragma: no cover - compiled
    """``(a^-1 b, ok)`` for a small symmetric positive definite ``a`` (n, n) and ``b`` (n,),
    by Cholesky; ``(zeros, False)`` where ``a`` is not positive definite, ``ok`` False where
    the result is not finite."""
    n = b.size
    low = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            total = a[i, j]
            for m in range(j):
                total -= low[i, m] * low[j, m]
            if i != j:
                low[i, j] = total / low[j, j]
            elif total > 1e-300 and np.isfinite(total):
                low[i, i] = math.sqrt(total)
            else:
                return np.zeros(n), False
    out = b.copy()
    for i in range(n):
        for m in range(i):
            out[i] -= low[i, m] * out[m]
        out[i] /= low[i, i]
    for i in range(n - 1, -1, -1):
        for m in range(i + 1, n):
            out[i] -= low[m, i] * out[m]
        out[i] /= low[i, i]
    ok = True
    for i in range(n):
        if not np.isfinite(out[i]):
            ok = False
    return out, ok
