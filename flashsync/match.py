"""Pair events across cameras from the pattern of their times, with no manual step.

Every camera's sync events get an approximate time on its own clock, ``t_frame + q *
T_nominal`` (``T_nominal`` = frame period / height, a few per cent off: good to a few ms).
For each pair of cameras, the offsets between all their event times vote for the shift
(flashes fired by hand are irregular, so only the true shift lines many of them up); each
leading candidate is refined into an affine map (shift and drift) by alternating one-to-one
matching and fitting. Pairs are then merged, strongest first, into flashes: groups of at
most one event per camera.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flashsync.errors import FlashsyncError

#: Largest clock drift considered, as a fraction (100 ppm).
MAX_DRIFT = 100e-6
#: Another shift that explains this fraction of the best one's matches makes a pair
#: ambiguous (a periodic strobe fits at every multiple of its period).
RIVAL_FRACTION = 0.7


@dataclass(frozen=True)
class PairAlignment:
    """Affine map ``t_a ≈ alpha * t_b + beta`` between two cameras' event times (ms).

    ``matches`` has shape (n, 2): indices into camera a's and camera b's events;
    ``ambiguous`` is True when another shift explained nearly as many events.
    """

    alpha: float
    beta: float
    matches: np.ndarray
    rms_ms: float
    ambiguous: bool


def align_pair(
    times_a: np.ndarray,
    times_b: np.ndarray,
    tolerance_ms: float,
    anchor: tuple[int, int] | None = None,
    n_candidates: int = 8,
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

    Returns
    -------
    The alignment with most matched events (at least 2), or None.
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
    if not results:
        return None
    best = results[0]
    rivals = [
        r
        for r in results[1:]
        if len(r.matches) >= max(3, RIVAL_FRACTION * len(best.matches)) and abs(r.beta - best.beta) > tolerance_ms
    ]
    return PairAlignment(best.alpha, best.beta, best.matches, best.rms_ms, bool(rivals))


def _candidate_shifts(times_a: np.ndarray, times_b: np.ndarray, tolerance_ms: float, n_candidates: int) -> np.ndarray:
    """The shifts (ms) that line up most event pairs, strongest first."""
    differences = np.sort((times_a[:, None] - times_b[None, :]).ravel())
    span = max(np.ptp(times_a), np.ptp(times_b))
    window = tolerance_ms + MAX_DRIFT * span
    votes = np.searchsorted(differences, differences + window) - np.searchsorted(differences, differences - window)
    chosen: list[float] = []
    for index in np.argsort(-votes, kind="stable"):
        if votes[index] < 2 or len(chosen) == n_candidates:
            break
        if all(abs(differences[index] - shift) > 2 * window for shift in chosen):
            chosen.append(differences[index])
    return np.asarray(chosen)


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
        if np.ptp(b) > 0:
            slope, intercept = np.polyfit(b - b.mean(), a, 1)
            if abs(slope - 1.0) <= 1.5 * MAX_DRIFT:
                alpha, beta = slope, intercept - slope * b.mean()
                continue
        alpha, beta = 1.0, float(np.mean(a - b))
    residuals = times_a[matches[:, 0]] - (alpha * times_b[matches[:, 1]] + beta)
    return PairAlignment(alpha, beta, matches, float(np.sqrt(np.mean(residuals**2))), False)


def _mutual_nearest(times_a: np.ndarray, mapped_b: np.ndarray, window: float) -> np.ndarray:
    """Pairs (i, j) where a_i and mapped b_j are each other's nearest and within ``window``."""
    order = np.argsort(times_a)
    sorted_a = times_a[order]
    position = np.clip(np.searchsorted(sorted_a, mapped_b), 1, len(sorted_a) - 1)
    left, right = sorted_a[position - 1], sorted_a[position]
    nearest_a = order[np.where(mapped_b - left < right - mapped_b, position - 1, position)]
    distance = np.abs(times_a[nearest_a] - mapped_b)
    pairs = []
    for j in np.argsort(distance):
        i = nearest_a[j]
        if distance[j] <= window:
            closest_b = np.argmin(np.abs(mapped_b - times_a[i]))
            if closest_b == j:
                pairs.append((i, j))
    return np.asarray(pairs, dtype=np.int64).reshape(-1, 2)


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
    two cameras.
    """
    parent = {(camera, i): (camera, i) for camera, n in n_events.items() for i in range(n)}
    members = {node: {node[0]: node[1]} for node in parent}

    def root(node):
        while parent[node] != node:
            parent[node] = parent[parent[node]]
            node = parent[node]
        return node

    ranked = sorted(alignments.items(), key=lambda item: -len(item[1].matches))
    for (camera_a, camera_b), alignment in ranked:
        for i, j in alignment.matches:
            ra, rb = root((camera_a, int(i))), root((camera_b, int(j)))
            if ra == rb or set(members[ra]) & set(members[rb]):
                continue
            parent[rb] = ra
            members[ra].update(members.pop(rb))
    flashes: dict[tuple[str, int], int] = {}
    roots = sorted({root(node) for node in parent if len(members[root(node)]) > 1})
    for number, group_root in enumerate(roots):
        for camera, event in members[group_root].items():
            flashes[(camera, event)] = number
    return flashes


def parse_anchors(anchors: list[str], n_events: dict[str, int]) -> dict[str, int]:
    """``['cam1:0', 'cam2:3']`` -> ``{'cam1': 0, 'cam2': 3}``: these events are one flash."""
    result = {}
    for text in anchors:
        camera, _, index = text.rpartition(":")
        if camera not in n_events or not index.isdigit():
            raise FlashsyncError(
                f"--anchor {text}: expected CAMERA:EVENT_INDEX with a camera of "
                f"{', '.join(n_events)} and a 0-based event index"
            )
        if int(index) >= n_events[camera]:
            raise FlashsyncError(f"--anchor {text}: {camera} has only {n_events[camera]} sync events")
        result[camera] = int(index)
    return result
