"""flashsync: sub-millisecond synchronisation of rolling-shutter cameras from flash bands.

The library API (the ``flashsync`` command is a thin layer over it)::

    from flashsync import detect_videos, synchronize, save_model, load_model
    detections = detect_videos(["cam1.mp4", "cam2.mkv"])
    model, report = synchronize(detections)
    save_model(model, "sync.json")
    load_model("sync.json").camera("cam2").t_global_ms(frame=10, row=200.5)
"""

from flashsync.detect import DetectorSettings, EventDetector, detect_video
from flashsync.errors import FlashsyncError
from flashsync.model import CameraClock, SyncModel
from flashsync.model_file import load_model, save_model
from flashsync.pipeline import all_events, detect_videos, synchronize

__all__ = [
    "CameraClock",
    "DetectorSettings",
    "EventDetector",
    "FlashsyncError",
    "SyncModel",
    "all_events",
    "detect_video",
    "detect_videos",
    "load_model",
    "save_model",
    "synchronize",
]
