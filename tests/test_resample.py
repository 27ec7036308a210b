"""flashsync resample: tracks interpolated at common ticks, against the simulated puck path."""

import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from cli_run import one_error_line, run

from flashsync.evaluate import clock_origin_ms
from flashsync.io import load_detections, load_ground_truth, load_homographies, load_model
from flashsync.simulation.truth import puck_image_px
from flashsync.ticks import model_ticks_ms
from tracking_adapter.interpolate import interpolate_track
from tracking_adapter.resample import TRACK_COLUMNS, resample


def true_puck_px(folder, model, tracks):
    """Where the simulated puck is in each row's camera image at the row's tick, px."""
    truth = load_ground_truth(folder / "truth.json")
    homographies = load_homographies(folder / "homographies.json")
    instants = tracks["t_global_ms"].to_numpy() - clock_origin_ms(model, truth)
    image = np.full((len(tracks), 2), np.nan)
    for name, homography in homographies.items():
        mine = (tracks["camera"] == name).to_numpy()
        image[mine] = puck_image_px(truth, homography, instants[mine])
    return image


def test_interpolate_track_between_close_detections_only():
    times = np.array([40.0, 0.0, 80.0, 200.0])  # any order
    values = np.array([[4.0, 40.0], [0.0, 0.0], [8.0, 80.0], [20.0, 200.0]])
    sample = interpolate_track(times, values, np.array([-5.0, 0.0, 10.0, 80.0, 150.0, 200.0, 201.0]), max_gap_ms=50.0)
    np.testing.assert_allclose(sample.values[[1, 2, 3, 5]], [[0, 0], [1, 10], [8, 80], [20, 200]])
    assert np.isnan(sample.values[[0, 4, 6]]).all()
    np.testing.assert_array_equal(sample.status, [1, 0, 0, 0, 3, 0, 2])
    np.testing.assert_allclose(sample.nearest_ms, [5, 0, 10, 0, 50, 0, 1])
    single = interpolate_track(np.array([5.0]), np.array([[1.0]]), np.array([4.0, 5.0, 6.0]), 50.0)
    np.testing.assert_array_equal(single.status, [1, 2, 2])


@pytest.fixture(scope="module")
def resampled(synced_scenario):
    model = load_model(synced_scenario / "sync.json")
    detections = load_detections(synced_scenario / "detections.csv")
    return model, detections, resample(detections, model, model_ticks_ms(model, 100.0))


def test_points_as_shown_of_a_turned_camera_resample_as_their_stored_pixels(resampled):
    """Camera r stored upside down for display: its detections in the picture as shown
    (x' = W - 1 - x, y' = H - 1 - y) resample with ``as_shown`` to the stored ones' ticks
    and gaps, at the shown positions."""
    model, detections, result = resampled
    turned = replace(model, cameras={**model.cameras, "r": replace(model.camera("r"), display_rotation_deg=180)})
    clock, mine = turned.camera("r"), detections["camera"] == "r"
    shown = detections.copy()
    shown.loc[mine, "x"] = clock.width - 1 - detections.loc[mine, "x"]
    shown.loc[mine, "y"] = clock.height - 1 - detections.loc[mine, "y"]
    ticks = model_ticks_ms(model, 100.0)
    again = resample(shown, turned, ticks, as_shown=True).tracks
    expected = result.tracks.copy()
    on_r = expected["camera"] == "r"
    expected.loc[on_r, "x"] = clock.width - 1 - expected.loc[on_r, "x"]
    expected.loc[on_r, "y"] = clock.height - 1 - expected.loc[on_r, "y"]
    pd.testing.assert_frame_equal(again, expected)
    assert not resample(shown, turned, ticks).tracks["gap_ms"].equals(expected["gap_ms"])


def test_resampled_positions_follow_the_simulated_puck(synced_scenario, resampled):
    """Interpolated at mid-exposure instants, every camera's track lies on the true puck path
    to a few hundredths of a pixel (end-of-exposure instants would be 0.3-1.2 px off)."""
    model, _, result = resampled
    tracks = result.tracks
    assert list(tracks.columns) == list(TRACK_COLUMNS)
    interpolated = tracks[tracks["reason"] == ""]
    error = np.hypot(*(interpolated[["x", "y"]].to_numpy() - true_puck_px(synced_scenario, model, interpolated)).T)
    for name in model.cameras:
        mine = error[(interpolated["camera"] == name).to_numpy()]
        assert len(mine) > 150, name
        assert np.median(mine) < 0.1 and np.percentile(mine, 90) < 0.25 and mine.max() < 1.0, (
            name,
            np.median(mine),
            np.percentile(mine, 90),
            mine.max(),
        )


def test_ticks_are_refused_outside_tracks_and_over_dropped_frames(resampled):
    """No extrapolation: ticks before or after a track, and in the gap two dropped frames
    of the upside-down camera leave (3 periods > 2.5), get no position; the one-frame drop
    (2 periods) is interpolated over. gap_ms is the distance to the nearest detection."""
    model, detections, result = resampled
    tracks = result.tracks
    refused = tracks[tracks["reason"] != ""]
    assert refused[["x", "y"]].isna().all().all() and tracks.loc[tracks["reason"] == "", "x"].notna().all()
    assert set(refused["reason"]) == {"before the track", "after the track", "gap over the limit"}
    f = model.camera("f")
    centre = {
        frame: float(f.t_global_ms(frame, y) - f.exposure_ms / 2)
        for frame, y in detections[detections["camera"] == "f"][["frame", "y"]].itertuples(index=False)
    }
    in_f = tracks[tracks["camera"] == "f"]
    two_dropped = in_f[(in_f["t_global_ms"] > centre[44]) & (in_f["t_global_ms"] < centre[45])]
    one_dropped = in_f[(in_f["t_global_ms"] > centre[57]) & (in_f["t_global_ms"] < centre[58])]
    assert len(two_dropped) >= 9 and (two_dropped["reason"] == "gap over the limit").all()
    assert len(one_dropped) >= 6 and (one_dropped["reason"] == "").all()
    nearest = np.minimum(two_dropped["t_global_ms"] - centre[44], centre[45] - two_dropped["t_global_ms"])
    np.testing.assert_allclose(two_dropped["gap_ms"], nearest, atol=1e-9)
    for (camera, _), track in tracks.groupby(["camera", "object"]):
        first = track["reason"].eq("").idxmax()
        assert (track.loc[: first - 1, "reason"].isin(["before the track", ""])).all(), camera
        assert track["reason"].iloc[0] == "before the track" and track["reason"].iloc[-1] == "after the track"


def test_resample_command_on_raw_and_restamped_detections(synced_scenario, tmp_path, capsys):
    model, detections = synced_scenario / "sync.json", synced_scenario / "detections.csv"
    code, _, err = run(capsys, "resample", detections, "--model", model, "--rate", 50, "-o", tmp_path / "tracks.csv")
    assert code == 0, err
    assert "3 tracks" in err and "interpolated" in err
    raw = pd.read_csv(tmp_path / "tracks.csv", keep_default_na=False)
    assert list(raw.columns) == list(TRACK_COLUMNS)
    code, _, err = run(capsys, "frames", "--model", model, "--rate", 50, "-o", tmp_path / "frames.csv")
    assert code == 0, err
    ticks = pd.read_csv(tmp_path / "frames.csv")["t_global_ms"].unique()
    assert np.isin(raw["t_global_ms"].unique(), ticks).all()  # the same default instants
    code, _, err = run(capsys, "restamp", detections, "--model", model, "-o", tmp_path / "stamped.csv")
    assert code == 0, err
    code, _, err = run(
        capsys, "resample", tmp_path / "stamped.csv", "--model", model, "--rate", 50, "-o", tmp_path / "again.parquet"
    )
    assert code == 0, err
    again = pd.read_parquet(tmp_path / "again.parquet")
    pd.testing.assert_frame_equal(
        again[["t_global_ms", "x", "y", "gap_ms"]],
        pd.read_csv(tmp_path / "tracks.csv")[["t_global_ms", "x", "y", "gap_ms"]],
    )


def test_resample_refuses_bad_input(synced_scenario, tmp_path, capsys):
    model, detections = synced_scenario / "sync.json", synced_scenario / "detections.csv"
    table = pd.read_csv(detections)
    table.loc[3, "camera"] = "cam9"
    table.to_csv(tmp_path / "unknown.csv", index=False)
    document = json.loads(model.read_text())
    document["cameras"][1]["exposure_ms"] = None
    (tmp_path / "no-exposure.json").write_text(json.dumps(document))
    cases = [
        ([tmp_path / "unknown.csv", "--model", model, "--rate", 100], ["unknown.csv", "cam9", "not in the model"]),
        ([detections, "--model", tmp_path / "nope.json", "--rate", 100], ["nope.json", "no such model file"]),
        ([detections, "--model", model, "--rate", 0], ["--rate 0", "positive"]),
        ([detections, "--model", model, "--rate", "nan"], ["--rate nan", "positive"]),
        ([detections, "--model", model, "--rate", 100, "--start-ms", 500, "--end-ms", 400], ["not after"]),
        ([detections, "--model", model, "--rate", 100, "--max-gap-ms", 0], ["--max-gap-ms 0", "positive"]),
        (
            [detections, "--model", tmp_path / "no-exposure.json", "--rate", 100],
            ["camera f", "exposure unknown", "--exposure f=MS"],
        ),
    ]
    for options, words in cases:
        code, _, err = run(capsys, "resample", *options, "-o", tmp_path / "out" / "tracks.csv")
        assert code == 1, options
        one_error_line(err, *words)
    assert not (tmp_path / "out").exists()
    code, _, err = run(
        capsys,
        "resample",
        detections,
        "--model",
        tmp_path / "no-exposure.json",
        "--rate",
        100,
        "--exposure",
        "f=8",
        "-o",
        tmp_path / "out" / "tracks.csv",
    )
    assert code == 0, err


def test_objects_are_tracked_apart_and_every_left_out_detection_is_counted(resampled):
    model, detections, _ = resampled
    table = detections[detections["camera"] == "r"].head(12).drop(columns="object")
    table = table.assign(id=[7.0] * 6 + [8.0] * 5 + [np.nan])  # read as floats: a gap
    table = pd.concat([table, table.iloc[[2]]], ignore_index=True)  # 7 twice in one frame
    result = resample(table, model, model_ticks_ms(model, 100.0))
    assert set(result.tracks["object"]) == {7, 8}
    assert result.not_used == {"object id missing": 1, "another detection of the object in the frame": 1}
    interpolated = result.tracks[result.tracks["reason"] == ""]
    assert interpolated.groupby("object")["t_global_ms"].agg(["min", "max"]).diff()["min"].iloc[1] > 0


def test_a_row_whose_y_is_text_is_counted_not_a_traceback(synced_scenario, tmp_path, capsys):
    table = pd.read_csv(synced_scenario / "detections.csv").astype({"y": object})
    table.loc[2, "y"] = "abc"
    table.to_csv(tmp_path / "text.csv", index=False)
    model, output = synced_scenario / "sync.json", tmp_path / "tracks.csv"
    code, _, err = run(capsys, "resample", tmp_path / "text.csv", "--model", model, "--rate", 100, "-o", output)
    assert code == 0 and "Traceback" not in err, err
    assert "detections not used: 1 y not a number" in err


@pytest.mark.parametrize(
    "xs, not_used",
    [([np.inf], {"x missing or not a number": 1}), ([1e308, -1e308], {"x beyond 1e+09 px": 2})],
    ids=["inf", "1e308 then -1e308"],
)
def test_an_infinite_or_huge_x_is_counted_not_interpolated(resampled, xs, not_used):
    """x = inf is left out as not a number, and x beyond 1e9 px as beyond any image (between 1e308
    and -1e308 the difference overflowed to -inf): no infinite, empty or absurd x is written as
    interpolated."""
    model, detections, _ = resampled
    table = detections[detections["camera"] == "r"].head(6).copy()
    table.loc[table.index[2 : 2 + len(xs)], "x"] = xs
    result = resample(table, model, model_ticks_ms(model, 100.0))
    assert result.not_used == not_used
    interpolated = result.tracks[result.tracks["reason"] == ""]
    assert len(interpolated) and np.isfinite(interpolated[["x", "y"]].to_numpy()).all()
    kept = table["x"].drop(table.index[2 : 2 + len(xs)])
    assert interpolated["x"].between(kept.min(), kept.max()).all()
