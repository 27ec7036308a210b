"""The library API: detect events in videos, match them and solve for a :class:`SyncModel`.

The CLI is a thin layer over these functions; a notebook calls them the same way::

    detections = detect_videos(["cam1.mp4", "cam2.mkv", "cam3.mp4"])
    model = synchronize(detections)
    model.camera("cam2").t_global_ms(frame=120, row=200.5)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from flashsync.detect import CameraDetection, DetectorSettings, detect_video
from flashsync.errors import FlashsyncError
from flashsync.match import PairAlignment, align_pair, group_flashes, parse_anchors
from flashsync.model import CameraClock, SyncModel
from flashsync.profiles import probe_video
from flashsync.solve import Durations, Events, Priors, solve_clocks

#: Weak prior on T_row where no datasheet value is given: frame period / (1.05 x height),
#: std 8 %; only decisive where the events cannot tell T_row (few flashes).
NOMINAL_HIDDEN_ROWS = 1.05
NOMINAL_ROW_TIME_STD = 0.08


def detect_videos(paths: Sequence[str | Path], flipped: Sequence[str] = (),
                  settings: DetectorSettings | None = None,
                  progress: Callable[[str, int], Callable[[int], None]] | None = None,
                  ) -> list[CameraDetection]:
    """Detect events in each video (camera names = file stems, which must be unique).

    ``progress(camera, n_frames_hint)`` may return a callback taking frames decoded.
    """
    paths = [Path(p) for p in paths]
    stems = [p.stem for p in paths]
    duplicates = sorted({s for s in stems if stems.count(s) > 1})
    if duplicates:
        raise FlashsyncError(f"camera names come from file stems and {', '.join(duplicates)} is "
                             "given twice; rename one of the videos")
    unknown = sorted(set(flipped) - set(stems))
    if unknown:
        raise FlashsyncError(f"--flipped {', '.join(unknown)}: no such camera among {', '.join(stems)}")
    results = []
    for path in paths:
        callback = None
        if progress is not None:
            callback = progress(path.stem, probe_video(path).n_frames_hint)
        results.append(detect_video(path, flipped=path.stem in flipped, settings=settings,
                                    progress=callback))
    return results


def all_events(detections: Sequence[CameraDetection]) -> pd.DataFrame:
    """One events table (``detect`` output) for all cameras."""
    return pd.concat([d.events for d in detections], ignore_index=True)


@dataclass
class SyncReport:
    """What :func:`synchronize` found besides the model: pair alignments and warnings."""

    alignments: dict[tuple[str, str], PairAlignment] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    sigma_ms: float = float("nan")


def synchronize(detections: Sequence[CameraDetection], reference: str | None = None,
                row_times: dict[str, float] | None = None, anchors: Sequence[str] = (),
                ) -> tuple[SyncModel, SyncReport]:
    """Match events across cameras and solve every camera's clock.

    Parameters
    ----------
    detections : one per camera (from :func:`detect_videos`).
    reference : camera whose clock is the global clock; default the first.
    row_times : known time per row (ms) per camera, e.g. from a datasheet.
    anchors : ``CAMERA:EVENT`` strings naming events that are one flash (optional).
    """
    cameras = {d.camera: d for d in detections}
    reference = reference or detections[0].camera
    if reference not in cameras:
        raise FlashsyncError(f"--reference {reference}: no such camera among {', '.join(cameras)}")
    sync_events = {name: _sync_events(d) for name, d in cameras.items()}
    usable = [name for name, events in sync_events.items() if len(events) >= 2]
    report = SyncReport()
    for name in cameras:
        if name not in usable:
            report.warnings.append(f"{cameras[name].video}: {len(sync_events[name])} usable flash "
                                   "events (need at least 2); left out")
    if len(usable) < 2:
        counts = ", ".join(f"{cameras[n].video.name}: {len(sync_events[n])}" for n in cameras)
        raise FlashsyncError(f"need two or more cameras with at least two flash events each; found "
                             f"{counts}; check that the videos show flashes (or lights switching)")
    anchor_events = parse_anchors(list(anchors), {n: len(sync_events[n]) for n in usable})
    approx = {name: _approximate_times(cameras[name], sync_events[name]) for name in usable}
    tolerance = max(5.0, 0.25 * max(_frame_period(cameras[n]) for n in usable))
    for i, name_a in enumerate(usable):
        for name_b in usable[i + 1:]:
            anchor = ((anchor_events[name_a], anchor_events[name_b])
                      if name_a in anchor_events and name_b in anchor_events else None)
            alignment = align_pair(approx[name_a], approx[name_b], tolerance, anchor)
            if alignment is not None and len(alignment.matches) >= 3 and not alignment.ambiguous:
                report.alignments[(name_a, name_b)] = alignment
    flashes = group_flashes({n: len(sync_events[n]) for n in usable}, report.alignments)
    connected = _connected(reference, usable, report.alignments)
    for name in usable:
        if name not in connected:
            report.warnings.append(f"{cameras[name].video}: shares fewer than 3 unambiguous flashes "
                                   f"with the other cameras; cannot be tied to {reference}; left out")
    if reference not in connected or len(connected) < 2:
        raise FlashsyncError(f"no camera shares at least 3 flashes with {reference}; check that "
                             "the videos overlap in time and saw the same flashes")
    observations = _observations(connected, sync_events, flashes)
    order = {name: i for i, name in enumerate(connected)}
    row_time_priors = {order[name]: (value, 1e-4 * value) for name, value in (row_times or {}).items()
                       if name in order}
    for name in connected:
        if order[name] not in row_time_priors:
            nominal = _frame_period(cameras[name]) / (NOMINAL_HIDDEN_ROWS * cameras[name].height)
            row_time_priors[order[name]] = (nominal, NOMINAL_ROW_TIME_STD * nominal)
    durations = _durations([cameras[name] for name in connected])
    solution = solve_clocks(
        Events(observations["camera_index"].to_numpy(), observations["flash"].to_numpy(),
               observations["t_frame_ms"].to_numpy(), observations["q"].to_numpy()),
        len(connected), order[reference],
        durations=durations,
        priors=Priors(row_time_priors))
    report.sigma_ms = solution.sigma_ms
    n_events = len(observations)
    clocks = {}
    for name in connected:
        d, s = cameras[name], solution.cameras[order[name]]
        clocks[name] = CameraClock(name, d.frame_times_ms, d.height, d.width, s.alpha, s.beta_ms,
                                   s.row_time_ms, d.flipped, s.covariance,
                                   _exposure_ms(durations, order[name], s.alpha, s.row_time_ms),
                                   video=str(d.video))
    observations["t_global_ms"] = solution.flash_ms[observations["flash"].to_numpy()]
    observations["residual_ms"] = solution.residual_ms[:n_events]
    observations["inlier"] = solution.inlier[:n_events]
    events = observations.drop(columns=["camera_index", "q"])
    return SyncModel(reference, clocks, events.reset_index(drop=True)), report


def _with_readout_rows(detection: CameraDetection) -> pd.DataFrame:
    """The camera's events with their readout row ``q``."""
    events = detection.events
    q = detection.height - 1 - events["row"] if detection.flipped else events["row"]
    return events.assign(q=q.to_numpy())


def _sync_events(detection: CameraDetection) -> pd.DataFrame:
    """Leading edges, the synchronisation events, with their readout row ``q``."""
    events = _with_readout_rows(detection)
    return events[events["edge"] == "leading"].reset_index(drop=True)


def _exposure_ms(durations: Durations, camera: int, alpha: float, row_time_ms: float) -> float | None:
    """Exposure time (ms, reference clock) from the camera's bands, or None without any.

    A band's half-fall comes one exposure after its half-rise (rows that saw the whole
    flash are the ones whose exposure window holds it), so its duration is the exposure.
    """
    mine = durations.camera == camera
    if not mine.any():
        return None
    return float(np.median(alpha * durations.dt_frame_ms[mine] + durations.dq[mine] * row_time_ms))


def _durations(detections: list[CameraDetection]) -> Durations:
    """Pulse bands with both edges visible and unsaturated, camera indices in list order."""
    camera, dt, dq = [], [], []
    for index, detection in enumerate(detections):
        events = _with_readout_rows(detection)
        usable = events[(events["band"] == "pulse") & ~events["flags"].str.contains("saturated")]
        both = usable.pivot_table(index="event", columns="edge", values=["t_frame_ms", "q"]).dropna()
        if both.empty:
            continue
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


def _observations(names: list[str], sync_events: dict[str, pd.DataFrame],
                  flashes: dict[tuple[str, int], int]) -> pd.DataFrame:
    """One row per (camera, event) that belongs to a flash seen by >= 2 connected cameras."""
    rows = []
    for index, name in enumerate(names):
        events = sync_events[name]
        for i, event in events.iterrows():
            if (name, i) in flashes:
                rows.append({"flash": flashes[(name, i)], "camera": name, "camera_index": index,
                             "event": int(event["event"]), "frame": int(event["frame"]),
                             "row": float(event["row"]), "q": float(event["q"]),
                             "t_frame_ms": float(event["t_frame_ms"])})
    table = pd.DataFrame(rows)
    counts = table.groupby("flash")["camera"].transform("size")
    table = table[counts >= 2].copy()
    table["flash"] = pd.factorize(table["flash"], sort=True)[0]
    return table.reset_index(drop=True)
