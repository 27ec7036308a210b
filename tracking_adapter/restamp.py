"""Re-stamp tracker detections with global times from a :class:`~flashsync.model.SyncModel`.

Every input row and column is kept, in order and unchanged, and new columns follow:

``t_global_ms``
    End-of-exposure instant of the detection's row, reference clock, ms
    (docs/architecture.md, time convention); empty where the row cannot be stamped.
``t_global_std_ms``
    Its standard deviation from the solve's covariance, ms (only with ``with_std=True``).
``t_center_ms``
    Mid-exposure instant ``t_global_ms - exposure_ms / 2``, ms, the instant a blurred
    centroid belongs to; present when any model camera has a known exposure (from the
    model or given by the caller), empty for cameras whose exposure is unknown.
``t_center_std_ms``
    Its standard deviation, ms (with ``with_std=True`` and ``t_center_ms``): the root of
    the sum of the squares of ``t_global_std_ms`` and half the exposure's standard
    deviation (the model's ``exposure_std_ms``; a caller's exposure counts as exact), their
    correlation left out; empty where the model states no exposure standard deviation.
``restamp_error``
    Why a row was not stamped (one of :data:`REASONS`), empty for stamped rows.

A row is stamped when its camera is in the model, its frame is an integer in
``[0, n_frames)`` and its ``y`` (stored-image row, px) lies in ``[-0.5, height - 0.5]``,
the image's extent in pixel-centre coordinates. With ``as_shown``, ``x`` and ``y`` are in
the picture a player shows (the stored frame turned upright by the video's display matrix,
as OpenCV reads it by default; :meth:`~flashsync.model.CameraClock.stored_row`): a camera
turned a quarter either way takes its stored row from ``x``, which then lies in
``[-0.5, height - 0.5]``.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from flashsync.atomic import atomic_output
from flashsync.errors import InputError
from flashsync.io.detections import (
    REQUIRED_COLUMNS,
    check_required_types,
    detections_format,
    iter_csv_blocks,
    load_mot,
    read_csv_header,
    require_columns,
)
from flashsync.io.files import first_line
from flashsync.model import CameraClock, SyncModel
from flashsync.timestamps import median_step_ms

#: Why a row was not stamped, in the order the checks run (the first failing one is reported).
REASONS = (
    "camera missing",
    "unknown camera",
    "frame missing",
    "frame not a number",
    "frame not an integer",
    "frame negative",
    "frame past the end of the video",
    "y missing",
    "y not a number",
    "y outside the image rows",
    "x missing",
    "x not a number",
    "x outside the shown image",
    "no finite time from the model",
)
NEW_COLUMNS = ("t_global_ms", "t_global_std_ms", "t_center_ms", "t_center_std_ms", "restamp_error")
#: How far an exposure may exceed its camera's frame period before it is called longer, ms: the
#: rounding of 1 ms stamps (a period read from them can come out up to 1 ms short).
PERIOD_SLACK_MS = 1.0
_MISSING_TEXT = ["", "nan", "-nan", "na", "n/a", "null", "none"]
_BATCH_ROWS = 1 << 20


class Exposure(NamedTuple):
    """A camera's exposure in each of its decoded frames and its standard deviation, ms,
    shape (n_frames,) each (NaN: not stated)."""

    ms: np.ndarray
    std_ms: np.ndarray


def _coordinate_columns(as_shown: bool) -> tuple[str, ...]:
    """The columns a detection is stamped from: :data:`REQUIRED_COLUMNS`, and ``x`` for
    points given as shown."""
    return REQUIRED_COLUMNS + ("x",) * as_shown


@dataclass
class RestampSummary:
    """What :func:`restamp_file` did.

    Attributes
    ----------
    source, output : str
        Input and output files.
    rows : int
        Detections read (= written).
    stamped : int
        Rows given a ``t_global_ms``.
    failed : dict of str to int
        Rows not stamped, by reason (:data:`REASONS`), only reasons that occurred.
    unknown_cameras : set of str
        The cameras of the rows not stamped for an ``unknown camera`` (not in the model).
    """

    source: str
    output: str
    rows: int = 0
    stamped: int = 0
    failed: dict[str, int] = field(default_factory=dict)
    unknown_cameras: set[str] = field(default_factory=set)


def restamp(
    detections: pd.DataFrame,
    model: SyncModel,
    *,
    exposure_ms: Mapping[str, float] | None = None,
    with_std: bool = False,
    as_shown: bool = False,
    source: str = "detections",
) -> pd.DataFrame:
    """Add global times to a detections table.

    Parameters
    ----------
    detections : DataFrame
        Columns ``camera`` (name), ``frame`` (0-based decoded frame index), ``y`` (stored-
        image row, px) and any others, of any dtype (numbers as text are parsed).
    model : SyncModel
        The synchronisation model.
    exposure_ms : mapping of str to float, optional
        Exposure time per camera, ms; overrides the model's value for those cameras.
    with_std : bool
        Add ``t_global_std_ms`` (and ``t_center_std_ms``).
    as_shown : bool
        ``x`` and ``y`` are in the picture a player shows, not the stored frame's pixels
        (module docstring); ``x`` is then required too.
    source : str
        Name of the table's file, used in error messages.

    Returns
    -------
    DataFrame
        A copy of ``detections`` (same index, columns, dtypes and values) followed by
        ``t_global_ms`` (float64, NaN where not stamped), optionally ``t_global_std_ms``,
        ``t_center_ms`` and ``t_center_std_ms`` (float64), and ``restamp_error`` (str, NaN
        where stamped).

    Examples
    --------
    >>> stamped = restamp(pd.read_csv("detections.csv"), load_model("sync.json"))  # doctest: +SKIP
    >>> stamped.loc[stamped.restamp_error.isna(), "t_global_ms"]                    # doctest: +SKIP
    """
    names, needed = list(detections.columns), _coordinate_columns(as_shown)
    require_columns(names, needed, source)
    _check_free(names, source)
    exposures = _exposures(model, exposure_ms)
    arrays = [_series_to_arrow(detections[name]) for name in needed]
    check_required_types({"camera": arrays[0].type}, source)
    columns, reasons = _stamp(arrays, model, exposures, with_std)
    columns["restamp_error"] = pd.array(np.array([None, *REASONS], dtype=object)[reasons], dtype="str")
    return detections.assign(**{name: pd.Series(values, index=detections.index) for name, values in columns.items()})


def restamp_file(
    in_path: str | Path,
    out_path: str | Path,
    model: SyncModel,
    *,
    camera: str | None = None,
    input_format: str | None = None,
    exposure_ms: Mapping[str, float] | None = None,
    with_std: bool = False,
    as_shown: bool = False,
    block_bytes: int = 1 << 24,
) -> RestampSummary:
    """Re-stamp a detections file into another, streaming, with bounded memory.

    CSV to CSV copies every input line byte for byte and appends the new values, so
    nothing is reformatted. CSV to Parquet stores the input columns as text, exactly as
    in the CSV. Parquet input keeps its column types. A MOTChallenge file (one camera,
    read whole) becomes the table of :func:`~flashsync.io.detections.load_mot`. The
    output is written atomically: an interrupted run leaves no file behind.

    Parameters
    ----------
    in_path : str or Path
        Detections: ``.csv``, ``.parquet`` / ``.pq``, or ``.txt`` (MOTChallenge).
    out_path : str or Path
        ``.csv`` or ``.parquet`` / ``.pq``.
    model : SyncModel
        The synchronisation model.
    camera : str, optional
        Camera name of a MOTChallenge input; default: its file stem.
    input_format : {"csv", "parquet", "mot"}, optional
        Overrides the input's extension.
    exposure_ms : mapping of str to float, optional
        Exposure time per camera, ms; overrides the model's value.
    with_std : bool
        Add ``t_global_std_ms`` (and ``t_center_std_ms``).
    as_shown : bool
        ``x`` and ``y`` are in the picture a player shows (:func:`restamp`).
    block_bytes : int
        Size of the CSV blocks read at a time, bytes; memory use is a small multiple.

    Returns
    -------
    RestampSummary
        Rows read, stamped, and not stamped by reason; :func:`format_summary` prints it.
    """
    kind = detections_format(in_path, input_format)
    out_kind = detections_format(out_path)
    if camera is not None and kind != "mot":
        raise InputError(
            f"{in_path}: a camera name is only given for MOTChallenge files; "
            "the detections' camera column names the cameras"
        )
    if out_kind == "mot":
        raise InputError(
            f"{out_path}: re-stamped detections are written as .csv or .parquet; change the output extension"
        )
    exposures = _exposures(model, exposure_ms)
    summary = RestampSummary(source=str(in_path), output=str(out_path))
    needed = _coordinate_columns(as_shown)
    if kind == "csv" and out_kind == "csv":
        _restamp_csv_text(Path(in_path), Path(out_path), model, exposures, with_std, needed, block_bytes, summary)
    else:
        _restamp_batches(
            Path(in_path),
            kind,
            camera,
            Path(out_path),
            out_kind,
            model,
            exposures,
            with_std,
            needed,
            block_bytes,
            summary,
        )
    return summary


#: The files of a detections folder that are re-stamped: its tables (a partitioned dataset).
FOLDER_TABLES = (".parquet", ".pq", ".csv")


def restamp_folder(
    in_folder: str | Path,
    out_folder: str | Path,
    model: SyncModel,
    *,
    exposure_ms: Mapping[str, float] | None = None,
    with_std: bool = False,
    as_shown: bool = False,
    scheduler: str | None = None,
) -> RestampSummary:
    """Re-stamp a folder of detections tables (a partitioned dataset) partition by partition.

    Every ``.parquet``, ``.pq`` and ``.csv`` file under ``in_folder`` (sub-folders too, such as
    ``camera=cam1/``) is re-stamped by :func:`restamp_file` into the same relative path
    under ``out_folder``, in its own format; each file holds the required columns. The
    output folder appears whole or not at all: it is written beside its place under a
    temporary name and renamed once every partition is done, so it must not exist yet (or be
    empty).

    Parameters
    ----------
    in_folder, out_folder : str or Path
    model, exposure_ms, with_std, as_shown : as for :func:`restamp_file`.
    scheduler : ``tcp://HOST:PORT`` or ``local:N``: the partitions are re-stamped on that Dask
        cluster (:mod:`flashsync.cluster`), whose workers see both folders under the same paths.

    Returns
    -------
    RestampSummary
        Summed over the partitions.
    """
    in_folder, out_folder = Path(in_folder), Path(out_folder)
    files = sorted(p.relative_to(in_folder) for p in in_folder.rglob("*") if p.suffix.lower() in FOLDER_TABLES)
    if not files:
        raise InputError(f"{in_folder}: holds no .parquet or .csv tables; give a folder of detections tables")
    if out_folder.resolve().is_relative_to(in_folder.resolve()):
        raise InputError(
            f"{out_folder}: is inside the detections folder {in_folder}, whose tables it would join; give a folder "
            "outside it for the output"
        )
    if out_folder.exists() and (not out_folder.is_dir() or any(out_folder.iterdir())):
        raise InputError(f"{out_folder}: exists and is not an empty folder; give a new folder for the output")
    out_folder.parent.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=f".{out_folder.name}.", dir=out_folder.parent))
    options = {"exposure_ms": exposure_ms, "with_std": with_std, "as_shown": as_shown}
    try:
        sources, targets = [in_folder / f for f in files], [scratch / f for f in files]
        if scheduler is None:
            parts = [restamp_file(source, target, model, **options) for source, target in zip(sources, targets)]
        else:
            from flashsync.cluster import connect

            with connect(scheduler) as client:
                shared = client.scatter(model, broadcast=True)
                parts = client.gather(client.map(restamp_file, sources, targets, model=shared, **options))
        if out_folder.exists():
            out_folder.rmdir()
        scratch.rename(out_folder)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    summary = RestampSummary(source=str(in_folder), output=str(out_folder))
    for part in parts:
        summary.rows += part.rows
        summary.stamped += part.stamped
        for reason, count in part.failed.items():
            summary.failed[reason] = summary.failed.get(reason, 0) + count
        summary.unknown_cameras |= part.unknown_cameras
    return summary


def format_summary(summary: RestampSummary) -> str:
    """One line for the terminal, e.g. ``detections.csv -> out.csv: 1000 rows, 998 stamped,
    2 not stamped (2 unknown camera)``."""
    text = f"{summary.source} -> {summary.output}: {summary.rows} rows, {summary.stamped} stamped"
    if summary.failed:
        reasons = ", ".join(f"{count} {reason}" for reason, count in summary.failed.items())
        text += f", {summary.rows - summary.stamped} not stamped ({reasons})"
    return text


def _restamp_csv_text(
    in_path: Path,
    out_path: Path,
    model: SyncModel,
    exposures: dict[str, Exposure | None],
    with_std: bool,
    needed: tuple[str, ...],
    block_bytes: int,
    summary: RestampSummary,
) -> None:
    header = read_csv_header(in_path)
    require_columns(header.names, needed, in_path)
    _check_free(header.names, in_path)
    options = dict(
        read_options=pacsv.ReadOptions(column_names=header.names),
        parse_options=pacsv.ParseOptions(newlines_in_values=False),
        convert_options=pacsv.ConvertOptions(
            include_columns=list(needed),
            strings_can_be_null=True,
            column_types={name: pa.string() for name in needed},
        ),
    )
    names = _new_columns(exposures, with_std)
    with open(in_path, "rb") as source, atomic_output(out_path) as temporary, open(temporary, "wb") as output:
        source.seek(header.size)
        output.write(header.raw + b"," + ",".join(names).encode())
        line_number = 1  # the header's
        for block in iter_csv_blocks(source, block_bytes, header.eol):
            lines, filled = _lines(block, header.eol, in_path)
            try:
                table = pacsv.read_csv(pa.BufferReader(block), **options)
            except pa.ArrowInvalid as error:
                if "UTF8" in str(error):
                    raise InputError(
                        f"{in_path}: line {line_number + _first_not_utf8(block)} is not UTF-8 text; save the file "
                        "as UTF-8 CSV"
                    ) from None
                raise InputError(
                    f"{in_path}: {first_line(error)}; every row needs the header's {len(header.names)} columns"
                ) from None
            if table.num_rows != int(filled.sum()):
                raise InputError(f"{in_path}: a quoted value spans several lines; remove the line breaks inside values")
            columns, reasons = _stamp([table.column(name) for name in needed], model, exposures, with_std)
            _count(reasons, table.column("camera"), summary)
            texts = [pc.cast(pa.array(columns[name], from_pandas=True), pa.string()) for name in names[:-1]]
            texts.append(_reason_texts(reasons))
            joined = pc.binary_join_element_wise(
                lines.filter(pa.array(filled)),
                *(text.cast(pa.binary()) for text in texts),
                b",",
                null_handling="replace",
                null_replacement=b"",
            )
            if not filled.all():  # blank lines are kept as they are
                order = np.where(filled, np.cumsum(filled) - 1, len(joined) + np.cumsum(~filled) - 1)
                joined = pa.concat_arrays([joined, lines.filter(pa.array(~filled))]).take(pa.array(order))
            end = np.frombuffer(joined.buffers()[1], dtype=np.int32)[joined.offset + len(joined)]
            start = np.frombuffer(joined.buffers()[1], dtype=np.int32)[joined.offset]
            output.write(memoryview(joined.buffers()[2])[start:end])
            line_number += len(filled)
        output.write(header.eol)


def _first_not_utf8(block: bytes) -> int:
    """1-based number of the first line of ``block`` that is not UTF-8 text (0 if none)."""
    for number, line in enumerate(block.split(b"\n"), start=1):
        try:
            line.decode("utf-8")
        except UnicodeDecodeError:
            return number
    return 0


def _lines(block: bytes, eol: bytes, path: Path) -> tuple[pa.BinaryArray, np.ndarray]:
    """Every line of ``block`` as ``eol + line`` (line endings moved to the front), and a
    mask of those that are not blank (the rows; a CSV reader skips blank lines)."""
    data = np.frombuffer(block, dtype=np.uint8)
    ends = np.flatnonzero(data == ord("\n"))
    carriage = data[ends - 1] == ord("\r")
    if not np.all(carriage == (eol == b"\r\n")):
        raise InputError(
            f"{path}: mixed line endings (\\n and \\r\\n); convert the file to one kind, e.g. with dos2unix"
        )
    offsets = np.concatenate([[0], ends + 1]).astype(np.int32)
    buffer = pa.py_buffer(eol + block[: -len(eol)])
    lines = pa.Array.from_buffers(pa.binary(), len(ends), [None, pa.py_buffer(offsets), buffer])
    return lines, np.diff(offsets) > len(eol)


def _restamp_batches(
    in_path: Path,
    kind: str,
    camera: str | None,
    out_path: Path,
    out_kind: str,
    model: SyncModel,
    exposures: dict[str, Exposure | None],
    with_std: bool,
    needed: tuple[str, ...],
    block_bytes: int,
    summary: RestampSummary,
) -> None:
    schema, batches = _read_batches(in_path, kind, camera, block_bytes)
    require_columns(schema.names, needed, in_path)
    check_required_types(dict(zip(schema.names, schema.types)), in_path)
    _check_free(schema.names, in_path)
    nested = [i for i, kind in enumerate(schema.types) if out_kind == "csv" and pa.types.is_nested(kind)]
    for i in nested:  # CSV holds no lists: they are written as JSON text
        schema = schema.set(i, pa.field(schema.names[i], pa.string()))
    names = _new_columns(exposures, with_std)
    for name in names:
        schema = schema.append(pa.field(name, pa.string() if name == "restamp_error" else pa.float64()))
    with atomic_output(out_path) as temporary:
        writer = pq.ParquetWriter(temporary, schema) if out_kind == "parquet" else pacsv.CSVWriter(temporary, schema)
        with writer:
            try:
                for batch in batches:
                    columns, reasons = _stamp([batch.column(name) for name in needed], model, exposures, with_std)
                    _count(reasons, batch.column("camera"), summary)
                    new = [pa.array(columns[name], from_pandas=True) for name in names[:-1]]
                    old = [_json_texts(column) if i in nested else column for i, column in enumerate(batch.columns)]
                    writer.write_batch(pa.RecordBatch.from_arrays([*old, *new, _reason_texts(reasons)], schema=schema))
            except pa.ArrowInvalid as error:
                raise InputError(f"{in_path}: {first_line(error)}; fix the file") from None


def _read_batches(
    path: Path, kind: str, camera: str | None, block_bytes: int
) -> tuple[pa.Schema, Iterator[pa.RecordBatch]]:
    """The schema of a detections file and an iterator over its record batches."""
    try:
        if kind == "parquet":
            parquet = pq.ParquetFile(path)
            return parquet.schema_arrow, parquet.iter_batches(batch_size=_BATCH_ROWS)
        if kind == "mot":
            table = pa.Table.from_pandas(load_mot(path, camera), preserve_index=False)
            return table.schema, iter(table.to_batches(max_chunksize=_BATCH_ROWS))
        header = read_csv_header(path)
        reader = pacsv.open_csv(
            path,
            read_options=pacsv.ReadOptions(block_size=block_bytes),
            convert_options=pacsv.ConvertOptions(column_types={name: pa.string() for name in header.names}),
        )
        return reader.schema, reader
    except (OSError, pa.ArrowException) as error:
        raise InputError(f"{path}: cannot read it as {kind} ({first_line(error)}); check the file") from None


def _stamp(
    arrays: list[pa.Array], model: SyncModel, exposures: dict[str, Exposure | None], with_std: bool
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Stamp the rows given by their ``camera``, ``frame`` and ``y`` arrays, and an ``x``
    array where the points are given as shown (:func:`_coordinate_columns`).

    Returns
    -------
    columns : dict of str to ndarray of shape (n,)
        ``t_global_ms``, optionally ``t_global_std_ms``, ``t_center_ms`` and
        ``t_center_std_ms``, ms, NaN where not stamped.
    reasons : ndarray of shape (n,), int8
        0 where stamped, else ``1 +`` index into :data:`REASONS`.
    """
    codes, names = _camera_codes(arrays[0])
    frame, frame_text = _to_float(arrays[1])
    y, y_text = _to_float(arrays[2])
    as_shown = len(arrays) == 4
    x, x_text = _to_float(arrays[3]) if as_shown else (np.full(len(y), np.nan), np.zeros(len(y), dtype=bool))
    clocks = [model.cameras.get(name) for name in names]
    codes = np.where(codes < 0, len(clocks), codes)  # missing camera -> last entry
    known = np.array([clock is not None for clock in clocks] + [True])
    n_frames = np.array([clock.n_frames if clock else 0 for clock in clocks] + [0])
    height = np.array([clock.height if clock else 0 for clock in clocks] + [0])
    sideways = np.array([as_shown and clock is not None and clock.sideways for clock in clocks], dtype=bool)
    from_x = np.append(sideways, False)[codes]  # the stored row comes from x
    with np.errstate(invalid="ignore"):
        checks = [
            codes == len(clocks),
            ~known[codes],
            np.isnan(frame) & ~frame_text,
            frame_text,
            np.floor(frame) != frame,
            frame < 0,
            frame >= n_frames[codes],
            np.isnan(y) & ~y_text & ~from_x,
            y_text & ~from_x,
            ((y < -0.5) | (y > height[codes] - 0.5)) & ~from_x,
            np.isnan(x) & ~x_text & from_x,
            x_text & from_x,
            ((x < -0.5) | (x > height[codes] - 0.5)) & from_x,
        ]
    reasons = np.zeros(len(frame), dtype=np.int8)
    for code, failed in enumerate(checks, start=1):
        reasons[(reasons == 0) & failed] = code
    columns = {name: np.full(len(frame), np.nan) for name in _new_columns(exposures, with_std)[:-1]}
    for code, clock in enumerate(clocks):
        rows = np.flatnonzero((codes == code) & (reasons == 0))
        if clock is None or not len(rows):
            continue
        frames = frame[rows].astype(np.int64)
        stored = clock.stored_row(x[rows], y[rows]) if as_shown else y[rows]
        with np.errstate(over="ignore", invalid="ignore"):  # a time that overflows gets a reason below
            columns["t_global_ms"][rows] = clock.t_global_ms(frames, stored)
            if "t_global_std_ms" in columns:
                columns["t_global_std_ms"][rows] = clock.t_global_std_ms(frames, stored)
        exposure = exposures[clock.name]
        if "t_center_ms" in columns and exposure is not None:
            columns["t_center_ms"][rows] = columns["t_global_ms"][rows] - exposure.ms[frames] / 2
            if "t_center_std_ms" in columns:
                columns["t_center_std_ms"][rows] = np.hypot(
                    columns["t_global_std_ms"][rows], exposure.std_ms[frames] / 2
                )
    computed = [columns[name] for name in ("t_global_ms", "t_global_std_ms") if name in columns]
    infinite = ~np.all([np.isfinite(values) for values in computed], axis=0)
    reasons[infinite & (reasons == 0)] = len(REASONS)
    for values in columns.values():
        values[reasons != 0] = np.nan
    return columns, reasons


def camera_list(names: Iterable[object]) -> str:
    """Camera names for an error line, comma-separated; a name that spaces begin or end is
    quoted (``'cam1 '``), where they would not show."""
    return ", ".join(repr(name) if name != name.strip() else name for name in map(str, names))


def _camera_codes(array: pa.Array | pa.ChunkedArray) -> tuple[np.ndarray, list[str]]:
    """Integer codes (-1 = missing) and the distinct names of a camera column."""
    array = _plain(array)
    if not pa.types.is_string(array.type) and not pa.types.is_large_string(array.type):
        array = array.cast(pa.string())
    array = pc.if_else(pc.equal(array, ""), pa.scalar(None, array.type), array)
    encoded = pc.dictionary_encode(array)
    codes = pc.fill_null(encoded.indices, -1).to_numpy(zero_copy_only=False).astype(np.int64)
    return codes, encoded.dictionary.to_pylist()


def _to_float(array: pa.Array | pa.ChunkedArray) -> tuple[np.ndarray, np.ndarray]:
    """Numbers of a column as float64 (NaN where missing or not a number), and a mask of
    the values that are present but not numbers."""
    array = _plain(array)
    kind = array.type
    if pa.types.is_boolean(kind) or pa.types.is_nested(kind) or pa.types.is_temporal(kind):
        # true/false, lists, dates and durations: not frame numbers nor rows
        present = np.asarray(array.is_valid().to_numpy(zero_copy_only=False), dtype=bool)
        return np.full(len(array), np.nan), present
    if pa.types.is_integer(kind) or pa.types.is_floating(kind) or pa.types.is_decimal(kind):
        # unsafe: a whole number beyond 2**53 is rounded (it is past any video's end), not refused
        values = array.cast(pa.float64(), safe=False)
        return values.to_numpy(zero_copy_only=False), np.zeros(len(array), dtype=bool)
    try:
        values = pc.cast(array, pa.float64())
        return values.to_numpy(zero_copy_only=False), np.zeros(len(array), dtype=bool)
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
        pass
    text = pd.Series(array.cast(pa.string()).to_pandas(), dtype="str")
    values = pd.to_numeric(text, errors="coerce").to_numpy(dtype=np.float64, na_value=np.nan)
    missing = text.isna() | text.str.strip().str.lower().isin(_MISSING_TEXT)
    return values, np.isnan(values) & ~missing.to_numpy(dtype=bool)


def _plain(array: pa.Array | pa.ChunkedArray) -> pa.Array:
    """A single, non-dictionary array."""
    if isinstance(array, pa.ChunkedArray):
        array = array.combine_chunks()
    if pa.types.is_dictionary(array.type):
        array = array.dictionary_decode()
    return array


def _series_to_arrow(series: pd.Series) -> pa.Array:
    try:
        return pa.array(series, from_pandas=True)
    except (pa.ArrowInvalid, pa.ArrowTypeError):  # mixed Python objects
        return pa.array(series.astype("str"), from_pandas=True)


def _json_texts(array: pa.Array) -> pa.Array:
    """Lists and records as JSON text (empty where missing): how a CSV holds them."""
    return pa.array([None if value is None else json.dumps(value) for value in array.to_pylist()], pa.string())


def _reason_texts(reasons: np.ndarray) -> pa.Array:
    return pc.take(pa.array([None, *REASONS], type=pa.string()), pa.array(reasons))


def _count(reasons: np.ndarray, cameras: pa.Array, summary: RestampSummary) -> None:
    """Add the rows of ``reasons`` (0 stamped, else 1 + the index in :data:`REASONS`) and the
    ``cameras`` (one per row) of those of an unknown camera to ``summary``."""
    unknown = np.flatnonzero(reasons == 1 + REASONS.index("unknown camera"))
    if unknown.size:
        summary.unknown_cameras |= {str(name) for name in pc.take(cameras, pa.array(unknown)).to_pylist()}
    counts = np.bincount(reasons, minlength=len(REASONS) + 1)
    summary.rows += len(reasons)
    summary.stamped += int(counts[0])
    for reason, count in zip(REASONS, counts[1:]):
        if count:
            summary.failed[reason] = summary.failed.get(reason, 0) + int(count)


def _exposures(model: SyncModel, exposure_ms: Mapping[str, float] | None) -> dict[str, Exposure | None]:
    """Each model camera's exposure frame by frame (None if unknown): the caller's, taken as
    exact throughout, else the model's (:meth:`~flashsync.model.CameraClock.exposure_at`: where
    it changes while the camera records, each frame's)."""
    given = dict(exposure_ms or {})
    unknown = [name for name in given if name not in model.cameras]
    if unknown:
        raise InputError(
            f"{', '.join(unknown)}: exposure given for a camera the model does not have "
            f"(it has {', '.join(model.cameras)}); fix the name",
            parameter="exposure_ms",
        )
    for name, value in given.items():
        if not (isinstance(value, (int, float)) and np.isfinite(value) and value >= 0):
            raise InputError(f"exposure of camera {name} is {value!r}; give a time >= 0 in ms")
        period = longer_than_frame(model.cameras[name], value)
        if period is not None:
            raise InputError(
                f"{name}={value:g}: longer than camera {name}'s frame period ({period:.2f} ms); a video camera exposes "
                "each frame within its period - give the exposure in ms",
                parameter="exposure_ms",
            )
    exposures = {}
    for name, clock in model.cameras.items():
        if name in given:
            exposures[name] = Exposure(np.full(clock.n_frames, float(given[name])), np.zeros(clock.n_frames))
        elif clock.exposure_ms is not None:
            exposures[name] = Exposure(*clock.exposure_at(np.arange(clock.n_frames)))
    return {name: exposures.get(name) for name in model.cameras}


def longer_than_frame(clock: CameraClock, exposure_ms: float) -> float | None:
    """The camera's frame period (median step of its frame times, ms) where ``exposure_ms`` is
    longer than it by over :data:`PERIOD_SLACK_MS`, else None: no video camera exposes a frame
    for longer than its period."""
    period = median_step_ms(clock.frame_times_ms)
    return period if clock.n_frames > 1 and exposure_ms > period + PERIOD_SLACK_MS else None


def _new_columns(exposures: dict[str, Exposure | None], with_std: bool) -> list[str]:
    """The columns restamp adds, in order."""
    wanted = {"t_global_ms", "restamp_error"}
    if with_std:
        wanted.add("t_global_std_ms")
    if any(value is not None for value in exposures.values()):
        wanted.update(("t_center_ms", "t_center_std_ms") if with_std else ("t_center_ms",))
    return [name for name in NEW_COLUMNS if name in wanted]


def _check_free(columns: list, source: str | Path) -> None:
    taken = [name for name in NEW_COLUMNS if name in columns]
    if taken:
        raise InputError(
            f"{source}: already has column {', '.join(taken)}; restamp the original detections or drop those columns"
        )
