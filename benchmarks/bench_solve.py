"""Time of the joint robust solve for many cameras and flashes (synthetic events).

Run: python benchmarks/bench_solve.py [--cameras 64] [--flashes 500]

Every camera (random frame rate 25/30/50 fps, drift within ±50 ppm, shift within ±60 s,
time per row for ~1000 rows) sees each flash with probability 0.8; event rows carry 0.05 ms
of noise. Prints the solve time and the largest parameter errors against the truth.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from flashsync.solve import Observations, Priors, solve_clocks


def synthetic_events(n_cameras: int, n_flashes: int, seed: int = 0):
    """Observations of ``n_flashes`` flashes in 10 minutes seen by ``n_cameras`` cameras, and the
    true (alpha, beta_ms, row_time_ms) per camera (camera 0 is the reference)."""
    rng = np.random.default_rng(seed)
    tau = np.sort(rng.uniform(0, 600_000.0, n_flashes))
    truth, camera, flash, t_frame, q = [], [], [], [], []
    for c in range(n_cameras):
        fps = rng.choice([25.0, 30.0, 50.0])
        alpha = 1.0 if c == 0 else 1 + rng.uniform(-50e-6, 50e-6)
        beta = 0.0 if c == 0 else rng.uniform(-60_000.0, 60_000.0)
        row_time = 1000.0 / fps / rng.uniform(1080, 1125)
        truth.append((alpha, beta, row_time))
        frames = (np.arange(-2000.0, 700_000.0, 1000.0 / fps) - beta) / alpha
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
    return events, np.array(truth)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cameras", type=int, default=64)
    parser.add_argument("--flashes", type=int, default=500)
    args = parser.parse_args()
    events, truth = synthetic_events(args.cameras, args.flashes)
    priors = Priors({c: (truth[c, 2], 0.08 * truth[c, 2]) for c in range(args.cameras)})
    start = time.perf_counter()
    solution = solve_clocks(events, args.cameras, priors=priors)
    elapsed = time.perf_counter() - start
    solved = np.array([[s.alpha, s.beta_ms, s.row_time_ms] for s in solution.cameras])
    print(f"{args.cameras} cameras x {args.flashes} flashes: {len(events.camera)} events, solved in {elapsed:.3f} s")
    print(
        f"largest errors: drift {np.max(np.abs(solved[:, 0] - truth[:, 0])) * 1e6:.4f} ppm, "
        f"shift {np.max(np.abs(solved[:, 1] - truth[:, 1])):.4f} ms, "
        f"time per row {np.max(np.abs(solved[:, 2] / truth[:, 2] - 1)) * 100:.4f} %"
    )


if __name__ == "__main__":
    main()
