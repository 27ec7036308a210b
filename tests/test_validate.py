"""validate: cross-camera interpolation of a fast object, on synthetic tracks and the simulator."""

import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from flashsync.io import load_detections, load_ground_truth, load_homographies
from flashsync.model import CameraClock, SyncModel
from flashsync.simulation import preset, render_scenario
from tracking_adapter.validate import format_report, image_to_plane, validate

SPEED_MPS = 36.0
PX_M = 0.01  # plane metres per image px


def straight_track(model, row_by_camera, n_frames=60):
    """Detections of a puck moving along the plane's x axis at 36 m/s, and homographies.

    Camera ``c`` sees the puck at the fixed row ``row_by_camera[c]``, and its image maps
    to the plane at 1 cm/px with that row on y = 0; the puck's x (px) is its position at
    the end of exposure of its row under ``model``.

    Returns
    -------
    detections : DataFrame
    homographies : dict of str to ndarray of shape (3, 3)
    """
    tables, homographies = [], {}
    for name, clock in model.cameras.items():
        frames = np.arange(n_frames)
        y = np.full(n_frames, row_by_camera[name])
        x = clock.t_global_ms(frames, y) * SPEED_MPS / 1000 / PX_M
        tables.append(pd.DataFrame({"camera": name, "frame": frames, "x": x, "y": y}))
        homographies[name] = np.array([[PX_M, 0, 0], [0, PX_M, -PX_M * y[0]], [0, 0, 1]])
    return pd.concat(tables, ignore_index=True), homographies


@pytest.fixture
def two_cameras():
    clocks = {
        "a": CameraClock("a", np.arange(60) * 40.0, height=100, width=100000, row_time_ms=0.35),
        "b": CameraClock(
            "b", np.arange(60) * 33.3 + 5000.0, height=100, width=100000, alpha=1.002, beta_ms=-4990.0, row_time_ms=0.3
        ),
    }
    return SyncModel("a", clocks)


def test_exact_model_gives_zero_and_the_baselines_their_known_errors(two_cameras):
    detections, homographies = straight_track(two_cameras, {"a": 90.0, "b": 10.0})
    report = validate(detections, two_cameras, homographies)
    pair = {(p.interpolated, p.observed): p.stats for p in report.pairs}
    assert set(pair) == {("a", "b"), ("b", "a")}
    stats = pair["a", "b"]
    assert stats["subframe"].triples > 40 and stats["subframe"].max_m < 1e-9
    # frame level: a's rows are (90 - 49.5) * 0.35 ms late, b's (10 - 49.5) * 0.3 ms early
    offset_ms = (90 - 49.5) * 0.35 + (49.5 - 10) * 0.3
    assert stats["frame"].median_m == pytest.approx(SPEED_MPS * offset_ms / 1000, rel=1e-6)
    # no drift: b's clock error grows by 2 ms per second away from its mid-video
    frame_times = two_cameras.camera("b").frame_times_ms
    worst_ms = 0.002 * (frame_times[-1] - frame_times.mean())
    assert stats["no_drift"].max_m == pytest.approx(SPEED_MPS * worst_ms / 1000, rel=0.05)


def test_gap_limit_and_skip_reasons(two_cameras):
    detections, homographies = straight_track(two_cameras, {"a": 50.0, "b": 50.0})
    detections = detections[(detections.camera == "b") | (detections.frame % 4 == 0)]
    default = validate(detections, two_cameras, homographies)  # 2.5 x 40 ms < 160 ms
    a_to_b, b_to_a = (pair.stats["subframe"] for pair in default.pairs)
    assert (a_to_b.triples, a_to_b.median_m, a_to_b.skipped) == (0, None, {"A's gap over the limit": 60})
    # a's 15 detections, 0 ... 56: the first is before b's first, 52 and 56 after b's last
    assert (b_to_a.triples, b_to_a.skipped) == (12, {"outside A's track": 3})
    wide = validate(detections, two_cameras, homographies, max_gap_ms=170.0)
    a_to_b = wide.pairs[0].stats["subframe"]
    assert (a_to_b.triples, a_to_b.skipped) == (60, {}) and a_to_b.max_m < 1e-9


def test_objects_are_interpolated_with_their_own_track(two_cameras):
    one, homographies = straight_track(two_cameras, {"a": 30.0, "b": 70.0})
    other = one.assign(x=one.x + 5000.0)  # 50 m further along
    detections = pd.concat([one.assign(object=1), other.assign(object=2)], ignore_index=True)
    report = validate(detections.sample(frac=1.0, random_state=0), two_cameras, homographies)
    assert all(p.stats["subframe"].max_m < 1e-9 for p in report.pairs)
    assert (
        validate(detections.rename(columns={"object": "id"}), two_cameras, homographies)
        .pairs[0]
        .stats["subframe"]
        .max_m
        < 1e-9
    )


def test_unusable_detections_are_counted(two_cameras):
    detections, homographies = straight_track(two_cameras, {"a": 30.0, "b": 70.0})
    detections = detections.astype({"x": object})
    detections.loc[0, "x"] = "n/a"
    detections.loc[1, "frame"] = 999
    report = validate(detections, two_cameras, {"a": homographies["a"]})
    assert report.not_used == {
        "frame past the end of the video": 1,
        "x missing or not a number": 1,
        "camera without homography": 60,
    }
    assert report.pairs == []


@pytest.mark.filterwarnings("error")
def test_an_infinite_x_is_counted_as_not_a_number(two_cameras):
    """Not as beyond the horizon (where an infinite point lands, with a RuntimeWarning)."""
    detections, homographies = straight_track(two_cameras, {"a": 30.0, "b": 70.0})
    detections.loc[0, "x"] = np.inf
    report = validate(detections, two_cameras, homographies)
    assert report.not_used == {"x missing or not a number": 1}


def test_points_as_shown_of_a_turned_camera_are_timed_by_their_stored_rows(two_cameras):
    """b's video is stored turned -90 degrees for display; its detections and homography in
    the picture as shown (x' = H - 1 - y, y' = x) give, with ``as_shown``, the report of the
    stored pixels (b's homography has a horizon far above the image: the shown picture's
    bottom is its ground side)."""
    detections, homographies = straight_track(two_cameras, {"a": 90.0, "b": 10.0})
    homographies["b"][2] = [0.0, 1e-4, 1.0]
    turned = replace(two_cameras, cameras={**two_cameras.cameras})
    turned.cameras["b"] = replace(two_cameras.camera("b"), display_rotation_deg=-90)
    height = turned.camera("b").height
    is_b = detections.camera == "b"
    shown = detections.copy()
    shown.loc[is_b, "x"], shown.loc[is_b, "y"] = height - 1 - detections.y[is_b], detections.x[is_b]
    shown_to_stored = np.array([[0.0, 1, 0], [-1, 0, height - 1], [0, 0, 1]])
    shown_homographies = {**homographies, "b": homographies["b"] @ shown_to_stored}
    expected = format_report(validate(detections, turned, homographies))
    assert format_report(validate(shown, turned, shown_homographies, as_shown=True)) == expected
    assert format_report(validate(shown, turned, shown_homographies)) != expected


def test_image_to_plane():
    homography = np.array([[2.0, 0, 1], [0, 3, 0], [0, 0, 0.5]])
    np.testing.assert_allclose(image_to_plane(np.array([1.0, 0]), np.array([1.0, 2]), homography), [[6, 6], [2, 12]])


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """The simulator's tiny scenario: two cameras (25 and 30 fps), a puck at 36 m/s."""
    folder = tmp_path_factory.mktemp("tiny")
    render_scenario(preset("tiny"), folder)
    return folder


def true_model(truth, frame_times="frame_times_ms"):
    """The ground-truth sync model (true frame times unless told otherwise)."""
    return SyncModel(
        truth.reference,
        {
            name: CameraClock(
                name,
                np.asarray(getattr(camera, frame_times)),
                camera.height,
                camera.width,
                camera.alpha,
                camera.beta_ms,
                camera.row_time_ms,
                camera.flipped,
                exposure_ms=camera.exposure_ms,
            )
            for name, camera in truth.cameras.items()
        },
    )


def test_simulated_puck_with_the_true_model(tiny):
    truth = load_ground_truth(tiny)
    model = true_model(truth)
    detections = load_detections(tiny / "detections.csv")
    for name in truth.cameras:  # the model is the truth
        mine = detections[detections.camera == name]
        np.testing.assert_allclose(
            model.camera(name).t_global_ms(mine.frame, mine.y),
            truth.global_time_ms(name, mine.frame.to_numpy(), mine.y.to_numpy()),
            atol=1e-4,
        )
    report = validate(detections, model, load_homographies(tiny / "homographies.json"))
    assert report.instant == "t_center_ms"
    assert len(report.pairs) == 2
    for pair in report.pairs:
        subframe, frame = pair.stats["subframe"], pair.stats["frame"]
        assert subframe.triples > 30
        assert subframe.median_m < 0.002  # detections rounded to 1e-3 px
        assert 5 * subframe.p95_m < frame.median_m
        assert 0.1 < frame.p95_m < 0.8  # half a readout at 36 m/s
    json.dumps(report.to_dict())


def test_simulated_timing_error_shows_as_speed_times_error(tiny):
    truth = load_ground_truth(tiny)
    model = true_model(truth)
    cam2 = model.camera("cam2")
    model.cameras["cam2"] = replace(cam2, beta_ms=cam2.beta_ms + 2.0)
    report = validate(load_detections(tiny / "detections.csv"), model, load_homographies(tiny / "homographies.json"))
    for pair in report.pairs:
        assert pair.stats["subframe"].median_m == pytest.approx(SPEED_MPS * 0.002, rel=0.15)


def test_report_text(tiny):
    truth = load_ground_truth(tiny)
    detections = load_detections(tiny / "detections.csv")
    report = validate(detections, true_model(truth, "stamps_ms"), load_homographies(tiny / "homographies.json"))
    text = format_report(report)
    for pair in report.pairs:
        line = next(line for line in text.splitlines() if line.startswith(f"{pair.interpolated} -> {pair.observed} "))
        numbers = line.split()[3:]
        assert int(numbers[0]) == pair.stats["subframe"].triples
        assert float(numbers[1]) == pytest.approx(pair.stats["subframe"].median_m, abs=5e-4)
        assert float(numbers[4]) == pytest.approx(pair.stats["frame"].median_m, abs=5e-4)
        assert len(numbers) == 10


def test_points_beyond_a_homographys_horizon_are_left_out_and_far_ones_fit_the_table(two_cameras):
    """Camera b's homography has its horizon at row 50: its detections above are behind the
    camera and left out with a reason; those just below map 10 km away, and the table's
    columns still line up."""
    detections, homographies = straight_track(two_cameras, {"a": 90.0, "b": 10.0})
    homographies["b"] = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.01, -0.5]])  # w = 0.01 y - 0.5
    rows = np.where(np.arange(60) % 2 == 0, 40.0, 50.01)
    detections.loc[detections["camera"] == "b", "y"] = rows
    report = validate(detections, two_cameras, homographies)
    assert report.not_used == {"beyond the horizon of its camera's homography": 30}
    lines = format_report(report).splitlines()
    table = [line for line in lines if line.startswith(("a -> b", "b -> a"))]
    assert any("e+" in line for line in table)  # metres past 10 km in three digits
    assert len({len(line) for line in table}) == 1 and "beyond the horizon" in lines[-1]
