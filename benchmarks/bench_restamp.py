"""Time ``flashsync restamp`` against a plain pyarrow CSV read + write of the same file.

Target: restamp <= 2x the plain read + write, whole commands (each a fresh Python process,
start-up and imports included), on 2 million rows; ``restamp_file`` alone is timed too.

Usage::

    python benchmarks/bench_restamp.py [ROWS] [--dir DIR] [--repeat N]

Writes ``detections.csv`` (ROWS rows, default 2,000,000: ``camera,frame,x,y,object,conf``
for 4 cameras at 30 fps) and its ``sync.json`` into DIR (default: a temporary directory,
removed afterwards), then prints the best of N (default 3) runs of: a ``python`` process
doing a pyarrow read_csv + write_csv, the ``flashsync restamp`` command, ``restamp_file``
in this process, and the ratios.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from flashsync.io import save_model  # noqa: E402
from flashsync.model import CameraClock, SyncModel  # noqa: E402
from tracking_adapter.restamp import restamp_file  # noqa: E402

CAMERAS = ("cam1", "cam2", "cam3", "cam4")
HEIGHT, WIDTH = 1080, 1920
FRAME_MS = 1000 / 30


def make_model(n_frames: int) -> SyncModel:
    """Four 1080p cameras at 30 fps with ``n_frames`` frames each, small drifts and shifts."""
    clocks = {}
    for index, name in enumerate(CAMERAS):
        clocks[name] = CameraClock(
            name=name,
            frame_times_ms=np.arange(n_frames) * FRAME_MS + 7.0 * index,
            height=HEIGHT,
            width=WIDTH,
            alpha=1 + 3e-6 * index,
            beta_ms=-11.0 * index,
            row_time_ms=FRAME_MS / 1125,
            covariance=np.diag([1e-12, 1e-4, 1e-10]),
            exposure_ms=2.0,
        )
    return SyncModel(reference=CAMERAS[0], cameras=clocks)


def write_detections_csv(path: Path, rows: int, n_frames: int, seed: int = 0) -> None:
    """Write ``rows`` random detections as an unquoted CSV, like a tracker's output."""
    rng = np.random.default_rng(seed)
    with open(path, "wb") as file:
        file.write(b"camera,frame,x,y,object,conf\n")
        for start in range(0, rows, 1 << 20):
            n = min(1 << 20, rows - start)
            columns = [
                pc.take(pa.array(CAMERAS), pa.array(rng.integers(0, len(CAMERAS), n))),
                pa.array(rng.integers(0, n_frames, n)),
                pa.array(np.round(rng.uniform(0, WIDTH, n), 2)),
                pa.array(np.round(rng.uniform(0, HEIGHT - 1, n), 2)),
                pa.array(rng.integers(0, 50, n)),
                pa.array(np.round(rng.uniform(0, 1, n), 3)),
            ]
            lines = pc.binary_join_element_wise(*(pc.cast(column, pa.string()) for column in columns), ",")
            text = pc.binary_join(pa.ListArray.from_arrays([0, n], lines), "\n")[0]
            file.write(text.as_buffer())
            file.write(b"\n")


def timed(function, repeat: int = 1) -> float:
    """Best wall time of ``repeat`` calls, s."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


PLAIN = "import sys, pyarrow.csv as c; c.write_csv(c.read_csv(sys.argv[1]), sys.argv[2])"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rows", nargs="?", type=int, default=2_000_000)
    parser.add_argument("--dir", type=Path, help="working directory (kept)")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each, the best counts (default 3)")
    arguments = parser.parse_args()
    n_frames = 108_000  # one hour at 30 fps
    with tempfile.TemporaryDirectory() as scratch:
        directory = arguments.dir or Path(scratch)
        directory.mkdir(parents=True, exist_ok=True)
        source, model_path = directory / "detections.csv", directory / "sync.json"
        write_detections_csv(source, arguments.rows, n_frames)
        model = make_model(n_frames)
        save_model(model, model_path)
        size_mb = source.stat().st_size / 1e6
        print(f"{arguments.rows} rows, {size_mb:.0f} MB: {source}")

        def run(*command: str) -> None:
            subprocess.run(command, check=True, stderr=subprocess.DEVNULL)

        plain = timed(
            lambda: run(sys.executable, "-c", PLAIN, str(source), str(directory / "plain.csv")), arguments.repeat
        )
        print(f"python + pyarrow read_csv + write_csv:  {plain:6.2f} s")
        command = timed(
            lambda: run(
                "flashsync", "restamp", str(source), "--model", str(model_path), "-o", str(directory / "r.csv")
            ),
            arguments.repeat,
        )
        print(f"flashsync restamp (CSV -> CSV):         {command:6.2f} s   ratio {command / plain:.2f} (target <= 2)")
        plain_in = timed(lambda: pacsv.write_csv(pacsv.read_csv(source), directory / "plain.csv"), arguments.repeat)
        stamped = timed(lambda: restamp_file(source, directory / "restamped.csv", model), arguments.repeat)
        print(f"in process: pyarrow {plain_in:.2f} s, restamp_file {stamped:.2f} s, ratio {stamped / plain_in:.2f}")


if __name__ == "__main__":
    main()
