"""False events in a long clip without flashes: the detector must find none.

Run: python benchmarks/bench_false_events.py [--minutes 10] [--dir DIR]

Renders one camera (320x180, 25 fps, H.264) watching the rink for ``--minutes`` with
everything that is not a flash: skating players, the puck, 100 Hz mains flicker (3 %),
auto-exposure steps every two minutes, sensor noise and compression. Prints the number of
detected events (the target is 0) and the detection throughput.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from flashsync.detect import detect_video
from flashsync.io import events_to_frame
from flashsync.simulation import CameraSpec, Scenario, render_scenario


def flash_free_scenario(minutes: float) -> Scenario:
    duration_ms = minutes * 60_000.0
    steps = tuple((t, 1.15 if i % 2 == 0 else 1 / 1.15) for i, t in enumerate(range(60_000, int(duration_ms), 120_000)))
    camera = CameraSpec("quiet", 320, 180, 25.0, r0=8, r1=6, exposure_ms=10.0, noise_std=1.5, crf=26, gain_steps=steps)
    return Scenario(
        "flash-free", (camera,), duration_ms=duration_ms, flicker_depth=0.03, flicker_hz=100.0, n_players=12, seed=21
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--dir", type=Path, help="where to write the clip (default: a temp dir)")
    args = parser.parse_args()
    folder = args.dir or Path(tempfile.mkdtemp(prefix="flashsync-quiet-"))
    video = folder / "quiet.mp4"
    if not video.exists():
        render_scenario(flash_free_scenario(args.minutes), folder)
    start = time.perf_counter()
    detection = detect_video(video)
    elapsed = time.perf_counter() - start
    events = detection.events
    print(
        f"{args.minutes:g} min, {len(detection.frame_times_ms)} frames: {len(set(events.event.tolist()))} "
        f"false events ({len(events)} edges), detection {len(detection.frame_times_ms) / elapsed:.0f} fps"
    )
    if len(events):
        print(events_to_frame(events).to_string())


if __name__ == "__main__":
    main()
