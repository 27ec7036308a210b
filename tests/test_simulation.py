"""Tests of the simulator: rolling-shutter physics, container stamps, ground truth."""

import csv
import dataclasses
import math
from fractions import Fraction

import numpy as np
import pytest
from decoded import decode, half_rise, row_profile

from flashsync.errors import FlashsyncError
from flashsync.io import load_ground_truth, load_scenario
from flashsync.io.scenario import scenario_from_dict
from flashsync.simulation import CameraSpec, FlashSpec, LightSwitch, Scenario, preset, render_scenario
from flashsync.simulation.encode import write_video
from flashsync.simulation.light import flash_light
from flashsync.simulation.render import (
    Lighting,
    ambient_light,
    camera_view,
    exposure_end_ms,
    frame_gain,
    kept_frames,
    puck_track,
    render_frame,
    row_light,
)
from flashsync.simulation.scene import apply_homography, make_scene

# A camera with a non-trivial clock: 50 ppm fast, camera time 7 s ahead of the world.
CAM = CameraSpec(
    "c",
    320,
    180,
    25.0,
    r0=8,
    r1=4,
    exposure_ms=10.0,
    start_ms=7000.0,
    offset_ms=-5000.0,
    drift_ppm=50.0,
    flash_gain=0.8,
    noise_std=0.0,
)
T_FRAME = 7200.0  # camera time of the frame under test, ms
Q_TAU = 60.3  # readout row whose exposure ends when the flash fires


@pytest.fixture(scope="module")
def empty_scene():
    return make_scene(0, n_players=0)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """The tiny preset, 1.6 s, with frames 3 and 10 of cam1 dropped."""
    sc = preset("tiny", duration_ms=1600.0)
    cam1 = dataclasses.replace(sc.cameras[0], dropped_frames=(3, 10))
    sc = dataclasses.replace(sc, cameras=(cam1,) + sc.cameras[1:])
    out = tmp_path_factory.mktemp("tiny")
    return sc, render_scenario(sc, out), out


def flash_at_row(camera, q_tau):
    """A flash that fires when readout row `q_tau` of the test frame ends its exposure."""
    tau = float(camera.world_ms(T_FRAME + (camera.r0 + q_tau) * camera.row_time_ms))
    return FlashSpec(world_ms=tau, strength=0.3, decay_ms=0.5)


def test_flash_band_half_rise_is_at_the_analytic_row(empty_scene):
    flash = flash_at_row(CAM, Q_TAU)
    view = camera_view(empty_scene, CAM)
    lit = render_frame(view, empty_scene, T_FRAME, Lighting(flashes=(flash,))).astype(float)
    dark = render_frame(view, empty_scene, T_FRAME, Lighting()).astype(float)
    profile = row_profile(lit, dark)
    plateau = CAM.flash_gain * flash.strength
    assert np.median(profile[75:100]) == pytest.approx(plateau, abs=0.005)  # multiplicative flash
    assert np.abs(profile[:55]).max() < 0.005  # rows that ended before the flash
    # Half of the light is in once the row's exposure ends d*ln2 after the flash (world time).
    expected = Q_TAU + flash.decay_ms * math.log(2) / (1 + CAM.drift_ppm * 1e-6) / CAM.row_time_ms
    assert half_rise(profile, plateau) == pytest.approx(expected, abs=0.1)
    # The band ends when the exposure start passes the flash: exposure_ms later.
    assert half_rise(plateau - profile[70:], plateau) + 70 == pytest.approx(
        expected + CAM.exposure_ms / CAM.row_time_ms, abs=0.1
    )


def test_flipped_camera_band_is_mirrored(empty_scene):
    flipped = dataclasses.replace(CAM, flipped=True)
    flash = flash_at_row(CAM, Q_TAU)
    profiles = []
    for cam in (CAM, flipped):
        view = camera_view(empty_scene, cam)
        lit = render_frame(view, empty_scene, T_FRAME, Lighting(flashes=(flash,))).astype(float)
        dark = render_frame(view, empty_scene, T_FRAME, Lighting()).astype(float)
        profiles.append(row_profile(lit, dark))
    normal, upside_down = profiles
    assert np.allclose(upside_down[::-1], normal, atol=0.006)
    assert not np.allclose(upside_down, normal, atol=0.05)


def test_colour_frames_encode_with_chosen_stamps(empty_scene, tmp_path):
    view = camera_view(empty_scene, CAM, color=True)
    flash = flash_at_row(CAM, Q_TAU)
    frames = [render_frame(view, empty_scene, T_FRAME, Lighting(flashes=lit)) for lit in ((), (flash,), ())]
    assert frames[0].shape == (180, 320, 3) and frames[0].dtype == np.uint8
    grey = [f.astype(float) @ [0.114, 0.587, 0.299] for f in frames]  # BT.601 luma of BGR
    profile = row_profile(grey[1], grey[0])
    assert np.median(profile[75:100]) == pytest.approx(CAM.flash_gain * flash.strength, abs=0.01)
    write_video(tmp_path / "c.mkv", frames, [7000, 7040, 7081], Fraction(1, 1000), crf=0)
    decoded, stamps, _ = decode(tmp_path / "c.mkv")
    assert stamps.tolist() == [7000.0, 7040.0, 7081.0]
    assert np.abs(decoded[1] - grey[1]).mean() < 1.0
    assert [p.name for p in tmp_path.iterdir()] == ["c.mkv"]


def test_light_switch_gain_step_and_flicker_integrals():
    on = Lighting(switches=(LightSwitch(world_ms=4.0, factor=2.0),))
    light = ambient_light(np.array([0.0, 5.0, -10.0]), np.array([10.0, 15.0, 0.0]), on)
    assert light == pytest.approx([(4 * 1 + 6 * 2) / 10, 2.0, 1.0])
    flicker = Lighting(flicker_depth=0.5, flicker_hz=100.0)
    assert ambient_light(np.array([3.7]), np.array([13.7]), flicker) == pytest.approx([1.0])  # one period
    assert ambient_light(np.array([0.0]), np.array([5.0]), flicker) == pytest.approx([1 + 0.5 * 2 / math.pi])
    cam = dataclasses.replace(CAM, gain_steps=((2200.0, 1.5), (2300.0, 0.5)))
    # Frame at camera time 7200 starts at world ~2200.36, the next one ~2240.36.
    assert [frame_gain(cam, t) for t in (7160.0, 7200.0, 7280.0, 7320.0)] == pytest.approx([1, 1.5, 1.5, 0.75])


def test_puck_is_drawn_with_rolling_shutter_skew(empty_scene):
    scene = make_scene(0, n_players=0, puck_speed_mps=36.0)
    view = camera_view(scene, CAM)
    times = CAM.start_ms + np.arange(200) * CAM.frame_period_ms
    xy, visible = puck_track(view, scene.puck, times)
    k = int(np.flatnonzero(visible & (xy[:, 1] > 110))[0])  # low in the image: large skew
    img = render_frame(view, scene, times[k], Lighting()).astype(float)
    bare = render_frame(view, scene, times[k], Lighting(), objects=False).astype(float)
    dark = np.clip(bare - img, 0, None)
    rows, cols = np.nonzero(dark > 1)
    w = dark[rows, cols]
    centroid = np.array([np.sum(cols * w), np.sum(rows * w)]) / w.sum()
    assert centroid == pytest.approx(xy[k], abs=0.5)
    # A global shutter at the frame's first row would put it several px elsewhere.
    first_row = CAM.world_ms(times[k] + CAM.r0 * CAM.row_time_ms - CAM.exposure_ms / 2)
    unskewed = apply_homography(view.to_image, scene.puck.position(first_row))
    assert np.linalg.norm(unskewed - xy[k]) > 3.0


def test_dropped_frames_are_missing_and_mp4_keeps_90khz_stamps(rendered):
    sc, truth, out = rendered
    cam = truth.cameras["cam1"]
    n = sc.frame_count(sc.cameras[0])
    frames, stamps, time_base = decode(out / "cam1.mp4")
    assert time_base.denominator == 90000
    assert len(frames) == n - 2
    assert cam.frame_index == [f for f in range(n) if f not in (3, 10)]
    true = sc.cameras[0].start_ms + np.array(cam.frame_index) * sc.cameras[0].frame_period_ms
    assert np.allclose(cam.frame_times_ms, true, atol=1e-9, rtol=0)
    assert sorted(p.name for p in out.iterdir()) == [
        "cam1.mp4",
        "cam2.mkv",
        "detections.csv",
        "homographies.json",
        "truth.json",
    ]
    assert np.allclose(stamps, np.round(true * 90) / 90, atol=1e-9, rtol=0)
    assert np.allclose(stamps, cam.stamps_ms, atol=1e-9, rtol=0)
    gaps = np.round(np.diff(stamps) / sc.cameras[0].frame_period_ms)
    assert np.flatnonzero(gaps == 2).tolist() == [2, 8]


def test_mkv_stamps_are_quantised_to_1ms(rendered):
    sc, truth, out = rendered
    cam = truth.cameras["cam2"]
    _, stamps, time_base = decode(out / "cam2.mkv")
    assert time_base.denominator == 1000
    true = np.array(cam.frame_times_ms)
    assert np.any(np.abs(true - np.round(true)) > 0.1)  # true times are not whole ms
    assert np.array_equal(stamps, np.round(true))
    assert np.array_equal(stamps, np.array(cam.stamps_ms))


def test_reference_global_time_is_frame_time_plus_rows(rendered):
    sc, truth, out = rendered
    ref = truth.cameras["cam1"]
    t_row = 1000.0 / ref.fps / (ref.r0 + ref.height + ref.r1)
    frames = np.arange(len(ref.frame_index))[:, None]
    rows = np.array([0.0, 17.25, 179.0])
    expected = np.array(ref.frame_times_ms)[frames] + rows * t_row
    assert np.allclose(truth.global_time_ms("cam1", frames, rows), expected, atol=1e-9, rtol=0)
    assert (ref.alpha, ref.beta_ms, ref.row_time_ms) == (1.0, 0.0, pytest.approx(t_row))
    # Another camera follows the affine model with its true parameters.
    c2 = truth.cameras["cam2"]
    assert c2.alpha == pytest.approx(1 + 15e-6, abs=1e-12)
    model = c2.alpha * np.array(c2.frame_times_ms)[frames] + c2.beta_ms + rows * c2.row_time_ms
    assert np.allclose(truth.global_time_ms("cam2", frames, rows), model, atol=1e-6, rtol=0)
    again = load_ground_truth(out / "truth.json")
    assert scenario_from_dict(again.scenario) == sc
    assert np.array_equal(again.global_time_ms("cam2", frames, rows), truth.global_time_ms("cam2", frames, rows))
    # A drifting drift: the global time follows the quadratic clock, not the affine model.
    rate = 2.0  # ppm/s
    drifting = dataclasses.replace(
        truth, cameras=dict(truth.cameras, cam2=dataclasses.replace(c2, drift_rate_ppm_per_s=rate))
    )
    t = np.array(c2.frame_times_ms)[frames] + (c2.r0 + rows) * c2.sensor_row_ms
    extra = 0.5 * rate * 1e-9 * t**2 / (1 + truth.cameras["cam1"].drift_ppm * 1e-6)
    assert np.allclose(drifting.global_time_ms("cam2", frames, rows), model + extra, atol=1e-6, rtol=0)


def test_bands_in_the_videos_agree_with_the_ground_truth(rendered):
    sc, truth, out = rendered
    checked = 0
    for name, cam in truth.cameras.items():
        frames, _, _ = decode(out / cam.file)
        for k, flash in enumerate(truth.flashes):
            seen = cam.flashes_seen.get(k, [])
            if len(seen) != 1 or seen[0] == 0:
                continue
            j = seen[0]
            profile = row_profile(frames[j], frames[j - 1])
            plateau = np.median(profile[profile > 0.5 * profile.max()])
            if profile[0] > plateau / 4:  # leading edge in the hidden rows
                continue
            row = half_rise(profile, plateau)
            assert truth.global_time_ms(name, j, row) == pytest.approx(flash["half_rise_global_ms"], abs=0.1)
            checked += 1
    assert checked >= 3


def test_detections_file_holds_the_puck_track(rendered):
    sc, truth, out = rendered
    with open(out / "detections.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == ["camera", "frame", "x", "y", "object"]
    cam2 = [r for r in rows if r["camera"] == "cam2"]
    assert cam2 and all(r["object"] == "puck" for r in cam2)
    scene = make_scene(sc.seed, sc.n_players, sc.puck_speed_mps)
    view = camera_view(scene, sc.cameras[1])
    xy, visible = puck_track(view, scene.puck, np.array(truth.cameras["cam2"].frame_times_ms))
    assert [int(r["frame"]) for r in cam2] == np.flatnonzero(visible).tolist()
    got = np.array([[float(r["x"]), float(r["y"])] for r in cam2])
    assert np.allclose(got, xy[visible], atol=1e-3, rtol=0)


def test_drops_and_misses_are_reproducible_from_the_seed():
    sc = preset("tiny", duration_ms=20000.0)
    cam = dataclasses.replace(sc.cameras[0], drop_fraction=0.1)
    sc = dataclasses.replace(sc, cameras=(cam,) + sc.cameras[1:])
    kept = kept_frames(sc, 0)
    assert np.array_equal(kept, kept_frames(sc, 0))
    assert 0.05 < 1 - len(kept) / sc.frame_count(cam) < 0.15
    assert not np.array_equal(kept, kept_frames(dataclasses.replace(sc, seed=2), 0))


def test_a_render_is_the_same_file_every_time(tmp_path):
    """x264's AVX-512 code encoded this clip differently on most renders in one process
    (three distinct files of four); the simulator keeps x264 off it, so a test, a benchmark
    and CI see the same bytes for the same scenario."""
    camera = CameraSpec("cam", 320, 240, 30.0, r0=8, r1=12, exposure_ms=0.5, n_frames=24, noise_std=1.5, crf=23)
    scenario = Scenario(
        "same", (camera,), flashes=(FlashSpec(400.0, strength=0.3),), flicker_depth=0.03, flicker_hz=100.0, seed=4
    )
    files = set()
    for attempt in range(4):
        render_scenario(scenario, tmp_path / str(attempt))
        files.add((tmp_path / str(attempt) / "cam.mp4").read_bytes())
    distinct = len(files)
    assert distinct == 1


def test_load_scenario_from_yaml_and_refuse_unknown_keys(tmp_path):
    good = tmp_path / "s.yaml"
    good.write_text("preset: tiny\nseed: 5\nduration_ms: 1000\n")
    sc = load_scenario(good)
    assert (sc.name, sc.seed, sc.duration_ms, len(sc.cameras)) == ("tiny", 5, 1000, 2)
    bad = tmp_path / "bad.yaml"
    assert load_scenario("paper").name == "paper"  # a preset name when no such file exists
    bad.write_text("name: x\ncameras:\n  - {name: a, width: 64, height: 48, fps: 25, shutter: 3}\n")
    with pytest.raises(FlashsyncError, match=r"bad\.yaml.*unknown key 'shutter' in cameras\[0\]"):
        load_scenario(bad)
    top = tmp_path / "top.json"
    top.write_text('{"preset": "tiny", "colour": true}')
    with pytest.raises(FlashsyncError, match=r"top\.json.*unknown key 'colour'"):
        load_scenario(top)
    odd = tmp_path / "odd.yaml"
    odd.write_text("name: x\ncameras:\n  - {name: a, width: 65, height: 48, fps: 25}\n")
    with pytest.raises(FlashsyncError, match=r"odd\.yaml.*even"):
        load_scenario(odd)


def test_a_frames_light_skips_only_flashes_that_add_exactly_nothing():
    """`row_light` leaves out, per frame, the flashes that cannot reach its rows (not fired
    yet, or their tail underflowed to 0): every frame's rows are bit for bit the sum over
    every flash, for exponential, held and switched-off pulses, frames before, during and
    long after them."""
    camera = CameraSpec("c", 64, 48, 30.0, exposure_ms=4.0)
    flashes = (
        FlashSpec(100.0, 0.5, decay_ms=0.8),
        FlashSpec(130.0, 0.4, decay_ms=0.0, hold_ms=1.5),
        FlashSpec(400.0, 0.6, decay_ms=2.0, rise_ms=0.05),
    )
    lighting = Lighting(flashes=flashes)
    for t_frame_ms in np.arange(0.0, 3000.0, 1000.0 / 30.0):
        end = exposure_end_ms(camera, t_frame_ms)
        start_w, end_w = camera.world_ms(end - camera.exposure_ms), camera.world_ms(end)
        every = ambient_light(start_w, end_w, lighting)
        for flash in flashes:
            every = every + camera.flash_gain * flash_light(start_w, end_w, flash)
        assert np.array_equal(row_light(camera, t_frame_ms, lighting), every), t_frame_ms
