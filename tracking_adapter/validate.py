"""Validate a synchronisation on fast objects seen by several cameras.

For every detection of an object in camera B, camera A's two detections of the same object
that bracket it in global time are interpolated linearly to B's instant and the
interpolated position is compared with B's on the ground plane (homographies image px ->
plane m). With a good synchronisation the distance is the detection and homography
noise; a timing error ``dt`` adds ``speed * dt`` (36 m/s: 3.6 cm per ms).

The same triples are measured under three time models, each with its own bracketing:

``subframe``
    The full model, ``alpha * t_f + beta + q * T_row`` (what ``restamp`` writes).
``frame``
    Frame-level synchronisation: every detection gets the time of its frame's middle row,
    ``alpha * t_f + beta + (height - 1) / 2 * T_row``, as if the camera had a global
    shutter exposed at mid-readout (the best a per-frame stamp can do).
``no_drift``
    No clock drift, ``alpha = 1``, with the shift moved to keep the model's time at the
    camera's mean frame time, ``beta + (alpha - 1) * mean(t_f)`` (the best constant offset).

Instants are mid-exposure (``t_center_ms``) when the exposure of every camera used is
known, else end of exposure (``t_global_ms``).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace

import numpy as np
import pandas as pd

from flashsync.io.detections import require_columns
from flashsync.model import CameraClock, SyncModel
from tracking_adapter.interpolate import (
    AFTER_TRACK,
    BEFORE_TRACK,
    GAP_OVER_LIMIT,
    INTERPOLATED,
    default_gap_ms,
    interpolate_track,
)
from tracking_adapter.restamp import restamp

TIME_MODELS = {
    "subframe": "sub-frame (model)",
    "frame": "frame-level (mid row)",
    "no_drift": "no drift (alpha = 1)",
}
TRIPLE_COLUMNS = ["camera_a", "camera_b", "object", "t_global_ms", "x_b", "y_b", "x_a", "y_a", "error_m"]
OBJECT_COLUMNS = ("object", "id")


@dataclass
class ErrorStats:
    """Interpolation errors of one camera pair under one time model.

    Attributes
    ----------
    triples : int
        Detections of B with a bracketing pair of A's detections within the gap limit.
    median_m, p95_m, max_m : float or None
        Median, 95th percentile and maximum of the plane distance, m; None without triples.
    skipped : dict of str to int
        Detections of B not used, by reason: ``object not seen by A``, ``outside A's
        track`` (before A's first or after its last detection of the object), ``A's gap
        over the limit``.
    """

    triples: int
    median_m: float | None
    p95_m: float | None
    max_m: float | None
    skipped: dict[str, int] = field(default_factory=dict)


@dataclass
class PairValidation:
    """One ordered camera pair: A's track interpolated at B's detections.

    Attributes
    ----------
    interpolated : str
        Camera A.
    observed : str
        Camera B.
    max_gap_ms : float
        Longest time between A's bracketing detections, ms.
    stats : dict of str to ErrorStats
        By time model (keys of :data:`TIME_MODELS`).
    """

    interpolated: str
    observed: str
    max_gap_ms: float
    stats: dict[str, ErrorStats]


@dataclass
class ValidationReport:
    """Result of :func:`validate`; ``to_dict()`` is JSON-able.

    Attributes
    ----------
    pairs : list of PairValidation
        Every ordered pair of cameras with usable detections, in model order; a pair that
        does not overlap has no triples and says why in ``skipped``.
    instant : str
        ``"t_center_ms"`` (mid-exposure) or ``"t_global_ms"`` (end of exposure).
    not_used : dict of str to int
        Detections left out, by reason (the restamp reasons, ``x missing or not a number``,
        ``object id missing``, ``camera without homography``, ``beyond the horizon of its camera's
        homography``).
    triples : DataFrame
        Every triple of the sub-frame model (:data:`TRIPLE_COLUMNS`): B's detection at its
        instant (ms) and plane position (m), A's interpolated position there, the distance.
    """

    pairs: list[PairValidation]
    instant: str
    not_used: dict[str, int] = field(default_factory=dict)
    triples: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=TRIPLE_COLUMNS))

    def to_dict(self) -> dict:
        """Plain dicts, lists, numbers and strings, for ``json.dumps``; ``triples`` as a list
        of records."""
        return {
            "pairs": [asdict(pair) for pair in self.pairs],
            "instant": self.instant,
            "not_used": self.not_used,
            "triples": json.loads(self.triples.to_json(orient="records")),
        }


def image_to_plane(x: np.ndarray, y: np.ndarray, homography: np.ndarray) -> np.ndarray:
    """Map image points to the plane of a homography.

    Parameters
    ----------
    x, y : arrays of shape (n,)
        Image column and stored-image row, px.
    homography : array of shape (3, 3)
        Image px -> plane m.

    Returns
    -------
    ndarray of shape (n, 2)
        Plane coordinates, m.
    """
    points = homography @ np.vstack([x, y, np.ones(len(x))])
    return (points[:2] / points[2]).T


def beyond_horizon(x: np.ndarray, y: np.ndarray, homography: np.ndarray, width: int, height: int) -> np.ndarray:
    """Image points beyond the horizon of a homography: on the other side of its horizon line
    from the image's bottom centre (which shows the ground), or on it; there the plane
    position is behind the camera or at infinity.

    Parameters
    ----------
    x, y : arrays of shape (n,)
        Image column and stored-image row, px.
    homography : array of shape (3, 3)
        Image px -> plane m.
    width, height : int
        Image size, px.

    Returns
    -------
    bool ndarray of shape (n,)
    """
    w = homography[2] @ np.vstack([x, y, np.ones(len(x))])
    ground = homography[2] @ np.array([(width - 1) / 2.0, height - 1.0, 1.0])
    return ~(w * np.sign(ground) > 1e-12 * np.abs(ground))


def validate(
    detections: pd.DataFrame,
    model: SyncModel,
    homographies: Mapping[str, np.ndarray],
    *,
    max_gap_ms: float | None = None,
    exposure_ms: Mapping[str, float] | None = None,
    as_shown: bool = False,
    source: str = "detections",
) -> ValidationReport:
    """Cross-camera interpolation errors of fast objects, per ordered camera pair.

    Parameters
    ----------
    detections : DataFrame
        ``camera``, ``frame`` (0-based), ``x``, ``y`` (stored-image px, or as shown with
        ``as_shown``) and optionally an object id ``object`` (or ``id``); without one, all
        detections are one object.
    model : SyncModel
        The synchronisation model.
    homographies : mapping of str to array of shape (3, 3)
        Image px -> plane m, per camera; cameras without one are left out.
    max_gap_ms : float, optional
        Longest time between camera A's bracketing detections, ms; default 2.5 frame
        periods of camera A.
    exposure_ms : mapping of str to float, optional
        Exposure per camera, ms, overriding the model's.
    as_shown : bool
        ``x`` and ``y`` are in the picture a player shows, as the homographies then are
        (:func:`tracking_adapter.restamp.restamp`).
    source : str
        Name of the detections file, for error messages.

    Returns
    -------
    ValidationReport
        Per pair and time model: triples, median / p95 / max plane error (m), skips.

    Examples
    --------
    >>> report = validate(load_detections("puck.csv"), load_model("sync.json"),
    ...                   load_homographies("H.json"))               # doctest: +SKIP
    >>> print(format_report(report))                                  # doctest: +SKIP
    """
    require_columns(detections.columns, ("camera", "frame", "x", "y"), source)
    stamped = restamp(
        detections[["camera", "frame", "x", "y"]], model, exposure_ms=exposure_ms, as_shown=as_shown, source=source
    )
    not_used = stamped["restamp_error"].value_counts().to_dict()
    usable = stamped["restamp_error"].isna().to_numpy().copy()
    id_column = next((name for name in OBJECT_COLUMNS if name in detections.columns), None)
    objects = pd.factorize(detections[id_column])[0] if id_column else np.zeros(len(detections), dtype=np.int64)
    x = pd.to_numeric(detections["x"], errors="coerce").to_numpy(dtype=np.float64)
    cameras = stamped["camera"].astype("str").to_numpy(dtype=object)
    for reason, bad in (
        ("x missing or not a number", ~np.isfinite(x)),
        ("object id missing", objects < 0),
        ("camera without homography", ~np.isin(cameras, list(homographies))),
    ):
        _add(not_used, reason, int(np.count_nonzero(usable & bad)))
        usable &= ~bad
    y_all = pd.to_numeric(stamped["y"], errors="coerce").to_numpy(dtype=np.float64)
    beyond = np.zeros(len(usable), dtype=bool)
    for name in set(cameras[usable]):
        mine = usable & (cameras == name)
        clock = model.camera(name)
        width, height = (clock.height, clock.width) if as_shown and clock.sideways else (clock.width, clock.height)
        beyond[mine] = beyond_horizon(x[mine], y_all[mine], np.asarray(homographies[name]), width, height)
    _add(not_used, "beyond the horizon of its camera's homography", int(np.count_nonzero(beyond)))
    usable &= ~beyond

    instant = (
        "t_center_ms"
        if "t_center_ms" in stamped and not stamped.loc[usable, "t_center_ms"].isna().any()
        else "t_global_ms"
    )
    rows = np.flatnonzero(usable)
    names, objects, x = cameras[rows], objects[rows], x[rows]
    frames = pd.to_numeric(stamped["frame"].iloc[rows]).to_numpy().astype(np.int64)
    y = pd.to_numeric(stamped["y"].iloc[rows]).to_numpy(dtype=np.float64)
    shift = (stamped["t_global_ms"] - stamped[instant]).to_numpy()[rows]  # exposure / 2 or 0
    used = [name for name in model.cameras if name in set(names)]
    plane = np.empty((len(rows), 2))
    times = {time_model: np.empty(len(rows)) for time_model in TIME_MODELS}
    for name in used:
        mine = names == name
        plane[mine] = image_to_plane(x[mine], y[mine], np.asarray(homographies[name]))
        clock = model.camera(name)
        row = clock.stored_row(x[mine], y[mine]) if as_shown else y[mine]
        for time_model in TIME_MODELS:
            times[time_model][mine] = _times(clock, time_model, frames[mine], row) - shift[mine]

    report = ValidationReport(pairs=[], instant=instant, not_used=not_used)
    object_names = pd.factorize(detections[id_column])[1] if id_column else pd.Index(["object"])
    triples = []
    for a in used:
        gap = max_gap_ms if max_gap_ms is not None else default_gap_ms(model, a)
        in_a = names == a
        for b in used:
            if a == b:
                continue
            in_b = names == b
            results = {
                time_model: _pair_stats(
                    objects[in_a], values[in_a], plane[in_a], objects[in_b], values[in_b], plane[in_b], gap
                )
                for time_model, values in times.items()
            }
            report.pairs.append(PairValidation(a, b, float(gap), {name: result[0] for name, result in results.items()}))
            found = results["subframe"][1]
            triples.append(
                pd.DataFrame(
                    {
                        "camera_a": a,
                        "camera_b": b,
                        "object": object_names[found[:, 0].astype(np.int64)],
                        "t_global_ms": found[:, 1],
                        "x_b": found[:, 2],
                        "y_b": found[:, 3],
                        "x_a": found[:, 4],
                        "y_a": found[:, 5],
                        "error_m": np.hypot(found[:, 4] - found[:, 2], found[:, 5] - found[:, 3]),
                    }
                )
            )
    if triples:
        report.triples = pd.concat(triples, ignore_index=True)
    return report


def format_report(report: ValidationReport) -> str:
    """A text table: one line per camera pair, median / p95 / max error (m) per time model."""
    header = f"{'A -> B':<24}{'triples':>8}" + "".join(f"  {title:^26}" for title in TIME_MODELS.values())
    units = f"{'':<24}{'':>8}" + "  {:>8}{:>9}{:>9}".format("median", "p95", "max") * len(TIME_MODELS)
    lines = [
        f"interpolation error on the plane, m (instant: {report.instant}; A's track interpolated at B's detections)",
        header,
        units,
    ]
    for pair in report.pairs:
        name = f"{pair.interpolated} -> {pair.observed}"
        line = f"{name:<24}{pair.stats['subframe'].triples:>8}"
        for time_model in TIME_MODELS:
            stats = pair.stats[time_model]
            line += "  " + "".join(
                f"{_number(value):>{width}}"
                for value, width in ((stats.median_m, 8), (stats.p95_m, 9), (stats.max_m, 9))
            )
        lines.append(line)
    for pair in report.pairs:
        skipped = pair.stats["subframe"].skipped
        if skipped:
            lines.append(
                f"skipped {pair.interpolated} -> {pair.observed} (gap limit "
                f"{pair.max_gap_ms:.1f} ms): " + ", ".join(f"{count} {reason}" for reason, count in skipped.items())
            )
    if report.not_used:
        lines.append(
            "detections not used: " + ", ".join(f"{count} {reason}" for reason, count in report.not_used.items())
        )
    return "\n".join(lines)


def _times(clock: CameraClock, time_model: str, frames: np.ndarray, row: np.ndarray) -> np.ndarray:
    """End-of-exposure times (ms) of detections in stored rows ``row`` under one time model."""
    if time_model == "frame":
        return clock.t_global_ms(frames, np.full(len(frames), (clock.height - 1) / 2))
    if time_model == "no_drift":
        mean_ms = float(np.mean(clock.frame_times_ms))
        clock = replace(clock, alpha=1.0, beta_ms=clock.beta_ms + (clock.alpha - 1) * mean_ms)
    return clock.t_global_ms(frames, row)


def _pair_stats(
    object_a: np.ndarray,
    t_a: np.ndarray,
    plane_a: np.ndarray,
    object_b: np.ndarray,
    t_b: np.ndarray,
    plane_b: np.ndarray,
    max_gap_ms: float,
) -> tuple[ErrorStats, np.ndarray]:
    """Interpolate A's track (times ms, plane m) at B's detections and measure the distance.

    Returns the statistics and the triples, shape (n, 6): object code, B's instant (ms),
    B's plane position and A's interpolated position (m)."""
    errors, skipped, found = [], {}, []
    for obj in np.unique(object_b):
        in_a, in_b = object_a == obj, object_b == obj
        if not in_a.any():
            _add(skipped, "object not seen by A", int(in_b.sum()))
            continue
        instants, observed = t_b[in_b], plane_b[in_b]
        sample = interpolate_track(t_a[in_a], plane_a[in_a], instants, max_gap_ms)
        _add(skipped, "outside A's track", int(np.isin(sample.status, (BEFORE_TRACK, AFTER_TRACK)).sum()))
        _add(skipped, "A's gap over the limit", int((sample.status == GAP_OVER_LIMIT).sum()))
        kept = sample.status == INTERPOLATED
        instants, observed, interpolated = instants[kept], observed[kept], sample.values[kept]
        errors.append(np.linalg.norm(interpolated - observed, axis=1))
        found.append(np.column_stack([np.full(len(instants), obj), instants, observed, interpolated]))
    errors = np.concatenate(errors) if errors else np.empty(0)
    found = np.concatenate(found) if found else np.empty((0, 6))
    if not len(errors):
        return ErrorStats(0, None, None, None, skipped), found
    return ErrorStats(
        len(errors), float(np.median(errors)), float(np.percentile(errors, 95)), float(errors.max()), skipped
    ), found


def _add(counts: dict[str, int], reason: str, count: int) -> None:
    if count:
        counts[reason] = counts.get(reason, 0) + count


def _number(value: float | None) -> str:
    """A distance in m for the table: three decimals, or three digits where that would not
    fit its column (10 km and more)."""
    if value is None:
        return "-"
    return f"{value:.3f}" if abs(value) < 1e4 else f"{value:.3g}"
