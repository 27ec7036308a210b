"""Hostile inputs to every command, as a table: each case prepares its files, runs the command
and expects an exit code, one error line holding some words, and no output or temporary file
left behind (inputs unchanged)."""

from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_run import one_error_line, run

from flashsync.cli import main
from flashsync.simulation.encode import reencode


def _model(folder: Path, change=None, name: str = "bad.json") -> Path:
    """The synced scenario's model, changed by ``change(document)``, written to ``folder``."""
    document = json.loads((SYNCED / "sync.json").read_text())
    if change:
        change(document)
    (folder / name).write_text(json.dumps(document))
    return folder / name


def _camera(document: dict, index: int = 1) -> dict:
    return document["cameras"][index]


def _set(field: str, value, index: int = 1):
    return lambda document: _camera(document, index).__setitem__(field, value)


def _detections(folder: Path, name: str = "d.csv") -> Path:
    pd.DataFrame({"camera": ["r", "f"], "frame": [3, 4], "x": [10.0, 20.0], "y": [12.5, 30.0]}).to_csv(
        folder / name, index=False
    )
    return folder / name


def _parquet(folder: Path, **columns) -> Path:
    table = {"camera": ["r", "f"], "frame": [3, 4], "y": [12.5, 30.0]} | columns
    pd.DataFrame(table).to_parquet(folder / "d.parquet")
    return folder / "d.parquet"


def _restamp_with_model(change, *options):
    def prepare(tmp):
        return ["restamp", _detections(tmp), "--model", _model(tmp, change), "-o", tmp / "out" / "o.csv", *options]

    return prepare


def _resample(table, model=lambda tmp: SYNCED / "sync.json"):
    """``resample`` at 10 Hz of the table ``table(tmp)`` writes, with the model ``model(tmp)``
    writes (default the synced one)."""
    return lambda tmp: [
        "resample",
        table(tmp),
        "--model",
        model(tmp),
        "--rate",
        "10",
        "-o",
        tmp / "out" / "r.csv",
    ]


def _view_plane(*corners: str):
    """``view`` of the synced model with ``--plane`` at these corners, saved to a recording."""
    return lambda tmp: ["view", "--model", SYNCED / "sync.json", "--plane", *corners, "--save", tmp / "out" / "v.rrd"]


def _view_serve(*options: str):
    """``view --serve`` of the synced model with these options (refused before any server starts)."""
    return lambda tmp: ["view", "--model", SYNCED / "sync.json", "--serve", *options]


def _copy(tmp: Path, name: str) -> Path:
    (tmp / name).write_bytes((SYNCED / name).read_bytes())
    return tmp / name


def _truncated(tmp: Path, name: str, keep: float) -> Path:
    data = (SYNCED / name).read_bytes()
    (tmp / f"cut{Path(name).suffix}").write_bytes(data[: int(len(data) * keep)])
    return tmp / f"cut{Path(name).suffix}"


def _fast_start_cut(tmp: Path) -> Path:
    """s.mp4 remuxed with its index at the front, cut at a packet boundary two thirds in."""
    import av

    with (
        av.open(str(SYNCED / "s.mp4")) as source,
        av.open(str(tmp / "fast.mp4"), "w", options={"movflags": "faststart"}) as out,
    ):
        stream = out.add_stream_from_template(source.streams.video[0])
        for packet in source.demux(source.streams.video[0]):
            if packet.dts is not None:
                packet.stream = stream
                out.mux(packet)
    with av.open(str(tmp / "fast.mp4")) as container:
        positions = [p.pos for p in container.demux(video=0) if p.pos is not None and p.pos > 0]
    data = (tmp / "fast.mp4").read_bytes()
    (tmp / "cut.mp4").write_bytes(data[: positions[len(positions) * 2 // 3]])
    return tmp / "cut.mp4"


def _one_frame(tmp: Path) -> Path:
    """r.mp4's first frame alone as an MP4 (its header states the one frame's 40 ms)."""
    import av

    with av.open(str(SYNCED / "r.mp4")) as source, av.open(str(tmp / "one.mp4"), "w") as out:
        stream = out.add_stream("libx264", rate=25)
        stream.width, stream.height, stream.pix_fmt = 320, 180, "yuv420p"
        frame = next(source.decode(video=0))
        frame.pts = None
        for packet in [*stream.encode(frame), *stream.encode()]:
            out.mux(packet)
    return tmp / "one.mp4"


def _events_changed(tmp: Path, **last) -> Path:
    """The events of f.mkv, the last one's columns set to ``last``."""
    from flashsync.io import events_to_frame
    from flashsync.pipeline import all_events, detect_videos

    events = events_to_frame(all_events(detect_videos([SYNCED / "f.mkv"])))
    events.loc[events.index[-1], list(last)] = list(last.values())
    events.to_csv(tmp / "events.csv", index=False)
    return tmp / "events.csv"


def _validation_of(tmp: Path, camera_b: str) -> Path:
    """A validation JSON of one triple, camera r against ``camera_b``."""
    triple = {"camera_a": "r", "camera_b": camera_b, "object": "puck", "t_global_ms": 100.0}
    triple |= {"x_b": 1.0, "y_b": 2.0, "x_a": 1.0, "y_a": 2.5, "error_m": 0.5}
    (tmp / "v.json").write_text(json.dumps({"triples": [triple]}))
    return tmp / "v.json"


def _raw_stream(tmp: Path) -> Path:
    """r.mp4 as a raw H.264 stream (Annex B, as some IP cameras and recorders export it)."""
    reencode(SYNCED / "r.mp4", tmp / "r.h264", "libx264", "yuv420p", rate=25)
    return tmp / "r.h264"


def _size_change(tmp: Path) -> Path:
    """r.mp4 (320x180, 3.2 s) and then f.mkv (256x144) in one MPEG-TS file, its stamps going
    on (TS concatenates: a camera that changed resolution, an NVR's export)."""
    reencode(SYNCED / "r.mp4", tmp / "a.ts", "libx264", "yuv420p", rate=25)
    reencode(SYNCED / "f.mkv", tmp / "b.ts", "libx264", "yuv420p", rate=30, start_s=3.2)
    (tmp / "sizes.ts").write_bytes((tmp / "a.ts").read_bytes() + (tmp / "b.ts").read_bytes())
    return tmp / "sizes.ts"


def _homographies(tmp: Path, change) -> Path:
    document = json.loads((SYNCED / "homographies.json").read_text())
    change(document)
    (tmp / "h.json").write_text(json.dumps(document))
    return tmp / "h.json"


def _validate(tmp, *options, homographies=None, detections=None):
    return [
        "validate",
        detections or _detections(tmp),
        "--model",
        SYNCED / "sync.json",
        "--homographies",
        homographies or SYNCED / "homographies.json",
        *options,
    ]


def _nonfinite_std(document):
    _camera(document)["frame_std_ms"] = [math.nan] * len(_camera(document)["frame_times_ms"])


def _reversed_times(document):
    _camera(document)["frame_times_ms"] = _camera(document)["frame_times_ms"][::-1]


def _duplicate(document):
    document["cameras"].append(document["cameras"][1])


def _exposure_spans(first_frames):
    """Camera f's exposure in spans of one frame each, beginning at ``first_frames``."""
    spans = [
        {
            "first_frame": frame,
            "last_frame": frame,
            "exposure_ms": 2.0,
            "exposure_std_ms": 0.1,
            "n_bands": 1,
            "holds_frames": False,
        }
        for frame in first_frames
    ]
    return _set("exposure_spans", spans)


def _knots(document):
    _camera(document)["drift_knots_ms"] = [0.0, 100.0, 200.0]


def _one_frame_camera(document, name: str = "f"):
    """Camera f with its first frame alone (and none of its events)."""
    _camera(document)["frame_times_ms"] = _camera(document)["frame_times_ms"][:1]
    _camera(document)["name"] = name
    document["events"] = [event for event in document["events"] if event["camera"] != "f"]


def _one_frame_r_model(tmp: Path) -> Path:
    """A model whose camera "one" is r.mp4's size with one frame, as :func:`_one_frame` writes."""

    def change(document):
        _one_frame_camera(document, "one")
        _camera(document).update(width=320, height=180, flipped=False)

    return _model(tmp, change)


def _event_camera(document):
    document["events"][0]["camera"] = "nobody"


#: (id, prepare(tmp) -> argv, exit code, words of the error line)
CASES = [
    # outputs that would overwrite an input or each other, or cannot be written
    (
        "sync -o an input video",
        lambda t: ["sync", _copy(t, "r.mp4"), _copy(t, "f.mkv"), "-o", t / "r.mp4"],
        1,
        ["-o", "r.mp4", "is also an input (VIDEO"],
    ),
    (
        "sync --json the same as -o",
        lambda t: ["sync", SYNCED / "r.mp4", SYNCED / "f.mkv", "-o", t / "x.json", "--json", t / "x.json"],
        1,
        ["--json", "is the same file as -o"],
    ),
    (
        "sync --events the same as --rrd",
        lambda t: [
            "sync",
            SYNCED / "r.mp4",
            SYNCED / "f.mkv",
            "-o",
            t / "s.json",
            "--events",
            t / "e.csv",
            "--rrd",
            t / "e.csv",
        ],
        1,
        ["--rrd", "same file as --events"],
    ),
    (
        "restamp -o its detections",
        lambda t: ["restamp", _detections(t), "--model", SYNCED / "sync.json", "-o", t / "d.csv"],
        1,
        ["-o", "is also an input (DETECTIONS"],
    ),
    (
        "restamp -o a hard link to its detections",
        lambda t: ["restamp", _detections(t), "--model", SYNCED / "sync.json", "-o", _link(t / "d.csv", t / "l.csv")],
        1,
        ["-o", "l.csv", "is also an input"],
    ),
    (
        "restamp -o the model",
        lambda t: ["restamp", _detections(t), "--model", _model(t), "-o", t / "bad.json"],
        1,
        ["is also an input (--model"],
    ),
    (
        "validate --json its homographies",
        lambda t: _validate(t, "--json", _copy(t, "homographies.json"), homographies=t / "homographies.json"),
        1,
        ["--json", "is also an input (--homographies"],
    ),
    (
        "restamp a folder -o inside it",
        lambda t: [
            "restamp",
            _detections(_folder(t / "d")).parent,
            "--model",
            SYNCED / "sync.json",
            "-o",
            t / "d" / "out",
        ],
        1,
        ["d/out: is inside the detections folder", "give a folder outside it"],
    ),
    (
        "-o an existing folder",
        lambda t: ["restamp", _detections(t), "--model", SYNCED / "sync.json", "-o", _folder(t / "out" / "dir")],
        1,
        ["-o", "is a folder"],
    ),
    (
        "-o inside a file",
        lambda t: [
            "frames",
            "--model",
            SYNCED / "sync.json",
            "--rate",
            "10",
            "-o",
            _file(t / "out" / "plain") / "f.csv",
        ],
        1,
        ["-o", "plain is a file"],
    ),
    (
        "sync -o inside a file, before any decoding",
        lambda t: ["sync", SYNCED / "r.mp4", SYNCED / "f.mkv", "-o", _file(t / "out" / "plain") / "s.json"],
        1,
        ["-o", "is a file and not a folder"],
    ),
    ("simulate -o a file", lambda t: ["simulate", "tiny", "-o", _file(t / "out" / "x")], 1, ["-o", "is a file"]),
    # model files that would give wrong numbers
    ("model alpha NaN", _restamp_with_model(_set("alpha", math.nan)), 1, ["bad.json", "'f'", '"alpha"', "NaN"]),
    ("model beta_ms inf", _restamp_with_model(_set("beta_ms", math.inf)), 1, ['"beta_ms"', "Infinity"]),
    (
        "model frame time NaN",
        _restamp_with_model(lambda d: _camera(d)["frame_times_ms"].__setitem__(5, math.nan)),
        1,
        ['"frame_times_ms" [5]', "NaN"],
    ),
    ("model exposure NaN", _restamp_with_model(_set("exposure_ms", math.nan)), 1, ['"exposure_ms"', "finite"]),
    # rows that run backwards in time (sync leaves such a reading out; a model edited by hand)
    ("model time per row 0", _restamp_with_model(_set("row_time_ms", 0.0)), 1, ['"row_time_ms"', "positive"]),
    ("model time per row below 0", _restamp_with_model(_set("row_time_ms", -0.1)), 1, ['"row_time_ms"', "positive"]),
    ("model exposure as text", _restamp_with_model(_set("exposure_ms", "8")), 1, ['"exposure_ms"', 'text "8"']),
    ("model exposure sigma below 0", _restamp_with_model(_set("exposure_std_ms", -0.1)), 1, ['"exposure_std_ms"']),
    ("model exposure sigma NaN", _restamp_with_model(_set("exposure_std_ms", math.nan)), 1, ['"exposure_std_ms"']),
    (
        "model flipped as text",
        _restamp_with_model(_set("flipped", "false")),
        1,
        ['"flipped" is the text "false"', "true or false"],
    ),
    (
        "model version as text",
        _restamp_with_model(lambda d: d.__setitem__("version", "1")),
        1,
        ['"version" is the text "1"', "the number 1"],
    ),
    ("model version 2", _restamp_with_model(lambda d: d.__setitem__("version", 2)), 1, ["version 2 is not supported"]),
    ("model frame times reversed", _restamp_with_model(_reversed_times), 1, ['"frame_times_ms" is not increasing']),
    (
        "model reference not there",
        _restamp_with_model(lambda d: d.__setitem__("reference", "z")),
        1,
        ['"reference"', "not among the cameras"],
    ),
    (
        "model reference alpha not 1",
        _restamp_with_model(_set("alpha", 1.5, index=0)),
        1,
        ["reference", "alpha 1, beta_ms 0"],
    ),
    ("model camera twice", _restamp_with_model(_duplicate), 1, ["names f twice"]),
    ("model knots without warp", _restamp_with_model(_knots), 1, ['"drift_warp_ms" has 0 values, expected 1']),
    (
        "model 2x2 covariance with --std",
        _restamp_with_model(_set("covariance", [[1, 0], [0, 1]]), "--std"),
        1,
        ['"covariance"', "3 rows of 3"],
    ),
    ("model frame std NaN", _restamp_with_model(_nonfinite_std), 1, ['"frame_std_ms" [0]']),
    (
        "model display turn of 45 degrees",
        _restamp_with_model(_set("display_rotation_deg", 45)),
        1,
        ['"display_rotation_deg"', "is 45", "-90, 0, 90, 180"],
    ),
    (
        "model exposure spans out of order",
        _restamp_with_model(_exposure_spans([3, 1])),
        1,
        ["exposure_spans[1]", '"first_frame" is 1, not after the span before (to frame 3)'],
    ),
    (
        "model exposure span past the frames",
        _restamp_with_model(_exposure_spans([10**6])),
        1,
        ["exposure_spans[0]", '"last_frame" is 1000000, past the camera', "frames"],
    ),
    (
        "restamp --as-shown without x",
        lambda t: ["restamp", _parquet(t), "--model", SYNCED / "sync.json", "-o", t / "out" / "o.csv", "--as-shown"],
        1,
        ["d.parquet", "missing column x"],
    ),
    (
        "resample a camera of one frame in the model, no gap limit",
        _resample(
            lambda t: _bytes(t / "d.csv", b"camera,frame,x,y\nr,3,1,2\nf,0,1,2\n"),
            lambda t: _model(t, _one_frame_camera),
        ),
        1,
        ["bad.json: camera f has 1 frame in the model", "give the longest gap"],
    ),
    (
        "montage of a camera of one frame in the model, no rate",
        lambda t: ["montage", _one_frame(t), "--model", _one_frame_r_model(t), "-o", t / "out" / "m.mp4"],
        1,
        ["bad.json: camera one has one frame in the model", "give the rate of the ticks"],
    ),
    ("model event of an unknown camera", _restamp_with_model(_event_camera), 1, ["events[0]", "nobody"]),
    (
        "model event flash 1e308",
        _restamp_with_model(lambda d: d["events"][0].__setitem__("flash", 1e308)),
        1,
        ["events[0]", '"flash" is 1e+308', "below 2**63"],
    ),
    (
        "model a folder",
        lambda t: ["restamp", _detections(t), "--model", _folder(t / "m"), "-o", t / "out" / "o.csv"],
        1,
        ["m: is a folder"],
    ),
    # options
    (
        "--row-time of an unknown camera",
        lambda t: ["sync", SYNCED / "r.mp4", SYNCED / "f.mkv", "-o", t / "out" / "s.json", "--row-time", "z=0.03"],
        1,
        ["--row-time z", "no such camera"],
    ),
    (
        "--row-time inf",
        lambda t: ["sync", SYNCED / "r.mp4", SYNCED / "f.mkv", "--row-time", "r=inf"],
        1,
        ["--row-time r=inf", "finite"],
    ),
    (
        "--row-time nan",
        lambda t: ["sync", SYNCED / "r.mp4", SYNCED / "f.mkv", "--row-time", "r=nan"],
        1,
        ["--row-time r=nan"],
    ),
    (
        "--row-time twice",
        lambda t: ["sync", SYNCED / "r.mp4", SYNCED / "f.mkv", "--row-time", "r=0.1", "--row-time", "r=0.2"],
        1,
        ["--row-time r=0.2", "give one value"],
    ),
    (
        "contradictory --anchor",
        lambda t: ["sync", SYNCED / "r.mp4", SYNCED / "f.mkv", "--anchor", "r:0", "--anchor", "f:1", "--anchor", "r:2"],
        1,
        ["--anchor", "r:0 and r:2", "one event"],
    ),
    (
        "--anchor with a superscript digit",
        lambda t: ["sync", SYNCED / "r.mp4", SYNCED / "f.mkv", "-o", t / "out" / "s.json", "--anchor", "r:\u00b2"],
        1,
        ["--anchor r:\u00b2", "expected CAMERA:EVENT"],
    ),
    (
        "montage --cell with superscript digits",
        lambda t: ["montage", SYNCED / "r.mp4", "--model", SYNCED / "sync.json", "--cell", "\u00b2\u2070x16"],
        1,
        ["--cell \u00b2\u2070x16", "expected WIDTHxHEIGHT"],
    ),
    (
        "montage --cell wider than x264 encodes",
        lambda t: [
            "montage",
            SYNCED / "r.mp4",
            "--model",
            SYNCED / "sync.json",
            "--cell",
            "20000x16",
            "-o",
            t / "out" / "m.mp4",
        ],
        1,
        ["--cell 20000x16", "montage of 20000x16 px", "give smaller cells"],
    ),
    (
        "--exposure inf",
        lambda t: [
            "restamp",
            _detections(t),
            "--model",
            SYNCED / "sync.json",
            "-o",
            t / "out" / "o.csv",
            "--exposure",
            "r=inf",
        ],
        1,
        ["--exposure r=inf"],
    ),
    (
        "--exposure without a value: an exposure as the example",
        _restamp_with_model(None, "--exposure", "r"),
        1,
        ["--exposure r: expected CAMERA=MILLISECONDS, e.g. cam1=8"],
    ),
    (
        "--exposure longer than the frame period",
        _restamp_with_model(None, "--exposure", "r=50"),
        1,
        ["--exposure r=50: longer than camera r's frame period (40.00 ms)", "give the exposure in ms"],
    ),
    (
        "--exposure of an unknown camera",
        lambda t: [
            "restamp",
            _detections(t),
            "--model",
            SYNCED / "sync.json",
            "-o",
            t / "out" / "o.csv",
            "--exposure",
            "z=4",
        ],
        1,
        ["--exposure z"],
    ),
    (
        "validate no detection usable",
        lambda t: _validate(
            t,
            "--json",
            t / "out" / "v.json",
            detections=_bytes(t / "n.csv", b"camera,frame,x,y\nz,3,1,2\nr,99999,1,2\n"),
        ),
        1,
        ["n.csv: none of the 2 detections can be used", "1 unknown camera", "nothing to validate"],
    ),
    (
        "validate detections of one camera",
        lambda t: _validate(t, detections=_bytes(t / "one.csv", b"camera,frame,x,y\nr,3,1,2\nr,4,1,2\n")),
        1,
        ["one.csv: the 2 usable detections are all of one camera", "two cameras or more"],
    ),
    ("validate --max-gap-ms -5", lambda t: _validate(t, "--max-gap-ms", "-5"), 1, ["--max-gap-ms -5", "positive"]),
    ("validate --max-gap-ms nan", lambda t: _validate(t, "--max-gap-ms", "nan"), 1, ["--max-gap-ms nan"]),
    (
        "resample --max-gap-ms 0",
        lambda t: [
            "resample",
            _detections(t),
            "--model",
            SYNCED / "sync.json",
            "--rate",
            "10",
            "--max-gap-ms",
            "0",
            "-o",
            t / "out" / "r.csv",
        ],
        1,
        ["--max-gap-ms 0"],
    ),
    (
        "frames --rate nan",
        lambda t: ["frames", "--model", SYNCED / "sync.json", "--rate", "nan", "-o", t / "out" / "f.csv"],
        1,
        ["--rate nan"],
    ),
    (
        "frames --rate 1e308: more ticks than a float counts",
        lambda t: ["frames", "--model", SYNCED / "sync.json", "--rate", "1e308", "-o", t / "out" / "f.csv"],
        1,
        ["--rate 1e+308", "inf ticks", "lower the rate"],
    ),
    (
        "frames --rate 5e-324: an infinite period",
        lambda t: ["frames", "--model", SYNCED / "sync.json", "--rate", "5e-324", "-o", t / "out" / "f.csv"],
        1,
        ["--rate 5e-324", "positive number"],
    ),
    (
        "an option that is not a number",
        lambda t: ["frames", "--model", SYNCED / "sync.json", "--rate", "fast"],
        1,
        ["flashsync frames: error", "--rate", "invalid float"],
    ),
    (
        "--timestamps of one camera twice",
        lambda t: ["sync", SYNCED / "r.mp4", SYNCED / "f.mkv", "--timestamps", "r=a.csv", "--timestamps", "r=b.csv"],
        1,
        ["two timestamp files"],
    ),
    # detections
    (
        "parquet true/false in y",
        lambda t: ["restamp", _parquet(t, y=[True, False]), "--model", SYNCED / "sync.json", "-o", t / "out" / "o.csv"],
        1,
        ["column y holds true/false values"],
    ),
    (
        "parquet true/false in frame, read whole",
        _resample(lambda t: _parquet(t, frame=[True, False])),
        1,
        ["column frame holds true/false"],
    ),
    (
        "parquet lists in y",
        lambda t: [
            "restamp",
            _parquet(t, y=[[1.0, 2.0], [3.0]]),
            "--model",
            SYNCED / "sync.json",
            "-o",
            t / "out" / "o.parquet",
        ],
        1,
        ["column y holds lists or records"],
    ),
    (
        "CSV not UTF-8 in a camera name",
        lambda t: [
            "restamp",
            _bytes(t / "l.csv", b"camera,frame,y\nr,1,2\n\xe9r,2,3\n"),
            "--model",
            SYNCED / "sync.json",
            "-o",
            t / "out" / "o.csv",
        ],
        1,
        ["l.csv: line 3 is not UTF-8", "save the file as UTF-8"],
    ),
    (
        "CSV with classic Mac line endings",
        lambda t: [
            "restamp",
            _bytes(t / "mac.csv", b"camera,frame,y\rr,1,2\rr,2,3\r"),
            "--model",
            SYNCED / "sync.json",
            "-o",
            t / "out" / "o.csv",
        ],
        1,
        ["mac.csv: its lines end with \\r alone", "convert the line endings"],
    ),
    (
        "MOTChallenge frame as text, not called missing",
        lambda t: [
            "restamp",
            _bytes(t / "r.txt", b"4,1,10,10,5,5,1\nfour,1,10,10,5,5,1\n"),
            "--model",
            SYNCED / "sync.json",
            "-o",
            t / "out" / "o.csv",
        ],
        1,
        ["r.txt: row 2, column frame is 'four', not a number", "fix the file"],
    ),
    (
        "detections a folder without tables",
        lambda t: ["restamp", _folder(t / "d.csv"), "--model", SYNCED / "sync.json", "-o", t / "out" / "o.csv"],
        1,
        ["d.csv: holds no .parquet or .csv tables"],
    ),
    (
        "resample a folder of tables (only restamp takes one)",
        _resample(lambda t: _parquet(_folder(t / "parts")).parent),
        1,
        ["parts: is a folder, not a detections table", "give the tables in it by their file names"],
    ),
    (
        "resample a camera name with a trailing space",
        _resample(lambda t: _bytes(t / "sp.csv", b"camera,frame,x,y\nr ,3,1,2\n")),
        1,
        ["sp.csv: camera 'r ' is not in the model"],
    ),
    ("view --plane of no area", _view_plane("0", "0", "60", "0"), 1, ["--plane 0 0 60 0", "corners of a rectangle"]),
    ("view --plane nan", _view_plane("0", "0", "nan", "5"), 1, ["--plane 0 0 nan 5", "finite metres"]),
    ("view --serve --port 99999", _view_serve("--port", "99999"), 1, ["--port 99999: not a TCP port", "1-65535"]),
    ("view --serve --port 0: no port to wait on", _view_serve("--port", "0"), 1, ["--port 0: not a TCP port"]),
    (
        "view --serve --port the same as --grpc-port",
        _view_serve("--port", "9876"),
        1,
        ["--port 9876: the web viewer's port is also the recording stream's", "give each its own port"],
    ),
    (
        "view --spawn --grpc-port 70000",
        lambda t: ["view", "--model", SYNCED / "sync.json", "--spawn", "--grpc-port", "70000"],
        1,
        ["--grpc-port 70000: not a TCP port"],
    ),
    (
        "view --validation of a camera not in the model",
        lambda t: [
            "view",
            "--model",
            SYNCED / "sync.json",
            "--validation",
            _validation_of(t, "x"),
            "--save",
            t / "v.rrd",
        ],
        1,
        ["v.json: triples[0]", "\"camera_b\" is 'x', not a camera of the model (r, f, s)"],
    ),
    (
        "view --events past the end of a video",
        lambda t: [
            "view",
            "--model",
            SYNCED / "sync.json",
            "--events",
            _events_changed(t, frame=99999, t_frame_ms=1e7),
            "--save",
            t / "v.rrd",
        ],
        1,
        ["events.csv: an event of camera f on frame 99999, past its", "give the events of the videos"],
    ),
    (
        "view --events of a camera not in the model",
        lambda t: [
            "view",
            "--model",
            SYNCED / "sync.json",
            "--events",
            _events_changed(t, camera="x"),
            "--save",
            t / "v.rrd",
        ],
        1,
        ["events.csv: events of camera x, which is not in the model"],
    ),
    (
        "view --detections not re-stamped",
        lambda t: [
            "view",
            "--model",
            SYNCED / "sync.json",
            "--detections",
            _detections(t),
            "--save",
            t / "out" / "v.rrd",
        ],
        1,
        ["d.csv: missing column t_global_ms"],
    ),
    # timestamps, homographies, scenario, videos
    (
        "timestamps not increasing",
        lambda t: [
            "detect",
            SYNCED / "r.mp4",
            "--timestamps",
            _flat_stamps(t),
            "-o",
            t / "out" / "e.csv",
        ],
        1,
        ["ts.csv", "not increasing", "fix the CSV"],
    ),
    (
        "timestamps without a header line",
        lambda t: ["detect", SYNCED / "r.mp4", "--timestamps", "r=" + str(_bytes(t / "ts.csv", b"0\n40\n80\n"))],
        1,
        ["ts.csv: its first line, 0, is not a header", "add a header line"],
    ),
    (
        "homography of text numbers",
        lambda t: _validate(
            t, homographies=_homographies(t, lambda d: d.__setitem__("r", [["1", 0, 0], [0, 1, 0], [0, 0, 1]]))
        ),
        1,
        ['"r" [0][0] is the text "1"'],
    ),
    (
        "scenario seed as text",
        lambda t: ["simulate", _bytes(t / "s.yaml", b"preset: tiny\nseed: abc\n"), "-o", t / "out" / "sim"],
        1,
        ["s.yaml", "'seed' is the text \"abc\""],
    ),
    (
        "scenario duration 1e308 ms: no frame count",
        lambda t: ["simulate", _bytes(t / "s.yaml", b"preset: tiny\nduration_ms: 1.0e+308\n"), "-o", t / "out" / "sim"],
        1,
        ["s.yaml", "duration_ms times fps is too large"],
    ),
    (
        "scenario n_frames 1e30",
        lambda t: [
            "simulate",
            _bytes(
                t / "n.yaml",
                b"preset: tiny\ncameras: [{name: a, width: 64, height: 48, fps: 25.0, n_frames: 1"
                + b"0" * 30
                + b"}]\n",
            ),
            "-o",
            t / "out" / "sim",
        ],
        1,
        ["n.yaml", "camera a: n_frames 1" + "0" * 30, "limit of 1000000 frames"],
    ),
    (
        "scenario lasting 1e15 ms",
        lambda t: ["simulate", _bytes(t / "s.yaml", b"preset: tiny\nduration_ms: 1.0e+15\n"), "-o", t / "out" / "sim"],
        1,
        ["s.yaml", "duration_ms 1e+15 at 25 fps is 2.5e+13 frames", "limit of 1000000 frames"],
    ),
    (
        "scenario starting at 1e20 ms: stamps a container cannot hold",
        lambda t: [
            "simulate",
            _bytes(
                t / "s.yaml",
                b"preset: tiny\ncameras: [{name: a, width: 64, height: 48, fps: 25.0, start_ms: 1.0e+20}]\n",
            ),
            "-o",
            t / "out" / "sim",
        ],
        1,
        ["s.yaml", "camera a: start_ms 1e+20", "limit of 1e+12 ms"],
    ),
    (
        "scenario camera wider than x264 encodes",
        lambda t: [
            "simulate",
            _bytes(t / "w.yaml", b"preset: tiny\ncameras: [{name: a, width: 16386, height: 180, fps: 25.0}]\n"),
            "-o",
            t / "out" / "sim",
        ],
        1,
        ["w.yaml", "camera a", "at most 16384", "16386x180"],
    ),
    (
        "video a folder",
        lambda t: ["detect", _folder(t / "v.mp4"), "-o", t / "out" / "e.csv"],
        1,
        ["v.mp4: is a folder"],
    ),
    (
        "MKV cut short",
        lambda t: ["detect", _truncated(t, "f.mkv", 0.5), "-o", t / "out" / "e.csv"],
        1,
        ["cut.mkv: cut short", "header states"],
    ),
    (
        "MKV cut before its first whole frame",
        lambda t: ["detect", _truncated(t, "f.mkv", 0.1), "-o", t / "out" / "e.csv"],
        1,
        ["cut.mkv: cut short: no frame decoded", "header states", "copy the whole file again"],
    ),
    (
        "MP4 with its index at the front cut short",
        lambda t: ["detect", _fast_start_cut(t), "-o", t / "out" / "e.csv"],
        1,
        ["cut.mp4: cut short", "its index lists"],
    ),
    (
        "a video of one frame: not cut short",
        lambda t: ["detect", _one_frame(t), "-o", t / "out" / "e.csv"],
        1,
        ["one.mp4: only 1 frame decoded", "give a longer video"],
    ),
    (
        "a raw H.264 stream: no timestamps",
        lambda t: ["detect", _raw_stream(t), "-o", t / "out" / "e.csv"],
        1,
        ["r.h264: a frame has no timestamp", "ffmpeg -r FPS -i IN -c copy OUT.mkv", "--timestamps"],
    ),
    (
        "frames change size mid-video",
        lambda t: ["detect", _size_change(t), "-o", t / "out" / "e.csv"],
        1,
        ["sizes.ts: its frames change size at 3.200 s", "(320x180 -> 256x144)", "give each part as a video of its own"],
    ),
]

#: The synced scenario's folder (``synced_scenario``), set by :func:`synced` for the cases.
SYNCED: Path


@pytest.fixture(autouse=True)
def synced(synced_scenario):
    global SYNCED
    SYNCED = synced_scenario


def _flat_stamps(tmp: Path) -> str:
    """``r=FILE``: a timestamps CSV whose times do not increase."""
    path = _bytes(tmp / "ts.csv", b"t_ms" + b"\n0" * 76)
    return f"r={path}"


def _link(target: Path, link: Path) -> Path:
    os.link(target, link)
    return link


def _folder(path: Path) -> Path:
    path.mkdir(parents=True)
    return path


def _file(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("x")
    return path


def _bytes(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _digest(folder: Path) -> dict[str, str]:
    """Every file and folder under ``folder`` (hidden ones too) and a hash of each file."""
    return {
        str(path.relative_to(folder)): hashlib.sha1(path.read_bytes()).hexdigest() if path.is_file() else "folder"
        for path in folder.rglob("*")
    }


@pytest.mark.parametrize("prepare, code, words", [pytest.param(*case[1:], id=case[0]) for case in CASES])
def test_bad_input(synced_scenario, tmp_path, capsys, monkeypatch, prepare, code, words):
    before_synced = _digest(synced_scenario)
    monkeypatch.chdir(tmp_path)
    argv = [str(arg) for arg in prepare(tmp_path)]
    before = _digest(tmp_path)
    try:
        result = main(argv)
    except SystemExit as exit_:  # argparse
        result = exit_.code
    err = capsys.readouterr().err
    assert result == code, err
    one_error_line(err, *words)
    assert _digest(tmp_path) == before, "an input changed or an output was left"
    assert _digest(synced_scenario) == before_synced
    assert not [p for p in tmp_path.rglob(".*") if p.is_file()], "a temporary file was left"


def test_a_parquet_list_column_is_written_to_csv_as_json(synced_scenario, tmp_path, capsys):
    source = _parquet_with_boxes(tmp_path)
    assert (
        main(["restamp", str(source), "--model", str(synced_scenario / "sync.json"), "-o", str(tmp_path / "o.csv")])
        == 0
    )
    out = pd.read_csv(tmp_path / "o.csv")
    assert [json.loads(text) for text in out["bbox"]] == [[1.0, 2.0, 3.0, 4.0], [5.0, 6.0, 7.0, 8.0]]
    assert out["t_global_ms"].notna().all()


def _parquet_with_boxes(folder: Path) -> Path:
    table = pd.DataFrame({"camera": ["r", "f"], "frame": [3, 4], "y": [12.5, 30.0]})
    table["bbox"] = [np.array([1.0, 2.0, 3.0, 4.0]), np.array([5.0, 6.0, 7.0, 8.0])]
    table.to_parquet(folder / "boxes.parquet")
    return folder / "boxes.parquet"


def test_a_model_exposure_longer_than_the_frame_period_is_a_warning(synced_scenario, tmp_path, capsys):
    """A model's exposure longer than its camera's frame period (33.3 ms) is stamped with one warning
    naming the file; --exposure of that camera replaces it without one."""
    model = _model(tmp_path, _set("exposure_ms", 50.0))
    argv = ["restamp", _detections(tmp_path), "--model", model, "-o", tmp_path / "o.csv"]
    code, _, err = run(capsys, *argv)
    assert code == 0 and (tmp_path / "o.csv").exists()
    warning, summary = err.splitlines()
    assert warning.startswith("flashsync restamp: warning: ") and "Traceback" not in err
    assert "bad.json: camera f's exposure_ms, 50, is longer than its frame period (33.33 ms)" in warning
    assert "--exposure f=MS" in warning and summary.endswith("2 rows, 2 stamped")
    code, _, err = run(capsys, *argv, "--exposure", "f=8")
    assert code == 0 and "warning" not in err


def test_restamp_strict_fails_where_the_model_gives_no_finite_time(synced_scenario, tmp_path, capsys):
    """A model whose numbers overflow stamps nothing for that camera, says why, and --strict fails."""
    from flashsync.io import load_model, save_model

    model = load_model(synced_scenario / "sync.json")
    model.cameras["f"].alpha = 1e308
    save_model(model, tmp_path / "huge.json")
    detections = _detections(tmp_path)
    code = main(
        ["restamp", str(detections), "--model", str(tmp_path / "huge.json"), "-o", str(tmp_path / "o.csv"), "--strict"]
    )
    err = capsys.readouterr().err
    assert code == 1 and "1 no finite time from the model" in err
    out = pd.read_csv(tmp_path / "o.csv")
    assert np.isfinite(out["t_global_ms"][0]) and np.isnan(out["t_global_ms"][1])
    assert "inf" not in (tmp_path / "o.csv").read_text()
