"""Typed records of what the detector finds: band edges (:class:`Events`) and the bands they
pair into (:class:`Bands`), with enums for their kinds and flags.

An *event* is one band the detector found in one camera's frames: a flash (``Band.PULSE``) or
a light switched on or off (``Band.ON`` / ``Band.OFF``, a step). Events are numbered per
camera in the order they end (``event``, the number every report and ``--anchor`` use). An
event has up to two *edges*: the leading edge, the first row in readout order that saw the
change (the synchronisation event; its row's exposure *ended* at the flash), and the trailing
edge, the first row after the band (its exposure *started* at the flash; pulses only). An
edge hidden in the vertical blanking or in dark rows is not reported and the event says so in
its flags. The events table file (:mod:`flashsync.io.events`) has one row per edge.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from enum import StrEnum

import numpy as np


class Edge(StrEnum):
    """Which edge of a band, in readout order."""

    LEADING = "leading"
    TRAILING = "trailing"


class Band(StrEnum):
    """What made a band: a flash (a pulse), or a light switched on or off (a step)."""

    PULSE = "pulse"
    ON = "on"
    OFF = "off"


class Flag(StrEnum):
    """Something to know about an event (both its edges carry the same flags)."""

    SPLIT = "split"  # the band continues in the next frame
    LEADING_HIDDEN = "leading_hidden"  # its leading edge fell into the blanking or dark rows
    TRAILING_HIDDEN = "trailing_hidden"  # its trailing edge did (or the video ended)
    SATURATED = "saturated"  # some of its rows clipped at white
    LONG_PULSE = "long_pulse"  # its pulse may outlast the exposure, its edges not fitted with it


@dataclass(frozen=True)
class Events:
    """Band edges, arrays of shape (n_edges,), in the order the detector found them.

    Attributes
    ----------
    camera : str array
        Camera name (video file stem).
    event : int array
        Event number within the camera; an event's edges share it.
    frame : int array
        0-based decoded frame holding the edge.
    t_frame_ms : float array
        That frame's time, ms (container stamp, or the frame clock once retimed).
    row : float array
        Stored-image row of the edge (top = 0), sub-row.
    edge : array of Edge
    band : array of Band
    rise_rows : float array
        Rows from 25 % to 75 % of the band's plateau at this edge (NaN where not measured).
    strength : float array
        Relative brightness change of the band (0.4 = 40 % brighter; negative: darker).
    quality : float array
        Plateau over the video's profile noise.
    flags : array of frozenset of Flag
    """

    camera: np.ndarray
    event: np.ndarray
    frame: np.ndarray
    t_frame_ms: np.ndarray
    row: np.ndarray
    edge: np.ndarray
    band: np.ndarray
    rise_rows: np.ndarray
    strength: np.ndarray
    quality: np.ndarray
    flags: np.ndarray

    @classmethod
    def from_columns(
        cls,
        camera: Sequence[str],
        event: Sequence[int],
        frame: Sequence[int],
        t_frame_ms: Sequence[float],
        row: Sequence[float],
        edge: Sequence[Edge],
        band: Sequence[Band],
        rise_rows: Sequence[float],
        strength: Sequence[float],
        quality: Sequence[float],
        flags: Sequence[frozenset[Flag]],
    ) -> Events:
        """Events from one sequence per field (each of length n_edges), cast to their types."""
        return cls(
            _objects(camera),
            np.asarray(event, dtype=np.int64),
            np.asarray(frame, dtype=np.int64),
            np.asarray(t_frame_ms, dtype=np.float64),
            np.asarray(row, dtype=np.float64),
            _objects(edge),
            _objects(band),
            np.asarray(rise_rows, dtype=np.float64),
            np.asarray(strength, dtype=np.float64),
            np.asarray(quality, dtype=np.float64),
            _objects(flags),
        )

    @classmethod
    def concat(cls, parts: Sequence[Events]) -> Events:
        """The edges of all ``parts``, one after the other."""
        if not parts:
            return cls.from_columns(*([()] * len(fields(cls))))
        return cls(*(np.concatenate([getattr(part, f.name) for part in parts]) for f in fields(cls)))

    def __len__(self) -> int:
        return len(self.event)

    def take(self, which: np.ndarray) -> Events:
        """The edges selected by a boolean mask or an index array, in that order."""
        return Events(*(getattr(self, f.name)[which] for f in fields(self)))

    def retimed(self, frame_times_ms: np.ndarray) -> Events:
        """These edges with their frames' times taken from ``frame_times_ms`` (ms, one per
        decoded frame)."""
        return replace(self, t_frame_ms=np.asarray(frame_times_ms, dtype=np.float64)[self.frame])

    def has_flag(self, flag: Flag) -> np.ndarray:
        """Boolean mask of the edges whose event carries ``flag``."""
        return np.array([flag in flags for flags in self.flags], dtype=bool)

    def bands(self) -> Bands:
        """Each event's edges side by side (the events of one camera)."""
        numbers = np.unique(self.event)
        leading = np.full(len(numbers), -1, dtype=np.int64)
        trailing = np.full(len(numbers), -1, dtype=np.int64)
        slot = np.searchsorted(numbers, self.event)
        is_leading = self.edge == Edge.LEADING
        leading[slot[is_leading]] = np.flatnonzero(is_leading)
        trailing[slot[~is_leading]] = np.flatnonzero(~is_leading)
        return Bands(numbers, leading, trailing)


@dataclass(frozen=True)
class Bands:
    """The edges of each event of one camera side by side, arrays of shape (n_events,), by
    ascending event number: where the band starts and where it ends.

    Attributes
    ----------
    event : int array
        Event number.
    leading, trailing : int arrays
        Index of the event's leading and trailing edge in the :class:`Events` they came
        from; -1 where that edge is hidden.
    """

    event: np.ndarray
    leading: np.ndarray
    trailing: np.ndarray

    def __len__(self) -> int:
        return len(self.event)

    @property
    def complete(self) -> np.ndarray:
        """Boolean mask of the bands with both edges visible."""
        return (self.leading >= 0) & (self.trailing >= 0)

    def take(self, which: np.ndarray) -> Bands:
        """The bands selected by a boolean mask or an index array."""
        return Bands(self.event[which], self.leading[which], self.trailing[which])

    def first_edges(self) -> np.ndarray:
        """Index of each band's leading edge, else its trailing one: an edge every band has
        (for what both edges of an event share: band, flags, strength)."""
        return np.where(self.leading >= 0, self.leading, self.trailing)


def _objects(values: Sequence) -> np.ndarray:
    """A 1-d object array holding ``values`` as they are."""
    array = np.empty(len(values), dtype=object)
    array[:] = list(values)
    return array
