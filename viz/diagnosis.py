"""The discrepancy workflow in Rerun: every edge's residual under each model it tried."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr

from flashsync.atomic import atomic_output
from flashsync.diagnose import Diagnosis
from viz.palette import camera_colors


def save_diagnosis(path: str | Path, diagnosis: Diagnosis) -> None:
    """Write the recording of :func:`log_diagnosis` to an ``.rrd`` file, atomically."""
    with atomic_output(path) as temporary:
        recording = rr.RecordingStream("flashsync-diagnose")
        recording.save(temporary)
        log_diagnosis(diagnosis, recording)
        recording.flush()
        recording.disconnect()


def log_diagnosis(diagnosis: Diagnosis, recording: rr.RecordingStream | None = None) -> rr.RecordingStream:
    """Log each model's edge residuals (ms) on a ``flash`` sequence timeline.

    Entity ``diagnose/<k>_<effect>/<camera>/<edge>`` holds the residuals after step ``k``
    (``0_plain`` is the plain model, ``<k>_sync_shape`` the final one in ``sync``'s shape),
    one scalar per edge at its flash number, in the camera's colour, so the gap closing step
    by step is seen side by side.
    """
    recording = recording if recording is not None else rr.RecordingStream("flashsync-diagnose")
    data = diagnosis.edge_residuals
    cameras = np.asarray(data["camera"])
    flash = np.asarray(data["flash"], dtype=np.int64)
    trailing = np.asarray(data["trailing"], dtype=bool)
    colors = camera_colors(diagnosis.cameras)
    titles = ["plain"] + [
        ("out_" if step.removed else "") + step.effect + "_" + step.camera for step in diagnosis.steps
    ]
    titles += ["sync_shape"] * diagnosis.sync_shape
    for k, (title, residual) in enumerate(zip(titles, data["residual_ms"])):
        residual = np.asarray(residual, dtype=np.float64)
        for name in diagnosis.cameras:
            for edge, kind in ((False, "leading"), (True, "trailing")):
                mine = (cameras == name) & (trailing == edge)
                if not mine.any():
                    continue
                path = f"diagnose/{k}_{title}/{name}/{kind}"
                recording.send_columns(
                    path,
                    indexes=[rr.TimeColumn("flash", sequence=flash[mine])],
                    columns=rr.Scalars.columns(scalars=residual[mine]),
                )
                recording.log(path, rr.SeriesPoints(colors=[colors[name]], markers="circle"), static=True)
    return recording
