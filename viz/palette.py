"""Colours and markers of the recording: one colour per camera, one style per event status.

Colours that label text is drawn in (flash rows, detections) are dark enough to read on
the viewer's light label boxes and on bright video.
"""

from __future__ import annotations

from collections.abc import Iterable

Color = tuple[int, int, int]

# Tableau 10 without red and grey, which mark rejected and unmatched events.
_CAMERA_COLORS = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (188, 189, 34),
    (23, 190, 207),
]

STATUS_COLORS: dict[str, Color] = {
    "matched": (0, 140, 60),
    "rejected": (215, 25, 28),
    "unmatched": (100, 100, 100),
}
"""RGB colour of an event by status: matched (inlier), rejected (outlier), unmatched."""

_STATUS_MARKERS = {"matched": "Circle", "rejected": "Cross", "unmatched": "Diamond"}

ERROR_COLOR: Color = (215, 25, 28)
"""RGB colour of validation error arrows."""
CUT_ERROR_COLOR: Color = (240, 130, 0)
"""RGB colour of validation error arrows cut to the longest drawn."""

NOW_COLOR: Color = (255, 210, 0)
"""RGB colour of the line across the row exposed at the time cursor."""

# Light fills (black labels read on them) for the flashes in the event lanes, cycling;
# no red or grey, which mark rejected and unmatched events.
FLASH_FILLS: list[Color] = [
    (120, 170, 225),
    (250, 180, 90),
    (140, 205, 120),
    (195, 160, 225),
    (240, 215, 90),
    (110, 205, 205),
    (215, 180, 145),
    (235, 160, 205),
]
LANE_FILLS: dict[str, Color] = {"rejected": (235, 80, 80), "unmatched": (175, 175, 175), "before": (228, 228, 228)}
"""Fills of the event lanes: rejected and unmatched events, and a camera's video before
its first event."""


def camera_colors(names: Iterable[str]) -> dict[str, Color]:
    """A distinct RGB colour (0-255) for each camera, in the given order (cycling after 8)."""
    return {name: _CAMERA_COLORS[i % len(_CAMERA_COLORS)] for i, name in enumerate(names)}


def status_style(status: str, camera_color: Color) -> tuple[Color, str]:
    """Colour and marker shape of a camera's events of ``status`` in a time series.

    Matched events take the camera's colour; rejected and unmatched ones the colour of
    their status, so that they stand out whatever the camera.
    """
    color = camera_color if status == "matched" else STATUS_COLORS[status]
    return color, _STATUS_MARKERS[status]
