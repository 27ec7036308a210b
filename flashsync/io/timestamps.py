"""Timestamps CSV: a camera's frame times, one row per decoded frame in presentation order.

The column is ``t_ms`` (or ``timestamp_ms``, ``time_ms``), ms; or ``rtp``, 32-bit 90 kHz RTP
stamps, unwrapped (:func:`flashsync.timestamps.rtp_timestamps`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from flashsync.errors import InputError
from flashsync.timestamps import check_timestamps, rtp_timestamps


def load_timestamps(path: str | Path, column: str | None = None) -> np.ndarray:
    """Frame times (ms) from a CSV file, one row per frame in presentation order.

    The column is ``column`` if given, else the first of ``t_ms``, ``timestamp_ms``,
    ``time_ms``; a column ``rtp`` (90 kHz RTP stamps) is unwrapped with
    :func:`rtp_timestamps`.
    """
    path = Path(path)
    try:
        table = pd.read_csv(path)
    except (OSError, ValueError) as error:
        raise InputError(f"{path}: cannot read as CSV ({error})") from None
    candidates = [column] if column else ["t_ms", "timestamp_ms", "time_ms", "rtp"]
    found = [name for name in candidates if name in table.columns]
    if not found:
        raise InputError(f"{path}: no timestamp column; expected one of {', '.join(candidates)}")
    values = pd.to_numeric(table[found[0]], errors="coerce").to_numpy()
    if found[0] == "rtp":
        if np.any(~np.isfinite(values)):
            raise InputError(f"{path}: column rtp has empty or non-numeric values")
        values = rtp_timestamps(values.astype(np.uint64))
    return check_timestamps(values, str(path))
