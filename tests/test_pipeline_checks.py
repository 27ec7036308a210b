"""synchronize's checks of its arguments and of what it announces: datasheet times per row
of unknown cameras or no number, anchors naming two events of one camera, cameras left out;
and which edges it synchronises on, with what weight."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import flashsync.match as match
import flashsync.pipeline as pipeline
from flashsync import detect_videos, synchronize
from flashsync.detect import LONG_PULSE_EDGE_SIGMA, SATURATED_EDGE_SIGMA, CameraDetection
from flashsync.diagnose import diagnose
from flashsync.errors import InputError, NotEnoughDataError
from flashsync.events import Band, Edge, Events, Flag
from flashsync.flicker import Flicker
from flashsync.frame_clock import fit_frame_clock
from flashsync.match import nominal_row_time_ms
from flashsync.model import CameraClock, SyncModel
from flashsync.pipeline import (
    EDGE_NOISE_FLOOR_ROWS,
    EDGE_NOISE_QUALITY,
    LONE_CUT_SIGMA,
    LONE_EDGE_SIGMA,
    MISREAD_DECAY_SHARE,
    _Attempt,
    _edge_sigma,
    _exposure_rows,
    _exposures_bands_tell,
    _exposures_the_others_tell,
    _lone_sigma,
    _misread_decay_rows,
    _pulse_lengths,
    _pulses_seen_shorter,
    _readout_doubts,
    _ShownExposure,
    _sync_events,
    _toward_cut_rows,
    _unturned_exposures_ms,
    check_anchors,
    check_row_times,
    row_time_prior_ms,
)
from flashsync.simulation.band_events import EXPOSURE_MS, HEIGHT, synthetic_detections, synthetic_events
from flashsync.solve import Priors


@pytest.mark.parametrize(
    "row_times, words",
    [({"cam9": 0.03}, "cam9: no such camera among cam1, cam2"), ({"cam1": math.inf}, "cam1=inf"),
     ({"cam1": math.nan}, "cam1=nan"), ({"cam1": -0.1}, "cam1=-0.1"), ({"cam1": True}, "cam1=True")],
)  # fmt: skip
def test_datasheet_times_per_row_of_no_camera_or_no_number_are_errors(row_times, words):
    with pytest.raises(InputError) as error:
        check_row_times(row_times, ["cam1", "cam2"])
    assert error.value.parameter == "row_times" and words in str(error.value)


def test_anchors_naming_two_events_of_one_camera_are_an_error():
    check_anchors(["cam1:0", "cam2:3", "cam1:0"])  # the same anchor twice is one
    with pytest.raises(InputError) as error:
        check_anchors(["cam1:0", "cam2:3", "cam1:4"])
    assert error.value.parameter == "anchors" and "cam1:0 and cam1:4" in str(error.value)


def test_a_camera_left_out_is_not_announced_upside_down(tiny_scenario):
    """A third camera read both ways up whose bottom-up reading has two leading edges fewer:
    the search reads it bottom-up (two events fewer unexplained raise the likelihood by more
    than a choice needs), but it
    is left out (too few events) and must not be reported as mounted upside down."""
    detections = detect_videos([tiny_scenario / "cam1.mp4", tiny_scenario / "cam2.mkv"], estimate_readout=False)

    def one_edge(count: int) -> Events:
        return Events.from_columns(
            ["cam3"] * count, range(count), [5] * count, [200.0] * count, [10.0] * count, [Edge.LEADING] * count,
            [Band.PULSE] * count, [1.0] * count, [0.5] * count, [50.0] * count, [frozenset()] * count,
        )  # fmt: skip

    lonely = CameraDetection("cam3", tiny_scenario / "cam3.mp4", 160, 120, np.arange(50) * 40.0, one_edge(2),
                             one_edge(0))  # fmt: skip
    model, report = synchronize([*detections, lonely])
    assert "cam3" not in model.cameras and any("cam3.mp4: 0 usable flash events" in w for w in report.warnings)
    assert report.flipped_found == []


def _reading(score: float, upside_down: bool) -> SimpleNamespace:
    """What :func:`~flashsync.pipeline._readout_doubts` reads of an attempt: cam2 read one way
    or the other (cam1 upright in both), its score, and a model whose cam2 is 1 ms later
    and its exposure 2.5 ms shorter upside down."""
    flipped = {"cam1": False, "cam2": upside_down}
    clock = SimpleNamespace(
        n_frames=3,
        height=10,
        flipped=upside_down,
        exposure_ms=4.0 - 2.5 * upside_down,
        t_global_ms=lambda frame, row: frame * 40.0 + row + upside_down,
    )
    reading = SimpleNamespace(
        score=score,
        connected=["cam1", "cam2"],
        implausible=[],
        cameras={name: SimpleNamespace(flipped=f, video=f"{name}.mp4") for name, f in flipped.items()},
        model=lambda reference: SimpleNamespace(cameras={"cam2": clock}),
        freed_drift_cost=0.0,
    )
    reading.evidence = _Attempt.evidence.fget(reading)  # the score less the upside-down prior
    return reading


@pytest.mark.parametrize(
    "free, drift_ppm, wider, cost",
    [
        ((2,), -1500.0, {}, math.log1p(30.0**2)),  # AP1's rig-893 read as its mirror: cam3 freed at -1500 ppm
        ((2,), 1000.0, {}, math.log1p(20.0**2)),  # stamps at a nominal rate: about as much in every reading
        ((2,), -1500.0, {2: 500e-6}, math.log1p(3.0**2)),  # a frame clock whose rate is loose widens the prior
        ((), -118.0, {}, 0.0),  # held by its prior: the solve's pull already counts
    ],
)
def test_a_reading_whose_events_free_a_drift_pays_what_a_heavy_tailed_prior_says_of_it(free, drift_ppm, wider, cost):
    """A reading of the rig that fits its edges only with a camera's drift freed from the prior
    (events that contradict it) loses ``log(1 + (drift / std) ** 2)`` of its evidence, a
    Cauchy prior's log-density as wide as the drift prior: AP1's rig-893 (three cameras at
    25-30 fps, auto exposure) read as its mirror led the right reading by 6.6 with its cam3 at
    -1500 ppm (every camera 18-31 ms off at error/σ 4-9); that costs it 6.8."""
    attempt = SimpleNamespace(
        score=50.0,
        cameras={"cam1": SimpleNamespace(flipped=False)},
        priors=Priors({}, wider_drift_std=wider),
        solution=SimpleNamespace(
            free_drift=free, cameras=[SimpleNamespace(alpha=1.0)] * 2 + [SimpleNamespace(alpha=1.0 + drift_ppm * 1e-6)]
        ),
    )
    attempt.freed_drift_cost = _Attempt.freed_drift_cost.fget(attempt)
    assert attempt.freed_drift_cost == pytest.approx(cost)
    assert _Attempt.evidence.fget(attempt) == pytest.approx(50.0 - cost)


@pytest.mark.parametrize("lead, warned", [(6.0, True), (8.0, False)])
def test_a_flip_needs_the_upside_down_prior_in_its_lead_on_the_reference_given(lead, warned):
    """A camera read upside down leads its upright reading by ``lead``: the search takes a flip
    at DECIDED_LOG_LIKELIHOOD (5) plus UPSIDE_DOWN_PRIOR (2), so a lead of 6 is a near tie,
    warned with the two readings' spreads of its times and exposure in sigma (it went unwarned
    when the check asked 5)."""
    spreads, exposures_ms, warnings = _readout_doubts(_reading(lead, True), {"cam2": _reading(0.0, False)}, "cam1")
    assert (list(spreads), list(exposures_ms), len(warnings)) == ((["cam2"], ["cam2"], 1) if warned else ([], [], 0))
    if warned:
        assert spreads["cam2"] == pytest.approx([1.0, 1.0, 1.0]) and exposures_ms["cam2"] == pytest.approx(2.5)
        assert "cam2.mp4: read bottom-up" in warnings[0] and "its exposure by 2.50 ms (in its sigma)" in warnings[0]


@pytest.mark.parametrize("flipped", [False, True])
def test_a_band_cut_by_the_readout_end_is_a_sync_event_within_one_exposure_of_it(flipped):
    """180 rows, a 20-row exposure: a band whose leading edge is hidden is matched by its
    trailing edge within 1.1 exposures of the first readout row (weighed 2x down), not
    further in (its leading edge would have been seen: the band is not one exposure long);
    a leading edge whose trailing one is hidden that far from the last row is weighed down
    as a pulse outlasting the exposure, one nearer counts as any other. Where the detector
    fitted no common exposure, the camera's whole bands' median length stands in; without
    those, the least exposure its lone edges allow (79 rows: event 4's leading edge lies 79
    rows from the last row), so its lone trailing edges are sync events and no lone edge
    lies further in than the exposure."""
    hidden = {"leading": frozenset({Flag.LEADING_HIDDEN}), "trailing": frozenset({Flag.TRAILING_HIDDEN})}
    edges = [  # (event, readout row, edge, flags)
        (0, 50.0, Edge.LEADING, frozenset()), (0, 70.0, Edge.TRAILING, frozenset()),
        (1, 15.0, Edge.TRAILING, hidden["leading"]), (2, 40.0, Edge.TRAILING, hidden["leading"]),
        (3, 165.0, Edge.LEADING, hidden["trailing"]), (4, 100.0, Edge.LEADING, hidden["trailing"]),
    ]  # fmt: skip
    n = len(edges)
    rows = [179.0 - q if flipped else q for _, q, _, _ in edges]
    events = Events.from_columns(
        ["cam"] * n, [e[0] for e in edges], [3] * n, [120.0] * n, rows, [e[2] for e in edges], [Band.PULSE] * n,
        [1.0] * n, [0.5] * n, [50.0] * n, [e[3] for e in edges],
    )  # fmt: skip
    reading = (
        dict(bottom_up=events, bottom_up_exposure_rows=20.0, flipped=True)
        if flipped
        else dict(top_down_exposure_rows=20.0)
    )
    detection = CameraDetection("cam", Path("cam.mp4"), 320, 180, np.arange(10) * 40.0, events, **reading)
    sync = _sync_events(detection)
    assert sync.event.tolist() == [0, 1, 3, 4]
    assert _edge_sigma(detection, sync).tolist() == [1.0, LONE_EDGE_SIGMA, 1.0, LONG_PULSE_EDGE_SIGMA]
    unfitted = replace(detection, top_down_exposure_rows=None, bottom_up_exposure_rows=None)
    assert _sync_events(unfitted).event.tolist() == [0, 1, 3, 4]  # its whole band's 20 rows stand in
    partial = events.take(np.arange(n) != 1)  # no whole band: the exposure from its lone edges
    unknown = replace(unfitted, top_down=partial, bottom_up=partial if flipped else None)
    assert _exposure_rows(unknown) == 79.0
    assert _sync_events(unknown).event.tolist() == [0, 1, 2, 3, 4]
    assert _edge_sigma(unknown, _sync_events(unknown)).tolist() == [1.0, LONE_EDGE_SIGMA, LONE_EDGE_SIGMA, 1.0, 1.0]


def test_only_bands_longer_than_the_exposure_others_share_are_taken_for_their_pulses():
    """A 10-row exposure: the bands 12 and 30 rows long are as long as their pulses (their
    lengths left out of the solve), those of 10 and 11.5 rows measure the exposure; where
    every band is that much longer, none is left out (the exposure would rest on nothing),
    nor where the detector fitted no common exposure."""
    lengths = [10.0, 12.0, 11.5, 30.0]
    n = 2 * len(lengths)
    rows = np.ravel([(40.0, 40.0 + length) for length in lengths])
    events = Events.from_columns(
        ["cam"] * n, np.repeat(np.arange(len(lengths)), 2), [3] * n, [120.0] * n, rows,
        [Edge.LEADING, Edge.TRAILING] * len(lengths), [Band.PULSE] * n, [1.0] * n, [0.5] * n, [50.0] * n,
        [frozenset()] * n,
    )  # fmt: skip
    detection = CameraDetection(
        "cam", Path("cam.mp4"), 320, 180, np.arange(10) * 40.0, events, top_down_exposure_rows=10.0
    )
    assert _pulse_lengths(detection).tolist() == [1, 3]
    assert _pulse_lengths(replace(detection, top_down_exposure_rows=8.0)).tolist() == []
    assert _pulse_lengths(replace(detection, top_down_exposure_rows=None)).tolist() == []


def test_a_faint_bands_edges_weigh_less_than_a_bright_ones():
    """Edges of qualities 2000 (the camera's median), 500, 5000, 500 and 3000: in units of
    the median one's, the faint edge's noise is hypot(0.21, 485 / 500) over hypot(0.21,
    485 / 2000) rows (3.1), the bright one's 0.73; a flag's factor multiplies its band's (a
    saturated faint edge)."""
    qualities = [2000.0, 500.0, 5000.0, 500.0, 3000.0]
    flags = [frozenset()] * 3 + [frozenset({Flag.SATURATED}), frozenset()]
    events = Events.from_columns(
        ["cam"] * 5, range(5), [3] * 5, [120.0] * 5, [20.0, 60.0, 100.0, 140.0, 160.0], [Edge.LEADING] * 5,
        [Band.PULSE] * 5, [1.0] * 5, [0.5] * 5, qualities, flags,
    )  # fmt: skip
    detection = CameraDetection("cam", Path("cam.mp4"), 320, 180, np.arange(10) * 40.0, events)
    noise = np.hypot(EDGE_NOISE_FLOOR_ROWS, EDGE_NOISE_QUALITY / np.array(qualities))
    sigma = _edge_sigma(detection, events)
    assert sigma == pytest.approx(noise / noise[0] * [1.0, 1.0, 1.0, SATURATED_EDGE_SIGMA, 1.0])
    assert sigma[1] > 3.0 and 0.7 < sigma[2] < 0.75


def lone_edges(rises: np.ndarray, rise_rows: float, flipped: bool) -> tuple[CameraDetection, Events]:
    """A camera of 180 rows (read bottom-up where ``flipped``) and its edges: lone leading
    edges (trailing edge hidden past the last readout row) ``rises`` ramps of ``rise_rows``
    from that row, lone trailing edges as far from the first, both edges of a whole band, and
    a lone leading edge of no known rise."""
    hidden = {Edge.LEADING: frozenset({Flag.TRAILING_HIDDEN}), Edge.TRAILING: frozenset({Flag.LEADING_HIDDEN})}
    edges = [(Edge.LEADING, 179.0 - rise_rows * r, hidden[Edge.LEADING], rise_rows) for r in rises]
    edges += [(Edge.TRAILING, rise_rows * r, hidden[Edge.TRAILING], rise_rows) for r in rises]
    edges += [(Edge.LEADING, 60.0, frozenset(), rise_rows), (Edge.TRAILING, 80.0, frozenset(), rise_rows)]
    edges += [(Edge.LEADING, 178.0, hidden[Edge.LEADING], math.nan)]
    n = len(edges)
    rows = [179.0 - q if flipped else q for _, q, _, _ in edges]
    events = Events.from_columns(
        ["cam"] * n, range(n), [3] * n, [120.0] * n, rows, [e[0] for e in edges], [Band.PULSE] * n,
        [e[3] for e in edges], [0.5] * n, [50.0] * n, [e[2] for e in edges],
    )  # fmt: skip
    return CameraDetection("cam", Path("cam.mp4"), 320, 180, np.arange(10) * 40.0, events, flipped=flipped), events


@pytest.mark.parametrize("flipped", [False, True])
def test_a_lone_edge_is_weighed_down_as_its_ramp_nears_the_cut(flipped):
    """A lone edge (its band's other edge hidden beyond the first or last readout row) is
    noisier the fewer rises of its ramp lie between it and that row: ``LONE_CUT_SIGMA /
    sqrt(rises)``, between 1 and ``LONE_CUT_SIGMA`` (within two rises of the cut such edges
    spread 1.4 rows against the truth, beyond sixteen 0.33-0.47); a lone trailing edge at
    least ``LONE_EDGE_SIGMA``; an edge of a whole band, or of a ramp of no known rise, 1."""
    rises = np.array([0.5, 1.0, 4.0, 9.0, 25.0])  # from the cut, of a 4-row ramp
    detection, events = lone_edges(rises, 4.0, flipped)
    near = np.clip(LONE_CUT_SIGMA / np.sqrt(np.maximum(rises, 1.0)), 1.0, LONE_CUT_SIGMA)
    expected = [*near, *np.maximum(near, LONE_EDGE_SIGMA), 1.0, 1.0, 1.0]
    assert _lone_sigma(detection, events) == pytest.approx(expected)
    assert near[:3] == pytest.approx([LONE_CUT_SIGMA, LONE_CUT_SIGMA, LONE_CUT_SIGMA / 2])


@pytest.mark.parametrize("flipped", [False, True])
def test_a_lone_edge_may_lie_a_share_of_its_ramp_further_from_the_cut(flipped):
    """A lone edge of a ramp 20 rows long may lie ``LONE_RISE_SHARE`` of the rise (12 rows)
    further from the frame's cut than its flash puts it within a rise of the cut, less as the
    cut moves away (``rises ** -LONE_RISE_POWER``: 5 rows two rises away, 2.1 four, 0.9
    eight): readout rows towards the cut, a lone trailing edge's (its leading edge hidden
    before the first row) negative, a lone leading edge's positive; 0 for the edges of a
    whole band and of a ramp of no known rise. (Against the truth such edges lie 0.3 of a
    rise further from the cut within one and a half rises of it, and spread 0.4-0.6.)"""
    detection, events = lone_edges(np.array([0.5, 1.0, 2.0, 4.0, 8.0]), 20.0, flipped)
    away = np.array([12.0, 12.0, 5.05, 2.12, 0.89])
    expected = [*away, *-away, 0.0, 0.0, 0.0]
    assert _toward_cut_rows(detection, events) == pytest.approx(expected, abs=0.01)


@pytest.mark.parametrize("seed, lone", [(1, 3), (0, 0)])
def test_a_cameras_sigma_holds_what_the_reference_s_lone_edges_may_move(monkeypatch, seed, lone):
    """Three synthetic cameras, 10 flashes; the reference's bands whose trailing edge falls
    past its last row (three at seed 1, none at seed 0) have ramps 40 rows long: their
    leading edges may lie up to 24 rows further from the cut (:func:`_toward_cut_rows`), and
    what that moves the other cameras' clocks (the solve again with them so moved) is in
    their sigma: cam1's shift's 0.43 -> 0.49 ms. Where the reference has no lone edge nothing
    changes."""
    events, truth, frame_times = synthetic_events(3, 10, seed=seed)
    detections = synthetic_detections(events, truth, frame_times, seed=seed)
    bands = detections[0].top_down
    cut = bands.has_flag(Flag.TRAILING_HIDDEN)
    assert cut.sum() == lone  # the premise
    bands = replace(bands, rise_rows=np.where(cut, 40.0, bands.rise_rows))
    detections[0] = replace(detections[0], top_down=bands, bottom_up=None)
    shift_std = []
    for share in (0.0, pipeline.LONE_RISE_SHARE):
        monkeypatch.setattr(pipeline, "LONE_RISE_SHARE", share)
        model, _ = synchronize(detections)
        shift_std.append(np.sqrt(model.cameras["cam1"].covariance[1, 1]))
    if lone:
        assert shift_std[1] > 1.1 * shift_std[0], shift_std
    else:
        assert shift_std[1] == pytest.approx(shift_std[0], rel=1e-6)


def test_what_split_bands_left_out_move_is_in_every_cameras_covariance(monkeypatch):
    """The final solve's scatter holds what each camera's split bands left out move where
    they disagree with the other edges (:func:`~flashsync.jackknife.split_left_out_scatter`),
    weighed against every camera's time per row's variance with the other errors in it: a
    change it reports lands in the model's covariance as it is."""
    events, truth, frame_times = synthetic_events(3, 10, seed=0)
    detections = synthetic_detections(events, truth, frame_times, seed=0)
    before, _ = synchronize(detections)
    seen = []

    def disagreeing(events, n_cameras, reference, solution, priors, row_time_var):
        seen.append(row_time_var)
        return [np.diag([0.0, 0.01, 1e-6, *np.zeros(len(camera.warp_ms)), 0.0]) for camera in solution.cameras]

    monkeypatch.setattr(pipeline, "split_left_out_scatter", disagreeing)
    after, _ = synchronize(detections)
    variance = sorted(camera.covariance[2, 2] for camera in before.cameras.values())  # with every other error
    assert seen and sorted(seen[-1]) == pytest.approx(variance, rel=1e-6)
    for name, camera in after.cameras.items():
        added = camera.covariance[1:3, 1:3] - before.cameras[name].covariance[1:3, 1:3]
        assert added == pytest.approx(np.diag([0.01, 1e-6]), abs=1e-9), name


def test_only_whole_bands_of_the_exposures_length_under_longer_pulses_move_with_a_misread_decay():
    """A 10-row exposure: the edges of the bands 10 and 11.5 rows long under pulses of 15
    and 12 rows may move :data:`MISREAD_DECAY_SHARE` of their pulse; not those of a band
    under a shorter pulse, of one as long as its pulse (13 rows: a rectangle's, or an
    exposure the camera changed to) nor a lone edge (its band not fitted whole); none
    without a common exposure or pulses."""
    lengths, pulses = [10.0, 11.5, 10.0, 13.0], [15.0, 12.0, 4.0, 16.0, np.nan]
    n = 2 * len(lengths) + 1
    rows = [*np.ravel([(40.0, 40.0 + length) for length in lengths]), 170.0]
    events = Events.from_columns(
        ["cam"] * n, [0, 0, 1, 1, 2, 2, 3, 3, 4], [3] * n, [120.0] * n, rows,
        [Edge.LEADING, Edge.TRAILING] * len(lengths) + [Edge.LEADING], [Band.PULSE] * n, [1.0] * n, [0.5] * n,
        [50.0] * n, [frozenset()] * (n - 1) + [frozenset({Flag.TRAILING_HIDDEN})],
    )  # fmt: skip
    detection = CameraDetection(
        "cam", Path("cam.mp4"), 320, 180, np.arange(10) * 40.0, events, top_down_exposure_rows=10.0,
        top_down_pulse_rows=np.array(pulses),
    )  # fmt: skip
    expected = MISREAD_DECAY_SHARE * np.array([15.0, 15.0, 12.0, 12.0, 0, 0, 0, 0, 0])
    assert _misread_decay_rows(detection, events) == pytest.approx(expected)
    for unknown in ({"top_down_exposure_rows": None}, {"top_down_pulse_rows": None}):
        assert not _misread_decay_rows(replace(detection, **unknown), events).any()


def test_an_error_common_to_a_cameras_long_pulses_is_in_sigma(monkeypatch):
    """Two cameras, 24 flashes; camera 1's bands in its lower half saw pulses 1.5 exposures
    long (the others 0.3), their decays read short so that both edges lie 0.1 of the pulse
    early (RC12's rolling-flicker reference: 5.7-row exposure, 7-15-row decays read 2-36 %
    short). Those edges move by :data:`MISREAD_DECAY_SHARE` of their pulse in the scatter
    (both edges of each band, no other edge), and its time per row, 1.6 % off, is within
    2 sigma (3.5 without)."""
    events, truth, frame_times = synthetic_events(2, 24, seed=0)
    detections = []
    for c, detection in enumerate(synthetic_detections(events, truth, frame_times, seed=0)):
        bands, exposure = detection.top_down, EXPOSURE_MS / truth[c][2]
        pulses = np.full(bands.event.max() + 1, 0.3 * exposure)
        if c == 1:
            lower = np.unique(bands.event[(bands.edge == Edge.LEADING) & (bands.row > HEIGHT / 2)])
            pulses[lower] = 1.5 * exposure
            early = np.where(np.isin(bands.event, lower), 0.1 * pulses[bands.event], 0.0)
            bands = replace(bands, row=bands.row - early)
        detections.append(
            replace(
                detection, top_down=bands, bottom_up=None, top_down_exposure_rows=exposure, top_down_pulse_rows=pulses
            )
        )
    seen = []
    moved_scatter = pipeline.moved_scatter
    monkeypatch.setattr(pipeline, "moved_scatter", lambda *args: seen.append(args) or moved_scatter(*args))
    model, _ = synchronize(detections)
    observations, moves = seen[-2][0], seen[-2][-1]  # the misread decays' (the bands fitted too short follow)
    long_pulse = 1.5 * EXPOSURE_MS / truth[1][2]
    assert sorted(set(np.round(moves, 6))) == pytest.approx([0.0, MISREAD_DECAY_SHARE * long_pulse])
    moved, trailing = moves != 0, observations.trailing
    assert set(observations.camera[moved]) == {1}
    assert np.all(moved[observations.leading_of[moved & trailing]])
    assert np.count_nonzero(moved & trailing) == np.count_nonzero(moved & ~trailing) >= 4
    error = model.cameras["cam1"].row_time_ms - truth[1][2]
    assert abs(error) / truth[1][2] > 0.01
    assert abs(error) < 2 * np.sqrt(model.cameras["cam1"].covariance[2, 2])
    monkeypatch.setattr(pipeline, "MISREAD_DECAY_SHARE", 0.0)
    before, _ = synchronize(detections)
    assert abs(before.cameras["cam1"].row_time_ms - truth[1][2]) > 3 * np.sqrt(before.cameras["cam1"].covariance[2, 2])


def test_both_equations_of_a_faint_band_are_weighed_by_its_quality(monkeypatch):
    """Three cameras, 20 flashes, every other band faint (quality 400, the rest 4000): the
    solve gets each band's midpoint (its leading edge's row) and length (its trailing edge's)
    with the noise its quality gives, in units of the camera's median edge's."""
    events, truth, frame_times = synthetic_events(3, 20, seed=0)
    detections = []
    for detection in synthetic_detections(events, truth, frame_times):
        bands = detection.top_down
        bands = replace(bands, quality=np.where(bands.event % 2 == 1, 400.0, 4000.0))
        detections.append(replace(detection, top_down=bands, bottom_up=None))
    seen = []
    solve = pipeline.solve_with_drift_model
    monkeypatch.setattr(
        pipeline,
        "solve_with_drift_model",
        lambda edges, *args, **kwargs: seen.append(edges) or solve(edges, *args, **kwargs),
    )
    synchronize(detections)
    observations = seen[-1]
    noise = np.hypot(EDGE_NOISE_FLOOR_ROWS, EDGE_NOISE_QUALITY / np.array([400.0, 4000.0]))
    for c, detection in enumerate(detections):
        expected = noise / np.hypot(EDGE_NOISE_FLOOR_ROWS, EDGE_NOISE_QUALITY / np.median(detection.top_down.quality))
        for trailing in (False, True):
            factors = observations.sigma_factor[(observations.camera == c) & (observations.trailing == trailing)]
            # a leading edge whose trailing one is hidden far from the last row also counts as a long pulse's
            factors = np.where(
                factors >= LONG_PULSE_EDGE_SIGMA * expected.min(), factors / LONG_PULSE_EDGE_SIGMA, factors
            )
            assert sorted(set(np.round(factors, 9))) == pytest.approx(sorted(expected)), (c, trailing)


def clip(detection: CameraDetection, out_ms: np.ndarray, unclipped: int, row_time_ms: float) -> CameraDetection:
    """``detection`` (top-down reading in use, no other) with its bands but the first
    ``unclipped`` clipped at white as a clip widens a band: flagged ``saturated``, both
    edges moved out by ``out_ms[event]`` (ms; a band that would leave the image kept as it was)."""
    bands = detection.top_down
    out = out_ms[bands.event] / row_time_ms
    lead = dict(zip(bands.event[bands.edge == Edge.LEADING], bands.row[bands.edge == Edge.LEADING]))
    trail = dict(zip(bands.event[bands.edge == Edge.TRAILING], bands.row[bands.edge == Edge.TRAILING]))
    inside = np.array(
        [e in trail and lead[e] >= o and trail[e] + o <= detection.height - 1 for e, o in zip(bands.event, out)]
    )
    clipped = inside & (bands.event >= unclipped)
    row = bands.row + np.where(clipped, np.where(bands.edge == Edge.LEADING, -out, out), 0.0)
    flags = np.array([f | {Flag.SATURATED} if c else f for f, c in zip(bands.flags, clipped)], dtype=object)
    return replace(detection, top_down=replace(bands, row=row, flags=flags), bottom_up=None)


def clock_errors_ms(model: SyncModel, truth: np.ndarray, frame_times: list[np.ndarray], c: int) -> tuple:
    """The model's times of synthetic camera ``c`` (every 50th frame, every 60th row) minus
    the true ones (the global clock's origin removed), and their predicted σ, ms."""
    camera = model.cameras[f"cam{c}"]
    frame, row = np.meshgrid(np.arange(0, camera.n_frames, 50), np.arange(0.0, 1080.0, 60.0))
    origin = model.cameras["cam0"].t_global_ms(0, 0.0) - frame_times[0][0]
    alpha, beta, row_time = truth[c]
    error = camera.t_global_ms(frame, row) - (alpha * frame_times[c][frame] + beta + row * row_time) - origin
    return error, camera.t_global_std_ms(frame, row)


@pytest.mark.parametrize("seed", range(4))
def test_a_camera_of_clipped_bands_is_timed_by_their_midpoints(seed):
    """Three synthetic cameras (1080 rows, edges 0.05 ms noisy), 30 flashes; cam1's bands
    clipped at white but its first three, each one's edges moved out alike by 0-0.3 ms (a
    clip widens a band about its midpoint: over the kept random rigs 0-49 the midpoints of
    105 clipped bands were as close to the truth as those of unclipped ones, robust sigma
    0.19-0.32 rows against 0.21-0.24, their lengths 1 row too long). ``sync`` times cam1 by
    those midpoints and leaves their lengths out of its exposure: its times within 1.8x
    (+ 5 us) of what the same flashes give it unclipped (0.022-0.103 ms against
    0.024-0.067, RMS), its exposure within 0.08 ms. Timed by the clipped bands' leading
    edges, weighed 12x down (the code before), it was 0.086-0.171 ms off and fails on three
    of the four seeds; with their lengths in its exposure at full weight, 0.11-0.18 ms off
    and its exposure 0.18 ms long (seed 3)."""
    events, truth, frame_times = synthetic_events(3, 30, seed=seed)
    out_ms = np.random.default_rng(seed).uniform(0.0, 0.3, 30)

    def error_rms_ms(unclipped: int) -> tuple[float, float]:
        detections = synthetic_detections(events, truth, frame_times, seed=seed)
        detections[1] = clip(detections[1], out_ms, unclipped, truth[1, 2])
        model, _ = synchronize(detections)
        error, _ = clock_errors_ms(model, truth, frame_times, 1)
        return float(np.sqrt(np.mean(error**2))), model.cameras["cam1"].exposure_ms - EXPOSURE_MS

    unclipped_ms, _ = error_rms_ms(unclipped=30)
    clipped_ms, exposure_error_ms = error_rms_ms(unclipped=3)
    assert clipped_ms <= 1.8 * unclipped_ms + 0.005, (clipped_ms, unclipped_ms)
    assert abs(exposure_error_ms) < 0.08


@pytest.mark.parametrize("seed", range(2))
def test_a_camera_of_clipped_bands_alone_states_no_exposure(seed):
    """The same rig with every one of cam1's bands clipped: a clipped band is longer than the
    exposure by what the clip adds, so with fewer than two unclipped bands
    (``pipeline.MIN_UNCLIPPED_BANDS``) the clipped ones are not timing bands: cam1 is timed by
    their leading edges, 12x down, states no exposure, and its σ covers its error (0.11 and
    0.21 ms RMS at error/σ 0.86 and 1.69). Timed by their midpoints it stated one, 2.20 ±
    0.14 and 2.17 ± 0.18 ms against the true 2; on a rendered camera whose scene was at white
    under the bands (white level 140), 1.15 ± 0.08 ms against 8, and its times were 17 σ off."""
    events, truth, frame_times = synthetic_events(3, 30, seed=seed)
    detections = synthetic_detections(events, truth, frame_times, seed=seed)
    detections[1] = clip(detections[1], np.random.default_rng(seed).uniform(0.0, 0.3, 30), 0, truth[1, 2])
    model, _ = synchronize(detections)
    assert model.cameras["cam1"].exposure_ms is None
    error, sigma = clock_errors_ms(model, truth, frame_times, 1)
    assert np.sqrt(np.mean((error / sigma) ** 2)) < 2.0


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_band_whose_ramp_was_not_measured_does_not_set_the_exposure(seed):
    """Three synthetic cameras (1080 rows, 2 ms exposures, edges 0.05 ms noisy), 30 flashes;
    every third of cam1's bands ends 0.2-0.6 ms late on a ramp the detector could not
    measure (no rise: its foot or its plateau beyond the frame's cut or in blind rows; rig
    420's cam4 had one such band alone, its exposure 0.45 ms long at error/σ 10.9). Those
    lengths weigh less (:data:`~flashsync.pipeline.UNMEASURED_RAMP_SIGMA`): cam1's exposure
    within 0.04 ms (0.025-0.038), at error/σ under 2. Weighed as the others', it was
    0.043-0.089 ms long."""
    events, truth, frame_times = synthetic_events(3, 30, seed=seed)
    detections = synthetic_detections(events, truth, frame_times, seed=seed)
    bands = detections[1].top_down
    late = (bands.edge == Edge.TRAILING) & (bands.event % 3 == 0)
    late_rows = np.random.default_rng(seed).uniform(0.2, 0.6, len(bands)) / truth[1, 2]
    late &= bands.row + late_rows < detections[1].height - 1
    bands = replace(
        bands, row=bands.row + np.where(late, late_rows, 0.0), rise_rows=np.where(late, np.nan, bands.rise_rows)
    )
    detections[1] = replace(detections[1], top_down=bands, bottom_up=None)
    model, _ = synchronize(detections)
    camera = model.cameras["cam1"]
    assert abs(camera.exposure_ms - EXPOSURE_MS) < 0.04, (camera.exposure_ms, camera.exposure_std_ms)
    assert abs(camera.exposure_ms - EXPOSURE_MS) < 2 * camera.exposure_std_ms


def test_equal_rate_cameras_without_split_bands_keep_an_honest_time_per_row():
    """Three 50 fps cameras of 1080 rows in one phase over 10 minutes, 100 flashes, edges
    0.05 ms noisy, no band split across frames: the flashes leave the time per row to the
    prior, and its error must stay within 2 σ, its σ one camera's prior (one size and rate:
    one readout, :data:`~flashsync.solve.SHARED_READOUT_CORRELATION`; three independent
    priors pinned their common scale sqrt(3) too tightly), and a correct datasheet value
    must stand. These sensors read over 95 % of their frame, the slow end of the prior's
    10-100 %: 44 % short at 1.7 σ (2.9 σ with independent priors; 3 % at 0.15 σ with the
    prior centred on the nominal, to 2026-12-02). Before the rows' noise was taken out of
    the time per row's information it came out 89 % short at 57 σ, overruling the datasheet."""
    events, truth, frame_times = synthetic_events(3, 100, seed=6)
    detections = synthetic_detections(events, truth, frame_times, seed=6)
    model, _ = synchronize(detections)
    for c in range(3):
        camera = model.cameras[f"cam{c}"]
        sigma = np.sqrt(camera.covariance[2, 2])
        assert abs(camera.row_time_ms - truth[c, 2]) <= 2 * sigma
        assert sigma >= 0.9 * row_time_prior_ms(nominal_row_time_ms(detections[c]))[1]
    known = {f"cam{c}": truth[c, 2] for c in range(3)}
    model, report = synchronize(detections, row_times=known)
    assert not [w for w in report.warnings if "contradicts" in w]
    for c in range(3):
        assert model.cameras[f"cam{c}"].row_time_ms == pytest.approx(truth[c, 2], rel=1e-3)


def test_a_mains_flicker_that_contradicts_the_flashes_is_not_a_prior():
    """rig-318 of the random rigs: two 59.94 fps cameras named their 100 Hz flicker 120 Hz,
    and its period then told a time per row 20 % short, at 1 % standard deviation;
    as the prior it took every 59.94 fps camera 20 % off (error/σ up to 22), 6.9 ms RMS.
    Three synthetic cameras at different rates, 30 flashes: cam2's flicker is a 100 Hz
    period named 120 Hz, cam1's is right. cam2's is dropped with a warning and its time per
    row is the events' (within 3σ of the truth); cam1's stands as its prior, no warning.
    ``diagnose`` takes no evidence from cam2's flicker either (``sync``'s decision,
    :attr:`~flashsync.pipeline.SyncReport.distrusted_flicker`): taking it, it named the
    flicker on cam2 and its final model's times per row were 0.3-0.45 % short on every
    camera; now within 0.1 %."""
    events, truth, frame_times = synthetic_events(3, 30, seed=0)
    detections = synthetic_detections(events, truth, frame_times)

    def seen(c: int, hz: float, named: float) -> Flicker:
        period = 1000.0 / hz / truth[c, 2]
        return Flicker(named, period, 0.001 * period, 0.03, 100, np.zeros(1), detections[c].height)

    detections[1] = replace(detections[1], flicker=seen(1, 120.0, 120.0))
    detections[2] = replace(detections[2], flicker=seen(2, 100.0, 120.0))
    model, report = synchronize(detections)
    warned = [w for w in report.warnings if "flicker" in w and "contradicts the events" in w]
    assert len(warned) == 1 and warned[0].startswith("cam2.mp4"), report.warnings
    camera = model.cameras["cam2"]
    assert abs(camera.row_time_ms - truth[2, 2]) <= 3 * np.sqrt(camera.covariance[2, 2])
    assert model.cameras["cam1"].row_time_ms == pytest.approx(truth[1, 2], rel=1e-3)
    assert report.distrusted_flicker == ["cam2"]
    d = diagnose(detections)
    assert any(w.startswith("cam2.mp4: sync takes no prior from its rolling flicker") for w in d.warnings), d.warnings
    assert ("flicker", "cam2") not in {(s.effect, s.camera) for s in d.steps}
    assert [m["row_time_ms"] for m in d.model] == pytest.approx(truth[:, 2], rel=1e-3)


def test_a_reference_tied_to_no_camera_names_the_cameras_tied_without_it():
    """The first camera saw two of the flashes, the others all thirty: nothing can be tied to
    it. Given as the reference, the error names the cameras tied among themselves and the
    one to give as the reference instead (a random rig's first camera saw two of six
    flashes); so does diagnose's."""
    detections, *_ = _first_camera_saw_two_flashes()
    with pytest.raises(NotEnoughDataError, match=r"cam1, cam2 share enough among themselves: .*\(--reference cam"):
        synchronize(detections, reference="cam0")
    with pytest.raises(NotEnoughDataError, match=r"cam1, cam2 share enough among themselves: .*\(--reference cam"):
        diagnose(detections, reference="cam0")


def test_a_first_video_tied_to_no_camera_leaves_the_reference_to_the_others():
    """Not given a reference, ``sync`` took the first video and failed where it shares too
    few flashes with the others (9 of 44 fast-readout random rigs; with another reference 5
    of them sync). Now the camera the error would name is the reference, and the first
    line of the report says so; the others' clocks come out right on its clock, and
    ``diagnose`` takes the same reference."""
    detections, truth, frames = _first_camera_saw_two_flashes()
    model, report = synchronize(detections)
    assert set(model.cameras) == {"cam1", "cam2"} and model.reference in model.cameras
    assert report.warnings[0].startswith(
        f"{detections[0].video}: the first video, the reference unless one is given, shares too few flashes"
    ), report.warnings
    assert f"{model.reference}'s clock is the global clock instead" in report.warnings[0]
    other = ({"cam1", "cam2"} - {model.reference}).pop()
    (a_ref, b_ref, _), (a, b, _) = truth[int(model.reference[3:])], truth[int(other[3:])]
    start_ref, start = frames[int(model.reference[3:])][0], frames[int(other[3:])][0]  # the stamps' zeros
    clock = model.cameras[other]
    assert clock.alpha == pytest.approx(a / a_ref, abs=1e-6)
    assert clock.beta_ms == pytest.approx((a * start + b - a_ref * start_ref - b_ref) / a_ref, abs=0.05)
    for c, name in ((1, "cam1"), (2, "cam2")):
        row_time, std = model.cameras[name].row_time_ms, np.sqrt(model.cameras[name].covariance[2, 2])
        assert abs(row_time - truth[c, 2]) < 3 * std and std < 0.01 * truth[c, 2]
    assert diagnose(detections).sync_model.reference == model.reference


def test_a_first_video_tied_in_a_smaller_group_leaves_the_reference_to_the_larger():
    """Not given a reference, ``sync`` kept the first video's clock wherever it was tied to
    any camera, and left out every camera not tied to it: random rig 98 of fast readouts had
    its first video tied to one camera by three flashes and eight cameras left out that
    share five to eight flashes among themselves. Here cam0 and cam1 share ten flashes and
    cam2-cam4 twenty others: the larger group is solved, on the clock of its camera with the
    most matched flashes, as if it were named, the first line of the report says so, and the
    others' clocks come out right on it (within 3 sigma). Named, cam0 keeps its own group."""
    events, truth, frames = synthetic_events(5, 30, seed=2)
    keep = (events.camera < 2) == (events.flash < 10)
    columns = {name: getattr(events, name)[keep] for name in ("camera", "flash", "t_frame_ms", "q")}
    detections = synthetic_detections(replace(events, **columns), truth, frames)
    model, report = synchronize(detections)
    assert set(model.cameras) == {"cam2", "cam3", "cam4"}, report.warnings
    assert report.warnings[0].startswith(
        f"{detections[0].video}: the first video, the reference unless one is given, is tied to 1 of the 4 other "
        f"cameras only; {model.reference}'s clock ties 2 and is the global clock instead"
    ), report.warnings
    assert any("cam0" in w and "left out" in w for w in report.warnings)
    r = int(model.reference[3:])
    for name, clock in model.cameras.items():
        if (c := int(name[3:])) == r:
            continue
        (a_ref, b_ref, _), (a, b, _) = truth[r], truth[c]
        assert clock.alpha == pytest.approx(a / a_ref, abs=1e-6)
        beta_error = clock.beta_ms - (a * frames[c][0] + b - a_ref * frames[r][0] - b_ref) / a_ref
        assert abs(beta_error) < 3.0 * np.sqrt(clock.covariance[1, 1])
    named = synchronize(detections, reference=model.reference)[0]
    assert all(named.cameras[name].beta_ms == clock.beta_ms for name, clock in model.cameras.items())
    assert set(synchronize(detections, reference="cam0")[0].cameras) == {"cam0", "cam1"}


def _first_camera_saw_two_flashes():
    """Three synthetic cameras (cam0 first) of thirty flashes of which cam0 saw two: their
    detections, true (alpha, beta_ms, row_time_ms) on cam0's clock (shape (3, 3)) and frame
    times on their own clocks (ms; the stamps start at each one's first)."""
    events, truth, frames = synthetic_events(3, 30, seed=1)
    keep = (events.camera != 0) | (events.flash < 2)
    columns = {name: getattr(events, name)[keep] for name in ("camera", "flash", "t_frame_ms", "q")}
    return synthetic_detections(replace(events, **columns), truth, frames), truth, frames


class _Matched(SimpleNamespace):
    """Matched sync events: ``flash``, ``camera`` and ``event`` arrays of one length."""

    def __len__(self) -> int:
        return len(self.flash)


def _pulse_rig(**changes) -> SimpleNamespace:
    """A solve's matched pulses: three flashes of 0.05-0.1 ms and one of 3 ms seen by a camera
    whose bands read as a 1.2-row exposure (0.12 ms) that every pulse outlasts (0.83-0.85 ms,
    3 ms) and by one whose 2 ms exposure outlasts them (pulses read by its ramps); ``changes``
    per camera: ``rows`` (its bands' exposure), ``pulses`` (ms), ``solved`` (its solve's
    exposure, ms); a third camera where given."""
    cameras = {
        "short": dict(rows=1.2, pulses=[0.84, 0.83, 0.85, 3.0], solved=0.12),
        "ramps": dict(rows=20.0, pulses=[0.05, 0.1, 0.08, np.nan], solved=2.0),
    }
    for name, change in changes.items():
        cameras[name] = {**cameras.get(name, cameras["ramps"]), **change}
    names = list(cameras)
    best = SimpleNamespace(
        connected=names,
        matches=_Matched(
            flash=np.tile(np.arange(4), len(names)),
            camera=np.repeat(names, 4),
            event=np.tile(np.arange(4), len(names)),
            frame=np.tile(10 * np.arange(1, 5), len(names)),
        ),
        cameras={
            n: SimpleNamespace(
                camera=n,
                video=Path(f"{n}.mp4"),
                exposure_rows=c["rows"],
                pulse_rows=np.array(c["pulses"]) / 0.1,
            )
            for n, c in cameras.items()
        },
        solution=SimpleNamespace(
            cameras=[SimpleNamespace(row_time_ms=0.1, exposure_ms=c["solved"]) for c in cameras.values()]
        ),
    )
    return best


def _told(turnable: bool = True, **changes) -> dict:
    """:func:`_exposures_the_others_tell` on :func:`_pulse_rig` with ``changes``."""
    best = _pulse_rig(**changes)
    return _exposures_the_others_tell(best, _pulses_seen_shorter(best), turnable)


def test_a_camera_is_read_the_other_way_round_only_on_evidence_that_holds():
    """The short camera's three flashes the ramp-reading camera sees at most half as long,
    its pulses of them 0.83-0.85 ms: read as a 0.84 ms exposure. Not where its pulses of them
    disagree, where another ramp-reading camera sees them as long, where its exposure was
    read longer than the fits' largest blur, nor where the ramp-reading camera's pulses were
    fitted at an exposure its solve does not confirm. A third camera that sees them as long
    under its own shorter exposure (its bands longer than one exposure) is no witness: it
    reads them as the short camera does (EC5's rig-1107: two cameras misread so outvoted the
    reference's ramps, their exposures 53 and 31 sigma off)."""
    exposure_ms, std_ms, n_flashes = _told()["short"]
    assert (round(exposure_ms, 3), n_flashes) == (0.84, 3) and 0 < std_ms < 0.01
    assert _told(short=dict(pulses=[0.84, 0.4, 1.3, 3.0])) == {}
    assert _told(third=dict(rows=30.0, pulses=[0.8, 0.8, 0.8, np.nan], solved=3.0)) == {}
    assert _told(third=dict(rows=5.0, pulses=[0.8, 0.8, 0.8, 3.0], solved=0.5))["short"][2] == 3
    assert _told(short=dict(rows=3.5, solved=0.35)) == {}
    assert _told(ramps=dict(rows=40.0)) == {}


def test_a_flash_that_one_camera_sees_as_long_is_shorter_where_more_see_it_so():
    """A flash the camera saw long is shorter by the others where more of them see it at
    most half as long than see it as long: one witness's misread pulse does not outvote
    the rest, and one against one keeps the camera's reading. Random rig 133 of TTL flashes
    at two powers: cam8 (6.61 ms, 50 fps) was read as 0.15 ms under 7.4 ms pulses; of its
    four flashes that four to six cameras saw at most 1 ms long, two had one camera each
    that saw them as long (cam10's ramps fitted 8.8 ms, cam12 itself read the other way
    round): not turned, its times 2.7 ms off at 3.7 sigma. Here a third camera sees the
    short camera's first flash as long (0.9 ms) as it did."""
    odd, again = dict(pulses=[0.9, 0.1, 0.08, np.nan]), dict(pulses=[0.06, 0.09, 0.07, np.nan])
    assert _told(odd=odd) == {}
    exposure_ms, _, n_flashes = _told(odd=odd, again=again)["short"]
    assert (round(exposure_ms, 3), n_flashes) == (0.84, 3)


def test_a_camera_read_too_long_to_turn_keeps_its_reading_with_the_other_in_its_sigma():
    """The same camera with its exposure read at 3.5 rows (0.35 ms), more than the fits'
    largest blur: the others' flashes tell 0.84 ms, but a reading that long is not turned on
    their ramps alone; the 0.49 ms between the two is its exposure's doubt, with a warning
    naming both. Read at 1.2 rows (turned), once turned, or where a span of its bands holds
    the frames of those flashes (10-30) at about 0.84 ms (auto exposure changed it there:
    each span holds its own), none; a span of 0.6 ms, or one that holds but two of them,
    does not explain them."""
    long_read = _pulse_rig(short=dict(rows=3.5, solved=0.35))
    assert _told(turnable=False) == {} and "short" in _told(turnable=False, short=dict(rows=3.5, solved=0.35))
    spreads, warnings = _unturned_exposures_ms(long_read, turned=set(), shown={})
    assert spreads == {"short": pytest.approx(0.49)}, spreads
    assert len(warnings) == 1 and warnings[0].startswith("short.mp4: its bands read as a 0.35 ms exposure"), warnings
    assert "may be 0.84 ms" in warnings[0] and "3.5 rows" in warnings[0]
    assert _unturned_exposures_ms(long_read, turned={"short"}, shown={}) == ({}, [])
    assert _unturned_exposures_ms(_pulse_rig(), turned=set(), shown={}) == ({}, [])
    held = _ShownExposure(0, 5, 0.35, 2, True, solved=True)
    for later_ms, last_frame, doubted in ((0.8, 40, False), (0.6, 40, True), (0.8, 25, True)):
        shown = {"short": [held, _ShownExposure(6, last_frame, later_ms, 4, True, solved=False)]}
        assert ("short" in _unturned_exposures_ms(long_read, turned=set(), shown=shown)[0]) == doubted, later_ms


def test_a_camera_too_few_flashes_tell_was_read_the_other_way_round_has_the_other_reading_in_its_sigma():
    """The short camera (1.2 rows, 0.12 ms) with two of the three flashes it read a pulse of
    seen shorter by the ramp-reading camera, 0.83-0.84 ms in its bands: too few to read it
    the other way round, so it keeps 0.12 ms and the 0.715 ms to the other reading is its
    exposure's doubt, with a warning (EC2's rig-1075 cam5, 0.89 ms held 0.19 ± 0.04 with no
    word); read too long to turn (3.5 rows, 0.35 ms), the 0.485 ms (EC5's rig-1107 cam2, 0.93 ms
    read as 0.16 ms over 3.1 rows, two of its three flashes seen shorter: its exposure 1.6
    sigma off where the doubt was the turnable camera's alone). Not where those are two of
    four, nor once turned."""
    few = dict(short=dict(pulses=[0.84, 0.83, 3.0, np.nan]), ramps=dict(pulses=[0.05, 0.1, np.nan, np.nan]))
    assert _told(**few) == {}
    spreads, warnings = _unturned_exposures_ms(_pulse_rig(**few), turned=set(), shown={})
    assert spreads == {"short": pytest.approx(0.715)}, spreads
    assert len(warnings) == 1 and warnings[0].startswith("short.mp4: its bands read as a 0.12 ms exposure"), warnings
    assert "2 of the 3 flashes" in warnings[0] and "too few flashes" in warnings[0]
    assert _unturned_exposures_ms(_pulse_rig(**few), turned={"short"}, shown={}) == ({}, [])
    two_of_four = dict(few, short=dict(pulses=[0.84, 0.83, 3.0, 2.9]))
    assert _unturned_exposures_ms(_pulse_rig(**two_of_four), turned=set(), shown={}) == ({}, [])
    read_long = dict(few, short=dict(pulses=[0.84, 0.83, 3.0, np.nan], rows=3.5, solved=0.35))
    assert _unturned_exposures_ms(_pulse_rig(**read_long), turned=set(), shown={})[0] == {"short": pytest.approx(0.485)}


def test_a_camera_whose_flashes_tell_exposures_that_disagree_has_the_other_reading_in_its_sigma():
    """EC6's rig-1117 cam8 (1.24 ms, then 2.01 from frame 122) was read as 0.43 ms under
    longer pulses; four of its five flashes the others saw at most 0.15 ms long, its pulses of
    them 1.06, 1.15, 1.83 and 1.83 ms: too far apart to read it as one exposure (auto exposure
    changed it between them), and it was held at 0.43 ± 0.04 ms, frame by frame at
    error/sigma 24.6, its times at 2.9, with no word of it. Here the short camera's four
    flashes, seen at most 0.1 ms long, read 0.83-1.7 ms: not turned, the 1.1 ms to the other
    reading (their median, 1.22 ms) in its sigma, with a warning naming them; read at 3.5 rows
    (0.35 ms: too long to turn, as cam8's 5.2 rows were), the 0.87 ms."""
    ramps = dict(pulses=[0.05, 0.1, 0.08, 0.09])
    for rows, solved_ms in ((1.2, 0.12), (3.5, 0.35)):
        disagree = dict(short=dict(pulses=[0.84, 0.83, 1.6, 1.7], rows=rows, solved=solved_ms), ramps=ramps)
        assert _told(**disagree) == {} and _told(turnable=False, **disagree) == {}
        spreads, warnings = _unturned_exposures_ms(_pulse_rig(**disagree), turned=set(), shown={})
        assert spreads == {"short": pytest.approx(1.22 - solved_ms)}, spreads
        assert len(warnings) == 1, warnings
        assert warnings[0].startswith(f"short.mp4: its bands read as a {solved_ms:.2f} ms exposure"), warnings
        assert "4 of the 4 flashes" in warnings[0] and "those pulses disagree (0.83-1.70 ms" in warnings[0]
        assert _unturned_exposures_ms(_pulse_rig(**disagree), turned={"short"}, shown={}) == ({}, [])


def test_a_band_whose_flash_the_others_see_shorter_than_the_exposure_puts_its_pulse_in_its_sigma():
    """A camera on auto exposure whose bands read as 0.3 ms (3 rows) under longer pulses, one
    of them 1.2 ms of a flash two ramp-reading cameras see 0.05-0.06 ms long (or two such
    bands, 1.2 and 1.3 ms, each of a flash one of them sees so): a flash shorter
    than the exposure makes a band one exposure long, so the camera's exposure was 1.2 ms
    there; one band is too few to read the camera the other way round, so the 0.9 ms between
    the two is its exposure's doubt, with a warning (random rig 914's cam5: 0.56 ms read,
    1.46 and 2.22 true, at error/sigma 42 frame by frame). Not on one witness (long
    exposures may take an LED's ramps for blur), nor where a third camera sees that flash
    as long, nor where the others see it longer than the camera's exposure (0.5 ms: the
    pulse is the flash's, read long), nor where the pulse is less than 1.5 times the
    exposure (0.4 ms: bands of a steady exposure come so long), nor for a camera told
    already (turned, or its changes found)."""
    auto = dict(rows=3.0, pulses=[1.2, 0.1, 0.2, 3.0], solved=0.3)
    again = dict(pulses=[0.06, 0.09, 0.07, np.nan])
    spreads, warnings = _exposures_bands_tell(_pulse_rig(auto=auto, again=again), told={"short"})
    assert spreads == {"auto": pytest.approx(0.9)}, spreads
    assert len(warnings) == 1 and warnings[0].startswith("auto.mp4: its bands read as a 0.30 ms exposure"), warnings
    assert "one of them (1.20 ms) is of a flash the other cameras saw shorter" in warnings[0]
    apart = dict(ramps=dict(pulses=[0.05, np.nan, 0.08, np.nan]), again=dict(pulses=[np.nan, 0.06, 0.07, np.nan]))
    spreads, warnings = _exposures_bands_tell(
        _pulse_rig(auto=dict(auto, pulses=[1.2, 1.3, 0.2, 3.0]), **apart), {"short"}
    )
    assert spreads == {"auto": pytest.approx(1.0)} and "2 of them (1.20, 1.30 ms) are of flashes" in warnings[0]
    as_long = dict(rows=3.0, solved=0.3, pulses=[1.1, 0.1, 0.1, np.nan])
    slow = dict(pulses=[0.5, 0.1, 0.08, np.nan])
    steady = dict(auto=dict(auto, pulses=[0.4, 0.1, 0.2, 3.0]), short=dict(pulses=[np.nan, 0.83, 0.85, 3.0]))
    for changes, told in [
        (dict(auto=auto), {"short"}),
        (dict(auto=auto, again=again, odd=as_long), {"short", "odd"}),
        (dict(auto=auto, ramps=slow, again=slow), {"short"}),
        (dict(steady, again=again), {"short"}),
        (dict(auto=auto, again=again), {"short", "auto"}),
    ]:
        assert _exposures_bands_tell(_pulse_rig(**changes), told=told) == ({}, []), changes


def test_a_cameras_reference_share_is_the_references_rows_and_rate_then():
    """Every camera's times against the truth carry the global clock's own errors, the
    reference's that all cameras share (:func:`~flashsync.pipeline._reference_shares_ms`):
    per frame of a camera, the reference's rows' (RMS over them) and its clock's rate's, in
    the frame it records when the camera reads its middle row; not the scatter of its kept
    stamps, white from frame to frame. Here a 25 fps reference of 200 rows whose time per row
    is 0.00005 ms sure, whose rate leaves 0.01 ms more per frame and whose stamps scatter
    1 ms; a 50 fps camera read 3 ms later."""
    frames = np.arange(100)
    reference = CameraClock("ref", frames * 40.0, 200, 320, row_time_ms=0.1, covariance=np.diag([0.0, 0.0, 5e-5**2]))
    reference.frame_std_ms = np.hypot(0.01 * frames, 1.0)
    camera = CameraClock("cam", np.arange(200) * 20.0 + 3.0, 100, 160, beta_ms=0.0, row_time_ms=0.05)
    (share,) = pipeline._reference_shares_ms(reference, 0.01 * frames, [camera])
    rows = np.linspace(0.0, 199.0, pipeline.SHARE_ROWS)
    held = np.minimum((np.arange(200) * 20.0 + 3.0 + 50 * 0.05) // 40.0, 99).astype(int)
    assert share.shape == (200,)
    assert share == pytest.approx(np.sqrt((0.01 * held) ** 2 + np.mean((5e-5 * rows) ** 2)))


def test_the_references_rate_spread_is_its_stamps_jitter_not_their_grid():
    """The reference's frame times carry what its stamps leave of its clock's rate, counted
    from its first frame (:func:`~flashsync.pipeline._rate_spread_ms`): white jitter gives
    the rate's standard error its full share, by 8 s of 59.94 fps stamps jittered 0.5 ms
    about 0.1 ms; a steady clock only rounded to a 1 ms grid, whose rounding leaves its rate
    seven times better than white noise of that RMS would, none."""
    ladder = 1234.5 + np.arange(480) * 1000.0 / 59.94
    jittered = fit_frame_clock(ladder + np.random.default_rng(0).normal(0.0, 0.5, len(ladder)))
    spread = pipeline._rate_spread_ms(jittered, jittered.times_ms)
    assert spread[0] == 0.0 and spread[-1] == pytest.approx(jittered.rate_std * np.ptp(ladder), rel=0.01)
    assert 0.05 < spread[-1] < 0.2
    rounded = fit_frame_clock(np.round(ladder))
    assert rounded.quantum_ms == 1.0 and rounded.rate_std > 1e-6
    assert pipeline._rate_spread_ms(rounded, rounded.times_ms)[-1] < 0.002


@pytest.mark.parametrize("split", [True, False])
def test_a_flash_matched_apart_is_named_and_solving_it_as_one_is_in_sigma(monkeypatch, split):
    """Four synthetic cameras, 12 flashes; the matching puts cam2's and cam3's edges of the
    first flash all four saw into a flash of their own (as AE7's rig-749 had one flash 5.0 ms
    apart: its cam2's time per row 44 % short at error/σ 16, at 1.1 with what solving them
    as one moves in its sigma). Two solved flashes closer than the matching tells apart that
    no camera saw both of are named on the cameras of the later one, and what solving them
    as one moves is in every camera's sigma; an unsplit rig names none."""
    events, truth, frame_times = synthetic_events(4, 12, seed=4)
    detections = synthetic_detections(events, truth, frame_times, seed=4)
    grouped = match.group_flashes

    def split_first_flash_all_saw(*args, **kwargs):
        flashes = grouped(*args, **kwargs)
        seen: dict[int, set[str]] = {}
        for (camera, _), flash in flashes.items():
            seen.setdefault(flash, set()).add(camera)
        every = sorted(flash for flash, cameras in seen.items() if len(cameras) == 4)
        moved = every[0] if every else None
        new = max(flashes.values(), default=0) + 1
        return {key: new if flash == moved and key[0] in ("cam2", "cam3") else flash for key, flash in flashes.items()}

    if split:
        monkeypatch.setattr(match, "group_flashes", split_first_flash_all_saw)
    model, report = synchronize(detections)
    named = [line.split(":")[0] for line in report.warnings if "one flash matched apart" in line]
    assert named == (["cam0.mp4", "cam1.mp4"] if split else []), report.warnings
    if split:
        assert all("from one that cam2, cam3 saw and it did not" in line for line in report.warnings if "apart" in line)
        monkeypatch.setattr(pipeline, "rival_scatter", lambda *args: [0.0] * 4)
        without, _ = synchronize(detections)
        for name in ("cam1", "cam2", "cam3"):
            assert model.cameras[name].covariance[1, 1] > without.cameras[name].covariance[1, 1]
