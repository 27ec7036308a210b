"""Row profiles: the robust mean luma of each image row, one profile per decoded frame.

A robust row statistic ignores moving players and bright spots, so a profile changes only
where a whole row changed its brightness: where it integrated flash light. Profiles are computed
on the decoder's luma plane directly (no colour conversion) from every ``column_step``-th
column, streaming, so memory stays flat whatever the video's length.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import av
import numba
import numpy as np

from flashsync.errors import FlashsyncError
from flashsync.timestamps import open_video

#: Columns between samples of a row.
DEFAULT_COLUMN_STEP = 2
#: Column blocks of a row profile.
DEFAULT_BLOCKS = 4


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


def row_profile(luma: np.ndarray, column_step: int = DEFAULT_COLUMN_STEP,
                blocks: int = DEFAULT_BLOCKS) -> np.ndarray:
    """Interquartile mean of each row of ``luma`` in ``blocks`` column blocks.

    The mean of the middle half of the values: robust like the median (players, bright
    spots and anything covering under a quarter of a block are ignored) but continuous where
    a row holds two populations of similar size (rink and crowd), where the median jumps
    from one to the other with the noise. Separate column blocks let the detector tell a
    flash, which changes every block alike, from an object that changes one. Computed from
    per-row histograms of the uint8 values (every ``column_step``-th column) in a compiled
    kernel, about ten times faster than ``np.median``.

    Parameters
    ----------
    luma : uint8 array of shape (height, width)
    column_step : int
        Columns between samples.
    blocks : int
        Column blocks, left to right.

    Returns
    -------
    float32 array of shape (height, blocks), DN.
    """
    return _interquartile_mean(np.ascontiguousarray(luma) if luma.strides[1] != 1 else luma,
                               column_step, blocks)


@numba.njit(cache=True, nogil=True)
def _interquartile_mean(luma, column_step, blocks):  # pragma: no cover - compiled
    height, width = luma.shape
    out = np.empty((height, blocks), np.float32)
    histogram = np.empty(256, np.int64)
    for r in range(height):
        for b in range(blocks):
            histogram[:] = 0
            n = 0
            for c in range(b * width // blocks, (b + 1) * width // blocks, column_step):
                histogram[luma[r, c]] += 1
                n += 1
            low, high = 0.25 * n, 0.75 * n
            below, total = 0, 0.0
            for v in range(256):
                count = histogram[v]
                inside = min(below + count, high) - max(below, low)
                if inside > 0:
                    total += inside * v
                below += count
                if below >= high:
                    break
            out[r, b] = total / (high - low)
    return out


def luma_range(frame: av.VideoFrame) -> tuple[float, float]:
    """Luma of black and of white, DN: 0 and 255 for full-range video (JPEG range,
    ``yuvj*``, gray), else 16 and 235."""
    full = frame.color_range == 2 or frame.format.name.startswith(("yuvj", "gray"))
    return (0.0, 255.0) if full else (16.0, 235.0)


def iter_profiles(path: str | Path, column_step: int = DEFAULT_COLUMN_STEP,
                  ) -> Iterator[tuple[float, np.ndarray]]:
    """Decode a video and yield ``(t_frame_ms, profile)`` per frame, presentation order.

    ``profile`` is the float32 robust row mean of the luma per column block, shape (height,
    blocks), as a fraction of the way from black (0) to white (1), so that light scales it:
    a flash multiplies it by the same factor whatever the row's content. Frames without a timestamp are an error
    naming the file.
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
                black, white = luma_range(frame)
                profile = (row_profile(luma_plane(frame), column_step) - black) / (white - black)
                yield float(frame.pts * frame.time_base) * 1000.0, profile
        except av.FFmpegError as error:
            raise FlashsyncError(f"{path}: cannot decode ({error.strerror}); is the file complete?") from None
