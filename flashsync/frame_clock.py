"""The frame clock: a camera's steady frame period behind its quantised, jittered stamps.

Container timestamps are often quantised (Matroska stores 1 ms) or jittered by the muxer,
while the sensor's frame clock is far steadier. Where the stamps are consistent with a
steady period (dropped frames are whole missing periods), frame times are taken from a
robust line through them, so quantisation and jitter do not become synchronisation error.
Where they are not (true variable frame rate), the stamps are kept as they are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flashsync.robust import mad_sigma
from flashsync.timestamps import median_step_ms

#: Largest stamp residual (ms) still explained by quantisation or muxer jitter.
MAX_STEADY_RESIDUAL_MS = 2.0
#: Frames over which the clock's slow wander (a rate that changes with temperature) is
#: averaged; quantisation and jitter average out over as many stamps.
SMOOTHING_FRAMES = 301


@dataclass(frozen=True)
class FrameClock:
    """A camera's frame times and what was found in its stamps.

    Attributes
    ----------
    times_ms : ndarray of shape (n_frames,)
        Frame times to use, ms: the steady clock where ``steady``, else the stamps.
    period_ms : float
        Frame period, ms (median stamp step where not steady).
    steady : bool
        The stamps fit a steady period within quantisation and jitter.
    stamp_noise_ms : float
        Standard deviation of stamps about the steady clock, ms (quantisation + jitter).
    quantum_ms : float
        Grid the stamps lie on, ms (0 when none is found coarser than 1 µs).
    dropped : int
        Frame slots without a frame.
    """

    times_ms: np.ndarray
    period_ms: float
    steady: bool
    stamp_noise_ms: float
    quantum_ms: float
    dropped: int


def fit_frame_clock(stamps_ms: np.ndarray) -> FrameClock:
    """Fit a steady frame clock to container stamps (ms, increasing, shape (n_frames,)).

    Each frame gets an integer slot ``round((stamp - t0) / period)``, refined over a
    doubling head of the recording so that a period error cannot add up; a robust line
    ``stamp ≈ t0 + slot * period`` plus the running mean of the stamps about it (over
    :data:`SMOOTHING_FRAMES`, for a slowly wandering rate) gives the steady times. They are
    used only if every stamp lies within :data:`MAX_STEADY_RESIDUAL_MS` of them and slots are
    unique.

    Examples
    --------
    >>> clock = fit_frame_clock(np.round(np.arange(100) * 40.0 / 1.001))
    >>> clock.steady, round(clock.period_ms, 4), clock.quantum_ms
    (True, 39.96, 1.0)
    """
    stamps = np.asarray(stamps_ms, dtype=np.float64)
    period = median_step_ms(stamps)
    quantum = _grid(stamps)
    if stamps.size < 3 or period <= 0:
        return FrameClock(stamps, period, False, 0.0, quantum, 0)
    t0, count = stamps[0], 16
    while True:
        head = stamps[:count]
        t0, period = _robust_line(np.round((head - t0) / period), head)
        if count >= len(stamps):
            break
        count *= 2
    slots = np.round((stamps - t0) / period)
    line = t0 + slots * period
    wander = _running_mean(stamps - line, SMOOTHING_FRAMES)
    residual = stamps - line - wander
    steady = bool(np.all(np.diff(slots) > 0) and np.max(np.abs(residual)) <= MAX_STEADY_RESIDUAL_MS)
    times = line + wander if steady else stamps
    dropped = int(slots[-1] - slots[0] + 1 - len(slots)) if steady else 0
    return FrameClock(times, float(period), steady, float(np.std(residual)), quantum, dropped)


def _running_mean(values: np.ndarray, window: int) -> np.ndarray:
    """Centred running mean over ``window`` samples (fewer at the ends)."""
    half = window // 2
    total = np.concatenate([[0.0], np.cumsum(values)])
    index = np.arange(len(values))
    low, high = np.maximum(index - half, 0), np.minimum(index + half + 1, len(values))
    return (total[high] - total[low]) / (high - low)


def _robust_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Intercept and slope of a line through (x, y), refitted without points beyond 3 sigma."""
    keep = np.ones(len(x), dtype=bool)
    for _ in range(3):
        slope, intercept = np.polyfit(x[keep], y[keep], 1)
        residual = y - (intercept + slope * x)
        sigma = mad_sigma(residual[keep], 1e-6)
        keep = np.abs(residual) <= 3 * sigma + 0.5
    return float(intercept), float(slope)


def _grid(stamps: np.ndarray) -> float:
    """The coarsest of 1, 0.5, 0.1 ms and 1/90 ms (RTP) that every stamp lies on, or 0."""
    for quantum in (1.0, 0.5, 0.1, 1.0 / 90.0):
        if np.all(np.abs(stamps / quantum - np.round(stamps / quantum)) < 1e-3):
            return quantum
    return 0.0
