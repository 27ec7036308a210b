"""The viewer layout: the first screen shows every part of the recording, readable as it is.

Top: one 2D view per camera with a video (frame, flash rows, "now" line, detections), named
after the camera, up to :data:`VIDEO_COLUMNS` in a row. Below, on the left, the plane (a
top view in metres with a trail of the last :data:`TRAIL_S` seconds) where there are plane
data, over the flash log (matched events; its DEBUG level, the unmatched events, is
filtered out); on the right, stacked on one time range, the event lanes (one per camera),
the residuals and the validation error. The time range runs from 0 to the end of the
recordings plus a margin on the right that holds the plots' legends (top right), so they
cover no data; the plots' value ranges are round (see :mod:`viz.scales`) so that their
axes have labelled ticks. The views' value axes differ in width, so each view's time range
starts a little before 0 by as much as its axis is narrower than the widest: in a
:data:`WINDOW_PX` wide window every instant is at the same x in all of them (a pixel or
two off in other windows). The time panel is collapsed to its slider, on
``global_time``, paused at 0.
"""

from __future__ import annotations

import math
from collections.abc import Collection

import numpy as np
import rerun.blueprint as rrb

from flashsync.model import SyncModel
from viz import events, residuals, validation
from viz.plane import PLANE, PlaneView
from viz.scales import ticked_range
from viz.timeline import GLOBAL_TIMELINE, Timeline
from viz.video import camera_entity

TRAIL_S = 0.5
VIDEO_COLUMNS = 4
WINDOW_PX = (1600.0, 1000.0)
"""Width and height of the viewer's window the layout is made for, px."""
_LEGEND_PX = (28.0, 7.0)
"""Width of a legend: marker and padding, and per character of the longest name, px."""
_VIDEO_SHARE = 0.28
_LEFT_SHARE = 0.33
PLOT_WIDTH_PX = WINDOW_PX[0] * (1 - _LEFT_SHARE)
"""Width of the stacked plots in a :data:`WINDOW_PX` window, px."""
_CHROME_PX = (65.0, 46.0)
"""Heights of the viewer's top bar and time slider, and of a plot's title and time axis, px."""
_DIGIT_PX, _CHAR_PX, _AXIS_PAD_PX, _LANES_GUTTER_PX = 6.0, {"-": 5.0, ".": 4.0}, 12.0, 1.0
"""Widths in the viewer's default font: a digit, a minus sign and a point; the padding of a
plot's value axis; the left edge of the event lanes."""
_LANE_SHARE = (0.06, 0.062)
"""Height of the event lanes among the plots: a share, plus one per camera."""


def legend_margin(names: Collection[str]) -> float:
    """The share of the time range to add on the right so that a legend of ``names`` (top
    right) sits beside the data, between 0.08 and 0.4."""
    longest = max((len(name) for name in names), default=0)
    return min(0.4, max(0.08, (_LEGEND_PX[0] + _LEGEND_PX[1] * longest) / PLOT_WIDTH_PX))


def sync_blueprint(
    model: SyncModel,
    timeline: Timeline,
    *,
    video_cameras: Collection[str] = (),
    plane: PlaneView | None = None,
    errors_max_m: float | None = None,
) -> rrb.Blueprint:
    """The default layout of a flashsync recording.

    Parameters
    ----------
    model : SyncModel
        Its cameras give the event lanes and the legends, its residuals the residual
        plot's range.
    timeline : Timeline
        The time range of the plots is 0 to its duration, plus the legends' margin.
    video_cameras : collection of str
        Cameras whose video is in the recording; one view each, in model order.
    plane : PlaneView, optional
        Add the plane view, showing this.
    errors_max_m : float, optional
        Largest validation error, m; adds the validation error plot.
    """
    legend_names = [f"at {name}" if errors_max_m is not None else name for name in model.cameras]
    end_s = timeline.duration_ms / 1000 * (1 + legend_margin(legend_names))
    legend = rrb.PlotLegend(corner=rrb.Corner2D.RightTop, visible=True)
    videos = [name for name in model.cameras if name in video_cameras]
    n_plots = 1 if errors_max_m is None else 2
    lanes = min(0.4, _LANE_SHARE[0] + _LANE_SHARE[1] * len(model.cameras))
    plot_px = (WINDOW_PX[1] - _CHROME_PX[0]) * (1 - _VIDEO_SHARE if videos else 1) * (1 - lanes) / n_plots - _CHROME_PX[
        1
    ]
    value_ranges = [ticked_range(max(residuals.residual_extent_ms(model), 1e-6), plot_px, symmetric=True)]
    if errors_max_m is not None:
        value_ranges.append(ticked_range(max(errors_max_m, 1e-6), plot_px, symmetric=False))
    gutters = [_LANES_GUTTER_PX] + [value_axis_px(*value_range) for value_range in value_ranges]
    time_axes = [_time_axis(end_s, gutter, max(gutters)) for gutter in gutters]
    series: list[rrb.View] = [
        rrb.StateTimelineView(
            origin=events.ROOT,
            name="flash events per camera (a block runs from an event to the camera's next)",
            time_view=time_axes[0],
        ),
        rrb.TimeSeriesView(
            origin=residuals.ROOT,
            name="residuals of the solve (ms); lines: ±1σ of the sync",
            axis_x=time_axes[1],
            axis_y=rrb.ScalarAxis(range=value_ranges[0]),
            plot_legend=legend,
        ),
    ]
    if errors_max_m is not None:
        series.append(
            rrb.TimeSeriesView(
                origin=validation.ROOT,
                name="validation error (m) at each camera's detections",
                axis_x=time_axes[2],
                axis_y=rrb.ScalarAxis(range=value_ranges[1]),
                plot_legend=legend,
            )
        )
    log = rrb.TextLogView(
        origin=events.LOG_ENTITY,
        name="flash log (click a line to go there)",
        columns=rrb.TextLogColumns(
            timeline_columns=[rrb.encodings.TimelineColumn(GLOBAL_TIMELINE)],
            text_log_columns=[rrb.encodings.TextLogColumn("Body")],
        ),
        rows=rrb.TextLogRows(filter_by_log_level=["INFO", "WARN"]),
    )
    left: rrb.View | rrb.Container = log
    if plane is not None:
        x_range, y_range = plane.display_bounds()
        trail = rrb.VisibleTimeRange(
            GLOBAL_TIMELINE,
            start=rrb.TimeRangeBoundary.cursor_relative(seconds=-TRAIL_S),
            end=rrb.TimeRangeBoundary.cursor_relative(),
        )
        left = rrb.Vertical(
            rrb.Spatial2DView(
                origin="/",
                contents=[f"{PLANE}/**"],
                name=plane.title(),
                visual_bounds=rrb.VisualBounds2D(x_range=x_range, y_range=y_range),
                time_ranges=trail,
            ),
            log,
            row_shares=[0.55, 0.45],
        )
    plots = rrb.Vertical(*series, row_shares=[lanes] + [(1 - lanes) / n_plots] * n_plots)
    rows: list[rrb.View | rrb.Container] = []
    if videos:
        rows.append(
            rrb.Grid(*[_video_view(model, name) for name in videos], grid_columns=min(len(videos), VIDEO_COLUMNS))
        )
    rows.append(rrb.Horizontal(left, plots, column_shares=[_LEFT_SHARE, 1 - _LEFT_SHARE]))
    return rrb.Blueprint(
        rrb.Vertical(*rows, row_shares=[_VIDEO_SHARE, 1 - _VIDEO_SHARE] if videos else None),
        rrb.TimePanel(timeline=GLOBAL_TIMELINE, state="collapsed", play_state="paused"),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
    )


def value_axis_px(low: float, high: float) -> float:
    """Width of a plot's value axis, px: padding and its widest tick label (ticks at
    multiples of the largest power of ten in the range, :mod:`viz.scales`), at the viewer's
    default font."""
    step = 10.0 ** math.floor(math.log10(max(abs(low), abs(high))))
    decimals = max(0, -math.floor(math.log10(step)))
    ticks = step * np.arange(math.ceil(low / step - 1e-9), math.floor(high / step + 1e-9) + 1)
    labels = [f"{tick:.{decimals}f}" if round(tick / step) else "0" for tick in ticks]
    return _AXIS_PAD_PX + max(sum(_CHAR_PX.get(char, _DIGIT_PX) for char in label) for label in labels)


def _time_axis(end_s: float, gutter_px: float, widest_gutter_px: float) -> rrb.TimeAxis:
    """The time axis from 0 to ``end_s`` of a view whose value axis is ``gutter_px`` wide,
    started early enough that 0 is as far right as in the view with the widest one."""
    lead_s = (widest_gutter_px - gutter_px) * end_s / (PLOT_WIDTH_PX - widest_gutter_px)
    return rrb.TimeAxis(
        view_range=rrb.TimeRange(
            start=rrb.TimeRangeBoundary.absolute(seconds=-lead_s), end=rrb.TimeRangeBoundary.absolute(seconds=end_s)
        )
    )


def _video_view(model: SyncModel, name: str) -> rrb.Spatial2DView:
    """A camera's view, named after it, bounded by its image (also before its first frame)."""
    camera = model.cameras[name]
    return rrb.Spatial2DView(
        origin=camera_entity(name),
        name=name,
        visual_bounds=rrb.VisualBounds2D(x_range=(0, camera.width), y_range=(0, camera.height)),
    )
