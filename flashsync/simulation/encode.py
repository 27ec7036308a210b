"""Writing simulated frames as H.264 video with chosen container stamps, atomically, and a
rendered video again in another camera's codec, pixel format and container."""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence
from fractions import Fraction
from pathlib import Path

import av
import numpy as np

from flashsync.atomic import atomic_output
from flashsync.errors import FlashsyncError
from flashsync.simulation.scenario import CameraSpec

MP4_TIME_BASE = Fraction(1, 90000)
MKV_TIME_BASE = Fraction(1, 1000)
_FORMATS = {".mp4": "mp4", ".mkv": "matroska"}


def stamp_clock_ms(camera: CameraSpec, t_true_ms: np.ndarray) -> np.ndarray:
    """Camera times as the muxer stamps them: the true time, except that after each of
    ``camera.stamp_rate_changes`` ``(sensor frame, factor)`` the stamps advance ``factor``
    times as fast (cumulative), from that frame's true time on; ms, shape of `t_true_ms`."""
    t = np.asarray(t_true_ms, dtype=float)
    stamp, rate = t.copy(), 1.0
    for frame, factor in sorted(camera.stamp_rate_changes):
        since = np.maximum(t - (camera.start_ms + frame * camera.frame_period_ms), 0.0)
        stamp += rate * (factor - 1.0) * since
        rate *= factor
    return stamp


def container_stamps(
    camera: CameraSpec, t_true_ms: np.ndarray, rng: np.random.Generator
) -> tuple[np.ndarray, Fraction]:
    """Container timestamps a camera reports for its frames.

    The stamp is the true camera time (through `stamp_clock_ms`, which changes its rate
    where the camera has ``stamp_rate_changes``) plus Gaussian jitter
    (``camera.jitter_ms``), rounded to ``camera.quantize_ms`` if set, then to the
    container's time base (1 ms for MKV, 1/90 ms for MP4). Stamps are kept strictly
    increasing and non-negative.

    Parameters
    ----------
    camera : CameraSpec
    t_true_ms : ndarray, shape (F,)
        True camera times of the written frames, ms, increasing.
    rng : numpy.random.Generator
        Source of the jitter.

    Returns
    -------
    pts : ndarray of int64, shape (F,)
        Stamps in units of `time_base`.
    time_base : fractions.Fraction
        Seconds per unit.
    """
    time_base = MKV_TIME_BASE if camera.container == "mkv" else MP4_TIME_BASE
    stamp = stamp_clock_ms(camera, t_true_ms) + camera.jitter_ms * rng.standard_normal(len(t_true_ms))
    if camera.quantize_ms:
        stamp = np.round(stamp / camera.quantize_ms) * camera.quantize_ms
    pts = np.round(stamp / 1000.0 / float(time_base)).astype(np.int64)
    pts = np.maximum.accumulate(np.maximum(pts, 0) - np.arange(len(pts))) + np.arange(len(pts))
    return pts, time_base


def x264_options(
    crf: int = 23,
    keyint: int | None = None,
    bframes: int | None = None,
    preset: str | None = None,
    open_gop: bool = False,
) -> dict[str, str]:
    """libx264 options for PyAV's ``stream.options``: x264's defaults where None; x264's
    code kept at AVX2 (:data:`X264_ASM`) on a CPU that has AVX-512."""
    options = {"crf": str(crf)}
    if preset is not None:
        options["preset"] = preset
    given = (
        ("keyint", keyint),
        ("bframes", bframes),
        ("open_gop", 1 if open_gop else None),
        ("asm", X264_ASM if _has_avx512() else None),
    )
    params = [f"{name}={value}" for name, value in given if value is not None]
    if params:
        options["x264-params"] = ":".join(params)
    return options


#: x264's code on a CPU with AVX-512: its AVX-512 code encoded the same frames to a
#: different file on four renders of five in one process; at AVX2 every render of a
#: scenario is the same file (x264's plain C gives yet another file: its code paths are not
#: bit-exact with each other; a CPU with AVX2 alone was not at hand to compare).
X264_ASM = "AVX2"


@functools.cache
def _has_avx512() -> bool:
    """The CPU has AVX-512 (Linux's /proc/cpuinfo says so; False where it cannot be read)."""
    try:
        return "avx512f" in Path("/proc/cpuinfo").read_text().split()
    except OSError:
        return False


def write_video(
    path: str | Path,
    frames: Iterable[np.ndarray],
    pts: Sequence[int],
    time_base: Fraction,
    crf: int = 23,
    fps: float | None = None,
    keyint: int | None = None,
    bframes: int | None = None,
    preset: str | None = None,
    open_gop: bool = False,
) -> int:
    """Encode frames with libx264 (yuv420p) and explicit presentation stamps.

    Parameters
    ----------
    path : str or Path
        Output file, ``.mp4`` or ``.mkv``; written through a temporary file and renamed.
    frames : iterable of ndarray, uint8, shape (H, W) or (H, W, 3)
        Grey or BGR frames; H and W even.
    pts : sequence of int
        Presentation stamp of each frame in units of `time_base`, increasing.
    time_base : fractions.Fraction
        Seconds per stamp unit (1/90000 for MP4, 1/1000 for MKV, which stores 1 ms).
    crf : int
        x264 constant rate factor.
    fps : float, optional
        Nominal frame rate written as metadata.
    keyint, bframes : int, optional
        Longest GOP and most consecutive B-frames; x264's defaults (250, 3) if None.
    preset : str, optional
        x264 speed preset; ``medium`` if None.
    open_gop : bool
        x264's open GOPs (B-frames before a key frame in presentation order reference the
        GOP before it).

    Returns
    -------
    int
        Number of frames written.

    Examples
    --------
    >>> frames = [np.zeros((48, 64), np.uint8)] * 3  # doctest: +SKIP
    >>> write_video("a.mkv", frames, [0, 40, 81], Fraction(1, 1000))  # doctest: +SKIP
    """
    path = Path(path)
    fmt = _FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise FlashsyncError(f"{path}: cannot write '{path.suffix}' video; use .mp4 or .mkv")
    pts = [int(p) for p in pts]
    count = 0
    with atomic_output(path) as tmp:
        with av.open(str(tmp), "w", format=fmt) as container:
            stream = None
            for image, stamp in zip(frames, pts, strict=True):
                if stream is None:
                    rate = Fraction(fps).limit_denominator(1001) if fps else None
                    stream = container.add_stream("libx264", rate=rate)
                    stream.height, stream.width = image.shape[:2]
                    stream.pix_fmt = "yuv420p"
                    stream.time_base = time_base
                    stream.codec_context.time_base = time_base
                    stream.options = x264_options(crf, keyint, bframes, preset, open_gop)
                frame = av.VideoFrame.from_ndarray(image, format="gray" if image.ndim == 2 else "bgr24")
                frame.pts = stamp
                frame.time_base = time_base
                container.mux(stream.encode(frame))
                count += 1
            if stream is None:
                raise FlashsyncError(f"{path}: no frames to write")
            container.mux(stream.encode())
    return count


def reencode(
    source: str | Path,
    target: str | Path,
    codec: str,
    pixel_format: str,
    options: dict[str, str] | None = None,
    rate: int = 25,
    drop: Iterable[int] = (),
    rotation_deg: int = 0,
    start_s: float | None = None,
) -> int:
    """A rendered video written again as another camera would write it: any FFmpeg encoder
    ``codec`` (``libx265``, ``prores``, ``mjpeg``, ...) and ``pixel_format`` (10-bit,
    4:2:2, RGB, ...), the container of ``target``'s suffix (``.mov``, ``.avi``, ``.webm``,
    ...), written through a temporary file.

    Frame k keeps its time (or its time since the first frame after ``start_s``), stamped
    in units of 1 / ``rate`` s (``source`` runs at ``rate`` fps); the frames in ``drop`` are
    left out (an AVI lists their slots empty); a display matrix turns the frames
    ``rotation_deg`` counterclockwise for showing (as a phone held upright writes them).
    Returns the frames written.
    """
    target, drop = Path(target), set(drop)
    written = 0
    with atomic_output(target) as tmp, av.open(str(source)) as video, av.open(str(tmp), "w") as out:
        decoded = video.streams.video[0]
        stream = out.add_stream(codec, rate=rate, options=options or {})
        stream.width, stream.height, stream.pix_fmt = decoded.width, decoded.height, pixel_format
        stream.time_base = time_base = Fraction(1, rate)  # the muxer may change the stream's
        if rotation_deg:
            stream.set_display_rotation(rotation_deg)
        shift = None
        for index, frame in enumerate(video.decode(decoded)):
            if shift is None:
                shift = 0.0 if start_s is None else start_s - frame.time
            if index in drop:
                continue
            image = frame.reformat(format=pixel_format)
            image.pts, image.time_base = round((frame.time + shift) * rate), time_base
            out.mux(stream.encode(image))
            written += 1
        out.mux(stream.encode())
    return written
