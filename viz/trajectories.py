"""Tracked objects: on each camera's frames, and in the common plane at their global times.

The plane is the rink in metres (``z = 0`` the ice, ``z`` up). An image detection
``(x, y)`` (px) is projected into it through its camera's homography (image px -> plane
m, :func:`tracking_adapter.validate.image_to_plane`). Each camera's observations of an
object are a point series in the camera's colour at the detection's time: ``t_center_ms``
(mid-exposure, what a blurred centroid corresponds to) where the table has it, else
``t_global_ms`` (end of exposure of the detection's row). With good synchronisation the
cameras' points of a moving object lie on one curve; the blueprint's 3D view shows the
last second of them.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
import rerun as rr

from flashsync.model import CameraClock, SyncModel
from tracking_adapter.formats import require_columns
from tracking_adapter.validate import OBJECT_COLUMNS, image_to_plane
from viz.palette import Color, camera_colors
from viz.timeline import frame_batches, frame_timeline, global_time_column
from viz.video import PIXEL_CENTRE, camera_entity

PLANE = "plane"
RINK_ENTITY = f"{PLANE}/rink"
RINK_CORNER_RADIUS_M = 8.5
_NO_OBJECT = "detections"


def entity_part(name: object) -> str:
    """``name`` (a camera or object id) as one escaped entity path part."""
    return rr.escape_entity_path_part(str(name))


def observation_entity(camera: str, obj: object) -> str:
    """Entity path of ``camera``'s plane observations of object ``obj``."""
    return f"{PLANE}/{entity_part(camera)}/{entity_part(obj)}"


def detections_entity(camera: str) -> str:
    """Entity path of the detections drawn on ``camera``'s frames."""
    return f"{camera_entity(camera)}/detections"


def stamped(detections: pd.DataFrame) -> pd.DataFrame:
    """The detections restamp gave a global time, with ``object`` and ``t_plane_ms``.

    Rows without a finite ``t_global_ms``, ``x`` or ``y`` (restamp says why in
    ``restamp_error``) are left out. ``object`` is the object id column (``object`` or
    ``id``, as in :mod:`tracking_adapter.validate`), or one object for all rows without
    one; ``t_plane_ms`` is ``t_center_ms`` where finite, else ``t_global_ms``.
    """
    require_columns(detections.columns, ("camera", "frame", "x", "y", "t_global_ms"), "restamped detections")
    numbers = detections[["x", "y", "t_global_ms"]].apply(pd.to_numeric, errors="coerce")
    table = detections[np.isfinite(numbers).all(axis=1)]
    id_column = next((name for name in OBJECT_COLUMNS if name in table), None)
    objects = table[id_column] if id_column else _NO_OBJECT
    center = (
        pd.to_numeric(table["t_center_ms"], errors="coerce")
        if "t_center_ms" in table
        else pd.Series(np.nan, index=table.index)
    )
    return table.assign(
        object=objects,
        frame=table["frame"].astype(np.int64),
        t_plane_ms=center.where(np.isfinite(center), table["t_global_ms"]),
    )


def log_frame_detections(
    recording: rr.RecordingStream, camera: CameraClock, detections: pd.DataFrame, color: Color
) -> None:
    """Draw ``camera``'s detections on the frames that hold them, labelled by object.

    A detection ``(x, y)`` (px, pixel centres at integers) is drawn at ``(x, y) +``
    :data:`viz.video.PIXEL_CENTRE` in Rerun's image coordinates.

    Parameters
    ----------
    recording : RecordingStream
    camera : CameraClock
    detections : DataFrame
        This camera's rows of :func:`stamped`; ``x, y`` in px.
    color : (int, int, int)
        The camera's colour, RGB.
    """
    if detections.empty:
        return
    indexes, order, lengths = frame_batches(camera, detections["frame"].to_numpy())
    ordered = detections.iloc[order]
    positions = ordered[["x", "y"]].to_numpy(dtype=np.float64) + PIXEL_CENTRE
    columns = rr.Points2D.columns(
        positions=positions, colors=[color] * len(ordered), labels=ordered["object"].astype(str).tolist()
    )
    recording.send_columns(detections_entity(camera.name), indexes=indexes, columns=columns.partition(lengths))


def log_observations(
    recording: rr.RecordingStream, model: SyncModel, detections: pd.DataFrame, homographies: Mapping[str, np.ndarray]
) -> None:
    """Log each camera's detections of each object in the plane, at ``t_plane_ms``.

    Parameters
    ----------
    recording : RecordingStream
    model : SyncModel
        Gives the cameras' colours.
    detections : DataFrame
        :func:`stamped` restamped detections.
    homographies : mapping of camera name to ndarray of shape (3, 3)
        Image px -> plane m; cameras without one are left out.
    """
    colors = camera_colors(model.cameras)
    for (name, obj), track in detections.groupby(["camera", "object"], sort=False):
        if name not in homographies:
            continue
        plane = image_to_plane(
            track["x"].to_numpy(dtype=np.float64), track["y"].to_numpy(dtype=np.float64), np.asarray(homographies[name])
        )
        points = np.column_stack([plane, np.zeros(len(plane))])
        recording.send_columns(
            observation_entity(name, obj),
            indexes=[
                global_time_column(track["t_plane_ms"].to_numpy()),
                rr.TimeColumn(frame_timeline(name), sequence=track["frame"].to_numpy()),
            ],
            columns=rr.Points3D.columns(
                positions=points, colors=[colors[name]] * len(points), radii=[0.15] * len(points)
            ),
        )


def log_plane(recording: rr.RecordingStream, rink_m: tuple[float, float] | None) -> None:
    """Set up the plane (static): ``z`` up, and the rink outline if ``rink_m`` is given.

    The outline is a rectangle from (0, 0) to ``rink_m`` (length, width; m) with corners
    rounded to :data:`RINK_CORNER_RADIUS_M`, and the centre line.
    """
    recording.log(PLANE, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    if rink_m is None:
        return
    length, width = rink_m
    radius = min(RINK_CORNER_RADIUS_M, length / 2, width / 2)
    arc = np.linspace(0.0, np.pi / 2, 12)
    corners = [
        ((length - radius, width - radius), 0.0),
        ((radius, width - radius), np.pi / 2),
        ((radius, radius), np.pi),
        ((length - radius, radius), 1.5 * np.pi),
    ]
    outline = np.concatenate(
        [
            np.stack([cx + radius * np.cos(start + arc), cy + radius * np.sin(start + arc)], axis=1)
            for (cx, cy), start in corners
        ]
    )
    outline = np.concatenate([outline, outline[:1]])
    strips = [np.column_stack([outline, np.zeros(len(outline))]), [[length / 2, 0.0, 0.0], [length / 2, width, 0.0]]]
    recording.log(RINK_ENTITY, rr.LineStrips3D(strips, colors=(120, 160, 200), radii=0.05), static=True)
