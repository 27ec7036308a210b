"""Exact synthetic observations of flashes by cameras with known clocks (no video)."""

from __future__ import annotations

import numpy as np


def observe(
    tau_ms: np.ndarray, alpha: float, beta_ms: float, row_time_ms: float, frame_times_ms: np.ndarray, height: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where a camera sees each flash: (flash index, frame index, readout row) for the flashes
    whose instant falls on a visible row of some frame."""
    starts = alpha * frame_times_ms + beta_ms
    frame = np.searchsorted(starts, tau_ms, side="right") - 1
    q = (tau_ms - starts[np.clip(frame, 0, None)]) / row_time_ms
    seen = (frame >= 0) & (q <= height - 1)
    return np.flatnonzero(seen), frame[seen], q[seen]
