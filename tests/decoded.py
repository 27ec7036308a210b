"""Reading rendered videos back for tests: decoded grey frames, stamps, row profiles."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import av
import numpy as np


def decode(path: str | Path) -> tuple[np.ndarray, np.ndarray, Fraction]:
    """Grey frames (float, shape (F, H, W)), stamps (ms, shape (F,)) and the stream's time
    base of a video file, decoded with PyAV."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        frames = list(container.decode(stream))
        return (
            np.stack([f.to_ndarray(format="gray").astype(float) for f in frames]),
            np.array([f.pts * 1000.0 * float(stream.time_base) for f in frames]),
            stream.time_base,
        )


def row_profile(lit: np.ndarray, dark: np.ndarray, floor: float = 0.0, min_dn: float = 20.0) -> np.ndarray:
    """Relative brightening of each row: median over columns of (lit - floor) / (dark - floor) - 1,
    on pixels more than `min_dn` above `floor` in `dark` (NaN for a row without any)."""
    ratio = np.where(dark > floor + min_dn, (lit - floor) / np.maximum(dark - floor, 1.0), np.nan)
    return np.nanmedian(ratio, axis=1) - 1.0


def half_rise(profile: np.ndarray, plateau: float) -> float:
    """First fractional index where `profile` crosses half of `plateau`."""
    i = int(np.argmax(profile >= plateau / 2))
    return i - 1 + (plateau / 2 - profile[i - 1]) / (profile[i] - profile[i - 1])
