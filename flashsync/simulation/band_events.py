"""Band edges of many cameras without video: what the detector would give ``sync`` for a
rig too large to render (64 cameras x 500 flashes), with the true clocks to check against.

Every camera (random frame rate 25/30/50 fps, drift within ±50 ppm, shift within ±60 s,
time per row for ~1000 rows, 1080 rows high) sees each flash with probability 0.8; event
rows carry 0.05 ms of noise. Used by ``benchmarks/bench_solve.py`` and the tests of the
readout search at scale. :func:`seen_by` makes one camera of such a rig see flashes at
instants of one's choosing (pre-flashes, a fast readout, an exposure that changes).
"""

from __future__ import annotations

from collections.abc import Collection

import numpy as np

from flashsync.detect import CameraDetection
from flashsync.events import Band, Edge, Events, Flag
from flashsync.solve import Observations

HEIGHT, WIDTH = 1080, 1920
#: Exposure of every camera, ms (a band's trailing edge is one exposure after its leading edge).
EXPOSURE_MS = 2.0


def synthetic_events(n_cameras: int, n_flashes: int, seed: int = 0) -> tuple[Observations, np.ndarray, list]:
    """Observations of ``n_flashes`` flashes in 10 minutes seen by ``n_cameras`` cameras
    (readout rows ``q``), the true (alpha, beta_ms, row_time_ms) per camera (shape
    (n_cameras, 3); camera 0 is the reference) and each camera's frame times on its own
    clock (ms, one array per camera)."""
    rng = np.random.default_rng(seed)
    tau = np.sort(rng.uniform(0, 600_000.0, n_flashes))
    truth, camera, flash, t_frame, q, frame_times = [], [], [], [], [], []
    for c in range(n_cameras):
        fps = rng.choice([25.0, 30.0, 50.0])
        alpha = 1.0 if c == 0 else 1 + rng.uniform(-50e-6, 50e-6)
        beta = 0.0 if c == 0 else rng.uniform(-60_000.0, 60_000.0)
        row_time = 1000.0 / fps / rng.uniform(1080, 1125)
        truth.append((alpha, beta, row_time))
        frames = (np.arange(-2000.0, 700_000.0, 1000.0 / fps) - beta) / alpha
        frame_times.append(frames)
        starts = alpha * frames + beta
        seen = np.flatnonzero(rng.uniform(size=n_flashes) < 0.8)
        frame = np.searchsorted(starts, tau[seen], side="right") - 1
        rows = (tau[seen] - starts[frame]) / row_time
        visible = rows <= HEIGHT - 1
        camera += [c] * int(visible.sum())
        flash += list(seen[visible])
        t_frame += list(frames[frame[visible]])
        q += list(rows[visible] + rng.normal(0, 0.05 / row_time, visible.sum()))
    events = Observations(np.array(camera), np.array(flash), np.array(t_frame), np.array(q))
    return events, np.array(truth), frame_times


def synthetic_detections(
    events: Observations,
    truth: np.ndarray,
    frame_times: list[np.ndarray],
    seed: int = 0,
    upside_down: Collection[int] = (),
) -> list[CameraDetection]:
    """The events of :func:`synthetic_events` as ``detect_videos`` gives them to ``sync``,
    cameras ``cam0``, ``cam1``, ...: per camera its frame stamps (rounded to 1 ms, from 0)
    and both readings of its bands, the top-down one in use. A band's trailing edge is one
    exposure after its leading edge (hidden where that falls past the last row read). The
    cameras of ``upside_down`` (indices) are mounted upside down: their stored rows run
    against their readout, so their top-down reading is the wrong one."""
    rng = np.random.default_rng(seed + 1)
    detections = []
    for c, (_, _, row_time) in enumerate(truth):
        mine = np.flatnonzero(events.camera == c)
        order = np.argsort(events.t_frame_ms[mine])
        t_frame, lead = events.t_frame_ms[mine][order], events.q[mine][order]
        frame = np.searchsorted(frame_times[c], t_frame)
        stamps = np.round(frame_times[c] - frame_times[c][0])
        trail = lead + EXPOSURE_MS / row_time + rng.normal(0, 0.05 / row_time, len(lead))
        readings = []
        for bottom_up in (False, True):
            columns = [[] for _ in range(11)]
            for number, (f, a, b) in enumerate(zip(frame, lead, trail)):
                edges = [(Edge.LEADING, a), (Edge.TRAILING, b)] if b < HEIGHT - 0.5 else [(Edge.LEADING, a)]
                flags = frozenset() if len(edges) == 2 else frozenset({Flag.TRAILING_HIDDEN})
                if bottom_up != (c in upside_down):  # the reading against the readout: the band's edges swap
                    edges = [(Edge.LEADING, b), (Edge.TRAILING, a)] if len(edges) == 2 else []
                for edge, row in edges:
                    stored = HEIGHT - 1 - row if c in upside_down else row
                    values = (f"cam{c}", number, f, stamps[f], stored, edge, Band.PULSE, 2.0, 0.5, 50.0, flags)
                    for column, value in zip(columns, values):
                        column.append(value)
            readings.append(Events.from_columns(*columns))
        detections.append(CameraDetection(f"cam{c}", f"cam{c}.mp4", WIDTH, HEIGHT, stamps, *readings))
    return detections


def flash_instants_ms(events: Observations, truth: np.ndarray) -> np.ndarray:
    """The global instant of each flash of :func:`synthetic_events` (ms, by flash number),
    as a camera that saw it places it (its rows 0.05 ms noisy)."""
    instants = np.full(events.flash.max() + 1, np.nan)
    for c, (alpha, beta, row_time) in enumerate(truth):
        mine = events.camera == c
        instants[events.flash[mine]] = alpha * events.t_frame_ms[mine] + beta + events.q[mine] * row_time
    return instants


def seen_by(
    name: str,
    instants_ms: np.ndarray,
    clock: np.ndarray,
    frame_times: np.ndarray,
    exposure_ms: np.ndarray | float = EXPOSURE_MS,
    readout_share: float = 1.0,
    split: bool = False,
    strength: np.ndarray | float = 0.5,
) -> CameraDetection:
    """What the detector gives ``sync`` of a synthetic camera (its ``clock``: alpha, beta_ms
    and row_time_ms, one row of :func:`synthetic_events`'s truth; its ``frame_times``, ms)
    that reads its rows at ``readout_share`` times that time per row and sees flashes at the
    global ``instants_ms``, in time order each through its ``exposure_ms`` (one for all, or
    one per instant in time order): a band whole where both its edges lie in the rows read,
    its leading edge alone where the trailing one does not, and its trailing edge alone in
    the next frame where the flash fell in the vertical blanking less than one exposure before
    that frame and it lies in the rows read; with ``split``, a band whose trailing edge lies
    past the rows read goes on in the next frame where it lies in them (a readout with no
    blanking: ``readout_share`` near 1). Each band's ``strength`` (relative brightness; one for
    all, or one per instant in time order). Events numbered in time order, no noise, top-down
    (the reading known)."""
    alpha, beta, row_time = clock
    start, row_time = alpha * frame_times + beta, row_time * readout_share
    stamps = np.round(frame_times - frame_times[0])
    exposures = np.broadcast_to(exposure_ms, len(instants_ms))
    strengths = np.broadcast_to(strength, len(instants_ms))
    rows = []
    for number, (instant, exposure, brightness) in enumerate(zip(np.sort(instants_ms), exposures, strengths)):
        frame = int(np.searchsorted(start, instant, side="right")) - 1
        if frame < 0 or frame + 1 >= len(start):
            continue  # before the first frame, or after the last frame's start: not in sight
        lead = (instant - start[frame]) / row_time
        trail = lead + exposure / row_time
        next_trail = (instant + exposure - start[frame + 1]) / row_time
        if lead < HEIGHT - 1 and trail < HEIGHT - 1:
            edges = [(frame, Edge.LEADING, lead, frozenset()), (frame, Edge.TRAILING, trail, frozenset())]
        elif lead < HEIGHT - 1 and split and 0 <= next_trail < HEIGHT - 1:
            cut = frozenset({Flag.SPLIT})
            edges = [(frame, Edge.LEADING, lead, cut), (frame + 1, Edge.TRAILING, next_trail, cut)]
        elif lead < HEIGHT - 1:
            edges = [(frame, Edge.LEADING, lead, frozenset())]
        else:
            edges = (
                [(frame + 1, Edge.TRAILING, next_trail, frozenset({Flag.LEADING_HIDDEN}))]
                if 0 <= next_trail < HEIGHT - 1
                else []
            )
        for at, edge, row, flags in edges:
            rows.append((name, number, at, stamps[at], row, edge, Band.PULSE, 2.0, brightness, 50.0, flags))
    return CameraDetection(name, f"{name}.mp4", WIDTH, HEIGHT, stamps, Events.from_columns(*zip(*rows)))
