"""Real light, measured against simulation truth: rolling flicker, crowds, a long recording.

Run: python benchmarks/bench_light.py [--rigs rolling-flicker,ripple-300hz,flash-free,long-pair] [--dir DIR]
[--minutes M]

Four rigs of the real-light issue, each rendered once into ``--dir`` and then synced with no
options (``flashsync.synchronize(detect_videos(...))``) in a fresh process whose peak memory
is measured:

- ``rolling-flicker``: two 640x360 cameras under 3 % 100 Hz mains flicker, one at 30 fps
  with a 0.5 ms exposure (the pattern rolls a third of a period a frame), one at 25 fps
  with 1 ms (it stands still), 12 flashes in 30 s. Target: sync error <= 0.1 ms RMS;
- ``ripple-300hz``: the same cameras and flashes under 3 % 300 Hz ripple (lamps on three-phase
  rectified supplies, as arenas are lit): a period of a third of mains', 32-39 rows here.
  Target: as ``rolling-flicker``;
- ``flash-free``: two 320x240 cameras (25 and 30 fps, 8 ms) over the ice seen from close
  by, 20 players 8-16 px in radius, 5 % flicker, no flash, 30 s. Target: 0 events;
- ``long-pair``: two 320x240 cameras (25 and 30 fps, 8 ms), ten players 8-16 px in radius,
  30 flashes in 15 minutes (``--minutes``), the second camera's drift changing by 0.01 ppm
  per second. Target: no traceback, sync error <= 0.05 ms RMS, memory that does not grow
  with the length (its detection's peak is printed next to that of its first minute; "in
  all" adds the solve and the evaluation of every frame and row against truth).

Prints per rig the events, the flicker found, the sync error over every frame and row of
every camera (``flashsync.evaluate.sync_errors``), the time and the peak resident memory.
"""

from __future__ import annotations

import argparse
import multiprocessing
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario

#: Pose of a camera close enough for players 0.4-0.55 m wide to be 8-16 px in radius at 320x240.
CLOSE = dict(hfov_deg=26.0, look_at_m=(30.0, 15.0))


def irregular_flashes(seed: int, count: int, duration_ms: float) -> tuple[FlashSpec, ...]:
    """``count`` flashes at irregular instants (as fired by hand) over the recording."""
    rng = np.random.default_rng(seed)
    step = 0.84 * duration_ms / count
    instants = 0.08 * duration_ms + np.arange(count) * step + rng.uniform(0.0, 0.6 * step, count)
    return tuple(FlashSpec(round(float(t), 3), round(float(rng.uniform(0.3, 0.7)), 3)) for t in instants)


def crowd_camera(name: str, fps: float, y_m: float, **changes) -> CameraSpec:
    """A 320x240 camera with an 8 ms exposure close to the crowd, on the rink's long side at
    ``y_m`` (m)."""
    return CameraSpec(
        name,
        320,
        240,
        fps,
        r0=8,
        r1=12,
        exposure_ms=8.0,
        noise_std=1.5,
        position_m=(30.0, y_m, 10.0),
        **CLOSE,
        **changes,
    )


#: The rigs, in the order they run.
RIGS = ("rolling-flicker", "ripple-300hz", "flash-free", "long-pair")


def rig(name: str, minutes: float) -> Scenario:
    if name in ("rolling-flicker", "ripple-300hz"):
        cameras = (
            CameraSpec("cam1", 640, 360, 30.0, r0=12, r1=20, exposure_ms=0.5, noise_std=1.5),
            CameraSpec(
                "cam2",
                640,
                360,
                25.0,
                r0=10,
                r1=14,
                exposure_ms=1.0,
                noise_std=1.5,
                start_ms=2000.0,
                offset_ms=-1876.5,
                drift_ppm=8.0,
                container="mkv",
                position_m=(-6.0, 15.0, 14.0),
                look_at_m=(18.0, 15.0),
            ),
        )
        return Scenario(
            name,
            cameras,
            duration_ms=30_000.0,
            flashes=irregular_flashes(1, 12, 30_000.0),
            flicker_depth=0.03,
            flicker_hz=100.0 if name == "rolling-flicker" else 300.0,
            n_players=10,
            seed=31,
        )
    if name == "flash-free":
        cameras = (crowd_camera("cam1", 25.0, -6.0), crowd_camera("cam2", 30.0, 36.0))
        return Scenario(
            name, cameras, duration_ms=30_000.0, flicker_depth=0.05, flicker_hz=100.0, n_players=20, seed=32
        )
    duration_ms = minutes * 60_000.0
    cameras = (
        crowd_camera("cam1", 25.0, -6.0),
        crowd_camera(
            "cam2",
            30.0,
            36.0,
            start_ms=3000.0,
            offset_ms=-2713.0,
            drift_ppm=12.0,
            drift_rate_ppm_per_s=0.01,
            container="mkv",
        ),
    )
    return Scenario(
        name,
        cameras,
        duration_ms=duration_ms,
        flashes=irregular_flashes(3, round(2 * minutes), duration_ms),
        n_players=10,
        seed=33,
    )


def measure(folder: Path, sync: bool) -> dict:
    """In a fresh process: detect (and sync) the videos in ``folder``, against its truth."""
    from flashsync.evaluate import sync_errors
    from flashsync.io import load_ground_truth
    from flashsync.pipeline import detect_videos, synchronize

    start = time.perf_counter()
    videos = sorted(p for p in folder.iterdir() if p.suffix in (".mp4", ".mkv"))
    detections = detect_videos(videos)
    result = {
        "events": {d.camera: len(set(d.events.event.tolist())) for d in detections},
        "flicker": {d.camera: d.flicker for d in detections},
        "frames": sum(len(d.frame_times_ms) for d in detections),
        "detect_peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }
    if sync:
        model, _ = synchronize(detections)
        errors = sync_errors(model, load_ground_truth(folder / "truth.json"))
        result["errors"] = errors
    result["seconds"] = time.perf_counter() - start
    result["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return result


def render(name: str, minutes: float, folder: Path) -> None:
    """Render a rig in a fresh process: a child's peak memory starts at its parent's size
    (Linux keeps it across exec), so the rendering must not grow this one."""
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        pool.apply(render_scenario, (rig(name, minutes), folder))


def run(folder: Path, sync: bool) -> dict:
    """:func:`measure` in a fresh process; errors come back here. Its peak memory starts at
    this process's size (:func:`render`)."""
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        return pool.apply(measure, (folder, sync))


def report(name: str, result: dict) -> None:
    events = ", ".join(f"{camera} {n}" for camera, n in result["events"].items())
    print(
        f"{name}: {result['frames']} frames, events {events}; {result['seconds']:.0f} s, "
        f"peak memory {result['detect_peak_mb']:.0f} MB detecting, {result['peak_mb']:.0f} MB in all"
    )
    for camera, flicker in result["flicker"].items():
        if flicker is not None:
            hz = f"{flicker.hz:.0f} Hz" if flicker.hz else "Hz not told"
            print(
                f"  {camera}: flicker {hz}, period {flicker.period_rows:.2f} ± {flicker.period_rows_sigma:.2f} rows, "
                f"depth {100 * flicker.depth:.1f} %"
            )
    if "errors" in result:
        errors = result["errors"]
        for row in errors.itertuples():
            print(f"  {row.camera:<6} RMS {row.rms_ms:.4f} ms   max {row.max_ms:.4f} ms")
        print(f"  all    RMS {np.sqrt(np.mean(errors['rms_ms'] ** 2)):.4f} ms")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rigs", default=",".join(RIGS))
    parser.add_argument("--minutes", type=float, default=15.0, help="length of long-pair")
    parser.add_argument("--dir", type=Path, help="where to render (default: a temp dir); reused if there")
    args = parser.parse_args()
    unknown = set(args.rigs.split(",")) - set(RIGS)
    if unknown:
        parser.error(f"--rigs: no rig {', '.join(sorted(unknown))}; the rigs are {', '.join(RIGS)}")
    root = args.dir or Path(tempfile.mkdtemp(prefix="flashsync-light-"))
    for name in args.rigs.split(","):
        folder = root / name
        if not (folder / "truth.json").exists():
            start = time.perf_counter()
            render(name, args.minutes, folder)
            print(f"{name}: rendered in {time.perf_counter() - start:.0f} s")
        report(name, run(folder, sync=name != "flash-free"))
        if name == "long-pair":
            first = root / "long-pair-first-minute"
            if not (first / "truth.json").exists():
                render(name, 1.0, first)
            report("long-pair, first minute (memory)", run(first, sync=False))


if __name__ == "__main__":
    main()
