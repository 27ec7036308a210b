"""flashsync frames: the (frame, row) each camera exposes at common ticks, against the
simulator's true clocks (an upside-down camera with dropped frames among them)."""

import numpy as np
import pandas as pd
import pytest
from cli_run import one_error_line, run

from flashsync.evaluate import clock_origin_ms, sync_errors, tick_errors_ms
from flashsync.io import load_ground_truth, load_model
from flashsync.model import CameraClock, SyncModel
from flashsync.ticks import REASONS, frame_table, model_ticks_ms, tick_times_ms


def true_exposure(truth, camera, ticks_ms):
    """From the simulator's sensor, independently of the model: the (file frame, stored row,
    reason) exposed at truth-global instants. Sensor frame ``n`` starts its readout at
    camera time ``start + n / fps``; readout row ``q`` ends its exposure ``(r0 + q)`` row
    times later; the sensor frames missing from ``frame_index`` were dropped."""
    cam, ref = truth.cameras[camera], truth.cameras[truth.reference]
    world = (np.asarray(ticks_ms) + ref.r0 * ref.sensor_row_ms) * (1 + ref.drift_ppm * 1e-6) + ref.offset_ms
    t = (world - cam.offset_ms) / (1 + cam.drift_ppm * 1e-6) - cam.start_ms - cam.r0 * cam.sensor_row_ms
    period = 1000.0 / cam.fps
    sensor = np.floor(t / period).astype(np.int64)
    q = (t - sensor * period) / cam.sensor_row_ms
    kept = np.asarray(cam.frame_index)
    reason = np.where(q > cam.height - 1, "vertical blanking", "")
    reason = np.where((reason == "") & ~np.isin(sensor, kept), "dropped frame", reason)
    reason = np.where(
        (sensor > kept[-1]) | ((sensor == kept[-1]) & (q > cam.height - 1)), "after the recording", reason
    )
    reason = np.where(sensor < kept[0], "before the recording", reason)
    frame = np.searchsorted(kept, sensor)
    row = cam.height - 1 - q if cam.flipped else q
    located = reason == ""
    return np.where(located, frame, -1), np.where(located, row, np.nan), reason


def true_model(truth) -> SyncModel:
    """The model with the simulator's own clock parameters (exact for constant drift)."""
    return SyncModel(
        truth.reference,
        {
            name: CameraClock(
                name,
                np.asarray(cam.frame_times_ms),
                cam.height,
                cam.width,
                cam.alpha,
                cam.beta_ms,
                cam.row_time_ms,
                cam.flipped,
            )
            for name, cam in truth.cameras.items()
        },
    )


@pytest.fixture(scope="module")
def truth(synced_scenario):
    return load_ground_truth(synced_scenario / "truth.json")


def test_ticks_end_is_exclusive():
    assert len(tick_times_ms(25.0, 10_000.0, 14_000.0)) == 100
    assert tick_times_ms(25.0, 10_000.0, 14_000.0)[-1] == 13_960.0
    assert len(tick_times_ms(30.0, 0.0, 1000.0)) == 30
    assert len(tick_times_ms(30.0, 0.0, 1000.1)) == 31


def test_true_clocks_give_the_simulators_frames_rows_and_reasons(truth):
    """With the simulator's clock parameters, every tick gets exactly the sensor's answer:
    the same frame and row, and the same reason where none is exposed, including the
    upside-down camera's dropped frames (two in a row and one alone)."""
    model = true_model(truth)
    ticks = model_ticks_ms(model, 1000.0)
    table = frame_table(model, ticks)
    for name in model.cameras:
        mine = table[table["camera"] == name]
        frame, row, reason = true_exposure(truth, name, ticks)
        np.testing.assert_array_equal(mine["reason"].to_numpy(dtype=object), reason)
        located = reason == ""
        np.testing.assert_array_equal(mine["frame"].to_numpy(dtype=float)[located], frame[located])
        np.testing.assert_allclose(mine["row"].to_numpy()[located], row[located], atol=1e-6)
        assert mine["row"].isna().to_numpy()[~located].all()
    counts = table.groupby("camera")["reason"].value_counts().unstack(fill_value=0)
    assert counts.loc["f", "dropped frame"] > 0 and counts.loc["r", "dropped frame"] == 0
    assert (counts[["vertical blanking", "before the recording", "after the recording"]].sum() > 0).all()


def test_rows_of_the_solved_model_are_exposed_at_their_ticks(synced_scenario, truth):
    """Each (frame, row) the solved model gives for a tick ends its exposure at that tick by
    the true clocks, to a small fraction of a row: no error beyond the model's own."""
    model = load_model(synced_scenario / "sync.json")
    table = frame_table(model, model_ticks_ms(model, 100.0))
    errors = tick_errors_ms(table, model, truth)
    sync_rms = sync_errors(model, truth, row_step=1).set_index("camera")["rms_ms"]
    for name, clock in model.cameras.items():
        error = errors[(table.loc[table["reason"] == "", "camera"] == name).to_numpy()]
        rms = float(np.sqrt(np.mean(error**2)))
        assert rms <= 1.2 * sync_rms[name] + 0.002, (name, rms, sync_rms[name])
        assert rms < 0.35 * clock.row_time_ms and np.abs(error).max() < clock.row_time_ms, name
        inside = table[
            (table["camera"] == name) & ~table["reason"].isin(["before the recording", "after the recording"])
        ]
        assert (inside["reason"] == "").mean() >= 0.8, name


def test_reasons_of_the_solved_model_match_the_sensor_away_from_boundaries(synced_scenario, truth):
    """Reasons and frames agree with the sensor except where the tick lies within the
    model's error (0.1 ms) of a frame's first or last row."""
    model = load_model(synced_scenario / "sync.json")
    ticks = model_ticks_ms(model, 1000.0)
    table = frame_table(model, ticks)
    truth_ticks = ticks - clock_origin_ms(model, truth)
    for name in model.cameras:
        mine = table[table["camera"] == name]
        frame, _, reason = true_exposure(truth, name, truth_ticks)
        early, _, early_reason = true_exposure(truth, name, truth_ticks - 0.1)
        late, _, late_reason = true_exposure(truth, name, truth_ticks + 0.1)
        clear = (early_reason == reason) & (late_reason == reason) & (early == frame) & (late == frame)
        assert clear.mean() > 0.9
        np.testing.assert_array_equal(mine["reason"].to_numpy(dtype=object)[clear], reason[clear])
        got = mine["frame"].to_numpy(dtype=float, na_value=-1)
        np.testing.assert_array_equal(got[clear], frame[clear])
    assert (table[table["camera"] == "f"]["reason"] == "dropped frame").sum() >= 3 * 25


def test_frames_command_writes_csv_and_parquet(synced_scenario, tmp_path, capsys):
    model = synced_scenario / "sync.json"
    for name in ("frames.csv", "frames.parquet"):
        code, _, err = run(
            capsys,
            "frames",
            "--model",
            model,
            "--rate",
            100,
            "--start-ms",
            1000,
            "--end-ms",
            2000,
            "-o",
            tmp_path / name,
        )
        assert code == 0, err
        assert "100 ticks x 3 cameras" in err
    table = pd.read_csv(tmp_path / "frames.csv", keep_default_na=False)
    assert list(table.columns) == ["t_global_ms", "camera", "frame", "row", "reason"]
    assert len(table) == 300 and table["t_global_ms"].iloc[0] == 1000.0
    assert set(table["reason"]) <= set(REASONS)
    assert ((table["frame"] == "") == (table["reason"] != "")).all()
    assert ((table["row"] == "") == (table["reason"] != "")).all()
    parquet = pd.read_parquet(tmp_path / "frames.parquet")
    assert str(parquet["frame"].dtype) == "Int64"
    csv = pd.read_csv(tmp_path / "frames.csv")
    pd.testing.assert_series_equal(parquet["row"], csv["row"])


@pytest.mark.parametrize(
    "options, words",
    [
        (["--rate", "0"], ["--rate 0", "positive"]),
        (["--rate", "-5"], ["--rate -5", "positive"]),
        (["--rate", "nan"], ["--rate nan", "positive"]),
        (["--rate", "100", "--start-ms", "2000", "--end-ms", "1000"], ["--end-ms 1000", "not after"]),
        (["--rate", "100", "--start-ms", "99999"], ["--start-ms 99999", "not before the end"]),
        (["--rate", "1e9"], ["--rate 1000000000", "ticks", "lower the rate"]),
    ],
)
def test_frames_refuses_bad_ticks(synced_scenario, tmp_path, capsys, options, words):
    code, _, err = run(
        capsys, "frames", "--model", synced_scenario / "sync.json", *options, "-o", tmp_path / "frames.csv"
    )
    assert code == 1
    one_error_line(err, *words)
    assert not list(tmp_path.iterdir())


def test_frames_refuses_a_missing_model_and_an_unknown_format(synced_scenario, tmp_path, capsys):
    code, _, err = run(
        capsys, "frames", "--model", tmp_path / "nope.json", "--rate", 100, "-o", tmp_path / "frames.csv"
    )
    assert code == 1
    one_error_line(err, "nope.json", "no such model file")
    code, _, err = run(
        capsys, "frames", "--model", synced_scenario / "sync.json", "--rate", 100, "-o", tmp_path / "frames.xlsx"
    )
    assert code == 1
    one_error_line(err, "frames.xlsx", "use .csv or .parquet")
    assert not list(tmp_path.iterdir())


def test_rows_round_trip_through_a_warped_clock():
    """With a drift warp (a clock whose rate changes), an upside-down readout and dropped
    frames, every located (frame, row) maps back onto its tick, and no tick is located
    in a frame the camera dropped."""
    stamps = np.delete(np.arange(300) * 40.0 + 3.0, [100, 101, 200])
    clock = CameraClock(
        "w",
        stamps,
        height=200,
        width=320,
        alpha=1.00002,
        beta_ms=-51.7,
        row_time_ms=0.19,
        flipped=True,
        drift_knots_ms=np.array([3.0, 4000.0, 8000.0, 11963.0]),
        drift_warp_ms=np.array([0.8, -0.5]),
    )
    model = SyncModel("w", {"w": clock})
    table = frame_table(model, model_ticks_ms(model, 1000.0))
    located = table[table["reason"] == ""]
    back = clock.t_global_ms(located["frame"].to_numpy(dtype=np.int64), located["row"].to_numpy())
    np.testing.assert_allclose(back, located["t_global_ms"], atol=1e-9)
    starts = clock.frame_start_ms(stamps)
    dropped = table[table["reason"] == "dropped frame"]["t_global_ms"].to_numpy()
    assert 3 * 37 <= len(dropped) <= 3 * 38  # 3 frames x 37.8 ms of visible rows
    assert np.all(
        ((dropped > starts[99]) & (dropped < starts[100])) | ((dropped > starts[197]) & (dropped < starts[198]))
    )


def test_default_grid_meets_visible_rows():
    """A 50 fps camera reading 185 of its 200 rows' time: at 100 Hz the same two instants
    of its frame recur; the default grid's phase keeps both on visible rows, where the grid
    on whole multiples of 10 ms would put every other tick in its blanking."""
    clock = CameraClock("c", 1.0 + np.arange(100) * 20.0, height=185, width=320, row_time_ms=0.1)
    model = SyncModel("c", {"c": clock})
    ticks = model_ticks_ms(model, 100.0)
    assert (frame_table(model, ticks)["reason"] == "").all() and len(ticks) == 199
    whole = frame_table(model, tick_times_ms(100.0, 10.0, 1990.0))["reason"]
    assert (whole == "vertical blanking").sum() == 99 and (whole == "").sum() == 99
