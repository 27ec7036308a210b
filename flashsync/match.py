"""Pair events across cameras from the pattern of their times, with no manual step: the one
matcher of the pipeline and of ``diagnose``.

Every camera's events get an approximate time on its own clock, ``t_frame + q * T_nominal``
(``T_nominal`` = frame period / height, a few per cent off: good to a few ms). For each pair
of cameras aligned (every pair in rigs of a few cameras, else a spanning structure with a few
partners per camera: :mod:`flashsync.partners`), the offsets between all their event times
vote for the shift (flashes fired by hand are irregular, so only the true shift lines many of
them up); each leading candidate is refined into an affine map (shift and drift) by
alternating one-to-one matching and fitting, and where the events' band strengths are given
a shift that leaves several of one camera's bright events unmatched while it matches its
faint ones is not considered (a camera misses faint flashes: :data:`BRIGHTER_LEFT`,
:data:`MIN_LEFT_EVENTS`). Pairs sharing at least
:data:`MIN_SHARED_FLASHES` events without a rival shift are then merged, strongest first,
into flashes: groups of at most one event per camera (:func:`match_events`). Cameras are
tied together through chains of shared flashes (:meth:`Matching.tied_to`). A pair that
lines up at a few shifts about as well (a flash that fires a pre-flash) is kept aside as
undecided, with the other shifts of every pair, for the solve's fit to decide
(:func:`flashsync.pipeline.synchronize`); so is a pair whose other shift, too weak to
convince alone, lies as far from its own as such a pair's rival does (one pre-flash delay
for the whole rig).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field, replace

import numpy as np

from flashsync.coincidence import chance_alignments
from flashsync.compiled import njit
from flashsync.detect import CameraDetection
from flashsync.errors import InputError
from flashsync.events import Events
from flashsync.model import readout_rows
from flashsync.partners import occupied_bins, planned_pairs, shared_flash_estimate
from flashsync.timestamps import shortest_step_ms

#: Largest clock drift considered, as a fraction (100 ppm).
MAX_DRIFT = 100e-6
#: Another shift that explains this fraction of the best one's matches makes a pair
#: ambiguous (a periodic strobe fits at every multiple of its period).
RIVAL_FRACTION = 0.7
#: A convincing other shift of a pair that lines up this fraction of the best one's events
#: is its rival, for the solve's fit to decide: a camera blind to pre-flashes lines up with
#: one that saw them at two shifts with as many events but for the flashes or pre-flashes
#: each missed (random rig 417 with pre-flashes: 13 against 9 and 11 against 7, the more at
#: the wrong shift; taken, the reference was read upside down to fit them and every other
#: camera was 49 ms off at error/sigma 10); two cameras that both saw them line up at the
#: pre-flash's delay with about half (a flash to the other's pre-flash).
RIVAL_SHIFT_FRACTION = 0.6
#: A shift under which a camera's events left unmatched while the other camera recorded are
#: this many times brighter (median band strength) than those it matched is not believed
#: (:func:`align_pair`): a camera misses faint flashes, not bright ones, and at a pre-flash's
#: delay a camera that saw the pre-flashes (0.3 of their flash) lines its faint pre-flashes up
#: with the other's flashes and leaves its own flashes unmatched. Over 44 rigs fired with
#: pre-flashes, of 861 right shifts 4 came to 2.5 or more (two pairs of rig 416 and of its
#: twin), of 555 wrong ones 360, and all 11 wrong ones that counted as convincing 2.58 or
#: more (random rig 455: its reference saw mostly pre-flashes, five pairs with it lined up at
#: the pre-flash's delay, six cameras 59 ms off at error/sigma 100-253).
BRIGHTER_LEFT = 2.5
#: ... judged only where a camera leaves this many events unmatched or more: one or two
#: flashes a camera missed at random (out of view, or between its frames) may be its
#: brightest, and where both cameras saw the pre-flashes the true shift matches mostly faint
#: ones (random rig 817 fired with pre-flashes 60 ms early: its cam2 and cam4 lined up nine
#: events at the true shift, and cam4's two flashes that cam2 missed, 2.75 times the matched
#: median, set it aside for the pre-flash's delay, six events). Over 73 kept rigs (README,
#: "Two flashes missed at random") four moved: rig 813 with pre-flashes solved (refused
#: before), rig 416 with pre-flashes 0.163 -> 0.070 ms RMS, rig 817's cam2 still 60 ms off
#: (tied through cam1 at the pre-flash's delay; :func:`_at_a_rivals_delay` mends it).
MIN_LEFT_EVENTS = 3
#: Most rival shifts of a pair that the solve's fit may decide between (a flash with a
#: pre-flash lines up a camera that saw the pre-flashes with one that did not at two).
MAX_RIVALS = 2
#: Fewest flashes two cameras must share for their pair alignment to count.
MIN_SHARED_FLASHES = 3
#: Largest expected number of chance alignments as good for a pair alignment to count. The
#: count is conservative: of 100,000 random pairs of unrelated sequences (3-15 events over
#: 1.5 s to 10 min, or 10 over a minute; tolerance 5-40 ms) 0.13 % came below 0.1, 0.013 %
#: below 0.01, one below 0.003 and none below 0.001.
MAX_CHANCE = 1e-3
#: The matching tolerance, in frame periods of the slowest camera (and at least
#: MIN_TOLERANCE_MS): where every camera's readout direction is known, approximate times
#: are off by the few per cent the nominal time per row is off; where it may be wrong, a
#: camera read the wrong way up misplaces a band by up to a frame.
TOLERANCE_FRAMES = {True: 0.25, False: 1.0}
MIN_TOLERANCE_MS = 5.0
#: Shift votes are counted first in the bins as full as the (FLOOR_RANK x n_candidates)-th
#: fullest (:func:`_candidate_shifts`).
FLOOR_RANK = 8
#: Rows read per visible row, nominally: sensors read some hidden rows too, so the frame
#: period over the height is always a few per cent long as a time per row.
NOMINAL_HIDDEN_ROWS = 1.05


def approximate_times_ms(detection: CameraDetection, events: Events, share: float = 1.0) -> np.ndarray:
    """Times of the camera's ``events`` on its own clock, ms, with a nominal time per row: frame
    time + readout row x shortest frame step / (:data:`NOMINAL_HIDDEN_ROWS` x height) (a few per
    cent off: good to a few ms; the closer, the tighter true matches sit and the stronger
    their evidence), or ``share`` of it."""
    row_time = share * nominal_row_time_ms(detection)
    return events.t_frame_ms + readout_rows(events.row, detection.height, detection.flipped) * row_time


def nominal_row_time_ms(detection: CameraDetection) -> float:
    """The camera's time per row were its rows read evenly over its shortest frame period
    (:func:`~flashsync.timestamps.shortest_step_ms`: a camera whose frame rate drops part-way
    reads its rows as fast as before) with :data:`NOMINAL_HIDDEN_ROWS` of hidden rows, ms:
    shortest frame step / (1.05 x height)."""
    return shortest_step_ms(detection.frame_times_ms) / (NOMINAL_HIDDEN_ROWS * detection.height)


@dataclass(frozen=True)
class PairAlignment:
    """Affine map ``t_a ≈ alpha * t_b + beta`` between two cameras' event times (ms).

    ``matches`` has shape (n, 2): indices into camera a's and camera b's events;
    ``ambiguous`` is True when another shift explained nearly as many events; ``chance`` is
    the expected number of shifts and drifts under which unrelated events would match as
    well (:func:`flashsync.coincidence.chance_alignments`): the evidence is strong where it
    is far below one. ``others``: the other shifts (more than the tolerance away) that line
    up events as convincingly on their own, most matches first: a flash that fires a weaker
    pre-flash a few tens of ms before it (TTL metering) lines up a camera that saw the
    pre-flashes with one that did not at two shifts, and the counts alone need not tell
    which (the solve's fit can: :func:`flashsync.pipeline.synchronize`). ``unconvincing``:
    the other shifts that line up :data:`MIN_SHARED_FLASHES` events or more but would not
    convince on their own (a rival where the rig shows a pre-flash's delay:
    :func:`match_events`).
    """

    alpha: float
    beta: float
    matches: np.ndarray
    rms_ms: float
    ambiguous: bool
    chance: float = float("nan")
    others: tuple[PairAlignment, ...] = ()
    unconvincing: tuple[PairAlignment, ...] = ()

    @property
    def convincing(self) -> bool:
        """Enough shared events (:data:`MIN_SHARED_FLASHES`), no shift that lines up nearly
        as many (:attr:`ambiguous`) nor a rival one, and a chance alignment this good less
        likely than :data:`MAX_CHANCE`."""
        return (
            len(self.matches) >= MIN_SHARED_FLASHES
            and not self.ambiguous
            and not self.rivals
            and self.chance <= MAX_CHANCE
        )

    @property
    def rivals(self) -> tuple[PairAlignment, ...]:
        """The :attr:`others` that line up a good share of its events (:data:`RIVAL_SHIFT_FRACTION`)."""
        return tuple(o for o in self.others if len(o.matches) >= RIVAL_SHIFT_FRACTION * len(self.matches))

    @property
    def undecided(self) -> bool:
        """Convincing but for a few rival shifts (at most :data:`MAX_RIVALS`), each convincing
        on its own: a fit of the edges may tell them apart (a periodic strobe lines up at
        many shifts, and nothing does)."""
        return (
            len(self.matches) >= MIN_SHARED_FLASHES and self.chance <= MAX_CHANCE and 0 < len(self.rivals) <= MAX_RIVALS
        )


def align_pair(
    times_a: np.ndarray,
    times_b: np.ndarray,
    tolerance_ms: float,
    anchor: tuple[int, int] | None = None,
    n_candidates: int = 8,
    strengths: tuple[np.ndarray, np.ndarray] | None = None,
) -> PairAlignment | None:
    """Coarse alignment of two cameras' event times (ms, own clocks).

    Parameters
    ----------
    times_a, times_b : arrays of shape (n_a,), (n_b,)
        Approximate event times, ms.
    tolerance_ms : float
        How far a matched pair may be from the fitted map (approximation error of the
        times), ms.
    anchor : (i, j), optional
        Event i of a and event j of b are known to be the same flash.
    strengths : (arrays of shape (n_a,), (n_b,)), optional
        The events' band strengths (relative change, positive): a shift that leaves several
        of one camera's bright events unmatched and matches its faint ones is not considered
        (:data:`BRIGHTER_LEFT`, :data:`MIN_LEFT_EVENTS`).

    Returns
    -------
    The alignment with most matched events (at least 2, and without an anchor a shift that
    lines up :data:`MIN_SHARED_FLASHES`), or None.
    """
    times_a = np.asarray(times_a, dtype=np.float64)
    times_b = np.asarray(times_b, dtype=np.float64)
    if len(times_a) < 2 or len(times_b) < 2:
        return None
    if anchor is not None:
        shifts = np.array([times_a[anchor[0]] - times_b[anchor[1]]])
    else:
        shifts = _candidate_shifts(times_a, times_b, tolerance_ms, n_candidates)
    results = [_refine(times_a, times_b, shift, tolerance_ms) for shift in shifts]
    results = sorted((r for r in results if r is not None), key=lambda r: (-len(r.matches), r.rms_ms))
    if strengths is not None and anchor is None:
        results = [r for r in results if _brighter_left(r, times_a, times_b, *strengths) < BRIGHTER_LEFT]
    if not results:
        return None
    best = results[0]
    distinct = [best]
    for r in results[1:]:
        if len(r.matches) >= MIN_SHARED_FLASHES and all(abs(r.beta - d.beta) > tolerance_ms for d in distinct):
            distinct.append(r)
    ambiguous = any(len(r.matches) >= RIVAL_FRACTION * len(best.matches) for r in distinct[1:])
    if anchor is not None:
        return replace(best, ambiguous=ambiguous, chance=0.0)
    sizes = (len(times_a), len(times_b), np.ptp(times_a), np.ptp(times_b), tolerance_ms, MAX_DRIFT)
    chance = [chance_alignments(_residuals_ms(r, times_a, times_b), *sizes) for r in distinct]
    others = tuple(replace(r, chance=c) for r, c in zip(distinct[1:], chance[1:]) if c <= MAX_CHANCE)
    unconvincing = tuple(replace(r, chance=c) for r, c in zip(distinct[1:], chance[1:]) if c > MAX_CHANCE)
    return replace(best, ambiguous=ambiguous, chance=chance[0], others=others, unconvincing=unconvincing)


def _brighter_left(
    alignment: PairAlignment, times_a: np.ndarray, times_b: np.ndarray, strength_a: np.ndarray, strength_b: np.ndarray
) -> float:
    """How many times brighter (median strength) the events a camera leaves unmatched while
    the other camera recorded are than those it matches, the larger of the two cameras'
    (0 where neither leaves :data:`MIN_LEFT_EVENTS`)."""
    mapped_b = alignment.alpha * times_b + alignment.beta  # b's times on a's clock
    ratios = [0.0]
    for times, other, strength, column in ((times_a, mapped_b, strength_a, 0), (mapped_b, times_a, strength_b, 1)):
        matched = np.zeros(len(times), dtype=bool)
        matched[alignment.matches[:, column]] = True
        left = ~matched & (times >= other.min()) & (times <= other.max())
        if left.sum() >= MIN_LEFT_EVENTS:
            ratios.append(float(np.median(strength[left]) / np.median(strength[matched])))
    return max(ratios)


def _residuals_ms(alignment: PairAlignment, times_a: np.ndarray, times_b: np.ndarray) -> np.ndarray:
    """Camera a's matched times less the alignment's map of camera b's, ms."""
    a, b = alignment.matches.T
    return times_a[a] - (alignment.alpha * times_b[b] + alignment.beta)


def _candidate_shifts(times_a: np.ndarray, times_b: np.ndarray, tolerance_ms: float, n_candidates: int) -> np.ndarray:
    """The shifts (ms) that line up most event pairs, strongest first; only those that line
    up at least :data:`MIN_SHARED_FLASHES` (fewer never count).

    A shift's votes are the event-time differences ``d'`` with ``d - window <= d' < d + window``;
    the candidates are the differences with most votes (the smaller first among equals), each
    more than two windows from a stronger one. The votes are counted only in bins (one window
    wide) whose differences can have at least ``floor`` votes (the bin and its two
    neighbours hold that many): first the floor of the (:data:`FLOOR_RANK` x
    ``n_candidates``)-th fullest bin, lowered until the last shift chosen has at least
    ``floor`` votes, so that no shift under the floor could rank among them: the candidates
    are those of counting every difference (:func:`_strongest_shifts`, compiled)."""
    span = max(np.ptp(times_a), np.ptp(times_b))
    window = tolerance_ms + MAX_DRIFT * span
    return _strongest_shifts(times_a, times_b, window, FLOOR_RANK * n_candidates, n_candidates, MIN_SHARED_FLASHES)


@njit
def _strongest_shifts(times_a, times_b, window, rank, n_candidates, min_votes):  # pragma: no cover - compiled
    """Up to ``n_candidates`` differences ``a_i - b_j`` (ms) with most votes, at least
    ``min_votes`` (see :func:`_candidate_shifts`); shape (n_chosen,)."""
    scale = 1.0 / (window * (1.0 + 1e-9))  # differences within a window of each other are in neighbouring bins
    low = np.min(times_a) - np.max(times_b)  # the smallest difference
    n_bins = int((np.max(times_a) - np.min(times_b) - low) * scale) + 1
    counts = np.zeros(n_bins, dtype=np.int64)
    for a in times_a:
        for b in times_b:
            counts[int((a - b - low) * scale)] += 1
    bound = counts.copy()  # most votes of a difference in each bin
    bound[1:] += counts[:-1]
    bound[:-1] += counts[1:]
    floor = max(_largest(bound, min(n_bins, rank)), min_votes)
    while True:
        counted = bound >= floor
        near = counted.copy()  # the bins whose differences are needed: the counted ones and their neighbours
        near[1:] |= counted[:-1]
        near[:-1] |= counted[1:]
        first = np.zeros(n_bins + 1, dtype=np.int64)  # bin m's differences are ordered[first[m]:first[m + 1]]
        first[1:] = np.cumsum(np.where(near, counts, 0))
        ordered, filled = np.empty(first[-1]), first[:-1].copy()
        for a in times_a:
            for b in times_b:
                m = int((a - b - low) * scale)
                if near[m]:
                    ordered[filled[m]] = a - b
                    filled[m] += 1
        for m in np.flatnonzero(near):
            ordered[first[m] : first[m + 1]].sort()
        votes = np.zeros(len(ordered), dtype=np.int64)
        for m in np.flatnonzero(counted):
            below, under, stop = first[max(m - 1, 0)], first[max(m - 1, 0)], first[min(m + 2, n_bins)]
            for k in range(first[m], first[m + 1]):  # votes: differences in [d - window, d + window)
                while below < stop and ordered[below] < ordered[k] - window:
                    below += 1
                while under < stop and ordered[under] < ordered[k] + window:
                    under += 1
                votes[k] = under - below
        chosen = np.empty(n_candidates)
        n_chosen, last = 0, 0
        while n_chosen < n_candidates:
            best = -1
            for k in range(len(ordered)):  # the most votes, the smallest first, away from those chosen
                if votes[k] >= min_votes and (best < 0 or votes[k] > votes[best]):
                    free = True
                    for c in range(n_chosen):
                        if abs(ordered[k] - chosen[c]) <= 2 * window:
                            free = False
                    if free:
                        best = k
            if best < 0:
                break
            chosen[n_chosen] = ordered[best]
            last = votes[best]
            n_chosen += 1
        if floor == min_votes or (n_chosen == n_candidates and last >= floor):
            return chosen[:n_chosen]  # every difference with more votes than the last one chosen was counted
        floor = max(min(last, floor - 1), min_votes)


@njit
def _largest(values, rank):  # pragma: no cover - compiled
    """The ``rank``-th largest of non-negative integers (``np.sort(values)[-rank]``)."""
    histogram = np.bincount(values)
    total = 0
    for value in range(len(histogram) - 1, -1, -1):
        total += histogram[value]
        if total >= rank:
            return value
    return 0


def _refine(
    times_a: np.ndarray,
    times_b: np.ndarray,
    shift: float,
    tolerance_ms: float,
) -> PairAlignment | None:
    """Alternate one-to-one matching and an affine fit, starting from ``shift``."""
    alpha, beta = 1.0, shift
    span = max(np.ptp(times_a), np.ptp(times_b))
    matches = np.empty((0, 2), dtype=np.int64)
    for window in (tolerance_ms + MAX_DRIFT * span, tolerance_ms, tolerance_ms):
        matches = _mutual_nearest(times_a, alpha * times_b + beta, window)
        if len(matches) < 2:
            return None
        a, b = times_a[matches[:, 0]], times_b[matches[:, 1]]
        centred = b - b.mean()
        if np.ptp(b) > 0:
            slope = float(centred @ (a - a.mean()) / (centred @ centred))
            if abs(slope - 1.0) <= 1.5 * MAX_DRIFT:
                alpha, beta = slope, a.mean() - slope * b.mean()
                continue
        alpha, beta = 1.0, float(np.mean(a - b))
    residuals = times_a[matches[:, 0]] - (alpha * times_b[matches[:, 1]] + beta)
    return PairAlignment(alpha, beta, matches, float(np.sqrt(np.mean(residuals**2))), False)


@njit
def _mutual_nearest(times_a, mapped_b, window):  # pragma: no cover - compiled
    """Pairs (i, j) where a_i and mapped b_j are each other's nearest and within ``window``,
    closest first; shape (n_pairs, 2)."""
    nearest_a = _nearest(times_a, mapped_b)
    nearest_b = _nearest(mapped_b, times_a)
    mutual = np.zeros(len(mapped_b), dtype=np.bool_)
    for j in range(len(mapped_b)):
        mutual[j] = nearest_b[nearest_a[j]] == j and abs(times_a[nearest_a[j]] - mapped_b[j]) <= window
    j = np.flatnonzero(mutual)
    j = j[np.argsort(np.abs(times_a[nearest_a[j]] - mapped_b[j]), kind="mergesort")]
    pairs = np.empty((len(j), 2), dtype=np.int64)
    pairs[:, 0] = nearest_a[j]
    pairs[:, 1] = j
    return pairs


@njit
def _nearest(values, queries):  # pragma: no cover - compiled
    """Index into ``values`` (at least one) of the nearest to each query (the lower on a tie)."""
    order = np.argsort(values, kind="mergesort")
    ordered = values[order]
    last = len(values) - 1
    nearest = np.empty(len(queries), dtype=np.int64)
    for q in range(len(queries)):
        position = min(max(np.searchsorted(ordered, queries[q]), 1), max(last, 1))
        right = min(position, last)
        below = queries[q] - ordered[position - 1] <= ordered[right] - queries[q]
        nearest[q] = order[position - 1] if below else order[right]
    return nearest


def group_flashes(
    n_events: dict[str, int],
    alignments: dict[tuple[str, str], PairAlignment],
) -> dict[tuple[str, int], int]:
    """Merge pairwise matches into flashes: groups holding at most one event per camera.

    Pairs are merged strongest first (most matches); a merge that would put two events of one
    camera into a flash is refused, so one bad pair cannot chain flashes together.

    Returns
    -------
    dict mapping (camera, event index) to a flash number, for events in a flash of at least
    two cameras; flashes numbered in the order of their first member (camera name, event).
    """
    names = list(n_events)
    offset = dict(zip(names, np.cumsum([0, *n_events.values()])[:-1].tolist()))
    camera = np.repeat(np.arange(len(names)), list(n_events.values()))
    ranked = sorted(alignments.items(), key=lambda item: -len(item[1].matches))
    merges = np.zeros((0, 2), dtype=np.int64)
    if ranked:
        merges = np.concatenate([alignment.matches + [offset[a], offset[b]] for (a, b), alignment in ranked]).astype(
            np.int64
        )
    root, size = _merged_groups(merges, camera, len(names))
    event = np.arange(len(camera)) - np.repeat(list(offset.values()), list(n_events.values()))
    grouped = np.flatnonzero(size[root] > 1)
    roots = sorted(set(root[grouped].tolist()), key=lambda node: (names[camera[node]], int(event[node])))
    number = dict(zip(roots, range(len(roots))))
    return {(names[camera[node]], int(event[node])): number[root[node]] for node in grouped.tolist()}


@njit
def _merged_groups(merges, camera, n_cameras):  # pragma: no cover - compiled
    """Union of events (nodes of camera ``camera[node]``) along ``merges`` (pairs of nodes,
    in order), refusing a merge that would hold two events of one camera: each node's group
    (its root node) and each root's size."""
    n = len(camera)
    parent = np.arange(n)
    words = (n_cameras + 63) // 64
    cameras = np.zeros((n, words), dtype=np.uint64)  # per root, the cameras in its group (bits)
    for node in range(n):
        cameras[node, camera[node] // 64] = np.uint64(1) << np.uint64(camera[node] % 64)
    size = np.ones(n, dtype=np.int64)
    for k in range(len(merges)):
        a, b = _root(parent, merges[k, 0]), _root(parent, merges[k, 1])
        if a == b or np.any(cameras[a] & cameras[b]):
            continue
        parent[b] = a
        cameras[a] |= cameras[b]
        size[a] += size[b]
    for node in range(n):
        parent[node] = _root(parent, node)
    return parent, size


@njit
def _root(parent, node):  # pragma: no cover - compiled
    """The root of ``node``'s group, halving the path on the way."""
    while parent[node] != node:
        parent[node] = parent[parent[node]]
        node = parent[node]
    return node


def match_tolerance_ms(frame_periods_ms: Iterable[float], readout_known: bool) -> float:
    """How far two cameras' approximate times of one flash may be apart, ms (see
    :data:`TOLERANCE_FRAMES`)."""
    return max(MIN_TOLERANCE_MS, TOLERANCE_FRAMES[readout_known] * max(frame_periods_ms))


@dataclass(frozen=True)
class Matching:
    """Events of several cameras matched into flashes.

    Attributes
    ----------
    alignments : dict
        ``(camera a, camera b) -> PairAlignment`` of every pair that counts.
    flashes : dict
        ``(camera, event index) -> flash number`` of every event in a flash of two or more
        cameras (:func:`group_flashes`).
    undecided : dict
        ``(camera a, camera b) -> PairAlignment`` of the pairs aligned but left out as
        :attr:`~PairAlignment.undecided` (their rival shifts in it), for a fit to decide.
    """

    alignments: dict[tuple[str, str], PairAlignment]
    flashes: dict[tuple[str, int], int]
    undecided: dict[tuple[str, str], PairAlignment] = field(default_factory=dict)

    def with_alignments(self, alignments: dict[tuple[str, str], PairAlignment], n_events: dict[str, int]) -> Matching:
        """This matching with ``alignments`` instead (flashes grouped again; ``n_events``: per
        camera, its number of events)."""
        return replace(self, alignments=alignments, flashes=group_flashes(n_events, alignments))

    def tied_to(self, reference: str) -> set[str]:
        """The cameras linked to ``reference`` through chains of shared flashes (it included)."""
        seen_by: dict[int, set[str]] = {}
        for (camera, _), flash in self.flashes.items():
            seen_by.setdefault(flash, set()).add(camera)
        tied, grew = {reference}, True
        while grew:
            grew = False
            for group in seen_by.values():
                if group & tied and not group <= tied:
                    tied |= group
                    grew = True
        return tied


def match_events(
    times_ms: dict[str, np.ndarray],
    tolerance_ms: float,
    anchors: dict[str, int] | None = None,
    memo: dict | None = None,
    strengths: dict[str, np.ndarray] | None = None,
) -> Matching:
    """Align pairs of cameras along a spanning structure (every pair in rigs of a few
    cameras; :mod:`flashsync.partners`) and merge the pairs that count into flashes.

    Parameters
    ----------
    times_ms : dict of str to array of shape (n_events,)
        Per camera, its events' approximate times on its own clock, ms.
    tolerance_ms : float
        See :func:`align_pair` and :func:`match_tolerance_ms`.
    anchors : dict of str to int, optional
        Per camera, the index of an event known to be one flash with the other cameras'.
    memo : dict, optional
        Alignments and estimates of earlier calls, by the pair's event times: give the same
        dict to calls that differ in a few cameras' times (readout directions tried one
        camera at a time) and only those cameras' pairs are aligned again.
    strengths : dict of str to array of shape (n_events,), optional
        Per camera, its events' band strengths (:func:`align_pair`).

    Returns
    -------
    Matching
        With the pairs aligned that share at least :data:`MIN_SHARED_FLASHES` events and
        have no rival shift, nor an unconvincing one at an undecided pair's rival's delay
        (:func:`_at_a_rivals_delay`: those are undecided too).
    """
    anchors = anchors or {}
    memo = {} if memo is None else memo
    names = list(times_ms)
    keys = {name: times.tobytes() for name, times in times_ms.items()}
    span = max((np.ptp(times) for times in times_ms.values() if len(times)), default=0.0)
    window = tolerance_ms + MAX_DRIFT * span

    def bins(name: str) -> np.ndarray:
        key = ("bins", keys[name], window)
        if key not in memo:
            memo[key] = occupied_bins(times_ms[name], window)
        return memo[key]

    def estimate(a: str, b: str) -> int:
        key = ("estimate", keys[a], keys[b], window)
        if key not in memo:
            memo[key] = shared_flash_estimate(bins(a), bins(b))
        return memo[key]

    def aligned(a: str, b: str) -> PairAlignment | None:
        anchor = (anchors[a], anchors[b]) if a in anchors and b in anchors else None
        pair_strengths = (strengths[a], strengths[b]) if strengths is not None else None
        key = ("alignment", keys[a], keys[b], tolerance_ms, anchor, pair_strengths is not None)
        if key not in memo:
            memo[key] = align_pair(times_ms[a], times_ms[b], tolerance_ms, anchor, strengths=pair_strengths)
        return memo[key]

    def convincing(a: str, b: str) -> bool:
        alignment = aligned(a, b)
        return alignment is not None and alignment.convincing

    pairs = planned_pairs(names, estimate, convincing, MIN_SHARED_FLASHES)
    alignments = {pair: aligned(*pair) for pair in pairs if convincing(*pair)}
    undecided = {pair: aligned(*pair) for pair in pairs if aligned(*pair) is not None and aligned(*pair).undecided}
    delays_ms = [abs(rival.beta - alignment.beta) for alignment in undecided.values() for rival in alignment.rivals]
    for pair, alignment in list(alignments.items()):
        at_delay = _at_a_rivals_delay(alignment, delays_ms, tolerance_ms)
        if at_delay:
            undecided[pair] = replace(alignment, others=alignment.others + at_delay)
            del alignments[pair]
    n_events = {name: len(times) for name, times in times_ms.items()}
    return Matching(alignments, group_flashes(n_events, alignments), undecided)


def _at_a_rivals_delay(
    alignment: PairAlignment, delays_ms: list[float], tolerance_ms: float
) -> tuple[PairAlignment, ...]:
    """The :attr:`~PairAlignment.unconvincing` other shifts of ``alignment`` that line up a
    rival's share of its events (:data:`RIVAL_SHIFT_FRACTION`) as far from it as one of
    ``delays_ms`` (within ``tolerance_ms``): the distances, ms, of the undecided pairs'
    rivals from their shifts, as the pairs were aligned. A TTL flash's pre-flash fires at
    one delay before it for the whole rig, so such a shift is no chance alignment (random
    rig 817 with pre-flashes 60 ms early: cam1 and cam2 lined up five events at the delay
    and three at the true shift, too few to convince alone)."""
    return tuple(
        other
        for other in alignment.unconvincing
        if len(other.matches) >= RIVAL_SHIFT_FRACTION * len(alignment.matches)
        and any(abs(abs(other.beta - alignment.beta) - delay) <= tolerance_ms for delay in delays_ms)
    )[:MAX_RIVALS]


def shared_flashes(camera: np.ndarray, flash: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which of some flashes' observations belong to a flash two or more cameras saw.

    Parameters
    ----------
    camera, flash : int arrays of shape (n,)
        The camera and the flash number of each observation.

    Returns
    -------
    keep : bool array of shape (n,)
    numbers : int array of shape (keep.sum(),)
        The kept observations' flashes numbered 0, 1, ... in the order of their numbers.
    """
    camera, flash = np.asarray(camera, dtype=np.int64), np.asarray(flash, dtype=np.int64)
    if not len(flash):
        return np.zeros(0, dtype=bool), np.zeros(0, dtype=np.int64)
    seen = np.unique(np.stack([flash, camera]), axis=1)[0]
    keep = np.bincount(seen, minlength=flash.max() + 1)[flash] >= 2
    return keep, np.unique(flash[keep], return_inverse=True)[1]


def parse_anchors(anchors: list[str], event_numbers: dict[str, np.ndarray]) -> dict[str, int]:
    """``['cam1:0', 'cam2:3']``: these events are one flash.

    Parameters
    ----------
    anchors : list of str
        ``CAMERA:EVENT``, EVENT the detector's event number (the events table's ``event``).
    event_numbers : dict of str to int array
        Per camera, the event number of each of its sync events (a leading edge, or a
        trailing edge whose leading edge is hidden).

    Returns
    -------
    dict of str to int
        Per anchored camera, the index of that event among its sync events.
    """
    result = {}
    for text in anchors:
        camera, _, number = text.rpartition(":")
        if camera not in event_numbers or not number.isdecimal():
            raise InputError(
                f"{text}: expected CAMERA:EVENT with a camera of {', '.join(event_numbers)} and an "
                "event number (the events table's event column)",
                parameter="anchors",
            )
        where = np.flatnonzero(np.asarray(event_numbers[camera]) == int(number))
        if not where.size:
            raise InputError(
                f"{text}: {camera} has no event {number} among its sync events (bands with a visible "
                "leading edge, or cut at the frame's start); anchor one "
                "of its events " + ", ".join(map(str, event_numbers[camera])),
                parameter="anchors",
            )
        result[camera] = int(where[0])
    return result
