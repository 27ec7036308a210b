"""Residuals of the solve per camera, with the predicted synchronisation uncertainty.

Per camera, on ``global_time``:

``residuals/<camera>/matched``, ``residuals/<camera>/rejected``
    The residual (ms) of each matched event at its flash's global time: inliers and
    outliers of the solve.
``residuals/<camera>/sigma_plus``, ``residuals/<camera>/sigma_minus``
    ``+-`` the standard deviation (ms) of the camera's global time of its middle row
    (``height // 2``) from the solve's covariance, at up to :data:`BAND_SAMPLES` frames
    spread over the recording. Left out where the covariance is zero (unknown, or the
    reference camera).
"""

from __future__ import annotations

import numpy as np
import rerun as rr

from flashsync.model import CameraClock, SyncModel
from viz.palette import Color, camera_colors, status_style
from viz.series import log_series

ROOT = "residuals"
BAND_SAMPLES = 500


def residual_entity(camera: str, series: str) -> str:
    """Entity path of ``camera``'s ``series``: matched, rejected, sigma_plus or sigma_minus."""
    return f"{ROOT}/{rr.escape_entity_path_part(camera)}/{series}"


def log_residuals(recording: rr.RecordingStream, model: SyncModel) -> None:
    """Log each camera's residuals and uncertainty band.

    Parameters
    ----------
    recording : RecordingStream
    model : SyncModel
        Its events (``camera, t_global_ms, residual_ms, inlier``) give the residuals,
        each at its flash's global time; its cameras' covariances the bands.
    """
    colors = camera_colors(model.cameras)
    matched = model.events.reindex(columns=["camera", "t_global_ms", "residual_ms", "inlier"])
    for name, camera in model.cameras.items():
        for status, inlier in (("matched", True), ("rejected", False)):
            rows = matched[(matched["camera"] == name) & (matched["inlier"] == inlier)]
            if rows.empty:
                continue
            color, marker = status_style(status, colors[name])
            log_series(
                recording,
                residual_entity(name, status),
                rr.SeriesPoints(colors=color, markers=marker, marker_sizes=3.0, names=f"{name} residual ({status})"),
                rows["t_global_ms"].to_numpy(),
                rows["residual_ms"].to_numpy(),
            )
        if np.any(camera.covariance):
            _log_band(recording, camera, colors[name])


def _log_band(recording: rr.RecordingStream, camera: CameraClock, color: Color) -> None:
    frames = np.unique(np.linspace(0, camera.n_frames - 1, BAND_SAMPLES).round().astype(np.int64))
    row = np.full(len(frames), camera.height // 2)
    sigma = camera.t_global_std_ms(frames, row)
    t_global_ms = camera.t_global_ms(frames, row)
    for series, sign in (("sigma_plus", 1.0), ("sigma_minus", -1.0)):
        log_series(
            recording,
            residual_entity(camera.name, series),
            rr.SeriesLines(colors=color, widths=1.0, names=f"{camera.name} {'+' if sign > 0 else '-'}1 sigma"),
            t_global_ms,
            sign * sigma,
        )
