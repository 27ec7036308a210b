"""One Rerun recording of a synchronisation, and the ways to show it.

:func:`log_sync` logs everything into a recording stream; :func:`save_recording`,
:func:`spawn` and :func:`serve` are the three output modes of ``flashsync view``.

Entity paths (``<camera>`` and ``<object>`` escaped as entity path parts); the
``cameras/`` entities exist for cameras whose video is given, the ``plane/`` ones where
there are detections with homographies or validation triples:

=========================================================  ===================================
``events/<camera>``                                        event lane (StateChange)
``events/log``                                             a line per event (TextLog)
``residuals/<camera>/{matched,rejected}``                  residuals, ms (Scalars)
``residuals/<camera>/{sigma_plus,sigma_minus}``            +-1 sigma of the sync, ms (Scalars)
``cameras/<camera>/video``                                 AssetVideo + VideoFrameReference
``cameras/<camera>/flash_rows``, ``.../flash_labels``      edge rows on frames (LineStrips2D,
                                                           Points2D labels)
``cameras/<camera>/now``                                   row exposed at the cursor (LineStrips2D)
``cameras/<camera>/status``                                when the video starts, ended (Points2D)
``cameras/<camera>/detections``                            detections on frames (Points2D)
``plane``, ``plane/map/{outline,grid,ticks,scale}``        top view transform; outline, metre
                                                           grid, scale bar, m (see :mod:`viz.plane`)
``plane/observations/<camera>/<object>``                   observations, m (Points2D)
``plane/validation/<A>_vs_<B>/<object>/error``             error arrow, scaled (Arrows2D)
``validation/<A>_vs_<B>/<object>``                         error, m (Scalars)
=========================================================  ===================================

Timelines: ``global_time`` (duration from the start of the recordings) and
``frame_<camera>`` (sequence); see :mod:`viz.timeline`. The recording's ``description``
property says where ``global_time`` 0 is on the global clock. Nothing is logged on
Rerun's automatic ``log_time``/``log_tick``.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.parse
import warnings
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path

import numpy as np
import pandas as pd
import rerun as rr

from flashsync.atomic import atomic_output
from flashsync.errors import FlashsyncError, InputError
from flashsync.model import SyncModel
from viz.blueprint import sync_blueprint
from viz.events import event_table, log_events, log_start
from viz.palette import camera_colors
from viz.plane import PlaneView, PlaneWarning, log_plane, plane_view, plane_warnings
from viz.residuals import log_residuals
from viz.timeline import Timeline
from viz.trajectories import log_frame_detections, log_observations, project, stamped
from viz.validation import log_validation, validation_points
from viz.video import camera_videos, log_flash_rows, log_now_line, log_video, log_video_span

APPLICATION_ID = "flashsync"
WEB_PORT = 9090
"""HTTP port of the web viewer :func:`serve` hosts."""
GRPC_PORT = 9876
"""Port of the gRPC server :func:`serve` streams the recording from."""
BIND = "127.0.0.1"
"""Address :func:`serve` listens on: this machine only."""
SERVER_START_S = 60.0

Videos = Mapping[str, str | Path] | Iterable[str | Path]


def log_sync(
    model: SyncModel,
    *,
    videos: Videos | None = None,
    events: pd.DataFrame | None = None,
    detections: pd.DataFrame | None = None,
    validation: pd.DataFrame | None = None,
    homographies: Mapping[str, np.ndarray] | None = None,
    plane_outline_m: np.ndarray | None = None,
    recording: rr.RecordingStream | None = None,
) -> rr.RecordingStream:
    """Log a synchronisation and send its default blueprint.

    Detections that land where a plane cannot be (see :func:`viz.plane.plane_warnings`)
    raise a :class:`PlaneWarning` per camera (with :mod:`warnings`); they are logged all
    the same.

    Parameters
    ----------
    model : SyncModel
        The synchronisation; its events are the matched events.
    videos : mapping of camera name to path, or iterable of paths, optional
        Videos to show in sync (paths alone are named by file stem). MP4 files are logged
        as they are, other containers remuxed to MP4 (see :mod:`viz.video`); each must
        have as many frames as the model's camera.
    events : DataFrame, optional
        The ``detect`` table; adds the unmatched events.
    detections : DataFrame, optional
        Restamped detections (``camera, frame, x, y, t_global_ms``, optional ``object``,
        ``t_center_ms``), px and ms.
    validation : DataFrame, optional
        Validation triples (see :func:`viz.validation.log_validation`).
    homographies : mapping of camera name to ndarray of shape (3, 3), optional
        Image px -> plane m, to draw detections in the plane.
    plane_outline_m : ndarray of shape (n, 2), optional
        The plane's outline (a closed polyline), m, drawn under plane data; the plane
        view shows its bounding box. Without one, no outline and the data's extent.
    recording : RecordingStream, optional
        Where to log; default a new recording of application ``flashsync`` (no sink yet).

    Returns
    -------
    RecordingStream
        ``recording``, or the new one.

    Examples
    --------
    >>> model = load_model("sync.json")                                      # doctest: +SKIP
    >>> recording = log_sync(model, videos=["cam1.mp4", "cam2.mkv"])        # doctest: +SKIP
    >>> recording.notebook_show()                                           # doctest: +SKIP
    """
    recording = recording if recording is not None else rr.RecordingStream(APPLICATION_ID)
    timeline = Timeline.of(model)
    log_start(recording, model, timeline)
    recording.flush()  # the first data on global_time: the viewer opens at 0
    table = event_table(model, events)
    log_instants = log_events(recording, model, table, timeline)
    log_residuals(recording, model, timeline)
    named = camera_videos(videos, model) if videos is not None else {}
    stamped_detections = stamped(detections, model) if detections is not None else None
    colors = camera_colors(model.cameras)
    for name, path in named.items():
        camera = model.cameras[name]
        log_video(recording, timeline, camera, path)
        log_video_span(recording, timeline, camera)
        log_flash_rows(recording, timeline, camera, table[table["camera"] == name])
        log_now_line(recording, timeline, camera, also_at_ms=log_instants)
        if stamped_detections is not None:
            log_frame_detections(
                recording, timeline, camera, stamped_detections[stamped_detections["camera"] == name], colors[name]
            )
    view = _plane(recording, timeline, model, stamped_detections, homographies, validation, plane_outline_m)
    errors_max_m = None
    if validation is not None and len(validation):
        errors_max_m = float(np.nanmax(validation["error_m"].to_numpy(dtype=np.float64)))
    recording.send_blueprint(
        sync_blueprint(model, timeline, video_cameras=named, plane=view, errors_max_m=errors_max_m)
    )
    return recording


def _plane(
    recording: rr.RecordingStream,
    timeline: Timeline,
    model: SyncModel,
    detections: pd.DataFrame | None,
    homographies: Mapping[str, np.ndarray] | None,
    validation: pd.DataFrame | None,
    outline_m: np.ndarray | None,
) -> PlaneView | None:
    """Log the plane view's data (observations, validation arrows, map); None without any."""
    projected = project(detections, homographies) if detections is not None and homographies else None
    if projected is None and validation is None:
        return None
    points = [np.zeros((0, 2))]
    if projected is not None:
        by_camera = {
            name: rows[["plane_x", "plane_y"]].to_numpy(dtype=np.float64)
            for name, rows in projected.groupby("camera", sort=False)
        }
        for line in plane_warnings(by_camera, outline_m):
            warnings.warn(line, PlaneWarning, stacklevel=3)
        points += by_camera.values()
    errors = np.zeros(0)
    if validation is not None:
        points.append(validation_points(validation))
        errors = validation["error_m"].to_numpy(dtype=np.float64)
    view = plane_view(model, homographies, outline_m, np.concatenate(points), errors)
    log_plane(recording, view)
    if projected is not None:
        log_observations(recording, timeline, model, projected)
    if validation is not None:
        log_validation(recording, timeline, model, validation, view.error_scale or 1.0, view.arrow_cap_m())
    return view


def save_recording(path: str | Path, model: SyncModel, **data) -> None:
    """Write the recording of :func:`log_sync` to an ``.rrd`` file, atomically.

    Parameters
    ----------
    path : str or Path
        Output file; open it with ``rerun FILE.rrd``.
    model : SyncModel
    **data
        The keyword arguments of :func:`log_sync` but ``recording``.
    """
    with atomic_output(path) as temporary:
        recording = rr.RecordingStream(APPLICATION_ID)
        recording.save(temporary)
        log_sync(model, recording=recording, **data)
        recording.flush()
        recording.disconnect()


def spawn(model: SyncModel, *, grpc_port: int = GRPC_PORT, **data) -> rr.RecordingStream:
    """Start the native Rerun viewer (or use the one running) and stream the recording to it.

    The viewer (the ``rerun`` program of rerun-sdk) listens on 127.0.0.1 only, port
    ``grpc_port``, and outlives this process; one already listening there is used. It
    needs a display.

    Parameters
    ----------
    model : SyncModel
    grpc_port : int
        TCP port of the viewer.
    **data
        The keyword arguments of :func:`log_sync` but ``recording``.
    """
    check_ports(None, grpc_port)
    if not _listening(BIND, grpc_port):
        if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
            raise FlashsyncError(
                "the native Rerun viewer needs a display, and neither DISPLAY "
                "nor WAYLAND_DISPLAY is set; save the recording to a file or "
                "serve it to a web browser instead"
            )
        _check_free(BIND, grpc_port)
        viewer = subprocess.Popen(
            [str(rerun_program()), "--bind", BIND, "--port", str(grpc_port), "--expect-data-soon"],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        deadline = time.monotonic() + SERVER_START_S
        while not _listening(BIND, grpc_port):
            if viewer.poll() is not None or time.monotonic() > deadline:
                _stop(viewer)
                raise FlashsyncError(
                    f"the native Rerun viewer did not start (exit code "
                    f"{viewer.returncode}); try rerun --port {grpc_port} to see why"
                )
            time.sleep(0.2)
    recording = rr.RecordingStream(APPLICATION_ID)
    recording.connect_grpc(f"rerun+http://{BIND}:{grpc_port}/proxy")
    log_sync(model, recording=recording, **data)
    recording.flush()
    return recording


def viewer_url(web_port: int = WEB_PORT, grpc_port: int = GRPC_PORT, host: str = "127.0.0.1") -> str:
    """Address of the web viewer of :func:`serve`, connected to its recording."""
    source = f"rerun+http://{host}:{grpc_port}/proxy"
    return f"http://{host}:{web_port}/?url={urllib.parse.quote(source, safe='')}"


def check_ports(web_port: int | None, grpc_port: int) -> None:
    """An :class:`~flashsync.errors.InputError` (parameter ``web_port`` or ``grpc_port``) unless
    each port is a TCP port, 1-65535, and the two differ (``web_port`` None: not served)."""
    for parameter, port in (("web_port", web_port), ("grpc_port", grpc_port)):
        if port is not None and not 1 <= port <= 65535:
            raise InputError(f"{port}: not a TCP port; give one of 1-65535", parameter=parameter)
    if web_port == grpc_port:
        raise InputError(
            f"{web_port}: the web viewer's port is also the recording stream's; give each its own port",
            parameter="web_port",
        )


def url_host(bind: str) -> str:
    """The host a browser reaches a server listening on address ``bind`` by: the address
    itself, or this machine's name where it listens on every interface."""
    if bind in ("0.0.0.0", "::"):
        return socket.gethostname()
    return f"[{bind}]" if ":" in bind else bind


def serve(
    model: SyncModel,
    *,
    bind: str = BIND,
    web_port: int = WEB_PORT,
    grpc_port: int = GRPC_PORT,
    open_browser: bool = False,
    **data,
) -> None:
    """Serve the recording to web browsers until Ctrl-C.

    The recording is written to a temporary ``.rrd`` file, then the ``rerun`` program that
    ships with rerun-sdk hosts the web viewer over HTTP on ``web_port`` and streams the
    file from a gRPC server on ``grpc_port``, both listening on ``bind`` only (default
    127.0.0.1: this machine; ``0.0.0.0`` is every IPv4 interface). The address
    (:func:`viewer_url`) is printed on stderr once both listen. Returns after Ctrl-C
    (KeyboardInterrupt; SIGTERM and SIGHUP too), having stopped the server and removed the
    file.

    Parameters
    ----------
    model : SyncModel
    bind : str
        IP address to listen on.
    web_port, grpc_port : int
        TCP ports.
    open_browser : bool
        Also open the address in the default browser.
    **data
        The keyword arguments of :func:`log_sync` but ``recording``.
    """
    check_ports(web_port, grpc_port)
    with tempfile.TemporaryDirectory(prefix="flashsync-serve-") as folder, _stopped_as_by_ctrl_c():
        recording = Path(folder) / "recording.rrd"
        save_recording(recording, model, **data)
        log = Path(folder) / "rerun.log"
        server = _start_server(recording, log, bind, web_port, grpc_port)
        try:
            url = viewer_url(web_port, grpc_port, url_host(bind))
            print(f"serving the Rerun web viewer at {url} (Ctrl-C to stop)", file=sys.stderr)
            if open_browser:
                import webbrowser

                webbrowser.open(url)
            server.wait()
            raise FlashsyncError(f"the Rerun server stopped by itself: {_last_line(log)}")
        except KeyboardInterrupt:
            pass
        finally:
            _stop(server)


@contextlib.contextmanager
def _stopped_as_by_ctrl_c() -> Iterator[None]:
    """Within: SIGTERM and SIGHUP (``kill``, a closed terminal) raise KeyboardInterrupt like
    Ctrl-C, so that the server is stopped, not left behind (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(number, frame):
        raise KeyboardInterrupt(signal.Signals(number).name)

    kinds = [kind for kind in ("SIGTERM", "SIGHUP") if hasattr(signal, kind)]
    previous = {kind: signal.signal(getattr(signal, kind), interrupt) for kind in kinds}
    try:
        yield
    finally:
        for kind, handler in previous.items():
            signal.signal(getattr(signal, kind), handler)


def rerun_program() -> Path:
    """The ``rerun`` program that ships with rerun-sdk (package ``rerun_cli``)."""
    try:
        import rerun_cli
    except ImportError:
        raise FlashsyncError(
            "the rerun program of rerun-sdk is missing (no package rerun_cli); reinstall rerun-sdk"
        ) from None
    program = Path(rerun_cli.__file__).with_name("rerun.exe" if sys.platform == "win32" else "rerun")
    if not program.is_file():
        raise FlashsyncError(f"{program}: the rerun program of rerun-sdk is missing; reinstall rerun-sdk")
    return program


def _start_server(recording: Path, log: Path, bind: str, web_port: int, grpc_port: int) -> subprocess.Popen:
    """Start ``rerun --serve-web`` on ``recording``; return once both ports listen."""
    for port in (web_port, grpc_port):
        _check_free(bind, port)
    with log.open("wb") as output:
        server = subprocess.Popen(
            [
                str(rerun_program()),
                "--serve-web",
                "--bind",
                bind,
                "--port",
                str(grpc_port),
                "--web-viewer-port",
                str(web_port),
                str(recording),
            ],
            stdin=subprocess.DEVNULL,
            stdout=output,
            stderr=output,
        )
    deadline = time.monotonic() + SERVER_START_S
    try:
        while not all(_listening(bind, port) for port in (web_port, grpc_port)):
            if server.poll() is not None:
                raise FlashsyncError(f"the Rerun server did not start: {_last_line(log)}")
            if time.monotonic() > deadline:
                raise FlashsyncError(
                    f"the Rerun server did not listen on {bind} ports {web_port} "
                    f"and {grpc_port} within {SERVER_START_S:.0f} s: "
                    f"{_last_line(log)}"
                )
            time.sleep(0.2)
    except BaseException:
        _stop(server)
        raise
    return server


def _check_free(bind: str, port: int) -> None:
    """Raise a :class:`FlashsyncError` if ``bind:port`` cannot be listened on."""
    try:
        family, kind, _, _, address = socket.getaddrinfo(bind, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)[
            0
        ]
        with socket.socket(family, kind) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            probe.bind(address)
    except OSError as error:
        raise FlashsyncError(
            f"cannot listen on {bind} port {port} ({error.strerror or error}); choose another port or address"
        ) from None


def _listening(bind: str, port: int) -> bool:
    """Whether a server accepts connections on ``bind:port`` (on the loopback address for a
    wildcard ``bind``)."""
    host = {"0.0.0.0": "127.0.0.1", "::": "::1"}.get(bind, bind)
    try:
        with socket.create_connection((host, port), timeout=1.0):
            return True
    except OSError:
        return False


def _stop(server: subprocess.Popen) -> None:
    """Stop the server process and wait for it."""
    if server.poll() is None:
        server.terminate()
        try:
            server.wait(timeout=10)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()


def _last_line(log: Path) -> str:
    """The last line the server wrote (without terminal colours), or a placeholder."""
    text = log.read_bytes().decode("utf-8", "replace") if log.exists() else ""
    lines = [line for line in re.sub(r"\x1b\[[0-9;]*m", "", text).splitlines() if line.strip()]
    return lines[-1].strip() if lines else "no output"
