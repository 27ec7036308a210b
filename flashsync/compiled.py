"""Compiled kernels: numba's ``njit``, cached on disk where numba can write a cache, else
compiled in memory.

numba caches a compiled kernel beside its source (``__pycache__``) or in the user's cache
folder (``$NUMBA_CACHE_DIR``, ``~/.cache``). Where neither can be written (a package
installed read-only and run by a service account without a writable home), asking for the
cache fails at import; the kernels are then compiled in memory on first use in each process
(a few seconds once) instead.
"""

from __future__ import annotations

from collections.abc import Callable

import numba


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
