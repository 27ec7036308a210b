"""viz: a recording of the tiny simulated scenario, read back with the Rerun SDK."""

import copy
import os
import select
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import av
import numpy as np
import pandas as pd
import pytest
import rerun as rr
import rerun.chunk

import viz
from flashsync.errors import FlashsyncError
from flashsync.model_file import save_model
from flashsync.pipeline import all_events, detect_videos, synchronize
from flashsync.timestamps import video_timestamps
from tracking_adapter.formats import load_homographies
from tracking_adapter.restamp import restamp
from tracking_adapter.validate import image_to_plane
from viz.events import event_table
from viz.timeline import frame_batches, readout_start_ms
from viz.video import viewer_mp4

RERUN = Path(sys.executable).with_name("rerun")


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
    model, _ = synchronize(detections)
    restamped = restamp(pd.read_csv(tiny_scenario / "detections.csv"), model)
    puck = restamped[restamped["restamp_error"].isna()].iloc[:3]
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
            "x_a": plane_b[:, 0] + 0.1,
            "y_a": plane_b[:, 1] - 0.2,
            "error_m": np.hypot(0.1, 0.2),
        }
    )
    events = all_events(detections)
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
    )
    directory = tmp_path_factory.mktemp("viz")
    save_model(model, directory / "sync.json")
    viz.save_recording(directory / "tiny.rrd", **data)
    return dict(data, rrd=directory / "tiny.rrd", directory=directory)


def read_recording(path: Path) -> tuple[dict[str, pd.DataFrame], dict[str, pd.DataFrame]]:
    """Temporal and static rows of every entity of the first recording in an .rrd file."""
    temporal, static = {}, {}
    for chunk in rerun.chunk.RrdReader(path).store().stream():
        table = chunk.to_record_batch().to_pandas().drop(columns="rerun.controls.RowId")
        into = static if chunk.is_static else temporal
        into[chunk.entity_path] = pd.concat([into.get(chunk.entity_path), table], ignore_index=True)
    return temporal, static


def nanos(column: pd.Series) -> np.ndarray:
    """A duration column as int64 nanoseconds."""
    return column.to_numpy().astype("timedelta64[ns]").astype(np.int64)


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
        "/events/cam1/matched",
        "/events/cam2/matched",
        "/events/log",
        "/residuals/cam1/matched",
        "/residuals/cam2/matched",
        "/residuals/cam2/sigma_plus",
        "/residuals/cam2/sigma_minus",
        "/cameras/cam1/video",
        "/cameras/cam2/video",
        "/cameras/cam1/flash_rows",
        "/cameras/cam2/flash_rows",
        "/cameras/cam1/detections",
        "/cameras/cam2/detections",
        "/plane/cam1/puck",
        "/plane/cam2/puck",
        "/plane/validation/cam1_vs_cam2/puck/error",
        "/plane/validation/cam1_vs_cam2/puck/interpolated",
        "/validation/cam1_vs_cam2/puck",
    }
    assert expected <= set(temporal)
    assert {"/cameras/cam1/video", "/cameras/cam2/video", "/plane/rink", "/plane"} <= set(static)
    timelines = {
        column
        for table in temporal.values()
        for column in table
        if column in ("global_time", "frame_cam1", "frame_cam2", "log_time", "log_tick")
    }
    assert timelines == {"global_time", "frame_cam1", "frame_cam2"}


@pytest.mark.parametrize("name", ["cam1", "cam2"])
def test_one_frame_reference_per_frame_at_its_readout_start(tiny, recording, name):
    temporal, static = recording
    camera = tiny["model"].cameras[name]
    frames = temporal[f"/cameras/{name}/video"].sort_values(f"frame_{name}")
    assert len(frames) == camera.n_frames
    np.testing.assert_array_equal(frames[f"frame_{name}"], np.arange(camera.n_frames))
    expected = np.round(readout_start_ms(camera, np.arange(camera.n_frames)) * 1e6)
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
    camera = tiny["model"].cameras["cam2"]
    logged = np.sort(nanos(temporal["/cameras/cam2/video"]["global_time"])) / 1e6
    instants = np.random.default_rng(0).uniform(logged[0], logged[-1], 200)
    shown = np.searchsorted(logged, instants, side="right") - 1
    np.testing.assert_array_equal(shown, camera.locate(instants)[0])


@pytest.mark.parametrize("name", ["cam1", "cam2"])
def test_residuals_are_the_models(tiny, recording, name):
    temporal, _ = recording
    events = tiny["model"].events
    mine = events[(events["camera"] == name) & events["inlier"]].sort_values("t_global_ms")
    logged = temporal[f"/residuals/{name}/matched"].sort_values("global_time")
    np.testing.assert_allclose(
        np.concatenate(logged["Scalars:scalars"].to_numpy()), mine["residual_ms"], rtol=0, atol=1e-12
    )
    np.testing.assert_array_equal(nanos(logged["global_time"]), np.round(mine["t_global_ms"].to_numpy() * 1e6))
    camera = tiny["model"].cameras[name]
    if not np.any(camera.covariance):
        assert f"/residuals/{name}/sigma_plus" not in temporal
        return
    band = temporal[f"/residuals/{name}/sigma_plus"].sort_values("global_time")
    sigma = np.concatenate(band["Scalars:scalars"].to_numpy())
    assert 0 < len(sigma) <= camera.n_frames
    assert sigma.max() == pytest.approx(camera.t_global_std_ms(np.arange(camera.n_frames), camera.height // 2).max())


def test_event_raster_has_every_detected_edge_in_its_lane(tiny, recording):
    temporal, _ = recording
    table = event_table(tiny["model"], tiny["events"])
    assert len(table) == len(tiny["events"])
    for lane, name in enumerate(tiny["model"].cameras):
        for status in ("matched", "rejected", "unmatched"):
            expected = table[(table["camera"] == name) & (table["status"] == status)]
            logged = temporal.get(f"/events/{name}/{status}")
            if expected.empty:
                assert logged is None
                continue
            assert len(logged) == len(expected)
            assert {float(v[0]) for v in logged["Scalars:scalars"]} == {float(lane)}
    assert "/events/cam1/unmatched" in temporal  # the made-up event
    model_events = tiny["model"].events
    matched_events = model_events[model_events["inlier"]].groupby("camera").size()
    in_table = table[table["status"] == "matched"].groupby("camera")["event"].nunique()
    pd.testing.assert_series_equal(in_table, matched_events, check_names=False)


def test_flash_log_links_the_cameras_of_each_flash(tiny, recording):
    temporal, _ = recording
    log = temporal["/events/log"]
    texts = [t[0] for t in log["TextLog:text"]]
    events = tiny["model"].events
    table = event_table(tiny["model"], tiny["events"])
    n_unmatched = table[table["status"] == "unmatched"].groupby(["camera", "event"]).ngroups
    assert len(texts) == events["flash"].nunique() + n_unmatched
    for flash, group in events.groupby("flash"):
        line = next(t for t in texts if t.startswith(f"flash {flash}:"))
        assert all(f"{name} frame {frame}" in line for name, frame in zip(group["camera"], group["frame"]))


def test_flash_rows_drawn_on_their_frames_only(tiny, recording):
    temporal, _ = recording
    camera = tiny["model"].cameras["cam1"]
    rows = temporal["/cameras/cam1/flash_rows"].sort_values("frame_cam1")
    edges = tiny["events"][tiny["events"]["camera"] == "cam1"]
    for frame, strips in zip(rows["frame_cam1"], rows["LineStrips2D:strips"]):
        expected = np.sort(edges.loc[edges["frame"] == frame, "row"].to_numpy() + 0.5)
        ys = np.sort([strip[0][1] for strip in strips])
        np.testing.assert_allclose(ys, expected, rtol=0, atol=1e-4)  # float32 in Rerun
        for strip in strips:
            assert [point[0] for point in strip] == [0.0, camera.width]
    cleared = rows[[len(s) == 0 for s in rows["LineStrips2D:strips"]]]["frame_cam1"]
    assert set(cleared) == set(edges["frame"] + 1) - set(edges["frame"])


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


def test_plane_observations_are_projected_detections(tiny, recording):
    temporal, _ = recording
    detections = tiny["detections"]
    puck = detections[
        (detections["camera"] == "cam2") & (detections["object"] == "puck") & detections["restamp_error"].isna()
    ]
    logged = temporal["/plane/cam2/puck"].sort_values("frame_cam2")
    positions = np.stack([p[0] for p in logged["Points3D:positions"]])
    expected = image_to_plane(puck["x"].to_numpy(), puck["y"].to_numpy(), tiny["homographies"]["cam2"])
    np.testing.assert_allclose(
        positions[:, :2], expected[np.argsort(puck["frame"].to_numpy(), kind="stable")], atol=1e-4
    )
    assert np.all(positions[:, 2] == 0)
    instants = puck.get("t_center_ms", puck["t_global_ms"]).to_numpy()
    np.testing.assert_array_equal(nanos(logged["global_time"]), np.round(np.sort(instants) * 1e6))


def test_each_camera_keeps_its_colour(recording):
    temporal, static = recording

    def colors(entity, column):
        return {int(c) for row in temporal[entity][column] for c in row}

    for name in ("cam1", "cam2"):
        on_frames = colors(f"/cameras/{name}/detections", "Points2D:colors")
        in_plane = colors(f"/plane/{name}/puck", "Points3D:colors")
        series = {int(c[0]) for c in static[f"/events/{name}/matched"]["SeriesPoints:colors"]}
        assert len(on_frames) == 1 and on_frames == in_plane == series
    assert colors("/plane/cam1/puck", "Points3D:colors") != colors("/plane/cam2/puck", "Points3D:colors")


def test_validation_arrows_point_from_b_to_interpolated_a(tiny, recording):
    temporal, _ = recording
    triples = tiny["validation"]
    arrows = temporal["/plane/validation/cam1_vs_cam2/puck/error"]
    assert len(arrows) == len(triples)
    origins = np.stack([a[0] for a in arrows["Arrows3D:origins"]])
    vectors = np.stack([v[0] for v in arrows["Arrows3D:vectors"]])
    np.testing.assert_allclose(origins[:, :2], triples[["x_b", "y_b"]], atol=1e-4)
    np.testing.assert_allclose(vectors[:, :2], np.tile([0.1, -0.2], (len(triples), 1)), atol=1e-4)
    errors = np.concatenate(temporal["/validation/cam1_vs_cam2/puck"]["Scalars:scalars"].to_numpy())
    np.testing.assert_allclose(errors, triples["error_m"])


def test_model_alone_with_a_rejected_event(tiny, tmp_path):
    model = copy.deepcopy(tiny["model"])
    model.events.loc[model.events.index[-1], "inlier"] = False
    model.cameras["cam1"].covariance = np.zeros((3, 3))
    viz.save_recording(tmp_path / "model.rrd", model)
    temporal, static = read_recording(tmp_path / "model.rrd")
    rejected = model.events.iloc[-1]
    assert len(temporal[f"/events/{rejected.camera}/rejected"]) == 1
    residual = temporal[f"/residuals/{rejected.camera}/rejected"]["Scalars:scalars"]
    assert residual[0][0] == pytest.approx(rejected.residual_ms, abs=1e-12)
    log = temporal["/events/log"]
    warned = [text[0] for text, level in zip(log["TextLog:text"], log["TextLog:level"]) if level[0] == "WARN"]
    assert len(warned) == 1 and warned[0].startswith(f"flash {rejected.flash}:")
    assert "REJECTED" in warned[0]
    assert "/residuals/cam1/sigma_plus" not in temporal
    assert "/residuals/cam2/sigma_plus" in temporal
    assert not [path for path in {*temporal, *static} if path.startswith(("/cameras", "/plane"))]


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
    indexes, order, lengths = frame_batches(camera, frames)
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


def test_serve_hosts_the_web_viewer_until_ctrl_c(tiny):
    web_port, grpc_port = free_port(), free_port()
    script = (
        "import viz; from flashsync.model_file import load_model; "
        f"viz.serve(load_model({str(tiny['directory'] / 'sync.json')!r}), "
        f"web_port={web_port}, grpc_port={grpc_port})"
    )
    server = subprocess.Popen(
        [sys.executable, "-c", script],
        cwd=Path(__file__).parents[1],
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        line, deadline = "", time.monotonic() + 120
        while "serving the Rerun web viewer" not in line:  # printed once all is logged
            assert server.poll() is None and time.monotonic() < deadline, "serve did not start"
            if select.select([server.stderr], [], [], 1.0)[0]:
                line = server.stderr.readline()
        assert viz.viewer_url(web_port, grpc_port) in line
        with urllib.request.urlopen(f"http://127.0.0.1:{web_port}/", timeout=30) as page:
            assert page.status == 200 and b"rerun" in page.read().lower()
        with socket.create_connection(("127.0.0.1", grpc_port), timeout=30):
            pass
        server.send_signal(signal.SIGINT)
        assert server.wait(timeout=60) == 0
    finally:
        if server.poll() is None:
            os.killpg(server.pid, signal.SIGKILL)
            server.wait()
