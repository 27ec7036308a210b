"""Writing tables: CSV or Parquet by the file's extension, atomically."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from flashsync.atomic import atomic_output
from flashsync.errors import InputError

FORMATS = {".csv": "csv", ".parquet": "parquet", ".pq": "parquet"}


def table_format(path: str | Path) -> str:
    """``'csv'`` or ``'parquet'`` from the extension, or a one-line error."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise InputError(f"{path}: unknown table format {suffix or '(none)'}; use .csv or .parquet")
    return FORMATS[suffix]


def write_table(table: pd.DataFrame, path: str | Path) -> None:
    """Write ``table`` to ``path`` (.csv or .parquet), atomically, without the index."""
    kind = table_format(path)
    with atomic_output(path) as temporary:
        if kind == "csv":
            table.to_csv(temporary, index=False)
        else:
            table.to_parquet(temporary, index=False)
