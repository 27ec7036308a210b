"""Frame timestamps in ms: from video containers and from RTP 90 kHz stamps (CSV files of
frame times: :mod:`flashsync.io.timestamps`).

flashsync works with container timestamps, never with ``frame_index / fps``, so dropped
frames and variable frame rates cost nothing. All functions return float64 arrays of
shape (n_frames,) in milliseconds, in presentation order.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

import av
import numpy as np

from flashsync.errors import InputError

RTP_CLOCK_HZ = 90_000
_RTP_WRAP = 2**32


#: What to do about bad stamps in a video file.
REMUX = "remux the file (ffmpeg -i IN -c copy OUT.mkv) or give the timestamps as CSV"


def check_timestamps(times_ms: np.ndarray, source: str, fix: str = REMUX) -> np.ndarray:
    """Return ``times_ms`` as float64 if they are finite and strictly increasing.

    Parameters
    ----------
    times_ms : array of shape (n_frames,)
        Frame times in ms, presentation order.
    source : str
        File name used in the error message.
    fix : str
        What to do, ending the error message (the default suits a video file).
    """
    times = np.asarray(times_ms, dtype=np.float64)
    if times.ndim != 1 or times.size == 0:
        raise InputError(f"{source}: no frame timestamps found; check that it holds video frames")
    if not np.all(np.isfinite(times)):
        raise InputError(f"{source}: {np.count_nonzero(~np.isfinite(times))} frames have no timestamp; {fix}")
    steps = np.diff(times)
    if np.any(steps <= 0):
        bad = int(np.argmax(steps <= 0)) + 1
        raise InputError(
            f"{source}: frame timestamps are not increasing at frame {bad} "
            f"({times[bad - 1]:.3f} ms then {times[bad]:.3f} ms); {fix}"
        )
    return times


def video_timestamps(path: str | Path) -> np.ndarray:
    """Presentation times (ms) of every frame of a video file, without decoding pixels.

    Packet PTS times the stream time base, sorted into presentation order (B-frames are
    stored out of order). Frames without a PTS are an error, as are repeated stamps.

    Examples
    --------
    >>> video_timestamps("cam1.mp4")[:3]       # doctest: +SKIP
    array([ 0.    , 33.3667, 66.7333])
    """
    path = Path(path)
    with open_video(path) as container:
        stream = video_stream(container)
        pts = [packet.pts for packet in container.demux(stream) if packet.size > 0]
        time_base = stream.time_base
    if any(p is None for p in pts):
        raise InputError(f"{path}: {sum(p is None for p in pts)} frames have no timestamp; {NO_STAMPS}")
    times = np.sort(np.asarray(pts, dtype=np.float64)) * float(time_base) * 1000.0
    return check_timestamps(times, str(path))


#: What to do about a video whose frames have no timestamps.
NO_STAMPS = (
    "a raw H.264 or HEVC stream keeps none: remux it at the camera's frame rate (ffmpeg -r FPS -i IN -c copy "
    "OUT.mkv; without -r FFmpeg takes 25 fps), or remux it and give its frames' times with --timestamps"
)


def open_video(path: Path) -> av.container.InputContainer:
    """Open a video file for reading, or raise a one-line error naming the file: a folder,
    no such file, no permission to read it, not a video."""
    if path.is_dir():
        raise InputError(f"{path}: is a folder, not a video file; give the video's path")
    if not path.is_file():
        raise InputError(f"{path}: no such file; check the path")
    if not os.access(path, os.R_OK):
        raise InputError(f"{path}: cannot be read (permission denied); check its permissions")
    try:
        container = av.open(str(path))
    except av.FFmpegError as error:
        if error.errno == errno.EACCES:
            raise InputError(f"{path}: cannot be read (permission denied); check its permissions") from None
        raise InputError(
            f"{path}: not a video file FFmpeg can open ({error.strerror}); if it is one, it may be cut short "
            "(an MP4 keeps its index at the end): copy the whole file again"
        ) from None
    if not container.streams.video:
        container.close()
        raise InputError(f"{path}: has no video stream; give a video file")
    return container


def video_stream(container: av.container.InputContainer) -> av.video.stream.VideoStream:
    """The video stream flashsync reads, the one a player shows: FFmpeg's best (not a cover
    picture or a thumbnail track beside the video; the one with more frames where there
    are two). Every reader of a video takes this one."""
    return container.streams.best("video") or container.streams.video[0]


def shortest_step_ms(times_ms: np.ndarray) -> float:
    """The frame period where the camera ran fastest, ms: the median of the steps within
    10 % of their 10th percentile (a phone whose frame rate drops in dim light reads its
    rows as fast as before; a dropped frame lengthens a step and does not count); 0 for
    fewer than two frames."""
    steps = np.diff(np.asarray(times_ms, dtype=np.float64))
    if steps.size == 0:
        return 0.0
    return float(np.median(steps[steps <= 1.1 * np.percentile(steps, 10)]))


def median_step_ms(times_ms: np.ndarray) -> float:
    """The median interval between consecutive frame times, ms: the nominal frame period
    (0 for fewer than two frames)."""
    times = np.asarray(times_ms, dtype=np.float64)
    return float(np.median(np.diff(times))) if times.size > 1 else 0.0


def rtp_timestamps(stamps: np.ndarray, clock_hz: int = RTP_CLOCK_HZ) -> np.ndarray:
    """Unwrap 32-bit RTP timestamps into ms since the first frame.

    RTP video stamps count a 90 kHz clock modulo 2**32 (a wrap every 13.25 h). Each
    step is taken modulo 2**32 as a signed number, so a wrap between two frames costs
    nothing and a step backwards stays negative (and is caught by :func:`check_timestamps`).

    Parameters
    ----------
    stamps : integer array of shape (n_frames,)
        RTP timestamps, 0 <= stamp < 2**32.
    """
    stamps = np.asarray(stamps, dtype=np.int64)
    steps = (np.diff(stamps) + _RTP_WRAP // 2) % _RTP_WRAP - _RTP_WRAP // 2
    ticks = np.concatenate([[0], np.cumsum(steps)])
    return ticks * (1000.0 / clock_hz)
