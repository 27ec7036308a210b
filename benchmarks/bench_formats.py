"""The shipped sample's cam1 written again as other cameras write video (codec, bit depth,
chroma subsampling, RGB, container), then synchronised with the sample's other three
cameras as `flashsync sync` does: every camera's error against the sample's truth, cam1's
exposure and time per row, and the largest error/sigma (RMS over a camera's probes,
against the reference; and a time per row's).

    python benchmarks/bench_formats.py [--samples DIR]

The first row is the shipped file itself; the others re-encode its decoded frames, so they
carry its H.264 losses and their own.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

os.environ.setdefault("SVT_LOG", "1")  # the AV1 encoder's banner: errors only

from flashsync import detect_videos, synchronize  # noqa: E402
from flashsync.evaluate import camera_accuracy, sync_errors  # noqa: E402
from flashsync.io import load_ground_truth  # noqa: E402
from flashsync.simulation.encode import reencode  # noqa: E402

#: name: suffix, FFmpeg encoder, pixel format, encoder options.
FORMATS = {
    "H.264 4:2:0 (re-encoded)": ("mp4", "libx264", "yuv420p", {"crf": "18"}),
    "H.264 10-bit": ("mp4", "libx264", "yuv420p10le", {"crf": "18"}),
    "H.264 4:4:4": ("mp4", "libx264", "yuv444p", {"crf": "18"}),
    "HEVC 8-bit": ("mp4", "libx265", "yuv420p", {"crf": "18", "x265-params": "log-level=none"}),
    "HEVC 10-bit (phones)": ("mov", "libx265", "yuv420p10le", {"crf": "18", "x265-params": "log-level=none"}),
    "ProRes 4:2:2 10-bit": ("mov", "prores", "yuv422p10le", {}),
    "MJPEG full range, AVI": ("avi", "mjpeg", "yuvj420p", {"q:v": "2"}),
    "MPEG-2, MPEG-TS": ("ts", "mpeg2video", "yuv420p", {"q:v": "2"}),
    "MPEG-4 Part 2, AVI": ("avi", "mpeg4", "yuv420p", {"q:v": "2"}),
    "PNG RGB, MOV": ("mov", "png", "rgb24", {}),
    "VP9, WebM": ("webm", "libvpx-vp9", "yuv420p", {"crf": "10", "b:v": "0"}),
    "AV1, Matroska": ("mkv", "libsvtav1", "yuv420p", {"crf": "15"}),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=Path, default=Path(__file__).resolve().parents[1] / "samples")
    args = parser.parse_args()
    truth = load_ground_truth(args.samples / "truth.json")
    others = detect_videos([args.samples / name for name in ("cam2.mkv", "cam3.mp4", "cam4.mp4")])
    header = " ".join(f"{camera:>7s}" for camera in ("cam1", "cam2", "cam3", "cam4"))
    print(f"{'cam1 as':26s} {header}  (RMS ms)  cam1: exposure, T_row errors (ms, %)  error/sigma max: time, T_row")
    with tempfile.TemporaryDirectory() as folder:
        runs = [("as shipped (H.264, MP4)", args.samples / "cam1.mp4")]
        for name, (suffix, codec, pixel_format, options) in FORMATS.items():
            path = Path(folder) / name.replace(" ", "_").replace(",", "") / f"cam1.{suffix}"
            reencode(args.samples / "cam1.mp4", path, codec, pixel_format, options, rate=30)
            runs.append((name, path))
        for name, path in runs:
            model, _ = synchronize(detect_videos([path]) + others)
            errors = sync_errors(model, truth).set_index("camera")["rms_ms"]
            accuracy = camera_accuracy(model, truth).set_index("camera")
            cam1 = accuracy.loc["cam1"]
            print(
                f"{name:26s} "
                + " ".join(f"{errors[camera]:7.4f}" for camera in ("cam1", "cam2", "cam3", "cam4"))
                + f"            {cam1['exposure_error_ms']:+.3f}, {cam1['row_time_error_pct']:+.3f}"
                + f"                      {accuracy['z_rms'].max():.2f}, {accuracy['row_time_z'].abs().max():.2f}"
            )


if __name__ == "__main__":
    main()
