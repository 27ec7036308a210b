"""``flashsync sync`` against ``flashsync diagnose -o``: both models scored against the truth.

Run: python benchmarks/bench_diagnose.py [--folder DIR] [--cases all|NAME,...]
     python benchmarks/bench_diagnose.py --seeds 0:40 [--max-height 360] [--duration-s 8] [--folder DIR]
                                         [--preflash MS] [--readout LO:HI] [--flash-powers SHARE]
                                         [--exposure-changes SHARE]

Renders each rig once (kept in --folder for the next run, each in its own sub-folder, with
``truth.json``), detects its events as each command does, runs ``synchronize`` (what
``flashsync sync`` writes) and ``diagnose`` (whose model ``flashsync diagnose -o`` writes,
:mod:`flashsync.diagnose.adopt`), and prints per rig and model the error against truth over
every frame and every 8th row (RMS over all cameras, then each camera's RMS, ms), the
effects diagnose named, its verdict, what it wrote and how that compares with sync's model
(a command that fails: its error). Rigs:

=====================  ===================================================================
``jittered-stamps``    the second world's recipe, its 25 fps camera and the 30 fps one whose
                       stamps are jittered 1.2 ms, 6 s
``stamp-rate-change``  the second world's recipe, its 25 fps camera and the 30 fps one whose
                       stamps run 1.5x as fast from frame 90 on (the sensor keeps its rate), 6 s
``drifting``           three cameras at 29.97 / 29.97 / 59.94 fps, 320x180, 10 s, clocks 80
                       and 100 ppm from the reference's (the issue's drifting HD rig, smaller)
``short-exposure``     320x180, 6 s: 25 fps with an 8 ms exposure and 30 fps with 1 ms,
                       linear sensors, the default (xenon-like) flash
``rolling-flicker``    the same under 5 % 100 Hz mains flicker
``jittered-60fps``     320x180, 6 s: 25 fps and 59.94 fps whose stamps are jittered 3 ms (a
                       sixth of its period); also 5 and 6 ms (``jittered-5ms-60fps``,
                       ``jittered-6ms-60fps``: 0.3 and 0.36 of its period)
``fast-stamps-60fps``  the same, its stamps 5 % fast from frame 150 on, jittered 1.2 ms (also
                       3 ms: ``fast-stamps-3ms-60fps``)
``slowing-stamps``     the same, its stamps half as fast from frame 150 on, not jittered
=====================  ===================================================================

With ``--seeds``, the second world's random rigs instead (``random_rig(seed)``, in the
world ``bench_rigs.py``'s options ask for: ``--preflash``, ``--readout``, ``--flash-powers``,
``--exposure-changes``;
kept in ``DIR/<rig name>`` as ``bench_rigs.py --keep DIR`` keeps them, so one rendering
serves both), and after them a summary: the median RMS of each model over the rigs, and the rigs
with a camera ``diagnose -o`` puts more than twice as far off as ``sync``'s worst camera
(plus 0.05 ms): how many pass the verdict, and how many of those cameras the line on
``sync``'s model names.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
from bench_rigs import add_world_options, dressed, parse_seeds, rendered  # the sibling: one layout, seeds, worlds

from flashsync import detect_videos, synchronize
from flashsync.diagnose import diagnose
from flashsync.errors import FlashsyncError
from flashsync.evaluate import sync_errors
from flashsync.simulation import CameraSpec, FlashSpec, Scenario
from flashsync.simulation.rigs import NTSC_30, NTSC_60, random_rig, recipe


def drifting() -> Scenario:
    rng = np.random.default_rng(2)
    instants = 300.0 + np.cumsum(120.0 + rng.exponential(150.0, 100))
    flashes = tuple(
        FlashSpec(round(float(t), 3), round(float(rng.uniform(0.35, 0.7)), 3)) for t in instants[instants < 9700.0]
    )
    cameras = (
        CameraSpec("cam1", 320, 180, NTSC_30, exposure_ms=2.0),
        CameraSpec("cam2", 320, 180, NTSC_30, exposure_ms=4.0, drift_ppm=80.0, start_ms=1000.0, offset_ms=-900.0),
        CameraSpec("cam3", 320, 180, NTSC_60, exposure_ms=3.0, drift_ppm=100.0, start_ms=5000.0, offset_ms=-4950.0),
    )
    return Scenario("drifting", cameras, duration_ms=10_000.0, flashes=flashes, n_players=0, seed=2)


def short_exposure(flicker_depth: float = 0.0) -> Scenario:
    rng = np.random.default_rng(1)
    instants = 300.0 + np.cumsum(120.0 + rng.exponential(150.0, 100))
    flashes = tuple(
        FlashSpec(round(float(t), 3), round(float(rng.uniform(0.35, 0.7)), 3)) for t in instants[instants < 5700.0]
    )
    cameras = (
        CameraSpec("cam0", 320, 180, 25.0, exposure_ms=8.0, tone="linear"),
        CameraSpec("cam1", 320, 180, 30.0, exposure_ms=1.0, start_ms=3000.0, offset_ms=-2830.0, tone="linear"),
    )
    return Scenario(
        "short-exposure",
        cameras,
        duration_ms=6000.0,
        flashes=flashes,
        n_players=0,
        seed=1,
        flicker_depth=flicker_depth,
        flicker_hz=100.0,
    )


def sixty_fps(jitter_ms: float, **fault) -> Scenario:
    rng = np.random.default_rng(2)
    instants = 300.0 + np.cumsum(120.0 + rng.exponential(150.0, 100))
    flashes = tuple(
        FlashSpec(round(float(t), 3), round(float(rng.uniform(0.35, 0.7)), 3)) for t in instants[instants < 5700.0]
    )
    cameras = (
        CameraSpec("cam0", 320, 180, 25.0, exposure_ms=8.0),
        CameraSpec(
            "cam1", 320, 180, NTSC_60, exposure_ms=4.0, start_ms=3000.0, offset_ms=-2830.0, jitter_ms=jitter_ms, **fault
        ),
    )
    return Scenario("sixty", cameras, duration_ms=6000.0, flashes=flashes, n_players=0, seed=2)


def two_of(name: str) -> Scenario:
    scenario = recipe(name, seed=0, duration_ms=6000.0)
    return dataclasses.replace(scenario, cameras=scenario.cameras[:2])


RIGS = {
    "jittered-stamps": lambda: two_of("jittered-stamps"),
    "stamp-rate-change": lambda: two_of("stamp-rate-change"),
    "drifting": drifting,
    "short-exposure": short_exposure,
    "rolling-flicker": lambda: short_exposure(0.05),
    "jittered-60fps": lambda: sixty_fps(3.0),
    "jittered-5ms-60fps": lambda: sixty_fps(5.0),
    "jittered-6ms-60fps": lambda: sixty_fps(6.0),
    "fast-stamps-60fps": lambda: sixty_fps(1.2, stamp_rate_changes=((150, 1.05),)),
    "fast-stamps-3ms-60fps": lambda: sixty_fps(3.0, stamp_rate_changes=((150, 1.05),)),
    "slowing-stamps": lambda: sixty_fps(0.0, stamp_rate_changes=((150, 0.5),)),
}


def pooled_ms(table) -> float:
    """RMS over cameras of the per-camera RMS errors of a :func:`sync_errors` table, ms."""
    return float(np.sqrt(np.mean(table["rms_ms"] ** 2)))


def errors(table) -> str:
    cameras = "  ".join(f"{row.camera} {row.rms_ms:.4f}" for row in table.itertuples())
    return f"{pooled_ms(table):.4f} ms RMS ({cameras})"


def run(scenario: Scenario, folder: Path) -> dict | None:
    """Print one rig's block; returns both models' error tables, the verdict and the cameras
    the line on sync's model names (None where a command failed)."""
    truth = rendered(scenario, folder)
    videos = [folder / f"{c.name}.{c.container}" for c in scenario.cameras]
    print(f"{folder.name}:")
    synced = None
    try:
        model, _ = synchronize(detect_videos(videos))
        synced = sync_errors(model, truth)
        print(f"  sync         {errors(synced)}")
    except FlashsyncError as error:
        print(f"  sync         {error}")
    try:
        d = diagnose(detect_videos(videos))
    except FlashsyncError as error:
        print(f"  diagnose     {error}")
        return None
    diagnosed = sync_errors(d.sync_model, truth)
    print(f"  diagnose -o  {errors(diagnosed)}")
    steps = [("out: " if step.removed else "") + f"{step.effect} {step.camera}" for step in d.steps]
    print(f"  steps        {', '.join(steps)}")
    print(f"  verdict      {d.verdict}")
    print(f"  written      {d.written}")
    print(f"  vs sync      {d.agreement}")
    if synced is None:
        return None
    return {"sync": synced, "diagnose": diagnosed, "consistent": d.consistent, "named": set(d.disagrees)}


def summary(results: list[dict | None]) -> str:
    """The random rigs' summary (module docstring)."""
    done = [r for r in results if r is not None]
    far = []
    for r in done:
        line = r["sync"]["rms_ms"].max() * 2.0 + 0.05
        far.append(set(r["diagnose"].loc[r["diagnose"]["rms_ms"] > line, "camera"]))
    off = [(r, cameras) for r, cameras in zip(done, far) if cameras]
    cameras = sum(len(c) for _, c in off)
    named = sum(len(c & r["named"]) for r, c in off)
    return "\n".join(
        [
            f"{len(done)} of {len(results)} rigs run by both; median RMS: sync "
            f"{np.median([pooled_ms(r['sync']) for r in done]):.3f} ms, diagnose -o "
            f"{np.median([pooled_ms(r['diagnose']) for r in done]):.3f} ms",
            f"rigs with a camera diagnose -o puts over twice sync's worst + 0.05 ms: {len(off)}, "
            f"{sum(r['consistent'] for r, _ in off)} of them passing the verdict; such cameras {cameras}, "
            f"{named} named by the line on sync's model",
        ]
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--folder", type=Path, default=Path("bench_diagnose"), help="rendered rigs (kept)")
    parser.add_argument("--cases", default="all", help=f"all, or some of {','.join(RIGS)}")
    parser.add_argument("--seeds", help="random rigs A:B (seeds A..B-1) or one seed, instead of the cases")
    parser.add_argument("--max-height", type=int, default=360, help="largest image height of random rigs")
    parser.add_argument("--duration-s", type=float, default=8.0, help="length of random rigs, s")
    add_world_options(parser)
    args = parser.parse_args()
    if args.seeds:
        rigs = dressed(
            [random_rig(seed, args.max_height, 1000.0 * args.duration_s) for seed in parse_seeds(args.seeds)], args
        )
        results = [run(rig, args.folder / rig.name) for rig in rigs]
        print(summary(results))
        return
    for name in list(RIGS) if args.cases == "all" else args.cases.split(","):
        run(RIGS[name](), args.folder / name)


if __name__ == "__main__":
    main()
