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
from flashsync.timestamps import NO_STAMPS, open_video, video_stream

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
    stream = video_stream(container)
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
    """Luma of black and of white in :func:`luma_plane`'s values, DN: 0 and 255 for
    full-range video (JPEG range, ``yuvj*``, gray) and for every frame converted to gray
    (FFmpeg's gray is full range: it stretches a 10-bit or 4:2:2 video's limited range, an
    RGB one's is full), else 16 and 235."""
    name = frame.format.name
    full = frame.color_range == 2 or name.startswith(("yuvj", "gray")) or name not in _PLANAR_LUMA
    return (0.0, 255.0) if full else (16.0, 235.0)


#: Picture types of :func:`read_profiles`: key, predicted from before, from both sides.
PICTURES = ("I", "P", "B")


def picture_type(frame: av.VideoFrame) -> str:
    """``"I"`` for a key frame (or any intra-coded one), ``"B"`` for a bidirectionally
    predicted frame, ``"P"`` otherwise (:data:`PICTURES`)."""
    if frame.key_frame or frame.pict_type == av.video.frame.PictureType.I:
        return "I"
    return "B" if frame.pict_type == av.video.frame.PictureType.B else "P"


def display_rotation_deg(frame: av.VideoFrame) -> int:
    """Degrees counterclockwise that the frame's display matrix turns it for showing (a
    phone held upright stores its frames on their side), to a quarter turn: -90, 0, 90 or
    180, as FFmpeg states it; 0 without one."""
    return (round(frame.rotation / 90.0) + 1) % 4 * 90 - 90


def read_profiles(
    path: str | Path, start_pts: int | None = None, stop_pts: int | None = None
) -> tuple[VideoInfo, Iterator[tuple[float, np.ndarray, str, int]]]:
    """Open a video once: its :class:`VideoInfo` and an iterator of ``(t_frame_ms, profile,
    picture, rotation_deg)`` per decoded frame, presentation order (the file closes when the
    iterator ends).

    ``start_pts``, ``stop_pts`` (stream time-base units) read a segment only: the frames
    whose stamps are in ``[start_pts, stop_pts)``, decoded from the key frame at or before
    ``start_pts`` (:mod:`flashsync.segments`; a segment that starts at a key frame decodes to
    the same pixels as the whole video does); the check that the video is complete is then
    the caller's (:func:`cut_short`).

    ``profile`` is the float32 mean luma per row and column block, shape (height, blocks),
    as a fraction of the way from black (0) to white (1), so that light scales it: a flash
    multiplies it by the same factor whatever the row's content. ``picture``: how the frame
    was coded, ``"I"`` a key frame (on its own; the codec refreshes there what it kept from
    frame to frame), ``"P"`` predicted from frames before it, ``"B"`` from frames before and
    after it (:data:`PICTURES`). ``rotation_deg``: its display matrix's turn
    (:func:`display_rotation_deg`). Frames without a timestamp are an error naming the file.
    """
    path = Path(path)
    container = open_video(path)
    try:
        info = video_info(container, path)
    except FlashsyncError:
        container.close()
        raise
    return info, _profiles(container, path, start_pts, stop_pts)


def _profiles(
    container: av.container.InputContainer, path: Path, start_pts: int | None, stop_pts: int | None
) -> Iterator[tuple[float, np.ndarray, str, int]]:
    whole = start_pts is None and stop_pts is None
    with container:
        stream = video_stream(container)
        stream.thread_type = "AUTO"
        if start_pts is not None:
            container.seek(start_pts, stream=stream, backward=True)
        decoded, times, size = 0, [], (stream.width, stream.height)  # the decoder updates the stream's
        try:
            for frame in container.decode(stream):
                if frame.pts is None:
                    raise InputError(f"{path}: a frame has no timestamp; {NO_STAMPS}")
                if start_pts is not None and frame.pts < start_pts:
                    continue
                if stop_pts is not None and frame.pts >= stop_pts:
                    break
                time_ms = float(frame.pts * frame.time_base) * 1000.0
                if (frame.width, frame.height) != size:
                    raise InputError(
                        f"{path}: its frames change size at {time_ms / 1000.0:.3f} s ({size[0]}x{size[1]} "
                        f"-> {frame.width}x{frame.height}); give each part as a video of its own "
                        f"(ffmpeg -i IN -ss {time_ms / 1000.0:.3f} -c copy PART.mkv, and -to for the part before)"
                    )
                decoded += 1
                times = [*times[-1:], time_ms]
                profile = row_profile(luma_plane(frame), *luma_range(frame))
                yield time_ms, profile, picture_type(frame), display_rotation_deg(frame)
        except av.FFmpegError as error:
            cut = cut_short(container, decoded, times) if whole else None
            if cut:
                raise InputError(f"{path}: {cut} (decoding failed: {error.strerror}); {RECOPY}") from None
            raise InputError(f"{path}: cannot decode ({error.strerror}); is the file complete?") from None
        cut = cut_short(container, decoded, times) if whole else None
        if cut:
            raise InputError(f"{path}: {cut}; {RECOPY}")


#: What to do about a video that is cut short.
RECOPY = "copy the whole file again, or remux the part that is there (ffmpeg -i IN -c copy OUT.mkv) to use it"


def cut_short(container: av.container.InputContainer, decoded: int, last_times_ms: list[float]) -> str | None:
    """What shows a video is cut short, or None: no frame where its header states a duration,
    frames that end well before that duration (a Matroska file), or fewer frames decoded
    than its index lists (an MP4 whose index is at the front) where they also end more than
    a frame and a half before that duration or it states none: an AVI lists a dropped frame
    as an empty entry of its index, and one with drops ends where its header says.
    ``last_times_ms``: the last one or two frame times."""
    stream = video_stream(container)
    if stream.duration and stream.time_base:
        duration_ms = float(stream.duration * stream.time_base) * 1000.0
    elif container.duration:
        duration_ms = container.duration / 1000.0
    else:
        duration_ms = None
    # the header's end is at least its duration (a Matroska duration runs from time 0, an
    # MP4 stream's from its first frame)
    step = last_times_ms[-1] - last_times_ms[0] if len(last_times_ms) > 1 else _frame_period_ms(stream)
    short_ms = duration_ms - (last_times_ms[-1] + step) if duration_ms is not None and last_times_ms else None
    if not last_times_ms and duration_ms:
        return f"cut short: no frame decoded of the {duration_ms / 1000.0:.2f} s its header states"
    listed = stream.frames or 0
    if listed and decoded < listed - max(2, 0.01 * listed) and (short_ms is None or short_ms > 1.5 * step):
        return f"cut short: {decoded} frames decoded of the {listed} its index lists"
    if short_ms is not None and short_ms > max(3.0 * step, 0.02 * duration_ms):
        end = duration_ms - short_ms
        return (
            f"cut short: its frames end at {end / 1000.0:.2f} s of the {duration_ms / 1000.0:.2f} s its header states"
        )
    return None


def _frame_period_ms(stream: av.video.stream.VideoStream) -> float:
    """The frame period the stream states, ms (0 where it states no rate): the step after a
    single decoded frame, which a video of one frame lasts in its header."""
    rate = stream.average_rate
    return 1000.0 / float(rate) if rate else 0.0
