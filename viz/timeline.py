"""Timelines of the recording and the instants at which things are logged.

Two kinds of timeline:

``global_time``
    The reference camera's clock (``t_global_ms`` of :mod:`flashsync.model`) shifted so
    that 0 is the start of the recordings: the readout start of the earliest first frame of
    any camera (:class:`Timeline`). A Rerun *duration* timeline with nanosecond
    resolution: ``t_global_ms = origin_ms + 12.5`` is logged at 12 500 000 ns and shown as
    ``+0.0125 s``. The recording's description states the origin.
``frame_<camera>``
    A sequence timeline per camera: the 0-based decoded frame index. Only that camera's
    video, overlays and detections are on it.

A frame is logged at the global time at which its readout starts, the end of exposure of
its first readout row (row 0, or the bottom row of a flipped camera). Scrubbing
``global_time`` to an instant ``t`` thus shows, for every camera, the frame being read out
at ``t`` -- the frame :meth:`flashsync.model.CameraClock.locate` returns for ``t``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import rerun as rr

from flashsync.model import CameraClock, SyncModel

GLOBAL_TIMELINE = "global_time"


def frame_timeline(camera: str) -> str:
    """Name of the frame-index timeline of ``camera``."""
    return f"frame_{camera}"


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


def readout_end_ms(camera: CameraClock, frames: np.ndarray) -> np.ndarray:
    """Global time (ms) at which the readout of ``frames`` ends (last readout row)."""
    frames = np.asarray(frames, dtype=np.int64)
    return camera.t_global_ms(frames, camera.readout_row(np.full(frames.shape, camera.height - 1)))


@dataclass(frozen=True)
class Timeline:
    """``global_time`` of a recording: the global clock with 0 at the start of the recordings.

    Attributes
    ----------
    origin_ms : float
        ``t_global_ms`` of ``global_time = 0``: the readout start of the earliest first
        frame of any camera, ms.
    duration_ms : float
        ``global_time`` of the end of the readout of the last frame of any camera, ms.
    first_camera : str
        The camera whose first frame is the origin.
    """

    origin_ms: float
    duration_ms: float
    first_camera: str

    @classmethod
    def of(cls, model: SyncModel) -> Timeline:
        """The timeline of ``model``'s cameras (each with at least one frame)."""
        starts = {name: float(readout_start_ms(camera, [0])[0]) for name, camera in model.cameras.items()}
        ends = [float(readout_end_ms(camera, [camera.n_frames - 1])[0]) for camera in model.cameras.values()]
        first = min(starts, key=starts.get)
        return cls(origin_ms=starts[first], duration_ms=max(ends) - starts[first], first_camera=first)

    def column(self, t_global_ms: np.ndarray) -> rr.TimeColumn:
        """A ``global_time`` index column.

        Parameters
        ----------
        t_global_ms : float array of shape (n,)
            Instants on the global clock, ms; logged at ``t_global_ms - origin_ms``,
            rounded to whole nanoseconds.
        """
        shifted_ns = (np.asarray(t_global_ms, dtype=np.float64) - self.origin_ms) * 1e6
        return rr.TimeColumn(GLOBAL_TIMELINE, duration=np.round(shifted_ns).astype(np.int64).astype("timedelta64[ns]"))

    def round_up(self, t_global_ms: np.ndarray, step_ms: float) -> np.ndarray:
        """Instants moved on to the next ``global_time`` multiple of ``step_ms`` (the viewer
        shows fewer digits of rounder times), as ``t_global_ms``."""
        shifted = np.asarray(t_global_ms, dtype=np.float64) - self.origin_ms
        return self.origin_ms + step_ms * np.ceil(np.round(shifted / step_ms, 9))

    def frame_columns(self, camera: CameraClock, frames: np.ndarray) -> list[rr.TimeColumn]:
        """Index columns placing each of ``frames`` at its readout start and its frame index."""
        frames = np.asarray(frames, dtype=np.int64)
        return [
            self.column(readout_start_ms(camera, frames)),
            rr.TimeColumn(frame_timeline(camera.name), sequence=frames),
        ]

    def frame_batches(
        self, camera: CameraClock, frames: np.ndarray
    ) -> tuple[list[rr.TimeColumn], np.ndarray, np.ndarray]:
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
            ``global_time`` and ``frame_<camera>`` of each row (see :meth:`frame_columns`).
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
        return self.frame_columns(camera, rows[by_frame]), order, lengths[by_frame]

    def description(self, model: SyncModel) -> str:
        """What ``global_time`` means, in words (the recording's description)."""
        return (
            f"global_time 0 is the start of the recordings: the first frame of "
            f"{self.first_camera} (the earliest camera). t_global_ms (end of exposure of "
            f"a row on the clock of {model.reference}, the reference camera, as in sync.json "
            f"and the restamped detections) = global_time + {self.origin_ms:.3f} ms."
        )
