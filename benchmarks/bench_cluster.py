"""Detection on a Dask cluster against the plain run: throughput with 1 and 2 workers here,
the cost of a segment, and what that projects for N machines.

Run: python benchmarks/bench_cluster.py [--seconds 120] [--size 1080p] [--segment 30] [--dir DIR]

Writes a clip (``bench_detect``'s scene: textured, moving blobs, a flash every 40 frames;
25 fps, x264 veryfast, a key frame every 250 frames), then times whole ``flashsync detect``
commands on it: plain (local threads), and with ``--scheduler tcp://127.0.0.1:PORT`` against
``dask scheduler`` + ``dask worker --nworkers W --nthreads 1 --preload flashsync.cluster``
processes started here for W = 1 and 2 (their start-up, the detector's imports and compiled
kernels included, is not timed: a cluster runs before a job comes), each run's
events compared with the plain run's byte for byte (on 2 workers with segments of a quarter
the length too). Then the cost of a segment: decoding the video in segments of a quarter
the length, one after the other in this process, against decoding it whole (seeking, the
decoder's start, the frames read past a segment's end), plus a Dask task's round trip on
the 2-worker cluster; the detection state pushed through the video in one process without
decoding (the part that runs in order): the rate of the per-video chain; and decode-only
(PyAV, threads AUTO), the floor.

The projection for N machines like this one, a game of C cameras x F frames each::

    time ~ max(C F / (N r), F / chain) + C F / (segment frames) x overhead / (N W)

with r the frames per second of one machine (the 2-worker run, conservative: one video),
chain the chain's rate, segments of the default 60 s and W = 2 workers per machine:
decoding scales with machines, each video's chain runs in order (the videos' chains in
parallel, on the workers too).
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
from flashsync.segments import SEGMENT_MS, plan_segments, read_segment  # noqa: E402
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
    """``dask scheduler`` and ``dask worker --nworkers W --preload flashsync.cluster`` on
    127.0.0.1, stopped on exit."""

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
                [dask, "worker", self.address, "--nworkers", str(self.workers), "--nthreads", "1", "--no-dashboard"]
                + ["--preload", "flashsync.cluster"],
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


def segment_cost(video: Path, segment_ms: float) -> tuple[float, float, int]:
    """Time to decode the video's profiles whole and in segments (one after the other), s,
    and the number of segments."""
    start = time.perf_counter()
    for _ in read_profiles(video)[1]:
        pass
    whole = time.perf_counter() - start
    segments = plan_segments(video, segment_ms)[1]
    start = time.perf_counter()
    for segment in segments:
        read_segment(segment)
    return whole, time.perf_counter() - start, len(segments)


def task_round_trip(address: str, n_tasks: int = 200) -> float:
    """Mean wall time of a trivial task submitted and gathered one at a time, s."""
    from distributed import Client

    with Client(address) as client:
        client.submit(abs, -1, pure=False).result()
        start = time.perf_counter()
        for i in range(n_tasks):
            client.submit(abs, -i, pure=False).result()
        return (time.perf_counter() - start) / n_tasks


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
    print(f"{video.name}: {n_frames} frames {args.size}, segments of {args.segment:g} s; whole commands", flush=True)
    plain = timed_detect(video, folder / "plain.csv")
    expected = (folder / "plain.csv").read_bytes()
    print(f"plain (local threads):  {plain:7.2f} s  {n_frames / plain:6.1f} frames/s", flush=True)
    times, round_trip = {}, 0.0
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
                    f"{took / plain:.2f}x plain  events {'identical' if same else 'DIFFER'}",
                    flush=True,
                )
            if workers == 2:
                round_trip = task_round_trip(address)
    whole, parts, n_parts = segment_cost(video, args.segment * 1000.0 / 4)
    overhead = (parts - whole) / n_parts + round_trip
    chain = chain_fps(video)
    start = time.perf_counter()
    decoded = decode_only(video)
    floor = decoded / (time.perf_counter() - start)
    print(
        f"per-segment overhead:   {overhead * 1000:6.1f} ms (decoding in {n_parts} segments {parts:.2f} s, whole "
        f"{whole:.2f} s; a task's round trip {round_trip * 1000:.1f} ms)"
    )
    print(f"per-video chain:        {chain:7.1f} frames/s (the part that runs in order)")
    print(f"decode-only floor:      {floor:7.1f} frames/s")
    coarse = times[(2, args.segment)]
    rate = n_frames / coarse
    cameras, game = 20, 3 * 3600 * FPS
    segment_frames = SEGMENT_MS / 1000.0 * FPS  # a real run's default segments
    print(f"one 3 h video's chain alone: {game / chain / 60:.1f} min (the floor of any number of machines)")
    for machines in (1, 4, 16, 64):
        projected = max(cameras * game / (machines * rate), game / chain)
        projected += cameras * game / segment_frames * max(overhead, 0.0) / (machines * 2)
        print(
            f"projection, {cameras} cameras x 3 h at {FPS:g} fps on {machines:>2} machines like this: "
            f"{projected / 60:6.1f} min"
        )


if __name__ == "__main__":
    main()
