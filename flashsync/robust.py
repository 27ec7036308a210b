"""Robust statistics shared by the detector, the frame clock and the solves."""

from __future__ import annotations

import numpy as np

#: A Gaussian's standard deviation over its median absolute deviation.
MAD_TO_SIGMA = 1.4826


def mad_sigma(values: np.ndarray, floor: float = 0.0) -> float:
    """Robust standard deviation of values about zero: :data:`MAD_TO_SIGMA` x their median
    absolute value, at least ``floor`` (``floor`` for no values)."""
    values = np.asarray(values)
    return max(MAD_TO_SIGMA * float(np.median(np.abs(values))), floor) if values.size else floor
