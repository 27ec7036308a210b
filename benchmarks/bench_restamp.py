"""Time ``restamp_file`` against a plain pyarrow CSV read + write of the same file.

Target: restamp <= 2x the plain read + write, on 10 million rows.

Usage::

    python benchmarks/bench_restamp.py [ROWS] [--dir DIR]

Writes ``detections.csv`` (ROWS rows, default 10,000,000: ``camera,frame,x,y,object,conf``
for 4 cameras at 30 fps) into DIR (default: a temporary directory, removed afterwards),
then prints the time of the plain read + write, of ``restamp_file``, and their ratio.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

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


def timed(function) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rows", nargs="?", type=int, default=10_000_000)
    parser.add_argument("--dir", type=Path, help="working directory (kept)")
    arguments = parser.parse_args()
    n_frames = 108_000  # one hour at 30 fps
    with tempfile.TemporaryDirectory() as scratch:
        directory = arguments.dir or Path(scratch)
        directory.mkdir(parents=True, exist_ok=True)
        source = directory / "detections.csv"
        write_detections_csv(source, arguments.rows, n_frames)
        model = make_model(n_frames)
        size_mb = source.stat().st_size / 1e6
        print(f"{arguments.rows} rows, {size_mb:.0f} MB: {source}")
        plain = timed(lambda: pacsv.write_csv(pacsv.read_csv(source), directory / "plain.csv"))
        print(f"pyarrow read_csv + write_csv: {plain:6.2f} s")
        stamped = timed(lambda: restamp_file(source, directory / "restamped.csv", model))
        print(f"restamp_file (CSV -> CSV):    {stamped:6.2f} s")
        print(f"ratio: {stamped / plain:.2f} (target <= 2)")


if __name__ == "__main__":
    main()
