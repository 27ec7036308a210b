"""Montage throughput against the floor (decode the inputs + encode the output), and its
memory against the montage's length, on the shipped sample.

Run: python benchmarks/bench_montage.py [--rounds N] [--dir DIR]

The sample's four videos (8 s) are synchronised once. Then, in alternating rounds on this
machine: the floor's two parts -- decoding every frame of the four videos with PyAV
(threading AUTO, no pixel conversion) and encoding the montage's frames with the same
libx264 settings (its own output, decoded ahead so that only the encode is timed) -- and
``flashsync.write_montage`` over the whole span. Prints the best of each and the ratio of
the montage to the floor (1.0 = no cost beyond decoding and encoding). Last, the peak
resident memory of a fresh process writing a 2 s and an 8 s montage: constant memory means
the two are about equal.
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
from pathlib import Path

import av

from flashsync import detect_videos, save_model, synchronize, write_montage
from flashsync.demo import VIDEO_SUFFIXES, default_samples
from flashsync.io import load_model

# Peak resident memory from /proc (getrusage's maximum survives exec: it would be this
# script's own).
MEMORY_PROBE = """
import re, sys
from pathlib import Path
from flashsync import load_model, write_montage
model = load_model(sys.argv[1])
summary = write_montage(sys.argv[4:], model, sys.argv[2], 30.0, 0.0, float(sys.argv[3]))
peak_kb = int(re.search(r"VmHWM:\\s+(\\d+)", Path("/proc/self/status").read_text()).group(1))
print(summary.frames, peak_kb // 1024)
"""


def decode_inputs(videos: list[Path]) -> int:
    """Decode every frame of every video, touching nothing: the floor's first part."""
    count = 0
    for path in videos:
        with av.open(str(path)) as container:
            stream = container.streams.video[0]
            stream.thread_type = "AUTO"
            count += sum(1 for _ in container.decode(stream))
    return count


def encode_seconds(montage: Path, workdir: Path) -> float:
    """Seconds spent encoding the montage's frames again with write_montage's settings
    (each frame decoded and converted to BGR outside the timing)."""
    spent = 0.0
    with av.open(str(montage)) as source, av.open(str(workdir / "encode.mp4"), "w") as container:
        rate = Fraction(30)
        stream = container.add_stream("libx264", rate=rate)
        input_stream = source.streams.video[0]
        stream.width, stream.height = input_stream.width, input_stream.height
        stream.pix_fmt = "yuv420p"
        stream.codec_context.time_base = 1 / rate
        stream.options = {"crf": "20", "preset": "veryfast"}
        for k, decoded in enumerate(source.decode(input_stream)):
            image = decoded.to_ndarray(format="bgr24")
            start = time.perf_counter()
            frame = av.VideoFrame.from_ndarray(image, format="bgr24")
            frame.pts, frame.time_base = k, 1 / rate
            container.mux(stream.encode(frame))
            spent += time.perf_counter() - start
        start = time.perf_counter()
        container.mux(stream.encode())
        spent += time.perf_counter() - start
    return spent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--dir", type=Path, help="folder for the outputs (default: a temporary one)")
    args = parser.parse_args()
    samples = default_samples()
    videos = sorted(p for p in samples.glob("*") if p.suffix.lower() in VIDEO_SUFFIXES)
    with tempfile.TemporaryDirectory() as scratch:
        workdir = args.dir or Path(scratch)
        workdir.mkdir(parents=True, exist_ok=True)
        model, _ = synchronize(detect_videos(videos, estimate_readout=True))
        save_model(model, workdir / "sync.json")
        model = load_model(workdir / "sync.json")
        decode, encode, montage = [], [], []
        for _ in range(args.rounds):
            start = time.perf_counter()
            decoded = decode_inputs(videos)
            decode.append(time.perf_counter() - start)
            start = time.perf_counter()
            summary = write_montage(videos, model, workdir / "synced.mp4", 30.0)
            montage.append(time.perf_counter() - start)
            encode.append(encode_seconds(workdir / "synced.mp4", workdir))
        floor = min(decode) + min(encode)
        print(
            f"machine: {platform.machine()}, {os.cpu_count()} cores, PyAV {av.__version__}, "
            f"best of {args.rounds} rounds"
        )
        print(
            f"montage of {len(videos)} videos ({decoded} frames) -> {summary.frames} frames of "
            f"{summary.width}x{summary.height} at 30 Hz"
        )
        print(f"decode inputs:   {min(decode):6.2f} s")
        print(f"encode output:   {min(encode):6.2f} s")
        print(f"write_montage:   {min(montage):6.2f} s   ratio to the floor {min(montage) / floor:.2f}")
        for span_ms in (2000.0, 8000.0):
            result = subprocess.run(
                [
                    sys.executable,
                    "-c",
                    MEMORY_PROBE,
                    str(workdir / "sync.json"),
                    str(workdir / "memory.mp4"),
                    str(span_ms),
                    *map(str, videos),
                ],
                capture_output=True,
                text=True,
                check=True,
            )
            frames, megabytes = result.stdout.split()
            print(f"peak memory, {span_ms / 1000:.0f} s montage ({frames} frames): {megabytes} MB")


if __name__ == "__main__":
    main()
