"""The events table (``flashsync detect -o events.csv|.parquet``): one row per band edge.

Columns :data:`COLUMNS`, the fields of :class:`~flashsync.events.Events`: ``edge`` and
``band`` as their names (``leading``, ``pulse``, ...), ``flags`` as the event's flag names
joined by ``|`` in alphabetical order (empty for none).
"""

from __future__ import annotations

from pathlib import Path

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
    """Typed events from a table with :data:`COLUMNS`; ``source`` names it in errors."""
    missing = [name for name in COLUMNS if name not in table.columns]
    if missing:
        raise InputError(
            f"{source}: missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)}; "
            f"an events table has {', '.join(COLUMNS)}"
        )
    flags = table["flags"].astype(object).where(table["flags"].notna(), "")
    try:
        return Events.from_columns(
            [str(name) for name in table["camera"]],
            table["event"].to_numpy(),
            table["frame"].to_numpy(),
            table["t_frame_ms"].to_numpy(),
            table["row"].to_numpy(),
            [Edge(edge) for edge in table["edge"]],
            [Band(band) for band in table["band"]],
            table["rise_rows"].to_numpy(),
            table["strength"].to_numpy(),
            table["quality"].to_numpy(),
            [frozenset(Flag(flag) for flag in str(text).split(FLAG_SEPARATOR) if flag) for text in flags],
        )
    except (TypeError, ValueError) as error:
        raise InputError(
            f"{source}: not an events table ({first_line(error)}); give a table the detector wrote"
        ) from None


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
