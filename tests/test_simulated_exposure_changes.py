"""Auto-exposure in the simulator: a camera's exposure changing mid-recording
(``CameraSpec.exposure_changes``), rendered, checked, kept in the ground truth and drawn by
`with_exposure_changes`."""

import dataclasses
import json

import numpy as np
import pytest
from decoded import decode, half_rise, row_profile

from flashsync.errors import FlashsyncError, InputError
from flashsync.io import load_ground_truth
from flashsync.io.scenario import scenario_from_dict
from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario
from flashsync.simulation.render import Lighting, camera_view, flash_frames, puck_track, render_frame
from flashsync.simulation.rigs import random_rig, with_exposure_changes
from flashsync.simulation.scenario import check_scenario
from flashsync.simulation.scene import make_scene
from flashsync.simulation.truth import camera_truth

# 25 fps, 192 rows a frame (0.2083 ms a row); 4 ms of exposure, 2 ms from sensor frame 90 on.
CAM = CameraSpec(
    "cam1",
    320,
    180,
    25.0,
    r0=8,
    r1=4,
    exposure_ms=4.0,
    exposure_changes=((90, 2.0),),
    start_ms=7000.0,
    offset_ms=-5000.0,
    drift_ppm=50.0,
    n_frames=180,
    noise_std=0.5,
)


def frame_ms(camera, frame):
    """True camera time of a sensor frame, ms."""
    return camera.start_ms + frame * camera.frame_period_ms


def flash_in(camera, frame, q=60.3, strength=0.25):
    """A 0.1 ms flash that fires when readout row `q` of sensor `frame` ends its exposure."""
    tau = float(camera.world_ms(frame_ms(camera, frame) + (camera.r0 + q) * camera.row_time_ms))
    return FlashSpec(world_ms=tau, strength=strength, decay_ms=0.1)


def test_exposure_at_ms_follows_the_changes_from_their_sensor_frame():
    t = frame_ms(CAM, np.arange(180))
    assert CAM.exposure_at_ms(t).tolist() == [4.0] * 90 + [2.0] * 90
    two = dataclasses.replace(CAM, exposure_changes=((120, 3.0), (90, 2.0)))  # in any order
    assert two.exposure_at_ms(t.reshape(18, 10)).ravel().tolist() == [4.0] * 90 + [2.0] * 30 + [3.0] * 60
    assert CAM.exposure_at_ms(frame_ms(CAM, 89)).shape == ()


def test_a_frame_renders_as_a_camera_always_at_its_exposure():
    """Rows' windows (flicker), the puck's motion blur and a flash's light all follow the
    frame's exposure: the last frame before the change renders as a 4 ms camera, the first
    after it as a 2 ms camera whose flash gain is twice as high (the ambient level is kept)."""
    scene = make_scene(0, n_players=0, puck_speed_mps=36.0)
    times = frame_ms(CAM, np.arange(180))
    xy, visible = puck_track(camera_view(scene, CAM), scene.puck, times)
    change = int(np.flatnonzero(visible[:-1] & visible[1:] & (xy[:-1, 1] > 60))[0]) + 1
    cam = dataclasses.replace(CAM, exposure_changes=((change, 2.0),))
    long = dataclasses.replace(cam, exposure_changes=())
    short = dataclasses.replace(cam, exposure_ms=2.0, exposure_changes=(), flash_gain=2.0 * cam.flash_gain)
    for frame, same, other in ((change - 1, long, short), (change, short, long)):
        lighting = Lighting(flashes=(flash_in(cam, frame),), flicker_depth=0.2)
        image = render_frame(camera_view(scene, cam), scene, times[frame], lighting)
        assert np.array_equal(image, render_frame(camera_view(scene, same), scene, times[frame], lighting))
        assert not np.array_equal(image, render_frame(camera_view(scene, other), scene, times[frame], lighting))


def test_the_puck_centroid_and_the_frames_a_flash_reaches_follow_the_exposure():
    scene = make_scene(0, n_players=0, puck_speed_mps=36.0)
    times = frame_ms(CAM, np.arange(180))
    xy = puck_track(camera_view(scene, CAM), scene.puck, times)[0]
    for exposure, frames in ((4.0, slice(0, 90)), (2.0, slice(90, 180))):
        steady = dataclasses.replace(CAM, exposure_ms=exposure, exposure_changes=())
        expected = puck_track(camera_view(scene, steady), scene.puck, times)[0]
        assert np.array_equal(xy[frames], expected[frames], equal_nan=True)
    # A flash 3 ms before a frame's first row ends its exposure: the last rows of the frame
    # before see it, and that frame's first rows too while they are exposed for 4 ms.
    for frame, seen in ((60, [59, 60]), (100, [99])):
        tau = float(CAM.world_ms(times[frame] + CAM.r0 * CAM.row_time_ms - 3.0))
        assert np.flatnonzero(flash_frames(CAM, times, FlashSpec(tau, 0.25, decay_ms=0.1))).tolist() == seen


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """CAM (7.2 s, no players) rendered with flashes in sensor frames 30, 60, 89, 90, 120 and 150."""
    frames = (30, 60, 89, 90, 120, 150)
    scenario = Scenario("exposure", (CAM,), flashes=tuple(flash_in(CAM, f) for f in frames), n_players=0, seed=1)
    out = tmp_path_factory.mktemp("exposure")
    return scenario, frames, render_scenario(scenario, out), out


def test_the_flash_bands_shorten_in_the_video_from_the_frame_of_the_change(rendered):
    """Decoded, a band is the exposure long (half-rise to half-fall, 19.2 rows at 4 ms, 9.6
    at 2 ms; x264 at crf 23 moves the edges by up to 0.35 rows) and twice as strong in the
    shorter exposure."""
    _, frames, _, out = rendered
    video = decode(out / "cam1.mp4")[0]
    lengths, plateaus = [], []
    for f in frames:
        profile = row_profile(video[f], video[f - 2])
        plateau = float(np.median(profile[profile > profile.max() / 2]))
        lead = half_rise(profile, plateau)
        start = int(lead) + 3
        lengths.append(half_rise(plateau - profile[start:], plateau) + start - lead)
        plateaus.append(plateau)
    expected = [4.0 / CAM.row_time_ms] * 3 + [2.0 / CAM.row_time_ms] * 3
    assert lengths == pytest.approx(expected, abs=0.6), lengths
    assert plateaus == pytest.approx([0.25] * 3 + [0.5] * 3, abs=0.03)


def test_the_truth_keeps_the_change_and_round_trips(rendered, tmp_path):
    scenario, _, truth, out = rendered
    camera = truth.cameras["cam1"]
    assert camera.exposure_ms == 4.0 and camera.exposure_changes == [(90, 2.0)]
    assert camera.exposure_of_ms([0, 89, 90, 179]).tolist() == [4.0, 4.0, 2.0, 2.0]
    assert load_ground_truth(out) == truth
    assert scenario_from_dict(truth.scenario) == scenario
    # A steady camera's truth, and a truth file written before exposure changes existed, load with none.
    data = json.loads((out / "truth.json").read_text())
    for steady in (dict(exposure_changes=[]), {}):
        data["cameras"]["cam1"] = {k: v for k, v in data["cameras"]["cam1"].items() if k != "exposure_changes"}
        data["cameras"]["cam1"].update(steady)
        (tmp_path / "truth.json").write_text(json.dumps(data))
        assert load_ground_truth(tmp_path).cameras["cam1"].exposure_changes == []
    for bad in ([[1.5, 2.0]], [[90, 0.0]], [[90, 2.0], [80, 3.0]], [[-1, 2.0]], [90, 2.0], "x"):
        data["cameras"]["cam1"]["exposure_changes"] = bad
        (tmp_path / "truth.json").write_text(json.dumps(data))
        with pytest.raises(InputError, match="exposure_changes"):
            load_ground_truth(tmp_path)


def test_the_truth_numbers_a_change_by_the_written_frames():
    """A drop before the change moves it one written frame earlier; a change at a dropped
    frame shows at the next written one; a change at frame 0 is the truth's exposure_ms."""
    cases = [
        (((90, 2.0),), [f for f in range(180) if f != 50], 4.0, [(89, 2.0)]),
        (((90, 2.0),), [f for f in range(180) if f not in (90, 91)], 4.0, [(90, 2.0)]),
        (((0, 3.0), (90, 2.0)), list(range(180)), 3.0, [(90, 2.0)]),
    ]
    for changes, kept, first, expected in cases:
        cam = dataclasses.replace(CAM, exposure_changes=changes)
        t = frame_ms(cam, np.array(kept))
        truth = camera_truth(cam, "cam1.mp4", np.array(kept), t, t, {}, cam)
        assert (truth.exposure_ms, truth.exposure_changes) == (first, expected)
        assert truth.exposure_of_ms(np.arange(len(kept))).tolist() == cam.exposure_at_ms(t).tolist()


BAD_CHANGES = {
    "not a pair": ((90,),),
    "frame before the first": ((-1, 2.0),),
    "fractional frame": ((1.5, 2.0),),
    "infinite frame": ((float("inf"), 2.0),),
    "no exposure": ((90, 0.0),),
    "over a frame period": ((90, 41.0),),
    "two at one frame": ((90, 2.0), (90, 3.0)),
}


@pytest.mark.parametrize("changes", BAD_CHANGES.values(), ids=BAD_CHANGES.keys())
def test_bad_exposure_changes_are_refused(changes):
    scenario = Scenario("bad", (dataclasses.replace(CAM, exposure_changes=changes),))
    with pytest.raises(FlashsyncError, match="exposure_changes"):
        check_scenario(scenario, "scenario 'bad'")


def test_scenario_files_read_exposure_changes_and_need_not_have_them():
    scenario = Scenario("ok", (CAM,))
    data = scenario.to_dict()
    assert data["cameras"][0]["exposure_changes"] == [[90, 2.0]]
    assert scenario_from_dict(data) == scenario
    del data["cameras"][0]["exposure_changes"]
    assert scenario_from_dict(data).cameras[0].exposure_changes == ()
    data["cameras"][0]["exposure_changes"] = [[90.5, 2.0]]
    with pytest.raises(InputError, match="not a whole number"):
        scenario_from_dict(data)


def test_with_exposure_changes_changes_some_cameras_once_in_their_middle_half():
    rigs = [random_rig(seed, max_height=180, duration_ms=8000.0) for seed in range(12)]
    assert with_exposure_changes(rigs[0], seed=4) == with_exposure_changes(rigs[0], seed=4)
    factors = []
    for seed, rig in enumerate(rigs):
        changed = with_exposure_changes(rig, share=0.5, seed=seed)
        assert [dataclasses.replace(c, exposure_changes=()) for c in changed.cameras] == list(rig.cameras)
        for camera in changed.cameras:
            if camera.exposure_changes:
                ((frame, exposure),) = camera.exposure_changes
                n = changed.frame_count(camera)
                assert n // 4 <= frame < 3 * n // 4 and exposure <= camera.frame_period_ms
                if exposure < camera.frame_period_ms:
                    factors.append(exposure / camera.exposure_ms)
    cameras = sum(len(rig.cameras) for rig in rigs)
    assert 0.3 * cameras < len(factors) < 0.7 * cameras
    factors = np.array(factors)
    shorter = (factors >= 0.4 - 2e-3) & (factors <= 0.7 + 2e-3)
    assert np.all(shorter | ((factors >= 1.4 - 2e-3) & (factors <= 2.0 + 2e-3))) and 0 < shorter.sum() < len(factors)
    assert all(not c.exposure_changes for c in with_exposure_changes(rigs[0], share=0.0).cameras)
