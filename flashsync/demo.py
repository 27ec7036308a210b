"""The whole chain on the shipped sample: detect -> sync -> restamp, scored against truth."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from flashsync.errors import InputError
from flashsync.evaluate import stamp_errors, sync_errors
from flashsync.io import (
    events_to_frame,
    load_detections,
    load_ground_truth,
    load_homographies,
    load_plane_outline,
    save_events,
    save_model,
)
from flashsync.pipeline import all_events, detect_videos, synchronize
from flashsync.report import sync_table
from tracking_adapter.restamp import format_summary, restamp_file

VIDEO_SUFFIXES = (".mp4", ".mkv", ".mov", ".avi")


def default_samples() -> Path:
    """The repository's ``samples/`` beside the package, else ``./samples``."""
    shipped = Path(__file__).resolve().parents[1] / "samples"
    return shipped if shipped.is_dir() else Path("samples")


def _below_working_directory(path: Path) -> Path:
    """``path`` relative to the working directory where it lies below it (so that the report
    names it as the user would), else as it is."""
    try:
        return path.resolve().relative_to(Path.cwd().resolve())
    except ValueError:
        return path


def run_demo(
    samples: Path | None,
    output: Path,
    progress: Callable[[str, int], Callable[[int], None]] | None = None,
    recording: Path | None = None,
) -> str:
    """Run the chain on ``samples`` (videos, ``truth.json``, ``detections.csv``), write
    ``events.csv``, ``sync.json`` and ``restamped.csv`` into ``output`` (and a Rerun
    recording to ``recording`` if given); return the report."""
    samples = _below_working_directory(samples or default_samples())
    videos = sorted(p for p in samples.glob("*") if p.suffix.lower() in VIDEO_SUFFIXES)
    if not videos or not (samples / "truth.json").is_file():
        raise InputError(
            f"{samples}: no sample videos with truth.json; run the demo from the repository, "
            "or on a folder that 'flashsync simulate sample' rendered",
            parameter="samples",
        )
    started = time.perf_counter()
    detections = detect_videos(videos, progress=progress)
    save_events(all_events(detections), output / "events.csv")
    model, report = synchronize(detections)
    save_model(model, output / "sync.json")
    summary = restamp_file(samples / "detections.csv", output / "restamped.csv", model)
    elapsed = time.perf_counter() - started

    truth = load_ground_truth(samples / "truth.json")
    errors = sync_errors(model, truth)
    detection_error = stamp_errors(load_detections(output / "restamped.csv"), model, truth)

    lines = [f"flashsync demo on {samples} ({len(videos)} videos, {elapsed:.1f} s)", "", sync_table(model, report), ""]
    lines += [f"warning: {w}" for w in report.warnings]
    lines.append("synchronisation error against ground truth, every frame and row, and each exposure:")
    for row in errors.itertuples():
        camera = model.cameras[row.camera]
        exposure = (
            f"   exposure {camera.exposure_ms:5.2f} ± {camera.exposure_std_ms:.2f} ms, "
            f"true {truth.cameras[row.camera].exposure_ms:5.2f}"
            if camera.exposure_ms is not None and camera.exposure_std_ms is not None
            else ""
        )
        lines.append(f"  {row.camera:<10} RMS {row.rms_ms:.4f} ms   max {row.max_ms:.4f} ms{exposure}")
    overall = float(np.sqrt(np.mean(errors["rms_ms"] ** 2)))
    lines.append(f"  {'all':<10} RMS {overall:.4f} ms")
    lines.append(f"re-stamped {format_summary(summary)}")
    lines.append(f"puck detections: t_global_ms RMS error {np.sqrt(np.mean(detection_error**2)):.4f} ms against truth")
    lines.append(f"outputs in {output}/: events.csv sync.json restamped.csv")
    if recording is not None:
        import viz

        viz.save_recording(
            recording,
            model,
            videos=videos,
            events=events_to_frame(all_events(detections)),
            detections=load_detections(output / "restamped.csv"),
            homographies=load_homographies(samples / "homographies.json"),
            plane_outline_m=load_plane_outline(samples / "homographies.json"),
        )
        lines.append(f"recording -> {recording} (open it with: rerun {recording})")
    return "\n".join(lines)
