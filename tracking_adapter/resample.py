"""Tracks at common instants: each (camera, object) track interpolated at global ticks.

A triangulation or multi-view pose step wants every camera's observation of an object at
the same instants. The detections are stamped with the model (:func:`~tracking_adapter.
restamp.restamp`; a table that was re-stamped before is stamped again from its ``camera``,
``frame`` and ``y``, so the times always come from the model given) and placed at their
mid-exposure instants ``t_center_ms`` — a blurred centroid belongs to the middle of the
exposure, so a camera whose exposure is neither in the model nor given is an error. Each
track is interpolated linearly (:func:`~tracking_adapter.interpolate.interpolate_track`,
the interpolation ``validate`` uses) at the ticks from ``max_gap_ms`` before its first
detection to ``max_gap_ms`` after its last. Nothing is extrapolated: a tick outside the
track, or between two detections more than ``max_gap_ms`` apart, keeps empty ``x`` and
``y`` and says why in ``reason``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from flashsync.errors import InputError
from flashsync.io.detections import require_columns
from flashsync.model import SyncModel
from tracking_adapter.interpolate import STATUS, default_gap_ms, interpolate_track
from tracking_adapter.restamp import camera_list, restamp
from tracking_adapter.validate import OBJECT_COLUMNS

TRACK_COLUMNS = ("t_global_ms", "camera", "object", "x", "y", "gap_ms", "reason")
#: Largest |x| of a detection that is interpolated, px: far beyond any image, and far below
#: where the difference of two x overflows (1.8e308).
MAX_X_PX = 1e9


@dataclass
class Resampled:
    """Result of :func:`resample`.

    Attributes
    ----------
    tracks : DataFrame
        :data:`TRACK_COLUMNS`, one row per (tick, track) near the track, ordered by tick,
        then camera (model order), then object (order of first appearance):
        ``t_global_ms`` the tick (global clock, ms), ``camera``, ``object`` (the input's
        ``object`` or ``id``, or ``object`` when it has none), ``x``, ``y`` (image px,
        interpolated; NaN where refused), ``gap_ms`` (from the tick to the track's nearest
        detection, ms), ``reason`` (empty where interpolated, else ``before the track``,
        ``after the track`` or ``gap over the limit``).
    detections : int
        Detections read.
    not_used : dict of str to int
        Detections left out, by reason (restamp's reasons, ``x missing or not a number``,
        ``x beyond 1e+09 px`` (:data:`MAX_X_PX`), ``object id missing``, ``another detection of
        the object in the frame``).
    """

    tracks: pd.DataFrame
    detections: int
    not_used: dict[str, int] = field(default_factory=dict)


def resample(
    detections: pd.DataFrame,
    model: SyncModel,
    ticks_ms: np.ndarray,
    *,
    max_gap_ms: float | None = None,
    exposure_ms: Mapping[str, float] | None = None,
    as_shown: bool = False,
    source: str = "detections",
) -> Resampled:
    """Interpolate every (camera, object) track at common instants.

    Parameters
    ----------
    detections : DataFrame
        ``camera``, ``frame`` (0-based), ``x``, ``y`` (stored-image px, or as shown with
        ``as_shown``) and optionally an object id ``object`` (or ``id``); without one each
        camera has one track.
    model : SyncModel
        The synchronisation model.
    ticks_ms : array of shape (n_ticks,)
        Common instants on the global clock, ms, increasing
        (:func:`flashsync.ticks.model_ticks_ms`).
    max_gap_ms : float, optional
        Longest time between the two detections an instant is interpolated between, ms;
        default 2.5 frame periods of the track's camera.
    exposure_ms : mapping of str to float, optional
        Exposure per camera, ms, overriding the model's.
    as_shown : bool
        ``x`` and ``y`` are in the picture a player shows (:func:`tracking_adapter.restamp.restamp`).
    source : str
        Name of the detections file, for messages.

    Returns
    -------
    Resampled

    Examples
    --------
    >>> model = load_model("sync.json")                                      # doctest: +SKIP
    >>> result = resample(load_detections("puck.csv"), model,
    ...                   model_ticks_ms(model, 100.0))                      # doctest: +SKIP
    """
    require_columns(detections.columns, ("camera", "frame", "x", "y"), source)
    if max_gap_ms is not None and not (np.isfinite(max_gap_ms) and max_gap_ms > 0):
        raise InputError(f"{max_gap_ms}: the longest gap must be a positive time in ms", parameter="max_gap_ms")
    stamped = restamp(
        detections[["camera", "frame", "x", "y"]], model, exposure_ms=exposure_ms, as_shown=as_shown, source=source
    )
    unknown = stamped.loc[stamped["restamp_error"] == "unknown camera", "camera"].unique()
    if len(unknown):
        raise InputError(
            f"{source}: camera {camera_list(unknown)} is not in the model "
            f"(it has {', '.join(model.cameras)}); sync its video too or fix the "
            "camera names"
        )
    not_used = {str(k): int(v) for k, v in stamped["restamp_error"].value_counts().items()}
    usable = stamped["restamp_error"].isna().to_numpy().copy()
    id_column = next((name for name in OBJECT_COLUMNS if name in detections.columns), None)
    objects, object_names = (
        pd.factorize(_whole_ids(detections[id_column]))
        if id_column
        else (np.zeros(len(detections), dtype=np.int64), pd.Index(["object"]))
    )
    x = pd.to_numeric(detections["x"], errors="coerce").to_numpy(dtype=np.float64)
    for reason, bad in (
        ("x missing or not a number", ~np.isfinite(x)),
        (f"x beyond {MAX_X_PX:g} px", np.abs(x) > MAX_X_PX),
        ("object id missing", objects < 0),
    ):
        _count(not_used, reason, int(np.count_nonzero(usable & bad)))
        usable &= ~bad
    cameras = stamped["camera"].astype("str").to_numpy(dtype=object)
    _require_exposures(stamped, cameras, usable, model)
    t = stamped["t_center_ms"].to_numpy(dtype=np.float64)
    frames = pd.to_numeric(stamped["frame"], errors="coerce").to_numpy(dtype=np.float64)
    y = pd.to_numeric(stamped["y"], errors="coerce").to_numpy(dtype=np.float64)
    ticks = np.asarray(ticks_ms, dtype=np.float64)

    pieces = []
    for camera_index, name in enumerate(model.cameras):
        gap_limit = max_gap_ms if max_gap_ms is not None else default_gap_ms(model, name)
        for obj in pd.unique(objects[usable & (cameras == name)]):
            rows = np.flatnonzero(usable & (cameras == name) & (objects == obj))
            first = rows[np.unique(frames[rows], return_index=True)[1]]
            _count(not_used, "another detection of the object in the frame", len(rows) - len(first))
            times = t[first]
            near = np.flatnonzero((ticks >= times[0] - gap_limit) & (ticks <= times[-1] + gap_limit))
            sample = interpolate_track(times, np.column_stack([x[first], y[first]]), ticks[near], gap_limit)
            pieces.append(
                pd.DataFrame(
                    {
                        "tick": near,
                        "camera_index": camera_index,
                        "object_index": obj,
                        "x": sample.values[:, 0],
                        "y": sample.values[:, 1],
                        "gap_ms": sample.nearest_ms,
                        "status": sample.status,
                    }
                )
            )
    found = (
        pd.concat(pieces, ignore_index=True)
        if pieces
        else pd.DataFrame(
            {name: pd.Series(dtype=np.int64) for name in ("tick", "camera_index", "object_index", "status")}
            | {name: pd.Series(dtype=np.float64) for name in ("x", "y", "gap_ms")}
        )
    )
    found = found.sort_values(["tick", "camera_index", "object_index"], kind="stable")
    tracks = pd.DataFrame(
        {
            "t_global_ms": ticks[found["tick"].to_numpy()],
            "camera": pd.array(
                np.array(list(model.cameras), dtype=object)[found["camera_index"].to_numpy()], dtype="str"
            ),
            "object": object_names.take(found["object_index"].to_numpy()).to_numpy(),
            "x": found["x"].to_numpy(),
            "y": found["y"].to_numpy(),
            "gap_ms": found["gap_ms"].to_numpy(),
            "reason": pd.array(np.array(STATUS, dtype=object)[found["status"].to_numpy()], dtype="str"),
        }
    )
    return Resampled(tracks, len(detections), not_used)


def format_resampled(result: Resampled, source: str, output: str) -> str:
    """One line for the terminal: detections used, rows written, rows refused by reason."""
    tracks = result.tracks
    refused = tracks.loc[tracks["reason"] != "", "reason"].value_counts()
    text = (
        f"{source} -> {output}: {result.detections} detections, "
        f"{tracks.groupby(['camera', 'object']).ngroups} tracks, {len(tracks)} rows, "
        f"{len(tracks) - int(refused.sum())} interpolated"
    )
    if len(refused):
        text += " (" + ", ".join(f"{count} {reason}" for reason, count in refused.items()) + ")"
    if result.not_used:
        text += "; detections not used: " + ", ".join(f"{count} {reason}" for reason, count in result.not_used.items())
    return text


def _require_exposures(stamped: pd.DataFrame, cameras: np.ndarray, usable: np.ndarray, model: SyncModel) -> None:
    """A one-line error naming the cameras whose detections have no mid-exposure time."""
    if "t_center_ms" in stamped:
        usable = usable & stamped["t_center_ms"].isna().to_numpy()
    missing = [name for name in model.cameras if np.any(usable & (cameras == name))]
    if missing:
        raise InputError(
            f"{missing[0]}=MS: camera {', '.join(missing)}: exposure unknown (not in the model), so "
            "its detections have no mid-exposure time; give the exposure in ms",
            parameter="exposure_ms",
        )


def _whole_ids(ids: pd.Series) -> pd.Series:
    """Integer ids read as floats (a column of numbers with a gap) back as integers: 7, not 7.0."""
    if pd.api.types.is_float_dtype(ids) and (ids.dropna() % 1 == 0).all():
        return ids.astype("Int64")
    return ids


def _count(counts: dict[str, int], reason: str, count: int) -> None:
    if count:
        counts[reason] = counts.get(reason, 0) + count
