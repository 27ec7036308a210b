"""Flash events on ``global_time``: a lane per camera and a log of the flashes.

Every event edge has a status: ``matched`` (its event is in the model's events, an inlier
of the solve), ``rejected`` (in the model's events, an outlier) or ``unmatched`` (detected,
but not paired with any other camera's event). Flashes are numbered in time order (flash
0 is the first), whatever their ids in the model file.

``events/<camera>`` (StateChange)
    The camera's lane: from its first frame a grey block, then at each event (its
    leading edge, or its first visible edge) a block named after it -- ``flash 3``,
    ``flash 3 rejected``, ``unmatched`` -- that lasts until the camera's next event or its
    last frame. The same flash has the same fill in every lane, so a flash seen by every
    camera is a column of blocks starting at one instant.
``events/log`` (TextLog)
    Two lines at the start of the recordings saying what ``global_time`` 0 is; a line per
    matched event at its flash's time (camera, frame, row, residual in ms), in the
    camera's colour, rejected ones in red with their event number (level WARN); a line per
    unmatched event (level DEBUG).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import rerun as rr

from flashsync.model import SyncModel
from viz.palette import FLASH_FILLS, LANE_FILLS, STATUS_COLORS, camera_colors
from viz.timeline import Timeline, readout_end_ms, readout_start_ms

ROOT = "events"
LOG_ENTITY = f"{ROOT}/log"
STATUSES = ("matched", "rejected", "unmatched")
BEFORE_FIRST_EVENT = "recording"
"""State of a lane from the camera's first frame to its first event (light grey)."""
LOG_STEP_MS = 1.0
"""The flash log's lines are at the next whole ms of ``global_time`` after their flash, so
that its time column fits; the videos still show the frames of the flash there (a frame
ends with blanking rows, about a millisecond or more)."""
_COLUMNS = ["camera", "event", "frame", "row", "edge", "band", "flash", "status", "t_global_ms"]


def lane_entity(camera: str) -> str:
    """Entity path of ``camera``'s event lane."""
    return f"{ROOT}/{rr.escape_entity_path_part(camera)}"


def flash_instants_ms(model: SyncModel) -> np.ndarray:
    """The global time (ms) of each of ``model.events``, shape (n,): its flash's
    (``t_global_ms``); where the solve placed no flash (every event of it rejected), the
    earliest of the flash's events on their cameras' clocks."""
    events = model.events
    own = np.full(len(events), np.nan)
    frames = events["frame"].to_numpy(dtype=np.int64)
    rows = events["row"].to_numpy(dtype=np.float64)
    for name, index in events.groupby("camera", sort=False).indices.items():
        own[index] = model.camera(name).t_global_ms(frames[index], rows[index])
    earliest = pd.Series(own, index=events.index).groupby(events["flash"]).transform("min")
    fitted = events["t_global_ms"].to_numpy(dtype=np.float64)
    return np.where(np.isfinite(fitted), fitted, earliest.to_numpy())


def flash_numbers(model: SyncModel) -> dict[int, int]:
    """Model flash id -> flash number in time order (0 = the earliest flash)."""
    instants = pd.Series(flash_instants_ms(model), index=model.events.index)
    times = instants.groupby(model.events["flash"]).min().sort_values(kind="stable")
    return {int(flash): number for number, flash in enumerate(times.index)}


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
        ``detected``), ``flash`` (number in time order, see :func:`flash_numbers`; NA if
        unmatched), ``status``, and ``t_global_ms``:
        ``model.camera(camera).t_global_ms(frame, row)``, ms.
    """
    matched = model.events.reindex(columns=["flash", "camera", "event", "frame", "row", "inlier"])
    matched = matched.assign(flash=matched["flash"].map(flash_numbers(model)))
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


def lane_state(flash: object, status: str) -> str:
    """The state an event starts in its lane: ``flash 3``, ``flash 3 rejected``, ``unmatched``."""
    if status == "unmatched":
        return "unmatched"
    return f"flash {flash}" + (" rejected" if status == "rejected" else "")


def lane_events(events: pd.DataFrame) -> pd.DataFrame:
    """One row per event of :func:`event_table`: its lane state and start time, in time order.

    Returns
    -------
    DataFrame
        ``camera, event, state, t_global_ms`` (the leading edge's time, or the earliest
        edge's where the leading edge is not in the table), sorted by time.
    """
    leading_first = events.assign(_trailing=events["edge"].eq("trailing").fillna(False).astype(bool))
    first = (
        leading_first.sort_values(["_trailing", "t_global_ms"], kind="stable")
        .groupby(["camera", "event"], sort=False)
        .head(1)
    )
    states = [lane_state(flash, status) for flash, status in zip(first["flash"], first["status"])]
    return (
        first.assign(state=states)[["camera", "event", "state", "t_global_ms"]]
        .sort_values("t_global_ms", kind="stable")
        .reset_index(drop=True)
    )


def log_events(recording: rr.RecordingStream, model: SyncModel, events: pd.DataFrame, timeline: Timeline) -> np.ndarray:
    """Log the event lanes and the flash log.

    Parameters
    ----------
    recording : RecordingStream
    model : SyncModel
        Its cameras give the lanes, its matched events the log lines.
    events : DataFrame
        :func:`event_table`.
    timeline : Timeline

    Returns
    -------
    ndarray
        The instants of the flash log's event lines (``t_global_ms``, ms), in time order.
    """
    lanes = lane_events(events)
    n_flashes = len(flash_numbers(model))
    configuration = _lane_configuration(n_flashes)
    for name, camera in model.cameras.items():
        mine = lanes[lanes["camera"] == name]
        start = readout_start_ms(camera, [0])[0]
        end = readout_end_ms(camera, [camera.n_frames - 1])[0]
        times = np.concatenate([[start], mine["t_global_ms"].to_numpy(), [end]])
        states = [BEFORE_FIRST_EVENT, *mine["state"], ""]  # "" ends the lane
        recording.log(lane_entity(name), configuration, static=True)
        recording.send_columns(
            lane_entity(name), indexes=[timeline.column(times)], columns=rr.StateChange.columns(state=states)
        )
    lines = _event_lines(model, events)
    instants = timeline.round_up(lines["t_global_ms"].to_numpy(), LOG_STEP_MS)
    recording.send_columns(
        LOG_ENTITY,
        indexes=[timeline.column(instants)],
        columns=rr.TextLog.columns(
            text=lines["text"].tolist(), level=lines["level"].tolist(), color=lines["color"].tolist()
        ),
    )
    return instants


def log_start(recording: rr.RecordingStream, model: SyncModel, timeline: Timeline) -> None:
    """Log what ``global_time`` 0 is: the recording's description, and two log lines at 0.

    Logged before anything else on ``global_time``, so that the viewer opens at 0.
    """
    recording.send_recording_name(f"flashsync: {', '.join(model.cameras)}")
    recording.send_property("description", rr.TextDocument(timeline.description(model)))
    sign = "-" if timeline.origin_ms < 0 else "+"
    texts = [
        f"start of the recordings: {timeline.first_camera}'s first frame",
        f"t_global_ms = time {sign} {abs(timeline.origin_ms):.3f} ms ({model.reference}'s clock)",
    ]
    recording.send_columns(
        LOG_ENTITY,
        indexes=[timeline.column(np.full(2, timeline.origin_ms))],
        columns=rr.TextLog.columns(text=texts, level=["INFO", "INFO"]),
    )


def _lane_configuration(n_flashes: int) -> rr.StateConfiguration:
    """Fills and labels of the lane states: each flash its fill, light grey before the first
    event."""
    values, labels, colors = [BEFORE_FIRST_EVENT], [BEFORE_FIRST_EVENT], [LANE_FILLS["before"]]
    for flash in range(n_flashes):
        values += [lane_state(flash, "matched"), lane_state(flash, "rejected")]
        labels += [lane_state(flash, "matched"), f"flash {flash} REJECTED"]
        colors += [FLASH_FILLS[flash % len(FLASH_FILLS)], LANE_FILLS["rejected"]]
    values.append(lane_state(None, "unmatched"))
    labels.append("unmatched")
    colors.append(LANE_FILLS["unmatched"])
    return rr.StateConfiguration(values=values, labels=labels, colors=colors)


def _event_lines(model: SyncModel, events: pd.DataFrame) -> pd.DataFrame:
    """``t_global_ms, text, level, color`` of each event's log line, in time order.

    A matched event's line is at its flash's time (the earliest of its events), so the
    lines of a flash sit together, in camera order.
    """
    colors = camera_colors(model.cameras)
    matched = model.events.reindex(columns=["flash", "camera", "event", "frame", "row", "residual_ms", "inlier"])
    numbers = flash_numbers(model)
    flash_ms = pd.Series(flash_instants_ms(model), index=matched.index).groupby(matched["flash"]).transform("min")
    camera_order = {name: i for i, name in enumerate(model.cameras)}
    rows = []
    for e, t_ms in zip(matched.itertuples(), flash_ms):
        rejected = not e.inlier
        rows.append(
            (
                t_ms,
                numbers[e.flash],
                camera_order.get(e.camera, 0),
                f"flash {numbers[e.flash]}  {e.camera}  frame {e.frame}  row {e.row:.1f}  "
                f"{e.residual_ms:+.4f} ms" + (f"  REJECTED (event {e.event})" if rejected else ""),
                "WARN" if rejected else "INFO",
                STATUS_COLORS["rejected"] if rejected else colors[e.camera],
            )
        )
    unmatched = events[events["status"] == "unmatched"]
    for (camera, event), group in unmatched.groupby(["camera", "event"], sort=False):
        edges = ", ".join(f"{g.edge} frame {g.frame} row {g.row:.1f}" for g in group.itertuples())
        rows.append(
            (
                group["t_global_ms"].min(),
                -1,
                camera_order.get(camera, 0),
                f"unmatched  {camera} event {event}  {group['band'].iloc[0]}: {edges}",
                "DEBUG",
                STATUS_COLORS["unmatched"],
            )
        )
    table = pd.DataFrame(rows, columns=["t_global_ms", "flash", "camera", "text", "level", "color"])
    return table.sort_values(["t_global_ms", "flash", "camera"], kind="stable")
