"""The common plane as the viewer shows it: a top view in metres, turned as a camera sees it.

Plane data (observations, validation errors) are logged in plane metres under ``plane``;
the static ``Transform3D`` of ``plane`` turns and, where the plane's axes are mirrored
against the image, flips them into the view's display coordinates (x right, y down), so
that the top view has the orientation of the reference camera's image (image up = view
up). Hovering a point still shows plane metres.

=====================  =============================================================
``plane``              display transform (Transform3D), static
``plane/map/outline``  the plane's outline, when one is given (LineStrips2D), static
``plane/map/grid``     metre grid over the shown extent (LineStrips2D), static
``plane/map/ticks``    grid values, ``x 10 m``, ``y 5 m`` (Points2D labels), static
``plane/map/scale``    the longest error arrow drawn, and its error (LineStrips2D), static
=====================  =============================================================

The outline is never invented: it comes from the homographies file (``"plane":
{"outline_m": ...}``, see :func:`flashsync.io.homographies.load_plane_outline`) or from
the caller (``flashsync view --plane``). Without one, the view shows the extent of the
data.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import rerun as rr

from flashsync.model import SyncModel
from tracking_adapter.validate import image_to_plane
from viz.palette import ERROR_COLOR
from viz.scales import format_length, nice_ceiling, nice_floor

PLANE = "plane"
MAP = f"{PLANE}/map"
OUTLINE_ENTITY = f"{MAP}/outline"
GRID_ENTITY = f"{MAP}/grid"
TICKS_ENTITY = f"{MAP}/ticks"
SCALE_ENTITY = f"{MAP}/scale"
GRID_LINES = 8
"""About as many grid lines along the longer side of the extent."""
ARROW_SHARE = 0.04
"""A validation error arrow as long as the median error spans this share of the extent's
diagonal (before rounding the scale down to 1, 2 or 5 times a power of ten)."""
ARROW_CAP_SHARE = 0.15
"""No error arrow is drawn longer than this share of the extent's diagonal; a longer one
is cut to it (and drawn orange)."""
ABSURD_EXTENT_M = 1000.0
"""A camera whose detections spread wider than this in the plane gets a warning."""
OUTSIDE_SHARE = 0.2
"""A camera with more than this share of its detections far outside the outline (further
than half the outline's size from its bounding box) gets a warning."""
_OUTLINE_COLOR = (30, 50, 150)
_GRID_COLOR = (190, 190, 190)
_TICK_COLOR = (70, 70, 70)


class PlaneWarning(UserWarning):
    """Plane positions that look wrong (e.g. a homography in the wrong direction)."""


def rectangle_outline(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """The closed outline (shape (5, 2), m) of the rectangle with corners (x0, y0), (x1, y1)."""
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]], dtype=np.float64)


def display_transform(homography: np.ndarray | None, width: int, height: int) -> np.ndarray:
    """The 2x2 orthonormal map from plane metres to display coordinates (x right, y down)
    that shows the plane as the camera of ``homography`` sees it.

    The direction in the plane of the image's up at its centre becomes the display's up;
    the display's right follows the image's right, so a plane whose axes are mirrored
    against the image is flipped. Without a usable homography: plane x right, y up.

    Parameters
    ----------
    homography : ndarray of shape (3, 3) or None
        Image px -> plane m.
    width, height : int
        The camera's image size, px.
    """
    default = np.array([[1.0, 0.0], [0.0, -1.0]])
    if homography is None:
        return default
    cx, cy, step = width / 2, height / 2, max(height, 1) / 10
    points = image_to_plane(
        np.array([cx, cx, cx - step, cx + step]), np.array([cy - step, cy + step, cy, cy]), np.asarray(homography)
    )
    up, right = points[0] - points[1], points[3] - points[2]
    if not (np.all(np.isfinite(points)) and np.linalg.norm(up) > 0):
        return default
    up = up / np.linalg.norm(up)
    mirrored = up[0] * right[1] - up[1] * right[0] > 0  # right is not clockwise of up
    display_right = np.array([-up[1], up[0]]) if mirrored else np.array([up[1], -up[0]])
    return np.stack([display_right, -up])


@dataclass(frozen=True)
class PlaneView:
    """What the plane view shows and how.

    Attributes
    ----------
    to_display : ndarray of shape (2, 2)
        Plane m -> display coordinates (:func:`display_transform`).
    low_m, high_m : ndarray of shape (2,)
        Corners of the plane extent shown, m: the outline's bounding box, or the data's.
    oriented_as : str or None
        The camera whose image the view's orientation follows.
    outline_m : ndarray of shape (n, 2) or None
        The plane's outline, m.
    error_scale : float or None
        Validation error arrows are drawn this many times their length; None without
        validation errors.
    """

    to_display: np.ndarray
    low_m: np.ndarray
    high_m: np.ndarray
    oriented_as: str | None
    outline_m: np.ndarray | None
    error_scale: float | None

    def grid_step_m(self) -> float:
        """Spacing of the metre grid, m."""
        return nice_ceiling(float(np.max(self.high_m - self.low_m)) / GRID_LINES)

    def display_bounds(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """``(x_range, y_range)`` in display coordinates that hold the extent, its tick
        labels and the scale bar."""
        corners = np.array(
            [
                [self.low_m[0], self.low_m[1]],
                [self.high_m[0], self.low_m[1]],
                [self.low_m[0], self.high_m[1]],
                [self.high_m[0], self.high_m[1]],
            ]
        )
        shown = corners @ self.to_display.T
        low, high = shown.min(axis=0), shown.max(axis=0)
        margin = 0.12 * float(np.max(high - low))
        return ((low[0] - margin, high[0] + margin / 2), (low[1] - margin * 0.6, high[1] + margin))

    def arrow_cap_m(self) -> float:
        """Longest error arrow drawn, m: about :data:`ARROW_CAP_SHARE` of the diagonal, the
        arrow of a round error."""
        scale = self.error_scale or 1.0
        diagonal = float(np.hypot(*(self.high_m - self.low_m)))
        return nice_floor(ARROW_CAP_SHARE * diagonal / scale) * scale

    def title(self) -> str:
        """The view's name: unit, orientation and arrow scale."""
        title = "plane (m), top view"
        if self.oriented_as is not None:
            title += f" as {self.oriented_as} sees it"
        if self.error_scale is not None:
            title += f"; error arrows ×{self.error_scale:g}"
        return title


def plane_view(
    model: SyncModel,
    homographies: Mapping[str, np.ndarray] | None,
    outline_m: np.ndarray | None,
    points_m: np.ndarray,
    errors_m: np.ndarray,
) -> PlaneView:
    """Decide the plane view: orientation, extent and error arrow scale.

    Parameters
    ----------
    model : SyncModel
        The first of its cameras (reference first) with a homography sets the orientation.
    homographies : mapping of camera name to ndarray of shape (3, 3), optional
    outline_m : ndarray of shape (n, 2), optional
        The plane's outline, m; its bounding box is the extent shown.
    points_m : ndarray of shape (k, 2)
        Every plane position to show (observations, validation), m; without an outline
        their bounding box is the extent shown (at least 1 m), leaving out stray points
        further than half its size beyond their 1st to 99th percentile box.
    errors_m : ndarray of shape (e,)
        Validation errors, m; empty without validation.
    """
    homographies = homographies or {}
    oriented_as = next((name for name in model.cameras if name in homographies), None)
    if oriented_as is None:
        to_display = display_transform(None, 0, 0)
    else:
        camera = model.cameras[oriented_as]
        to_display = display_transform(homographies[oriented_as], camera.width, camera.height)
    points = points_m[np.all(np.isfinite(points_m), axis=1)] if len(points_m) else points_m
    if outline_m is not None:
        low, high = outline_m.min(axis=0), outline_m.max(axis=0)
    elif len(points):
        box_low, box_high = np.percentile(points, 1, axis=0), np.percentile(points, 99, axis=0)
        reach = (box_high - box_low) / 2
        near = points[np.all((points >= box_low - reach) & (points <= box_high + reach), axis=1)]
        low, high = near.min(axis=0), near.max(axis=0)
    else:
        low, high = np.zeros(2), np.ones(2)
    middle, half = (low + high) / 2, np.maximum((high - low) / 2, 0.5)
    low, high = middle - half, middle + half
    scale = None
    errors = errors_m[np.isfinite(errors_m) & (errors_m > 0)]
    if len(errors):
        diagonal = float(np.hypot(*(high - low)))
        scale = max(1.0, nice_floor(ARROW_SHARE * diagonal / float(np.median(errors))))
    return PlaneView(to_display, low, high, oriented_as, outline_m, scale)


def plane_warnings(points_by_camera: Mapping[str, np.ndarray], outline_m: np.ndarray | None) -> list[str]:
    """One line per camera whose detections land where a plane cannot be.

    A homography in the wrong direction (plane -> image) puts points hundreds of metres to
    thousands of kilometres away: a camera whose points spread wider than
    :data:`ABSURD_EXTENT_M`, or, with an outline, that has more than
    :data:`OUTSIDE_SHARE` of its points far outside it, is named.

    Parameters
    ----------
    points_by_camera : mapping of camera name to ndarray of shape (n, 2)
        Each camera's detections in the plane, m.
    outline_m : ndarray of shape (k, 2), optional
    """
    lines = []
    advice = "check that its homography maps image pixels to plane metres (not the inverse)"
    for name, points in points_by_camera.items():
        finite = points[np.all(np.isfinite(points), axis=1)]
        if len(finite) < len(points):
            lines.append(f"{len(points) - len(finite)} of {name}'s detections map to infinity in the plane; {advice}")
        if not len(finite):
            continue
        low, high = np.percentile(finite, 1, axis=0), np.percentile(finite, 99, axis=0)
        if outline_m is not None:
            size = outline_m.max(axis=0) - outline_m.min(axis=0)
            near_low, near_high = outline_m.min(axis=0) - size / 2, outline_m.max(axis=0) + size / 2
            outside = np.mean(np.any((finite < near_low) | (finite > near_high), axis=1))
            if outside > OUTSIDE_SHARE:
                lines.append(
                    f"{outside:.0%} of {name}'s detections land far outside the plane "
                    f"outline (x {_span(outline_m[:, 0])}, y {_span(outline_m[:, 1])}): "
                    f"at x {_span(finite[:, 0])}, y {_span(finite[:, 1])}; {advice}"
                )
                continue
        if np.max(high - low) > ABSURD_EXTENT_M:
            lines.append(
                f"{name}'s detections spread over {format_length(float(np.max(high - low)))} "
                f"in the plane (x {_span(finite[:, 0])}, y {_span(finite[:, 1])}); {advice}"
            )
    return lines


def _span(values_m: np.ndarray) -> str:
    """``"-3.2 m..61 m"``: the 1st to 99th percentile of ``values_m``."""
    low, high = np.percentile(values_m, [1, 99])
    return f"{format_length(low)}..{format_length(high)}"


def log_plane(recording: rr.RecordingStream, view: PlaneView) -> None:
    """Log the static parts of the plane view: transform, outline, metre grid, ticks, scale.

    Parameters
    ----------
    recording : RecordingStream
    view : PlaneView
    """
    to_display = np.eye(3)
    to_display[:2, :2] = view.to_display
    recording.log(PLANE, rr.Transform3D(mat3x3=to_display), static=True)
    if view.outline_m is not None:
        recording.log(
            OUTLINE_ENTITY,
            rr.LineStrips2D([view.outline_m], colors=_OUTLINE_COLOR, radii=rr.Radius.ui_points(1.5)),
            static=True,
        )
    step = view.grid_step_m()
    low, high = view.low_m, view.high_m
    xs = step * np.arange(np.ceil(low[0] / step), np.floor(high[0] / step) + 1)
    ys = step * np.arange(np.ceil(low[1] / step), np.floor(high[1] / step) + 1)
    strips = [[[x, low[1]], [x, high[1]]] for x in xs] + [[[low[0], y], [high[0], y]] for y in ys]
    recording.log(GRID_ENTITY, rr.LineStrips2D(strips, colors=_GRID_COLOR, radii=rr.Radius.ui_points(0.5)), static=True)
    positions, labels = [], []
    for axis, values in ((0, xs), (1, ys)):
        other = 1 - axis
        for value in values:
            ends = np.zeros((2, 2))
            ends[:, axis] = value
            ends[:, other] = low[other], high[other]
            shown = ends @ view.to_display.T
            end = ends[np.argmin(shown[:, 0] - shown[:, 1])]  # the bottom or left end
            outward = end - (low + high) / 2
            outward[axis] = 0.0
            positions.append(end + 0.04 * np.sign(outward) * np.max(high - low))
            labels.append(f"{'xy'[axis]} {value:g} m")
    recording.log(
        TICKS_ENTITY,
        rr.Points2D(positions, labels=labels, colors=_TICK_COLOR, radii=rr.Radius.ui_points(0.0), show_labels=True),
        static=True,
    )
    if view.error_scale is not None:
        _log_scale_bar(recording, view)


def _log_scale_bar(recording: rr.RecordingStream, view: PlaneView) -> None:
    """A bar above the extent (display) as long as the longest error arrow drawn, labelled
    with its error and the scale; longer errors are cut to it (orange)."""
    (x0, x1), (y0, _) = view.display_bounds()
    length = view.arrow_cap_m()
    start = np.array([(x0 + x1 - length) / 2, y0 + 0.025 * (x1 - x0)])
    bar = np.stack([start, start + [length, 0.0]]) @ view.to_display  # display -> plane m
    error = format_length(length / view.error_scale)
    recording.log(
        SCALE_ENTITY,
        rr.LineStrips2D(
            [bar],
            colors=ERROR_COLOR,
            radii=rr.Radius.ui_points(2.0),
            labels=[f"error {error} ×{view.error_scale:g} (longer: cut, orange)"],
            show_labels=True,
        ),
        static=True,
    )
