"""Time of :func:`~flashsync.synchronize` as ``flashsync sync`` runs it, for many cameras
and flashes (synthetic events), and of the joint robust solve alone.

Run: python benchmarks/bench_solve.py [--cameras 64] [--flashes 500] [--readout-known]

Every camera (random frame rate 25/30/50 fps, drift within ±50 ppm, shift within ±60 s,
time per row for ~1000 rows) sees each flash with probability 0.8; event rows carry 0.05 ms
of noise. ``synchronize`` gets what ``flashsync sync`` gives it: per camera the frame
stamps and both readings of its events (top-down and bottom-up, the readout direction to be
found; with ``--readout-known`` only the top-down one, as for ``sync --flipped``), no time
per row (the nominal prior) and no anchor; its cameras are 1080 rows high.
The solve alone (:func:`~flashsync.solve.solve_clocks`) gets the true matches and row-time
priors centred on the truth. Prints both times (for ``synchronize`` also its CPU time and the
load average: the box is shared) and the largest parameter errors against the truth.
Target: ``synchronize`` of 64 cameras x 500 flashes within 10 s.
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

import numpy as np

from flashsync.detect import CameraDetection
from flashsync.events import Band, Edge, Events, Flag
from flashsync.pipeline import synchronize
from flashsync.solve import Observations, Priors, solve_clocks

HEIGHT, WIDTH = 1080, 1920
#: Exposure of every camera, ms (a band's trailing edge is one exposure after its leading edge).
EXPOSURE_MS = 2.0


def synthetic_events(n_cameras: int, n_flashes: int, seed: int = 0):
    """Observations of ``n_flashes`` flashes in 10 minutes seen by ``n_cameras`` cameras, the
    true (alpha, beta_ms, row_time_ms) per camera (camera 0 is the reference) and each
    camera's frame times on its own clock, ms."""
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
        visible = rows <= 1079
        camera += [c] * int(visible.sum())
        flash += list(seen[visible])
        t_frame += list(frames[frame[visible]])
        q += list(rows[visible] + rng.normal(0, 0.05 / row_time, visible.sum()))
    events = Observations(np.array(camera), np.array(flash), np.array(t_frame), np.array(q))
    return events, np.array(truth), frame_times


def synthetic_detections(
    events: Observations, truth: np.ndarray, frame_times: list[np.ndarray], seed: int = 0
) -> list[CameraDetection]:
    """The events of :func:`synthetic_events` as ``detect_videos`` gives them to ``sync``:
    per camera its frame stamps (rounded to 1 ms, from 0) and both readings of its bands,
    the top-down one in use. A band's trailing edge is one exposure after its leading edge (hidden where
    that falls past the last row); read bottom-up, the band's edges swap."""
    rng = np.random.default_rng(seed + 1)
    detections = []
    for c, (alpha, beta, row_time) in enumerate(truth):
        mine = np.flatnonzero(events.camera == c)
        order = np.argsort(events.t_frame_ms[mine])
        t_frame, lead = events.t_frame_ms[mine][order], events.q[mine][order]
        frame = np.searchsorted(frame_times[c], t_frame)
        stamps = np.round(frame_times[c] - frame_times[c][0])
        trail = lead + EXPOSURE_MS / row_time + rng.normal(0, 0.05 / row_time, len(lead))
        readings = []
        for flipped in (False, True):
            columns = [[] for _ in range(11)]
            for number, (f, a, b) in enumerate(zip(frame, lead, trail)):
                edges = [(Edge.LEADING, a), (Edge.TRAILING, b)] if b < HEIGHT - 0.5 else [(Edge.LEADING, a)]
                flags = frozenset() if len(edges) == 2 else frozenset({Flag.TRAILING_HIDDEN})
                if flipped:  # the band's bottom is its leading edge read bottom-up
                    edges = [(Edge.LEADING, b), (Edge.TRAILING, a)] if len(edges) == 2 else []
                for edge, row in edges:
                    values = (f"cam{c}", number, f, stamps[f], row, edge, Band.PULSE, 2.0, 0.5, 50.0, flags)
                    for column, value in zip(columns, values):
                        column.append(value)
            readings.append(Events.from_columns(*columns))
        detections.append(CameraDetection(f"cam{c}", f"cam{c}.mp4", WIDTH, HEIGHT, stamps, *readings))
    return detections


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cameras", type=int, default=64)
    parser.add_argument("--flashes", type=int, default=500)
    parser.add_argument("--readout-known", action="store_true", help="give every camera's readout direction")
    args = parser.parse_args()
    events, truth, frame_times = synthetic_events(args.cameras, args.flashes)
    detections = synthetic_detections(events, truth, frame_times)
    if args.readout_known:
        detections = [replace(detection, bottom_up=None) for detection in detections]
    start, cpu = time.perf_counter(), time.process_time()
    model, report = synchronize(detections)
    elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
    solved = np.array([[model.cameras[f"cam{c}"].alpha, model.cameras[f"cam{c}"].beta_ms] for c in range(args.cameras)])
    # stamps start at 0: each camera's beta moves by alpha times its first frame's time
    first = np.array([times[0] for times in frame_times])
    beta_error = solved[:, 1] - (truth[:, 1] + truth[:, 0] * first - first[0])
    print(
        f"synchronize: {args.cameras} cameras x {args.flashes} flashes, {len(report.alignments)} pairs aligned, "
        f"{len(report.flipped_found)} found upside down, in {elapsed:.2f} s ({cpu:.2f} s CPU, load average "
        f"{os.getloadavg()[0]:.1f})"
    )
    print(
        f"  largest errors: drift {np.max(np.abs(solved[:, 0] - truth[:, 0])) * 1e6:.3f} ppm, "
        f"shift {np.max(np.abs(beta_error)):.3f} ms (relative to the reference)"
    )
    priors = Priors({c: (truth[c, 2], 0.08 * truth[c, 2]) for c in range(args.cameras)})
    start = time.perf_counter()
    solution = solve_clocks(events, args.cameras, priors=priors)
    elapsed = time.perf_counter() - start
    solved = np.array([[s.alpha, s.beta_ms, s.row_time_ms] for s in solution.cameras])
    print(f"solve_clocks alone: {len(events.camera)} events, true matches, solved in {elapsed:.3f} s")
    print(
        f"  largest errors: drift {np.max(np.abs(solved[:, 0] - truth[:, 0])) * 1e6:.4f} ppm, "
        f"shift {np.max(np.abs(solved[:, 1] - truth[:, 1])):.4f} ms, "
        f"time per row {np.max(np.abs(solved[:, 2] / truth[:, 2] - 1)) * 100:.4f} %"
    )


if __name__ == "__main__":
    main()
