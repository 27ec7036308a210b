"""The library API: detect events in videos, match them and solve for a :class:`SyncModel`.

The CLI is a thin layer over these functions; a notebook calls them the same way::

    detections = detect_videos(["cam1.mp4", "cam2.mkv", "cam3.mp4"])
    model, report = synchronize(detections)
    model.camera("cam2").t_global_ms(frame=120, row=200.5)

:func:`synchronize` runs four steps: each camera's frame clock (steady period behind
quantised stamps), the coarse matching of events across cameras, the choice of readout
direction of cameras where it is not given, and the joint robust solve.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from functools import cached_property
from itertools import combinations, compress, pairwise, product
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd

from flashsync.detect import (
    LONG_PULSE_EDGE_SIGMA,
    SATURATED_EDGE_SIGMA,
    CameraDetection,
    DetectorSettings,
    detect_video,
)
from flashsync.errors import FlashsyncError, InputError, NotEnoughDataError, UntiedReferenceError
from flashsync.events import Band, Bands, Edge, Events, Flag
from flashsync.exposure_changes import (
    MIN_STEP_ROWS,
    MIN_STEP_SHARE,
    ExposureSpan,
    all_band_spans,
    exposure_spans,
    length_scatter_rows,
    outreaching_splits,
    outside_left_out,
    pulse_spans,
    shorter_bands,
    split_across_frames,
    split_lengths_ms,
    with_one_exposure,
    with_pulses_as_exposures,
)
from flashsync.flicker import Flicker
from flashsync.frame_clock import FrameClock, fit_frame_clock
from flashsync.io.timestamps import load_timestamps
from flashsync.jackknife import flash_scatter, moved_scatter, rival_scatter, split_left_out_scatter, split_scatter
from flashsync.likelihood import (
    SCORE_MIN_SIGMA_MS,
    HeldClock,
    ReadingEdges,
    edge_log_likelihood,
    held_log_likelihood,
    residual_log_likelihood,
)
from flashsync.match import (
    MIN_SHARED_FLASHES,
    MIN_TOLERANCE_MS,
    NOMINAL_HIDDEN_ROWS,
    Matching,
    PairAlignment,
    approximate_times_ms,
    match_events,
    match_tolerance_ms,
    nominal_row_time_ms,
    parse_anchors,
    shared_flashes,
)
from flashsync.model import MATCHED_EVENT_COLUMNS, CameraClock, HeldExposure, SyncModel, readout_rows
from flashsync.ramp import MAX_BLUR
from flashsync.segments import SEGMENT_MS
from flashsync.solve import DRIFT_PRIOR_STD, CameraSolution, Observations, Priors, Solution, solve_with_drift_model
from flashsync.timestamps import median_step_ms, shortest_step_ms

#: Fastest readout the weak prior on T_row spans, a share of the frame period: the prior
#: (:func:`row_time_prior_ms`) spreads a camera's readout evenly from this to the whole
#: frame. A sensor built for 50-120 fps run at 25-30 reads its rows in a third to three
#: quarters of the frame period, a stacked sensor in a tenth to a third of it. The nominal
#: +-8 % and then +-35 % (to 2026-12-02) centred the prior on the slowest readout, which
#: only a sensor reading over its whole frame has: on random rigs reading in 25-45 % of their
#: frame, cameras whose flashes left their time per row to the prior came out 1-29 ms off
#: (README, "Sensors that read out in a part of their frame").
FASTEST_READOUT = 0.1

#: Part of a camera's exposure error (ms) that all its flashes share and neither the solve's
#: residuals nor the flashes left out show: its tone curve, codec and the pulse shape bend its
#: trailing edges against its leading ones alike. Over the 210 exposures of the kept random
#: rigs 0-29 (`benchmarks/bench_rigs.py`) the errors scatter 0.037 ms (mean 0.01) against a
#: median sigma of 0.025 ms without it (error / sigma RMS 1.5, 84 % within 2 sigma); with it
#: 0.98 and 93 %, in milliseconds whatever the time per row (0.043-0.22 ms).
EXPOSURE_FLOOR_MS = 0.02
#: The tone curve a camera may encode light through (sRGB, gamma: nearly every consumer
#: camera) compresses the top of a band's light, so both half-level crossings move out and
#: the band reads longer than the exposure; a linear sensor's does not, and which a camera
#: is its bands do not tell safely (README, "A tone curve moves every edge out"). Its
#: exposure's standard deviation takes this share of the widening a gamma of
#: :data:`TONE_GAMMA` would give its bands (:func:`_tone_widening_ms`). The exposure errors
#: of 61 tone-curved cameras (six of the issue's recipes at seeds 1 and 2, three rigs under
#: 1-2 ms LED pulses) over that widening: median 0.7, 90 % under 1.3, at most 1.7; of six
#: linear ones at most 0.35. With this share the recipes' exposure error/sigma RMS 1.30 and
#: 1.68 -> 0.70 and 0.86 (84.6-88.5 -> 100 % within 2 sigma), random rigs 0-11's 1.24 -> 1.00.
#: Each edge moves out by half the widening, so a camera's times come late by half its
#: exposure's error; the same share of that half is in their standard deviation
#: (:meth:`_Attempt.tone_shift_std_ms`).
TONE_WIDENING_SHARE = 0.75
#: The exponent of light in a tone-curved pixel value that :func:`_tone_widening_ms` assumes.
TONE_GAMMA = 2.2

#: A camera whose bands read as a short exposure under pulses longer than it
#: (:func:`~flashsync.ramp.common_width`) was read the other way round where the other cameras
#: see :data:`MIN_PULSE_FLASHES` or more of its flashes shorter than it does, each by
#: :data:`SHORTER_PULSE_SHARE` of its pulse or more, and its pulses of those flashes agree
#: (:data:`PULSES_AGREE`) on a length :data:`MIN_EXPOSURE_GAIN` times its exposure or more: a
#: band is the exposure convolved with the pulse, and blur mimics a short rectangle's ramps, so
#: each band of a short flash was read as a pulse as long as the exposure
#: (:func:`_exposures_by_pulses`). rig-415's 9.4-row cam5 at two flash powers
#: (`bench_rigs.py --seeds 412:428 --flash-powers 0.3`), read as 1.2 rows (0.11 ms), saw 8
#: flashes 0.84 ms long (median) that the others saw 0.3 ms long or less. Over its 117
#: cameras, the same 16 rigs with their own pulses and 29 pairs at two powers, no camera read
#: right passed the first two tests; of the five misread that did, the two whose pulses
#: scatter by 0.67 and 0.91 of their median (the others' by 0.02-0.19) would have been read
#: as 0.58 and 1.22 ms against 0.5.
SHORTER_PULSE_SHARE = 0.5
MIN_EXPOSURE_GAIN = 1.5
PULSES_AGREE = 0.25
MIN_PULSE_FLASHES = 3

#: A camera's pulses (:attr:`~flashsync.detect.CameraDetection.pulse_rows`) are fitted at the
#: exposure its bands share; they count in :func:`_exposures_the_others_tell` only where the
#: solve's exposure is within this share of it. A 0.5 ms camera whose bands read as 1.53 ms
#: (the solve: 0.61) saw every flash shorter than its exposure, and the other camera of the
#: pair was read as 1.6 ms against 0.5, its times 0.5 ms off.
READINGS_AGREE = 0.25

#: Two more guards in :func:`_exposures_the_others_tell`, for the others' pulses measured by
#: ramps that the fit's blur can absorb: a flash counts as seen shorter only where no other
#: camera sees it :data:`PULSES_AGREE` as long or longer, and a camera is read the other way
#: round only where its bands' shared exposure is this many readout rows or fewer (the ramp
#: fits' largest blur, :data:`~flashsync.ramp.MAX_BLUR`; the misread exposures were 1.2-1.7
#: rows). rig-4 of `bench_diagnose.py --seeds 0:12` has a 0.65 ms cam5 read right at 14.8
#: rows whose 1.0-1.9 ms pulses two long exposures saw 0.06-0.47 ms long (their ramps taken
#: for blur); without the guards it was read as 1.68 ms. A camera the others' flashes read
#: the other way round above this many rows keeps its reading, the other one in its sigma
#: (:func:`_unturned_exposures_ms`).
MAX_TURNED_ROWS = MAX_BLUR

#: Shares of the nominal time per row at which a camera that matching at the nominal leaves
#: untied is matched again (:func:`_tie_fast_readouts`): a sensor that reads its rows in part
#: of its frame period puts its lower rows' flashes up to half a frame later than the nominal
#: does, beyond the matching tolerance.
FAST_READOUT_SHARES = (0.8, 0.65, 0.5, 0.35)

#: Fewest sync events (:func:`_sync_events`) a camera needs to be matched at all.
MIN_SYNC_EVENTS = 2


def detect_videos(
    paths: Sequence[str | Path],
    flipped: Sequence[str] = (),
    estimate_readout: bool = True,
    settings: DetectorSettings | None = None,
    progress: Callable[[str, int], Callable[[int], None]] | None = None,
    timestamps: dict[str, Path] | None = None,
    scheduler: str | None = None,
    segment_ms: float = SEGMENT_MS,
) -> list[CameraDetection]:
    """Detect events in each video (camera names = file stems, which must be unique).

    Parameters
    ----------
    paths : video files.
    flipped : cameras known to be mounted upside down.
    estimate_readout : read the other cameras both ways up, so that :func:`synchronize` can
        find an upside-down camera (as ``flashsync sync`` does); False reads them top-down
        only (``flashsync detect``, which writes one reading).
    progress : ``progress(camera, n_frames_hint)`` may return a callback taking frames decoded.
    timestamps : per camera, a CSV of frame timestamps (``t_ms``, or 90 kHz ``rtp``, one row
        per decoded frame) used instead of the container's (see :func:`~flashsync.io.timestamps.load_timestamps`).
    scheduler : ``tcp://HOST:PORT`` of a Dask scheduler or ``local:N`` (N worker processes):
        the videos are decoded there in segments of ``segment_ms`` (ms), with the same
        events (:mod:`flashsync.cluster`; needs the ``cluster`` extra).

    Without a scheduler, videos are decoded in parallel threads, one per core (decoding and
    the compiled row kernel release the GIL).
    """
    paths = [Path(p) for p in paths]
    stems = [p.stem for p in paths]
    duplicates = sorted({s for s in stems if stems.count(s) > 1})
    if duplicates:
        raise InputError(
            f"camera names come from file stems and {', '.join(duplicates)} is given twice; rename one of the videos"
        )
    timestamps = timestamps or {}
    for parameter, names in (("flipped", flipped), ("timestamps", timestamps)):
        unknown = sorted(set(names) - set(stems))
        if unknown:
            raise InputError(f"{', '.join(unknown)}: no such camera among {', '.join(stems)}", parameter=parameter)
    stamps = {camera: load_timestamps(path) for camera, path in timestamps.items()}
    cancelled = threading.Event()

    def watched(camera: str, total: int) -> Callable[[int], None]:
        """The progress callback, which also stops a decoding thread once the run is cancelled."""
        update = progress(camera, total) if progress else None

        def step(frames: int) -> None:
            if cancelled.is_set():
                raise _Cancelled()
            if update is not None:
                update(frames)

        return step

    def direction(path: Path) -> bool | None:
        return True if path.stem in flipped else (None if estimate_readout else False)

    def retimed(path: Path, detection: CameraDetection) -> CameraDetection:
        if path.stem not in stamps:
            return detection
        if len(stamps[path.stem]) != len(detection.frame_times_ms):
            raise InputError(
                f"{timestamps[path.stem]}: {len(stamps[path.stem])} timestamps for the "
                f"{len(detection.frame_times_ms)} frames of {path}; give one row per decoded frame"
            )
        return detection.retimed(stamps[path.stem])

    if scheduler is not None:
        from flashsync.cluster import detect_on_cluster

        found = detect_on_cluster(scheduler, paths, [direction(p) for p in paths], settings, progress, segment_ms)
        return [retimed(path, detection) for path, detection in zip(paths, found)]

    def detect(path: Path) -> CameraDetection:
        return retimed(path, detect_video(path, flipped=direction(path), settings=settings, progress=watched))

    with ThreadPoolExecutor(max_workers=max(1, min(len(paths), os.cpu_count() or 1))) as pool:
        try:
            return list(pool.map(detect, paths))
        except BaseException:  # an error or an interrupt: the other threads stop at their next frame
            cancelled.set()
            pool.shutdown(cancel_futures=True)
            raise


class _Cancelled(Exception):
    """Raised in a decoding thread once :func:`detect_videos` is cancelled."""


def all_events(detections: Sequence[CameraDetection]) -> Events:
    """The events of all cameras (in their readings in use), one camera after the other: the
    events table ``flashsync detect`` writes (:func:`~flashsync.io.events.save_events`)."""
    return Events.concat([d.events for d in detections])


@dataclass
class SyncReport:
    """What :func:`synchronize` found besides the model.

    Attributes
    ----------
    alignments : accepted pair alignments (camera a, camera b) -> coarse map and matches.
    frame_clocks : per camera, the frame clock found behind its stamps.
    frame_times : per camera whose stamps change rate, which frame times the flashes chose
        (:func:`_best_frame_times`).
    flipped_found : cameras found to read bottom-up (upside down), by the flashes or by their
        rolling flicker's roll.
    free_drift : cameras whose clock drift was solved without the drift prior: their events
        contradict it (:func:`~flashsync.solve.solve_with_drift_model`).
    distrusted_flicker : cameras whose rolling mains flicker's time per row the events
        contradict: no prior is taken from it (:func:`_contradicted_flicker`).
    longer_exposures : cameras read the other way round by the flashes the others see
        (:func:`_exposures_by_pulses`): the readout rows by which their exposure was made
        longer in the reading the model uses
        (:meth:`~flashsync.detect.CameraDetection.with_longer_exposure`).
    stepped_exposures : cameras read the other way round band by band, their pulses that
        step while they record their exposures
        (:func:`~flashsync.exposure_changes.with_pulses_as_exposures`).
    warnings : cameras left out and why; stamps that follow no steady clock or change rate;
        datasheet times per row the events contradict.
    sigma_ms : robust residual scale of the solve, ms.
    """

    alignments: dict[tuple[str, str], PairAlignment] = field(default_factory=dict)
    frame_clocks: dict[str, FrameClock] = field(default_factory=dict)
    frame_times: dict[str, str] = field(default_factory=dict)
    flipped_found: list[str] = field(default_factory=list)
    free_drift: list[str] = field(default_factory=list)
    distrusted_flicker: list[str] = field(default_factory=list)
    longer_exposures: dict[str, float] = field(default_factory=dict)
    stepped_exposures: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    sigma_ms: float = float("nan")


def synchronize(
    detections: Sequence[CameraDetection],
    reference: str | None = None,
    row_times: dict[str, float] | None = None,
    anchors: Sequence[str] = (),
) -> tuple[SyncModel, SyncReport]:
    """Match events across cameras and solve every camera's clock.

    Parameters
    ----------
    detections : one per camera (from :func:`detect_videos`); a detection read both ways
        up has its readout direction chosen here: the way its rolling mains flicker rolls
        where that tells (:meth:`~flashsync.detect.CameraDetection.read_as_rolled`), else the
        way that explains the flashes best.
    reference : camera whose clock is the global clock; default the first, or where the first
        shares too few flashes with the others to be tied to them, or the cameras it leaves
        out are tied among themselves in a larger group, the camera with the most matched
        events of the largest group tied among themselves (with a warning).
    row_times : known time per row (ms) per camera, e.g. from a datasheet.
    anchors : ``CAMERA:EVENT`` strings naming events that are one flash (optional); EVENT is
        the detector's event number, as in the events table and the model's events.

    Events are matched at each camera's nominal time per row; a sensor that reads its rows
    in part of its frame period may then be left untied, and is matched again at shorter
    ones (:func:`_tie_fast_readouts`), in every attempt the readout search makes.
    """
    names = [d.camera for d in detections]
    if reference is not None and reference not in names:
        raise InputError(
            f"{reference}: no such camera among {', '.join(names)}; the reference must be one of them",
            parameter="reference",
        )
    check_row_times(row_times or {}, names)
    check_anchors(anchors)
    try:
        model, report = _synchronized(detections, reference or names[0], row_times, anchors)
    except UntiedReferenceError as untied:
        if reference is not None or untied.instead is None:
            raise
        model, report = _synchronized(detections, untied.instead, row_times, anchors)
        report.warnings.insert(
            0,
            f"{detections[0].video}: the first video, the reference unless one is given, shares too few flashes "
            f"with the other cameras to be tied to them; {untied.instead}'s clock is the global clock instead (of "
            "the cameras tied among themselves, the one with the most matched flashes; name the reference to "
            "choose another)",
        )
        return model, report
    return (
        (model, report)
        if reference is not None
        else _on_the_largest_group(detections, model, report, row_times, anchors)
    )


def _on_the_largest_group(
    detections: Sequence[CameraDetection],
    model: SyncModel,
    report: SyncReport,
    row_times: dict[str, float] | None,
    anchors: Sequence[str],
) -> tuple[SyncModel, SyncReport]:
    """``model`` and ``report``, solved on the first video's clock, or where the cameras they
    leave out are tied among themselves in a larger group (on a reference of their own), the
    solve on the clock of that group's camera with the most matched events, with a warning
    first. Random rig 98 of fast readouts had its first video tied to one camera by three
    flashes and the other eight left out, though they share five to eight among themselves;
    on one of theirs nine are tied."""
    best = (model, report)
    left = [d.camera for d in detections if d.camera not in model.cameras]
    while len(left) > len(best[0].cameras):  # only there may a larger group lie
        try:
            trial = _synchronized(detections, left[0], row_times, anchors)
        except FlashsyncError:
            left = left[1:]
            continue
        if len(trial[0].cameras) > len(best[0].cameras):
            best = trial
        left = [name for name in left if name not in trial[0].cameras]
    if best[0] is model:
        return model, report
    busiest = best[0].events.camera.value_counts().idxmax()  # as the untied first video's stand-in is chosen
    if busiest != best[0].reference:
        best = _synchronized(detections, busiest, row_times, anchors)
    best[1].warnings.insert(
        0,
        f"{detections[0].video}: the first video, the reference unless one is given, is tied to "
        f"{len(model.cameras) - 1} of the {len(detections) - 1} other cameras only; {best[0].reference}'s clock "
        f"ties {len(best[0].cameras) - 1} and is the global clock instead (of the largest group of cameras tied "
        "among themselves, the one with the most matched flashes; name the reference to choose another)",
    )
    return best


def _synchronized(
    detections: Sequence[CameraDetection],
    reference: str,
    row_times: dict[str, float] | None,
    anchors: Sequence[str],
) -> tuple[SyncModel, SyncReport]:
    """:func:`synchronize` on checked arguments."""
    names = [d.camera for d in detections]
    as_rolled = [d.read_as_rolled() for d in detections]  # where its flicker's roll tells its readout
    rolled = [d.camera for d, read in zip(detections, as_rolled) if read is not d]
    detections = as_rolled
    report = SyncReport(frame_clocks={d.camera: fit_frame_clock(d.frame_times_ms) for d in detections})
    cameras = {d.camera: with_one_exposure(d.retimed(report.frame_clocks[d.camera].times_ms)) for d in detections}
    undecided = [name for name, d in cameras.items() if d.undecided]

    rate_std = {name: clock.rate_std for name, clock in report.frame_clocks.items()}
    memo: dict = {}  # pair alignments shared by the attempts (a flip changes only that camera's pairs)

    def attempt_on(on: str) -> Callable[[dict[str, CameraDetection]], _Attempt]:
        return lambda trial: _attempt(trial, on, row_times, anchors, rate_std, memo)

    # The choices (readouts, frame times) are made in name order on a reference that neither
    # the camera order nor the reference given decides (:func:`_search_reference`); the
    # model is then solved on the reference given, in the order given. Without a choice to
    # make (every readout known, no stamps that change rate) it is solved once.
    choices = bool(undecided) or any(clock.rate_changes for clock in report.frame_clocks.values())
    if choices:
        start = {name: cameras[name] for name in sorted(cameras)}
        search_reference = _search_reference(start, reference, attempt_on(reference))
    else:
        start, search_reference = cameras, reference
    attempt = attempt_on(search_reference)
    best, rivals = _first_readout(start, report, undecided, attempt)
    best, frame_std, clock_warnings = _best_frame_times(best, report, attempt)
    if any(choice != STAMPS_OWN_RATES for choice in report.frame_times.values()):
        best, rivals = _best_readout(best.cameras, undecided, attempt)  # the readouts again, on the chosen times
    spreads, readout_exposures_ms, readout_warnings = _readout_doubts(best, rivals, search_reference)
    if choices:
        best = attempt_on(reference)({name: best.cameras[name] for name in cameras})
    if search_reference != reference:
        more_spreads, more_exposures_ms, more_warnings = _doubts_on_reference(
            best, cameras, undecided, set(spreads), reference, attempt_on(reference)
        )
        spreads.update(more_spreads)
        readout_exposures_ms.update(more_exposures_ms)
        readout_warnings += more_warnings

    def final(trial: dict[str, CameraDetection], other_shifts: bool = False) -> _Attempt:
        # the choices made, cameras of one size and rate share one readout a priori (not in the search: there
        # it read two of random rig 544's cameras the wrong way up)
        return _attempt(trial, reference, row_times, anchors, rate_std, memo, other_shifts, shared_readout=True)

    if shared_readouts(list(best.cameras.values()), set()):
        best = final(best.cameras)
    best, backward_warnings = _without_backward_readings(best, final)
    best, pulse_warnings, longer, stepped = _exposures_by_pulses(best, final)
    report.longer_exposures = {name: rows for name, (rows, _) in longer.items()}
    report.stepped_exposures = stepped
    by_name = {d.camera: d for d in detections}
    best, solved_again = _solved_on_one_exposure(best, final, by_name, stepped)
    if any(alignment.others for alignment in best.alignments.values()):
        best = final(best.cameras, other_shifts=True)
    exposure_spreads = {name: std_ms for name, (_, std_ms) in longer.items()}
    bound_ms = _pulse_bound_exposures_ms(best)
    change_warnings, changes_ms, shown, scatters_ms = _exposure_changes(best, by_name, stepped, solved_again)
    unturned_ms, unturned_warnings = _unturned_exposures_ms(best, set(longer) | set(stepped), shown)
    readings_ms = _in_quadrature(exposure_spreads, bound_ms, unturned_ms)
    for name, spread in [*spreads.items(), *best.shift_spreads.items()]:
        frame_std[name] = np.hypot(frame_std[name], spread)
    for name in best.connected:
        if name != reference:  # its times move by half its exposure's error, and by half the reference's
            frame_std[name] = np.hypot(
                frame_std[name], np.hypot(readings_ms.get(name, 0.0), readings_ms.get(reference, 0.0)) / 2.0
            )
    rate_spread = _rate_spread_ms(report.frame_clocks[reference], best.cameras[reference].frame_times_ms)
    frame_std[reference] = np.hypot(frame_std[reference], rate_spread)
    told = {*longer, *stepped, *unturned_ms, *changes_ms}  # cameras whose exposure a rule before told
    told_ms, told_warnings = _exposures_bands_tell(best, told)
    for name, spread in told_ms.items():  # its times move by half its exposure's error
        frame_std[name] = np.hypot(frame_std[name], spread / 2.0)
    short_ms, short_warnings = _exposures_short_bands_tell(best, by_name, told)
    rivals_ms = _rival_exposures_ms(best)
    best = best.with_scatter(
        _in_quadrature(readings_ms, scatters_ms, rivals_ms, readout_exposures_ms, told_ms, short_ms),
        _refit_rows(best, by_name, shown),
    )
    report.alignments = best.alignments
    report.warnings = (
        best.warnings
        + clock_warnings
        + readout_warnings
        + backward_warnings
        + pulse_warnings
        + unturned_warnings
        + told_warnings
        + short_warnings
        + _few_flashes(best, reference)
        + _turned_for_display(best.cameras)
        + _row_time_doubts(best)
        + change_warnings
        + _exposure_doubts(
            best, told=set(changes_ms) | set(unturned_ms) | set(told_ms) | set(short_ms) | set(readout_exposures_ms)
        )
        + _free_drifts(best, reference)
        + _reference_rate_doubt(report.frame_clocks, reference, best)
        + _apart_warnings(best)
    )
    report.flipped_found = [
        name for name in names if name in undecided + rolled and name in best.connected and best.cameras[name].flipped
    ]
    report.free_drift = [best.connected[c] for c in best.solution.free_drift]
    report.distrusted_flicker = list(best.distrusted_flicker)
    report.sigma_ms = best.solution.sigma_ms
    model = best.model(reference)
    burst_gaps_ms, burst_warnings = _burst_doubts(best, model)
    report.warnings += burst_warnings
    for name, clock in model.cameras.items():
        clock.frame_std_ms = np.hypot(frame_std[name], burst_gaps_ms.get(name, 0.0))
        if name in changes_ms:
            clock.exposure_spans = _held_exposures(clock, shown[name]) if shown.get(name) else ()
            clock.exposure_std_ms = float(np.hypot(clock.exposure_std_ms, changes_ms[name]))
    others = [clock for name, clock in model.cameras.items() if name != reference]
    for clock, share in zip(others, _reference_shares_ms(model.cameras[reference], rate_spread, others)):
        clock.frame_std_ms = np.hypot(clock.frame_std_ms, share)
    return model, report


def _in_quadrature(*parts: dict[str, float]) -> dict[str, float]:
    """Per camera named in any of ``parts`` (ms per camera), the root of the sum of their
    squares, ms: independent doubts added."""
    return {name: float(np.sqrt(sum(part.get(name, 0.0) ** 2 for part in parts))) for name in set().union(*parts)}


#: Rows of the reference at which its sigma is sampled for :func:`_reference_shares_ms`.
SHARE_ROWS = 16


def _reference_shares_ms(
    reference: CameraClock, rate_spread_ms: np.ndarray, cameras: list[CameraClock]
) -> list[np.ndarray]:
    """Per camera of ``cameras``, per frame (shape (n_frames,)), the errors of the reference
    that every camera's times share (ms), in the frame the reference records when the camera
    reads its middle row: its rows' below its first (its covariance's, RMS over its rows) and its
    clock's rate's (``rate_spread_ms``, per reference frame: :func:`_rate_spread_ms`). The
    global clock is the reference's, so every camera's times against the truth carry them,
    whatever the flashes tie them by (their times against each other do not); not its frame
    times' own scatter beyond those (stamps kept as they are: white from frame to frame, which
    the fit of every camera's clock to many flashes averages). Against the truth on nine kept
    benches (586 cameras other than the reference), their errors over their own sigma: RMS
    1.16, 37 over 2, 93 % of the probes within 2 sigma; with the reference's share, 0.84, 10
    and 98 % (the errors unchanged); with its rate's alone (not its rows'), 1.06 and 18 of
    424 where 1.20 and 32."""
    frames = np.arange(reference.n_frames)
    rows = np.linspace(0.0, reference.height - 1.0, SHARE_ROWS)
    rows_only = replace(reference, frame_std_ms=np.zeros(reference.n_frames))
    rows_ms = np.sqrt(np.mean(rows_only.t_global_std_ms(frames[:, None], rows[None, :]) ** 2, axis=1))
    share = np.hypot(rows_ms, rate_spread_ms)
    shares = []
    for camera in cameras:
        middle = camera.t_global_ms(np.arange(camera.n_frames), np.full(camera.n_frames, camera.height / 2.0))
        shares.append(share[np.clip(reference.locate(middle)[0], 0, reference.n_frames - 1)])
    return shares


def _without_backward_readings(
    best: _Attempt, attempt: Callable[[dict[str, CameraDetection]], _Attempt]
) -> tuple[_Attempt, list[str]]:
    """``best`` solved again without the cameras whose time per row comes out negative, and
    a warning naming each. Read the wrong way up (an upside-down camera given upright, or an
    upright one given as ``--flipped``), a camera's bands still fit the other cameras'
    flashes with its rows running backwards in time, its times wrong by up to a frame under
    a small sigma. Raises where the reference is one of them (the others' times would be
    wrong with it), or where too few cameras are left."""
    warnings = []
    while True:
        row_times = {name: camera.row_time_ms for name, camera in zip(best.connected, best.solution.cameras)}
        backward = [name for name, row_time in row_times.items() if row_time <= 0]
        if not backward:
            return best, warnings
        for name in backward:
            detection = best.cameras[name]
            why = (
                f"read {'bottom-up' if detection.flipped else 'top-down'}, its time per row comes out "
                f"{row_times[name]:.5f} ms: its rows would run backwards in time, so it is read the wrong way up "
                "(check --flipped)"
            )
            if name == best.reference:
                raise NotEnoughDataError(f"{detection.video}, the reference: {why}; or give another --reference")
            warnings.append(f"{detection.video}: {why}; left out")
        try:
            best = attempt({name: d for name, d in best.cameras.items() if name not in backward})
        except NotEnoughDataError as error:
            raise NotEnoughDataError(f"{'; '.join(warnings)}; then {error}") from None


def _exposures_by_pulses(
    best: _Attempt, attempt: Callable[[dict[str, CameraDetection]], _Attempt]
) -> tuple[_Attempt, list[str], dict[str, tuple[float, float]], list[str]]:
    """``best`` solved again with each camera read the other way round by the flashes the
    other cameras see shorter: given one exposure (:func:`_exposures_the_others_tell`,
    :meth:`~flashsync.detect.CameraDetection.with_longer_exposure`), or band by band where
    its pulses step while it records (:func:`_exposure_steps_the_others_tell`, or so read at
    one exposure and :func:`_pulses_step`;
    :func:`~flashsync.exposure_changes.with_pulses_as_exposures`); a warning naming each,
    per camera given one exposure the readout rows its exposure was made longer by and the
    exposure's standard error (ms; its times take half of it), and the cameras read band by
    band."""
    stepped = _exposure_steps_the_others_tell(best)
    told = {
        name: seen
        for name, seen in _exposures_the_others_tell(best, _pulses_seen_shorter(best)).items()
        if name not in stepped
    }
    for name in [name for name in told if _pulses_step(best.cameras[name])]:
        stepped[name] = told.pop(name)[2]
    if not told and not stepped:
        return best, [], {}, []
    cameras = dict(best.cameras)
    warnings, longer = [], {}
    for name, (exposure_ms, std_ms, n_flashes) in told.items():
        camera = best.solution.cameras[best.connected.index(name)]
        frames, shorter_ms = _bands_shorter_than(cameras[name], exposure_ms, camera.row_time_ms)
        spread_ms = exposure_ms - float(shorter_ms.min()) if len(frames) else 0.0
        longer[name] = ((exposure_ms - camera.exposure_ms) / camera.row_time_ms, float(np.hypot(std_ms, spread_ms)))
        cameras[name] = cameras[name].with_longer_exposure(longer[name][0])
        warnings.append(
            f"{cameras[name].video}: its bands read as a {camera.exposure_ms:.2f} ms exposure under longer pulses, but "
            f"{n_flashes} flashes it saw {exposure_ms:.2f} ms long the other cameras saw shorter: read the other way "
            f"round, its exposure is {exposure_ms:.2f} ms"
            + (
                f"; but {_bands_at(frames)} cannot be that long, the shortest {shorter_ms.min():.2f} ms at most "
                "(auto exposure?): in its sigma (half of it in its times')"
                if len(frames)
                else ""
            )
            + "; check it against the camera's shutter setting"
        )
    for name, n_flashes in stepped.items():
        camera = best.solution.cameras[best.connected.index(name)]
        cameras[name] = with_pulses_as_exposures(cameras[name])
        warnings.append(
            f"{cameras[name].video}: its bands read as a {camera.exposure_ms:.2f} ms exposure under longer pulses that "
            f"step while it records, but {n_flashes} flashes it saw so long the other cameras saw shorter: read the "
            "other way round band by band, its pulses are its exposures, and its exposure changes (below)"
        )
    return attempt(cameras), warnings, longer, list(stepped)


def _bands_at(frames: np.ndarray) -> str:
    """Bands at ``frames`` (decoded frames, shape (n,), n >= 1), as a warning names them."""
    if len(frames) == 1:
        return f"one of its bands (frame {frames[0]})"
    return f"{len(frames)} of its bands (frames {frames.min()}-{frames.max()})"


def _bands_shorter_than(
    detection: CameraDetection, exposure_ms: float, row_time_ms: float
) -> tuple[np.ndarray, np.ndarray]:
    """The frames and the longest exposure (ms; shapes (n,)) of the camera's bands fitted whole
    that cannot be ``exposure_ms`` long, a step (:data:`~flashsync.exposure_changes.MIN_STEP_SHARE`)
    short of it: a band is its exposure convolved with its pulse, so its exposure and pulse
    as read (:attr:`~flashsync.detect.CameraDetection.pulse_rows`) sum to the longest exposure
    it allows, an exposure read longer takes that much off its pulse. Random rig 898 of a
    bench of two flash powers and auto exposure (``bench_rigs.py --seeds 890:902
    --max-height 360 --duration-s 8 --exposure-changes 0.5 --flash-powers 0.5``): its cam2
    (0.55 ms, then 0.29 from frame 99) read as 0.31 ms under longer pulses, three flashes it
    saw 0.55 ms long that the others saw shorter: read the other way round at 0.55 ms
    throughout, while its bands of frames 194 and 211 (pulses of 0.03 and 0.06 ms as read)
    allow 0.33 and 0.36 ms at most; its exposure frame by frame at error/sigma 7.2 with no
    word."""
    pulses = detection.pulse_rows
    if pulses is None or detection.exposure_rows is None:
        return np.empty(0, np.int64), np.empty(0)
    events = detection.events
    leading = events.bands().leading
    leading = leading[leading >= 0]
    longest_ms = (detection.exposure_rows + pulses[events.event[leading]]) * row_time_ms
    short = longest_ms < (1 - MIN_STEP_SHARE) * exposure_ms  # NaN pulses (no band fitted whole) compare False
    return events.frame[leading[short]], longest_ms[short]


def _pulse_bound_exposures_ms(best: _Attempt) -> dict[str, float]:
    """Per camera whose every unclipped band within one frame is about as long as its flash's
    pulse as the other cameras see it (:data:`PULSES_AGREE` either way: each may be its
    pulse's length, not the exposure's) and that has a band of a flash the others see
    shorter than that (a band clipped at white, then: it is no shorter than the exposure),
    how far its solved exposure lies above the shortest such band, ms: a reading its bands
    leave open, which neither the residuals nor the flashes left out see. Random rig 65's
    reference (1.264 ms, 21.7 rows, sRGB) had six of its nine bands clipped and three clean
    ones of 1.55-1.89 ms pulses, 27.5-33.9 rows long; its exposure came out 1.594 ms, 0.18
    ms above its shortest clipped band (of a 0.51 ms pulse), 0.33 ms long under a sigma of
    0.08, and every other camera's times 0.15-0.19 ms off. Over ten kept benches (510
    cameras) no other camera is so bound."""
    matches = best.matches
    pulse_of, _ = _pulses_seen(best)
    bound = {}
    for name, camera in zip(best.connected, best.solution.cameras):
        events = best.cameras[name].events
        bands = events.bands()
        bands, rows = _within_one_frame(events, bands.take(bands.complete & (events.band[bands.leading] == Band.PULSE)))
        if camera.exposure_ms <= 0 or not len(bands):
            continue
        lengths = rows * camera.row_time_ms
        pulses = np.full(len(bands), np.nan)
        mine = np.flatnonzero(matches.camera == name)
        for b, flash in enumerate(_flash_of(matches.event[mine], matches.flash[mine], bands.event)):
            seen = (matches.flash == flash) & (matches.camera != name) & np.isfinite(pulse_of)
            if flash >= 0 and seen.any():
                pulses[b] = np.median(pulse_of[seen])
        clipped = events.has_flag(Flag.SATURATED)[bands.leading]
        as_long = (pulses >= (1 - PULSES_AGREE) * lengths) & (pulses <= lengths / (1 - PULSES_AGREE))
        shorter = pulses < (1 - PULSES_AGREE) * lengths
        if (~clipped).any() and as_long[~clipped].all() and shorter.any():
            bound[name] = max(camera.exposure_ms - float(lengths[shorter].min()), 0.0)
    return bound


def _flash_of(events: np.ndarray, flashes: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """The flash of each of the ``wanted`` event numbers among a camera's matched ``events``
    (their ``flashes``), -1 where unmatched; shape of ``wanted``."""
    flash_of = dict(zip(events.tolist(), flashes.tolist()))
    return np.array([flash_of.get(e, -1) for e in wanted.tolist()], dtype=np.int64)


def _rival_exposures_ms(best: _Attempt) -> dict[str, float]:
    """Per camera whose bands' reading left a rival exposure (pulses longer than it,
    :attr:`~flashsync.detect.CameraDetection.rival_exposure_rows`), how far that lies from
    its solved exposure, ms (into the exposure's sigma): its bands cannot tell the two
    (random rig 4's reference, 0.62 ms under 1.0-1.9 ms LED pulses at 5.7 rows, read 1.03
    ms at a sigma of 0.06; its rival 0.79)."""
    spreads = {}
    for name, camera in zip(best.connected, best.solution.cameras):
        rival = best.cameras[name].rival_exposure_rows
        if rival is not None and camera.exposure_ms > 0:
            spreads[name] = abs(camera.exposure_ms - rival * camera.row_time_ms)
    return spreads


def _turnable(detection: CameraDetection) -> bool:
    """Whether the camera's bands share an exposure of at most :data:`MAX_TURNED_ROWS` rows:
    short enough for the others' flashes to read it the other way round."""
    return (detection.exposure_rows or np.inf) <= MAX_TURNED_ROWS


def _unturned_exposures_ms(
    best: _Attempt, turned: set[str], shown: dict[str, list[_ShownExposure]]
) -> tuple[dict[str, float], list[str]]:
    """Per camera but the ``turned`` that the others' flashes show was read the other way
    round (:func:`_exposures_the_others_tell`) but whose bands share an exposure of more than
    :data:`MAX_TURNED_ROWS` rows, not turned: how far the exposure they tell lies from its
    solved one, ms (into the exposure's sigma, and half into its times'), and a warning for
    each. Random rig 103 at two flash powers (``bench_rigs.py --seeds 100:108 --flash-powers
    0.5``) has a 0.666 ms reference of 540 rows whose bands read as a 0.120 ms exposure (3.5
    rows) under 0.67 ms pulses that another camera saw 0-0.07 ms long: its exposure came out
    0.55 ms short at 26 sigmas, every other camera's times then 0.27 ms off. The same per
    camera, short enough to turn or not, that most of the flashes it read a pulse of tell so
    (their median :data:`MIN_EXPOSURE_GAIN` times its exposure or more), but too few of them
    (fewer than :data:`MIN_PULSE_FLASHES`) or with pulses that disagree (auto exposure may
    change it between them): EC2's rig-1075 cam5 (0.89 ms, 0.49 from frame 78; three bands,
    read as 1.1 and 3 rows), two of whose three flashes the others saw 0.1-0.2 ms long, held
    0.19 ± 0.04 ms with no word; EC6's rig-1117 cam8 (1.24 ms, then 2.01 from frame 122;
    read as 0.43 ms over 5.2 rows), four of whose five flashes the others saw at most 0.15 ms
    long, its pulses of them 1.06-1.83 ms, held 0.43 ± 0.04 ms frame by frame at error/sigma
    24.6 and its times at 2.9. Neither where the exposures its bands show (``shown``,
    :func:`_exposure_changes`) hold the frame of each of those flashes whose pulse outlasts
    its exposure at the exposure they tell (:func:`_held_there`): its exposure changed to
    that, and each span holds its own (EC2's rig-1079 cam2, 8.09 ms, then 15.92 from frame
    145, held 8.12 and 15.97: the others' flashes told 17.21 ms from its later bands, and its
    times took 4.5 ms in their sigma for an error of 0.12). Where one of them lies in another
    span, the change may be misplaced (EC4's rig-1096 cam3: two of its three in the span of
    its solved exposure, whose first frames held the earlier one)."""

    seen_shorter = _pulses_seen_shorter(best)

    def unexplained(name: str, exposure_ms: float) -> bool:  # by a turn, or by a change its bands show
        solved_ms = best.solution.cameras[best.connected.index(name)].exposure_ms
        return name not in turned and not all(
            _held_there(shown.get(name, []), frame, exposure_ms)
            for frame, pulse in seen_shorter[name][0]
            if pulse > solved_ms
        )

    spreads, warnings = {}, []
    unturnable = _exposures_the_others_tell(best, seen_shorter, turnable=False)
    for name, (exposure_ms, _, n_flashes) in unturnable.items():
        if not unexplained(name, exposure_ms):
            continue
        detection = best.cameras[name]
        camera = best.solution.cameras[best.connected.index(name)]
        spreads[name] = abs(exposure_ms - camera.exposure_ms)
        warnings.append(
            f"{detection.video}: its bands read as a {camera.exposure_ms:.2f} ms exposure under longer pulses, but "
            f"{n_flashes} flashes it saw {exposure_ms:.2f} ms long the other cameras saw shorter: its exposure may be "
            f"{exposure_ms:.2f} ms; read over {detection.exposure_rows:.1f} rows, more than blur makes, it is kept, "
            "the other in its sigma (half of it in its times'); check it against the camera's shutter setting, or "
            "give it (restamp --exposure CAMERA=MS)"
        )
    told = {*unturnable, *_exposures_the_others_tell(best, seen_shorter)}
    for name, (seen, n_pulses) in seen_shorter.items():
        if name in told or n_pulses >= 2 * len(seen):  # told so above (or turned), or not by most of its flashes
            continue
        camera = best.solution.cameras[best.connected.index(name)]
        pulses = [pulse for _, pulse in seen]
        exposure_ms = float(np.median(pulses))
        if exposure_ms < MIN_EXPOSURE_GAIN * camera.exposure_ms or not unexplained(name, exposure_ms):
            continue
        spreads[name] = exposure_ms - camera.exposure_ms
        why = (
            "too few flashes to read it so"
            if len(seen) < MIN_PULSE_FLASHES
            else f"those pulses disagree ({min(pulses):.2f}-{max(pulses):.2f} ms: auto exposure?), so it is not read so"
        )
        warnings.append(
            f"{best.cameras[name].video}: its bands read as a {camera.exposure_ms:.2f} ms exposure under longer "
            f"pulses, but {len(seen)} of the {n_pulses} flashes it read a pulse of the other cameras saw "
            f"shorter: its exposure may be {exposure_ms:.2f} ms (its pulses of them); {why}, "
            "it is kept, the other in its sigma (half of it in its times'); check it against the camera's shutter "
            "setting, or give it (restamp --exposure CAMERA=MS)"
        )
    return spreads, warnings


def _held_there(shown: list[_ShownExposure], frame: int, exposure_ms: float) -> bool:
    """Whether one of the exposures a camera's bands show (``shown``) holds ``frame`` at
    ``exposure_ms`` (within :data:`MIN_STEP_SHARE`)."""
    return any(
        s.first_frame <= frame <= s.last_frame and abs(s.exposure_ms - exposure_ms) <= MIN_STEP_SHARE * s.exposure_ms
        for s in shown
    )


#: Fewest other cameras that read the pulses by their bands' ramps, over all the flashes of a
#: camera's bands that tell its exposure (:func:`_exposures_bands_tell`): long exposures may
#: take an LED's 1-2 ms ramps for blur and see it 0.05 ms long (random rig 4's cam4, whose
#: reading alone named its cam5, 0.65 ms steady).
BAND_WITNESSES = 2


def _exposures_bands_tell(best: _Attempt, told: set[str]) -> tuple[dict[str, float], list[str]]:
    """Per camera but the ``told`` with a band read at its exposure under a pulse
    :data:`MIN_EXPOSURE_GAIN` times longer or more whose flash the other cameras show
    shorter than that (:func:`_seen_shorter`), none as long, and shorter than the camera's
    exposure, :data:`BAND_WITNESSES` of them or more over all such bands: such a flash makes
    a band one exposure long, so that band's pulse is the camera's exposure where it saw it
    (auto exposure), too few such bands to read the camera the other way round
    (:func:`_exposures_the_others_tell`) and no band's length to show the change
    (:mod:`~flashsync.exposure_changes`; the cameras whose changes were found are among the
    ``told``). How far the longest such pulse lies beyond its solved exposure, ms (into the
    exposure's sigma, and half into its own times'), and a warning each. Random rig 914 of a
    bench of TTL flashes, fast readouts and auto exposure (``bench_rigs.py --seeds 910:920
    --preflash 30 --readout 0.5:0.9 --exposure-changes 0.5``): its cam5 (1.46 ms, 2.22 from
    frame 109) read as 0.56 ms under pulses of 1.5-2.2, a 0.29 ms flash among them, its
    exposure frame by frame at error/sigma 42 with no word. Where the others see the flash
    longer than the camera's exposure, the pulse is the flash's, read long (a 24.7 ms pulse
    of a 2.5 ms flash on random rig 898 of a bench of two flash powers and auto exposure,
    its exposure 0.51 ms all along)."""
    matches = best.matches
    pulse_of, ramp_read = _pulses_seen(best)
    spreads, warnings = {}, []
    for name, camera in zip(best.connected, best.solution.cameras):
        if name in told:
            continue
        others = matches.camera != name
        shown = [
            (pulse, flash)
            for flash, pulse in _flashes_seen_shorter(matches, name, pulse_of, ramp_read)
            if pulse >= MIN_EXPOSURE_GAIN * camera.exposure_ms > 0
            and not np.any((matches.flash == flash) & others & (pulse_of >= (1 - PULSES_AGREE) * pulse))
            and np.median(pulse_of[(matches.flash == flash) & others & ramp_read]) < camera.exposure_ms
        ]
        witnesses = np.isin(matches.flash, [flash for _, flash in shown]) & others & ramp_read
        longer = [pulse for pulse, _ in shown]
        if len(np.unique(matches.camera[witnesses])) >= BAND_WITNESSES:
            spreads[name] = max(longer) - camera.exposure_ms
            lengths = ", ".join(f"{pulse:.2f}" for pulse in sorted(longer))
            which = (
                f"one of them ({lengths} ms) is of a flash"
                if len(longer) == 1
                else f"{len(longer)} of them ({lengths} ms) are of flashes"
            )
            warnings.append(
                f"{best.cameras[name].video}: its bands read as a {camera.exposure_ms:.2f} ms exposure under longer "
                f"pulses, but {which} the other cameras saw shorter than that exposure: its exposure may have been "
                "that long at those flashes (auto exposure?), in its sigma (half of it in its times'); set the "
                "camera's shutter to one exposure to record with it, or give it (restamp --exposure CAMERA=MS)"
            )
    return spreads, warnings


def _exposures_short_bands_tell(
    best: _Attempt, detections: dict[str, CameraDetection], told: set[str]
) -> tuple[dict[str, float], list[str]]:
    """Per camera but the ``told`` (whose exposure changes, or is read the other way round)
    with bands a step shorter than its solved exposure beyond every band of that length
    (:func:`~flashsync.exposure_changes.shorter_bands`, of every band in the reading in use):
    how far the shortest lies below that exposure, ms (into the exposure's sigma; its
    times rest on the edges the solve kept), and a warning each. Random rig 1020 of a bench
    of TTL flashes at two powers, fast readouts and auto exposure (``bench_rigs.py --seeds
    1020:1032 --preflash 40 --readout 0.4:0.8 --flash-powers 0.5 --exposure-changes 0.5
    --max-height 360 --duration-s 8``): its cam7 (1.65 ms, then 0.79 from frame 66) had one
    band of a short flash after the change, 0.77 ms long, among bands of pulses that outlast
    the exposure (1.9-2.4 ms long: no step a span could show); held at 1.63 ± 0.09 ms
    throughout, its exposure 8.9 sigma off over most of its frames, with no word."""
    spreads, warnings = {}, []
    for name, solution in zip(best.connected, best.solution.cameras):
        if name in told or not solution.exposure_ms > 0:
            continue
        frames, rows = shorter_bands(_in_use(best, detections, name), solution.exposure_ms / solution.row_time_ms)
        if not len(frames):
            continue
        shortest_ms = float(rows.min()) * solution.row_time_ms
        spreads[name] = solution.exposure_ms - shortest_ms
        one = len(frames) == 1
        exposure = f"a step shorter than its {solution.exposure_ms:.2f} ms exposure"
        lengths = (
            f"is {shortest_ms:.2f} ms long, {exposure}" if one else f"are {exposure}, the shortest {shortest_ms:.2f} ms"
        )
        warnings.append(
            f"{best.cameras[name].video}: {_bands_at(frames)} {lengths}: a band is one exposure long at least, so "
            f"its exposure was that short there (auto exposure?) or {'that band is' if one else 'those bands are'} "
            "misread; in its exposure's sigma; set the camera's shutter to one exposure to record with it, or give "
            "it (restamp --exposure CAMERA=MS)"
        )
    return spreads, warnings


def _exposures_the_others_tell(
    best: _Attempt, seen_shorter: dict[str, tuple[list[tuple[int, float]], int]], turnable: bool = True
) -> dict[str, tuple[float, float, int]]:
    """Per camera of ``seen_shorter`` (:func:`_pulses_seen_shorter` of ``best``: its bands
    read with some pulses longer than its exposure), :func:`_turnable` (or, ``turnable``
    False, not), and that the other cameras show was read the other way round
    (:func:`_seen_shorter`, :data:`MIN_EXPOSURE_GAIN`): its exposure (ms), the median of its
    pulses of the flashes that the cameras whose bands of them are one exposure long (the
    pulse measured by the band's ramps) see shorter, that median's standard error (ms) and
    the number of those flashes."""
    told = {}
    for name, (seen, _) in seen_shorter.items():
        camera = best.solution.cameras[best.connected.index(name)]
        longer = [pulse for _, pulse in seen]
        if _turnable(best.cameras[name]) != turnable or len(longer) < MIN_PULSE_FLASHES:
            continue
        exposure_ms = float(np.median(longer))
        spread_ms = 1.4826 * float(np.median(np.abs(np.array(longer) - exposure_ms)))
        if exposure_ms >= MIN_EXPOSURE_GAIN * camera.exposure_ms and spread_ms <= PULSES_AGREE * exposure_ms:
            told[name] = (exposure_ms, spread_ms / np.sqrt(len(longer)), len(longer))
    return told


def _pulses_seen_shorter(best: _Attempt) -> dict[str, tuple[list[tuple[int, float]], int]]:
    """Per camera whose bands read with some pulses longer than its exposure: the frame and
    its pulse (ms) of each flash the other cameras show shorter (:func:`_flashes_seen_shorter`)
    and the number of its flashes with a pulse."""
    matches = best.matches
    pulse_of, ramp_read = _pulses_seen(best)
    seen = {}
    for name, camera in zip(best.connected, best.solution.cameras):
        mine = (matches.camera == name) & np.isfinite(pulse_of)
        if camera.exposure_ms > 0 and np.any(pulse_of[mine] > camera.exposure_ms):
            frame_of = dict(zip(matches.flash[mine], matches.frame[mine]))
            longer = [
                (int(frame_of[flash]), pulse)
                for flash, pulse in _flashes_seen_shorter(matches, name, pulse_of, ramp_read)
            ]
            seen[name] = (longer, int(np.count_nonzero(mine)))
    return seen


def _flashes_seen_shorter(
    matches: Matches, name: str, pulse_of: np.ndarray, ramp_read: np.ndarray
) -> list[tuple[int, float]]:
    """The flashes of camera ``name``'s matched sync events with a pulse (``pulse_of``, ms;
    :func:`_pulses_seen` gives it and ``ramp_read``) that the other cameras show shorter
    (:func:`_seen_shorter`), each with that pulse."""
    mine = (matches.camera == name) & np.isfinite(pulse_of)
    others = matches.camera != name
    return [
        (int(flash), float(pulse))
        for flash, pulse in zip(matches.flash[mine], pulse_of[mine])
        if _seen_shorter(matches.flash == flash, pulse, pulse_of, ramp_read, others)
    ]


def _seen_shorter(
    flash: np.ndarray, pulse_ms: float, pulse_of: np.ndarray, ramp_read: np.ndarray, witnesses: np.ndarray
) -> bool:
    """Whether the ``witnesses`` among the matched sync events of one ``flash`` (masks of shape
    (n_matches,); :func:`_pulses_seen` gives ``pulse_of`` and ``ramp_read``) show its pulse
    shorter than ``pulse_ms``: those whose bands of it are one exposure long (its pulse read
    by their ramps) see it :data:`SHORTER_PULSE_SHARE` shorter (their median), and more of
    them see it so than :data:`PULSES_AGREE` as long. One witness's misread pulse does not
    outvote the rest: random rig 133's cam8 (6.61 ms, read as 0.15 ms under 7.4 ms pulses)
    saw four flashes that four to six cameras saw at most 1 ms long, two of them seen as long
    by one camera each (cam10's ramps fitted at 8.8 ms; cam12, itself read the other way
    round), and stayed 2.7 ms off at 3.7 sigma. A witness whose band of it is longer than
    one exposure is no witness: its pulse, too, is a reading under a pulse longer than its
    exposure, misread alike where the camera's is (EC5's rig-1107: cam2 and cam3, 0.93 and
    0.97 ms read as 0.16 and 0.19 ms under longer pulses, saw each other's flashes as long
    as their own and outvoted the reference's ramps; their exposures 53 and 31 sigma off)."""
    others = flash & witnesses & ramp_read
    shorter = np.count_nonzero(others & (pulse_of <= (1 - SHORTER_PULSE_SHARE) * pulse_ms))
    as_long = np.count_nonzero(others & (pulse_of >= (1 - PULSES_AGREE) * pulse_ms))
    return bool(
        others.any() and shorter > as_long and pulse_ms - np.median(pulse_of[others]) >= SHORTER_PULSE_SHARE * pulse_ms
    )


def _pulses_seen(best: _Attempt) -> tuple[np.ndarray, np.ndarray]:
    """Per matched sync event of ``best`` (shape (n_matches,) each): its band's pulse (ms;
    NaN where its camera's reading of its exposure disagrees with the solve's,
    :data:`READINGS_AGREE`) and whether the pulse was measured by the band's ramps (shorter
    than its camera's exposure)."""
    matches = best.matches
    pulse_of = np.full(len(matches), np.nan)
    exposure_of = np.full(len(matches), np.nan)
    for detection, camera in zip((best.cameras[name] for name in best.connected), best.solution.cameras):
        mine = matches.camera == detection.camera
        read_ms = (detection.exposure_rows or np.nan) * camera.row_time_ms
        agree = abs(read_ms - camera.exposure_ms) <= READINGS_AGREE * camera.exposure_ms
        if detection.pulse_rows is not None and agree:
            pulse_of[mine] = detection.pulse_rows[matches.event[mine]] * camera.row_time_ms
        exposure_of[mine] = camera.exposure_ms
    return pulse_of, pulse_of < exposure_of


def _pulses_step(detection: CameraDetection) -> bool:
    """Whether the camera's pulses, read at its exposure under longer pulses, step in spans
    of one length each (:func:`~flashsync.exposure_changes.pulse_spans`): read the other way
    round, its exposure changes."""
    spans = pulse_spans(detection)
    return len(spans) > 1 and all(span.one_length for span in spans)


def _exposure_steps_the_others_tell(best: _Attempt) -> dict[str, int]:
    """Per camera whose bands read with pulses longer than its exposure that step while it
    records (:func:`~flashsync.exposure_changes.pulse_spans`) and that the other cameras show
    was read the other way round, the number of its flashes that tell so: the cameras whose
    bands of them are one exposure long see them shorter (:func:`_seen_shorter`; the cameras
    whose pulses step are no witnesses); :data:`MIN_PULSE_FLASHES` or more and most of its
    flashes so read. A pulse is the flash's, the same in every camera, an exposure the
    camera's: random rig 542's cam1, cam8 and cam9 on auto exposure under short pulses were
    read as exposures of 0.30-1.27 ms under pulses that stepped in time, and each saw the
    others' flashes as long as its own."""
    matches = best.matches
    pulse_of, ramp_read = _pulses_seen(best)
    stepping = [name for name in best.connected if len(pulse_spans(best.cameras[name])) > 1]
    told = {}
    for name in stepping:
        mine = (matches.camera == name) & (pulse_of > best.solution.cameras[best.connected.index(name)].exposure_ms)
        witnesses = ~np.isin(matches.camera, stepping)
        shorter = sum(
            _seen_shorter(matches.flash == flash, pulse, pulse_of, ramp_read, witnesses)
            for flash, pulse in zip(matches.flash[mine], pulse_of[mine])
        )
        if shorter >= MIN_PULSE_FLASHES and 2 * shorter > np.count_nonzero(mine):
            told[name] = shorter
    return told


def check_row_times(row_times: dict[str, float], cameras: Sequence[str]) -> None:
    """Raise an :class:`~flashsync.errors.InputError` (parameter ``row_times``) for a camera
    that is not among ``cameras`` or a time per row that is not a positive number of ms."""
    unknown = sorted(set(row_times) - set(cameras))
    if unknown:
        raise InputError(f"{', '.join(unknown)}: no such camera among {', '.join(cameras)}", parameter="row_times")
    for name, value in row_times.items():
        if not (isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value) and value > 0):
            raise InputError(
                f"{name}={value}: a time per row is a positive number of ms, e.g. {name}=0.0296",
                parameter="row_times",
            )


def check_anchors(anchors: Sequence[str]) -> None:
    """Raise an :class:`~flashsync.errors.InputError` (parameter ``anchors``) where anchors
    name two different events of one camera: the anchored events are one flash, which a
    camera sees once."""
    seen: dict[str, str] = {}
    for text in anchors:
        camera, _, number = str(text).rpartition(":")
        if camera in seen and seen[camera] != number:
            raise InputError(
                f"{camera}:{seen[camera]} and {text}: the anchors are one flash, which {camera} sees "
                "once; anchor one event per camera",
                parameter="anchors",
            )
        seen[camera] = number


#: The frame times of stamps that change rate taken at the stamps' own rates.
STAMPS_OWN_RATES = "the stamps' own rate in each segment"
#: A choice of frame times, or of readout directions, whose log-likelihood leads the next
#: by less than this is undecided.
DECIDED_LOG_LIKELIHOOD = 5.0


def _best_frame_times(
    best: _Attempt, report: SyncReport, attempt: Callable[[dict[str, CameraDetection]], _Attempt]
) -> tuple[_Attempt, dict[str, np.ndarray], list[str]]:
    """Each camera's frame times chosen where its stamps leave a choice, their standard
    deviations (ms, per frame) and warnings about stamps that follow no steady clock.

    A camera whose stamps change rate may have a sensor that changed rate (the stamps' own
    rate in each segment) or one that kept its rate while the stamps did not
    (:meth:`FrameClock.one_rate_alternatives`); the matched flashes choose (the
    likelihood of :attr:`_Attempt.score`). Where they cannot (no flash tells them apart),
    the frames where the choices differ carry the difference in their standard deviation.
    """
    frame_std = {name: clock.std_ms for name, clock in report.frame_clocks.items()}
    warnings = []
    for name, clock in report.frame_clocks.items():
        video = best.cameras[name].video
        if not clock.steady:
            warnings.append(
                f"{video}: its frame stamps follow no steady clock (variable frame rate); frame times are the "
                f"stamps as they are, each uncertain by {float(np.median(clock.std_ms)):.2f} ms (in its sigma)"
            )
        if not clock.rate_changes:
            continue
        frame, before, after = clock.rate_changes[0]
        change = f"{video}: its frame stamps change rate at frame {frame} ({before:.3f} -> {after:.3f} ms per frame)"
        choices = [(STAMPS_OWN_RATES, clock.times_ms), *clock.one_rate_alternatives()]
        # on the wrong frame times too few flashes may match to tie the camera at all
        tried = []
        for description, times in choices:
            if np.array_equal(times, best.cameras[name].frame_times_ms):  # the times it was solved on
                if name in best.connected:
                    tried.append((best.score, description, times, best))
                continue
            trial = dict(best.cameras)
            trial[name] = trial[name].retimed(times)
            try:
                result = attempt(trial)
            except FlashsyncError:
                continue
            if name in result.connected:
                tried.append((result.score, description, times, result))
        if not tried:
            warnings.append(f"{change}; no choice of its frame times ties it to the other cameras")
            continue
        tried.sort(key=lambda entry: -entry[0])
        best, times = tried[0][3], tried[0][2]
        report.frame_times[name] = tried[0][1]
        if len(tried) > 1 and tried[0][0] - tried[1][0] < DECIDED_LOG_LIKELIHOOD:
            spread = np.abs(times - tried[1][2])
            frame_std[name] = np.hypot(frame_std[name], spread)
            warnings.append(
                f"{change}; the flashes cannot tell {tried[0][1]} from {tried[1][1]}: its frame times are "
                f"uncertain by up to {float(spread.max()):.1f} ms (in its sigma); check its timestamps"
            )
        else:
            warnings.append(f"{change}; the flashes fit {tried[0][1]}")
    return best, frame_std, warnings


def _first_readout(
    cameras: dict[str, CameraDetection],
    report: SyncReport,
    undecided: list[str],
    attempt: Callable[[dict[str, CameraDetection]], _Attempt],
) -> tuple[_Attempt, dict[str, _Attempt]]:
    """:func:`_best_readout` on the stamps' own rates; where nothing solves on them and a
    camera's stamps change rate, on each of its one-rate frame times in turn, the first that
    solves (on stamps that slow to half their rate the flashes after the change are too far
    off to match: none was tied). Raises the own rates' failure where none solves; the frame
    times are chosen after (:func:`_best_frame_times`)."""
    try:
        return _best_readout(cameras, undecided, attempt)
    except FlashsyncError as error:
        failure = error
    for name, clock in report.frame_clocks.items():
        for _, times in clock.one_rate_alternatives():
            trial = dict(cameras)
            trial[name] = trial[name].retimed(times)
            try:
                return _best_readout(trial, undecided, attempt)
            except FlashsyncError:
                continue
    raise failure


def _best_readout(
    cameras: dict[str, CameraDetection], undecided: list[str], attempt: Callable[[dict[str, CameraDetection]], _Attempt]
) -> tuple[_Attempt, dict[str, _Attempt]]:
    """The readout directions of the ``undecided`` cameras that the events support
    (:attr:`_Attempt.score`): from the detected ones (top-down, the usual mounting), the
    best reading where it explains the events better by :data:`DECIDED_LOG_LIKELIHOOD` at
    least. Up to :data:`EVERY_READING` readings, every reading is solved. Beyond, an ascent:
    each step takes the best move that gains the margin, until none does. The moves are the
    single flips and, where none of those pays, joint ones: a camera flipped together with
    the undecided cameras that lose inlier flashes when it alone is flipped (cameras read
    the wrong way up that share flashes fit each other, so neither flip pays alone: rig-14
    of the random rigs), and, where neither pays, every undecided camera flipped at once
    (but the detected reading's :func:`_mirror`): the mirror of a reading is the other
    reading that fits a rig of one frame rate, and a rig of mostly one rate ends its ascent
    there (random rig 782 at 720 rows, four 30 fps cameras and one at 25 fps: every camera
    read the wrong way up, log-likelihood 50 against the right reading's 139, 27 ms off).
    Candidates are tried in name order and a reading is solved once,
    so the camera order decides nothing; at most two attempts per undecided camera per step.
    The held estimate of each flip (:func:`_held_gains`) spares the whole attempts of rigs
    with many flashes: a single flip it puts beyond :data:`FLIP_SCREEN_SLACK` below is not
    tried, and the flips it puts beyond it above are tried first, all together.

    A near tie is not decided by the noise of the edges (H.264 output changes slightly with
    what the encoder did before): the reading stays, :func:`_readout_doubts` warns and
    widens sigma. Returns the chosen attempt and, per undecided camera, the best attempt
    tried with that camera read the other way (where one solved: with two cameras read the
    wrong way up, the rival may differ in both). Raises the first failure if nothing solves."""
    undecided = sorted(undecided)
    failure: FlashsyncError | None = None
    tried: dict[tuple[bool, ...], _Attempt | None] = {}

    def tries(start: dict[str, CameraDetection], flips: set[str]) -> _Attempt | None:
        nonlocal failure
        trial = {name: d.read_flipped(not d.flipped) if name in flips else d for name, d in start.items()}
        key = tuple(trial[name].flipped for name in undecided)
        if key not in tried:
            try:
                tried[key] = attempt(trial)
            except FlashsyncError as error:
                failure = failure or error
                tried[key] = None
        return tried[key]

    def leads(trial: _Attempt | None, than: _Attempt) -> bool:
        return trial is not None and trial.evidence >= than.evidence + DECIDED_LOG_LIKELIHOOD + _chance_lead(
            trial, than, cameras
        )

    best = tries(cameras, set())
    every = 2 ** len(undecided) <= EVERY_READING
    if every:
        readings = [flips for flips in product((False, True), repeat=len(undecided)) if not _mirror(flips, cameras)]
        results = [r for flips in readings if (r := tries(cameras, set(compress(undecided, flips)))) is not None]
        if best is None:
            best = max(results, key=lambda r: r.evidence, default=None)
        elif leading := [r for r in results if leads(r, best)]:
            best = max(leading, key=lambda r: r.evidence)
    while not every:
        start = best.cameras if best is not None else cameras
        gains = _held_gains(best, undecided)
        certain = {name for name, gain in gains.items() if gain > FLIP_SCREEN_SLACK}
        if certain and leads(together := tries(start, certain), best):
            best = together
            continue
        singles = {name: tries(start, {name}) for name in undecided if gains.get(name, 0.0) >= -FLIP_SCREEN_SLACK}
        steps = [r for r in singles.values() if r is not None]
        if best is None and steps:  # the detected reading failed: the best single flip is the start
            best = max(steps, key=lambda r: r.evidence)
            continue
        better = [r for r in steps if best is not None and leads(r, best)]
        if not better and best is not None:
            groups = [{name, *_losing(best, r, undecided)} for name, r in singles.items() if r is not None]
            steps = [tries(start, group) for group in groups if len(group) > 1]
            mirrored = tuple(start[name].flipped == cameras[name].flipped for name in undecided)
            if not _mirror(mirrored, cameras):
                steps.append(tries(start, set(undecided)))
            better = [r for r in steps if leads(r, best)]
        if not better:
            break
        best = max(better, key=lambda r: r.evidence)
    if best is None:
        raise failure
    rivals = {}
    solved = [r for r in tried.values() if r is not None]
    for name in undecided:
        other = [r for r in solved if r.cameras[name].flipped != best.cameras[name].flipped]
        if other:
            rivals[name] = max(other, key=lambda r: r.score)
    return best, rivals


def _chance_lead(trial: _Attempt, current: _Attempt, cameras: dict[str, CameraDetection]) -> float:
    """What ``trial`` must lead its ``current`` reading by beyond :data:`DECIDED_LOG_LIKELIHOOD`:
    per camera it turns from both ``current`` and the detected reading (``cameras``) that is
    tied by fewer than :data:`FEW_FLASHES` inlier flashes there, its :meth:`_Attempt.flash_worth`
    (but where its ``current`` reading is :attr:`_Attempt.implausible`). On so few a reading
    that fits one flash more than the other leads by chance: random rig 15 of ``bench_rigs.py``
    (two cameras sharing four flashes) read its 25 fps camera upside down on three, a lead of
    10.5 (a flash worth 12), its time per row 65 % short, 30 ms off; rig-30's reference, truly
    upside down on three flashes, leads by 42.8."""
    matches = trial.matches
    inlier = trial.solution.inlier[: len(matches)]
    lead = 0.0
    for name, detection in trial.cameras.items():
        turned = detection.flipped != current.cameras[name].flipped and detection.flipped != cameras[name].flipped
        if turned and name in trial.connected and name not in current.implausible:
            mine = inlier & (matches.camera == name)
            others = inlier & (matches.camera != name)
            if np.count_nonzero(np.isin(np.unique(matches.flash[mine]), matches.flash[others])) < FEW_FLASHES:
                lead += trial.flash_worth(name)
    return lead


#: A single flip whose held estimate (:func:`_flip_gains`) loses more than this log-likelihood
#: is not solved whole, and flips that gain more are taken together where that pays. Over
#: the 24 random rigs and the 10 recipes of bench_rigs (231 single flips of rigs with every
#: camera tied) the whole attempt came out at most 58 above the estimate (the other cameras
#: gain what the flipped camera no longer pulls askew), and the estimates lay between -157
#: and +78. On 64 cameras x 500 flashes a wrong flip loses 3258-3817; with three of them read
#: the wrong way up, their flips gain 942-1012 and every other loses 956-1518.
FLIP_SCREEN_SLACK = 200.0


def _held_gains(best: _Attempt | None, undecided: list[str]) -> dict[str, float]:
    """:func:`_flip_gains` of the ``undecided`` cameras; none where there is no ``best`` or it
    leaves an undecided camera out: a flip may tie it (on rig-2 of the random rigs one flip
    tied five cameras and gained 522, estimated -47), so every single flip is solved whole."""
    if best is None or any(name not in best.connected for name in undecided):
        return {}
    return _flip_gains(best, undecided)


def _flip_gains(best: _Attempt, names: list[str]) -> dict[str, float]:
    """Per camera of ``names`` tied in ``best``: what its edges' log-likelihood gains read the
    other way up, estimated with the other cameras' flashes held where ``best`` put them
    (:func:`~flashsync.likelihood.held_log_likelihood`, both readings refitted alike, with
    the time-per-row priors of the events alone). No estimate for a camera ``best`` left out."""
    cameras = list(best.cameras.values())
    priors = _row_time_priors(cameras, {})
    uniform = _uniform_ms(best.cameras)
    gains = {}
    for name in names:
        if name not in best.connected:
            continue
        solved = best.solution.cameras[best.connected.index(name)]
        detection = best.cameras[name]
        period = median_step_ms(detection.frame_times_ms)
        clock = HeldClock(
            solved.alpha,
            solved.beta_ms,
            period,
            priors[list(best.cameras).index(name)],
            READOUT_SLACK * period / detection.height,
        )
        now, other = (
            held_log_likelihood(_reading_edges(d), best.solution.flash_ms, clock, uniform)
            for d in (detection, detection.read_flipped(not detection.flipped))
        )
        gains[name] = other - now
    return gains


def _mirror(flips: tuple[bool, ...], cameras: dict[str, CameraDetection]) -> bool:
    """Whether ``flips`` (one per undecided camera) turns every camera of a rig whose cameras
    all run at one frame rate (periods within 0.1 %): that mirror of the detected reading
    fits about as well (with one frame rate every camera's rows reversed are taken up by
    the shifts and the times per row), so the flashes cannot choose it and the usual
    mounting stands. On the four 25 fps cameras of tests/test_accuracy.py it led the
    upright reading by 3.2 in one render and by 20.7 in another (the upright reading's
    log-likelihood 85.6 there, 68.0 here)."""
    if len(flips) < len(cameras) or not all(flips):
        return False
    periods = [float(np.median(np.diff(d.frame_times_ms))) for d in cameras.values()]
    return max(periods) <= 1.001 * min(periods)


def _losing(before: _Attempt, after: _Attempt, undecided: list[str]) -> list[str]:
    """The ``undecided`` cameras read the same way in both attempts that have fewer inlier
    flashes in ``after`` than in ``before`` (none where it left them out, or its time per row
    is :attr:`~_Attempt.implausible`)."""
    count_before, count_after = _inlier_counts(before), _inlier_counts(after)
    return [
        name
        for name in undecided
        if before.cameras[name].flipped == after.cameras[name].flipped
        and count_after.get(name, 0) < count_before.get(name, 0)
    ]


def _inlier_counts(result: _Attempt) -> dict[str, int]:
    """Per camera tied with a plausible time per row: its inlier sync events."""
    inlier = result.solution.inlier[: len(result.matches)]
    return {
        name: int(np.sum(inlier & (result.matches.camera == name)))
        for name in result.connected
        if name not in result.implausible
    }


def _search_reference(
    cameras: dict[str, CameraDetection], reference: str, attempt: Callable[[dict[str, CameraDetection]], _Attempt]
) -> str:
    """The reference the readouts are chosen on: of the cameras tied to ``reference`` in
    their detected readings (``attempt`` solves on it), the one with the most matched sync
    events, the first name among equals; ``reference`` itself where those readings do not
    solve. A camera's score depends a little on the reference (its drift prior is relative
    to the reference's clock), and with it an ascent of one flip at a time can end
    elsewhere: rig-14 of the random rigs did with ``cam1`` as reference, not with ``cam10``."""
    try:
        start = attempt(cameras)
    except FlashsyncError:
        return reference
    counts = {name: int(np.sum(start.matches.camera == name)) for name in start.connected}
    return max(sorted(counts), key=lambda name: counts[name])


#: The lead of log-likelihood that decides between two shifts of a pair (:func:`_decided`,
#: by :func:`_shift_evidence`). On random rigs 414-426 fired with pre-flashes 60 ms early
#: (each camera blind to them p 1/2) and random rig 35 so, where the delay varied (1 ms std)
#: the right shift led by 5-124 (by over 30 in most trials), and where it did not the lead
#: went either way by up to 24 (the wrong one's by up to 17: rig-414, whose first camera
#: missed four flashes whose pre-flashes it saw, lines up 8 events against 5 at the wrong
#: shift): a constant delay can favour either, and the margin keeps it undecided.
SHIFT_DECIDED_LOG_LIKELIHOOD = 20.0
#: Log prior odds of a camera mounted upright against upside down: a reading costs this
#: much of its log-likelihood per camera read the other way than detected (top-down, the
#: usual mounting). On random rig 18 (three 59.94 fps cameras) one wrong flip led the
#: upright reading by 5.3 on the search reference.
UPSIDE_DOWN_PRIOR = 2.0

#: Rigs with at most this many readings of their undecided cameras (two ways up each) have
#: every reading solved, not an ascent: three cameras of rig-14 (cam6 upright, cam8 and cam10
#: upside down) took the wrong single flip first (cam6: a gain of 33, the right ones 26 and 14)
#: and ended there, all three read wrong with no warning.
EVERY_READING = 16


#: A camera tied by fewer inlier flashes than this has almost no equation to spare.
FEW_FLASHES = 4


def _few_flashes(best: _Attempt, reference: str) -> list[str]:
    """A warning per camera tied to the others by fewer than :data:`FEW_FLASHES` inlier
    flashes: its drift, shift and time per row rest on them alone (its sigma comes from the
    other cameras' edge noise and the priors, not from its own)."""
    inlier = best.solution.inlier[: len(best.matches)]
    warnings = []
    for name in best.connected:
        count = int(np.sum(inlier & (best.matches.camera == name)))
        if name != reference and count < FEW_FLASHES:
            warnings.append(
                f"{best.cameras[name].video}: tied to the other cameras by {count} flashes only; its clock rests on "
                "them alone with nothing to check them against (its sigma takes the other cameras' edge noise); "
                "record more flashes seen by it"
            )
    return warnings


def _turned_for_display(cameras: dict[str, CameraDetection]) -> list[str]:
    """A warning per video whose display matrix turns its stored frames: the model's rows,
    and a detection's ``y``, are the stored frame's, not the picture's a player shows."""
    return [
        f"{d.video}: its frames are stored turned ({d.display_rotation_deg} degrees counterclockwise for display, "
        "as a phone held upright records); rows here are the stored frame's: give restamp, validate and resample "
        "detections from the picture as shown (OpenCV turns frames upright unless CAP_PROP_ORIENTATION_AUTO is 0) "
        "with --as-shown, or their times are off by up to a frame's readout"
        for d in cameras.values()
        if d.display_rotation_deg
    ]


def _rate_spread_ms(clock: FrameClock, times_ms: np.ndarray) -> np.ndarray:
    """Per frame (``times_ms``, shape (n_frames,)), the standard deviation (ms) the error of
    the clock's rate puts on its time counted from its first frame: the stamps' jitter beyond
    their grid's rounding (quantum**2 / 12) is white, and its share of
    :attr:`FrameClock.rate_std` is that rate's error; a steady clock's stamps rounded to a
    grid are not (their rounding errors spread evenly over a period, and the rate they leave
    is seven times better than ``rate_std``: 25 references of the kept benches on a 1 ms grid,
    error over it RMS 0.14; 20 with jittered stamps, 1.00). The reference's, in its frame
    times' sigma: the global clock is the reference's and its origin the reference's first
    frame, so no drift takes that error up and every camera's times share it (not against
    each other)."""
    beyond_grid = np.sqrt(max(clock.jitter_ms**2 - clock.quantum_ms**2 / 12.0, 0.0))
    share = beyond_grid / clock.jitter_ms if clock.jitter_ms > 0 else 0.0
    return share * clock.rate_std * np.abs(times_ms - times_ms[0])


#: A reference whose frame clock's rate is uncertain by more than this by its last frame
#: (ms, :func:`_rate_spread_ms`) is warned about.
REFERENCE_RATE_DOUBT_MS = 0.06


def _reference_rate_doubt(clocks: dict[str, FrameClock], reference: str, best: _Attempt) -> list[str]:
    """A warning where the reference's stamps leave its clock's rate uncertain by more than
    :data:`REFERENCE_RATE_DOUBT_MS` by its last frame: the global clock is the reference's,
    so every camera's times share that error (their times against each other do not);
    naming the tied camera whose clock is steadiest. A 3-hour recording averages jitter
    away; 8 s of 50 fps stamps jittered by 0.79 ms leave 17 ppm (random rig 10: four of its
    cameras 0.18-0.19 ms RMS off the truth, 0.08-0.09 against the reference)."""

    def spread_ms(name: str) -> float:
        return float(_rate_spread_ms(clocks[name], clocks[name].times_ms)[-1])

    if spread_ms(reference) <= REFERENCE_RATE_DOUBT_MS:
        return []
    steadiest = min(best.connected, key=spread_ms)
    if spread_ms(steadiest) >= spread_ms(reference) / 2.0:
        return []
    return [
        f"{best.cameras[reference].video}: the reference's frame stamps leave its clock's rate uncertain by "
        f"{clocks[reference].rate_std * 1e6:.1f} ppm, the global clock's: every camera's times may be off by up to "
        f"{spread_ms(reference):.3f} ms by the end of the recording alike (in the reference's sigma; not against "
        "each other); "
        f"{best.cameras[steadiest].video.name} has steadier stamps: make it the reference (--reference {steadiest})"
    ]


#: A camera's time per row whose standard deviation times its rows exceeds this (ms) is
#: warned about: it alone may put the frame's last rows that far off (the issue's maximum
#: error target).
ROW_TIME_DOUBT_MS = 0.1


def _row_time_doubts(best: _Attempt) -> list[str]:
    """A warning per camera whose time per row the events pin down too loosely for its rows'
    times (std x height > :data:`ROW_TIME_DOUBT_MS`): no split bands, few flashes, or equal
    frame rates (docs/architecture.md, the identifiability trap). Its sigma says so already."""
    warnings = []
    for name, solution in zip(best.connected, best.solution.cameras):
        detection = best.cameras[name]
        std = solution.row_time_std_ms
        if std * detection.height > ROW_TIME_DOUBT_MS:
            warnings.append(
                f"{detection.video}: its time per row is {solution.row_time_ms:.5f} ± {std:.5f} ms "
                f"(± {100 * std / abs(solution.row_time_ms):.1f} %; ± {std * detection.height:.2f} ms over its "
                f"{detection.height} rows, in its sigma): the flashes do not pin it down (too few, no band split "
                "across frames, or the same frame rate as the others); give it (--row-time CAMERA=MS) if known"
            )
    return warnings


#: A camera's exposure whose standard deviation exceeds this (ms) is warned about (the
#: issue's exposure target): its mid-exposure times carry half of it.
EXPOSURE_DOUBT_MS = 0.1


def _exposure_changes(
    best: _Attempt, detections: dict[str, CameraDetection], stepped: Sequence[str], solved_again: Sequence[str]
) -> tuple[list[str], dict[str, float], dict[str, list[_ShownExposure]], dict[str, float]]:
    """Per camera whose exposure changes while it records (:func:`_change_by_spans`, else
    :func:`_change_by_all_bands`, else :func:`_change_by_left_out_edges`): a warning naming
    what its bands show; how far the farthest exposure lies from the one solved, ms (into its
    exposure's sigma); and what the bands show frame by frame (:func:`_shown_exposures`, for
    :func:`_held_exposures`; empty where that is not known). Last, per camera whose bands
    show no change, whose lengths scatter (a change its trailing edges left out show
    explains none of that: MS9's rig-186 cam8, bands 19-156 rows long), that scatter about
    the solved exposure, ms, into its exposure's sigma
    (:func:`~flashsync.exposure_changes.length_scatter_rows`)."""
    warnings, changes_ms, shown, scatters_ms = [], {}, {}, {}
    for name, solution in zip(best.connected, best.solution.cameras):
        if not solution.exposure_ms > 0:
            continue
        detection = _in_use(best, detections, name)
        change = _change_by_spans(detection, solution, name in stepped)
        if not (change and change.shown) and name not in stepped:
            change = _change_by_all_bands(detection, solution, change, name in solved_again)
        if change is None and name not in stepped:
            change = _change_by_left_out_edges(best, name, detection, solution)
            scatter_rows = length_scatter_rows(detection, solution.exposure_ms / solution.row_time_ms)
            if scatter_rows > 0:
                scatters_ms[name] = scatter_rows * solution.row_time_ms
        if change is None:
            continue
        changes_ms[name], shown[name] = change.farthest_ms, change.shown
        warnings.append(
            f"{detection.video}: its exposure changes while it records (auto exposure?): its bands show "
            f"{', '.join(change.parts)}; {change.solved_on}, and restamp's t_center_ms "
            + (
                "takes each span's exposure (between spans, and beyond a lone band, the middle of the two, its sigma "
                "half their difference)"
                if change.shown
                else f"takes {solution.exposure_ms:.2f} ms throughout (its sigma ± {change.farthest_ms:.2f} ms)"
            )
            + "; set the camera's shutter to one exposure to record with it"
        )
    return warnings, changes_ms, shown, scatters_ms


class _Change(NamedTuple):
    """A change of exposure a camera's bands show (:func:`_exposure_changes`): what its
    warning names of them, how its times were solved, how far the farthest exposure lies
    from the one solved (ms) and what they show frame by frame (empty where not known)."""

    parts: list[str]
    solved_on: str
    farthest_ms: float
    shown: list[_ShownExposure]


def _change_by_spans(detection: CameraDetection, solution: CameraSolution, stepped: bool) -> _Change | None:
    """The change the spans of the detection's reading in use show
    (:func:`~flashsync.exposure_changes.exposure_spans`, or of its pulses for a camera
    ``stepped``, :func:`~flashsync.exposure_changes.pulse_spans`), and its bands split across
    two frames longer in sight (:func:`~flashsync.exposure_changes.outreaching_splits`),
    timed by its solved clock (``solution``): solved on the span of the most bands
    (:func:`~flashsync.exposure_changes.with_one_exposure`), what the bands show frame by
    frame known where that span is. None without either."""
    every_span = pulse_spans(detection) if stepped else exposure_spans(detection)
    splits = outreaching_splits(detection)
    if len(every_span) < 2 and not len(splits):
        return None
    main = max(every_span, key=lambda span: span.n_bands, default=None)
    every_ms = [solution.exposure_ms + (s.length_rows - main.length_rows) * solution.row_time_ms for s in every_span]
    spans, exposures_ms = (every_span, every_ms) if len(every_span) > 1 else ([], [])
    split_ms = split_lengths_ms(detection, splits, solution.row_time_ms)
    split_frames = detection.events.frame[splits.leading]
    parts = [_shown_part(e, s.first_frame, s.last_frame, s.n_bands) for e, s in zip(exposures_ms, spans)]
    if len(splits):
        parts.append(
            f"{split_ms[0]:.2f} ms in a band split across frames {split_frames[0]} and {split_frames[0] + 1}"
            if len(splits) == 1
            else f"{split_ms.min():.2f}-{split_ms.max():.2f} ms in {len(splits)} bands split across two frames "
            f"(frames {split_frames.min()}-{split_frames.max() + 1})"
        )
    return _Change(
        parts,
        f"its times take only the leading edges of the bands outside the {solution.exposure_ms:.2f} ms span",
        float(np.max(np.abs(np.array([*exposures_ms, *split_ms]) - solution.exposure_ms))),
        _shown_exposures(every_span, every_ms, main, split_frames, split_ms) if main is not None else [],
    )


def _shown_part(exposure_ms: float, first_frame: int, last_frame: int, n_bands: int) -> str:
    """An exposure a camera's bands show, as its warning names it."""
    if n_bands > 1:
        return f"{exposure_ms:.2f} ms over frames {first_frame}-{last_frame} ({n_bands} bands)"
    return f"{exposure_ms:.2f} ms in frame {first_frame} (one band: a change, or a band the others' lengths do not fit)"


def _change_by_all_bands(
    detection: CameraDetection, solution: CameraSolution, change: _Change | None, solved_again: bool
) -> _Change | None:
    """``change`` (:func:`_change_by_spans`; None where it found none) with what all of a
    camera's bands that tell their exposure show of it frame by frame (as
    :func:`_shown_exposures`), those split across two frames timed by its solved clock
    (``solution``; :func:`~flashsync.exposure_changes.all_band_spans`): the span nearest the
    solved exposure has it, where within :data:`~flashsync.exposure_changes.MIN_STEP_SHARE`
    of it, and each other one as much more or less as its bands are longer or shorter. The
    same ``change`` where they show one span, or spans whose lengths scatter (not one
    exposure and then another: a steady camera under flashes at two powers), or none near
    the solved exposure. After the solve: where ``change`` is None, every band's edges were
    solved on, unless the camera was ``solved_again`` without the trailing edges outside the
    span nearest its first solved exposure (:func:`_solved_on_one_exposure`). On six
    auto-exposure benches, of the 105 cameras whose change the bands fitted whole did not
    show, it found 10 (their exposure frame by frame 4.54 ms RMS off the truth, error/sigma
    up to 160; now 1.93 ms, up to 1.9), and it took a steady camera's one split band 0.68 ms
    too long for a change."""
    found = _spans_by_all_bands(detection, solution)
    if found is None:
        return change
    shown = found[2]
    farthest_ms = max(abs(s.exposure_ms - solution.exposure_ms) for s in shown)
    if change is None:
        parts = [_shown_part(s.exposure_ms, s.first_frame, s.last_frame, s.n_bands) for s in shown]
        parts[-1] += " (bands split across frames among them, timed by its solved clock)"
        solved_on = (
            f"its times take only the leading edges of the bands outside the {solution.exposure_ms:.2f} ms span "
            "(solved again without the others' trailing edges)"
            if solved_again
            else "its times take every band's edges"
        )
        return _Change(parts, solved_on, farthest_ms, shown)
    return change._replace(farthest_ms=max(change.farthest_ms, farthest_ms), shown=shown)


def _spans_by_all_bands(
    detection: CameraDetection, solution: CameraSolution
) -> tuple[list[ExposureSpan], ExposureSpan, list[_ShownExposure]] | None:
    """The spans of all of a camera's bands that tell their exposure
    (:func:`~flashsync.exposure_changes.all_band_spans`, timed by its solved clock
    ``solution``), the one nearest the solved exposure, and what they show frame by frame
    (:func:`_shown_exposures`): None where they show one span, spans whose lengths scatter,
    none within :data:`~flashsync.exposure_changes.MIN_STEP_SHARE` of the solved exposure, or
    nothing frame by frame."""
    spans = all_band_spans(detection, solution.row_time_ms)
    if len(spans) < 2 or not all(span.one_length for span in spans):
        return None
    solved_rows = solution.exposure_ms / solution.row_time_ms
    near = min(spans, key=lambda span: abs(span.length_rows - solved_rows))
    if abs(near.length_rows - solved_rows) > MIN_STEP_SHARE * max(near.length_rows, solved_rows):
        return None
    spans_ms = [solution.exposure_ms + (s.length_rows - near.length_rows) * solution.row_time_ms for s in spans]
    shown = _shown_exposures(spans, spans_ms, near, np.empty(0, np.int64), np.empty(0))
    return (spans, near, shown) if shown else None


def _solved_on_one_exposure(
    best: _Attempt,
    final: Callable[[dict[str, CameraDetection]], _Attempt],
    detections: dict[str, CameraDetection],
    stepped: Sequence[str],
) -> tuple[_Attempt, list[str]]:
    """``best`` solved again (``final``) without the trailing edges outside the span nearest
    its solved exposure of each camera whose change of exposure only all its bands show
    (:func:`_spans_by_all_bands`: bands split across frames, timed by its solved clock), as
    :func:`~flashsync.exposure_changes.with_one_exposure` leaves out those the bands fitted
    whole show before the solve; and those cameras."""
    trial, changed = dict(best.cameras), []
    for name, solution in zip(best.connected, best.solution.cameras):
        if name in stepped or not solution.exposure_ms > 0:
            continue
        detection = _in_use(best, detections, name)
        found = None if _change_by_spans(detection, solution, False) else _spans_by_all_bands(detection, solution)
        if found is not None:
            trial[name] = outside_left_out(best.cameras[name], found[0], found[1])
            changed.append(name)
    return (final(trial), changed) if changed else (best, changed)


def _in_use(best: _Attempt, detections: dict[str, CameraDetection], name: str) -> CameraDetection:
    """Camera ``name``'s detection of ``detections`` (every band) on its frame clock and in the
    reading ``best`` chose."""
    return detections[name].retimed(best.cameras[name].frame_times_ms).read_flipped(best.cameras[name].flipped)


#: Fewest trailing edges the solve left out, one after the other, whose lateness shows a
#: change of exposure (:func:`_change_by_left_out_edges`) ...
LEFT_OUT_STEP_EDGES = 2
#: ... each within this share of their median lateness.
LEFT_OUT_AGREE = 0.25


def _change_by_left_out_edges(
    best: _Attempt, name: str, detection: CameraDetection, solution: CameraSolution
) -> _Change | None:
    """The change of exposure shown by a camera's trailing edges whose leading edges are
    hidden (one exposure after their flash) where the solve left out, or did not match
    (:func:`_unmatched_lateness`), :data:`LEFT_OUT_STEP_EDGES` or more of them one after the
    other, each as late (or as early) as their median within :data:`LEFT_OUT_AGREE` of it,
    and that median is a step (:data:`~flashsync.exposure_changes.MIN_STEP_SHARE` of the
    exposure and a row at least): those frames held the solved exposure plus that median.
    Its other trailing edges and its bands as long as the solved exposure
    (:func:`_solved_length_frames`) hold that; none may lie among them. Without such a run,
    one such edge a step late or early before the first frame that held the solved exposure
    or after the last shows its own frame's exposure: beyond them the model holds the middle
    of the two, its sigma half their difference. An edge alone may not be a change: of the
    51 such edges on seventeen benches (2026-12-06; the forty-eighth stop took one only
    where lone leading edges bore it out, their bands ended out of sight where the solved
    exposure would have ended them in sight), 27 lay where the exposure had changed (MT8's
    rig-171 cam8, 12.78 ms then 21.27 from frame 167, one trailing edge 8.46 ms late at
    frame 183: frame by frame 5.6 ms RMS off at error/sigma 60), 24 where it held (edges
    read late on a pulse's tail, or matched to another flash): their frames' exposure then
    0.52 -> 0.83 ms RMS off, within their sigma.

    A camera read fast (a readout much shorter than its frame period) shows few bands
    whole: random rig 116 of the mixed bench (``--readout 0.4:0.8 --flash-powers 0.5
    --exposure-changes 0.5``), its reference's exposure 12.42 ms then 17.99 from frame 192,
    one band whole, its last four trailing edges left out 5.62-7.47 ms late: its exposure
    frame by frame was 3.83 ms RMS off under a sigma of 0.11 ms. None where they show none."""
    matches = best.matches
    mine = np.flatnonzero((matches.camera == name) & matches.trailing)
    unmatched_frames, unmatched_ms = _unmatched_lateness(best, name, detection, solution)
    frames = np.concatenate([matches.frame[mine], unmatched_frames])
    late_ms = np.concatenate([best.solution.residual_ms[mine], unmatched_ms])
    left_out = np.concatenate([~best.solution.inlier[mine], np.ones(len(unmatched_frames), bool)])
    order = np.argsort(frames, kind="stable")
    frames, late_ms, left_out = frames[order], late_ms[order], left_out[order]
    floor_ms = max(MIN_STEP_ROWS * solution.row_time_ms, MIN_STEP_SHARE * solution.exposure_ms)
    held = np.sort(np.concatenate([frames[~left_out], _solved_length_frames(detection, solution)]))
    if not len(held):
        return None
    run = _agreeing_run(late_ms, left_out, floor_ms)
    if run is None:
        stepped = np.flatnonzero(left_out & (np.abs(late_ms) >= floor_ms))
        if (
            len(stepped) != 1
            or held[0] <= frames[stepped[0]] <= held[-1]
            or solution.exposure_ms + late_ms[stepped[0]] <= 0
        ):
            return None
        run = slice(stepped[0], stepped[0] + 1)
    first, last = int(frames[run.start]), int(frames[run.stop - 1])
    if np.any((held >= first) & (held <= last)):
        return None
    step_ms = float(np.median(late_ms[run]))
    shown = [
        _ShownExposure(int(part[0]), int(part[-1]), solution.exposure_ms, len(part), len(part) >= 2, True)
        for part in (held[held < first], held[held > last])
        if len(part)
    ]
    n_late = run.stop - run.start
    shown.append(_ShownExposure(first, last, solution.exposure_ms + step_ms, n_late, n_late > 1, False))
    shown.sort()
    solved_on = (
        f"its times take none of those {n_late} trailing edges" if n_late > 1 else "its times do not take that edge"
    )
    return _Change([_left_out_part(s) for s in shown], solved_on, abs(step_ms), shown)


def _left_out_part(shown: _ShownExposure) -> str:
    """An exposure :func:`_change_by_left_out_edges` found, as its warning names it."""
    if not shown.solved and shown.n_bands == 1:
        return (
            f"{shown.exposure_ms:.2f} ms in frame {shown.first_frame} (one trailing edge the solve left out or did "
            "not match: a change, or an edge read late or early)"
        )
    return (
        f"{shown.exposure_ms:.2f} ms over frames {shown.first_frame}-{shown.last_frame} ({shown.n_bands} "
        + ("bands or trailing edges" if shown.solved else "trailing edges the solve left out or did not match")
        + ")"
    )


def _solved_length_frames(detection: CameraDetection, solution: CameraSolution) -> np.ndarray:
    """The frames (leading edges') of the camera's bands that show its solved exposure
    (``solution``) within :data:`~flashsync.exposure_changes.MIN_STEP_SHARE` of it: fitted
    whole within one frame, or split across two frames and timed by its solved clock."""
    events, bands = detection.events, detection.events.bands()
    complete = bands.take(bands.complete)
    within, lengths = _within_one_frame(events, complete)
    split = complete.take(split_across_frames(events, complete))
    lengths_ms = np.concatenate(
        [lengths * solution.row_time_ms, split_lengths_ms(detection, split, solution.row_time_ms)]
    )
    frames = events.frame[np.concatenate([within.leading, split.leading])]
    return frames[np.abs(lengths_ms - solution.exposure_ms) <= MIN_STEP_SHARE * solution.exposure_ms]


def _unmatched_lateness(
    best: _Attempt, name: str, detection: CameraDetection, solution: CameraSolution
) -> tuple[np.ndarray, np.ndarray]:
    """The frame and lateness (ms, shapes (n,)) of each trailing edge of the camera whose
    leading edge is hidden that no flash matched, against the one flash of the rig it can
    be of: matched by no other edge of the camera, at most a frame period before the edge's
    row ended its exposure. Lateness as a matched edge's residual: how much longer than the
    solved exposure its row's was. An exposure that changed puts such edges as far from
    their flashes as it changed, too far to match (random rig 154 with all four departures,
    ``--preflash 40 --readout 0.4:0.8 --flash-powers 0.5 --exposure-changes 0.5``: cam3 13.66
    ms, then 8.80 from frame 243; none of its three lone trailing edges before the change
    matched, two of them 4.7 and 4.9 ms late)."""
    events, bands, mine = detection.events, detection.events.bands(), best.matches.camera == name
    matched = np.isin(bands.event, best.matches.event[mine])
    edge = bands.trailing[(bands.leading < 0) & (bands.trailing >= 0) & ~matched]
    free = np.setdiff1d(np.flatnonzero(np.isfinite(best.solution.flash_ms)), best.matches.flash[mine])
    flash_ms = best.solution.flash_ms[free]
    clock = best.clock(name)
    ended_ms = clock.t_global_ms(events.frame[edge], events.row[edge])
    period_ms = median_step_ms(clock.frame_times_ms) * clock.alpha
    candidates = (flash_ms[None, :] <= ended_ms[:, None]) & (flash_ms[None, :] >= ended_ms[:, None] - period_ms)
    one = candidates.sum(axis=1) == 1
    started_ms = flash_ms[np.nonzero(candidates[one])[1]]
    return events.frame[edge[one]], ended_ms[one] - solution.exposure_ms - started_ms


def _agreeing_run(late_ms: np.ndarray, left_out: np.ndarray, floor_ms: float) -> slice | None:
    """The longest run of ``left_out`` edges one after the other (shape (n,), in frame order)
    whose lateness ``late_ms`` (ms) lies within :data:`LEFT_OUT_AGREE` of its median, that
    median ``floor_ms`` or more either way, of :data:`LEFT_OUT_STEP_EDGES` edges or more;
    None where there is none."""
    best = None
    for start in range(len(late_ms)):
        stop = start
        while stop < len(late_ms) and left_out[stop]:
            stop += 1
            median = float(np.median(late_ms[start:stop]))
            agree = np.all(np.abs(late_ms[start:stop] - median) <= LEFT_OUT_AGREE * abs(median))
            longer = stop - start >= LEFT_OUT_STEP_EDGES and (best is None or stop - start > best.stop - best.start)
            if agree and abs(median) >= floor_ms and longer:
                best = slice(start, stop)
    return best


class _ShownExposure(NamedTuple):
    """An exposure a camera's bands show (:func:`_shown_exposures`): its first and last frame,
    ms, bands, whether it holds those frames (:attr:`~flashsync.model.HeldExposure.holds_frames`)
    and whether the solve was on it."""

    first_frame: int
    last_frame: int
    exposure_ms: float
    n_bands: int
    holds_frames: bool
    solved: bool


def _shown_exposures(
    spans: list[ExposureSpan],
    spans_ms: list[float],
    main: ExposureSpan,
    split_frames: np.ndarray,
    split_ms: np.ndarray,
) -> list[_ShownExposure]:
    """What a camera's bands show of its exposure, in frame order: each span (``spans``,
    :func:`~flashsync.exposure_changes.exposure_spans`, their exposures ``spans_ms``, ms;
    ``main`` the one solved on) and each band split across frames at ``split_frames`` (its
    exposure ``split_ms``, ms; those within a span that holds its frames left out). Lone bands
    one after the other whose exposures agree (:data:`~flashsync.exposure_changes.MIN_STEP_SHARE`
    of their median) hold the frames from the first to the last (:func:`_lone_runs`). None
    (an empty list) where that leaves one, or where two overlap (a band split into the frame
    that ends a span): the camera's sigma covers them all then."""
    shown = [
        _ShownExposure(s.first_frame, s.last_frame, ms, s.n_bands, s.n_bands >= 2 and s.one_length, s is main)
        for s, ms in zip(spans, spans_ms)
    ]
    for frame, ms in zip(split_frames.tolist(), split_ms.tolist()):
        if not any(s.holds_frames and s.first_frame <= frame <= s.last_frame for s in shown):
            shown.append(_ShownExposure(frame, frame, ms, 1, False, False))
    shown.sort()
    overlap = any(after.first_frame <= before.last_frame for before, after in pairwise(shown))
    return [] if overlap or len(shown) < 2 else _lone_runs(shown)


def _lone_runs(shown: list[_ShownExposure]) -> list[_ShownExposure]:
    """``shown`` (in frame order) with each run of lone bands (one band each, holding no
    frames) whose exposures lie within :data:`~flashsync.exposure_changes.MIN_STEP_SHARE` of
    the run's median made one span that holds its frames: a camera whose exposure grew till
    its bands split across frames shows it band by band (on six auto-exposure benches, 15
    runs of 2-7 such bands, each within 0.65 ms of the one exposure the truth held over
    their frames, 0.1 ms but one)."""

    def lone(s: _ShownExposure) -> bool:
        return s.n_bands == 1 and not (s.holds_frames or s.solved)

    runs: list[list[_ShownExposure]] = []
    for s in shown:
        run = runs[-1] if runs and lone(runs[-1][-1]) and lone(s) else []
        median = float(np.median([r.exposure_ms for r in run])) if run else 0.0
        if run and abs(s.exposure_ms - median) <= MIN_STEP_SHARE * median:
            run.append(s)
        else:
            runs.append([s])
    return [
        run[0]
        if len(run) == 1
        else _ShownExposure(
            run[0].first_frame,
            run[-1].last_frame,
            float(np.median([r.exposure_ms for r in run])),
            len(run),
            True,
            False,
        )
        for run in runs
    ]


def _held_exposures(clock: CameraClock, shown: list[_ShownExposure]) -> tuple[HeldExposure, ...]:
    """The exposures a camera's bands show (``shown``), each with its standard deviation, ms:
    the solved one's (``clock``'s), for a median of fewer bands than the solved one's as much
    more (``sqrt(1 + solved bands / bands)``, every band's length as noisy), and the time per
    row's over the rows it differs by."""
    row_time_std = float(np.sqrt(clock.covariance[2, 2]))
    solved_bands = next(s.n_bands for s in shown if s.solved)
    held = []
    for s in shown:
        share = 1.0 if s.solved else np.sqrt(1.0 + solved_bands / s.n_bands)
        rows = (s.exposure_ms - clock.exposure_ms) / clock.row_time_ms
        std = float(np.hypot(clock.exposure_std_ms * share, rows * row_time_std))
        held.append(HeldExposure(s.first_frame, s.last_frame, float(s.exposure_ms), std, s.n_bands, s.holds_frames))
    return tuple(held)


def _exposure_doubts(best: _Attempt, told: set[str]) -> list[str]:
    """A warning per camera whose exposure the band lengths pin down more loosely than
    :data:`EXPOSURE_DOUBT_MS` (few bands with both edges, lengths that differ from flash to
    flash, or a time per row the flashes leave loose: a length is in rows; its sigma with
    its lengths' scatter, :func:`_exposure_changes`, without its tone curve's part,
    :func:`_tone_std_ms`, which every camera has), but the cameras ``told`` of already.
    Its sigma says so already."""

    def lengths_std_ms(name: str, solution: CameraSolution) -> float:
        tone = _tone_std_ms(best.cameras[name], solution.row_time_ms)
        return float(np.sqrt(max(solution.exposure_std_ms**2 - tone**2, 0.0)))

    return [
        f"{best.cameras[name].video}: its exposure is {solution.exposure_ms:.2f} ± {solution.exposure_std_ms:.2f} ms: "
        "its bands' lengths do not pin it down to 0.1 ms (few bands with both edges, lengths that differ from flash "
        "to flash, pulses that may all outlast it, or a loose time per row); restamp's t_center_ms carries half of "
        "it; give it (restamp --exposure CAMERA=MS) if known"
        for name, solution in zip(best.connected, best.solution.cameras)
        if solution.exposure_ms > 0 and lengths_std_ms(name, solution) > EXPOSURE_DOUBT_MS and name not in told
    ]


def _free_drifts(best: _Attempt, reference: str) -> list[str]:
    """A warning per camera whose drift prior the events contradicted, solved without it
    (:func:`~flashsync.solve.solve_with_drift_model`)."""
    return [
        f"{best.cameras[best.connected[c]].video}: its clock runs "
        f"{(best.solution.cameras[c].alpha - 1.0) * 1e6:+.0f} ppm from {reference}'s, beyond the "
        f"± {DRIFT_PRIOR_STD * 1e6:.0f} ppm camera clocks keep; solved without that prior (its clock's rate "
        "changes during the recording, or its stamps were written at a nominal frame rate)"
        for c in best.solution.free_drift
    ]


def _readout_doubts(
    best: _Attempt, rivals: dict[str, _Attempt], reference: str
) -> tuple[dict[str, np.ndarray], dict[str, float], list[str]]:
    """Cameras whose other reading (``rivals``, from :func:`_best_readout`) explains the
    flashes about as well as the chosen one (its :attr:`_Attempt.evidence` less than
    :data:`DECIDED_LOG_LIKELIHOOD` below it, or above it by less: not a lead that decides;
    nor, above it by more, one that :func:`_chance_lead` keeps from turning a camera):
    per camera, how far the two readings' times of each frame are apart (ms, the largest
    over its rows; into its sigma), how far their exposures are (ms, where both read one;
    into the exposure's sigma), and a warning line each. A band's length is the same rows
    either way, but each reading times its rows and parts its length into exposure and
    pulse in its own way: random rig 135 of a bench of TTL flashes at two powers with auto
    exposure (two 25 fps cameras, both read the wrong way round, warned) had its cam2's
    4.1 ms exposure at 0.42 ± 0.15 ms, 24 sigmas off; the other reading's was 2.31 ms."""
    spreads, exposures_ms, warnings = {}, {}, []
    for name, other in rivals.items():
        if name not in best.connected or name not in other.connected or name in other.implausible:
            continue
        if best.evidence >= other.evidence + DECIDED_LOG_LIKELIHOOD:
            continue
        margin = best.score - other.score
        # a lead that decides, short of what turning a camera few flashes tie needs
        chance = (
            _chance_lead(other, best, best.cameras) if other.evidence >= best.evidence + DECIDED_LOG_LIKELIHOOD else 0.0
        )
        chosen, rival = best.model(reference).cameras[name], other.model(reference).cameras[name]
        spreads[name] = _frame_gaps_ms(chosen, rival)
        if chosen.exposure_ms is not None and rival.exposure_ms is not None:
            exposures_ms[name] = abs(chosen.exposure_ms - rival.exposure_ms)
        exposure = f" and its exposure by {exposures_ms[name]:.2f} ms" if name in exposures_ms else ""
        way = "bottom-up (upside down)" if chosen.flipped else "top-down (upright)"
        few = (
            f", and {chance:.1f} more (a flash's worth per camera it turns that fewer than {FEW_FLASHES} flashes tie)"
            if chance
            else ""
        )
        freed = other.freed_drift_cost - best.freed_drift_cost
        drift = f"; the other way pays {freed:.1f} for a clock drift it frees from the prior" if freed > 0 else ""
        warnings.append(
            f"{best.cameras[name].video}: read {way}, but the flashes fit the other way about as well "
            f"(log-likelihood {-margin:+.1f} against this reading's; a choice needs a lead of "
            f"{DECIDED_LOG_LIKELIHOOD:g}, {UPSIDE_DOWN_PRIOR:g} more per camera read upside down{few}{drift}); "
            f"its times may be off by up to {float(spreads[name].max()):.2f} ms{exposure} "
            "(in its sigma); give its mounting (--flipped) if known"
        )
    return spreads, exposures_ms, warnings


def _doubts_on_reference(
    final: _Attempt,
    cameras: dict[str, CameraDetection],
    undecided: list[str],
    warned: set[str],
    reference: str,
    attempt: Callable[[dict[str, CameraDetection]], _Attempt],
) -> tuple[dict[str, np.ndarray], dict[str, float], list[str]]:
    """:func:`_readout_doubts` of the readings chosen on the search reference, checked on the
    ``reference`` given (``final`` and ``attempt`` solve on it) against the detected reading of
    the cameras it flipped (not already ``warned`` about). The score depends a little on the
    reference, and a flip that leads by the margin on one may trail on the other: rig-18 of
    the random rigs (three 59.94 fps cameras) flipped cam1 with a lead of 5.3 on cam2 that
    trailed by 5.3 on cam1, 15 ms off, with a σ of 0.7 ms and no warning."""
    flipped = [n for n in undecided if n not in warned and final.cameras[n].flipped != cameras[n].flipped]
    if not flipped:
        return {}, {}, []
    detected = {n: d.read_flipped(cameras[n].flipped) if n in flipped else d for n, d in final.cameras.items()}
    try:
        rival = attempt(detected)
    except FlashsyncError:
        return {}, {}, []
    return _readout_doubts(final, dict.fromkeys(flipped, rival), reference)


def solve_pairs(detections: Sequence[CameraDetection], **options) -> list[tuple[str, str, SyncModel | str]]:
    """Every pair of cameras solved on its own, camera b on camera a's clock (the paper's
    Table 2): ``(a, b, model)``, or ``(a, b, reason)`` where the pair cannot be solved or b
    cannot be tied to a. ``options`` go to :func:`synchronize`."""
    results = []
    for a, b in combinations(detections, 2):
        try:
            model, _ = synchronize([a, b], reference=a.camera, **options)
        except FlashsyncError as error:
            results.append((a.camera, b.camera, str(error)))
            continue
        results.append(
            (a.camera, b.camera, model if b.camera in model.cameras else f"{b.camera} could not be tied to {a.camera}")
        )
    return results


@dataclass(frozen=True)
class Matches:
    """The sync events (:func:`_sync_events`: a leading edge, or a trailing edge whose
    leading edge is hidden) that belong to a flash seen by two or more cameras, arrays of
    shape (n,).

    Attributes
    ----------
    flash : int array
        Flash number, 0..n_flashes-1.
    camera : str array
        Camera name.
    camera_index : int array
        Index of the camera among the cameras solved.
    event, frame : int arrays
        The detector's event number and the decoded frame of the edge.
    row, q : float arrays
        Stored-image row and readout row of the edge.
    t_frame_ms : float array
        The frame's time (frame clock), ms.
    edge_sigma : float array
        The edge's noise in units of a clean one's (:func:`_edge_sigma`).
    trailing : bool array
        The edge is a trailing edge (one exposure after its flash).
    toward_cut_rows : float array
        How far a lone edge may lie from where its flash puts it, readout rows towards the
        frame's cut that hides its band's other edge (:func:`_toward_cut_rows`; 0 for others).
    misread_decay_rows : float array
        How far the edge's half-light may move with an error its camera's readings of long
        pulses share, readout rows (:func:`_misread_decay_rows`; 0 for others).
    """

    flash: np.ndarray
    camera: np.ndarray
    camera_index: np.ndarray
    event: np.ndarray
    frame: np.ndarray
    row: np.ndarray
    q: np.ndarray
    t_frame_ms: np.ndarray
    edge_sigma: np.ndarray
    trailing: np.ndarray
    toward_cut_rows: np.ndarray
    misread_decay_rows: np.ndarray

    def __len__(self) -> int:
        return len(self.flash)

    def table(self, solution: Solution) -> pd.DataFrame:
        """The matched events with the solve's results (:data:`~flashsync.model.MATCHED_EVENT_COLUMNS`)."""
        n_events = len(self)
        return pd.DataFrame(
            {
                "flash": self.flash,
                "camera": list(self.camera),
                "event": self.event,
                "frame": self.frame,
                "row": self.row,
                "t_frame_ms": self.t_frame_ms,
                "t_global_ms": solution.flash_ms[self.flash],
                "residual_ms": solution.residual_ms[:n_events],
                "inlier": solution.inlier[:n_events],
            },
        ).astype(MATCHED_EVENT_COLUMNS)


@dataclass
class _Attempt:
    """One matching and solve with given readout directions."""

    cameras: dict[str, CameraDetection]
    connected: list[str]
    alignments: dict[tuple[str, str], PairAlignment]
    warnings: list[str]
    matches: Matches
    observations: Observations
    solution: Solution
    priors: Priors
    reference: str
    distrusted_flicker: tuple[str, ...] = ()
    #: per camera, how far a pair's other shift that explains the edges about as well moves
    #: its frames' times (ms, largest over its rows; :func:`_shift_doubts`)
    shift_spreads: dict[str, np.ndarray] = field(default_factory=dict)

    @cached_property
    def implausible(self) -> list[str]:
        """Cameras whose solved time per row cannot be a sensor's: not positive, or reading
        the visible rows takes longer than a frame period. Read the wrong way up, a camera's
        bands still fit the other cameras' flashes, with a negative time per row: its rows
        then run backwards in time, the trailing edges (one exposure late) standing in for
        the leading ones."""
        names = []
        for index, name in enumerate(self.connected):
            detection = self.cameras[name]
            row_time = self.solution.cameras[index].row_time_ms
            if not 0.0 < row_time * detection.height <= READOUT_SLACK * median_step_ms(detection.frame_times_ms):
                names.append(name)
        return names

    @cached_property
    def score(self) -> float:
        """Log-likelihood of all the cameras' band edges under these readout directions (both
        edges of every band are fitted, :func:`_observations`): inliers Gaussian with their
        camera's noise for edges of their kind (the solve's group scale, times the edge's
        sigma factor), every other edge (rejected, or matched to nothing, or of a camera
        whose time per row is :attr:`implausible`) uniform over a frame period. Counting
        inliers alone would prefer a wrong direction whose loose fit (a scale ten times
        larger) lets one more event in; one scale for all cameras would let a camera read
        the wrong way up win by dropping its misfits from the rig's scale (rig-5: its other
        cameras' scale fell 30 %). A camera's scale counts as :data:`SCORE_MIN_SIGMA_MS` at
        least: with few flashes a wrong reading can fit its few events almost exactly (a
        scale of a few microseconds) and outscore the right one, which matched more events."""
        inlier, sigma = self._scored_sigma_ms
        return edge_log_likelihood(sigma[inlier], self.n_edges, _uniform_ms(self.cameras))

    @cached_property
    def _scored_sigma_ms(self) -> tuple[np.ndarray, np.ndarray]:
        """Per observation, whether :attr:`score` counts it Gaussian (an inlier of a camera
        with a plausible time per row) and the noise it counts it at (ms); shapes (n,)."""
        camera = self.observations.camera
        implausible = [self.connected.index(name) for name in self.implausible]
        noise = np.array([[c.edge_sigma_ms, c.trailing_sigma_ms] for c in self.solution.cameras])
        sigma = np.maximum(
            np.nan_to_num(noise[camera, self.observations.trailing.astype(np.int64)], nan=SCORE_MIN_SIGMA_MS),
            SCORE_MIN_SIGMA_MS,
        )
        return self.solution.inlier & ~np.isin(camera, implausible), sigma * self.solution.sigma_factor

    def flash_worth(self, name: str) -> float:
        """What one flash more tying camera ``name`` adds to :attr:`score`: a leading and a
        trailing edge at the mean Gaussian log-density of its inlier edges instead of uniform
        over a frame period (0 where it has no inlier edge)."""
        inlier, sigma = self._scored_sigma_ms
        mine = sigma[inlier & (self.observations.camera == self.connected.index(name))]
        if not mine.size:
            return 0.0
        density = -np.log(mine * np.sqrt(2.0 * np.pi)) - 0.5
        return 2.0 * float(np.mean(density) + np.log(_uniform_ms(self.cameras)))

    @cached_property
    def n_edges(self) -> int:
        """Every band edge the cameras' readings hold, fitted or not (what a score counts)."""
        return sum(len(_sync_events(d)) + len(_trailing_edges(d)) for d in self.cameras.values())

    @property
    def evidence(self) -> float:
        """The :attr:`score` less :data:`UPSIDE_DOWN_PRIOR` per camera read upside down and
        what a drift its events freed from the prior costs (:meth:`freed_drift_cost`): what
        readings are compared by (:func:`_best_readout`, :func:`_readout_doubts`)."""
        return self.score - UPSIDE_DOWN_PRIOR * sum(d.flipped for d in self.cameras.values()) - self.freed_drift_cost

    @property
    def freed_drift_cost(self) -> float:
        """Log-density that the clock drifts the events freed from their prior
        (:attr:`~flashsync.solve.Solution.free_drift`) lose under a heavy-tailed prior of the
        same width, ``log(1 + (drift / std) ** 2)`` each (a Cauchy's: clocks keep a few tens
        of ppm, stamps written at a nominal rate 1000 ppm and more). A reading of the rig that
        fits its edges only with a drift far beyond what clocks keep pays for it: AP1's
        rig-893 read as its mirror (every camera the wrong way up, 18-31 ms off) led the
        right reading by 6.6 with its cam3 at -1500 ppm."""
        priors = self.priors
        cost = 0.0
        for c in self.solution.free_drift:
            std = max(priors.drift_std or DRIFT_PRIOR_STD, priors.wider_drift_std.get(c, 0.0))
            cost += float(np.log1p(((self.solution.cameras[c].alpha - 1.0) / std) ** 2))
        return cost

    def with_scatter(self, exposure_spreads: dict[str, float], refit_rows: np.ndarray) -> _Attempt:
        """This attempt with what the residuals do not show added to every camera's
        covariance and exposure variance: the scatter of the solve with each flash left out
        (:func:`~flashsync.jackknife.flash_scatter`: the errors a flash brings to all its
        edges), what an error common to a camera's split bands moves
        (:func:`~flashsync.jackknife.split_scatter`), what its lone edges' lying further
        from the frame's cut than their flashes put them moves (:func:`_toward_cut_rows`,
        :func:`~flashsync.jackknife.moved_scatter`), what an error common to its readings of
        the pulses that outlast its exposure moves (:func:`_misread_decay_rows`), what
        solving flashes that may be one matched apart as one moves (:meth:`flashes_apart`,
        :func:`~flashsync.jackknife.rival_scatter`), what the edges of bands the detector
        fitted too short move (``refit_rows``, readout rows per observation:
        :func:`_refit_rows`) and what a camera's split bands left out move where they
        disagree with the other edges (:func:`~flashsync.jackknife.split_left_out_scatter`);
        what the tone curves may move its times by (:meth:`tone_shift_std_ms`) in its
        shift's; and :data:`EXPOSURE_FLOOR_MS`, a share of the widening a tone curve would
        give its bands (:data:`TONE_WIDENING_SHARE`) and the camera's ``exposure_spreads``
        (ms, where given) in the exposure's (the flashes' scatter over the solves that read it; a
        change to a solve that left it unread adds none)."""
        solve = (self.observations, len(self.connected), self.connected.index(self.reference), self.solution)
        toward_cut = np.zeros(len(self.observations.camera))
        toward_cut[: len(self.matches)] = self.matches.toward_cut_rows  # the matched edges come first
        misread = np.zeros(len(self.observations.camera))
        misread[: len(self.matches)] = self.matches.misread_decay_rows
        if self.observations.leading_of is not None:  # a band's trailing edge moves with its leading one
            paired = self.observations.leading_of >= 0
            misread[paired] = misread[self.observations.leading_of[paired]]
        apart = self.flashes_apart()
        scatter = [
            flashes + split + cut + decay + refit + one
            for flashes, split, cut, decay, refit, one in zip(
                flash_scatter(*solve, self.priors),
                split_scatter(*solve, self.priors),
                moved_scatter(*solve, self.priors, toward_cut),
                moved_scatter(*solve, self.priors, misread),
                moved_scatter(*solve, self.priors, refit_rows),
                rival_scatter(
                    replace(self.observations, flash=_as_one(self.observations.flash, apart)), *solve[1:], self.priors
                )
                if apart
                else [0.0] * len(self.connected),
            )
        ]
        row_time_var = [camera.covariance[2, 2] + extra[2, 2] for camera, extra in zip(self.solution.cameras, scatter)]
        left_out = split_left_out_scatter(*solve, self.priors, np.array(row_time_var))
        scatter = [extra + split_out for extra, split_out in zip(scatter, left_out)]
        for name, extra in zip(self.connected, scatter):
            extra[1, 1] += self.tone_shift_std_ms(name) ** 2  # beta_ms: a shift of all its times
        cameras = [
            replace(
                camera,
                covariance=camera.covariance + extra[:-1, :-1],
                exposure_std_ms=float(
                    np.sqrt(
                        camera.exposure_std_ms**2
                        + np.nan_to_num(extra[-1, -1])
                        + EXPOSURE_FLOOR_MS**2
                        + _tone_std_ms(self.cameras[name], camera.row_time_ms) ** 2
                        + exposure_spreads.get(name, 0.0) ** 2
                    )
                ),
            )
            for name, camera, extra in zip(self.connected, self.solution.cameras, scatter)
        ]
        return replace(self, solution=replace(self.solution, cameras=cameras))

    def flashes_apart(self) -> dict[int, int]:
        """The solved flashes that may be one flash matched apart, by flash number: the
        earlier flash each is one with. A flash closer than the matching can tell apart
        (:func:`~flashsync.match.match_tolerance_ms`, readouts known) to the one before it,
        which none of the cameras that saw it saw (nor those of the flashes already one with
        that one), is one with it."""
        flash_ms, observations = self.solution.flash_ms, self.observations
        periods = [median_step_ms(self.cameras[name].frame_times_ms) for name in self.connected]
        tolerance = match_tolerance_ms(periods, readout_known=True)
        seen = {
            int(f): set(observations.camera[observations.flash == f].tolist()) for f in np.unique(observations.flash)
        }
        order = sorted((f for f in seen if np.isfinite(flash_ms[f])), key=lambda f: flash_ms[f])
        apart: dict[int, int] = {}
        for before, after in zip(order, order[1:]):
            first = apart.get(before, before)
            if flash_ms[after] - flash_ms[before] < tolerance and not seen[first] & seen[after]:
                apart[after] = first
                seen[first] |= seen[after]
        return apart

    def tone_shift_std_ms(self, name: str) -> float:
        """How far the tone curves may shift camera ``name``'s times against the reference's,
        ms (one standard deviation; 0 for the reference). A tone curve moves each edge of a
        band out by half the band's widening (:func:`_tone_widening_ms`): a camera's leading
        edges come early by half of it, every flash alike (and its midpoints less half the
        exposure its lengths read long), so its times come late by as much; against the
        reference's, by the difference of the two, unseen by the residuals and the flashes
        left out. Which camera has a curve is not known; the larger of the two cameras' half
        :func:`_tone_std_ms` bounds it (one curved, the other linear)."""
        if name == self.reference:
            return 0.0
        return max(
            _tone_std_ms(self.cameras[camera], self.solution.cameras[self.connected.index(camera)].row_time_ms) / 2.0
            for camera in (name, self.reference)
        )

    def model(self, reference: str) -> SyncModel:
        clocks = {name: self.clock(name) for name in self.connected}
        return SyncModel(reference, clocks, self.matches.table(self.solution))

    def clock(self, name: str) -> CameraClock:
        """The solved clock of connected camera ``name``."""
        d, s = self.cameras[name], self.solution.cameras[self.connected.index(name)]
        return CameraClock(
            name,
            d.frame_times_ms,
            d.height,
            d.width,
            s.alpha,
            s.beta_ms,
            s.row_time_ms,
            d.flipped,
            s.covariance,
            float(s.exposure_ms) if s.exposure_ms > 0 else None,
            str(d.video),
            s.knots_ms,
            s.warp_ms,
            display_rotation_deg=d.display_rotation_deg,
            exposure_std_ms=float(s.exposure_std_ms) if s.exposure_ms > 0 else None,
        )


def _as_one(flash: np.ndarray, apart: dict[int, int]) -> np.ndarray:
    """Flash numbers (n,) with those of :meth:`_Attempt.flashes_apart` made the earlier one's."""
    return np.array([apart.get(f, f) for f in flash.tolist()], dtype=np.int64)


def _apart_warnings(best: _Attempt) -> list[str]:
    """A line for each camera of a flash that may be one with an earlier one
    (:meth:`_Attempt.flashes_apart`): what the sigma took in, and how to decide."""
    observations, flash_ms = best.observations, best.solution.flash_ms
    lines = []
    for after, before in best.flashes_apart().items():
        theirs = [best.connected[c] for c in dict.fromkeys(observations.camera[observations.flash == before].tolist())]
        for c in dict.fromkeys(observations.camera[observations.flash == after].tolist()):
            lines.append(
                f"{best.cameras[best.connected[c]].video}: its flash at {flash_ms[after]:.1f} ms lies "
                f"{flash_ms[after] - flash_ms[before]:.1f} ms from one that {', '.join(theirs)} saw and it did not, "
                "closer than the matching tells flashes apart: they may be one flash matched apart; what solving "
                "them as one moves is in every camera's sigma; name one flash both saw (--anchor CAMERA:EVENT, the "
                "events table) if so"
            )
    return lines


def _tone_std_ms(detection: CameraDetection, row_time_ms: float) -> float:
    """The part of the camera's exposure's standard deviation its unknown tone curve makes, ms
    (:data:`TONE_WIDENING_SHARE`)."""
    return TONE_WIDENING_SHARE * _tone_widening_ms(detection, row_time_ms)


def _tone_widening_ms(detection: CameraDetection, row_time_ms: float) -> float:
    """How much longer than the exposure a tone curve of :data:`TONE_GAMMA` would make the
    camera's bands, ms, from the median relative change and the median 25 %-to-75 % rise (ms
    at ``row_time_ms``) of its flash bands whose ramps the detector measured, each ramp taken
    as straight in light (twice its rise) and each edge where the pixel value, not the light,
    is halfway; 0 where no ramp was measured."""
    events = detection.events
    measured = (events.band == Band.PULSE) & np.isfinite(events.rise_rows)
    change = float(np.median(np.abs(events.strength[measured]))) if measured.any() else 0.0
    if change <= 0.0:
        return 0.0
    halfway = ((1.0 + change / 2.0) ** TONE_GAMMA - 1.0) / ((1.0 + change) ** TONE_GAMMA - 1.0)
    return 4.0 * (0.5 - halfway) * float(np.median(events.rise_rows[measured])) * row_time_ms


def _attempt(
    cameras: dict[str, CameraDetection],
    reference: str,
    row_times: dict[str, float] | None,
    anchors: Sequence[str],
    rate_std: dict[str, float] | None = None,
    memo: dict | None = None,
    other_shifts: bool = False,
    shared_readout: bool = False,
) -> _Attempt:
    """Match and solve with the cameras' current readout directions. ``rate_std``: per camera,
    the relative standard error of its frame clock's rate (it and the reference's widen the
    prior on its drift); ``memo``: pair alignments of earlier attempts (:func:`~flashsync.match.match_events`);
    ``other_shifts``: try the pairs' other shifts too (:func:`_shifts_by_fit`);
    ``shared_readout``: the weak priors on the times per row of cameras of one size and rate
    correlated (:func:`shared_readouts`; the final solves only, not the search). The cameras
    the nominal time per row leaves untied are matched again at shorter ones
    (:func:`_tie_fast_readouts`)."""
    sync_events = {name: _sync_events(d) for name, d in cameras.items()}
    usable = [name for name, events in sync_events.items() if len(events) >= MIN_SYNC_EVENTS]
    warnings = [
        f"{cameras[name].video}: {len(sync_events[name])} usable flash events "
        f"(need at least {MIN_SYNC_EVENTS}); left out{_whole_frames_note(cameras[name])}"
        for name in cameras
        if name not in usable
    ]
    if len(usable) < 2:
        counts = ", ".join(f"{cameras[n].video.name}: {len(sync_events[n])}" for n in cameras)
        raise NotEnoughDataError(
            f"need two or more cameras with at least two flash events each; found "
            f"{counts}; check that the videos show flashes (or lights switching)"
        )
    anchor_events = parse_anchors(list(anchors), {n: sync_events[n].event for n in usable})
    tolerance = match_tolerance_ms([median_step_ms(cameras[n].frame_times_ms) for n in usable], readout_known=True)
    times = {n: _start_times_ms(cameras[n], sync_events[n]) for n in usable}
    strengths = {n: np.abs(sync_events[n].strength) for n in usable}

    def matched(times: dict[str, np.ndarray]) -> Matching:
        return match_events(times, tolerance, anchor_events, memo, strengths)

    matching = _tie_fast_readouts(matched(times), times, reference, cameras, sync_events, matched)

    def solved(matching: Matching) -> _Attempt:
        return _solved(
            cameras, sync_events, usable, matching, reference, row_times, rate_std or {}, warnings, shared_readout
        )

    return _shifts_by_fit(matching, {n: len(t) for n, t in times.items()}, solved, other_shifts)


def _whole_frames_note(detection: CameraDetection) -> str:
    """Why a camera left out for want of flash events saw none, where its frames tell: flashes
    that lit every row of a frame at once (:attr:`~flashsync.detect.CameraDetection.n_whole_frames`)
    leave no band edge to time rows by."""
    if detection.n_whole_frames < MIN_SYNC_EVENTS:
        return ""
    return (
        f": {detection.n_whole_frames} of its frames were lit whole by a flash, every row at once (a global "
        "shutter, or rows read far faster than the exposure?); flashsync times a camera by the edges of the "
        "bands a rolling shutter leaves"
    )


def _tie_fast_readouts(
    matching: Matching,
    times: dict[str, np.ndarray],
    reference: str,
    cameras: dict[str, CameraDetection],
    sync_events: dict[str, Events],
    matched: Callable[[dict[str, np.ndarray]], Matching],
) -> Matching:
    """``matching`` where the nominal time per row leaves cameras untied to ``reference``:
    first every camera matched at one share of it (:data:`FAST_READOUT_SHARES`; a rig of
    sensors that all read fast), the share that ties the most cameras where it ties more;
    then each camera still untied matched again at the share that ties it with the most of
    its events, where one does and no camera tied before comes loose. ``times``: the events'
    approximate times the matching was made on (:func:`_start_times_ms`); ``matched``
    matches a set of them. The reference is tried first where it is tied to no camera. Only
    cameras with the events to be matched (``times`` holds them) are tried, the reference
    among them. A camera of an undecided pair counts as tied: the edges' fit decides its
    shift (:func:`_shifts_by_fit`; matched again, a pre-flash's shift could line up alone,
    60 ms off with no word)."""

    def reached(matching: Matching) -> set[str]:
        return matching.tied_to(reference) | {name for pair in matching.undecided for name in pair}

    tied = reached(matching)
    if reference not in times or len(tied) == len(times):
        return matching
    trials = []
    for share in FAST_READOUT_SHARES:
        retimed = {name: _start_times_ms(cameras[name], sync_events[name], share) for name in times}
        trials.append((matched(retimed), retimed))
    trial, retimed = max(trials, key=lambda entry: len(reached(entry[0])), default=(matching, times))
    if len(reached(trial)) > len(tied):
        matching, times, tied = trial, retimed, reached(trial)
    loose = [name for name in times if name not in tied]
    if len(tied) == 1:
        loose.insert(0, reference)
    for name in loose:
        best, most = None, 0
        for share in FAST_READOUT_SHARES:
            retimed = {**times, name: _start_times_ms(cameras[name], sync_events[name], share)}
            trial = matched(retimed)
            now = reached(trial)
            count = sum(camera == name for camera, _ in trial.flashes)
            if name in now and tied <= now and count > most:
                best, most = (trial, retimed), count
        if best is not None:
            (matching, times), tied = best, reached(best[0])
    return matching


def _shifts_by_fit(
    matching: Matching, n_events: dict[str, int], solved: Callable[[Matching], _Attempt], other_shifts: bool
) -> _Attempt:
    """The solve of ``matching`` with the shifts of its pairs that the edges' fit decides: of
    a pair's shifts, the one whose solve explains the edges best at one noise for all
    (:func:`_shift_evidence`) where it leads the others by :data:`SHIFT_DECIDED_LOG_LIKELIHOOD`.
    An undecided pair (:attr:`Matching.undecided`) is left out where its cameras are tied
    through other pairs (those that count, and undecided ones the fit decided, in any
    order), unless the solve puts the events it lines up at its shift with most events more
    than :data:`~flashsync.match.MIN_TOLERANCE_MS` apart: then that shift, with its camera
    of fewer matched events tied by it alone, replaces the solve where the fit so decides
    (random rig 143 of TTL flashes and fast readouts: cam6, tied by cam5's flashes to its
    own pre-flashes, 41.5 ms off at error/sigma 21, left out its pair with cam4, which lined
    up eight events at the true shift); where the fit does not, the solve stands (taken as
    a doubt, such shifts put 40 ms into the sigma of three cameras read right, the shift of
    most events the pre-flash's, on three benches). Else it counts at the shift so decided,
    or where none is at the shift with most events, the others its doubts
    (:func:`_shift_doubts`; random rig 415 with pre-flashes: its first undecided pair taken
    so put five cameras' sigma at 60 ms, though a pair decided after it tied them, and every
    pair after it was solved twice for nothing). A pair's
    other shift (:attr:`~flashsync.match.PairAlignment.others`) that matches at least
    :data:`MIN_SHARED_FLASHES` events the chosen one leaves unmatched replaces it where it
    is so decided and is its doubt where neither is (random rig 416 with pre-flashes: the
    other shift led by 18, and the camera it moves was 60 ms off at error/sigma 63 with no
    word), where ``other_shifts`` asks (a solve per such shift: once, on the readouts
    chosen; the decisions hang on the other cameras' readouts, and kept from one attempt of
    the readout search to the next they put rigs 406 and 408 tens of ms off).

    A TTL flash fires a weak pre-flash a few tens of ms before it: a camera that saw the
    pre-flashes lines up with one that did not at two shifts, the wrong one with as many
    events, or more where the first missed a few flashes (random rig 414 with pre-flashes
    60 ms early: 60 ms off, its sigma 1 ms). Where the pre-flash's delay varies by more than
    the edges' noise the wrong shift fits loosely (0.29 ms against 0.02, or bent over fewer
    edges); a constant delay leaves little to tell them apart by but an anchor."""
    alignments = dict(matching.alignments)

    def trial(pair: tuple[str, str], shift: PairAlignment, untied: str = "") -> _Attempt | None:
        """``pair`` at ``shift``, and the other pairs of camera ``untied`` (if given) left out."""
        kept = {p: a for p, a in alignments.items() if untied not in p}
        return _solved_or_none(solved, matching.with_alignments({**kept, pair: shift}, n_events))

    chosen, group = None, {}  # group: each camera's group of cameras tied through the pairs that count
    if matching.undecided:
        counting = matching.with_alignments(alignments, n_events)
        chosen = _solved_or_none(solved, counting)
        connected = set(chosen.connected) if chosen is not None else set()  # the reference's group, as solved
        group = {name: "" if name in connected else min(counting.tied_to(name) - connected) for name in n_events}

    def tie(a: str, b: str) -> None:
        joined = group[b]
        group.update({name: group[a] for name, g in group.items() if g == joined})

    undecided, left_out = [], []
    for pair, alignment in matching.undecided.items():
        if group[pair[0]] == group[pair[1]]:
            left_out.append((pair, alignment))  # tied through other pairs
            continue
        shifts = (alignment, *alignment.rivals)
        decided = _decided([trial(pair, s) for s in shifts])
        if decided is None:
            undecided.append((pair, shifts))
        else:
            alignments[pair] = shifts[decided]
            tie(*pair)
    needed = []
    for pair, shifts in undecided:
        if group[pair[0]] != group[pair[1]]:  # not tied by a pair decided after it
            alignments[pair] = shifts[0]
            tie(*pair)
            needed.append((pair, shifts))
    if chosen is None or len(alignments) > len(matching.alignments):
        chosen = solved(matching.with_alignments(alignments, n_events))
    if needed:
        return _shift_doubts(chosen, [(pair, [trial(pair, s) for s in shifts[1:]]) for pair, shifts in needed])
    doubts = []
    for pair, alignment in left_out:
        if _apart_in_chosen_ms(chosen, pair, alignment) > MIN_TOLERANCE_MS:
            weaker = min(pair, key=lambda name: np.count_nonzero(chosen.matches.camera == name))
            swapped = trial(pair, alignment, untied=weaker)
            if _decided([chosen, swapped]) == 1:
                return _shift_doubts(swapped, doubts)
    for pair, alignment in alignments.items() if other_shifts else ():
        for other in alignment.others:
            if _unmatched_in_chosen(alignment, other) >= MIN_SHARED_FLASHES:
                swapped = trial(pair, other)
                decided = _decided([chosen, swapped])
                if decided == 1:
                    return _shift_doubts(swapped, doubts)
                if decided is None:
                    doubts.append((pair, [swapped]))
    return _shift_doubts(chosen, doubts)


def _apart_in_chosen_ms(chosen: _Attempt, pair: tuple[str, str], alignment: PairAlignment) -> float:
    """How far apart ``chosen`` puts the starts of the bands a pair's alignment matches, ms
    (median); 0 where it leaves either camera out (nothing to compare)."""
    if not set(pair) <= set(chosen.connected):
        return 0.0
    model = chosen.model(chosen.reference)
    starts = [
        _band_starts_ms(model.cameras[name], _sync_events(chosen.cameras[name]).take(alignment.matches[:, column]))
        for name, column in zip(pair, (0, 1))
    ]
    return float(np.median(np.abs(starts[0] - starts[1])))


def _band_starts_ms(clock: CameraClock, events: Events) -> np.ndarray:
    """Global times (ms, shape (n_events,)) of the starts of the bands of a camera's sync
    ``events`` by its solved ``clock``: a trailing edge's one exposure earlier."""
    later = np.where(events.edge == Edge.TRAILING, clock.exposure_ms or 0.0, 0.0)
    return clock.t_global_ms(events.frame, events.row) - later


def _frame_gaps_ms(mine: CameraClock, theirs: CameraClock) -> np.ndarray:
    """How far two clocks of one camera put each of its frames apart, ms, shape (n_frames,):
    the larger gap of its first and last row."""
    frames = np.arange(mine.n_frames)[:, None]
    rows = np.array([0.0, mine.height - 1.0])
    return np.abs(mine.t_global_ms(frames, rows) - theirs.t_global_ms(frames, rows)).max(axis=1)


def _shift_doubts(chosen: _Attempt, pairs: list[tuple[tuple[str, str], list[_Attempt | None]]]) -> _Attempt:
    """``chosen`` with the doubt of each pair's other shifts (``pairs``: the pair and the
    solves at its other shifts): per camera whose times another shift moves
    by more than half the largest move and by a matching tolerance at least
    (:data:`~flashsync.match.MIN_TOLERANCE_MS`: less is a solve that left the pair's
    events out, not another shift), how far (ms, each frame's largest over its rows;
    :attr:`_Attempt.shift_spreads`, into its sigma) and a warning line naming the pairs;
    ``chosen`` itself where there are no pairs."""
    if not pairs:
        return chosen
    model = chosen.model(chosen.reference)
    spreads, doubted = {}, {}
    for (a, b), trials in pairs:
        for trial in trials:
            if trial is None:
                continue
            other = trial.model(chosen.reference)
            gaps = {
                name: _frame_gaps_ms(model.cameras[name], other.cameras[name])
                for name in model.cameras
                if name in other.cameras
            }
            largest = max((gap.max() for gap in gaps.values()), default=0.0)
            for name, gap in gaps.items():
                if gap.max() <= max(largest / 2.0, MIN_TOLERANCE_MS):
                    continue
                spreads[name] = np.maximum(spreads.get(name, gap), gap)
                doubted.setdefault(name, []).append(f"{a} and {b}")
    warnings = [
        f"{chosen.cameras[name].video}: the flashes of {', of '.join(dict.fromkeys(named))} also line up at another "
        "shift that explains the edges about as well (a flash with a weaker pre-flash before it, as TTL flashes fire, "
        f"makes two); its times may be off by up to {float(spreads[name].max()):.1f} ms (in its sigma); name one "
        "flash both saw (--anchor CAMERA:EVENT, the events table) to decide"
        for name, named in doubted.items()
    ]
    return replace(chosen, warnings=chosen.warnings + warnings, shift_spreads=spreads)


#: Two sync events of one camera this far apart (ms, least and most) are a burst: a TTL
#: flash's metering pre-flash and its flash (:func:`_burst_doubts`) ...
BURST_GAP_MS = (10.0, 150.0)
#: ... and a group of cameras is in doubt where its ties to the rest match the first of this
#: many bursts at least (a false event next to a flash makes one), their gaps within this
#: share of their median of each other, each band of the group's that lies that gap after a
#: flash the others saw counting as one more (:func:`_displaced`: nothing fires then); a
#: burst ties cameras where its gap lies within that share of the rig's delay.
MIN_BURSTS = 2
BURST_AGREE = 0.2


def _burst_doubts(best: _Attempt, model: SyncModel) -> tuple[dict[str, float], list[str]]:
    """Per camera of a group tied to the reference's only by flashes that match the first of
    one camera's bursts (its events :data:`BURST_GAP_MS` apart: a TTL pre-flash and its
    flash), each followed by one the other camera does not see, at :data:`MIN_BURSTS` or more
    whose gaps agree: how far (ms, the bursts' median gap; into its sigma) and a warning line
    each. A camera that sees one event a burst sees the flash, not its faint pre-flash,
    unless the flash falls where it does not look (a fast readout's blanking): there the
    flashes may match one burst later. Where the flashes are missed as often as that, the
    wrong shift matches more events than the right one, too many for the right one to be its
    rival (:func:`_shift_doubts`), and the events it leaves unmatched, pre-flashes and flashes
    alike, are not so much brighter than those it matches that the matcher refuses it
    (:data:`~flashsync.match.BRIGHTER_LEFT`): random rig 125 of a mixed bench (``--preflash
    40 --readout 0.4:0.8 --exposure-changes 0.5``), its cam2 matched to five of cam1's
    pre-flashes against two of its flashes, 40 ms off at error/sigma 29 with no word.

    The groups: cameras that a flash both see ties where each sees it as the same of a burst,
    or one as a burst's second and the other alone where that camera sees no bursts (its lone
    events are flashes), in bursts of the rig's delay (the firsts' median gap: a false event
    next to a flash makes a burst of another); and the groups these make where the flashes
    they share seen by cameras without bursts, alone in each (the same flash at one shift: no
    pre-flash to mistake it for), outnumber the bursts whose first matches the other's lone
    event or a burst's second. A lone event of a camera that sees bursts, matched to another
    camera's burst, may be its pre-flash or its flash and counts for neither: random rig 147
    of a bench of all four departures at once (``--preflash 40 --readout 0.4:0.8
    --flash-powers 0.5 --exposure-changes 0.5``), whose cam8 saw bursts and was matched by
    its pre-flashes to the flash-only cameras, 40 ms off at error/sigma 30 with no word, tied
    to the rest by a pre-flash whose flash it missed at another camera's second and by a
    false event 20 ms before one of its pre-flashes. A camera without a burst of its own may
    still see pre-flashes whose flash it missed, and those match another camera's flashes as
    well as flashes do: random rig 152 of another such bench, four cameras that saw
    bursts (one of them none of its own, but tied to the others by the seconds of theirs)
    matched by their pre-flashes to the flash-only cameras, the reference's group, at eight
    bursts and by that camera's two lone events, 40 ms off at error/sigma 43-57 with no word.
    A camera without bursts matched to the firsts of several (:func:`_pre_flash_seers`) saw
    pre-flashes alone or is matched a delay off; where it also has a band one delay after a
    flash the others were matched at (:func:`_displaced`), it is the one off, and its lone
    events tie no group: random rig 185 of a fresh such bench, whose reference saw mostly
    pre-flashes whose flash it missed, matched by them to a flash-only camera, which tied the
    other five to it; those six were 37-39 ms off at error/sigma 15-21 with no word, and the
    one camera warned was right. (Random rig 152 is that rig mirrored, its reference on the
    flashes' side and right: it has no such band.) Bursts are counted once each, however many
    cameras match their first, and a group's bands a burst's gap after a flash the others saw
    (not a burst's second) count as bursts: random rig 911 of a bench of TTL flashes, fast
    readouts and auto exposure (``--preflash 30 --readout 0.5:0.9 --exposure-changes 0.5``)
    had two cameras that saw one burst each, matched by it and their lone pre-flashes to the
    others' flashes, 24-30 ms off with no word (error/sigma 28-29 with a codec-drawn edge of
    the reference left out; 2.1 with it, every sigma 11 ms), each with a flash seen alone 30
    ms after the others'. A pair's ties at a burst's second do not tie it where the other
    camera's events at the burst camera's firsts outnumber them and are its flashes by their
    strengths (:func:`_flashes_at_firsts`); the gaps then need not agree, measured by the
    times per row such a match bent: FP8's rig-1135, two cameras read the wrong way up, one
    matched by four flashes to the other's pre-flashes and by one to a flash, 14.8 ms off at
    error/sigma 63 with no word (its gaps 17-43 ms). A camera whose pair's other shift is
    its doubt already keeps that one."""
    followed, following = _bursts(best, model)
    bursty = {name for name, _ in followed}
    pins, lone, firsts, at_firsts = {}, {}, {}, {}
    flashes = _matched_flashes(best.matches)
    for flash, seen in flashes.items():
        for a, b in combinations(seen.items(), 2):
            pair, (role_a, role_b) = frozenset((a[0], b[0])), (_burst_role(e, followed, following) for e in (a, b))
            if role_a and role_b:  # an event in a burst of each: the same of each, or a first at a second
                if role_a == role_b:
                    pins.setdefault(pair, []).append((following if role_a == "second" else followed)[a])
                else:
                    first = a if role_a == "first" else b
                    firsts.setdefault(pair, {})[first] = followed[first]
            elif role_a or role_b:  # one camera's event in a burst, the other's alone
                burst, alone = (a, b) if role_a else (b, a)
                if alone[0] in bursty:
                    continue  # it may be a pre-flash whose flash that camera missed, or a flash
                if burst in following:
                    pins.setdefault(pair, []).append(following[burst])
                else:
                    firsts.setdefault(pair, {})[burst] = followed[burst]
                    at_firsts.setdefault(pair, []).append(alone)
            elif not pair & bursty:
                lone.setdefault(pair, set()).add(flash)
    if not firsts:
        return _displaced_doubts(best, model, flashes, {})
    delay = np.median([gap for bursts in firsts.values() for gap in bursts.values()])
    seers = _pre_flash_seers(firsts, bursty)
    misled = seers & {name for name, _ in _displaced(best, model, flashes, delay)} if seers else set()
    trusted = {pair: shared for pair, shared in lone.items() if not pair & misled}
    told = _flashes_at_firsts(best, followed, following, at_firsts)
    outweighed = {pair: len(gaps) for pair, gaps in pins.items() if pair in told and len(gaps) < len(firsts[pair])}
    groups = {name: {name} for name in best.connected}
    for (a, b), gaps in pins.items():
        if frozenset((a, b)) in outweighed:
            continue
        if np.any(np.abs(np.array(gaps) - delay) <= BURST_AGREE * delay):  # a burst of the rig's delay
            _tie(groups, a, b)
    for g, h in combinations({frozenset(group) for group in groups.values()}, 2):
        if len(_between(trusted, g, h)) > len(_between(firsts, g, h)):
            _tie(groups, next(iter(g)), next(iter(h)))
    doubts, warnings = {}, []
    others = {frozenset(group) for group in groups.values()} - {frozenset(groups[best.reference])}
    for group in sorted(others, key=lambda group: min(map(best.connected.index, group))):
        rest = frozenset(best.connected) - group
        gaps = [followed[first] for first in _between(firsts, group, rest)]
        ties = [pair for pair in firsts if pair & group and pair & rest]
        bright = all(pair in told for pair in ties)
        if not gaps or (np.ptp(gaps) > BURST_AGREE * np.median(gaps) and not bright):
            continue
        gap_ms, names = float(np.median(gaps)), ", ".join(sorted(group, key=best.connected.index))
        after = {band for band in _displaced(best, model, flashes, gap_ms) if band[0] in group} - set(following)
        if len(gaps) + len(after) < MIN_BURSTS:
            continue
        lie = "a band of its lies" if len(after) == 1 else f"{len(after)} of its bands lie"
        late = f", and {lie} that long after a flash the others saw (nothing fires then)" if after else ""
        seconds = sum(outweighed.get(pair, 0) for pair in ties)
        which = f"the first (at {len(gaps)}; at {seconds} the second)" if seconds else "only the first"
        apart = f"{gap_ms:.0f}" if np.ptp(gaps) <= BURST_AGREE * gap_ms else f"{min(gaps):.0f}-{max(gaps):.0f}"
        flashes_there = ", its events there as bright as its others (flashes, not pre-flashes)" if bright else ""
        for name in sorted(group - set(best.shift_spreads), key=best.connected.index):
            doubts[name] = gap_ms
            warnings.append(
                f"{best.cameras[name].video}: the flashes that tie {names} to the rest of the rig match {which} "
                f"of one camera's pairs of events {apart} ms apart, each followed by one the other camera "
                f"does not see (a TTL flash's pre-flash and its flash?){flashes_there}{late}; its times may be off by "
                f"{gap_ms:.0f} ms (in its sigma); name one flash both saw (--anchor CAMERA:EVENT, the events table) "
                "to decide"
            )
    more, also = _displaced_doubts(best, model, flashes, doubts)
    return doubts | more, warnings + also


def _displaced_doubts(
    best: _Attempt, model: SyncModel, flashes: dict[int, dict[str, int]], doubted: dict[str, float]
) -> tuple[dict[str, float], list[str]]:
    """Per camera not ``doubted`` already (by :func:`_burst_doubts`) with :data:`MIN_BURSTS`
    bands or more matched to no flash that start one gap (:data:`BURST_GAP_MS`, within
    :data:`BURST_AGREE` of their median) after a flash the others saw and near none (a band
    next to one may be that flash, unmatched: random rig 154's cam3, two flashes left
    unmatched 44-47 ms after the pre-flashes the others saw and 5 ms from those flashes),
    and per camera tied to the reference's only through it: how far (ms, the gaps' median;
    into its sigma) and a warning line each. Nothing fires a pre-flash's delay after a
    flash: such a camera saw pre-flashes whose flashes it missed and is tied by them alone,
    one delay late, whether or not any camera's bursts show the delay. Random rig 182 of a
    bench of TTL flashes, fast readouts, two powers and auto exposure (``--preflash 40
    --readout 0.4:0.8 --flash-powers 0.5 --exposure-changes 0.5``): its cam8 saw three
    pre-flashes and two flashes, shared the pre-flashes with cam11's flashes (at the true
    shift its two flashes with three cameras, which tied it by none) and was 37 ms off at
    error/sigma 4.2, its two flashes placed 40 ms after the others'."""
    low, high = BURST_GAP_MS
    bands: dict[tuple[str, int], list[float]] = {}
    for name, event, gap in _gaps_after_flashes(best, model, flashes):
        bands.setdefault((name, event), []).append(gap)
    gaps: dict[str, list[float]] = {}
    for (name, _), apart in bands.items():
        after = [gap for gap in apart if low <= gap <= high]
        if after and min(map(abs, apart)) >= low:  # not a flash the others saw, unmatched
            gaps.setdefault(name, []).append(min(after))
    doubts, warnings = {}, []
    for name, after in gaps.items():
        delay = float(np.median(after))
        count = int(np.sum(np.abs(np.array(after) - delay) <= BURST_AGREE * delay))
        if name == best.reference or name in doubted or count < MIN_BURSTS:
            continue
        tied = _tied_without(flashes, best.reference, name)
        for other in (c for c in best.connected if c not in tied):
            if other in doubted or other in doubts or other in best.shift_spreads:
                continue
            doubts[other] = delay
            whose, who = (
                (f"{count} of its", "it") if other == name else (f"tied through {name}, {count} of whose", name)
            )
            warnings.append(
                f"{best.cameras[other].video}: {whose} bands matched to no flash lie {delay:.0f} ms after a flash the "
                f"others saw, where nothing fires: {who} may be tied by the pre-flashes of flashes it missed (a TTL "
                f"flash's pre-flash fires a fixed delay before it); its times may be off by {delay:.0f} ms (in its "
                "sigma); name one flash both saw (--anchor CAMERA:EVENT, the events table) to decide"
            )
    return doubts, warnings


def _tied_without(flashes: dict[int, dict[str, int]], reference: str, left_out: str) -> set[str]:
    """The cameras tied to ``reference`` through pairs that share :data:`MIN_SHARED_FLASHES`
    matched flashes or more (``flashes``: :func:`_matched_flashes`), camera ``left_out``'s
    left out."""
    shared: dict[frozenset, int] = {}
    for seen in flashes.values():
        for pair in combinations(sorted(set(seen) - {left_out}), 2):
            shared[frozenset(pair)] = shared.get(frozenset(pair), 0) + 1
    tied, grown = {reference}, True
    while grown:
        reached = {
            name for pair, count in shared.items() if count >= MIN_SHARED_FLASHES and pair & tied for name in pair
        }
        grown = not reached <= tied
        tied |= reached
    return tied


def _displaced(
    best: _Attempt, model: SyncModel, flashes: dict[int, dict[str, int]], delay_ms: float
) -> set[tuple[str, int]]:
    """The bands (camera, event number) matched to no flash that start one pre-flash delay
    (``delay_ms``, within :data:`BURST_AGREE` of it) after a flash the others saw
    (:func:`_gaps_after_flashes`): nothing fires a delay after a flash, so their camera's
    times are a delay off the others'."""
    return {
        (name, event)
        for name, event, gap in _gaps_after_flashes(best, model, flashes)
        if abs(gap - delay_ms) <= BURST_AGREE * delay_ms
    }


def _gaps_after_flashes(
    best: _Attempt, model: SyncModel, flashes: dict[int, dict[str, int]]
) -> list[tuple[str, int, float]]:
    """Per band matched to no flash (any band: rig-185's reference's was a lone trailing edge
    of a long pulse, no sync event) and per flash other cameras were matched at: (camera,
    event number, how long after the flash the band starts in ms, by the solved clocks)."""
    matched = {(name, event) for seen in flashes.values() for name, event in seen.items()}
    starts = {}
    for name in best.connected:
        events = best.cameras[name].events
        first = (events.edge == Edge.LEADING) | events.has_flag(Flag.LEADING_HIDDEN)
        events = events.take(first)
        starts[name] = dict(zip(events.event.tolist(), _band_starts_ms(model.cameras[name], events).tolist()))
    flash_starts = [
        (set(seen), float(np.median([starts[name][event] for name, event in seen.items()])))
        for seen in flashes.values()
    ]
    return [
        (name, event, start - at)
        for name, bands in starts.items()
        for event, start in bands.items()
        if (name, event) not in matched
        for seen, at in flash_starts
        if name not in seen
    ]


#: A camera's bursts are a TTL flash's pre-flash and its flash by their bands' strengths where
#: the firsts' median is at most this share of the seconds' (:func:`_flashes_at_firsts`; the
#: bench's pre-flashes fire at 0.3 of their flash).
PRE_FLASH_SHARE = 0.5


def _flashes_at_firsts(
    best: _Attempt, followed: dict, following: dict, at_firsts: dict[frozenset, list[tuple[str, int]]]
) -> set[frozenset]:
    """The pairs of cameras (of ``at_firsts``: per pair, the lone events (camera, event
    number) of the camera without bursts matched to the first of the other's) whose such
    events are its flashes, not pre-flashes, by their bands' strengths: the other camera's
    firsts are faint beside its seconds (:data:`PRE_FLASH_SHARE`), as a pre-flash is in every
    camera that sees it, and these events' median is nearer their camera's other bands'
    than that share of it (over its root). A camera that sees pre-flashes whose flash it
    misses (a fast readout's blanking) is matched to the firsts by faint events; one matched a
    pre-flash's delay off, by bright ones: FP8's rig-1135, whose cam2, blind to the
    pre-flashes, matched four of its five flashes to cam1's pre-flashes."""
    strength = {}  # per event (camera, event number), its band's
    for name in best.connected:
        events = best.cameras[name].events
        strength.update({(name, int(e)): abs(float(s)) for e, s in zip(events.event, events.strength)})

    def median(keys: Iterable[tuple[str, int]]) -> float:
        values = [strength[key] for key in keys]
        return float(np.median(values)) if values else np.nan

    told = set()
    for pair, alone in at_firsts.items():
        name = alone[0][0]
        (bursty,) = pair - {name}
        share = median(k for k in followed if k[0] == bursty) / median(k for k in following if k[0] == bursty)
        others = median(k for k in strength if k[0] == name and k not in alone)
        if share <= PRE_FLASH_SHARE and median(alone) > np.sqrt(share) * others:
            told.add(pair)
    return told


def _pre_flash_seers(firsts: dict[frozenset, dict], bursty: set[str]) -> set[str]:
    """The cameras without bursts of their own whose events are matched to the first of
    :data:`MIN_BURSTS` or more of another camera's bursts (``firsts``: per pair of cameras,
    the bursts' firsts matched to the other's lone event): they see pre-flashes whose flash
    they miss, or are matched one pre-flash's delay off, and their lone events may be
    either."""
    seen: dict[str, set] = {}
    for pair, bursts in firsts.items():
        for first in bursts:
            for name in pair - {first[0]} - bursty:
                seen.setdefault(name, set()).add(first)
    return {name for name, bursts in seen.items() if len(bursts) >= MIN_BURSTS}


def _burst_role(event: tuple[str, int], followed: dict, following: dict) -> str | None:
    """``"second"`` for a camera's event (camera, event number) that follows another of its
    own within a burst, ``"first"`` for one that another follows, else None."""
    return "second" if event in following else "first" if event in followed else None


def _between(table: dict[frozenset, Iterable], g: frozenset, h: frozenset) -> set:
    """The keys that ``table``'s pairs of cameras with one in group ``g`` and one in ``h`` hold."""
    return {key for pair, keys in table.items() if pair & g and pair & h for key in keys}


def _tie(groups: dict[str, set[str]], a: str, b: str) -> None:
    """Merge the groups of cameras ``a`` and ``b`` (each camera's entry is its group's set)."""
    if groups[a] is not groups[b]:
        merged = groups[a] | groups[b]
        for name in merged:
            groups[name] = merged


def _bursts(best: _Attempt, model: SyncModel) -> tuple[dict[tuple[str, int], float], dict[tuple[str, int], float]]:
    """The cameras' sync events (camera, event number) that another of the same camera's
    follows within :data:`BURST_GAP_MS`, and those that follow one, each with that gap (ms,
    by the solved clocks), of the bursts of the rig's delay: those whose gap lies within
    :data:`BURST_AGREE` of the median of the most bursts that agree so. A TTL flash fires its
    pre-flash one delay before it for the whole rig, and a false event next to a flash makes
    a burst of another gap (TT9's rig-1141: cam3, blind to the pre-flashes, had two of 80 and
    125 ms among cam1's and cam5's of 39-41; counted as a camera that sees bursts, whose
    flashes matched to cam1's pre-flashes tie it to neither side, it was tied to cam1 by one
    of its own, and it and two more were 38.7 ms off at error/sigma 32-33 with no word)."""
    bursts = []
    for name in best.connected:
        events = _sync_events(best.cameras[name])
        times = _band_starts_ms(model.cameras[name], events)
        order = np.argsort(times)
        for first, second in pairwise(order):
            if BURST_GAP_MS[0] <= times[second] - times[first] <= BURST_GAP_MS[1]:
                bursts.append((name, int(events.event[first]), int(events.event[second]), times[second] - times[first]))
    if not bursts:
        return {}, {}
    gaps = np.array([gap for *_, gap in bursts])
    agree = np.abs(gaps[:, None] - gaps[None, :]) <= BURST_AGREE * gaps[:, None]  # [i, j]: gap j near gap i
    delay = np.median(gaps[agree[np.argmax(agree.sum(axis=1))]])
    kept = [(name, a, b, float(gap)) for name, a, b, gap in bursts if abs(gap - delay) <= BURST_AGREE * delay]
    followed = {(name, a): gap for name, a, _, gap in kept}
    following = {(name, b): gap for name, _, b, gap in kept}
    return followed, following


def _matched_flashes(matches: Matches) -> dict[int, dict[str, int]]:
    """Per flash matched, each camera's event number matched into it."""
    flashes: dict[int, dict[str, int]] = {}
    for flash, name, event in zip(matches.flash, matches.camera, matches.event):
        flashes.setdefault(int(flash), {})[str(name)] = int(event)
    return flashes


def _decided(trials: list[_Attempt | None]) -> int | None:
    """The index of the trial (solves of one set of edges matched differently; None: not
    solved) whose :func:`_shift_evidence` leads every other's by
    :data:`SHIFT_DECIDED_LOG_LIKELIHOOD`, or None."""
    solved = [t for t in trials if t is not None]
    if not solved:
        return None
    names = {name for t in solved for name in t.connected}
    noise = {name: np.nanmin([_camera_noise(t, name) for t in solved if name in t.connected], axis=0) for name in names}
    evidence = np.array([-np.inf if t is None else _shift_evidence(t, noise) for t in trials])
    best = int(np.argmax(evidence))
    return best if np.all(evidence[best] >= np.delete(evidence, best) + SHIFT_DECIDED_LOG_LIKELIHOOD) else None


def _camera_noise(attempt: _Attempt, name: str) -> np.ndarray:
    """The camera's leading and trailing edges' noise in ``attempt``'s solve (ms, shape (2,);
    a kind without edges its leading edges'; at least :data:`SCORE_MIN_SIGMA_MS`)."""
    camera = attempt.solution.cameras[attempt.connected.index(name)]
    leading = camera.edge_sigma_ms
    return np.maximum([leading, np.nan_to_num(camera.trailing_sigma_ms, nan=leading)], SCORE_MIN_SIGMA_MS)


def _shift_evidence(attempt: _Attempt, noise: dict[str, np.ndarray]) -> float:
    """Log-likelihood of every camera's band edges under ``attempt``'s solve at the noise
    ``noise`` gives each camera's edges of each kind, the flashes' times integrated out
    (:func:`~flashsync.likelihood.residual_log_likelihood`: the solves of rival shifts
    compared at the tightest noise any of them reaches), each band no other camera shares
    placed by a flash of its own (:func:`_unshared_bands_log_likelihood`), and the priors'
    log density at the clocks solved (:func:`_prior_log_density`). Counted so, a matching
    pays for the flashes it names and the clocks it bends: on random rig 414 with
    pre-flashes (cam1 missed four flashes whose pre-flashes it saw) the wrong shift paired
    8 flashes with pre-flashes through a clock 138 ppm off whose rate it bent by 2.4 ms
    mid-way, and led the right one (5 flashes) by 28; counted so, the right one leads by 33."""
    observations = attempt.observations
    names = np.array(attempt.connected)[observations.camera]
    kinds = observations.trailing.astype(np.int64)
    sigma = np.array([noise[name][kind] for name, kind in zip(names, kinds)]) * attempt.solution.sigma_factor
    period = _uniform_ms(attempt.cameras)
    edges = residual_log_likelihood(attempt.solution.residual_ms, sigma, observations.flash, attempt.n_edges, period)
    return edges + _unshared_bands_log_likelihood(attempt, noise, period) + _prior_log_density(attempt)


def _unshared_bands_log_likelihood(attempt: _Attempt, noise: dict[str, np.ndarray], period_ms: float) -> float:
    """What the bands no flash of ``attempt`` shares add to the log-likelihood of their edges
    counted as unexplained (uniform over ``period_ms``): a band's own flash places its
    leading edge, and its trailing edge lies one exposure later (the camera's solved
    exposure and time per row). Per such band of a camera with an exposure, both edges
    timing evidence (:func:`_trailing_edges`), its trailing edge's Gaussian density about
    that at the camera's ``noise`` (the larger of it and the uniform one) in place of the
    uniform."""
    total = 0.0
    for index, name in enumerate(attempt.connected):
        camera = attempt.solution.cameras[index]
        if not np.isfinite(camera.exposure_ms):
            continue
        edges = _reading_edges(attempt.cameras[name])
        leading = np.flatnonzero(~edges.trailing)
        unshared = ~np.isin(edges.band, attempt.matches.event[attempt.matches.camera == name])
        trailing = np.flatnonzero(edges.trailing & unshared & np.isin(edges.band, edges.band[leading]))
        order = np.argsort(edges.band[leading])
        lead = leading[order[np.searchsorted(edges.band[leading][order], edges.band[trailing])]]
        length = (
            camera.alpha * (edges.t_frame_ms[trailing] - edges.t_frame_ms[lead])
            + camera.row_time_ms * (edges.q[trailing] - edges.q[lead])
            - camera.exposure_ms
        )
        sigma = np.hypot(noise[name][0] * edges.sigma_factor[lead], noise[name][1] * edges.sigma_factor[trailing])
        gaussian = -np.log(sigma * np.sqrt(2.0 * np.pi)) - 0.5 * (length / sigma) ** 2
        total += float(np.sum(np.maximum(gaussian, -np.log(period_ms)) + np.log(period_ms)))
    return total


def _prior_log_density(attempt: _Attempt) -> float:
    """Log density of the solve's priors at its clocks, up to a constant: each camera's drift
    against its prior (kept where the events contradicted it), each time per row against its."""
    priors, cameras = attempt.priors, attempt.solution.cameras
    total = 0.0
    for index, camera in enumerate(cameras):
        drift_std = max(priors.drift_std or np.inf, priors.wider_drift_std.get(index, 0.0))
        total -= 0.5 * ((camera.alpha - 1.0) / drift_std) ** 2
    with_prior, mean, information = priors.row_time_information()
    off = np.array([cameras[c].row_time_ms for c in with_prior]) - mean
    return total - 0.5 * float(off @ information @ off)


def _solved_or_none(solved: Callable[[Matching], _Attempt], matching: Matching) -> _Attempt | None:
    """``solved(matching)``, or None where it cannot be solved."""
    try:
        return solved(matching)
    except FlashsyncError:
        return None


def _unmatched_in_chosen(chosen: PairAlignment, other: PairAlignment) -> int:
    """The most events of one of the pair's cameras that ``other`` matches and ``chosen`` does not."""
    return max(len(np.setdiff1d(other.matches[:, i], chosen.matches[:, i])) for i in (0, 1))


def _solved(
    cameras: dict[str, CameraDetection],
    sync_events: dict[str, Events],
    usable: list[str],
    matching: Matching,
    reference: str,
    row_times: dict[str, float] | None,
    rate_std: dict[str, float],
    warnings: list[str],
    shared_readout: bool,
) -> _Attempt:
    """The solve of the ``usable`` cameras' events matched as ``matching`` (see :func:`_attempt`)."""
    warnings = list(warnings)
    matching = _with_a_leading_edge(matching, sync_events)
    tied = matching.tied_to(reference)
    connected = [name for name in usable if name in tied]
    warnings += [
        f"{cameras[name].video}: shares too few flashes with the other cameras to tell them from a chance "
        f"coincidence (at least {MIN_SHARED_FLASHES}, whose intervals match); cannot be tied to {reference}; "
        "left out"
        for name in usable
        if name not in connected
    ]
    if reference not in connected or len(connected) < 2:
        found = _reference_instead(matching, usable, reference)
        raise UntiedReferenceError(
            f"no camera shares enough flashes with {reference} to tell them from a chance coincidence (at least "
            f"{MIN_SHARED_FLASHES}, whose intervals match); check that the videos overlap in time and saw the "
            f"same flashes, or record more flashes{another_reference(matching, usable, reference)}",
            instead=found[1] if found else None,
        )
    matches = _matches([cameras[name] for name in connected], sync_events, matching.flashes)
    chosen = [cameras[name] for name in connected]
    observations = _observations(chosen, matches)

    wider = {
        index: float(np.hypot(rate_std.get(name, 0.0), rate_std.get(reference, 0.0)) * DRIFT_PRIOR_WIDENING)
        for index, name in enumerate(connected)
    }

    def priors(given: dict[str, float], flicker: dict[str, Flicker]) -> Priors:
        shared = shared_readouts(chosen, set(given) | set(flicker)) if shared_readout else ()
        return Priors(_row_time_priors(chosen, given, flicker), wider_drift_std=wider, shared_readout=shared)

    def solve(given: dict[str, float], flicker: dict[str, Flicker]) -> Solution:
        return solve_with_drift_model(
            observations, len(connected), connected.index(reference), priors=priors(given, flicker)
        )

    given = {name: value for name, value in (row_times or {}).items() if name in connected}
    flicker = {
        name: seen for name, seen in zip(connected, mains_flicker(chosen)) if seen is not None and name not in given
    }
    solution = solve(given, flicker)
    distrusted = {}
    if given or _flicker_in_doubt(solution, connected, flicker):
        free = solve({}, {})
        contradicted = _contradicted_row_times(free, connected, given, chosen)
        for name, (value, std) in contradicted.items():
            warnings.append(
                f"{cameras[name].video}: the datasheet time per row {given[name]:g} ms contradicts the events, "
                f"which give {value:.5f} ± {std:.5f} ms; the events' value is used"
            )
        distrusted = _contradicted_flicker(free, connected, flicker)
        for name, (value, std) in distrusted.items():
            row_time, spread = flicker_row_time_ms(flicker[name])
            warnings.append(
                f"{cameras[name].video}: the time per row its rolling mains flicker tells, {row_time:.5f} ± "
                f"{spread:.5f} ms, contradicts the events, which give {value:.5f} ± {std:.5f} ms (through the "
                "codec a flicker's period or mains frequency can be misread); the events' value is used"
            )
        given = {name: value for name, value in given.items() if name not in contradicted}
        flicker = {name: seen for name, seen in flicker.items() if name not in distrusted}
        if contradicted or distrusted:
            solution = solve(given, flicker)
    return _Attempt(
        cameras,
        connected,
        matching.alignments,
        warnings,
        matches,
        observations,
        solution,
        priors(given, flicker),
        reference,
        tuple(distrusted),
    )


def _reference_instead(matching: Matching, usable: list[str], reference: str) -> tuple[list[str], str] | None:
    """The largest group of two or more ``usable`` cameras tied among themselves without
    ``reference``, and the one of them with the most matched events; None where there is no
    such group."""
    largest = max((matching.tied_to(name) for name in usable if name != reference), key=len, default=set())
    if len(largest) < 2:  # the reference is tied to none of them: none of these groups holds it
        return None
    group = [name for name in usable if name in largest]
    matched = [sum(camera == name for camera, _ in matching.flashes) for name in group]
    return group, group[int(np.argmax(matched))]


def another_reference(matching: Matching, usable: list[str], reference: str) -> str:
    """Words naming the cameras tied among themselves without ``reference`` and the one to
    give as the reference instead (:func:`_reference_instead`); empty where there are none."""
    found = _reference_instead(matching, usable, reference)
    if found is None:
        return ""
    group, instead = found
    return (
        f"; {', '.join(group)} share enough among themselves: make one of them the reference "
        f"(--reference {instead}) to sync them without {reference}"
    )


#: The visible rows of a frame are read within this many frame periods (a little over one:
#: the time per row is an estimate).
READOUT_SLACK = 1.05

#: A camera's drift prior is at least this many times the relative standard error of its and
#: the reference's frame-clock rates: the drift must take up the rate the stamps give the frames.
DRIFT_PRIOR_WIDENING = 3.0

#: A datasheet time per row is contradicted by the events when it is this many of their
#: standard deviations and this fraction of itself away from their own estimate.
ROW_TIME_SIGMAS = 5.0
ROW_TIME_TOLERANCE = 0.01


def _flicker_in_doubt(solution: Solution, connected: list[str], flicker: dict[str, Flicker]) -> bool:
    """Whether a camera's flicker prior may contradict the events, so that they are solved
    alone (:func:`_contradicted_flicker`): its time per row with the prior taken back out of
    ``solution`` (for a linear fit a prior on one unknown adds its information to the
    events') is more than :data:`FLICKER_DOUBT_SIGMAS` of both apart from the prior's. A
    cheap test: the robust solve weighs the events by noise that a wrong prior inflates (on
    rig-104 of the random rigs it left 3.2σ where the events alone give 6.3σ), so only the
    solve without it decides; solving it in every attempt of the readout search took ``sync``
    from 9.5 to 17 s on four flicker rigs."""
    for name, seen in flicker.items():
        camera = solution.cameras[connected.index(name)]
        prior, spread = flicker_row_time_ms(seen)
        variance = camera.covariance[2, 2]
        information = 1.0 / variance - 1.0 / spread**2 if variance > 0 else 0.0
        if information > 0:
            events = (camera.row_time_ms / variance - prior / spread**2) / information
            if abs(events - prior) > FLICKER_DOUBT_SIGMAS * np.hypot(information**-0.5, spread):
                return True
    return False


#: A flicker prior whose time per row, taken back out of the solve, is this many standard
#: deviations from the events' is checked against the events solved alone.
FLICKER_DOUBT_SIGMAS = 2.0


def _contradicted_flicker(
    free: Solution, connected: list[str], flicker: dict[str, Flicker]
) -> dict[str, tuple[float, float]]:
    """The cameras whose mains flicker's time per row (:func:`flicker_row_time_ms`) the events
    alone (``free``: solved with the weak prior) contradict: more than
    :data:`ROW_TIME_SIGMAS` standard deviations of the two together apart. Through the codec
    a flicker's period came out up to 12 % off, and a 100 Hz flicker was named 120 Hz (20 %):
    camera -> (the events' value, its std), ms."""
    contradicted = {}
    for name, seen in flicker.items():
        camera = free.cameras[connected.index(name)]
        std = camera.row_time_std_ms
        row_time, spread = flicker_row_time_ms(seen)
        if abs(camera.row_time_ms - row_time) > ROW_TIME_SIGMAS * np.hypot(std, spread):
            contradicted[name] = (camera.row_time_ms, std)
    return contradicted


def _contradicted_row_times(
    free: Solution, connected: list[str], given: dict[str, float], cameras: list[CameraDetection]
) -> dict[str, tuple[float, float]]:
    """The datasheet times per row (ms) that the events alone (``free``: solved with the weak
    nominal prior) contradict, or that no sensor can have (reading the visible rows would
    take more than :data:`READOUT_SLACK` frame periods): camera -> (the events' value, its
    std), ms."""
    contradicted = {}
    for name, value in given.items():
        index = connected.index(name)
        camera, detection = free.cameras[index], cameras[index]
        std = camera.row_time_std_ms
        too_slow = value * detection.height > READOUT_SLACK * median_step_ms(detection.frame_times_ms)
        if too_slow or abs(camera.row_time_ms - value) > max(ROW_TIME_SIGMAS * std, ROW_TIME_TOLERANCE * value):
            contradicted[name] = (camera.row_time_ms, std)
    return contradicted


def mains_flicker(cameras: Sequence[CameraDetection]) -> list[Flicker | None]:
    """Per camera, its rolling flicker where it identified the rig's mains frequency (the
    one most cameras identified: one hall, one mains) and a whole period fits in the image,
    else None: a flicker the camera could not identify, or one longer than the image (its
    period came out 40 % off once), times nothing. What ``sync``'s prior and ``diagnose``'s
    evidence on the time per row both trust."""
    known = [c.flicker.hz for c in cameras if c.flicker is not None and c.flicker.hz is not None]
    hall_hz = max(set(known), key=known.count) if known else None
    return [
        c.flicker if c.flicker and hall_hz and c.flicker.hz == hall_hz and c.flicker.period_rows < c.height else None
        for c in cameras
    ]


def flicker_row_time_ms(flicker: Flicker) -> tuple[float, float]:
    """The time per row a mains flicker tells, ``(1000 / hz) / period_rows``, and its standard
    deviation (the period's relative :attr:`~flashsync.flicker.Flicker.period_rows_sigma`), ms."""
    row_time = 1000.0 / flicker.hz / flicker.period_rows
    return row_time, row_time * flicker.period_rows_sigma / flicker.period_rows


def _row_time_priors(
    cameras: list[CameraDetection], row_times: dict[str, float], flicker: dict[str, Flicker] | None = None
) -> dict[int, tuple[float, float]]:
    """Per camera index: a datasheet T_row (std 0.01 %), else its mains flicker's (``flicker``
    by camera name, :func:`flicker_row_time_ms`; None: :func:`mains_flicker`), else the
    weak prior (:func:`row_time_prior_ms`)."""
    if flicker is None:
        flicker = {c.camera: seen for c, seen in zip(cameras, mains_flicker(cameras)) if seen is not None}
    priors = {}
    for index, camera in enumerate(cameras):
        if camera.camera in row_times:
            priors[index] = (row_times[camera.camera], 1e-4 * row_times[camera.camera])
        elif camera.camera in flicker:
            priors[index] = flicker_row_time_ms(flicker[camera.camera])
        else:
            priors[index] = row_time_prior_ms(nominal_row_time_ms(camera))
    return priors


def shared_readouts(cameras: list[CameraDetection], told: set[str]) -> tuple[tuple[int, ...], ...]:
    """The groups of two or more indices of ``cameras`` under the weak prior on their time per
    row (:func:`row_time_prior_ms`: none ``told``, by datasheet or flicker) that share a width,
    a height and a frame rate (to the nearest frame a second): likely one model read out
    alike (:data:`~flashsync.solve.SHARED_READOUT_CORRELATION`)."""
    groups: dict[tuple[int, int, int], list[int]] = {}
    for index, camera in enumerate(cameras):
        if camera.camera not in told:
            rate = round(1000.0 / shortest_step_ms(camera.frame_times_ms))
            groups.setdefault((camera.width, camera.height, rate), []).append(index)
    return tuple(tuple(group) for group in groups.values() if len(group) > 1)


def row_time_prior_ms(nominal_ms: float) -> tuple[float, float]:
    """The weak prior on a camera's T_row where no datasheet value nor mains flicker gives
    one, ms: mean and standard deviation of a readout spread evenly from
    :data:`FASTEST_READOUT` of the frame period to all of it; ``nominal_ms`` is the frame period
    over (:data:`~flashsync.match.NOMINAL_HIDDEN_ROWS` x height)
    (:func:`~flashsync.match.nominal_row_time_ms`): 0.58 and 0.27 of it. Only decisive where
    the events cannot tell T_row (few flashes, all on a few rows)."""
    slowest = NOMINAL_HIDDEN_ROWS * nominal_ms
    fastest = FASTEST_READOUT * slowest
    return (fastest + slowest) / 2.0, (slowest - fastest) / np.sqrt(12.0)


def _readout_rows(detection: CameraDetection, events: Events) -> np.ndarray:
    """Readout rows of the camera's events."""
    return readout_rows(events.row, detection.height, detection.flipped)


def _uniform_ms(cameras: dict[str, CameraDetection]) -> float:
    """The span over which an edge no fit explains is uniform (ms): the longest frame period."""
    return max(median_step_ms(d.frame_times_ms) for d in cameras.values())


def _reading_edges(detection: CameraDetection) -> ReadingEdges:
    """The edges a solve fits of the camera in its reading in use: its sync events, then its
    trailing edges (:func:`_trailing_edges`), each with its noise (:func:`_edge_sigma`)."""
    events = Events.concat([_sync_events(detection), _trailing_edges(detection)])
    return ReadingEdges(
        events.t_frame_ms,
        _readout_rows(detection, events),
        _start_times_ms(detection, events),
        events.edge == Edge.TRAILING,
        events.event,
        _edge_sigma(detection, events),
    )


#: Noise of a trailing edge whose leading edge is hidden, in units of a clean one's: fitted
#: without its band's other half, it scatters about twice as much (MAD 0.53 rows against 0.33
#: over the kept rigs).
LONE_EDGE_SIGMA = 2.0
#: Noise of a lone edge (its band's other edge beyond the frame's cut) whose ramp reaches the
#: cut, in units of a clean one's; one ``r`` rises of its ramp from the cut has
#: ``LONE_CUT_SIGMA / sqrt(r)``, at least 1. Against the truth over the kept random rigs 0-49
#: (``bench_rigs.py``'s block "lone flash edges against the truth by their distance from the
#: frame's cut") such edges spread 1.4 rows within two rises of the cut and 0.33-0.47 beyond
#: sixteen, a paired edge 0.26-0.54. 4 gained most on those rigs, but on rigs whose sensors
#: read out in part of their frame (more lone edges, fewer flashes) it took the median camera
#: 0.090 -> 0.102 ms off, 3 to 0.095 (README, "Lone edges weighed by their distance from the cut").
LONE_CUT_SIGMA = 3.0
#: A lone edge ``r`` rises of its ramp from the frame's cut that hides its band's other edge
#: lies up to this share of its ramp's rise, times ``min(1, r ** -LONE_RISE_POWER)``, further
#: from the cut than its flash puts it (the cut hides the ramp's far foot; the decay tail of
#: a flash that fired before the frame's first row, read as the ramp of a band whose leading
#: edge the cut hid, puts its trailing edge tens of rows late). Against the truth over the
#: 1188 lone edges of thirteen benches (2026-12-05, forty-ninth stop) such edges lie further
#: from the cut by 0.29-0.32 of a rise (median) within one and a half rises of it, 0.06-0.16
#: within three, 0.04 within eight, and spread 0.45 of a rise (MAD) within one and a half,
#: 0.13-0.34 within three, 0.07-0.08 within eight. ``LONE_CUT_SIGMA`` weighs them (weighed by
#: this share they were lost to the solve's rejection); the sigma holds what this share moves
#: (:func:`_toward_cut_rows`; README, "Lone edges' error the weights miss, in σ").
LONE_RISE_SHARE = 0.6
LONE_RISE_POWER = 1.25


def _edge_sigma(detection: CameraDetection, events: Events) -> np.ndarray:
    """Each of the camera's edges' noise in units of its typical edge's: its band's signal
    to noise (:func:`_faintness`), and a clipped band's
    (:data:`~flashsync.detect.SATURATED_EDGE_SIGMA`), one that the flash may have
    outlasted (:data:`~flashsync.detect.LONG_PULSE_EDGE_SIGMA`: flagged ``long_pulse``, or
    :func:`_outreaching`) and a lone edge (:func:`_lone_sigma`) noisier."""
    outlasted = events.has_flag(Flag.LONG_PULSE) | _outreaching(detection, events)
    sigma = np.maximum(np.where(outlasted, LONG_PULSE_EDGE_SIGMA, 1.0), _lone_sigma(detection, events))
    return _faintness(detection, events) * np.where(events.has_flag(Flag.SATURATED), SATURATED_EDGE_SIGMA, sigma)


def _lone_sigma(detection: CameraDetection, events: Events) -> np.ndarray:
    """Each edge's noise as a lone edge, in units of a clean one's (1 for an edge of a whole
    band; shape (n,)): from its ramp's distance to the frame's cut that hides its band's other
    edge (:data:`LONE_CUT_SIGMA`; a ramp of no known rise counts as far), and a trailing one
    at least :data:`LONE_EDGE_SIGMA`."""
    to_cut = _rows_to_cut(detection, events)
    rises = np.nan_to_num(to_cut / np.where(events.rise_rows > 0, events.rise_rows, np.nan), nan=np.inf)
    near = np.clip(LONE_CUT_SIGMA / np.sqrt(np.maximum(rises, 1.0)), 1.0, LONE_CUT_SIGMA)
    lone_trailing = np.isfinite(to_cut) & (events.edge == Edge.TRAILING)
    return np.where(lone_trailing, np.maximum(near, LONE_EDGE_SIGMA), near)


def _rows_to_cut(detection: CameraDetection, events: Events) -> np.ndarray:
    """Each lone edge's readout rows to the frame's cut that hides its band's other edge: a
    trailing edge whose leading one is hidden to the first row, a leading edge whose trailing
    one is hidden to the last; NaN for the other edges. Shape (n,)."""
    q = _readout_rows(detection, events)
    lone_trailing = (events.edge == Edge.TRAILING) & events.has_flag(Flag.LEADING_HIDDEN)
    lone_leading = (events.edge == Edge.LEADING) & events.has_flag(Flag.TRAILING_HIDDEN)
    return np.where(lone_trailing, q, np.where(lone_leading, detection.height - 1 - q, np.nan))


def _toward_cut_rows(detection: CameraDetection, events: Events) -> np.ndarray:
    """How far each lone edge may lie from where its flash puts it, away from the frame's cut
    that hides its band's other edge: readout rows towards that cut (a lone trailing edge's
    negative, a lone leading edge's positive; :data:`LONE_RISE_SHARE`), 0 for the edges of
    whole bands and of ramps of no known rise. Shape (n,)."""
    to_cut = _rows_to_cut(detection, events)
    rise = np.where(events.rise_rows > 0, events.rise_rows, np.nan)
    rises = np.maximum(to_cut / rise, 1.0)
    rows = np.nan_to_num(LONE_RISE_SHARE * rises**-LONE_RISE_POWER * rise)
    return np.where(events.edge == Edge.TRAILING, -rows, rows)


#: Noise of a band's length where the detector could not measure the ramp of one of its
#: edges (no rise: the ramp's foot or its 25 %/75 % crossing beyond the frame's cut or in
#: blind rows), in units of a clean one's. Against the truth over 28 fresh rigs (seeds
#: 760-771, and 412-427 with auto exposure; each camera in its true reading) the lengths of
#: 26 such bands within one frame spread 2.28 rows (MAD; 10 rows at the 90th percentile)
#: against 0.51 for the 804 others. Weighed so, 4.5 times down, a length would still be the
#: truer; but the trailing edge of a band whose leading ramp was cut also times its flash,
#: and with it 5 times down a rig's reference lost its time per row (rig-771: 0.09 -> 0.33 %
#: off, its ten cameras 0.02 -> 0.06 ms). At 3 two rigs' times moved by 4.5 %, one closer
#: and one further, the others by 2 % or less; rig-420's cam4, its exposure read from one
#: such band 0.45 ms long, went from error/σ 10.9 to 4.8.
UNMEASURED_RAMP_SIGMA = 3.0


def _trailing_sigma(detection: CameraDetection, edges: Events) -> np.ndarray:
    """The noise of the lengths of the bands whose trailing ``edges`` (of
    :func:`_trailing_edges`) end, in units of a clean one's: its band's signal to noise
    (:func:`_faintness`), and one as long as its pulse (:func:`_pulse_lengths`,
    :data:`~flashsync.detect.LONG_PULSE_EDGE_SIGMA`) or clipped at white
    (:data:`~flashsync.detect.SATURATED_EDGE_SIGMA`) far noisier: such a band is longer than
    the exposure its length measures; one with a ramp the detector could not measure
    (:data:`UNMEASURED_RAMP_SIGMA`) noisier. Shape (n,)."""
    long = np.where(np.isin(edges.event, _pulse_lengths(detection)), LONG_PULSE_EDGE_SIGMA, 1.0)
    events = detection.events
    unmeasured = np.where(np.isin(edges.event, events.event[np.isnan(events.rise_rows)]), UNMEASURED_RAMP_SIGMA, 1.0)
    clipped = np.where(edges.has_flag(Flag.SATURATED), SATURATED_EDGE_SIGMA, 1.0)
    return np.maximum(long, unmeasured) * clipped * _faintness(detection, edges)


#: A clean edge's noise, rows: ``hypot(EDGE_NOISE_FLOOR_ROWS, EDGE_NOISE_QUALITY / quality)``,
#: its band's ``quality`` its plateau over the video's profile noise. Over the 3255 clean
#: edges of the 40 kept random rigs (errors against the simulator's truth) the robust sigma
#: falls from 0.75 rows at a quality under 950 to 0.20 above 3000, within 20 % of this in
#: each of six equal bins; fitted on quality by ramp-width bins (the width adds nothing
#: clear). ``benchmarks/bench_rigs.py`` prints it against the truth.
EDGE_NOISE_FLOOR_ROWS, EDGE_NOISE_QUALITY = 0.21, 485.0


def _faintness(detection: CameraDetection, events: Events) -> np.ndarray:
    """Each of the camera's ``events``' noise (:func:`edge_noise_rows`) over that at the
    median quality of all its edges: a faint band's edges weigh less than a bright one's."""
    if len(events) == 0:
        return np.ones(0)
    return edge_noise_rows(events.quality) / edge_noise_rows(np.median(detection.events.quality))


def edge_noise_rows(quality: np.ndarray) -> np.ndarray:
    """A clean edge's noise, rows, at its band's ``quality`` (:data:`EDGE_NOISE_QUALITY`)."""
    return np.hypot(EDGE_NOISE_FLOOR_ROWS, EDGE_NOISE_QUALITY / np.maximum(np.abs(quality), 1.0))


#: A band one exposure long whose edge is hidden runs past the end of the readout: its
#: visible edge lies within this many exposures of it. Further in, where the other edge would
#: have been seen, the band is not one exposure long (a pulse that outlasts the exposure, an
#: edge lost in dark rows): over the kept rigs such edges were up to 5 rows late (a trailing
#: edge, leading hidden) or 2.7 rows early (a leading edge; README, "Bands whose leading edge
#: is hidden").
LONE_REACH = 1.1


def _exposure_rows(detection: CameraDetection) -> float | None:
    """The camera's exposure, readout rows: the one its bands share
    (:attr:`~flashsync.detect.CameraDetection.exposure_rows`), else the median length of its
    timing bands within one frame (fewer than three were fitted), else the least its lone
    edges allow: a band reaches at least as far as any lone edge lies from the frame's cut
    (:func:`_rows_to_cut`; an exposure longer than the readout leaves no band whole). None
    without any. It places a lone trailing edge's flash for matching; the solve fits the
    exposure itself."""
    if detection.exposure_rows is not None:
        return detection.exposure_rows
    lengths = _whole_bands(detection.events)[1]
    if len(lengths):
        return float(np.median(lengths))
    reach = _rows_to_cut(detection, detection.events)
    reach = reach[np.isfinite(reach)]
    return float(reach.max()) if len(reach) else None


def _whole_bands(events: Events) -> tuple[Bands, np.ndarray]:
    """The unclipped :func:`_timing_bands` that lie within one frame and their lengths (rows):
    a band clipped at white is longer than the exposure."""
    bands = _timing_bands(events)
    return _within_one_frame(events, bands.take(~events.has_flag(Flag.SATURATED)[bands.leading]))


def _within_one_frame(events: Events, bands: Bands) -> tuple[Bands, np.ndarray]:
    """Those of the complete ``bands`` of ``events`` that lie within one frame, and their
    lengths (rows)."""
    bands = bands.take(events.frame[bands.leading] == events.frame[bands.trailing])
    return bands, np.abs(events.row[bands.trailing] - events.row[bands.leading])


#: The share of a band's pulse (hold and decay, rows) by which an error common to its
#: camera's readings of the pulses that outlast its exposure may move its edges
#: (:func:`_misread_decay_rows`). Where the pulse is the longer, the band rises over the
#: exposure and only its tail tells the decay, and the edges (the pulse's half-light) move
#: with it. Against the truth over eighteen kept benches, the 148 cameras with bands of
#: both kinds (whole, within one frame, shorter than :data:`OUTLASTED_SHARE` exposures) have
#: their long pulses' leading edges a robust 0.049 of the pulse off their short ones' (0.040
#: where two or more are long; README, "An error common to a camera's long pulses, in σ").
#: RC12's rolling-flicker reference, a 5.7-row exposure under 7-15-row decays read 2-36 %
#: short, had 0.1: its time per row 0.74 % off at 4.6 sigma.
MISREAD_DECAY_SHARE = 0.05


def _refit_rows(
    best: _Attempt, detections: dict[str, CameraDetection], shown: dict[str, list[_ShownExposure]]
) -> np.ndarray:
    """How far each of ``best``'s observations may lie inside its band's edge, readout rows
    (shape (n_observations,); leading edges negative, trailing positive, 0 for the others):
    a band the detector fitted at the exposure its camera's bands share under a longer pulse
    (:attr:`~flashsync.detect.CameraDetection.exposure_rows`) is that long, so where its
    camera's bands show another exposure at its frame (``shown``, :func:`_shown_exposure_ms`)
    both its edges lie half the difference inside (its bands from ``detections``, every
    band: the solve may have left trailing edges out). EC5's rig-1100 cam1, the reference (0.60 ms,
    then 1.07 from frame 216), had its bands read as a 5.6-row exposure under longer pulses
    where they were 8.4 and then 14.9 rows long; its six bands fitted at 5.6 rows put their
    leading edges 0.10, then 0.33 ms late, and every other camera's times came out on a ramp
    0.4 ms steep over the recording, at error/sigma 1.8-2.95."""
    observations, matches = best.observations, best.matches
    moves = np.zeros(len(observations.camera))
    for name, camera in zip(best.connected, best.solution.cameras):
        detection = _in_use(best, detections, name)
        fitted = detection.exposure_rows
        if fitted is None or detection.pulse_rows is None or not camera.exposure_ms > 0:
            continue
        events = detection.events
        bands, lengths = _within_one_frame(events, _timing_bands(events))
        at_fitted = (np.abs(lengths - fitted) < 1e-6) & (detection.pulse_rows[bands.event] > fitted)
        half = {}
        for event, frame in zip(bands.event[at_fitted], events.frame[bands.leading[at_fitted]]):
            shown_ms = _shown_exposure_ms(
                shown.get(name, []), int(frame), camera.exposure_ms, fitted * camera.row_time_ms
            )
            difference = shown_ms / camera.row_time_ms - fitted
            half[int(event)] = difference / 2.0 if abs(difference) > 1e-6 else 0.0  # the same width
        mine = np.flatnonzero((matches.camera == name) & np.isin(matches.event, list(half)))
        moves[mine] = [-half[int(event)] for event in matches.event[mine]]
    if observations.leading_of is not None:  # a band's trailing edge, the other way
        paired = observations.leading_of >= 0
        moves[paired] = -moves[observations.leading_of[paired]]
    return moves


def _shown_exposure_ms(shown: list[_ShownExposure], frame: int, solved_ms: float, fitted_ms: float) -> float:
    """The exposure (ms) a camera's bands show at ``frame``: the span's of ``shown`` that
    holds it; else of the spans either side of it the one farther from ``fitted_ms`` (either
    may hold it); else ``solved_ms``."""
    holding = [s.exposure_ms for s in shown if s.first_frame <= frame <= s.last_frame]
    if holding:
        return float(holding[0])
    before = [s for s in shown if s.last_frame < frame]
    after = [s for s in shown if s.first_frame > frame]
    sides = ([max(before, key=lambda s: s.last_frame)] if before else []) + (
        [min(after, key=lambda s: s.first_frame)] if after else []
    )
    return float(max((s.exposure_ms for s in sides), key=lambda e: abs(e - fitted_ms), default=solved_ms))


def _misread_decay_rows(detection: CameraDetection, events: Events) -> np.ndarray:
    """How far each edge's half-light may move with an error common to its camera's
    readings of the pulses that outlast its exposure, readout rows: :data:`MISREAD_DECAY_SHARE`
    of its band's pulse (:attr:`~flashsync.detect.CameraDetection.pulse_rows`) where that
    is longer than the exposure the bands share and the band, whole within one frame, is not
    (:data:`OUTLASTED_SHARE`: a band that long is a rectangle's, or an exposure's the camera
    changed to), 0 for the other edges. Shape (n,)."""
    pulses, exposure = detection.pulse_rows, detection.exposure_rows
    if pulses is None or exposure is None:
        return np.zeros(len(events))
    bands, lengths = _whole_bands(detection.events)
    decaying = bands.event[(lengths < OUTLASTED_SHARE * exposure) & (pulses[bands.event] > exposure)]
    return np.where(np.isin(events.event, decaying), MISREAD_DECAY_SHARE * pulses[events.event], 0.0)


#: A band within one frame this many times as long as the exposure its camera's bands share
#: (:attr:`~flashsync.detect.CameraDetection.exposure_rows`) or longer is as long as its
#: pulse. Over the 40 kept random rigs and the ten recipes (each camera in its true reading)
#: the share leaves out the lengths of 69 of 127 clean bands whose LED pulse was 1.2
#: exposures or longer (their lengths 6.5 rows too long, median) and of 47 of 1788 bands of
#: shorter pulses (5.7 rows too long); the kept lengths are 0.1 rows too long.
OUTLASTED_SHARE = 1.2


def _pulse_lengths(detection: CameraDetection) -> np.ndarray:
    """Event numbers of the camera's bands within one frame that are :data:`OUTLASTED_SHARE`
    times as long as the exposure its bands share or longer, where another is not: the
    flash outlasted the exposure, and such a band is as long as its pulse. Its midpoint
    still lies half an exposure after the pulse's middle (a rectangle's both edges are half
    the difference off, the other way), so the solve keeps the band's midpoint and leaves
    its length out (:data:`~flashsync.detect.LONG_PULSE_EDGE_SIGMA`): the bands of the
    exposure's length measure the exposure, which places every midpoint."""
    if detection.exposure_rows is None:
        return detection.events.event[:0]
    bands, lengths = _whole_bands(detection.events)
    longer = lengths >= OUTLASTED_SHARE * detection.exposure_rows
    return bands.event[longer] if not longer.all() else bands.event[:0]


def _outreaching(detection: CameraDetection, events: Events) -> np.ndarray:
    """Boolean mask of the camera's edges whose band's other edge is hidden though it would
    lie more than :data:`LONE_REACH` exposures (:func:`_exposure_rows`) inside the readout:
    the band is not one exposure long. All False where the camera's exposure is unknown."""
    exposure = _exposure_rows(detection)
    if exposure is None:
        return np.zeros(len(events), dtype=bool)
    return np.nan_to_num(_rows_to_cut(detection, events), nan=0.0) > LONE_REACH * exposure


def _sync_events(detection: CameraDetection) -> Events:
    """The synchronisation events, one edge per band: its leading edge, or where that is
    hidden (a flash during the vertical blanking or just before it) the trailing edge of a
    clean pulse band (unclipped, not ``long_pulse``, not :func:`_outreaching`), one exposure
    after its flash: of a camera with an exposure to place the flash by for matching
    (:func:`_exposure_rows`, :func:`_start_times_ms`)."""
    events = detection.events
    leading = events.edge == Edge.LEADING
    if _exposure_rows(detection) is None:
        return events.take(leading)
    clean = ~events.has_flag(Flag.SATURATED) & ~events.has_flag(Flag.LONG_PULSE) & ~_outreaching(detection, events)
    lone = (events.edge == Edge.TRAILING) & events.has_flag(Flag.LEADING_HIDDEN) & (events.band == Band.PULSE)
    return events.take(leading | (lone & clean))


def _start_times_ms(detection: CameraDetection, events: Events, share: float = 1.0) -> np.ndarray:
    """Approximate times (ms, the camera's own clock) of the starts of the bands of the
    camera's ``events``: :func:`~flashsync.match.approximate_times_ms` at ``share`` of the
    nominal time per row, a trailing edge's one exposure (:func:`_exposure_rows` at that
    time per row; none where that is unknown) earlier."""
    trailing = events.edge == Edge.TRAILING
    exposure_ms = (_exposure_rows(detection) or 0.0) * share * nominal_row_time_ms(detection)
    return approximate_times_ms(detection, events, share) - np.where(trailing, exposure_ms, 0.0)


def _trailing_edges(detection: CameraDetection) -> Events:
    """The trailing edges that are timing evidence: of :func:`_timing_bands`."""
    events = detection.events
    return events.take(_timing_bands(events).trailing)


#: Fewest unclipped bands with both edges a camera needs for its clipped bands to time their
#: flashes by their midpoints (:func:`_timing_bands`): a midpoint lies half an exposure after
#: its flash, and a clipped band is longer than the exposure by what the clip adds. With
#: fewer the exposure would rest on clipped lengths (on random rigs 0-49 such cameras moved
#: their rigs' references: rig-4 0.32 -> 0.45 ms, rig-30 0.07 -> 0.14; a camera whose scene
#: was at white under its bands stated 1.15 +- 0.08 ms against 8).
MIN_UNCLIPPED_BANDS = 2


def _timing_bands(events: Events) -> Bands:
    """The pulse bands whose both edges time their flash: both visible and not flagged
    ``long_pulse`` (a pulse longer than the exposure may have made the band as wide). A band
    clipped at white is one: its two edges move alike, out or in, so its midpoint is as
    sharp as an unclipped band's (over the kept random rigs 0-49 the midpoints of 105
    clipped bands within 0.05 rows of the truth, median, robust sigma 0.19 rows in one
    frame and 0.32 split across two; of 2445 unclipped ones 0.00 and 0.21-0.24), its length
    about a row too long (:func:`_trailing_sigma`); in a camera of at least
    :data:`MIN_UNCLIPPED_BANDS` unclipped ones, whose lengths give the exposure."""
    bands = events.bands()
    first = bands.first_edges()
    timing = bands.complete & (events.band[first] == Band.PULSE) & ~events.has_flag(Flag.LONG_PULSE)[first]
    clipped = events.has_flag(Flag.SATURATED)[first]
    if np.count_nonzero(timing & ~clipped) < MIN_UNCLIPPED_BANDS:
        timing &= ~clipped
    return bands.take(timing)


def _observations(cameras: list[CameraDetection], matches: Matches) -> Observations:
    """What the solve fits: the matched sync events (in the order of ``matches``, with their
    noise; a trailing one stands alone, its band's leading edge hidden), then the trailing
    edges (:func:`_trailing_edges`) of their bands, on the same flashes (a band longer than
    the exposure weighed down in its length, :func:`_trailing_sigma`)."""
    camera, flash, t_frame, q = [matches.camera_index], [matches.flash], [matches.t_frame_ms], [matches.q]
    leading_of = [np.full(len(matches), -1, dtype=np.int64)]
    split = [np.zeros(len(matches), dtype=bool)]
    sigma_factor = [matches.edge_sigma.copy()]
    for index, detection in enumerate(cameras):
        mine = np.flatnonzero(matches.camera_index == index)
        row_of = dict(zip(matches.event[mine].tolist(), mine.tolist()))
        edges = _trailing_edges(detection)
        edges = edges.take(np.isin(edges.event, list(row_of)))
        leading_of.append(np.array([row_of[e] for e in edges.event.tolist()], dtype=np.int64))
        sigma_factor.append(_trailing_sigma(detection, edges))
        # a clipped band's midpoint (its leading edge's row) is as sharp as an unclipped one's (_timing_bands)
        clipped = edges.has_flag(Flag.SATURATED)
        sigma_factor[0][leading_of[-1][clipped]] = _faintness(detection, edges)[clipped]
        split.append(edges.has_flag(Flag.SPLIT))
        camera.append(np.full(len(edges), index, dtype=np.int64))
        flash.append(matches.flash[leading_of[-1]])
        t_frame.append(edges.t_frame_ms)
        q.append(_readout_rows(detection, edges))
    trailing = np.concatenate([matches.trailing, np.ones(sum(len(c) for c in camera[1:]), dtype=bool)])
    return Observations(
        np.concatenate(camera),
        np.concatenate(flash),
        np.concatenate(t_frame),
        np.concatenate(q),
        np.concatenate(sigma_factor),
        trailing,
        np.concatenate(leading_of),
        np.concatenate(split),
    )


def _with_a_leading_edge(matching: Matching, sync_events: dict[str, Events]) -> Matching:
    """``matching`` without the cameras none of whose matched sync events is a leading edge:
    tied by trailing edges alone (one exposure after their flashes), a camera's shift and
    exposure are one unknown."""
    leading = {camera for camera, i in matching.flashes if sync_events[camera].edge[i] == Edge.LEADING}
    return replace(matching, flashes={key: f for key, f in matching.flashes.items() if key[0] in leading})


def _matches(
    cameras: list[CameraDetection], sync_events: dict[str, Events], flashes: dict[tuple[str, int], int]
) -> Matches:
    """The sync events of ``cameras`` that belong to a flash seen by two or more of them."""
    chosen, flash, camera_index = [], [], []
    for index, detection in enumerate(cameras):
        mine = [i for i in range(len(sync_events[detection.camera])) if (detection.camera, i) in flashes]
        chosen.append(sync_events[detection.camera].take(np.array(mine, dtype=np.int64)))
        flash += [flashes[(detection.camera, i)] for i in mine]
        camera_index += [index] * len(mine)
    events = Events.concat(chosen)
    q = np.concatenate([_readout_rows(detection, mine) for detection, mine in zip(cameras, chosen)])
    sigma = np.concatenate([_edge_sigma(detection, mine) for detection, mine in zip(cameras, chosen)])
    toward_cut = np.concatenate([_toward_cut_rows(detection, mine) for detection, mine in zip(cameras, chosen)])
    misread = np.concatenate([_misread_decay_rows(detection, mine) for detection, mine in zip(cameras, chosen)])
    camera_index = np.asarray(camera_index, dtype=np.int64)
    keep, flash = shared_flashes(camera_index, flash)
    return Matches(
        flash,
        events.camera[keep],
        camera_index[keep],
        events.event[keep],
        events.frame[keep],
        events.row[keep],
        q[keep],
        events.t_frame_ms[keep],
        sigma[keep],
        (events.edge == Edge.TRAILING)[keep],
        toward_cut[keep],
        misread[keep],
    )
