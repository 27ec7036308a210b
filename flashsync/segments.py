"""A long video as segments that start at key frames, for decoding in parts on a cluster.

A segment is the frames whose stamps lie in ``[start_pts, stop_pts)`` (stream time-base
units), where both ends are key frames: decoded from its first key frame, a segment gives the
same pixels, stamps and picture types as the whole video decoded in one go (a key frame
refreshes all the decoder keeps; frames an open GOP puts before the key frame in
presentation order are decoded by the segment before, which reads on past its end until
its stop stamp). :func:`read_segment` decodes one; :mod:`flashsync.cluster` decodes them
in parallel and detects them in order.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flashsync.errors import InputError
from flashsync.profiles import RECOPY, VideoInfo, cut_short, read_profiles, video_info
from flashsync.timestamps import open_video, video_stream

#: Default length of a segment, ms: a minute is long against the cost of starting one
#: (seeking, the decoder's first frames, a task on the cluster: 0.04-0.4 s measured by
#: ``benchmarks/bench_cluster.py``, a few per cent of decoding a minute of 1080p), and an
#: 8-minute video still gives two workers eight segments to share.
SEGMENT_MS = 60_000.0


@dataclass(frozen=True)
class Segment:
    """Frames ``[start_pts, stop_pts)`` of a video (None: from its start, to its end), stream
    time-base units."""

    path: Path
    start_pts: int | None
    stop_pts: int | None


def plan_segments(path: str | Path, segment_ms: float = SEGMENT_MS) -> tuple[VideoInfo, list[Segment]]:
    """The video's :class:`VideoInfo` and its segments of at least ``segment_ms`` (the last one
    may be shorter), each starting at a key frame.

    The key frames come from the packets, without decoding (one read of the file). A video
    whose key frames are further apart than ``segment_ms`` has longer segments; one without
    any has one segment.
    """
    path = Path(path)
    container = open_video(path)
    with container:
        info = video_info(container, path)
        stream = video_stream(container)
        keys = sorted(p.pts for p in container.demux(stream) if p.is_keyframe and p.pts is not None)
        step = float(stream.time_base or 0) * 1000.0  # ms per time-base unit
    bounds = []
    for pts in keys[1:] if step > 0 else []:
        if (pts - (bounds[-1] if bounds else keys[0])) * step >= segment_ms:
            bounds.append(pts)
    ends = [None, *bounds, None]
    return info, [Segment(path, start, stop) for start, stop in zip(ends[:-1], ends[1:])]


def read_segment(segment: Segment) -> list[tuple[float, np.ndarray, str, int]]:
    """``(t_frame_ms, profile, picture, rotation_deg)`` of every frame of the segment,
    presentation order (:func:`~flashsync.profiles.read_profiles`)."""
    _, profiles = read_profiles(segment.path, segment.start_pts, segment.stop_pts)
    return list(profiles)


def check_complete(path: str | Path, decoded: int, last_times_ms: list[float]) -> None:
    """Raise a one-line error where a video decoded in segments turns out cut short:
    ``decoded`` frames in all, the last one or two at ``last_times_ms``."""
    path = Path(path)
    container = open_video(path)
    with container:
        cut = cut_short(container, decoded, last_times_ms)
    if cut:
        raise InputError(f"{path}: {cut}; {RECOPY}")
