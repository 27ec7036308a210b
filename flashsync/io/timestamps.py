"""Timestamps CSV: a camera's frame times, one row per decoded frame in presentation order.

The column is ``t_ms`` (or ``timestamp_ms``, ``time_ms``), ms; or ``rtp``, 32-bit 90 kHz RTP
stamps, unwrapped (:func:`flashsync.timestamps.rtp_timestamps`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from flashsync.errors import InputError
from flashsync.io.files import existing_file, first_line
from flashsync.timestamps import check_timestamps, rtp_timestamps


def load_timestamps(path: str | Path, column: str | None = None) -> np.ndarray:
    """Frame times (ms) from a CSV file, one row per frame in presentation order.

    The column is ``column`` if given, else the first of ``t_ms``, ``timestamp_ms``,
    ``time_ms``; a column ``rtp`` (whole 90 kHz RTP stamps, 0 to 2**32 - 1) is unwrapped with
    :func:`rtp_timestamps`. Every value must be a finite number and the times must
    increase; a bad one is an error naming the row.
    """
    path = existing_file(path)
    try:
        table = pd.read_csv(path, dtype=str, keep_default_na=False, skip_blank_lines=False)
    except UnicodeDecodeError as error:
        raise InputError(f"{path}: not UTF-8 text (byte {error.start}); save the timestamps as a UTF-8 CSV") from None
    except (OSError, ValueError, pd.errors.ParserError) as error:
        raise InputError(f"{path}: cannot read it as CSV ({first_line(error)}); {FIX}") from None
    candidates = [column] if column else ["t_ms", "timestamp_ms", "time_ms", "rtp"]
    found = [name for name in candidates if name in table.columns]
    header_is_a_time = len(table.columns) > 0 and pd.notna(pd.to_numeric(str(table.columns[0]), errors="coerce"))
    if not found and header_is_a_time:
        raise InputError(
            f"{path}: its first line, {table.columns[0]}, is not a header; add a header line naming the column "
            f"({', '.join(candidates)})"
        )
    if not found:
        raise InputError(
            f"{path}: no timestamp column (it has {', '.join(map(str, table.columns)) or 'none'}); "
            f"expected one of {', '.join(candidates)}"
        )
    name = found[0]
    text = table[name].str.strip()
    if text.empty:
        raise InputError(f"{path}: no rows; {FIX}")
    values = pd.to_numeric(text, errors="coerce").to_numpy(dtype=np.float64, na_value=np.nan)
    bad = ~np.isfinite(values)
    if name == "rtp":
        bad |= np.isfinite(values) & ((values != np.round(values)) | (values < 0) | (values >= 2**32))
    if bad.any():
        index = int(np.argmax(bad))
        expected = "a whole 90 kHz RTP stamp from 0 to 2**32 - 1" if name == "rtp" else "a finite number of ms"
        raise InputError(f"{path}: row {index + 1}, column {name} is {text.iloc[index]!r}, expected {expected}; {FIX}")
    if name == "rtp":
        values = rtp_timestamps(values.astype(np.uint64))
    return check_timestamps(values, str(path), fix=FIX)


#: What to do about a bad timestamps file.
FIX = "fix the CSV: one row per decoded frame, times increasing"
