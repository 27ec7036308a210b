"""False events in long clips without flashes: the detector must find none.

Run: python benchmarks/bench_false_events.py [--minutes 10] [--cases rink,crowd-16ms,...] [--keep DIR]
     python benchmarks/bench_false_events.py --minutes 10 --keep DIR --render-only

Renders one camera per case watching the rink for ``--minutes`` with everything that is not
a flash, and counts the detected events (the target is 0 in every case):

- ``rink``: 320x180, 25 fps, 10 ms, the whole rink with twelve players, 3 % mains flicker,
  auto-exposure steps every two minutes;
- ``rink-0.5ms-3%``: 320x240, 30 fps, 0.5 ms, the same rink under 3 % 100 Hz flicker, which
  rolls a third of a period a frame (the detector used to find 1,799 events in 30 s);
- ``crowd-*``: 320x240 zoomed onto the ice, 24 players (dark and white shirts, 8-16 px in
  radius), at 25 or 30 fps, exposures 0.5-16 ms, mains flicker 0-10 % (100 Hz, rolling at
  30 fps, or 120 Hz, rolling at 25 fps), auto-exposure steps, and one at 29.97 fps under 5 %
  120 Hz flicker, which rolls slowly (0.004 of a period a frame: American footage under
  American mains);
- ``rink-0.7ms-7%-59.94fps``: after rig-307's cam7 of ``bench_rigs.py``, no flashes: the
  whole rink at 640x360, 59.94 fps, 0.73 ms under 7 % 120 Hz flicker rolling 0.002 of a
  period a frame, crf 30, stamps on a 1 ms grid (the detector found 35 false events in
  rig-307's 8 s, 131 in 20 s of this case).

All H.264 (crf 23-30, a key frame every 250 frames), sensor noise. Prints per case the
frames, the false events and the detection throughput; the events themselves if any. With
``--keep DIR`` the clips are rendered into ``DIR/<case>`` and a clip kept there of exactly
the same scenario is reused (ten minutes of the first seven cases took ~45 min to render, seconds
to detect); ``--render-only`` renders them, one at a time, and detects nothing.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_rigs import rendered  # noqa: E402

from flashsync.detect import detect_video  # noqa: E402
from flashsync.io import events_to_frame  # noqa: E402
from flashsync.simulation import CameraSpec, Scenario  # noqa: E402

#: name: (fps, exposure ms, flicker depth, flicker Hz)
CROWD_CASES = {
    "crowd-16ms": (25.0, 16.0, 0.0, 100.0),
    "crowd-8ms-5%": (25.0, 8.0, 0.05, 100.0),
    "crowd-0.5ms-10%": (30.0, 0.5, 0.10, 100.0),
    "crowd-2ms-10%-120Hz": (25.0, 2.0, 0.10, 120.0),
    "crowd-16ms-10%": (30.0, 16.0, 0.10, 100.0),
    "crowd-4ms-5%-29.97fps": (30000 / 1001, 4.0, 0.05, 120.0),
}
CASES = ("rink", "rink-0.5ms-3%", "rink-0.7ms-7%-59.94fps", *CROWD_CASES)


def exposure_steps(duration_ms: float) -> tuple:
    """Auto-exposure steps up and down every two minutes."""
    return tuple((t, 1.15 if i % 2 == 0 else 1 / 1.15) for i, t in enumerate(range(60_000, int(duration_ms), 120_000)))


def flash_free_scenario(case: str, minutes: float) -> Scenario:
    duration_ms = minutes * 60_000.0
    if case == "rink":
        camera = CameraSpec(
            "quiet",
            320,
            180,
            25.0,
            r0=8,
            r1=6,
            exposure_ms=10.0,
            noise_std=1.5,
            crf=26,
            gain_steps=exposure_steps(duration_ms),
        )
        return Scenario(
            "flash-free",
            (camera,),
            duration_ms=duration_ms,
            flicker_depth=0.03,
            flicker_hz=100.0,
            n_players=12,
            seed=21,
        )
    if case == "rink-0.5ms-3%":
        camera = CameraSpec(
            "quiet",
            320,
            240,
            30.0,
            r0=8,
            r1=12,
            exposure_ms=0.5,
            noise_std=1.5,
            crf=23,
            gain_steps=exposure_steps(duration_ms),
        )
        return Scenario(
            case, (camera,), duration_ms=duration_ms, flicker_depth=0.03, flicker_hz=100.0, n_players=10, seed=3
        )
    if case == "rink-0.7ms-7%-59.94fps":
        camera = CameraSpec(
            "quiet",
            640,
            360,
            60000 / 1001,
            r0=20,
            r1=6,
            exposure_ms=0.729,
            noise_std=2.27,
            crf=30,
            quantize_ms=1.0,
            white_level=279.0,
            vignetting=0.3,
            position_m=(-3.25, 12.89, 11.46),
            look_at_m=(17.38, 8.37),
            hfov_deg=54.2,
        )
        return Scenario(
            case, (camera,), duration_ms=duration_ms, flicker_depth=0.0725, flicker_hz=120.0, n_players=10, seed=307
        )
    fps, exposure_ms, depth, hz = CROWD_CASES[case]
    camera = CameraSpec(
        "quiet",
        320,
        240,
        fps,
        r0=8,
        r1=12,
        exposure_ms=exposure_ms,
        noise_std=1.5,
        crf=23,
        gain_steps=exposure_steps(duration_ms),
        hfov_deg=26.0,
        position_m=(30.0, -6.0, 10.0),
        look_at_m=(30.0, 15.0),
    )
    return Scenario(case, (camera,), duration_ms=duration_ms, flicker_depth=depth, flicker_hz=hz, n_players=24, seed=21)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    names = ", ".join(CASES).replace("%", "%%")  # argparse formats help with %
    parser.add_argument("--cases", default=",".join(CASES), help=f"comma-separated, of {names}")
    parser.add_argument("--keep", type=Path, help="render into (and reuse from) this folder (default: a temp dir)")
    parser.add_argument("--render-only", action="store_true", help="render the clips, detect nothing")
    args = parser.parse_args()
    root = args.keep or Path(tempfile.mkdtemp(prefix="flashsync-quiet-"))
    if not args.render_only:
        print(f"{'case':<26} {'frames':>7} {'false events':>12} {'detect fps':>10}")
    for case in args.cases.split(","):
        folder = root / case
        rendered(flash_free_scenario(case, args.minutes), folder)
        if args.render_only:
            print(f"{case}: rendered in {folder}", flush=True)
            continue
        video = folder / "quiet.mp4"
        start = time.perf_counter()
        detection = detect_video(video)
        elapsed = time.perf_counter() - start
        events = detection.events
        frames = len(detection.frame_times_ms)
        print(
            f"{case:<26} {frames:>7} {len(set(events.event.tolist())):>12} {frames / elapsed:>10.0f}",
            flush=True,
        )
        if len(events):
            print(events_to_frame(events).to_string())


if __name__ == "__main__":
    main()
