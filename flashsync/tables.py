"""Tables on disk: CSV or Parquet by the file's extension, written atomically."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from flashsync.atomic import atomic_output
from flashsync.errors import FlashsyncError

FORMATS = (".csv", ".parquet")


def table_format(path: str | Path) -> str:
    """``'.csv'`` or ``'.parquet'`` from the extension, or a one-line error."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise FlashsyncError(f"{path}: unknown table format {suffix or '(none)'}; use .csv or .parquet")
    return suffix


def write_table(table: pd.DataFrame, path: str | Path) -> None:
    """Write ``table`` to ``path`` (.csv or .parquet), atomically, without the index."""
    suffix = table_format(path)
    with atomic_output(path) as temporary:
        if suffix == ".csv":
            table.to_csv(temporary, index=False)
        else:
            table.to_parquet(temporary, index=False)


def read_table(path: str | Path, **csv_options) -> pd.DataFrame:
    """Read a .csv or .parquet table, or raise a one-line error naming the file."""
    path = Path(path)
    suffix = table_format(path)
    if not path.is_file():
        raise FlashsyncError(f"{path}: no such file; check the path")
    try:
        if suffix == ".csv":
            return pd.read_csv(path, **csv_options)
        return pd.read_parquet(path)
    except (OSError, ValueError, UnicodeDecodeError) as error:
        raise FlashsyncError(f"{path}: cannot read as {suffix[1:]} ({str(error).splitlines()[0]})") from None
