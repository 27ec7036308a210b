"""The flashsync command end to end on rendered videos, and every bad input it must refuse."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_run import one_error_line, run

from flashsync.evaluate import sync_errors
from flashsync.io import load_ground_truth, load_model
from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario


@pytest.fixture(scope="module")
def three_cameras(tmp_path_factory):
    """Three unseen cameras (mp4, mkv, mp4) at 25/30/50 fps that share exactly three flashes."""
    cameras = (
        CameraSpec("a", 320, 180, 25.0, r0=8, r1=6, start_ms=0.0, n_frames=75),
        CameraSpec(
            "b",
            320,
            180,
            30.0,
            r0=6,
            r1=8,
            start_ms=5000.0,
            offset_ms=-5000.0 + 130.0,
            drift_ppm=-20.0,
            container="mkv",
            n_frames=90,
        ),
        CameraSpec(
            "c",
            256,
            144,
            50.0,
            r0=10,
            r1=6,
            start_ms=90_000.0,
            offset_ms=-90_000.0 - 210.0,
            drift_ppm=30.0,
            exposure_ms=6.0,
            n_frames=150,
        ),
    )
    flashes = (FlashSpec(700.0, 0.5), FlashSpec(1460.0, 0.6), FlashSpec(2270.0, 0.45))
    folder = tmp_path_factory.mktemp("three")
    render_scenario(Scenario("three", cameras, flashes=flashes, n_players=4, seed=2), folder)
    return folder


def test_sync_unseen_videos_sharing_three_flashes(three_cameras, tmp_path, capsys):
    videos = [three_cameras / name for name in ("a.mp4", "b.mkv", "c.mp4")]
    code, out, err = run(capsys, "sync", *videos, "-o", tmp_path / "sync.json")
    assert code == 0, err
    assert "drift ppm" in out and "T_row ms" in out
    model = load_model(tmp_path / "sync.json")
    assert list(model.cameras) == ["a", "b", "c"]
    errors = sync_errors(model, load_ground_truth(three_cameras / "truth.json"))
    assert errors["rms_ms"].max() < 0.5, errors


def test_detect_writes_events_table(three_cameras, tmp_path, capsys):
    code, _, err = run(capsys, "detect", three_cameras / "a.mp4", "-o", tmp_path / "events.parquet")
    assert code == 0, err
    events = pd.read_parquet(tmp_path / "events.parquet")
    assert (events["edge"] == "leading").sum() == 3
    assert {"camera", "event", "frame", "t_frame_ms", "row", "edge", "band", "flags"} <= set(events.columns)


def test_restamp_keeps_every_row_and_explains_failures(tiny_scenario, tmp_path, capsys):
    code, _, err = run(
        capsys, "sync", tiny_scenario / "cam1.mp4", tiny_scenario / "cam2.mkv", "-o", tmp_path / "sync.json"
    )
    assert code == 0, err
    detections = pd.read_csv(tiny_scenario / "detections.csv")
    bad = pd.DataFrame(
        {
            "camera": ["cam1", "cam2"],
            "frame": [-1, 10_000],
            "x": [1.0, 2.0],
            "y": [5.0, 6.0],
            "object": ["puck", "puck"],
        }
    )
    table = pd.concat([detections, bad], ignore_index=True)
    table.to_csv(tmp_path / "in.csv", index=False)
    code, _, err = run(
        capsys, "restamp", tmp_path / "in.csv", "--model", tmp_path / "sync.json", "-o", tmp_path / "out.csv"
    )
    assert code == 0, err
    out = pd.read_csv(tmp_path / "out.csv")
    assert len(out) == len(table)
    pd.testing.assert_frame_equal(out[table.columns], table)
    assert out["t_global_ms"].notna().sum() == len(detections)
    assert list(out["restamp_error"].tail(2)) == ["frame negative", "frame past the end of the video"]
    code, _, _ = run(
        capsys,
        "restamp",
        tmp_path / "in.csv",
        "--model",
        tmp_path / "sync.json",
        "-o",
        tmp_path / "strict.csv",
        "--strict",
    )
    assert code == 1


def test_the_demo_syncs_the_sample_and_checks_it_against_the_truth(tmp_path, capsys):
    """``flashsync demo`` (the README's first command): the chain on the shipped sample,
    its outputs written, every camera's sync error and exposure against the truth printed:
    within 0.1 ms RMS, and each exposure within 3 of its stated standard deviation."""
    code, out, _ = run(capsys, "demo", "-o", tmp_path / "demo")
    assert code == 0
    assert all((tmp_path / "demo" / name).is_file() for name in ("events.csv", "sync.json", "restamped.csv"))
    cameras = re.findall(
        r"^  (cam\d) +RMS ([\d.]+) ms +max [\d.]+ ms +exposure +([\d.]+) ± ([\d.]+) ms, true +([\d.]+)$", out, re.M
    )
    assert len(cameras) == 4, out
    for _, rms, exposure, std, true in cameras:
        assert float(rms) < 0.1 and abs(float(exposure) - float(true)) <= 3 * float(std), out


def test_an_exposure_the_bands_do_not_pin_to_a_tenth_of_a_millisecond_is_warned(tmp_path, capsys):
    """The sample's cam4 (seven flashes, stamps jittered 0.1 ms): its exposure comes out
    11.87 ± 0.15 ms (truth 12), its bands' lengths alone ± 0.12; ``sync`` warns about it,
    and about no other camera's (± 0.03-0.04 ms by their lengths; 0.07-0.11 with the share
    an unknown tone curve adds, which is no reason to warn)."""
    samples = Path(__file__).resolve().parents[1] / "samples"
    videos = [samples / name for name in ("cam1.mp4", "cam2.mkv", "cam3.mp4", "cam4.mp4")]
    code, _, err = run(capsys, "sync", *videos, "-o", tmp_path / "sync.json")
    warned = [line for line in err.splitlines() if "its exposure is" in line]
    assert code == 0 and len(warned) == 1 and "cam4.mp4: its exposure is 11.87 ± 0.15 ms" in warned[0], err


def test_help_of_every_command_has_an_example():
    for command in ("detect", "sync", "restamp", "validate", "simulate", "demo", "frames", "resample", "montage"):
        result = subprocess.run([sys.executable, "-m", "flashsync", command, "--help"], capture_output=True, text=True)
        assert result.returncode == 0 and "example:" in result.stdout and "flashsync " + command in result.stdout


def test_missing_file(tmp_path, capsys):
    code, _, err = run(capsys, "detect", tmp_path / "nope.mp4")
    assert code == 1
    one_error_line(err, "nope.mp4", "no such file")


def test_not_a_video(tmp_path, capsys):
    (tmp_path / "notes.mp4").write_text("not a video")
    code, _, err = run(capsys, "sync", tmp_path / "notes.mp4", tmp_path / "notes.mp4")
    assert code == 1
    one_error_line(err)


def test_file_that_is_not_a_video(tmp_path, capsys):
    (tmp_path / "a.mp4").write_text("not a video")
    (tmp_path / "b.mkv").write_bytes(b"\x00" * 100)
    code, _, err = run(capsys, "sync", tmp_path / "a.mp4", tmp_path / "b.mkv")
    assert code == 1
    one_error_line(err, "a.mp4", "not a video file")
    assert not (tmp_path / "sync.json").exists()


def test_duplicate_camera_names(tiny_scenario, tmp_path, capsys):
    (tmp_path / "cam1.mkv").write_bytes((tiny_scenario / "cam2.mkv").read_bytes())
    code, _, err = run(capsys, "sync", tiny_scenario / "cam1.mp4", tmp_path / "cam1.mkv")
    assert code == 1
    one_error_line(err, "cam1", "rename")


@pytest.fixture(scope="module")
def no_flash_videos(tmp_path_factory):
    cameras = (
        CameraSpec("quiet1", 160, 90, 25.0, n_frames=25),
        CameraSpec("quiet2", 160, 90, 30.0, n_frames=30, container="mkv"),
    )
    folder = tmp_path_factory.mktemp("quiet")
    render_scenario(Scenario("quiet", cameras, n_players=3, seed=4), folder)
    return folder


def test_videos_with_no_flashes(no_flash_videos, tmp_path, capsys):
    code, _, err = run(
        capsys, "sync", no_flash_videos / "quiet1.mp4", no_flash_videos / "quiet2.mkv", "-o", tmp_path / "sync.json"
    )
    assert code == 1
    one_error_line(err, "quiet1.mp4: 0", "quiet2.mkv: 0", "flash events")
    assert not (tmp_path / "sync.json").exists()


def test_fewer_than_two_cameras(tiny_scenario, capsys):
    code, _, err = run(capsys, "sync", tiny_scenario / "cam1.mp4")
    assert code == 1
    one_error_line(err, "two or more cameras", "cam1.mp4: 4")


def _cut(video: Path, until_ms: float, out: Path) -> Path:
    """The frames of ``video`` up to ``until_ms`` (its own stamps, ms), encoded again to ``out``."""
    import av

    from flashsync.simulation.encode import write_video

    frames, pts = [], []
    with av.open(str(video)) as container:
        time_base = container.streams.video[0].time_base
        for frame in container.decode(video=0):
            if frame.time * 1000 > until_ms:
                break
            frames.append(frame.to_ndarray(format="gray"))
            pts.append(frame.pts)
    write_video(out, frames, pts, time_base)
    return out


def test_cameras_sharing_fewer_events_than_unknowns(tiny_scenario, tmp_path, capsys):
    # cam1 sees four flashes, cam2's clip is cut to its first two: 2 shared events
    short = _cut(tiny_scenario / "cam2.mkv", 1934 + 40, tmp_path / "short.mkv")
    code, _, err = run(capsys, "sync", tiny_scenario / "cam1.mp4", short, "-o", tmp_path / "sync.json")
    assert code == 1
    one_error_line(err, "share")


def test_a_first_video_tied_to_no_camera_hands_the_reference_to_the_others(three_cameras, tmp_path, capsys):
    """``a`` cut to its first second sees one of the three flashes. Given first, with no
    reference, ``sync`` used to stop; now it writes the model on the clock of ``b`` or ``c``
    (0.058 and 0.042 ms RMS off the truth on ``b``'s) and its first warning line says so.
    Given as the reference, ``a`` stops it with one line."""
    short = _cut(three_cameras / "a.mp4", 1000.0, tmp_path / "a.mp4")
    others = [three_cameras / "b.mkv", three_cameras / "c.mp4"]
    code, _, err = run(capsys, "sync", short, *others, "-o", tmp_path / "sync.json")
    assert code == 0, err
    model = load_model(tmp_path / "sync.json")
    assert set(model.cameras) == {"b", "c"}
    warnings = [line for line in err.splitlines() if "warning:" in line]
    assert (
        f"{short}: the first video, the reference unless one is given, shares too few flashes" in warnings[0]
        and f"{model.reference}'s clock is the global clock instead" in warnings[0]
    ), err
    errors = sync_errors(model, load_ground_truth(three_cameras / "truth.json"))
    assert errors["rms_ms"].max() < 0.2, errors
    code, _, err = run(capsys, "sync", short, *others, "--reference", "a", "-o", tmp_path / "again.json")
    assert code == 1
    one_error_line(err, "no camera shares enough flashes with a")
    assert not (tmp_path / "again.json").exists()


def test_detections_without_required_columns(tiny_scenario, tmp_path, capsys):
    run(capsys, "sync", tiny_scenario / "cam1.mp4", tiny_scenario / "cam2.mkv", "-o", tmp_path / "sync.json")
    pd.DataFrame({"camera": ["cam1"], "frame_no": [1], "row": [3.0]}).to_csv(tmp_path / "d.csv", index=False)
    code, _, err = run(
        capsys, "restamp", tmp_path / "d.csv", "--model", tmp_path / "sync.json", "-o", tmp_path / "out.csv"
    )
    assert code == 1
    one_error_line(err, "d.csv", "frame", "y")
    assert not (tmp_path / "out.csv").exists()


def test_camera_missing_from_model(tiny_scenario, tmp_path, capsys):
    run(capsys, "sync", tiny_scenario / "cam1.mp4", tiny_scenario / "cam2.mkv", "-o", tmp_path / "sync.json")
    pd.DataFrame({"camera": ["cam1", "cam7"], "frame": [1, 1], "y": [3.0, 4.0]}).to_csv(tmp_path / "d.csv", index=False)
    code, _, err = run(
        capsys, "restamp", tmp_path / "d.csv", "--model", tmp_path / "sync.json", "-o", tmp_path / "out.csv"
    )
    assert code == 1
    error_lines = [line for line in err.splitlines() if "error:" in line]
    assert len(error_lines) == 1 and "Traceback" not in err
    assert "d.csv names cameras that are not in" in error_lines[0]
    assert "sync.json: cam7 (it holds cam1, cam2);" in error_lines[0]
    out = pd.read_csv(tmp_path / "out.csv")
    assert list(out["restamp_error"].fillna("")) == ["", "unknown camera"]


def test_missing_model_file(tmp_path, capsys):
    pd.DataFrame({"camera": ["a"], "frame": [1], "y": [3.0]}).to_csv(tmp_path / "d.csv", index=False)
    code, _, err = run(capsys, "restamp", tmp_path / "d.csv", "--model", tmp_path / "none.json")
    assert code == 1
    one_error_line(err, "none.json", "flashsync sync")


def test_bad_option_values(tiny_scenario, capsys):
    code, _, err = run(
        capsys, "sync", tiny_scenario / "cam1.mp4", tiny_scenario / "cam2.mkv", "--row-time", "cam1=fast"
    )
    assert code == 1
    one_error_line(err, "--row-time")


def test_timestamps_from_an_rtp_csv(tiny_scenario, tmp_path, capsys):
    """Frame times from a CSV of 90 kHz RTP stamps that wrap around replace the container's."""
    from flashsync.timestamps import video_timestamps

    stamps_ms = video_timestamps(tiny_scenario / "cam2.mkv")
    rtp = (2**32 - 45_000 + np.round((stamps_ms - stamps_ms[0]) * 90).astype(np.int64)) % 2**32
    pd.DataFrame({"rtp": rtp}).to_csv(tmp_path / "cam2.csv", index=False)
    code, _, err = run(
        capsys,
        "sync",
        tiny_scenario / "cam1.mp4",
        tiny_scenario / "cam2.mkv",
        "--timestamps",
        f"cam2={tmp_path / 'cam2.csv'}",
        "-o",
        tmp_path / "sync.json",
    )
    assert code == 0, err
    run(capsys, "sync", tiny_scenario / "cam1.mp4", tiny_scenario / "cam2.mkv", "-o", tmp_path / "own.json")
    from_csv = load_model(tmp_path / "sync.json").camera("cam2")
    from_container = load_model(tmp_path / "own.json").camera("cam2")
    assert from_csv.frame_times_ms[0] == pytest.approx(0.0, abs=0.5)  # the CSV's clock starts at 0
    np.testing.assert_allclose(
        from_csv.t_global_ms(np.arange(72), 90.0), from_container.t_global_ms(np.arange(72), 90.0), atol=0.05
    )
    pd.DataFrame({"t_ms": stamps_ms[:-3]}).to_csv(tmp_path / "short.csv", index=False)
    code, _, err = run(
        capsys,
        "sync",
        tiny_scenario / "cam1.mp4",
        tiny_scenario / "cam2.mkv",
        "--timestamps",
        f"cam2={tmp_path / 'short.csv'}",
        "-o",
        tmp_path / "bad.json",
    )
    assert code == 1
    one_error_line(err, "short.csv", "timestamps for the")
    code, _, err = run(capsys, "detect", tiny_scenario / "cam1.mp4", "--timestamps", "cam9=x.csv")
    assert code == 1
    one_error_line(err, "--timestamps cam9")


def test_library_errors_name_data_and_the_command_adds_its_option(tiny_scenario, capsys):
    from flashsync.errors import InputError
    from flashsync.pipeline import detect_videos

    with pytest.raises(InputError) as error:
        detect_videos([tiny_scenario / "cam1.mp4"], flipped=["cam9"])
    assert error.value.parameter == "flipped" and "--" not in str(error.value)
    code, _, err = run(capsys, "sync", tiny_scenario / "cam1.mp4", tiny_scenario / "cam2.mkv", "--reference", "cam9")
    assert code == 1
    one_error_line(err, "--reference cam9: no such camera among cam1, cam2")
