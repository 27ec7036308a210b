"""restamp: the detections contract (rows, columns, order, values kept), formats, bad rows."""

import io
from dataclasses import replace

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from flashsync.errors import FlashsyncError
from flashsync.io import load_detections, load_mot, save_detections
from flashsync.model import CameraClock, SyncModel
from tracking_adapter import format_summary, restamp, restamp_file

N_FRAMES = 50


@pytest.fixture
def model():
    """cam1: reference, 100 rows; cam2: flipped, drifting, 80 rows, exposure 4 ± 0.06 ms."""
    cam1 = CameraClock(
        "cam1",
        np.arange(N_FRAMES) * 40.0 + 3.0,
        height=100,
        width=160,
        row_time_ms=0.35,
        covariance=np.diag([0.0, 0.01, 1e-6]),
    )
    cam2 = CameraClock(
        "cam2",
        np.arange(N_FRAMES) * 33.0 + 1000.0,
        height=80,
        width=120,
        alpha=1.0001,
        beta_ms=-950.5,
        row_time_ms=0.4,
        flipped=True,
        covariance=np.diag([1e-10, 0.04, 4e-6]),
        exposure_ms=4.0,
        exposure_std_ms=0.06,
    )
    return SyncModel("cam1", {"cam1": cam1, "cam2": cam2})


def expected_time(camera, frame, y):
    """The model written out by hand (not via CameraClock)."""
    if camera == "cam1":
        return 3.0 + 40.0 * frame + 0.35 * y
    return 1.0001 * (1000.0 + 33.0 * frame) - 950.5 + 0.4 * (79 - y)


CSV_TEXT = (
    "camera,frame,x,y,object,note\n"
    'cam1,0,10.50,20.250,7,"quoted, with comma"\n'
    "cam2,3,1e2,0,007,\n"
    'cam1,12,  5 ,99.5,a,"say ""hi"""\n'
    "cam2,49,0.000,79.0,8,last frame\n"
)


def write(path, text):
    path.write_bytes(text.encode())
    return path


def split_output(path, n_new):
    """Output lines, each cut into (original text, new values)."""
    lines = path.read_bytes().decode().split("\n")
    assert lines[-1] == ""
    return [line.rsplit(",", n_new) for line in lines[:-1]]


def test_csv_to_csv_keeps_every_byte_and_adds_times(tmp_path, model):
    source = write(tmp_path / "dets.csv", CSV_TEXT)
    summary = restamp_file(source, tmp_path / "out.csv", model)
    rows = split_output(tmp_path / "out.csv", 3)
    assert [row[0] for row in rows] == CSV_TEXT.split("\n")[:-1]
    assert rows[0][1:] == ["t_global_ms", "t_center_ms", "restamp_error"]
    expected = [("cam1", 0, 20.25), ("cam2", 3, 0.0), ("cam1", 12, 99.5), ("cam2", 49, 79.0)]
    for row, (camera, frame, y) in zip(rows[1:], expected):
        assert float(row[1]) == pytest.approx(expected_time(camera, frame, y), abs=1e-9)
        assert row[3] == ""
    assert float(rows[2][2]) == pytest.approx(expected_time("cam2", 3, 0.0) - 2.0, abs=1e-9)
    assert rows[1][2] == ""  # cam1 has no exposure
    assert (summary.rows, summary.stamped, summary.failed) == (4, 4, {})


def test_crlf_blank_lines_kept_no_final_newline_and_tiny_blocks(tmp_path, model):
    text = CSV_TEXT.replace("\n", "\r\n").replace("cam2,3,", "\r\ncam2,3,").rstrip("\r\n")
    source = write(tmp_path / "dets.csv", text)
    restamp_file(source, tmp_path / "big.csv", model)
    restamp_file(source, tmp_path / "small.csv", model, block_bytes=16)
    out = (tmp_path / "small.csv").read_bytes()
    assert out == (tmp_path / "big.csv").read_bytes()
    lines = out.decode().split("\r\n")
    kept = [line.rsplit(",", 3)[0] for line in lines[:-1]]
    assert kept == text.split("\r\n")  # byte for byte: the blank line too
    assert "\n" not in out.decode().replace("\r\n", "")


def test_byte_order_mark_quoted_header_and_header_only(tmp_path, model):
    text = '\ufeff"camera","frame","y"\n"cam1","2","3"\n'
    source = write(tmp_path / "in.csv", text)
    restamp_file(source, tmp_path / "out.csv", model)
    assert (tmp_path / "out.csv").read_text(encoding="utf-8") == (
        f'\ufeff"camera","frame","y",t_global_ms,t_center_ms,restamp_error\n'
        f'"cam1","2","3",{expected_time("cam1", 2, 3.0)!r},,\n'
    )
    source = write(tmp_path / "empty.csv", "camera,frame,y\n")
    assert restamp_file(source, tmp_path / "out.csv", model).rows == 0
    assert (tmp_path / "out.csv").read_text() == ("camera,frame,y,t_global_ms,t_center_ms,restamp_error\n")


def test_rows_without_any_camera_name_and_an_empty_table(tmp_path, model):
    """No camera to look up (every name blank, or no rows): each row kept with its reason."""
    source = write(tmp_path / "blank.csv", "camera,frame,y\n,2,3\n,4,5\n")
    summary = restamp_file(source, tmp_path / "out.csv", model)
    assert (summary.rows, summary.failed) == (2, {"camera missing": 2})
    empty = pd.DataFrame({"camera": pd.Series([], dtype="str"), "frame": [], "y": []})
    assert list(restamp(empty, model)["restamp_error"]) == []


def test_a_whole_frame_number_beyond_2_53_is_past_the_end(tmp_path, model):
    """Not an error for the whole file (nor a traceback where the table is read whole)."""
    frames = pa.array([2, 2**64 - 1], pa.uint64())
    pq.write_table(pa.table({"camera": ["cam1", "cam1"], "frame": frames, "y": [3.0, 3.0]}), tmp_path / "big.parquet")
    summary = restamp_file(tmp_path / "big.parquet", tmp_path / "out.csv", model)
    assert (summary.stamped, summary.failed) == (1, {"frame past the end of the video": 1})
    stamped = restamp(pd.DataFrame({"camera": ["cam1"], "frame": [2**53 + 1], "y": [3.0]}), model)
    assert list(stamped["restamp_error"]) == ["frame past the end of the video"]


def test_durations_are_not_frame_numbers(tmp_path, model):
    """A duration of 3 s is not frame 3 (as timestamps and dates are not frames either)."""
    frames = pa.array([3, 4], pa.duration("s"))
    pq.write_table(pa.table({"camera": ["cam1", "cam1"], "frame": frames, "y": [3.0, 3.0]}), tmp_path / "d.parquet")
    summary = restamp_file(tmp_path / "d.parquet", tmp_path / "out.csv", model)
    assert (summary.stamped, summary.failed) == (0, {"frame not a number": 2})


def test_dataframe_contract(model):
    detections = pd.DataFrame(
        {
            "object": pd.Categorical(["a", "b", "a"]),
            "y": [10.0, 20.5, 79.0],
            "camera": ["cam1", "cam2", "cam2"],
            "frame": np.array([1, 2, 3], dtype=np.int32),
            "flag": [True, False, True],
        },
        index=[10, 5, 7],
    )
    before = detections.copy()
    stamped = restamp(detections, model, with_std=True)
    pd.testing.assert_frame_equal(detections, before)  # input untouched
    pd.testing.assert_frame_equal(stamped[list(detections.columns)], detections)
    assert list(stamped.columns) == [
        *detections.columns,
        "t_global_ms",
        "t_global_std_ms",
        "t_center_ms",
        "t_center_std_ms",
        "restamp_error",
    ]
    expected = [expected_time(c, f, y) for c, f, y in zip(stamped.camera, stamped.frame, stamped.y)]
    np.testing.assert_allclose(stamped.t_global_ms, expected, atol=1e-9)
    std_cam1 = np.sqrt(0.01 + 1e-6 * 10.0**2)
    assert stamped.t_global_std_ms.iloc[0] == pytest.approx(std_cam1)
    # mid-exposure: half the exposure's sigma on top; none where the exposure is unknown (cam1)
    assert np.isnan(stamped.t_center_std_ms.iloc[0])
    np.testing.assert_allclose(stamped.t_center_std_ms.iloc[1:], np.hypot(stamped.t_global_std_ms.iloc[1:], 0.03))
    assert stamped.restamp_error.isna().all()


def test_exposure_given_by_caller_overrides_model(model):
    detections = pd.DataFrame({"camera": ["cam1", "cam2"], "frame": [0, 0], "y": [0.0, 0.0]})
    stamped = restamp(detections, model, exposure_ms={"cam1": 10.0, "cam2": 6.0}, with_std=True)
    np.testing.assert_allclose(stamped.t_global_ms - stamped.t_center_ms, [5.0, 3.0])
    np.testing.assert_allclose(stamped.t_center_std_ms, stamped.t_global_std_ms)  # a caller's exposure is exact
    with pytest.raises(FlashsyncError, match="cam9"):
        restamp(detections, model, exposure_ms={"cam9": 1.0})


BAD_ROWS = {
    "nan y": ("cam1", "3", "NaN", "y missing"),
    "empty y": ("cam1", "3", "", "y missing"),
    "text y": ("cam1", "3", "left", "y not a number"),
    "y below the image": ("cam1", "3", "-3", "y outside the image rows"),
    "y past the last row": ("cam2", "3", "80", "y outside the image rows"),
    "negative frame": ("cam1", "-1", "5", "frame negative"),
    "frame past the end": ("cam2", str(N_FRAMES), "5", "frame past the end of the video"),
    "fractional frame": ("cam1", "2.5", "5", "frame not an integer"),
    "text frame": ("cam1", "three", "5", "frame not a number"),
    "empty frame": ("cam1", "", "5", "frame missing"),
    "unknown camera": ("cam9", "3", "5", "unknown camera"),
    "empty camera": ("", "3", "5", "camera missing"),
}


@pytest.mark.parametrize("route", ["dataframe", "csv", "csv->parquet", "parquet->csv"])
@pytest.mark.parametrize("case", list(BAD_ROWS))
def test_bad_row_is_kept_with_a_reason(tmp_path, model, case, route):
    camera, frame, y, reason = BAD_ROWS[case]
    text = f"camera,frame,y,id\ncam1,1,2.5,a\n{camera},{frame},{y},b\ncam2,4,7,c\n"
    if route == "dataframe":
        out = restamp(pd.read_csv(io.StringIO(text), dtype=str, keep_default_na=False), model)
    else:
        source = write(tmp_path / "in.csv", text)
        if route == "parquet->csv":
            source = tmp_path / "in.parquet"
            pd.read_csv(tmp_path / "in.csv", dtype=str, keep_default_na=False).to_parquet(source)
        target = tmp_path / ("out.parquet" if route == "csv->parquet" else "out.csv")
        summary = restamp_file(source, target, model)
        assert summary.failed == {reason: 1} and summary.rows == 3
        out = pd.read_parquet(target) if target.suffix == ".parquet" else pd.read_csv(target, dtype={"id": str})
    assert list(out["id"]) == ["a", "b", "c"]
    assert pd.isna(out.t_global_ms.iloc[1]) and out.restamp_error.iloc[1] == reason
    assert out.t_global_ms.iloc[0] == pytest.approx(expected_time("cam1", 1, 2.5))
    assert out.t_global_ms.iloc[2] == pytest.approx(expected_time("cam2", 4, 7.0))
    assert out.restamp_error.iloc[[0, 2]].isna().all()


AS_SHOWN_BAD_ROWS = {
    "nan x": ("NaN", "x missing"),
    "text x": ("left", "x not a number"),
    "x past the shown picture": ("80", "x outside the shown image"),
}


@pytest.mark.parametrize("route", ["dataframe", "csv"])
@pytest.mark.parametrize("case", list(AS_SHOWN_BAD_ROWS))
def test_as_shown_a_camera_turned_sideways_takes_its_row_from_x(tmp_path, model, case, route):
    """cam2 stored turned 90 degrees counterclockwise for display: given as shown, a point's
    stored row is its x (its y, here text, is not needed); cam1, not turned, needs no x."""
    x, reason = AS_SHOWN_BAD_ROWS[case]
    turned = SyncModel("cam1", {**model.cameras, "cam2": replace(model.camera("cam2"), display_rotation_deg=90)})
    text = f"camera,frame,x,y,id\ncam1,1,,2.5,a\ncam2,4,{x},left,b\ncam2,4,7,left,c\n"
    if route == "dataframe":
        out = restamp(pd.read_csv(io.StringIO(text), dtype=str, keep_default_na=False), turned, as_shown=True)
    else:
        summary = restamp_file(write(tmp_path / "in.csv", text), tmp_path / "out.csv", turned, as_shown=True)
        assert summary.failed == {reason: 1}
        out = pd.read_csv(tmp_path / "out.csv")
    assert pd.isna(out.t_global_ms.iloc[1]) and out.restamp_error.iloc[1] == reason
    assert out.t_global_ms.iloc[0] == pytest.approx(expected_time("cam1", 1, 2.5))
    assert out.t_global_ms.iloc[2] == pytest.approx(expected_time("cam2", 4, 7.0))
    assert out.restamp_error.iloc[[0, 2]].isna().all()


def test_numeric_text_with_spaces_is_parsed(tmp_path, model):
    source = write(tmp_path / "in.csv", "camera,frame,y\ncam1, 4 ,1e1\n")
    restamp_file(source, tmp_path / "out.csv", model)
    assert (tmp_path / "out.csv").read_text().splitlines()[1] == (f"cam1, 4 ,1e1,{expected_time('cam1', 4, 10.0)!r},,")


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_missing_columns_name_the_file_and_the_columns(tmp_path, model, suffix):
    source = tmp_path / f"tracks{suffix}"
    table = pd.DataFrame({"camera": ["cam1"], "x": [1.0]})
    table.to_csv(source, index=False) if suffix == ".csv" else table.to_parquet(source)
    with pytest.raises(FlashsyncError, match=rf"tracks\{suffix}: missing columns frame, y"):
        restamp_file(source, tmp_path / "out.csv", model)
    assert not (tmp_path / "out.csv").exists()
    with pytest.raises(FlashsyncError, match="mine.csv: missing columns frame, y"):
        restamp(table, model, source="mine.csv")


def test_duplicate_column_names_are_refused(tmp_path, model):
    source = write(tmp_path / "in.csv", "camera,frame,y,y\ncam1,1,1,2\n")
    with pytest.raises(FlashsyncError, match="in.csv: duplicate column names y"):
        restamp_file(source, tmp_path / "out.csv", model)


def test_already_stamped_input_is_refused(tmp_path, model):
    source = write(tmp_path / "in.csv", "camera,frame,y,t_global_ms\ncam1,1,1,5\n")
    with pytest.raises(FlashsyncError, match="already has column t_global_ms"):
        restamp_file(source, tmp_path / "out.csv", model)


def test_malformed_row_in_a_late_block_leaves_no_output(tmp_path, model):
    text = "camera,frame,y\n" + "cam1,1,2\n" * 200 + "cam1,1,2,extra\n"
    source = write(tmp_path / "in.csv", text)
    for target in ("out.csv", "out.parquet"):
        with pytest.raises(FlashsyncError, match="in.csv"):
            restamp_file(source, tmp_path / target, model, block_bytes=256)
        assert not (tmp_path / target).exists()
    assert [p.name for p in tmp_path.iterdir()] == ["in.csv"]


def test_parquet_in_and_out_keeps_types(tmp_path, model):
    table = pa.table(
        {
            "camera": pa.array(["cam2", "cam1", "cam1"]).dictionary_encode(),
            "frame": pa.array([0, 5, 60], pa.int16()),
            "y": pa.array([1.5, None, 3.0], pa.float32()),
            "score": pa.array([0.25, 0.5, 0.75]),
            "when": pa.array([1, 2, 3], pa.timestamp("ms")),
        }
    )
    pq.write_table(table, tmp_path / "in.parquet")
    summary = restamp_file(tmp_path / "in.parquet", tmp_path / "out.parquet", model)
    out = pq.read_table(tmp_path / "out.parquet")
    assert out.select(table.column_names).equals(table)
    assert out.column_names[len(table.column_names) :] == ["t_global_ms", "t_center_ms", "restamp_error"]
    assert out.column("t_global_ms")[0].as_py() == pytest.approx(expected_time("cam2", 0, 1.5))
    assert out.column("restamp_error").to_pylist() == [None, "y missing", "frame past the end of the video"]
    assert format_summary(summary) == (
        f"{tmp_path / 'in.parquet'} -> {tmp_path / 'out.parquet'}: 3 rows, 1 stamped, "
        "2 not stamped (1 frame past the end of the video, 1 y missing)"
    )


def test_read_restamp_write_round_trip(tmp_path, model):
    source = write(tmp_path / "dets.csv", CSV_TEXT)
    stamped = restamp(load_detections(source), model)
    save_detections(stamped, tmp_path / "out.parquet")
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "out.parquet"), stamped)
    with pytest.raises(FlashsyncError, match="out.txt"):
        save_detections(stamped, tmp_path / "out.txt")


def test_csv_to_parquet_keeps_the_text(tmp_path, model):
    source = write(tmp_path / "dets.csv", CSV_TEXT)
    restamp_file(source, tmp_path / "out.parquet", model, block_bytes=64)
    out = pd.read_parquet(tmp_path / "out.parquet")
    text = pd.read_csv(source, dtype=str, keep_default_na=False)
    pd.testing.assert_frame_equal(out[list(text.columns)], text, check_dtype=False)
    assert out.t_global_ms.iloc[2] == pytest.approx(expected_time("cam1", 12, 99.5))


MOT_ROWS = "1,3,10,20,4,6,0.9,-1,-1,-1\n2,3,12,21,4,6,0.8,-1,-1,-1\n51,4,0,0,2,2,1,-1,-1,-1\n"
MOT_HEADER = "frame,id,bb_left,bb_top,bb_width,bb_height,conf,x,y,z\n"


@pytest.mark.parametrize("header, extra", [("", ["mot_8", "mot_9", "mot_10"]), (MOT_HEADER, ["mot_x", "mot_y", "z"])])
def test_mot_input(tmp_path, model, header, extra):
    source = write(tmp_path / "cam2.txt", header + MOT_ROWS)
    detections = load_mot(source)
    assert list(detections.columns) == [
        "camera",
        "frame",
        "object",
        "x",
        "y",
        "bb_left",
        "bb_top",
        "bb_width",
        "bb_height",
        "conf",
        *extra,
    ]
    assert list(detections.frame) == [0, 1, 50]
    np.testing.assert_allclose(detections.y, [23.0, 24.0, 1.0])
    np.testing.assert_allclose(detections.x, [12.0, 14.0, 1.0])
    restamp_file(source, tmp_path / "out.csv", model)
    out = pd.read_csv(tmp_path / "out.csv")
    assert list(out.camera) == ["cam2"] * 3
    assert list(out.bb_left) == [10, 12, 0]
    assert list(out.columns) == [*detections.columns, "t_global_ms", "t_center_ms", "restamp_error"]
    assert out.t_global_ms.iloc[0] == pytest.approx(expected_time("cam2", 0, 23.0))
    assert out.restamp_error.iloc[2] == "frame past the end of the video"


def test_mot_camera_name_given(tmp_path, model):
    source = write(tmp_path / "det.txt", MOT_ROWS)
    assert set(load_mot(source, camera="cam1").camera) == {"cam1"}
    summary = restamp_file(source, tmp_path / "out.parquet", model, camera="cam1")
    assert summary.stamped == 2


def test_output_extension_is_checked(tmp_path, model):
    source = write(tmp_path / "in.csv", CSV_TEXT)
    with pytest.raises(FlashsyncError, match="out.txt"):
        restamp_file(source, tmp_path / "out.txt", model)
    with pytest.raises(FlashsyncError, match=r"out.json: unknown detections file type"):
        restamp_file(source, tmp_path / "out.json", model)
