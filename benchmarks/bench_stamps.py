"""Stamp faults against truth: jitter, a rate change, a pause, a wrong datasheet.

Run: python benchmarks/bench_stamps.py [--duration-s 30] [--folder DIR] [--cases all|NAME,...]

Renders three independent cameras once (640x360 at 25, 30 and 50 fps, 12 flashes, exact
90 kHz stamps; kept in --folder for the next run), detects their events once, then for each
case replaces the second camera's frame stamps with faulted ones made from its true frame
times and runs `synchronize` as `flashsync sync` does. Cases:

==============  =========================================================================
``exact``       the true stamps
``jitter-1.2``  Gaussian jitter, std 1.2 ms (also 2 and 5 ms: ``jitter-2``, ``jitter-5``)
``rate-1.5``    from the middle frame on the stamps advance 1.5x as fast (the sensor keeps
                its rate; a muxer fault)
``pause``       the recording pauses for 300 frames in the middle (those frames are not in
                the video; the sensor's clock runs on)
``row-time``    exact stamps and a wrong datasheet time per row for that camera (+40 %)
==============  =========================================================================

Per case and camera: the sync error against truth over all frames and every 8th row (RMS and
max, ms), the predicted sync uncertainty ("sync ± ms" of the table: the largest sigma of
``t_global_std_ms``) and the ratio RMS error / sigma; and the warnings. The same script runs
on an older flashsync (it uses the public API only) for a before/after comparison.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from flashsync import detect_videos, synchronize
from flashsync.evaluate import sync_errors
from flashsync.io import load_ground_truth
from flashsync.report import sync_uncertainty_ms
from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario

CASES = ("exact", "jitter-1.2", "jitter-2", "jitter-5", "rate-1.5", "pause", "row-time")


def scenario(duration_ms: float) -> Scenario:
    """Three independent cameras, 12 flashes spread over the recording."""
    cameras = (
        CameraSpec("cam1", 640, 360, 25.0, r0=12, r1=8, exposure_ms=4.0, noise_std=1.5),
        CameraSpec(
            "cam2",
            640,
            360,
            30.0,
            r0=9,
            r1=14,
            exposure_ms=5.0,
            start_ms=41_000.0,
            offset_ms=-41_000.0 + 230.0,
            drift_ppm=12.0,
            noise_std=1.5,
            position_m=(-7.0, 15.0, 14.0),
            look_at_m=(18.0, 15.0),
        ),
        CameraSpec(
            "cam3",
            640,
            360,
            50.0,
            r0=6,
            r1=10,
            exposure_ms=3.0,
            start_ms=7_000.0,
            offset_ms=-7_000.0 - 410.0,
            drift_ppm=-31.0,
            noise_std=1.5,
            position_m=(66.0, 33.0, 16.0),
            look_at_m=(44.0, 16.0),
        ),
    )
    instants = np.linspace(0.08, 0.92, 12) * duration_ms + np.random.default_rng(5).uniform(-300, 300, 12)
    flashes = tuple(FlashSpec(round(float(t), 1), 0.5) for t in instants)
    return Scenario("stamps", cameras, duration_ms=duration_ms, flashes=flashes, n_players=6, seed=11)


def faulted(case: str, true_ms: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The stamps of a case and the frames kept (indices into the true frames)."""
    frames = np.arange(len(true_ms))
    if case.startswith("jitter"):
        stamps = true_ms + float(case.split("-")[1]) * rng.standard_normal(len(true_ms))
        return np.maximum.accumulate(stamps + 1e-6 * frames), frames
    if case == "rate-1.5":
        middle = len(true_ms) // 2
        stamps = true_ms.copy()
        stamps[middle:] = true_ms[middle] + 1.5 * (true_ms[middle:] - true_ms[middle])
        return stamps, frames
    if case == "pause":
        middle = len(true_ms) // 2
        kept = np.concatenate([frames[: middle - 150], frames[middle + 150 :]])
        return true_ms[kept], kept
    return true_ms, frames


def run_case(case: str, detections: list, truth) -> list[dict]:
    """Synchronise with the case's stamps on the second camera; per camera, its errors and sigma."""
    rng = np.random.default_rng(7)
    target = 1
    detection = detections[target]
    true_ms = np.asarray(truth.cameras[detection.camera].frame_times_ms)
    stamps, kept = faulted(case, true_ms, rng)
    row_times = {}
    if case == "row-time":
        row_times = {detection.camera: 1.4 * truth.cameras[detection.camera].row_time_ms}
    trial = list(detections)
    if len(kept) != len(true_ms):
        trial[target] = _keep_frames(detection, kept).retimed(stamps)
        truth = _truth_keeping(truth, detection.camera, kept)
    else:
        trial[target] = detection.retimed(stamps)
    model, report = synchronize(trial, row_times=row_times)
    errors = sync_errors(model, truth).set_index("camera")
    rows = []
    for name, camera in model.cameras.items():
        sigma = sync_uncertainty_ms(camera)
        rms = float(errors.loc[name, "rms_ms"])
        rows.append(
            dict(
                case=case,
                camera=name,
                rms_ms=rms,
                max_ms=float(errors.loc[name, "max_ms"]),
                sigma_ms=sigma,
                ratio=rms / sigma if sigma > 0 else np.inf,
            )
        )
    for warning in report.warnings:
        print(f"    warning: {warning}")
    return rows


def _keep_frames(detection, kept):
    """The detection with only the ``kept`` frames (events renumbered onto them)."""
    index = np.full(len(detection.frame_times_ms), -1)
    index[kept] = np.arange(len(kept))

    def events(e):
        if e is None:
            return None
        mine = index[e.frame] >= 0
        e = e.take(np.flatnonzero(mine))
        return dataclasses.replace(e, frame=index[e.frame])

    return dataclasses.replace(
        detection,
        frame_times_ms=detection.frame_times_ms[kept],
        top_down=events(detection.top_down),
        bottom_up=events(detection.bottom_up),
    )


def _truth_keeping(truth, name, kept):
    camera = truth.cameras[name]
    changed = dataclasses.replace(
        camera,
        frame_times_ms=list(np.asarray(camera.frame_times_ms)[kept]),
        frame_index=list(np.asarray(camera.frame_index)[kept]),
    )
    return dataclasses.replace(truth, cameras={**truth.cameras, name: changed})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration-s", type=float, default=30.0)
    parser.add_argument("--folder", type=Path, default=Path("bench-stamps"))
    parser.add_argument("--cases", default="all")
    args = parser.parse_args()
    cases = CASES if args.cases == "all" else tuple(args.cases.split(","))
    if not (args.folder / "truth.json").is_file():
        start = time.perf_counter()
        render_scenario(scenario(1000.0 * args.duration_s), args.folder)
        print(f"rendered in {time.perf_counter() - start:.0f} s -> {args.folder}")
    truth = load_ground_truth(args.folder / "truth.json")
    detections = detect_videos([args.folder / f"{name}.mp4" for name in truth.cameras])
    print(f"{'case':<12} {'camera':<6} {'rms ms':>8} {'max ms':>8} {'sigma ms':>9} {'rms/sigma':>9}")
    for case in cases:
        print(case)
        try:
            rows = run_case(case, detections, truth)
        except Exception as error:  # a failure is a result
            print(f"    failed: {type(error).__name__}: {error}")
            continue
        for row in rows:
            print(
                f"{'':<12} {row['camera']:<6} {row['rms_ms']:>8.3f} {row['max_ms']:>8.3f} "
                f"{row['sigma_ms']:>9.3f} {row['ratio']:>9.2f}"
            )


if __name__ == "__main__":
    main()
