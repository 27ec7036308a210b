"""Each camera's video in sync on ``global_time``, with the flash rows drawn on its frames.

The Rerun viewer plays MP4 files (``AssetVideo``) holding H.264, H.265 or AV1. An MP4
input is logged as it is; any other container (MKV, MOV, ...) is first remuxed into a
temporary MP4 with PyAV -- packets are copied, nothing is re-encoded, so the remux costs
about as much as reading the file and the recording grows by the size of the video.
The whole video is stored in the recording once, as a static blob; every frame is a
``VideoFrameReference`` logged at the global time its readout starts (see
:mod:`viz.timeline`) and at its index on ``frame_<camera>``.
"""

from __future__ import annotations

import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

import av
import numpy as np
import pandas as pd
import rerun as rr

from flashsync.errors import FlashsyncError
from flashsync.model import CameraClock, SyncModel
from flashsync.timestamps import open_video
from viz.palette import STATUS_COLORS
from viz.timeline import frame_batches, frame_columns

ROOT = "cameras"
VIEWER_CODECS = ("h264", "hevc", "av1")
PIXEL_CENTRE = 0.5
"""Add to flashsync image coordinates (px; pixel centres at integers, stored row ``r`` at
``y = r``) to get Rerun's (the first pixel's top-left corner at 0, its centre at 0.5)."""


def camera_entity(camera: str) -> str:
    """Entity path of ``camera``'s image space (video, flash rows, detections)."""
    return f"{ROOT}/{rr.escape_entity_path_part(camera)}"


def video_entity(camera: str) -> str:
    """Entity path of ``camera``'s ``AssetVideo`` and frame references."""
    return f"{camera_entity(camera)}/video"


def flash_rows_entity(camera: str) -> str:
    """Entity path of the flash-row lines drawn on ``camera``'s frames."""
    return f"{camera_entity(camera)}/flash_rows"


def camera_videos(videos: Mapping[str, str | Path] | Iterable[str | Path], model: SyncModel) -> dict[str, Path]:
    """Name each video by its camera.

    Parameters
    ----------
    videos : mapping of camera name to path, or iterable of paths
        Paths alone are named by their file stem (``cam1.mkv`` -> ``cam1``).
    model : SyncModel
        Every named camera must be in it.

    Returns
    -------
    dict of str to Path
        In the order given.
    """
    if isinstance(videos, Mapping):
        named = [(str(name), Path(path)) for name, path in videos.items()]
    else:
        named = [(Path(path).stem, Path(path)) for path in videos]
    names = [name for name, _ in named]
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise FlashsyncError(
            f"two videos are named {', '.join(duplicates)}; camera names are "
            "file stems and must be unique: rename the files"
        )
    for name, path in named:
        if name not in model.cameras:
            raise FlashsyncError(
                f"{path}: camera {name!r} is not in the model (it has "
                f"{', '.join(model.cameras)}); give the videos the model was "
                "made from"
            )
    return dict(named)


def viewer_mp4(path: Path, workdir: Path) -> Path:
    """An MP4 file the Rerun viewer can play holding ``path``'s video stream.

    Parameters
    ----------
    path : Path
        Video file; H.264, H.265 or AV1 in any container FFmpeg reads.
    workdir : Path
        Directory for the remuxed copy of a non-MP4 input.

    Returns
    -------
    Path
        ``path`` itself if it is an ``.mp4`` file, else ``workdir / (stem + ".mp4")``
        with the packets of its first video stream copied (same timestamps).
    """
    with open_video(path) as container:
        stream = container.streams.video[0]
        codec = stream.codec_context.name
        if codec not in VIEWER_CODECS:
            raise FlashsyncError(
                f"{path}: the Rerun viewer cannot play {codec} video (it plays "
                f"{', '.join(VIEWER_CODECS)}); re-encode it, e.g. "
                f"ffmpeg -i {path.name} -c:v libx264 {path.stem}.mp4"
            )
        if path.suffix.lower() == ".mp4" and "mp4" in container.format.name.split(","):
            return path
        target = workdir / f"{path.stem}.mp4"
        with av.open(str(target), "w", format="mp4") as output:
            copy = output.add_stream_from_template(stream)
            for packet in container.demux(stream):
                if packet.size == 0:  # the demuxer's end-of-stream marker
                    continue
                packet.stream = copy
                output.mux(packet)
    return target


def log_video(recording: rr.RecordingStream, camera: CameraClock, path: Path) -> None:
    """Log ``camera``'s video and one frame reference per frame.

    Parameters
    ----------
    recording : RecordingStream
    camera : CameraClock
        Its ``n_frames`` must equal the number of frames in the video.
    path : Path
        Video file (see :func:`viewer_mp4` for the formats).
    """
    with tempfile.TemporaryDirectory(prefix="flashsync-viz-") as workdir:
        contents = viewer_mp4(path, Path(workdir)).read_bytes()
    asset = rr.AssetVideo(contents=contents, media_type="video/mp4")
    # The viewer's own frame timestamps, in presentation order: frame i is the i-th.
    video_nanos = np.sort(asset.read_frame_timestamps_nanos())
    if len(video_nanos) != camera.n_frames:
        raise FlashsyncError(
            f"{path}: {len(video_nanos)} frames, but the model has {camera.n_frames} for camera "
            f"{camera.name!r}; give the video the model was made from"
        )
    entity = video_entity(camera.name)
    recording.log(entity, asset, static=True)
    recording.send_columns(
        entity,
        indexes=frame_columns(camera, np.arange(camera.n_frames)),
        columns=rr.VideoFrameReference.columns_nanos(video_nanos),
    )


def log_flash_rows(recording: rr.RecordingStream, camera: CameraClock, events: pd.DataFrame) -> None:
    """Draw each event's edge row across the frame that holds it.

    A horizontal line through the centre of the edge row (``y = row +``
    :data:`PIXEL_CENTRE` in Rerun's image coordinates) from ``x = 0`` to the image width,
    coloured by status (:data:`viz.palette.STATUS_COLORS`), labelled with
    the flash id (or ``unmatched``) and the edge. It is shown on that frame only.

    Parameters
    ----------
    recording : RecordingStream
    camera : CameraClock
    events : DataFrame
        This camera's rows of :func:`viz.events.event_table`.
    """
    if events.empty:
        return
    indexes, order, lengths = frame_batches(camera, events["frame"].to_numpy())
    events = events.iloc[order]
    y = events["row"].to_numpy(dtype=np.float64) + PIXEL_CENTRE
    strips = np.stack(
        [np.stack([np.zeros_like(y), y], axis=1), np.stack([np.full_like(y, camera.width), y], axis=1)], axis=1
    )
    names = [
        "unmatched" if status == "unmatched" else f"flash {flash}"
        for flash, status in zip(events["flash"], events["status"])
    ]
    labels = [name if pd.isna(edge) else f"{name} {edge}" for name, edge in zip(names, events["edge"])]
    colors = [STATUS_COLORS[status] for status in events["status"]]
    columns = rr.LineStrips2D.columns(strips=strips, colors=colors, labels=labels)
    recording.send_columns(flash_rows_entity(camera.name), indexes=indexes, columns=columns.partition(lengths))
