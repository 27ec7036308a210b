"""Property-based tests of the file readers and the command's options (hypothesis): random
valid inputs round-trip; random corruptions end in one clean error line, never a traceback
and never a silent result."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from flashsync.cli import main
from flashsync.errors import FlashsyncError, InputError, ModelFileError
from flashsync.events import Band, Edge, Events, Flag
from flashsync.io import (
    events_to_frame,
    load_events,
    load_homographies,
    load_model,
    load_timestamps,
    load_validation,
    save_events,
    save_model,
)
from flashsync.io.scenario import scenario_from_dict
from flashsync.model import MATCHED_EVENT_COLUMNS, CameraClock, SyncModel

FAST = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """One folder for the module's examples (hypothesis cannot use the per-test tmp_path)."""
    return tmp_path_factory.mktemp("properties")


finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)
positive = st.floats(1e-3, 1e3, allow_nan=False, allow_infinity=False)
#: Values of the wrong kind for any number, whole number, flag or list of numbers.
not_a_number = st.sampled_from(["1", "abc", "", True, False, None, [1.0], {"a": 1}, math.nan, math.inf, -math.inf])
not_a_flag = st.sampled_from(["false", "true", 0, 1, None, [True], math.nan])
not_a_whole_number = st.sampled_from(["3", 2.5, True, None, math.nan, [3], -1])


def one_line(error: Exception, source: Path) -> None:
    text = str(error)
    assert "\n" not in text and text.startswith(str(source)), text


# --- the model file ----------------------------------------------------------------------------


@st.composite
def models(draw) -> SyncModel:
    names = draw(st.lists(st.sampled_from(["a", "b", "cam1", "cam_2", "x.y"]), min_size=1, max_size=3, unique=True))
    cameras = {}
    for index, name in enumerate(names):
        steps = draw(st.lists(st.floats(1.0, 100.0), min_size=0, max_size=20))
        times = draw(finite) + np.concatenate([[0.0], np.cumsum(steps)])
        interior = draw(st.sampled_from([0, 1, 2]))
        knots = np.linspace(times[0], times[0] + 100.0 * (interior + 1), interior + 2) if interior else np.zeros(0)
        size = 3 + interior
        root = np.asarray(draw(st.lists(st.floats(-1, 1), min_size=size * size, max_size=size * size)))
        covariance = root.reshape(size, size) @ root.reshape(size, size).T * 1e-6
        reference = index == 0
        cameras[name] = CameraClock(
            name,
            times,
            draw(st.integers(1, 4000)),
            draw(st.integers(1, 4000)),
            alpha=1.0 if reference else draw(st.floats(0.999, 1.001)),
            beta_ms=0.0 if reference else draw(finite),
            row_time_ms=draw(positive),
            flipped=draw(st.booleans()),
            covariance=covariance,
            exposure_ms=draw(st.none() | positive),
            video=draw(st.text(max_size=10)),
            drift_knots_ms=knots if not reference else np.zeros(0),
            drift_warp_ms=np.asarray(draw(st.lists(finite, min_size=interior, max_size=interior)))
            if not reference
            else np.zeros(0),
            frame_std_ms=np.asarray(draw(st.lists(positive, min_size=len(times), max_size=len(times))))
            if draw(st.booleans())
            else None,
        )
        if reference:  # the reference has no warp: keep the covariance 3 x 3
            cameras[name].covariance = covariance[:3, :3]
    events = pd.DataFrame(
        [
            {
                "flash": draw(st.integers(0, 9)),
                "camera": name,
                "event": draw(st.integers(0, 99)),
                "frame": draw(st.integers(0, cameras[name].n_frames - 1)),
                "row": draw(finite),
                "t_frame_ms": draw(finite),
                "t_global_ms": draw(st.none() | finite),
                "residual_ms": draw(finite),
                "inlier": draw(st.booleans()),
            }
            for name in draw(st.lists(st.sampled_from(names), max_size=4))
        ],
        columns=list(MATCHED_EVENT_COLUMNS),
    ).astype(MATCHED_EVENT_COLUMNS)
    return SyncModel(names[0], cameras, events)


@FAST
@given(models())
def test_a_model_round_trips(folder, model):
    path = folder / "model.json"
    save_model(model, path)
    loaded = load_model(path)
    assert loaded.reference == model.reference and list(loaded.cameras) == list(model.cameras)
    for name, clock in model.cameras.items():
        again = loaded.cameras[name]
        for field in ("alpha", "beta_ms", "row_time_ms", "flipped", "width", "height", "exposure_ms", "video"):
            assert getattr(again, field) == getattr(clock, field)
        for field in ("frame_times_ms", "covariance", "drift_knots_ms", "drift_warp_ms", "frame_std_ms"):
            np.testing.assert_array_equal(getattr(again, field), getattr(clock, field))
    pd.testing.assert_frame_equal(loaded.events, model.events)


#: Corruptions of a camera's fields: (field, values that are wrong for it).
CAMERA_CORRUPTIONS = [
    ("alpha", not_a_number | st.sampled_from([0.0, -1.0])),
    ("beta_ms", not_a_number),
    ("row_time_ms", not_a_number),
    ("width", not_a_whole_number | st.just(0)),
    ("height", not_a_whole_number),
    ("flipped", not_a_flag),
    ("exposure_ms", st.sampled_from(["8", math.nan, -1.0, [8.0], True])),
    (
        "covariance",
        st.sampled_from([[[1.0, 0.0], [0.0, 1.0]], [[1.0, 0.0, 0.0]] * 2, "cov", None, [[math.nan] * 3] * 3]),
    ),
    ("drift_knots_ms", st.sampled_from([[0.0], [0.0, 1.0], [2.0, 1.0, 3.0], "knots", [math.inf, 1.0, 2.0]])),
    ("name", st.sampled_from([3, None, "", True])),
    ("frame_std_ms", st.sampled_from([-1.0, math.nan, "0", [0.1]])),
]


@FAST
@given(models(), st.data())
def test_a_corrupted_model_is_one_clean_error(folder, model, data):
    path = folder / "corrupt.json"
    save_model(model, path)
    document = json.loads(path.read_text())
    kind = data.draw(st.sampled_from(["camera", "frames", "top", "event"]))
    camera = data.draw(st.sampled_from(document["cameras"]))
    if kind == "camera":
        field, values = data.draw(st.sampled_from(CAMERA_CORRUPTIONS))
        if field == "frame_std_ms" and len(camera["frame_times_ms"]) == 1:
            values = st.sampled_from([-1.0, math.nan, "0", [0.1, 0.2]])
        camera[field] = data.draw(values)
    elif kind == "frames":
        times = camera["frame_times_ms"]
        index = data.draw(st.integers(0, len(times) - 1))
        if len(times) > 1 and data.draw(st.booleans()):
            times[index] = times[index - 1] if index else times[1]  # not increasing
        else:
            times[index] = data.draw(not_a_number)
    elif kind == "top":
        field, value = data.draw(
            st.sampled_from(
                [
                    ("version", "1"),
                    ("version", 1.0),
                    ("version", True),
                    ("version", 2),
                    ("reference", "nobody"),
                    ("reference", 0),
                    ("cameras", {}),
                    ("cameras", []),
                    ("events", "none"),
                    ("format", "other"),
                ]
            )
        )
        document[field] = value
    else:
        event = {"flash": 0, "camera": camera["name"], "event": 0, "frame": 0, "row": 1.0, "t_frame_ms": 0.0,
                 "t_global_ms": 1.0, "residual_ms": 0.0, "inlier": True}  # fmt: skip
        field = data.draw(st.sampled_from(sorted(event)))
        event[field] = data.draw(not_a_whole_number if field in ("flash", "event", "frame") else not_a_number)
        if field == "t_global_ms" and event[field] is None:
            event[field] = "x"  # null is allowed there (a flash without a time)
        if field == "camera":
            event[field] = data.draw(st.sampled_from(["nobody", 3, None]))
        if field == "inlier":
            event[field] = data.draw(not_a_flag)
        document["events"].append(event)
    path.write_text(json.dumps(document))
    with pytest.raises(ModelFileError) as error:
        load_model(path)
    one_line(error.value, path)


# --- the events table --------------------------------------------------------------------------


@st.composite
def events(draw) -> Events:
    rows = []
    for camera in draw(st.lists(st.sampled_from(["a", "b", "c"]), min_size=1, max_size=3, unique=True)):
        frames = sorted(draw(st.lists(st.integers(0, 500), min_size=1, max_size=5, unique=True)))
        for number, frame in enumerate(frames):
            for edge in draw(st.sampled_from([[Edge.LEADING], [Edge.LEADING, Edge.TRAILING], [Edge.TRAILING]])):
                rows.append(
                    (camera, number, frame, 40.0 * frame + 3.0, draw(st.floats(0, 1079)), edge,
                     draw(st.sampled_from(list(Band))), draw(st.floats(0.1, 30) | st.just(math.nan)),
                     draw(st.floats(-0.9, 5)), draw(st.floats(0, 1000)),
                     frozenset(draw(st.sets(st.sampled_from(list(Flag)), max_size=2))))
                )  # fmt: skip
    return Events.from_columns(*zip(*rows))


def assert_same_events(a: Events, b: Events) -> None:
    assert list(a.camera) == list(b.camera) and list(a.edge) == list(b.edge) and list(a.band) == list(b.band)
    assert list(a.flags) == list(b.flags)
    for field in ("event", "frame", "t_frame_ms", "row", "rise_rows", "strength", "quality"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


@FAST
@given(events(), st.sampled_from([".csv", ".parquet"]))
def test_an_events_table_round_trips(folder, table, suffix):
    path = folder / f"events{suffix}"
    save_events(table, path)
    assert_same_events(load_events(path), table)


@FAST
@given(events(), st.sampled_from([".csv", ".parquet"]), st.data())
def test_a_corrupted_events_table_is_one_clean_error(folder, table, suffix, data):
    frame = events_to_frame(table).astype(object)
    index = data.draw(st.integers(0, len(frame) - 1))
    column, bad = data.draw(
        st.sampled_from(
            [
                ("event", "x"), ("event", 1.5), ("event", -2), ("frame", "x"), ("frame", -1), ("frame", math.nan),
                ("t_frame_ms", "soon"), ("t_frame_ms", math.inf), ("row", "x"), ("row", math.nan),
                ("edge", "middle"), ("band", "flash"), ("flags", "split|bent"), ("strength", "x"),
                ("quality", math.nan), ("camera", ""), ("camera", None), ("t_frame_ms", "out of order"),
            ]
        )
    )  # fmt: skip
    if bad == "out of order":  # a later frame at an earlier time: every edge of that frame
        camera = frame.loc[index, "camera"]
        mine = frame["camera"] == camera
        assume(frame.loc[mine, "frame"].nunique() > 1)
        last = frame["frame"] == frame.loc[mine, "frame"].max()
        frame.loc[mine & last, column] = frame.loc[mine, "t_frame_ms"].min() - 1.0
    else:
        frame.loc[index, column] = bad
    path = folder / f"bad-events{suffix}"
    if suffix == ".csv":
        frame.to_csv(path, index=False)
    else:  # every column as text (a typed Parquet file round-trips above)
        frame.map(lambda value: None if value is None else str(value)).to_parquet(path)
    with pytest.raises(InputError) as error:
        load_events(path)
    one_line(error.value, path)


# --- timestamps, homographies, validation JSON, scenario ---------------------------------------


increasing_times = st.lists(st.floats(0.01, 1e4), min_size=1, max_size=60).map(
    lambda steps: list(np.cumsum(steps) + 1000.0)
)


@FAST
@given(increasing_times)
def test_timestamps_round_trip(folder, times):
    path = folder / "t.csv"
    path.write_text("t_ms\n" + "\n".join(repr(float(t)) for t in times) + "\n")
    np.testing.assert_array_equal(load_timestamps(path), times)


@FAST
@given(increasing_times.filter(lambda times: len(times) > 1), st.data())
def test_corrupted_timestamps_are_one_clean_error(folder, times, data):
    texts = [repr(float(t)) for t in times]
    index = data.draw(st.integers(0, len(texts) - 1))
    texts[index] = data.draw(st.sampled_from(["", "abc", "nan", "inf", "-inf", texts[index - 1] if index else "1e9"]))
    path = folder / "bad-t.csv"
    path.write_text("t_ms\n" + "\n".join(texts) + "\n")
    with pytest.raises(InputError) as error:
        load_timestamps(path)
    one_line(error.value, path)
    assert "remux" not in str(error.value)


matrices = (
    st.lists(st.floats(-100, 100), min_size=9, max_size=9)
    .map(lambda v: np.reshape(v, (3, 3)))
    .filter(lambda m: abs(np.linalg.det(m)) > 1e-3)
)


@FAST
@given(st.dictionaries(st.sampled_from(["a", "b", "c"]), matrices, min_size=1))
def test_homographies_round_trip(folder, homographies):
    path = folder / "h.json"
    path.write_text(json.dumps({name: matrix.tolist() for name, matrix in homographies.items()}))
    loaded = load_homographies(path)
    for name, matrix in homographies.items():
        np.testing.assert_array_equal(loaded[name], matrix)


@FAST
@given(matrices, st.data())
def test_corrupted_homographies_are_one_clean_error(folder, matrix, data):
    document = matrix.tolist()
    i, j = data.draw(st.integers(0, 2)), data.draw(st.integers(0, 2))
    document[i][j] = data.draw(not_a_number)
    if data.draw(st.booleans()):
        document = data.draw(st.sampled_from([document, document[:2], [row[:2] for row in matrix.tolist()], "H", 3]))
    path = folder / "bad-h.json"
    path.write_text(json.dumps({"cam": document}))
    with pytest.raises(InputError) as error:
        load_homographies(path)
    one_line(error.value, path)


triples = st.lists(
    st.fixed_dictionaries(
        {
            "camera_a": st.sampled_from(["a", "b"]),
            "camera_b": st.sampled_from(["a", "b"]),
            "object": st.sampled_from(["puck", 7]),
            **{name: finite for name in ("t_global_ms", "x_b", "y_b", "x_a", "y_a", "error_m")},
        }
    ),
    max_size=5,
)


@FAST
@given(triples, st.data())
def test_validation_json_round_trips_and_corruptions_are_clean_errors(folder, records, data):
    path = folder / "v.json"
    path.write_text(json.dumps({"pairs": [], "instant": "t_global_ms", "not_used": {}, "triples": records}))
    loaded = load_validation(path)
    assert loaded.to_dict(orient="records") == records
    if not records:
        return
    record = data.draw(st.sampled_from(records))
    field = data.draw(st.sampled_from(sorted(record)))
    wrong = {"object": [None, True, [1]], "camera_a": [None, True, 3, [1]], "camera_b": [None, 3]}
    record[field] = data.draw(st.sampled_from(wrong.get(field, [None, "x", True, math.nan, [1.0]])))
    path.write_text(json.dumps({"triples": records}))
    with pytest.raises(InputError) as error:
        load_validation(path)
    one_line(error.value, path)


#: Scenario fields and values of the wrong type for them.
SCENARIO_CORRUPTIONS = [
    ("seed", st.sampled_from(["abc", 1.5, True, None, [1]])),
    ("duration_ms", st.sampled_from(["3000", math.nan, math.inf, None, True])),
    ("color", st.sampled_from(["false", 0, None])),
    ("n_players", st.sampled_from([2.5, "8", False])),
    ("name", st.sampled_from([3, None, ["a"]])),
    ("flicker_hz", st.sampled_from(["100", None, -1.0, 0.0])),
    ("cameras", st.sampled_from(["cams", 3, [3], [{"name": "a"}], [{"name": "a", "width": "64", "height": 48,
                                                                     "fps": 25.0}]])),
    ("flashes", st.sampled_from(["x", [{"world_ms": "1"}], [{"world_ms": 1.0, "strength": None}], [5]])),
]  # fmt: skip


@FAST
@given(st.integers(0, 2**31), st.floats(500, 5000), st.booleans())
def test_a_valid_scenario_is_read(seed, duration_ms, color):
    scenario = scenario_from_dict({"preset": "tiny", "seed": seed, "duration_ms": duration_ms, "color": color})
    assert (scenario.seed, scenario.duration_ms, scenario.color) == (seed, duration_ms, color)


@FAST
@given(st.sampled_from(SCENARIO_CORRUPTIONS), st.data())
def test_a_corrupted_scenario_is_one_clean_error(corruption, data):
    field, values = corruption
    with pytest.raises(FlashsyncError) as error:
        scenario_from_dict({"preset": "tiny", field: data.draw(values)}, "s.yaml")
    assert "\n" not in str(error.value) and str(error.value).startswith("s.yaml")


# --- the command's options ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def small_model(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("options")
    cameras = {
        "a": CameraClock("a", np.arange(50) * 40.0, 120, 160, row_time_ms=0.3),
        "b": CameraClock("b", 5.0 + np.arange(60) * 33.3, 100, 160, alpha=1.00001, beta_ms=3.0, row_time_ms=0.3),
    }
    save_model(SyncModel("a", cameras, pd.DataFrame(columns=list(MATCHED_EVENT_COLUMNS))), folder / "sync.json")
    pd.DataFrame({"camera": ["a", "b", "a"], "frame": [1, 2, 3], "x": [5.0, 6.0, 7.0], "y": [10.0, 20.0, 30.0],
                  "object": ["p"] * 3}).to_csv(folder / "d.csv", index=False)  # fmt: skip
    (folder / "h.json").write_text(json.dumps({"a": np.eye(3).tolist(), "b": np.eye(3).tolist()}))
    return folder


def run_quietly(argv: list[str], capsys) -> tuple[int, str]:
    try:
        code = main(argv)
    except SystemExit as exit_:
        code = exit_.code
    return code, capsys.readouterr().err


option_text = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "-5", "0", "1e308", "a=1", "a=nan", "a=-1", "=3", "a=", "a:0", "b:x", ""]),
    st.text(alphabet="ab:=0123456789.-einf ", max_size=12),
)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    command=st.sampled_from(["frames", "restamp", "validate", "sync", "resample"]),
    option=st.sampled_from(["--rate", "--start-ms", "--end-ms", "--exposure", "--max-gap-ms", "--row-time",
                            "--anchor", "--cell"]),
    value=option_text,
)  # fmt: skip
def test_any_option_value_ends_in_a_result_or_one_clean_error(folder, small_model, capsys, command, option, value):
    out = folder / "out"
    base = {
        "frames": ["frames", "--model", small_model / "sync.json", "-o", out / "f.csv"],
        "restamp": ["restamp", small_model / "d.csv", "--model", small_model / "sync.json", "-o", out / "r.csv"],
        "validate": ["validate", small_model / "d.csv", "--model", small_model / "sync.json", "--homographies",
                     small_model / "h.json"],
        "sync": ["sync", folder / "no-a.mp4", folder / "no-b.mp4", "-o", out / "s.json"],
        "resample": ["resample", small_model / "d.csv", "--model", small_model / "sync.json", "-o", out / "t.csv"],
    }[command]  # fmt: skip
    rate = [] if command not in ("frames", "resample") or option == "--rate" else ["--rate", "10"]
    code, err = run_quietly([*map(str, base), *rate, f"{option}={value}"], capsys)
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.strip()]
    if code == 0:
        assert not [line for line in lines if "error" in line], err
    else:
        assert code == 1 and len(lines) == 1 and "error:" in lines[0], err
