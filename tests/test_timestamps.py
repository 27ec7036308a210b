from fractions import Fraction

import numpy as np
import pytest

from flashsync.errors import FlashsyncError
from flashsync.io.timestamps import load_timestamps
from flashsync.simulation.encode import write_video
from flashsync.timestamps import rtp_timestamps, shortest_step_ms, video_timestamps


def frames(n):
    return [np.full((32, 48), 40 + 5 * i, np.uint8) for i in range(n)]


def test_variable_frame_rate_and_drops_in_mp4(tmp_path):
    # 90 kHz stamps: 40 ms steps, one dropped frame (80 ms gap), then 33.3 ms steps
    stamps_ms = np.array([0, 40, 80, 160, 200, 233.333, 266.667, 300, 333.333, 366.667, 400, 433.333])
    pts = np.round(stamps_ms * 90).astype(int)
    write_video(tmp_path / "vfr.mp4", frames(len(pts)), pts, Fraction(1, 90_000))
    np.testing.assert_allclose(video_timestamps(tmp_path / "vfr.mp4"), pts / 90.0, atol=1e-9)


def test_b_frames_come_back_in_presentation_order(tmp_path):
    pts = np.arange(30) * 40
    write_video(tmp_path / "b.mkv", frames(30), pts, Fraction(1, 1000))  # libx264 uses B-frames
    times = video_timestamps(tmp_path / "b.mkv")
    np.testing.assert_array_equal(times, pts.astype(float))


def test_rtp_wraparound_is_unwrapped():
    start = 2**32 - 3 * 3600
    stamps = (start + np.arange(8) * 3600) % 2**32  # wraps after the third frame
    assert stamps[3] < stamps[2]
    np.testing.assert_allclose(rtp_timestamps(stamps), np.arange(8) * 40.0)


def test_rtp_csv_and_step_backwards(tmp_path):
    good = tmp_path / "rtp.csv"
    good.write_text("rtp\n" + "\n".join(str((2**32 - 3600 + i * 3000) % 2**32) for i in range(5)))
    np.testing.assert_allclose(load_timestamps(good), np.arange(5) * 1000 / 30)
    bad = tmp_path / "back.csv"
    bad.write_text("rtp\n1000\n4600\n2000\n")
    with pytest.raises(FlashsyncError, match="not increasing at frame 2"):
        load_timestamps(bad)


def test_csv_timestamps_in_ms(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("frame,t_ms\n0,0.0\n1,33.4\n2,66.7\n")
    np.testing.assert_allclose(load_timestamps(path), [0.0, 33.4, 66.7])


@pytest.mark.parametrize(
    "content, message",
    [
        ("frame,when\n0,1\n", "no timestamp column"),
        ("t_ms\n0\nabc\n5\n", "row 2, column t_ms is 'abc', expected a finite number of ms; fix the CSV"),
        ("t_ms\n0\n\n5\n", "row 2, column t_ms is '', expected a finite number"),
        ("t_ms\n0\ninf\n5\n", "row 2, column t_ms is 'inf'"),
        ("rtp\n0\n3003.5\n", "row 2, column rtp is '3003.5', expected a whole 90 kHz RTP stamp"),
        ("t_ms\n", "no rows; fix the CSV"),
        ("t_ms\n0\n40\n40\n", "not increasing at frame 2 .* fix the CSV: one row per decoded frame"),
    ],
)
def test_bad_timestamp_csv(tmp_path, content, message):
    path = tmp_path / "t.csv"
    path.write_text(content)
    with pytest.raises(FlashsyncError, match=message):
        load_timestamps(path)


def test_not_a_video_and_missing_file(tmp_path):
    text = tmp_path / "notes.mp4"
    text.write_text("hello")
    with pytest.raises(FlashsyncError, match="not a video file"):
        video_timestamps(text)
    with pytest.raises(FlashsyncError, match="no such file"):
        video_timestamps(tmp_path / "missing.mp4")


def test_frame_clock_behind_quantised_stamps_with_drops_and_its_parts():
    """29.97 fps stamped on a 1 ms grid, two frames dropped: the clock finds the period and
    the drops; each part switched off leaves what it explains."""
    from flashsync.frame_clock import fit_frame_clock

    period = 1000.0 / 29.97
    slots = np.delete(np.arange(400), [100, 250])
    true_ms = 5000.0 + slots * period
    clock = fit_frame_clock(np.round(true_ms))
    assert clock.steady and clock.dropped == 2 and clock.quantum_ms == 1.0
    assert clock.period_ms == pytest.approx(period, abs=1e-4)
    assert np.max(np.abs(clock.times_ms - true_ms)) < 0.05
    index_only = fit_frame_clock(np.round(true_ms), count_gaps=False, smoothing=False)
    assert not index_only.steady and index_only.missing == 0
    median_step = fit_frame_clock(np.round(true_ms), least_squares=False, smoothing=False)
    assert median_step.period_ms == median_step.median_step_ms == 33.0 and not median_step.steady


def test_the_shortest_step_is_the_fast_rates_whatever_the_drops_and_rounding():
    """The frame period a camera's rows are read within: 20 ms for a 50 fps camera that
    halves its rate for most of the recording; drops and 1 ms rounding do not move it."""
    fast, slow = np.arange(100) * 20.0, 2000.0 + np.arange(150) * 40.0
    assert shortest_step_ms(np.concatenate([fast, slow])) == 20.0
    steady = np.delete(np.arange(300) * 1000.0 / 29.97, [40, 41, 90])
    assert shortest_step_ms(np.round(steady)) == 33.0  # 1 ms stamps: steps of 33 and 34
    assert shortest_step_ms(steady) == pytest.approx(1000.0 / 29.97)
    assert shortest_step_ms(np.array([5.0])) == 0.0
