"""Rerun visualisation of a flashsync synchronisation.

Events, residuals, videos in sync, trajectories in the plane and validation errors in
one Rerun recording on the reference clock (timeline ``global_time``). Only this package
imports Rerun. See :mod:`viz.recording` for the entity paths and :mod:`viz.timeline` for
the timelines.

Examples
--------
>>> import viz                                                            # doctest: +SKIP
>>> from flashsync.model_file import load_model                          # doctest: +SKIP
>>> model = load_model("sync.json")                                      # doctest: +SKIP
>>> viz.save_recording("sync.rrd", model, videos=["cam1.mp4", "cam2.mkv"])  # doctest: +SKIP
>>> viz.serve(model, videos=["cam1.mp4", "cam2.mkv"])  # Ctrl-C stops     # doctest: +SKIP
"""

from viz.blueprint import sync_blueprint
from viz.diagnosis import log_diagnosis, save_diagnosis
from viz.recording import (
    APPLICATION_ID,
    GRPC_PORT,
    RINK_M,
    WEB_PORT,
    log_sync,
    save_recording,
    serve,
    spawn,
    viewer_url,
)

__all__ = [
    "APPLICATION_ID",
    "GRPC_PORT",
    "RINK_M",
    "WEB_PORT",
    "log_diagnosis",
    "log_sync",
    "save_diagnosis",
    "save_recording",
    "serve",
    "spawn",
    "sync_blueprint",
    "viewer_url",
]
