"""Homographies JSON: ``{camera: 3x3 matrix}`` mapping image pixels (x, y) to a plane in metres."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from flashsync.errors import InputError
from flashsync.io.fields import Fields
from flashsync.io.files import existing_file, first_line


def load_homographies(path: str | Path) -> dict[str, np.ndarray]:
    """Read ``{camera: 3x3 matrix}`` (image px -> plane m) from a JSON file.

    Returns
    -------
    dict of str to ndarray of shape (3, 3)
        Each camera's homography, float64.
    """
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
    fields = Fields(document, str(path), fix="write one 3x3 image->plane homography of numbers per camera")
    homographies = {}
    for name in document:
        matrix = fields.matrix(name, (3, 3))
        if abs(np.linalg.det(matrix)) < 1e-300:
            fields.fail(name, "is not invertible (its determinant is 0)")
        homographies[str(name)] = matrix
    return homographies
