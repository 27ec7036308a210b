"""The frame clock: a camera's steady frame period behind its quantised, jittered stamps.

Container timestamps are often quantised (Matroska stores 1 ms) or jittered by the muxer
(a few ms where frames are stamped on arrival), while the sensor's frame clock is far
steadier. Where the stamps scatter about a steady period as white noise (dropped frames are
whole missing periods), frame times are taken from a robust line through them, so
quantisation and jitter do not become synchronisation error; the scatter is estimated and
what remains of it in the line goes into each frame time's standard deviation.

Real stamps break in three more ways, each found here:

- a *rate change*: from some frame on the stamps advance at another rate (a muxer that
  changes its time base, a camera that changes its frame rate). The stamps are split into
  segments, each with its own steady clock (binary segmentation where the scatter is not
  white); :attr:`FrameClock.rate_changes` lists them and
  :meth:`FrameClock.one_rate_alternatives` gives the frame times as if the sensor had kept
  one rate, for the events to choose between;
- a *gap*: a pause in the recording. Where the sensor's clock ran on through it (the stamps
  after it lie on the same ladder) it is a long run of missing slots; where it did not (a
  new phase), the stamps after it get a clock of their own (:attr:`FrameClock.breaks`);
- *variable rate*: stamps that follow no piecewise-steady clock. They are kept as they are
  (``steady`` is False) and their own white scatter is their standard deviation.

The clock is built from parts that can be switched off one by one (``diagnose`` adds them
to its plainest model as effects): counting the frame slots from the stamp gaps, fitting the
period to all stamps, and following the clock's slow wander.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flashsync.compiled import njit
from flashsync.robust import mad_sigma
from flashsync.timestamps import median_step_ms

#: The clock's slow wander (a rate that changes with temperature) is the running mean of the
#: stamps about the line over at least SMOOTHING_FRAMES frames, more where the jitter needs
#: them to average down to WANDER_NOISE_MS; it is followed only where it stands out of the
#: jitter averaged as much (WANDER_SIGNIFICANCE standard deviations, RMS).
SMOOTHING_FRAMES = 31
WANDER_NOISE_MS = 0.02
WANDER_SIGNIFICANCE = 2.5
#: Stamps scatter about a clock as white noise when their running mean over WHITE_FRAMES
#: frames has an RMS within WHITE_RATIO of what white noise of their RMS gives.
WHITE_FRAMES = 15
WHITE_RATIO = 2.0
#: Stamps whose periodogram starts the slot count; the count then doubles at a time. Where
#: the periodogram's peak does not stand out of what random phases give (PHASE_SIGNIFICANCE
#: times the square root of the stamps' number), the head doubles, up to MAX_HEAD_FRAMES:
#: stamps jittered by 5 ms at 59.94 fps (0.3 of a period) put an alias at 0.73 of the period
#: ahead of the true one over 64 stamps.
HEAD_FRAMES = 64
MAX_HEAD_FRAMES = 512
PHASE_SIGNIFICANCE = 3.5
#: Where no peak stands out, the period is sought within this fraction of the median step
#: (which drops and jitter leave at the period while fewer than half the steps skip a slot).
NEAR_STEP = 0.05
#: Fewest frames in a segment of its own clock, and most segments per recording.
MIN_SEGMENT_FRAMES = 30
MAX_SEGMENTS = 8
#: Two segments' periods differing by less than this fraction (and their standard errors)
#: are one rate: a clock's drift is some ppm, a rate change some per cent.
SAME_RATE = 1e-3
#: Stamps farther than this many robust sigmas from the clock are outliers (a glitch); a
#: clock with more than MAX_OUTLIERS of them is not the stamps' clock.
OUTLIER_SIGMAS = 5.0
MAX_OUTLIERS = 0.02
#: Runs of at least this many missing slots are a gap in the recording, not dropped frames.
GAP_SLOTS = 10
#: Slots that skip at least REGULAR_SKIPS times at intervals varying by less than
#: REGULAR_SPREAD of their mean follow stamps at another rate (:func:`_regular_skips`).
REGULAR_SKIPS = 8
REGULAR_SPREAD = 0.25
#: A stamp's slot lies within this many of its nearest tick, and a skipped slot costs this
#: many squared periods (:func:`_ladder_slots`).
SLOT_BAND = 2
SKIP_COST = 1.0


@dataclass(frozen=True)
class ClockSegment:
    """Frames ``start <= i < stop`` whose stamps follow one clock: slot ``k`` at
    ``offset_ms + k * period_ms`` (plus the wander).

    Attributes
    ----------
    start, stop : int
        Frame range.
    offset_ms, period_ms : float
        Time of slot 0 and the frame period, ms.
    jitter_ms : float
        RMS of the stamps about the clock, ms (quantisation and jitter; outliers left out).
    white : bool
        The stamps scatter about the clock as white noise: no structure is left in them.
    period_std_ms : float
        Standard error of the period, ms (the jitter over the root of the slots' spread).
    """

    start: int
    stop: int
    offset_ms: float
    period_ms: float
    jitter_ms: float
    white: bool
    period_std_ms: float = 0.0


@dataclass(frozen=True)
class FrameClock:
    """A camera's frame clock: the steady clock (or clocks, one per segment) behind its
    stamps, and what was found in them.

    Attributes
    ----------
    stamps_ms : ndarray of shape (n_frames,)
        The stamps, ms.
    slots : int ndarray of shape (n_frames,)
        Frame slot of each decoded frame: counted from the stamp gaps (a gap of two periods
        skips a slot), or the frame index.
    segments : tuple of ClockSegment
        The clocks, in frame order, covering every frame.
    wander_ms : ndarray of shape (n_frames,)
        The clock's slow wander about its segment's line, ms (zeros unless smoothed and
        significant).
    median_step_ms : float
        The median stamp step, ms.
    quantum_ms : float
        Grid the stamps lie on, ms (0 when none is found coarser than 1 µs).
    std_ms : ndarray of shape (n_frames,)
        Standard deviation of :attr:`times_ms` beyond an affine error, ms: where steady, the
        jitter left in the wander (zero without one) and, with several segments, each
        segment's line's uncertainty; where the stamps are kept, their white scatter. An
        error of one line (an offset and a rate) is not in it: the solve's affine map of
        the camera's clock (alpha, beta) absorbs it, since the events' frame times share it.
    """

    stamps_ms: np.ndarray
    slots: np.ndarray
    segments: tuple[ClockSegment, ...]
    wander_ms: np.ndarray
    median_step_ms: float
    quantum_ms: float
    std_ms: np.ndarray

    @property
    def main(self) -> ClockSegment:
        """The segment with the most frames."""
        return max(self.segments, key=lambda segment: segment.stop - segment.start)

    @property
    def offset_ms(self) -> float:
        """Time of slot 0 of the main segment's clock, ms."""
        return self.main.offset_ms

    @property
    def period_ms(self) -> float:
        """Frame period of the main segment's clock, ms."""
        return self.main.period_ms

    @property
    def jitter_ms(self) -> float:
        """RMS of the stamps about the clock over all segments, ms (outliers left out)."""
        lengths = np.array([s.stop - s.start for s in self.segments])
        jitter = np.array([s.jitter_ms for s in self.segments])
        return float(np.sqrt(np.sum(lengths * jitter**2) / max(lengths.sum(), 1)))

    @property
    def rate_std(self) -> float:
        """Relative standard error of the frame rate the clock gives the frame times (the main
        segment's period's; 0 where the stamps are kept): an error of the camera's clock rate
        the solve's drift must take up."""
        return self.main.period_std_ms / self.main.period_ms if self.steady and self.main.period_ms > 0 else 0.0

    @property
    def steady(self) -> bool:
        """Every segment's stamps scatter about its clock as white noise: frame times come
        from the clock(s)."""
        return all(segment.white for segment in self.segments)

    @property
    def ladder_ms(self) -> np.ndarray:
        """The clock's time of each decoded frame, ms (a stamp within a nanosecond of it is
        taken as it is, free of the line's rounding)."""
        ladder = np.empty(len(self.stamps_ms))
        for s in self.segments:
            ladder[s.start : s.stop] = s.offset_ms + self.slots[s.start : s.stop] * s.period_ms
        ladder += self.wander_ms
        return np.where(np.abs(self.stamps_ms - ladder) < 1e-6, self.stamps_ms, ladder)

    @property
    def times_ms(self) -> np.ndarray:
        """Frame times to use, ms: the clock's where the stamps are steady, else the stamps."""
        return self.ladder_ms if self.steady else self.stamps_ms

    @property
    def residual_ms(self) -> np.ndarray:
        """Stamps minus the clock, ms."""
        return self.stamps_ms - self.ladder_ms

    @property
    def stamp_noise_ms(self) -> float:
        """Standard deviation of the stamps about the clock, ms (quantisation + jitter)."""
        return float(np.std(self.residual_ms))

    @property
    def missing(self) -> int:
        """Frame slots inside the segments without a decoded frame."""
        return int(sum(self.slots[s.stop - 1] - self.slots[s.start] + 1 - (s.stop - s.start) for s in self.segments))

    @property
    def gaps(self) -> list[tuple[int, int]]:
        """Pauses in the recording that the clock ran through: ``(frame after the pause,
        missing slots)`` for runs of at least :data:`GAP_SLOTS` missing slots in a segment."""
        skipped = np.diff(self.slots) - 1
        starts = {s.start for s in self.segments}
        return [(int(i) + 1, int(skipped[i])) for i in np.flatnonzero(skipped >= GAP_SLOTS) if i + 1 not in starts]

    @property
    def dropped(self) -> int:
        """Frames dropped: the missing slots outside gaps where the stamps are steady, else 0."""
        return self.missing - sum(count for _, count in self.gaps) if self.steady else 0

    @property
    def rate_changes(self) -> list[tuple[int, float, float]]:
        """``(first frame, period before, period after)`` (ms) where the stamps change rate."""
        return [
            (b.start, a.period_ms, b.period_ms)
            for a, b in zip(self.segments, self.segments[1:])
            if not _same_rate(a.period_ms, b.period_ms, 0.0)
        ]

    @property
    def breaks(self) -> list[int]:
        """First frames of segments at the same rate as the one before but another phase
        (the recording restarted after a pause)."""
        return [b.start for a, b in zip(self.segments, self.segments[1:]) if _same_rate(a.period_ms, b.period_ms, 0.0)]

    def one_rate_alternatives(self) -> list[tuple[str, np.ndarray]]:
        """Where the stamps change rate, the frame times as if the sensor had kept the rate
        of one segment throughout (the stamps of the others then advance at a wrong rate):
        ``(description, times ms of shape (n_frames,))`` per segment of its own rate; empty
        without rate changes. Slots are counted at each segment's own rate."""
        if not self.rate_changes:
            return []
        alternatives, seen = [], []
        for s in self.segments:
            if any(_same_rate(s.period_ms, period, 0.0) for period in seen):
                continue
            seen.append(s.period_ms)
            anchor = s.offset_ms + s.period_ms * self.slots[s.start]
            times = anchor + (self.slots - self.slots[s.start]) * s.period_ms
            description = f"one rate throughout, {s.period_ms:.3f} ms per frame as in frames {s.start}-{s.stop - 1}"
            alternatives.append((description, times))
        return alternatives


def fit_frame_clock(
    stamps_ms: np.ndarray, count_gaps: bool = True, least_squares: bool = True, smoothing: bool = True
) -> FrameClock:
    """Fit a frame clock to container stamps (ms, increasing, shape (n_frames,)).

    Parameters
    ----------
    stamps_ms : array of shape (n_frames,)
    count_gaps : bool
        Each frame's slot counted from the stamps (a gap of two periods skips a slot), and
        the stamps split where their rate changes or their phase breaks; else its frame
        index, one segment.
    least_squares : bool
        Offset and period from a robust line through (slot, stamp) (refitted without stamps
        beyond 3 sigma); else the median step and the median offset.
    smoothing : bool
        Follow a slowly wandering rate: the running mean of the stamps about the line over
        :data:`SMOOTHING_FRAMES`, where it stands out of the jitter.

    Examples
    --------
    >>> clock = fit_frame_clock(np.round(np.arange(100) * 40.0 / 1.001))
    >>> clock.steady, round(clock.period_ms, 4), clock.quantum_ms
    (True, 39.9588, 1.0)
    """
    stamps = np.asarray(stamps_ms, dtype=np.float64)
    step = median_step_ms(stamps)
    quantum = _grid(stamps)
    n = stamps.size
    if n < 3 or step <= 0:
        offset = float(stamps[0]) if n else 0.0
        segment = ClockSegment(0, n, offset, step, 0.0, False)
        return FrameClock(stamps, np.arange(n), (segment,), np.zeros(n), step, quantum, np.zeros(n))
    fitter = _Fitter(stamps, step, quantum, smoothing)
    if count_gaps:
        fits = _refine(fitter, _merge(fitter, _split(fitter)))
    else:
        fits = [fitter.fit(0, n, np.arange(n))]
    slots = _joined_slots(stamps, fits)
    if not least_squares:
        fits = [fitter.fit(f.start, f.stop, f.slots, median_line=True) for f in fits]
    segments = tuple(f.segment(slots) for f in fits)
    wander = np.concatenate([f.wander for f in fits])
    std = np.concatenate([f.std_ms for f in fits])
    if len(fits) > 1:  # one affine map absorbs one line's error, not several
        std = np.hypot(std, np.concatenate([f.line_std_ms for f in fits]))
    return FrameClock(stamps, slots, segments, wander, step, quantum, std)


@dataclass(frozen=True)
class _SegmentFit:
    """One range's clock: slots counted from its first frame, the line (intercept at its
    first slot, slope), the wander, each frame time's std beyond the line's and the line's
    own, the stamps kept (not outliers), the residual about the line, the jitter, whether it
    is white, and the period's standard error."""

    start: int
    stop: int
    slots: np.ndarray
    intercept: float
    slope: float
    wander: np.ndarray
    std_ms: np.ndarray
    line_std_ms: np.ndarray
    keep: np.ndarray
    residual: np.ndarray
    jitter_ms: float
    white: bool
    period_se_ms: float

    def segment(self, slots: np.ndarray) -> ClockSegment:
        """The clock in terms of the recording's ``slots``."""
        offset = self.intercept - self.slope * slots[self.start]
        period_std = self.period_se_ms if np.isfinite(self.period_se_ms) else 0.0
        return ClockSegment(self.start, self.stop, offset, self.slope, self.jitter_ms, self.white, period_std)


class _Fitter:
    """Fits one range's clock: its slots, a robust line through (slot, stamp), the wander
    where significant, the white-noise check and each frame time's standard deviation."""

    def __init__(self, stamps: np.ndarray, step: float, quantum: float, smoothing: bool):
        self.stamps, self.step, self.smoothing = stamps, step, smoothing
        #: Structure smaller than this (ms RMS) is quantisation, not a clock's.
        self.floor = 0.5 * quantum + 1e-3

    def fit(self, lo: int, hi: int, slots: np.ndarray | None = None, median_line: bool = False) -> _SegmentFit:
        """The clock of frames ``lo:hi``; ``slots`` from ``lo`` (counted here if None);
        ``median_line``: the median step and median offset instead of the robust line."""
        y = self.stamps[lo:hi]
        if slots is None:
            slots = _count_slots(y)
        x = slots.astype(np.float64)
        intercept, slope, keep = _robust_line(x, y)
        if median_line:
            slope = self.step
            intercept = float(np.median(y - x * slope))
        residual = y - (intercept + slope * x)
        wander, counts = np.zeros(hi - lo), np.full(hi - lo, np.inf)
        if self.smoothing:
            wander, counts = _significant_wander(residual, keep, self.floor)
        noise = (residual - wander)[keep]
        jitter = float(np.sqrt(np.mean(noise**2))) if noise.size else 0.0
        white = (
            _white(noise, self.floor, _white_scatter(y))
            and keep.mean() >= 1.0 - MAX_OUTLIERS
            and not _regular_skips(slots)
        )
        x_mean = float(np.mean(x[keep])) if keep.any() else 0.0
        sxx = float(np.sum((x[keep] - x_mean) ** 2))
        line = jitter**2 * (1.0 / max(int(keep.sum()), 1) + ((x - x_mean) ** 2 / sxx if sxx > 0 else 0.0))
        std = jitter / np.sqrt(counts) if white else np.full(hi - lo, _white_scatter(y))
        period_se = jitter / np.sqrt(sxx) if sxx > 0 else np.inf
        return _SegmentFit(
            lo, hi, slots, intercept, slope, wander, std, np.sqrt(line), keep, residual, jitter, white, float(period_se)
        )


def _split(fitter: _Fitter) -> list[_SegmentFit]:
    """The segments' fits, in frame order: binary segmentation of the stamps where they do
    not scatter about one clock as white noise, at the split that two lines fit best."""
    pending, done = [(0, len(fitter.stamps))], []
    while pending:
        lo, hi = pending.pop(0)
        fit = fitter.fit(lo, hi)
        if fit.white or hi - lo < 2 * MIN_SEGMENT_FRAMES or len(done) + len(pending) + 2 > MAX_SEGMENTS:
            done.append(fit)
            continue
        middle = lo + _best_split(fit.slots.astype(np.float64), fit.residual)
        pending[:0] = [(lo, middle), (middle, hi)]
    return sorted(done, key=lambda fit: fit.start)


def _best_split(x: np.ndarray, y: np.ndarray) -> int:
    """The index that splits (x, y) into two runs of at least :data:`MIN_SEGMENT_FRAMES`
    whose own lines leave the least squared residual (outliers too: a rate change can make
    half of the stamps outliers of one clock)."""
    x = x - np.mean(x)
    w = np.ones(len(x))
    sums = np.cumsum(np.stack([w, w * x, w * y, w * x * x, w * x * y, w * y * y]), axis=1)
    sums = np.concatenate([np.zeros((6, 1)), sums], axis=1)
    split = np.arange(MIN_SEGMENT_FRAMES, len(x) - MIN_SEGMENT_FRAMES + 1)
    left, right = sums[:, split], sums[:, -1:] - sums[:, split]
    return int(split[np.argmin(_line_sse(left) + _line_sse(right))])


def _line_sse(s: np.ndarray) -> np.ndarray:
    """Squared residual of the least-squares line from sums (n, x, y, xx, xy, yy), per column."""
    n, sx, sy, sxx, sxy, syy = s
    n = np.maximum(n, 1.0)
    vxx = np.maximum(sxx - sx * sx / n, 1e-12)
    vxy = sxy - sx * sy / n
    return np.maximum(syy - sy * sy / n - vxy * vxy / vxx, 0.0)


def _merge(fitter: _Fitter, fits: list[_SegmentFit]) -> list[_SegmentFit]:
    """Neighbouring segments joined where they are one clock: the same rate and the later
    one's stamps on the earlier one's ladder (a gap the sensor ran through), provided the
    joined stamps still scatter as white noise."""
    merged = [fits[0]]
    for b in fits[1:]:
        a = merged[-1]
        if _same_rate(a.slope, b.slope, np.hypot(a.period_se_ms, b.period_se_ms)):
            weights = 1.0 / np.maximum([a.period_se_ms, b.period_se_ms], 1e-12) ** 2
            period = float(np.average([a.slope, b.slope], weights=weights))
            a_end = a.intercept + a.slope * a.slots[-1]
            b_start = b.intercept
            skip = max(int(round((b_start - a_end) / period)), 1)
            slots = np.concatenate([a.slots, a.slots[-1] + skip + b.slots])
            joined = fitter.fit(a.start, b.stop, slots)
            if joined.white:
                merged[-1] = joined
                continue
        merged.append(b)
    return merged


def _refine(fitter: _Fitter, fits: list[_SegmentFit]) -> list[_SegmentFit]:
    """Each boundary between segments moved to where the stamps leave one clock for the
    other: within :data:`MIN_SEGMENT_FRAMES` of where the split put it and of where the two
    clocks' lines cross (:func:`_crossing`; with 3 ms of jitter the split put a 5 % rate
    change 20-120 frames late), the frame that minimises the misfit (:func:`_ladder_misfit`)
    of the stamps before it to the earlier clock and of those from it on to the later one's."""
    fits = list(fits)
    for k in range(1, len(fits)):
        a, b = fits[k - 1], fits[k]
        crossing = _crossing(a, b)
        first, last = (b.start, b.start) if crossing is None else sorted((b.start, crossing))
        lo = max(first - MIN_SEGMENT_FRAMES, a.start + MIN_SEGMENT_FRAMES // 2)
        hi = min(last + MIN_SEGMENT_FRAMES, b.stop - MIN_SEGMENT_FRAMES // 2)
        if hi <= lo:
            continue
        stamps = fitter.stamps[lo - 1 : hi]
        before = np.concatenate([[0.0], np.cumsum(_ladder_misfit(stamps, a.intercept, a.slope))])
        after = np.concatenate([np.cumsum(_ladder_misfit(stamps, b.intercept, b.slope)[::-1])[::-1], [0.0]])
        boundary = lo + int(np.argmin(before + after))
        if boundary != b.start:
            fits[k - 1], fits[k] = fitter.fit(a.start, boundary), fitter.fit(boundary, b.stop)
    return fits


def _crossing(a: _SegmentFit, b: _SegmentFit) -> int | None:
    """The frame where the lines of two neighbouring segments cross (stamp against frame,
    each line's slots counted as frames), if it lies within the two: where stamps that
    change rate without a jump leave one clock for the other."""
    if a.slope == b.slope:
        return None
    # a: t = a.intercept + a.slope * (i - a.start); b: t = b.intercept + b.slope * (i - b.start)
    i = (b.intercept - a.intercept + a.slope * a.start - b.slope * b.start) / (a.slope - b.slope)
    if not a.start < i < b.stop:
        return None
    return int(round(i))


def _ladder_misfit(stamps: np.ndarray, offset: float, period: float) -> np.ndarray:
    """How badly each stamp but the first follows the clock ``offset + k * period``, ms, shape
    (n - 1,): its distance to the nearest tick, plus half a period where it skips a tick
    after the stamp before it. A clock at half the rate of the stamps' ticks every one of
    them too; the skips tell that they follow the slower one (stamps slowing to half their
    rate)."""
    phase = (stamps[1:] - offset) / period
    skips = np.round(np.diff(stamps) / period) >= 2
    return np.abs(phase - np.round(phase)) * period + 0.5 * period * skips


def _joined_slots(stamps: np.ndarray, fits: list[_SegmentFit]) -> np.ndarray:
    """The recording's slots: each segment's own, its first following the last one's by
    its first step over its period or the last one's, whichever counts fewer slots (at
    least one): the step into a rate change may be at either rate, and where the stamps
    slow to half their rate it is two periods of the new one, a slot the sensor never
    skipped."""
    slots, last, previous = [], -1, fits[0]
    for fit in fits:
        first = 0
        if fit.start > 0:
            step = stamps[fit.start] - stamps[fit.start - 1]
            first = last + max(min(int(round(step / fit.slope)), int(round(step / previous.slope))), 1)
        slots.append(first + fit.slots)
        last, previous = int(slots[-1][-1]), fit
    return np.concatenate(slots).astype(np.int64)


def _same_rate(period_a: float, period_b: float, standard_error: float) -> bool:
    """Two periods are one rate: within :data:`SAME_RATE` (relative) or four standard errors."""
    return abs(period_a - period_b) <= max(SAME_RATE * max(period_a, period_b), 4.0 * standard_error)


def _count_slots(stamps: np.ndarray) -> np.ndarray:
    """Slot of each stamp (from 0): the period and phase of the first :data:`HEAD_FRAMES`
    from the peak of their periodogram (robust to drops; under jitter of a quarter period
    and more, more stamps until the peak stands out, :data:`PHASE_SIGNIFICANCE`), then the
    stamps on the ticks of a robust line through twice as many at a time
    (:func:`_ladder_slots`)."""
    n = len(stamps)
    if n < 3:
        return np.arange(n)
    head = min(n, HEAD_FRAMES)
    period, offset, power = _phase_clock(stamps[:head])
    while power < PHASE_SIGNIFICANCE * np.sqrt(head) and head < min(n, MAX_HEAD_FRAMES):
        head = min(2 * head, n, MAX_HEAD_FRAMES)
        period, offset, power = _phase_clock(stamps[:head])
    if power < PHASE_SIGNIFICANCE * np.sqrt(head):  # no clear peak: the one near the median step
        period, offset, power = _phase_clock(stamps[:head], NEAR_STEP)
    size, slots = head, _ladder_slots(stamps[:head], offset, period)
    while True:
        intercept, slope, _ = _robust_line(slots.astype(np.float64), stamps[:size])
        size = min(2 * size, n)
        slots = _ladder_slots(stamps[:size], intercept, slope)
        if size == n:
            intercept, slope, _ = _robust_line(slots.astype(np.float64), stamps)
            return _ladder_slots(stamps, intercept, slope)


def _phase_clock(stamps: np.ndarray, spread: float = 0.3) -> tuple[float, float, float]:
    """Period and offset (ms) of the steady clock whose phase the stamps share best: the peak
    of ``|sum exp(2 pi i t / P)|`` over P within ``spread`` (a fraction) of the median step;
    and that peak (the stamps' number where they all share one phase, about its square
    root for random ones)."""
    step = median_step_ms(stamps)
    span = max(stamps[-1] - stamps[0], step)
    periods = np.arange((1.0 - spread) * step, (1.0 + spread) * step, step * step / (16.0 * span))
    t = stamps - stamps[0]
    power = np.abs(np.exp(2j * np.pi * t[None, :] / periods[:, None]).sum(axis=1))
    peak = int(np.argmax(power))
    period = float(periods[peak])
    phase = np.angle(np.exp(2j * np.pi * t / period).sum())
    return period, float(stamps[0] + phase / (2.0 * np.pi) * period), float(power[peak])


def _ladder_slots(stamps: np.ndarray, offset: float, period: float) -> np.ndarray:
    """Slot of each stamp on the ladder ``offset + k * period``, strictly increasing, from 0:
    each stamp's nearest tick where no two share one; else the assignment with the least
    squared distance of the stamps to their ticks plus :data:`SKIP_COST` periods squared
    for each tick skipped (a dropped frame), each stamp within :data:`SLOT_BAND` slots of
    its nearest tick (:func:`_monotone_slots`). Stamps jittered past half a period land on
    a neighbour's tick; settling such clashes one by one put every slot after a run of them
    one late (4 ms of jitter at 59.94 fps: a slot wrong on 22 of 40 draws of 360 frames,
    none now). Where no assignment fits within the band, the nearest ticks, pushed on past
    their predecessors'."""
    nearest = np.round((stamps - offset) / period).astype(np.int64)
    slots = nearest
    if np.any(np.diff(nearest) <= 0):  # stamps that share a tick
        slots = _monotone_slots(stamps, nearest, offset, period, SKIP_COST * period**2)
        if slots[0] < 0:  # no path: the nearest ticks, pushed on
            index = np.arange(len(nearest))
            slots = np.maximum.accumulate(nearest - index) + index
    return slots - slots[0]


@njit
def _monotone_slots(stamps, nearest, offset, period, skip_cost):  # pragma: no cover - compiled
    """The slots (int64, (n,)) among ``nearest[i] - SLOT_BAND .. nearest[i] + SLOT_BAND`` that
    rise strictly and minimise the squared distances to their ticks plus ``skip_cost`` per
    slot skipped (dynamic programming, then the path back); all -1 where none rise."""
    n, width = stamps.size, 2 * SLOT_BAND + 1
    cost = np.empty((n, width))
    back = np.zeros((n, width), dtype=np.int64)
    for j in range(width):
        slot = nearest[0] + j - SLOT_BAND
        cost[0, j] = (stamps[0] - offset - slot * period) ** 2
    for i in range(1, n):
        for j in range(width):
            slot = nearest[i] + j - SLOT_BAND
            best, arg = np.inf, -1
            for a in range(width):
                before = nearest[i - 1] + a - SLOT_BAND
                if before < slot and cost[i - 1, a] < np.inf:
                    total = cost[i - 1, a] + skip_cost * (slot - before - 1)
                    if total < best:
                        best, arg = total, a
            cost[i, j] = best + (stamps[i] - offset - slot * period) ** 2
            back[i, j] = arg
    slots = np.full(n, -1, dtype=np.int64)
    j = int(np.argmin(cost[n - 1]))
    if not cost[n - 1, j] < np.inf:
        return slots
    for i in range(n - 1, -1, -1):
        slots[i] = nearest[i] + j - SLOT_BAND
        j = back[i, j]
    return slots


def _significant_wander(residual: np.ndarray, keep: np.ndarray, floor: float) -> tuple[np.ndarray, np.ndarray]:
    """The clock's slow wander: the running mean of the kept residuals (ms) and how many
    stamps each value averages, over a window long enough to average the jitter down to
    :data:`WANDER_NOISE_MS` (at least :data:`SMOOTHING_FRAMES`), where it stands out of
    the jitter and of ``floor`` (ms); zeros and infinity (nothing averaged in) elsewhere."""
    values = np.where(keep, residual, 0.0)
    wander, counts = np.zeros(len(residual)), np.ones(len(residual))
    for _ in range(2):
        jitter = float(np.sqrt(np.mean((residual - wander)[keep] ** 2))) if keep.any() else 0.0
        window = int(np.clip((jitter / WANDER_NOISE_MS) ** 2, SMOOTHING_FRAMES, len(residual)))
        counts = np.maximum(_running_sum(keep.astype(np.float64), window), 1.0)
        wander = _running_sum(values, window) / counts
    jitter = float(np.sqrt(np.mean((residual - wander)[keep] ** 2))) if keep.any() else 0.0
    size = float(np.sqrt(np.mean(wander**2)))
    if size <= floor or np.sqrt(np.mean(wander**2 * counts)) <= WANDER_SIGNIFICANCE * jitter:
        return np.zeros(len(residual)), np.full(len(residual), np.inf)
    return wander, counts


def _running_sum(values: np.ndarray, window: int) -> np.ndarray:
    """Centred running sum over ``window`` samples (fewer at the ends)."""
    half = window // 2
    total = np.concatenate([[0.0], np.cumsum(values)])
    index = np.arange(len(values))
    low, high = np.maximum(index - half, 0), np.minimum(index + half + 1, len(values))
    return total[high] - total[low]


def _white(noise: np.ndarray, floor: float, scatter: float) -> bool:
    """Whether ``noise`` (ms) looks white: no slow structure (its running mean over
    :data:`WHITE_FRAMES` has an RMS within :data:`WHITE_RATIO` of its RMS over
    sqrt(WHITE_FRAMES)) and no fast one (its steps vary at most WHITE_RATIO x 3/4 as
    much as white noise's, twice its variance: stamps that alternate between two ladders
    vary twice as much) and no sawtooth (its RMS within WHITE_RATIO of ``scatter``, the
    white scatter of the stamps' second differences, :func:`_white_scatter`, ms: stamps 5 %
    faster than a 59.94 fps clock with 1.2 ms of jitter stay within half a period of it for
    20 frames at a time, a sawtooth of 3.8 ms RMS whose running mean and steps look white;
    stamps 1.5x as fast as a 29.97 fps clock with 3 ms of jitter alternate between its ticks
    and their middles, 7.4 ms RMS, where the stamps scatter by 3); always below ``floor``
    (its RMS, ms) or for too few values."""
    if len(noise) < 3 * WHITE_FRAMES:
        return True
    variance = float(np.mean(noise**2))
    if variance <= floor**2:
        return True
    means = np.convolve(noise, np.full(WHITE_FRAMES, 1.0 / WHITE_FRAMES), mode="valid")
    slow = float(np.mean(means**2)) * WHITE_FRAMES <= WHITE_RATIO**2 * variance
    fast = float(np.mean(np.diff(noise) ** 2)) <= 0.75 * WHITE_RATIO * 2.0 * variance
    sawtooth = variance > WHITE_RATIO**2 * scatter**2
    return slow and fast and not sawtooth


def _regular_skips(slots: np.ndarray) -> bool:
    """Whether the slots skip at regular intervals (at least :data:`REGULAR_SKIPS` skips whose
    intervals vary by less than :data:`REGULAR_SPREAD` of their mean): stamps at another rate
    than the clock they are counted on, which slip one slot every so many frames, not
    dropped frames, which come at random (their intervals vary about as much as their mean).
    Stamps 5 % faster than a 59.94 fps clock with 3 ms of jitter skip every 18-23 frames
    (0.08 of their mean); a camera that drops 5 % of its frames at random, 0.8; eight drops
    at random pass for regular in 0.13 % of draws."""
    skips = np.flatnonzero(np.diff(slots) > 1)
    if len(skips) < REGULAR_SKIPS:
        return False
    intervals = np.diff(skips)
    return float(np.std(intervals)) < REGULAR_SPREAD * float(np.mean(intervals))


def _white_scatter(stamps: np.ndarray) -> float:
    """The white part of stamps' scatter, ms: from their second differences (6 variances of
    white noise; a smooth rate leaves none), robustly."""
    if len(stamps) < 4:
        return 0.0
    return mad_sigma(np.diff(stamps, 2)) / np.sqrt(6.0)


def _robust_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float, np.ndarray]:
    """Intercept, slope of a line through (x, y) refitted without points beyond 3 sigma, and
    the points kept (those within :data:`OUTLIER_SIGMAS` sigma of it)."""
    keep = np.ones(len(x), dtype=bool)
    for _ in range(3):
        slope, intercept = _line(x[keep], y[keep])
        residual = y - (intercept + slope * x)
        sigma = mad_sigma(residual[keep], 1e-6)
        keep = np.abs(residual) <= 3 * sigma + 0.5
        if keep.sum() < 2:
            keep = np.ones(len(x), dtype=bool)
    keep = np.abs(residual) <= OUTLIER_SIGMAS * sigma + 0.5
    return float(intercept), float(slope), keep


def _line(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Slope and intercept of the least-squares line through (x, y) (x not all equal), from
    the centred sums: what ``np.polyfit(x, y, 1)`` gives, without its SVD."""
    x_mean, y_mean = np.mean(x), np.mean(y)
    dx = x - x_mean
    slope = float(np.sum(dx * (y - y_mean)) / np.sum(dx * dx))
    return slope, float(y_mean - slope * x_mean)


def _grid(stamps: np.ndarray) -> float:
    """The coarsest of 1, 0.5, 0.1 ms and 1/90 ms (RTP) that every stamp lies on, or 0."""
    for quantum in (1.0, 0.5, 0.1, 1.0 / 90.0):
        if np.all(np.abs(stamps / quantum - np.round(stamps / quantum)) < 1e-3):
            return quantum
    return 0.0
