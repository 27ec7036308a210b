"""Tracker detections in and out: CSV, Parquet and MOTChallenge files.

A detections table has one row per detection with at least ``camera`` (name = video file
stem), ``frame`` (0-based decoded frame index) and ``y`` (stored-image row, px, top = 0);
``x`` (px), an object id (``object`` or ``id``) and anything else are optional.

The format of a file follows its extension: ``.csv`` CSV, ``.parquet`` / ``.pq`` Parquet,
``.txt`` MOTChallenge (one file per camera).
"""

from __future__ import annotations

import csv
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from flashsync.errors import InputError
from flashsync.io.files import existing_file, first_line
from flashsync.io.tables import write_table

REQUIRED_COLUMNS = ("camera", "frame", "y")
MOT_COLUMNS = ("frame", "id", "bb_left", "bb_top", "bb_width", "bb_height", "conf")
_EXTENSIONS = {".csv": "csv", ".parquet": "parquet", ".pq": "parquet", ".txt": "mot"}
_UTF8_BOM = b"\xef\xbb\xbf"


def detections_format(path: str | Path, input_format: str | None = None) -> str:
    """The format of a detections file: ``"csv"``, ``"parquet"`` or ``"mot"``.

    Parameters
    ----------
    path : str or Path
        The file; its extension decides unless ``input_format`` is given.
    input_format : {"csv", "parquet", "mot"}, optional
        Explicit format, e.g. for a MOTChallenge file named ``*.csv``.
    """
    if input_format is not None:
        if input_format not in set(_EXTENSIONS.values()):
            raise InputError(f"{path}: unknown detections format {input_format!r}; use csv, parquet or mot")
        return input_format
    try:
        return _EXTENSIONS[Path(path).suffix.lower()]
    except KeyError:
        raise InputError(
            f"{path}: unknown detections file type {Path(path).suffix!r}; name it .csv, .parquet or .txt (MOTChallenge)"
        ) from None


def require_columns(columns: Iterable[str], required: Iterable[str], source: str | Path) -> None:
    """Raise an :class:`~flashsync.errors.InputError` naming ``source`` if a column name is duplicated or
    a required one is missing."""
    columns = list(columns)
    duplicates = sorted({str(name) for name in columns if columns.count(name) > 1})
    if duplicates:
        raise InputError(
            f"{source}: duplicate column names {', '.join(duplicates)}; rename them so that every column name is unique"
        )
    missing = [name for name in required if name not in columns]
    if missing:
        raise InputError(
            f"{source}: missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
            f"(it has {', '.join(map(str, columns)) or 'no columns'}); detections need "
            f"{', '.join(REQUIRED_COLUMNS)}: rename the columns or convert the file"
        )


def check_required_types(types: dict[str, pa.DataType], source: str | Path) -> None:
    """Raise an :class:`~flashsync.errors.InputError` naming ``source`` if a required column
    holds what cannot be a camera name, a frame or a row in any row: true/false values in
    ``frame`` or ``y`` (they would read as 1 and 0), or lists and records in any of them.
    ``types`` maps column names to Arrow types (other columns may hold anything)."""
    for name in REQUIRED_COLUMNS:
        kind = types.get(name)
        if kind is None:
            continue
        nested = pa.types.is_nested(kind)
        if nested or (name != "camera" and pa.types.is_boolean(kind)):
            held = "lists or records" if nested else "true/false values"
            wanted = "camera names" if name == "camera" else "numbers"
            raise InputError(
                f"{source}: column {name} holds {held} ({kind}), expected {wanted}; "
                "write plain values in the required columns camera, frame, y"
            )


def load_detections(path: str | Path, *, camera: str | None = None, input_format: str | None = None) -> pd.DataFrame:
    """Read a detections file into a DataFrame (column types inferred).

    Parameters
    ----------
    path : str or Path
        CSV, Parquet or MOTChallenge file (see :func:`detections_format`).
    camera : str, optional
        Camera name of a MOTChallenge file; default: the file stem.
    input_format : {"csv", "parquet", "mot"}, optional
        Overrides the extension.

    Returns
    -------
    DataFrame
        The file's columns; for MOTChallenge the columns of :func:`load_mot`.

    Examples
    --------
    >>> tables = [load_detections(p) for p in ["cam1.txt", "cam2.txt"]]  # doctest: +SKIP
    >>> detections = pd.concat(tables, ignore_index=True)                  # doctest: +SKIP
    """
    if Path(path).is_dir():
        raise InputError(
            f"{path}: is a folder, not a detections table; give the tables in it by their file names "
            "(.csv, .parquet or .txt)"
        )
    path = existing_file(path)
    kind = detections_format(path, input_format)
    if kind == "mot":
        return load_mot(path, camera=camera)
    try:
        if kind == "parquet":
            schema = pq.read_schema(path)
            check_required_types(dict(zip(schema.names, schema.types)), path)
            return pd.read_parquet(path)
        table = pd.read_csv(path)
    except UnicodeDecodeError as error:
        raise InputError(f"{path}: not UTF-8 text (byte {error.start}); save the file as UTF-8 CSV") from None
    except (OSError, ValueError, pd.errors.ParserError, pa.ArrowException) as error:
        raise InputError(f"{path}: cannot read it as {kind} ({first_line(error)}); check the file") from None
    check_required_types({name: pa.bool_() for name in table.columns if pd.api.types.is_bool_dtype(table[name])}, path)
    return table


def save_detections(table: pd.DataFrame, path: str | Path) -> None:
    """Write ``table`` to ``path`` (CSV or Parquet by extension) atomically, without index."""
    kind = detections_format(path)
    if kind == "mot":
        raise InputError(f"{path}: detections are written as .csv or .parquet, not .txt; change the output extension")
    write_table(table, path)


def load_mot(path: str | Path, camera: str | None = None) -> pd.DataFrame:
    """Read a MOTChallenge file (one camera) as a detections table.

    The file has comma-separated ``frame, id, bb_left, bb_top, bb_width, bb_height, conf,
    ...`` with 1-based frames, with or without a header line. Box coordinates are taken as
    stored-image pixels with top = 0 (a 1-based convention moves a time by one row time,
    some 0.03 ms).

    Parameters
    ----------
    path : str or Path
        The MOTChallenge file.
    camera : str, optional
        Camera name; default: the file stem (``cam1.txt`` -> ``cam1``).

    Returns
    -------
    DataFrame
        ``camera``; ``frame`` (0-based: MOT frame - 1); ``object`` (the MOT id); ``x``,
        ``y`` (box centre, px); then the MOT columns other than ``frame`` and ``id`` in
        file order: ``bb_left, bb_top, bb_width, bb_height, conf`` and further columns
        named by the header, or ``mot_8``, ``mot_9``, ... (1-based position) without one.
        A header name that clashes with the new columns gets a ``mot_`` prefix.
    """
    path = existing_file(path)
    with open(path, "rb") as file:
        first = file.readline().decode("utf-8", errors="replace").strip()
    fields = [field.strip() for field in first.split(",")]
    has_header = bool(first) and not _is_number(fields[0])
    try:
        table = pd.read_csv(path, header=0 if has_header else None, skipinitialspace=True)
    except (OSError, ValueError, pd.errors.ParserError) as error:
        raise InputError(
            f"{path}: cannot read it as a MOTChallenge file ({first_line(error)}); check the file"
        ) from None
    if not has_header:
        if table.shape[1] < len(MOT_COLUMNS) - 1:
            raise InputError(
                f"{path}: {table.shape[1]} columns, a MOTChallenge file has at least 6 "
                f"({', '.join(MOT_COLUMNS[:6])}); check the file or its format"
            )
        table.columns = [MOT_COLUMNS[i] if i < len(MOT_COLUMNS) else f"mot_{i + 1}" for i in range(table.shape[1])]
    table.columns = [str(name).strip() for name in table.columns]
    require_mot = MOT_COLUMNS[:6]
    missing = [name for name in require_mot if name not in table.columns]
    if missing:
        raise InputError(
            f"{path}: MOTChallenge header lacks {', '.join(missing)}; use the "
            f"columns {', '.join(MOT_COLUMNS)} or remove the header line"
        )
    numbers = {name: pd.to_numeric(table[name], errors="coerce") for name in require_mot}
    for name in ("frame", "bb_left", "bb_top", "bb_width", "bb_height"):  # the id may be text
        text = table[name][numbers[name].isna() & table[name].notna()]
        if len(text):
            row = table.index.get_loc(text.index[0]) + 1
            raise InputError(
                f"{path}: row {row}{' after the header' if has_header else ''}, column {name} is {text.iloc[0]!r}, "
                "not a number; a MOTChallenge file holds numbers there - fix the file"
            )
    new = pd.DataFrame(
        {
            "camera": camera if camera is not None else path.stem,
            "frame": numbers["frame"] - 1,
            "object": table["id"],
            "x": numbers["bb_left"] + numbers["bb_width"] / 2,
            "y": numbers["bb_top"] + numbers["bb_height"] / 2,
        },
        index=table.index,
    )
    rest = table.drop(columns=["frame", "id"])
    rest.columns = [f"mot_{name}" if name in new.columns else name for name in rest.columns]
    return pd.concat([new, rest], axis=1)


@dataclass(frozen=True)
class CsvHeader:
    """The header line of a CSV file.

    Attributes
    ----------
    names : list of str
        Column names (a UTF-8 byte-order mark removed).
    raw : bytes
        The header line as stored, without its line ending.
    eol : bytes
        The file's line ending, ``b"\\n"`` or ``b"\\r\\n"``.
    size : int
        Bytes from the start of the file to the first data row.
    """

    names: list[str]
    raw: bytes
    eol: bytes
    size: int


def read_csv_header(path: str | Path) -> CsvHeader:
    """Read the header line of a CSV file; an error for an empty file."""
    path = existing_file(path)
    with open(path, "rb") as file:
        line = file.readline()
    if not line.strip():
        raise InputError(
            f"{path}: empty file or empty first line; a detections CSV starts "
            "with a header line such as camera,frame,x,y"
        )
    eol = b"\r\n" if line.endswith(b"\r\n") else b"\n"
    raw = line[: -len(eol)] if line.endswith(eol) else line
    if b"\r" in raw:
        raise InputError(
            f"{path}: its lines end with \\r alone (a classic Mac CSV); convert the line endings to \\n or "
            "\\r\\n, e.g. with mac2unix"
        )
    text = raw[len(_UTF8_BOM) :] if raw.startswith(_UTF8_BOM) else raw
    try:
        names = next(csv.reader([text.decode("utf-8")]))
    except UnicodeDecodeError:
        raise InputError(f"{path}: the header line is not UTF-8 text; save the file as UTF-8 CSV") from None
    return CsvHeader(names=names, raw=raw, eol=eol, size=len(line))


def iter_csv_blocks(file: BinaryIO, block_bytes: int, eol: bytes = b"\n") -> Iterator[bytes]:
    """Yield the rest of an open binary file in blocks of whole lines.

    Every block ends with ``b"\\n"`` (``eol`` is added after a last line without one) and
    is at most about ``block_bytes`` long, unless a single line is longer. Quoted values
    that span lines are split like any other line.
    """
    carry = b""
    while chunk := file.read(block_bytes):
        chunk = carry + chunk
        cut = chunk.rfind(b"\n") + 1
        carry = chunk[cut:]
        if cut:
            yield chunk[:cut]
    if carry:
        yield carry + eol


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
