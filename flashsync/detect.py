"""Flash events from row profiles: bands of rows that changed brightness, and their edges.

Each frame's row profile is compared with a baseline (per-row median of the last few
profiles, so one or two flashed frames do not move it) as a relative change
``(p - b) / b``, the median over column blocks: illumination is multiplicative, so a flash
gives a flat plateau whatever the scene's texture, and a player changes only a few blocks.
Rows over a noise-adaptive threshold form bands. A band's leading edge (first affected row
in readout order) is where the change reaches half of the band's local plateau, refined to
a fraction of a row by fitting the flash's pulse, integrated over the exposure and blurred
by the codec, to the whole band where it lies in one frame, else to the rows around the
edge (:mod:`flashsync.ramp`): the row whose exposure ended when the flash had given half
its light, the same instant in every camera, whatever its gain, scene or exposure.

A band that reaches the last row continues in the next frame (one event, flagged
``split``); a band that starts at row 0 with nothing open before it had its leading edge in
the vertical blanking (flagged ``leading_hidden``, only its trailing edge is reported). A
change that fills whole frames for several frames is a light switching on or off (``on`` /
``off``); one without any edge (auto-exposure) only resets the baseline. The records are in
:mod:`flashsync.events`.

The detector is streaming: :class:`EventDetector` keeps a few profiles, not the video.
"""

from __future__ import annotations

import statistics
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from flashsync.compiled import njit
from flashsync.errors import NotEnoughDataError
from flashsync.events import Band, Edge, Events, Flag
from flashsync.flicker import Flicker, FlickerRemover
from flashsync.model import readout_rows
from flashsync.profiles import VideoInfo, read_profiles
from flashsync.ramp import BandFit, common_width, fit_pulse_band, fit_pulse_edge, fit_split_band
from flashsync.recurrence import ECHO_FRACTION, RecurrenceFilter, Stripe
from flashsync.robust import MAD_TO_SIGMA
from flashsync.timestamps import check_timestamps

#: Profile level (fraction of white) of a clipped column block; a band saturates where half
#: a row's blocks do (the median over blocks, and with it the band's level, is clipped; a few
#: clipped blocks do not move it).
SATURATED = 0.98
#: Noise of a saturated band's leading edge in units of a clean one's. Its clipped rows are
#: left out of its fit (:attr:`_Segment.unclipped_change`), but its level then rests on its
#: ramps' shape: ``python benchmarks/bench_edges.py --clips 12 --crf 23 --strengths
#: 1.0,2.5``: 0.85-1.11 rows RMS, mean -0.6 to -0.75 rows (4.1-11.1 rows RMS fitted on the
#: clipped level), against 0.10-0.13 rows for unsaturated edges at crf 23; an edge whose
#: partner is hidden cannot tell the level, nor a rectangular pulse's ramps (their slope
#: alone). The solve weighs such an edge alone down by its square, and a clipped band's
#: length; the band's midpoint, as sharp as an unclipped band's, it does not
#: (:func:`flashsync.pipeline._timing_bands`).
SATURATED_EDGE_SIGMA = 12.0
#: The same for an edge flagged ``long_pulse``: in a camera whose flashes outlast its
#: exposure (:func:`~flashsync.ramp.common_width`), an edge not fitted whole with that
#: exposure (alone, or of a band split across frames) is read as if the exposure were the
#: longer, up to half the difference off (on the LED rig of ``tests/test_exposure.py``
#: 4-14 rows at 0.7-1.0 ms under pulses of 1.2-2 ms; at 12, a saturated edge's weight,
#: they still put a camera of the 24 kept random rigs 3.5 % off in its time per row).
LONG_PULSE_EDGE_SIGMA = 50.0
#: A band split across two frames whose part in the next frame peaks under this share of
#: the first's is the pulse's tail: its half-level trailing edge lay in the rows hidden
#: between frames, and only the leading edge of the two parts' fit is kept (random rigs: a
#: 270-row camera's next frame held five rows at 0.036 under a 0.168 band, read on a level
#: of their own as a trailing edge 1.1 ms late, its times 0.37 ms off; a 360-row camera's
#: tail at 0.41 of its band, 1.4 ms late, its time per row 5 % off).
TAIL_SHARE = 0.5
#: Fewest profiles in the baseline before a frame is searched for bands (the first frames of
#: a video, or after a light switch, compare with one or two frames only: codec and flicker
#: differences between two frames are not averaged out).
MIN_BASELINE = 3
#: Recent frames whose largest change gives the clutter level (:attr:`DetectorSettings.clutter_factor`).
CLUTTER_FRAMES = 101


@dataclass(frozen=True)
class DetectorSettings:
    """Tuning of :class:`EventDetector`.

    Attributes
    ----------
    history : int
        Recent profiles in the baseline median (a flash lights at most two of them).
    k_sigma : float
        Threshold in units of the video's profile noise (robust sigma, relative change).
    min_change : float
        Smallest relative brightness change that can be an event (0.03 = 3 %). Where the
        video makes bands again and again (codec echoes, leftover flicker), 1.25 times the
        median strength of the last ones dropped as recurring, up to twice this: a flash
        has to stand out of them.
    min_rows : int
        Shortest band, rows; at least 1 % of the frame height is used.
    min_level : float
        Darkest row (fraction of white above black) whose relative change is measured;
        darker rows are blind, as are rows at white (:data:`SATURATED`).
    min_step : float
        Smallest brightness step (fraction of white; 1.5 DN) that counts as a change.
    min_band_step : float
        Smallest brightness step of a band (fraction of white; 2 DN), the median over its
        rows and blocks; a fainter band is held for the recurrence filter (its repeats are
        evidence) but is not an event. The codec rounds a dark flat area to a DN or two, and
        differently in a frame it codes afresh than in the key frame that the frames around
        it copy: in rows 24 DN above black, a B-frame two frames after a key frame stood
        1.6 DN (6.6 %) above its neighbours. A band of 20 % passes in rows from 10 DN (0.046
        of white) up.
    step_frames : int
        Whole frames a change must fill to be a light switched on or off.
    agreement : float
        Light changes every column block of a row alike; a player changes a few, each by
        its own amount. Over a band's rows, at least this fraction of the blocks (median
        over its rows) must have changed within a factor of two of the row's median change:
        several players in one row can lift the median, they do not agree with it.
    pedestal_agreement, pedestal_share : float
        A band whose blocks agree less than ``pedestal_agreement`` (the median over its rows,
        as ``agreement``) is no event where ``pedestal_share`` or more of the lit blocks of
        the frame's quiet rows (those outside it changed by under half its level) changed
        within a factor of two of its level: the codec's pedestal, not light. x264's weighted
        prediction codes the frame a flash brightens in part from the one before it with a
        gain, and the blocks it leaves uncoded keep that gain wherever they lie: rows where
        most are uncoded make a band at the gain's level, their blocks in patches, and the
        frame's quiet rows carry the same patches (random rig 810's reference, 59.94 fps at
        14 ms under TTL flashes: five such bands of 6-32 rows above flashes' bands, three
        matched in place of flashes, its time per row 6 % short). Of the 10,467 bands of 826
        cameras on fourteen kept benches, it takes out 77 that no flash made and 4 of
        flashes (3-13 rows each; two at a frame's foot, the band going on in the next).
    clutter_factor : float
        Threshold in units of the video's clutter: the median over recent frames of each
        frame's largest change (what players, leftover flicker and the codec leave in frames
        without a flash; a flash is in few frames and does not move the median).
    flipped : bool
        The sensor reads bottom-up in stored rows (camera mounted upside down).
    """

    history: int = 5
    k_sigma: float = 8.0
    min_change: float = 0.03
    min_rows: int = 3
    min_level: float = 0.035
    min_step: float = 1.5 / 219.0
    min_band_step: float = 2.0 / 219.0
    step_frames: int = 2
    agreement: float = 0.6
    pedestal_agreement: float = 0.8
    pedestal_share: float = 0.12
    clutter_factor: float = 2.5
    flipped: bool = False


@dataclass
class _Segment:
    """A run ``[start, stop)`` of changed readout rows in one frame; ``change`` is that
    frame's relative change times the run's sign (so the band is positive), ``clipped``
    which of its readout rows are at white (bool, shape (height,): the median of the row's
    column blocks at :data:`SATURATED` or more)."""

    frame: int
    t_frame_ms: float
    change: np.ndarray
    start: int
    stop: int
    sign: int
    clipped: np.ndarray
    sigma: float
    stripe: Stripe
    step: float

    @property
    def saturated(self) -> bool:
        """Some of the run's rows are clipped at white."""
        return bool(self.clipped[self.start : self.stop].any())

    @property
    def unclipped_change(self) -> np.ndarray:
        """``change`` with the clipped rows blind (NaN), for the ramp fits: a clipped row's
        change says only "at least this", and fitted as the band's level it pulls a
        band's half-light crossings out (leading edges early, trailing ones late). Left out,
        a band's level comes from its ramps' shape where both are in view; an edge alone
        cannot tell it and stays near its crossing."""
        return np.where(self.clipped, np.nan, self.change)


@dataclass
class _Event:
    """A band followed across frames: its segments, first to last."""

    segments: list[_Segment]
    full_frames: int = 0


class EventDetector:
    """Streaming event detector for one camera; feed it profiles with :meth:`push`.

    Parameters
    ----------
    camera : str
        Camera name written into each event.
    height : int
        Rows per profile.
    settings : DetectorSettings
    """

    def __init__(self, camera: str, height: int, settings: DetectorSettings = DetectorSettings()):
        self.camera = camera
        self.height = height
        self.settings = settings
        self._history: np.ndarray | None = None  # (history, height, blocks) ring of profiles
        self._n_history = self._next = 0
        self._noise: deque[float] = deque(maxlen=25)
        self._peaks: deque[float] = deque(maxlen=CLUTTER_FRAMES)
        self._open: _Event | None = None
        self._lit_rows = (0, height)
        self._global_frames = 0
        self._global_sign = 0
        self._n_events = 0
        self._edges: list[tuple] = []  # one tuple of the Events fields per edge found
        self._whole: list[tuple[BandFit, int]] = []  # bands fitted whole that passed the recurrence
        # filter, with where their two edges start in ``_edges``
        self.exposure_rows: float | None = None
        self.rival_exposure_rows: float | None = None
        self.pulse_rows = np.empty(0)
        self._recurrence = RecurrenceFilter()
        self.n_degenerate = 0
        self.n_faint = 0
        self.n_whole_frames = 0

    def push(self, frame: int, t_frame_ms: float, profile: np.ndarray) -> None:
        """Process one frame's row profile (shape (height, blocks) or (height,), stored rows).

        The relative change of a row is the median over its column blocks: a flash changes
        every block alike, an object that fills one block changes only that one. Frames
        where no row passes the threshold (nearly all) cost one compiled call.
        """
        profile = np.asarray(profile, dtype=np.float32).reshape(self.height, -1)
        readout = profile[::-1] if self.settings.flipped else profile
        if self._history is None:
            self._history = np.empty((self.settings.history, *readout.shape), np.float32)
        if self._n_history == 0:
            self._remember(readout)
            return
        change, agree, blocks, noise, peak, lit_start, lit_stop = _relative_change(
            self._history[: self._n_history], readout, self.settings.min_level, self.settings.min_step
        )
        if np.isfinite(noise):
            self._noise.append(noise)
        sigma = max(statistics.median(self._noise), 1e-4) if self._noise else 1e-4
        self._peaks.append(peak)
        clutter = statistics.median(self._peaks) if len(self._peaks) >= 3 else 0.0
        recurring = self._recurrence.recent_dropped
        echoes = min(1.25 * statistics.median(recurring), 2 * self.settings.min_change) if len(recurring) >= 5 else 0.0
        threshold = max(
            self.settings.min_change, self.settings.k_sigma * sigma, self.settings.clutter_factor * clutter, echoes
        )
        self._lit_rows = (lit_start, lit_stop)
        segments = []
        # an echo or a repeat of a band near the threshold is below it: bands down to the
        # fraction of it that makes an echo are evidence of recurrence, and a band is compared
        # with them as it stands at that level
        searched = ECHO_FRACTION * threshold
        shortest = max(self.settings.min_rows, self.height // 100)
        searching = peak > searched and self._n_history >= MIN_BASELINE
        clipped = np.median(readout, axis=1) >= SATURATED if searching else None
        for sign in (1, -1) if searching else ():
            signed = sign * change
            stripes = []
            for start, stop in _runs(signed > searched, gap=2):
                if stop - start >= shortest:
                    level = sign * float(np.median(signed[start:stop]))
                    stripes.append(Stripe(frame, int(start), int(stop), level, start <= lit_start, stop >= lit_stop))
                    self._recurrence.see(stripes[-1])  # whether or not it is light
            for start, stop in _joined(signed, _runs(signed > threshold, gap=2), searched) if peak > threshold else ():
                agreeing = np.median(agree[start:stop])
                if stop - start < shortest or agreeing < self.settings.agreement:
                    continue
                if agreeing < self.settings.pedestal_agreement and (
                    _pedestal_share(signed, sign * blocks, start, stop) >= self.settings.pedestal_share
                ):
                    continue
                stripe = next(s for s in stripes if s.start <= start and stop <= s.stop)
                segments.append(
                    _Segment(
                        frame,
                        t_frame_ms,
                        signed,
                        int(start),
                        int(stop),
                        sign,
                        clipped,
                        sigma,
                        stripe,
                        _step(readout[start:stop], float(np.median(signed[start:stop])), sign),
                    )
                )
        self._remember(readout)
        self._consume(sorted(segments, key=lambda s: s.start), readout)
        self._number(self._recurrence.release(frame))

    def _remember(self, readout: np.ndarray) -> None:
        """Put a profile into the baseline's ring (the oldest one leaves once it is full)."""
        self._history[self._next] = readout
        self._next = (self._next + 1) % len(self._history)
        self._n_history = min(self._n_history + 1, len(self._history))

    def finish(self) -> Events:
        """Close a band still open at the end of the video; return all the events' edges.
        Sets :attr:`exposure_rows`: the exposure, readout rows, that the bands fitted whole
        share (:func:`~flashsync.ramp.common_width`; one band alone tells a short exposure
        from the pulse's decay only to a row or two, and a rectangular pulse from the
        exposure not at all where the pulse is the longer), or None with fewer than three,
        and :attr:`rival_exposure_rows`, the exposure of a reading it could not rule out;
        where some of the pulses are longer than it, those bands' edges are the ones fitted
        with that exposure, and every other flash edge is flagged ``long_pulse``. Sets
        :attr:`pulse_rows`: per event, the pulse of its band fitted whole with that exposure
        (:attr:`BandFit.pulse`; the pulse may be the longer), NaN for the others."""
        if self._open is not None:
            self._emit(self._open, Band.PULSE, trailing_visible=False)
            self._open = None
        self._number(self._recurrence.release())
        common = common_width([fit for fit, _ in self._whole])
        self.exposure_rows, pulses_longer, self.rival_exposure_rows = (
            common if common is not None else (None, False, None)
        )
        self.pulse_rows = np.full(self._n_events, np.nan)
        settled = set()
        for fit, at in self._whole if self.exposure_rows is not None else ():
            refit = fit.with_width(self.exposure_rows, longer=True)
            if refit is not None:
                self.pulse_rows[self._edges[at][1]] = refit[0].pulse
                if pulses_longer and self._settle(fit, refit[0], at):
                    settled |= {at, at + 1}
        if pulses_longer:
            self._edges = [
                edge if k in settled or edge[6] is not Band.PULSE else (*edge[:-1], edge[-1] | {Flag.LONG_PULSE})
                for k, edge in enumerate(self._edges)
            ]
        return Events.from_columns(*zip(*self._edges)) if self._edges else Events.concat([])

    @property
    def n_recurring(self) -> int:
        """Bands dropped because they recur at the same rows (:mod:`flashsync.recurrence`)."""
        return self._recurrence.dropped

    def _number(self, released: list[tuple[list[tuple], BandFit | None]]) -> None:
        """Number the events that passed the recurrence filter and keep their edges (and
        the fits of the bands fitted whole)."""
        for payload in released:
            if payload is None:
                self.n_faint += 1
                continue
            edges, whole = payload
            if whole is not None:
                self._whole.append((whole, len(self._edges)))
            self._edges += [(camera, self._n_events, *rest) for camera, *rest in edges]
            self._n_events += 1

    def _settle(self, fit: BandFit, band: BandFit, at: int) -> bool:
        """Settle the two edges of a band fitted whole, ``_edges[at]`` and ``_edges[at + 1]``,
        in a camera whose exposure some pulses outlast, given ``band``, its ``fit`` again with
        that exposure: where it finds the pulse the longer (alone the band was read the
        other way round), they move to it; where it finds it the shorter, they stay.
        Unsettled (False) where it would move the band's middle (the same whichever
        rectangle is the exposure) further than its ramp could explain."""
        if band.p[1] <= band.width:
            return True
        reach = 2.0 + 2.0 * float(fit.p[2])
        if abs(band.leading + band.trailing - fit.leading - fit.trailing) > 2.0 * reach:
            return False
        for k, row in ((at, band.leading), (at + 1, band.trailing)):
            edge = self._edges[k]
            self._edges[k] = (*edge[:4], readout_rows(row, self.height, self.settings.flipped), *edge[5:])
        return True

    def _consume(self, segments: list[_Segment], readout: np.ndarray) -> None:
        """Follow bands across frames. A band reaching the first (last) lit row of the frame
        (rows above a dark sky are blind) continues from the previous (into the next) frame."""
        opened, self._open = self._open, None
        for segment in segments:
            at_top, at_bottom = segment.start <= self._lit_rows[0], segment.stop >= self._lit_rows[1]
            if at_top and opened is not None and segment.sign == opened.segments[0].sign:
                opened.segments.append(segment)
                if not at_bottom:
                    self._emit(opened, Band.PULSE)
                elif opened.full_frames + 1 >= self.settings.step_frames:
                    self._emit(opened, Band.ON if segment.sign > 0 else Band.OFF, trailing_visible=False)
                    self._reset_baseline(readout)
                else:
                    opened.full_frames += 1
                    self._open = opened
                opened = None
            elif at_top and at_bottom:
                self._global_frames += 1
                self._global_sign = segment.sign
                if self._global_frames >= self.settings.step_frames:
                    self._reset_baseline(readout)
                return
            elif at_bottom:
                self._open = _Event([segment])
            else:
                self._emit(_Event([segment]), Band.PULSE)
        if opened is not None:
            self._emit(opened, Band.PULSE, trailing_visible=False)
        if self._global_frames and self._global_sign > 0:
            self.n_whole_frames += 1  # lit whole and gone again: a flash without a band
        self._global_frames = 0

    def _reset_baseline(self, readout: np.ndarray) -> None:
        self._n_history = self._next = 0
        self._remember(readout)
        self._global_frames = 0

    def _emit(self, event: _Event, kind: Band, trailing_visible: bool = True) -> None:
        """Locate the edges of a finished band (:func:`_local_edge`; a band in one frame is
        then fitted whole, :func:`~flashsync.ramp.fit_pulse_band`, so that its edges are one
        exposure apart and at the flash's half-light instant even where the exposure is
        shorter than the pulse; a band split across two frames too,
        :func:`~flashsync.ramp.fit_split_band`, its trailing edge then hidden where the next
        frame shows only the pulse's tail, :data:`TAIL_SHARE`) and hold them for the recurrence
        filter; a band that darkens
        rows without staying dark (a passing shadow) is not an event, and a degenerate one
        (no positive plateau to fit an edge on) is dropped and counted in
        :attr:`n_degenerate`."""
        first, last = event.segments[0], event.segments[-1]
        if kind is Band.PULSE and first.sign < 0:
            return
        plateau = float(np.median(np.concatenate([s.change[s.start : s.stop] for s in event.segments])))
        window = max(6, self.height // 40)
        leading, leading_rise = _local_edge(_rising_crossing, first, plateau, window, kind)
        trailing, trailing_rise = (
            _local_edge(_falling_crossing, last, plateau, window, kind) if trailing_visible else (None, np.nan)
        )
        if any(edge is not None and not np.isfinite(edge) for edge in (leading, trailing)):
            self.n_degenerate += 1
            return
        whole = None
        if kind is Band.PULSE and len(event.segments) == 1 and leading is not None and trailing is not None:
            whole = fit_pulse_band(first.unclipped_change, leading, trailing, trailing_rise, plateau)
            leading, trailing = (whole.leading, whole.trailing) if whole is not None else (leading, trailing)
        elif kind is Band.PULSE and len(event.segments) == 2 and leading is not None and trailing is not None:
            split = fit_split_band(
                first.unclipped_change, leading, last.unclipped_change, trailing, trailing_rise, plateau
            )
            leading, trailing = split if split is not None else (leading, trailing)
            if _peak(last) < TAIL_SHARE * _peak(first):  # the next frame holds the pulse's tail alone
                trailing, trailing_rise = None, np.nan
        flags = {Flag.SPLIT} if len(event.segments) > 1 and kind is Band.PULSE else set()
        flags |= {Flag.SATURATED} if any(s.saturated for s in event.segments) else set()
        flags |= {Flag.LEADING_HIDDEN} if leading is None else set()
        flags |= {Flag.TRAILING_HIDDEN} if trailing is None and kind is Band.PULSE else set()
        edges = ((Edge.LEADING, first, leading, leading_rise), (Edge.TRAILING, last, trailing, trailing_rise))
        found = []
        for edge, segment, row, rise in edges:
            if row is None:
                continue
            found.append(
                (
                    self.camera,
                    segment.frame,
                    segment.t_frame_ms,
                    readout_rows(row, self.height, self.settings.flipped),
                    edge,
                    kind,
                    rise,
                    first.sign * plateau,
                    plateau / first.sigma,
                    frozenset(flags),
                )
            )
        stripes = [segment.stripe for segment in event.segments]
        faint = max(segment.step for segment in event.segments) < self.settings.min_band_step
        payload = None if faint else (found, whole)  # still held: its repeats count as recurrence
        self._recurrence.hold(stripes, first.sign * plateau, payload, checked=kind is Band.PULSE)


def _peak(segment: _Segment) -> float:
    """The largest relative change of a band's rows in one frame."""
    return float(np.max(segment.change[segment.start : segment.stop]))


def _step(rows: np.ndarray, strength: float, sign: int) -> float:
    """A band's brightness step (fraction of white): its ``strength`` (relative change, made
    positive by ``sign``) times the level before it of its ``rows`` (shape (rows, blocks),
    the median over them)."""
    return float(np.median(rows)) * strength / (1.0 + sign * strength)


@njit
def _relative_change(history, current, min_level, min_step):  # pragma: no cover - compiled
    """One frame's relative change against the baseline, with what the detector needs of it.

    Per row: the median over column blocks of ``(current - baseline) / baseline``, with the
    baseline the per-block median of ``history`` (shape (k, height, blocks)); NaN where
    fewer than half the blocks are lit (baseline at ``min_level`` or above, and under
    :data:`SATURATED`: a block already at white cannot show a flash, and counted as
    unchanged it ended a band where the scene turned white, its edge read there). A block
    that moved by less than ``min_step`` counts as unchanged (a one-DN jump of a dark flat
    area at an H.264 key frame is a large relative change).

    Returns (change, agree, blocks, noise, peak, lit_start, lit_stop): change of shape
    (height,); ``agree``, the fraction of the lit blocks whose change is within a factor of
    two of the row's (light scales every block alike; a player changes a few, by its own
    amount), shape (height,); ``blocks``, each block's relative change (0 under
    ``min_step``, NaN where not lit), shape (height, blocks); the robust sigma of the
    change's row-to-row noise (NaN if nothing is lit); the largest ``|change|``; and the
    first and past-the-last lit rows ((0, height) if none).
    """
    k, height, blocks = history.shape
    change = np.empty(height, np.float64)
    agree = np.zeros(height, np.float64)
    block_change = np.full((height, blocks), np.nan)
    column = np.empty(k, np.float64)
    lit = np.empty(blocks, np.float64)
    for r in range(height):
        n_lit = 0
        for b in range(blocks):
            if k == 5:
                baseline = _median5(
                    history[0, r, b], history[1, r, b], history[2, r, b], history[3, r, b], history[4, r, b]
                )
            else:
                for i in range(k):
                    column[i] = history[i, r, b]
                baseline = _median_in_place(column, k)
            if min_level <= baseline < SATURATED:
                step = current[r, b] - baseline
                lit[n_lit] = step / baseline if abs(step) >= min_step else 0.0
                block_change[r, b] = lit[n_lit]
                n_lit += 1
        change[r] = _median_in_place(lit, n_lit) if 2 * n_lit >= blocks and n_lit > 0 else np.nan
        middle = change[r]
        if np.isfinite(middle) and middle != 0.0:
            alike = 0
            for i in range(n_lit):
                ratio = lit[i] / middle
                if 0.5 <= ratio <= 2.0:
                    alike += 1
            agree[r] = alike / n_lit
    steps = np.empty(height, np.float64)
    n_steps, peak, lit_start, lit_stop = 0, 0.0, height, 0
    for r in range(height):
        if np.isnan(change[r]):
            continue
        peak = max(peak, abs(change[r]))
        lit_start, lit_stop = min(lit_start, r), r + 1
        if r > 0 and not np.isnan(change[r - 1]):
            steps[n_steps] = abs(change[r] - change[r - 1])
            n_steps += 1
    noise = MAD_TO_SIGMA / np.sqrt(2.0) * np.median(steps[:n_steps]) if n_steps else np.nan
    if lit_stop == 0:
        lit_start, lit_stop = 0, height
    return change, agree, block_change, noise, peak, lit_start, lit_stop


@njit(inline="always")
def _median5(a, b, c, d, e):  # pragma: no cover - compiled
    """Median of five values by eight comparisons (no sorting)."""
    low, high = max(min(a, b), min(c, d)), min(max(a, b), max(c, d))
    return max(min(e, low), min(max(e, low), high))


@njit
def _median_in_place(values, n):  # pragma: no cover - compiled
    """Median of ``values[:n]`` by insertion sort (n is small); reorders them."""
    for i in range(1, n):
        value = values[i]
        j = i - 1
        while j >= 0 and values[j] > value:
            values[j + 1] = values[j]
            j -= 1
        values[j + 1] = value
    middle = n // 2
    return values[middle] if n % 2 else 0.5 * (values[middle - 1] + values[middle])


def _pedestal_share(change: np.ndarray, blocks: np.ndarray, start: int, stop: int) -> float:
    """Share of the lit blocks of a frame's quiet rows that changed within a factor of two of
    the band ``[start, stop)``'s level (its rows' median change): ``change``, the frame's
    relative change per readout row, made positive over the band (shape (height,)), and
    ``blocks`` per column block (shape (height, blocks), NaN where not lit). The quiet rows
    are those outside the band changed by under half its level
    (:attr:`DetectorSettings.pedestal_share`)."""
    level = float(np.median(change[start:stop]))
    quiet = np.abs(np.nan_to_num(change, nan=np.inf)) < 0.5 * level
    quiet[start:stop] = False
    lit = blocks[quiet]
    lit = lit[np.isfinite(lit)]
    return float(np.mean((lit >= 0.5 * level) & (lit <= 2.0 * level))) if len(lit) else 0.0


def _runs(mask: np.ndarray, gap: int) -> list[tuple[int, int]]:
    """``[start, stop)`` of True runs in ``mask``, merging runs separated by <= ``gap`` rows."""
    padded = np.concatenate([[False], mask, [False]])
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    runs = list(zip(edges[::2], edges[1::2]))
    merged: list[tuple[int, int]] = []
    for start, stop in runs:
        if merged and start - merged[-1][1] <= gap:
            merged[-1] = (merged[-1][0], stop)
        else:
            merged.append((start, stop))
    return merged


def _joined(signed: np.ndarray, runs: list[tuple[int, int]], floor: float) -> list[tuple[int, int]]:
    """The ``runs`` of rows above the threshold (:func:`_runs`), two in a row joined where
    every row between them lies above half the lower of their levels (their median change)
    and above ``floor`` (the echo search's level: one stripe then holds the joined run): one
    band whose middle dips under the threshold. Both runs would find its edges at the same
    half-level crossings (:func:`_local_edge`), and the band was counted twice (rig-771's
    cam3: a faint band of rows 158-208 as two runs, 176-181 and 185-194, each an event
    with the same two edges)."""
    joined: list[tuple[int, int]] = []
    for start, stop in runs:
        if joined:
            first, last = joined[-1]
            half = 0.5 * min(float(np.median(signed[first:last])), float(np.median(signed[start:stop])))
            if np.all(signed[last:start] > max(half, floor)):
                joined[-1] = (first, stop)
                continue
        joined.append((start, stop))
    return joined


def _local_edge(crossing, segment: _Segment, plateau: float, window: int, kind: Band) -> tuple[float | None, float]:
    """Sub-row edge of a band and its rise (rows from 25 % to 75 % of the local plateau).

    The edge is the half-rise point for a pulse, the foot of the ramp for a step.
    Brightness, saturation and scene vary along a band, so the level is the band's local
    plateau: the median change of ``window`` rows that start where the ramp has settled: on a
    leading edge five times the 10 %-to-50 % rise length past the edge (an exponential ramp
    is then within 3 % of its plateau), on a trailing edge twice that length before it (a
    falling ramp leaves its plateau steeply and ends in the pulse's long tail: five times
    that length reached back across a short band into its leading ramp and halved the
    level, putting the trailing edge of a 1 ms xenon pulse a whole decay late). A pulse's
    half-rise point marks the same instant in every camera. A step ramps linearly over one
    exposure, so its half-rise point moves with the exposure; its
    foot (half-rise minus the 25 %-to-75 % length) is the row whose exposure ended at the
    switch. Returns (None, nan) where the edge is not visible, (nan, nan) where the band is
    degenerate (its local plateau is not positive: nothing to locate an edge on).
    """
    level = plateau
    for _ in range(2):
        if not level > 0:
            return np.nan, np.nan
        row = crossing(segment.change, 0.5 * level, segment.start, segment.stop)
        foot = crossing(segment.change, 0.1 * level, segment.start, segment.stop)
        if row is None or foot is None:
            return row, np.nan
        if row > foot:
            settle = min(int(np.ceil(row + 5 * (row - foot))), segment.stop - window)
            inside = segment.change[max(settle, int(row) + 1) : settle + window]
        else:  # a falling ramp is steep at its top: its plateau ends just before the fall
            settle = max(int(row + 2 * (row - foot)), segment.start + window)
            inside = segment.change[settle - window : min(settle, int(row))]
        if not np.isfinite(inside).any():
            break
        level = float(np.nanmedian(inside))
    quarter = crossing(segment.change, 0.25 * level, segment.start, segment.stop)
    three_quarters = crossing(segment.change, 0.75 * level, segment.start, segment.stop)
    if quarter is None or three_quarters is None:
        return (row if kind is Band.PULSE else None), np.nan
    rise = abs(three_quarters - quarter)
    if kind is not Band.PULSE:
        return row - (three_quarters - quarter), rise
    return fit_pulse_edge(segment.unclipped_change, row, rise, level, rising=crossing is _rising_crossing), rise


#: Rows before a leading edge (after a trailing edge) that must be visible and lit.
_EDGE_CONTEXT = 3


def _rising_crossing(values: np.ndarray, level: float, start: int, stop: int) -> float | None:
    """Sub-row position where ``values`` rises through ``level`` at the start of the run
    ``[start, stop)``; None when the run never reaches ``level``, or when the rows just
    before the crossing are outside the frame or blind (NaN: too dark to measure)."""
    i = start
    while i > 0 and values[i - 1] >= level:
        i -= 1
    while i < stop and values[i] < level:
        i += 1
    if i < _EDGE_CONTEXT or i == stop or np.isnan(values[i - _EDGE_CONTEXT : i]).any():
        return None
    return i - 1 + (level - values[i - 1]) / (values[i] - values[i - 1])


def _falling_crossing(values: np.ndarray, level: float, start: int, stop: int) -> float | None:
    """Sub-row position where ``values`` falls through ``level`` at the end of the run
    ``[start, stop)``; None when the run never reaches ``level``, or when the rows just
    after the crossing are outside the frame or blind."""
    last = len(values) - 1
    i = stop - 1
    while i < last and values[i + 1] >= level:
        i += 1
    while i >= start and values[i] < level:
        i -= 1
    if i > last - _EDGE_CONTEXT or i < start or np.isnan(values[i + 1 : i + 1 + _EDGE_CONTEXT]).any():
        return None
    return i + (values[i] - level) / (values[i] - values[i + 1])


@dataclass(frozen=True)
class CameraDetection:
    """One video's detection pass: its frame times and its events, read one or both ways up.

    A camera mounted upside down reads its stored image bottom-up, so its bands start at
    their bottom row. Where the mounting is known, the video is read that way only; where it
    is not, it is read both ways and :func:`~flashsync.pipeline.synchronize` picks the
    reading that explains the flashes best.

    Attributes
    ----------
    camera : str
        Camera name (video file stem).
    video : Path
    width, height : int
        Stored image size, px.
    frame_times_ms : ndarray of shape (n_frames,)
        Frame times, ms: the container stamps (or given ones), or the frame clock once
        retimed.
    top_down, bottom_up : Events or None
        The events as read with the sensor reading top-down (upright camera) and bottom-up
        (upside down); None where not read that way.
    flipped : bool
        The reading in use: bottom-up.
    flicker : Flicker or None
        The camera's rolling mains flicker, removed before detection (None: none seen).
    n_recurring, n_degenerate : int
        Bands dropped as recurring at the same rows (:mod:`flashsync.recurrence`) and as
        degenerate (no plateau to fit an edge on), in the first reading.
    n_whole_frames : int
        Flashes that lit every row of a frame at once and were gone the next frame (no band,
        no edge: a global shutter, or a sensor that reads its rows far faster than its
        exposure), in the first reading.
    top_down_exposure_rows, bottom_up_exposure_rows : float or None
        The exposure in readout rows that the camera's bands within one frame share, as
        each reading fitted them (:attr:`EventDetector.exposure_rows`); None where fewer
        than three were fitted or not read that way (:attr:`exposure_rows`: the reading
        in use).
    top_down_rival_exposure_rows, bottom_up_rival_exposure_rows : float or None
        The exposure, readout rows, of a reading of the bands with pulses longer than it
        that explained them better at its best but not by what a choice needs, where each
        reading took its exposure from the bands' lengths
        (:attr:`EventDetector.rival_exposure_rows`; :attr:`rival_exposure_rows`: the reading
        in use); None where there was none.
    top_down_pulse_rows, bottom_up_pulse_rows : float arrays of shape (n_events,) or None
        Per event number, the pulse of its band fitted whole, readout rows, as each reading
        fitted it (:attr:`EventDetector.pulse_rows`; NaN for the other events; None where
        not read that way or not recorded).
    display_rotation_deg : int
        Degrees counterclockwise that the video's display matrix turns its stored frames
        for showing (:func:`~flashsync.profiles.display_rotation_deg`); rows here are always
        the stored frame's.
    """

    camera: str
    video: Path
    width: int
    height: int
    frame_times_ms: np.ndarray
    top_down: Events | None
    bottom_up: Events | None = None
    flipped: bool = False
    flicker: Flicker | None = None
    n_recurring: int = 0
    n_degenerate: int = 0
    n_whole_frames: int = 0
    top_down_exposure_rows: float | None = None
    bottom_up_exposure_rows: float | None = None
    top_down_rival_exposure_rows: float | None = None
    bottom_up_rival_exposure_rows: float | None = None
    top_down_pulse_rows: np.ndarray | None = None
    bottom_up_pulse_rows: np.ndarray | None = None
    display_rotation_deg: int = 0

    @property
    def events(self) -> Events:
        """The events of the reading in use."""
        return self.bottom_up if self.flipped else self.top_down

    @property
    def exposure_rows(self) -> float | None:
        """The exposure, readout rows, that the bands of the reading in use share."""
        return self.bottom_up_exposure_rows if self.flipped else self.top_down_exposure_rows

    @property
    def rival_exposure_rows(self) -> float | None:
        """The exposure, readout rows, of a reading of the bands of the reading in use that
        they could not rule out (pulses longer than it), or None."""
        return self.bottom_up_rival_exposure_rows if self.flipped else self.top_down_rival_exposure_rows

    @property
    def pulse_rows(self) -> np.ndarray | None:
        """Per event number, the pulse of its band fitted whole, readout rows, in the reading
        in use (NaN for the other events)."""
        return self.bottom_up_pulse_rows if self.flipped else self.top_down_pulse_rows

    @property
    def undecided(self) -> bool:
        """Read both ways up: the readout direction is still to be chosen."""
        return self.top_down is not None and self.bottom_up is not None

    def read_flipped(self, flipped: bool) -> CameraDetection:
        """This detection with the reading bottom-up (``flipped``) or top-down in use."""
        if (self.bottom_up if flipped else self.top_down) is None:
            raise ValueError(f"{self.video} was not read {'bottom-up' if flipped else 'top-down'}")
        return replace(self, flipped=flipped)

    def read_only(self, flipped: bool) -> CameraDetection:
        """This detection read bottom-up (``flipped``) or top-down only: the readout direction
        decided."""
        reading = self.read_flipped(flipped)
        return replace(
            reading, top_down=None if flipped else self.top_down, bottom_up=self.bottom_up if flipped else None
        )

    def read_as_rolled(self) -> CameraDetection:
        """Where it was read both ways up and its rolling mains flicker's roll tells the
        readout direction (:attr:`~flashsync.flicker.Flicker.bottom_up`), read that way only;
        else this detection."""
        roll = self.flicker.bottom_up if self.flicker is not None else None
        return self.read_only(roll) if self.undecided and roll is not None else self

    def with_longer_exposure(self, rows: float) -> CameraDetection:
        """This detection with the exposure of the reading in use ``rows`` readout rows longer
        and each band fitted whole split again around its middle: its leading edge half of
        that earlier, its trailing edge half later, its pulse that much shorter (a band is the
        exposure convolved with the pulse, so a rectangle's band is the same whichever of the
        two is taken the longer; its leading edge lies half a pulse in, its trailing edge one
        exposure after that)."""
        return self.with_band_exposures(np.where(np.isfinite(self.pulse_rows), rows, 0.0), self.exposure_rows + rows)

    def with_band_exposures(self, rows: np.ndarray, exposure_rows: float) -> CameraDetection:
        """This detection with the band of each event of the reading in use ``rows[event]``
        readout rows longer (shape (n_events,)), as :meth:`with_longer_exposure` makes every
        band fitted whole, and ``exposure_rows`` (rows) the reading's exposure (with no rival)."""
        events, pulses = self.events, self.pulse_rows
        later = np.where(events.edge == Edge.TRAILING, 0.5, -0.5) * rows[events.event]
        moved = replace(events, row=events.row + (-later if self.flipped else later))
        side = "bottom_up" if self.flipped else "top_down"
        return replace(
            self,
            **{
                side: moved,
                f"{side}_exposure_rows": exposure_rows,
                f"{side}_rival_exposure_rows": None,
                f"{side}_pulse_rows": pulses - rows,
            },
        )

    def retimed(self, frame_times_ms: np.ndarray) -> CameraDetection:
        """This detection with other frame times (ms, one per decoded frame), its events' too."""
        return replace(
            self,
            frame_times_ms=frame_times_ms,
            top_down=self.top_down.retimed(frame_times_ms) if self.top_down is not None else None,
            bottom_up=self.bottom_up.retimed(frame_times_ms) if self.bottom_up is not None else None,
        )


def detect_video(
    path: str | Path,
    flipped: bool | None = False,
    settings: DetectorSettings | None = None,
    progress: Callable[[str, int], Callable[[int], None] | None] | None = None,
) -> CameraDetection:
    """Decode a video once and detect its flash events.

    Parameters
    ----------
    path : path of a video file FFmpeg can open.
    flipped : the camera reads bottom-up in stored rows (mounted upside down); None: not
        known, the video is read both ways up (the top-down reading in use).
    settings : detector tuning; ``flipped`` overrides its field.
    progress : ``progress(camera, n_frames_hint)`` may return a callback taking the number
        of frames decoded since its last call.

    Returns
    -------
    CameraDetection
    """
    info, profiles = read_profiles(path)
    update = progress(info.camera, info.n_frames_hint) if progress else None
    detection = VideoDetection(info, flipped, settings)
    for frame in profiles:
        detection.push(*frame)
        if update is not None:
            update(1)
    return detection.finish()


class VideoDetection:
    """One video's detection pass, fed its frames in order, in one go or in parts.

    Everything the pass carries from frame to frame (the flicker model, each reading's
    baseline, recurrence filter and event numbering) is in this object, which pickles: a
    video decoded in segments on several machines is detected by handing it from one
    segment to the next (:mod:`flashsync.cluster`), with the same events as in one go.

    Parameters
    ----------
    info : the video's :class:`~flashsync.profiles.VideoInfo`.
    flipped, settings : as for :func:`detect_video`.
    """

    def __init__(self, info: VideoInfo, flipped: bool | None = False, settings: DetectorSettings | None = None):
        self.info = info
        self.directions = [False, True] if flipped is None else [flipped]
        base = settings or DetectorSettings()
        self._detectors = [
            EventDetector(info.camera, info.height, replace(base, flipped=direction)) for direction in self.directions
        ]
        self._remove_flicker = FlickerRemover(info.height)
        self._times: list[float] = []
        self._rotation_deg: int | None = None

    @property
    def n_frames(self) -> int:
        """Frames pushed so far."""
        return self._remove_flicker.n_seen

    def push(self, t_ms: float, profile: np.ndarray, picture: str = "P", rotation_deg: int = 0) -> None:
        """One decoded frame: its time (ms), row profile (:func:`~flashsync.profiles.row_profile`),
        picture type (``"I"``, ``"P"`` or ``"B"``) and display turn (degrees; the first
        frame's is the video's), as :func:`~flashsync.profiles.read_profiles` gives them."""
        if self._rotation_deg is None:
            self._rotation_deg = rotation_deg
        self._detect(self._remove_flicker.push(t_ms, profile, picture))

    def finish(self) -> CameraDetection:
        """The detection, once every frame is pushed."""
        self._detect(self._remove_flicker.flush())
        frame_times = check_timestamps(np.asarray(self._times), str(self.info.path))
        if len(frame_times) < 2:
            raise NotEnoughDataError(f"{self.info.path}: only {len(frame_times)} frame decoded; give a longer video")
        readings = {direction: detector.finish() for direction, detector in zip(self.directions, self._detectors)}
        exposures = {direction: detector.exposure_rows for direction, detector in zip(self.directions, self._detectors)}
        rivals = {
            direction: detector.rival_exposure_rows for direction, detector in zip(self.directions, self._detectors)
        }
        pulses = {direction: detector.pulse_rows for direction, detector in zip(self.directions, self._detectors)}
        return CameraDetection(
            self.info.camera,
            self.info.path,
            self.info.width,
            self.info.height,
            frame_times,
            readings.get(False),
            readings.get(True),
            flipped=self.directions[0],
            flicker=self._remove_flicker.estimate(),
            n_recurring=self._detectors[0].n_recurring,
            n_degenerate=self._detectors[0].n_degenerate,
            n_whole_frames=self._detectors[0].n_whole_frames,
            top_down_exposure_rows=exposures.get(False),
            bottom_up_exposure_rows=exposures.get(True),
            top_down_rival_exposure_rows=rivals.get(False),
            bottom_up_rival_exposure_rows=rivals.get(True),
            top_down_pulse_rows=pulses.get(False),
            bottom_up_pulse_rows=pulses.get(True),
            display_rotation_deg=self._rotation_deg or 0,
        )

    def _detect(self, frames: list[tuple[float, np.ndarray]]) -> None:
        for t_ms, profile in frames:
            frame = len(self._times)
            self._times.append(t_ms)
            for detector in self._detectors:
                detector.push(frame, t_ms, profile)
