"""A camera whose exposure changes while it records (auto exposure), found by its bands' lengths.

A flash band's leading edge is the first row whose exposure *ended* at the flash, its trailing
edge the first whose exposure *started* there, so the band is one exposure long whatever the
flash. Where the camera's exposure changes (a phone or action camera on auto exposure), the
lengths of its bands step with it, at one frame; the solve holds one exposure per camera, and
the trailing edges of the bands under another exposure put their flashes half the step off
(a 320x180 camera at 30 fps whose exposure went from 4 to 2 ms halfway: 0.62 ms RMS off the
truth). So the bands are split into spans of frames over which their lengths stay one
(:func:`exposure_spans`), and the trailing edges outside the span of the most bands are left
out before anything is solved (:func:`with_one_exposure`: the readout directions and frame
times are chosen on the edges too); their leading edges still time their flashes (the same
camera then 0.054 ms off). Only bands within one frame and fitted whole tell a length, so
a camera needs two of them on each side of a change, in frames apart, or, where the change
comes before its second band or after its last but one, that one band in a burst of its own
stepping from all the others (:func:`length_spans`). A band split across two frames tells
no length (the rows hidden between them are not seen), only a floor, its rows in sight:
where those outreach the exposure, its trailing edge is left out as well
(:func:`outreaching_splits`). Where one exposure fits such bands only as a short exposure
under longer pulses (the detector's other reading, :func:`~flashsync.ramp.common_width`),
the pulses step instead (:func:`pulse_spans`); where the other cameras see those flashes
shorter, the pipeline reads each band the other way round (:func:`with_pulses_as_exposures`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.ndimage import median_filter

from flashsync.detect import CameraDetection
from flashsync.events import Band, Bands, Edge, Events, Flag
from flashsync.model import readout_rows
from flashsync.robust import mad_sigma

#: Fewest bands on each side of a change of exposure, each in a frame of its own: bands in
#: one frame or the next are one burst of light (a pre-flash and its flash, a strobe's double
#: pulse), whose pulses may differ. A camera's first or last band may be a side alone
#: (:func:`_lone_end`).
MIN_SPAN_BANDS = 2
#: A change of exposure steps the mean length of the bands on either side of it by this many
#: standard errors of the difference of the two means at least: a length's standard deviation
#: (robust, from the differences of one band's length to the next's, or the lengths' RMS about
#: each side's median where that is less) times ``sqrt(1/n1 + 1/n2)`` for sides of ``n1`` and
#: ``n2`` bands. It was :data:`STEP_SIGMAS` of a length however many bands the sides held: on
#: the auto-exposure bench rendered again (`bench_rigs.py --seeds 412:428 --exposure-changes
#: 0.5`) random rig 413's cam1 (its reference; 6 rows, then 2.8: three bands and five, a step
#: of 2.6 rows in a noise of 0.59) made one span, and its rig was 0.55 ms RMS off the truth.
STEP_MEAN_SIGMAS = 5.0
#: ... a lone band at either end steps from the others' median by this many standard
#: deviations of a length (:func:`_lone_end`: a band the codec damaged looks as much like one) ...
STEP_SIGMAS = 8.0
#: ... and by this many rows (a step in the lengths under a row moves an edge by less than its
#: noise; a length within it of its span's median is of that span).
MIN_STEP_ROWS = 1.0
#: Neighbouring spans whose median lengths differ by less than this share of the longer are
#: one (auto exposure steps by a third of a stop, 26 %, or more; at two flash powers a
#: steady camera's last bands, measured against their flashes, came out 3.6 % longer).
MIN_STEP_SHARE = 0.15
#: Least robust standard deviation of a band's length, rows (bands fitted at one width
#: share their length exactly).
LENGTH_FLOOR_ROWS = 0.1
#: Share of each span's bands within :data:`INLIER_SIGMAS` of the lengths' noise of its
#: median length at least, or within 1/:data:`STEP_SIGMAS` of the step to its nearest
#: neighbour where that is more: lengths that scatter, as bands of flashes fired at two
#: powers do, are not one exposure and then another; lengths that stray a row from their
#: span's median across a step of 72 (random rig 546's cam3) are.
SPAN_INLIERS = 0.8
INLIER_SIGMAS = 3.0


@dataclass(frozen=True)
class ExposureSpan:
    """Frames over which a camera's bands share one length.

    Attributes
    ----------
    first_frame, last_frame : int
        Decoded frames of its first and last band.
    length_rows : float
        Its bands' median length, rows: the exposure in readout rows.
    n_bands : int
        Its bands.
    one_length : bool
        :data:`SPAN_INLIERS` of its bands within :data:`MIN_STEP_SHARE` of its median, or, of
        :func:`exposure_spans`, as long as a pulse that outlasts the exposure
        (:func:`pulse_excess_rows`): lengths that scatter more are of no one exposure (the
        span of a camera whose lengths do not step apart).
    """

    first_frame: int
    last_frame: int
    length_rows: float
    n_bands: int
    one_length: bool


def exposure_spans(detection: CameraDetection) -> list[ExposureSpan]:
    """The spans of frames, in frame order, over which the bands of the detection's reading in
    use share one length: the flash bands it fitted whole within one frame (the others'
    edges come from a band's parts and their lengths scatter: random rig 427's last three
    bands 4-13 rows long) but those fitted at the exposure it read its bands to share (pulses
    longer than it: their length is that exposure, not measured), split where their
    lengths step (:func:`length_spans`)."""
    return _lengths_and_spans(detection)[2]


def pulse_spans(detection: CameraDetection) -> list[ExposureSpan]:
    """The spans of frames, in frame order, over which the pulses of the bands that the
    detection's reading in use fitted at its exposure under longer pulses stay one
    (:func:`length_spans`): where they step, and the other cameras saw those flashes
    shorter, each is an exposure read the other way round, and the camera's exposure
    changes (random rig 542's cam8, 9.8 ms and then 3.9 under LED pulses of 0.2-1.9 ms,
    read as 0.35 ms under pulses of 45.7, 45.4, 18.3, 18.3 and 18.3 rows)."""
    return _spans(*_measured(detection, pulses=True)[:2])


def with_pulses_as_exposures(detection: CameraDetection) -> CameraDetection:
    """The detection with each band of :func:`pulse_spans` read the other way round, its
    pulse its exposure and the reading's exposure its pulse
    (:meth:`~flashsync.detect.CameraDetection.with_band_exposures`), the span of the most
    bands' its exposure, and the trailing edges outside that span left out (as
    :func:`with_one_exposure`)."""
    frames, pulses, events = _measured(detection, pulses=True)
    spans = _spans(frames, pulses)
    rows = np.zeros(len(detection.pulse_rows))
    rows[events] = pulses - detection.exposure_rows
    main = max(spans, key=lambda span: span.n_bands)
    return outside_left_out(detection.with_band_exposures(rows, main.length_rows), spans, main)


def outside_left_out(detection: CameraDetection, spans: list[ExposureSpan], main: ExposureSpan) -> CameraDetection:
    """The detection with the flash bands' trailing edges of its reading in use outside span
    ``main`` of ``spans`` left out (:func:`_outside`)."""
    side = "bottom_up" if detection.flipped else "top_down"
    return replace(detection, **{side: detection.events.take(~_outside(detection.events, spans, main))})


def length_scatter_rows(detection: CameraDetection, exposure_rows: float) -> float:
    """The RMS (rows) about ``exposure_rows`` of the lengths of the bands :func:`exposure_spans`
    takes, where they make one span whose lengths scatter (not
    :attr:`ExposureSpan.one_length`), else 0; bands as long as a pulse that outlasts the
    exposure (:func:`pulse_excess_rows`) are of it. Such lengths differ from flash to flash (two
    powers, pre-flashes) or step with a change their spans did not find (random rig 642's
    cam2 before a damaged last band was held to its neighbour), and the bands do not say
    which: on six auto-exposure benches 43 steady cameras and 45 changing ones had such
    lengths, the changing ones' exposure frame by frame 0.37 ms off (median) under a sigma
    of 0.06 ms."""
    lengths, excused, spans = _lengths_and_spans(detection)
    if len(spans) != 1 or spans[0].one_length:
        return 0.0
    return float(np.sqrt(np.mean((lengths[~excused] - exposure_rows) ** 2)))


def shorter_bands(detection: CameraDetection, exposure_rows: float) -> tuple[np.ndarray, np.ndarray]:
    """The frames and lengths (rows; shapes (n,)) of the bands :func:`exposure_spans` takes
    that are a step (:data:`MIN_STEP_SHARE` and :data:`MIN_STEP_ROWS`) shorter than
    ``exposure_rows``, where they all lie after the last band of that length (within
    :data:`MIN_STEP_SHARE`, but those as long as a pulse that outlasts it,
    :func:`pulse_excess_rows`) or all before the first: a band is one exposure long at
    least, so the exposure changed there (a lone band among bands of pulses that outlast
    the exposure shows no span), or they are misread. None where bands of that length lie
    on both sides of them, or nowhere: a band misread short (random rig 1044's cam1, a band
    of 15.5 rows amid eight of 27.6-28.9; on six benches, 22 of the 28 cameras with short
    bands amid bands of their exposure had them misread against the truth, 6 of the 12 with
    them beyond)."""
    frames, lengths, events = _measured(detection, pulses=False)
    short = (lengths < (1 - MIN_STEP_SHARE) * exposure_rows) & (exposure_rows - lengths >= MIN_STEP_ROWS)
    held = np.abs(lengths - exposure_rows) <= MIN_STEP_SHARE * exposure_rows
    held &= pulse_excess_rows(detection, events) == 0
    beyond = bool(held.any() and short.any()) and (
        frames[held].max() < frames[short].min() or frames[held].min() > frames[short].max()
    )
    return frames[short & beyond], lengths[short & beyond]


def _lengths_and_spans(detection: CameraDetection) -> tuple[np.ndarray, np.ndarray, list[ExposureSpan]]:
    """The lengths (rows, in frame order, shape (n,)) of the bands :func:`exposure_spans`
    takes, whether each is as long as a pulse that outlasts the exposure
    (:func:`pulse_excess_rows`: of the span's one length whatever its own), and their spans."""
    frames, lengths, events = _measured(detection, pulses=False)
    excused = pulse_excess_rows(detection, events) > 0
    return lengths, excused, _spans(frames, lengths, excused)


def _measured(detection: CameraDetection, pulses: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per flash band of the detection's reading in use fitted whole within one frame, in
    frame order (shape (n,) each): its frame, the length it tells (rows) and its event.
    Without ``pulses`` its own length, but not those fitted at the exposure the reading
    read its bands to share (under longer pulses: their length is that exposure); with
    ``pulses``, only those, and their pulses."""
    events, pulse_rows = detection.events, detection.pulse_rows
    if pulse_rows is None:
        return np.empty(0, np.int64), np.empty(0), np.empty(0, np.int64)
    bands = events.bands()
    whole = bands.take(bands.complete)
    lead, trail = whole.leading, whole.trailing
    lengths = np.abs(events.row[trail] - events.row[lead])
    band_pulses = pulse_rows[events.event[lead]]
    fitted = np.nan if detection.exposure_rows is None else detection.exposure_rows
    at_exposure = np.abs(lengths - fitted) < 1e-6
    usable = (
        (events.band[lead] == Band.PULSE)
        & (events.frame[lead] == events.frame[trail])
        & np.isfinite(band_pulses)
        & (at_exposure & (band_pulses > fitted) if pulses else ~at_exposure)
    )
    order = np.argsort(events.frame[lead][usable], kind="stable")
    measured = band_pulses if pulses else lengths
    return events.frame[lead][usable][order], measured[usable][order], events.event[lead][usable][order]


def _spans(frames: np.ndarray, lengths: np.ndarray, excused: np.ndarray | None = None) -> list[ExposureSpan]:
    """The :class:`ExposureSpan` of each of :func:`length_spans`; ``excused`` (shape of
    ``lengths``; default none) the bands that count as of its one length whatever theirs."""
    spans = []
    for a, b in length_spans(frames, lengths):
        median = float(np.median(lengths[a:b]))
        inlier = np.abs(lengths[a:b] - median) <= MIN_STEP_SHARE * median
        if excused is not None:
            inlier |= excused[a:b]
        spans.append(
            ExposureSpan(int(frames[a]), int(frames[b - 1]), median, b - a, bool(np.mean(inlier) >= SPAN_INLIERS))
        )
    return spans


def length_spans(frames: np.ndarray, lengths: np.ndarray) -> list[tuple[int, int]]:
    """The spans ``[a, b)`` of bands, given in frame order (``frames``, decoded frames, and
    ``lengths``, rows, shape (n,) each), over which the lengths stay one: one span where
    they do not step, none without :data:`MIN_SPAN_BANDS` bands. The lengths, each clipped
    to :data:`INLIER_SIGMAS` of the lengths' noise (from one band to the next) about the
    median of it and its neighbours (:func:`_local_medians`; a lone length that a codec
    moved leans on no split), are split in two between bands in frames apart where that
    leaves the least squared deviation from each side's mean, and again within each side,
    while the means step (:data:`STEP_MEAN_SIGMAS` and :data:`MIN_STEP_ROWS`); neighbours
    whose medians differ by less than :data:`MIN_STEP_SHARE` are one again; where some
    span's lengths then scatter (:data:`SPAN_INLIERS`, against the noise, the step to its
    neighbour or a row, :data:`MIN_STEP_ROWS`), they are taken as one. Where that leaves one
    span, its first or last band may be a span alone (:func:`_lone_end`).
    """
    if len(lengths) < MIN_SPAN_BANDS:
        return []
    noise = mad_sigma(np.diff(lengths), LENGTH_FLOOR_ROWS * np.sqrt(2.0)) / np.sqrt(2.0)
    local = _local_medians(lengths)
    clipped = np.clip(lengths, local - INLIER_SIGMAS * noise, local + INLIER_SIGMAS * noise)
    bursts = np.concatenate([[0], np.cumsum(np.diff(frames) > 1)])
    cuts = _merged(lengths, _cuts(clipped, bursts, 0, len(lengths), noise))
    medians = np.array([np.median(lengths[a:b]) for a, b in cuts])
    steps = np.abs(np.diff(medians))
    nearest = np.minimum(np.append(steps, np.inf), np.insert(steps, 0, np.inf))
    steady = all(
        np.mean(np.abs(lengths[a:b] - median) <= max(INLIER_SIGMAS * noise, step / STEP_SIGMAS, MIN_STEP_ROWS))
        >= SPAN_INLIERS
        for (a, b), median, step in zip(cuts, medians, nearest)
    )
    return cuts if steady and len(cuts) > 1 else _lone_end(frames, lengths)


def _local_medians(lengths: np.ndarray) -> np.ndarray:
    """Per length (rows, shape (n,)), the median of it and its neighbours; at either end, of
    the first or last three (of two, each one's neighbour). With an end's one neighbour
    counted twice, a wild neighbour held the end to itself: random rig 1064's cam2 (auto
    exposure) had bands of 10.6 and 7.1 rows (a misread band), then seven of 10.2-11.2 and
    three of 15.6-16.3; the first, held to 7.1, made a side of the first two whose lengths
    scatter, and every span was taken as one but the last band."""
    width = 2 * MIN_SPAN_BANDS - 1
    local = median_filter(lengths, size=width, mode="mirror")
    if len(lengths) >= width:
        local[0], local[-1] = np.median(lengths[:width]), np.median(lengths[-width:])
    return local


def _lone_end(frames: np.ndarray, lengths: np.ndarray) -> list[tuple[int, int]]:
    """One span of all the bands (``frames`` and ``lengths`` as :func:`length_spans`'), or two
    where the first band or else the last, in a burst of its own, steps from the median of
    all the others as a change does (by :data:`STEP_SIGMAS` of their noise from one band to
    the next, :data:`MIN_STEP_ROWS` and :data:`MIN_STEP_SHARE`): an exposure that changed
    before the camera's second band, or after its last but one. Over ten kept benches (877
    cameras: plain, fast readout, four of auto exposure, TTL flashes at two powers, the ten
    recipes twice), 44 of the 269 cameras whose exposure changes have such a band, and 6 of
    the 608 steady ones (a damaged band, a pre-flash's)."""
    n = len(lengths)
    ends = ((0, lengths[1:], frames[1] - frames[0]), (n - 1, lengths[:-1], frames[-1] - frames[-2]))
    for lone, others, apart in ends:
        if len(others) < MIN_SPAN_BANDS or apart <= 1:
            continue
        noise = mad_sigma(np.diff(others), LENGTH_FLOOR_ROWS * np.sqrt(2.0)) / np.sqrt(2.0)
        median = float(np.median(others))
        step = abs(float(lengths[lone]) - median)
        if step >= max(STEP_SIGMAS * noise, MIN_STEP_ROWS) and step >= MIN_STEP_SHARE * max(lengths[lone], median):
            return [(0, 1), (1, n)] if lone == 0 else [(0, n - 1), (n - 1, n)]
    return [(0, n)]


def _cuts(lengths: np.ndarray, bursts: np.ndarray, start: int, stop: int, noise: float) -> list[tuple[int, int]]:
    """``[start, stop)`` split in two between bursts (``bursts``: each band's, counted in frame
    order), :data:`MIN_SPAN_BANDS` or more on each side, where that leaves the least squared
    deviation from each side's mean, recursively, while the means step (:func:`length_spans`;
    ``noise``: a length's robust standard deviation, rows; the step is weighed against the
    sides' own RMS about their medians where that is less: a step between two clean sides
    then shows whatever noise the step put into ``noise``, while wild lengths on a side
    still hold it back, as a robust spread would not)."""

    def deviation(part: np.ndarray) -> float:
        return float(np.sum((part - part.mean()) ** 2))

    splits = [
        k
        for k in range(start + 1, stop)
        if bursts[k] != bursts[k - 1]
        and bursts[k - 1] - bursts[start] + 1 >= MIN_SPAN_BANDS
        and bursts[stop - 1] - bursts[k] + 1 >= MIN_SPAN_BANDS
    ]
    if not splits:
        return [(start, stop)]
    k = min(splits, key=lambda k: deviation(lengths[start:k]) + deviation(lengths[k:stop]))
    step = abs(float(lengths[k:stop].mean() - lengths[start:k].mean()))
    sides = np.concatenate([part - np.median(part) for part in (lengths[start:k], lengths[k:stop])])
    spread = max(float(np.sqrt(np.mean(sides**2))), LENGTH_FLOOR_ROWS)
    if step < max(STEP_MEAN_SIGMAS * min(noise, spread) * np.sqrt(1.0 / (k - start) + 1.0 / (stop - k)), MIN_STEP_ROWS):
        return [(start, stop)]
    return _cuts(lengths, bursts, start, k, noise) + _cuts(lengths, bursts, k, stop, noise)


def _merged(lengths: np.ndarray, cuts: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """``cuts`` with each pair of neighbours whose median lengths differ by less than
    :data:`MIN_STEP_SHARE` of the longer joined."""
    merged = [cuts[0]]
    for start, stop in cuts[1:]:
        before, after = np.median(lengths[slice(*merged[-1])]), np.median(lengths[start:stop])
        if abs(after - before) < MIN_STEP_SHARE * max(before, after):
            merged[-1] = (merged[-1][0], stop)
        else:
            merged.append((start, stop))
    return merged


def with_one_exposure(detection: CameraDetection) -> CameraDetection:
    """The detection with, in each of its readings, the flash bands' trailing edges that are
    not of its exposure left out: where that changes (:func:`exposure_spans`), those
    outside the span of the most bands, and those of bands split across two frames that
    outreach it (:func:`outreaching_splits`)."""
    readings = {}
    for side, flipped in (("top_down", False), ("bottom_up", True)):
        if getattr(detection, side) is not None:
            reading = detection.read_flipped(flipped)
            spans = exposure_spans(reading)
            other = np.isin(np.arange(len(reading.events)), outreaching_splits(reading).trailing)
            if len(spans) > 1:
                other |= _outside(reading.events, spans, max(spans, key=lambda span: span.n_bands))
            if other.any():
                readings[side] = reading.events.take(~other)
    return replace(detection, **readings) if readings else detection


def outreaching_splits(detection: CameraDetection) -> Bands:
    """The flash bands of the detection's reading in use that are split across two frames and
    whose rows in sight alone (from the leading edge to the frame's end, and from the next
    frame's start to the trailing edge) outreach its exposure (:func:`_exposure_or_longest_rows`)
    as a change does (:data:`MIN_STEP_SHARE` and :data:`MIN_STEP_ROWS`). A band is one
    exposure long, the rows hidden between frames counted, so such a band's exposure is
    longer: the camera's changed (random rig 546's reference, 114 rows and then 216, its four
    split bands 194 rows in sight). But not within the frames of the span of the most bands
    (:func:`length_spans`) where most of them lie within :data:`MIN_STEP_SHARE` of its median:
    amid bands of one exposure such a band is of it, its trailing edge read late on a
    pulse's tail in the next frame (the HD rig of ``tests/test_diagnose.py``); amid lengths
    that scatter (flashes at two powers, pre-flashes) nothing says so. Of 959 split
    bands over the ten kept benches of :func:`_lone_end`, 82 outreach so, every one on a
    camera whose exposure changed."""
    bands = detection.events.bands()
    bands = bands.take(bands.complete)
    events, lead = detection.events, bands.leading
    exposure = _exposure_or_longest_rows(detection, bands)
    if exposure is None:
        return bands.take(np.zeros(len(bands), dtype=bool))
    sight = _rows_between(detection, bands) + detection.height
    outreach = sight - exposure > np.maximum(MIN_STEP_SHARE * sight, MIN_STEP_ROWS)
    return bands.take(
        split_across_frames(events, bands) & outreach & ~_amid_one_exposure(detection, events.frame[lead])
    )


def split_across_frames(events: Events, bands: Bands) -> np.ndarray:
    """Boolean mask of ``bands`` (of ``events``): the flash bands split across two frames,
    the trailing edge in the frame after the leading edge's."""
    return (events.frame[bands.trailing] == events.frame[bands.leading] + 1) & (
        events.band[bands.leading] == Band.PULSE
    )


def _amid_one_exposure(detection: CameraDetection, frames: np.ndarray) -> np.ndarray:
    """Boolean mask of ``frames`` (decoded frames, shape (n,)): within the frames of the span
    of the detection's most bands (:func:`exposure_spans`) where that span is of one length
    (:attr:`ExposureSpan.one_length`; its bands as long as a pulse that outlasts the exposure
    count: LED strobes at two powers, 2-3 ms over a 1 ms exposure, gave a steady camera a
    quarter of such bands, and its one split band of 2.3 ms was taken for a change)."""
    main = max(exposure_spans(detection), key=lambda span: span.n_bands, default=None)
    if main is None or not main.one_length:
        return np.zeros(len(frames), dtype=bool)
    return (frames >= main.first_frame) & (frames <= main.last_frame)


def pulse_excess_rows(detection: CameraDetection, event: np.ndarray) -> np.ndarray:
    """How far (rows) the pulse each event's band was read with at the camera's exposure
    (:attr:`~flashsync.detect.CameraDetection.pulse_rows`) outlasts that exposure, where it
    does as a change outreaches it (:data:`MIN_STEP_SHARE`, :data:`MIN_STEP_ROWS`), else 0;
    shape of ``event`` (event numbers). Such a band may be as long as its pulse: a rectangle
    longer than the exposure widens it by that much (a pulse that decays does not)."""
    if detection.exposure_rows is None or detection.pulse_rows is None:
        return np.zeros(len(event))
    excess = detection.pulse_rows[event] - detection.exposure_rows
    return np.where(excess > max(MIN_STEP_SHARE * detection.exposure_rows, MIN_STEP_ROWS), excess, 0.0)


def _exposure_or_longest_rows(detection: CameraDetection, bands: Bands) -> float | None:
    """The camera's exposure, readout rows: the one its bands were read to share, else (fewer
    than three fitted whole) the longest of its unclipped flash bands within one frame (of
    ``bands``, complete ones; random rig 653's cam8: two of 127 rows, then four split across
    frames 223 rows in sight; not their median: rig 426's cam1 has bands of 162 and 326
    rows, and split ones of 312 and 306 in sight under its 326-row exposure), None with
    fewer than two."""
    if detection.exposure_rows is not None:
        return detection.exposure_rows
    events, lead, trail = detection.events, bands.leading, bands.trailing
    within = (events.frame[lead] == events.frame[trail]) & (events.band[lead] == Band.PULSE)
    within &= ~events.has_flag(Flag.SATURATED)[lead]
    lengths = np.abs(events.row[trail] - events.row[lead])[within]
    return float(np.max(lengths)) if len(lengths) >= MIN_SPAN_BANDS else None


def all_band_spans(detection: CameraDetection, row_time_ms: float) -> list[ExposureSpan]:
    """The spans of frames, in frame order, over which every flash band of the detection's
    reading in use that tells its exposure shares one length (rows at ``row_time_ms``, a
    solved time per row): those of :func:`exposure_spans` and those split across two frames,
    timed by the camera's frames (:func:`split_lengths_ms`), split where their lengths step
    (:func:`length_spans`). A camera whose exposure grew till most of its bands split shows
    its change only so (random rig 561's cam7: one band fitted whole, 5.9 ms, then three
    split, 13.7 ms)."""
    frames, lengths, _ = _measured(detection, pulses=False)
    events = detection.events
    bands = events.bands()
    bands = bands.take(bands.complete)
    split = bands.take(split_across_frames(events, bands))
    frames = np.concatenate([frames, events.frame[split.leading]])
    lengths = np.concatenate([lengths, split_lengths_ms(detection, split, row_time_ms) / row_time_ms])
    order = np.argsort(frames, kind="stable")
    return _spans(frames[order], lengths[order])


def split_lengths_ms(detection: CameraDetection, bands: Bands, row_time_ms: float) -> np.ndarray:
    """The length (ms) of each of the detection's ``bands`` split across two frames (its
    reading in use): from its leading edge's frame to the next, and its trailing edge's
    readout rows less its leading edge's at ``row_time_ms``; shape (len(bands),)."""
    frames = detection.events.frame[bands.leading]
    period = detection.frame_times_ms[frames + 1] - detection.frame_times_ms[frames]
    return period + _rows_between(detection, bands) * row_time_ms


def _rows_between(detection: CameraDetection, bands: Bands) -> np.ndarray:
    """Each band's trailing edge's readout row less its leading edge's, rows."""
    rows = readout_rows(detection.events.row, detection.height, detection.flipped)
    return rows[bands.trailing] - rows[bands.leading]


def _outside(events: Events, spans: list[ExposureSpan], main: ExposureSpan) -> np.ndarray:
    """Boolean mask of the events: the flash bands' trailing edges outside span ``main`` of
    ``spans`` (beyond its bands only where no other span lies that way: the frames between
    two spans' bands may have either exposure)."""
    first = main.first_frame if main is not spans[0] else -np.inf
    last = main.last_frame if main is not spans[-1] else np.inf
    inside = (events.frame >= first) & (events.frame <= last)
    return (events.edge == Edge.TRAILING) & (events.band == Band.PULSE) & ~inside
