"""Detection on a Dask cluster against the plain run: throughput with 1 and 2 workers here,
the cost of a segment, and what that projects for N machines.

Run: python benchmarks/bench_cluster.py [--seconds 120] [--size 1080p] [--segment 30] [--dir DIR]

Writes a clip (``bench_detect``'s scene: textured, moving blobs, a flash every 40 frames;
25 fps, x264 veryfast, a key frame every 250 frames), then times whole ``flashsync detect``
commands on it: plain (local threads), and with ``--scheduler tcp://127.0.0.1:PORT`` against
``dask scheduler`` + ``dask worker --nworkers W --nthreads 1`` processes started here for
W = 1 and 2 (their start-up is not timed: a cluster runs before a job comes), each run's
events compared with the plain run's byte for byte. Then, on 2 workers, segments of a
quarter the length give the per-segment overhead; and the detection state pushed through one
video in one process without decoding (the part that runs in order) gives the rate of the
per-video chain. Last, decode-only (PyAV, threads AUTO): the floor.

The projection for N machines like this one, a game of C cameras x F frames each::

    time ~ max(C F / (N r), F / chain) + C F / (segment frames) x overhead / (N W)

with r the frames per second of one machine (the 2-worker run), chain the chain's rate and W
workers per machine: decoding scales with machines, each video's chain runs in order (the
videos' chains in parallel).
"""

from __future__ import annotations

import argparse
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from fractions import Fraction
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_detect import SIZES, decode_only  # noqa: E402

from flashsync.detect import VideoDetection  # noqa: E402
from flashsync.profiles import read_profiles  # noqa: E402
from flashsync.simulation.encode import write_video  # noqa: E402

FPS = 25.0


def make_clip(path: Path, width: int, height: int, n_frames: int) -> None:
    """``bench_detect``'s scene, encoded fast (x264 veryfast) with default key frames."""
    import bench_detect

    step = Fraction(1, 1000)
    frames = _frames(bench_detect, width, height, n_frames)
    write_video(path, frames, [round(i * 1000 / FPS) for i in range(n_frames)], step, crf=23, preset="veryfast")


def _frames(bench_detect, width, height, n_frames):
    """bench_detect.make_clip's frames (its generator, through a capturing writer)."""
    captured = []

    def capture(path, frames, pts, time_base, crf):
        captured.append(frames)

    original = bench_detect.write_video
    bench_detect.write_video = capture
    try:
        bench_detect.make_clip(Path("unused"), width, height, n_frames, FPS)
    finally:
        bench_detect.write_video = original
    return captured[0]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class DaskProcesses:
    """``dask scheduler`` and ``dask worker --nworkers W`` on 127.0.0.1, stopped on exit."""

    def __init__(self, workers: int):
        self.workers = workers
        self.port = free_port()
        self.address = f"tcp://127.0.0.1:{self.port}"
        self.processes: list[subprocess.Popen] = []

    def __enter__(self) -> str:
        dask = shutil.which("dask", path=str(Path(sys.executable).parent)) or "dask"
        quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        self.processes.append(
            subprocess.Popen(
                [dask, "scheduler", "--host", "127.0.0.1", "--port", str(self.port), "--no-dashboard"], **quiet
            )
        )
        self.processes.append(
            subprocess.Popen(
                [dask, "worker", self.address, "--nworkers", str(self.workers), "--nthreads", "1", "--no-dashboard"],
                **quiet,
            )
        )
        from distributed import Client

        with Client(self.address, timeout=60) as client:
            client.wait_for_workers(self.workers, timeout=120)
        return self.address

    def __exit__(self, *exc) -> None:
        for process in reversed(self.processes):
            process.terminate()
            process.wait(timeout=60)


def timed_detect(video: Path, output: Path, *options: str) -> float:
    """Wall time of a whole ``flashsync detect`` command, s."""
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "flashsync", "detect", str(video), "-o", str(output), *options],
        check=True,
        stderr=subprocess.DEVNULL,
    )
    return time.perf_counter() - start


def chain_fps(video: Path) -> float:
    """Frames per second of the detection state alone (profiles decoded beforehand)."""
    info, profiles = read_profiles(video)
    frames = list(profiles)
    state = VideoDetection(info, False)
    start = time.perf_counter()
    for frame in frames:
        state.push(*frame)
    state.finish()
    return len(frames) / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="clip length, s (default 120)")
    parser.add_argument("--size", default="1080p", choices=list(SIZES))
    parser.add_argument("--segment", type=float, default=30.0, help="segment length, s (default 30)")
    parser.add_argument("--dir", type=Path, help="where to write the clip (default: a temp dir, kept)")
    args = parser.parse_args()
    folder = args.dir or Path(tempfile.mkdtemp(prefix="flashsync-bench-cluster-"))
    folder.mkdir(parents=True, exist_ok=True)
    n_frames = int(args.seconds * FPS)
    video = folder / f"cluster_{args.size}_{n_frames}.mkv"
    if not video.exists():
        make_clip(video, *SIZES[args.size], n_frames)
    print(f"{video.name}: {n_frames} frames {args.size}, segments of {args.segment:g} s; whole commands")
    plain = timed_detect(video, folder / "plain.csv")
    expected = (folder / "plain.csv").read_bytes()
    print(f"plain (local threads):  {plain:7.2f} s  {n_frames / plain:6.1f} frames/s")
    times = {}
    for workers in (1, 2):
        with DaskProcesses(workers) as address:
            runs = [(args.segment, f"{workers} worker{'s' * (workers > 1)}")]
            runs += [(args.segment / 4, f"{workers} workers, segments / 4")] if workers == 2 else []
            for segment, label in runs:
                output = folder / f"cluster_{workers}_{segment:g}.csv"
                took = timed_detect(video, output, "--scheduler", address, "--segment", f"{segment:g}")
                same = output.read_bytes() == expected
                times[(workers, segment)] = took
                print(
                    f"{label + ':':<24}{took:7.2f} s  {n_frames / took:6.1f} frames/s  "
                    f"{took / plain:.2f}x plain  events {'identical' if same else 'DIFFER'}"
                )
    coarse, fine = times[(2, args.segment)], times[(2, args.segment / 4)]
    n_coarse, n_fine = (max(1, int(args.seconds // s)) for s in (args.segment, args.segment / 4))
    overhead = (fine - coarse) / (n_fine - n_coarse)
    chain = chain_fps(video)
    start = time.perf_counter()
    decoded = decode_only(video)
    floor = decoded / (time.perf_counter() - start)
    print(f"per-segment overhead:   {overhead:+.3f} s ({n_coarse} -> {n_fine} segments on 2 workers)")
    print(f"per-video chain:        {chain:7.1f} frames/s (the part that runs in order)")
    print(f"decode-only floor:      {floor:7.1f} frames/s")
    rate = n_frames / coarse
    cameras, game = 20, 3 * 3600 * FPS
    segment_frames = args.segment * FPS
    for machines in (1, 4, 16, 64):
        projected = max(cameras * game / (machines * rate), game / chain)
        projected += cameras * game / segment_frames * max(overhead, 0.0) / (machines * 2)
        print(
            f"projection, {cameras} cameras x 3 h at {FPS:g} fps on {machines:>2} machines like this: "
            f"{projected / 60:6.1f} min"
        )


if __name__ == "__main__":
    main()
