"""Accuracy of a model against ground truth (a simulation), over all frames and rows."""

from __future__ import annotations

from typing import Protocol

import numpy as np
import pandas as pd

from flashsync.model import SyncModel


class TrueClock(Protocol):
    """Anything that knows the true global time of (camera, frame, stored row), ms."""

    def global_time_ms(self, camera: str, frame: np.ndarray, row: np.ndarray) -> np.ndarray: ...


def sync_errors(model: SyncModel, truth: TrueClock, row_step: int = 8) -> pd.DataFrame:
    """Per camera: RMS and max |model - truth| (ms) over every frame and every
    ``row_step``-th row (plus the last row).

    Both clocks are compared after removing their difference on the reference camera's
    first frame, row 0 (the global clock's origin is a convention, not a result).
    """
    origin = clock_origin_ms(model, truth)
    rows = []
    for name, camera in model.cameras.items():
        row = np.unique(np.append(np.arange(0, camera.height, row_step), camera.height - 1)).astype(float)
        frame = np.arange(camera.n_frames)
        frames, grid = np.meshgrid(frame, row, indexing="ij")
        error = (
            camera.t_global_ms(frames, grid)
            - origin
            - truth.global_time_ms(name, frames.ravel(), grid.ravel()).reshape(frames.shape)
        )
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
