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
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import cached_property
from itertools import combinations
from pathlib import Path

import numpy as np
import pandas as pd

from flashsync.detect import CameraDetection, DetectorSettings, detect_video
from flashsync.errors import FlashsyncError, InputError, NotEnoughDataError
from flashsync.events import Band, Edge, Events, Flag
from flashsync.frame_clock import FrameClock, fit_frame_clock
from flashsync.io.timestamps import load_timestamps
from flashsync.match import (
    MIN_SHARED_FLASHES,
    PairAlignment,
    approximate_times_ms,
    match_events,
    match_tolerance_ms,
    parse_anchors,
    shared_flashes,
)
from flashsync.model import MATCHED_EVENT_COLUMNS, CameraClock, SyncModel, readout_rows
from flashsync.solve import Durations, Observations, Priors, Solution, solve_with_drift_model
from flashsync.timestamps import median_step_ms

#: Weak prior on T_row where no datasheet value is given: frame period / (1.05 x height),
#: std 8 %; only decisive where the events cannot tell T_row (few flashes).
NOMINAL_HIDDEN_ROWS = 1.05
NOMINAL_ROW_TIME_STD = 0.08


def detect_videos(
    paths: Sequence[str | Path],
    flipped: Sequence[str] = (),
    estimate_readout: bool = True,
    settings: DetectorSettings | None = None,
    progress: Callable[[str, int], Callable[[int], None]] | None = None,
    timestamps: dict[str, Path] | None = None,
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

    Videos are decoded in parallel threads, one per core (decoding and the compiled row
    kernel release the GIL).
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

    def detect(path: Path) -> CameraDetection:
        direction = True if path.stem in flipped else (None if estimate_readout else False)
        detection = detect_video(path, flipped=direction, settings=settings, progress=progress)
        if path.stem not in stamps:
            return detection
        if len(stamps[path.stem]) != len(detection.frame_times_ms):
            raise InputError(
                f"{timestamps[path.stem]}: {len(stamps[path.stem])} timestamps for the "
                f"{len(detection.frame_times_ms)} frames of {path}; give one row per decoded frame"
            )
        return detection.retimed(stamps[path.stem])

    with ThreadPoolExecutor(max_workers=max(1, min(len(paths), os.cpu_count() or 1))) as pool:
        return list(pool.map(detect, paths))


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
    flipped_found : cameras found to read bottom-up (upside down).
    warnings : cameras left out and why.
    sigma_ms : robust residual scale of the solve, ms.
    """

    alignments: dict[tuple[str, str], PairAlignment] = field(default_factory=dict)
    frame_clocks: dict[str, FrameClock] = field(default_factory=dict)
    flipped_found: list[str] = field(default_factory=list)
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
        up has its readout direction chosen here.
    reference : camera whose clock is the global clock; default the first.
    row_times : known time per row (ms) per camera, e.g. from a datasheet.
    anchors : ``CAMERA:EVENT`` strings naming events that are one flash (optional); EVENT is
        the detector's event number, as in the events table and the model's events.
    """
    reference = reference or detections[0].camera
    names = [d.camera for d in detections]
    if reference not in names:
        raise InputError(
            f"{reference}: no such camera among {', '.join(names)}; the reference must be one of them",
            parameter="reference",
        )
    report = SyncReport(frame_clocks={d.camera: fit_frame_clock(d.frame_times_ms) for d in detections})
    cameras = {d.camera: d.retimed(report.frame_clocks[d.camera].times_ms) for d in detections}
    undecided = [name for name, d in cameras.items() if d.undecided]
    best = _best_readout(cameras, undecided, lambda trial: _attempt(trial, reference, row_times, anchors))
    report.alignments, report.warnings = best.alignments, best.warnings
    report.flipped_found = [name for name in undecided if best.cameras[name].flipped]
    report.sigma_ms = best.solution.sigma_ms
    return best.model(reference), report


def _best_readout(
    cameras: dict[str, CameraDetection], undecided: list[str], attempt: Callable[[dict[str, CameraDetection]], _Attempt]
) -> _Attempt:
    """The readout directions of the ``undecided`` cameras that explain the events best
    (:attr:`_Attempt.score`): steepest ascent from the detected ones, each step taking the
    best of all single flips, until none helps. Raises the first failure if nothing solves."""
    best, failure, start = None, None, cameras
    while True:
        improved = False
        for flip in [None, *undecided] if best is None else undecided:
            trial = dict(start)
            if flip is not None:
                trial[flip] = trial[flip].read_flipped(not trial[flip].flipped)
            try:
                result = attempt(trial)
            except FlashsyncError as error:
                failure = failure or error
                continue
            if best is None or result.score > best.score:
                best, improved = result, True
        if best is None:
            raise failure
        if not improved:
            return best
        start = best.cameras


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
    """The sync events (leading edges) that belong to a flash seen by two or more cameras,
    arrays of shape (n,).

    Attributes
    ----------
    flash : int array
        Flash number, 0..n_flashes-1.
    camera : str array
        Camera name.
    camera_index : int array
        Index of the camera among the cameras solved.
    event, frame : int arrays
        The detector's event number and the decoded frame of its leading edge.
    row, q : float arrays
        Stored-image row and readout row of the edge.
    t_frame_ms : float array
        The frame's time (frame clock), ms.
    """

    flash: np.ndarray
    camera: np.ndarray
    camera_index: np.ndarray
    event: np.ndarray
    frame: np.ndarray
    row: np.ndarray
    q: np.ndarray
    t_frame_ms: np.ndarray

    def __len__(self) -> int:
        return len(self.flash)

    def observations(self) -> Observations:
        """What the solve needs of them."""
        return Observations(self.camera_index, self.flash, self.t_frame_ms, self.q)

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
    durations: Durations
    solution: Solution

    @cached_property
    def score(self) -> float:
        """Log-likelihood of all the cameras' sync events under these readout directions:
        inliers Gaussian with the solve's residual scale, every other event (rejected, or
        matched to nothing) uniform over a frame period. Counting inliers alone would
        prefer a wrong direction whose loose fit (a scale ten times larger) lets one more
        event in."""
        n_inliers = int(self.solution.inlier[: len(self.matches)].sum())
        n_events = sum(len(_sync_events(d)) for d in self.cameras.values())
        sigma = max(self.solution.sigma_ms, 1e-4)
        period = max(median_step_ms(d.frame_times_ms) for d in self.cameras.values())
        return n_inliers * (-np.log(sigma * np.sqrt(2.0 * np.pi)) - 0.5) - (n_events - n_inliers) * np.log(period)

    def model(self, reference: str) -> SyncModel:
        clocks = {}
        for index, name in enumerate(self.connected):
            d, s = self.cameras[name], self.solution.cameras[index]
            clocks[name] = CameraClock(
                name,
                d.frame_times_ms,
                d.height,
                d.width,
                s.alpha,
                s.beta_ms,
                s.row_time_ms,
                d.flipped,
                s.covariance,
                _exposure_ms(self.durations, index, s.alpha, s.row_time_ms),
                str(d.video),
                s.knots_ms,
                s.warp_ms,
            )
        return SyncModel(reference, clocks, self.matches.table(self.solution))


def _attempt(
    cameras: dict[str, CameraDetection], reference: str, row_times: dict[str, float] | None, anchors: Sequence[str]
) -> _Attempt:
    """Match and solve with the cameras' current readout directions."""
    sync_events = {name: _sync_events(d) for name, d in cameras.items()}
    usable = [name for name, events in sync_events.items() if len(events) >= 2]
    warnings = [
        f"{cameras[name].video}: {len(sync_events[name])} usable flash events (need at least 2); left out"
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
    matching = match_events(
        {n: approximate_times_ms(cameras[n], sync_events[n]) for n in usable}, tolerance, anchor_events
    )
    tied = matching.tied_to(reference)
    connected = [name for name in usable if name in tied]
    warnings += [
        f"{cameras[name].video}: shares fewer than {MIN_SHARED_FLASHES} unambiguous flashes "
        f"with the other cameras; cannot be tied to {reference}; left out"
        for name in usable
        if name not in connected
    ]
    if reference not in connected or len(connected) < 2:
        raise NotEnoughDataError(
            f"no camera shares at least {MIN_SHARED_FLASHES} flashes with {reference}; "
            "check that the videos overlap in time and saw the same flashes"
        )
    matches = _matches([cameras[name] for name in connected], sync_events, matching.flashes)
    durations = _durations([cameras[name] for name in connected])
    priors = _row_time_priors([cameras[name] for name in connected], row_times or {})
    solution = solve_with_drift_model(
        matches.observations(), len(connected), connected.index(reference), durations=durations, priors=Priors(priors)
    )
    return _Attempt(cameras, connected, matching.alignments, warnings, matches, durations, solution)


def _row_time_priors(cameras: list[CameraDetection], row_times: dict[str, float]) -> dict[int, tuple[float, float]]:
    """Per camera index: a datasheet T_row (std 0.01 %) or the weak nominal prior."""
    priors = {}
    for index, camera in enumerate(cameras):
        if camera.camera in row_times:
            priors[index] = (row_times[camera.camera], 1e-4 * row_times[camera.camera])
        else:
            nominal = median_step_ms(camera.frame_times_ms) / (NOMINAL_HIDDEN_ROWS * camera.height)
            priors[index] = (nominal, NOMINAL_ROW_TIME_STD * nominal)
    return priors


def _exposure_ms(durations: Durations, camera: int, alpha: float, row_time_ms: float) -> float | None:
    """Exposure time (ms, reference clock) from the camera's bands, or None without any.

    A band's half-fall comes one exposure after its half-rise (rows that saw the whole
    flash are the ones whose exposure window holds it), so its duration is the exposure.
    """
    mine = durations.camera == camera
    if not mine.any():
        return None
    return float(np.median(alpha * durations.dt_frame_ms[mine] + durations.dq[mine] * row_time_ms))


def _readout_rows(detection: CameraDetection, events: Events) -> np.ndarray:
    """Readout rows of the camera's events."""
    return readout_rows(events.row, detection.height, detection.flipped)


def _sync_events(detection: CameraDetection) -> Events:
    """Leading edges: the synchronisation events."""
    events = detection.events
    return events.take(events.edge == Edge.LEADING)


def _durations(detections: list[CameraDetection]) -> Durations:
    """Pulse bands with both edges visible and unsaturated, camera indices in list order."""
    camera, dt, dq = [], [], []
    for index, detection in enumerate(detections):
        events = detection.events
        bands = events.bands()
        first = bands.first_edges()
        bands = bands.take(
            bands.complete & (events.band[first] == Band.PULSE) & ~events.has_flag(Flag.SATURATED)[first]
        )
        q = _readout_rows(detection, events)
        camera += [index] * len(bands)
        dt += list(events.t_frame_ms[bands.trailing] - events.t_frame_ms[bands.leading])
        dq += list(q[bands.trailing] - q[bands.leading])
    return Durations(np.asarray(camera, dtype=np.int64), np.asarray(dt), np.asarray(dq))


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
    )
