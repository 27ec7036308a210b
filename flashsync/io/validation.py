"""Validation JSON (``flashsync validate --json``): a :class:`~tracking_adapter.validate.ValidationReport`
with its per-pair statistics and every triple."""

from __future__ import annotations

import json
from collections.abc import Collection
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from flashsync.atomic import write_text
from flashsync.errors import InputError
from flashsync.io.fields import Fields
from flashsync.io.files import existing_file, first_line

if TYPE_CHECKING:
    from tracking_adapter.validate import ValidationReport


def save_validation(report: ValidationReport, path: str | Path) -> None:
    """Write the report (``report.to_dict()``) to ``path`` as JSON, atomically."""
    write_text(path, json.dumps(report.to_dict(), indent=1))


def load_validation(path: str | Path, cameras: Collection[str] | None = None) -> pd.DataFrame:
    """The triples of a validation JSON file: B's detection, A's interpolated position and
    the distance (columns :data:`tracking_adapter.validate.TRIPLE_COLUMNS`), every value
    checked: camera names as text (one of ``cameras`` where given: the model's), finite
    times, positions and distances."""
    path = existing_file(path)
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InputError(
            f"{path}: not the JSON of a validation report ({first_line(error)}); give the JSON a validation saved"
        ) from None
    fix = "give the JSON that flashsync validate --json saved"
    records = []
    for triple in Fields(document, str(path), fix=fix).objects("triples", "triples[{}]"):
        record = {name: triple.text(name) for name in ("camera_a", "camera_b")}
        for name, camera in record.items():
            if cameras is not None and camera not in cameras:
                triple.fail(name, f"is {camera!r}, not a camera of the model ({', '.join(cameras)})")
        value = triple.value("object")
        if not isinstance(value, (str, int, float)) or isinstance(value, bool):
            triple.fail("object", "is not an object id (text or a number)")
        record["object"] = value
        record |= {name: triple.number(name) for name in _NUMBERS}
        records.append(record)
    return pd.DataFrame.from_records(records, columns=["camera_a", "camera_b", "object", *_NUMBERS])


#: The numbers of a triple: B's instant (ms), B's and A's plane positions and their distance (m).
_NUMBERS = ("t_global_ms", "x_b", "y_b", "x_a", "y_a", "error_m")
