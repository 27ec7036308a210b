"""Accuracy and calibration on small rigs of the simulator's second world
(`flashsync.simulation.rigs.random_rig`: pulses, tone curves, codecs and stamps the detector
was not designed on), against their ground truth, run as ``flashsync sync`` runs (both
readings, no options). Each rig is 320x180 at most, 8 s, two to four cameras."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from flashsync import detect_videos, synchronize
from flashsync.evaluate import camera_accuracy
from flashsync.model import readout_rows
from flashsync.simulation import render_scenario
from flashsync.simulation.rigs import random_rig

#: Seeds of small rigs. 20: a 59.94 fps upright camera and a 29.97 fps upside-down one with
#: six LED flashes; both used to be read the wrong way up (18 and 39 ms off): each wrong
#: reading fitted its few events almost exactly, and outscored the right readings, which
#: matched more events; then its sigma was 2.5 times too small. 22: the same rates, the
#: 59.94 fps camera upside down. 8: three rates, one upside down.
SEEDS = (20, 22, 8)


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """Each seed's scenario, model, report and accuracy table (per camera)."""
    rigs = []
    for seed in SEEDS:
        scenario = random_rig(seed, max_height=180, duration_ms=8000.0, cameras=(2, 4))
        folder = tmp_path_factory.mktemp(scenario.name)
        truth = render_scenario(scenario, folder)
        detections = detect_videos([folder / truth.cameras[c.name].file for c in scenario.cameras])
        model, report = synchronize(detections)
        rigs.append((scenario, model, report, camera_accuracy(model, truth).set_index("camera")))
    return rigs


def test_every_camera_is_read_the_right_way_up_or_warned(solved):
    """A camera read the wrong way up is allowed only where the report says the other
    reading fits about as well and its sigma covers its error. Rig-20 is such a near tie
    when it is the first clip this process encodes (x264's output then differs slightly):
    its mirror reading scores a log-likelihood lead of 2.5 where a choice needs 5, both
    cameras are warned and their sigmas (16 and 51 ms) cover their errors (19 and 39 ms);
    rendered after other clips it is read right."""
    for scenario, model, report, table in solved:
        wrong = [c.name for c in scenario.cameras if model.cameras[c.name].flipped != c.flipped]
        for name in wrong:
            warned = [w for w in report.warnings if Path(w.split(": ")[0]).stem == name]
            assert any("fit the other way about as well" in w for w in warned), (scenario.name, name, warned)
            assert table.loc[name, "rms_ms"] <= 2.0 * table.loc[name, "sigma_rms_ms"], (scenario.name, table)
        if not wrong:
            assert table["rms_ms"].max() < 0.5, (scenario.name, table)


def test_sigma_is_calibrated(solved):
    """Error / sigma of the non-reference cameras against the truth (their sigma holds the
    reference's) has an RMS of at most 2, pairwise too, and over the rigs 90 % of the probes
    lie within 2 sigma (the issue's measure; one camera alone may have fewer). Per camera: none over 3
    and at most one over 2. A camera's RMS is one draw too, and an exact sigma puts it over
    2 for about 2 % of cameras (chi-square of two degrees of freedom over two above 4:
    e^-4), over 3 for 0.01 %: with "every camera at most 2" one suite run in ten or so
    would fail with a perfect sigma (a fresh-clone run did: rig-20's camera at 2.07, every
    other camera of the three rigs under 0.7). Sigma is not too wide
    either: the RMS of error / sigma over all cameras' probes is 0.3 at least. Per camera
    it may be less: a camera's error is one draw of its few parameters' errors (shift, time
    per row), and a calibrated sigma gives an RMS under 0.5 to a fifth of the cameras
    (chi-square of two degrees of freedom over two under 0.25: 22 %). Sigma holds the
    errors a flash brings to all of a camera's edges, which the solve's residuals do not
    show, from the solve with each flash left out (:mod:`flashsync.jackknife`; before, two
    bias terms set by hand). Rig-20 included: a
    59.94 fps reference and a 29.97 fps camera with six LED flashes, whose one split band
    used to tie the reference's time per row 1.6 % off at a claimed 0.02 % (error / sigma 2.5)."""
    tables = pd.concat([table.assign(rig=scenario.name) for scenario, _, _, table in solved])
    others = tables[~tables["reference"]]
    for z in (others["z_rms"], tables["pair_z_rms"]):
        assert (z <= 3.0).all() and (z > 2.0).sum() <= 1, tables
    assert 0.3 <= np.sqrt(np.mean(others["z_rms"] ** 2)) <= 2.0, others
    assert others["within_2sigma"].mean() >= 0.9, others
    assert tables["pair_within_2sigma"].mean() >= 0.9, tables
    assert 0.3 <= np.sqrt(np.mean(tables["pair_z_rms"] ** 2)), tables


def test_the_exposures_sigma_covers_its_error(solved):
    """Every camera's exposure lies within 3 sigma of the truth and the RMS of error / sigma
    over the rigs' cameras is between 0.3 and 2: sigma holds the solve's, the flashes' scatter
    and the share all of a camera's flashes have (:data:`~flashsync.pipeline.EXPOSURE_FLOOR_MS`).
    The solve's alone gave 2.4 over the kept random rigs 0-29, 66 % within 2 sigma."""
    tables = pd.concat([table.assign(rig=scenario.name) for scenario, _, _, table in solved])
    z = tables["exposure_z"].dropna()
    assert len(z) == tables["exposure_error_ms"].notna().sum() >= 6, tables
    assert (z.abs() <= 3.0).all() and 0.3 <= np.sqrt(np.mean(z**2)) <= 2.0, tables[["exposure_error_ms", "exposure_z"]]


def test_the_reference_cameras_sigma_is_its_rows(solved):
    """The global clock is the reference's: at its first row the reference's times are that
    clock, uncertain by its frame times' own std alone; further down they carry its time per
    row's uncertainty. (Every other camera's sigma holds the reference's edges' share: the
    flashes' scatter, :mod:`flashsync.jackknife`.)"""
    for _, model, _, _ in solved:
        reference = model.camera(model.reference)
        rows = readout_rows(np.array([0.0, reference.height - 1.0]), reference.height, reference.flipped)
        std = reference.t_global_std_ms(np.array([0, 0]), rows)
        assert std[0] == pytest.approx(reference.alpha * reference.frame_std_ms[0], abs=1e-9)
        assert std[1] > std[0] + 0.001


@pytest.fixture(scope="module")
def rig_4(tmp_path_factory):
    """Random rig 4 as bench_rigs.py renders it (six cameras of 180-360 rows at 25, 50 and
    59.94 fps, 8 s, cam1 the reference with exact stamps): its detections (both readings),
    accuracy table (per camera) and truth."""
    scenario = random_rig(4, max_height=360, duration_ms=8000.0)
    folder = tmp_path_factory.mktemp(scenario.name)
    truth = render_scenario(scenario, folder)
    detections = detect_videos([folder / truth.cameras[c.name].file for c in scenario.cameras])
    model, _ = synchronize(detections)
    return detections, camera_accuracy(model, truth).set_index("camera"), truth


def test_time_per_row_sigma_is_calibrated(rig_4):
    """Each camera's time per row lies within 3 of its own sigmas of the truth. A camera's
    edges share a bias that grows with the row, about 0.15 ms across the frame: a larger
    share of a shorter readout. Rig-4's cam2 (50 fps, 180 rows) is 2.2 % off: 4.45 sigmas
    where the bias was 0.3 % of its time per row, 2.4 now."""
    _, table, _ = rig_4
    assert (table["row_time_z"].abs() <= 3.0).all(), table[["row_time_error_pct", "row_time_z"]]


@pytest.fixture(scope="module")
def rig_4_jittered(rig_4):
    """Rig 4 solved with its reference's (cam1's, 50 fps) stamps jittered by 0.8 ms: the
    model and report."""
    detections = rig_4[0]
    reference = detections[0]
    jitter = np.random.default_rng(0).normal(0.0, 0.8, len(reference.frame_times_ms))
    return synchronize([reference.retimed(reference.frame_times_ms + jitter), *detections[1:]])


def test_a_reference_with_jittered_stamps_is_warned_about_and_in_its_sigma(rig_4, rig_4_jittered):
    """The global clock is the reference's: where its stamps leave its rate uncertain (8 s
    of 50 fps stamps jittered by 0.8 ms: about 17 ppm), every camera's times share the error,
    and the report says so and names a camera with steadier stamps. The reference's sigma
    holds it, counted from its first frame (the global clock's origin): by its last frame
    its time is 0.12 ms off the truth here, its sigma 0.14 ms (0 before 2026-12-03). With
    its exact stamps, no such warning and no such sigma."""
    detections, _, truth = rig_4
    reference = detections[0]
    model, report = rig_4_jittered
    (warning,) = [w for w in report.warnings if "the reference's frame stamps" in w]
    assert warning.startswith(str(reference.video)) and "ppm" in warning, warning
    assert "(--reference cam" in warning and "(--reference cam1)" not in warning, warning
    first_and_last = np.array([0, len(reference.frame_times_ms) - 1])
    clock = model.camera(reference.camera)
    error = np.diff(
        clock.t_global_ms(first_and_last, 0.0) - truth.global_time_ms(reference.camera, first_and_last, 0.0)
    )
    sigma = clock.t_global_std_ms(first_and_last, np.zeros(2))
    assert abs(error[0]) > 0.06 and sigma[1] > 0.5 * abs(error[0]) and sigma[1] < 3 * abs(error[0]), (error, sigma)
    model, report = synchronize(detections)
    assert not [w for w in report.warnings if "the reference's frame stamps" in w], report.warnings
    assert model.camera(reference.camera).t_global_std_ms(first_and_last, np.zeros(2))[1] < 0.01


def test_every_cameras_sigma_holds_the_references(rig_4_jittered):
    """The errors of the reference's clock, the global clock, are every camera's against the
    truth: each camera's frame times carry the reference's then
    (:func:`~flashsync.pipeline._reference_shares_ms`), its rows' below its first (RMS over
    them; here 0.4 ms, its time per row pinned to 3.6 %) and, by its last frame, what its
    jittered stamps leave of its clock's rate (0.14 ms). Before 2026-12-03 the cameras with
    exact stamps had no frame sigma at all."""
    model, _ = rig_4_jittered
    reference = model.camera(model.reference)
    rows_ms = np.sqrt(reference.covariance[2, 2] * np.mean(np.arange(reference.height) ** 2.0))
    rate_ms = reference.frame_std_ms[-1]
    assert rate_ms > 0.1 and rows_ms > 0.1, (rate_ms, rows_ms)
    for name, camera in model.cameras.items():
        if name != model.reference:
            assert camera.frame_std_ms.min() >= 0.9 * rows_ms, (name, camera.frame_std_ms.min(), rows_ms)
            assert camera.frame_std_ms[-1] >= 0.8 * np.hypot(rows_ms, rate_ms), (name, camera.frame_std_ms[-1])
