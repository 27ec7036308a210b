"""``sync.json``: the self-contained, versioned model file (everything ``restamp`` needs)."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd

from flashsync.atomic import write_text
from flashsync.errors import ModelFileError
from flashsync.io.fields import Fields, describe, is_number
from flashsync.model import MATCHED_EVENT_COLUMNS, CameraClock, HeldExposure, SyncModel

FORMAT = "flashsync.sync"
VERSION = 1
#: A camera's ``display_rotation_deg`` (optional; 0 where absent, as in files before it).
ROTATIONS_DEG = (-90, 0, 90, 180)
TIME_CONVENTION = (
    "t_global_ms = alpha * t_frame_ms + beta_ms + warp(t_frame_ms) + q * row_time_ms, the "
    "end-of-exposure instant of stored row r (q = r, or height - 1 - r when flipped) on the "
    "reference camera's clock, ms; warp is piecewise linear through drift_warp_ms at the "
    "interior drift_knots_ms (zero at the end knots), absent for an affine clock; its standard deviation adds "
    "alpha * frame_std_ms (per frame, or one value for all) to the covariance's in quadrature"
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
    """Read a model written by :func:`save_model`, every field checked; a
    :class:`~flashsync.errors.ModelFileError` naming the file, the field and what is wrong
    for anything else.

    Checked: types (``"flipped": "false"`` is text, not false), finite numbers, the
    covariance's shape (3 + k, 3 + k) and the drift knots' and warp's lengths (k + 2, k),
    increasing frame times and knots, unique camera names, a reference camera that is
    there with ``alpha`` 1 and ``beta_ms`` 0, matched events of known cameras and frames, and
    exposure spans (optional; none where absent, as in files before them) in frame order within
    the frames, apart, each of one band or more.
    """
    path = Path(path)
    if path.is_dir():
        raise ModelFileError(f"{path}: is a folder, not a model file; give the sync.json that flashsync sync wrote")
    if not path.is_file():
        raise ModelFileError(f"{path}: no such model file; synchronise the videos first")
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise ModelFileError(
            f"{path}: not a flashsync model file (not UTF-8 text); give the sync.json that flashsync sync wrote"
        ) from None
    except json.JSONDecodeError as error:
        raise ModelFileError(f"{path}: not a flashsync model file (not JSON: {error}); sync again") from None
    except OSError as error:
        raise ModelFileError(f"{path}: cannot be read ({error.strerror}); check its permissions") from None
    top = Fields(document, str(path), error=ModelFileError, fix="sync again or fix the file")
    if document.get("format") != FORMAT:
        raise ModelFileError(f'{path}: not a flashsync model file (no "format": "{FORMAT}")')
    version = document.get("version")
    if not is_number(version) or isinstance(version, float):
        top.fail("version", f"is {describe(version)}, expected the number {VERSION} (no quotes)")
    if version != VERSION:
        raise ModelFileError(
            f"{path}: model format version {version} is not supported (this flashsync reads version "
            f"{VERSION}); sync again"
        )
    cameras = [_camera_from_fields(entry) for entry in top.objects("cameras", "cameras[{}]")]
    if not cameras:
        top.fail("cameras", "is empty, expected one object per camera")
    names = [camera.name for camera in cameras]
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        top.fail("cameras", f"names {', '.join(duplicates)} twice; each camera once")
    clocks = {camera.name: camera for camera in cameras}
    reference = top.text("reference")
    if reference not in clocks:
        top.fail("reference", f"is {reference!r}, which is not among the cameras ({', '.join(names)})")
    ref = clocks[reference]
    if ref.alpha != 1.0 or ref.beta_ms != 0.0 or ref.drift_warp_ms.size:
        top.fail(
            "reference",
            f"camera {reference!r} has alpha {ref.alpha!r} and beta_ms {ref.beta_ms!r}; the reference camera "
            "defines the global clock: alpha 1, beta_ms 0, no drift warp",
        )
    events = _events_from_fields(top, clocks)
    return SyncModel(reference=reference, cameras=clocks, events=events, source=str(path))


def _camera_to_dict(camera: CameraClock) -> dict:
    std = camera.frame_std_ms
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
        "exposure_std_ms": camera.exposure_std_ms,
        "frame_times_ms": camera.frame_times_ms.tolist(),
        "frame_std_ms": float(std[0]) if std.size and np.all(std == std[0]) else std.tolist(),
        "display_rotation_deg": camera.display_rotation_deg,
        "exposure_spans": [asdict(span) for span in camera.exposure_spans],
    }


def _camera_from_fields(entry: Fields) -> CameraClock:
    name = entry.text("name")
    entry.where = f"camera {name!r}"
    frame_times = entry.numbers("frame_times_ms", minimum_length=1, increasing=True)
    knots = entry.numbers("drift_knots_ms", increasing=True)
    if len(knots) == 1 or len(knots) == 2:
        entry.fail(
            "drift_knots_ms", f"has {len(knots)} values, expected none or k + 2 >= 3 (the ends and k interior knots)"
        )
    interior = max(len(knots) - 2, 0)
    warp = entry.numbers("drift_warp_ms", length=interior)
    frame_std = np.zeros(len(frame_times))
    if entry.has("frame_std_ms"):
        if isinstance(entry.value("frame_std_ms"), list):
            frame_std = entry.numbers("frame_std_ms", length=len(frame_times), minimum=0.0)
        else:
            frame_std = np.full(len(frame_times), entry.number("frame_std_ms", minimum=0.0))
    rotation = entry.integer("display_rotation_deg") if entry.has("display_rotation_deg") else 0
    if rotation not in ROTATIONS_DEG:
        entry.fail("display_rotation_deg", f"is {rotation}, expected one of {', '.join(map(str, ROTATIONS_DEG))}")
    return CameraClock(
        name=name,
        video=entry.text("video", nonempty=False),
        width=entry.integer("width", minimum=1),
        height=entry.integer("height", minimum=1),
        flipped=entry.boolean("flipped"),
        alpha=entry.number("alpha", positive=True),
        beta_ms=entry.number("beta_ms"),
        row_time_ms=entry.number("row_time_ms", positive=True),
        covariance=entry.matrix("covariance", (3 + interior, 3 + interior)),
        drift_knots_ms=knots,
        drift_warp_ms=warp,
        exposure_ms=entry.number("exposure_ms", minimum=0.0, optional=True),
        exposure_std_ms=entry.number("exposure_std_ms", minimum=0.0, optional=True),
        frame_times_ms=frame_times,
        frame_std_ms=frame_std,
        display_rotation_deg=rotation,
        exposure_spans=_exposure_spans(entry, len(frame_times)) if entry.has("exposure_spans") else (),
    )


def _exposure_spans(entry: Fields, n_frames: int) -> tuple[HeldExposure, ...]:
    """A camera's exposure spans, checked: frames within its ``n_frames``, in order and apart."""
    spans, after = [], -1
    for span in entry.objects("exposure_spans", f"{entry.where}, exposure_spans[{{}}]"):
        first = span.integer("first_frame", minimum=0)
        if first <= after:
            span.fail(
                "first_frame", f"is {first}, not after the span before (to frame {after}): spans are in frame order"
            )
        last = span.integer("last_frame", minimum=first)
        if last >= n_frames:
            span.fail("last_frame", f"is {last}, past the camera's {n_frames} frames")
        spans.append(
            HeldExposure(
                first,
                last,
                span.number("exposure_ms", minimum=0.0),
                span.number("exposure_std_ms", minimum=0.0),
                span.integer("n_bands", minimum=1),
                span.boolean("holds_frames"),
            )
        )
        after = last
    return tuple(spans)


def _events_from_fields(top: Fields, clocks: dict[str, CameraClock]) -> pd.DataFrame:
    """The matched events, each field checked: known cameras, frames in range, finite times."""
    records = []
    for entry in top.objects("events", "events[{}]"):
        camera = entry.text("camera")
        if camera not in clocks:
            entry.fail("camera", f"is {camera!r}, which is not among the cameras ({', '.join(clocks)})")
        frame = entry.integer("frame", minimum=0)
        if frame >= clocks[camera].n_frames:
            entry.fail("frame", f"is {frame}, past the {clocks[camera].n_frames} frames of camera {camera!r}")
        records.append(
            {
                "flash": entry.integer("flash", minimum=0),
                "camera": camera,
                "event": entry.integer("event", minimum=0),
                "frame": frame,
                "row": entry.number("row"),
                "t_frame_ms": entry.number("t_frame_ms"),
                "t_global_ms": _nan_for_none(entry.number("t_global_ms", optional=True)),
                "residual_ms": entry.number("residual_ms"),
                "inlier": entry.boolean("inlier"),
            }
        )
    return pd.DataFrame(records, columns=list(MATCHED_EVENT_COLUMNS)).astype(MATCHED_EVENT_COLUMNS)


def _nan_for_none(value: float | None) -> float:
    return float("nan") if value is None else value
