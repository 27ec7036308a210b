"""The frame clock: a camera's steady frame period behind its quantised, jittered stamps.

Container timestamps are often quantised (Matroska stores 1 ms) or jittered by the muxer,
while the sensor's frame clock is far steadier. Where the stamps are consistent with a
steady period (dropped frames are whole missing periods), frame times are taken from a
robust line through them, so quantisation and jitter do not become synchronisation error.
Where they are not (true variable frame rate), the stamps are kept as they are.

The clock is built from parts that can be switched off one by one (``diagnose`` adds them
to its plainest model as effects): counting the frame slots from the stamp gaps, fitting the
period to all stamps, and following the clock's slow wander.
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
    """A camera's frame clock: frame slot ``k`` starts at ``offset_ms + k * period_ms`` plus
    the clock's slow wander; and what was found in the stamps it was fitted to.

    Attributes
    ----------
    stamps_ms : ndarray of shape (n_frames,)
        The stamps, ms.
    slots : int ndarray of shape (n_frames,)
        Frame slot of each decoded frame: counted from the stamp gaps (a gap of two periods
        skips a slot), or the frame index.
    offset_ms, period_ms : float
        Time of slot 0 and the frame period, ms.
    wander_ms : ndarray of shape (n_frames,)
        The clock's slow wander about ``offset_ms + slots * period_ms``, ms (zeros unless
        smoothed).
    median_step_ms : float
        The median stamp step, ms.
    quantum_ms : float
        Grid the stamps lie on, ms (0 when none is found coarser than 1 µs).
    steady : bool
        Every stamp lies within :data:`MAX_STEADY_RESIDUAL_MS` of the clock: the stamps fit
        a steady period within quantisation and jitter.
    """

    stamps_ms: np.ndarray
    slots: np.ndarray
    offset_ms: float
    period_ms: float
    wander_ms: np.ndarray
    median_step_ms: float
    quantum_ms: float
    steady: bool

    @property
    def ladder_ms(self) -> np.ndarray:
        """The clock's time of each decoded frame, ms."""
        return self.offset_ms + self.slots * self.period_ms + self.wander_ms

    @property
    def times_ms(self) -> np.ndarray:
        """Frame times to use, ms: the clock's where the stamps are steady, else the stamps."""
        return self.ladder_ms if self.steady else self.stamps_ms

    @property
    def residual_ms(self) -> np.ndarray:
        """Stamps minus the clock, ms."""
        return self.stamps_ms - (self.offset_ms + self.slots * self.period_ms) - self.wander_ms

    @property
    def stamp_noise_ms(self) -> float:
        """Standard deviation of the stamps about the clock, ms (quantisation + jitter)."""
        return float(np.std(self.residual_ms))

    @property
    def missing(self) -> int:
        """Frame slots between the first and the last frame without a decoded frame."""
        return int(self.slots[-1] - self.slots[0] + 1 - len(self.slots))

    @property
    def dropped(self) -> int:
        """Frames dropped: the missing slots where the stamps are steady, else 0."""
        return self.missing if self.steady else 0


def fit_frame_clock(
    stamps_ms: np.ndarray, count_gaps: bool = True, least_squares: bool = True, smoothing: bool = True
) -> FrameClock:
    """Fit a frame clock to container stamps (ms, increasing, shape (n_frames,)).

    Parameters
    ----------
    stamps_ms : array of shape (n_frames,)
    count_gaps : bool
        Each frame's slot counted from the stamp gaps (``round(gap / median step)``, so a
        dropped frame skips a slot); else its frame index.
    least_squares : bool
        Offset and period from a robust line through (slot, stamp) (refitted without stamps
        beyond 3 sigma); else the median step and the median offset.
    smoothing : bool
        Follow a slowly wandering rate: the running mean of the stamps about the line over
        :data:`SMOOTHING_FRAMES`.

    Examples
    --------
    >>> clock = fit_frame_clock(np.round(np.arange(100) * 40.0 / 1.001))
    >>> clock.steady, round(clock.period_ms, 4), clock.quantum_ms
    (True, 39.9588, 1.0)
    """
    stamps = np.asarray(stamps_ms, dtype=np.float64)
    step = median_step_ms(stamps)
    quantum = _grid(stamps)
    if stamps.size < 3 or step <= 0:
        offset = float(stamps[0]) if stamps.size else 0.0
        return FrameClock(stamps, np.arange(stamps.size), offset, step, np.zeros(stamps.size), step, quantum, False)
    if count_gaps:
        slots = np.concatenate([[0], np.cumsum(np.maximum(np.round(np.diff(stamps) / step), 1).astype(np.int64))])
    else:
        slots = np.arange(len(stamps))
    if least_squares:
        offset, period = _robust_line(slots, stamps)
    else:
        offset, period = float(np.median(stamps - slots * step)), step
    line = offset + slots * period
    wander = _running_mean(stamps - line, SMOOTHING_FRAMES) if smoothing else np.zeros(len(stamps))
    steady = bool(np.max(np.abs(stamps - line - wander)) <= MAX_STEADY_RESIDUAL_MS)
    return FrameClock(stamps, slots, offset, period, wander, step, quantum, steady)


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
