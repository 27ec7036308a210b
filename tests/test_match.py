"""Coarse alignment from event patterns alone, on the hard cases: missing and spurious
events, different frame rates, drift up to 100 ppm, offsets of minutes."""

import numpy as np
import pytest

from flashsync.match import align_pair, group_flashes

TOLERANCE_MS = 10.0


def flashes(rng, n=40, span_ms=20 * 60_000.0):
    """Irregular flash instants (as a photographer fires them), ms."""
    return np.sort(rng.uniform(0, span_ms, n))


def seen_by(rng, tau, alpha, beta, frame_ms, miss=0.0, spurious=0):
    """A camera's approximate event times on its own clock for true instants ``tau``:
    global = alpha * t + beta, each time off by up to 10 % of a frame (the nominal time per
    row is a few per cent off), some flashes missed and some spurious events added.
    Returns (times, index of each true flash or -1)."""
    keep = rng.uniform(size=len(tau)) >= miss
    times = (tau[keep] - beta) / alpha + rng.uniform(-0.1, 0.1, keep.sum()) * frame_ms
    extra = rng.uniform(times.min(), times.max(), spurious)
    truth = np.concatenate([np.flatnonzero(keep), -np.ones(spurious, int)])
    order = np.argsort(np.concatenate([times, extra]))
    return np.concatenate([times, extra])[order], truth[order]


def correct_fraction(alignment, truth_a, truth_b):
    pairs = [(truth_a[i], truth_b[j]) for i, j in alignment.matches]
    return np.mean([a == b and a >= 0 for a, b in pairs]), len(pairs)


@pytest.mark.parametrize("seed", range(5))
def test_missing_and_spurious_events_on_both_sides(seed):
    rng = np.random.default_rng(seed)
    tau = flashes(rng)
    a, truth_a = seen_by(rng, tau, 1.0, 0.0, 40.0, miss=0.2, spurious=8)
    b, truth_b = seen_by(rng, tau, 1 + 35e-6, -183_456.0, 33.3, miss=0.2, spurious=8)
    alignment = align_pair(a, b, TOLERANCE_MS)
    fraction, n = correct_fraction(alignment, truth_a, truth_b)
    assert fraction == 1.0 and n >= 0.5 * len(tau)
    assert not alignment.ambiguous


@pytest.mark.parametrize("drift", [-100e-6, 100e-6])
def test_drift_of_100_ppm_over_20_minutes(drift):
    rng = np.random.default_rng(7)
    tau = flashes(rng, n=30)
    a, truth_a = seen_by(rng, tau, 1.0, 0.0, 40.0)
    b, truth_b = seen_by(rng, tau, 1 + drift, 300_000.0, 20.0)  # 5 minutes offset, 50 fps
    alignment = align_pair(a, b, TOLERANCE_MS)
    fraction, n = correct_fraction(alignment, truth_a, truth_b)
    assert fraction == 1.0 and n == len(tau)
    assert alignment.alpha == pytest.approx(1 + drift, abs=2e-6)


def test_periodic_flashes_are_ambiguous_not_guessed():
    tau = np.arange(10) * 2000.0 + 500.0  # a strobe: every shift fits
    alignment = align_pair(tau, tau - 10_000.0, TOLERANCE_MS)
    assert alignment.ambiguous


def test_anchor_picks_the_shift():
    tau = np.arange(10) * 2000.0 + 500.0
    alignment = align_pair(tau, tau - 10_000.0, TOLERANCE_MS, anchor=(3, 0))
    assert alignment.beta == pytest.approx(10_000.0 + 3 * 2000.0)
    assert not alignment.ambiguous


def test_no_common_flashes():
    rng = np.random.default_rng(3)
    a = flashes(rng, 10, 60_000.0)
    b = flashes(rng, 10, 60_000.0) + 1e6
    alignment = align_pair(a, b, TOLERANCE_MS)
    assert alignment is None or not alignment.convincing


def test_no_false_match_in_ten_thousand_unrelated_pairs():
    """Unrelated sequences of 10 flashes over a minute (the shift and the drift free): a few
    line up 3 events within the tolerance somewhere (the pipeline used to accept 1 % of
    them); how often that happens by chance is counted, and none is convincing."""
    rng = np.random.default_rng(12)
    lined_up = 0
    for _ in range(10_000):
        a, b = flashes(rng, 10, 60_000.0), flashes(rng, 10, 60_000.0) + rng.uniform(-1e6, 1e6)
        alignment = align_pair(a, b, TOLERANCE_MS)
        assert alignment is None or not alignment.convincing, (alignment, a, b)
        lined_up += alignment is not None and len(alignment.matches) >= 3
    assert lined_up > 10  # the chance coincidences it must not take


def test_a_short_clip_with_four_flashes_is_convincing():
    """Four flashes in two seconds, matched within half a millisecond: convincing (unrelated
    events line up that well far less than once in a thousand pairs)."""
    rng = np.random.default_rng(4)
    tau = np.sort(rng.uniform(0.0, 2000.0, 4)) + np.arange(4) * 100.0
    a = tau + rng.normal(0.0, 0.3, 4)
    b = tau - 1234.5 + rng.normal(0.0, 0.3, 4)
    assert align_pair(a, b, TOLERANCE_MS).convincing


def test_flashes_grouped_across_cameras_that_share_none_with_the_reference():
    from flashsync.match import PairAlignment

    # camera a sees flashes 0-4, c sees 5-9, b sees all: a and c are tied through b
    ab = PairAlignment(1.0, 0.0, np.array([[i, i] for i in range(5)]), 0.0, False)
    bc = PairAlignment(1.0, 0.0, np.array([[5 + i, i] for i in range(5)]), 0.0, False)
    groups = group_flashes({"a": 5, "b": 10, "c": 5}, {("a", "b"): ab, ("b", "c"): bc})
    assert groups[("a", 2)] == groups[("b", 2)]
    assert groups[("c", 1)] == groups[("b", 6)]
    assert len(set(groups.values())) == 10


def test_a_bad_pair_cannot_chain_two_events_of_one_camera():
    from flashsync.match import PairAlignment

    good = PairAlignment(1.0, 0.0, np.array([[0, 0], [1, 1]]), 0.0, False)
    bad = PairAlignment(1.0, 0.0, np.array([[0, 1]]), 0.0, False)  # a0 with b1: conflicts
    groups = group_flashes({"a": 2, "b": 2}, {("a", "b"): good, ("b", "a"): bad})
    assert groups[("a", 0)] == groups[("b", 0)] != groups[("b", 1)]


def test_cameras_are_tied_through_chains_of_shared_flashes():
    """a and c share one flash (too few to align them) but both share many with b; d's flashes
    are another session's."""
    from flashsync.match import match_events

    rng = np.random.default_rng(3)
    tau = flashes(rng, n=12)
    a, _ = seen_by(rng, tau[:7], 1.0, 0.0, 40.0)
    b, _ = seen_by(rng, tau, 1.0, -50_000.0, 33.3)
    c, _ = seen_by(rng, tau[6:], 1.0, 20_000.0, 40.0)
    d, _ = seen_by(rng, flashes(rng, n=12), 1.0, 0.0, 40.0)
    matching = match_events({"a": a, "b": b, "c": c, "d": d}, TOLERANCE_MS)
    assert matching.tied_to("a") == {"a", "b", "c"}
    assert matching.tied_to("d") == {"d"}


def test_only_flashes_two_cameras_saw_are_kept_and_renumbered():
    from flashsync.match import shared_flashes

    keep, numbers = shared_flashes(camera=[0, 1, 0, 0, 2, 2], flash=[4, 4, 7, 9, 9, 9])
    assert list(keep) == [True, True, False, True, True, True]
    assert list(numbers) == [0, 0, 1, 1, 1]


def test_anchors_name_the_detectors_event_numbers():
    """cam1's event 2 has no leading edge (hidden): its sync events are events 0, 1, 3, 4."""
    from flashsync.errors import InputError
    from flashsync.match import parse_anchors

    numbers = {"cam1": np.array([0, 1, 3, 4]), "cam2": np.array([0, 1, 2])}
    assert parse_anchors(["cam1:3", "cam2:1"], numbers) == {"cam1": 2, "cam2": 1}
    with pytest.raises(InputError, match="cam1:2: cam1 has no event 2") as error:
        parse_anchors(["cam1:2"], numbers)
    assert error.value.parameter == "anchors"


def many_cameras(rng, tau_of_camera):
    """Per camera ``c0, c1, ...``: approximate times of the flashes it sees (random shift up to
    a minute, drift up to 50 ppm, 25-50 fps, 10 % missed, 2 spurious) and the true flash of
    each (-1 spurious)."""
    times, truth = {}, {}
    for c, tau in enumerate(tau_of_camera):
        alpha, beta = 1 + rng.uniform(-50e-6, 50e-6), rng.uniform(-60_000.0, 60_000.0)
        times[f"c{c}"], truth[f"c{c}"] = seen_by(rng, tau, alpha, beta, rng.choice([20.0, 40.0]), 0.1, 2)
    return times, truth


def assert_true_flashes(matching, truth, tau_index):
    """Every flash holds events of one true flash (``tau_index`` maps a camera's truth to
    the rig's flash numbers)."""
    groups = {}
    for (camera, event), flash in matching.flashes.items():
        groups.setdefault(flash, set()).add(
            tau_index[camera][truth[camera][event]] if truth[camera][event] >= 0 else -1
        )
    assert groups and all(len(true) == 1 and -1 not in true for true in groups.values())


def test_a_large_rig_aligns_a_spanning_structure_not_every_pair():
    """12 cameras: each aligned with a few partners (66 pairs otherwise), all tied, every
    flash one true flash."""
    from flashsync.match import match_events
    from flashsync.partners import PARTNERS

    rng = np.random.default_rng(5)
    tau = flashes(rng, n=60)
    times, truth = many_cameras(rng, [tau] * 12)
    matching = match_events(times, TOLERANCE_MS)
    assert len(matching.alignments) <= len(times) * PARTNERS < 66
    assert all(sum(name in pair for pair in matching.alignments) >= PARTNERS for name in times)
    assert matching.tied_to("c0") == set(times)
    assert_true_flashes(matching, truth, {name: np.arange(60) for name in times})


def test_two_groups_sharing_a_few_flashes_stay_tied():
    """c0-c4 see one half's flashes, c5-c9 the other's, and all see 6 more: each camera's best
    partners are in its own group, the spanning forest links the groups."""
    from flashsync.match import match_events

    rng = np.random.default_rng(6)
    tau = flashes(rng, n=66)
    order = rng.permutation(66)
    halves = [np.sort(np.concatenate([order[:30], order[60:]])), np.sort(np.concatenate([order[30:60], order[60:]]))]
    times, truth = many_cameras(rng, [tau[halves[c // 5]] for c in range(10)])
    matching = match_events(times, TOLERANCE_MS)
    assert matching.tied_to("c0") == set(times)
    assert any(int(a[1:]) // 5 != int(b[1:]) // 5 for a, b in matching.alignments)
    assert_true_flashes(matching, truth, {f"c{c}": halves[c // 5] for c in range(10)})


def test_alignments_are_remembered_between_calls(monkeypatch):
    """With the same memo, a call where one camera's times changed (read the other way up)
    aligns only that camera's pairs again."""
    import flashsync.match as match

    rng = np.random.default_rng(7)
    tau = flashes(rng, n=40)
    times, _ = many_cameras(rng, [tau] * 8)
    aligned = []
    original = match.align_pair
    monkeypatch.setattr(
        match, "align_pair", lambda a, b, *rest, **options: aligned.append(1) or original(a, b, *rest, **options)
    )
    memo = {}
    first = match.match_events(times, TOLERANCE_MS, memo=memo)
    n_first = len(aligned)
    again = match.match_events(dict(times), TOLERANCE_MS, memo=memo)
    assert len(aligned) == n_first and again.flashes == first.flashes
    times["c3"] = times["c3"] + 1.0
    match.match_events(times, TOLERANCE_MS, memo=memo)
    assert 0 < len(aligned) - n_first <= len(times) - 1


def counting_every_difference(times_a, times_b, tolerance_ms, n_candidates=8):
    """The candidate shifts by definition: every difference's votes (differences in
    [d - window, d + window)), the most first (the smaller among equals), each more than two
    windows from a stronger one, at least MIN_SHARED_FLASHES votes."""
    from flashsync.match import MAX_DRIFT, MIN_SHARED_FLASHES

    window = tolerance_ms + MAX_DRIFT * max(np.ptp(times_a), np.ptp(times_b))
    differences = np.sort(np.subtract.outer(times_a, times_b).ravel())
    votes = np.searchsorted(differences, differences + window) - np.searchsorted(differences, differences - window)
    chosen = []
    for index in np.argsort(-votes, kind="stable"):
        if votes[index] < MIN_SHARED_FLASHES or len(chosen) == n_candidates:
            break
        if all(abs(differences[index] - shift) > 2 * window for shift in chosen):
            chosen.append(differences[index])
    return np.array(chosen)


def test_candidate_shifts_are_those_of_counting_every_difference():
    """The compiled vote counts only bins near the fullest ones and still gives what counting
    every difference gives: shared flashes with drift and jitter, unrelated events, times on a
    1 ms grid (ties), unsorted times."""
    from flashsync.match import _candidate_shifts

    rng = np.random.default_rng(8)
    for _ in range(300):
        span = rng.choice([1500.0, 60_000.0, 600_000.0])
        shared = rng.uniform(0, span, rng.integers(0, 40))
        a = np.concatenate([rng.uniform(0, span, rng.integers(2, 60)), shared + rng.normal(0, 2, len(shared))])
        b = np.concatenate([rng.uniform(0, span, rng.integers(2, 60)), shared * (1 + 5e-5) + rng.uniform(-1e5, 1e5)])
        if rng.uniform() < 0.3:
            a, b = np.round(a), np.round(b)
        tolerance = rng.choice([5.0, 10.0, 40.0])
        assert np.array_equal(_candidate_shifts(a, b, tolerance, 8), counting_every_difference(a, b, tolerance))


def test_shared_flash_estimate_counts_event_pairs_one_shift_apart():
    """The most event pairs whose bin differences are two adjacent values, as counted pair by pair."""
    from flashsync.partners import occupied_bins, shared_flash_estimate

    rng = np.random.default_rng(9)
    for _ in range(200):
        a, b = (rng.uniform(0, rng.uniform(100, 60_000), rng.integers(1, 80)) for _ in range(2))
        bins_a, bins_b = occupied_bins(a, 25.0), occupied_bins(b, 25.0)
        differences = np.subtract.outer(bins_a, bins_b).ravel()
        counts = np.bincount(differences - differences.min(), minlength=2)
        assert shared_flash_estimate(bins_a, bins_b) == np.max(counts[:-1] + counts[1:])
    assert shared_flash_estimate(occupied_bins(np.zeros(0), 25.0), bins_b) == 0


def test_flashes_of_more_than_64_cameras_hold_one_event_per_camera():
    """70 cameras (a flash's cameras kept in two 64-bit words): event 0 chained through all,
    event 1 through c64-c69; a bad pair of c0's event 0 with c69's event 1 would put two
    events of c64-c69 (the second word only) into one flash, and is refused."""
    from flashsync.match import PairAlignment

    chain = {
        (f"c{c}", f"c{c + 1}"): PairAlignment(1.0, 0.0, np.array([[0, 0], [1, 1]] if c >= 64 else [[0, 0]]), 0.0, False)
        for c in range(69)
    }
    bad = {("c0", "c69"): PairAlignment(1.0, 0.0, np.array([[0, 1]]), 0.0, False)}
    groups = group_flashes({f"c{c}": 2 for c in range(70)}, {**chain, **bad})
    assert groups[("c0", 0)] == groups[("c69", 0)] != groups[("c64", 1)] == groups[("c69", 1)]
    assert ("c0", 1) not in groups and sorted(set(groups.values())) == [0, 1]
