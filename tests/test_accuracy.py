"""Synchronisation accuracy against simulation ground truth, over every frame and row,
on the two scenarios of the matching-and-solving issue (scaled down to small frames and
a shorter recording so that they render in seconds), the mixed one in three draws of its
flashes and scene. Never measured on the fitted events."""

import dataclasses

import numpy as np
import pytest

from flashsync import detect_videos, synchronize
from flashsync.evaluate import camera_accuracy, sync_errors
from flashsync.events import Edge, Flag
from flashsync.io import load_ground_truth
from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario


def irregular_flashes(rng, n, start_ms, stop_ms, min_gap_ms):
    instants = np.sort(rng.uniform(start_ms, stop_ms - n * min_gap_ms, n)) + np.arange(n) * min_gap_ms
    return tuple(FlashSpec(float(t), float(rng.uniform(0.35, 0.7))) for t in instants)


def paper_like():
    """Four cameras at 25 fps (two larger, two smaller), 1 ms stamps on two, drifts of
    -10..+10 ppm, shifts of tens of seconds, 0.3 % dropped frames, flashes every few
    seconds, H.264, mild mains flicker."""
    rng = np.random.default_rng(2017)
    common = dict(fps=25.0, noise_std=1.5, drop_fraction=0.003, crf=23)
    cameras = (
        CameraSpec("p1", 384, 216, r0=10, r1=8, exposure_ms=10.0, **common),
        CameraSpec(
            "p2",
            384,
            216,
            r0=12,
            r1=6,
            exposure_ms=12.0,
            start_ms=24306.0,
            offset_ms=-23456.0,
            drift_ppm=-10.0,
            container="mkv",
            position_m=(-7.0, 15.0, 14.0),
            look_at_m=(18.0, 15.0),
            hfov_deg=75.0,
            **common,
        ),
        CameraSpec(
            "p3",
            320,
            180,
            r0=8,
            r1=6,
            exposure_ms=8.0,
            start_ms=39800.5,
            offset_ms=-41000.5,
            drift_ppm=7.0,
            quantize_ms=1.0,
            position_m=(66.0, 33.0, 16.0),
            look_at_m=(44.0, 16.0),
            hfov_deg=75.0,
            **common,
        ),
        CameraSpec(
            "p4",
            320,
            180,
            r0=6,
            r1=8,
            exposure_ms=16.0,
            start_ms=12400.0,
            offset_ms=-12000.0,
            drift_ppm=4.0,
            position_m=(30.0, 42.0, 17.0),
            look_at_m=(30.0, 18.0),
            hfov_deg=70.0,
            **common,
        ),
    )
    return Scenario(
        "paper-like",
        cameras,
        duration_ms=20_000.0,
        flashes=irregular_flashes(rng, 7, 800.0, 19_200.0, 1500.0),
        n_players=6,
        flicker_depth=0.02,
        seed=17,
    )


def mixed():
    """Three cameras at 25, 30 and 50 fps, 90 kHz and 1 ms stamps, one upside down, drifts
    up to 40 ppm, each flash missed by a camera with probability 15 %."""
    rng = np.random.default_rng(5)
    cameras = (
        CameraSpec("m1", 320, 180, 25.0, r0=8, r1=6, exposure_ms=10.0, noise_std=1.5),
        CameraSpec(
            "m2",
            320,
            180,
            30.0,
            r0=6,
            r1=10,
            exposure_ms=8.0,
            start_ms=61000.0,
            offset_ms=-60700.0,
            drift_ppm=40.0,
            container="mkv",
            flipped=True,
            miss_probability=0.15,
            noise_std=1.5,
            position_m=(-7.0, 15.0, 14.0),
            look_at_m=(18.0, 15.0),
            hfov_deg=75.0,
        ),
        CameraSpec(
            "m3",
            256,
            144,
            50.0,
            r0=6,
            r1=4,
            exposure_ms=6.0,
            start_ms=5000.0,
            offset_ms=-5210.0,
            drift_ppm=-25.0,
            quantize_ms=1.0,
            miss_probability=0.15,
            noise_std=1.5,
            position_m=(66.0, 33.0, 16.0),
            look_at_m=(44.0, 16.0),
            hfov_deg=75.0,
        ),
    )
    return Scenario(
        "mixed",
        cameras,
        duration_ms=15_000.0,
        flashes=irregular_flashes(rng, 10, 800.0, 14_200.0, 900.0),
        n_players=6,
        seed=9,
    )


def mixed_reshuffled(seed):
    """The mixed scenario with other flash instants and scene. In seed 3 a wrong readout
    direction lets one more event in under a ten times looser fit, which a search counting
    inliers took (a 9 ms sync error)."""
    scenario = mixed()
    flashes = irregular_flashes(
        np.random.default_rng(1000 + seed), len(scenario.flashes), 800.0, scenario.duration_ms - 800.0, 900.0
    )
    return dataclasses.replace(scenario, name=f"mixed-{seed}", flashes=flashes, seed=50 + seed)


@pytest.fixture(
    scope="module",
    params=[paper_like, mixed, lambda: mixed_reshuffled(1), lambda: mixed_reshuffled(3)],
    ids=["paper-like", "mixed", "mixed-1", "mixed-3"],
)
def solved(request, tmp_path_factory):
    scenario = request.param()
    folder = tmp_path_factory.mktemp(scenario.name)
    truth = render_scenario(scenario, folder)
    videos = sorted(p for p in folder.iterdir() if p.suffix in (".mp4", ".mkv"))
    model, report = synchronize(detect_videos(videos, estimate_readout=True))
    return scenario, truth, model, report, load_ground_truth(folder / "truth.json")


def test_sub_tenth_of_a_millisecond_with_no_manual_input(solved):
    scenario, _, model, report, truth = solved
    assert list(model.cameras) == [c.name for c in scenario.cameras]
    errors = sync_errors(model, truth, row_step=1)
    assert np.sqrt(np.mean(errors["rms_ms"] ** 2)) <= 0.1, errors
    assert errors["max_ms"].max() <= 0.3, errors


def test_upside_down_camera_is_found(solved):
    scenario, _, model, report, _ = solved
    expected = sorted(c.name for c in scenario.cameras if c.flipped)
    assert sorted(report.flipped_found) == expected
    assert [name for name, clock in model.cameras.items() if clock.flipped] == expected


def test_predicted_uncertainty_is_honest(solved):
    """The calibration of issue #11 on every camera, the reference included: error/sigma
    RMS at most 2 and 90 % of the probes within 2 sigma, against the truth (each camera's
    sigma holds the reference's) and against every other camera (measured 2026-12-03: RMS
    0.16-0.76 against the truth, 0.13-0.57 pairwise)."""
    _, _, model, _, truth = solved
    accuracy = camera_accuracy(model, truth).set_index("camera")
    others = accuracy[~accuracy["reference"]]
    assert (others["z_rms"] <= 2).all() and (others["within_2sigma"] >= 0.9).all(), others
    assert (accuracy["pair_z_rms"] <= 2).all() and (accuracy["pair_within_2sigma"] >= 0.9).all(), accuracy


def test_exposure_and_stamp_grid_are_found(solved):
    scenario, _, model, report, _ = solved
    for spec in scenario.cameras:
        assert model.cameras[spec.name].exposure_ms == pytest.approx(spec.exposure_ms, abs=0.2)
        if spec.container == "mkv" or spec.quantize_ms:
            assert report.frame_clocks[spec.name].quantum_ms == 1.0


def twins_with_flashes_in_the_blanking() -> tuple[Scenario, list[int]]:
    """Two identical 25 fps cameras 17 ms apart (320x180 plus 20 hidden rows: 0.2 ms a row,
    4 ms exposures = 20 rows), ten flashes about 0.6 s apart, five of them 1.2-2.8 ms before
    one of ``late``'s frames starts its visible rows: ``late`` sees their bands at the top of
    a frame, their leading edges hidden (the flash fell in its vertical blanking), their
    trailing edges 6-14 rows down; ``early`` sees them whole. Equal rates are the hard case
    (DESIGN.md): the flashes where one camera's band wraps into the next frame are what tie
    the time per row to the frame period. Returns the scenario and the indices of those
    five flashes."""
    rng = np.random.default_rng(11)
    period, first_row = 40.0, 17.0 + 8 * 0.2  # late's row 0 ends its exposure at 18.6 + 40 f ms
    frames = 15 * np.arange(1, 11) + rng.integers(0, 3, 10)
    in_blanking = [1, 3, 4, 6, 8]
    ahead = np.where(np.isin(np.arange(10), in_blanking), rng.uniform(1.2, 2.8, 10), rng.uniform(-30.0, -6.0, 10))
    flashes = tuple(
        FlashSpec(round(float(first_row + period * f - a), 3), float(rng.uniform(0.4, 0.7)))
        for f, a in zip(frames, ahead)
    )
    common = dict(fps=25.0, r0=8, r1=12, exposure_ms=4.0, noise_std=1.0, crf=23)
    cameras = (
        CameraSpec("early", 320, 180, **common),
        CameraSpec("late", 320, 180, start_ms=500.0, offset_ms=17.0 - 500.0, **common),
    )
    scenario = Scenario("twins-in-blanking", cameras, duration_ms=7000.0, flashes=flashes, n_players=0, seed=11)
    return scenario, in_blanking


@pytest.fixture(scope="module")
def twins(tmp_path_factory):
    scenario, in_blanking = twins_with_flashes_in_the_blanking()
    folder = tmp_path_factory.mktemp(scenario.name)
    truth = render_scenario(scenario, folder)
    return scenario, in_blanking, truth, detect_videos([folder / "early.mp4", folder / "late.mp4"])


def test_a_flash_in_a_cameras_vertical_blanking_ties_it_by_its_trailing_edge(twins):
    """The five flashes that fell in ``late``'s blanking are matched by the trailing edges of
    its bands (one exposure after the flash) and tie the twins to a few hundredths of a ms.
    Leading edges alone matched 4 of the 10 flashes, and the twins were 1.1 and 1.9 ms RMS
    off with a time per row 5 % off. At one frame rate the times per row rest on one flash:
    left out, they rest on the prior, so the jackknife does not count that solve
    (``jackknife.PRIOR_BOUND_SHARE``; it had moved both 5.6 % under the nominal prior and put
    sigma at 1.09 and 1.88 ms RMS for errors of 0.009 and 0.046 ms, with a warning on each
    exposure), and sigma is the edges' own: 0.061 and 0.082 ms, error/sigma 0.45, the time
    per row 0.37 % off at 1.3 sigma. A warning per camera still says the flashes do not pin
    its time per row down (0.10 ms over its rows)."""
    scenario, in_blanking, truth, detections = twins
    late = detections[1].events
    lone = late.has_flag(Flag.LEADING_HIDDEN) & (late.edge == Edge.TRAILING)
    assert len(np.unique(late.frame[lone])) == len(in_blanking)  # the scenario's premise
    model, report = synchronize(detections)
    matched = model.events[model.events["camera"] == "late"]
    assert set(zip(late.event[lone], late.frame[lone])) <= set(zip(matched["event"], matched["frame"]))
    assert model.events["flash"].nunique() == len(scenario.flashes) and matched["inlier"].all()
    accuracy = camera_accuracy(model, truth).set_index("camera")
    assert accuracy.rms_ms.max() < 0.1 and accuracy.reference_rms_ms["late"] < 0.1, accuracy
    assert accuracy.pair_z_rms.max() < 2.0, accuracy
    assert accuracy.sigma_rms_ms.max() < 0.2, accuracy
    warned = [w.split(": ")[1][:16] for w in report.warnings]
    assert warned == ["its time per row"] * 2, report.warnings


def test_a_camera_tied_by_trailing_edges_alone_is_left_out(twins):
    """``late`` with only its bands cut at the top (their trailing edges) beside two copies of
    ``early``: its shift and exposure are one unknown, so it is left out, with a warning;
    the others are solved (taken in, it made the solve singular: no model at all)."""
    _, _, _, (early, late) = twins
    cut_bands = late.events.take(late.events.has_flag(Flag.LEADING_HIDDEN))
    cut = dataclasses.replace(late, top_down=cut_bands, bottom_up=None)
    model, report = synchronize([early, dataclasses.replace(early, camera="copy"), cut])
    assert list(model.cameras) == ["early", "copy"]
    assert any(w.startswith(f"{late.video}: shares too few flashes") for w in report.warnings), report.warnings
