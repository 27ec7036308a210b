"""The discrepancy workflow on rendered clips in which one effect (or two, or none) is hidden:
the model under test starts without it and nothing in the videos names it. Each hidden-effect
case runs in two worlds: the first (exponential flashes on linear sensors, the detector's
own model) and the simulator's second (:func:`~flashsync.simulation.rigs.second_world`:
xenon and LED pulses in turn, tone curves, black levels, x264 at crf 23)."""

import json
from dataclasses import fields, replace
from itertools import takewhile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy.stats import chi2

from flashsync.diagnose import diagnose, format_diagnosis
from flashsync.diagnose.adopt import _moved_back, written_model
from flashsync.diagnose.agreement import agreement, model_gaps
from flashsync.diagnose.candidate import Term, _pseudo_rows, fit_candidate
from flashsync.diagnose.effects import DRIFT_RATE, FLIPPED, PULSE_SHAPE, ROW_TIME
from flashsync.diagnose.measure import Edges, Measurement, measure
from flashsync.diagnose.verdict import noise_test
from flashsync.diagnose.workflow import SYNC_SHAPE, Diagnosis, _candidates, _diagnosis, in_sync_shape, residual_test
from flashsync.errors import FlashsyncError
from flashsync.evaluate import camera_accuracy, probe_errors, probes, sync_errors
from flashsync.events import Edge, Flag
from flashsync.io import events_from_frame, events_to_frame, load_ground_truth, load_model, save_model
from flashsync.match import NOMINAL_HIDDEN_ROWS
from flashsync.model import CameraClock, SyncModel
from flashsync.pipeline import detect_videos, row_time_prior_ms, shared_readouts, synchronize
from flashsync.simulation import CameraSpec, FlashSpec, GroundTruth, Scenario, render_scenario
from flashsync.simulation.rigs import NTSC_30, NTSC_60, random_rig, recipe, second_world, with_flash_powers
from flashsync.solve import SHARED_READOUT_CORRELATION

DURATION_MS = 6000.0
#: Noise floor of a gap in the hidden-effect tests: this many times the RMS the edge noise
#: would leave (band lengths miss errors common to both edges of a band).
FLOOR = 3.0

#: Per case, the settings of the camera that hides it (everything not named is off); every
#: case is a pair of that camera (30 fps, 3 s later on its own clock) and the reference
#: (25 fps). All cameras film the same flashes in one scenario and have neutral names.
HIDDEN = {
    "drift": dict(drift_ppm=150.0),
    "drift_rate": dict(drift_rate_ppm_per_s=100.0),
    "row_time": dict(r0=8, r1=20),
    "flipped": dict(flipped=True),
    "dropped_frames": dict(dropped_frames=(40, 90)),
    "frame_clock": dict(container="mkv", jitter_ms=0.2),
    "exposure": dict(exposure_ms=14.0),
    "stamp_jitter": dict(jitter_ms=3.0),
    "stamp_jitter_1ms": dict(jitter_ms=1.2),
    "stamp_rate": dict(stamp_rate_changes=((90, 1.5),)),
    "saturation": dict(white_level=190.0),
    "two": dict(dropped_frames=(60,), drift_ppm=150.0),
}
CAMERA = {case: f"cam{i}" for i, case in enumerate(HIDDEN, start=1)}
#: The effect each case's hidden setting is, where the case is not named after it.
EFFECT = {"stamp_jitter": "frame_clock", "stamp_jitter_1ms": "frame_clock"}
#: Cases whose gap shows in the stamps: the plain model's frame index x median step is right
#: for the edges while the stamps run away from it.
STAMP_GAP = {"stamp_rate"}

FIRST, SECOND = "first world", "second world"


def dress(scenario: Scenario, world: str) -> Scenario:
    """The scenario in that world: as it is, or in the second world with xenon and LED
    pulses in turn (seed 1; its first flash is a xenon with a 0.78 ms decay)."""
    return scenario if world == FIRST else second_world(scenario, seed=1, pulses=("xenon", "led"))


def flashes(seed: int, duration_ms: float = DURATION_MS) -> tuple[FlashSpec, ...]:
    """Flashes at irregular instants (as fired by hand), 120 ms or more apart."""
    rng = np.random.default_rng(seed)
    instants = 300.0 + np.cumsum(120.0 + rng.exponential(150.0, 100))
    return tuple(
        FlashSpec(round(float(t), 3), round(float(rng.uniform(0.35, 0.7)), 3))
        for t in instants[instants < duration_ms - 300.0]
    )


@pytest.fixture(scope="module", params=[FIRST, SECOND])
def rendered(request, tmp_path_factory) -> tuple[dict, GroundTruth, str]:
    """Every camera's detection (320x180), rendered and detected once per world, the truth
    and the world; the upside-down camera also as ``"<name>+declared"``, detected with its
    readout direction given."""
    cameras = [CameraSpec("cam0", 320, 180, 25.0, exposure_ms=8.0)]
    cameras += [
        CameraSpec(
            CAMERA[case], 320, 180, 30.0, **(dict(exposure_ms=8.0, start_ms=3000.0, offset_ms=-2830.0) | settings)
        )
        for case, settings in HIDDEN.items()
    ]
    folder = tmp_path_factory.mktemp("hidden")
    scenario = Scenario("hidden", tuple(cameras), duration_ms=DURATION_MS, flashes=flashes(1), n_players=0, seed=1)
    truth = render_scenario(dress(scenario, request.param), folder)
    videos = [folder / f"{spec.name}.{spec.container}" for spec in cameras]
    found = {d.camera: d for d in detect_videos(videos)}
    flipped = CAMERA["flipped"]
    found[f"{flipped}+declared"] = detect_videos([folder / f"{flipped}.mp4"], flipped=[flipped])[0]
    return found, truth, request.param


@pytest.fixture(scope="module")
def detections(rendered) -> dict:
    return rendered[0]


def pair(detections: dict, name: str) -> list:
    return [detections["cam0"], detections[name]]


def true_chi2_per_dof(measurement: Measurement, truth: GroundTruth) -> float:
    """χ² per degree of freedom of the true clocks against the edge noise the band lengths
    show: each edge's true error (:func:`true_edge_errors_ms`), each camera's mean taken out
    (as its shift would), over its camera's edge noise."""
    errors = true_edge_errors_ms(measurement, truth)
    camera = measurement.edges.camera
    for c in range(len(measurement.cameras)):
        errors[camera == c] -= errors[camera == c].mean()
    return float(np.sum((errors / measurement.camera_noise_ms[camera]) ** 2) / (len(errors) - len(measurement.cameras)))


def assert_settled(d, cameras: list, truth: GroundTruth, world: str) -> None:
    """The final residuals pass the χ² test; in the second world, where the band lengths
    understate the edge noise (xenon tails and LED plateaus move both edges of a band alike,
    by up to 0.1-0.2 ms, which its length does not show) and the true clocks themselves fail
    the test (χ² per degree of freedom 2.0-3.1 on these cases), they pass it against the
    edge noise the truth shows: χ² over the truth's χ² per degree of freedom. (Until
    2026-12-02 the model's χ² per degree of freedom was held under the truth's; on three
    flashes, 3 degrees of freedom, that is a coin toss: rendered with OpenCV 5.1, the CI
    machine's of 2026-12-02, the second world's flicker pair gave 4.6 against 2.8, p = 0.18
    so scaled.)"""
    if world == FIRST or d.consistent:
        assert d.consistent, format_diagnosis(d)
        return
    truth_chi2 = true_chi2_per_dof(measure(cameras), truth)
    p_value = chi2.sf(d.noise.chi2 / truth_chi2, d.noise.dof)
    assert truth_chi2 > 1.5 and p_value >= 0.01, (truth_chi2, p_value, format_diagnosis(d))


@pytest.mark.parametrize("effect", [case for case in HIDDEN if case not in ("two", "saturation")])
def test_a_hidden_effect_is_named_first_and_the_gap_closes(rendered, effect):
    detections, truth, world = rendered
    d = diagnose(pair(detections, CAMERA[effect]))
    step = d.steps[0]
    assert (step.effect, step.camera) == (EFFECT.get(effect, effect), CAMERA[effect]), format_diagnosis(d)
    if effect in STAMP_GAP:
        before, after, floor = step.stamp_rms_before_ms, step.stamp_rms_after_ms, 0.0
    else:
        before, after, floor = step.rms_before_ms, step.rms_after_ms, FLOOR * d.expected_ms
    assert before > floor, "the hidden effect must show above the noise"
    # closed: 5x, or to the floor, or by half where the residuals then pass the chi-squared test
    # against each camera's own edge noise (the floor pools the cameras' noise: a camera whose
    # bands scatter 0.06 ms beside the reference's 0.0135 is held to 3x 0.012 ms by it)
    closed = after <= max(before / 5.0, floor) or (d.consistent and after <= before / 2.0)
    assert closed, format_diagnosis(d)
    assert_settled(d, pair(detections, CAMERA[effect]), truth, world)


def test_hidden_saturation_is_named_first_and_the_gap_closes(rendered):
    """Bands clipped at white (32 of the camera's 38 events) come out longer the deeper the
    clip: the effect fits how far a clipped band's edges move out (one offset for bands in
    one frame, one for bands split across two, each kind's length measured against its own
    median), the share of a band's length over that median they move by, and how much
    farther the trailing edge moves (the pulse's tail). The edge noise comes from the
    unclipped bands (a clipped band's length is the effect's evidence). Since the detector
    leaves a band's clipped rows out of its fit (``tests/test_detect.py``), the offset is
    gone and what is left goes with the depth of the clip: named first in both worlds, the
    gap 0.058 -> 0.021 ms (first world) and 0.069 -> 0.036 (second), within the noise floor,
    the share 0.26 and 0.34. Whether it comes alone or with the camera's time per row, which
    its 18 flashes hardly tell from it, turns on the renders' last bits: rendered with OpenCV
    5.1 (the CI machine of 2026-12-02) the second world's step is the pair, 0.074 -> 0.037
    ms, the share 0.41. ``sync`` times a clipped band by its midpoint and leaves its length
    out of the exposure (``tests/test_pipeline_checks.py``), which edges moved out
    alike leave in place; ``diagnose -o`` writes ``sync``'s solve with the clipped edges
    moved back by what the effect moves each, no further off the truth than ``sync``'s
    own (0.076 against 0.085 ms in the first world, 0.036 against 0.038 in the second). It
    wrote the workflow's own model until 2026-12-02, nearer the truth here, where
    the time per row is frame period / height (its plain model's), but a mean 0.071 ms off
    on the 12 renders of this pair with hidden rows where ``sync``'s solve on the moved
    edges is 0.049 (README, "Saturation and pulse shape in sync's solve")."""
    detections, truth, _ = rendered
    cameras = pair(detections, CAMERA["saturation"])
    d = diagnose(cameras)
    step = d.steps[0]
    assert "saturation" in step.effect.split("+") and step.camera == CAMERA["saturation"], format_diagnosis(d)
    floor = FLOOR * d.expected_ms
    assert step.rms_before_ms > floor, "the hidden effect must show above the noise"
    assert step.rms_after_ms <= max(step.rms_before_ms / 5.0, floor), format_diagnosis(d)
    assert 0.2 < d.model[1]["saturation_share"] < 0.6, d.model[1]
    assert d.written == f"sync's solve on the readouts found, band edges moved back by the saturation on {step.camera}"
    assert pooled_error_ms(d.sync_model, truth) <= 1.05 * pooled_error_ms(synchronize(cameras)[0], truth)


@pytest.fixture(scope="module", params=[FIRST, SECOND])
def strobed(request, tmp_path_factory) -> tuple[list, GroundTruth, str]:
    """Two cameras at 1 ms exposures (25 and 30 fps, 320x180) under strobes fired at two
    powers (:func:`~flashsync.simulation.rigs.with_flash_powers`, seed 1: 30 % of them
    2-3 ms long, the rest 0.05-0.3), rendered and detected once per world: LED rectangles on
    linear sensors in the first; in the second, xenon and LED pulses in turn (:func:`dress`).
    Their detections, the truth and the world."""
    cameras = (
        CameraSpec("cam0", 320, 180, 25.0, exposure_ms=1.0),
        CameraSpec("cam1", 320, 180, 30.0, exposure_ms=1.0, start_ms=3000.0, offset_ms=-2830.0),
    )
    rectangles = tuple(replace(flash, decay_ms=0.0) for flash in flashes(1))
    scenario = Scenario("strobed", cameras, duration_ms=DURATION_MS, flashes=rectangles, n_players=0, seed=1)
    scenario = with_flash_powers(dress(scenario, request.param), seed=1)
    folder = tmp_path_factory.mktemp("strobed")
    truth = render_scenario(scenario, folder)
    return detect_videos([folder / f"{spec.name}.{spec.container}" for spec in cameras]), truth, request.param


def test_strobes_that_outlast_the_exposure_are_named_first_as_the_pulse_shape_and_the_gap_closes(strobed):
    """A rectangle longer than the exposure widens its band to its own length, the leading
    edge early and the trailing one late by half the excess each (0.6-0.9 ms here): the
    plain model's gap is 0.21-0.35 ms. The flash pulse shape is named first, on one camera
    or on each in turn, with shares near a half, and closes the gap to the noise (first
    world 0.347 -> 0.044 ms, second 0.215 -> 0.045); ``diagnose -o`` writes ``sync``'s solve
    with the widened bands' edges moved back, as near the truth as ``sync``'s. Until
    2026-12-03 nothing was named: the widened bands counted as the edge noise (a camera's
    0.25-0.47 ms) and the verdict called the gap noise."""
    cameras, truth, world = strobed
    d = diagnose(cameras)
    shape = list(takewhile(lambda step: step.effect == PULSE_SHAPE, d.steps))
    assert shape, format_diagnosis(d)
    first = d.model[[c.camera for c in cameras].index(shape[0].camera)]
    assert 0.35 < first["pulse_trailing"] < 0.65 and 0.35 < first["pulse_leading"] < 0.65, first
    before, after, floor = shape[0].rms_before_ms, shape[-1].rms_after_ms, FLOOR * d.expected_ms
    assert before > floor, "the hidden effect must show above the noise"
    assert after <= max(before / 5.0, floor), format_diagnosis(d)
    assert_settled(d, cameras, truth, world)
    assert "flash pulse shape" in d.written
    assert pooled_error_ms(d.sync_model, truth) <= 1.1 * pooled_error_ms(synchronize(cameras)[0], truth) + 0.005


def test_sync_times_strobes_that_outlast_the_exposure_and_warns_of_no_change(strobed):
    """``sync`` on the strobed pair: bands as long as their strobes are timed by their
    midpoints (each camera within 0.05 ms of the truth, its exposure within 0.05 ms, its
    error under its sigma), and a band of a long strobe split across two frames, among bands
    as long as their pulses, is no sign of another exposure (in the first world it was:
    "its exposure changes while it records", the exposure's sigma 1.25 ms)."""
    cameras, truth, _ = strobed
    model, report = synchronize(cameras)
    accuracy = camera_accuracy(model, truth).set_index("camera")
    assert (accuracy["rms_ms"] < 0.05).all() and (accuracy["exposure_error_ms"].abs() < 0.05).all(), accuracy
    assert (accuracy["z_rms"].dropna() < 1.0).all(), accuracy
    assert not [w for w in report.warnings if "its exposure changes while it records" in w], report.warnings
    assert all(camera.exposure_std_ms < 0.1 for camera in model.cameras.values())


@pytest.mark.parametrize("name", ["cam0", f"{CAMERA['flipped']}+declared"])
def test_an_edge_moved_back_goes_towards_the_first_row_read(detections, name):
    """``diagnose -o`` moves an edge that an effect puts later back by that time over the time
    per row: up the stored image on a camera read top-down, down it on one read bottom-up
    (0.5 ms at 0.1 ms a row: 5 rows); no other edge moves."""
    detection = detections[name]
    events = detection.events
    edges = Edges(
        *(np.array([value]) for value in (0, 0, events.event[0], events.frame[0], events.row[0])),
        np.array([events.edge[0] == "trailing"]),
        np.zeros(1, bool),
        np.zeros(1),
        np.zeros(1),
        np.zeros(1, bool),
    )
    moved = _moved_back(detection, edges, np.array([0.5]), 0, 0.1).events
    assert moved.row[0] - events.row[0] == pytest.approx(5.0 if detection.flipped else -5.0)
    assert np.array_equal(moved.row[1:], events.row[1:])


def test_two_hidden_effects_are_found_the_larger_gap_first(detections):
    d = diagnose(pair(detections, CAMERA["two"]))
    assert [s.effect for s in d.steps] == ["dropped_frames", "drift"], format_diagnosis(d)
    assert d.steps[0].rms_before_ms > 20 * d.steps[1].rms_before_ms  # a frame period vs 0.5 ms
    assert d.consistent and d.final_rms_ms < d.initial_rms_ms / 100
    assert d.model[1]["drift_ppm"] == pytest.approx(150.0, abs=15.0)
    assert d.model[1]["missing_frames"] == 1
    text = format_diagnosis(d)
    lines = text.splitlines()
    assert lines[3].split()[1:3] == ["dropped", "frames"] and "ΔBIC" in lines[3]
    assert lines[4].split()[1:3] == ["clock", "drift"] and "ppm" in lines[4]
    assert "residuals consistent with noise: χ²" in text
    data = json.loads(json.dumps(d.to_dict()))
    assert [s["effect"] for s in data["steps"]] == ["dropped_frames", "drift"]
    assert data["steps"][1]["evidence"].startswith("ΔBIC") and data["verdict"] == d.verdict


def test_no_hidden_effect_names_nothing_and_ends_at_the_plain_model_in_syncs_shape(rendered):
    detections, truth, world = rendered
    cameras = pair(detections, f"{CAMERA['flipped']}+declared")
    d = diagnose(cameras)
    assert d.steps == [], format_diagnosis(d)
    assert d.sync_shape and all(set(model["effects"]) <= set(SYNC_SHAPE) for model in d.model)
    assert d.found_rms_ms == d.initial_rms_ms
    assert_settled(d, cameras, truth, world)
    assert "no effect of the catalogue" in format_diagnosis(d)


def test_diagnose_o_writing_syncs_solve_keeps_each_exposures_sigma_and_it_covers_the_error(rendered):
    """``diagnose -o`` writes ``sync``'s solve (a hidden exposure): every exposure with its
    standard deviation, the truth within 3 of it (second world: 2.6 and 2.5; without
    ``sync``'s floor 3.8 and 4.8)."""
    detections, truth, _ = rendered
    d = diagnose(pair(detections, CAMERA["exposure"]))
    table = camera_accuracy(d.sync_model, truth)
    table = table[table["solved"]]
    assert len(table) == 2 and (table["exposure_z"].abs() <= 3.0).all(), table[
        ["camera", "exposure_error_ms", "exposure_z"]
    ]


def test_one_bad_edge_names_nothing(detections):
    ref, other = pair(detections, f"{CAMERA['flipped']}+declared")
    events = events_to_frame(ref.events)
    bad = events.index[events["edge"] == "trailing"][1]  # an edge a weak fit bends to
    events.loc[bad, "row"] -= 15.0  # 15 rows = 3.3 ms off
    d = diagnose([replace(ref, top_down=events_from_frame(events)), other])
    assert d.steps == [], format_diagnosis(d)


def true_edge_errors_ms(measurement: Measurement, truth: GroundTruth) -> np.ndarray:
    """Each measured edge's time minus its flash's half-light instant, both on the true
    clocks (a trailing edge, in the true readout direction, one true exposure earlier), ms,
    shape (n_edges,): what the detector alone got wrong."""
    edges, names = measurement.edges, [c.camera for c in measurement.cameras]
    instants = np.array([flash["half_rise_global_ms"] for flash in truth.flashes])
    errors = np.empty(len(edges))
    for i, (c, frame, row, told) in enumerate(zip(edges.camera, edges.frame, edges.row, edges.trailing)):
        camera = names[c]
        trailing = told != (measurement.cameras[c].flipped != truth.cameras[camera].flipped)
        t = float(truth.global_time_ms(camera, frame, row)) - trailing * truth.cameras[camera].exposure_ms
        errors[i] = t - instants[np.argmin(np.abs(instants - t))]
    return errors


def test_shipped_sample_needs_a_pair_and_ends_at_the_truth():
    """Four cameras, seven flashes, hidden rows and exposures everywhere: cam4's exposure
    shows only together with a time per row (cam1's; cam4's own follows). Its drift (7 ppm
    from the reference's, 0.13 ms over the clip) is too small for seven flashes to name; the
    strict verdict states its test (p = 0.012). The true clocks themselves (each camera's
    mean edge error taken out, as its shift would) score χ² per degree of freedom 2.36
    against the same band-length noise (1.11 before the split bands whose trailing edges
    lie at the next frame's top were fitted at their bands' level: their lengths, off by
    up to a row, had widened cam3's and cam4's noise); the final model's is within 1.3x of
    that (1.78). cam3's three one-frame bands are as long as each other to 0.025 rows: its
    noise is shrunk towards the pooled one as sync's solve does, else 0.0016 ms failed the
    verdict at χ² 2808."""
    samples = Path(__file__).parent.parent / "samples"
    cameras = detect_videos(sorted(samples.glob("cam*.m*")))
    d = diagnose(cameras)
    assert "row_time+exposure" in [s.effect for s in d.steps], format_diagnosis(d)
    assert d.consistent and "χ²" in d.verdict and "degrees of freedom" in d.verdict and "p = " in d.verdict, d.verdict
    assert not d.disagrees and "within 3 sigma on every camera" in d.agreement, d.agreement
    truth = load_ground_truth(samples / "truth.json")
    truth_chi2 = true_chi2_per_dof(measure(cameras), truth)
    assert 1.0 < truth_chi2 and d.noise.chi2 / d.noise.dof < 1.3 * truth_chi2, (truth_chi2, d.verdict)
    for model in d.model:
        camera = truth.cameras[model["camera"]]
        assert model["row_time_ms"] == pytest.approx(camera.row_time_ms, rel=0.01)
        assert model["exposure_ms"] == pytest.approx(camera.exposure_ms, abs=0.2)


def test_models_apart_by_more_than_syncs_sigma_disagree():
    """Two models of one camera 0.5 ms apart at every row: 0.5 ms RMS, against a sigma of
    0.1 ms (the solve's shift variance 0.01 ms²) that is beyond 3 sigma; 0.2 ms apart is not."""
    frames = np.arange(100) * 40.0
    clock = CameraClock("cam1", frames, 180, 320, row_time_ms=0.1, covariance=np.diag([0.0, 0.01, 0.0]))
    synced = SyncModel("cam1", {"cam1": clock})
    for shift_ms, apart in ((0.5, True), (0.2, False)):
        (gap,) = model_gaps(SyncModel("cam1", {"cam1": replace(clock, beta_ms=shift_ms)}), synced)
        assert gap.camera == "cam1" and gap.apart == apart
        assert gap.rms_ms == pytest.approx(shift_ms) and gap.sigma_ms == pytest.approx(0.1)
        assert ("disagree beyond" in agreement([gap])) == apart
    assert "none (sync cannot solve" in agreement([])


@pytest.fixture(scope="module")
def changing_drift(tmp_path_factory) -> tuple[GroundTruth, list[Path]]:
    """The reference (25 fps) and a 30 fps camera whose clock's drift changes 100 ppm/s (the
    ``drift_rate`` case above), first world, rendered once: its truth and videos."""
    cameras = (
        CameraSpec("cam0", 320, 180, 25.0, exposure_ms=8.0),
        CameraSpec("cam1", 320, 180, 30.0, exposure_ms=8.0, start_ms=3000.0, offset_ms=-2830.0, **HIDDEN["drift_rate"]),
    )
    folder = tmp_path_factory.mktemp("drift_rate")
    scenario = Scenario("drift_rate", cameras, duration_ms=DURATION_MS, flashes=flashes(1), n_players=0, seed=1)
    return render_scenario(scenario, folder), [folder / f"{c.name}.mp4" for c in cameras]


def test_sync_adopts_the_drift_rate_change_diagnose_names_and_the_two_agree(changing_drift):
    """A drift-rate change (100 ppm/s on cam1, whose clock runs 300-900 ppm fast): ``diagnose``
    names it. Both held cam1 to ``sync``'s 50 ppm drift prior: ``sync`` was 0.24 and 0.59 ms
    RMS off the truth, ``diagnose -o`` 0.08 and 0.09, the agreement line naming cam1. The
    events contradict that prior: ``sync`` drops it, says so and takes a changing rate, 0.06
    and 0.04 ms off; ``sync``'s shape drops it where ``sync`` does: ``diagnose -o`` 0.07 and
    0.045, the two 0.02 ms apart on cam1 (0.07 with the prior in ``sync``'s shape)."""
    truth, videos = changing_drift
    detections = detect_videos(videos)
    d = diagnose(detections)
    assert "drift_rate" in {s.effect for s in d.steps}, format_diagnosis(d)
    assert any("cam1.mp4: sync solves its clock without the drift prior" in w for w in d.warnings), d.warnings
    synced, report = synchronize(detections)
    assert (sync_errors(d.sync_model, truth).rms_ms < 0.1).all() and (sync_errors(synced, truth).rms_ms < 0.1).all()
    assert synced.cameras["cam1"].drift_knots_ms.size > 0
    assert any("cam1.mp4: its clock runs +6" in w and "solved without that prior" in w for w in report.warnings)
    assert d.disagrees == [] and max(gap.rms_ms for gap in d.sync_gaps) < 0.04, d.agreement


def test_cli_diagnose_o_names_the_cameras_its_model_and_syncs_part_on(changing_drift, tmp_path, capsys, monkeypatch):
    """``flashsync diagnose -o`` on the same rig, with ``sync``'s own model for it moved 1 ms on
    cam1 (as if ``sync`` had missed the effect) and the written one solved anew: its ``model
    ->`` line names the camera on which it and ``sync``'s disagree; the JSON holds the gaps."""
    from flashsync.cli import main
    from flashsync.diagnose import adopt, workflow

    def missed(*args, **kwargs):
        model, report = synchronize(*args, **kwargs)
        clock = model.cameras["cam1"]
        return replace(model, cameras={**model.cameras, "cam1": replace(clock, beta_ms=clock.beta_ms + 1.0)}), report

    monkeypatch.setattr(workflow, "synchronize", missed)
    monkeypatch.setattr(adopt, "_same_choices", lambda *args: False)
    _, videos = changing_drift
    out = ["-o", str(tmp_path / "sync.json"), "--json", str(tmp_path / "d.json")]
    assert main(["diagnose", *map(str, videos), *out]) == 0
    shown = capsys.readouterr()
    assert f"model -> {tmp_path / 'sync.json'} (it and sync's disagree on cam1)" in shown.err, shown.err
    assert "they disagree beyond 3 sigma" in shown.out
    gaps = {g["camera"]: g for g in json.loads((tmp_path / "d.json").read_text())["sync_gaps"]}
    assert [name for name, gap in gaps.items() if gap["rms_ms"] > 3 * gap["sigma_ms"]] == ["cam1"]


def test_diagnose_o_writes_syncs_solve_on_the_readouts_and_frame_times_found(changing_drift):
    """What ``diagnose -o`` writes (:func:`~flashsync.diagnose.adopt.written_model`): where the
    final model reads and times every camera as ``sync`` chose, ``sync``'s own model; where it
    names a stamp rate change on cam1, ``sync``'s solve on the frame times it found (with
    that clock's frame uncertainty; here cam1's clock moved 0.5 ms, its stamps change no
    rate); where its frame clock or dropped frames (``sync``'s clock has both), ``sync``'s
    own model; where it names cam1 read
    the other way up (``sync`` then ties no flash: cam1's clock runs 300-900 ppm fast),
    the final model itself, and it says why, with no exposure sigma (the robust fit's, even
    with ``sync``'s floor in quadrature, put the truth 3.1 and 2.5 sigma away on the hidden
    saturation pair's second world, 2026-11-29); where it reads
    cam1 the other way up without naming it (as a detection told the other way, whose
    readout ``sync`` found by the flashes and the workflow had no evidence to turn: random
    rig 428's cam4, written so 9.3 ms off), ``sync``'s own model."""
    truth, videos = changing_drift
    detections = detect_videos(videos)
    synced = synchronize(detections)
    d = diagnose(detections)
    assert d.written.endswith("(the same as sync's own)"), d.written
    assert d.sync_model is synced[0] or all(gap.rms_ms == 0 for gap in d.sync_gaps), d.agreement
    measurement = measure(detections)
    found = fit_candidate(measurement, frozenset(Term(e, c) for c, m in enumerate(d.model) for e in m["effects"]))
    other_way = [found.flipped[0], not found.flipped[1]]
    assert written_model(detections, None, replace(found, flipped=other_way), synced)[0] is synced[0]
    upside_down = replace(found, flipped=other_way, terms=found.terms | {Term("flipped", 1)})
    model, words = written_model(detections, None, upside_down, synced)
    assert words.startswith("the workflow's own model: sync cannot solve the detections with its choices (no camera")
    where = probes(model.cameras["cam1"])
    own = upside_down.sync_model().cameras["cam1"]
    assert model.cameras["cam1"].flipped and np.array_equal(
        model.cameras["cam1"].t_global_ms(*where), own.t_global_ms(*where)
    )
    assert all(camera.exposure_std_ms is None for camera in model.cameras.values())
    clocked = fit_candidate(measurement, found.terms | {Term("frame_clock", 1), Term("dropped_frames", 1)})
    later = replace(clocked.timing[1], times_ms=clocked.timing[1].times_ms + 0.5)
    assert written_model(detections, None, replace(clocked, timing=[clocked.timing[0], later]), synced)[0] is synced[0]
    clocked = replace(clocked, terms=clocked.terms | {Term("stamp_rate", 1)}, timing=[clocked.timing[0], later])
    model, words = written_model(detections, None, clocked, synced)
    assert words == "sync's solve on the readouts found and the one-rate frame times found on cam1", words
    assert np.array_equal(model.cameras["cam1"].frame_times_ms, clocked.timing[1].times_ms)
    assert np.array_equal(model.cameras["cam1"].frame_std_ms, clocked.clocks[1].std_ms)
    assert pooled_error_ms(model, truth) < 0.1


def test_a_changing_rate_is_offered_only_to_a_camera_of_eight_flashes_or_more(changing_drift):
    """``sync`` gives a clock a changing rate on eight flashes or more (two warp segments), and
    so does the workflow: on the drift-rate rig it offers cam1 the drift-rate change, on the
    edges of its first seven flashes alone it does not (random rig 15 of the second world: a
    drift-rate change named on the four flashes its cameras share put ``diagnose -o`` 0.13 ms
    off the truth; without it, 0.10)."""
    _, videos = changing_drift
    measurement = measure(detect_videos(videos))
    edges = measurement.edges
    first = edges.flash < 7
    fewer = replace(measurement, edges=Edges(*(getattr(edges, f.name)[first] for f in fields(Edges))))
    assert np.sum((edges.camera == 1) & ~edges.trailing) >= 8 and fewer.n_flashes == 7
    assert Term(DRIFT_RATE, 1) in _candidates(measurement, frozenset())
    assert Term(DRIFT_RATE, 1) not in _candidates(fewer, frozenset())


def test_syncs_shape_frees_every_time_per_row_exposure_and_drift_under_syncs_priors(tmp_path):
    """Three cameras (25, 30, 50 fps, 8 s, twelve flashes) with hidden rows on each (their
    times per row 8-10 % under frame period / height), exposures of 4, 2 and 6 ms and clocks
    30 and -25 ppm from the reference's. The plain model in ``sync``'s shape is 0.017 ms RMS
    off the truth where the plain model is 2.45: every camera's time per row, exposure and
    drift come from the edges and ``sync``'s priors, with no step. The workflow names them
    all here and its model (in that shape) is 0.017 ms off, ``sync``'s 0.014 (on the second
    world's random rigs, twelve cameras of a few flashes each, steps above the threshold
    leave many of them at the plain model's: README, ``flashsync diagnose``)."""
    duration = 8000.0
    rig = (
        CameraSpec("cam1", 320, 180, 25.0, r0=6, r1=14, exposure_ms=4.0),
        CameraSpec(
            "cam2", 320, 180, 30.0, r0=10, r1=10, exposure_ms=2.0, drift_ppm=30.0, start_ms=1000.0, offset_ms=-900.0
        ),
        CameraSpec(
            "cam3", 320, 180, 50.0, r0=4, r1=16, exposure_ms=6.0, drift_ppm=-25.0, start_ms=2000.0, offset_ms=-1950.0
        ),
    )
    scenario = Scenario(
        "hidden-rows", rig, duration_ms=duration, flashes=flashes(4, duration)[::2], n_players=0, seed=4
    )
    truth = render_scenario(scenario, tmp_path)
    cameras = detect_videos([tmp_path / f"{c.name}.mp4" for c in rig])
    measurement = measure(cameras)
    plain = fit_candidate(measurement, frozenset())
    shaped = in_sync_shape(measurement, plain)
    assert pooled_error_ms(plain.sync_model(), truth) > 1.0
    assert pooled_error_ms(shaped.sync_model(), truth) < 0.03
    for name, camera in shaped.sync_model().cameras.items():
        assert camera.row_time_ms == pytest.approx(truth.cameras[name].row_time_ms, rel=0.005), name
        assert camera.exposure_ms == pytest.approx(truth.cameras[name].exposure_ms, abs=0.1), name
    d = diagnose(cameras)
    assert d.sync_shape and pooled_error_ms(d.sync_model, truth) < 0.03, format_diagnosis(d)


def test_the_fits_priors_on_the_times_per_row_are_syncs_identical_cameras_sharing_a_readout():
    """Two 640x360 cameras at 30 fps and one 480x270 at 25 fps, every time per row free: the
    prior the fit's pseudo-rows carry (the inverse of their information) gives each camera
    ``sync``'s weak prior and the two identical ones correlated
    :data:`~flashsync.solve.SHARED_READOUT_CORRELATION`, the third independent, as
    :func:`~flashsync.pipeline.shared_readouts` has ``sync``'s solve take them."""
    sizes = [(640, 360, 1000 / 30), (640, 360, 1000 / 30), (480, 270, 40.0)]
    cameras = [
        SimpleNamespace(camera=f"cam{c}", width=w, height=h, frame_times_ms=np.arange(100) * period)
        for c, (w, h, period) in enumerate(sizes)
    ]
    measurement = SimpleNamespace(
        cameras=cameras,
        noise_ms=0.02,
        free_drift=(),
        n_flashes=0,
        flicker_row_time_ms=lambda c: (np.nan, np.nan),
        readout_groups=shared_readouts(cameras, set()),  # Measurement.readout_groups: none told by flicker
    )
    timing = [SimpleNamespace(period_ms=period) for _, _, period in sizes]
    keys = [(ROW_TIME, c) for c in range(3)]
    rows, observed, weight = _pseudo_rows(measurement, frozenset(), timing, keys)
    weighted = rows * weight[:, None] / 0.02
    covariance = np.linalg.inv(weighted.T @ weighted)
    std = np.sqrt(np.diag(covariance))
    nominal = [period / (NOMINAL_HIDDEN_ROWS * h) for _, h, period in sizes]
    assert std == pytest.approx([row_time_prior_ms(n)[1] for n in nominal])
    correlation = covariance / np.outer(std, std)
    assert correlation[0, 1] == pytest.approx(SHARED_READOUT_CORRELATION)
    assert correlation[0, 2] == pytest.approx(0.0, abs=1e-9) and correlation[1, 2] == pytest.approx(0.0, abs=1e-9)
    mean = np.linalg.solve(weighted, observed * weight / 0.02)
    assert mean + [period / h for _, h, period in sizes] == pytest.approx([row_time_prior_ms(n)[0] for n in nominal])


def test_without_syncs_shape_the_diagnosis_says_so_and_keeps_the_last_steps_model(detections):
    """Where the found effects cannot be fitted in ``sync``'s shape (:func:`in_sync_shape`
    gives None: undetermined, or a time per row or an exposure below zero), the diagnosis is
    the last step's model, and a warning says why."""
    measurement = measure(pair(detections, CAMERA["exposure"]))
    found = fit_candidate(measurement, frozenset({Term("exposure", 1)}))
    step = [s for s in diagnose(pair(detections, CAMERA["exposure"])).steps if not s.removed][:1]
    d = _diagnosis(measurement, [fit_candidate(measurement, frozenset()), found], step)
    assert not d.sync_shape and d.final_rms_ms == d.found_rms_ms == found.rms_ms
    assert any("cannot be fitted in sync's shape" in w and "the model is the last step's" in w for w in d.warnings)
    text = format_diagnosis(d)
    assert "in sync's shape".ljust(32) + " every" not in text and "warning: the effects found cannot" in text


def test_a_model_with_a_time_per_row_or_exposure_below_zero_is_neither_added_nor_kept(tmp_path):
    """Random rig 38 of the second world (five cameras, 8 s): cam2 is upside down and the
    workflow names it, then fits its time per row; without the flip, that time per row or its
    exposure comes out below zero (rows read the other way), which fit the edges as well,
    and the flip came out as no longer needed: cam2 1.55 ms RMS off the truth, 16 sigma
    from sync's model. A time per row or an exposure below zero is no camera's: such a model
    is neither taken nor kept, and every camera is within 0.1 ms (across the 40 kept random
    rigs, 13 moved closer to the truth and none further: README, "Against sync's model")."""
    scenario = random_rig(38, max_height=360, duration_ms=8000.0)
    truth = render_scenario(scenario, tmp_path)
    d = diagnose(detect_videos([tmp_path / f"{c.name}.{c.container}" for c in scenario.cameras]))
    assert [s.removed for s in d.steps if (s.effect, s.camera) == ("flipped", "cam2")] == [False], format_diagnosis(d)
    assert (sync_errors(d.sync_model, truth).rms_ms < 0.1).all() and not d.disagrees, format_diagnosis(d)


def test_too_few_cameras_or_shared_flashes_is_one_line_error(detections):
    ref, other = pair(detections, CAMERA["drift"])
    with pytest.raises(FlashsyncError, match="two or more cameras"):
        diagnose([ref])
    with pytest.raises(FlashsyncError, match="shares at least 3 flashes") as error:
        diagnose([ref, replace(other, top_down=other.events.take(slice(0, 4)))])
    assert "\n" not in str(error.value)


def test_a_camera_sync_leaves_out_is_left_out_with_a_pointer_to_syncs_reason(detections):
    """A third camera with one flash: ``sync`` leaves it out and says why; the workflow,
    paired by ``sync``, leaves it out too and points there, not at a count of shared
    flashes it never made."""
    ref, other = pair(detections, CAMERA["drift"])
    one_flash = other.events.take(other.events.event == other.events.event.min())
    lonely = replace(other, camera="lonely", video=Path("lonely.mp4"), top_down=one_flash, bottom_up=one_flash)
    model, report = synchronize([ref, other, lonely])
    assert "lonely" not in model.cameras and any(w.startswith("lonely.mp4: ") for w in report.warnings)
    measurement = measure([ref, other, lonely], paired_by=model)
    assert [c.camera for c in measurement.cameras] == [ref.camera, other.camera]
    assert measurement.warnings == ("lonely.mp4: sync ties it to no other camera (flashsync sync says why); left out",)


def test_a_camera_no_clean_band_ties_is_left_out_and_the_rest_diagnosed(detections):
    """A third camera with no band the workflow counts clean (both edges inside the image
    and the pulse within the exposure; here every trailing edge hidden, as random rig 420's
    cam4 at two flash powers had every band outlasted by its pulse): ``sync`` ties it by
    its other edges; the workflow had no edge of it, left the plain model undetermined and
    stopped ("cannot determine even the plain model") where ``sync`` solved. It is left out
    with a warning, the rest diagnosed, and ``-o`` writes ``sync``'s solve of all three."""
    ref, other = pair(detections, CAMERA["drift"])
    source = detections[CAMERA["row_time"]]
    leading = source.events.take(source.events.edge == Edge.LEADING)
    flags = np.array([flags | {Flag.TRAILING_HIDDEN} for flags in leading.flags], dtype=object)
    hidden = replace(leading, camera=np.full(len(leading), "lone", dtype=object), flags=flags)
    lone = replace(source, camera="lone", video=Path("lone.mp4"), top_down=hidden, bottom_up=None)
    d = diagnose([ref, other, lone])
    assert d.cameras == [ref.camera, other.camera], format_diagnosis(d)
    assert any(w.startswith("lone.mp4: no band of it with both edges clean") for w in d.warnings), d.warnings
    assert "lone" in d.sync_model.cameras and len(d.sync_model.events.query("camera == 'lone'")) >= 10


def test_cli_writes_the_table_json_and_a_recording_of_every_step(tmp_path, capsys):
    """``flashsync diagnose`` on the shipped sample: a table, JSON with the steps, and a Rerun
    recording whose residual series are one per step, camera and edge kind, then the final
    model's in ``sync``'s shape."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    from flashsync.cli import main

    samples = Path(__file__).resolve().parents[1] / "samples"
    videos = sorted(str(p) for p in samples.iterdir() if p.suffix in (".mp4", ".mkv"))
    outputs = ["-o", str(tmp_path / "sync.json"), "--json", str(tmp_path / "d.json"), "--rrd", str(tmp_path / "d.rrd")]
    assert main(["diagnose", *videos, *outputs]) == 0
    shown = capsys.readouterr()
    assert "χ²" in shown.out and "against the model flashsync sync writes: within 3 sigma" in shown.out
    assert "in sync's shape" in shown.out
    assert "sync.json\n" in shown.err  # no disagreement to name
    model = load_model(tmp_path / "sync.json")
    assert list(model.cameras) == ["cam1", "cam2", "cam3", "cam4"] and len(model.events) > 0
    restamped = tmp_path / "restamped.csv"
    assert (
        main(
            [
                "restamp",
                str(samples / "detections.csv"),
                "--model",
                str(tmp_path / "sync.json"),
                "-o",
                str(restamped),
                "--std",
            ]
        )
        == 0
    )
    stamped = pd.read_csv(restamped)
    assert stamped["t_global_ms"].notna().all() and (stamped["t_global_std_ms"] > 0).all()
    data = json.loads((tmp_path / "d.json").read_text())
    assert data["steps"] and data["sync_shape"]
    assert len(data["edge_residuals"]["residual_ms"]) == len(data["steps"]) + 2
    rerun = Path(sys.executable).with_name("rerun")
    printed = subprocess.run(
        [str(rerun), "rrd", "print", "-v", str(tmp_path / "d.rrd")], capture_output=True, text=True, check=True
    ).stdout
    first = data["steps"][0]
    assert "/diagnose/0_plain/cam1/leading" in printed
    assert f"/diagnose/1_{first['effect']}_{first['camera']}/" in printed
    assert f"/diagnose/{len(data['steps']) + 1}_sync_shape/cam4/trailing" in printed


def pooled_error_ms(model: SyncModel, truth: GroundTruth) -> float:
    """RMS of model minus truth over every camera's frames and rows, ms."""
    return float(np.sqrt(np.mean(sync_errors(model, truth)["rms_ms"] ** 2)))


def test_sync_and_diagnose_o_agree_on_stamps_jittered_by_1_2_ms(rendered, tmp_path):
    """The issue's jittered rig, in each world: ``sync`` and the model ``diagnose -o`` writes
    are both within 0.1 ms RMS of the truth, read back from the file."""
    found, truth, _ = rendered
    cameras = pair(found, CAMERA["stamp_jitter_1ms"])
    model, _ = synchronize(cameras)
    d = diagnose(cameras)
    save_model(d.sync_model, tmp_path / "sync.json")
    written = load_model(tmp_path / "sync.json")
    assert pooled_error_ms(model, truth) < 0.1
    assert pooled_error_ms(written, truth) < 0.1, format_diagnosis(d)
    assert written.camera(CAMERA["stamp_jitter_1ms"]).frame_std_ms.shape == (
        written.camera(CAMERA["stamp_jitter_1ms"]).n_frames,
    )


#: Stamp faults of a 59.94 fps camera (against a 25 fps reference, 6 s, 320x180) that put
#: ``sync`` or ``diagnose -o`` milliseconds off before the frame clock kept a jittered stamp
#: on its slot and saw a sawtooth: the effect named first, and the stamps' jitter (ms).
SIXTY_FPS_STAMPS = {
    "jittered 3 ms": ("frame_clock", 3.0, {}),
    "5 % fast from frame 150, jittered 1.2 ms": ("stamp_rate", 1.2, dict(stamp_rate_changes=((150, 1.05),))),
    "half as fast from frame 150": ("stamp_rate", 0.0, dict(stamp_rate_changes=((150, 0.5),))),
}


@pytest.mark.parametrize("case", SIXTY_FPS_STAMPS)
def test_59_94_fps_stamp_faults_sync_and_diagnose_o_agree_at_the_truth(tmp_path, case):
    """Stamps jittered by 3 ms (a sixth of the period), running 5 % fast from frame 150 with
    1.2 ms of jitter, or half as fast from there, on a 59.94 fps camera: ``diagnose`` names
    the fault first on that camera, and ``sync`` and the model ``diagnose -o`` writes are
    both within 0.1 ms RMS of the truth and of each other (they were 2.9 and 0.008 ms off on
    the jittered rig, 54.6 and 54.3 on the fast one, and both failed on the slowing one, "no
    camera shares enough flashes"; now 0.003-0.031 ms, ``benchmarks/bench_diagnose.py`` and
    seeds 1-4)."""
    effect, jitter, fault = SIXTY_FPS_STAMPS[case]
    rig = (
        CameraSpec("cam0", 320, 180, 25.0, exposure_ms=8.0),
        CameraSpec(
            "cam1", 320, 180, NTSC_60, exposure_ms=4.0, start_ms=3000.0, offset_ms=-2830.0, jitter_ms=jitter, **fault
        ),
    )
    scenario = Scenario("sixty", rig, duration_ms=DURATION_MS, flashes=flashes(2), n_players=0, seed=2)
    truth = render_scenario(scenario, tmp_path)
    videos = [tmp_path / "cam0.mp4", tmp_path / "cam1.mp4"]
    model, _ = synchronize(detect_videos(videos))
    d = diagnose(detect_videos(videos, estimate_readout=False))
    assert (d.steps[0].effect, d.steps[0].camera) == (effect, "cam1"), format_diagnosis(d)
    assert pooled_error_ms(model, truth) < 0.1
    assert pooled_error_ms(d.sync_model, truth) < 0.1, format_diagnosis(d)
    assert max(gap.rms_ms for gap in model_gaps(d.sync_model, model)) < 0.1


def small(spec: CameraSpec, width: int, height: int, **fields) -> CameraSpec:
    """A second-world camera at a smaller frame size (its hidden rows scaled along)."""
    k = height / spec.height
    return replace(
        spec, width=width, height=height, r0=max(1, round(spec.r0 * k)), r1=max(1, round(spec.r1 * k)), **fields
    )


#: Second-world cases: recipe, settings of its cam2, the effect hidden there, and the bound
#: on sync's RMS error (ms): on the rate change (8 flashes, two cameras) sync's time per row
#: of cam1 is 0.36 % short (0.137 ms at its last row) where diagnose's is within 0.1 %.
SECOND_WORLD = {
    "stamps jittered 1.2 ms": ("jittered-stamps", {}, "frame_clock", 0.1),
    "stamps jittered 3 ms": ("jittered-stamps", dict(jitter_ms=3.0), "frame_clock", 0.1),
    "stamp rate change": ("stamp-rate-change", {}, "stamp_rate", 0.15),
}


@pytest.mark.parametrize("case", SECOND_WORLD)
def test_second_world_stamp_faults_are_named_first_and_sync_and_diagnose_o_agree(tmp_path, case):
    """The simulator's second world (``recipe(name)``: xenon or LED pulses, tone curves, crf
    18-30, players), its 25 fps camera and the 30 fps one with the stamp fault, 6 s: the
    fault is named first on that camera, its gap (edges, or stamps for a rate change)
    shrinks 5x, and the model ``diagnose -o`` writes is within 0.1 ms RMS of the truth, and
    so is ``sync``'s but for the rate change."""
    name, settings, effect, sync_bound = SECOND_WORLD[case]
    scenario = recipe(name, seed=0, duration_ms=DURATION_MS)
    scenario = replace(scenario, cameras=(scenario.cameras[0], replace(scenario.cameras[1], **settings)))
    truth = render_scenario(scenario, tmp_path)
    videos = [tmp_path / f"{c.name}.{c.container}" for c in scenario.cameras]
    model, _ = synchronize(detect_videos(videos))
    d = diagnose(detect_videos(videos, estimate_readout=False))
    step = d.steps[0]
    assert (step.effect, step.camera) == (effect, "cam2"), format_diagnosis(d)
    before, after = (
        (step.stamp_rms_before_ms, step.stamp_rms_after_ms)
        if effect == "stamp_rate"
        else (step.rms_before_ms, step.rms_after_ms)
    )
    assert after <= before / 5.0, format_diagnosis(d)
    assert pooled_error_ms(model, truth) < sync_bound
    assert pooled_error_ms(d.sync_model, truth) < 0.1, format_diagnosis(d)


def test_drifting_clocks_get_a_drift_step_and_sync_agrees_with_diagnose_o(tmp_path):
    """The issue's drifting HD rig, smaller: three cameras at 29.97/29.97/59.94 fps
    (320x180, 10 s) whose clocks run 80 and 100 ppm from the reference's (0.8-1.0 ms over
    the clip; at 180 rows an edge is 6x less precise in ms than at 1080). Without drift the
    residuals fail the chi-squared test, on the drifting cameras; the workflow takes a
    drift step, passes it, and its model is within 0.05 ms RMS of the truth. Drift is in
    ``sync``'s model too, which fits both edges of every band as the workflow does: its model
    is as close to the truth, and on every camera within its own sigma of the workflow's. (In
    the second world it passes too, 42 s on a busy machine: the next test's second-world case,
    the same rig with twelve flashes, stands for it.)"""
    duration = 10_000.0
    rig = (
        CameraSpec("cam1", 320, 180, NTSC_30, exposure_ms=2.0),
        CameraSpec("cam2", 320, 180, NTSC_30, exposure_ms=4.0, drift_ppm=80.0, start_ms=1000.0, offset_ms=-900.0),
        CameraSpec("cam3", 320, 180, NTSC_60, exposure_ms=3.0, drift_ppm=100.0, start_ms=5000.0, offset_ms=-4950.0),
    )
    scenario = Scenario("drifting", rig, duration_ms=duration, flashes=flashes(2, duration), n_players=0, seed=2)
    truth = render_scenario(scenario, tmp_path)
    cameras = detect_videos([tmp_path / f"{c.name}.mp4" for c in rig], estimate_readout=False)
    d = diagnose(cameras)
    drifting = {c for s in d.steps if "drift" in s.effect.split("+") for c in s.camera.split("+")}
    assert drifting == {"cam2", "cam3"}, format_diagnosis(d)
    assert [m["drift_ppm"] for m in d.model] == pytest.approx([0.0, 80.0, 100.0], abs=10.0)
    assert d.consistent, format_diagnosis(d)
    measurement = measure(cameras)
    final = {Term(effect, c) for c, model in enumerate(d.model) for effect in model["effects"]}
    without = fit_candidate(measurement, frozenset(t for t in final if t.effect != "drift"))
    verdict = residual_test(measurement, without)
    assert not verdict.consistent and set(verdict.cameras) & {"cam2", "cam3"}, verdict.describe()
    assert pooled_error_ms(d.sync_model, truth) < 0.05
    model, _ = synchronize(cameras)
    assert pooled_error_ms(model, truth) < 0.05
    for name, clock in model.cameras.items():
        where = probes(clock)
        gap = probe_errors(model, truth, name, *where) - probe_errors(d.sync_model, truth, name, *where)
        sigma = clock.t_global_std_ms(*where)
        assert np.sqrt(np.mean(gap**2)) < np.sqrt(np.mean(sigma**2)), name


@pytest.mark.parametrize("world", [FIRST, SECOND])
def test_one_band_moved_a_millisecond_does_not_hide_a_drift(tmp_path, world):
    """The issue's HD rig, as the workflow saw it: twelve flashes, clocks 30 and 40 ppm from
    the reference's (0.3-0.4 ms over 10 s), and on the 59.94 fps camera one band whose
    trailing edge is 1 ms late (the pulse's tail on a short exposure; there it made the
    camera's band-length noise 0.25 ms against 0.02 for its other bands, and no drift step
    was taken). The band is an outlier of the band lengths and left out of the noise, so
    both drifts are named and the model is within 0.02 ms RMS of the truth; in the second
    world, whose bands on that camera scatter as 0.045 ms of edge noise, within 0.06 (0.052:
    in ``sync``'s shape the reference's time per row is free, and comes out 0.2 % short of
    frame period / height, which this rig without hidden rows has exactly; 0.04 before, at
    frame period / height; ``sync`` 0.033). There
    the band is 19 robust sigmas off, under :data:`OUTLIER_BAND_SIGMAS` (the three split
    bands, fitted whole since 2026-11-26, count now and widen the spread; 25 sigmas before),
    so it stays in the noise (0.21 ms), and both drifts are named all the same."""
    duration = 10_000.0
    rig = (
        CameraSpec("cam1", 320, 180, NTSC_30, exposure_ms=2.0),
        CameraSpec("cam2", 320, 180, NTSC_30, exposure_ms=4.0, drift_ppm=30.0, start_ms=1000.0, offset_ms=-900.0),
        CameraSpec("cam3", 320, 180, NTSC_60, exposure_ms=3.0, drift_ppm=40.0, start_ms=5000.0, offset_ms=-4950.0),
    )
    scenario = Scenario("drifting", rig, duration_ms=duration, flashes=flashes(2, duration)[::3], n_players=0, seed=2)
    truth = render_scenario(dress(scenario, world), tmp_path)
    cameras = detect_videos([tmp_path / f"{c.name}.mp4" for c in rig], estimate_readout=False)
    unmoved = measure(cameras).camera_noise_ms[2]
    events = events_to_frame(cameras[2].events)
    late = events.index[(events["edge"] == "trailing") & (events["flags"] == "")][3]
    events.loc[late, "row"] += 1.0 / (1000.0 / NTSC_60 / 180)
    cameras[2] = replace(cameras[2], top_down=events_from_frame(events))
    measurement = measure(cameras)
    assert world == SECOND or (measurement.camera_noise_ms[2] < 1.5 * unmoved and unmoved < 0.02)
    d = diagnose(cameras)
    drifting = {c for s in d.steps if "drift" in s.effect.split("+") for c in s.camera.split("+")}
    assert drifting == {"cam2", "cam3"}, format_diagnosis(d)
    assert [m["drift_ppm"] for m in d.model] == pytest.approx([0.0, 30.0, 40.0], abs=5.0)
    assert pooled_error_ms(d.sync_model, truth) < (0.02 if world == FIRST else 0.06)


@pytest.fixture(scope="module", params=[FIRST, SECOND])
def flickering(request, tmp_path_factory) -> tuple[list, GroundTruth, str]:
    """Two cameras at one frame rate (30 fps) with the same hidden rows (8 + 20 of 208: their
    time per row is 13 % under frame period / height) under 5 % 100 Hz mains flicker: the
    reference's 10 ms exposure (one flicker period) averages it out, the other camera's 2 ms
    sees it roll (a third of a period per frame). Eleven flashes, three of them seen clean by
    both (10 ms bands are long): at one frame rate and a steady phase the flashes tell the
    difference of the two times per row, not their common part. Detected once per world."""
    rig = (
        CameraSpec("cam0", 320, 180, 30.0, r0=8, r1=20, exposure_ms=10.0),
        CameraSpec("cam1", 320, 180, 30.0, r0=8, r1=20, exposure_ms=2.0, start_ms=3000.0, offset_ms=-2817.0),
    )
    scenario = Scenario(
        "flicker", rig, duration_ms=DURATION_MS, flashes=flashes(3)[::2], n_players=0, seed=3, flicker_depth=0.05
    )
    folder = tmp_path_factory.mktemp("flicker")
    truth = render_scenario(dress(scenario, request.param), folder)
    return detect_videos([folder / "cam0.mp4", folder / "cam1.mp4"], estimate_readout=False), truth, request.param


def test_rolling_flicker_is_named_first_and_times_the_rows(flickering, tmp_path):
    """The flicker (its frequency and depth) is named first on the camera that sees it roll,
    its period in rows then times that camera's rows (the model's time per row is the
    flicker's: the gap between them, 4.5 ms over the image under frame period / height,
    closes; in ``sync``'s shape the flicker is that time per row's prior, as in ``sync``), the
    flashes carry it to the reference, and the model ``diagnose -o`` writes is within 0.1 ms
    RMS of the truth (0.036 in the first world, 0.073 in the second, where the tone curve
    leaves 1.8 % of the flicker's 5 % and the period comes out 0.26 % long). The same
    workflow blind to the flicker is as close (0.036 and 0.082 ms): in ``sync``'s shape both
    edges of every band pin the times per row here, as they do for ``sync`` without the
    flicker's prior; at frame period / height, before ``sync``'s shape, it was 2.1 ms off.
    ``sync`` (the same flicker, :func:`~flashsync.pipeline.mains_flicker`, is its prior) is
    within 0.1 ms of the truth (0.038 and 0.049 ms) and of ``diagnose -o``. The time per row
    written is the flicker's within 0.5 % (first world) and 1 % (second: rendered with OpenCV
    5.1, the CI machine's of 2026-12-02, the flicker's is 0.21 % short, the three flashes
    pull the solve 0.58 % long, 0.79 % apart; the times 0.08 ms off at error/sigma 2.2, a
    miss the README lists under "Renders move with the machine")."""
    cameras, truth, world = flickering
    d = diagnose(cameras)
    step = d.steps[0]
    assert (step.effect, step.camera) == ("flicker", "cam1"), format_diagnosis(d)
    assert step.estimate.startswith("100 Hz, depth"), step.estimate
    assert step.flicker_gap_before_ms > 1.0 and step.flicker_gap_after_ms <= step.flicker_gap_before_ms / 5.0
    assert_settled(d, cameras, truth, world)
    blind = diagnose([replace(camera, flicker=None) for camera in cameras])
    assert "flicker" not in {s.effect for s in blind.steps}, format_diagnosis(blind)
    error = pooled_error_ms(d.sync_model, truth)
    assert error < 0.1, format_diagnosis(d)
    assert pooled_error_ms(blind.sync_model, truth) < 0.1, format_diagnosis(blind)
    model, _ = synchronize(cameras)  # the same flicker (pipeline.mains_flicker) as its prior
    assert pooled_error_ms(model, truth) < 0.1
    assert max(gap.rms_ms for gap in model_gaps(d.sync_model, model)) < 0.1
    save_model(d.sync_model, tmp_path / "sync.json")
    written = load_model(tmp_path / "sync.json").camera("cam1")
    flicker = cameras[1].flicker
    rel = 0.005 if world == FIRST else 0.01
    assert written.row_time_ms == pytest.approx(1000.0 / flicker.hz / flicker.period_rows, rel=rel)
    assert written.row_time_ms == pytest.approx(truth.cameras["cam1"].row_time_ms, rel=0.01)


def test_second_world_pulse_tail_is_named_on_the_hd_rig_and_diagnose_o_closes_in(tmp_path, monkeypatch):
    """The second world's HD rig (``recipe("hd")``, xenon flashes, 12 s, every camera at
    320x180): on the 59.94 fps camera bands split across frames come out up to 2 ms long,
    their trailing edges read on the pulse's tail in the next frame, late against the
    truth, their leading edges 0.2-0.3 ms early. The detector now hides a trailing edge
    whose next-frame part peaks under half the band (``detect.TAIL_SHARE``; this rig then
    needs no pulse-shape step and ``diagnose -o`` ends 0.033 ms off); tails above it (a
    fresh random rig's at 0.65, 0.94 ms late) still make such edges, so the test keeps this
    rig's tails (the rule off) to stand for them. Without a pulse-shape step the workflow's
    final model is 0.20 ms RMS off the truth; it names the flash pulse shape on that camera
    (not first, see the README), and from before that step to the run's end the gap
    shrinks over 3.5x (0.306 to 0.044 ms: the step, 0.306 to 0.254, and the times per row it
    leaves to the next one; with split bands located edge by edge it was a pair with the
    time per row, 0.220 to 0.049; rendered with OpenCV 5.1, the CI machine's of 2026-12-02,
    the step comes last, 0.186 to 0.047). ``diagnose -o`` writes ``sync``'s solve with the
    widened bands' edges moved back by the shares found (0.068 ms off the truth, ``sync`` 0.070;
    the workflow's own model, written until 2026-12-02, 0.030: its cam2's time per row
    0.23 % off against ``sync``'s 0.71 %, not the pulse shape)."""
    monkeypatch.setattr("flashsync.detect.TAIL_SHARE", 0.0)
    scenario = recipe("hd", seed=0, duration_ms=12_000.0)
    scenario = replace(scenario, cameras=tuple(small(c, 320, 180) for c in scenario.cameras))
    truth = render_scenario(scenario, tmp_path)
    d = diagnose(
        detect_videos([tmp_path / f"{c.name}.{c.container}" for c in scenario.cameras], estimate_readout=False)
    )
    (step,) = [s for s in d.steps if "pulse_shape" in s.effect.split("+")]
    assert step.camera == "cam3", format_diagnosis(d)
    assert d.steps[-1].rms_after_ms <= step.rms_before_ms / 3.5, format_diagnosis(d)
    assert d.written == "sync's solve on the readouts found, band edges moved back by the flash pulse shape on cam3"
    assert pooled_error_ms(d.sync_model, truth) < 0.1, format_diagnosis(d)


def test_a_final_time_per_row_far_from_the_written_models_is_named(tmp_path):
    """The line-locked recipe (three 25 fps cameras in one phase) at 320x180 for 6 s: the
    workflow's fit reads the rows' noise as information and puts every time per row 59 %
    short, its verdict passing; ``sync``'s solve, written by ``-o``, is within 1 % of the
    truth. The report names each camera so (:data:`~flashsync.diagnose.workflow.TABLE_DOUBT_SIGMAS`)."""
    scenario = recipe("line-locked", seed=0, duration_ms=6000.0)
    scenario = replace(scenario, cameras=tuple(small(c, 320, 180) for c in scenario.cameras))
    truth = render_scenario(scenario, tmp_path)
    d = diagnose(detect_videos([tmp_path / f"{c.name}.{c.container}" for c in scenario.cameras]))
    doubted = [w for w in d.warnings if "the final model's time per row" in w]
    assert [w.split(":")[0] for w in doubted] == [str(tmp_path / f"{c.name}.mp4") for c in scenario.cameras]
    for name, clock in d.sync_model.cameras.items():
        assert clock.row_time_ms == pytest.approx(truth.cameras[name].row_time_ms, rel=0.01)
    assert all(row["row_time_ms"] < 0.5 * truth.cameras[row["camera"]].row_time_ms for row in d.model)


@pytest.mark.parametrize(
    "output, message",
    [("folder", "-o {}: is a folder; give a file name"), ("input", "is also an input (VIDEO {})")],
)
def test_cli_bad_model_output_is_one_line_error(tmp_path, capsys, output, message):
    """``diagnose -o`` into a folder or over one of its videos: one line, exit 1, nothing written
    (checked before any decoding)."""
    from flashsync.cli import main

    samples = Path(__file__).resolve().parents[1] / "samples"
    videos = [str(samples / "cam1.mp4"), str(samples / "cam2.mkv")]
    target = str(tmp_path) if output == "folder" else videos[0]
    before = Path(target).stat().st_mtime_ns
    assert main(["diagnose", *videos, "-o", target]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and message.format(target) in err
    assert Path(target).stat().st_mtime_ns == before


def test_the_verdicts_rms_is_over_the_edges_its_test_counts():
    """100 edges of 0.02 ms noise and three paired with the wrong flash, 58 ms off (random
    rig 416's pre-flash, at most :data:`~flashsync.diagnose.verdict.OUTLIER_SHARE` of the
    edges: left out of χ² as outliers): the verdict passes and gives the RMS of the edges it
    counts, and the RMS with the outliers apart. Before, it read "consistent with noise …
    (RMS 7.9171 ms, expected 0.2016 ms)", an RMS 40 times the noise it called consistent."""
    residual_ms = np.random.default_rng(1).normal(0.0, 0.02, 103)
    residual_ms[[10, 50, 90]] = 58.0
    test = noise_test(
        residual_ms, np.zeros(103, int), np.linspace(0, 8, 103), ["e"] * 103, ["cam1"], np.array([0.02]), 10
    )
    assert test.consistent and len(test.outliers) == 3 and test.counted_rms_ms == pytest.approx(0.02, rel=0.2)
    rms_ms = float(np.sqrt(np.mean(residual_ms**2)))
    d = Diagnosis(["cam1"], "cam1", 40, 103, [], rms_ms, rms_ms, rms_ms, True, 0.019, test, [], {})
    assert (
        f"(RMS {test.counted_rms_ms:.4f} ms, expected 0.0190 ms; {rms_ms:.4f} ms with the outlier edges)" in d.verdict
    ), d.verdict


def test_the_final_model_reads_every_camera_as_sync_reads_it(tmp_path):
    """The second world's rig-428 (``random_rig(428, max_height=360, duration_ms=8000)``: four
    cameras, three upside down, four or five flashes). Where no step turns cam4, ``sync``
    reading it bottom-up by them, as it is, the final model reads it so too and says so: its
    residuals pass the χ² test (before: cam4 top-down, 0.39 ms RMS, χ² 17.6 over 2 on the
    model ``-o`` did not write) and every camera is read as the model ``-o`` writes. Which
    way the workflow takes turns on the renders' last bits: rendered with OpenCV 5.1 (the CI
    machine of 2026-12-02) five flashes are found and a step turns cam4 (ΔBIC 15.1), so the
    model reads it as ``sync`` does with no word needed."""
    scenario = random_rig(428, max_height=360, duration_ms=8000.0)
    render_scenario(scenario, tmp_path)
    d = diagnose(detect_videos([tmp_path / f"{c.name}.{c.container}" for c in scenario.cameras]))
    turned = bool([s for s in d.steps if s.effect == FLIPPED and s.camera == "cam4"])
    assert d.sync_readouts == ([] if turned else ["cam4"])
    truth = {c.name: c.flipped for c in scenario.cameras}
    assert {m["camera"]: m["readout"] == "bottom-up" for m in d.model} == truth
    assert {name: camera.flipped for name, camera in d.sync_model.cameras.items()} == truth
    assert d.consistent, d.verdict
    assert turned or "and cam4 read the other way up, as sync reads it" in format_diagnosis(d)
