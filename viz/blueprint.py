"""The viewer layout: the first screen shows every part of the recording.

Top: one 2D view per camera with a video (frame, flash rows, detections), up to
:data:`VIDEO_COLUMNS` in a row. Bottom row: the plane (3D, with a trail of the last
:data:`TRAIL_S` seconds of observations) where there are plane data; the event raster,
the residuals and the validation error as time series; the flash log (matched flashes;
its DEBUG level, the unmatched events, is filtered out). The time panel is collapsed to
its slider, on ``global_time``, paused at the start.
"""

from __future__ import annotations

from collections.abc import Collection

import rerun.blueprint as rrb

from flashsync.model import SyncModel
from viz import events, residuals, trajectories, validation
from viz.timeline import GLOBAL_TIMELINE
from viz.video import camera_entity

TRAIL_S = 1.0
VIDEO_COLUMNS = 4


def sync_blueprint(
    model: SyncModel,
    *,
    video_cameras: Collection[str] = (),
    plane: bool = False,
    errors: bool = False,
    rink_m: tuple[float, float] | None = None,
) -> rrb.Blueprint:
    """The default layout of a flashsync recording.

    Parameters
    ----------
    model : SyncModel
        Its cameras give the lanes of the event raster.
    video_cameras : collection of str
        Cameras whose video is in the recording; one view each, in model order.
    plane : bool
        Add the 3D plane view.
    errors : bool
        Add the validation error time series.
    rink_m : (float, float), optional
        Rink length and width, m; the 3D view starts looking at it from above one long
        side.
    """
    bottom: list[rrb.View | rrb.Container] = []
    if plane:
        eye = None
        if rink_m is not None:
            length, width = rink_m
            eye = rrb.EyeControls3D(
                position=(length / 2, -0.8 * width, 0.8 * length),
                look_target=(length / 2, width / 2, 0.0),
                eye_up=(0, 0, 1),
            )
        trail = rrb.VisibleTimeRange(
            GLOBAL_TIMELINE,
            start=rrb.TimeRangeBoundary.cursor_relative(seconds=-TRAIL_S),
            end=rrb.TimeRangeBoundary.cursor_relative(),
        )
        bottom.append(
            rrb.Spatial3DView(origin=trajectories.PLANE, name="plane (m)", time_ranges=trail, eye_controls=eye)
        )
    lanes = len(model.cameras)
    series = [
        rrb.TimeSeriesView(
            origin=events.ROOT,
            name="events (lane = camera)",
            axis_y=rrb.ScalarAxis(range=(-0.5, lanes - 0.5), zoom_lock=True),
        ),
        rrb.TimeSeriesView(origin=residuals.ROOT, name="residuals (ms)", plot_legend=rrb.PlotLegend(visible=False)),
    ]
    if errors:
        series.append(rrb.TimeSeriesView(origin=validation.ROOT, name="validation error (m)"))
    bottom.append(rrb.Vertical(*series))
    columns = rrb.TextLogColumns(
        timeline_columns=[rrb.encodings.TimelineColumn(GLOBAL_TIMELINE)],
        text_log_columns=[rrb.encodings.TextLogColumn(kind) for kind in ("LogLevel", "Body")],
    )
    bottom.append(
        rrb.TextLogView(
            origin=events.LOG_ENTITY,
            name="flash log",
            columns=columns,
            rows=rrb.TextLogRows(filter_by_log_level=["INFO", "WARN"]),
        )
    )
    rows: list[rrb.View | rrb.Container] = []
    videos = [name for name in model.cameras if name in video_cameras]
    if videos:
        rows.append(
            rrb.Grid(
                *[rrb.Spatial2DView(origin=camera_entity(name), name=name) for name in videos],
                grid_columns=min(len(videos), VIDEO_COLUMNS),
            )
        )
    rows.append(rrb.Horizontal(*bottom))
    return rrb.Blueprint(
        rrb.Vertical(*rows),
        rrb.TimePanel(timeline=GLOBAL_TIMELINE, state="collapsed", play_state="paused"),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
    )
