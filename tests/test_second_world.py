"""The simulator's second world: each option rendered, encoded, decoded with PyAV and
compared with its analytic truth (small frames, a few frames each)."""

from __future__ import annotations

import dataclasses
from fractions import Fraction

import av
import numpy as np
import pytest
from av.video.frame import PictureType
from decoded import decode, half_rise, row_profile

from flashsync.errors import FlashsyncError
from flashsync.frame_clock import fit_frame_clock
from flashsync.io import load_scenario
from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario
from flashsync.simulation.light import Lighting, ambient_light, flash_remaining, half_light_ms
from flashsync.simulation.render import camera_view, exposure_end_ms, render_frame
from flashsync.simulation.rigs import NTSC_30, NTSC_60
from flashsync.simulation.scene import make_scene
from flashsync.simulation.sensor import sensor_response, shading, tone_curve

SMALL = dict(width=192, height=108, r0=6, r1=6, noise_std=0.0, crf=0)


def camera(name: str = "c", fps: float = 25.0, **fields) -> CameraSpec:
    return CameraSpec(name=name, fps=fps, **{**SMALL, **fields})


def flash_on_row(spec: CameraSpec, frame: int, readout_row: float, **pulse) -> FlashSpec:
    """A flash fired when `readout_row` of sensor frame `frame` ends its exposure."""
    t = spec.start_ms + frame * spec.frame_period_ms + (spec.r0 + readout_row) * spec.row_time_ms
    return FlashSpec(world_ms=float(spec.world_ms(t)), **pulse)


PULSES = {
    "led": dict(strength=0.3, decay_ms=0.0, hold_ms=1.0),
    "xenon": dict(strength=0.3, decay_ms=0.6, rise_ms=0.05),
    "cosine": dict(strength=0.3, decay_ms=0.3, rise_ms=0.8, rise="cosine"),
}


def intensity(x: np.ndarray, flash: FlashSpec) -> np.ndarray:
    """The pulse at peak 1, written out piece by piece."""
    r, h, d = flash.rise_ms, flash.hold_ms, flash.decay_ms
    u = x / max(r, 1e-300)
    rising = u if flash.rise == "linear" else (1 - np.cos(np.pi * u)) / 2
    tail = np.exp(-(x - r - h) / d) if d > 0 else np.zeros_like(x)
    return np.select([x < 0, x < r, x < r + h], [0.0, rising, 1.0], tail)


@pytest.mark.parametrize("shape", [*PULSES, "exponential"])
def test_closed_form_pulse_integrals_match_numerical_ones(shape):
    flash = FlashSpec(0.0, **PULSES.get(shape, dict(strength=0.3, decay_ms=0.5)))
    x = np.linspace(-1.0, 12.0, 1_300_001)
    given = np.concatenate([[0.0], np.cumsum((intensity(x[1:], flash) + intensity(x[:-1], flash)) / 2 * np.diff(x))])
    given /= given[-1]
    assert np.max(np.abs(flash_remaining(x, flash) - (1 - given))) < 1e-5
    assert half_light_ms(flash) == pytest.approx(np.interp(0.5, given, x), abs=1e-4)


def test_pulse_shapes_integrate_exactly_and_the_half_rise_follows_the_shape(tmp_path):
    spec = camera(exposure_ms=4.0, n_frames=8)
    flashes = tuple(flash_on_row(spec, 2 + 2 * k, 40.3, **pulse) for k, pulse in enumerate(PULSES.values()))
    truth = render_scenario(Scenario("pulses", (spec,), flashes=flashes, n_players=0), tmp_path)
    frames, _, _ = decode(tmp_path / "c.mp4")
    for k, (flash, shape) in enumerate(zip(flashes, PULSES)):
        j = 2 + 2 * k
        profile = row_profile(frames[j], frames[j - 1])
        x = exposure_end_ms(spec, j * spec.frame_period_ms) - flash.world_ms
        expected = flash.strength * (flash_remaining(x - spec.exposure_ms, flash) - flash_remaining(x, flash))
        assert np.nanmax(np.abs(profile - expected)) < 0.01, shape
        edge = half_rise(profile, expected.max())
        assert truth.global_time_ms("c", j, edge) == pytest.approx(
            truth.flashes[k]["half_rise_global_ms"], abs=0.05 * 1
        ), shape
    # The half-light instant is the shape's, not the exponential's d ln 2.
    assert half_light_ms(flashes[0]) == pytest.approx(0.5)
    assert half_light_ms(flashes[1]) == pytest.approx(0.05 + 0.6 * np.log(2 * 0.6 / 0.625))
    assert truth.flashes[0]["half_rise_global_ms"] - truth.flashes[0]["global_ms"] == pytest.approx(0.5)


@pytest.mark.parametrize("tone", ["srgb", "gamma"])
def test_tone_curve_black_level_clipping_and_vignetting(tmp_path, tone):
    base = camera("lin", exposure_ms=8.0, n_frames=3)
    toned = dataclasses.replace(base, name="toned", tone=tone, black_level=16.0, white_level=200.0)
    clipping = dataclasses.replace(base, name="clip", white_level=150.0)
    vignetted = dataclasses.replace(base, name="vig", vignetting=0.4)
    flash = flash_on_row(base, 1, 30.0, strength=0.3, decay_ms=0.3)
    render_scenario(Scenario("tone", (base, toned, clipping, vignetted), flashes=(flash,), n_players=0), tmp_path)
    lin, toned_frames, clip, vig = (decode(tmp_path / f"{name}.mp4")[0] for name in ("lin", "toned", "clip", "vig"))
    # A known linear level maps to black + (255 - black) tone(level / white).
    assert sensor_response(np.array([50.0], np.float32), toned)[0] == pytest.approx(
        16 + 239 * (1.055 * 0.25 ** (1 / 2.4) - 0.055 if tone == "srgb" else 0.25 ** (1 / 2.2)), abs=1e-3
    )
    dark = lin[0]
    unclipped = (dark > 30) & (dark < 190)
    expected = 16 + 239 * tone_curve(dark / 200.0, tone)
    assert np.median(np.abs(toned_frames[0] - expected)[unclipped]) < 0.6
    assert np.abs(toned_frames[0] - expected)[unclipped].max() < 3.5
    # Flash rows: the band is no longer a pure multiplicative step (1.3 in linear light).
    rows = slice(36, 53)  # rows that integrated all of the flash (readout rows 30 to 30 + 24)
    bright = dark[rows] > 60
    assert np.mean(np.abs(lin[1][rows] / lin[0][rows] - 1.3)[bright]) < 0.02
    ratio = (toned_frames[1] - 16) / np.maximum(toned_frames[0] - 16, 1)
    power = 1 / 2.2 if tone == "gamma" else 1 / 2.4
    assert np.median(ratio[rows][bright]) == pytest.approx(1.3**power, abs=0.03 if tone == "srgb" else 0.01)
    # White 150: the ice (~140) is not clipped, but the flash clips it to 255.
    ice = (dark > 120) & (dark < 140)
    assert np.abs(clip[0] - dark * 255 / 150)[ice].max() < 3.5
    assert ice[rows].sum() > 100 and clip[1][rows][ice[rows]].min() >= 253
    # Vignetting: the ratio to the plain camera is the shading, 1 - 0.4 rho**2 (0.6 in the corners).
    shade = shading(vignetted)
    assert shade[0, 0] == pytest.approx(0.6, abs=0.01) and shade[53:55, 95:97] == pytest.approx(1.0, abs=1e-3)
    lit = (dark > 60) & (shade < 0.8)
    assert lit.sum() > 500 and np.median(np.abs(vig[0] / dark - shade)[lit]) < 0.01


def picture_types(path) -> list[str]:
    with av.open(str(path)) as container:
        return [PictureType(f.pict_type).name for f in container.decode(video=0)]


def test_encoder_settings_reach_the_file(tmp_path):
    common = dict(exposure_ms=8.0, n_frames=40, crf=28, noise_std=1.0)
    with_b = camera("b", bframes=3, keyint=12, x264_preset="fast", **common)
    without_b = camera("nob", bframes=0, keyint=250, x264_preset="veryfast", **common)
    render_scenario(Scenario("gop", (with_b, without_b), n_players=12, seed=4), tmp_path)
    types = picture_types(tmp_path / "b.mp4")
    keys = [i for i, t in enumerate(types) if t == "I"]
    assert "B" in types and max(np.diff(keys + [len(types)])) <= 12
    assert "B" not in picture_types(tmp_path / "nob.mp4")


def test_ntsc_rates_stamps_and_frame_clock(tmp_path):
    sixty = camera("sixty", fps=NTSC_60, exposure_ms=2.0, n_frames=120, start_ms=1000.0, width=128, height=72)
    thirty = camera("thirty", fps=NTSC_30, exposure_ms=2.0, n_frames=300, container="mkv", width=128, height=72)
    truth = render_scenario(Scenario("ntsc", (sixty, thirty), n_players=0), tmp_path)
    _, stamps, time_base = decode(tmp_path / "sixty.mp4")
    true = 1000.0 + np.arange(120) * 1001.0 / 60.0
    assert time_base.denominator == 90000
    assert np.allclose(truth.cameras["sixty"].frame_times_ms, true, atol=1e-9, rtol=0)
    assert np.allclose(stamps, truth.cameras["sixty"].stamps_ms, atol=1e-9, rtol=0)
    assert np.max(np.abs(stamps - true)) <= 1 / 180 + 1e-9  # 1501.5 ticks a frame: 1501, 1502, ...
    assert sorted(set(np.round(np.diff(stamps) * 90).astype(int))) == [1501, 1502]
    clock = fit_frame_clock(stamps)
    assert clock.steady and clock.period_ms == pytest.approx(1001.0 / 60.0, abs=1e-4)
    with av.open(str(tmp_path / "sixty.mp4")) as container:
        assert container.streams.video[0].average_rate == Fraction(60000, 1001)
    _, stamps, _ = decode(tmp_path / "thirty.mkv")
    true = np.arange(300) * 1001.0 / 30.0
    assert np.allclose(truth.cameras["thirty"].frame_times_ms, true)
    assert np.array_equal(stamps, truth.cameras["thirty"].stamps_ms) and np.max(np.abs(stamps - true)) <= 0.5 + 1e-9
    clock = fit_frame_clock(stamps)
    assert clock.steady and clock.quantum_ms == 1.0 and clock.period_ms == pytest.approx(1001.0 / 30.0, abs=1e-3)


def flicker_profile(frame: np.ndarray, view, scene, t_frame_ms: float) -> np.ndarray:
    """Per row: light of a decoded (noisy, so that rounding is dithered) frame over that of
    the noise- and flicker-free render at the same instant, on its ice (> 100 DN), minus 1;
    NaN for rows with fewer than 50 ice pixels."""
    quiet = dataclasses.replace(view, camera=dataclasses.replace(view.camera, noise_std=0.0))
    plain = render_frame(quiet, scene, t_frame_ms, Lighting()).astype(float)
    ice = plain > 100
    enough = np.where(ice.sum(axis=1) >= 50, 1.0, np.nan)
    with np.errstate(invalid="ignore"):
        return np.sum(frame * ice, axis=1) / np.sum(plain * ice, axis=1) * enough - 1


def test_rolling_rectified_flicker_is_exact_per_row(tmp_path):
    fast = camera("fast", fps=30.0, exposure_ms=0.5, n_frames=3, noise_std=2.0)
    slow = camera("slow", fps=25.0, exposure_ms=0.5, n_frames=3, noise_std=2.0)
    scenario = Scenario(
        "flicker",
        (fast, slow),
        flicker_depth=0.05,
        flicker_hz=100.0,
        flicker_phase=0.4,
        flicker_waveform="rectified",
        n_players=0,
    )
    render_scenario(scenario, tmp_path)
    scene = make_scene(0, n_players=0)
    lighting = Lighting(flicker_depth=0.05, flicker_hz=100.0, flicker_phase=0.4, flicker_waveform="rectified")
    sine = dataclasses.replace(lighting, flicker_waveform="sine")
    for spec, rolls in ((fast, True), (slow, False)):
        view = camera_view(scene, spec)
        frames = decode(tmp_path / f"{spec.name}.mp4")[0]
        profiles = [flicker_profile(f, view, scene, j * spec.frame_period_ms) for j, f in enumerate(frames)]
        for j, profile in enumerate(profiles):
            end = exposure_end_ms(spec, j * spec.frame_period_ms)
            expected = ambient_light(end - spec.exposure_ms, end, lighting) - 1
            assert np.nanmax(np.abs(profile - expected)) < 0.006, (spec.name, j)
            assert np.max(np.abs(ambient_light(end - spec.exposure_ms, end, sine) - 1 - expected)) > 0.02
        moved = np.nanmax(np.abs(profiles[1] - profiles[0]))
        assert moved > 0.05 if rolls else moved < 0.006  # 33.3 ms is not a whole number of 10 ms periods


def test_many_large_dark_and_bright_movers():
    scene = make_scene(5, n_players=24, player_radius_m=(1.5, 2.5))
    assert len(scene.players) == 24
    assert all(1.5 <= p.radius_m <= 2.5 for p in scene.players)
    grey = [np.dot(p.color, [0.114, 0.587, 0.299]) for p in scene.players]
    assert min(grey) < 40 and max(grey) > 200
    spec = camera(exposure_ms=8.0)
    view = camera_view(scene, spec)
    covered = (
        np.abs(
            render_frame(view, scene, 0.0, Lighting()).astype(float)
            - render_frame(view, scene, 0.0, Lighting(), objects=False)
        )
        > 10
    )
    assert covered.mean() > 0.05


def test_stamp_rate_change_and_recording_gap(tmp_path):
    spec = camera(
        exposure_ms=8.0,
        n_frames=40,
        start_ms=500.0,
        stamp_rate_changes=((20, 1.5),),
        frame_gaps=((5, 3),),
        width=128,
        height=72,
    )
    truth = render_scenario(Scenario("stamps", (spec,), n_players=0), tmp_path)
    _, stamps, _ = decode(tmp_path / "c.mp4")
    kept = [f for f in range(40) if f not in (5, 6, 7)]
    assert truth.cameras["c"].frame_index == kept
    assert np.allclose(truth.cameras["c"].frame_times_ms, 500.0 + 40.0 * np.array(kept))
    assert np.allclose(stamps, truth.cameras["c"].stamps_ms)
    steps = np.round(np.diff(stamps), 6)
    assert steps[4] == 160.0  # frames 5, 6, 7 missing
    assert set(steps[:4]) | set(steps[5:17]) == {40.0} and set(steps[17:]) == {60.0}  # 1.5x after frame 20
    assert stamps[-1] == pytest.approx(500.0 + 20 * 40.0 + 19 * 60.0)


def test_slowly_changing_drift_of_a_camera_fifteen_minutes_in(tmp_path):
    ref = camera("ref", exposure_ms=4.0, n_frames=2, drift_ppm=-5.0)
    start, drift, rate = 900_000.0, 20.0, 0.05
    offset = 1000.0 - (1 + drift * 1e-6) * start - 0.5 * rate * 1e-9 * start**2
    late = camera(
        "late",
        exposure_ms=8.0,
        n_frames=3,
        start_ms=start,
        offset_ms=offset,
        drift_ppm=drift,
        drift_rate_ppm_per_s=rate,
    )
    flash = flash_on_row(late, 1, 50.2, strength=0.3, decay_ms=0.4)
    truth = render_scenario(Scenario("late", (ref, late), flashes=(flash,), n_players=0), tmp_path)
    frames, _, _ = decode(tmp_path / "late.mp4")
    profile = row_profile(frames[1], frames[0])
    edge = half_rise(profile, np.median(profile[58:72]))  # readout rows 50 to 50 + 24
    assert truth.global_time_ms("late", 1, edge) == pytest.approx(truth.flashes[0]["half_rise_global_ms"], abs=0.05)
    # The affine parameters alone (no drift rate) would be ~20 ms off this far in.
    c = truth.cameras["late"]
    affine = c.alpha * c.frame_times_ms[1] + c.beta_ms + edge * c.row_time_ms
    assert abs(affine - truth.global_time_ms("late", 1, edge)) > 15.0


def test_scenario_files_set_the_second_world(tmp_path):
    path = tmp_path / "second.yaml"
    path.write_text(
        "preset: tiny\nflicker_waveform: rectified\nplayer_radius_m: [1.0, 2.0]\n"
        "flashes:\n  - {world_ms: 500, rise_ms: 0.5, rise: cosine, decay_ms: 0.3}\n"
        "  - {world_ms: 900, hold_ms: 1.0, decay_ms: 0}\n"
        "cameras:\n  - {name: a, width: 320, height: 180, fps: 29.97, tone: srgb, black_level: 16, white_level: 300,\n"
        "     vignetting: 0.3, keyint: 60, bframes: 0, x264_preset: fast, frame_gaps: [[10, 5]],\n"
        "     stamp_rate_changes: [[30, 1.5]]}\n"
    )
    scenario = load_scenario(path)
    cam = scenario.cameras[0]
    assert (scenario.flicker_waveform, scenario.player_radius_m) == ("rectified", (1.0, 2.0))
    assert [f.shape for f in scenario.flashes] == ["cosine rise", "rectangular"]
    assert (cam.tone, cam.black_level, cam.white_level, cam.vignetting) == ("srgb", 16, 300, 0.3)
    assert (cam.keyint, cam.bframes, cam.x264_preset) == (60, 0, "fast")
    assert cam.frame_gaps == ((10, 5),) and cam.stamp_rate_changes == ((30, 1.5),)
    path.write_text("preset: tiny\nflashes:\n  - {world_ms: 500, decay_ms: 0}\n")
    with pytest.raises(FlashsyncError, match="flash 0: the pulse has no duration"):
        load_scenario(path)
