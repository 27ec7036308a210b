"""The ``flashsync`` command: a thin layer over the library API.

Every command prints one clear line on stderr and exits non-zero on bad input; outputs are
written atomically.
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import shutil
import signal
import sys
import threading
from collections.abc import Iterable
from pathlib import Path

from flashsync.atomic import check_output, remove_temporaries
from flashsync.errors import FlashsyncError, InputError, ModelFileError

EXAMPLES = {
    "detect": "flashsync detect cam1.mp4 cam2.mkv -o events.csv\n"
    "  flashsync detect /shared/game1/*.mp4 -o events.csv --scheduler tcp://scheduler:8786   (on a Dask cluster)",
    "sync": "flashsync sync cam1.mp4 cam2.mkv cam3.mp4 -o sync.json",
    "restamp": "flashsync restamp detections.csv --model sync.json -o restamped.csv\n"
    "  flashsync restamp detections/ --model sync.json -o restamped/   (a folder of Parquet files)",
    "validate": "flashsync validate restamped.csv --model sync.json --homographies homographies.json",
    "view": "flashsync sync cam1.mp4 cam2.mkv cam3.mp4 -o sync.json --events events.csv\n"
    "  flashsync restamp detections.csv --model sync.json -o restamped.csv\n"
    "  flashsync validate restamped.csv --model sync.json --homographies homographies.json --json validation.json\n"
    "  flashsync view --model sync.json --videos cam1.mp4 cam2.mkv cam3.mp4 --events events.csv \\\n"
    "      --detections restamped.csv --homographies homographies.json --validation validation.json --save sync.rrd\n"
    "  rerun sync.rrd        (or: ... --serve, then open the address it prints)",
    "simulate": "flashsync simulate sample -o sim/",
    "diagnose": "flashsync diagnose cam1.mp4 cam2.mkv -o sync.json --json diagnosis.json --rrd diagnosis.rrd",
    "demo": "flashsync demo",
    "frames": "flashsync frames --model sync.json --rate 100 -o frames.csv",
    "resample": "flashsync resample restamped.csv --model sync.json --rate 100 -o tracks.csv",
    "montage": "flashsync montage cam1.mp4 cam2.mkv --model sync.json --rate 25 -o synced.mp4",
}

#: Plausible values of --exposure (a 1/125 s shutter) and --row-time (1080 rows of 1/30 s), ms.
EXPOSURE_EXAMPLE = "cam1=8"
ROW_TIME_EXAMPLE = "cam1=0.0296"

#: The library's parameters and the options that set them: an error about a parameter's value
#: is shown after its option.
OPTIONS = {
    "anchors": "--anchor",
    "cell": "--cell",
    "end_ms": "--end-ms",
    "exposure_ms": "--exposure",
    "flipped": "--flipped",
    "grpc_port": "--grpc-port",
    "max_gap_ms": "--max-gap-ms",
    "rate_hz": "--rate",
    "reference": "--reference",
    "row_times": "--row-time",
    "samples": "--samples",
    "scheduler": "--scheduler",
    "start_ms": "--start-ms",
    "timestamps": "--timestamps",
    "web_port": "--port",
}


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like an interrupt so that outputs are cleaned up."""


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit code (0 ok, 1 bad input, 130 interrupted, 143 terminated).

    A bad input or argument is one line on stderr; an interrupt (SIGINT) or SIGTERM leaves
    every output either as it was or complete, removes unfinished temporary files and says
    which outputs were written and which not.
    """
    parser = _parser()
    args = parser.parse_args(argv)
    _PLAN.clear()
    previous = _handle_sigterm()
    try:
        return args.run(args) or 0
    except FlashsyncError as error:
        print(f"flashsync {args.command}: error: {_message(error)}{_PLAN.written_note()}", file=sys.stderr)
        return 1
    except OSError as error:
        print(f"flashsync {args.command}: error: {_os_message(error)}{_PLAN.written_note()}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, RuntimeError) as error:
        interrupt = _interrupt_in(error)
        if interrupt is None:
            raise
        remove_temporaries()
        _PLAN.undo()
        print(f"flashsync {args.command}: {_PLAN.interrupted()}", file=sys.stderr)
        return 143 if isinstance(interrupt, Terminated) else 130
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def process_main() -> int:
    """:func:`main` as a whole process runs it (the ``flashsync`` script, ``python -m flashsync``).

    Once it returns, every output is complete or undone; SIGINT is then ignored, so that a
    Ctrl-C while the interpreter shuts down (which can take a good part of a second) neither
    kills it nor changes its exit code. And CPython's mark of an unhandled KeyboardInterrupt is
    cleared: a Ctrl-C that left a string ``exec`` (a dataclass being built while a module is
    imported) sets it even though :func:`main` caught the interrupt, and under ``python -m``
    the interpreter then kills itself with SIGINT at exit instead of returning 130. Every string
    ``exec`` clears the mark as it starts.
    """
    code = main()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    exec("pass", {})
    return code


def _interrupt_in(error: BaseException | None) -> KeyboardInterrupt | None:
    """The interrupt ``error`` is or was raised from, or None: Python 3.11 wraps an exception
    raised in ``__set_name__`` in a RuntimeError, and a SIGTERM landing while pandas builds a
    dataclass on import came out as that error's traceback, exit 1."""
    while error is not None and not isinstance(error, KeyboardInterrupt):
        error = error.__cause__
    return error


def _handle_sigterm():
    """Make SIGTERM raise :class:`Terminated` in the main thread; returns the handler before
    (None where it cannot be set: not the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        return None

    def terminate(number, frame):
        raise Terminated()

    return signal.signal(signal.SIGTERM, terminate)


def _message(error: FlashsyncError) -> str:
    """The error's line, after the option that set the parameter it is about."""
    option = OPTIONS.get(error.parameter)
    return f"{option} {error}" if option else str(error)


def _os_message(error: OSError) -> str:
    """An operating-system error as one line naming the file."""
    where = f"{error.filename}: " if error.filename else ""
    return f"{where}{error.strerror or error}; check the file and its folder"


class _Plan:
    """What a command promised to write or print and what it has done, for an honest line
    when it is interrupted (every file output is atomic: either as it was or complete)."""

    def __init__(self):
        self.clear()

    def clear(self) -> None:
        self.items: list[tuple[str, str]] = []
        self.done: list[str] = []
        self.folders: list[Path] = []

    def outputs(self, *items: tuple[str, str]) -> None:
        """The command's outputs in the order it makes them: ``(name, 'written' or 'printed')``."""
        self.items = list(items)

    def did(self, name: object) -> None:
        self.done.append(str(name))

    def new_folder(self, folder: Path) -> None:
        """A folder this run creates: removed again if the run does not complete."""
        self.folders.append(folder)

    def undo(self) -> None:
        """Remove the folders this run created (a run that did not complete)."""
        for folder in self.folders:
            shutil.rmtree(folder, ignore_errors=True)

    def written_note(self) -> str:
        """``'; sync.json was written'`` where outputs were made before an error."""
        done = [name for name, verb in self.items if name in self.done and verb == "written"]
        return f"; {', '.join(done)} {'was' if len(done) == 1 else 'were'} written" if done else ""

    def interrupted(self) -> str:
        """E.g. ``interrupted; sync.json written; the --pairwise table not printed; out.json not written``."""
        if not any(name in self.done for name, verb in self.items if verb == "written"):
            self.items = [item for item in self.items if item[1] == "written"] or [("output", "written")]
            if not self.done:
                return "interrupted; no output written"
        parts = []
        for done in (True, False):
            for verb in ("written", "printed"):
                names = [name for name, v in self.items if v == verb and (name in self.done) == done]
                if names:
                    parts.append(f"{', '.join(names)} {'' if done else 'not '}{verb}")
        return "interrupted; " + "; ".join(parts)


_PLAN = _Plan()


def _files(inputs: dict[str, Iterable[Path]], outputs: dict[str, Path | None], folders: Iterable[str] = ()) -> None:
    """Check a command's outputs before any work: each can be written (``folders`` name the
    options whose output is a folder), none is one of the inputs or another output (the
    same file by path or by inode). Plans them for the interrupt line."""
    given = [(option, Path(path)) for option, path in outputs.items() if path is not None]
    for option, path in given:
        try:
            check_output(path, folder=option in folders)
        except InputError as error:
            raise InputError(f"{option} {error}") from None
    sources = [(option, Path(path)) for option, paths in inputs.items() for path in paths if path is not None]
    for index, (option, path) in enumerate(given):
        for source_option, source in sources:
            if _same_file(path, source):
                raise InputError(
                    f"{option} {path}: is also an input ({source_option} {source}); writing it would destroy "
                    "that input: give the output another name"
                )
        for other_option, other in given[:index]:
            if _same_file(path, other):
                raise InputError(
                    f"{option} {path}: is the same file as {other_option} {other}; give each output its own name"
                )
    _PLAN.outputs(*((str(path), "written") for _, path in given))


def _same_file(a: Path, b: Path) -> bool:
    """Whether two paths name one file: the same inode where both exist, else the same
    resolved path."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return a.resolve() == b.resolve()


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="flashsync",
        description="Synchronise rolling-shutter cameras to a fraction of a "
        "millisecond from the bands that flashes leave in their frames.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, help_text: str, run) -> argparse.ArgumentParser:
        sub = commands.add_parser(
            name,
            prog=f"flashsync {name}",
            help=help_text,
            description=help_text,
            epilog=f"example:\n  {EXAMPLES[name]}",
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        sub.set_defaults(run=run)
        return sub

    detect = command("detect", "Detect flash events (band edges) in videos.", _run_detect)
    detect.add_argument("videos", nargs="+", type=Path, metavar="VIDEO")
    detect.add_argument(
        "-o",
        "--output",
        type=Path,
        default=Path("events.csv"),
        help="events table, .csv or .parquet (default: events.csv)",
    )
    _detection_options(detect)

    sync = command("sync", "Detect, match and solve: write the model file sync.json.", _run_sync)
    sync.add_argument("videos", nargs="+", type=Path, metavar="VIDEO")
    sync.add_argument("-o", "--output", type=Path, default=Path("sync.json"), help="model file (default: sync.json)")
    sync.add_argument(
        "--reference",
        help="camera whose clock is the global clock (default: the first, or where it shares too few flashes with "
        "the others or is tied in a smaller group than others are, the camera of the largest group with the most "
        "matched flashes)",
    )
    sync.add_argument(
        "--row-time",
        action="append",
        default=[],
        metavar="CAMERA=MS",
        help=f"known time per row of a camera in ms (datasheet), e.g. {ROW_TIME_EXAMPLE}; repeatable",
    )
    sync.add_argument(
        "--anchor",
        action="append",
        default=[],
        metavar="CAMERA:EVENT",
        help="events that are one flash, by their event number in the events table (--events); optional, repeatable",
    )
    sync.add_argument("--events", type=Path, help="also write the detected events table here")
    sync.add_argument(
        "--pairwise", action="store_true", help="also solve every pair of cameras on its own and print that table"
    )
    sync.add_argument(
        "--json", type=Path, metavar="OUT.json", help="also write the tables, rejected events and warnings as JSON"
    )
    sync.add_argument(
        "--rrd",
        type=Path,
        metavar="OUT.rrd",
        help="also write a Rerun recording of the result (events, residuals, videos)",
    )
    _detection_options(sync)

    restamp = command("restamp", "Add t_global_ms to each row of a detections table.", _run_restamp)
    restamp.add_argument(
        "detections",
        type=Path,
        metavar="DETECTIONS",
        help="a table (.csv, .parquet, MOTChallenge .txt) or a folder of .parquet/.csv tables (a partitioned dataset)",
    )
    restamp.add_argument(
        "--model", type=Path, default=Path("sync.json"), help="model file (default: sync.json in the current folder)"
    )
    restamp.add_argument(
        "-o",
        "--output",
        type=Path,
        help="output table, .csv or .parquet (default: DETECTIONS.restamped.csv); for a folder, a new folder "
        "with the same files (default: DETECTIONS.restamped)",
    )
    restamp.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="with a folder: re-stamp its tables on a Dask cluster, tcp://HOST:PORT or local:N "
        "(its workers see both folders by the same paths; needs flashsync[cluster])",
    )
    restamp.add_argument("--camera", help="camera name of a MOTChallenge .txt file (default: its stem)")
    restamp.add_argument(
        "--exposure",
        action="append",
        default=[],
        metavar="CAMERA=MS",
        help=f"exposure time of a camera in ms, e.g. {EXPOSURE_EXAMPLE}: adds t_center_ms; repeatable",
    )
    restamp.add_argument("--std", action="store_true", help="add t_global_std_ms (and t_center_std_ms) from the solve")
    _as_shown_option(restamp)
    restamp.add_argument("--strict", action="store_true", help="exit with code 1 if any row could not be stamped")

    validate = command(
        "validate",
        "Cross-camera interpolation errors of a fast object, with sub-frame and frame-level sync.",
        _run_validate,
    )
    validate.add_argument("detections", nargs="+", type=Path, metavar="DETECTIONS")
    validate.add_argument("--model", type=Path, default=Path("sync.json"), help="model file (default: sync.json)")
    validate.add_argument(
        "--homographies", type=Path, required=True, help="JSON {camera: 3x3 image->plane (metres) matrix}"
    )
    validate.add_argument(
        "--max-gap-ms", type=float, help="longest gap between bracketing observations (default 2.5 frames)"
    )
    validate.add_argument(
        "--exposure",
        action="append",
        default=[],
        metavar="CAMERA=MS",
        help=f"exposure time of a camera in ms, e.g. {EXPOSURE_EXAMPLE}; repeatable",
    )
    validate.add_argument("--json", type=Path, metavar="OUT.json", help="also write the report as JSON")
    _as_shown_option(validate)

    view = command(
        "view",
        "Show a synchronisation in the Rerun viewer: events, residuals, "
        "videos in sync, trajectories, on one global timeline.",
        _run_view,
    )
    view.epilog += VIEW_UNITS
    view.add_argument("--model", type=Path, default=Path("sync.json"), help="model file (default: sync.json)")
    _view_inputs(view)
    output = view.add_mutually_exclusive_group(required=True)
    output.add_argument("--save", type=Path, metavar="OUT.rrd", help="write a recording file")
    output.add_argument(
        "--spawn", action="store_true", help="open the native viewer (needs a display; it listens on 127.0.0.1)"
    )
    output.add_argument(
        "--serve", action="store_true", help="serve the web viewer (default http://127.0.0.1:9090) until Ctrl-C"
    )
    view.add_argument(
        "--bind",
        default="127.0.0.1",
        metavar="ADDRESS",
        help="IP address --serve listens on (default 127.0.0.1: this machine only; "
        "0.0.0.0: every IPv4 interface, reachable from other machines)",
    )
    view.add_argument("--port", type=int, default=9090, help="HTTP port of --serve's web viewer (default 9090)")
    view.add_argument(
        "--grpc-port",
        type=int,
        default=9876,
        help="port --serve streams the recording from, or --spawn's viewer listens on (default 9876)",
    )

    simulate = command("simulate", "Render a simulated multi-camera scenario with ground truth.", _run_simulate)
    simulate.add_argument(
        "scenario", nargs="?", default="sample", help="preset name or a YAML/JSON scenario file (default: sample)"
    )
    simulate.add_argument("-o", "--output", type=Path, required=True, help="output folder")

    diagnose = command(
        "diagnose",
        "Find where the plain time model and the measurement disagree, "
        "name the missing effects one by one and show the gap shrink.",
        _run_diagnose,
    )
    diagnose.add_argument("videos", nargs="+", type=Path, metavar="VIDEO")
    diagnose.add_argument("--reference", help="camera whose clock is the global clock (default: as sync)")
    diagnose.add_argument(
        "-o",
        "--output",
        type=Path,
        metavar="sync.json",
        help="also write a sync model file (the format sync writes; restamp uses it): sync's solve on the "
        "readouts and stamp-rate choices found, band edges moved back where saturation or a pulse shape moved them",
    )
    diagnose.add_argument("--json", type=Path, metavar="OUT.json", help="also write the steps as JSON")
    diagnose.add_argument(
        "--rrd", type=Path, metavar="OUT.rrd", help="also write a Rerun recording of the residuals after each step"
    )
    _detection_options(diagnose)

    demo = command(
        "demo", "Run detect -> sync -> restamp on the shipped sample and compare with its ground truth.", _run_demo
    )
    demo.add_argument("--samples", type=Path, help="sample folder (default: the shipped samples/)")
    demo.add_argument(
        "-o",
        "--output",
        type=Path,
        default=Path("flashsync-demo"),
        help="folder for the demo's outputs (default: flashsync-demo)",
    )
    demo.add_argument(
        "--rrd", type=Path, metavar="OUT.rrd", help="also write a Rerun recording of the demo (videos, events, puck)"
    )

    frames = command(
        "frames",
        "Which frame and row of each camera is exposed at common instants (ticks) of the global clock.",
        _run_frames,
    )
    frames.add_argument("--model", type=Path, default=Path("sync.json"), help="model file (default: sync.json)")
    _tick_options(frames, rate_default=None)
    frames.add_argument(
        "-o", "--output", type=Path, default=Path("frames.csv"), help="table, .csv or .parquet (default: frames.csv)"
    )

    resample = command(
        "resample",
        "Each (camera, object) track interpolated at common instants of the global clock (input for triangulation).",
        _run_resample,
    )
    resample.add_argument("detections", type=Path, metavar="DETECTIONS")
    resample.add_argument("--model", type=Path, default=Path("sync.json"), help="model file (default: sync.json)")
    _tick_options(resample, rate_default=None)
    resample.add_argument(
        "--max-gap-ms",
        type=float,
        help="longest time between the two detections a tick is interpolated "
        "between (default 2.5 frame periods of the camera)",
    )
    resample.add_argument(
        "--exposure",
        action="append",
        default=[],
        metavar="CAMERA=MS",
        help=f"exposure time of a camera in ms, e.g. {EXPOSURE_EXAMPLE} (mid-exposure instants); repeatable",
    )
    resample.add_argument("--camera", help="camera name of a MOTChallenge .txt file (default: its stem)")
    resample.add_argument(
        "-o", "--output", type=Path, default=Path("tracks.csv"), help="table, .csv or .parquet (default: tracks.csv)"
    )
    _as_shown_option(resample)

    montage = command(
        "montage",
        "The videos tiled in one H.264 video, in sync, with the row exposed at each instant drawn on every tile.",
        _run_montage,
    )
    montage.add_argument("videos", nargs="+", type=Path, metavar="VIDEO")
    montage.add_argument("--model", type=Path, default=Path("sync.json"), help="model file (default: sync.json)")
    _tick_options(montage, rate_default="the highest frame rate of the videos")
    montage.add_argument(
        "--cell", metavar="WIDTHxHEIGHT", help="size of each camera's cell, px (default: the largest width and height)"
    )
    montage.add_argument(
        "-o", "--output", type=Path, default=Path("synced.mp4"), help="video, .mp4, .mkv or .mov (default: synced.mp4)"
    )
    return parser


class _Parser(argparse.ArgumentParser):
    """argparse with a usage error as one line on stderr and exit code 1, like every other
    bad input (``flashsync sync: error: ...``); ``--help`` shows the usage."""

    def error(self, message: str):
        self.exit(1, f"{self.prog}: error: {message}; see '{self.prog} --help'\n")


def _tick_options(parser: argparse.ArgumentParser, rate_default: str | None) -> None:
    parser.add_argument(
        "--rate",
        type=float,
        required=rate_default is None,
        metavar="HZ",
        help="ticks per second" + (f" (default: {rate_default})" if rate_default else ""),
    )
    parser.add_argument(
        "--start-ms",
        type=float,
        metavar="MS",
        help="first tick, global clock (default: the first tick on the rate's grid in the span covered by any camera)",
    )
    parser.add_argument(
        "--end-ms",
        type=float,
        metavar="MS",
        help="end of the ticks, exclusive (default: the end of the last recording)",
    )


VIEW_UNITS = """

units: the time axis (global_time) is seconds from the start of the recordings, the
earliest first frame of any camera; the recording's description and the first lines of
the flash log give that instant's t_global_ms (ms, the reference camera's clock).
Residuals and their +-1 sigma band are in ms; plane positions and validation errors in
metres (error arrows are drawn enlarged: the factor is in the plane view's title and on
its scale bar); image positions in px. The plane view is a top view turned as the first
camera with a homography sees it."""


def _view_inputs(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--videos",
        nargs="+",
        type=Path,
        default=[],
        metavar="VIDEO",
        help="videos to show in sync (camera = file stem)",
    )
    parser.add_argument("--events", type=Path, help="events table from detect or sync --events (adds unmatched events)")
    parser.add_argument("--detections", type=Path, help="re-stamped detections (restamp output)")
    parser.add_argument(
        "--homographies",
        type=Path,
        help='JSON {camera: 3x3 image px -> plane m matrix}, optionally with "plane": '
        '{"outline_m": [[x, y], ...]}, the plane\'s outline (m)',
    )
    parser.add_argument(
        "--plane",
        type=float,
        nargs=4,
        metavar=("X0", "Y0", "X1", "Y1"),
        help="the plane's outline as the rectangle with corners (X0, Y0) and (X1, Y1), m (e.g. 0 0 60 30); "
        "replaces one in --homographies. Without either, no outline is drawn",
    )
    parser.add_argument("--validation", type=Path, help="validate --json output (interpolation errors)")


def _as_shown_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--as-shown",
        action="store_true",
        help="x and y are in the picture as a player shows it: a video stored turned (a phone held upright) "
        "turned upright by its display matrix, as OpenCV reads it by default (default: the stored frame's pixels)",
    )


def _detection_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--flipped",
        action="append",
        default=[],
        metavar="CAMERA",
        help="camera mounted upside down (reads bottom-up); repeatable",
    )
    parser.add_argument(
        "--timestamps",
        action="append",
        default=[],
        metavar="CAMERA=FILE.csv",
        help="frame timestamps of a camera from a CSV (column t_ms, or rtp for 90 kHz "
        "RTP stamps; one row per frame) instead of the container's; repeatable",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="decode on a Dask cluster: tcp://HOST:PORT of a running scheduler (its workers read the videos "
        "by the same paths), or local:N for N worker processes here; same events (needs flashsync[cluster])",
    )
    parser.add_argument(
        "--segment",
        type=float,
        default=SEGMENT_S,
        metavar="SECONDS",
        help=f"with --scheduler: videos are split at key frames into segments this long (default {SEGMENT_S:g})",
    )


#: Default --segment, s (flashsync.segments.SEGMENT_MS: the CLI does not import the detector to --help).
SEGMENT_S = 60.0


def _cluster_options(args) -> dict:
    """detect_videos' scheduler and segment_ms from --scheduler and --segment."""
    if args.scheduler is None:
        return {}
    from flashsync.cluster import check_scheduler

    check_scheduler(args.scheduler)
    if not (math.isfinite(args.segment) and args.segment > 0):
        raise InputError(f"--segment {args.segment:g}: the value must be a positive, finite number of seconds")
    return {"scheduler": args.scheduler, "segment_ms": args.segment * 1000.0}


def _timestamp_files(values: list[str]) -> dict[str, Path]:
    """``['cam1=cam1.csv']`` -> ``{'cam1': Path('cam1.csv')}``; a camera given twice is an error."""
    result = {}
    for text in values:
        camera, _, path = text.partition("=")
        if not camera or not path:
            raise InputError(f"--timestamps {text}: expected CAMERA=FILE.csv")
        if camera in result and result[camera] != Path(path):
            raise InputError(f"--timestamps {text}: {camera} is given two timestamp files; give one")
        result[camera] = Path(path)
    return result


def _progress(camera: str, total: int):
    """One progress bar per video (shown on a terminal only)."""
    from tqdm import tqdm

    bar = tqdm(total=total or None, desc=camera, unit="frame", leave=False, disable=None, position=next(_BAR_POSITIONS))
    return bar.update


_BAR_POSITIONS = itertools.count()


def _run_detect(args) -> None:
    from flashsync.io import save_events
    from flashsync.pipeline import all_events, detect_videos
    from flashsync.report import detection_notes

    timestamps = _timestamp_files(args.timestamps)
    _files({"VIDEO": args.videos, "--timestamps": timestamps.values()}, {"-o": args.output})
    detections = detect_videos(
        args.videos,
        args.flipped,
        estimate_readout=False,
        progress=_progress,
        timestamps=timestamps,
        **_cluster_options(args),
    )
    save_events(all_events(detections), args.output)
    _PLAN.did(args.output)
    for detection in detections:
        for note in detection_notes(detection):
            print(note, file=sys.stderr)
    print(
        f"{sum(len(d.events) for d in detections)} edges of "
        f"{sum(len(set(d.events.event.tolist())) for d in detections)} events in {len(args.videos)} videos "
        f"-> {args.output}",
        file=sys.stderr,
    )


def _run_sync(args) -> None:
    import json

    from flashsync.atomic import write_text
    from flashsync.io import events_to_frame, save_events, save_model
    from flashsync.pipeline import all_events, check_anchors, check_row_times, detect_videos, solve_pairs, synchronize
    from flashsync.report import (
        detection_notes,
        pairwise_table,
        pairwise_text,
        rejected_events,
        sync_summary,
        sync_table,
    )

    timestamps = _timestamp_files(args.timestamps)
    options = {"row_times": _per_camera_ms("--row-time", args.row_time, ROW_TIME_EXAMPLE), "anchors": args.anchor}
    check_row_times(options["row_times"], [video.stem for video in args.videos])
    check_anchors(args.anchor)
    outputs = {"--events": args.events, "-o": args.output, "--json": args.json, "--rrd": args.rrd}
    _files({"VIDEO": args.videos, "--timestamps": timestamps.values()}, outputs)
    planned = [(str(path), "written") for path in (args.events, args.output) if path]
    planned += [("the --pairwise table", "printed")] if args.pairwise else []
    _PLAN.outputs(*planned, *((str(path), "written") for path in (args.json, args.rrd) if path))
    detections = detect_videos(
        args.videos, args.flipped, progress=_progress, timestamps=timestamps, **_cluster_options(args)
    )
    for detection in detections:
        for note in detection_notes(detection):
            print(f"flashsync sync: {note}", file=sys.stderr)
    if args.events:
        save_events(all_events(detections), args.events)
        _PLAN.did(args.events)
    model, report = synchronize(detections, args.reference, **options)
    for warning in report.warnings:
        print(f"flashsync sync: warning: {warning}", file=sys.stderr)
    for name in report.flipped_found:
        print(f"flashsync sync: {name} reads bottom-up (mounted upside down)", file=sys.stderr)
    save_model(model, args.output)
    _PLAN.did(args.output)
    print(sync_table(model, report), flush=True)
    rejected = rejected_events(model)
    for event in rejected.itertuples():
        print(
            f"rejected: {event.camera} event {event.event} (frame {event.frame}, row {event.row:.1f}), "
            f"residual {event.residual_ms:+.3f} ms"
        )
    pairwise = None
    if args.pairwise:
        pairwise = pairwise_table(
            solve_pairs(
                [
                    d.read_flipped(model.cameras[d.camera].flipped) if d.camera in model.cameras else d
                    for d in detections
                ],
                **options,
            )
        )
        print()
        print(pairwise_text(pairwise), flush=True)
        _PLAN.did("the --pairwise table")
    if args.json:
        write_text(args.json, json.dumps(sync_summary(model, report, pairwise), indent=1))
        _PLAN.did(args.json)
    if args.rrd:
        import viz

        viz.save_recording(args.rrd, model, videos=args.videos, events=events_to_frame(all_events(detections)))
        _PLAN.did(args.rrd)
        print(f"recording -> {args.rrd}", file=sys.stderr)
    print(f"model -> {args.output}", file=sys.stderr)


def _per_camera_ms(option: str, values: list[str], example: str) -> dict[str, float]:
    """``['cam1=0.03', ...]`` -> ``{'cam1': 0.03}``: finite, positive milliseconds, each
    camera once (the same value twice is allowed); ``example`` (``cam1=8``) is shown in the error."""
    result = {}
    for text in values:
        camera, _, value = text.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = None
        if not camera or number is None:
            raise InputError(f"{option} {text}: expected CAMERA=MILLISECONDS, e.g. {example}")
        if not (math.isfinite(number) and number > 0):
            raise InputError(f"{option} {text}: the value must be a positive, finite number of ms")
        if result.get(camera, number) != number:
            raise InputError(f"{option} {text}: {camera} is given {result[camera]:g} ms too; give one value")
        result[camera] = number
    return result


def _positive_ms(option: str, value: float | None) -> float | None:
    """An optional duration option: None, or a positive, finite number of ms."""
    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(f"{option} {value:g}: the value must be a positive, finite number of ms")
    return value


def _load_model(path: Path):
    """The model file, or an error saying how to make one."""
    from flashsync.io import load_model

    if not path.exists():
        raise ModelFileError(
            f"{path}: no such model file; run 'flashsync sync VIDEO...' first or name the model with --model"
        )
    return load_model(path)


def _run_restamp(args) -> int:
    from tracking_adapter.restamp import camera_list, format_summary, restamp_file, restamp_folder

    folder = args.detections.is_dir()
    output = args.output or args.detections.with_suffix(".restamped" if folder else ".restamped.csv")
    exposures = _per_camera_ms("--exposure", args.exposure, EXPOSURE_EXAMPLE)
    if args.scheduler is not None and not folder:
        raise InputError(f"--scheduler {args.scheduler}: re-stamps a folder of tables; {args.detections} is a file")
    if args.scheduler is not None:
        from flashsync.cluster import check_scheduler

        check_scheduler(args.scheduler)
    if folder and args.camera:
        raise InputError(f"--camera {args.camera}: names the camera of a MOTChallenge file, not of a folder")
    _files({"DETECTIONS": [args.detections], "--model": [args.model]}, {"-o": output}, ["-o"] if folder else [])
    model = _load_model(args.model)
    _note_turned("restamp", model, args.as_shown)
    _note_long_exposures("restamp", model, exposures)
    options = {"exposure_ms": exposures, "with_std": args.std, "as_shown": args.as_shown}
    if folder:
        summary = restamp_folder(args.detections, output, model, scheduler=args.scheduler, **options)
    else:
        summary = restamp_file(args.detections, output, model, camera=args.camera, **options)
    _PLAN.did(output)
    print(format_summary(summary), file=sys.stderr)
    if "unknown camera" in summary.failed:
        print(
            f"flashsync restamp: error: {args.detections} names cameras that are not in {args.model}: "
            f"{camera_list(sorted(summary.unknown_cameras))} (it holds {', '.join(model.cameras)}); their rows are "
            "kept without t_global_ms - sync those videos too or fix the camera names",
            file=sys.stderr,
        )
        return 1
    return 1 if args.strict and summary.stamped < summary.rows else 0


def _note_turned(command: str, model, as_shown: bool) -> None:
    """A warning per camera whose video is stored turned for display, where detections are
    read in stored pixels (without ``--as-shown``)."""
    for clock in model.cameras.values():
        if clock.display_rotation_deg and not as_shown:
            print(
                f"flashsync {command}: warning: {clock.name}: its video is stored turned "
                f"({clock.display_rotation_deg} degrees counterclockwise for display); x and y are read as the stored "
                "frame's pixels - give --as-shown if they come from the picture as shown (OpenCV's by default)",
                file=sys.stderr,
            )


def _run_validate(args) -> None:
    import pandas as pd

    from flashsync.io import load_detections, load_homographies, save_validation
    from tracking_adapter.validate import format_report, validate

    exposures = _per_camera_ms("--exposure", args.exposure, EXPOSURE_EXAMPLE)
    max_gap_ms = _positive_ms("--max-gap-ms", args.max_gap_ms)
    inputs = {"DETECTIONS": args.detections, "--model": [args.model], "--homographies": [args.homographies]}
    _files(inputs, {"--json": args.json})
    detections = pd.concat([load_detections(path) for path in args.detections], ignore_index=True)
    model = _load_model(args.model)
    _note_turned("validate", model, args.as_shown)
    _note_long_exposures("validate", model, exposures)
    report = validate(
        detections,
        model,
        load_homographies(args.homographies),
        max_gap_ms=max_gap_ms,
        exposure_ms=exposures,
        as_shown=args.as_shown,
        source=", ".join(map(str, args.detections)),
    )
    _check_compared(report, len(detections), ", ".join(map(str, args.detections)))
    print(format_report(report), flush=True)
    if args.json:
        save_validation(report, args.json)
        _PLAN.did(args.json)


def _note_long_exposures(command: str, model, given: dict[str, float]) -> None:
    """A warning per camera whose exposure in the model (not given by --exposure) is longer
    than its frame period: a model edited by hand, or a long exposure read wrong by sync (its
    mid-exposure times t_center_ms are then wrong; its t_global_ms are not)."""
    from tracking_adapter.restamp import longer_than_frame

    for clock in model.cameras.values():
        if clock.name in given or clock.exposure_ms is None:
            continue
        period = longer_than_frame(clock, clock.exposure_ms)
        if period is not None:
            print(
                f"flashsync {command}: warning: {model.source}: camera {clock.name}'s exposure_ms, "
                f"{clock.exposure_ms:g}, is longer than its frame period ({period:.2f} ms), so its t_center_ms are "
                f"wrong - give its exposure with --exposure {clock.name}=MS",
                file=sys.stderr,
            )


def _check_compared(report, rows: int, source: str) -> None:
    """An error where no two cameras have usable detections: an empty table measures nothing
    (a run that validates nothing fails rather than passes quietly)."""
    if report.pairs:
        return
    reasons = ", ".join(f"{count} {reason}" for reason, count in report.not_used.items())
    usable = rows - sum(report.not_used.values())
    if not usable:
        raise InputError(
            f"{source}: none of the {rows} detections can be used ({reasons}); nothing to validate - fix those "
            "rows or give the detections of the cameras in the model and the homographies"
        )
    left_out = f" ({reasons} left out)" if reasons else ""
    raise InputError(
        f"{source}: the {usable} usable detections are all of one camera{left_out}; validate compares cameras with "
        "each other - give the detections of two cameras or more"
    )


def _run_view(args) -> None:
    import warnings

    import viz
    from flashsync.io import (
        load_homographies,
        load_plane_outline,
        load_validation,
    )

    if args.plane:
        x0, y0, x1, y1 = args.plane
        if not (all(map(math.isfinite, args.plane)) and x0 != x1 and y0 != y1):
            raise InputError(
                f"--plane {' '.join(f'{v:g}' for v in args.plane)}: expected two opposite corners of a rectangle, "
                "finite metres, e.g. 0 0 60 30"
            )
    if args.serve or args.spawn:
        viz.check_ports(args.port if args.serve else None, args.grpc_port)
    inputs = {
        "--model": [args.model],
        "--videos": args.videos,
        **{option: [path] for option, path in _view_files(args).items() if path},
    }
    _files(inputs, {"--save": args.save})
    model = _load_model(args.model)
    data = {
        "videos": args.videos or None,
        "events": _events_to_view(args.events, model) if args.events else None,
        "detections": _detections_to_view(args.detections, model) if args.detections else None,
        "homographies": load_homographies(args.homographies) if args.homographies else None,
        "plane_outline_m": load_plane_outline(args.homographies) if args.homographies else None,
        "validation": load_validation(args.validation, model.cameras) if args.validation else None,
    }
    if args.plane:
        data["plane_outline_m"] = viz.rectangle_outline(*args.plane)
    show = warnings.showwarning

    def plane_warning(message, category, *rest, **options):
        if not issubclass(category, viz.PlaneWarning):
            return show(message, category, *rest, **options)
        print(f"flashsync view: warning: {args.homographies}: {message}", file=sys.stderr)

    with warnings.catch_warnings():
        warnings.simplefilter("always", viz.PlaneWarning)
        warnings.showwarning = plane_warning
        if args.save:
            viz.save_recording(args.save, model, **data)
            _PLAN.did(args.save)
            print(f"recording -> {args.save} (open it with: rerun {args.save})", file=sys.stderr)
        elif args.spawn:
            viz.spawn(model, grpc_port=args.grpc_port, **data)
        else:
            viz.serve(model, bind=args.bind, web_port=args.port, grpc_port=args.grpc_port, **data)


def _events_to_view(path: Path, model):
    """The events table ``view`` draws, each event's camera and frame checked against the model."""
    from flashsync.io import events_to_frame, load_events

    events = events_to_frame(load_events(path))
    for camera, frame in zip(events["camera"], events["frame"]):
        if camera not in model.cameras:
            problem = f"events of camera {camera}, which is not in the model (it has {', '.join(model.cameras)})"
        elif frame >= model.cameras[camera].n_frames:
            problem = f"an event of camera {camera} on frame {frame}, past its {model.cameras[camera].n_frames} frames"
        else:
            continue
        raise InputError(f"{path}: {problem}; give the events of the videos the model was made from")
    return events


def _detections_to_view(path: Path, model):
    """The re-stamped detections ``view`` draws, its columns checked naming the file, and a
    warning where rows that restamp gave no reason for are not drawn."""
    from flashsync.io import load_detections
    from viz.trajectories import stamped

    table = load_detections(path)
    shown = stamped(table, model, source=str(path))
    explained = int(table["restamp_error"].notna().sum()) if "restamp_error" in table else 0
    if len(table) - len(shown) > explained:
        print(
            f"flashsync view: warning: {path}: {len(table) - len(shown) - explained} rows are not drawn: no finite "
            f"t_global_ms, x or y, or not on a frame of a camera of the model ({', '.join(model.cameras)})",
            file=sys.stderr,
        )
    return table


def _view_files(args) -> dict[str, Path | None]:
    return {
        "--events": args.events,
        "--detections": args.detections,
        "--homographies": args.homographies,
        "--validation": args.validation,
    }


def _run_simulate(args) -> None:
    from flashsync.io import load_scenario
    from flashsync.simulation import render_scenario

    source = Path(args.scenario)
    _files({"SCENARIO": [source] if source.exists() else []}, {"-o": args.output}, folders=["-o"])
    scenario = load_scenario(args.scenario)
    if not args.output.exists():
        _PLAN.new_folder(args.output)
    try:
        truth = render_scenario(scenario, args.output)
    except BaseException:
        _PLAN.undo()
        raise
    _PLAN.did(args.output)
    print(f"{len(truth.cameras)} cameras rendered -> {args.output}", file=sys.stderr)


def _run_diagnose(args) -> None:
    import json

    from flashsync.atomic import write_text
    from flashsync.diagnose import diagnose, format_diagnosis
    from flashsync.io import save_model
    from flashsync.pipeline import detect_videos

    timestamps = _timestamp_files(args.timestamps)
    _files(
        {"VIDEO": args.videos, "--timestamps": timestamps.values()},
        {"-o": args.output, "--json": args.json, "--rrd": args.rrd},
    )
    diagnosis = diagnose(
        detect_videos(
            args.videos,
            args.flipped,
            estimate_readout=True,  # both ways up, as sync reads them: its model is compared with this one
            progress=_progress,
            timestamps=timestamps,
            **_cluster_options(args),
        ),
        args.reference,
    )
    print(format_diagnosis(diagnosis), flush=True)
    if args.output:
        save_model(diagnosis.sync_model, args.output)
        _PLAN.did(args.output)
        apart = f" (it and sync's disagree on {', '.join(diagnosis.disagrees)})" if diagnosis.disagrees else ""
        print(f"model -> {args.output}{apart}", file=sys.stderr)
    if args.json:
        write_text(args.json, json.dumps(diagnosis.to_dict(), indent=1))
        _PLAN.did(args.json)
    if args.rrd:
        import viz

        viz.save_diagnosis(args.rrd, diagnosis)
        _PLAN.did(args.rrd)
        print(f"recording -> {args.rrd}", file=sys.stderr)


def _run_demo(args) -> None:
    from flashsync.demo import run_demo

    _files({"--samples": [args.samples] if args.samples else []}, {"-o": args.output, "--rrd": args.rrd}, ["-o"])
    print(run_demo(args.samples, args.output, progress=_progress, recording=args.rrd))


def _run_frames(args) -> None:
    from flashsync.io.tables import table_format, write_table
    from flashsync.ticks import frame_table, model_ticks_ms

    table_format(args.output)
    _files({"--model": [args.model]}, {"-o": args.output})
    model = _load_model(args.model)
    table = frame_table(model, model_ticks_ms(model, args.rate, args.start_ms, args.end_ms))
    write_table(table, args.output)
    _PLAN.did(args.output)
    shown = table["reason"] == ""
    print(
        f"{table['t_global_ms'].nunique()} ticks x {len(model.cameras)} cameras -> {args.output}: "
        f"{int(shown.sum())} located"
        + "".join(f", {count} {reason}" for reason, count in table.loc[~shown, "reason"].value_counts().items()),
        file=sys.stderr,
    )


def _run_resample(args) -> None:
    from flashsync.io import load_detections
    from flashsync.io.tables import table_format, write_table
    from flashsync.ticks import model_ticks_ms
    from tracking_adapter.resample import format_resampled, resample

    table_format(args.output)
    exposures = _per_camera_ms("--exposure", args.exposure, EXPOSURE_EXAMPLE)
    max_gap_ms = _positive_ms("--max-gap-ms", args.max_gap_ms)
    _files({"DETECTIONS": [args.detections], "--model": [args.model]}, {"-o": args.output})
    model = _load_model(args.model)
    _note_turned("resample", model, args.as_shown)
    _note_long_exposures("resample", model, exposures)
    ticks = model_ticks_ms(model, args.rate, args.start_ms, args.end_ms)
    result = resample(
        load_detections(args.detections, camera=args.camera),
        model,
        ticks,
        max_gap_ms=max_gap_ms,
        exposure_ms=exposures,
        as_shown=args.as_shown,
        source=str(args.detections),
    )
    write_table(result.tracks, args.output)
    _PLAN.did(args.output)
    print(format_resampled(result, str(args.detections), str(args.output)), file=sys.stderr)


def _run_montage(args) -> None:
    from flashsync.montage import write_montage

    cell = _cell(args.cell)
    _files({"VIDEO": args.videos, "--model": [args.model]}, {"-o": args.output})
    summary = write_montage(
        args.videos,
        _load_model(args.model),
        args.output,
        args.rate,
        args.start_ms,
        args.end_ms,
        cell=cell,
        progress=_progress,
    )
    _PLAN.did(args.output)
    print(
        f"{summary.frames} frames of {summary.width}x{summary.height} at {summary.rate_hz:g} Hz "
        f"from {summary.start_ms:.1f} ms -> {summary.path}",
        file=sys.stderr,
    )


def _cell(text: str | None) -> tuple[int, int] | None:
    """``'640x360'`` -> ``(640, 360)``."""
    if text is None:
        return None
    width, _, height = text.lower().partition("x")
    if not (width.isdecimal() and height.isdecimal() and int(width) >= 16 and int(height) >= 16):
        raise InputError(f"--cell {text}: expected WIDTHxHEIGHT in px, at least 16x16, e.g. 640x360")
    return int(width), int(height)
