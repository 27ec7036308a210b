"""Flash events from row profiles: bands of rows that changed brightness, and their edges.

Each frame's row profile is compared with a baseline (per-row median of the last few quiet
profiles) as a relative change ``(p - b) / b``: illumination is multiplicative, so a flash
gives a flat plateau whatever the scene's texture. Rows over a noise-adaptive threshold form
bands; a band's leading edge (first affected row in readout order) is the row where the
change crosses half of the band's plateau, interpolated to a fraction of a row — the same
instant of the flash in every camera, whatever its gain or scene.

A band that reaches the last row continues in the next frame (one event, flagged
``split``); a band that starts at row 0 with nothing open before it had its leading edge in
the vertical blanking (flagged ``leading_hidden``, only its trailing edge is reported). A
change that fills whole frames for several frames is a light switching on or off (``on`` /
``off``); one without any edge (auto-exposure) only resets the baseline.

The detector is streaming: :class:`EventDetector` keeps a few profiles, not the video.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from flashsync.errors import FlashsyncError
from flashsync.profiles import DEFAULT_COLUMN_STEP, iter_profiles, probe_video
from flashsync.timestamps import check_timestamps

EVENT_COLUMNS = ["camera", "event", "frame", "t_frame_ms", "row", "edge", "band", "strength",
                 "quality", "flags"]


@dataclass(frozen=True)
class DetectorSettings:
    """Tuning of :class:`EventDetector`.

    Attributes
    ----------
    history : int
        Quiet profiles in the baseline median.
    k_sigma : float
        Threshold in units of the video's profile noise (robust sigma, relative change).
    min_change : float
        Smallest relative brightness change that can be an event (0.03 = 3 %).
    min_rows : int
        Shortest band, rows.
    step_frames : int
        Whole frames a change must fill to be a light switched on or off.
    flipped : bool
        The sensor reads bottom-up in stored rows (camera mounted upside down).
    """

    history: int = 4
    k_sigma: float = 8.0
    min_change: float = 0.03
    min_rows: int = 3
    step_frames: int = 2
    flipped: bool = False


@dataclass
class _Band:
    """A run of changed rows in one frame, in readout rows (None: edge outside the frame)."""

    leading: float | None
    trailing: float | None
    sign: int
    strength: float
    quality: float
    saturated: bool


@dataclass
class _OpenEvent:
    """A band that reached the last row and continues in the next frame."""

    frame: int
    t_frame_ms: float
    band: _Band
    full_frames: int = 0
    flags: set[str] = field(default_factory=set)


class EventDetector:
    """Streaming event detector for one camera; feed it profiles with :meth:`push`.

    Parameters
    ----------
    camera : str
        Camera name written into each event.
    height : int
        Rows per profile.
    settings : DetectorSettings
    """

    def __init__(self, camera: str, height: int, settings: DetectorSettings = DetectorSettings()):
        self.camera = camera
        self.height = height
        self.settings = settings
        self._history: deque[np.ndarray] = deque(maxlen=settings.history)
        self._noise: deque[float] = deque(maxlen=25)
        self._open: _OpenEvent | None = None
        self._global_frames = 0
        self._n_events = 0
        self.events: list[dict] = []

    def push(self, frame: int, t_frame_ms: float, profile: np.ndarray) -> None:
        """Process one frame's row profile (shape (height,), stored rows)."""
        profile = np.asarray(profile, dtype=np.float32)
        readout = profile[::-1] if self.settings.flipped else profile
        if not self._history:
            self._history.append(readout)
            return
        baseline = np.median(np.stack(self._history), axis=0)
        change = (readout - baseline) / np.maximum(baseline, 16.0)
        self._noise.append(1.4826 * float(np.median(np.abs(np.diff(change)))) / np.sqrt(2.0))
        sigma = max(float(np.median(self._noise)), 1e-4)
        threshold = max(self.settings.min_change, self.settings.k_sigma * sigma)
        bands = _find_bands(change, threshold, sigma, self.settings.min_rows, readout)
        self._consume(frame, t_frame_ms, bands, readout)

    def finish(self) -> pd.DataFrame:
        """Close a band still open at the end of the video; return all events (EVENT_COLUMNS)."""
        if self._open is not None:
            self._close_open(trailing=None, frame=None, t_frame_ms=None)
        return pd.DataFrame(self.events, columns=EVENT_COLUMNS)

    def _consume(self, frame: int, t_frame_ms: float, bands: list[_Band], readout: np.ndarray) -> None:
        continued = False
        for band in bands:
            whole_frame = band.leading is None and band.trailing is None
            if band.leading is None and self._open is not None and band.sign == self._open.band.sign:
                continued = True
                self._open.flags.add("split")
                if whole_frame:
                    self._open.full_frames += 1
                    if self._open.full_frames >= self.settings.step_frames:
                        self._emit_step(readout)
                else:
                    self._close_open(band.trailing, frame, t_frame_ms)
            elif whole_frame:
                self._global_frames += 1
                if self._global_frames >= self.settings.step_frames:
                    self._reset_baseline(readout)
                return
            elif band.trailing is None:
                self._open = _OpenEvent(frame, t_frame_ms, band)
                continued = True
            else:
                self._emit(frame, t_frame_ms, band, band.leading, frame, t_frame_ms, band.trailing,
                           "pulse", {"leading_hidden"} if band.leading is None else set())
        if self._open is not None and not continued:
            self._close_open(trailing=None, frame=None, t_frame_ms=None)
        self._global_frames = 0
        if not bands:
            self._history.append(readout)

    def _close_open(self, trailing: float | None, frame: int | None, t_frame_ms: float | None) -> None:
        opened = self._open
        flags = set(opened.flags)
        if trailing is None:
            flags.add("trailing_hidden")
        self._emit(opened.frame, opened.t_frame_ms, opened.band, opened.band.leading, frame,
                   t_frame_ms, trailing, "pulse", flags)
        self._open = None

    def _emit_step(self, readout: np.ndarray) -> None:
        opened = self._open
        kind = "on" if opened.band.sign > 0 else "off"
        self._emit(opened.frame, opened.t_frame_ms, opened.band, opened.band.leading, None, None,
                   None, kind, set(opened.flags) - {"split"})
        self._open = None
        self._reset_baseline(readout)

    def _reset_baseline(self, readout: np.ndarray) -> None:
        self._history.clear()
        self._history.append(readout)
        self._global_frames = 0

    def _emit(self, lead_frame: int, lead_t: float, band: _Band, leading: float | None,
              trail_frame: int | None, trail_t: float | None, trailing: float | None, kind: str,
              flags: set[str]) -> None:
        if band.saturated:
            flags.add("saturated")
        if leading is None:
            flags.add("leading_hidden")
        edges = [("leading", lead_frame, lead_t, leading), ("trailing", trail_frame, trail_t, trailing)]
        for edge, frame, t_frame_ms, row in edges:
            if row is None:
                continue
            stored = self.height - 1 - row if self.settings.flipped else row
            self.events.append({
                "camera": self.camera, "event": self._n_events, "frame": frame,
                "t_frame_ms": t_frame_ms, "row": stored, "edge": edge, "band": kind,
                "strength": band.strength, "quality": band.quality,
                "flags": "|".join(sorted(flags))})
        self._n_events += 1


def _find_bands(change: np.ndarray, threshold: float, sigma: float, min_rows: int,
                readout: np.ndarray) -> list[_Band]:
    """Runs of rows whose relative change exceeds ``threshold`` (either sign), with edges;
    a band's quality is its plateau over the noise ``sigma``."""
    bands = []
    for sign in (1, -1):
        signed = sign * change
        for start, stop in _runs(signed > threshold, gap=2):
            if stop - start < min_rows:
                continue
            plateau = float(np.median(signed[start:stop]))
            half = 0.5 * plateau
            bands.append(_Band(
                leading=_rising_crossing(signed, half, start),
                trailing=_falling_crossing(signed, half, stop - 1),
                sign=sign,
                strength=sign * plateau,
                quality=plateau / sigma,
                saturated=bool(np.max(readout[start:stop]) >= 250)))
    return sorted(bands, key=lambda band: -1.0 if band.leading is None else band.leading)


def _runs(mask: np.ndarray, gap: int) -> list[tuple[int, int]]:
    """``[start, stop)`` of True runs in ``mask``, merging runs separated by <= ``gap`` rows."""
    padded = np.concatenate([[False], mask, [False]])
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    runs = list(zip(edges[::2], edges[1::2]))
    merged: list[tuple[int, int]] = []
    for start, stop in runs:
        if merged and start - merged[-1][1] <= gap:
            merged[-1] = (merged[-1][0], stop)
        else:
            merged.append((start, stop))
    return merged


def _rising_crossing(values: np.ndarray, level: float, start: int) -> float | None:
    """Sub-row position where ``values`` first rises through ``level`` near ``start``;
    None when it is already above ``level`` at row 0 (the edge is outside the frame)."""
    i = start
    while i > 0 and values[i - 1] >= level:
        i -= 1
    while values[i] < level:
        i += 1
    if i == 0:
        return None
    return i - 1 + (level - values[i - 1]) / (values[i] - values[i - 1])


def _falling_crossing(values: np.ndarray, level: float, stop: int) -> float | None:
    """Sub-row position where ``values`` last falls through ``level`` near ``stop``;
    None when it is still above ``level`` at the last row."""
    last = len(values) - 1
    i = stop
    while i < last and values[i + 1] >= level:
        i += 1
    while values[i] < level:
        i -= 1
    if i == last:
        return None
    return i + (values[i] - level) / (values[i] - values[i + 1])


@dataclass
class CameraDetection:
    """One video's detection pass: its frame timestamps and its events."""

    camera: str
    video: Path
    width: int
    height: int
    frame_times_ms: np.ndarray
    events: pd.DataFrame
    flipped: bool = False


def detect_video(path: str | Path, flipped: bool = False,
                 settings: DetectorSettings | None = None,
                 column_step: int = DEFAULT_COLUMN_STEP,
                 progress: Callable[[int], None] | None = None) -> CameraDetection:
    """Decode a video once and detect its flash events.

    Parameters
    ----------
    path : path of a video file FFmpeg can open.
    flipped : the camera reads bottom-up in stored rows (mounted upside down).
    settings : detector tuning; ``flipped`` overrides its field.
    column_step : columns between median samples.
    progress : called with the number of frames decoded since the last call.

    Returns
    -------
    CameraDetection with ``events`` in EVENT_COLUMNS (rows are stored-image rows).
    """
    info = probe_video(path)
    settings = DetectorSettings(**{**(settings or DetectorSettings()).__dict__, "flipped": flipped})
    detector = EventDetector(info.camera, info.height, settings)
    times = []
    for frame, (t_ms, profile) in enumerate(iter_profiles(info.path, column_step)):
        times.append(t_ms)
        detector.push(frame, t_ms, profile)
        if progress is not None:
            progress(1)
    frame_times = check_timestamps(np.asarray(times), str(info.path))
    if len(frame_times) < 2:
        raise FlashsyncError(f"{info.path}: only {len(frame_times)} frame decoded; give a longer video")
    return CameraDetection(info.camera, info.path, info.width, info.height, frame_times,
                           detector.finish(), flipped)
