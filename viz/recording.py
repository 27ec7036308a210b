"""One Rerun recording of a synchronisation, and the ways to show it.

:func:`log_sync` logs everything into a recording stream; :func:`save_recording`,
:func:`spawn` and :func:`serve` are the three output modes of ``flashsync view``.

Entity paths (``<camera>`` and ``<object>`` escaped as entity path parts); the
``cameras/`` entities exist for cameras whose video is given, the ``plane/`` ones where
there are detections with homographies or validation triples:

=====================================================  ===================================
``events/<camera>/{matched,rejected,unmatched}``       event raster, lane (Scalars)
``events/log``                                         a line per flash (TextLog)
``residuals/<camera>/{matched,rejected}``              residuals, ms (Scalars)
``residuals/<camera>/{sigma_plus,sigma_minus}``        +-1 sigma of the sync, ms (Scalars)
``cameras/<camera>/video``                             AssetVideo + VideoFrameReference
``cameras/<camera>/flash_rows``                        edge rows on frames (LineStrips2D)
``cameras/<camera>/detections``                        detections on frames (Points2D)
``plane``, ``plane/rink``                              z up; rink outline, m (LineStrips3D)
``plane/<camera>/<object>``                            observations, m (Points3D)
``plane/validation/<A>_vs_<B>/<object>/interpolated``  A at B's instant, m (Points3D)
``plane/validation/<A>_vs_<B>/<object>/error``         error vector, m (Arrows3D)
``validation/<A>_vs_<B>/<object>``                     error, m (Scalars)
=====================================================  ===================================

Timelines: ``global_time`` (duration, reference clock) and ``frame_<camera>`` (sequence);
see :mod:`viz.timeline`. Nothing is logged on Rerun's automatic ``log_time``/``log_tick``.
"""

from __future__ import annotations

import sys
import time
import urllib.parse
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd
import rerun as rr

from flashsync.atomic import atomic_output
from flashsync.model import SyncModel
from flashsync.simulation.scene import RINK_LENGTH_M, RINK_WIDTH_M
from viz.blueprint import sync_blueprint
from viz.events import event_table, log_events
from viz.palette import camera_colors
from viz.residuals import log_residuals
from viz.trajectories import log_frame_detections, log_observations, log_plane, stamped
from viz.validation import log_validation
from viz.video import camera_videos, log_flash_rows, log_video

APPLICATION_ID = "flashsync"
RINK_M = (RINK_LENGTH_M, RINK_WIDTH_M)
"""Length and width of the rink, m, with a corner at the plane's origin (the simulator's)."""
WEB_PORT = 9090
"""HTTP port of the web viewer :func:`serve` hosts."""
GRPC_PORT = 9876
"""Port of the gRPC server :func:`serve` streams the recording from."""

Videos = Mapping[str, str | Path] | Iterable[str | Path]


def log_sync(
    model: SyncModel,
    *,
    videos: Videos | None = None,
    events: pd.DataFrame | None = None,
    detections: pd.DataFrame | None = None,
    validation: pd.DataFrame | None = None,
    homographies: Mapping[str, np.ndarray] | None = None,
    rink_m: tuple[float, float] | None = RINK_M,
    recording: rr.RecordingStream | None = None,
) -> rr.RecordingStream:
    """Log a synchronisation and send its default blueprint.

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
    rink_m : (float, float) or None
        Rink length and width, m, drawn under plane data; None draws no rink.
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
    table = event_table(model, events)
    log_events(recording, model, table)
    log_residuals(recording, model)
    named = camera_videos(videos, model) if videos is not None else {}
    stamped_detections = stamped(detections) if detections is not None else None
    colors = camera_colors(model.cameras)
    for name, path in named.items():
        camera = model.cameras[name]
        log_video(recording, camera, path)
        log_flash_rows(recording, camera, table[table["camera"] == name])
        if stamped_detections is not None:
            log_frame_detections(
                recording, camera, stamped_detections[stamped_detections["camera"] == name], colors[name]
            )
    plane = False
    if stamped_detections is not None and homographies:
        log_observations(recording, model, stamped_detections, homographies)
        plane = True
    if validation is not None:
        log_validation(recording, model, validation)
        plane = True
    if plane:
        log_plane(recording, rink_m)
    recording.send_blueprint(
        sync_blueprint(model, video_cameras=named, plane=plane, errors=validation is not None, rink_m=rink_m)
    )
    return recording


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


def spawn(model: SyncModel, **data) -> rr.RecordingStream:
    """Start the native Rerun viewer (or use the one running) and stream the recording to it.

    The viewer listens on port 9876 and outlives this process. Needs a display.

    Parameters
    ----------
    model : SyncModel
    **data
        The keyword arguments of :func:`log_sync` but ``recording``.
    """
    recording = rr.RecordingStream(APPLICATION_ID)
    recording.spawn()
    log_sync(model, recording=recording, **data)
    recording.flush()
    return recording


def viewer_url(web_port: int = WEB_PORT, grpc_port: int = GRPC_PORT) -> str:
    """Address of the web viewer of :func:`serve`, connected to its recording."""
    source = f"rerun+http://127.0.0.1:{grpc_port}/proxy"
    return f"http://127.0.0.1:{web_port}/?url={urllib.parse.quote(source, safe='')}"


def serve(
    model: SyncModel, *, web_port: int = WEB_PORT, grpc_port: int = GRPC_PORT, open_browser: bool = False, **data
) -> None:
    """Serve the recording to web browsers until Ctrl-C.

    The web viewer is hosted over HTTP on ``web_port`` (default 9090) and streams the
    recording from a gRPC server on ``grpc_port`` (default 9876), both listening on every
    interface (from another machine, use this one's name instead of 127.0.0.1). The
    address (:func:`viewer_url`) is printed on stderr. Returns after Ctrl-C
    (KeyboardInterrupt); the gRPC server stops then, the web server with the process.

    Parameters
    ----------
    model : SyncModel
    web_port, grpc_port : int
        TCP ports.
    open_browser : bool
        Also open the address in the default browser.
    **data
        The keyword arguments of :func:`log_sync` but ``recording``.
    """
    recording = rr.RecordingStream(APPLICATION_ID)
    source = recording.serve_grpc(grpc_port=grpc_port)
    rr.serve_web_viewer(web_port=web_port, open_browser=open_browser, connect_to=source)
    try:
        log_sync(model, recording=recording, **data)
        print(f"serving the Rerun web viewer at {viewer_url(web_port, grpc_port)} (Ctrl-C to stop)", file=sys.stderr)
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        recording.disconnect()
