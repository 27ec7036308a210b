"""Validation of the synchronisation on objects seen by two cameras.

A validation triple is camera B's observation of an object at B's global time, and
camera A's position of the object interpolated to that instant. Errors are a few
millimetres where the sync is right, so in the plane (see :mod:`viz.plane`), under
``plane/validation/<A>_vs_<B>/<object>/error``, each is an arrow from B's position
towards A's drawn :attr:`viz.plane.PlaneView.error_scale` times its length (the view's
title and its scale bar say how many). The error (m) is a time series under
``validation/<A>_vs_<B>/<object>`` in B's colour, named ``at <B>``: one legend entry per
camera whose detections were the instants.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import rerun as rr

from flashsync.model import SyncModel
from viz.palette import CUT_ERROR_COLOR, ERROR_COLOR, camera_colors
from viz.plane import PLANE
from viz.series import log_series
from viz.timeline import Timeline
from viz.trajectories import entity_part

ROOT = "validation"
ARROW_RADIUS_UI = 1.5


def pair_path(camera_a: str, camera_b: str) -> str:
    """Entity path parts naming a validated camera pair: ``at_<B>/from_<A>``."""
    return f"{entity_part(f'at_{camera_b}')}/{entity_part(f'from_{camera_a}')}"


def validation_points(validation: pd.DataFrame) -> np.ndarray:
    """B's plane positions of the triples, shape (n, 2), m."""
    return validation[["x_b", "y_b"]].to_numpy(dtype=np.float64)


def log_validation(
    recording: rr.RecordingStream,
    timeline: Timeline,
    model: SyncModel,
    validation: pd.DataFrame,
    arrow_scale: float,
    arrow_cap_m: float,
) -> None:
    """Log validation triples: scaled error arrows in the plane and error series.

    Parameters
    ----------
    recording : RecordingStream
    timeline : Timeline
    model : SyncModel
    validation : DataFrame
        ``camera_a, camera_b, object, t_global_ms`` (ms), ``x_b, y_b`` (B's plane position,
        m), ``x_a, y_a`` (A's position interpolated to ``t_global_ms``, m), ``error_m``.
    arrow_scale : float
        Arrows are drawn this many times the error's length...
    arrow_cap_m : float
        ... but no longer than this, m; those cut have another colour.
    """
    colors = camera_colors(model.cameras)
    for (camera_a, camera_b, obj), rows in validation.groupby(["camera_a", "camera_b", "object"], sort=False):
        t_global_ms = rows["t_global_ms"].to_numpy(dtype=np.float64)
        b = rows[["x_b", "y_b"]].to_numpy(dtype=np.float64)
        a = rows[["x_a", "y_a"]].to_numpy(dtype=np.float64)
        pair = pair_path(camera_a, camera_b)
        drawn = arrow_scale * (a - b)
        length = np.hypot(drawn[:, 0], drawn[:, 1])
        cut = length > arrow_cap_m
        drawn[cut] *= (arrow_cap_m / length[cut])[:, None]
        recording.send_columns(
            f"{PLANE}/{ROOT}/{pair}/{entity_part(obj)}/error",
            indexes=[timeline.column(t_global_ms)],
            columns=rr.Arrows2D.columns(
                origins=b,
                vectors=drawn,
                colors=np.where(cut[:, None], CUT_ERROR_COLOR, ERROR_COLOR),
                radii=[rr.Radius.ui_points(ARROW_RADIUS_UI)] * len(a),
            ),
        )
        log_series(
            recording,
            timeline,
            f"{ROOT}/{pair}/{entity_part(obj)}",
            rr.SeriesPoints(colors=colors[camera_b], markers="Circle", marker_sizes=2.5, names=f"at {camera_b}"),
            t_global_ms,
            rows["error_m"].to_numpy(dtype=np.float64),
        )
