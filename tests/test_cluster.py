"""Detection on a Dask cluster (flashsync.cluster): videos decoded in key-frame segments,
events identical to the plain run, on a real LocalCluster of processes and on ``dask
scheduler`` / ``dask worker`` processes started on 127.0.0.1."""

import contextlib
import pickle
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import av
import numpy as np
import pytest
from cli_run import one_error_line, run

from flashsync.cli import SEGMENT_S
from flashsync.detect import VideoDetection, detect_video
from flashsync.io import events_to_frame
from flashsync.pipeline import detect_videos
from flashsync.profiles import read_profiles
from flashsync.segments import SEGMENT_MS, plan_segments, read_segment

pytest.importorskip("distributed")

FPS, HEIGHT, R0, R1 = 30.0, 240, 8, 12
ROW_MS = 1000.0 / FPS / (R0 + HEIGHT + R1)
#: Segments of 1 s: the 10 s clips below (a key frame every 40 frames, 1.33 s) split at every
#: key frame, seven seams.
SEGMENT_TEST_MS = 1000.0


def render_clips(folder: Path, open_gop: bool = False) -> list[Path]:
    """Two 10 s clips, 320x240 at 30 fps with a 3 % 100 Hz rolling flicker, a key frame
    every 40 frames (x264's B-frames on; ``open_gop``: its open GOPs), 17 flashes, players:
    an MKV and an MP4."""
    from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario

    flashes = tuple(
        FlashSpec((10 + 17 * i) * 1000.0 / FPS + (R0 + 30 + (37 * i) % 200) * ROW_MS, strength=0.3) for i in range(17)
    )
    cameras = tuple(
        CameraSpec(
            name,
            320,
            HEIGHT,
            FPS,
            r0=R0,
            r1=R1,
            exposure_ms=0.5,
            n_frames=300,
            noise_std=1.5,
            keyint=40,
            open_gop=open_gop,
            container=container,
            start_ms=start_ms,
        )
        for name, container, start_ms in (("a", "mkv", 0.0), ("b", "mp4", 40.0))
    )
    scenario = Scenario("segments", cameras, flashes=flashes, flicker_depth=0.03, flicker_hz=100.0, n_players=6, seed=3)
    render_scenario(scenario, folder)
    return [folder / "a.mkv", folder / "b.mp4"]


@pytest.fixture(scope="module")
def clips(tmp_path_factory) -> list[Path]:
    return render_clips(tmp_path_factory.mktemp("segments"))


@pytest.fixture(scope="module")
def plain(clips):
    """The plain run, read both ways up (as ``sync`` reads them)."""
    return [detect_video(path, flipped=None) for path in clips]


def assert_identical(found, expected):
    """Same frame times, flicker and events, both readings, to the last bit."""
    assert len(found) == len(expected)
    for a, b in zip(found, expected):
        assert a.camera == b.camera
        assert np.array_equal(a.frame_times_ms, b.frame_times_ms)
        for reading in ("top_down", "bottom_up"):
            ours, theirs = events_to_frame(getattr(a, reading)), events_to_frame(getattr(b, reading))
            assert len(ours) and ours.equals(theirs), reading
        assert a.flicker.period_rows == b.flicker.period_rows and a.flicker.depth == b.flicker.depth
        assert np.array_equal(a.flicker.phase, b.flicker.phase, equal_nan=True)
        assert (a.n_recurring, a.n_degenerate, a.n_whole_frames) == (b.n_recurring, b.n_degenerate, b.n_whole_frames)


def test_segments_start_at_key_frames_and_decode_as_the_whole_video(clips):
    for path in clips:
        info, segments = plan_segments(path, SEGMENT_TEST_MS)
        assert len(segments) == 8 and segments[0].start_pts is None and segments[-1].stop_pts is None
        whole = list(read_profiles(path)[1])
        parts = [read_segment(segment) for segment in segments]
        assert all(part[0][2] == "I" for part in parts)  # each starts at a key frame
        joined = [frame for part in parts for frame in part]
        assert len(joined) == len(whole) == 300
        for (t_a, p_a, k_a, r_a), (t_b, p_b, k_b, r_b) in zip(joined, whole):
            assert t_a == t_b and k_a == k_b and r_a == r_b and np.array_equal(p_a, p_b)
    assert plan_segments(clips[0])[1] == [plan_segments(clips[0])[1][0]]  # 10 s: one segment of SEGMENT_MS
    assert SEGMENT_S * 1000.0 == SEGMENT_MS


def test_detection_state_handed_from_segment_to_segment_gives_the_same_events(clips, plain):
    """The flicker model, baselines, recurrence filter and numbering survive pickling at
    every seam (flashes at frames 44, 78 and 163 are 2 to 4 frames from one: the baseline,
    the flicker's lookahead and the recurrence filter's hold all span it)."""
    assert_identical(detect_in_segments(clips), plain)


def detect_in_segments(paths: list[Path]) -> list:
    """Each video detected segment by segment as :mod:`flashsync.cluster` does, the state
    pickled at every seam."""
    found = []
    for path in paths:
        info, segments = plan_segments(path, SEGMENT_TEST_MS)
        state = VideoDetection(info, None)
        for segment in segments:
            for frame in read_segment(segment):
                state.push(*frame)
            state = pickle.loads(pickle.dumps(state))
        found.append(state.finish())
    return found


def test_local_cluster_gives_the_plain_events(clips, plain, local_cluster):
    seen = {}

    def progress(camera, total):
        seen[camera] = 0

        def update(frames):
            seen[camera] += frames

        return update

    found = detect_videos(clips, scheduler=local_cluster, segment_ms=SEGMENT_TEST_MS, progress=progress)
    assert_identical(found, plain)
    assert seen == {"a": 300, "b": 300}  # the segments' frames came back to the progress bar


def test_open_gop_segments_give_the_plain_events(tmp_path):
    """With open GOPs the B-frames shown before a key frame are coded after it and reference
    the GOP before: the segment before decodes them (it reads on to its stop stamp), the
    segment that starts at the key frame skips them."""
    videos = render_clips(tmp_path, open_gop=True)
    for path in videos:
        with av.open(str(path)) as container:
            packets = [(p.pts, p.is_keyframe) for p in container.demux(container.streams.video[0]) if p.pts is not None]
        leading = [
            pts
            for i, (key_pts, key) in enumerate(packets)
            if key and i
            for pts, _ in packets[i + 1 : i + 4]
            if pts < key_pts
        ]
        assert len(leading) >= 4  # the hard case is there: frames coded after a key frame, shown before it
        _, segments = plan_segments(path, SEGMENT_TEST_MS)
        assert len(segments) == 8
        whole = list(read_profiles(path)[1])
        joined = [frame for segment in segments for frame in read_segment(segment)]
        assert len(joined) == len(whole) == 300
        assert all(a[0] == b[0] and a[2] == b[2] and np.array_equal(a[1], b[1]) for a, b in zip(joined, whole))
    assert_identical(detect_in_segments(videos), [detect_video(path, flipped=None) for path in videos])


def test_detect_command_on_local_n(clips, tmp_path, capsys, recwarn):
    """``--scheduler local:2`` gives the plain run's table; with Dask's default dashboard port
    taken (another cluster, a notebook's), its scheduler says nothing about it."""
    code, _, err = run(capsys, "detect", *clips, "-o", tmp_path / "plain.csv")
    assert code == 0, err
    with socket.socket() as taken:
        with contextlib.suppress(OSError):  # taken already: the case itself
            taken.bind(("", 8787))
            taken.listen()
        code, _, err = run(
            capsys, "detect", *clips, "-o", tmp_path / "cluster.csv", "--scheduler", "local:2", "--segment", 1
        )
    assert code == 0, err
    assert (tmp_path / "cluster.csv").read_bytes() == (tmp_path / "plain.csv").read_bytes()
    assert not [w for w in recwarn if "8787" in str(w.message)] and "8787" not in err


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def dask_processes(tmp_path):
    """``dask scheduler`` and ``dask worker`` (two processes) started on 127.0.0.1; stopped after."""
    dask = shutil.which("dask", path=str(Path(sys.executable).parent))
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    log = open(tmp_path / "dask.log", "w")
    started = [
        subprocess.Popen(
            [dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], stdout=log, stderr=log
        )
    ]
    try:
        deadline = time.monotonic() + 60
        while socket.socket().connect_ex(("127.0.0.1", port)) and time.monotonic() < deadline:
            time.sleep(0.2)
        started.append(
            subprocess.Popen(
                [dask, "worker", address, "--nworkers", "2", "--nthreads", "1", "--no-dashboard"],
                stdout=log,
                stderr=log,
            )
        )
        from distributed import Client

        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        yield address
    finally:
        for process in reversed(started):
            process.terminate()
            process.wait(timeout=30)
        log.close()


def test_dask_scheduler_and_worker_processes_give_the_plain_events(clips, plain, dask_processes, tmp_path, capsys):
    code, _, err = run(capsys, "detect", *clips, "-o", tmp_path / "plain.csv")
    assert code == 0, err
    code, _, err = run(
        capsys, "detect", *clips, "-o", tmp_path / "cluster.csv", "--scheduler", dask_processes, "--segment", 1
    )
    assert code == 0, err
    assert (tmp_path / "cluster.csv").read_bytes() == (tmp_path / "plain.csv").read_bytes()


@pytest.mark.parametrize(
    "options, words",
    [
        (["--scheduler", "tcp://127.0.0.1"], ["--scheduler tcp://127.0.0.1", "tcp://HOST:PORT", "local:N"]),
        (["--scheduler", "local:0"], ["--scheduler local:0", "local:N"]),
        (["--scheduler", "local:100000"], ["--scheduler local:100000", "100000 worker processes", "give at most"]),
        (["--scheduler", "tcp://127.0.0.1:99999"], ["--scheduler tcp://127.0.0.1:99999", "not a TCP port (1-65535)"]),
        (["--scheduler", "local:1", "--segment", "-5"], ["--segment -5", "positive"]),
    ],
)
def test_bad_cluster_options(clips, tmp_path, capsys, options, words):
    code, _, err = run(capsys, "detect", clips[0], "-o", tmp_path / "e.csv", *options)
    assert code == 1 and not (tmp_path / "e.csv").exists()
    one_error_line(err, *words)


@pytest.mark.parametrize("listening", [False, True], ids=["nothing listens", "a server that never answers"])
def test_no_scheduler_answers(clips, tmp_path, capsys, monkeypatch, listening):
    """Nothing on the port, or a server of another kind that takes the connection and says nothing
    (distributed's handshake waited for it without a limit): one line after the timeout."""
    monkeypatch.setattr("flashsync.cluster.CONNECT_TIMEOUT_S", 1)
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        if listening:
            server.listen()  # the kernel completes connections; nothing reads or writes them
        port = server.getsockname()[1]
        started = time.monotonic()
        code, _, err = run(
            capsys, "detect", clips[0], "-o", tmp_path / "e.csv", "--scheduler", f"tcp://127.0.0.1:{port}"
        )
    assert code == 1 and not (tmp_path / "e.csv").exists() and time.monotonic() - started < 30
    one_error_line(err, "no Dask scheduler answers", "dask scheduler", "local:N")


def test_without_the_cluster_extra(clips, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed raises ImportError
    code, _, err = run(capsys, "detect", clips[0], "-o", tmp_path / "e.csv", "--scheduler", "local:1")
    assert code == 1
    one_error_line(err, "flashsync[cluster]")


def test_a_broken_video_on_the_cluster_is_one_line(clips, tmp_path, capsys, local_cluster):
    broken = tmp_path / "c.mkv"
    broken.write_bytes(clips[0].read_bytes()[: clips[0].stat().st_size // 2])
    code, _, err = run(capsys, "detect", broken, "-o", tmp_path / "e.csv", "--scheduler", local_cluster)
    assert code == 1 and not (tmp_path / "e.csv").exists()
    one_error_line(err, str(broken), "cut short")


@pytest.mark.parametrize("command, output", [("sync", "-o")])
def test_sync_on_the_cluster_writes_what_the_plain_run_writes(
    tiny_scenario, local_cluster, tmp_path, capsys, command, output
):
    """(``diagnose`` passes the same options to the same detect_videos.)"""
    videos = sorted(p for p in tiny_scenario.iterdir() if p.suffix in (".mp4", ".mkv"))
    written = []
    for name, options in (("plain", []), ("cluster", ["--scheduler", local_cluster, "--segment", 0.5])):
        code, out, err = run(capsys, command, *videos, output, tmp_path / f"{name}.json", *options)
        assert code == 0, err
        written.append(((tmp_path / f"{name}.json").read_bytes(), out))
    assert written[0] == written[1]
