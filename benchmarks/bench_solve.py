"""Time of :func:`~flashsync.synchronize` as ``flashsync sync`` runs it, for many cameras
and flashes (synthetic events), and of the joint robust solve alone.

Run: python benchmarks/bench_solve.py [--cameras 64] [--flashes 500] [--readout-known] [--upside-down N]

The rig is :mod:`flashsync.simulation.band_events`' (frame rates 25/30/50 fps, drift within
±50 ppm, shift within ±60 s, each flash seen by each camera with probability 0.8, 0.05 ms of
edge noise); with ``--upside-down N`` its last N cameras are mounted upside down (their
top-down reading, the one detected, is wrong). ``synchronize`` gets what ``flashsync sync``
gives it: per camera the frame stamps and both readings of its events (top-down and
bottom-up, the readout direction to be found; with ``--readout-known`` only the right one,
as for ``sync --flipped``), no time
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

from flashsync.pipeline import synchronize
from flashsync.simulation.band_events import synthetic_detections, synthetic_events
from flashsync.solve import Priors, solve_clocks


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cameras", type=int, default=64)
    parser.add_argument("--flashes", type=int, default=500)
    parser.add_argument("--readout-known", action="store_true", help="give every camera's readout direction")
    parser.add_argument("--upside-down", type=int, default=0, help="mount the last N cameras upside down")
    args = parser.parse_args()
    events, truth, frame_times = synthetic_events(args.cameras, args.flashes)
    upside_down = range(args.cameras - args.upside_down, args.cameras)
    detections = synthetic_detections(events, truth, frame_times, upside_down=upside_down)
    if args.readout_known:
        detections = [
            replace(d, top_down=None, flipped=True) if c in upside_down else replace(d, bottom_up=None)
            for c, d in enumerate(detections)
        ]
    start, cpu = time.perf_counter(), time.process_time()
    model, report = synchronize(detections)
    elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
    solved = np.array([[model.cameras[f"cam{c}"].alpha, model.cameras[f"cam{c}"].beta_ms] for c in range(args.cameras)])
    # stamps start at 0: each camera's beta moves by alpha times its first frame's time
    first = np.array([times[0] for times in frame_times])
    wrong = sum(model.cameras[f"cam{c}"].flipped != (c in upside_down) for c in range(args.cameras))
    beta_error = solved[:, 1] - (truth[:, 1] + truth[:, 0] * first - first[0])
    print(
        f"synchronize: {args.cameras} cameras x {args.flashes} flashes, {len(report.alignments)} pairs aligned, "
        f"{len(report.flipped_found)} found upside down ({len(upside_down)} are; {wrong} read the wrong way), "
        f"in {elapsed:.2f} s ({cpu:.2f} s CPU, load average "
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
