"""Row profiles: the mean luma of each image row in column blocks, one per decoded frame.

A flash changes whole rows; the detector takes the median of the blocks' changes, which
ignores moving players and bright spots, so only rows that integrated flash light count.
Profiles are computed on the decoder's luma plane directly (no colour conversion, every
pixel, a SIMD row reduction), streaming, so memory stays flat whatever the video's
length.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import av
import cv2
import numpy as np

from flashsync.errors import FlashsyncError, InputError
from flashsync.timestamps import open_video

#: Column blocks of a row profile.
DEFAULT_BLOCKS = 8


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


def video_info(container: av.container.InputContainer, path: Path) -> VideoInfo:
    """Size and approximate frame count of an open video, or a one-line error."""
    stream = container.streams.video[0]
    if not stream.width or not stream.height:
        raise InputError(f"{path}: video stream has no frame size; is the file complete?")
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
_PLANAR_LUMA = {"yuv420p", "yuvj420p", "yuv422p", "yuvj422p", "yuv444p", "yuvj444p", "nv12", "nv21", "gray"}


def row_profile(luma: np.ndarray, black: float = 0.0, white: float = 255.0, blocks: int = DEFAULT_BLOCKS) -> np.ndarray:
    """Mean luma of each row in ``blocks`` equal column blocks, as a fraction of the way
    from ``black`` to ``white`` (DN); the ``width % blocks`` rightmost columns are left out.

    A flash scales every block of a row alike; a player, a bright spot or anything else
    that covers a few blocks changes only those, and the detector's median over blocks
    ignores them. A block mean is linear in the light (no clipping, no jumps between the
    two populations of a row that is half rink, half crowd) and cheap: OpenCV's SIMD row
    reduction over every pixel, each block a row of its own, two to three times faster
    than a compiled loop and a tenth of the cost of decoding the frame.

    Parameters
    ----------
    luma : uint8 array of shape (height, width)
    black, white : float
        Luma of black and of white, DN (:func:`luma_range`).
    blocks : int
        Column blocks, left to right.

    Returns
    -------
    float32 array of shape (height, blocks): 0 black, 1 white.
    """
    height, width = luma.shape
    blocks = min(blocks, width)
    block = width // blocks
    pixels = np.ascontiguousarray(luma[:, : block * blocks])  # a view for a plain frame
    sums = cv2.reduce(pixels.reshape(height * blocks, block), 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S)
    profile = sums.reshape(height, blocks).astype(np.float32)
    profile *= 1.0 / (block * (white - black))
    profile -= black / (white - black)
    return profile


def luma_range(frame: av.VideoFrame) -> tuple[float, float]:
    """Luma of black and of white, DN: 0 and 255 for full-range video (JPEG range,
    ``yuvj*``, gray), else 16 and 235."""
    full = frame.color_range == 2 or frame.format.name.startswith(("yuvj", "gray"))
    return (0.0, 255.0) if full else (16.0, 235.0)


def read_profiles(path: str | Path) -> tuple[VideoInfo, Iterator[tuple[float, np.ndarray]]]:
    """Open a video once: its :class:`VideoInfo` and an iterator of ``(t_frame_ms, profile)``
    per decoded frame, presentation order (the file closes when the iterator ends).

    ``profile`` is the float32 mean luma per row and column block, shape (height, blocks),
    as a fraction of the way from black (0) to white (1), so that light scales it: a flash
    multiplies it by the same factor whatever the row's content. Frames without a timestamp
    are an error naming the file.
    """
    path = Path(path)
    container = open_video(path)
    try:
        info = video_info(container, path)
    except FlashsyncError:
        container.close()
        raise
    return info, _profiles(container, path)


def _profiles(container: av.container.InputContainer, path: Path) -> Iterator[tuple[float, np.ndarray]]:
    with container:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        try:
            for frame in container.decode(stream):
                if frame.pts is None:
                    raise InputError(f"{path}: a frame has no timestamp; remux the file (ffmpeg -i IN -c copy OUT.mkv)")
                yield float(frame.pts * frame.time_base) * 1000.0, row_profile(luma_plane(frame), *luma_range(frame))
        except av.FFmpegError as error:
            raise InputError(f"{path}: cannot decode ({error.strerror}); is the file complete?") from None
