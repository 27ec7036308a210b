"""Sensors that read their rows in part of the frame period (a sensor built for 50-120 fps
run at 25-30 idles in a long vertical blanking): the frame period over the height is then
the slow end of what the camera may have, so where the flashes do not tell the time per
row ``sync`` takes a readout spread over 10-100 % of the frame (``pipeline.row_time_prior_ms``),
and its uncertainty must say so."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from flashsync import detect_videos, pipeline, synchronize
from flashsync.errors import NotEnoughDataError
from flashsync.evaluate import camera_accuracy
from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario


@pytest.fixture(scope="module")
def same_row(tmp_path_factory):
    """cam1 (25 fps) reads its 180 rows in 52 % of its frame and sees every flash on one row
    (they fire 7-13 of its frames apart): its flashes cannot tell its time per row, 0.116
    ms against the nominal 0.212. The reference (30 fps, full readout) sees them on rows
    all over its frame. Both are read top-down, as mounted (their readout direction is not
    in question here)."""
    cameras = (
        CameraSpec("cam0", 320, 180, 30.0, r0=6, r1=4, exposure_ms=4.0),
        CameraSpec("cam1", 320, 180, 25.0, r0=6, r1=160, exposure_ms=4.0),
    )
    frames_apart = np.random.default_rng(1).choice([7, 8, 9, 11, 12, 13], 16)  # irregular: a pattern to match
    flashes = tuple(FlashSpec(410.0 + 40.0 * float(n), 0.5) for n in np.cumsum(frames_apart))
    truth, detections = _rendered(tmp_path_factory, "same-row", cameras, flashes, estimate_readout=False)
    model, report = synchronize(detections)
    return truth, model, report


def test_a_time_per_row_the_flashes_do_not_tell_has_a_sigma_that_covers_a_fast_readout(same_row):
    """cam1's time per row rests on the prior, which must allow a readout in half the frame:
    its time per row and its exposure (the bands' length in rows times it) within 3 sigmas
    of the truth, its times within 2 (RMS of error/sigma), and the report warns that its
    flashes do not pin its time per row down. With the prior on a readout over 10-100 % of
    the frame it comes out 0.123 ms (6.7 % off), its times 0.42 ms RMS off at error/sigma
    0.14; with the prior centred on the nominal (+-35 %, to 2026-12-02) 0.213 ms (84 % off),
    its times 5.4 ms off at 1.3, and at +-8 % (to 2026-11-29) at 5.7 and 5.6 sigmas."""
    truth, model, report = same_row
    table = camera_accuracy(model, truth).set_index("camera")
    assert truth.cameras["cam1"].row_time_ms == pytest.approx(0.1156, abs=0.001)  # the premise
    assert abs(table.loc["cam1", "row_time_error_pct"]) < 15.0, table.loc["cam1"]
    assert table.loc["cam1", "rms_ms"] < 1.0, table.loc["cam1"]
    assert abs(table.loc["cam1", "row_time_z"]) <= 3.0, table.loc["cam1"]
    assert abs(table.loc["cam1", "exposure_z"]) <= 3.0, table.loc["cam1"]
    assert table.loc["cam1", "z_rms"] <= 2.0, table.loc["cam1"]
    assert [w for w in report.warnings if "cam1.mp4: its time per row" in w], report.warnings


@pytest.fixture(scope="module")
def fast_and_full(tmp_path_factory):
    """cam1 (25 fps) reads its 180 rows in 45 % of its frame (time per row 0.097 ms, the
    nominal 0.212): timed at the nominal, its flashes on the lower rows come up to 20 ms
    late, twice the matching tolerance. cam0 (30 fps) and cam2 (50 fps) read over their
    whole frame. Sixteen flashes at irregular instants, on rows all over the frames."""
    cameras = (
        CameraSpec("cam0", 320, 180, 30.0, r0=6, r1=4, exposure_ms=4.0),
        CameraSpec("cam1", 320, 180, 25.0, r0=6, r1=227, exposure_ms=4.0, start_ms=500.0, offset_ms=-480.0),
        CameraSpec("cam2", 320, 180, 50.0, r0=8, r1=6, exposure_ms=3.0, start_ms=200.0, offset_ms=150.0),
    )
    return _rendered(tmp_path_factory, "fast-and-full", cameras, _irregular_flashes(), estimate_readout=False)


def _irregular_flashes() -> tuple[FlashSpec, ...]:
    """Sixteen flashes 150 ms + an exponential of 200 ms mean apart (a pattern to match),
    strengths 0.4-0.7."""
    rng = np.random.default_rng(1)
    instants = 300.0 + np.cumsum(150.0 + rng.exponential(200.0, 60))
    return tuple(FlashSpec(round(float(t), 3), round(float(rng.uniform(0.4, 0.7)), 3)) for t in instants)[:16]


def _rendered(tmp_path_factory, name: str, cameras: tuple, flashes: tuple, duration_ms: float = 6000.0, **detect):
    """The truth and detections (``detect``: options of :func:`detect_videos`) of cameras
    that see ``flashes`` and nothing else for ``duration_ms``."""
    folder = tmp_path_factory.mktemp(name)
    truth = render_scenario(Scenario(name, cameras, duration_ms, flashes=flashes, n_players=0, seed=1), folder)
    return truth, detect_videos([folder / f"{c.name}.mp4" for c in cameras], **detect)


def test_a_camera_that_reads_fast_is_tied_not_left_out(fast_and_full, monkeypatch):
    """Matched at the nominal time per row, cam1 shares too few flashes with the others and
    is left out; matched again at shorter times per row, it is tied and solved: within 0.1
    ms RMS of the truth (0.030), its time per row within 1 % (+0.39 %), error/sigma RMS
    within 2 (1.2)."""
    truth, detections = fast_and_full
    model, report = synchronize(detections)
    table = camera_accuracy(model, truth).set_index("camera")
    assert table.loc["cam1", "rms_ms"] < 0.1, table
    assert abs(table.loc["cam1", "row_time_error_pct"]) < 1.0, table
    assert table.loc["cam1", "z_rms"] <= 2.0, table
    assert not [w for w in report.warnings if "left out" in w], report.warnings
    monkeypatch.setattr(pipeline, "FAST_READOUT_SHARES", ())  # the premise: the nominal leaves it out
    _, report = synchronize(detections)
    assert [w for w in report.warnings if "cam1.mp4: shares too few flashes" in w], report.warnings


def test_a_reference_that_reads_fast_is_tied_to_the_others(fast_and_full, monkeypatch):
    """With cam1 as the reference, the nominal ties it to no camera and ``sync`` failed;
    matched again at shorter times per row, every camera is solved within 0.1 ms RMS."""
    truth, detections = fast_and_full
    model, _ = synchronize(detections, reference="cam1")
    table = camera_accuracy(model, truth).set_index("camera")
    assert set(model.cameras) == {"cam0", "cam1", "cam2"}
    assert (table["rms_ms"] < 0.1).all(), table
    monkeypatch.setattr(pipeline, "FAST_READOUT_SHARES", ())
    with pytest.raises(NotEnoughDataError, match="no camera shares enough flashes with cam1"):
        synchronize(detections, reference="cam1")


def test_a_reference_that_saw_no_flash_is_named_not_a_crash(fast_and_full):
    """A reference with no flash events cannot be tied, at any time per row: ``sync`` says so
    and names the reference to give instead. Matching again at shorter times per row tried
    the reference first without its events and raised a ``KeyError`` (a throwaway fast rig
    whose reference saw none of its flashes; the CLI would print a traceback)."""
    _, detections = fast_and_full
    blind = replace(detections[1], top_down=detections[1].top_down.take(np.zeros(len(detections[1].top_down), bool)))
    with pytest.raises(NotEnoughDataError, match="no camera shares enough flashes with cam1.*--reference cam"):
        synchronize([detections[0], blind, detections[2]], reference="cam1")


@pytest.fixture(scope="module")
def all_fast(tmp_path_factory):
    """Three cameras (30, 25 and 50 fps) that all read their 180 rows in 40 % of the frame
    (a rig of one fast sensor model run at low frame rates): at the nominal times per row
    each is 2.5x slow, and only some of its flashes match. Sixteen flashes."""
    cameras = (
        CameraSpec("cam0", 320, 180, 30.0, r0=6, r1=264, exposure_ms=4.0),
        CameraSpec("cam1", 320, 180, 25.0, r0=6, r1=264, exposure_ms=4.0, start_ms=500.0, offset_ms=-480.0),
        CameraSpec("cam2", 320, 180, 50.0, r0=8, r1=264, exposure_ms=3.0, start_ms=200.0, offset_ms=150.0),
    )
    return _rendered(tmp_path_factory, "all-fast", cameras, _irregular_flashes(), estimate_readout=False)


def test_a_rig_whose_every_camera_reads_fast_is_matched_at_one_share(all_fast):
    """Matched one camera at a time (the others at the nominal), cam1 was tied by the few
    flashes the nominal matched: 0.36 ms off, its time per row 5 % off. Every camera
    matched at one share of the nominal, each is within 0.05 ms RMS of the truth (0.001-
    0.021), its time per row within 1 % (0.41 % at most) and error/sigma RMS within 2."""
    truth, detections = all_fast
    model, _ = synchronize(detections)
    table = camera_accuracy(model, truth).set_index("camera")
    assert set(model.cameras) == {"cam0", "cam1", "cam2"}
    assert (table["rms_ms"] < 0.05).all(), table
    assert (table["row_time_error_pct"].abs() < 1.0).all(), table
    assert (table["z_rms"].dropna() <= 2.0).all(), table


@pytest.fixture(scope="module")
def long_bands(tmp_path_factory):
    """cam1 (50 fps) reads its 180 rows in 10 ms of its 20 ms frame and exposes each row for
    14 ms (252 rows): no band has both its edges in one frame. Its flashes are timed so that
    12 of 16 show only their band's trailing edge (its leading edge above the first row),
    4 only their leading edge. cam0 (30 fps) and cam2 (25 fps) read over their whole frame.
    Every camera is read both ways up, as ``sync`` does."""
    cameras = (
        CameraSpec("cam0", 320, 180, 30.0, r0=6, r1=4, exposure_ms=4.0),
        CameraSpec("cam1", 320, 180, 50.0, r0=6, r1=174, exposure_ms=14.0, start_ms=500.0, offset_ms=-480.0),
        CameraSpec("cam2", 320, 180, 25.0, r0=8, r1=6, exposure_ms=3.0, start_ms=200.0, offset_ms=150.0),
    )
    rng = np.random.default_rng(1)
    instants = 300.0 + np.cumsum(150.0 + rng.exponential(200.0, 16))
    # ms into cam1's frame: its leading edge on rows 0-180 from 0.3 to 10.3, its trailing one 14 later
    lead = np.arange(16) % 5 == 0
    into_frame = np.where(lead, rng.uniform(2.5, 5.5, 16), rng.uniform(11.0, 14.5, 16))
    camera_ms = 500.0 + 20.0 * np.floor((instants + 480.0 - 500.0) / 20.0) + into_frame
    strengths = rng.uniform(0.4, 0.7, 16)
    flashes = tuple(FlashSpec(round(float(t - 480.0), 3), round(float(s), 3)) for t, s in zip(camera_ms, strengths))
    return _rendered(tmp_path_factory, "long-bands", cameras, flashes, duration_ms=6500.0)


def test_lone_trailing_edges_tie_a_camera_whose_bands_outlast_its_readout(long_bands):
    """With no band of both edges, cam1's exposure was unknown, its lone trailing edges
    left out: it was tied by its 4 leading edges, its time per row +/- 29 %, 0.043 ms off.
    Its lone trailing edges enter with the exposure unknown (the solve fits it): all 16
    flashes tie it, read the right way up, within 0.02 ms RMS of the truth (0.004), its
    time per row within 0.5 % at a sigma under 3 % (0.04 % +/- 1.1 %), its exposure within
    0.1 ms of 14 (-0.003)."""
    truth, detections = long_bands
    model, _ = synchronize(detections)
    table = camera_accuracy(model, truth).set_index("camera")
    camera = model.cameras["cam1"]
    assert not camera.flipped
    assert int(np.sum(model.events["camera"] == "cam1")) == 16, model.events
    assert table.loc["cam1", "rms_ms"] < 0.02, table
    assert abs(table.loc["cam1", "row_time_error_pct"]) < 0.5, table
    assert np.sqrt(camera.covariance[2, 2]) < 0.03 * camera.row_time_ms
    assert abs(table.loc["cam1", "exposure_error_ms"]) < 0.1, table
    assert table.loc["cam1", "z_rms"] <= 2.0, table


def test_a_camera_read_the_wrong_way_up_is_left_out_with_a_word(long_bands):
    """Read the wrong way up, a camera's bands still fit the other cameras' flashes, with a
    time per row no sensor has (negative: its rows running backwards in time). Matching
    again at shorter times per row in every attempt can tie it so (a variant measured
    without lone trailing edges put a throwaway fast draw's camera 12 ms off at error/sigma
    25), and an upside-down camera given upright, or an upright one given as ``--flipped``,
    is tied so: cam2 (upright) read bottom-up only came out 3.1 ms off at error/sigma 75,
    its time per row -0.206 ms, with no word. Now it is left out with a warning that names
    it, the others solved as before; the reference so read fails with one line that says
    why."""
    truth, detections = long_bands
    upside_down = [d.read_only(d.camera == "cam2") for d in detections]
    model, report = synchronize(upside_down)
    assert set(model.cameras) == {"cam0", "cam1"}
    assert [w for w in report.warnings if "cam2.mp4: read bottom-up, its time per row comes out -0.2" in w], report
    table = camera_accuracy(model, truth).set_index("camera")
    assert (table["rms_ms"].dropna() < 0.02).all(), table
    with pytest.raises(NotEnoughDataError, match=r"cam2.mp4, the reference: .*backwards in time.*another --reference"):
        synchronize(upside_down, reference="cam2")


@pytest.fixture(scope="module")
def whole_frames(tmp_path_factory):
    """cam1 (25 fps) reads its 180 rows in 1 % of its frame (0.4 ms, as a global shutter
    does) and exposes each for 16 ms: a flash in its exposure lights every row of one frame
    at once, one in the other 24 ms none. cam0 (30 fps) and cam2 (50 fps) read over their
    whole frame. Sixteen flashes."""
    cameras = (
        CameraSpec("cam0", 320, 180, 30.0, r0=6, r1=4, exposure_ms=4.0),
        CameraSpec("cam1", 320, 180, 25.0, r0=6, r1=18414, exposure_ms=16.0, start_ms=500.0, offset_ms=-480.0),
        CameraSpec("cam2", 320, 180, 50.0, r0=8, r1=6, exposure_ms=3.0, start_ms=200.0, offset_ms=150.0),
    )
    return _rendered(tmp_path_factory, "whole-frames", cameras, _irregular_flashes())


def test_a_camera_whose_flashes_light_whole_frames_is_left_out_with_the_reason(whole_frames):
    """cam1's flashes leave no band edge, so it has no event to be timed by: it is left out,
    and the warning says why (its frames lit whole, a global shutter?) instead of only that
    it had no usable event. The detector counts those frames (as many as the flashes that
    fell in its exposures) and none in the rolling-shutter cameras."""
    truth, detections = whole_frames
    lit = sum(1 for frames in truth.cameras["cam1"].flashes_seen.values() if frames)
    counts = {d.camera: d.n_whole_frames for d in detections}
    assert lit >= 3 and counts == {"cam0": 0, "cam1": lit, "cam2": 0}, (lit, counts)
    model, report = synchronize(detections)
    assert set(model.cameras) == {"cam0", "cam2"}
    assert [w for w in report.warnings if "cam1.mp4: 0 usable flash events" in w and "lit whole" in w], report.warnings
