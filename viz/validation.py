"""Validation of the synchronisation on objects seen by two cameras.

A validation triple is camera B's observation of an object at B's global time, and
camera A's position of the object interpolated to that instant. In the plane (see
:mod:`viz.trajectories`), under ``plane/validation/<A>_vs_<B>/<object>``, the
interpolated point is drawn in A's colour (``interpolated``) with an error arrow from
B's position to it (``error``); the error (m) is a time series under
``validation/<A>_vs_<B>/<object>``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import rerun as rr

from flashsync.model import SyncModel
from viz.palette import ERROR_COLOR, camera_colors
from viz.series import log_series
from viz.timeline import global_time_column
from viz.trajectories import PLANE, entity_part

ROOT = "validation"


def pair_name(camera_a: str, camera_b: str) -> str:
    """Entity path part naming a validated camera pair."""
    return entity_part(f"{camera_a}_vs_{camera_b}")


def log_validation(recording: rr.RecordingStream, model: SyncModel, validation: pd.DataFrame) -> None:
    """Log validation triples: interpolated points, error arrows and error series.

    Parameters
    ----------
    recording : RecordingStream
    model : SyncModel
    validation : DataFrame
        ``camera_a, camera_b, object, t_global_ms`` (ms), ``x_b, y_b`` (B's plane position,
        m), ``x_a, y_a`` (A's position interpolated to ``t_global_ms``, m), ``error_m``.
    """
    colors = camera_colors(model.cameras)
    for (camera_a, camera_b, obj), rows in validation.groupby(["camera_a", "camera_b", "object"], sort=False):
        t_global_ms = rows["t_global_ms"].to_numpy(dtype=np.float64)
        zeros = np.zeros(len(rows))
        b = np.stack([rows["x_b"], rows["y_b"], zeros], axis=1).astype(np.float64)
        a = np.stack([rows["x_a"], rows["y_a"], zeros], axis=1).astype(np.float64)
        base = f"{PLANE}/{ROOT}/{pair_name(camera_a, camera_b)}/{entity_part(obj)}"
        index = [global_time_column(t_global_ms)]
        recording.send_columns(
            f"{base}/interpolated",
            indexes=index,
            columns=rr.Points3D.columns(positions=a, radii=[0.1] * len(a), colors=[colors[camera_a]] * len(a)),
        )
        recording.send_columns(
            f"{base}/error",
            indexes=index,
            columns=rr.Arrows3D.columns(origins=b, vectors=a - b, colors=[ERROR_COLOR] * len(a), radii=[0.04] * len(a)),
        )
        log_series(
            recording,
            f"{ROOT}/{pair_name(camera_a, camera_b)}/{entity_part(obj)}",
            rr.SeriesPoints(
                colors=colors[camera_b],
                markers="Circle",
                marker_sizes=2.0,
                names=f"{camera_a} vs {camera_b}, {obj}: error (m)",
            ),
            t_global_ms,
            rows["error_m"].to_numpy(dtype=np.float64),
        )
