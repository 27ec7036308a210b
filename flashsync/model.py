"""The time model: a global time (ms, reference clock) for every (camera, frame, row).

A camera's map onto the reference clock is affine in its container time ``t_f`` and
linear in the readout row ``q`` (``q = row``, or ``height - 1 - row`` for a camera that
reads bottom-up)::

    t_global_ms(f, row) = alpha * t_f + beta_ms + q * row_time_ms

``t_global_ms`` is the end-of-exposure instant of that row (docs/architecture.md, time convention).
This module knows no file format; :mod:`flashsync.io.model_file` reads and writes it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from flashsync.errors import InputError


@dataclass(frozen=True)
class HeldExposure:
    """An exposure a camera held while it recorded, as its flash bands tell (auto exposure).

    Attributes
    ----------
    first_frame, last_frame : int
        Decoded frames of the first and last band that show it.
    exposure_ms, exposure_std_ms : float
        The exposure and its standard deviation, ms.
    n_bands : int
        Bands that show it.
    holds_frames : bool
        Its bands are two or more and of one length: the frames from its first to its last
        held it. Otherwise it only tells what the frames near it may hold (one band is a
        change, or a band the others' lengths do not fit; see :meth:`CameraClock.exposure_at`).
    """

    first_frame: int
    last_frame: int
    exposure_ms: float
    exposure_std_ms: float
    n_bands: int
    holds_frames: bool


@dataclass
class CameraClock:
    """One camera's frame timestamps and its map onto the reference clock.

    Attributes
    ----------
    name : str
        Camera name (the video file stem).
    frame_times_ms : ndarray of shape (n_frames,)
        Container timestamps of the decoded frames, presentation order, ms.
    height, width : int
        Stored image size, px.
    alpha : float
        Clock rate relative to the reference (1 + drift).
    beta_ms : float
        Shift, ms (absorbs the hidden rows before the first visible row).
    row_time_ms : float
        Time per row, ms (reference clock).
    flipped : bool
        True when the sensor reads bottom-up in stored rows (camera upside down).
    covariance : ndarray of shape (3, 3)
        Covariance of (alpha, beta_ms, row_time_ms) from the solve; zeros if unknown.
    exposure_ms : float or None
        Exposure time, ms, where known.
    exposure_std_ms : float or None
        Its standard deviation, ms, where the model states one.
    video : str
        The video file the camera came from.
    drift_knots_ms, drift_warp_ms : ndarrays of shape (k + 2,), (k,)
        A clock whose rate changes slowly: knots in camera time (ms, first and last at the
        ends of the recording) and the piecewise-linear correction (ms) at the k interior
        knots, added to the affine map; empty for an affine clock. ``covariance`` is then
        (3 + k, 3 + k), the warp values last.
    frame_std_ms : ndarray of shape (n_frames,)
        Standard deviation of each frame time beyond the map's (the frame clock's: stamps
        kept as they are, a clock's wander, segments of a clock that changed rate; and, of a
        camera other than the reference, the reference's errors then that every camera
        shares, the global clock's own, as :func:`~flashsync.pipeline.synchronize` makes
        it), ms; zeros where the frame times are exact up to the map (the default).
    display_rotation_deg : int
        Degrees counterclockwise a player turns the stored frames for showing (-90, 0, 90 or
        180: the display matrix of a phone held upright); rows are always the stored frame's.
    exposure_spans : tuple of HeldExposure
        Where the exposure changes while the camera records, the exposures its bands show, in
        frame order (:attr:`exposure_ms` is the one the solve took); empty for one exposure
        throughout. :meth:`exposure_at` gives each frame's.
    """

    name: str
    frame_times_ms: np.ndarray
    height: int
    width: int
    alpha: float = 1.0
    beta_ms: float = 0.0
    row_time_ms: float = 0.0
    flipped: bool = False
    covariance: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    exposure_ms: float | None = None
    video: str = ""
    drift_knots_ms: np.ndarray = field(default_factory=lambda: np.zeros(0))
    drift_warp_ms: np.ndarray = field(default_factory=lambda: np.zeros(0))
    frame_std_ms: np.ndarray | None = None
    display_rotation_deg: int = 0
    exposure_std_ms: float | None = None
    exposure_spans: tuple[HeldExposure, ...] = ()

    def __post_init__(self):
        if self.frame_std_ms is None:
            self.frame_std_ms = np.zeros(len(self.frame_times_ms))

    @property
    def n_frames(self) -> int:
        return len(self.frame_times_ms)

    def readout_row(self, row: np.ndarray) -> np.ndarray:
        """Readout index (0 = first row read) of stored-image rows."""
        return readout_rows(np.asarray(row, dtype=np.float64), self.height, self.flipped)

    @property
    def sideways(self) -> bool:
        """A player shows the stored frames turned a quarter either way (width and height
        swap places)."""
        return abs(self.display_rotation_deg) == 90

    def stored_row(self, x_shown: np.ndarray, y_shown: np.ndarray) -> np.ndarray:
        """Stored-image row (px) of points given in the picture a player shows: the stored
        frame turned :attr:`display_rotation_deg` counterclockwise (as OpenCV reads it by
        default); pixel-centre coordinates, arrays of one shape (``x_shown`` unused at 0 and
        180 degrees)."""
        x, y = np.asarray(x_shown, dtype=np.float64), np.asarray(y_shown, dtype=np.float64)
        last = self.height - 1.0
        return {0: y, 90: x, 180: last - y, -90: last - x}[self.display_rotation_deg]

    def exposure_at(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The exposure of each decoded ``frame`` and its standard deviation, ms (shape of
        ``frame``; NaN where the model states none).

        Without :attr:`exposure_spans`, :attr:`exposure_ms` throughout. With them, a frame
        within a span that :attr:`~HeldExposure.holds_frames` takes its exposure; any other
        takes the middle of the exposures that may hold it (a span that reaches over it, the
        nearest span on each side and the nearest of two bands or more on each side), its
        standard deviation covering them all (half their range, and the largest of theirs):
        a change came somewhere between two bands, and one band may be a change or not.
        Before the first band and after the last, the nearest span's, its standard deviation
        covering half the range of all of them: a camera on auto exposure may change again
        where no band shows it."""
        frame = np.asarray(frame, dtype=np.int64)
        if not self.exposure_spans:
            ms = np.nan if self.exposure_ms is None else self.exposure_ms
            std = np.nan if self.exposure_std_ms is None else self.exposure_std_ms
            return np.full(frame.shape, ms, dtype=np.float64), np.full(frame.shape, std, dtype=np.float64)
        first, last, ms, std, bands, holds = (
            np.array([getattr(span, key) for span in self.exposure_spans])
            for key in ("first_frame", "last_frame", "exposure_ms", "exposure_std_ms", "n_bands", "holds_frames")
        )
        f = frame.reshape(-1, 1)
        over = (first <= f) & (f <= last)
        candidates = over.copy()
        order = np.arange(len(first))  # spans in frame order: the nearest before ranks last, after first
        for rank, reached in ((order, last < f), (-order, first > f)):
            for among in (reached, reached & (bands >= 2)):
                nearest = np.where(among, rank, -len(order)).argmax(axis=1)
                candidates[np.arange(len(f)), nearest] |= among.any(axis=1)
        inside = over & holds
        candidates = np.where(inside.any(axis=1, keepdims=True), inside, candidates)
        low = np.where(candidates, ms, np.inf).min(axis=1)
        high = np.where(candidates, ms, -np.inf).max(axis=1)
        spread = np.where(candidates, std, 0.0).max(axis=1)
        beyond = (frame.ravel() < first[0]) | (frame.ravel() > last[-1])
        half_range = np.where(beyond, 0.5 * (ms.max() - ms.min()), 0.5 * (high - low))
        return (0.5 * (low + high)).reshape(frame.shape), np.hypot(half_range, spread).reshape(frame.shape)

    def t_global_ms(self, frame: np.ndarray, row: np.ndarray) -> np.ndarray:
        """Global time (ms) of the end of exposure of ``row`` in ``frame``.

        Parameters
        ----------
        frame : int array
            0-based decoded frame indices, ``0 <= frame < n_frames``.
        row : float array, broadcastable with ``frame``
            Stored-image rows (top = 0), sub-row precision allowed.
        """
        t_frame = self.frame_times_ms[np.asarray(frame, dtype=np.int64)]
        return self.frame_start_ms(t_frame) + self.readout_row(row) * self.row_time_ms

    def frame_start_ms(self, t_frame_ms: np.ndarray) -> np.ndarray:
        """Global time (ms) of readout row 0 of frames with container times ``t_frame_ms``."""
        t = np.asarray(t_frame_ms, dtype=np.float64)
        start = self.alpha * t + self.beta_ms
        if self.drift_warp_ms.size:
            start = start + hat_basis(self.drift_knots_ms, t) @ self.drift_warp_ms
        return start

    def t_global_std_ms(self, frame: np.ndarray, row: np.ndarray) -> np.ndarray:
        """Standard deviation (ms) of :meth:`t_global_ms`: the solve's covariance and the
        frame time's own (:attr:`frame_std_ms`, scaled by ``alpha``), independent."""
        frame = np.asarray(frame, dtype=np.int64)
        t_frame = self.frame_times_ms[frame]
        q = self.readout_row(row)
        t_frame, q = np.broadcast_arrays(t_frame, q)
        gradient = np.concatenate(
            [np.stack([t_frame, np.ones_like(t_frame), q], axis=-1), hat_basis(self.drift_knots_ms, t_frame)], axis=-1
        )
        variance = np.einsum("...i,ij,...j->...", gradient, self.covariance, gradient)
        variance = variance + (self.alpha * np.broadcast_to(self.frame_std_ms[frame], variance.shape)) ** 2
        return np.sqrt(np.maximum(variance, 0.0))

    def locate(self, t_global_ms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Inverse of :meth:`t_global_ms`: the frame and stored row imaged at a global time.

        Returns
        -------
        frame : int array
            Index of the last frame whose first row ends its exposure at or before the
            instant; -1 before the first frame.
        row : float array
            Stored-image row (sub-row); NaN where no visible row of that frame ends its
            exposure at the instant (vertical blanking, a dropped frame, outside the video).
        """
        t = np.asarray(t_global_ms, dtype=np.float64)
        starts = self.frame_start_ms(self.frame_times_ms)
        frame = np.searchsorted(starts, t, side="right") - 1
        q = (t - starts[np.clip(frame, 0, None)]) / self.row_time_ms
        visible = (frame >= 0) & (q <= self.height - 1 + 1e-6)
        q = np.where(visible, q, np.nan)
        return frame, readout_rows(q, self.height, self.flipped)


def readout_rows(rows: np.ndarray, height: int, flipped: bool) -> np.ndarray:
    """Readout index (0 = first row read) of stored-image rows (top = 0) of a camera that reads
    bottom-up when ``flipped``; the same map takes readout rows back to stored rows."""
    return height - 1 - rows if flipped else rows


def hat_basis(knots_ms: np.ndarray, t_ms: np.ndarray) -> np.ndarray:
    """Piecewise-linear hat functions of the interior ``knots_ms`` (shape (k + 2,)) at
    ``t_ms``: shape ``t_ms.shape + (k,)``; zero at the end knots, and beyond them the outermost
    segments' lines continued: a clock whose rate changes keeps the rate it had at its first
    and last events before and after them, not its mean rate."""
    t = np.asarray(t_ms, dtype=np.float64)
    knots = np.asarray(knots_ms, dtype=np.float64)
    interior = len(knots) - 2
    if interior <= 0:
        return np.zeros(t.shape + (0,))
    hats = np.stack([np.interp(t, knots, np.eye(interior + 2)[j + 1]) for j in range(interior)], axis=-1)
    hats[..., 0] += np.minimum(t - knots[0], 0.0) / (knots[1] - knots[0])
    hats[..., -1] += np.minimum(knots[-1] - t, 0.0) / (knots[-1] - knots[-2])
    return hats


#: The columns of :attr:`SyncModel.events`, one row per sync event matched into a flash: the
#: flash's number, the camera, the detector's event number, the frame and stored row of its
#: sync edge (the leading edge, or the trailing one where that is hidden), the frame's time
#: (ms), the flash's global time (ms), the edge's residual in the solve (ms, a trailing edge's
#: less the camera's exposure) and whether the robust solve kept it.
MATCHED_EVENT_COLUMNS = {
    "flash": "int64",
    "camera": "str",
    "event": "int64",
    "frame": "int64",
    "row": "float64",
    "t_frame_ms": "float64",
    "t_global_ms": "float64",
    "residual_ms": "float64",
    "inlier": "bool",
}


@dataclass
class SyncModel:
    """Every camera's clock on the reference clock, and the events it was fitted to.

    Attributes
    ----------
    reference : str
        Name of the reference camera (alpha = 1, beta = 0).
    cameras : dict[str, CameraClock]
        In the order the videos were given.
    events : DataFrame
        Matched events, columns :data:`MATCHED_EVENT_COLUMNS`.
    source : str
        The model file it was read from, named by errors about the model ('' when made in memory).
    """

    reference: str
    cameras: dict[str, CameraClock]
    events: pd.DataFrame = field(default_factory=pd.DataFrame)
    source: str = field(default="", compare=False)

    def named(self, message: str) -> str:
        """``message`` after the model file's name, where it was read from one."""
        return f"{self.source}: {message}" if self.source else message

    def camera(self, name: str) -> CameraClock:
        """The camera called ``name``, or an error listing the known ones."""
        try:
            return self.cameras[name]
        except KeyError:
            raise InputError(
                f"camera {name!r} is not in the model (it has {', '.join(self.cameras)}); "
                "sync its video too or fix the camera name"
            ) from None
