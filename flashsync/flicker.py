"""Mains flicker: estimated from the row profiles, removed before change detection, kept.

Lamps on mains power flicker at twice the mains frequency (100 or 120 Hz). A rolling-shutter
row integrates the light over its own exposure window, so each frame shows the flicker as a
periodic pattern down its rows: one period is ``1000 / hz`` ms of readout, i.e.
``period_rows = (1000 / hz) / T_row`` readout rows, the same in every frame. From frame to
frame the pattern moves by ``hz`` times the frame step (mod one period): it stands still when
the frame period holds a whole number of flicker periods (25 fps under 50 Hz mains), rolls
fast otherwise (30 fps under 50 Hz: a third of a period per frame) and slowly at 29.97 fps
under 60 Hz. Short exposures make it deep (a row integrates less than one period).

The model of a frame's profile is ``scene(row) * gain * (1 + flicker(row))`` with
``log(1 + flicker) = sum_h Re(A_h exp(2 pi i h nu row))``: ``nu = 1 / period_rows``
(cycles per stored row; the sign of the readout direction does not change it), a few
harmonics ``h`` (a lamp is not a pure sine), and complex amplitudes ``A_h`` free in every
frame (the phase moves, the depth is the same). :class:`FlickerRemover` learns ``nu`` from
the first frames (a periodogram over rows, combined over frames by a median, so a flashed
frame does not count, refined by least squares), then fits ``A_h`` of every frame against a
slow running mean of the raw profiles and divides the fitted pattern out before change
detection (in a frame of few periods the period kept is measured on the fundamental
alone). The fit is robust (a flash band or a player is an outlier to it), and only the
periodic part is removed, never the frame's mean level: a flash, an auto-exposure step or
a light switched on keeps its change.

What is kept (:class:`Flicker`) measures the time per row with no flash at all: the solve
can tie ``period_rows * T_row`` of every camera in one hall to one shared flicker period.
Standing flicker is invisible against the scene (and harmless: it cancels in the frame
differences); it is neither removed nor reported.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from flashsync.compiled import cholesky_solve, njit

#: Flicker frequencies of 50 Hz and 60 Hz mains, Hz.
MAINS_FLICKER_HZ = (100.0, 120.0)
#: Relative standard deviation of a period measured through a codec at the least: H.264
#: bends the pattern, and its spread over the video misses that. The 24 cameras of the kept
#: random rigs 0-29 whose mains frequency was named right (``bench_rigs.py --seeds 0:30
#: --max-height 360 --duration-s 8``, 2026-11-29): median 0.33 %, largest 1.96 % off the
#: truth, 6.7 times their spread RMS; against this floor 0.78, 95.8 % within 2 sigma.
CODEC_PERIOD_SHARE = 0.01
#: Flicker periods a frame must hold for the codec's bend (:data:`CODEC_PERIOD_SHARE`) to bound
#: its period's error. In fewer, what else changes down the rows (a stretch that varies from
#: frame to frame, dark rows) bends a pattern of so few periods further: the floor grows as
#: the square of ``FEW_PERIODS / periods`` (how a smooth disturbance leaks into a sinusoid's
#: frequency). The 75 cameras of the kept rigs whose flicker was named (rigs 0-61, the
#: recipes, 44 rigs reading out in 45-75 % of their frame; 2026-11-30), error against the
#: truth over this floor by periods a frame: 1-1.5 RMS 2.1 (0.03-9.2 % off and one 22 %, at
#: 6.9; 7.1 against the codec's 1 % alone), 1.5-2.5 0.56, beyond 0.70. As the cube, 1.2 under
#: 1.5 periods (that one at 3.9), but ``sync`` no longer found that 22 % prior contradicted
#: by the flashes and took it (its time per row 4.5 sigma off, 1.0 as the square).
#: A frame of fewer has its period measured on the fundamental alone (:class:`_FundamentalFrequency`).
FEW_PERIODS = 2.5


@dataclass(frozen=True)
class Flicker:
    """One camera's mains flicker, as its rows saw it.

    Attributes
    ----------
    hz : float or None
        100.0 or 120.0 (twice the mains frequency), identified from how far the pattern moves
        between frames; None where that does not tell (a non-mains light, or too few frames).
    period_rows : float
        Flicker period in readout rows (``(1000 / hz) / T_row``).
    period_rows_std : float
        Its spread, rows (of the estimates over parts of the video and over bands of rows);
        :attr:`period_rows_sigma` is the standard deviation taken. In a frame of fewer than
        :data:`FEW_PERIODS` periods both are the fundamental's (:class:`_FundamentalFrequency`).
    depth : float
        Amplitude of the fundamental as the rows saw it (0.03: rows swing by ±3 %; the
        exposure averages the lamp's own depth down); NaN where the pattern moved too little
        to tell it from the scene.
    n_frames : int
        Frames it was measured on.
    phase : ndarray of float, shape (frames,)
        Phase of the fundamental at stored row 0 in each decoded frame, radians (NaN where not
        measured).
    height : int
        Rows of the frames it was measured on.
    bottom_up : bool or None
        The readout direction its roll tells (a sensor reading bottom-up rolls the pattern
        the other way through the stored rows): True bottom-up, False top-down; None where
        it does not tell (:func:`_identify_hz`).
    """

    hz: float | None
    period_rows: float
    period_rows_std: float
    depth: float
    n_frames: int
    phase: np.ndarray
    height: int
    bottom_up: bool | None = None

    @property
    def periods(self) -> float:
        """Flicker periods a frame holds."""
        return self.height / self.period_rows

    @property
    def floor_share(self) -> float:
        """The least relative standard deviation of the period: :data:`CODEC_PERIOD_SHARE`,
        more in a frame of fewer than :data:`FEW_PERIODS` periods."""
        return CODEC_PERIOD_SHARE * max(1.0, (FEW_PERIODS / self.periods) ** 2)

    @property
    def period_rows_sigma(self) -> float:
        """The period's standard deviation as flashsync takes it, rows: its spread, and at
        least :attr:`floor_share` of the period."""
        spread = self.period_rows_std if np.isfinite(self.period_rows_std) else 0.0
        return max(spread, self.floor_share * self.period_rows)


@dataclass(frozen=True)
class FlickerSettings:
    """Tuning of :class:`FlickerRemover`.

    Attributes
    ----------
    lookahead : int
        Frames held back before change detection: the flicker is learned on them first.
    reservoir : int
        Older frames kept (one every ``reservoir_step``) for learning a slowly rolling flicker.
    reservoir_step : int
    harmonics : int
        Harmonics of the flicker fitted in every frame (below half a cycle per row).
    min_snr : float
        Amplitude of the fundamental over its noise (median over the learning frames) that
        counts as flicker.
    min_depth : float
        Smallest amplitude of the fundamental that counts (0.001: rows swing by ±0.1 %).
    min_periods, max_periods : float
        Flicker periods per frame height searched (a period is 0.2 to 1.5 frame heights at
        25-60 fps; a sensor that reads out faster than its frame period has longer ones).
    memory_frames : float
        Time constant of the running mean the flicker is measured against, frames.
    min_level : float
        Darkest block (fraction of white) that is measured.
    """

    lookahead: int = 32
    reservoir: int = 32
    reservoir_step: int = 8
    harmonics: int = 3
    min_snr: float = 8.0
    min_depth: float = 0.001
    min_periods: float = 0.75
    max_periods: float = 6.0
    memory_frames: float = 256.0
    min_level: float = 0.035


#: Frames per chunk: the frequency is updated after each, and the chunks' estimates are compared.
CHUNK_FRAMES = 64
#: Bands of rows whose estimates are compared (leave-one-out) for the standard deviation.
STRIPS = 6
#: Largest relative step a frame makes in the running mean (a flash or a player moves it little).
MEAN_CLIP = 0.2
#: A frame's fitted pattern farther than this many times the typical distance from the one
#: predicted by the frame before (its running mean over ``DEVIATION_FRAMES``), or without a
#: prediction a fundamental this many times the learned one, is not flicker (a flash band, a
#: scene change): the frame keeps the predicted pattern instead.
MAX_DEVIATION = 4.0
DEVIATION_FRAMES = 32.0
MAX_AMPLITUDE_FACTOR = 2.5
#: Time constant of each row's own gain on the pattern, frames, and its largest size.
ROW_GAIN_FRAMES = 32.0
MAX_ROW_GAIN = 1.5
#: Frames a corrected frame waits for those after it: a B-frame's blocks may be copies of
#: the reference frame after it, up to this many frames later (x264's runs of B-frames are
#: at most 3 long).
COPY_FRAMES = 4
#: Frames before a frame whose blocks it may copy (a run of frozen blocks carries its
#: source's correction from frame to frame).
COPY_REFERENCES = 4
#: Fewest rows a frame needs for its flicker to be looked for.
MIN_ROWS = 16
#: Gauss-Newton steps on the learning frames.
LEARNING_STEPS = 4
#: Share of the flicker thresholds (depth, signal to noise) that the fits at the periodogram's
#: peak must reach for the Gauss-Newton steps to be taken (most videos have no flicker: one
#: round of fits tells, at a quarter of the cost).
PRETEST_MARGIN = 0.5
#: Largest share of the fundamentals' spread (about their mean, and of what the other
#: frequency leaves) that a mains frequency's roll may leave unexplained to be named.
MAX_UNEXPLAINED = 1.0 / 3.0
#: A named flicker's roll tells the sensor's readout direction where the other direction
#: leaves this many times its residual (of the 97 named on the 163 kept random rigs, 59 so
#: told, every one right) ...
ROLL_DIRECTION_RATIO = 5.0
#: ... and it turns by at least this share of a period a frame (from standing: at 59.94 fps
#: a 120 Hz flicker turns 0.002, less than the codec moves it).
MIN_ROLL_PER_FRAME = 0.02


class FlickerRemover:
    """Streaming estimator and remover of one camera's rolling mains flicker.

    Call it on an iterable of ``(t_frame_ms, profile)`` (profile: float array (height, blocks),
    stored rows, light-linear as :func:`flashsync.profiles.row_profile` gives it); it yields
    the same pairs with the flicker divided out, ``settings.lookahead + COPY_FRAMES`` frames
    later (memory stays constant). :meth:`estimate` gives what it found once the iterator is exhausted.

    Examples
    --------
    >>> remover = FlickerRemover(height=240)                 # doctest: +SKIP
    >>> for t_ms, profile in remover(profiles): ...          # doctest: +SKIP
    >>> remover.estimate()                                   # doctest: +SKIP
    """

    def __init__(self, height: int, settings: FlickerSettings = FlickerSettings()):
        self.height = height
        self.settings = settings
        self._queue: deque[tuple[float, np.ndarray]] = deque()
        self._reservoir: deque[tuple[float, np.ndarray]] = deque(maxlen=settings.reservoir)
        self._n_seen = self._n_out = self._attempts = 0
        self._next_attempt = settings.lookahead
        self._lock: _Lock | None = None
        self._fits: list[tuple[int, float, complex]] = []  # (frame, t_ms, fundamental)
        self._evidence = _Evidence()
        self._fundamental: _FundamentalFrequency | None = None  # the period's measure in few periods
        self._mean_phasor = 0j
        # log corrections: None before a flicker is locked (nothing to divide out)
        self._key: tuple[np.ndarray, np.ndarray | None] | None = None  # last key frame: (profile, log correction)
        self._pending: deque[tuple[float, np.ndarray, str, np.ndarray | None]] = deque()  # corrections not yet applied
        self._before: deque[tuple[np.ndarray, np.ndarray | None]] = deque(maxlen=COPY_REFERENCES)  # (profile, applied)

    def __call__(self, frames: Iterable[tuple[float, np.ndarray]]) -> Iterator[tuple[float, np.ndarray]]:
        for t_ms, profile, *picture in frames:
            yield from self.push(t_ms, profile, *picture)
        yield from self.flush()

    @property
    def n_seen(self) -> int:
        """Frames taken so far."""
        return self._n_seen

    def push(self, t_ms: float, profile: np.ndarray, picture: str = "P") -> list[tuple[float, np.ndarray]]:
        """Take one frame (``picture``: ``"I"``, ``"P"`` or ``"B"``, how it was coded,
        :func:`~flashsync.profiles.read_profiles`); return the frames it lets out, corrected
        (none while the lookahead fills, then one). The state between calls is all in the
        object, which pickles: a video can be fed in parts, on different machines."""
        settings = self.settings
        profile = np.asarray(profile, dtype=np.float32).reshape(self.height, -1)
        self._queue.append((t_ms, profile, picture))
        if self._n_seen % settings.reservoir_step == 0:
            self._reservoir.append((t_ms, profile))
        self._n_seen += 1
        if self._lock is None and self._n_seen >= self._next_attempt:
            self._learn()
        if len(self._queue) > settings.lookahead:
            self._pending.append(self._correct(*self._queue.popleft()))
        return [self._apply()] if len(self._pending) > COPY_FRAMES else []

    def flush(self) -> list[tuple[float, np.ndarray]]:
        """The frames still held back, corrected: call once after the last :meth:`push`."""
        if self._lock is None and self._attempts == 0 and len(self._queue) >= 8:
            self._learn()
        self._pending.extend(self._correct(*self._queue.popleft()) for _ in range(len(self._queue)))
        return [self._apply() for _ in range(len(self._pending))]

    def _learn(self) -> None:
        """Look for a rolling flicker in the held-back and reservoir frames; lock onto it.

        Attempts are made when the lookahead first fills, then at doubling intervals (a light
        switched on later, a roll too slow to see at first), then every 1024 frames."""
        self._attempts += 1
        self._next_attempt = self._n_seen + min(self.settings.lookahead * 2**self._attempts, 1024)
        dense = [(t, p) for t, p, _ in self._queue]
        frames = [item for item in self._reservoir if item[0] < dense[0][0]] + dense
        profiles = np.stack([p for _, p in frames])
        middle = np.median(profiles, axis=0)
        logs = np.stack([_row_log_ratio(p, middle, self.settings.min_level) for p in profiles])
        found = _learn_frequency(logs, self.settings)
        if found is None:
            return
        nu, amplitude = found
        basis = _basis(self.height, nu, self.settings.harmonics)
        fundamentals = np.array(
            [_fit_frame(row, basis, np.zeros(basis.shape[1]), 1, 0.0)[0][1:3] for row in logs[-len(dense) :]]
        )
        recent = np.mean(np.stack([p for _, p in dense]), axis=0).astype(np.float32)
        lock = _Lock(
            nu,
            basis,
            recent,
            amplitude,
            _rotation_per_ms(fundamentals[:, 0] - 1j * fundamentals[:, 1], np.array([t for t, _ in dense])),
        )
        for _, profile in dense:  # the rows' gains learn before the first frame
            y = _row_log_ratio(profile, recent, self.settings.min_level)
            coef, scale, *_ = _fit_frame(y, basis, np.zeros(basis.shape[1]), 1, 0.0)
            _row_pattern(
                y,
                basis,
                coef,
                max(3.0 * scale, 0.75 * amplitude),
                lock.gains,
                1.0 / ROW_GAIN_FRAMES,
                2.0 * amplitude**2,
            )
        self._lock = lock
        if nu * self.height < FEW_PERIODS:
            self._fundamental = _FundamentalFrequency(nu, self.height)

    def _correct(
        self, t_ms: float, profile: np.ndarray, picture: str
    ) -> tuple[float, np.ndarray, str, np.ndarray | None]:
        """Fit the frame's pattern against the running mean, learn from it; the frame with its
        log correction (per row, repeated over the blocks: shape (height, blocks), float32;
        None before a flicker is locked), divided out by :meth:`_apply`.

        What the codec keeps from frame to frame (a row whose blocks it skips) holds the
        pattern of the last key frame, where it refreshes everything: each row removes its
        share ``G`` of this frame's pattern and the rest of the key frame's."""
        frame = self._n_out
        self._n_out += 1
        lock = self._lock
        if lock is None:
            return t_ms, profile, picture, None
        y = _row_log_ratio(profile, lock.mean, self.settings.min_level)
        init = lock.predict(t_ms)
        coef, scale, num, den, ok = _fit_frame(y, lock.basis, init, STRIPS, lock.scale if lock.last else 0.0)
        if ok and lock.plausible(coef, init, scale):
            self._fits.append((frame, t_ms, complex(coef[1], -coef[2]) + self._mean_phasor))
            if self._evidence.add(lock.nu, num / scale**2, den / scale**2):
                lock.retune(self._evidence.latest, self.settings.harmonics)
            if self._fundamental is not None:
                self._fundamental.add(y)
        else:
            coef = init
        lock.last = (t_ms, coef.copy())
        pattern, follows = _row_pattern(
            y,
            lock.basis,
            coef,
            max(3.0 * scale, 0.75 * lock.amplitude),
            lock.gains,
            1.0 / ROW_GAIN_FRAMES,
            2.0 * lock.amplitude**2,
        )
        if picture == "I":
            lock.key_pattern = lock.basis[:, 1:] @ coef[1:]
        pattern += (1.0 - np.clip(follows, 0.0, 1.0)) * lock.key_pattern
        _update_mean(lock.mean, profile, 1.0 / self.settings.memory_frames, MEAN_CLIP)
        self._mean_phasor += complex(coef[1], -coef[2]) / self.settings.memory_frames
        return t_ms, profile, picture, np.repeat(pattern.astype(np.float32)[:, None], profile.shape[1], axis=1)

    def _apply(self) -> tuple[float, np.ndarray]:
        """The oldest pending frame (shape (height, blocks)) with its log correction divided
        out of its rows, except in the blocks that the codec copied from another frame (the
        same value to the last bit: sensor noise never repeats): they hold that frame's light
        and get that frame's correction.

        Between key frames x264 predicts a frame from one at the same phase of a rolling
        flicker (three frames back at 30 fps under 50 Hz mains), so flat rows follow the
        pattern; the frames just after a key frame can only be predicted from it, at another
        phase, and their flat blocks are copies of it, as are those of the frames predicted
        from them, until the codec codes them again. Rows that follow the pattern in one
        group of pictures hold the key frame's in the next: no row's share of the pattern
        learned over the frames before can tell (5 % bands at rows that had followed it).

        A block's light is that of the frame that coded it, and a B-frame is decoded after
        the reference frame (I or P) shown next, so it may copy from it. The sources, first
        match first: the last key frame, the :data:`COPY_REFERENCES` frames before (nearest
        first) and, for a B-frame, the next reference frame (the division waits
        :data:`COPY_FRAMES` frames for it). A B-frame just before a key frame copies the key
        frame's blocks, and one just after an auto-exposure step copies the rows that the
        next P-frame codes again at its own phase."""
        t_ms, profile, picture, applied = self._pending.popleft()
        sources = []
        if picture != "I":
            sources = ([self._key] if self._key is not None else []) + list(reversed(self._before))
            if picture == "B":
                sources += [(p, c) for _, p, kind, c in self._pending if kind != "B"][:1]
        if applied is not None or any(correction is not None for _, correction in sources):
            applied = np.zeros(profile.shape, np.float32) if applied is None else applied
            free = np.ones(profile.shape, dtype=bool)
            for source, correction in sources:
                if source.shape == profile.shape:
                    copied = free & (profile == source)
                    applied[copied] = 0.0 if correction is None else correction[copied]
                    free &= ~copied
        if picture == "I":
            self._key = (profile, applied)
        self._before.append((profile, applied))
        return t_ms, profile if applied is None else profile / np.exp(applied)

    def estimate(self) -> Flicker | None:
        """The flicker found (None: no rolling flicker), once the frames are all through.

        The fundamentals are measured against a running mean that holds part of the pattern
        itself (its share is added back as it builds up, but not what it held at the start):
        the points lie on a circle about an unknown centre whose radius is the depth and along
        which the phase advances. Where a mains frequency's roll explains them
        (:func:`_identify_hz`), its fit gives both; else :func:`_circle`."""
        if self._lock is None or len(self._fits) < 2:
            return None
        nu, nu_std = (self._fundamental.evidence if self._fundamental else self._evidence).frequency()
        frames = np.array([f for f, _, _ in self._fits])
        times = np.array([t for _, t, _ in self._fits])
        points = np.array([z for _, _, z in self._fits])
        hz, centre, radius, bottom_up = _identify_hz(points, frames, times)
        if hz is None:
            centre, radius = _circle(points)
        phase = np.full(self._n_out, np.nan)
        if np.isfinite(radius):
            phase[frames] = np.angle(points - centre)
        return Flicker(
            hz, float(1.0 / nu), float(nu_std / nu**2), float(radius), len(frames), phase, self.height, bottom_up
        )


@dataclass
class _Lock:
    """A learned flicker: frequency ``nu`` (cycles per row), the frame basis, the running mean
    profile it is measured against, the fundamental's typical amplitude, its roll (radians per
    ms, aliased to one frame step) and the last frame's coefficients."""

    nu: float
    basis: np.ndarray
    mean: np.ndarray
    amplitude: float
    radians_per_ms: float
    last: tuple[float, np.ndarray] | None = None
    gains: np.ndarray = None
    key_pattern: np.ndarray = None
    deviation: float = 0.0
    scale: float = 0.0

    def __post_init__(self):
        self.gains = np.zeros((len(self.basis), 5))
        self.key_pattern = np.zeros(len(self.basis))
        self.deviation = 0.2 * self.amplitude

    def plausible(self, coef: np.ndarray, init: np.ndarray, scale: float) -> bool:
        """Whether a frame's fitted pattern can be flicker: no farther (largest difference over
        the rows) than :data:`MAX_DEVIATION` times the typical distance from the one predicted
        from the frame before (a band the harmonics of a long period would take in moves it
        far), or, without a prediction, no more than :data:`MAX_AMPLITUDE_FACTOR` times the
        learned amplitude. Keeps the typical distance of the frames that pass, and the
        residual scale of those fitted without a prediction: the others are fitted at this
        scale and given it back (:func:`_fit_frame`), so that a band does not widen it
        (made to follow every frame's own scale, the kept rigs came out worse: README,
        "Fewer than one period a frame")."""
        if self.last is None:
            if math.hypot(coef[1], coef[2]) > MAX_AMPLITUDE_FACTOR * self.amplitude:
                return False
        else:
            distance = float(np.max(np.abs(self.basis[:, 1:] @ (coef[1:] - init[1:]))))
            if distance > MAX_DEVIATION * self.deviation + 2.0 * scale:
                return False
            self.deviation += (distance - self.deviation) / DEVIATION_FRAMES
        self.scale = scale if self.scale == 0.0 else self.scale + (scale - self.scale) / DEVIATION_FRAMES
        return True

    def predict(self, t_ms: float) -> np.ndarray:
        """The previous frame's coefficients rotated by the roll since it (the fit's start)."""
        n = self.basis.shape[1]
        if self.last is None:
            return np.zeros(n)
        t_last, coef = self.last
        out = coef.copy()
        for h in range(1, (n - 1) // 2 + 1):
            z = complex(coef[2 * h - 1], -coef[2 * h]) * np.exp(1j * h * self.radians_per_ms * (t_ms - t_last))
            out[2 * h - 1], out[2 * h] = z.real, -z.imag
        return out

    def retune(self, nu: float, harmonics: int) -> None:
        """Follow a refined frequency (its basis too)."""
        self.nu = nu
        self.basis = _basis(len(self.basis), nu, harmonics)
        if self.last is not None and len(self.last[1]) != self.basis.shape[1]:
            self.last = None


class _Evidence:
    """The frames' Gauss-Newton sums for the frequency, per chunk of frames (each chunk's
    estimate retunes the lock) and per band of rows over the whole video."""

    def __init__(self):
        self.chunks: list[tuple[float, float]] = []  # (estimate, information)
        self.strip_sums = np.zeros(STRIPS)  # sum of information x estimate
        self.strip_information = np.zeros(STRIPS)
        self._num = np.zeros(STRIPS)
        self._den = np.zeros(STRIPS)
        self._n = 0
        self._nu = 0.0
        self.latest = float("nan")

    def add(self, nu: float, num: np.ndarray, den: np.ndarray) -> bool:
        """One frame's sums at frequency ``nu``; True when a chunk closed (see ``latest``)."""
        self._nu = nu
        self._num += num
        self._den += den
        self._n += 1
        if self._n < CHUNK_FRAMES:
            return False
        return self._close()

    def _close(self) -> bool:
        information = self._den.sum()
        closed = information > 0
        if closed:
            self.latest = self._nu + self._num.sum() / information
            self.chunks.append((self.latest, information))
            strip = self._den > 0
            self.strip_sums[strip] += self._den[strip] * self._nu + self._num[strip]
            self.strip_information += self._den
        self._num[:] = 0.0
        self._den[:] = 0.0
        self._n = 0
        return closed

    def frequency(self) -> tuple[float, float]:
        """Frequency (cycles per row) and its standard deviation: the largest of the formal
        error, the spread of the chunks' estimates (a wandering mains frequency) and the
        leave-one-band-out spread of the rows' estimates (a codec or a scene that bends the
        pattern in some rows)."""
        if self._n:
            self._close()
        if not self.chunks:
            return self._nu, float("nan")
        estimates = np.array([e for e, _ in self.chunks])
        weights = np.array([w for _, w in self.chunks])
        total = weights.sum()
        nu = float(np.sum(weights * estimates) / total)
        spreads = [1.0 / math.sqrt(total)]
        if len(estimates) >= 3:
            spreads.append(math.sqrt(np.sum(weights * (estimates - nu) ** 2) / total / (len(estimates) - 1)))
        used = self.strip_information > 0
        if used.sum() >= 3:
            sums, information = self.strip_sums[used], self.strip_information[used]
            left_out = (sums.sum() - sums) / (information.sum() - information)
            k = len(left_out)
            spreads.append(math.sqrt((k - 1) / k * np.sum((left_out - left_out.mean()) ** 2)))
        return nu, max(spreads)


class _FundamentalFrequency:
    """The flicker's frequency (cycles per row) measured on the pattern's fundamental alone,
    in frames of fewer than :data:`FEW_PERIODS` periods, beside the fit that removes the
    pattern with its harmonics (the removal keeps its own frequency: the events do not move).
    The codec and the scene let each row follow the pattern by its own share
    (:func:`_row_pattern`); over so few periods harmonics fitted at a wrong period take that
    envelope in, and the frequency they lock drifts with it (random rig 166's cam3 of a bench
    of all four departures, 1.53 periods a frame: 19.5 % short, 9 sigma; synthetic frames
    whose rows follow 20-100 % of the pattern: 13-60 % long); one sinusoid cannot bend so.
    On the 25 cameras of seven kept benches whose flicker a frame holds 1-2.5 periods of, its
    error over sigma RMS 2.09 -> 0.88, none over 3 (3 with the harmonics). Its own robust
    frame fits at their own scale and Gauss-Newton sums, retuned chunk by chunk
    (:class:`_Evidence`)."""

    def __init__(self, nu: float, height: int):
        self.nu = nu
        self.basis = _basis(height, nu, 1)
        self.evidence = _Evidence()

    def add(self, y: np.ndarray) -> None:
        """One frame's log ratio to the running mean (shape (height,))."""
        _, scale, num, den, ok = _fit_frame(y, self.basis, np.zeros(3), STRIPS, 0.0)
        if ok and self.evidence.add(self.nu, num / scale**2, den / scale**2):
            self.nu = self.evidence.latest
            self.basis = _basis(len(self.basis), self.nu, 1)


def _basis(height: int, nu: float, harmonics: int) -> np.ndarray:
    """Columns 1, cos(2 pi h nu r), sin(2 pi h nu r) for the harmonics h below 0.45 cycles per
    row; shape (height, 1 + 2 H)."""
    rows = np.arange(height, dtype=np.float64)
    columns = [np.ones(height)]
    for h in range(1, harmonics + 1):
        if h * nu >= 0.45:
            break
        columns += [np.cos(2 * np.pi * h * nu * rows), np.sin(2 * np.pi * h * nu * rows)]
    return np.stack(columns, axis=1)


def _learn_frequency(logs: np.ndarray, settings: FlickerSettings) -> tuple[float, float] | None:
    """The flicker's frequency (cycles per row) and the median amplitude of its fundamental
    over frames, or None where no periodic pattern stands out of the noise.

    ``logs`` (frames, height): each frame's log ratio to the frames' median profile. A
    periodogram of each frame's rows (mean removed, Hann taper, zero-padded), combined over
    frames by the median (a flashed frame does not count), gives the peak; Gauss-Newton steps
    of the robust fit of every frame (harmonics included) refine it, and the fitted
    amplitudes over their noise decide. The steps are taken only where the fits at the peak
    reach :data:`PRETEST_MARGIN` of the thresholds, and a frequency they move out of the band
    searched (``settings.min_periods`` to ``max_periods`` per frame height) is no flicker."""
    if logs.shape[1] < MIN_ROWS:
        return None
    valid = np.isfinite(logs)
    logs = logs[valid.sum(axis=1) >= logs.shape[1] // 2]
    if len(logs) < 4:
        return None
    frames, height = logs.shape
    valid = np.isfinite(logs)
    centred = np.where(valid, logs - np.nanmean(logs, axis=1, keepdims=True), 0.0)
    pad = 8 * (1 << int(np.ceil(np.log2(height))))
    grid = np.fft.rfftfreq(pad)
    search = np.flatnonzero((grid >= settings.min_periods / height) & (grid <= settings.max_periods / height))
    if not search.size:
        return None
    spectra = np.fft.rfft(centred * np.hanning(height), n=pad, axis=1)[:, search]  # the band searched only
    nu = float(grid[search[np.argmax(np.median(np.abs(spectra) ** 2, axis=0))]])
    for step in range(LEARNING_STEPS):
        basis = _basis(height, nu, settings.harmonics)
        fits = [_fit_frame(row, basis, np.zeros(basis.shape[1]), 1, 0.0) for row in logs]
        if step == 0 and _median_amplitude(fits, logs, settings, PRETEST_MARGIN) is None:
            return None
        num = sum(f[2][0] / f[1] ** 2 for f in fits if f[4])
        den = sum(f[3][0] / f[1] ** 2 for f in fits if f[4])
        if not den > 0:
            return None
        nu += float(np.clip(num / den, -1.0 / pad, 1.0 / pad))
    if not settings.min_periods <= nu * height <= settings.max_periods:
        return None  # the steps walked out of the band searched: a slow gradient, not flicker
    amplitude = _median_amplitude(fits, logs, settings, 1.0)
    return None if amplitude is None else (nu, amplitude)


def _median_amplitude(fits: list, logs: np.ndarray, settings: FlickerSettings, margin: float) -> float | None:
    """The median amplitude of the fundamental over the frames ``fits`` (:func:`_fit_frame`
    of each row of ``logs``) could fit, or None where it, or its median ratio to its noise,
    is below ``margin`` times what counts as flicker (``settings.min_depth``, ``min_snr``)."""
    amplitude = [math.hypot(f[0][1], f[0][2]) for f in fits if f[4]]
    noise = [f[1] * math.sqrt(2.0 / np.isfinite(row).sum()) for f, row in zip(fits, logs) if f[4]]
    if (
        not amplitude
        or np.median(amplitude) < margin * settings.min_depth
        or np.median(np.divide(amplitude, noise)) < margin * settings.min_snr
    ):
        return None
    return float(np.median(amplitude))


def _rotation_per_ms(fundamentals: np.ndarray, times: np.ndarray) -> float:
    """How fast the pattern rolls, radians per ms, from consecutive frames' fundamentals:
    the angle between successive differences (the differences cancel any pattern frozen in
    the reference), over the median frame step; aliased to one frame step, which is all a
    prediction of the next frame needs. No roll (0) where that roll predicts each next
    fundamental worse than the one before it does: a slow roll (59.94 fps under 120 Hz
    flicker: 0.013 rad a frame) moves the fundamental less than the codec and the noise do,
    and the angle between the steps is theirs (-1.45 rad a frame on ``tests/clips/slow_roll.mp4``)."""
    if len(fundamentals) < 3:
        return 0.0
    steps = np.diff(fundamentals)
    turn = np.sum(steps[1:] * np.conj(steps[:-1]))
    if not abs(turn) > 0:
        return 0.0
    step_ms = float(np.median(np.diff(times)))
    angle = float(np.angle(turn))
    rolled = np.sum(np.abs(fundamentals[1:] - np.exp(1j * angle) * fundamentals[:-1]) ** 2)
    return angle / step_ms if rolled < np.sum(np.abs(steps) ** 2) else 0.0


def _circle(points: np.ndarray) -> tuple[complex, float]:
    """Centre and radius of the circle through complex ``points`` (algebraic least squares);
    NaN radius where they do not spread around enough of it to tell (standing flicker)."""
    if len(points) < 3:
        return 0j, float("nan")
    x, y = points.real, points.imag
    design = np.stack([x, y, np.ones_like(x)], axis=1)
    coef, *_ = np.linalg.lstsq(design, -(x**2 + y**2), rcond=None)
    centre = complex(-coef[0] / 2.0, -coef[1] / 2.0)
    radius_sq = abs(centre) ** 2 - coef[2]
    if not np.isfinite(radius_sq) or radius_sq <= 0:
        return centre, float("nan")
    radius = math.sqrt(radius_sq)
    if np.sqrt(np.var(x) + np.var(y)) < 0.2 * radius:
        return centre, float("nan")
    return centre, radius


def _identify_hz(
    points: np.ndarray, frames: np.ndarray, times: np.ndarray
) -> tuple[float | None, complex, float, bool | None]:
    """100 or 120 Hz: the mains flicker whose roll explains the frames' fundamentals best,
    with the centre and radius of the circle its fit gives and the readout direction its roll
    tells (:attr:`Flicker.bottom_up`); (None, 0, NaN, None) where neither explains them (a
    frame period that holds whole periods of both, a light not on mains, a pattern the codec
    froze).

    ``points`` (complex), ``frames`` (decoded frame numbers) and ``times`` (ms), one per
    fitted frame. Each frequency, in either readout direction, is fitted as
    ``c + a exp(±2 pi i hz t / 1000)`` by least squares on a steady clock through the stamps
    (:func:`_steady_times`); it must leave at most :data:`MAX_UNEXPLAINED` of the points'
    spread about their mean, and of what the other frequency leaves. (The phase steps about
    :func:`_circle`'s centre, compared with each frequency's, named a cloud of fundamentals
    120 Hz flicker: the circle through a cloud is a large one, on which it barely turns.) The
    direction is the fit's (the phase turning with time: top-down) where the other direction
    at that frequency leaves :data:`ROLL_DIRECTION_RATIO` times its residual and the roll
    turns :data:`MIN_ROLL_PER_FRAME` of a period a frame or more from standing."""
    none = (None, 0j, float("nan"), None)
    if len(points) < 4:
        return none
    t = _steady_times(frames, times)
    centred = points - points.mean()
    spread = float(np.sum(np.abs(centred) ** 2))
    fits = {}
    for hz in MAINS_FLICKER_HZ:
        for sign in (1.0, -1.0):
            phasor = np.exp(sign * 2j * np.pi * hz * t / 1000.0)
            roll = phasor - phasor.mean()
            weight = float(np.sum(np.abs(roll) ** 2))
            if not weight > 1e-6 * len(t):  # standing: a roll of whole periods a frame
                continue
            a = np.sum(np.conj(roll) * centred) / weight
            fits[(hz, sign)] = (float(np.sum(np.abs(centred - a * roll) ** 2)), a, phasor.mean())
    if not fits or not spread > 0:
        return none
    best = min(fits, key=lambda key: fits[key][0])
    left, a, mean_phasor = fits[best]
    other = min((fits[key][0] for key in fits if key[0] != best[0]), default=spread)
    if left > MAX_UNEXPLAINED * min(spread, other):
        return none
    hz, sign = best
    turn = hz * float(np.median(np.diff(t))) / 1000.0 % 1.0
    reverse = fits.get((hz, -sign), (0.0,))[0]
    told = left * ROLL_DIRECTION_RATIO < reverse and min(turn, 1.0 - turn) >= MIN_ROLL_PER_FRAME
    return hz, complex(points.mean() - a * mean_phasor), float(abs(a)), (sign < 0) if told else None


def _steady_times(frames: np.ndarray, times: np.ndarray) -> np.ndarray:
    """The stamps ``times`` (ms) of decoded frames ``frames`` on a steady clock: each gap
    counted in frame steps (the decoded frames it spans, more where its length holds more
    steps: dropped frames), a line through the stamps over the count, and the count again at
    the line's step. Stamps as they are (a 1 ms grid, a muxer's jitter) turn a 100 Hz phase
    0.6 rad for each ms they are off."""
    gaps, spans = np.diff(times), np.diff(frames)
    step = float(np.median(gaps / spans))
    for _ in range(2):
        slots = np.concatenate([[0.0], np.cumsum(np.maximum(np.round(gaps / step), spans))])
        step, start = np.polyfit(slots, times, 1)
    return start + step * slots


@njit
def _row_log_ratio(profile, reference, min_level):  # pragma: no cover - compiled
    """Per row, the log of the median over blocks of ``profile / reference`` where the
    reference is lit (>= ``min_level``); NaN where fewer than half the blocks are. Shape (height,)."""
    height, blocks = profile.shape
    out = np.empty(height, np.float64)
    ratios = np.empty(blocks, np.float64)
    for r in range(height):
        n = 0
        for b in range(blocks):
            if reference[r, b] >= min_level:
                ratios[n] = max(profile[r, b] / reference[r, b], 1e-3)
                n += 1
        if n == 0 or 2 * n < blocks:
            out[r] = np.nan
            continue
        for i in range(1, n):  # insertion sort: n is small
            value = ratios[i]
            j = i - 1
            while j >= 0 and ratios[j] > value:
                ratios[j + 1] = ratios[j]
                j -= 1
            ratios[j + 1] = value
        middle = n // 2
        out[r] = math.log(ratios[middle] if n % 2 else 0.5 * (ratios[middle - 1] + ratios[middle]))
    return out


@njit
def _fit_frame(y, basis, init, strips, scale_hint):  # pragma: no cover - compiled
    """Robust fit of ``y ≈ basis @ coef`` (:func:`_basis`) over the finite rows (iteratively
    reweighted least squares, Tukey's biweight at 4.685 robust sigmas), started from
    ``init``; a flash band or a player is an outlier. The biweight gives rows far off no
    weight at all: with a few harmonics of a long period the pattern could otherwise bend
    to take in a flash band that a long-tailed weight leaves a little say. The residual
    scale is ``scale_hint`` where positive (the scale of recent frames: a band does not
    widen it), else the robust scale of each iteration's residuals.

    Returns (coef, scale, gn_num, gn_den, ok): the residual scale (``scale_hint`` where
    positive, else the robust scale of the last iteration's residuals); the Gauss-Newton
    sums (``sum w d e``, ``sum w d^2``) of the residual ``e`` against ``d``, the pattern's
    derivative with respect to nu less what the basis explains of it, in each of ``strips``
    equal bands of rows (shape (strips,)): their totals' ratio is this frame's correction to
    nu; ok False where too few rows are finite or the system is singular.
    """
    height, p = basis.shape
    coef = init.copy()
    rows = np.empty(height, np.int64)
    n = 0
    for r in range(height):
        if np.isfinite(y[r]):
            rows[n] = r
            n += 1
    residual = np.empty(n)
    weight = np.empty(n)
    scale = 1.0
    gn_num = np.zeros(strips)
    gn_den = np.zeros(strips)
    if n < 2 * p + 4:
        return coef, scale, gn_num, gn_den, False
    offset = np.empty(n)
    for i in range(n):  # the start's level: the median offset
        r = rows[i]
        fitted = 0.0
        for j in range(1, p):
            fitted += basis[r, j] * coef[j]
        offset[i] = y[r] - fitted
    coef[0] = np.median(offset)
    for _ in range(8):
        for i in range(n):
            r = rows[i]
            fitted = 0.0
            for j in range(p):
                fitted += basis[r, j] * coef[j]
            residual[i] = y[r] - fitted
        scale = scale_hint if scale_hint > 0 else max(1.4826 * np.median(np.abs(residual)), 1e-5)
        for i in range(n):
            u = residual[i] / (4.685 * scale)
            weight[i] = (1.0 - u * u) ** 2 if abs(u) < 1.0 else 0.0
        normal = np.zeros((p, p))
        right = np.zeros(p)
        for i in range(n):
            if weight[i] == 0.0:  # a row far off adds exactly nothing
                continue
            r = rows[i]
            for j in range(p):
                weighted = weight[i] * basis[r, j]
                right[j] += weighted * y[r]
                for k in range(j + 1):
                    normal[j, k] += weighted * basis[r, k]
        for j in range(p):
            for k in range(j + 1, p):
                normal[j, k] = normal[k, j]
        solved, ok = cholesky_solve(normal, right)
        if not ok:
            return coef, scale, gn_num, gn_den, False
        coef = solved
    slope = np.empty(n)
    projection = np.zeros(p)
    for i in range(n):  # the pattern's derivative in nu
        r = rows[i]
        total = 0.0
        for h in range(1, (p - 1) // 2 + 1):
            total += h * r * (-coef[2 * h - 1] * basis[r, 2 * h] + coef[2 * h] * basis[r, 2 * h - 1])
        slope[i] = 2.0 * math.pi * total
        for j in range(p):
            projection[j] += weight[i] * basis[rows[i], j] * slope[i]
    along, ok = cholesky_solve(normal, projection)  # what the other unknowns absorb of it
    if not ok:
        return coef, scale, gn_num, gn_den, False
    for i in range(n):
        r = rows[i]
        fitted = 0.0
        for j in range(p):
            slope[i] -= basis[r, j] * along[j]
            fitted += basis[r, j] * coef[j]
        strip = r * strips // height
        gn_num[strip] += weight[i] * slope[i] * (y[r] - fitted)
        gn_den[strip] += weight[i] * slope[i] * slope[i]
    return coef, scale, gn_num, gn_den, True


@njit
def _row_pattern(y, basis, coef, clip, sums, rate, prior):  # pragma: no cover - compiled
    """The log flicker to divide out of each row: the frame's fitted pattern ``z(r)``
    (complex: its value and its quadrature) times the row's own complex gain ``G(r)``; and
    ``Re G(r)``, the share of the pattern the row follows. Both shape (height,).

    The codec does not keep the pattern alike in every row: it freezes flat areas (skipped
    blocks keep an old phase or none) and delays others. Each row's gain is the least-squares
    regression of its observed log ratio (less the frame's level) on ``Re z`` and ``-Im z``
    over the recent frames (exponential memory at ``rate``; ``sums`` (height, 5) holds the
    running normal equations and is updated), Huber-weighted at ``clip`` from the row's
    current model so that a flash barely counts, with a weak prior ``prior`` at ``G = 1``.
    """
    height, p = basis.shape
    out = np.zeros(height)
    follows = np.zeros(height)
    for r in range(height):
        re = 0.0
        im = 0.0
        for h in range(1, (p - 1) // 2 + 1):
            a, b = coef[2 * h - 1], coef[2 * h]
            c, s = basis[r, 2 * h - 1], basis[r, 2 * h]
            re += a * c + b * s
            im += a * s - b * c
        n00, n01, n11 = sums[r, 0] + prior, sums[r, 1], sums[r, 2] + prior
        r0, r1 = sums[r, 3] + prior, sums[r, 4]
        det = n00 * n11 - n01 * n01
        g_re, g_im = (n11 * r0 - n01 * r1) / det, (n00 * r1 - n01 * r0) / det
        size = math.hypot(g_re, g_im)
        if size > MAX_ROW_GAIN:  # a codec attenuates or delays, never amplifies
            g_re, g_im = g_re * MAX_ROW_GAIN / size, g_im * MAX_ROW_GAIN / size
        if np.isfinite(y[r]):
            e = y[r] - coef[0]
            miss = abs(e - (g_re * re - g_im * im))
            w = 1.0 if miss <= clip else clip / miss
            for k in range(5):
                sums[r, k] *= 1.0 - rate
            sums[r, 0] += w * re * re
            sums[r, 1] -= w * re * im
            sums[r, 2] += w * im * im
            sums[r, 3] += w * re * e
            sums[r, 4] -= w * im * e
        out[r] = g_re * re - g_im * im
        follows[r] = g_re
    return out, follows


@njit
def _update_mean(mean, profile, rate, clip):  # pragma: no cover - compiled
    """``mean += rate * (profile - mean)``, each step clipped to ``clip`` times the mean (a
    flash or a player that passes moves it little)."""
    height, blocks = mean.shape
    for r in range(height):
        for b in range(blocks):
            step = profile[r, b] - mean[r, b]
            bound = clip * max(abs(mean[r, b]), 1e-3)
            mean[r, b] += rate * min(max(step, -bound), bound)
