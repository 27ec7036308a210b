"""Which pairs of cameras to align: a spanning structure instead of every pair.

Aligning a pair (:func:`flashsync.match.align_pair`) votes a shift from every pair of the
two cameras' event times; for 64 cameras of 400 events that is 2016 pairs of 160,000
differences each, minutes of work, while a camera needs only a few good partners to be
tied and checked. A cheap estimate of the flashes two cameras share (the fullest bin of a
histogram of their time differences, :func:`shared_flash_estimate`) ranks the pairs; the
pairs aligned are then

- a maximum spanning forest: the best-ranked pairs that join cameras not yet tied by a
  convincing alignment (so two groups of cameras linked by a few flashes only stay linked);
- each camera's best-ranked partners until :data:`PARTNERS` of its alignments convince:
  redundancy, so that one bad pair cannot mis-tie a camera (:func:`~flashsync.match.group_flashes`
  refuses a merge that puts two events of one camera into a flash).

Rigs of at most ``PARTNERS + 1`` cameras align every pair, as before.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from flashsync.compiled import njit

#: Convincing alignments sought per camera (its best-ranked partners first).
PARTNERS = 4


def occupied_bins(times: np.ndarray, window_ms: float) -> np.ndarray:
    """The bins (``window_ms`` wide, from the camera's first event) of a camera's events,
    int array of shape (n_events,)."""
    times = np.asarray(times, dtype=np.float64)
    return ((times - times.min()) // window_ms).astype(np.int64) if len(times) else np.zeros(0, dtype=np.int64)


@njit
def shared_flash_estimate(bins_a: np.ndarray, bins_b: np.ndarray) -> int:  # pragma: no cover - compiled
    """Upper estimate of the flashes two cameras share from their :func:`occupied_bins`: the
    most event pairs whose bin differences are one of two adjacent values (one shift, give
    or take a bin; chance coincidences add a few)."""
    if not len(bins_a) or not len(bins_b):
        return 0
    low = -np.max(bins_b)
    pairs = np.zeros(np.max(bins_a) - low + 2, dtype=np.int64)  # by bin difference, from low
    for i in bins_a:
        for j in bins_b:
            pairs[i - j - low] += 1
    best = 0
    for k in range(len(pairs) - 1):
        best = max(best, pairs[k] + pairs[k + 1])
    return best


def planned_pairs(
    names: list[str],
    estimate: Callable[[str, str], int],
    convincing: Callable[[str, str], bool],
    min_shared: int,
) -> list[tuple[str, str]]:
    """The pairs ``(a, b)`` (``a`` before ``b`` in ``names``) to align, in ``names`` order.

    Parameters
    ----------
    names : the cameras.
    estimate : ``estimate(a, b)``, the flashes a and b may share (:func:`shared_flash_estimate`).
    convincing : ``convincing(a, b)`` aligns the pair (once; the caller remembers it) and
        says whether the alignment counts.
    min_shared : pairs estimated to share fewer flashes are never aligned.
    """
    position = {name: index for index, name in enumerate(names)}

    def ordered(a: str, b: str) -> tuple[str, str]:
        return (a, b) if position[a] < position[b] else (b, a)

    everything = [(a, b) for i, a in enumerate(names) for b in names[i + 1 :]]
    if len(names) <= PARTNERS + 1:
        return everything
    shared = {pair: estimate(*pair) for pair in everything}
    ranked = sorted((pair for pair in everything if shared[pair] >= min_shared), key=lambda pair: -shared[pair])
    tried: set[tuple[str, str]] = set()
    good: set[tuple[str, str]] = set()

    def align(pair: tuple[str, str]) -> bool:
        tried.add(pair)
        if convincing(*pair):
            good.add(pair)
            return True
        return False

    group = {name: name for name in names}

    def root(name: str) -> str:
        while group[name] != name:
            group[name] = group[group[name]]
            name = group[name]
        return name

    for pair in ranked:  # maximum spanning forest of convincing alignments
        if root(pair[0]) != root(pair[1]) and align(pair):
            group[root(pair[1])] = root(pair[0])
    for name in names:  # redundancy: each camera's best partners
        partners = sorted((other for other in names if other != name), key=lambda other: -shared[ordered(name, other)])
        for other in partners:
            if sum(name in pair for pair in good) >= PARTNERS or shared[ordered(name, other)] < min_shared:
                break
            if ordered(name, other) not in tried:
                align(ordered(name, other))
    return sorted(tried, key=lambda pair: (position[pair[0]], position[pair[1]]))
