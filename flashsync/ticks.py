"""Common instants on the global clock, and the frame and row each camera exposes at them.

A tick is an instant ``t_global_ms`` on the reference camera's clock. At a tick a camera
exposes exactly one stored row of one frame: the row whose exposure *ends* at the tick
(DESIGN.md, time convention), given by :meth:`~flashsync.model.CameraClock.locate` with
the drift warp and the readout direction of an upside-down camera. Where no visible row
ends its exposure at the tick, the reason is one of :data:`REASONS`:

``before the recording``
    The tick precedes the first row of the camera's first frame.
``after the recording``
    The tick follows the last row of its last frame.
``vertical blanking``
    The tick falls after a frame's last visible row and before the next frame's first
    (the hidden rows).
``dropped frame``
    The tick falls on a visible row of a frame the camera did not deliver. A gap between
    consecutive frame starts longer than 1.5 frame periods (the median step between frame
    starts) holds ``round(gap / period) - 1`` missing frames, spread evenly over the gap;
    a tick on one of their visible rows is in a dropped frame, a tick in their hidden rows
    in the vertical blanking.

Ticks are ``start_ms + k * 1000 / rate_hz`` for ``k = 0, 1, ...`` while before
``end_ms``: the end is exclusive, so 10 000 to 14 000 ms at 25 Hz is 100 ticks. Without a
start, the grid's phase is chosen so that the most ticks meet a visible row
(:func:`model_ticks_ms`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from flashsync.errors import InputError
from flashsync.model import CameraClock, SyncModel

#: Why a camera shows no row at a tick; code 0 (located) has no reason.
REASONS = ("", "before the recording", "after the recording", "vertical blanking", "dropped frame")
LOCATED, BEFORE, AFTER, BLANKING, DROPPED = range(len(REASONS))
#: A gap between frame starts longer than this many frame periods holds dropped frames.
DROP_GAP_PERIODS = 1.5
#: Most ticks one call makes (a guard against a mistyped rate).
MAX_TICKS = 50_000_000
#: Phases of the default tick grid tried within one tick period, and the ticks scored.
GRID_PHASES = 16
PHASE_PROBES = 20_000


def tick_times_ms(rate_hz: float, start_ms: float, end_ms: float) -> np.ndarray:
    """Instants ``start_ms + k * 1000 / rate_hz`` before ``end_ms`` (exclusive), ms.

    Parameters
    ----------
    rate_hz : float
        Ticks per second, > 0.
    start_ms, end_ms : float
        First tick and the exclusive end, global clock, ms; ``end_ms > start_ms``.

    Returns
    -------
    ndarray of shape (n_ticks,)

    Examples
    --------
    >>> len(tick_times_ms(25.0, 10_000.0, 14_000.0))
    100
    """
    if not (math.isfinite(start_ms) and math.isfinite(end_ms)):
        raise InputError(f"ticks from {start_ms} to {end_ms} ms: give finite times in ms")
    if not end_ms > start_ms:
        raise InputError(
            f"{end_ms}: the end of the ticks is not after their start {start_ms}; give an end "
            "after the start (ms on the global clock)",
            parameter="end_ms",
        )
    return start_ms + np.arange(_tick_count(rate_hz, start_ms, end_ms)) * tick_period_ms(rate_hz)


def _tick_count(rate_hz: float, start_ms: float, end_ms: float) -> int:
    """How many ticks lie from ``start_ms`` to ``end_ms`` (exclusive, ms; none where the end
    is not after the start), or a one-line error for more than :data:`MAX_TICKS`."""
    ticks = (end_ms - start_ms) / tick_period_ms(rate_hz) - 1e-6  # a tick at the end is left out
    if ticks > MAX_TICKS:
        raise InputError(
            f"{rate_hz}: {ticks:.3g} ticks from {start_ms} to {end_ms} ms at {rate_hz} Hz is more "
            f"than {MAX_TICKS}; lower the rate or give a shorter span",
            parameter="rate_hz",
        )
    return max(math.ceil(ticks), 0)


def tick_period_ms(rate_hz: float) -> float:
    """``1000 / rate_hz``, ms, or a one-line error unless the rate is a positive number whose
    period is finite."""
    if not (math.isfinite(rate_hz) and rate_hz > 0 and math.isfinite(1000.0 / rate_hz)):
        raise InputError(
            f"{rate_hz}: the rate must be a positive number of ticks per second, e.g. 100", parameter="rate_hz"
        )
    return 1000.0 / rate_hz


def model_ticks_ms(
    model: SyncModel,
    rate_hz: float,
    start_ms: float | None = None,
    end_ms: float | None = None,
    cameras: Sequence[str] | None = None,
) -> np.ndarray:
    """Ticks over the span covered by any camera of ``model``, or over a given span.

    Without ``start_ms`` the ticks lie on the grid ``k * 1000 / rate_hz + phase`` (ms,
    global clock) from the first row of the earliest camera's first frame on, with the
    phase (one of :data:`GRID_PHASES` steps of the tick period) at which the most (tick,
    camera) pairs land on a visible row: where the rate is a multiple of a camera's frame
    rate the same few instants of its frame recur, and a grid that put one of them in the
    vertical blanking would lose that share of the ticks (a 50 fps camera half of them at
    100 Hz). The phase depends on the model and rate only, so runs at one rate share their
    instants. Without ``end_ms`` the end is the last row of the latest camera's last frame
    (exclusive). ``cameras`` limits those to some of the model's cameras (default: all).

    Returns
    -------
    ndarray of shape (n_ticks,)
        Global clock, ms (:func:`tick_times_ms`).
    """
    first, last = recording_span_ms(model, cameras)
    if start_ms is None:
        step_ms = tick_period_ms(rate_hz)
        start_ms = math.ceil(first / step_ms - 1e-6) * step_ms
        _tick_count(rate_hz, start_ms, last)  # too many ticks: one error line before the phase search
        start_ms += _best_phase_ms(model, cameras, start_ms, last, step_ms)
    elif end_ms is None and not start_ms < last:
        raise InputError(
            f"{start_ms}: the first tick is not before the end of the recordings "
            f"({last:.3f} ms on the global clock); give an earlier start",
            parameter="start_ms",
        )
    return tick_times_ms(rate_hz, start_ms, last if end_ms is None else end_ms)


def _best_phase_ms(
    model: SyncModel, cameras: Sequence[str] | None, start_ms: float, end_ms: float, step_ms: float
) -> float:
    """The offset (ms, one of :data:`GRID_PHASES` in ``[0, step_ms)``) of a tick grid from
    ``start_ms`` at which the most (tick, camera) pairs are located, scored on at most
    :data:`PHASE_PROBES` ticks spread over the span; the smallest offset on a tie."""
    count = max(math.ceil((end_ms - start_ms) / step_ms), 1)
    probes = start_ms + np.unique(np.linspace(0, count - 1, min(count, PHASE_PROBES)).astype(np.int64)) * step_ms
    clocks = [model.camera(name) for name in (cameras or model.cameras)]
    offsets = np.arange(GRID_PHASES) * step_ms / GRID_PHASES
    located = [
        sum(int(np.count_nonzero(locate_ticks(clock, probes + offset)[2] == LOCATED)) for clock in clocks)
        for offset in offsets
    ]
    return float(offsets[int(np.argmax(located))])


def recording_span_ms(model: SyncModel, cameras: Sequence[str] | None = None) -> tuple[float, float]:
    """From the first row of the earliest camera's first frame to the last row of the
    latest camera's last frame, global clock, ms: the span covered by any camera (of
    ``cameras``; default all)."""
    starts, ends = [], []
    for clock in (model.camera(name) for name in (cameras or model.cameras)):
        first, last = clock.frame_start_ms(clock.frame_times_ms[[0, -1]])
        starts.append(first)
        ends.append(last + (clock.height - 1) * clock.row_time_ms)
    return float(min(starts)), float(max(ends))


def locate_ticks(clock: CameraClock, ticks_ms: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The frame and stored row of one camera whose exposure ends at each tick.

    Parameters
    ----------
    clock : CameraClock
        The camera.
    ticks_ms : array of shape (n,)
        Instants on the global clock, ms.

    Returns
    -------
    frame : int64 array of shape (n,)
        0-based frame (presentation order) where located, else the last frame started
        before the tick (-1 before the recording).
    row : float array of shape (n,)
        Stored-image row (top = 0, sub-row), NaN where not located.
    reason : int array of shape (n,)
        Index into :data:`REASONS`; 0 where located.
    """
    ticks = np.asarray(ticks_ms, dtype=np.float64)
    frame, row = clock.locate(ticks)
    reason = np.where(np.isnan(row), BLANKING, LOCATED)
    reason[frame < 0] = BEFORE
    reason[(frame == clock.n_frames - 1) & np.isnan(row)] = AFTER
    starts = clock.frame_start_ms(clock.frame_times_ms)
    inside = np.flatnonzero(reason == BLANKING)
    if len(starts) > 1 and inside.size:
        gaps = np.diff(starts)
        period = float(np.median(gaps))
        f = frame[inside]
        slots = np.maximum(np.round(gaps[f] / period), 1.0)
        slot_ms = gaps[f] / slots
        since = ticks[inside] - starts[f]
        missing = np.floor(since / slot_ms)
        readout = (since - missing * slot_ms) / clock.row_time_ms
        dropped = (gaps[f] > DROP_GAP_PERIODS * period) & (missing >= 1) & (readout <= clock.height - 1)
        reason[inside[dropped]] = DROPPED
    return frame.astype(np.int64), row, reason


def frame_table(model: SyncModel, ticks_ms: np.ndarray) -> pd.DataFrame:
    """Which frame and row of every camera is exposed at each tick.

    Parameters
    ----------
    model : SyncModel
        The synchronisation model.
    ticks_ms : array of shape (n_ticks,)
        Instants on the global clock, ms (:func:`tick_times_ms`).

    Returns
    -------
    DataFrame
        One row per (tick, camera), ticks in order and cameras in model order:
        ``t_global_ms`` (float), ``camera`` (str), ``frame`` (Int64, 0-based, missing
        where not located), ``row`` (float, stored-image row whose exposure ends at the
        tick, NaN where not located) and ``reason`` (str, empty where located, else one of
        :data:`REASONS`).

    Examples
    --------
    >>> table = frame_table(load_model("sync.json"), tick_times_ms(100.0, 0.0, 1000.0))  # doctest: +SKIP
    """
    ticks = np.asarray(ticks_ms, dtype=np.float64)
    names = list(model.cameras)
    frames = np.empty((len(ticks), len(names)), dtype=np.int64)
    rows = np.empty((len(ticks), len(names)))
    reasons = np.empty((len(ticks), len(names)), dtype=np.int64)
    for column, name in enumerate(names):
        frames[:, column], rows[:, column], reasons[:, column] = locate_ticks(model.cameras[name], ticks)
    frame = pd.array(frames.ravel(), dtype="Int64")
    frame[reasons.ravel() != LOCATED] = pd.NA
    return pd.DataFrame(
        {
            "t_global_ms": np.repeat(ticks, len(names)),
            "camera": pd.array(np.tile(np.array(names, dtype=object), len(ticks)), dtype="str"),
            "frame": frame,
            "row": rows.ravel(),
            "reason": pd.array(np.array(REASONS, dtype=object)[reasons.ravel()], dtype="str"),
        }
    )
