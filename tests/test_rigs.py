"""The random-rig generator: seeded, within its documented distributions, renderable; and
the named recipes of the issues' rigs."""

from __future__ import annotations

import subprocess
import sys
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from flashsync.errors import FlashsyncError
from flashsync.simulation import render_scenario
from flashsync.simulation.rigs import (
    NTSC_24,
    NTSC_30,
    NTSC_60,
    RATES,
    RECIPES,
    random_rig,
    recipe,
    with_fast_readout,
    with_flash_powers,
)


def test_same_seed_same_rig_and_other_seeds_differ():
    assert random_rig(7, max_height=540) == random_rig(7, max_height=540)
    assert random_rig(7, max_height=540) != random_rig(8, max_height=540)


def test_rigs_stay_within_their_distributions():
    rigs = [random_rig(seed, max_height=540, duration_ms=12_000.0) for seed in range(40)]
    cameras = [c for rig in rigs for c in rig.cameras]
    assert all(2 <= len(rig.cameras) <= 12 for rig in rigs)
    assert max(len(rig.cameras) for rig in rigs) >= 10 and min(len(rig.cameras) for rig in rigs) <= 3
    assert all(c.height <= 540 for c in cameras) and {c.height for c in cameras} == {180, 270, 360, 540}
    assert {c.fps for c in cameras} == set(RATES)
    assert all(0.5 <= c.exposure_ms <= min(16.0, 0.95 * c.frame_period_ms) for c in cameras)
    assert all(abs(c.drift_ppm) <= 50 and 18 <= c.crf <= 30 for c in cameras)
    assert all(rig.cameras[0].drift_rate_ppm_per_s == 0 for rig in rigs)
    assert any(c.drift_rate_ppm_per_s != 0 for c in cameras)
    assert 0.1 < np.mean([c.flipped for c in cameras]) < 0.3
    assert Counter(c.tone for c in cameras).keys() == {"linear", "srgb", "gamma"}
    assert {c.container for c in cameras} == {"mp4", "mkv"} and any(c.quantize_ms for c in cameras)
    assert any(c.jitter_ms > 0 for c in cameras) and any(c.drop_fraction > 0 for c in cameras)
    assert {c.bframes for c in cameras} == {None, 0, 2} and {c.keyint for c in cameras} == {None, 60, 600}
    assert all(0 <= c.miss_probability <= 0.3 for c in cameras)
    assert {rig.flashes[0].shape for rig in rigs} == {"exponential", "rectangular", "linear rise", "cosine rise"}
    for rig in rigs:
        instants = np.array([f.world_ms for f in rig.flashes])
        assert 6 <= len(instants) <= 16 and np.all(np.diff(instants) >= 400.0 - 1e-3)
        assert instants[0] >= 0.08 * rig.duration_ms - 1e-3 and instants[-1] <= 0.92 * rig.duration_ms + 1e-3
    flicker = [rig for rig in rigs if rig.flicker_depth > 0]
    assert 10 < len(flicker) < 30 and all(0.005 <= rig.flicker_depth <= 0.1 for rig in flicker)
    assert {rig.flicker_hz for rig in flicker} == {100.0, 120.0}
    assert {rig.flicker_waveform for rig in flicker} == {"sine", "rectified"}
    assert any(rig.player_radius_m[1] > 2 for rig in rigs) and max(rig.n_players for rig in rigs) >= 25


def test_a_small_random_rig_renders(tmp_path):
    rig = random_rig(3, max_height=180, duration_ms=1500.0, cameras=(2, 2))
    truth = render_scenario(rig, tmp_path)
    assert list(truth.cameras) == ["cam1", "cam2"]
    assert all((tmp_path / c.file).stat().st_size > 0 for c in truth.cameras.values())
    assert any(c.flashes_seen for c in truth.cameras.values())


def test_a_fast_readout_reads_the_rows_in_part_of_the_frame(tmp_path):
    """`with_fast_readout` grows only the hidden rows after the image: the rendered truth's
    time per row reads the visible rows in the fraction drawn, the rest of the rig as it was."""
    rig = random_rig(3, max_height=180, duration_ms=1500.0, cameras=(2, 2))
    fast = with_fast_readout(rig, (0.45, 0.75), seed=1)
    assert [replace(c, r1=0) for c in fast.cameras] == [replace(c, r1=0) for c in rig.cameras]
    assert replace(fast, cameras=rig.cameras) == rig
    truth = render_scenario(fast, tmp_path)
    for camera in fast.cameras:
        read = truth.cameras[camera.name].row_time_ms * (camera.r0 + camera.height) / camera.frame_period_ms
        assert 0.45 <= read <= 0.75 and camera.r1 > 0.3 * camera.height


def test_flashes_at_two_powers_change_only_their_pulses_lengths(tmp_path):
    """`with_flash_powers` lengthens a share of the flashes to 2-3 ms and shortens the rest
    to 0.05-0.3 ms (to a tenth of the peak), a rectangle by its hold and a decaying pulse by
    its decay, keeping each one's kind, rise, instant and strength; the rendered truth fires
    them so."""
    rigs = [random_rig(seed, max_height=180, duration_ms=8000.0) for seed in range(8)]
    by_kind = {rig.flashes[0].shape: rig for rig in rigs}
    assert {"rectangular", "exponential"} <= set(by_kind)
    for rig in by_kind.values():
        fired = with_flash_powers(rig, share=0.5, seed=3)
        assert replace(fired, flashes=rig.flashes) == rig
        for before, after in zip(rig.flashes, fired.flashes):
            assert (after.world_ms, after.strength, after.rise_ms, after.shape) == (
                before.world_ms,
                before.strength,
                before.rise_ms,
                before.shape,
            )
        lengths = np.array([f.hold_ms if f.decay_ms == 0 else f.decay_ms * np.log(10) for f in fired.flashes])
        full = (lengths >= 2.0 - 1e-3) & (lengths <= 3.0 + 1e-3)
        assert np.all(full | ((lengths >= 0.05 - 1e-3) & (lengths <= 0.3 + 1e-3)))
        assert 0 < full.sum() < len(lengths)
    led = with_flash_powers(replace(by_kind["rectangular"], cameras=by_kind["rectangular"].cameras[:1]), 0.5, seed=3)
    truth = render_scenario(replace(led, duration_ms=3000.0), tmp_path)
    assert [(f["hold_ms"], f["decay_ms"]) for f in truth.flashes] == [(f.hold_ms, f.decay_ms) for f in led.flashes]


@pytest.mark.parametrize("fractions", ["0.5", "a:b", "0.7:0.4", "1.2:1.5", "0:0.5"])
def test_bench_rigs_readout_out_of_range_is_one_line(fractions):
    """``bench_rigs.py --readout`` takes LO:HI with 0 < LO <= HI <= 1; anything else is one
    line of argparse's and exit 2, before any rig is drawn."""
    script = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_rigs.py"
    run = subprocess.run(
        [sys.executable, str(script), "--readout", fractions], capture_output=True, text=True, timeout=60
    )
    assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr
    assert f"argument --readout: {fractions}: give LO:HI with 0 < LO <= HI <= 1" in run.stderr.splitlines()[-1]


@pytest.mark.parametrize("option", ["--flash-powers", "--exposure-changes"])
@pytest.mark.parametrize("share", ["1.5", "a"])
def test_bench_rigs_share_out_of_range_is_one_line(option, share):
    """``bench_rigs.py --flash-powers`` and ``--exposure-changes`` take a share between 0
    and 1; anything else is one line of argparse's and exit 2, before any rig is drawn."""
    script = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_rigs.py"
    run = subprocess.run([sys.executable, str(script), f"{option}={share}"], capture_output=True, text=True, timeout=60)
    assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr
    assert f"argument {option}: {share}: give a share between 0 and 1, e.g. 0.3" in run.stderr.splitlines()[-1]


def test_recipes_rebuild_the_issue_rigs_in_the_second_world():
    rigs = {name: recipe(name, seed=1, duration_ms=10_000.0) for name in RECIPES}
    four = rigs["four-ms-drops"].cameras
    assert [(c.width, c.height, c.fps, c.container) for c in four] == [(960, 540, 25.0, "mkv")] * 2 + [
        (640, 360, 25.0, "mkv")
    ] * 2
    assert all(c.drop_fraction > 0 for c in four) and [c.exposure_ms for c in four[:2]] == [6.0, 6.0]
    assert [c.fps for c in rigs["three-rates-flipped"].cameras] == [25.0, 30.0, 50.0]
    assert [c.flipped for c in rigs["twin-flipped"].cameras] == [False, True]
    assert [c.drop_fraction for c in rigs["twin-drops"].cameras] == [0.0, 0.05]
    hd = rigs["hd"].cameras
    assert [(c.width, c.height, c.fps) for c in hd] == [
        (1920, 1080, NTSC_30),
        (1280, 720, NTSC_30),
        (1280, 720, NTSC_60),
    ]
    twelve = rigs["twelve"].cameras
    assert len(twelve) == 12 and all((c.width, c.height, c.miss_probability) == (320, 180, 0.3) for c in twelve)
    assert rigs["rolling-flicker"].cameras[0].exposure_ms == 0.5 and rigs["rolling-flicker"].flicker_depth == 0.03
    assert not rigs["flash-free"].flashes
    assert [c.jitter_ms for c in rigs["jittered-stamps"].cameras] == [0.0, 1.2, 0.0]
    assert rigs["stamp-rate-change"].cameras[1].stamp_rate_changes == ((150, 1.5),)  # 300 frames in 10 s
    locked = rigs["line-locked"].cameras
    phases = [(c.offset_ms + c.start_ms) % 40.0 for c in locked]  # the world time of a frame's start, mod 40 ms
    assert [c.fps for c in locked] == [25.0] * 3 and all(c.drift_ppm == 0.0 for c in locked)
    assert phases[0] == 0.0 and all(0.0 < p < 0.3 for p in phases[1:])
    assert [(c.fps, c.exposure_ms) for c in rigs["action-cams"].cameras] == [(120.0, 2.0), (30.0, 4.0), (240.0, 1.0)]
    assert [c.fps for c in rigs["slow-rates"].cameras] == [15.0, 20.0, NTSC_24]
    long = recipe("long-pair")
    assert long.duration_ms == 900_000.0 and len(long.flashes) == 30
    assert long.cameras[1].drift_rate_ppm_per_s > 0 and long.player_radius_m == (0.55, 1.1)
    real_light = ("rolling-flicker", "large-movers", "long-pair", "flash-free")
    for name, rig in rigs.items():
        tones = ("linear",) if name in real_light else ("srgb", "gamma")
        assert all(c.tone in tones and 18 <= c.crf <= 30 for c in rig.cameras), name
        assert all(f.shape in ("linear rise", "rectangular") for f in rig.flashes), name
    assert recipe("hd", seed=1) == recipe("hd", seed=1)
    with pytest.raises(FlashsyncError, match="unknown rig recipe 'nope'"):
        recipe("nope")
