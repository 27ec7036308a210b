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

from flashsync.lazy import lazy_exports

#: Each exported name and the module that defines it, imported on first use
#: (:mod:`flashsync.lazy`): a command loads only the modules it needs.
_EXPORTS = {
    "Band": "flashsync.events",
    "Bands": "flashsync.events",
    "CameraClock": "flashsync.model",
    "CameraDetection": "flashsync.detect",
    "DetectorSettings": "flashsync.detect",
    "Edge": "flashsync.events",
    "EventDetector": "flashsync.detect",
    "Events": "flashsync.events",
    "Flag": "flashsync.events",
    "FlashsyncError": "flashsync.errors",
    "Flicker": "flashsync.flicker",
    "FlickerRemover": "flashsync.flicker",
    "FrameClock": "flashsync.frame_clock",
    "HeldExposure": "flashsync.model",
    "InputError": "flashsync.errors",
    "ModelFileError": "flashsync.errors",
    "MontageSummary": "flashsync.montage",
    "NotEnoughDataError": "flashsync.errors",
    "PairAlignment": "flashsync.match",
    "SyncModel": "flashsync.model",
    "SyncReport": "flashsync.pipeline",
    "all_events": "flashsync.pipeline",
    "detect_video": "flashsync.detect",
    "detect_videos": "flashsync.pipeline",
    "frame_table": "flashsync.ticks",
    "load_model": "flashsync.io.model_file",
    "model_ticks_ms": "flashsync.ticks",
    "save_model": "flashsync.io.model_file",
    "solve_pairs": "flashsync.pipeline",
    "synchronize": "flashsync.pipeline",
    "write_montage": "flashsync.montage",
}

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
    "Flicker",
    "FlickerRemover",
    "FrameClock",
    "HeldExposure",
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


lazy_exports(__name__, _EXPORTS)
