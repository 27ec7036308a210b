"""Which exposure to report: the solve's (both band edges, one unknown per camera) or the
detector's shared band width (rows) times the solved time per row, against the truth.

Run: python benchmarks/bench_exposure_source.py --rigs RIGS [--seeds 0:24] [--skip rig-14]

RIGS holds rigs kept by ``bench_rigs.py --keep RIGS`` (``RIGS/rig-<seed>`` with the videos
and ``truth.json``). Each rig is detected and synchronised as ``flashsync sync`` does; per
camera both exposures are compared with the true one. Prints, for true exposures of at
most 6 ms and above, each source's count, median error, p90 and max of its absolute error
and how many are within 0.1 ms, then on how many cameras with both the width is closer.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from flashsync import detect_videos, synchronize


def exposures(folder: Path) -> list[tuple[float, float, float]]:
    """Per solved camera of the rig in ``folder``: (true, solve's, width x T_row) exposure,
    ms; NaN where a source has none."""
    truth = json.loads((folder / "truth.json").read_text())["cameras"]
    detections = {d.camera: d for d in detect_videos([folder / truth[name]["file"] for name in truth])}
    model, _ = synchronize(list(detections.values()))
    rows = []
    for name, clock in model.cameras.items():
        width = detections[name].exposure_rows
        rows.append(
            (
                truth[name]["exposure_ms"],
                np.nan if clock.exposure_ms is None else clock.exposure_ms,
                np.nan if width is None else width * clock.row_time_ms,
            )
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rigs", type=Path, required=True, help="rigs kept by bench_rigs.py --keep")
    parser.add_argument("--seeds", default="0:24", help="first:last (exclusive) random rig seeds")
    parser.add_argument("--skip", default="rig-14", help="rigs left out, comma-separated (a misread one)")
    args = parser.parse_args()
    first, last = (int(v) for v in args.seeds.split(":"))
    skipped = set(args.skip.split(",")) if args.skip else set()
    rows = []
    for seed in range(first, last):
        if f"rig-{seed}" not in skipped:
            rows += exposures(args.rigs / f"rig-{seed}")
    true, solve, width = np.array(rows).T
    for label, mine in (("<= 6 ms", true <= 6.0), ("> 6 ms", true > 6.0)):
        for source, value in (("solve", solve), ("width x T_row", width)):
            error = (value - true)[mine]
            error = error[np.isfinite(error)]
            size = np.abs(error)
            print(
                f"{label:8} {source:14} n {len(error):4}  median {np.median(error):+.3f}  p90 |err| "
                f"{np.percentile(size, 90):.3f}  max {size.max():.3f} ms  within 0.1 ms: {int(np.sum(size < 0.1))}"
            )
    both = np.isfinite(solve) & np.isfinite(width)
    closer = int(np.sum(both & (np.abs(width - true) < np.abs(solve - true))))
    print(f"width x T_row closer on {closer} of {int(both.sum())} cameras with both")


if __name__ == "__main__":
    main()
