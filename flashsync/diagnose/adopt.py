"""The model ``flashsync diagnose -o`` writes: ``sync``'s solve with what the workflow found.

The workflow fits its own model to the clean bands it pairs (:mod:`flashsync.diagnose.measure`:
whole bands away from the image's edges); ``sync`` solves on every edge, with its weights,
priors and outlier rejection. Of the catalogue, ``sync``'s solve already holds every
camera's time per row, exposure and drift (its shape), a drift-rate change where the
flashes support one, and the rolling mains flicker as a prior on the time per row; its frame
clock always counts dropped frames and fits a least-squares line (the ``dropped_frames`` and
``frame_clock`` effects). What it chooses rather than fits is each camera's readout
direction and, where the stamps change rate, its frame times (the stamps' own rates or one
rate throughout); what it has no term for is how far saturation and a flash's pulse shape
move a band's edges off its flash (it times a band by its midpoint, which edges moved out
alike leave in place, but not edges moved out by different amounts). So the model written
is :func:`~flashsync.pipeline.synchronize` on the detections read the way up the workflow
found, on each camera where it named a stamp rate change timed as it found (one rate
throughout, with that clock's frame uncertainty), and on each camera where it named
saturation or the pulse shape with the edges it measured moved back by what the effect
moves them (:meth:`~flashsync.diagnose.candidate.Candidate.edge_shift_ms`). On 17 renders
of the hidden-saturation pair where the final model holds saturation, 12 of them with
hidden rows, that put the model a mean 0.049 ms RMS off the truth on those 12 where
``sync``'s own was 0.056 and the workflow's own model, written until 2026-12-02, 0.071
(README, "Saturation and pulse shape in sync's solve").
A camera whose readout the workflow did not name (``flipped``) is read as ``sync`` read it:
that the workflow found no evidence to turn it is no evidence against ``sync``'s (random
rig 428: on four flashes the workflow left cam4 as told, top-down, where ``sync`` had read
it bottom-up, as it is; written so, it was 9.3 ms off).
Edges of a camera read otherwise than the workflow measured it are not moved. Where the
final model holds a reading the detection lacks, or ``sync`` cannot solve the detections
so, the workflow's own model is written instead
(:meth:`~flashsync.diagnose.candidate.Candidate.sync_model`), and the description says why.

On the second world's 40 random rigs the workflow's own model was a median 0.088 ms off the
truth, ``sync``'s 0.047 (README, "One solver for ``sync`` and ``diagnose -o``"). The frame
times of a camera whose dropped frames the workflow named but not its frame clock are the
median step's line, a default rather than a finding: taken into ``sync``'s solve, they put
rig-38 0.025 -> 0.034 ms off.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from flashsync.detect import CameraDetection
from flashsync.diagnose.candidate import Candidate, Term
from flashsync.diagnose.effects import CATALOGUE, FLIPPED, PULSE_SHAPE, SATURATION, STAMP_RATE
from flashsync.diagnose.measure import Edges
from flashsync.errors import FlashsyncError
from flashsync.events import Edge
from flashsync.model import SyncModel
from flashsync.pipeline import SyncReport, synchronize

#: Effects that move band edges off their flash, each edge by its own amount: ``-o`` moves
#: the edges back before ``sync`` solves.
EDGE_EFFECTS = (SATURATION, PULSE_SHAPE)


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
    shift_ms = found.edge_shift_ms(EDGE_EFFECTS)
    moved = {}  # camera name -> (its index, the titles of the effects that move its edges)
    for term in sorted(found.terms):
        if term.effect in EDGE_EFFECTS and flipped[names[term.camera]] == measurement.cameras[term.camera].flipped:
            moved.setdefault(names[term.camera], (term.camera, []))[1].append(CATALOGUE[term.effect].title)
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
        if detection.camera in moved:
            c = moved[detection.camera][0]
            detection = _moved_back(detection, measurement.edges, shift_ms, c, found.row_time_ms(c))
        chosen.append(detection.retimed(timed[detection.camera][0]) if detection.camera in timed else detection)
    words = "sync's solve on the readouts found" + (
        f" and the one-rate frame times found on {', '.join(timed)}" if timed else ""
    )
    if moved:
        words += ", band edges moved back by the " + ", ".join(
            f"{' and '.join(titles)} on {name}" for name, (_, titles) in moved.items()
        )
    if synced is not None and not moved and _same_choices(synced[0], flipped, timed):
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


def _moved_back(
    detection: CameraDetection, edges: Edges, shift_ms: np.ndarray, camera: int, row_time_ms: float
) -> CameraDetection:
    """``detection``, read as the workflow measured it as its camera ``camera``, with each of
    that camera's ``edges`` ``shift_ms`` earlier (ms, shape (len(edges),)) at ``row_time_ms``
    per readout row."""
    events = detection.events
    index = {(int(event), kind): i for i, (event, kind) in enumerate(zip(events.event, events.edge))}
    mine = np.flatnonzero(edges.camera == camera)
    at = [index[(int(edges.event[i]), Edge.TRAILING if edges.trailing[i] else Edge.LEADING)] for i in mine]
    rows = events.row.copy()
    rows[at] -= shift_ms[mine] / row_time_ms * (-1.0 if detection.flipped else 1.0)
    events = replace(events, row=rows)
    return replace(detection, bottom_up=events) if detection.flipped else replace(detection, top_down=events)
