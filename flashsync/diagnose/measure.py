"""What the videos measured: each camera's frame stamps and the band edges matched across cameras.

A band (one detected pulse event with both edges visible and unsaturated) gives two edges:
the leading edge is the row whose exposure *ends* at the flash, the trailing edge the row
whose exposure *starts* there (docs/architecture.md, time convention). Where ``sync``
solved the detections, the bands are paired into flashes as ``sync`` paired them: each
event of its model's flashes is the band with an edge at the event's frame and row (in
the reading the detection was told; ``sync`` may have read the camera the other way up).
That pairing is the matcher's with the shifts the counts of events alone cannot decide
(a flash that fires a pre-flash lines two cameras up at two shifts) decided by the fit of
the edges; a camera whose times ``sync`` doubts by more than a matching tolerance (its
flashes line up at another shift about as well) is left out, and so is an event its solve
puts more than that off its flash. On 61 random rigs, 44 of them fired with pre-flashes,
this pairing put bands of two true flashes into 1 of 763 flashes and refused 2 rigs (of two
cameras each, the second doubted by 60 ms); the workflow's own pairing, below, 47 of 714,
and refused 7.

Where ``sync`` cannot solve them, the bands are paired by their approximate time on each
camera's own clock (stamp + row x frame step / height) and their strengths (a camera
misses faint flashes, not bright ones) with the pipeline's matcher,
:func:`flashsync.match.match_events`, at the tolerance of a readout direction that may be
wrong (one frame period): loose enough for every effect of the catalogue (an upside-down
camera misplaces a band by less than a frame, a dropped frame or a clock drift does not
move a stamp). A camera whose stamps change rate is paired both ways (its stamps as they
are, and at one rate throughout), and every pairing also at ``sync``'s tolerance (a
quarter of a frame period, every readout direction as told): flashes at nearly regular
intervals can leave the loose one a rival shift, and a pair with one is not paired. The
pairing that ties the most bands is kept (the loose one on a tie).

Either way the edges are the detections' own (frame, row): nothing here depends on a
model's clocks.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from itertools import product

import numpy as np

from flashsync.detect import CameraDetection
from flashsync.errors import InputError, NotEnoughDataError
from flashsync.events import Band, Bands, Events, Flag
from flashsync.exposure_changes import pulse_excess_rows
from flashsync.flicker import Flicker
from flashsync.frame_clock import FrameClock, fit_frame_clock
from flashsync.match import (
    MIN_SHARED_FLASHES,
    Matching,
    approximate_times_ms,
    match_events,
    match_tolerance_ms,
    shared_flashes,
)
from flashsync.model import SyncModel
from flashsync.pipeline import another_reference, flicker_row_time_ms, mains_flicker, shared_readouts
from flashsync.robust import cauchy_nll, cauchy_scale, mad_sigma
from flashsync.solve import POOLED_EQUATIONS
from flashsync.timestamps import median_step_ms

#: Bands with an edge this close (rows) to the top or bottom of the image are left out: the
#: detector sees only part of the edge's ramp and plateau there.
EDGE_MARGIN_ROWS = 6
#: A band whose length is this many robust standard deviations off its camera's others is
#: left out of the edge noise (no Gaussian gets there; a codec echo or a pulse's tail on a
#: short exposure does): on an HD rig one band 1 ms long (32 robust sigmas) made a 59.94 fps
#: camera's noise 0.25 ms, ten times its other bands', and hid its drift. The largest
#: deviation of an ordinary band seen on the shipped sample and the second world's rigs is
#: 10 robust sigmas (the median absolute deviation is small: a median band deviates by 0).
OUTLIER_BAND_SIGMAS = 20.0
#: A band longer than its camera's others of its kind by more than this many robust standard
#: deviations is widened (the ``pulse_shape`` effect's evidence): beyond the largest
#: deviation of an ordinary band (above). On the second world's HD rig the 59.94 fps
#: camera's widened bands are 17 and 58 robust sigmas long; on the shipped sample the
#: longest band is 8 (cam2, 0.12 ms).
WIDE_BAND_SIGMAS = 10.0
#: A band is widened, too, where the detector read it with a pulse that outlasts the
#: exposure (:func:`~flashsync.exposure_changes.pulse_excess_rows`) and it is longer than its
#: camera's others by at least this share of that: a rectangle longer than the exposure makes
#: the band as long as itself. Under LED strobes at two powers (2-3 ms over 1 ms exposures,
#: in either world) such bands were 0.93-1.04 of it longer, 5-14 robust sigmas of lengths
#: that the short pulses scatter; a decay read as long, 0.3 or less.
PULSE_LENGTH_SHARE = 0.5


@dataclass(frozen=True)
class Edges:
    """Matched band edges, arrays of shape (n_edges,).

    Attributes
    ----------
    camera : int array
        Index into :attr:`Measurement.cameras`.
    flash : int array
        Flash number, 0..n_flashes-1; every flash is seen by at least two cameras.
    event : int array
        The detector's event number of the edge (as in the events table).
    frame : int array
        Decoded frame index of the edge.
    row : float array
        Stored-image row of the edge (sub-row).
    trailing : bool array
        Trailing edge in the readout direction the detection was told.
    saturated : bool array
        The edge's band clipped at white (:data:`~flashsync.events.Flag.SATURATED`).
    excess_ms : float array
        How much longer the edge's band is than the median of its camera's bands of its kind
        (:func:`_length_excess_ms`), ms, where that is more than :data:`WIDE_BAND_SIGMAS`
        robust standard deviations of the camera's band lengths or as long as its pulse
        outlasts the exposure (:data:`PULSE_LENGTH_SHARE`): a widened band; else 0.
    clip_ms : float array
        For an edge of a band clipped at white, how much longer its band is than the median
        of its camera's clipped bands of its kind (:func:`_length_excess_ms`), ms: the deeper
        the clip, the longer the band and the farther out its edges; else 0.
    split : bool array
        The edge's band is split across two frames (its kind for :attr:`clip_ms`).
    """

    camera: np.ndarray
    flash: np.ndarray
    event: np.ndarray
    frame: np.ndarray
    row: np.ndarray
    trailing: np.ndarray
    saturated: np.ndarray
    excess_ms: np.ndarray
    clip_ms: np.ndarray
    split: np.ndarray

    def __len__(self) -> int:
        return len(self.camera)


@dataclass(frozen=True)
class Measurement:
    """Everything the workflow compares the model with.

    Attributes
    ----------
    cameras : tuple of CameraDetection
        Cameras tied to the reference by shared flashes, in input order, in the readout
        direction each detection was told.
    reference : int
        Index of the reference camera (its clock is the global clock).
    edges : Edges
    noise_ms : float
        Std of one edge's time, ms, from the scatter of band lengths in rows within each
        camera, whatever the clocks: bands with both edges in one frame are all as long
        (the exposure over the time per row), and so are bands split across two frames
        (shorter by the hidden rows); NaN without three bands of a kind. Bands clipped at
        white are left out (their length varies with the clip: the saturation effect's
        evidence, not noise), and so are widened bands (:attr:`Edges.excess_ms`: the pulse
        shape's; one of 1.33 ms, 19 robust sigmas, made a camera's noise 0.25 ms, four
        times its other bands', and hid its widened edges in it). Errors common to both
        edges of a band do not show in its length, so this is a lower bound (per camera, not
        quite: :attr:`camera_noise_ms`).
    camera_noise_ms : float array of shape (n_cameras,)
        The same per camera (its own unclipped, unwidened bands), shrunk towards :attr:`noise_ms` as
        ``sync``'s solve shrinks its groups' scales (the pooled noise counts as
        :data:`~flashsync.solve.POOLED_EQUATIONS` of the camera's band lengths: three bands
        as long as each other to 0.025 rows made the shipped sample's cam3 claim a noise of
        0.0016 ms); :attr:`noise_ms` where a camera has no three unclipped bands of a kind.
    warnings : tuple of str
        Cameras left out and why.
    flicker : tuple of (Flicker or None)
        Per camera, the rolling mains flicker whose period in rows times its rows
        (:func:`~flashsync.pipeline.mains_flicker`); None where it saw none to trust (the
        workflow also sets None where ``sync`` finds the events contradict it:
        :attr:`~flashsync.pipeline.SyncReport.distrusted_flicker`).
    free_drift : frozenset of int
        Cameras whose drift is fitted without ``sync``'s drift prior, as ``sync`` solved them
        (:func:`~flashsync.diagnose.workflow.in_sync_shape`).
    """

    cameras: tuple[CameraDetection, ...]
    reference: int
    edges: Edges
    noise_ms: float
    camera_noise_ms: np.ndarray
    warnings: tuple[str, ...] = ()
    flicker: tuple[Flicker | None, ...] = ()
    free_drift: frozenset[int] = frozenset()
    _clocks: dict = field(default_factory=dict, repr=False, compare=False)
    _stamp_nll: dict = field(default_factory=dict, repr=False, compare=False)

    def frame_clock(self, camera: int, count_gaps: bool, least_squares: bool) -> FrameClock:
        """The camera's frame clock with those parts switched on (never smoothed), fitted once."""
        key = (camera, count_gaps, least_squares)
        if key not in self._clocks:
            self._clocks[key] = fit_frame_clock(
                self.cameras[camera].frame_times_ms, count_gaps=count_gaps, least_squares=least_squares, smoothing=False
            )
        return self._clocks[key]

    def stamp_nll(self, camera: int, count_gaps: bool, least_squares: bool) -> float:
        """Negative log-likelihood of the camera's stamps about that frame clock
        (:meth:`frame_clock`) under a Cauchy distribution of their own maximum-likelihood
        scale (:func:`~flashsync.robust.cauchy_scale`), computed once."""
        key = (camera, count_gaps, least_squares)
        if key not in self._stamp_nll:
            residual = self.frame_clock(*key).residual_ms
            self._stamp_nll[key] = cauchy_nll(residual, cauchy_scale(residual))
        return self._stamp_nll[key]

    @cached_property
    def readout_groups(self) -> tuple[tuple[int, ...], ...]:
        """The groups of two or more camera indices whose weak priors on their time per row
        ``sync``'s solve correlates (:func:`~flashsync.pipeline.shared_readouts`: one size and
        frame rate, and no rolling flicker to time their rows), found once."""
        told = {camera.camera for c, camera in enumerate(self.cameras) if np.isfinite(self.flicker_row_time_ms(c)[0])}
        return shared_readouts(list(self.cameras), told)

    @property
    def n_flashes(self) -> int:
        return int(self.edges.flash.max()) + 1

    def flicker_row_time_ms(self, camera: int) -> tuple[float, float]:
        """The time per row the camera's rolling mains flicker tells and its standard
        deviation (:func:`~flashsync.pipeline.flicker_row_time_ms`, as ``sync``'s prior), ms;
        NaN, NaN where the camera saw no such flicker."""
        flicker = self.flicker[camera] if self.flicker else None
        return flicker_row_time_ms(flicker) if flicker is not None else (float("nan"), float("nan"))


def measure(
    detections: Sequence[CameraDetection], reference: str | None = None, paired_by: SyncModel | None = None
) -> Measurement:
    """Pair the bands of all cameras into flashes and collect their edges.

    Parameters
    ----------
    detections : one per camera, from :func:`flashsync.pipeline.detect_videos`.
    reference : camera whose clock is the global clock; default the first.
    paired_by : ``sync``'s model of the same detections, whose pairing is taken; None where
        ``sync`` cannot solve them (the workflow's own pairing).

    Raises
    ------
    InputError
        An unknown reference.
    NotEnoughDataError
        Fewer than two cameras, no camera sharing at least
        :data:`MIN_SHARED_FLASHES` flashes with the reference (or, paired by ``sync``, every
        camera that would doubted), or no clean band shared.
    """
    names = [d.camera for d in detections]
    if len(names) < 2:
        raise NotEnoughDataError(
            f"diagnose needs videos of two or more cameras, got {len(names)}; give every camera's video"
        )
    reference = reference or names[0]
    if reference not in names:
        raise InputError(
            f"{reference}: no such camera among {', '.join(names)}; the reference must be one of them",
            parameter="reference",
        )
    doubted: dict[str, float] = {}
    if paired_by is None:
        matching, pulses = _own_pairing(detections)
    else:
        pulses = {d.camera: _pulses(d) for d in detections}
        tolerance = match_tolerance_ms([median_step_ms(d.frame_times_ms) for d in detections], True)
        doubted = _doubted(paired_by, tolerance)
        sure = {name: mine for name, mine in pulses.items() if name not in doubted}
        matching = Matching({}, _sync_flashes(paired_by, sure, tolerance))
    tied = matching.tied_to(reference)
    kept = [d for d in detections if d.camera in tied]
    if len(kept) < 2 and doubted:
        raise NotEnoughDataError(
            f"sync's flashes of {', '.join(doubted)} line up with {reference}'s at another shift about as well "
            f"(times off by up to {max(doubted.values()):.1f} ms), so which flashes they share is not known; "
            "sync them with --anchor CAMERA:EVENT (one flash both saw) instead"
        )
    if len(kept) < 2:
        raise NotEnoughDataError(
            f"no camera shares at least {MIN_SHARED_FLASHES} flashes with {reference}; "
            "check that the videos overlap in time and saw the same flashes"
            + another_reference(matching, names, reference)
        )
    clean = Matching({}, {key: flash for key, flash in matching.flashes.items() if pulses[key[0]].clean[key[1]]})
    tied_clean = clean.tied_to(reference)
    warnings = tuple(_left_out(d, paired_by, doubted) for d in detections if d.camera not in tied)
    warnings += tuple(
        f"{d.video}: no band of it with both edges clean (inside the image, its pulse within its exposure) ties it "
        "to the reference's; left out (sync ties it by its other edges)"
        for d in kept
        if d.camera not in tied_clean
    )
    kept = [d for d in kept if d.camera in tied_clean] if len(tied_clean) > 1 else kept
    cameras = tuple(kept)
    pulses = [pulses[d.camera] for d in kept]
    excess = [_length_excess_ms(camera, mine) for camera, mine in zip(cameras, pulses)]
    widening = [_widening_ms(camera, mine, e) for camera, mine, e in zip(cameras, pulses, excess)]
    edges = _edges(pulses, matching.flashes, cameras, widening, [np.where(np.isfinite(e), e, 0.0) for e in excess])
    if len(edges) == 0:
        raise NotEnoughDataError(
            "no flash band with both edges inside the image is seen by two cameras; "
            "record more flashes, away from the top and bottom of the image"
        )
    unclipped = [
        e[np.isfinite(e) & ~mine.events.has_flag(Flag.SATURATED)[mine.bands.leading] & (wide == 0)]
        for e, mine, wide in zip(excess, pulses, widening)
    ]
    pooled = _edge_noise_ms(np.concatenate(unclipped))
    own = np.array([_edge_noise_ms(d) for d in unclipped])
    counts = np.array([d.size for d in unclipped], dtype=np.float64)
    shrunk = np.sqrt((counts * own**2 + POOLED_EQUATIONS * pooled**2) / (counts + POOLED_EQUATIONS))
    return Measurement(
        cameras,
        [c.camera for c in cameras].index(reference),
        edges,
        pooled,
        np.where(np.isfinite(own), shrunk, pooled),
        warnings,
        tuple(mains_flicker(cameras)),
    )


def _left_out(detection: CameraDetection, paired_by: SyncModel | None, doubted: dict[str, float]) -> str:
    """The warning for a camera no flash ties to the reference."""
    if detection.camera in doubted:
        return (
            f"{detection.video}: sync's flashes line up at another shift about as well (its times may be off by up "
            f"to {doubted[detection.camera]:.1f} ms); left out"
        )
    if paired_by is not None and detection.camera not in paired_by.cameras:
        return f"{detection.video}: sync ties it to no other camera (flashsync sync says why); left out"
    return f"{detection.video}: shares fewer than {MIN_SHARED_FLASHES} flashes with the other cameras; left out"


def _own_pairing(detections: Sequence[CameraDetection]) -> tuple[Matching, dict[str, _Pulses]]:
    """The workflow's own pairing of the cameras' bands and their pulses, per camera, on the
    frame times it was made with (the module's docstring)."""
    names = [d.camera for d in detections]
    periods = [median_step_ms(d.frame_times_ms) for d in detections]
    matchings = []
    for readout_known in (True, False):
        tolerance = match_tolerance_ms(periods, readout_known)
        for times in product(*map(_frame_times_ms, detections)):
            pulses = {d.camera: _pulses(d.retimed(t)) for d, t in zip(detections, times)}
            strengths = {name: np.abs(pulses[name].strength) for name in names}
            matching = match_events({name: pulses[name].time_ms for name in names}, tolerance, strengths=strengths)
            matchings.append((len(matching.flashes), len(matchings), matching, pulses))
    _, _, matching, pulses = max(matchings)
    return matching, pulses


def _doubted(model: SyncModel, tolerance_ms: float) -> dict[str, float]:
    """The cameras whose times ``model`` doubts by more than ``tolerance_ms`` (``sync``'s
    matching tolerance) and by how much, ms: the largest standard deviation of its frame
    times, which holds how far another shift of its flashes would move them."""
    spreads = {name: float(np.max(camera.frame_std_ms, initial=0.0)) for name, camera in model.cameras.items()}
    return {name: spread for name, spread in spreads.items() if spread > tolerance_ms}


#: An event of ``sync``'s flashes is the band with an edge in its frame this close (rows) to
#: its row: the same edge, or the same edge as the camera's other reading found it.
SAME_EDGE_ROWS = 2.0


def _sync_flashes(model: SyncModel, pulses: dict[str, _Pulses], tolerance_ms: float) -> dict[tuple[str, int], int]:
    """``sync``'s pairing: ``(camera, band) -> flash`` for the bands of ``pulses`` (per
    camera) with an edge at an event of ``model``'s flashes (in its frame, its row within
    :data:`SAME_EDGE_ROWS`), but the events its solve puts more than ``tolerance_ms`` (its
    matching tolerance) from their flash: paired with another flash (random rig 416 with
    pre-flashes: one band 57.5 ms off its flash, an outlier of the solve)."""
    flashes = {}
    events = model.events
    for camera, flash, frame, row, residual in zip(
        events.camera, events.flash, events.frame, events.row, events.residual_ms
    ):
        if camera not in pulses or abs(residual) > tolerance_ms:
            continue
        mine = pulses[camera]
        edges = np.stack([mine.bands.leading, mine.bands.trailing])
        rows = np.where((edges >= 0) & (mine.events.frame[edges] == frame), mine.events.row[edges], np.inf)
        distance = np.abs(rows - row).min(axis=0)
        if distance.size and distance.min() <= SAME_EDGE_ROWS:
            flashes[(camera, int(np.argmin(distance)))] = int(flash)
    return flashes


def _frame_times_ms(detection: CameraDetection) -> list[np.ndarray]:
    """The frame times to pair the camera's bands with: its stamps and, where they change
    rate, the times at one rate throughout for each rate (the sensor may not have changed
    its rate with the stamps; :meth:`~flashsync.frame_clock.FrameClock.one_rate_alternatives`)."""
    clock = fit_frame_clock(detection.frame_times_ms, smoothing=False)
    return [detection.frame_times_ms] + [times for _, times in clock.one_rate_alternatives()]


@dataclass(frozen=True)
class _Pulses:
    """One camera's pulse events: their edges side by side, where they are and whether they
    are clean.

    Attributes
    ----------
    events : Events
        The camera's events.
    bands : Bands
        Its pulse events, ascending event number.
    time_ms : float array of shape (n_bands,)
        Approximate time of each band on the camera's own clock, ms: the mean of its visible
        edges' :func:`~flashsync.match.approximate_times_ms`.
    clean : bool array of shape (n_bands,)
        Both edges visible and at least :data:`EDGE_MARGIN_ROWS` inside the image, and not
        flagged ``long_pulse`` (its edges may be half the pulse's excess over the exposure
        off: ``sync`` leaves its length out and weighs its leading edge down).
    """

    events: Events
    bands: Bands
    time_ms: np.ndarray
    clean: np.ndarray

    @property
    def strength(self) -> np.ndarray:
        """Each band's strength (relative brightness change), shape (n_bands,)."""
        return self.events.strength[self.bands.first_edges()]


def _pulses(detection: CameraDetection) -> _Pulses:
    """The camera's pulse events, with their approximate times and whether they are clean."""
    events = detection.events
    bands = events.bands()
    bands = bands.take(events.band[bands.first_edges()] == Band.PULSE)
    times = approximate_times_ms(detection, events)
    lead, trail = bands.leading >= 0, bands.trailing >= 0
    time_ms = np.where(
        lead & trail,
        (times[bands.leading] + times[bands.trailing]) / 2,
        np.where(lead, times[bands.leading], times[bands.trailing]),
    )
    inside = (events.row >= EDGE_MARGIN_ROWS) & (events.row <= detection.height - 1 - EDGE_MARGIN_ROWS)
    outlasted = events.has_flag(Flag.LONG_PULSE)[bands.first_edges()]
    clean = lead & trail & inside[bands.leading] & inside[bands.trailing] & ~outlasted
    return _Pulses(events, bands, time_ms, clean)


def _edges(
    pulses: list[_Pulses],
    flash_of: dict[tuple[str, int], int],
    cameras: tuple[CameraDetection, ...],
    excess_ms: list[np.ndarray],
    kind_excess_ms: list[np.ndarray],
) -> Edges:
    """Both edges of every clean band that belongs to a flash of two or more kept cameras;
    ``excess_ms`` per camera and band its widening, ``kind_excess_ms`` its length over its
    kind's median (0 where unknown)."""
    camera, flash, event, frame, row, trailing, saturated, excess, clip, split = ([] for _ in range(10))
    for index, (named, mine, longer, over) in enumerate(zip(cameras, pulses, excess_ms, kind_excess_ms)):
        clipped = mine.events.has_flag(Flag.SATURATED)
        for band in np.flatnonzero(mine.clean):
            if (named.camera, band) not in flash_of:
                continue
            for is_trailing, edge in ((False, mine.bands.leading[band]), (True, mine.bands.trailing[band])):
                camera.append(index)
                flash.append(flash_of[(named.camera, band)])
                event.append(mine.events.event[edge])
                frame.append(mine.events.frame[edge])
                row.append(mine.events.row[edge])
                trailing.append(is_trailing)
                saturated.append(bool(clipped[edge]))
                excess.append(float(longer[band]))
                clip.append(float(over[band]) if clipped[edge] else 0.0)
                split.append(
                    bool(mine.events.frame[mine.bands.trailing[band]] != mine.events.frame[mine.bands.leading[band]])
                )
    keep, flash = shared_flashes(camera, flash)
    return Edges(
        np.asarray(camera, dtype=np.int64)[keep],
        flash,
        np.asarray(event, dtype=np.int64)[keep],
        np.asarray(frame, dtype=np.int64)[keep],
        np.asarray(row, dtype=np.float64)[keep],
        np.asarray(trailing, dtype=bool)[keep],
        np.asarray(saturated, dtype=bool)[keep],
        np.asarray(excess, dtype=np.float64)[keep],
        np.asarray(clip, dtype=np.float64)[keep],
        np.asarray(split, dtype=bool)[keep],
    )


def _length_excess_ms(camera: CameraDetection, mine: _Pulses) -> np.ndarray:
    """Each band's length minus the median length of the camera's clean bands that span the
    same number of frames and are clipped at white or not as it is (with at least three of
    them), ms, shape (n_bands,); NaN for a band that is not clean or has no such kind. Every
    clean band counts here, one whose edge a codec artefact moved too (:func:`_edge_noise_ms`
    leaves out the outliers), but one whose length is the camera's exposure to a millionth
    of a row: fitted at it (the exposure was read with pulses longer than it,
    :func:`~flashsync.ramp.common_width`), its length was not measured."""
    excess = np.full(len(mine.clean), np.nan)
    clean = np.flatnonzero(mine.clean)
    bands = mine.bands.take(mine.clean)
    frames = mine.events.frame[bands.trailing] - mine.events.frame[bands.leading]
    lengths = mine.events.row[bands.trailing] - mine.events.row[bands.leading]
    clipped = mine.events.has_flag(Flag.SATURATED)[bands.leading]
    fixed = np.abs(lengths - (np.nan if camera.exposure_rows is None else camera.exposure_rows)) < 1e-6
    for span, saturated in sorted({(int(f), bool(c)) for f, c in zip(frames, clipped)}):
        kind = (frames == span) & (clipped == saturated) & ~fixed
        if np.count_nonzero(kind) >= 3:
            rows = lengths[kind]
            scale = _plain_row_time_ms(camera) * np.sqrt(len(rows) / (len(rows) - 1))
            excess[clean[kind]] = (rows - np.median(rows)) * scale
    return excess


def _plain_row_time_ms(camera: CameraDetection) -> float:
    """The plain model's time per row: the camera's median frame step / its height, ms."""
    return median_step_ms(camera.frame_times_ms) / camera.height


def _widening_ms(camera: CameraDetection, mine: _Pulses, excess_ms: np.ndarray) -> np.ndarray:
    """Each band's excess length ``excess_ms`` (:func:`_length_excess_ms`) where it is more
    than :data:`WIDE_BAND_SIGMAS` robust standard deviations of the camera's (all 0 where
    they do not scatter), or at least :data:`PULSE_LENGTH_SHARE` of how far its pulse
    outlasts the exposure, else 0, ms, shape (n_bands,)."""
    deviations = excess_ms[np.isfinite(excess_ms)]
    spread = mad_sigma(deviations) if deviations.size else 0.0
    event = mine.events.event[mine.bands.first_edges()]
    outlasting_ms = pulse_excess_rows(camera, event) * _plain_row_time_ms(camera)
    wide = ((spread > 0) & (excess_ms > WIDE_BAND_SIGMAS * spread)) | (
        (outlasting_ms > 0) & (excess_ms >= PULSE_LENGTH_SHARE * outlasting_ms)
    )
    return np.where(wide, excess_ms, 0.0)


def _edge_noise_ms(deviations: np.ndarray) -> float:
    """Std of one edge's time, ms, from band-length deviations (a length holds two edges'
    errors): their RMS, those beyond :data:`OUTLIER_BAND_SIGMAS` robust standard deviations
    (:func:`~flashsync.robust.mad_sigma`) left out; NaN without any."""
    if not deviations.size:
        return float("nan")
    spread = mad_sigma(deviations)
    kept = deviations[np.abs(deviations) <= OUTLIER_BAND_SIGMAS * spread] if spread > 0 else deviations
    return float(np.sqrt(np.mean(kept**2) / 2.0))
