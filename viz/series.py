"""Scalar time series on ``global_time``."""

from __future__ import annotations

import numpy as np
import rerun as rr

from viz.timeline import Timeline


def log_series(
    recording: rr.RecordingStream,
    timeline: Timeline,
    entity: str,
    style: rr.SeriesPoints | rr.SeriesLines,
    t_global_ms: np.ndarray,
    values: np.ndarray,
    *indexes: rr.TimeColumn,
) -> None:
    """Log one series: its style (static) and one scalar per instant.

    Parameters
    ----------
    recording : RecordingStream
    timeline : Timeline
    entity : str
        Entity path of the series.
    style : SeriesPoints or SeriesLines
        Colour, marker or width, and legend name.
    t_global_ms : float array of shape (n,)
        Instants on the global clock, ms.
    values : float array of shape (n,)
        The scalars, in the unit of the series.
    *indexes : TimeColumn
        Further index columns of length n (e.g. a camera's frame timeline).
    """
    recording.log(entity, style, static=True)
    recording.send_columns(
        entity,
        indexes=[timeline.column(t_global_ms), *indexes],
        columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)),
    )
