"""flashsync: sub-millisecond synchronisation of rolling-shutter cameras from flash bands.

The library API (the ``flashsync`` command is a thin layer over it)::

    from flashsync import detect_videos, synchronize, save_model, load_model
    detections = detect_videos(["cam1.mp4", "cam2.mkv"])     # finds upside-down cameras too
    model, report = synchronize(detections)
    save_model(model, "sync.json")
    load_model("sync.json").camera("cam2").t_global_ms(frame=10, row=200.5)
    model = load_model("sync.json")
    frame_table(model, model_ticks_ms(model, rate_hz=100.0))      # (frame, row) at common ticks
    write_montage(["cam1.mp4", "cam2.mkv"], model, "synced.mp4", rate_hz=25.0)

Every file format has its ``load_*`` / ``save_*`` in :mod:`flashsync.io`; the discrepancy
workflow is :mod:`flashsync.diagnose`; docs/architecture.md maps the modules.
"""

from flashsync.detect import CameraDetection, DetectorSettings, EventDetector, detect_video
from flashsync.errors import FlashsyncError, InputError, ModelFileError, NotEnoughDataError
from flashsync.events import Band, Bands, Edge, Events, Flag
from flashsync.frame_clock import FrameClock
from flashsync.io.model_file import load_model, save_model
from flashsync.match import PairAlignment
from flashsync.model import CameraClock, SyncModel
from flashsync.montage import MontageSummary, write_montage
from flashsync.pipeline import SyncReport, all_events, detect_videos, solve_pairs, synchronize
from flashsync.ticks import frame_table, model_ticks_ms

__all__ = [
    "Band",
    "Bands",
    "CameraClock",
    "CameraDetection",
    "DetectorSettings",
    "Edge",
    "EventDetector",
    "Events",
    "Flag",
    "FlashsyncError",
    "FrameClock",
    "InputError",
    "ModelFileError",
    "MontageSummary",
    "NotEnoughDataError",
    "PairAlignment",
    "SyncModel",
    "SyncReport",
    "all_events",
    "detect_video",
    "detect_videos",
    "frame_table",
    "load_model",
    "model_ticks_ms",
    "save_model",
    "solve_pairs",
    "synchronize",
    "write_montage",
]
