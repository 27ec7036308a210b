"""Detection throughput against the floor: decode-only, on generated 720p, 1080p and 4K H.264.

Run: python benchmarks/bench_detect.py [--frames N] [--rounds N] [--sizes 720p,1080p,2160p] [--dir DIR]
     python benchmarks/bench_detect.py --videos VIDEO... [--both-ways] [--rounds N]

For each size it writes a clip (textured scene, moving blobs, a flash every ~40 frames,
libx264 crf 23), then times on this machine, in alternating rounds on the same file:
decoding every frame with PyAV (threading AUTO, the fastest setting here; no pixel
conversion: the floor) and ``flashsync.detect_video``, which is what ``flashsync detect``
runs for each video. Prints the best frames per second of each, their ratio (1.0 = as fast
as decoding) and the spread of the per-round ratios: a shared virtual machine's speed
drifts by tens of percent between seconds, so only rounds run side by side compare.
Last, the fixed start-up of the ``flashsync detect`` command (imports, compiled-kernel
cache), which a long video amortises. ``--videos`` times given videos instead of the
generated clips (e.g. a random rig of the simulator's second world), ``--both-ways``
reading each both ways up as ``flashsync sync`` does.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from fractions import Fraction
from functools import partial
from pathlib import Path

import av
import cv2
import numpy as np

from flashsync.detect import detect_video
from flashsync.simulation.encode import write_video

SIZES = {"720p": (1280, 720), "1080p": (1920, 1080), "2160p": (3840, 2160)}


def make_clip(path: Path, width: int, height: int, n_frames: int, fps: float = 25.0) -> None:
    """A textured scene with moving dark blobs; every ~40th frame holds a flash band."""
    rng = np.random.default_rng(0)
    texture = cv2.resize(
        rng.uniform(60, 200, (height // 8, width // 8)).astype(np.float32),
        (width, height),
        interpolation=cv2.INTER_CUBIC,
    )
    rows = np.arange(height, dtype=np.float32)[:, None]

    def frames():
        for i in range(n_frames):
            image = texture.copy()
            for k in range(6):
                x = int((i * (7 + k) * width / 400 + k * width / 6) % width)
                y = int(height * (0.2 + 0.1 * k))
                cv2.circle(image, (x, y), max(4, height // 60), 30.0, -1)
            if i % 40 == 20:
                start = (i * 37) % height
                image *= 1.0 + 0.5 * (rows >= start) * (rows < start + height // 3)
            image += rng.normal(0, 2.0, image.shape).astype(np.float32)
            yield np.clip(image, 0, 255).astype(np.uint8)

    step = Fraction(1, 90_000)
    write_video(path, frames(), [round(i * 90_000 / fps) for i in range(n_frames)], step, crf=23)


def decode_only(path: Path) -> int:
    """Decode every frame with PyAV's best threading and touch nothing: the floor."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        return sum(1 for _ in container.decode(stream))


def fps(function, path: Path) -> float:
    """Frames per second of one run of ``function(path)``."""
    start = time.perf_counter()
    result = function(path)
    n_frames = result if isinstance(result, int) else len(result.frame_times_ms)
    return n_frames / (time.perf_counter() - start)


def startup_seconds() -> float:
    """Wall time of ``flashsync detect --help``: interpreter, imports, nothing decoded."""
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "flashsync", "detect", "--help"], check=True, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--sizes", default="720p,1080p,2160p")
    parser.add_argument("--dir", type=Path, help="where to write the clips (default: a temp dir)")
    parser.add_argument("--videos", type=Path, nargs="+", help="time these videos instead of generated clips")
    parser.add_argument("--both-ways", action="store_true", help="read each video both ways up, as sync does")
    args = parser.parse_args()
    folder = args.dir or Path(tempfile.mkdtemp(prefix="flashsync-bench-"))
    folder.mkdir(parents=True, exist_ok=True)
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"PyAV {av.__version__}, {'given videos' if args.videos else f'{args.frames} frames per clip'}, "
        f"best of {args.rounds} rounds"
    )
    print(f"{'size':<7} {'decode fps':>11} {'detect fps':>11} {'ratio':>6}   per-round ratios")
    detect_it = partial(detect_video, flipped=None if args.both_ways else False)
    clips = {path.name: path for path in args.videos or []}
    for name in () if args.videos else args.sizes.split(","):
        width, height = SIZES[name]
        clips[name] = folder / f"bench_{name}_{args.frames}.mp4"
        if not clips[name].exists():
            make_clip(clips[name], width, height, args.frames)
    for name, path in clips.items():
        detect_it(path)  # warm-up: loads the compiled kernels, fills the file cache
        decode, detect = [], []
        for round_ in range(args.rounds):
            pair = [(decode, decode_only), (detect, detect_it)]
            for results, function in pair[:: 1 if round_ % 2 else -1]:
                results.append(fps(function, path))
        ratios = np.array(detect) / np.array(decode)
        print(
            f"{name:<7} {max(decode):>11.1f} {max(detect):>11.1f} {max(detect) / max(decode):>6.2f}"
            f"   median {np.median(ratios):.2f}, {ratios.min():.2f}-{ratios.max():.2f}"
        )
    print(f"start-up of `flashsync detect`: {startup_seconds():.1f} s once per command")


if __name__ == "__main__":
    main()
