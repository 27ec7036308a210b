"""What the videos measured: each camera's frame stamps and the band edges matched across cameras.

A band (one detected pulse event with both edges visible and unsaturated) gives two edges:
the leading edge is the row whose exposure *ends* at the flash, the trailing edge the row
whose exposure *starts* there (DESIGN.md, time convention). Bands are paired across cameras
by their approximate time on each camera's own clock (stamp + row x frame step / height)
with :func:`flashsync.match.align_pair` and :func:`flashsync.match.group_flashes`, with a
tolerance of one frame period: loose enough for every effect of the catalogue (an
upside-down camera misplaces a band by less than a frame, a dropped frame or a clock drift
does not move a stamp). Nothing here depends on the model under test.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from flashsync.detect import CameraDetection
from flashsync.errors import FlashsyncError
from flashsync.match import align_pair, group_flashes

#: Fewest flashes two cameras must share for their pairing to count.
MIN_SHARED_BANDS = 3
#: Bands with an edge this close (rows) to the top or bottom of the image are left out: the
#: detector sees only part of the edge's ramp and plateau there.
EDGE_MARGIN_ROWS = 6


@dataclass(frozen=True)
class Camera:
    """One camera as measured.

    Attributes
    ----------
    name : str
        Camera name (video file stem).
    stamps_ms : ndarray of shape (n_frames,)
        Container stamps of the decoded frames, ms.
    height : int
        Stored image height, rows.
    flipped : bool
        Readout direction the detection was told (True: bottom-up).
    """

    name: str
    stamps_ms: np.ndarray
    height: int
    flipped: bool

    @property
    def median_step_ms(self) -> float:
        """The most common frame interval, ms: the nominal frame period."""
        return float(np.median(np.diff(self.stamps_ms)))


@dataclass(frozen=True)
class Edges:
    """Matched band edges, arrays of shape (n_edges,).

    Attributes
    ----------
    camera : int array
        Index into :attr:`Measurement.cameras`.
    flash : int array
        Flash number, 0..n_flashes-1; every flash is seen by at least two cameras.
    frame : int array
        Decoded frame index of the edge.
    row : float array
        Stored-image row of the edge (sub-row).
    trailing : bool array
        Trailing edge in the readout direction the detection was told.
    """

    camera: np.ndarray
    flash: np.ndarray
    frame: np.ndarray
    row: np.ndarray
    trailing: np.ndarray

    def __len__(self) -> int:
        return len(self.camera)


@dataclass(frozen=True)
class Measurement:
    """Everything the workflow compares the model with.

    Attributes
    ----------
    cameras : tuple of Camera
        Cameras tied to the reference by shared flashes, in input order.
    reference : int
        Index of the reference camera (its clock is the global clock).
    edges : Edges
    noise_ms : float
        Std of one edge's time, ms, from the scatter of band lengths in rows within each
        camera, whatever the clocks: bands with both edges in one frame are all as long
        (the exposure over the time per row), and so are bands split across two frames
        (shorter by the hidden rows); NaN without three bands of a kind. Errors common to
        both edges of a band do not show in its length, so this is a lower bound.
    warnings : tuple of str
        Cameras left out and why.
    """

    cameras: tuple[Camera, ...]
    reference: int
    edges: Edges
    noise_ms: float
    warnings: tuple[str, ...] = ()

    @property
    def n_flashes(self) -> int:
        return int(self.edges.flash.max()) + 1


def measure(detections: Sequence[CameraDetection], reference: str | None = None) -> Measurement:
    """Pair the bands of all cameras into flashes and collect their edges.

    Parameters
    ----------
    detections : one per camera, from :func:`flashsync.pipeline.detect_videos`.
    reference : camera whose clock is the global clock; default the first.

    Raises
    ------
    FlashsyncError
        Fewer than two cameras, an unknown reference, no camera sharing at least
        :data:`MIN_SHARED_BANDS` flashes with the reference, or no clean band shared.
    """
    names = [d.camera for d in detections]
    if len(names) < 2:
        raise FlashsyncError(
            f"diagnose needs videos of two or more cameras, got {len(names)}; give every camera's video"
        )
    reference = reference or names[0]
    if reference not in names:
        raise FlashsyncError(f"--reference {reference}: no such camera among {', '.join(names)}")
    pulses = {d.camera: _pulses(d) for d in detections}
    tolerance = max(float(np.median(np.diff(d.frame_times_ms))) for d in detections)
    alignments = {}
    for i, name_a in enumerate(names):
        for name_b in names[i + 1 :]:
            alignment = align_pair(
                pulses[name_a]["time_ms"].to_numpy(), pulses[name_b]["time_ms"].to_numpy(), tolerance
            )
            if alignment is not None and len(alignment.matches) >= MIN_SHARED_BANDS and not alignment.ambiguous:
                alignments[(name_a, name_b)] = alignment
    flash_of = group_flashes({name: len(pulses[name]) for name in names}, alignments)
    kept = [d for d in detections if d.camera in _tied_to(reference, flash_of)]
    if len(kept) < 2:
        raise FlashsyncError(
            f"no camera shares at least {MIN_SHARED_BANDS} flashes with {reference}; "
            "check that the videos overlap in time and saw the same flashes"
        )
    warnings = tuple(
        f"{d.video}: shares fewer than {MIN_SHARED_BANDS} flashes with the other cameras; left out"
        for d in detections
        if d not in kept
    )
    cameras = tuple(Camera(d.camera, np.asarray(d.frame_times_ms, dtype=np.float64), d.height, d.flipped) for d in kept)
    bands = [pulses[d.camera][pulses[d.camera]["clean"]] for d in kept]
    edges = _edges(bands, flash_of, cameras)
    if len(edges) == 0:
        raise FlashsyncError(
            "no flash band with both edges inside the image is seen by two cameras; "
            "record more flashes, away from the top and bottom of the image"
        )
    return Measurement(
        cameras, [c.name for c in cameras].index(reference), edges, _edge_noise_ms(cameras, bands), warnings
    )


def readout_rows(row: np.ndarray, height: int, flipped: bool) -> np.ndarray:
    """Readout index (0 = read first) of stored-image rows."""
    return height - 1 - row if flipped else row


def _pulses(detection: CameraDetection) -> pd.DataFrame:
    """The camera's pulse events, one row each: ``time_ms``, its approximate time on the
    camera's own clock (mean of its visible edges' stamp + readout row x frame step /
    height), ``frame_leading, row_leading, frame_trailing, row_trailing`` (NaN where hidden)
    and ``clean``: both edges visible and at least :data:`EDGE_MARGIN_ROWS` inside the image."""
    events = detection.events[detection.events["band"] == "pulse"]
    stamps = np.asarray(detection.frame_times_ms, dtype=np.float64)
    row_ms = float(np.median(np.diff(stamps))) / detection.height
    q = readout_rows(events["row"].to_numpy(dtype=np.float64), detection.height, detection.flipped)
    time_ms = pd.Series(stamps[events["frame"].to_numpy(dtype=np.int64)] + q * row_ms, index=events.index)
    pulses = events.pivot(index="event", columns="edge", values=["frame", "row"])
    pulses.columns = [f"{value}_{edge}" for value, edge in pulses.columns]
    pulses = pulses.reindex(columns=["frame_leading", "row_leading", "frame_trailing", "row_trailing"])
    inside = events["row"].between(EDGE_MARGIN_ROWS, detection.height - 1 - EDGE_MARGIN_ROWS)
    counts = inside.groupby(events["event"]).agg(["sum", "size"])
    pulses["clean"] = (counts["sum"] == 2) & (counts["size"] == 2)
    pulses["time_ms"] = time_ms.groupby(events["event"]).mean()
    return pulses.reset_index(drop=True)


def _tied_to(reference: str, flash_of: dict[tuple[str, int], int]) -> set[str]:
    """Cameras linked to the reference through chains of shared flashes."""
    seen_by: dict[int, set[str]] = {}
    for (camera, _), flash in flash_of.items():
        seen_by.setdefault(flash, set()).add(camera)
    tied, grew = {reference}, True
    while grew:
        grew = False
        for group in seen_by.values():
            if group & tied and not group <= tied:
                tied |= group
                grew = True
    return tied


def _edges(bands: list[pd.DataFrame], flash_of: dict[tuple[str, int], int], cameras: tuple[Camera, ...]) -> Edges:
    """Both edges of every clean band that belongs to a flash of two or more kept cameras."""
    rows = []
    for index, (camera, camera_bands) in enumerate(zip(cameras, bands)):
        for band, values in camera_bands.iterrows():
            flash = flash_of.get((camera.name, band))
            if flash is None:
                continue
            for trailing, edge in ((False, "leading"), (True, "trailing")):
                rows.append((index, flash, int(values[f"frame_{edge}"]), float(values[f"row_{edge}"]), trailing))
    table = pd.DataFrame(rows, columns=["camera", "flash", "frame", "row", "trailing"])
    cameras_seeing = table.groupby("flash")["camera"].transform("nunique")
    table = table[cameras_seeing >= 2]
    return Edges(
        table["camera"].to_numpy(),
        pd.factorize(table["flash"], sort=True)[0],
        table["frame"].to_numpy(),
        table["row"].to_numpy(dtype=np.float64),
        table["trailing"].to_numpy(dtype=bool),
    )


def _edge_noise_ms(cameras: tuple[Camera, ...], bands: list[pd.DataFrame]) -> float:
    """Std of one edge's time, ms, from the scatter of band lengths among the bands of one
    camera that span the same number of frames (a length holds two edges' errors). Every
    band counts, one whose edge a codec artefact moved too: the edge residuals this is
    compared with hold that edge as well."""
    deviations = []
    for camera, camera_bands in zip(cameras, bands):
        frames = camera_bands["frame_trailing"] - camera_bands["frame_leading"]
        for _, kind in camera_bands.groupby(frames):
            if len(kind) >= 3:
                rows = (kind["row_trailing"] - kind["row_leading"]).to_numpy()
                scale = camera.median_step_ms / camera.height * np.sqrt(len(rows) / (len(rows) - 1))
                deviations.append((rows - np.median(rows)) * scale)
    if not deviations:
        return float("nan")
    deviations = np.concatenate(deviations)
    return float(np.sqrt(np.mean(deviations**2) / 2.0))
