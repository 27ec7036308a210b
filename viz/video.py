"""Each camera's video in sync on ``global_time``, with the flash rows drawn on its frames.

The Rerun viewer plays MP4 files (``AssetVideo``) holding H.264, H.265 or AV1. An MP4
input is logged as it is; any other container (MKV, MOV, ...) is first remuxed into a
temporary MP4 with PyAV -- packets are copied, nothing is re-encoded, so the remux costs
about as much as reading the file and the recording grows by the size of the video.
The whole video is stored in the recording once, as a static blob; every frame is a
``VideoFrameReference`` logged at the global time its readout starts (see
:mod:`viz.timeline`) and at its index on ``frame_<camera>``.

On the frames: the flash rows (the edges of the bands, :func:`log_flash_rows`) and the
"now" line, the row exposed at the time cursor as the timeline plays
(:func:`log_now_line`).
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
from flashsync.timestamps import open_video, video_stream
from viz.palette import NOW_COLOR, STATUS_COLORS
from viz.timeline import Timeline, readout_end_ms, readout_start_ms

ROOT = "cameras"
VIEWER_CODECS = ("h264", "hevc", "av1")
NOW_RATE_HZ = 250.0
"""Ticks per second of ``global_time`` at which the "now" line is logged."""
LABEL_AT = 0.1
"""Where a flash row's name is, as a share of the image width from its side."""
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


def flash_labels_entity(camera: str) -> str:
    """Entity path of the names of the flash rows on ``camera``'s frames."""
    return f"{camera_entity(camera)}/flash_labels"


def status_entity(camera: str) -> str:
    """Entity path of the label saying when ``camera``'s video starts or ended."""
    return f"{camera_entity(camera)}/status"


def now_entity(camera: str) -> str:
    """Entity path of the line across the row of ``camera`` exposed at the time cursor."""
    return f"{camera_entity(camera)}/now"


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
        with the packets of its video stream copied (same timestamps; the one flashsync
        reads, :func:`~flashsync.timestamps.video_stream`).
    """
    with open_video(path) as container:
        stream = video_stream(container)
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


def log_video(recording: rr.RecordingStream, timeline: Timeline, camera: CameraClock, path: Path) -> None:
    """Log ``camera``'s video and one frame reference per frame.

    Parameters
    ----------
    recording : RecordingStream
    timeline : Timeline
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
        indexes=timeline.frame_columns(camera, np.arange(camera.n_frames)),
        columns=rr.VideoFrameReference.columns_nanos(video_nanos),
    )


def log_video_span(recording: rr.RecordingStream, timeline: Timeline, camera: CameraClock) -> None:
    """Say when ``camera``'s video starts and ends, where it shows no frame.

    Before its first frame (a camera that started after the earliest one), a label in the
    middle of the image names the instant the video starts; after its last frame has been
    read out, the frame is cleared (the viewer would go on showing it) and a label names
    the instant the video ended.
    """
    start = readout_start_ms(camera, [0])[0]
    end = readout_end_ms(camera, [camera.n_frames - 1])[0]
    rows: list[tuple[float, str | None]] = []
    if start > timeline.origin_ms:
        rows += [
            (timeline.origin_ms, f"{camera.name}: video starts at +{(start - timeline.origin_ms) / 1000:.3f} s"),
            (start, None),
        ]
    rows.append((end, f"{camera.name}: video ended at +{(end - timeline.origin_ms) / 1000:.3f} s"))
    times, labels = zip(*rows)
    shown = [label for label in labels if label is not None]
    recording.send_columns(
        status_entity(camera.name),
        indexes=[timeline.column(np.array(times))],
        columns=rr.Points2D.columns(
            positions=[[camera.width / 2, camera.height / 2]] * len(shown),
            labels=shown,
            radii=[0.0] * len(shown),
            colors=[STATUS_COLORS["unmatched"]] * len(shown),
        ).partition([int(label is not None) for label in labels]),
    )
    recording.send_columns(
        video_entity(camera.name), indexes=[timeline.column([end])], columns=rr.Clear.columns(is_recursive=[False])
    )


def log_flash_rows(
    recording: rr.RecordingStream, timeline: Timeline, camera: CameraClock, events: pd.DataFrame
) -> None:
    """Draw each event's edge row across the frame that holds it, and name it.

    A horizontal line through the centre of the edge row (``y = row +``
    :data:`PIXEL_CENTRE` in Rerun's image coordinates) from ``x = 0`` to the image width,
    coloured by status (:data:`viz.palette.STATUS_COLORS`), thick for a leading edge, thin
    for a trailing one. Its name (``flash 3``, ``flash 3 end``, ``unmatched``, ...) is a
    label at :data:`LABEL_AT` of the width from the left (leading) or the right (trailing)
    edge of the image, away from the middle where tracked objects often are. Both are shown
    on that frame only.

    Parameters
    ----------
    recording : RecordingStream
    timeline : Timeline
    camera : CameraClock
    events : DataFrame
        This camera's rows of :func:`viz.events.event_table`.
    """
    if events.empty:
        return
    indexes, order, lengths = timeline.frame_batches(camera, events["frame"].to_numpy())
    events = events.iloc[order]
    y = events["row"].to_numpy(dtype=np.float64) + PIXEL_CENTRE
    trailing = events["edge"].eq("trailing").fillna(False).to_numpy(dtype=bool)
    strips = _across(y, camera.width)
    colors = [STATUS_COLORS[status] for status in events["status"]]
    radii = np.where(trailing, rr.Radius.ui_points(0.75), rr.Radius.ui_points(1.5))
    recording.send_columns(
        flash_rows_entity(camera.name),
        indexes=indexes,
        columns=rr.LineStrips2D.columns(strips=strips, colors=colors, radii=radii).partition(lengths),
    )
    names = [
        ("unmatched" if status == "unmatched" else f"flash {flash}") + (" rejected" if status == "rejected" else "")
        for flash, status in zip(events["flash"], events["status"])
    ]
    labels = [f"{name} end" if end else name for name, end in zip(names, trailing)]
    x = np.where(trailing, (1 - LABEL_AT) * camera.width, LABEL_AT * camera.width)
    recording.send_columns(
        flash_labels_entity(camera.name),
        indexes=indexes,
        columns=rr.Points2D.columns(
            positions=np.stack([x, y], axis=1), colors=colors, labels=labels, radii=[0.0] * len(y)
        ).partition(lengths),
    )


def log_now_line(
    recording: rr.RecordingStream,
    timeline: Timeline,
    camera: CameraClock,
    also_at_ms: np.ndarray | tuple = (),
    rate_hz: float = NOW_RATE_HZ,
) -> None:
    """Draw the row exposed at the time cursor: a line across ``camera``'s frame.

    At every tick of a ``rate_hz`` grid on ``global_time`` (from 0) within the camera's
    video, and at the instants ``also_at_ms`` (e.g. those a click on the flash log goes
    to, where the cursor then is exactly), the line is at the stored-image row whose
    exposure ends at that instant,
    :meth:`flashsync.model.CameraClock.locate` (drift warp and upside-down cameras
    included), on the frame being read out -- the frame the video shows. In the vertical
    blanking or a dropped frame no row ends its exposure: the line is cleared until the
    next tick that has one. Coloured :data:`viz.palette.NOW_COLOR`.

    Parameters
    ----------
    recording : RecordingStream
    timeline : Timeline
    camera : CameraClock
    also_at_ms : float array
        More instants, ``t_global_ms``, ms.
    rate_hz : float
        Ticks per second of ``global_time``.
    """
    start = readout_start_ms(camera, [0])[0]
    end = readout_end_ms(camera, [camera.n_frames - 1])[0]
    period_ms, origin = 1000.0 / rate_hz, timeline.origin_ms
    grid = origin + period_ms * np.arange(
        np.ceil((start - origin) / period_ms), np.floor((end - origin) / period_ms) + 1
    )
    also = np.asarray(also_at_ms, dtype=np.float64)
    ticks = np.concatenate([grid, also[(also >= start) & (also <= end)]])
    ticks = origin + np.unique(np.round((ticks - origin) * 1e6)) / 1e6  # whole ns, once
    _, rows = camera.locate(ticks)
    shown = np.isfinite(rows)
    keep = shown | np.concatenate([[False], shown[:-1]])  # a tick that clears the line
    ticks, rows, shown = ticks[keep], rows[keep], shown[keep]
    entity = now_entity(camera.name)
    recording.log(
        entity, rr.LineStrips2D.from_fields(colors=[NOW_COLOR], radii=[rr.Radius.ui_points(1.0)]), static=True
    )
    recording.send_columns(
        entity,
        indexes=[timeline.column(ticks)],
        columns=rr.LineStrips2D.columns(strips=_across(rows[shown] + PIXEL_CENTRE, camera.width)).partition(
            shown.astype(np.int64)
        ),
    )


def _across(y: np.ndarray, width: int) -> np.ndarray:
    """Horizontal lines across an image of ``width`` px at heights ``y`` (Rerun image
    coordinates), shape (n, 2, 2)."""
    return np.stack([np.stack([np.zeros_like(y), y], axis=1), np.stack([np.full_like(y, width), y], axis=1)], axis=1)
