"""Accuracy of a model against ground truth (a simulation), over all frames and rows.

Probes are every frame and every ``row_step``-th row (plus the last row) of a camera. The
error of a probe is the model's global time minus the true one, both clocks compared after
removing their difference on the reference camera's first frame, row 0 (the global clock's
origin is a convention, not a result).

Calibration of the predicted uncertainty compares errors with a ``sigma`` function (by
default `predicted_std_ms`, i.e. `CameraClock.t_global_std_ms` from the solve's
covariance); pass another one to try a new definition of sigma:

- per camera, the error of each probe against its ``sigma``: a camera's sigma is its
  uncertainty against the true global clock, the reference's, whose shared errors it holds (see
  :func:`flashsync.pipeline._reference_shares_ms`). The reference camera's own calibration
  is not defined (NaN): at its first frame's first row its error and sigma are 0 by the
  origin convention, and further down they are its rows' and its clock's rate's;
- pairwise, for every camera including the reference: each probe of camera ``c`` is
  located in every other camera ``d`` at the same true instant (frame and row, from the
  truth; skipped where ``d`` is not recording then), and the error of the difference
  ``t_c - t_d`` is compared with ``sqrt(sigma_c**2 + sigma_d**2)``. The model keeps only
  each camera's own covariance block, so this treats the cameras' errors as independent
  (the cross-covariance of the joint solve is not stored), and two cameras other than the
  reference count its share twice.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol

import numpy as np
import pandas as pd

from flashsync.model import CameraClock, SyncModel


class TrueClock(Protocol):
    """Anything that knows the true global time of (camera, frame, stored row), ms."""

    def global_time_ms(self, camera: str, frame: np.ndarray, row: np.ndarray) -> np.ndarray: ...


class TrueRig(TrueClock, Protocol):
    """A true clock that also knows each camera's parameters: ``cameras[name]`` has
    ``exposure_ms`` and ``row_time_ms`` (global clock), e.g. a simulation's `GroundTruth`."""

    cameras: Mapping[str, Any]


#: ``sigma(camera, frame, row) -> std_ms``: the predicted standard deviation of
#: ``camera.t_global_ms(frame, row)``, ms, shape of the broadcast of frame and row.
Sigma = Callable[[CameraClock, np.ndarray, np.ndarray], np.ndarray]


def predicted_std_ms(camera: CameraClock, frame: np.ndarray, row: np.ndarray) -> np.ndarray:
    """The model's own sigma: `CameraClock.t_global_std_ms`, ms."""
    return camera.t_global_std_ms(frame, row)


def probes(camera: CameraClock, row_step: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Every frame and every ``row_step``-th stored row plus the last: frames (int) and
    rows (float), both of shape (n_frames, n_rows)."""
    row = np.unique(np.append(np.arange(0, camera.height, row_step), camera.height - 1)).astype(float)
    return np.meshgrid(np.arange(camera.n_frames), row, indexing="ij")


def probe_errors(
    model: SyncModel, truth: TrueClock, name: str, frames: np.ndarray, rows: np.ndarray, origin_ms: float | None = None
) -> np.ndarray:
    """Model minus truth (ms) of camera `name` at (frames, rows), origin removed; shape of
    the broadcast of `frames` and `rows`."""
    origin = clock_origin_ms(model, truth) if origin_ms is None else origin_ms
    frames, rows = np.broadcast_arrays(frames, rows)
    true = truth.global_time_ms(name, frames.ravel(), rows.ravel()).reshape(frames.shape)
    return model.camera(name).t_global_ms(frames, rows) - origin - true


def sync_errors(model: SyncModel, truth: TrueClock, row_step: int = 8) -> pd.DataFrame:
    """Per camera: RMS and max |model - truth| (ms) over every frame and every
    ``row_step``-th row (plus the last row)."""
    origin = clock_origin_ms(model, truth)
    rows = []
    for name, camera in model.cameras.items():
        error = probe_errors(model, truth, name, *probes(camera, row_step), origin)
        rows.append(
            {"camera": name, "rms_ms": float(np.sqrt(np.mean(error**2))), "max_ms": float(np.max(np.abs(error)))}
        )
    return pd.DataFrame(rows)


def clock_origin_ms(model: SyncModel, truth: TrueClock) -> float:
    """Model minus truth on the reference camera's frame 0, row 0, ms: the origin convention."""
    return float(
        model.camera(model.reference).t_global_ms(0, 0.0)
        - truth.global_time_ms(model.reference, np.array([0]), np.array([0.0]))[0]
    )


def true_location(
    truth: TrueClock, camera: CameraClock, t_global_ms: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where `camera` truly images global instants: frame, stored row (rows in the vertical
    blanking lie beyond the image) and whether it was recording then (within one frame
    period after the start of a frame's readout).

    Parameters
    ----------
    truth : TrueClock
    camera : CameraClock
        Gives the camera's name, frame count and height.
    t_global_ms : ndarray
        True global instants, ms.

    Returns
    -------
    frame : ndarray of int
    row : ndarray of float
    recording : ndarray of bool
    """
    frames = np.arange(camera.n_frames)
    top = truth.global_time_ms(camera.name, frames, np.zeros(camera.n_frames))
    bottom = truth.global_time_ms(camera.name, frames, np.full(camera.n_frames, camera.height - 1.0))
    start = np.minimum(top, bottom)
    row_time = np.abs(bottom - top) / max(camera.height - 1, 1)
    t = np.asarray(t_global_ms, dtype=float)
    frame = np.clip(np.searchsorted(start, t, side="right") - 1, 0, None)
    q = (t - start[frame]) / row_time[frame]
    period = float(np.median(np.diff(start))) if camera.n_frames > 1 else np.inf
    recording = (t >= start[0]) & (t - start[frame] <= period)
    row = np.where(top[frame] <= bottom[frame], q, camera.height - 1 - q)
    return frame, row, recording


def _true_exposures_ms(true, frames: np.ndarray) -> np.ndarray:
    """A camera's true exposure in each of ``frames`` (decoded frames), ms: a simulation's
    ``exposure_changes`` where it has them."""
    if not getattr(true, "exposure_changes", None):
        return np.full(len(frames), float(true.exposure_ms))
    return true.exposure_of_ms(frames)


def _true_exposure_ms(true) -> float:
    """A camera's true exposure, ms: where it changes while the camera records (a
    simulation's ``exposure_changes``), the one it held over the most frames."""
    if not getattr(true, "exposure_changes", None):
        return true.exposure_ms
    held, frames = np.unique(true.exposure_of_ms(np.arange(len(true.frame_times_ms))), return_counts=True)
    return float(held[np.argmax(frames)])


def _z_stats(error: np.ndarray, sigma: np.ndarray) -> tuple[float, float]:
    """RMS of error / sigma and the fraction of |error| <= 2 sigma (NaN without probes)."""
    if error.size == 0:
        return float("nan"), float("nan")
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.abs(error) / sigma
    z = np.where((sigma == 0) & (error == 0), 0.0, z)
    return float(np.sqrt(np.mean(z**2))), float(np.mean(np.abs(error) <= 2.0 * sigma))


def pair_errors(
    model: SyncModel, truth: TrueClock, name: str, other: str, row_step: int = 8, sigma: Sigma = predicted_std_ms
) -> tuple[np.ndarray, np.ndarray]:
    """Errors (ms) of ``t_name - t_other`` at the probes of `name`, with the sigma of the
    difference, ``sqrt(sigma_name**2 + sigma_other**2)``; probes at instants when `other`
    was not recording are left out. Both arrays of shape (n,)."""
    origin = clock_origin_ms(model, truth)
    camera, partner = model.camera(name), model.camera(other)
    frames, rows = probes(camera, row_step)
    frames, rows = frames.ravel(), rows.ravel()
    true = truth.global_time_ms(name, frames, rows)
    error = camera.t_global_ms(frames, rows) - origin - true
    frame, row, recording = true_location(truth, partner, true)
    error_other = partner.t_global_ms(frame, row) - origin - true
    std = np.hypot(sigma(camera, frames, rows), sigma(partner, frame, row))
    return (error - error_other)[recording], std[recording]


def camera_accuracy(
    model: SyncModel, truth: TrueRig, row_step: int = 8, sigma: Sigma = predicted_std_ms
) -> pd.DataFrame:
    """Per camera of the truth, how far the model is from it.

    Columns: ``camera``; ``reference``; ``solved`` (in the model); ``rms_ms``, ``max_ms``
    (sync error over the probes); ``reference_rms_ms`` (RMS of the error of its times
    against the reference's at the same instants: free of the global clock's own error;
    NaN for the reference); ``sigma_rms_ms`` (RMS of the predicted sigma over the probes);
    ``exposure_error_ms`` (model - truth, the exposure held over the most frames where it
    changes; NaN where the model has none) and ``exposure_z``
    (over its standard deviation; NaN where the model states none); ``exposure_frames_rms_ms``
    and ``exposure_frames_z_rms`` (RMS over its frames of the model's exposure of each,
    :meth:`~flashsync.model.CameraClock.exposure_at`, less the truth's, and of that over
    its standard deviation);
    ``row_time_error_pct`` (relative error of the time per row, %) and ``row_time_z`` (its
    error over its predicted standard deviation); ``z_rms`` and
    ``within_2sigma`` (RMS of error / sigma over the probes and the fraction within 2
    sigma; NaN for the reference); ``pair_z_rms`` and ``pair_within_2sigma`` (the same for the
    differences with every other solved camera, see the module docstring). Cameras the
    model left out have NaN everywhere.
    """
    origin = clock_origin_ms(model, truth)
    rows = []
    for name, true in truth.cameras.items():
        row: dict = {"camera": name, "reference": name == model.reference, "solved": name in model.cameras}
        if name not in model.cameras:
            rows.append(row)
            continue
        camera = model.camera(name)
        frames, grid = probes(camera, row_step)
        error = probe_errors(model, truth, name, frames, grid, origin)
        std = sigma(camera, frames, grid)
        pairs = [pair_errors(model, truth, name, other, row_step, sigma) for other in model.cameras if other != name]
        pair_error = np.concatenate([e for e, _ in pairs]) if pairs else np.empty(0)
        pair_std = np.concatenate([s for _, s in pairs]) if pairs else np.empty(0)
        against_reference = (
            pair_errors(model, truth, name, model.reference, row_step, sigma)[0]
            if name != model.reference
            else np.empty(0)
        )
        z_rms, within = _z_stats(error, std) if name != model.reference else (float("nan"), float("nan"))
        pair_z_rms, pair_within = _z_stats(pair_error, pair_std)
        exposure = camera.exposure_ms if camera.exposure_ms is not None else float("nan")
        exposure_std = camera.exposure_std_ms if camera.exposure_std_ms is not None else float("nan")
        every_frame = np.arange(camera.n_frames)
        by_frame, by_frame_std = camera.exposure_at(every_frame)
        by_frame_error = by_frame - _true_exposures_ms(true, every_frame)
        row.update(
            rms_ms=float(np.sqrt(np.mean(error**2))),
            max_ms=float(np.max(np.abs(error))),
            reference_rms_ms=float(np.sqrt(np.mean(against_reference**2))) if against_reference.size else np.nan,
            sigma_rms_ms=float(np.sqrt(np.mean(std**2))),
            exposure_error_ms=exposure - _true_exposure_ms(true),
            exposure_z=_over(exposure - _true_exposure_ms(true), exposure_std),
            exposure_frames_rms_ms=float(np.sqrt(np.mean(by_frame_error**2))),
            exposure_frames_z_rms=_z_stats(by_frame_error, by_frame_std)[0],
            row_time_error_pct=100.0 * (camera.row_time_ms / true.row_time_ms - 1.0),
            row_time_z=_over(camera.row_time_ms - true.row_time_ms, float(np.sqrt(camera.covariance[2, 2]))),
            z_rms=z_rms,
            within_2sigma=within,
            pair_z_rms=pair_z_rms,
            pair_within_2sigma=pair_within,
        )
        rows.append(row)
    return pd.DataFrame(rows)


def _over(error: float, std: float) -> float:
    """``error / std``; NaN where there is no standard deviation."""
    return error / std if std > 0 else float("nan")


def stamp_errors(stamped: pd.DataFrame, model: SyncModel, truth: TrueClock) -> np.ndarray:
    """``t_global_ms`` of re-stamped detections (columns camera, frame, y) minus truth, ms;
    rows without a stamp are left out."""
    stamped = stamped[stamped["t_global_ms"].notna()]
    errors = [
        group["t_global_ms"].to_numpy()
        - clock_origin_ms(model, truth)
        - truth.global_time_ms(name, group["frame"].to_numpy(), group["y"].to_numpy())
        for name, group in stamped.groupby("camera", sort=False)
    ]
    return np.concatenate(errors) if errors else np.empty(0)


def tick_errors_ms(table: pd.DataFrame, model: SyncModel, truth: TrueClock) -> np.ndarray:
    """True end-of-exposure time minus the tick, ms, of each located row of a frame table
    (:func:`flashsync.ticks.frame_table`; rows without a frame are left out), in the
    table's order."""
    located = table[table["frame"].notna()]
    error = np.empty(len(located))
    for name in located["camera"].unique():
        mine = (located["camera"] == name).to_numpy()
        true_ms = truth.global_time_ms(
            name, located["frame"].to_numpy(dtype=np.int64)[mine], located["row"].to_numpy()[mine]
        )
        error[mine] = true_ms + clock_origin_ms(model, truth) - located["t_global_ms"].to_numpy()[mine]
    return error
