"""Leading-edge precision against simulation truth, in rows (units of T_row).

Run: python benchmarks/bench_edges.py [--clips N] [--sizes 320x180,640x360] [--crf 0,23] [--strengths 0.25,0.45]
     python benchmarks/bench_edges.py --exposures 0.5,1,2,4,8,16 [--shapes ...] [--size 480x270] [--tone srgb]

For each frame size and H.264 quality it renders ``--clips`` rink clips (25 fps, 20 + 60
hidden rows, 8 flashes each at random rows and strengths 0.25-0.45 (``--strengths``; 1-2
clips the ice: saturated edges), exposure 4, 8 or 16 ms,
four players), detects them with ``flashsync.detect_video`` and compares every leading
edge with the instant the flash had given half its light (the simulator's truth), mapped
into the frame's rows. Saturated edges (flagged) are counted apart. Prints RMS, mean,
median, 95th percentile and maximum error per setting.

With ``--exposures 0.5,1,2,4,8,16`` it measures instead, per pulse shape (``--shapes``:
the exponential, a xenon tube with a 1 ms tail, an LED rectangle of 0.4 ms, a slow cosine
rise of 0.6 ms with a 0.5 ms decay) and exposure, one clip of ``--size`` (default
480x270, crf 23, 25 fps, 8 flashes, strengths 0.3-0.7, the sensor's ``--tone`` curve:
linear, srgb or gamma): the exposure the detector's bands
give (median over bands with both edges of the true end-of-exposure time of the trailing
edge's row minus the leading edge's, so the solve's time per row does not enter) minus
the true exposure, and the median error of the leading edges against the instant the
flash had given half its light, ms.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from flashsync.detect import detect_video
from flashsync.events import Edge, Flag
from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario
from flashsync.simulation.scenario import TONES

FPS, R0, R1, FLASHES = 25.0, 20, 60, 8


def edge_errors(
    width: int, height: int, crf: int, seed: int, folder: Path, strengths: tuple[float, float] = (0.25, 0.45)
) -> tuple[np.ndarray, np.ndarray]:
    """Leading-edge errors (rows) of one rendered clip and which edges are saturated."""
    rng = np.random.default_rng(seed)
    row_ms = 1000.0 / FPS / (R0 + height + R1)
    rows, strengths = rng.uniform(0.1 * height, 0.97 * height, FLASHES), rng.uniform(*strengths, FLASHES)
    flashes = tuple(
        FlashSpec(world_ms=(4 + 6 * i) * 1000.0 / FPS + (R0 + row) * row_ms, strength=strength)
        for i, (row, strength) in enumerate(zip(rows, strengths))
    )
    camera = CameraSpec(
        "cam",
        width,
        height,
        FPS,
        r0=R0,
        r1=R1,
        exposure_ms=float(rng.choice([4.0, 8.0, 16.0])),
        n_frames=6 * FLASHES + 7,
        noise_std=1.0,
        crf=crf,
    )
    truth = render_scenario(Scenario("edges", (camera,), flashes=flashes, n_players=4, seed=seed), folder)
    events = detect_video(folder / "cam.mp4").events
    leading = events.take(events.edge == Edge.LEADING)
    if len(leading) != FLASHES:
        raise RuntimeError(f"seed {seed}: {len(leading)} leading edges for {FLASHES} flashes")
    found = truth.global_time_ms("cam", leading.frame, leading.row)
    true = np.array([flash["half_rise_global_ms"] for flash in truth.flashes])
    return (found - true) / row_ms, leading.has_flag(Flag.SATURATED)


#: Pulse shapes of ``--exposures``: FlashSpec fields.
SHAPES = {
    "exponential": dict(decay_ms=0.5),
    "xenon": dict(decay_ms=1.0, rise_ms=0.05),
    "led": dict(decay_ms=0.0, hold_ms=0.4),
    "slow-rise": dict(decay_ms=0.5, rise_ms=0.6, rise="cosine"),
}


def exposure_errors(
    width: int, height: int, shape: str, exposure_ms: float, folder: Path, tone: str = "linear"
) -> tuple[float, float]:
    """(exposure error, median leading-edge error), ms, of one rendered clip: the
    detector's band durations against the true exposure, its leading edges against the
    flashes' half-light instants (NaN without a band with both edges)."""
    rng = np.random.default_rng(7)
    row_ms = 1000.0 / FPS / (R0 + height + R1)
    rows = rng.uniform(0.1 * height, 0.9 * height, FLASHES)
    flashes = tuple(
        FlashSpec(world_ms=(4 + 5 * i) * 1000.0 / FPS + (R0 + row) * row_ms, strength=strength, **SHAPES[shape])
        for i, (row, strength) in enumerate(zip(rows, rng.uniform(0.3, 0.7, FLASHES)))
    )
    camera = CameraSpec(
        "cam",
        width,
        height,
        FPS,
        r0=R0,
        r1=R1,
        exposure_ms=exposure_ms,
        n_frames=5 * FLASHES + 6,
        noise_std=1.0,
        crf=23,
        tone=tone,
    )
    truth = render_scenario(Scenario("exposure", (camera,), flashes=flashes, n_players=2, seed=7), folder)
    events = detect_video(folder / "cam.mp4").events
    bands = events.bands()
    complete = bands.take(bands.complete)
    t_leading = truth.global_time_ms("cam", events.frame[complete.leading], events.row[complete.leading])
    t_trailing = truth.global_time_ms("cam", events.frame[complete.trailing], events.row[complete.trailing])
    leading = events.take(events.edge == Edge.LEADING)
    found = truth.global_time_ms("cam", leading.frame, leading.row)
    half = np.array([flash["half_rise_global_ms"] for flash in truth.flashes])
    edge_error = [t - half[np.argmin(np.abs(half - t))] for t in found]
    exposure = float(np.median(t_trailing - t_leading)) - exposure_ms if len(t_leading) else float("nan")
    return exposure, float(np.median(edge_error)) if edge_error else float("nan")


def exposure_table(width: int, height: int, shapes: list[str], exposures: list[float], tone: str) -> None:
    """Print exposure and leading-edge errors by pulse shape and exposure."""
    print(f"{width}x{height} crf 23, {tone} tone: exposure error / median leading-edge error, ms")
    print(f"{'shape':<12}" + "".join(f"{f'{e:g} ms':>16}" for e in exposures))
    for shape in shapes:
        cells = []
        for exposure_ms in exposures:
            with tempfile.TemporaryDirectory() as folder:
                exposure, edge = exposure_errors(width, height, shape, exposure_ms, Path(folder), tone)
            cells.append(f"{exposure:+.3f} / {edge:+.3f}")
        print(f"{shape:<12}" + "".join(f"{cell:>16}" for cell in cells), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=int, default=10)
    parser.add_argument("--sizes", default="320x180,640x360")
    parser.add_argument("--crf", default="0,23")
    parser.add_argument("--strengths", default="0.25,0.45", help="range of the flashes' strengths")
    parser.add_argument("--exposures", help="exposures, ms: measure exposure and edge errors by pulse shape instead")
    parser.add_argument("--shapes", default=",".join(SHAPES), help="pulse shapes of --exposures")
    parser.add_argument("--size", default="480x270", help="frame size of --exposures")
    parser.add_argument("--tone", default="linear", choices=TONES, help="the sensor's tone curve in --exposures")
    args = parser.parse_args()
    if args.exposures:
        width, height = map(int, args.size.split("x"))
        exposures = [float(e) for e in args.exposures.split(",")]
        exposure_table(width, height, args.shapes.split(","), exposures, args.tone)
        return
    strengths = tuple(map(float, args.strengths.split(",")))
    print(
        f"{'size':<9} {'crf':>3} {'edges':>5} {'rms':>6} {'mean':>7} {'median':>7} {'p95':>6} {'max':>6}"
        "  (rows, |error| but the mean; saturated apart)"
    )
    for size in args.sizes.split(","):
        width, height = map(int, size.split("x"))
        for crf in map(int, args.crf.split(",")):
            errors, saturated = [], []
            for seed in range(args.clips):
                with tempfile.TemporaryDirectory() as folder:
                    error, flag = edge_errors(width, height, crf, seed, Path(folder), strengths)
                errors.append(error)
                saturated.append(flag)
            error, flag = np.concatenate(errors), np.concatenate(saturated)
            clean = np.abs(error[~flag])
            line = f"{size:<9} {crf:>3} {clean.size:>5} "
            if clean.size:
                line += (
                    f"{np.sqrt(np.mean(clean**2)):>6.3f} {error[~flag].mean():>+7.3f} {np.median(clean):>7.3f} "
                    f"{np.percentile(clean, 95):>6.3f} {clean.max():>6.2f}"
                )
            if flag.any():
                line += (
                    f"  saturated: {flag.sum()} edges, rms {np.sqrt(np.mean(error[flag] ** 2)):.3f}, "
                    f"mean {error[flag].mean():+.3f}"
                )
            print(line)


if __name__ == "__main__":
    main()
