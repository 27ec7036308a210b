"""viz: a recording of the tiny simulated scenario, read back with the Rerun SDK."""

import copy
import json
import os
import re
import select
import signal
import socket
import subprocess
import sys
import time
import urllib.request
import warnings
from pathlib import Path

import av
import numpy as np
import pandas as pd
import pytest
import rerun as rr
import rerun.chunk

import viz
from flashsync.cli import main
from flashsync.errors import FlashsyncError
from flashsync.io import events_to_frame, load_homographies, load_plane_outline, save_model
from flashsync.pipeline import all_events, detect_videos, synchronize
from flashsync.timestamps import video_timestamps
from tracking_adapter.restamp import restamp
from tracking_adapter.validate import image_to_plane
from viz.events import event_table, flash_numbers, lane_events
from viz.plane import display_transform, plane_view
from viz.scales import format_length, nice_ceiling, nice_floor, ticked_range
from viz.timeline import Timeline, readout_end_ms, readout_start_ms
from viz.video import NOW_RATE_HZ, viewer_mp4

RERUN = Path(sys.executable).with_name("rerun")
ERRORS_M = np.array([0.002, 0.003, 0.0025, 0.5, 0.004, 0.002])
"""Made-up validation errors: a few millimetres, and one bounce of half a metre."""
CLOCK_OFFSET_MS = 50_000.0
"""The reference camera's container clock reads this at its first frame (as real cameras'
often do), so ``global_time`` 0 is far from ``t_global_ms`` 0."""


def with_clock_offset(model, offset_ms: float):
    """``model`` with the reference camera's container clock ``offset_ms`` ahead: every
    ``t_global_ms`` grows by ``offset_ms``, every frame and row keeps its instant."""
    model = copy.deepcopy(model)
    for name, camera in model.cameras.items():
        if name == model.reference:
            camera.frame_times_ms = camera.frame_times_ms + offset_ms
            camera.drift_knots_ms = camera.drift_knots_ms + offset_ms
        else:
            camera.beta_ms += offset_ms
    model.events["t_global_ms"] += offset_ms
    reference = model.events["camera"] == model.reference
    model.events.loc[reference, "t_frame_ms"] += offset_ms
    return model


@pytest.fixture(scope="module", autouse=True)
def quiet_rerun():
    """No usage analytics (Rerun turns them off on CI, i.e. when ``CI`` is set) and no
    silently dropped log calls (strict mode raises instead of warning)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("CI", "1")
        rr.set_strict_mode(True)
        yield
        rr.set_strict_mode(False)


@pytest.fixture(scope="module")
def tiny(tiny_scenario, tmp_path_factory, quiet_rerun):
    """The tiny scenario synced and restamped: log_sync's inputs, with one made-up unmatched
    event and a few made-up validation triples; its model and recording saved as
    ``sync.json`` and ``tiny.rrd`` in ``directory``."""
    videos = [tiny_scenario / "cam1.mp4", tiny_scenario / "cam2.mkv"]
    detections = detect_videos(videos)
    model = with_clock_offset(synchronize(detections)[0], CLOCK_OFFSET_MS)
    # every matched event an inlier: the tests below make their own rejections (with both band
    # edges in the solve, the tiny rig's four flashes leave cam1's first leading edge, 0.04 ms
    # off, beyond five robust sigmas)
    model.events["inlier"] = True
    restamped = restamp(pd.read_csv(tiny_scenario / "detections.csv"), model)
    puck = restamped[restamped["restamp_error"].isna() & (restamped["camera"] == "cam2")]
    puck = puck.iloc[: len(ERRORS_M)]
    homographies = load_homographies(tiny_scenario / "homographies.json")
    plane_b = image_to_plane(puck["x"].to_numpy(), puck["y"].to_numpy(), homographies["cam2"])
    validation = pd.DataFrame(
        {
            "camera_a": "cam1",
            "camera_b": "cam2",
            "object": "puck",
            "t_global_ms": puck["t_global_ms"].to_numpy(),
            "x_b": plane_b[:, 0],
            "y_b": plane_b[:, 1],
            "x_a": plane_b[:, 0] + 0.6 * ERRORS_M,
            "y_a": plane_b[:, 1] - 0.8 * ERRORS_M,
            "error_m": ERRORS_M,
        }
    )
    events = events_to_frame(all_events(detections))
    spurious = events.iloc[[0]].assign(
        camera="cam1", event=events["event"].max() + 1, frame=10, row=50.25
    )  # an event no other camera saw
    events = pd.concat([events, spurious], ignore_index=True)
    data = dict(
        model=model,
        videos=videos,
        events=events,
        detections=restamped,
        homographies=homographies,
        validation=validation,
        plane_outline_m=load_plane_outline(tiny_scenario / "homographies.json"),
    )
    directory = tmp_path_factory.mktemp("viz")
    save_model(model, directory / "sync.json")
    viz.save_recording(directory / "tiny.rrd", **data)
    return dict(data, rrd=directory / "tiny.rrd", directory=directory, timeline=Timeline.of(model))


def read_recording(path: Path) -> tuple[dict[str, pd.DataFrame], dict[str, pd.DataFrame]]:
    """Temporal and static rows of every entity of the first recording in an .rrd file."""
    temporal, static = {}, {}
    for chunk in rerun.chunk.RrdReader(path).store().stream():
        table = chunk.to_record_batch().to_pandas().drop(columns="rerun.controls.RowId")
        into = static if chunk.is_static else temporal
        into[chunk.entity_path] = pd.concat([into.get(chunk.entity_path), table], ignore_index=True)
    return temporal, static


def read_blueprint(path: Path) -> dict[str, dict]:
    """Every blueprint entity of an .rrd file: its components' latest values."""
    reader = rerun.chunk.RrdReader(path)
    contents: dict[str, dict] = {}
    for chunk in reader.store(store=reader.blueprints()[0]).stream():
        for row in chunk.to_record_batch().to_pylist():
            contents.setdefault(chunk.entity_path, {}).update({key: value for key, value in row.items() if ":" in key})
    return contents


def views(blueprint: dict[str, dict]) -> dict[str, dict]:
    """Each view's name -> its components and those of its property entities."""
    found = {}
    for path, components in blueprint.items():
        if path.startswith("/view/") and path.count("/") == 2:
            merged = dict(components)
            for other, more in blueprint.items():
                if other.startswith(path + "/"):
                    merged.update(more)
            found[components["ViewBlueprint:display_name"][0]] = merged
    return found


def nanos(column: pd.Series) -> np.ndarray:
    """A duration column as int64 nanoseconds."""
    return column.to_numpy().astype("timedelta64[ns]").astype(np.int64)


def on_timeline(timeline: Timeline, t_global_ms) -> np.ndarray:
    """``global_time`` (ns) of global instants, as logged."""
    return np.round((np.asarray(t_global_ms, dtype=np.float64) - timeline.origin_ms) * 1e6)


@pytest.fixture(scope="module")
def recording(tiny):
    return read_recording(tiny["rrd"])


def test_recording_verifies_and_has_a_blueprint(tiny):
    verify = subprocess.run(
        [str(RERUN), "rrd", "verify", str(tiny["rrd"])], capture_output=True, text=True, timeout=120
    )
    assert verify.returncode == 0, verify.stderr
    reader = rerun.chunk.RrdReader(tiny["rrd"])
    assert [store.application_id for store in reader.recordings()] == [viz.APPLICATION_ID]
    assert len(reader.blueprints()) == 1


def test_entity_paths(recording):
    temporal, static = recording
    expected = {
        "/events/cam1",
        "/events/cam2",
        "/events/log",
        "/residuals/cam1/matched",
        "/residuals/cam2/matched",
        "/residuals/cam2/sigma_plus",
        "/residuals/cam2/sigma_minus",
        "/cameras/cam1/video",
        "/cameras/cam2/video",
        "/cameras/cam1/flash_rows",
        "/cameras/cam2/flash_rows",
        "/cameras/cam1/flash_labels",
        "/cameras/cam2/flash_labels",
        "/cameras/cam1/now",
        "/cameras/cam2/now",
        "/cameras/cam1/status",
        "/cameras/cam2/status",
        "/cameras/cam1/detections",
        "/cameras/cam2/detections",
        "/plane/observations/cam1/puck",
        "/plane/observations/cam2/puck",
        "/plane/validation/at_cam2/from_cam1/puck/error",
        "/validation/at_cam2/from_cam1/puck",
    }
    assert expected <= set(temporal)
    assert {
        "/cameras/cam1/video",
        "/cameras/cam2/video",
        "/plane",
        "/plane/map/outline",
        "/plane/map/grid",
        "/plane/map/ticks",
        "/plane/map/scale",
    } <= set(static)
    timelines = {
        column
        for table in temporal.values()
        for column in table
        if column in ("global_time", "frame_cam1", "frame_cam2", "log_time", "log_tick")
    }
    assert timelines == {"global_time", "frame_cam1", "frame_cam2"}


def test_timeline_starts_at_the_earliest_first_frame_and_says_so(tiny, recording):
    temporal, static = recording
    model, timeline = tiny["model"], tiny["timeline"]
    starts = {name: readout_start_ms(camera, [0])[0] for name, camera in model.cameras.items()}
    assert timeline.origin_ms == min(starts.values())
    assert timeline.first_camera == min(starts, key=starts.get)
    assert timeline.origin_ms > CLOCK_OFFSET_MS - 1000
    ends = [readout_end_ms(camera, [camera.n_frames - 1])[0] for camera in model.cameras.values()]
    assert timeline.duration_ms == pytest.approx(max(ends) - timeline.origin_ms)
    logged = np.concatenate([nanos(table["global_time"]) for table in temporal.values() if "global_time" in table])
    assert logged.min() == 0
    assert logged.max() <= round(timeline.duration_ms * 1e6)
    # The first data on global_time in the file is at 0, so that the viewer opens there.
    first = next(
        chunk
        for chunk in rerun.chunk.RrdReader(tiny["rrd"]).stream()
        if "global_time" in chunk.to_record_batch().schema.names
    )
    assert first.to_record_batch().column("global_time").to_pylist()[0] == pd.Timedelta(0)
    description = static["/__properties/description"]["TextDocument:text"][0][0]
    assert description.startswith("global_time 0 is the start of the recordings")
    assert f"= global_time + {timeline.origin_ms:.3f} ms" in description
    log = temporal["/events/log"]
    at_zero = [text[0] for text, t in zip(log["TextLog:text"], nanos(log["global_time"])) if t == 0]
    assert any(f"{abs(timeline.origin_ms):.3f} ms" in line for line in at_zero)


@pytest.mark.parametrize("name", ["cam1", "cam2"])
def test_one_frame_reference_per_frame_at_its_readout_start(tiny, recording, name):
    temporal, static = recording
    camera = tiny["model"].cameras[name]
    frames = temporal[f"/cameras/{name}/video"]
    frames = frames[frames[f"frame_{name}"].notna()].sort_values(f"frame_{name}")
    assert len(frames) == camera.n_frames
    np.testing.assert_array_equal(frames[f"frame_{name}"], np.arange(camera.n_frames))
    expected = on_timeline(tiny["timeline"], readout_start_ms(camera, np.arange(camera.n_frames)))
    np.testing.assert_array_equal(nanos(frames["global_time"]), expected)
    video_ns = np.concatenate(frames["VideoFrameReference:timestamp"].to_numpy())
    assert np.all(np.diff(video_ns) > 0)
    # The viewer's timestamps are the container's (the MKV's remuxed unchanged).
    video = next(path for path in tiny["videos"] if path.stem == name)
    stamps_ms = video_timestamps(video)
    np.testing.assert_allclose(np.diff(video_ns) / 1e6, np.diff(stamps_ms), rtol=0, atol=1e-3)
    assert static[f"/cameras/{name}/video"]["AssetVideo:media_type"][0][0] == "video/mp4"


def test_frame_shown_at_an_instant_is_the_one_read_out(tiny, recording):
    temporal, _ = recording
    camera, timeline = tiny["model"].cameras["cam2"], tiny["timeline"]
    video = temporal["/cameras/cam2/video"]
    logged = np.sort(nanos(video[video["frame_cam2"].notna()]["global_time"])) / 1e6
    instants = np.random.default_rng(0).uniform(logged[0], logged[-1], 200)
    shown = np.searchsorted(logged, instants, side="right") - 1
    np.testing.assert_array_equal(shown, camera.locate(instants + timeline.origin_ms)[0])


def test_videos_say_when_they_start_and_end(tiny, recording):
    temporal, _ = recording
    timeline = tiny["timeline"]
    for name, camera in tiny["model"].cameras.items():
        start = on_timeline(timeline, readout_start_ms(camera, [0]))[0]
        end = on_timeline(timeline, readout_end_ms(camera, [camera.n_frames - 1]))[0]
        status = temporal[f"/cameras/{name}/status"].sort_values("global_time")
        labels = {
            t: (list(text) if text is not None else [])
            for t, text in zip(nanos(status["global_time"]), status["Points2D:labels"])
        }
        if start > 0:
            assert "starts at" in labels[0][0] and labels[start] == []
        assert "ended at" in labels[end][0]
        video = temporal[f"/cameras/{name}/video"]
        cleared = video[video["frame_" + name].isna()]
        assert nanos(cleared["global_time"]).tolist() == [end]  # the last frame is cleared


@pytest.mark.parametrize("name", ["cam1", "cam2"])
def test_residuals_are_the_models(tiny, recording, name):
    temporal, static = recording
    events = tiny["model"].events
    mine = events[(events["camera"] == name) & events["inlier"]].sort_values("t_global_ms")
    logged = temporal[f"/residuals/{name}/matched"].sort_values("global_time")
    np.testing.assert_allclose(
        np.concatenate(logged["Scalars:scalars"].to_numpy()), mine["residual_ms"], rtol=0, atol=1e-12
    )
    np.testing.assert_array_equal(nanos(logged["global_time"]), on_timeline(tiny["timeline"], mine["t_global_ms"]))
    assert static[f"/residuals/{name}/matched"]["SeriesPoints:names"][0][0] == name
    camera = tiny["model"].cameras[name]
    if not np.any(camera.covariance):
        assert f"/residuals/{name}/sigma_plus" not in temporal
        return
    assert static[f"/residuals/{name}/sigma_plus"]["SeriesLines:names"][0][0] == name
    band = temporal[f"/residuals/{name}/sigma_plus"].sort_values("global_time")
    sigma = np.concatenate(band["Scalars:scalars"].to_numpy())
    assert 0 < len(sigma) <= camera.n_frames
    assert sigma.max() == pytest.approx(camera.t_global_std_ms(np.arange(camera.n_frames), camera.height // 2).max())


def test_flashes_are_numbered_in_time_order(tiny):
    model = copy.deepcopy(tiny["model"])
    ids = model.events["flash"].unique()
    model.events["flash"] = model.events["flash"].map(dict(zip(ids, ids[::-1] + 10)))
    numbers = flash_numbers(model)
    first_times = model.events.groupby("flash")["t_global_ms"].min()
    assert sorted(numbers.values()) == list(range(len(ids)))
    assert [numbers[f] for f in first_times.sort_values().index] == list(range(len(ids)))


def test_event_lanes_hold_every_event_from_its_leading_edge(tiny, recording):
    temporal, static = recording
    model, timeline = tiny["model"], tiny["timeline"]
    table = event_table(model, tiny["events"])
    assert len(table) == len(tiny["events"])
    lanes = lane_events(table)
    assert len(lanes) == tiny["events"].groupby(["camera", "event"]).ngroups
    for name, camera in model.cameras.items():
        lane = temporal[f"/events/{name}"].sort_values("global_time", kind="stable")
        states = [s[0] for s in lane["StateChange:state"]]
        mine = lanes[lanes["camera"] == name]
        assert states == ["recording", *mine["state"], ""]
        leading = table[(table["camera"] == name) & (table["edge"] == "leading")]
        expected = [
            readout_start_ms(camera, [0])[0],
            *mine["t_global_ms"],
            readout_end_ms(camera, [camera.n_frames - 1])[0],
        ]
        np.testing.assert_array_equal(nanos(lane["global_time"]), on_timeline(timeline, expected))
        assert set(mine["t_global_ms"]) == set(leading["t_global_ms"])
        values = list(static[f"/events/{name}"]["StateConfiguration:values"][0])
        assert set(states[:-1]) <= set(values)
    assert "unmatched" in [s[0] for s in temporal["/events/cam1"]["StateChange:state"]]
    matched = lanes[lanes["state"].str.fullmatch(r"flash \d+")]
    per_flash = matched.groupby("state")["camera"].nunique()
    assert (per_flash == 2).all()  # both cameras saw each matched flash


def test_flash_log_has_a_line_per_event_at_its_flash(tiny, recording):
    temporal, _ = recording
    model, timeline = tiny["model"], tiny["timeline"]
    log = temporal["/events/log"]
    lines = list(
        zip(
            nanos(log["global_time"]), [t[0] for t in log["TextLog:text"]], [level[0] for level in log["TextLog:level"]]
        )
    )
    numbers = flash_numbers(model)
    flash_ms = model.events.groupby("flash")["t_global_ms"].min()
    for e in model.events.itertuples():
        at = np.ceil(np.round((flash_ms[e.flash] - timeline.origin_ms) / 1.0, 9)) * 1e6
        line = [text for t, text, _ in lines if t == at and text.startswith(f"flash {numbers[e.flash]}  {e.camera}  ")]
        assert len(line) == 1 and f"frame {e.frame}  row {e.row:.1f}" in line[0]
        assert f"{e.residual_ms:+.4f} ms" in line[0]
    table = event_table(model, tiny["events"])
    n_unmatched = table[table["status"] == "unmatched"].groupby(["camera", "event"]).ngroups
    assert sum(level == "DEBUG" for *_, level in lines) == n_unmatched
    assert len(lines) == 2 + len(model.events) + n_unmatched


def test_flash_rows_drawn_on_their_frames_only(tiny, recording):
    temporal, _ = recording
    camera = tiny["model"].cameras["cam1"]
    rows = temporal["/cameras/cam1/flash_rows"].sort_values("frame_cam1")
    labels = temporal["/cameras/cam1/flash_labels"].sort_values("frame_cam1")
    edges = tiny["events"][tiny["events"]["camera"] == "cam1"]
    for frame, strips, names in zip(rows["frame_cam1"], rows["LineStrips2D:strips"], labels["Points2D:labels"]):
        mine = edges[edges["frame"] == frame]
        expected = np.sort(mine["row"].to_numpy() + 0.5)
        ys = np.sort([strip[0][1] for strip in strips])
        np.testing.assert_allclose(ys, expected, rtol=0, atol=1e-4)  # float32 in Rerun
        for strip in strips:
            assert [point[0] for point in strip] == [0.0, camera.width]
        names = [] if names is None else list(names)
        assert sum(name.endswith(" end") for name in names) == (mine["edge"] == "trailing").sum()
    cleared = rows[[len(s) == 0 for s in rows["LineStrips2D:strips"]]]["frame_cam1"]
    assert set(cleared) == set(edges["frame"] + 1) - set(edges["frame"])


@pytest.mark.parametrize("name", ["cam1", "cam2"])
def test_now_line_is_on_the_row_exposed_at_each_instant(tiny, recording, name):
    temporal, _ = recording
    camera, timeline = tiny["model"].cameras[name], tiny["timeline"]
    now = temporal[f"/cameras/{name}/now"].sort_values("global_time")
    ticks = timeline.origin_ms + nanos(now["global_time"]) / 1e6
    drawn = np.array([len(s) > 0 for s in now["LineStrips2D:strips"]])
    frames, rows = camera.locate(ticks)
    np.testing.assert_array_equal(drawn, np.isfinite(rows))  # cleared in the blanking
    ys = np.array([s[0][0][1] for s in now["LineStrips2D:strips"][drawn]])
    np.testing.assert_allclose(ys, rows[drawn] + 0.5, atol=2e-3)
    # The row drawn ends its exposure at the tick (the time convention), to float32.
    np.testing.assert_allclose(
        camera.t_global_ms(frames[drawn], ys - 0.5), ticks[drawn], atol=1e-3 * camera.row_time_ms * 4
    )
    period_ns = 1e9 / NOW_RATE_HZ
    on_grid = np.isclose(nanos(now["global_time"]) % period_ns, 0) | np.isclose(
        nanos(now["global_time"]) % period_ns, period_ns
    )
    assert on_grid.mean() > 0.9 and np.diff(nanos(now["global_time"])[on_grid]).max() <= 2 * period_ns
    # And exactly at each flash log line, where a click on it puts the cursor.
    log = temporal["/events/log"]
    flash_lines = nanos(log["global_time"])[[t[0].startswith("flash") for t in log["TextLog:text"]]]
    inside = (flash_lines >= nanos(now["global_time"]).min()) & (flash_lines <= nanos(now["global_time"]).max())
    assert set(flash_lines[inside]) <= set(nanos(now["global_time"]))


def test_now_line_of_an_upside_down_camera(tiny):
    model = copy.deepcopy(tiny["model"])
    camera = model.cameras["cam2"]
    camera.flipped = True
    recording = rr.RecordingStream("test")
    stream = recording.memory_recording()
    viz.video.log_now_line(recording, Timeline.of(model), camera, rate_hz=100.0)
    recording.flush()
    path = tiny["directory"] / "flipped.rrd"
    path.write_bytes(stream.drain_as_bytes())
    temporal, _ = read_recording(path)
    now = temporal["/cameras/cam2/now"]
    ticks = Timeline.of(model).origin_ms + nanos(now["global_time"]) / 1e6
    frames, rows = camera.locate(ticks)
    drawn = np.isfinite(rows)
    ys = np.array([s[0][0][1] for s in now["LineStrips2D:strips"][drawn]])
    np.testing.assert_allclose(camera.t_global_ms(frames[drawn], ys - 0.5), ticks[drawn], atol=1e-3)
    # Each frame's first tick (within 10 ms of its start) is low in the stored image.
    first_ticks = drawn & np.concatenate([[True], np.diff(frames) > 0])
    assert np.all(rows[first_ticks] > camera.height / 2)


def test_detections_drawn_on_their_frames_at_pixel_centres(tiny, recording):
    temporal, _ = recording
    detections = tiny["detections"]
    mine = detections[(detections["camera"] == "cam2") & detections["restamp_error"].isna()]
    drawn = temporal["/cameras/cam2/detections"]
    drawn = drawn[[len(p) > 0 for p in drawn["Points2D:positions"]]].sort_values("frame_cam2")
    np.testing.assert_array_equal(drawn["frame_cam2"], np.sort(mine["frame"].unique()))
    positions = np.concatenate([np.stack(p) for p in drawn["Points2D:positions"]])
    expected = mine.sort_values("frame", kind="stable")[["x", "y"]].to_numpy() + 0.5
    np.testing.assert_allclose(positions, expected, atol=1e-3)


def test_detections_off_their_cameras_frames_are_not_drawn(synced_scenario, tmp_path, capsys):
    """A frame that is text, fractional, negative or past the video's end (a table made by
    hand) is not drawn: before, text raised a ValueError, 3.5 was drawn on frame 3, -1 on
    the last frame and 80 (r has 80) raised an IndexError."""
    frames = ["2", "abc", "3.5", "-1", "80"]
    table = pd.DataFrame({"camera": "r", "frame": frames, "x": 5.0, "y": 6.0, "t_global_ms": 100.0})
    table.to_csv(tmp_path / "d.csv", index=False)
    inputs = ["--model", synced_scenario / "sync.json", "--videos", synced_scenario / "r.mp4"]
    inputs += ["--detections", tmp_path / "d.csv"]
    code = main([str(arg) for arg in ["view", *inputs, "--save", tmp_path / "v.rrd"]])
    err = capsys.readouterr().err
    assert code == 0 and "Traceback" not in err, err
    assert "d.csv: 4 rows are not drawn" in err
    temporal, _ = read_recording(tmp_path / "v.rrd")
    drawn = temporal["/cameras/r/detections"]
    assert list(drawn.loc[[len(p) > 0 for p in drawn["Points2D:positions"]], "frame_r"]) == [2]


def test_plane_observations_are_projected_detections(tiny, recording):
    temporal, _ = recording
    detections = tiny["detections"]
    puck = detections[
        (detections["camera"] == "cam2") & (detections["object"] == "puck") & detections["restamp_error"].isna()
    ]
    logged = temporal["/plane/observations/cam2/puck"].sort_values("frame_cam2")
    positions = np.stack([p[0] for p in logged["Points2D:positions"]])
    expected = image_to_plane(puck["x"].to_numpy(), puck["y"].to_numpy(), tiny["homographies"]["cam2"])
    np.testing.assert_allclose(positions, expected[np.argsort(puck["frame"].to_numpy(), kind="stable")], atol=1e-4)
    assert np.all(np.concatenate(logged["Points2D:radii"].to_numpy()) < 0)  # ui points
    instants = puck.get("t_center_ms", puck["t_global_ms"]).to_numpy()
    np.testing.assert_array_equal(nanos(logged["global_time"]), on_timeline(tiny["timeline"], np.sort(instants)))


def test_plane_view_is_turned_as_the_reference_camera_sees_it(tiny, recording):
    _, static = recording
    homography, camera = tiny["homographies"]["cam1"], tiny["model"].cameras["cam1"]
    columns = np.asarray(list(static["/plane"]["Transform3D:mat3x3"][0][0]), dtype=np.float64)
    to_display = columns.reshape(3, 3).T[:2, :2]  # Rerun stores columns
    np.testing.assert_allclose(to_display @ to_display.T, np.eye(2), atol=1e-6)
    # Image points up, down, left and right of the centre keep their places in the view.
    cx, cy = camera.width / 2, camera.height / 2
    plane = image_to_plane(np.array([cx, cx, cx - 50, cx + 50]), np.array([cy - 50, cy + 50, cy, cy]), homography)
    shown = plane @ to_display.T  # display: x right, y down
    assert shown[0, 1] < shown[1, 1] and shown[2, 0] < shown[3, 0]
    assert abs(shown[0, 0] - shown[1, 0]) < 0.05 * abs(shown[0, 1] - shown[1, 1])


def test_display_transform_follows_the_image_and_flips_a_mirrored_plane():
    # A camera looking along +y at a plane drawn x right, y away: image up is +y.
    upright = np.array([[0.1, 0.0, -32.0], [0.0, -0.1, 24.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(display_transform(upright, 640, 480), [[1, 0], [0, -1]], atol=1e-12)
    # The same plane with y mirrored (a template image, y down): the view flips it back.
    mirrored = np.diag([1.0, -1.0, 1.0]) @ upright
    np.testing.assert_allclose(display_transform(mirrored, 640, 480), [[1, 0], [0, 1]], atol=1e-12)
    # The plane turned by 90 degrees: image up is -x, image right +y.
    turned = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) @ upright
    np.testing.assert_allclose(display_transform(turned, 640, 480), [[0, 1], [1, 0]], atol=1e-12)
    assert display_transform(None, 0, 0).tolist() == [[1, 0], [0, -1]]


def test_each_camera_keeps_its_colour(recording):
    temporal, static = recording

    def colors(entity, column):
        return {int(c) for row in temporal[entity][column] for c in row}

    for name in ("cam1", "cam2"):
        on_frames = colors(f"/cameras/{name}/detections", "Points2D:colors")
        in_plane = colors(f"/plane/observations/{name}/puck", "Points2D:colors")
        series = {int(c[0]) for c in static[f"/residuals/{name}/matched"]["SeriesPoints:colors"]}
        assert len(on_frames) == 1 and on_frames == in_plane == series
    assert colors("/plane/observations/cam1/puck", "Points2D:colors") != colors(
        "/plane/observations/cam2/puck", "Points2D:colors"
    )


def test_validation_arrows_are_scaled_and_long_ones_cut(tiny, recording):
    temporal, static = recording
    triples = tiny["validation"]
    view = plane_view(
        tiny["model"],
        tiny["homographies"],
        tiny["plane_outline_m"],
        triples[["x_b", "y_b"]].to_numpy(),
        triples["error_m"].to_numpy(),
    )
    scale, cap = view.error_scale, view.arrow_cap_m()
    assert scale >= 100 and nice_floor(scale) == scale  # millimetres become metres
    arrows = temporal["/plane/validation/at_cam2/from_cam1/puck/error"].sort_values("global_time")
    assert len(arrows) == len(triples)
    origins = np.stack([a[0] for a in arrows["Arrows2D:origins"]])
    vectors = np.stack([v[0] for v in arrows["Arrows2D:vectors"]])
    np.testing.assert_allclose(origins, triples[["x_b", "y_b"]], atol=1e-4)
    expected = scale * np.stack([0.6 * ERRORS_M, -0.8 * ERRORS_M], axis=1)
    cut = ERRORS_M * scale > cap
    assert cut.sum() == 1 and not cut[0]
    np.testing.assert_allclose(vectors[~cut], expected[~cut], rtol=1e-4)
    np.testing.assert_allclose(np.hypot(*vectors[cut].T), cap, rtol=1e-4)
    np.testing.assert_allclose(vectors[cut] / cap, expected[cut] / np.hypot(*expected[cut].T), atol=1e-5)
    colors = [int(c[0]) for c in arrows["Arrows2D:colors"]]
    assert len(set(np.array(colors)[cut])) == 1 and set(np.array(colors)[cut]).isdisjoint(np.array(colors)[~cut])
    errors = np.concatenate(temporal["/validation/at_cam2/from_cam1/puck"]["Scalars:scalars"].to_numpy())
    np.testing.assert_allclose(errors, triples["error_m"])
    assert static["/validation/at_cam2/from_cam1/puck"]["SeriesPoints:names"][0][0] == "at cam2"
    label = static["/plane/map/scale"]["LineStrips2D:labels"][0][0]
    assert label.startswith(f"error {format_length(cap / scale)} ×{scale:g} ")
    bar = np.stack(static["/plane/map/scale"]["LineStrips2D:strips"][0][0])
    assert np.hypot(*(bar[1] - bar[0])) == pytest.approx(cap, rel=1e-5)


def test_blueprint_reads_at_first_glance(tiny):
    blueprint = read_blueprint(tiny["rrd"])
    found = views(blueprint)
    model, timeline = tiny["model"], tiny["timeline"]
    for name, camera in model.cameras.items():
        assert found[name]["ViewBlueprint:space_origin"] == [f"cameras/{name}"]
        assert found[name]["VisualBounds2D:range"] == [
            {"x_range": [0.0, camera.width], "y_range": [0.0, camera.height]}
        ]
    residuals = next(v for k, v in found.items() if k.startswith("residuals of the solve (ms)"))
    errors = next(v for k, v in found.items() if k.startswith("validation error (m)"))
    lanes = next(v for k, v in found.items() if k.startswith("flash events per camera"))
    plane = next(v for k, v in found.items() if k.startswith("plane (m), top view as cam1 sees it"))
    assert lanes["ViewBlueprint:class_identifier"] == ["StateTimeline"]
    assert any(k.startswith("flash log") for k in found)
    # One time range for the stacked plots: 0 to past the end, room for the legends; views
    # with narrower value axes start a little earlier, so that an instant is at one x in all.
    ranges = [v["TimeAxis:view_range"][0] for v in (lanes, residuals, errors)]
    assert len({r["end"] for r in ranges}) == 1
    assert ranges[0]["end"] > timeline.duration_ms * 1e6 * 1.05
    starts = [r["start"] for r in ranges]
    assert max(starts) == 0 and starts[0] == min(starts) > -0.05 * ranges[0]["end"]
    for plot in (residuals, errors):
        assert plot["PlotLegend:visible"] == [True]
    # Value ranges hold a labelled tick besides 0: a power of ten, a few times in range (at
    # most a ±8.8 or -0.8..8.8 range; the ticks' spacing on the plot is test_nice_numbers').
    for plot in (residuals, errors):
        low, high = plot["ScalarAxis:range"][0]
        step = 10.0 ** np.floor(np.log10(max(abs(low), abs(high)) / 1.1 * 1.0001))
        assert (high - low) / step <= 17.6 and max(abs(low), abs(high)) >= step
    top = residuals["ScalarAxis:range"][0][1]
    assert top >= viz.residuals.residual_extent_ms(model)
    assert errors["ScalarAxis:range"][0][1] >= ERRORS_M.max()
    x_range = plane["VisualBounds2D:range"][0]["x_range"]
    assert x_range[1] - x_range[0] > 10  # metres, the whole rink
    assert blueprint["/time_panel"]["TimePanelBlueprint:timeline"] == ["global_time"]


def test_nice_numbers():
    assert nice_ceiling(0.07) == 0.1 and nice_ceiling(0.012) == 0.02 and nice_ceiling(3.0) == 5.0
    # Ranges whose power-of-ten ticks are 25 px or more apart on the plot's height.
    assert ticked_range(0.025, 200, symmetric=True) == pytest.approx((-0.033, 0.033))
    assert ticked_range(0.035, 200, symmetric=True) == pytest.approx((-0.11, 0.11))
    assert ticked_range(0.74, 170, symmetric=False) == pytest.approx((-0.1, 1.1))
    assert ticked_range(0.74, 300, symmetric=False) == pytest.approx((-0.08, 0.88))
    assert ticked_range(0.55, 200, symmetric=False) == pytest.approx((-0.06, 0.66))
    assert nice_floor(670.0) == 500.0 and nice_floor(1.0) == 1.0
    assert format_length(0.02) == "2 cm" and format_length(0.005) == "5 mm"
    assert format_length(12.0) == "12 m" and format_length(32530.5) == "32.5 km"
    assert format_length(0.0) == "0 m"
    with pytest.raises(ValueError):
        nice_ceiling(0.0)


def test_no_outline_unless_given(tiny, tmp_path):
    data = {key: tiny[key] for key in ("model", "detections", "homographies")}
    viz.save_recording(tmp_path / "none.rrd", **data)
    temporal, static = read_recording(tmp_path / "none.rrd")
    assert "/plane/map/outline" not in static and "/plane/map/grid" in static
    # The view holds every observation (the data's extent, as the reference camera sees it).
    points = np.concatenate(
        [
            np.stack(list(p))
            for path, table in temporal.items()
            if path.startswith("/plane/observations/")
            for p in table["Points2D:positions"]
        ]
    )
    transform = np.asarray(list(static["/plane"]["Transform3D:mat3x3"][0][0])).reshape(3, 3).T
    shown = points @ transform[:2, :2].T
    plane = next(v for k, v in views(read_blueprint(tmp_path / "none.rrd")).items() if k.startswith("plane"))
    bounds = plane["VisualBounds2D:range"][0]
    assert bounds["x_range"][0] < shown[:, 0].min() and shown[:, 0].max() < bounds["x_range"][1]
    assert bounds["y_range"][0] < shown[:, 1].min() and shown[:, 1].max() < bounds["y_range"][1]
    viz.save_recording(tmp_path / "box.rrd", plane_outline_m=viz.rectangle_outline(0, 0, 60, 30), **data)
    _, static = read_recording(tmp_path / "box.rrd")
    outline = np.stack(static["/plane/map/outline"]["LineStrips2D:strips"][0][0])
    np.testing.assert_array_equal(outline, [[0, 0], [60, 0], [60, 30], [0, 30], [0, 0]])


def test_plane_extent_without_outline_holds_the_data_but_stray_points(tiny):
    rng = np.random.default_rng(1)
    points = np.concatenate(
        [
            rng.uniform([0, 0], [50, 20], (1000, 2)),
            [[-8.0, 10.0]] * 8,  # a few at the edge
            [[1e6, 10.0]],
        ]
    )  # one far off
    view = plane_view(tiny["model"], None, None, points, np.zeros(0))
    assert view.low_m[0] == -8.0 and 49.5 < view.high_m[0] <= 50
    assert 0 <= view.low_m[1] < 0.5 and 19.5 < view.high_m[1] <= 20


def test_plane_outline_in_the_homographies_file(tmp_path):
    matrix = np.eye(3).tolist()
    path = tmp_path / "h.json"
    path.write_text(json.dumps({"cam1": matrix, "plane": {"outline_m": [[0, 0], [4, 0], [4, 2]]}}))
    assert list(load_homographies(path)) == ["cam1"]
    np.testing.assert_array_equal(load_plane_outline(path), [[0, 0], [4, 0], [4, 2], [0, 0]])
    path.write_text(json.dumps({"cam1": matrix, "plane": matrix}))  # a camera named plane
    assert list(load_homographies(path)) == ["cam1", "plane"] and load_plane_outline(path) is None
    path.write_text(json.dumps({"cam1": matrix}))
    assert load_plane_outline(path) is None
    for bad in (
        {"outline_m": [[0, 0], [1, 1]]},
        {"outline_m": "rink"},
        {"corners": []},
        {"outline_m": [[0, 0, 0], [1, 0, 0], [1, 1, 0]]},
    ):
        path.write_text(json.dumps({"cam1": matrix, "plane": bad}))
        with pytest.raises(FlashsyncError, match='h.json: "plane" needs "outline_m"'):
            load_plane_outline(path)
    path.write_text(json.dumps({"plane": {"outline_m": [[0, 0], [4, 0], [4, 2]]}}))
    with pytest.raises(FlashsyncError, match="no camera in it"):
        load_homographies(path)


def test_inverted_homography_warns(tiny, tmp_path):
    inverted = {name: np.linalg.inv(matrix) for name, matrix in tiny["homographies"].items()}
    data = {key: tiny[key] for key in ("model", "detections", "plane_outline_m")}
    with pytest.warns(viz.PlaneWarning) as caught:
        viz.save_recording(tmp_path / "inverted.rrd", homographies=inverted, **data)
    assert sorted(str(w.message).split(" of ")[1][:4] for w in caught) == ["cam1", "cam2"]
    assert all(
        "detections land far outside the plane outline (x 0 m..60 m, y 0 m..30 m)" in str(w.message) for w in caught
    )
    in_mm = {
        name: np.diag([1000.0, 1000.0, 1.0]) @ matrix  # millimetres, no outline
        for name, matrix in tiny["homographies"].items()
    }
    with pytest.warns(viz.PlaneWarning) as caught:
        viz.save_recording(tmp_path / "mm.rrd", homographies=in_mm, model=tiny["model"], detections=tiny["detections"])
    assert len(caught) == 2
    assert all(re.search(r"cam\d's detections spread over [\d.]+ km", str(w.message)) for w in caught)
    with warnings.catch_warnings():
        warnings.simplefilter("error", viz.PlaneWarning)
        viz.save_recording(tmp_path / "right.rrd", homographies=tiny["homographies"], **data)


def test_view_command_warns_in_one_line_and_takes_a_plane(tiny, tmp_path, capsys):
    inverted = {name: np.linalg.inv(m).tolist() for name, m in tiny["homographies"].items()}
    (tmp_path / "inverted.json").write_text(json.dumps(inverted))
    tiny["detections"].to_csv(tmp_path / "restamped.csv", index=False)
    code = main(
        [
            "view",
            "--model",
            str(tiny["directory"] / "sync.json"),
            "--detections",
            str(tmp_path / "restamped.csv"),
            "--homographies",
            str(tmp_path / "inverted.json"),
            "--plane",
            "0",
            "0",
            "60",
            "30",
            "--save",
            str(tmp_path / "v.rrd"),
        ]
    )
    err = capsys.readouterr().err
    assert code == 0, err
    warned = [line for line in err.splitlines() if "warning" in line]
    assert len(warned) == 2 and all(
        line.startswith("flashsync view: warning: ") and "inverted.json" in line for line in warned
    )
    assert "Traceback" not in err
    _, static = read_recording(tmp_path / "v.rrd")
    outline = np.stack(static["/plane/map/outline"]["LineStrips2D:strips"][0][0])
    np.testing.assert_array_equal(outline[2], [60, 30])


def test_view_help_has_the_whole_chain_and_the_units(capsys):
    with pytest.raises(SystemExit):
        main(["view", "--help"])
    text = capsys.readouterr().out
    for option in (
        "--events events.csv",
        "--detections restamped.csv",
        "--homographies homographies.json",
        "--validation validation.json",
        "sync --events",
        "--plane",
        "--bind",
        "--port",
    ):
        assert option in " ".join(text.split()), option
    for unit in ("seconds from the start of the recordings", "in ms", "metres", "px"):
        assert unit in " ".join(text.split()), unit


def test_model_alone_with_a_rejected_event(tiny, tmp_path):
    model = copy.deepcopy(tiny["model"])
    model.events.loc[model.events.index[-1], "inlier"] = False
    model.cameras["cam1"].covariance = np.zeros((3, 3))
    viz.save_recording(tmp_path / "model.rrd", model)
    temporal, static = read_recording(tmp_path / "model.rrd")
    rejected = model.events.iloc[-1]
    number = flash_numbers(model)[rejected.flash]
    states = [s[0] for s in temporal[f"/events/{rejected.camera}"]["StateChange:state"]]
    assert f"flash {number} rejected" in states
    residual = temporal[f"/residuals/{rejected.camera}/rejected"]["Scalars:scalars"]
    assert residual[0][0] == pytest.approx(rejected.residual_ms, abs=1e-12)
    log = temporal["/events/log"]
    warned = [text[0] for text, level in zip(log["TextLog:text"], log["TextLog:level"]) if level[0] == "WARN"]
    assert len(warned) == 1 and warned[0].startswith(f"flash {number}  {rejected.camera}  ")
    assert f"REJECTED (event {rejected.event})" in warned[0]
    assert "/residuals/cam1/sigma_plus" not in temporal
    assert "/residuals/cam2/sigma_plus" in temporal
    assert not [path for path in {*temporal, *static} if path.startswith(("/cameras", "/plane"))]


def test_a_flash_the_solve_could_not_place(tiny, tmp_path):
    """Every event of a flash rejected: the model has no time for it (NaN) and residuals
    of seconds; it keeps its place in time, and the residual plot's range the inliers'."""
    model = copy.deepcopy(tiny["model"])
    flashes = model.events.groupby("flash")["t_global_ms"].min().sort_values().index
    lost = model.events["flash"] == flashes[1]
    model.events.loc[lost, ["inlier", "t_global_ms", "residual_ms"]] = [False, np.nan, 3387.0]
    viz.save_recording(tmp_path / "lost.rrd", model)
    temporal, _ = read_recording(tmp_path / "lost.rrd")
    timeline = Timeline.of(model)
    for entity in ("/events/log", "/residuals/cam1/rejected", "/residuals/cam2/rejected"):
        instants = nanos(temporal[entity]["global_time"])
        assert (instants >= 0).all() and (instants <= timeline.duration_ms * 1e6).all(), entity
    assert flash_numbers(model)[flashes[1]] == 1
    log = temporal["/events/log"]
    warned = [text[0] for text, level in zip(log["TextLog:text"], log["TextLog:level"]) if level[0] == "WARN"]
    assert len(warned) == 2 and all(line.startswith("flash 1  ") for line in warned)
    residuals = next(v for k, v in views(read_blueprint(tmp_path / "lost.rrd")).items() if k.startswith("residuals"))
    assert residuals["ScalarAxis:range"][0][1] < 1.0


def test_mkv_is_remuxed_packet_for_packet(tiny, tmp_path):
    source = tiny["videos"][1]
    remuxed = viewer_mp4(source, tmp_path)
    assert remuxed.suffix == ".mp4" and remuxed.parent == tmp_path

    def packets(path):
        with av.open(str(path)) as container:
            stream = container.streams.video[0]
            return [
                (bytes(p), round(float(p.pts * stream.time_base) * 1000, 3)) for p in container.demux(stream) if p.size
            ]

    assert packets(remuxed) == packets(source)
    mp4 = tiny["videos"][0]
    assert viewer_mp4(mp4, tmp_path) == mp4


def test_frame_batches_clear_the_following_frame(tiny):
    camera = tiny["model"].cameras["cam1"]
    frames = np.array([5, 3, 5, 4, camera.n_frames - 1])
    indexes, order, lengths = tiny["timeline"].frame_batches(camera, frames)
    sequence = indexes[1].as_arrow_array().to_numpy()
    np.testing.assert_array_equal(sequence, [3, 4, 5, 6, camera.n_frames - 1])
    np.testing.assert_array_equal(lengths, [1, 1, 2, 0, 1])
    np.testing.assert_array_equal(frames[order], [3, 4, 5, 5, camera.n_frames - 1])


def test_bad_videos_are_clear_errors(tiny, tmp_path):
    data = {key: tiny[key] for key in ("model", "events")}
    with pytest.raises(FlashsyncError, match="camera 'cam9' is not in the model"):
        viz.log_sync(videos=[tmp_path / "cam9.mp4"], **data)
    with pytest.raises(FlashsyncError, match="two videos are named cam1"):
        viz.log_sync(videos=[tiny["videos"][0], tmp_path / "cam1.mkv"], **data)
    with pytest.raises(FlashsyncError, match="72 frames, but the model has 60"):
        viz.log_sync(videos={"cam1": tiny["videos"][1]}, **data)
    mpeg4 = tmp_path / "cam1.avi"
    with av.open(str(mpeg4), "w") as container:
        stream = container.add_stream("mpeg4", rate=25)
        stream.width, stream.height = 64, 48
        for packet in stream.encode(av.VideoFrame.from_ndarray(np.zeros((48, 64, 3), np.uint8))):
            container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    with pytest.raises(FlashsyncError, match="cannot play mpeg4 video"):
        viz.log_sync(videos=[mpeg4], **data)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def listening_addresses(port: int) -> set[str]:
    """Local addresses with a TCP socket listening on ``port``, from /proc/net/tcp{,6}."""
    found = set()
    for table, width in (("/proc/net/tcp", 8), ("/proc/net/tcp6", 32)):
        if not os.path.exists(table):
            continue
        for line in Path(table).read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            address, hex_port = local.split(":")
            if int(hex_port, 16) == port and state == "0A":  # LISTEN
                raw = bytes.fromhex(address)
                if width == 8:
                    found.add(socket.inet_ntop(socket.AF_INET, raw[::-1]))
                else:
                    words = b"".join(raw[i : i + 4][::-1] for i in range(0, 16, 4))
                    found.add(socket.inet_ntop(socket.AF_INET6, words))
    return found


def test_serve_listens_on_this_machine_only_until_ctrl_c(tiny):
    web_port, grpc_port = free_port(), free_port()
    command = [
        sys.executable,
        "-m",
        "flashsync",
        "view",
        "--model",
        str(tiny["directory"] / "sync.json"),
        "--serve",
        "--port",
        str(web_port),
        "--grpc-port",
        str(grpc_port),
    ]
    server = subprocess.Popen(
        command,
        cwd=Path(__file__).parents[1],
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # Ctrl-C works even under `nohup pytest &`
    )
    try:
        line, deadline = "", time.monotonic() + 120
        while "serving the Rerun web viewer" not in line:  # printed once both listen
            assert server.poll() is None and time.monotonic() < deadline, "serve did not start"
            if select.select([server.stderr], [], [], 1.0)[0]:
                line = server.stderr.readline()
        url = viz.viewer_url(web_port, grpc_port)
        assert url in line and "127.0.0.1" in url
        for port in (web_port, grpc_port):
            assert listening_addresses(port) == {"127.0.0.1"}, port
        with urllib.request.urlopen(url, timeout=30) as page:
            assert page.status == 200 and b"rerun" in page.read().lower()
        with socket.create_connection(("127.0.0.1", grpc_port), timeout=30):
            pass
        # A second server on the same ports: one clear line, no traceback.
        second = subprocess.run(command, cwd=Path(__file__).parents[1], capture_output=True, text=True, timeout=120)
        assert second.returncode == 1 and "Traceback" not in second.stderr
        assert f"cannot listen on 127.0.0.1 port {web_port}" in second.stderr
        server.send_signal(signal.SIGINT)
        assert server.wait(timeout=60) == 0
        assert not listening_addresses(web_port) and not listening_addresses(grpc_port)
        # kill (SIGTERM) stops the server too, instead of leaving it behind.
        server = subprocess.Popen(
            command, cwd=Path(__file__).parents[1], stderr=subprocess.PIPE, text=True, start_new_session=True
        )
        while not listening_addresses(web_port):
            assert server.poll() is None and time.monotonic() < deadline + 120, "no second start"
            time.sleep(0.5)
        server.send_signal(signal.SIGTERM)
        server.wait(timeout=60)
        assert not listening_addresses(web_port) and not listening_addresses(grpc_port)
    finally:
        if server.poll() is None:
            os.killpg(server.pid, signal.SIGKILL)
            server.wait()


def test_spawn_without_a_display_is_one_clear_line(tiny, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    code = main(["view", "--model", str(tiny["directory"] / "sync.json"), "--spawn", "--grpc-port", str(free_port())])
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "needs a display" in err
