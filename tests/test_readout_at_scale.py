"""The readout search at scale: on a rig of many cameras with many flashes each, a single
flip that cannot pay is not solved whole and the flips that must pay are tried together
(each estimated with the other cameras' flashes held, :func:`flashsync.pipeline._flip_gains`),
and the cameras mounted upside down are still found. Synthetic band edges
(:mod:`flashsync.simulation.band_events`), no video."""

from __future__ import annotations

import numpy as np
import pytest

import flashsync.pipeline as pipeline
from flashsync.simulation.band_events import synthetic_detections, synthetic_events

#: 12 cameras x 60 flashes, cam3 and cam7 mounted upside down.
UPSIDE_DOWN = {3, 7}


@pytest.fixture(scope="module")
def rig():
    events, truth, frame_times = synthetic_events(12, 60, seed=1)
    return synthetic_detections(events, truth, frame_times, upside_down=UPSIDE_DOWN)


def test_upside_down_cameras_are_found_with_few_whole_solves(rig, monkeypatch):
    whole = []
    attempt = pipeline._attempt
    monkeypatch.setattr(pipeline, "_attempt", lambda *args, **kwargs: whole.append(1) or attempt(*args, **kwargs))
    model, report = pipeline.synchronize(rig)
    assert sorted(report.flipped_found) == sorted(f"cam{c}" for c in UPSIDE_DOWN)
    assert all(model.cameras[f"cam{c}"].flipped == (c in UPSIDE_DOWN) for c in range(12))
    # the detected readings on two references, both flips together, the final solve on the
    # reference given, its check of the flips, the solve with its cameras of one size and
    # rate sharing one readout, and the mirror of the reading the ascent ends at (every
    # undecided camera flipped at once): 7 (when one flip at a time took 7 without the
    # mirror and the shared readout, every single flip solved whole 39)
    assert len(whole) <= 7, len(whole)


def test_a_wrong_flip_is_estimated_to_lose_and_a_right_one_to_gain(rig):
    cameras = {d.camera: d for d in rig}
    best = pipeline._attempt(cameras, "cam0", None, ())
    gains = pipeline._flip_gains(best, list(cameras))
    right = [gains[f"cam{c}"] for c in UPSIDE_DOWN]
    wrong = [gains[name] for name in cameras if int(name[3:]) not in UPSIDE_DOWN]
    # each camera has about 96 edges: from the detected readings a wrong flip loses 238-350
    # (about 3 an edge: its edges fit nothing), a right one gains 238-303
    assert min(right) > pipeline.DECIDED_LOG_LIKELIHOOD, right
    assert max(wrong) < -pipeline.FLIP_SCREEN_SLACK, wrong
    assert np.all(np.isfinite(right + wrong))
