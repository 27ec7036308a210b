"""The readout directions :func:`~flashsync.synchronize` chooses do not depend on the order
of the cameras or on the reference, on a rig where they used to: three cameras of random
rig 14 (`flashsync.simulation.rigs.random_rig`, 12 players instead of 30 to render
faster), cam6 upright at 29.97 fps, cam8 and cam10 upside down at 59.94 fps, 8 flashes in
8 s. The ascent of single flips from the detected readings (all upright) read them right
with cam6 first; with cam10 or cam8 first it took the wrong single flip first (cam6) and
ended with all three read the wrong way up, 20-40 ms off with no warning."""

from __future__ import annotations

import re
import tempfile
from dataclasses import replace
from pathlib import Path

import pytest

from flashsync import detect_videos, synchronize
from flashsync.detect import CameraDetection
from flashsync.evaluate import camera_accuracy
from flashsync.report import detection_notes
from flashsync.simulation import render_scenario
from flashsync.simulation.rigs import random_rig

#: The cameras of rig-14 kept, in the order the scenario gives them (cam6 is the truth's reference).
CAMERAS = ("cam6", "cam8", "cam10")

#: Camera orders tried (the first camera is the reference).
ORDERS = (CAMERAS, ("cam10", "cam8", "cam6"), ("cam8", "cam10", "cam6"))


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """The scenario, its truth and the detections (both readings), in CAMERAS order."""
    full = random_rig(14, max_height=360, duration_ms=8000.0)
    cameras = tuple(c for c in full.cameras if c.name in CAMERAS)
    scenario = replace(full, name="rig-14-three", cameras=cameras, n_players=12)
    folder = tmp_path_factory.mktemp(scenario.name)
    truth = render_scenario(scenario, folder)
    detections = detect_videos([folder / truth.cameras[name].file for name in CAMERAS])
    return scenario, truth, detections


@pytest.fixture(scope="module")
def solved(rig):
    """Per order: the model, the report and the accuracy table (per camera)."""
    _, truth, detections = rig
    by_name = {d.camera: d for d in detections}
    results = {}
    for order in ORDERS:
        model, report = synchronize([by_name[name] for name in order])
        results[order] = (model, report, camera_accuracy(model, truth).set_index("camera"))
    return results


def test_the_readouts_do_not_depend_on_the_camera_order_or_the_reference(solved):
    readings = {
        order: {name: camera.flipped for name, camera in model.cameras.items()}
        for order, (model, _, _) in solved.items()
    }
    first = readings[ORDERS[0]]
    assert set(first) == set(CAMERAS), first
    for order, reading in readings.items():
        assert reading == first, (order, reading, first)


def test_every_camera_is_read_the_right_way_up_or_warned(rig, solved):
    """A camera read the wrong way up must be warned, its sigma covering its error; one
    read right is within 1 ms of the truth (a wrong reading is 20-40 ms off here; on
    another reference than the truth's, that reference's drift of 30-40 ppm adds up to
    0.3 ms over 8 s: the global clock runs at the reference's rate)."""
    scenario = rig[0]
    for order, (model, report, table) in solved.items():
        for spec in scenario.cameras:
            assert spec.name in model.cameras, (order, spec.name, report.warnings)
            if model.cameras[spec.name].flipped == spec.flipped:
                assert table.loc[spec.name, "rms_ms"] < 1.0, (order, table)
                continue
            warned = [w for w in report.warnings if f"{spec.name}." in w and "fit the other way about as well" in w]
            assert warned, (order, spec.name, report.warnings)
            assert table.loc[spec.name, "rms_ms"] <= 2.0 * table.loc[spec.name, "sigma_rms_ms"], (order, table)


@pytest.fixture(scope="module")
def equal_rates():
    """Random rig 18 as bench_rigs renders it: three upright cameras at 59.94 fps (two of
    270 rows, one of 360), 7 flashes in 8 s; its truth and its model from the detections
    (both readings) in the scenario's order. One flip of cam1 led the upright reading by
    5.3 on the reference the readouts were chosen on and trailed it by 5.3 on cam1: cam1
    was read upside down, 18 ms off with a sigma of 0.7 ms and no warning."""
    with tempfile.TemporaryDirectory() as folder:
        scenario = random_rig(18, max_height=360, duration_ms=8000.0)
        truth = render_scenario(scenario, Path(folder))
        detections = detect_videos([Path(folder) / truth.cameras[c.name].file for c in scenario.cameras])
    model, report = synchronize(detections)
    return scenario, model, report, camera_accuracy(model, truth).set_index("camera")


def test_a_flip_the_evidence_does_not_decide_is_not_taken_silently(equal_rates):
    """Every camera is read right or is warned with sigma covering its error (here: read
    right, the mounting prior and the margin together keep cam1 upright, and warned)."""
    scenario, model, report, table = equal_rates
    for spec in scenario.cameras:
        if model.cameras[spec.name].flipped == spec.flipped:
            continue
        warned = [w for w in report.warnings if f"{spec.name}." in w and "fit the other way about as well" in w]
        assert warned, (spec.name, report.warnings)
        assert table.loc[spec.name, "rms_ms"] <= 2.0 * table.loc[spec.name, "sigma_rms_ms"], table


def test_a_rig_of_mostly_one_frame_rate_is_not_read_as_its_mirror(tmp_path):
    """Random rig 782 as bench_rigs renders it at 360 rows: four 30 fps cameras (cam1, cam3
    and cam5 upside down) and one at 25 fps, 12 flashes in 10 s. The ascent of flips from
    the detected readings (all upright) ended with every camera read the wrong way up
    (log-likelihood 56 against the right reading's 122): at one frame rate a reading's
    mirror fits about as well, and no single flip, nor a camera with those that lose by it,
    leads out of it. 17-35 ms off the truth, with no warning. Every undecided camera
    flipped at once is the ascent's last move: all read right, within 0.2 ms."""
    scenario = random_rig(782, max_height=360, duration_ms=10000.0)
    truth = render_scenario(scenario, tmp_path)
    detections = detect_videos([tmp_path / truth.cameras[c.name].file for c in scenario.cameras])
    model, report = synchronize(detections)
    assert {name: camera.flipped for name, camera in model.cameras.items()} == {
        c.name: c.flipped for c in scenario.cameras
    }, report.warnings
    assert (camera_accuracy(model, truth).rms_ms < 0.2).all()


@pytest.mark.parametrize(("seed", "height"), [(15, 540), (30, 360)])
def test_a_camera_few_flashes_tie_is_turned_on_a_lead_beyond_a_flash(tmp_path, seed, height):
    """Random rig 15 as bench_rigs renders it (540 rows, 12 s): two upright cameras, 25 fps
    at 360 rows (the reference, seeing 4 of 8 flashes) and 50 fps at 540, sharing four. Read
    upside down, the first fits one flash more, a lead of 10.5, on three flashes tying it; it
    was read so, its time per row 65 % short, both cameras 7-30 ms off (under a sigma of
    25-34 ms). Random rig 30 at 360 rows: six cameras, the reference (59.94 fps, 270 rows)
    truly upside down, tied by three flashes that way, where it leads by 41 (as bench_rigs
    renders it, by 43: a rule of four flashes tying a turned camera kept it upright, every
    camera 6.5-14.5 ms off). A turn of a camera so few tie needs a lead beyond what one flash
    more is worth to it (about 12): rig-15 stays upright, warned, the other reading in its
    sigma, its times' and its exposure's (cam2's exposure 4.36 ms read upright, 2.53 ms the
    other way; its sigma was 0.03 ms); rig-30's reference is turned."""
    scenario = random_rig(seed, max_height=height, duration_ms=12000.0)
    truth = render_scenario(scenario, tmp_path)
    model, report = synchronize(detect_videos([tmp_path / truth.cameras[c.name].file for c in scenario.cameras]))
    assert {n: c.flipped for n, c in model.cameras.items()} == {
        c.name: c.flipped for c in scenario.cameras if c.name in model.cameras
    }, report.warnings
    table = camera_accuracy(model, truth).set_index("camera")
    assert (table["rms_ms"] < 1.5).all() and (table["rms_ms"] < table["sigma_rms_ms"]).all(), table
    if seed == 15:
        (warning,) = [w for w in report.warnings if "cam1." in w and "fit the other way about as well" in w]
        assert "read top-down (upright)" in warning and "a flash's worth per camera it turns" in warning
        for name in ("cam1", "cam2"):
            (warning,) = [w for w in report.warnings if f"{name}." in w and "fit the other way about as well" in w]
            gap_ms = float(re.search(r"its exposure by ([0-9.]+) ms", warning).group(1))
            assert gap_ms > 0.5 and model.cameras[name].exposure_std_ms >= gap_ms, warning


def test_a_flickers_roll_tells_the_readout_the_flashes_leave_mirrored(tmp_path, monkeypatch):
    """The second world's rig-366 (``random_rig(366, max_height=360, duration_ms=8000)``) at
    half its size: two 25 fps cameras under 9.4 % 120 Hz flicker, cam2 upside down. At one
    frame rate the flashes fit both cameras read the other way about as well, and they chose
    that mirror: 41.6 and 39.7 ms RMS off the truth. cam2's flicker rolls as a sensor reading
    bottom-up makes it (4.8 periods a frame), so it is read that way only; the flashes then
    read cam1 upright: 0.02 and 0.07 ms. ``flashsync detect``, which reads a camera as told,
    says that cam2's flicker rolls the other way."""
    scenario = random_rig(366, max_height=360, duration_ms=8000.0)
    cameras = tuple(replace(c, width=c.width // 4 * 2, height=c.height // 4 * 2) for c in scenario.cameras)
    truth = render_scenario(replace(scenario, cameras=cameras), tmp_path)
    detections = detect_videos([tmp_path / f"{c.name}.{c.container}" for c in cameras])
    assert detections[1].flicker.bottom_up is True and all(d.undecided for d in detections)
    model, report = synchronize(detections)
    assert report.flipped_found == ["cam2"]
    assert (camera_accuracy(model, truth).rms_ms < 0.15).all()
    monkeypatch.setattr(CameraDetection, "read_as_rolled", lambda self: self)
    model, report = synchronize(detections)
    assert report.flipped_found == ["cam1"]  # the mirror, without the roll
    told = detections[1].read_only(False)  # as `flashsync detect` reads it: upright unless told
    (note,) = [n for n in detection_notes(told) if "rolling flicker" in n]
    assert note.endswith(
        "rolling as a sensor reading bottom-up makes it (read top-down as told: give --flipped cam2 if it is "
        "mounted upside down)"
    )
