from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from flashsync.errors import FlashsyncError
from flashsync.io import load_model, save_model
from flashsync.model import MATCHED_EVENT_COLUMNS, CameraClock, HeldExposure, SyncModel


def camera(flipped=False):
    times = np.array([0.0, 40.0, 80.0, 160.0, 200.0])  # frame at 120 ms dropped
    return CameraClock(
        "cam2",
        times,
        height=100,
        width=160,
        alpha=1 + 20e-6,
        beta_ms=-1234.5,
        row_time_ms=0.37,
        flipped=flipped,
        covariance=np.diag([1e-12, 1e-4, 1e-8]),
        exposure_ms=10.0,
        video="cam2.mp4",
        exposure_std_ms=0.05,
    )


def test_global_time_of_frame_and_row():
    cam = camera()
    expected = (1 + 20e-6) * 160.0 - 1234.5 + 25.5 * 0.37
    assert cam.t_global_ms(3, 25.5) == pytest.approx(expected, abs=1e-9)
    np.testing.assert_allclose(cam.t_global_ms([0, 4], [0, 0]) - cam.t_global_ms([0, 4], [99, 99]), -99 * 0.37)


def test_flipped_camera_reads_bottom_up():
    cam = camera(flipped=True)
    assert cam.t_global_ms(1, 99) == pytest.approx(camera().t_global_ms(1, 0))
    assert cam.t_global_ms(1, 0) == pytest.approx(camera().t_global_ms(1, 99))


@pytest.mark.parametrize("flipped", [False, True])
def test_locate_inverts_global_time(flipped):
    cam = camera(flipped)
    frames = np.array([0, 1, 2, 3, 4, 4])
    rows = np.array([0.0, 10.25, 50.0, 98.5, 99.0, 3.75])
    frame, row = cam.locate(cam.t_global_ms(frames, rows))
    np.testing.assert_array_equal(frame, frames)
    np.testing.assert_allclose(row, rows, atol=1e-6)


def test_locate_outside_visible_rows_is_nan():
    cam = camera()
    start = cam.t_global_ms(0, 0)
    frame, row = cam.locate(np.array([start - 1.0, cam.t_global_ms(0, 99) + 1.0, cam.t_global_ms(2, 99) + 10]))
    assert frame[0] == -1 and np.isnan(row[0])
    assert frame[1] == 0 and np.isnan(row[1])  # vertical blanking after row 99
    assert frame[2] == 2 and np.isnan(row[2])  # the dropped frame's slot


def test_uncertainty_grows_with_distance_from_known_rows():
    cam = camera()
    std = cam.t_global_std_ms([0, 4], [0, 99])
    assert std.shape == (2,) and np.all(std > 0)


#: cam2's exposure as its bands show it: 12 ms over frames 0-1 (two bands), one band of 9 ms
#: in frame 2 (a change, or a band that does not fit), 8 ms in frame 3 (two bands).
SPANS = (
    HeldExposure(0, 1, 12.0, 0.1, 2, True),
    HeldExposure(2, 2, 9.0, 0.3, 1, False),
    HeldExposure(3, 3, 8.0, 0.05, 2, True),
)


def test_exposure_at_each_frame_is_its_span_s_between_spans_the_middle_and_beyond_them_wider():
    """Frames within a span of two bands or more take its exposure; the lone band's frame
    takes the middle of the exposures it and its neighbours show, its sigma half their range;
    the frame after the last band the last span's, its sigma half the range of them all."""
    clock = replace(camera(), exposure_ms=8.0, exposure_spans=SPANS)
    exposure, std = clock.exposure_at(np.arange(5))
    np.testing.assert_allclose(exposure, [12.0, 12.0, 10.0, 8.0, 8.0])
    np.testing.assert_allclose(std, [0.1, 0.1, np.hypot(2.0, 0.3), 0.05, np.hypot(2.0, 0.05)])
    np.testing.assert_allclose(camera().exposure_at(np.arange(5)), [[10.0] * 5, [0.05] * 5])  # no spans


def test_model_file_round_trip(tmp_path):
    model = SyncModel(
        "cam1",
        {
            "cam1": CameraClock("cam1", np.arange(5) * 33.4, 120, 160, row_time_ms=0.25),
            "cam2": replace(camera(True), exposure_spans=SPANS),
        },
        pd.DataFrame(
            {
                "flash": [0, 0],
                "camera": ["cam1", "cam2"],
                "event": [0, 0],
                "frame": [1, 2],
                "row": [10.5, 20.25],
                "t_frame_ms": [33.4, 40.0],
                "t_global_ms": [43.9, np.nan],
                "residual_ms": [0.01, -0.01],
                "inlier": [True, False],
            }
        ).astype(MATCHED_EVENT_COLUMNS),
    )
    save_model(model, tmp_path / "sync.json")
    loaded = load_model(tmp_path / "sync.json")
    assert loaded.reference == "cam1" and list(loaded.cameras) == ["cam1", "cam2"]
    original, again = model.camera("cam2"), loaded.camera("cam2")
    for field in ("alpha", "beta_ms", "row_time_ms", "flipped", "height", "width", "exposure_ms", "video"):
        assert getattr(again, field) == getattr(original, field)
    assert again.exposure_std_ms == 0.05 and loaded.camera("cam1").exposure_std_ms is None
    assert again.exposure_spans == SPANS and loaded.camera("cam1").exposure_spans == ()
    np.testing.assert_array_equal(again.frame_times_ms, original.frame_times_ms)
    np.testing.assert_array_equal(again.covariance, original.covariance)
    pd.testing.assert_frame_equal(loaded.events, model.events)


def test_unknown_camera_is_a_clear_error():
    model = SyncModel("cam2", {"cam2": camera()})
    with pytest.raises(FlashsyncError, match="'cam9' is not in the model"):
        model.camera("cam9")


@pytest.mark.parametrize(
    "content, message",
    [
        ("not json", "not a flashsync model file"),
        ('{"format": "other"}', "not a flashsync model file"),
        ('{"format": "flashsync.sync", "version": 99}', "version 99 is not supported"),
        (
            '{"format": "flashsync.sync", "version": 1, "reference": "a", "cameras": [{}], "events": []}',
            r'cameras\[0\]: "name" is missing',
        ),
    ],
)
def test_bad_model_files(tmp_path, content, message):
    path = tmp_path / "sync.json"
    path.write_text(content)
    with pytest.raises(FlashsyncError, match=message):
        load_model(path)
