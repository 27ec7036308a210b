"""Rerun visualisation of a flashsync synchronisation.

Events, residuals, videos in sync, trajectories in the plane and validation errors in
one Rerun recording on one timeline, ``global_time``: the global clock from the start of
the recordings. Only this package imports Rerun. See :mod:`viz.recording` for the entity
paths, :mod:`viz.timeline` for the timelines, :mod:`viz.blueprint` for the default layout
and :mod:`viz.plane` for the plane view.

Examples
--------
>>> import viz                                                            # doctest: +SKIP
>>> from flashsync.io import load_model                                  # doctest: +SKIP
>>> model = load_model("sync.json")                                      # doctest: +SKIP
>>> viz.save_recording("sync.rrd", model, videos=["cam1.mp4", "cam2.mkv"])  # doctest: +SKIP
>>> viz.serve(model, videos=["cam1.mp4", "cam2.mkv"])  # Ctrl-C stops     # doctest: +SKIP
"""

from viz.blueprint import sync_blueprint
from viz.diagnosis import log_diagnosis, save_diagnosis
from viz.plane import PlaneWarning, rectangle_outline
from viz.recording import (
    APPLICATION_ID,
    BIND,
    GRPC_PORT,
    WEB_PORT,
    check_ports,
    log_sync,
    save_recording,
    serve,
    spawn,
    viewer_url,
)

__all__ = [
    "APPLICATION_ID",
    "BIND",
    "GRPC_PORT",
    "PlaneWarning",
    "WEB_PORT",
    "check_ports",
    "log_diagnosis",
    "log_sync",
    "rectangle_outline",
    "save_diagnosis",
    "save_recording",
    "serve",
    "spawn",
    "sync_blueprint",
    "viewer_url",
]
