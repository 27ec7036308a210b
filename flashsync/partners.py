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

#: Convincing alignments sought per camera (its best-ranked partners first).
PARTNERS = 4


def occupancy_spectrum(times: np.ndarray, window_ms: float, length: int) -> np.ndarray:
    """Real FFT of a camera's events counted in bins ``window_ms`` wide from its first
    event, ``length`` bins (at least two spans' worth: the correlation of two cameras then
    does not wrap around); shape (length // 2 + 1,)."""
    times = np.asarray(times, dtype=np.float64)
    counts = np.zeros(length)
    if len(times):
        np.add.at(counts, ((times - times.min()) // window_ms).astype(np.int64), 1.0)
    return np.fft.rfft(counts)


def spectrum_length(spans_ms: list[float], window_ms: float) -> int:
    """Bins of :func:`occupancy_spectrum` for cameras whose events span ``spans_ms``: a power
    of two over twice the longest span in bins."""
    return 1 << int(np.ceil(np.log2(2 * (max(spans_ms, default=0.0) // window_ms + 2))))


def shared_flash_estimate(spectrum_a: np.ndarray, spectrum_b: np.ndarray) -> int:
    """Upper estimate of the flashes two cameras share from their :func:`occupancy_spectrum`:
    the most event pairs whose time differences fall into two adjacent bins (one shift,
    give or take a bin; chance coincidences add a few)."""
    correlation = np.fft.irfft(spectrum_a * np.conj(spectrum_b), n=2 * (len(spectrum_a) - 1))
    return int(np.rint(np.max(correlation + np.roll(correlation, -1))))


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
