"""Linear interpolation of one object's track at given instants: the one interpolation that
``validate`` (a camera's track at another camera's detections) and ``resample`` (every
track at common ticks) share.

An instant gets a value only between two detections of the track (never extrapolated)
that are at most ``max_gap_ms`` apart, or on a detection; elsewhere the value is NaN and the
status says why (:data:`STATUS`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flashsync.errors import NotEnoughDataError
from flashsync.model import SyncModel
from flashsync.timestamps import median_step_ms

#: Why an instant has no value; code 0 (interpolated) has none.
STATUS = ("", "before the track", "after the track", "gap over the limit")
INTERPOLATED, BEFORE_TRACK, AFTER_TRACK, GAP_OVER_LIMIT = range(len(STATUS))
#: Default longest time between the bracketing detections, in frame periods of the camera.
DEFAULT_GAP_FRAMES = 2.5


@dataclass(frozen=True)
class TrackSample:
    """A track interpolated at instants (see :func:`interpolate_track`).

    Attributes
    ----------
    values : float array of shape (n, d)
        Interpolated values; NaN where ``status`` is not 0.
    status : int array of shape (n,)
        Index into :data:`STATUS`.
    nearest_ms : float array of shape (n,)
        Time from each instant to the nearest detection of the track, ms (>= 0).
    """

    values: np.ndarray
    status: np.ndarray
    nearest_ms: np.ndarray


def interpolate_track(
    times_ms: np.ndarray, values: np.ndarray, instants_ms: np.ndarray, max_gap_ms: float
) -> TrackSample:
    """Interpolate a track linearly in time between its two detections that bracket each
    instant.

    Parameters
    ----------
    times_ms : array of shape (m,)
        Instants of the track's detections, ms, in any order, distinct.
    values : array of shape (m, d)
        Their values (image px, plane m, ...).
    instants_ms : array of shape (n,)
        Where to interpolate, ms.
    max_gap_ms : float
        Longest time between the two bracketing detections, ms; a wider gap is refused.

    Returns
    -------
    TrackSample

    Examples
    --------
    >>> sample = interpolate_track(np.array([0.0, 40.0]), np.array([[0.0], [4.0]]),
    ...                            np.array([10.0, 50.0]), max_gap_ms=100.0)
    >>> sample.values[:, 0], sample.status, sample.nearest_ms
    (array([1., nan]), array([0, 2]), array([10., 10.]))
    """
    order = np.argsort(times_ms, kind="stable")
    times, points = np.asarray(times_ms, dtype=np.float64)[order], np.asarray(values, dtype=np.float64)[order]
    instants = np.asarray(instants_ms, dtype=np.float64)
    status = np.full(len(instants), INTERPOLATED)
    result = np.full((len(instants), points.shape[1]), np.nan)
    if not len(times):
        return TrackSample(result, np.full(len(instants), BEFORE_TRACK), np.full(len(instants), np.inf))
    index = np.searchsorted(times, instants)
    nearest = np.minimum(
        np.abs(instants - times[np.maximum(index - 1, 0)]), np.abs(times[np.minimum(index, len(times) - 1)] - instants)
    )
    status[instants < times[0]] = BEFORE_TRACK
    status[(instants > times[-1]) | ((instants == times[-1]) & (len(times) < 2))] = AFTER_TRACK
    inside = np.flatnonzero(status == INTERPOLATED)
    after = np.clip(np.searchsorted(times, instants[inside], side="right"), 1, len(times) - 1)
    gap = times[after] - times[after - 1]
    close = (gap <= max_gap_ms) | (nearest[inside] == 0)  # or on a detection
    status[inside[~close]] = GAP_OVER_LIMIT
    after, inside, gap = after[close], inside[close], gap[close]
    weight = ((instants[inside] - times[after - 1]) / gap)[:, None]
    result[inside] = points[after - 1] + weight * (points[after] - points[after - 1])
    return TrackSample(result, status, nearest)


def default_gap_ms(model: SyncModel, name: str) -> float:
    """:data:`DEFAULT_GAP_FRAMES` frame periods of camera ``name`` (median step), ms of the
    reference clock."""
    clock = model.camera(name)
    if clock.n_frames < 2:
        raise NotEnoughDataError(
            model.named(
                f"camera {clock.name} has {clock.n_frames} frame in the model; give the longest gap between two "
                "detections to interpolate over, or sync a longer video"
            )
        )
    return DEFAULT_GAP_FRAMES * clock.alpha * median_step_ms(clock.frame_times_ms)
