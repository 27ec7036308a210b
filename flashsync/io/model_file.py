"""``sync.json``: the self-contained, versioned model file (everything ``restamp`` needs)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from flashsync.atomic import write_text
from flashsync.errors import ModelFileError
from flashsync.model import CameraClock, SyncModel

FORMAT = "flashsync.sync"
VERSION = 1
TIME_CONVENTION = (
    "t_global_ms = alpha * t_frame_ms + beta_ms + warp(t_frame_ms) + q * row_time_ms, the "
    "end-of-exposure instant of stored row r (q = r, or height - 1 - r when flipped) on the "
    "reference camera's clock, ms; warp is piecewise linear through drift_warp_ms at the "
    "interior drift_knots_ms (zero at the end knots), absent for an affine clock"
)


def save_model(model: SyncModel, path: str | Path) -> None:
    """Write ``model`` to ``path`` as JSON, atomically."""
    document = {
        "format": FORMAT,
        "version": VERSION,
        "time_convention": TIME_CONVENTION,
        "reference": model.reference,
        "cameras": [_camera_to_dict(camera) for camera in model.cameras.values()],
        "events": json.loads(model.events.to_json(orient="records")),
    }
    write_text(path, json.dumps(document, indent=1))


def load_model(path: str | Path) -> SyncModel:
    """Read a model written by :func:`save_model`; a clear error for anything else."""
    path = Path(path)
    if not path.is_file():
        raise ModelFileError(f"{path}: no such model file; synchronise the videos first")
    try:
        document = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ModelFileError(f"{path}: not a flashsync model file ({error})") from None
    if not isinstance(document, dict) or document.get("format") != FORMAT:
        raise ModelFileError(f'{path}: not a flashsync model file (no "format": "{FORMAT}")')
    if document.get("version") != VERSION:
        raise ModelFileError(
            f"{path}: model format version {document.get('version')} is not "
            f"supported (this flashsync reads version {VERSION}); sync again"
        )
    try:
        cameras = [_camera_from_dict(entry) for entry in document["cameras"]]
        return SyncModel(
            reference=document["reference"],
            cameras={camera.name: camera for camera in cameras},
            events=pd.DataFrame.from_records(document["events"]),
        )
    except (KeyError, TypeError, ValueError) as error:
        raise ModelFileError(f"{path}: damaged model file ({type(error).__name__}: {error}); sync again") from None


def _camera_to_dict(camera: CameraClock) -> dict:
    return {
        "name": camera.name,
        "video": camera.video,
        "width": camera.width,
        "height": camera.height,
        "flipped": camera.flipped,
        "alpha": camera.alpha,
        "beta_ms": camera.beta_ms,
        "row_time_ms": camera.row_time_ms,
        "std": dict(zip(["alpha", "beta_ms", "row_time_ms"], np.sqrt(np.diag(camera.covariance))[:3].tolist())),
        "drift_knots_ms": camera.drift_knots_ms.tolist(),
        "drift_warp_ms": camera.drift_warp_ms.tolist(),
        "covariance": camera.covariance.tolist(),
        "exposure_ms": camera.exposure_ms,
        "frame_times_ms": camera.frame_times_ms.tolist(),
    }


def _camera_from_dict(entry: dict) -> CameraClock:
    return CameraClock(
        name=entry["name"],
        video=entry["video"],
        width=int(entry["width"]),
        height=int(entry["height"]),
        flipped=bool(entry["flipped"]),
        alpha=float(entry["alpha"]),
        beta_ms=float(entry["beta_ms"]),
        row_time_ms=float(entry["row_time_ms"]),
        covariance=np.asarray(entry["covariance"], dtype=np.float64),
        drift_knots_ms=np.asarray(entry["drift_knots_ms"], dtype=np.float64),
        drift_warp_ms=np.asarray(entry["drift_warp_ms"], dtype=np.float64),
        exposure_ms=entry["exposure_ms"],
        frame_times_ms=np.asarray(entry["frame_times_ms"], dtype=np.float64),
    )
