"""Flash events on ``global_time``: a raster per camera and a log of the flashes.

Every event edge has a status: ``matched`` (its event is in the model's events, an inlier
of the solve), ``rejected`` (in the model's events, an outlier) or ``unmatched`` (detected,
but not paired with any other camera's event). The raster is a time series with one lane
per camera (lane = index of the camera in the model, reference first); each edge is a
point in its camera's lane at its global time, styled by status. The log has one line per
flash, at the flash's global time, naming each camera's event of that flash and its
residual -- the link between the cameras -- and one line per unmatched event.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import rerun as rr

from flashsync.model import SyncModel
from viz.palette import camera_colors, status_style
from viz.series import log_series
from viz.timeline import frame_timeline, global_time_column

ROOT = "events"
LOG_ENTITY = f"{ROOT}/log"
STATUSES = ("matched", "rejected", "unmatched")
_COLUMNS = ["camera", "event", "frame", "row", "edge", "band", "flash", "status", "t_global_ms"]


def raster_entity(camera: str, status: str) -> str:
    """Entity path of ``camera``'s events of ``status`` in the raster."""
    return f"{ROOT}/{rr.escape_entity_path_part(camera)}/{status}"


def event_table(model: SyncModel, detected: pd.DataFrame | None = None) -> pd.DataFrame:
    """Every event edge with its status and its global time on its camera's clock.

    Parameters
    ----------
    model : SyncModel
        Its ``events`` are the matched events (``flash, camera, event, frame, row,
        inlier, ...``), one synchronisation edge each.
    detected : DataFrame, optional
        The ``detect`` table (``camera, event, frame, row, edge, band, ...``), one row per
        edge. Given, the table has all its edges, each with the status of its event;
        else only the model's synchronisation edges.

    Returns
    -------
    DataFrame
        ``camera, event, frame, row`` (stored-image row, px), ``edge, band`` (NA without
        ``detected``), ``flash`` (integer id, NA if unmatched), ``status``, and
        ``t_global_ms``: ``model.camera(camera).t_global_ms(frame, row)``, ms.
    """
    matched = model.events.reindex(columns=["flash", "camera", "event", "frame", "row", "inlier"])
    if detected is None:
        table = matched.assign(edge=pd.NA, band=pd.NA)
    else:
        table = detected[["camera", "event", "frame", "row", "edge", "band"]].merge(
            matched[["camera", "event", "flash", "inlier"]], on=["camera", "event"], how="left"
        )
    known = table["inlier"].notna().to_numpy()
    inlier = table["inlier"].where(known, False).astype(bool).to_numpy()
    frames = table["frame"].to_numpy(dtype=np.int64)
    rows = table["row"].to_numpy(dtype=np.float64)
    t_global_ms = np.full(len(table), np.nan)
    for name, index in table.groupby("camera", sort=False).indices.items():
        t_global_ms[index] = model.camera(name).t_global_ms(frames[index], rows[index])
    status = np.where(known, np.where(inlier, "matched", "rejected"), "unmatched")
    return table.assign(frame=frames, flash=table["flash"].astype("Int64"), status=status, t_global_ms=t_global_ms)[
        _COLUMNS
    ]


def log_events(recording: rr.RecordingStream, model: SyncModel, events: pd.DataFrame) -> None:
    """Log the event raster and the flash log.

    Parameters
    ----------
    recording : RecordingStream
    model : SyncModel
        Its matched events make the flash lines of the log.
    events : DataFrame
        :func:`event_table`.
    """
    colors = camera_colors(model.cameras)
    for lane, name in enumerate(model.cameras):
        for status in STATUSES:
            rows = events[(events["camera"] == name) & (events["status"] == status)]
            if rows.empty:
                continue
            color, marker = status_style(status, colors[name])
            log_series(
                recording,
                raster_entity(name, status),
                rr.SeriesPoints(colors=color, markers=marker, names=f"{name} {status}", marker_sizes=4.0),
                rows["t_global_ms"].to_numpy(),
                np.full(len(rows), float(lane)),
                rr.TimeColumn(frame_timeline(name), sequence=rows["frame"].to_numpy()),
            )
    matched = model.events.reindex(columns=["flash", "camera", "frame", "row", "t_global_ms", "residual_ms", "inlier"])
    lines = _flash_lines(matched) + _unmatched_lines(events[events["status"] == "unmatched"])
    if lines:
        lines.sort(key=lambda line: line[0])
        times, texts, levels = zip(*lines)
        recording.send_columns(
            LOG_ENTITY,
            indexes=[global_time_column(np.array(times))],
            columns=rr.TextLog.columns(text=texts, level=levels),
        )


def _flash_lines(matched: pd.DataFrame) -> list[tuple[float, str, str]]:
    """(time, text, level) of each flash: its cameras' events and residuals."""
    lines = []
    for flash, group in matched.groupby("flash", sort=True):
        parts = [
            f"{e.camera} frame {e.frame} row {e.row:.1f} residual {e.residual_ms:+.4f} ms"
            + ("" if e.inlier else " REJECTED")
            for e in group.itertuples()
        ]
        lines.append(
            (
                group["t_global_ms"].min(),
                f"flash {flash}: " + "; ".join(parts),
                "INFO" if group["inlier"].all() else "WARN",
            )
        )
    return lines


def _unmatched_lines(unmatched: pd.DataFrame) -> list[tuple[float, str, str]]:
    """(time, text, level) of each unmatched event: its band and edges."""
    lines = []
    for (camera, event), group in unmatched.groupby(["camera", "event"], sort=False):
        edges = ", ".join(f"{e.edge} edge frame {e.frame} row {e.row:.1f}" for e in group.itertuples())
        lines.append(
            (
                group["t_global_ms"].min(),
                f"{camera} event {event}: {group['band'].iloc[0]} band, {edges}; unmatched",
                "DEBUG",
            )
        )
    return lines
