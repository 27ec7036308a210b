"""The events table (``flashsync detect -o events.csv|.parquet``): one row per band edge.

Columns :data:`COLUMNS`, the fields of :class:`~flashsync.events.Events`: ``edge`` and
``band`` as their names (``leading``, ``pulse``, ...), ``flags`` as the event's flag names
joined by ``|`` in alphabetical order (empty for none).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from flashsync.errors import InputError
from flashsync.events import Band, Edge, Events, Flag
from flashsync.io.files import existing_file, first_line
from flashsync.io.tables import table_format, write_table

COLUMNS = ["camera", "event", "frame", "t_frame_ms", "row", "edge", "band", "rise_rows", "strength", "quality", "flags"]
#: Separates an event's flags in the ``flags`` column.
FLAG_SEPARATOR = "|"


def events_to_frame(events: Events) -> pd.DataFrame:
    """The events as a table with :data:`COLUMNS` (the file's layout)."""
    return pd.DataFrame(
        {
            "camera": list(events.camera),
            "event": events.event,
            "frame": events.frame,
            "t_frame_ms": events.t_frame_ms,
            "row": events.row,
            "edge": [edge.value for edge in events.edge],
            "band": [band.value for band in events.band],
            "rise_rows": events.rise_rows,
            "strength": events.strength,
            "quality": events.quality,
            "flags": [FLAG_SEPARATOR.join(sorted(flag.value for flag in flags)) for flags in events.flags],
        },
        columns=COLUMNS,
    )


def events_from_frame(table: pd.DataFrame, source: str = "events") -> Events:
    """Typed events from a table with :data:`COLUMNS`; ``source`` names it in errors.

    Every value is checked: camera names present, event and frame numbers whole and not
    negative, times, rows, strengths and qualities finite numbers (``rise_rows`` may be
    empty), edges, bands and flags known names; and each camera's frame times one per frame,
    increasing with the frame. A bad value is one error naming the row and the column.
    """
    missing = [name for name in COLUMNS if name not in table.columns]
    if missing:
        raise InputError(
            f"{source}: missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)}; "
            f"an events table has {', '.join(COLUMNS)}"
        )
    table = table.reset_index(drop=True)
    camera = table["camera"]
    empty = camera.isna() | (camera.astype(str).str.strip() == "")
    if empty.any():
        _bad(source, int(np.argmax(empty.to_numpy())), "camera", "is empty", "a camera name")
    numbers = {name: _numbers(table, name, source, whole=name in ("event", "frame")) for name in _NUMERIC}
    names = {}
    for column, kind in (("edge", Edge), ("band", Band)):
        for index, value in enumerate(table[column]):
            if value not in set(kind):
                _bad(source, index, column, f"is {value!r}", f"one of {', '.join(kind)}")
        names[column] = [kind(value) for value in table[column]]
    flags = []
    for index, text in enumerate(table["flags"].astype(object).where(table["flags"].notna(), "")):
        parts = [part for part in str(text).split(FLAG_SEPARATOR) if part]
        unknown = [part for part in parts if part not in set(Flag)]
        if unknown:
            _bad(source, index, "flags", f"names {unknown[0]!r}", f"flags among {', '.join(Flag)} joined by |")
        flags.append(frozenset(Flag(part) for part in parts))
    events = Events.from_columns(
        [str(name) for name in camera],
        numbers["event"],
        numbers["frame"],
        numbers["t_frame_ms"],
        numbers["row"],
        names["edge"],
        names["band"],
        numbers["rise_rows"],
        numbers["strength"],
        numbers["quality"],
        flags,
    )
    _check_frame_times(events, source)
    return events


#: Numeric columns and whether an empty value is allowed.
_NUMERIC = {
    "event": False,
    "frame": False,
    "t_frame_ms": False,
    "row": False,
    "rise_rows": True,
    "strength": False,
    "quality": False,
}


def _numbers(table: pd.DataFrame, name: str, source: str, whole: bool) -> np.ndarray:
    """A numeric column as float64, or an error naming the first bad row."""
    column = table[name]
    if pd.api.types.is_bool_dtype(column) or column.map(lambda v: isinstance(v, (bool, np.bool_))).any():
        index = int(np.argmax(column.map(lambda v: isinstance(v, (bool, np.bool_))).to_numpy()))
        _bad(source, index, name, f"is {column.iloc[index]!r} (true/false)", "a number")
    values = pd.to_numeric(column, errors="coerce").to_numpy(dtype=np.float64, na_value=np.nan)
    empty = column.isna().to_numpy()
    bad = ~np.isfinite(values) & ~(empty & _NUMERIC[name])
    if whole:
        bad |= np.isfinite(values) & ((values != np.round(values)) | (values < 0))
    if bad.any():
        index = int(np.argmax(bad))
        shown = "empty" if empty[index] else f"{column.iloc[index]!r}"
        expected = "a whole number >= 0" if whole else "a finite number" + (" or empty" if _NUMERIC[name] else "")
        _bad(source, index, name, f"is {shown}", expected)
    return values


def _check_frame_times(events: Events, source: str) -> None:
    """Each camera's frames have one time each, increasing with the frame number."""
    for name in dict.fromkeys(events.camera):
        mine = np.flatnonzero(events.camera == name)
        order = mine[np.lexsort((events.t_frame_ms[mine], events.frame[mine]))]
        frame, time = events.frame[order], events.t_frame_ms[order]
        same = np.diff(frame) == 0
        bad = (same & (np.diff(time) != 0)) | (~same & (np.diff(time) <= 0))
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(
                f"{source}: camera {name}: frame {frame[i]} at {time[i]:g} ms and frame {frame[i + 1]} at "
                f"{time[i + 1]:g} ms; a camera's frame times increase with its frames: give a table the detector wrote"
            )


def _bad(source: str, index: int, column: str, problem: str, expected: str):
    raise InputError(f"{source}: row {index + 1}, column {column} {problem}, expected {expected}; fix the table")


def save_events(events: Events, path: str | Path) -> None:
    """Write the events table to ``path`` (.csv or .parquet), atomically."""
    write_table(events_to_frame(events), path)


def load_events(path: str | Path) -> Events:
    """Read an events table (.csv or .parquet) written by :func:`save_events`."""
    kind = table_format(path)
    path = existing_file(path)
    try:
        table = pd.read_parquet(path) if kind == "parquet" else pd.read_csv(path)
    except (OSError, ValueError, pd.errors.ParserError) as error:
        raise InputError(f"{path}: cannot read it as {kind} ({first_line(error)}); check the file") from None
    return events_from_frame(table, str(path))
