"""Timelines of the recording and the instants at which things are logged.

Two kinds of timeline:

``global_time``
    The reference camera's clock (``t_global_ms`` of :mod:`flashsync.model`), a Rerun
    *duration* timeline with nanosecond resolution: ``t_global_ms = 12.5`` is logged at
    12 500 000 ns and shown as ``+0.0125 s``. Values may be negative (a camera that
    started before the reference).
``frame_<camera>``
    A sequence timeline per camera: the 0-based decoded frame index. Only that camera's
    video, overlays and detections are on it.

A frame is logged at the global time at which its readout starts, the end of exposure of
its first readout row (row 0, or the bottom row of a flipped camera). Scrubbing
``global_time`` to an instant ``t`` thus shows, for every camera, the frame being read out
at ``t`` -- the frame :meth:`flashsync.model.CameraClock.locate` returns for ``t``.
"""

from __future__ import annotations

import numpy as np
import rerun as rr

from flashsync.model import CameraClock

GLOBAL_TIMELINE = "global_time"


def frame_timeline(camera: str) -> str:
    """Name of the frame-index timeline of ``camera``."""
    return f"frame_{camera}"


def global_time_column(t_global_ms: np.ndarray) -> rr.TimeColumn:
    """A ``global_time`` index column.

    Parameters
    ----------
    t_global_ms : float array of shape (n,)
        Instants on the reference clock, ms; rounded to whole nanoseconds.
    """
    nanos = np.round(np.asarray(t_global_ms, dtype=np.float64) * 1e6).astype(np.int64)
    return rr.TimeColumn(GLOBAL_TIMELINE, duration=nanos.astype("timedelta64[ns]"))


def readout_start_ms(camera: CameraClock, frames: np.ndarray) -> np.ndarray:
    """Global time (ms) at which the readout of ``frames`` starts (first readout row).

    Parameters
    ----------
    camera : CameraClock
    frames : int array of shape (n,)
        0-based frame indices.
    """
    frames = np.asarray(frames, dtype=np.int64)
    return camera.t_global_ms(frames, camera.readout_row(np.zeros(frames.shape)))


def frame_columns(camera: CameraClock, frames: np.ndarray) -> list[rr.TimeColumn]:
    """Index columns placing each of ``frames`` at its readout start and its frame index."""
    frames = np.asarray(frames, dtype=np.int64)
    return [
        global_time_column(readout_start_ms(camera, frames)),
        rr.TimeColumn(frame_timeline(camera.name), sequence=frames),
    ]


def frame_batches(camera: CameraClock, frames: np.ndarray) -> tuple[list[rr.TimeColumn], np.ndarray, np.ndarray]:
    """Group per-instance data into one batch per frame, shown on that frame only.

    Each frame that holds instances gets one row holding all of them; the next frame,
    if it holds none, gets an empty row, so the overlay disappears when the video moves
    on.

    Parameters
    ----------
    camera : CameraClock
    frames : int array of shape (n,)
        Frame index of each instance, ``0 <= frame < camera.n_frames``.

    Returns
    -------
    indexes : list of TimeColumn
        ``global_time`` and ``frame_<camera>`` of each row (see :func:`frame_columns`).
    order : int array of shape (n,)
        Permutation that sorts the instances into row order.
    lengths : int array of shape (n_rows,)
        Instances per row (0 for a clearing row); pass to ``ComponentColumnList.partition``.
    """
    frames = np.asarray(frames, dtype=np.int64)
    order = np.argsort(frames, kind="stable")
    held, counts = np.unique(frames, return_counts=True)
    following = np.setdiff1d(held + 1, held)
    following = following[following < camera.n_frames]
    rows = np.concatenate([held, following])
    lengths = np.concatenate([counts, np.zeros(len(following), dtype=np.int64)])
    by_frame = np.argsort(rows, kind="stable")
    return frame_columns(camera, rows[by_frame]), order, lengths[by_frame]
