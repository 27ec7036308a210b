"""The model ``flashsync diagnose -o`` writes: ``sync``'s solve with what the workflow found.

The workflow fits its own model to the clean bands it pairs (:mod:`flashsync.diagnose.measure`:
whole bands away from the image's edges); ``sync`` solves on every edge, with its weights,
priors and outlier rejection. Of the catalogue, ``sync``'s solve already holds every
camera's time per row, exposure and drift (its shape), a drift-rate change where the
flashes support one, and the rolling mains flicker as a prior on the time per row; its frame
clock always counts dropped frames and fits a least-squares line (the ``dropped_frames`` and
``frame_clock`` effects). What it chooses rather than fits is each camera's readout
direction and, where the stamps change rate, its frame times (the stamps' own rates or one
rate throughout). So the model written is :func:`~flashsync.pipeline.synchronize` on the
detections read the way up the workflow found and, on each camera where it named a stamp
rate change, timed as it found (one rate throughout, with that clock's frame uncertainty).
A camera whose readout the workflow did not name (``flipped``) is read as ``sync`` read it:
that the workflow found no evidence to turn it is no evidence against ``sync``'s (random
rig 428: on four flashes the workflow left cam4 as told, top-down, where ``sync`` had read
it bottom-up, as it is; written so, it was 9.3 ms off).
Where the final model holds an effect ``sync``'s solve has no term for (saturation, pulse
shape), or a reading the detection lacks, or ``sync`` cannot solve the detections so, the
workflow's own model is written instead
(:meth:`~flashsync.diagnose.candidate.Candidate.sync_model`), and the description says why.

On the second world's 40 random rigs the workflow's own model was a median 0.088 ms off the
truth, ``sync``'s 0.047 (README, "One solver for ``sync`` and ``diagnose -o``"). The frame
times of a camera whose dropped frames the workflow named but not its frame clock are the
median step's line, a default rather than a finding: taken into ``sync``'s solve, they put
rig-38 0.025 -> 0.034 ms off.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flashsync.detect import CameraDetection
from flashsync.diagnose.candidate import Candidate, Term
from flashsync.diagnose.effects import CATALOGUE, FLIPPED, PULSE_SHAPE, SATURATION, STAMP_RATE
from flashsync.errors import FlashsyncError
from flashsync.model import SyncModel
from flashsync.pipeline import SyncReport, synchronize

#: Effects ``sync``'s solve has no term for: a final model holding one is written as the workflow's.
NOT_IN_SYNC = (SATURATION, PULSE_SHAPE)


def written_model(
    detections: Sequence[CameraDetection],
    reference: str | None,
    found: Candidate,
    synced: tuple[SyncModel, SyncReport] | None,
) -> tuple[SyncModel, str]:
    """The model ``diagnose -o`` writes for the workflow's final model ``found`` and one line
    on what it is; ``synced`` is ``sync``'s own solve of ``detections`` (reused where the
    workflow's choices are ``sync``'s)."""
    measurement = found.measurement
    names = [camera.camera for camera in measurement.cameras]
    outside = sorted(
        {f"{CATALOGUE[t.effect].title} on {names[t.camera]}" for t in found.terms if t.effect in NOT_IN_SYNC}
    )
    if outside:
        return found.sync_model(), f"the workflow's own model: sync's solve has no term for {', '.join(outside)}"
    timed = {
        names[c]: (found.timing[c].times_ms, found.clocks[c].std_ms)
        for c in range(len(names))
        if Term(STAMP_RATE, c) in found.terms
    }
    flipped = {
        name: found.flipped[c]
        if synced is None or Term(FLIPPED, c) in found.terms or name not in synced[0].cameras
        else synced[0].cameras[name].flipped
        for c, name in enumerate(names)
    }
    chosen = []
    for detection in detections:
        if detection.camera not in flipped:
            chosen.append(detection)
            continue
        reading = detection.bottom_up if flipped[detection.camera] else detection.top_down
        if reading is None:
            way = "bottom-up" if flipped[detection.camera] else "top-down"
            return found.sync_model(), (
                f"the workflow's own model: it reads {detection.camera} {way}, a way its video was not read "
                "(sync cannot solve it so)"
            )
        detection = detection.read_only(flipped[detection.camera])
        chosen.append(detection.retimed(timed[detection.camera][0]) if detection.camera in timed else detection)
    words = "sync's solve on the readouts found" + (
        f" and the one-rate frame times found on {', '.join(timed)}" if timed else ""
    )
    if synced is not None and _same_choices(synced[0], flipped, timed):
        return synced[0], words + " (the same as sync's own)"
    try:
        model, _ = synchronize(chosen, reference)
    except FlashsyncError as error:
        return (
            found.sync_model(),
            f"the workflow's own model: sync cannot solve the detections with its choices ({error})",
        )
    for name, (_, std_ms) in timed.items():
        if name in model.cameras:
            model.cameras[name].frame_std_ms = std_ms
    return model, words


def _same_choices(model: SyncModel, flipped: dict[str, bool], timed: dict[str, tuple]) -> bool:
    """``sync``'s ``model`` reads every camera it solved the way up ``flipped`` says and times
    the cameras ``timed`` by those frame times."""
    return all(
        camera.flipped == flipped.get(name, camera.flipped)
        and (name not in timed or np.allclose(camera.frame_times_ms, timed[name][0], rtol=0, atol=1e-9))
        for name, camera in model.cameras.items()
    )
