"""Homographies JSON: ``{camera: 3x3 matrix}`` mapping image pixels (x, y) to a plane in metres.

The file may also describe the plane: ``"plane": {"outline_m": [[x, y], ...]}``, its
outline (a rink, a pitch) in metres. That entry is an object where a camera's is a matrix,
so a camera may still be named ``plane``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from flashsync.errors import InputError
from flashsync.io.fields import Fields, is_number
from flashsync.io.files import existing_file, first_line

PLANE_KEY = "plane"
"""Key of the optional plane description (a JSON object)."""


def load_homographies(path: str | Path) -> dict[str, np.ndarray]:
    """Read ``{camera: 3x3 matrix}`` (image px -> plane m) from a JSON file.

    An entry ``"plane": {...}`` (an object, not a matrix) describes the plane, not a
    camera; see :func:`load_plane_outline`.

    Returns
    -------
    dict of str to ndarray of shape (3, 3)
        Each camera's homography, float64.
    """
    path, document = _document(path)
    fields = Fields(document, str(path), fix="write one 3x3 image->plane homography of numbers per camera")
    homographies = {}
    for name in document:
        if name == PLANE_KEY and isinstance(document[name], dict):
            continue
        matrix = fields.matrix(name, (3, 3))
        if abs(np.linalg.det(matrix)) < 1e-300:
            fields.fail(name, "is not invertible (its determinant is 0)")
        homographies[str(name)] = matrix
    if not homographies:
        raise InputError(f"{path}: no camera in it; write one 3x3 image->plane homography per camera")
    return homographies


def load_plane_outline(path: str | Path) -> np.ndarray | None:
    """Read the plane's outline from a homographies file, if it has one.

    The file may hold, beside the cameras, ``"plane": {"outline_m": [[x, y], ...]}``: the
    outline of the plane as a polyline of at least 3 points in plane metres, closed by
    joining the last point to the first.

    Returns
    -------
    ndarray of shape (n + 1, 2) or None
        The closed outline, m (first point repeated last); None without ``"plane"``.
    """
    path, document = _document(path)
    plane = document.get(PLANE_KEY)
    if not isinstance(plane, dict):
        return None
    points = plane.get("outline_m")
    numbers = isinstance(points, list) and all(
        isinstance(point, list) and all(is_number(value) for value in point) for point in points
    )
    outline = np.asarray(points, dtype=np.float64) if numbers and points else np.empty(0)
    if outline.ndim != 2 or outline.shape[1:] != (2,) or len(outline) < 3 or not np.all(np.isfinite(outline)):
        raise InputError(
            f'{path}: "{PLANE_KEY}" needs "outline_m": [[x, y], ...] with at least 3 points in metres; '
            "fix or remove that entry"
        )
    return outline if np.array_equal(outline[0], outline[-1]) else np.vstack([outline, outline[:1]])


def _document(path: str | Path) -> tuple[Path, dict]:
    """The JSON object of a homographies file, and its path."""
    path = existing_file(path)
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InputError(
            f'{path}: not a JSON file ({first_line(error)}); give {{"camera": [[...], [...], [...]]}} with 3x3 matrices'
        ) from None
    if not isinstance(document, dict) or not document:
        raise InputError(
            f"{path}: expected a JSON object {{camera: 3x3 matrix}}; write one 3x3 image->plane homography per camera"
        )
    return path, document
