"""Tracked objects: on each camera's frames, and in the common plane at their global times.

An image detection ``(x, y)`` (px) is projected into the plane (metres, see
:mod:`viz.plane`) through its camera's homography (image px -> plane m,
:func:`tracking_adapter.validate.image_to_plane`). Each camera's observations of an
object are a point series in the camera's colour at the detection's time: ``t_center_ms``
(mid-exposure, what a blurred centroid corresponds to) where the table has it, else
``t_global_ms`` (end of exposure of the detection's row). With good synchronisation the
cameras' points of a moving object lie on one curve; the blueprint's plane view shows the
last :data:`viz.blueprint.TRAIL_S` seconds of them.

Detections without an object id column are one object named :data:`NO_OBJECT`, as in
``flashsync validate``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
import rerun as rr

from flashsync.io.detections import require_columns
from flashsync.model import CameraClock, SyncModel
from tracking_adapter.validate import OBJECT_COLUMNS, image_to_plane
from viz.palette import Color, camera_colors
from viz.plane import PLANE
from viz.timeline import Timeline, frame_timeline
from viz.video import PIXEL_CENTRE, camera_entity

NO_OBJECT = "object"
POINT_RADIUS_UI = 4.0
"""Radius of a plane observation, ui points (the same at any zoom)."""


def entity_part(name: object) -> str:
    """``name`` (a camera or object id) as one escaped entity path part."""
    return rr.escape_entity_path_part(str(name))


def observation_entity(camera: str, obj: object) -> str:
    """Entity path of ``camera``'s plane observations of object ``obj``."""
    return f"{PLANE}/observations/{entity_part(camera)}/{entity_part(obj)}"


def detections_entity(camera: str) -> str:
    """Entity path of the detections drawn on ``camera``'s frames."""
    return f"{camera_entity(camera)}/detections"


def stamped(detections: pd.DataFrame, model: SyncModel, source: str = "restamped detections") -> pd.DataFrame:
    """The detections restamp gave a global time, with ``object`` and ``t_plane_ms``.

    Rows without a finite ``t_global_ms``, ``x`` or ``y`` (restamp says why in
    ``restamp_error``), or not on a frame of a camera of ``model`` (a whole number from 0
    to its frame count - 1) are left out. ``object`` is the object id column (``object`` or
    ``id``, as in :mod:`tracking_adapter.validate`), or :data:`NO_OBJECT` for all rows
    without one; ``t_plane_ms`` is ``t_center_ms`` where finite, else ``t_global_ms``.
    ``source`` names the table in errors.
    """
    require_columns(detections.columns, ("camera", "frame", "x", "y", "t_global_ms"), source)
    numbers = detections[["x", "y", "t_global_ms"]].apply(pd.to_numeric, errors="coerce")
    frame = pd.to_numeric(detections["frame"], errors="coerce")
    n_frames = detections["camera"].astype("str").map({name: c.n_frames for name, c in model.cameras.items()})
    on_a_frame = (frame % 1 == 0) & (frame >= 0) & (frame < n_frames)
    shown = (np.isfinite(numbers).all(axis=1) & on_a_frame).to_numpy()
    table = detections[shown]
    id_column = next((name for name in OBJECT_COLUMNS if name in table), None)
    objects = table[id_column] if id_column else NO_OBJECT
    center = (
        pd.to_numeric(table["t_center_ms"], errors="coerce")
        if "t_center_ms" in table
        else pd.Series(np.nan, index=table.index)
    )
    return table.assign(
        object=objects,
        frame=frame[shown].to_numpy(dtype=np.int64),
        t_plane_ms=center.where(np.isfinite(center), table["t_global_ms"]),
    )


def project(detections: pd.DataFrame, homographies: Mapping[str, np.ndarray]) -> pd.DataFrame:
    """The :func:`stamped` detections of cameras with a homography, with their plane position.

    Returns
    -------
    DataFrame
        Those rows, in their order, plus ``plane_x, plane_y`` (m).
    """
    rows = detections[detections["camera"].isin(list(homographies))]
    plane = np.full((len(rows), 2), np.nan)
    for name, index in rows.groupby("camera", sort=False).indices.items():
        plane[index] = image_to_plane(
            rows["x"].to_numpy(dtype=np.float64)[index],
            rows["y"].to_numpy(dtype=np.float64)[index],
            np.asarray(homographies[name]),
        )
    return rows.assign(plane_x=plane[:, 0], plane_y=plane[:, 1])


def log_frame_detections(
    recording: rr.RecordingStream, timeline: Timeline, camera: CameraClock, detections: pd.DataFrame, color: Color
) -> None:
    """Draw ``camera``'s detections on the frames that hold them, labelled by object.

    A detection ``(x, y)`` (px, pixel centres at integers) is drawn at ``(x, y) +``
    :data:`viz.video.PIXEL_CENTRE` in Rerun's image coordinates.

    Parameters
    ----------
    recording : RecordingStream
    timeline : Timeline
    camera : CameraClock
    detections : DataFrame
        This camera's rows of :func:`stamped`; ``x, y`` in px.
    color : (int, int, int)
        The camera's colour, RGB.
    """
    if detections.empty:
        return
    indexes, order, lengths = timeline.frame_batches(camera, detections["frame"].to_numpy())
    ordered = detections.iloc[order]
    positions = ordered[["x", "y"]].to_numpy(dtype=np.float64) + PIXEL_CENTRE
    columns = rr.Points2D.columns(
        positions=positions, colors=[color] * len(ordered), labels=ordered["object"].astype(str).tolist()
    )
    recording.send_columns(detections_entity(camera.name), indexes=indexes, columns=columns.partition(lengths))


def log_observations(
    recording: rr.RecordingStream, timeline: Timeline, model: SyncModel, projected: pd.DataFrame
) -> None:
    """Log each camera's detections of each object in the plane, at ``t_plane_ms``.

    Parameters
    ----------
    recording : RecordingStream
    timeline : Timeline
    model : SyncModel
        Gives the cameras' colours.
    projected : DataFrame
        :func:`project`'s table.
    """
    colors = camera_colors(model.cameras)
    for (name, obj), track in projected.groupby(["camera", "object"], sort=False):
        points = track[["plane_x", "plane_y"]].to_numpy(dtype=np.float64)
        recording.send_columns(
            observation_entity(name, obj),
            indexes=[
                timeline.column(track["t_plane_ms"].to_numpy()),
                rr.TimeColumn(frame_timeline(name), sequence=track["frame"].to_numpy()),
            ],
            columns=rr.Points2D.columns(
                positions=points,
                colors=[colors[name]] * len(points),
                radii=[rr.Radius.ui_points(POINT_RADIUS_UI)] * len(points),
            ),
        )
