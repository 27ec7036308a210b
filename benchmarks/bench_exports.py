"""Accuracy of ``frames`` and ``resample`` against simulation ground truth.

Run: python benchmarks/bench_exports.py [FOLDER] [--rate HZ] [--model sync.json]

FOLDER holds a rendered scenario (videos, ``truth.json``, ``detections.csv``,
``homographies.json``; default the shipped ``samples/``, or ``flashsync simulate paper -o
FOLDER``). The videos are synchronised (or ``--model`` is read), then at ``--rate`` ticks
over the recordings:

- ``frames``: per camera, the ticks inside its recording, the share located (the rest fall
  in the vertical blanking or a dropped frame), and the error of the located rows by the
  true clocks (true end of exposure minus the tick; RMS and max, ms and rows), beside the
  model's own sync error over every frame and row;
- ``resample``: per camera, the ticks interpolated and the distance to the true puck
  position at each tick (median, 95th percentile and max, px).

Nothing here is fitted to the truth it is scored against.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from flashsync import detect_videos, load_model, synchronize
from flashsync.demo import VIDEO_SUFFIXES, default_samples
from flashsync.evaluate import clock_origin_ms, sync_errors, tick_errors_ms
from flashsync.io import load_detections, load_ground_truth, load_homographies
from flashsync.simulation.truth import puck_image_px
from flashsync.ticks import frame_table, model_ticks_ms
from tracking_adapter.resample import resample


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, nargs="?", default=default_samples())
    parser.add_argument("--rate", type=float, default=100.0, help="ticks per second (default 100)")
    parser.add_argument("--model", type=Path, help="model file (default: synchronise the videos)")
    args = parser.parse_args()
    truth = load_ground_truth(args.folder / "truth.json")
    if args.model:
        model = load_model(args.model)
    else:
        videos = sorted(p for p in args.folder.glob("*") if p.suffix.lower() in VIDEO_SUFFIXES)
        model, _ = synchronize(detect_videos(videos, estimate_readout=True))
    ticks = model_ticks_ms(model, args.rate)
    table = frame_table(model, ticks)
    errors = tick_errors_ms(table, model, truth)
    sync = sync_errors(model, truth).set_index("camera")
    print(f"frames at {args.rate:g} Hz on {args.folder.name}: true end of exposure of the row given minus the tick")
    print(
        f"{'camera':<8}{'inside':>8}{'located':>9}{'RMS ms':>9}{'max ms':>9}{'RMS rows':>10}"
        f"{'max rows':>10}{'sync RMS ms':>13}"
    )
    located = table.loc[table["reason"] == "", "camera"].to_numpy()
    for name, clock in model.cameras.items():
        mine = table[table["camera"] == name]
        inside = ~mine["reason"].isin(["before the recording", "after the recording"])
        error = errors[located == name]
        rms, worst = float(np.sqrt(np.mean(error**2))), float(np.abs(error).max())
        print(
            f"{name:<8}{int(inside.sum()):>8}{(mine['reason'] == '').sum() / inside.sum():>9.1%}"
            f"{rms:>9.4f}{worst:>9.4f}{rms / clock.row_time_ms:>10.3f}"
            f"{worst / clock.row_time_ms:>10.3f}{sync.loc[name, 'rms_ms']:>13.4f}"
        )
    every = float(np.sqrt(np.mean(errors**2)))
    print(f"{'all':<8}{'':>8}{'':>9}{every:>9.4f}")

    tracks = resample(load_detections(args.folder / "detections.csv"), model, ticks).tracks
    homographies = load_homographies(args.folder / "homographies.json")
    print(f"\nresample at {args.rate:g} Hz: interpolated puck position minus the true one, px")
    print(f"{'camera':<8}{'ticks':>8}{'median':>9}{'p95':>9}{'max':>9}")
    interpolated = tracks[tracks["reason"] == ""]
    instants = interpolated["t_global_ms"].to_numpy() - clock_origin_ms(model, truth)
    for name in model.cameras:
        mine = (interpolated["camera"] == name).to_numpy()
        true = puck_image_px(truth, homographies[name], instants[mine])
        distance = np.hypot(*(interpolated.loc[mine, ["x", "y"]].to_numpy() - true).T)
        print(
            f"{name:<8}{mine.sum():>8}{np.median(distance):>9.3f}{np.percentile(distance, 95):>9.3f}"
            f"{distance.max():>9.3f}"
        )


if __name__ == "__main__":
    main()
