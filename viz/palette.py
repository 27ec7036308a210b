"""Colours and markers of the recording: one colour per camera, one style per event status."""

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
    "matched": (44, 200, 90),
    "rejected": (230, 40, 40),
    "unmatched": (150, 150, 150),
}
"""RGB colour of an event by status: matched (inlier), rejected (outlier), unmatched."""

_STATUS_MARKERS = {"matched": "Circle", "rejected": "Cross", "unmatched": "Diamond"}

ERROR_COLOR: Color = (230, 40, 40)
"""RGB colour of validation error vectors."""


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
