"""The frame clock behind real-world stamps: jitter, drops, a rate change, pauses, a phase
break, a variable rate; and the pipeline using it (accuracy against simulator truth)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from flashsync.frame_clock import fit_frame_clock

PERIOD = 1000.0 / 29.97


def ladder(slots: np.ndarray, offset: float = 5000.0) -> np.ndarray:
    return offset + slots * PERIOD


def affine_rms(times: np.ndarray, truth: np.ndarray) -> float:
    """RMS of times minus truth after the best line (what the solve's alpha and beta absorb)."""
    error = times - truth
    fitted = np.polyval(np.polyfit(truth, error, 1), truth)
    return float(np.sqrt(np.mean((error - fitted) ** 2)))


@pytest.mark.parametrize("jitter_ms, drops", [(1.2, [100, 250, 251, 600]), (2.0, [100, 250, 251, 600]), (5.0, [])])
def test_jitter_of_a_few_ms_is_estimated_and_the_steady_clock_behind_it_used(jitter_ms, drops):
    """(At 5 ms a stamp lands 3.3 sigma, half a period, off once in a thousand: next to a
    dropped frame which slot it belongs to cannot be told.)"""
    rng = np.random.default_rng(int(jitter_ms * 10))
    slots = np.delete(np.arange(900), drops)
    truth = ladder(slots)
    clock = fit_frame_clock(truth + jitter_ms * rng.standard_normal(len(truth)))
    assert clock.steady and len(clock.segments) == 1
    assert clock.jitter_ms == pytest.approx(jitter_ms, rel=0.1)
    assert clock.dropped == len(drops) and clock.period_ms == pytest.approx(PERIOD, abs=0.01)
    assert affine_rms(clock.times_ms, truth) < 0.05 * jitter_ms
    assert np.all(clock.std_ms == 0)  # no wander followed: the error is affine, the solve absorbs it


def test_stamps_jittered_a_sixth_of_a_59_94_fps_period_keep_every_frame_on_its_slot():
    """3 ms of jitter at 59.94 fps (16.7 ms): now and then a stamp lands past half a period
    and rounds onto its neighbour's slot; the one farther from that slot moves (moving the
    later one always, every slot after it came out one late in 13 of 30 draws of 360 frames).
    Ten draws, every frame on its own slot, one steady segment."""
    period = 1000.0 / 59.94
    for seed in range(10):
        rng = np.random.default_rng(seed)
        truth = np.arange(360) * period
        clock = fit_frame_clock(truth + 3.0 * rng.standard_normal(len(truth)))
        assert np.array_equal(clock.slots, np.arange(len(truth))), seed
        assert clock.steady and len(clock.segments) == 1, seed


def test_stamps_jittered_three_tenths_of_a_59_94_fps_period_keep_every_frame_on_its_slot():
    """5 ms of jitter at 59.94 fps: over the first 64 stamps the periodogram's highest peak
    is often an alias (0.73 of the period in the bench_diagnose rig, whose ``sync`` was then
    4.1 ms off); the head grows until its peak stands out of what random phases give. Ten
    draws of 360 frames, every frame on its own slot."""
    period = 1000.0 / 59.94
    for seed in range(10):
        rng = np.random.default_rng(100 + seed)
        truth = np.arange(360) * period
        clock = fit_frame_clock(truth + 5.0 * rng.standard_normal(len(truth)))
        assert np.array_equal(clock.slots, np.arange(len(truth))), seed
        assert clock.period_ms == pytest.approx(period, abs=0.05), seed


@pytest.mark.parametrize(
    "fps, factor, jitter_ms, least",
    [
        (59.94, 1.05, 1.2, 10),
        (29.97, 1.5, 3.0, 10),
        (29.97, 0.5, 1.2, 10),
        (59.94, 0.5, 1.2, 10),
        (59.94, 1.05, 3.0, 9),
    ],
)
def test_a_rate_change_within_jitter_offers_the_steady_sensor(fps, factor, jitter_ms, least):
    """From frame 150 on the stamps run ``factor`` times as fast, with jitter. 5 % fast at
    59.94 fps with 1.2 ms stays within half a period of the old clock for 20 frames at a
    time, and 1.5x at 29.97 fps with 3 ms alternates between its ticks and their middles:
    residuals whose running mean and steps look white (every draw was one white clock with
    drops), three times the scatter the stamps' second differences show. Stamps slowing to
    half their rate tick on the faster clock too: the boundary went 30 frames early and
    the step into it counted a skipped slot. 5 % fast with 3 ms of jitter: one clock that
    slips a slot every 18-23 frames, regularly, where dropped frames come at random
    (:func:`~flashsync.frame_clock._regular_skips`); its boundary, once split, 20-120
    frames late, is sought from where the two clocks' lines cross. Of ten draws, at least
    ``least`` offer the truth as a one-rate alternative (up to the affine error the solve's
    drift and shift take up); over 40 draws 40, 39, 40, 40 and 37, against 37, 35, 40, 40
    and 0 before."""
    period = 1000.0 / fps
    truth = np.arange(360) * period
    stamps = np.where(np.arange(360) < 150, truth, truth[150] + (truth - truth[150]) * factor)
    right = 0
    for seed in range(10):
        clock = fit_frame_clock(stamps + jitter_ms * np.random.default_rng(seed).standard_normal(len(truth)))
        right += any(affine_rms(times, truth) < 0.5 for _, times in clock.one_rate_alternatives())
    assert right >= least


def test_a_rate_change_splits_the_clock_and_offers_the_steady_sensor():
    """From frame 451 on the stamps advance 1.5x as fast (a muxer fault): two segments, and
    the one-rate alternative is the truth."""
    truth = ladder(np.arange(900))
    stamps = truth.copy()
    stamps[450:] = truth[450] + 1.5 * (truth[450:] - truth[450])
    clock = fit_frame_clock(stamps + 0.3 * np.random.default_rng(1).standard_normal(900))
    assert clock.steady and len(clock.segments) == 2
    (frame, before, after), *_ = clock.rate_changes
    assert (
        frame in (450, 451)
        and before == pytest.approx(PERIOD, rel=1e-3)
        and after == pytest.approx(1.5 * PERIOD, rel=1e-3)
    )
    alternatives = dict(clock.one_rate_alternatives())
    assert len(alternatives) == 2
    best = min(alternatives.values(), key=lambda times: affine_rms(times, truth))
    assert affine_rms(best, truth) < 0.05
    assert np.all(clock.std_ms[451:] > 0)  # two lines: one affine map cannot absorb both errors


def test_a_pause_the_clock_ran_through_is_a_gap_not_drops():
    slots = np.concatenate([np.arange(400), np.arange(700, 1200)])
    truth = ladder(slots)
    clock = fit_frame_clock(truth + np.random.default_rng(2).standard_normal(len(truth)))
    assert clock.steady and len(clock.segments) == 1
    assert clock.gaps == [(400, 300)] and clock.dropped == 0
    assert affine_rms(clock.times_ms, truth) < 0.05


def test_a_pause_that_broke_the_phase_starts_a_new_segment():
    truth = ladder(np.concatenate([np.arange(400), np.arange(700, 1200)]))
    truth[400:] += 13.3  # the recording restarted off the old ladder
    clock = fit_frame_clock(np.round(truth))
    assert clock.breaks == [400] and not clock.rate_changes
    assert affine_rms(clock.times_ms, truth) < 0.05


def test_quantised_and_exact_stamps_are_steady_with_no_segments():
    truth = ladder(np.arange(900))
    for stamps in (np.round(truth), np.round(truth * 90) / 90):
        clock = fit_frame_clock(stamps)
        assert clock.steady and len(clock.segments) == 1 and clock.jitter_ms <= 0.3
        assert np.max(np.abs(clock.times_ms - truth)) < 0.05


def test_a_variable_rate_keeps_the_stamps_and_says_how_much_they_scatter():
    rng = np.random.default_rng(4)
    truth = 1000.0 + np.concatenate([[0.0], np.cumsum(PERIOD * rng.uniform(1.0, 1.3, 899))])
    clock = fit_frame_clock(truth + 0.5 * rng.standard_normal(900))
    assert not clock.steady
    np.testing.assert_array_equal(clock.times_ms, clock.stamps_ms)
    assert 0.2 < float(np.median(clock.std_ms)) < 3.0


def test_a_slow_wander_is_followed_where_it_stands_out_of_the_jitter():
    frames = np.arange(9000)
    truth = ladder(frames) + 0.5 * np.sin(frames / 9000 * 2 * np.pi)  # a 0.5 ms wander (a few ppm)
    clock = fit_frame_clock(truth + 0.2 * np.random.default_rng(5).standard_normal(9000))
    assert clock.steady and np.any(clock.wander_ms)
    assert affine_rms(clock.times_ms, truth) < 0.05
    assert 0 < float(np.median(clock.std_ms)) < 0.05  # the jitter left in the wander


# --- the pipeline on rendered footage, against truth -------------------------------------


@pytest.fixture(scope="module")
def synced_detections(synced_scenario):
    from flashsync import detect_videos
    from flashsync.io import load_ground_truth

    detections = detect_videos([synced_scenario / n for n in ("r.mp4", "f.mkv", "s.mp4")], estimate_readout=True)
    return detections, load_ground_truth(synced_scenario / "truth.json")


def _sync_errors(detections, truth, **options):
    from flashsync import synchronize
    from flashsync.evaluate import sync_errors
    from flashsync.report import sync_uncertainty_ms

    model, report = synchronize(detections, **options)
    errors = sync_errors(model, truth).set_index("camera")
    sigma = {name: sync_uncertainty_ms(camera) for name, camera in model.cameras.items()}
    return model, report, errors, sigma


def test_jittered_stamps_of_one_camera_cost_nothing(synced_detections):
    """Stamps of the 50 fps camera jittered by 2 ms (std): the sync stays at its accuracy
    with exact stamps (it cost 1.8 ms before the frame clock estimated jitter)."""
    detections, truth = synced_detections
    stamps = detections[2].frame_times_ms + 2.0 * np.random.default_rng(6).standard_normal(140)
    jittered = [*detections[:2], detections[2].retimed(np.maximum.accumulate(stamps))]
    _, report, errors, sigma = _sync_errors(jittered, truth)
    assert report.frame_clocks["s"].steady and report.frame_clocks["s"].jitter_ms == pytest.approx(2.0, rel=0.25)
    assert errors.loc["s", "rms_ms"] < 0.1, errors
    assert errors.loc["s", "rms_ms"] < 3 * sigma["s"]


def test_a_stamp_rate_change_is_resolved_by_the_flashes_and_reported(synced_detections):
    detections, truth = synced_detections
    times = detections[0].frame_times_ms.copy()
    times[40:] = times[40] + 1.5 * (times[40:] - times[40])
    changed = [detections[0].retimed(times), *detections[1:]]
    model, report, errors, _ = _sync_errors(changed, truth, reference="f")
    changes = [w for w in report.warnings if "r.mp4: its frame stamps change rate at frame" in w]
    assert len(changes) == 1 and "(40.000 -> 60.000 ms per frame)" in changes[0], report.warnings
    assert "the flashes fit one rate throughout, 40.000 ms per frame" in changes[0]
    assert errors["rms_ms"].max() < 0.1, errors


def test_a_datasheet_row_time_the_events_contradict_is_reported_and_not_used(synced_detections):
    detections, truth = synced_detections
    true_row = truth.cameras["s"].row_time_ms
    model, report, errors, _ = _sync_errors(detections, truth, row_times={"s": 1.4 * true_row})
    warning = [w for w in report.warnings if "datasheet time per row" in w]
    assert len(warning) == 1 and "s.mp4" in warning[0] and f"{1.4 * true_row:g}" in warning[0]
    assert model.cameras["s"].row_time_ms == pytest.approx(true_row, rel=0.01)
    assert errors["rms_ms"].max() < 0.1, errors
    model, report, _, _ = _sync_errors(detections, truth, row_times={"s": true_row})
    assert not [w for w in report.warnings if "datasheet" in w]


def test_the_frame_clock_uncertainty_is_in_sigma():
    from flashsync.model import CameraClock

    clock = CameraClock("c", np.arange(10) * 40.0, 100, 100, row_time_ms=0.3)
    assert clock.t_global_std_ms(np.array([3]), np.array([5.0]))[0] == 0.0
    noisy = dataclasses.replace(clock, alpha=2.0, frame_std_ms=np.full(10, 0.25))
    assert noisy.t_global_std_ms(np.array([3]), np.array([5.0]))[0] == pytest.approx(0.5)


def test_the_robust_line_is_the_least_squares_line_of_polyfit():
    from flashsync.frame_clock import _line

    rng = np.random.default_rng(3)
    x = np.cumsum(rng.integers(1, 3, 5000)).astype(np.float64)
    y = 1_234.5 + 33.3667 * x + rng.normal(0.0, 0.3, len(x))
    slope, intercept = np.polyfit(x, y, 1)
    np.testing.assert_allclose(_line(x, y), (slope, intercept), rtol=1e-12)
