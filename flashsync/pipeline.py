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
from dataclasses import dataclass, field, replace
from functools import cached_property
from itertools import combinations
from pathlib import Path

import numpy as np
import pandas as pd

from flashsync.detect import CameraDetection, DetectorSettings, detect_video
from flashsync.errors import FlashsyncError
from flashsync.frame_clock import FrameClock, fit_frame_clock
from flashsync.match import PairAlignment, align_pair, group_flashes, parse_anchors
from flashsync.model import CameraClock, SyncModel
from flashsync.solve import Durations, Events, Priors, Solution, solve_with_drift_model
from flashsync.timestamps import csv_timestamps

#: Weak prior on T_row where no datasheet value is given: frame period / (1.05 x height),
#: std 8 %; only decisive where the events cannot tell T_row (few flashes).
NOMINAL_HIDDEN_ROWS = 1.05
NOMINAL_ROW_TIME_STD = 0.08
#: Fewest flashes two cameras must share for their pair alignment to count.
MIN_SHARED_FLASHES = 3


def detect_videos(
    paths: Sequence[str | Path],
    flipped: Sequence[str] = (),
    estimate_readout: bool = False,
    settings: DetectorSettings | None = None,
    progress: Callable[[str, int], Callable[[int], None]] | None = None,
    timestamps: dict[str, Path] | None = None,
) -> list[CameraDetection]:
    """Detect events in each video (camera names = file stems, which must be unique).

    Parameters
    ----------
    paths : video files.
    flipped : cameras known to be mounted upside down.
    estimate_readout : detect the other cameras' events both ways, so that
        :func:`synchronize` can find an upside-down camera.
    progress : ``progress(camera, n_frames_hint)`` may return a callback taking frames decoded.
    timestamps : per camera, a CSV of frame timestamps (``t_ms``, or 90 kHz ``rtp``, one row
        per decoded frame) used instead of the container's (see :func:`csv_timestamps`).

    Videos are decoded in parallel threads, one per core (decoding and the compiled row
    kernel release the GIL).
    """
    paths = [Path(p) for p in paths]
    stems = [p.stem for p in paths]
    duplicates = sorted({s for s in stems if stems.count(s) > 1})
    if duplicates:
        raise FlashsyncError(
            f"camera names come from file stems and {', '.join(duplicates)} is given twice; rename one of the videos"
        )
    timestamps = timestamps or {}
    for option, names in (("--flipped", flipped), ("--timestamps", timestamps)):
        unknown = sorted(set(names) - set(stems))
        if unknown:
            raise FlashsyncError(f"{option} {', '.join(unknown)}: no such camera among {', '.join(stems)}")
    stamps = {camera: csv_timestamps(path) for camera, path in timestamps.items()}

    def detect(path: Path) -> CameraDetection:
        direction = True if path.stem in flipped else (None if estimate_readout else False)
        detection = detect_video(path, flipped=direction, settings=settings, progress=progress)
        if path.stem not in stamps:
            return detection
        if len(stamps[path.stem]) != len(detection.frame_times_ms):
            raise FlashsyncError(
                f"{timestamps[path.stem]}: {len(stamps[path.stem])} timestamps for the "
                f"{len(detection.frame_times_ms)} frames of {path}; give one row per decoded frame"
            )
        return with_frame_times(detection, stamps[path.stem])

    with ThreadPoolExecutor(max_workers=max(1, min(len(paths), os.cpu_count() or 1))) as pool:
        return list(pool.map(detect, paths))


def all_events(detections: Sequence[CameraDetection]) -> pd.DataFrame:
    """One events table (``detect`` output) for all cameras."""
    return pd.concat([d.events for d in detections], ignore_index=True)


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
    detections : one per camera (from :func:`detect_videos`); a detection with
        ``alternative`` events has its readout direction chosen here.
    reference : camera whose clock is the global clock; default the first.
    row_times : known time per row (ms) per camera, e.g. from a datasheet.
    anchors : ``CAMERA:EVENT`` strings naming events that are one flash (optional).
    """
    reference = reference or detections[0].camera
    names = [d.camera for d in detections]
    if reference not in names:
        raise FlashsyncError(f"--reference {reference}: no such camera among {', '.join(names)}")
    report = SyncReport(frame_clocks={d.camera: fit_frame_clock(d.frame_times_ms) for d in detections})
    cameras = {d.camera: with_frame_times(d, report.frame_clocks[d.camera].times_ms) for d in detections}
    undecided = [name for name, d in cameras.items() if d.alternative is not None]
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


@dataclass
class _Attempt:
    """One matching and solve with given readout directions."""

    cameras: dict[str, CameraDetection]
    connected: list[str]
    alignments: dict[tuple[str, str], PairAlignment]
    warnings: list[str]
    observations: pd.DataFrame
    durations: Durations
    solution: Solution

    @cached_property
    def score(self) -> float:
        """Log-likelihood of all the cameras' sync events under these readout directions:
        inliers Gaussian with the solve's residual scale, every other event (rejected, or
        matched to nothing) uniform over a frame period. Counting inliers alone would
        prefer a wrong direction whose loose fit (a scale ten times larger) lets one more
        event in."""
        n_inliers = int(self.solution.inlier[: len(self.observations)].sum())
        n_events = sum(len(_sync_events(d)) for d in self.cameras.values())
        sigma = max(self.solution.sigma_ms, 1e-4)
        period = max(_frame_period(d) for d in self.cameras.values())
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
        n_events = len(self.observations)
        events = self.observations.assign(
            t_global_ms=self.solution.flash_ms[self.observations["flash"].to_numpy()],
            residual_ms=self.solution.residual_ms[:n_events],
            inlier=self.solution.inlier[:n_events],
        )
        return SyncModel(reference, clocks, events.drop(columns=["camera_index", "q"]))


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
        raise FlashsyncError(
            f"need two or more cameras with at least two flash events each; found "
            f"{counts}; check that the videos show flashes (or lights switching)"
        )
    alignments = _align_pairs({n: cameras[n] for n in usable}, {n: sync_events[n] for n in usable}, anchors)
    flashes = group_flashes({n: len(sync_events[n]) for n in usable}, alignments)
    connected = _connected(reference, usable, alignments)
    warnings += [
        f"{cameras[name].video}: shares fewer than {MIN_SHARED_FLASHES} unambiguous flashes "
        f"with the other cameras; cannot be tied to {reference}; left out"
        for name in usable
        if name not in connected
    ]
    if reference not in connected or len(connected) < 2:
        raise FlashsyncError(
            f"no camera shares at least {MIN_SHARED_FLASHES} flashes with {reference}; "
            "check that the videos overlap in time and saw the same flashes"
        )
    observations = _observations(connected, sync_events, flashes)
    durations = _durations([cameras[name] for name in connected])
    priors = _row_time_priors([cameras[name] for name in connected], row_times or {})
    solution = solve_with_drift_model(
        Events(
            observations["camera_index"].to_numpy(),
            observations["flash"].to_numpy(),
            observations["t_frame_ms"].to_numpy(),
            observations["q"].to_numpy(),
        ),
        len(connected),
        connected.index(reference),
        durations=durations,
        priors=Priors(priors),
    )
    return _Attempt(cameras, connected, alignments, warnings, observations, durations, solution)


def with_frame_times(detection: CameraDetection, times_ms: np.ndarray) -> CameraDetection:
    """The detection with other frame times (ms, one per decoded frame), its events' frame
    times too."""

    def retimed(events: pd.DataFrame | None) -> pd.DataFrame | None:
        if events is None:
            return None
        return events.assign(t_frame_ms=times_ms[events["frame"].to_numpy(dtype=np.int64)])

    return replace(
        detection, frame_times_ms=times_ms, events=retimed(detection.events), alternative=retimed(detection.alternative)
    )


def _align_pairs(
    cameras: dict[str, CameraDetection], sync_events: dict[str, pd.DataFrame], anchors: Sequence[str]
) -> dict[tuple[str, str], PairAlignment]:
    """Coarse alignment of every pair of cameras; pairs sharing too few or ambiguous flashes
    are left out."""
    anchor_events = parse_anchors(list(anchors), {n: len(e) for n, e in sync_events.items()})
    approx = {name: _approximate_times(cameras[name], sync_events[name]) for name in cameras}
    tolerance = max(5.0, 0.25 * max(_frame_period(d) for d in cameras.values()))
    names = list(cameras)
    alignments = {}
    for i, name_a in enumerate(names):
        for name_b in names[i + 1 :]:
            anchor = (
                (anchor_events[name_a], anchor_events[name_b])
                if name_a in anchor_events and name_b in anchor_events
                else None
            )
            alignment = align_pair(approx[name_a], approx[name_b], tolerance, anchor)
            if alignment is not None and len(alignment.matches) >= MIN_SHARED_FLASHES and not alignment.ambiguous:
                alignments[(name_a, name_b)] = alignment
    return alignments


def _row_time_priors(cameras: list[CameraDetection], row_times: dict[str, float]) -> dict[int, tuple[float, float]]:
    """Per camera index: a datasheet T_row (std 0.01 %) or the weak nominal prior."""
    priors = {}
    for index, camera in enumerate(cameras):
        if camera.camera in row_times:
            priors[index] = (row_times[camera.camera], 1e-4 * row_times[camera.camera])
        else:
            nominal = _frame_period(camera) / (NOMINAL_HIDDEN_ROWS * camera.height)
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


def _with_readout_rows(detection: CameraDetection) -> pd.DataFrame:
    """The camera's events with their readout row ``q``."""
    events = detection.events
    q = detection.height - 1 - events["row"] if detection.flipped else events["row"]
    return events.assign(q=q.to_numpy())


def _sync_events(detection: CameraDetection) -> pd.DataFrame:
    """Leading edges, the synchronisation events, with their readout row ``q``."""
    events = _with_readout_rows(detection)
    return events[events["edge"] == "leading"].reset_index(drop=True)


def _durations(detections: list[CameraDetection]) -> Durations:
    """Pulse bands with both edges visible and unsaturated, camera indices in list order."""
    camera, dt, dq = [], [], []
    for index, detection in enumerate(detections):
        events = _with_readout_rows(detection)
        usable = events[(events["band"] == "pulse") & ~events["flags"].str.contains("saturated")]
        both = usable.pivot_table(index="event", columns="edge", values=["t_frame_ms", "q"])
        if not {("q", "leading"), ("q", "trailing")} <= set(both.columns):
            continue
        both = both.dropna()
        camera += [index] * len(both)
        dt += list(both[("t_frame_ms", "trailing")] - both[("t_frame_ms", "leading")])
        dq += list(both[("q", "trailing")] - both[("q", "leading")])
    return Durations(np.asarray(camera, dtype=np.int64), np.asarray(dt), np.asarray(dq))


def _frame_period(detection: CameraDetection) -> float:
    return float(np.median(np.diff(detection.frame_times_ms)))


def _approximate_times(detection: CameraDetection, events: pd.DataFrame) -> np.ndarray:
    """Event times on the camera's own clock, ms, with a nominal time per row."""
    row_time = _frame_period(detection) / detection.height
    return events["t_frame_ms"].to_numpy() + events["q"].to_numpy() * row_time


def _connected(reference: str, names: list[str], alignments: dict[tuple[str, str], PairAlignment]) -> list[str]:
    """Cameras reachable from the reference through accepted pair alignments, in input order."""
    reached, frontier = {reference}, [reference]
    while frontier:
        current = frontier.pop()
        for a, b in alignments:
            for here, there in ((a, b), (b, a)):
                if here == current and there not in reached:
                    reached.add(there)
                    frontier.append(there)
    return [name for name in names if name in reached]


def _observations(
    names: list[str], sync_events: dict[str, pd.DataFrame], flashes: dict[tuple[str, int], int]
) -> pd.DataFrame:
    """One row per (camera, event) that belongs to a flash seen by >= 2 connected cameras."""
    rows = []
    for index, name in enumerate(names):
        for i, event in sync_events[name].iterrows():
            if (name, i) in flashes:
                rows.append(
                    {
                        "flash": flashes[(name, i)],
                        "camera": name,
                        "camera_index": index,
                        "event": int(event["event"]),
                        "frame": int(event["frame"]),
                        "row": float(event["row"]),
                        "q": float(event["q"]),
                        "t_frame_ms": float(event["t_frame_ms"]),
                    }
                )
    table = pd.DataFrame(rows)
    counts = table.groupby("flash")["camera"].transform("size")
    table = table[counts >= 2].copy()
    table["flash"] = pd.factorize(table["flash"], sort=True)[0]
    return table.reset_index(drop=True)
