"""Residuals of the solve per camera, with the predicted synchronisation uncertainty.

Per camera, on ``global_time``, every series named after the camera (one legend entry
per camera):

``residuals/<camera>/matched``, ``residuals/<camera>/rejected``
    The residual (ms) of each matched event at its flash's global time
    (:func:`viz.events.flash_instants_ms`): inliers (in the camera's colour) and outliers
    (red crosses) of the solve. The plot's range is set by the inliers and the bands
    (:func:`residual_extent_ms`): an outlier far off, e.g. a flash the solve could not
    place, is beyond it (zoom out to see it; the flash log and the lanes name it).
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
from viz.events import flash_instants_ms
from viz.palette import Color, camera_colors, status_style
from viz.series import log_series
from viz.timeline import Timeline

ROOT = "residuals"
BAND_SAMPLES = 500


def residual_entity(camera: str, series: str) -> str:
    """Entity path of ``camera``'s ``series``: matched, rejected, sigma_plus or sigma_minus."""
    return f"{ROOT}/{rr.escape_entity_path_part(camera)}/{series}"


def uncertainty_band(camera: CameraClock) -> tuple[np.ndarray, np.ndarray]:
    """``(t_global_ms, sigma_ms)`` of ``camera``'s middle row at up to :data:`BAND_SAMPLES`
    frames; empty where its covariance is zero."""
    if not np.any(camera.covariance):
        return np.zeros(0), np.zeros(0)
    frames = np.unique(np.linspace(0, camera.n_frames - 1, BAND_SAMPLES).round().astype(np.int64))
    row = np.full(len(frames), camera.height // 2)
    return camera.t_global_ms(frames, row), camera.t_global_std_ms(frames, row)


def residual_extent_ms(model: SyncModel) -> float:
    """The largest absolute value the residual plot shows (inliers' residuals and bands), ms."""
    inliers = model.events[model.events["inlier"].astype(bool)]
    values = [np.abs(inliers["residual_ms"].to_numpy(dtype=np.float64))]
    values += [uncertainty_band(camera)[1] for camera in model.cameras.values()]
    finite = np.concatenate(values)
    finite = finite[np.isfinite(finite)]
    return float(finite.max()) if finite.size else 0.0


def log_residuals(recording: rr.RecordingStream, model: SyncModel, timeline: Timeline) -> None:
    """Log each camera's residuals and uncertainty band.

    Parameters
    ----------
    recording : RecordingStream
    model : SyncModel
        Its events (``camera, residual_ms, inlier``) give the residuals, each at its
        flash's global time; its cameras' covariances the bands.
    timeline : Timeline
    """
    colors = camera_colors(model.cameras)
    matched = model.events.reindex(columns=["camera", "residual_ms", "inlier"]).assign(
        t_global_ms=flash_instants_ms(model)
    )
    for name, camera in model.cameras.items():
        for status, inlier in (("matched", True), ("rejected", False)):
            rows = matched[(matched["camera"] == name) & (matched["inlier"] == inlier)]
            if rows.empty:
                continue
            color, marker = status_style(status, colors[name])
            log_series(
                recording,
                timeline,
                residual_entity(name, status),
                rr.SeriesPoints(colors=color, markers=marker, marker_sizes=4.0, names=name),
                rows["t_global_ms"].to_numpy(),
                rows["residual_ms"].to_numpy(),
            )
        _log_band(recording, timeline, camera, colors[name])


def _log_band(recording: rr.RecordingStream, timeline: Timeline, camera: CameraClock, color: Color) -> None:
    t_global_ms, sigma = uncertainty_band(camera)
    if not len(sigma):
        return
    for series, sign in (("sigma_plus", 1.0), ("sigma_minus", -1.0)):
        log_series(
            recording,
            timeline,
            residual_entity(camera.name, series),
            rr.SeriesLines(colors=color, widths=1.0, names=camera.name),
            t_global_ms,
            sign * sigma,
        )
