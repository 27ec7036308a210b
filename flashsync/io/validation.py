"""Validation JSON (``flashsync validate --json``): a :class:`~tracking_adapter.validate.ValidationReport`
with its per-pair statistics and every triple."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from flashsync.atomic import write_text
from flashsync.errors import InputError
from flashsync.io.files import existing_file

if TYPE_CHECKING:
    from tracking_adapter.validate import ValidationReport


def save_validation(report: ValidationReport, path: str | Path) -> None:
    """Write the report (``report.to_dict()``) to ``path`` as JSON, atomically."""
    write_text(path, json.dumps(report.to_dict(), indent=1))


def load_validation(path: str | Path) -> pd.DataFrame:
    """The triples of a validation JSON file: B's detection, A's interpolated position and
    the distance (columns :data:`tracking_adapter.validate.TRIPLE_COLUMNS`)."""
    path = existing_file(path)
    try:
        triples = json.loads(path.read_text())["triples"]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise InputError(
            f"{path}: not the JSON of a validation report ({type(error).__name__}: "
            f"{error}); give the JSON a validation saved"
        ) from None
    return pd.DataFrame.from_records(triples)
