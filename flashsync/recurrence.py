"""A flash happens once: bands that recur at the same rows are not flashes.

A photographer's flash lights the rows of one exposure window, once; the next flash comes
seconds later, at other rows. What else brightens a band of rows recurs there within a few
frames:

- codec echoes: an H.264 frame predicted from a flashed frame (a B-frame next to it, the
  P-frames after it) keeps part of the band for one or more frames;
- flicker the model left over, or one that is not mains: its pattern returns to the same
  rows every few frames (every third at 30 fps under 50 Hz mains);
- a slow player whose edge reads as a band in consecutive frames.

Before a flash, a codec's B-frames shown ahead of the frame it lit are predicted from that
frame in part and keep part of its band (:meth:`Stripe.foreruns`).

:class:`RecurrenceFilter` holds each candidate band for ``frames`` frames and drops it
where a band of the same sign came up to ``echo_frames`` frames before it at rows that hold
its rows, with at least ``ECHO_FRACTION`` of its strength (it is an echo, often only the
middle of the band), unless that band foreruns it, or comes up to ``frames`` frames after
it at the same rows with at least ``REPEAT_FRACTION`` (it repeats), or up to
``echo_frames`` after it with as much, and this one foreruns it. A flash keeps its weaker
echoes and the B-frames before it from dropping it; another flash a few frames later at
overlapping rows does not end where it ends.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

#: An earlier band at least this fraction as strong makes a band its echo.
ECHO_FRACTION = 0.5
#: A later band at least this fraction as strong makes a band a repeating pattern.
REPEAT_FRACTION = 0.7
#: Fraction of an echo's rows that lie among the rows of the band it echoes.
ECHO_OVERLAP = 0.5
#: Two bands are at the same rows when both their ends are within this fraction of the
#: shorter one's height of each other (and within :data:`MIN_TOLERANCE_ROWS`).
EDGE_TOLERANCE = 0.1
MIN_TOLERANCE_ROWS = 4


@dataclass(frozen=True)
class Stripe:
    """A band as the filter sees it: rows ``[start, stop)`` of one frame that changed by
    ``level`` (relative, signed); ``cut_start`` / ``cut_stop``: it runs into the first / last
    lit row of the frame, so that end is the frame's, not the band's."""

    frame: int
    start: int
    stop: int
    level: float
    cut_start: bool = False
    cut_stop: bool = False

    def within(self, other: Stripe) -> bool:
        """Same sign and at least :data:`ECHO_OVERLAP` of its rows among ``other``'s: where
        an echo of ``other`` would be (often only its middle, moved a few rows where the
        codec predicted it along a rolling flicker)."""
        shared = min(self.stop, other.stop) - max(self.start, other.start)
        return self.level * other.level > 0 and shared >= ECHO_OVERLAP * (self.stop - self.start)

    def same_rows(self, other: Stripe) -> bool:
        """Same sign, and both ends within :func:`tolerance` rows of ``other``'s: where a
        repeat of it would be (another flash that overlaps it does not end where it ends)."""
        slack = tolerance(self, other)
        start = self._start_near(other, slack) or (self.cut_start and other.cut_start)
        stop = self._stop_near(other, slack) or (self.cut_stop and other.cut_stop)
        return self.level * other.level > 0 and start and stop and not (self.cut_start and self.cut_stop)

    def foreruns(self, later: Stripe) -> bool:
        """A part of ``later``'s band shown before it: its rows mostly among ``later``'s,
        and fainter, or inside them and not the same rows. A B-frame shown before the frame a
        flash lit is predicted from it in part and keeps part of its band (up to three such
        frames, each stronger than the last: rig 47's cam1, x264 veryfast at crf 30); the last
        may measure stronger than the flash, whose baseline they lifted, but on fewer rows."""
        slack = tolerance(self, later)
        inside = self.start >= later.start - slack and self.stop <= later.stop + slack
        fainter = abs(self.level) < abs(later.level)
        return self.within(later) and (fainter or (inside and not self.same_rows(later)))

    def _start_near(self, other: Stripe, slack: float) -> bool:
        """Both start at the same row, and it is a band's end in both, not the frame's."""
        return not (self.cut_start or other.cut_start) and abs(self.start - other.start) <= slack

    def _stop_near(self, other: Stripe, slack: float) -> bool:
        return not (self.cut_stop or other.cut_stop) and abs(self.stop - other.stop) <= slack


def tolerance(a: Stripe, b: Stripe) -> float:
    """Rows two bands' ends may differ by and still be at the same rows."""
    return max(MIN_TOLERANCE_ROWS, EDGE_TOLERANCE * min(a.stop - a.start, b.stop - b.start))


@dataclass
class Candidate:
    """A band waiting for its verdict: its segments' bands, its strength and what to emit."""

    bands: list[Stripe]
    strength: float
    payload: object
    checked: bool = True
    verdict: str | None = field(default=None)


class RecurrenceFilter:
    """Hold candidate bands ``frames`` frames and release those that do not recur.

    Parameters
    ----------
    frames : int
        Frames after a band searched for its repeat: a mains flicker pattern returns to the
        same rows after 3 frames (30, 59.94 and 60 fps under 50 Hz mains) or 5 (25 and 50 fps
        under 60 Hz), the P-frames of a codec with up to three B-frames between come every 4.
    echo_frames : int
        Frames before a band searched for the band it echoes (the codec's references reach
        back this far: the previous P-frame, with two B-frames between).

    Feed it every band a frame shows (:meth:`see`), candidates as they end (:meth:`hold`);
    :meth:`release` returns the payloads whose verdict is in, in order, counts the dropped
    ones in :attr:`dropped` and keeps the strengths of the last ones in :attr:`recent_dropped`.
    """

    def __init__(self, frames: int = 5, echo_frames: int = 3):
        self.frames = frames
        self.echo_frames = echo_frames
        self._seen: deque[Stripe] = deque()
        self._held: deque[Candidate] = deque()
        self.dropped = 0
        self.recent_dropped: deque[float] = deque(maxlen=25)

    def see(self, band: Stripe) -> None:
        """A band of some frame (frames in increasing order); old ones are forgotten."""
        self._seen.append(band)
        while self._seen and self._seen[0].frame < band.frame - 3 * self.frames:
            self._seen.popleft()

    def hold(self, bands: list[Stripe], strength: float, payload: object, checked: bool = True) -> None:
        """A candidate made of ``bands`` (its segments, already :meth:`see`-n); ``checked``
        False lets it through unexamined (a light switched on is a step, not a band)."""
        self._held.append(Candidate(bands, strength, payload, checked))

    def release(self, frame: int | None = None) -> list[object]:
        """Payloads of the held candidates whose last band is more than ``frames`` before
        ``frame`` (all with None), dropping the recurring ones; in the order held."""
        out = []
        while self._held and (frame is None or self._held[0].bands[-1].frame < frame - self.frames):
            candidate = self._held.popleft()
            if candidate.checked and self._recurs(candidate):
                self.dropped += 1
                self.recent_dropped.append(abs(candidate.strength))
            else:
                out.append(candidate.payload)
        return out

    def _recurs(self, candidate: Candidate) -> bool:
        strength = abs(candidate.strength)
        for other in self._seen:
            if other in candidate.bands:
                continue
            for band in candidate.bands:
                if band.frame - self.echo_frames <= other.frame < band.frame:
                    if abs(other.level) >= ECHO_FRACTION * strength and band.within(other) and not other.foreruns(band):
                        return True
                elif (
                    band.frame < other.frame <= band.frame + self.frames
                    and abs(other.level) >= REPEAT_FRACTION * strength
                ):
                    if other.same_rows(band) or (other.frame <= band.frame + self.echo_frames and band.foreruns(other)):
                        return True
        return False
