"""Row profiles: the median luma of each image row, one profile per decoded frame.

The median ignores moving players and bright spots, so a profile changes only where a
whole row changed its brightness: where it integrated flash light. Profiles are computed
on the decoder's luma plane directly (no colour conversion) from every ``column_step``-th
column, streaming, so memory stays flat whatever the video's length.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import av
import numpy as np

from flashsync.errors import FlashsyncError
from flashsync.timestamps import open_video

#: Columns between median samples; 4 costs < 0.1 DN of profile accuracy on textured scenes.
DEFAULT_COLUMN_STEP = 4


@dataclass(frozen=True)
class VideoInfo:
    """What flashsync needs to know of a video before decoding it."""

    path: Path
    width: int
    height: int
    n_frames_hint: int

    @property
    def camera(self) -> str:
        return self.path.stem


def probe_video(path: str | Path) -> VideoInfo:
    """Size and approximate frame count of a video, or a one-line error."""
    path = Path(path)
    with open_video(path) as container:
        stream = container.streams.video[0]
        if not stream.width or not stream.height:
            raise FlashsyncError(f"{path}: video stream has no frame size; is the file complete?")
        hint = stream.frames or int((container.duration or 0) / 1e6 * float(stream.average_rate or 0))
        return VideoInfo(path, stream.width, stream.height, hint)


def luma_plane(frame: av.VideoFrame) -> np.ndarray:
    """The frame's Y plane as a uint8 view of shape (height, width), no copy where possible."""
    if frame.format.name not in _PLANAR_LUMA:
        return frame.to_ndarray(format="gray")
    plane = frame.planes[0]
    data = np.frombuffer(plane, dtype=np.uint8)
    return data.reshape(frame.height, plane.line_size)[:, : frame.width]


#: 8-bit pixel formats whose first plane is the luma; others are converted to gray.
_PLANAR_LUMA = {"yuv420p", "yuvj420p", "yuv422p", "yuvj422p", "yuv444p", "yuvj444p", "nv12",
                "nv21", "gray"}


def row_median(luma: np.ndarray, column_step: int = DEFAULT_COLUMN_STEP) -> np.ndarray:
    """Median of each row of ``luma`` (shape (height, width), uint8) over every
    ``column_step``-th column; float32 array of shape (height,)."""
    samples = luma[:, ::column_step]
    middle = samples.shape[1] // 2
    upper = np.partition(samples, middle, axis=1)
    if samples.shape[1] % 2:
        return upper[:, middle].astype(np.float32)
    lower = np.max(upper[:, :middle], axis=1)
    return (upper[:, middle].astype(np.float32) + lower) * 0.5


def iter_profiles(path: str | Path, column_step: int = DEFAULT_COLUMN_STEP,
                  ) -> Iterator[tuple[float, np.ndarray]]:
    """Decode a video and yield ``(t_frame_ms, profile)`` per frame, presentation order.

    ``profile`` is the float32 row-median luma of shape (height,). Frames without a
    timestamp are an error naming the file.
    """
    path = Path(path)
    with open_video(path) as container:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        try:
            for frame in container.decode(stream):
                if frame.pts is None:
                    raise FlashsyncError(f"{path}: a frame has no timestamp; remux the file "
                                         "(ffmpeg -i IN -c copy OUT.mkv)")
                yield float(frame.pts * frame.time_base) * 1000.0, row_median(luma_plane(frame), column_step)
        except av.FFmpegError as error:
            raise FlashsyncError(f"{path}: cannot decode ({error.strerror}); is the file complete?") from None
