"""TTL flashes fire a weak pre-flash a few tens of ms before each flash. A camera that sees
the pre-flashes lines up with one that does not at two shifts, the pre-flash's delay apart,
with as many events each (or more at the wrong one where the first camera missed a few
flashes but saw their pre-flashes): the counts alone cannot tell them apart. Random rig 35
(`flashsync.simulation.rigs.random_rig`, 320x180, 25 and 59.94 fps, 12 flashes in 6 s) fired
as TTL flashes (`with_preflashes`: 60 ms early at 0.3 of the strength, cam2 blind to them).
"""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from test_pipeline_checks import clock_errors_ms

from flashsync import detect_videos, pipeline, synchronize
from flashsync.diagnose import diagnose
from flashsync.diagnose.measure import measure
from flashsync.errors import NotEnoughDataError
from flashsync.evaluate import camera_accuracy
from flashsync.match import align_pair, match_events
from flashsync.simulation import render_scenario
from flashsync.simulation.band_events import flash_instants_ms, seen_by, synthetic_events
from flashsync.simulation.rigs import random_rig, with_preflashes


def ttl_rig(jitter_ms: float, missed: tuple[int, ...] = (), share: float = 0.3):
    """Rig 35 with pre-flashes 60 ms early (delay std ``jitter_ms``, ``share`` of the flash's
    strength) that cam2 does not see, no flash missed at random, and cam1 missing the
    flashes ``missed`` (not their pre-flashes)."""
    rig = random_rig(35, max_height=180, duration_ms=6000.0)
    cam1, cam2 = (replace(c, miss_probability=0.0) for c in rig.cameras)
    rig = replace(rig, cameras=(replace(cam1, missed_flashes=missed), cam2), n_players=6)
    return with_preflashes(rig, 60.0, share, jitter_ms, blind=("cam2",))


def rendered(scenario, folder):
    truth = render_scenario(scenario, folder)
    return truth, [folder / truth.cameras[c.name].file for c in scenario.cameras]


@pytest.mark.parametrize("missed", [0, 4], ids=["as many events", "more at the wrong shift"])
def test_a_pair_that_lines_up_at_a_few_shifts_is_undecided_not_dropped(missed):
    """Times of a camera with pre-flashes 60 ms before 13 irregular flashes (``missed`` of
    the flashes not seen, their pre-flashes seen), and of one that saw the flashes only: two
    shifts line up 13 and 13 - ``missed`` events; the pair does not count but is
    :attr:`~flashsync.match.PairAlignment.undecided`, the other shift its one rival (13
    against 9 made the wrong shift count before: random rig 417 with pre-flashes). A
    strobe's regular flashes line up at many shifts: not undecided."""
    rng = np.random.default_rng(3)
    flashes = np.cumsum(rng.uniform(400.0, 900.0, 13))
    seen = np.delete(flashes, [2, 5, 8, 11][:missed])
    a = np.sort(np.concatenate([seen, flashes - 60.0]))
    alignment = align_pair(a, flashes + 5000.0, tolerance_ms=10.0)
    assert not alignment.convincing and alignment.undecided
    (rival,) = alignment.rivals
    assert sorted([alignment.beta, rival.beta]) == pytest.approx([-5060.0, -5000.0], abs=1.0)
    strobe = np.arange(10) * 500.0
    assert not align_pair(strobe, strobe + 5000.0, tolerance_ms=10.0).undecided


@pytest.mark.parametrize(
    "missed",
    [(), (2, 5, 7, 10), (0, 2, 3, 5, 7, 9, 10)],
    ids=["as many events", "more at the wrong shift", "far more at the wrong shift"],
)
def test_the_edges_fit_decides_the_shift_a_pre_flash_makes(tmp_path, missed):
    """A pre-flash delay that varies (1 ms std) leaves the wrong shift a loose fit: the
    solve takes the right one. With cam1 missing four flashes whose pre-flashes it saw, the
    wrong shift lines up 12 events against 8 (the other shift its rival, at least 0.6 as
    many: :data:`~flashsync.match.RIVAL_SHIFT_FRACTION`); the fit takes the other.
    Before, both were a 'chance coincidence' error. Missing seven, the wrong shift lines
    up 9 against 5 through a clock 577 ppm off whose rate it bends, and its edges alone
    led by 38: it was taken 60 ms off with no word (error/sigma 12.5), until the flashes'
    times were integrated out and the priors counted (``pipeline._shift_evidence``;
    random rig 414 so, 8 against 5, the same)."""
    scenario = ttl_rig(1.0, missed)
    truth, videos = rendered(scenario, tmp_path)
    model, report = synchronize(detect_videos(videos))
    table = camera_accuracy(model, truth)
    assert table["rms_ms"].max() < 0.2, table.to_string()
    assert not [w for w in report.warnings if "pre-flash" in w]


def test_a_constant_pre_flash_delay_is_said_in_sigma_and_an_anchor_settles_it(tmp_path, capsys):
    """Pre-flashes at exactly 60 ms and bright enough (0.6 of the flash) for cam1 to see
    every one: both shifts line up 12 events and explain the edges about as well (a lead of
    18, short of the 20 a choice needs; at 0.3 cam1 misses three pre-flashes and the right
    shift leads by 53). ``flashsync sync`` takes one, says in a warning that cam2 may be
    60 ms off and names ``--anchor``, and cam2's sigma holds the gap (error/sigma at most 1;
    leaving the pair out instead read cam2 upside down, 5.4 ms off with no word); with one
    flash named in both cameras the rig is solved right, with no such warning."""
    from flashsync.cli import main
    from flashsync.io.model_file import load_model

    scenario = ttl_rig(0.0, share=0.6)
    truth, videos = rendered(scenario, tmp_path)
    model_file = tmp_path / "sync.json"
    assert main(["sync", *map(str, videos), "-o", str(model_file)]) == 0
    (warning,) = [line for line in capsys.readouterr().err.splitlines() if "pre-flash" in line]
    assert "cam2.mp4" in warning and "--anchor" in warning and "may be off by up to 6" in warning, warning
    table = camera_accuracy(load_model(model_file), truth).set_index("camera")
    assert table.loc["cam2", "z_rms"] <= 1.0 and table.loc["cam2", "sigma_rms_ms"] > 30.0, table.to_string()

    first = 1  # the first flash's index among the pre-flashes and flashes (its pre-flash is 0)
    anchors = []
    for d in detect_videos(videos):
        frames = truth.cameras[d.camera].flashes_seen[first]
        (event,) = set(d.events.event[np.isin(d.events.frame, frames)].tolist())
        anchors.append(f"--anchor={d.camera}:{event}")
    assert main(["sync", *map(str, videos), "-o", str(model_file), *anchors]) == 0
    assert "pre-flash" not in capsys.readouterr().err
    table = camera_accuracy(load_model(model_file), truth)
    assert table["rms_ms"].max() < 0.2, table.to_string()


def test_a_constant_delay_that_favours_the_shift_of_more_events_is_said_in_sigma(tmp_path):
    """Pre-flashes at exactly 60 ms (0.6 of the flash, cam1 sees every one) and cam1
    missing four flashes whose pre-flashes it saw: the wrong shift lines up 12 events
    against 8 and fits them as tightly as the right one, the delay being constant. Counted
    edge by edge it led by 48, and cam2 was taken 60 ms off at error/sigma 378 with no word;
    with each flash's time integrated out (a flash's first edge only places it) it leads by
    9, short of the 20 a choice needs: the pair's other shift is its doubt, a warning names
    the pair and ``--anchor``, and cam2's sigma holds the gap. ``diagnose``, which pairs as
    ``sync`` did, has no pairing to build on and says so (before: "no camera shares at
    least 3 flashes with cam1")."""
    truth, videos = rendered(ttl_rig(0.0, (2, 5, 7, 10), share=0.6), tmp_path)
    detections = detect_videos(videos)
    model, report = synchronize(detections)
    (warning,) = [w for w in report.warnings if "pre-flash" in w]
    assert "cam2.mp4" in warning and "cam1 and cam2" in warning and "--anchor" in warning, warning
    table = camera_accuracy(model, truth).set_index("camera")
    assert table.loc["cam2", "z_rms"] <= 1.0 and table.loc["cam2", "sigma_rms_ms"] > 30.0, table.to_string()
    with pytest.raises(NotEnoughDataError, match=r"flashes of cam2 line up with cam1's at another shift .*--anchor"):
        diagnose(detections)


def test_an_undecided_pair_tied_by_a_pair_decided_after_it_is_left_out(monkeypatch):
    """cam1 blind to the pre-flashes, cam2 and cam3 not (times only, 13 irregular flashes):
    cam2 and cam3 line up at one shift, cam1 with each of them at two. Of cam1's two pairs
    the fit cannot decide the first it tries and decides the second: the first is left out
    (tied through the second and cam2-cam3), not counted at its shift of most events with
    its other shift as a doubt (random rig 415 with pre-flashes: five cameras' sigma 60 ms
    so, 0.3 ms off). The solves and the fit's decisions are stand-ins here."""

    rng = np.random.default_rng(5)
    flashes = np.cumsum(rng.uniform(400.0, 900.0, 13))
    with_pre = np.sort(np.concatenate([flashes, flashes - 60.0]))
    offset = {"cam1": 1000.0, "cam2": 3000.0, "cam3": 7000.0}
    times = {"cam1": flashes + offset["cam1"], "cam2": with_pre + offset["cam2"], "cam3": with_pre + offset["cam3"]}
    matching = match_events(times, tolerance_ms=10.0)
    assert set(matching.undecided) == {("cam1", "cam2"), ("cam1", "cam3")}
    assert list(matching.alignments) == [("cam2", "cam3")]

    def solved(m):
        return SimpleNamespace(connected=sorted(m.tied_to("cam1")), reference="cam1", alignments=m.alignments)

    asked = []

    def decided(trials):
        """Undecided the first time; then the trial at the pair's right shift."""
        (pair,) = [p for p, a in trials[0].alignments.items() if a is not trials[1].alignments[p]]
        asked.append(pair)
        right = offset[pair[0]] - offset[pair[1]]
        betas = [t.alignments[pair].beta for t in trials]
        return None if len(asked) == 1 else int(np.argmin(np.abs(np.subtract(betas, right))))

    doubts = []
    monkeypatch.setattr(pipeline, "_decided", decided)
    monkeypatch.setattr(pipeline, "_shift_doubts", lambda chosen, pairs: doubts.extend(pairs) or chosen)
    result = pipeline._shifts_by_fit(matching, {n: len(t) for n, t in times.items()}, solved, other_shifts=False)
    assert len(asked) == 2 and not doubts, (asked, doubts)
    assert asked[0] not in result.alignments
    assert result.alignments[asked[1]].beta == pytest.approx(offset["cam1"] - offset[asked[1][1]], abs=1.0)


@pytest.mark.parametrize("fit_decides", [True, False])
def test_a_left_out_pair_whose_events_the_solve_puts_apart_is_tried_alone(monkeypatch, fit_decides):
    """cam1 blind to the pre-flashes, cam2 not, cam3 seeing eight pre-flashes and three
    flashes (times only, 13 irregular flashes 60 ms after their pre-flashes): cam1 and cam3
    line up at the pre-flash's delay (eight events against three: it counts), cam2 and cam3
    at two shifts, eleven events at the true one. The fit decides cam1-cam2, which ties cam2
    to cam3 and leaves the pair out, though the solve puts the events it lines up 60 ms
    apart (random rig 143 of TTL flashes and fast readouts: cam6, tied to cam5's flashes by
    its own pre-flashes, 41.5 ms off at error/sigma 21). The pair at that shift, cam3 (fewer
    matched events) tied by it alone, replaces the solve where the fit decides so; where it
    cannot decide, the solve stands (no doubt: the shift of most events may be the
    pre-flash's). The solves, where they put a pair's events and the fit's decisions are
    stand-ins here."""

    rng = np.random.default_rng(5)
    flashes = np.cumsum(rng.uniform(400.0, 900.0, 13))
    offset = {"cam1": 1000.0, "cam2": 3000.0, "cam3": 7000.0}
    seen = {
        "cam1": flashes,
        "cam2": np.sort(np.concatenate([flashes, flashes - 60.0])),
        "cam3": np.sort(np.concatenate([flashes[:8] - 60.0, flashes[10:]])),
    }
    times = {name: seen[name] + offset[name] for name in seen}
    matching = match_events(times, tolerance_ms=10.0)
    assert list(matching.alignments) == [("cam1", "cam3")]
    assert set(matching.undecided) == {("cam1", "cam2"), ("cam2", "cam3")}

    def beta(alignments, a, b, via=True):
        """The shift ``alignments`` put between cameras a and b (through the third where not a pair)."""
        if (a, b) in alignments:
            return alignments[(a, b)].beta
        if (b, a) in alignments:
            return -alignments[(b, a)].beta
        (c,) = set(offset) - {a, b}
        return beta(alignments, a, c, False) + beta(alignments, c, b, False) if via else np.nan

    def right(trial, name):
        return abs(beta(trial.alignments, "cam1", name) - (offset["cam1"] - offset[name])) < 1.0

    def solved(m):
        matched = np.concatenate([np.repeat(pair, len(a.matches)) for pair, a in m.alignments.items()])
        tied = sorted(m.tied_to("cam1"))
        return SimpleNamespace(connected=tied, alignments=m.alignments, matches=SimpleNamespace(camera=matched))

    def decided(trials):
        """The trial that puts the camera tried right (cam2, then cam3), where one does; the
        left-out pair's only where the fit decides."""
        tried = "cam3" if ("cam2", "cam3") in trials[-1].alignments else "cam2"
        fits = [right(trial, tried) for trial in trials]
        return fits.index(True) if fits.count(True) == 1 and (tried == "cam2" or fit_decides) else None

    doubts = []
    monkeypatch.setattr(pipeline, "_decided", decided)
    monkeypatch.setattr(pipeline, "_shift_doubts", lambda chosen, pairs: doubts.extend(pairs) or chosen)
    monkeypatch.setattr(
        pipeline, "_apart_in_chosen_ms", lambda chosen, pair, a: abs(beta(chosen.alignments, *pair) - a.beta)
    )
    result = pipeline._shifts_by_fit(matching, {n: len(t) for n, t in times.items()}, solved, other_shifts=False)
    assert right(result, "cam2") and right(result, "cam3") == fit_decides, result.alignments
    assert (("cam1", "cam3") in result.alignments) != fit_decides
    assert not doubts, doubts


def test_a_shift_that_leaves_the_bright_events_unmatched_is_not_taken():
    """A camera that saw seven pre-flashes (faint: 0.3 of their flash) and four flashes, and
    one that saw all eight flashes only (random rig 455's reference and cam6): at the
    pre-flash's delay seven events line up, each flash of the second on a pre-flash of the
    first, against four at the true shift. By count the wrong shift is convincing (four is
    no rival of seven) and six cameras came out 59 ms off; but it leaves the first camera's
    bright events unmatched while matching its faint ones, as a camera never misses: given
    the events' strengths, the pair is aligned at the true shift."""
    rng = np.random.default_rng(5)
    flashes = np.cumsum(rng.uniform(400.0, 900.0, 8))
    pre, seen = [0, 1, 2, 4, 5, 6, 7], [1, 3, 5, 6]
    a = np.concatenate([flashes[pre] - 60.0, flashes[seen]])
    order = np.argsort(a)
    a, strength_a = a[order], np.concatenate([np.full(len(pre), 0.03), np.full(len(seen), 0.1)])[order]
    b, strength_b = flashes + 5000.0, np.full(len(flashes), 0.1)
    by_count = align_pair(a, b, tolerance_ms=10.0)
    assert by_count.convincing and by_count.beta == pytest.approx(-5060.0, abs=1.0)
    by_light = align_pair(a, b, tolerance_ms=10.0, strengths=(strength_a, strength_b))
    assert by_light.beta == pytest.approx(-5000.0, abs=1.0) and len(by_light.matches) == len(seen)


def test_two_bright_events_left_unmatched_do_not_set_a_shift_aside():
    """Two cameras that both saw seven pre-flashes (faint) and some flashes: the first two,
    the second four (random rig 817's cam2 and cam4 so). At the true shift nine events line
    up, most of them faint pre-flashes, and the second camera's two flashes the first missed
    are left unmatched: brighter than the matched median, but two flashes missed at random
    are no sign of a wrong shift (:data:`~flashsync.match.MIN_LEFT_EVENTS`). Set aside,
    the pair was aligned at the pre-flash's delay (four events here; six of rig 817's)."""
    rng = np.random.default_rng(7)
    flashes = np.cumsum(rng.uniform(400.0, 900.0, 8))

    def camera(seen: list[int], offset_ms: float) -> tuple[np.ndarray, np.ndarray]:
        times = np.concatenate([flashes[:7] - 60.0, flashes[seen]]) + offset_ms
        strengths = np.concatenate([np.full(7, 0.03), np.full(len(seen), 0.1)])
        order = np.argsort(times)
        return times[order], strengths[order]

    (a, strength_a), (b, strength_b) = camera([0, 1], 0.0), camera([0, 1, 2, 3], 5000.0)
    aligned = align_pair(a, b, tolerance_ms=10.0, strengths=(strength_a, strength_b))
    assert aligned.beta == pytest.approx(-5000.0, abs=1.0) and len(aligned.matches) == 9
    assert [other.beta for other in aligned.others] == [pytest.approx(-5060.0, abs=1.0)]


def test_a_shift_at_the_rigs_pre_flash_delay_is_a_rival_though_it_would_not_convince_alone():
    """x saw every pre-flash and flash, y every flash, w five flashes and then only the
    pre-flashes of three (random rig 817's cam2 so, against cam1). x and y line up at two
    shifts 60 ms apart: the rig's pre-flash delay. w and y line up five events at the true
    shift and three at that delay, too few to convince on their own (chance above
    :data:`~flashsync.match.MAX_CHANCE`): alone they count at the five; with x they are
    undecided, the three at the delay their rival, for the solve's fit to decide (rig 817's
    cam2 was otherwise tied at the delay, 60 ms off at error/sigma 16)."""
    rng = np.random.default_rng(3)
    flashes = np.cumsum(rng.uniform(400.0, 900.0, 10))
    x = np.sort(np.concatenate([flashes - 60.0, flashes]))
    y = flashes + 3000.0
    w = np.sort(np.concatenate([flashes[:5], flashes[5:8] - 60.0])) - 2000.0
    alone = match_events({"y": y, "w": w}, tolerance_ms=10.0)
    assert ("y", "w") in alone.alignments and not alone.undecided
    assert alone.alignments[("y", "w")].beta == pytest.approx(5000.0, abs=1.0)
    rig = match_events({"x": x, "y": y, "w": w}, tolerance_ms=10.0)
    assert ("y", "w") not in rig.alignments
    pair = rig.undecided[("y", "w")]
    assert pair.beta == pytest.approx(5000.0, abs=1.0)
    assert [rival.beta for rival in pair.rivals] == [pytest.approx(5060.0, abs=1.0)]


@pytest.mark.parametrize(
    "missed", [(2, 5, 7, 10), (0, 2, 3, 5, 7, 9, 10)], ids=["more at the wrong shift", "far more at the wrong shift"]
)
def test_diagnose_pairs_each_band_with_its_own_flash(tmp_path, missed):
    """Where ``sync`` cannot solve the videos, ``flashsync diagnose`` pairs the bands itself
    (:func:`~flashsync.diagnose.measure.measure` without ``sync``'s model), by their times
    and strengths, as ``sync``'s matcher does (a camera misses faint flashes, not bright
    ones). cam1 saw the faint pre-flashes
    and missed ``missed`` of the flashes; every flash of the workflow's measurement holds
    bands of one true flash (by the frames that saw it). Before, the workflow paired by
    count alone: with four missed the shifts' rivalry left cam1 and cam2 unpaired
    ("no camera shares at least 3 flashes"); with seven it lined cam1's pre-flashes up with
    cam2's flashes, 60 ms off (random rig 455 so: a verdict of χ² 417642 over 76 degrees of
    freedom, the workflow's own pairing wrong, not the model)."""
    truth, videos = rendered(ttl_rig(1.0, missed), tmp_path)
    assert_one_true_flash_each(measure(detect_videos(videos)), truth, at_least=5)


def test_diagnose_takes_the_pairing_sync_decided(tmp_path):
    """Random rig 414 fired by TTL flashes (pre-flashes 60 ms early, cam2 blind to them,
    cam1 missing flashes whose pre-flashes it saw): by their times alone the two cameras
    line up five bands at the true shift at a chance of 1.09e-3, over the matcher's 1e-3,
    and the workflow's own pairing refused the rig ("no camera shares at least 3 flashes
    with cam1"), though ``sync`` pairs them (its fit of the edges decides the pre-flash's
    shift) and solves them to 0.1 ms. ``diagnose`` takes ``sync``'s pairing: every flash of
    its measurement holds bands of one true flash (two flashes left clean bands in both
    cameras), and it diagnoses the rig."""
    rig = random_rig(414, max_height=360, duration_ms=8000.0)
    truth, videos = rendered(with_preflashes(rig, 60.0, jitter_ms=1.0, seed=rig.seed), tmp_path)
    detections = detect_videos(videos)
    model, _ = synchronize(detections)
    assert_one_true_flash_each(measure(detections, paired_by=model), truth, at_least=2)
    found = diagnose(detections)
    assert camera_accuracy(found.sync_model, truth)["rms_ms"].max() < 0.2


def assert_one_true_flash_each(measurement, truth, at_least: int) -> None:
    """Every flash of ``measurement`` holds bands of one true flash (by the frames that saw
    it), and there are ``at_least`` of them."""
    edges = measurement.edges
    for flash in np.unique(edges.flash):
        at = edges.flash == flash
        seen_by = [
            {k for k, frames in truth.cameras[measurement.cameras[c].camera].flashes_seen.items() if f in frames}
            for c, f in zip(edges.camera[at], edges.frame[at])
        ]
        assert set.intersection(*seen_by), (flash, seen_by)
    assert len(np.unique(edges.flash)) >= at_least


@pytest.mark.parametrize(
    "pre_flashes, flashes_seen, instead, doubted",
    [
        pytest.param(range(12), (0, 1), (), True, id="its pre-flashes"),
        pytest.param((0, 1), range(12), (), False, id="its flashes"),
        pytest.param(range(12), range(12), (3,), False, id="one pre-flash for its flash"),
    ],
)
def test_flashes_matched_only_to_the_first_of_a_cameras_bursts_are_in_doubt_by_their_gap(
    pre_flashes, flashes_seen, instead, doubted
):
    """Two synthetic cameras (1080 rows) and twelve TTL flashes, each with a pre-flash 40 ms
    before it; cam1 sees every flash and no pre-flash. Where cam0 sees every pre-flash but
    only two of the flashes (the others fall where it does not look: random rig 125 of a
    mixed bench, its cam2 so, 40 ms off at error/sigma 29 with no word), twelve events line
    up at the pre-flash's delay and two at the true shift: cam1 is matched to cam0's
    pre-flashes, each followed 40 ms later by a flash cam1 does not see, its times 40 ms
    off. Its sigma takes the 40 ms and a warning names the pair. Not where cam1 is matched
    to cam0's flashes (the second of each pair): cam0 sees every flash and two pre-flashes;
    or both, and cam1 sees one pre-flash instead of its flash (matched to the first of
    cam0's pair there, and to the second everywhere else)."""
    events, truth, frame_times = synthetic_events(2, 12, seed=4)
    instants = flash_instants_ms(events, truth)
    seen = np.concatenate([instants[list(pre_flashes)] - 40.0, instants[list(flashes_seen)]])
    cam0 = seen_by("cam0", seen, truth[0], frame_times[0])
    instants[list(instead)] -= 40.0
    cam1 = seen_by("cam1", instants, truth[1], frame_times[1])
    model, report = synchronize([cam0, cam1])
    error, sigma = clock_errors_ms(model, truth, frame_times, 1)
    warned = [
        w
        for w in report.warnings
        if w.startswith("cam1.mp4: the flashes that tie cam1 to the rest of the rig match only")
    ]
    assert bool(warned) == doubted, report.warnings
    if doubted:
        assert np.abs(error).mean() == pytest.approx(40.0, abs=1.0), error  # the premise: the pre-flashes' shift
        assert np.sqrt(np.mean((error / sigma) ** 2)) < 1.5, (error, sigma)
    else:
        assert np.abs(error).max() < 0.1 and sigma.max() < 1.0, (error, sigma)


def test_a_group_of_cameras_tied_to_the_rest_only_by_the_first_of_their_bursts_is_in_doubt():
    """Five synthetic cameras (1080 rows) and twelve TTL flashes, each with a pre-flash 40 ms
    before it. cam0 (the reference) and cam1 see every flash and no pre-flash; cam2 and cam3
    see every pre-flash but only two of the flashes; cam4 sees those two flashes and three
    pre-flashes, none with its flash (random rig 152 of a bench of all four departures at
    once: its four cameras that saw pre-flashes were 40 ms off at error/sigma 43-57 with no
    word). cam2-cam4 are matched by their pre-flashes to the flashes of cam0 and cam1, 40 ms
    off, and to each other rightly. Each pair of cam2 or cam3 with cam0 or cam1 rests on
    flashes matched at the first of its bursts, but each of them is tied by the other, which
    kept the doubt off both; cam4's pairs with cam0 and cam1 are three lone events each.
    cam2-cam4 are one group (the seconds of cam2's bursts are cam4's first two flashes), tied
    to cam0 and to cam1 by the firsts of four bursts against three lone events: each of the
    three takes the 40 ms in its sigma, with a warning; cam1 keeps its sigma."""
    events, truth, frame_times = synthetic_events(5, 12, seed=4)
    instants = flash_instants_ms(events, truth)
    seen = [instants, instants, *[np.concatenate([instants - 40.0, instants[:2]])] * 2, instants[[0, 1, 5, 6, 7]]]
    seen[4][2:] -= 40.0
    cameras = [seen_by(f"cam{c}", instants_ms, truth[c], frame_times[c]) for c, instants_ms in enumerate(seen)]
    model, report = synchronize(cameras)
    for c in (2, 3, 4):
        error, sigma = clock_errors_ms(model, truth, frame_times, c)
        (warning,) = [
            w for w in report.warnings if w.startswith(f"cam{c}.mp4: the flashes that tie cam2, cam3, cam4 to")
        ]
        assert "its times may be off by 40 ms" in warning
        assert np.abs(error).mean() == pytest.approx(40.0, abs=1.0), error  # the premise: the pre-flashes' shift
        assert np.sqrt(np.mean((error / sigma) ** 2)) < 1.5, (error, sigma)
    error, sigma = clock_errors_ms(model, truth, frame_times, 1)
    assert np.abs(error).max() < 0.1 and sigma.max() < 1.0, (error, sigma)
    assert not [w for w in report.warnings if w.startswith(("cam0.mp4", "cam1.mp4")) and "pre-flash" in w]


def test_a_reference_that_sees_pre_flashes_alone_ties_no_group_by_them():
    """Five synthetic cameras (1080 rows) and twelve TTL flashes, each with a pre-flash 40 ms
    before it. cam0 (the reference) sees flash 0 and the pre-flashes of flashes 2-11 alone
    (their flashes fall where it does not look); cam1 the same pre-flashes and, after two of
    them, their flashes; cam2-cam4 every flash (random rig 185 of a bench of all four
    departures at once: six cameras 37-39 ms off at error/sigma 15-21 with no word, and the
    one warned was right). cam0 and cam1 are matched by their pre-flashes to the others'
    flashes, 40 ms off. cam0's lone events tied cam2-cam4 to it: the doubt fell on cam1
    alone. But cam0 is matched to the firsts of cam1's bursts, and its flash 0 lies 40 ms
    after the others': it is a delay off them, its lone events tie nothing, and cam2-cam4
    take the 40 ms in their sigma, warned. (Where the reference's side is right, it has no
    such band and keeps its ties: the rig-152 test above.)"""
    events, truth, frame_times = synthetic_events(5, 12, seed=4)
    instants = flash_instants_ms(events, truth)
    pre_flashes = instants[2:] - 40.0
    seen = [np.concatenate([instants[:1], pre_flashes]), np.concatenate([pre_flashes, instants[[3, 7]]])]
    seen += [instants] * 3
    model, report = synchronize([seen_by(f"cam{c}", s, truth[c], frame_times[c]) for c, s in enumerate(seen)])
    for c in (2, 3, 4):
        error, sigma = clock_errors_ms(model, truth, frame_times, c)
        assert [w for w in report.warnings if w.startswith(f"cam{c}.mp4: the flashes that tie ")]
        assert np.abs(error).mean() == pytest.approx(40.0, abs=1.0), error  # the premise: the pre-flashes' shift
        assert np.sqrt(np.mean((error / sigma) ** 2)) < 1.5, (error, sigma)
    error, _ = clock_errors_ms(model, truth, frame_times, 1)
    assert np.abs(error).max() < 0.1, error


@pytest.mark.parametrize("false_event", [False, True], ids=["a lone pre-flash", "and a false event"])
def test_a_camera_that_sees_bursts_is_not_tied_by_its_lone_events_nor_a_false_burst(false_event):
    """Three synthetic cameras (1080 rows) and twelve TTL flashes, each with a pre-flash 40 ms
    before it. cam0 (the reference) sees every flash; cam1 every pre-flash and two of the
    flashes, matched by its pre-flashes to cam0's flashes, 40 ms off; cam2 every flash and
    one pre-flash, read right (random rig 147 of a bench of all four departures at once: its
    cam8, which saw bursts, 40 ms off at error/sigma 30 with no word). cam1's pre-flash whose
    flash it missed meets cam2's flash at the second of cam2's one burst: a camera that sees
    bursts may see a pre-flash alone as well as a flash, so that ties nothing (it tied cam1
    to cam2). With a false event of cam1's 20 ms before one of its pre-flashes, that
    pre-flash is the second of a burst and meets cam0's flash: a burst of another gap than
    the rig's 40 ms is no TTL flash's and ties nothing either (it tied cam1 to cam0). cam1
    takes the 40 ms in its sigma, warned; cam2 keeps its own."""
    events, truth, frame_times = synthetic_events(3, 12, seed=4)
    instants = flash_instants_ms(events, truth)
    bursts = np.concatenate([instants - 40.0, instants[:2], instants[5:6] - 60.0 if false_event else []])
    seen = [instants, bursts, np.concatenate([instants, instants[3:4] - 40.0])]
    model, report = synchronize([seen_by(f"cam{c}", s, truth[c], frame_times[c]) for c, s in enumerate(seen)])
    error, sigma = clock_errors_ms(model, truth, frame_times, 1)
    (warning,) = [w for w in report.warnings if w.startswith("cam1.mp4: the flashes that tie cam1 to the rest")]
    assert "its times may be off by 40 ms" in warning
    assert np.abs(error).mean() == pytest.approx(40.0, abs=1.0), error  # the premise: the pre-flashes' shift
    assert np.sqrt(np.mean((error / sigma) ** 2)) < 1.5, (error, sigma)
    error, sigma = clock_errors_ms(model, truth, frame_times, 2)
    assert np.abs(error).max() < 0.1 and sigma.max() < 1.0, (error, sigma)


def test_a_false_burst_of_another_gap_makes_no_camera_one_that_sees_bursts():
    """Three synthetic cameras (1080 rows) and twelve TTL flashes, each with a pre-flash 40 ms
    before it. cam0 (the reference) sees every pre-flash and flashes 0 and 1; cam1 and cam2
    see every flash and no pre-flash, and cam2 two false events too, 80 ms after flash 3 and
    125 ms after flash 6 (TT9's rig-1141: its cam3 had two such bursts among the TTL ones
    of 39-41 ms, and it and two more were 38.7 ms off at error/sigma 32-33 with no word).
    cam1 and cam2 are matched by their flashes to cam0's pre-flashes, 40 ms off. cam2's
    false bursts made it a camera that sees bursts: its flashes at cam0's firsts counted
    for neither side, and its flash 6, the first of its own burst, met cam0's first and tied
    it to cam0. Bursts off the rig's delay are no TTL flash's: cam1 and cam2 are one group,
    both take the 40 ms in their sigma, warned."""
    events, truth, frame_times = synthetic_events(3, 12, seed=4)
    instants = flash_instants_ms(events, truth)
    seen = [np.r_[instants - 40.0, instants[:2]], instants, np.r_[instants, instants[3] + 80.0, instants[6] + 125.0]]
    model, report = synchronize([seen_by(f"cam{c}", s, truth[c], frame_times[c]) for c, s in enumerate(seen)])
    for c in (1, 2):
        error, sigma = clock_errors_ms(model, truth, frame_times, c)
        (warning,) = [w for w in report.warnings if w.startswith(f"cam{c}.mp4: the flashes that tie cam1, cam2 to")]
        assert "its times may be off by 40 ms" in warning
        assert np.abs(error).mean() == pytest.approx(40.0, abs=1.0), error  # the premise: the pre-flashes' shift
        assert np.sqrt(np.mean((error / sigma) ** 2)) < 1.5, (error, sigma)


def test_a_camera_tied_by_one_burst_whose_band_lies_a_delay_after_a_flash_is_in_doubt():
    """Three synthetic cameras (1080 rows) and twelve TTL flashes, each with a pre-flash 40 ms
    before it. cam0 (the reference) and cam2 see every flash; cam1 the pre-flash and the
    flash of flash 0, the pre-flashes of flashes 2-10 alone and flash 11 alone (random rig
    911 of a bench of TTL flashes, fast readouts and auto exposure, ``--seeds 910:920
    --preflash 30 --readout 0.5:0.9 --exposure-changes 0.5``: its cam5 and cam6 so, 30 ms
    off at error/sigma 28-29 with no word once a codec-drawn edge of the reference is left
    out). cam1 is matched by its pre-flashes to the others' flashes, 40 ms off: ten events
    against two at the true shift. One burst ties it (a false event next to a flash makes
    one: two are asked), but its flash 11 then lies 40 ms after the others' flash 11, where
    nothing fires: cam1 takes the 40 ms in its sigma, warned; cam2 keeps its own."""
    events, truth, frame_times = synthetic_events(3, 12, seed=4)
    instants = flash_instants_ms(events, truth)
    burst_and_lone = np.concatenate([instants[:1] - 40.0, instants[:1], instants[2:11] - 40.0, instants[11:]])
    seen = [instants, burst_and_lone, instants]
    model, report = synchronize([seen_by(f"cam{c}", s, truth[c], frame_times[c]) for c, s in enumerate(seen)])
    error, sigma = clock_errors_ms(model, truth, frame_times, 1)
    (warning,) = [w for w in report.warnings if w.startswith("cam1.mp4: the flashes that tie cam1 to the rest")]
    assert "a band of its lies that long after a flash the others saw" in warning
    assert "its times may be off by 40 ms" in warning
    assert np.abs(error).mean() == pytest.approx(40.0, abs=1.0), error  # the premise: the pre-flashes' shift
    assert np.sqrt(np.mean((error / sigma) ** 2)) < 1.5, (error, sigma)
    error, sigma = clock_errors_ms(model, truth, frame_times, 2)
    assert np.abs(error).max() < 0.1 and sigma.max() < 1.0, (error, sigma)


def tied_by_pre_flashes_alone():
    """Four synthetic cameras (1080 rows) and twelve TTL flashes, each with a pre-flash 40 ms
    before it: cam0 (the reference) and cam2 see every flash; cam1 the pre-flashes of flashes
    2-9, flashes 0 and 11 alone and three more flashes that only cam3 sees too. Returns the
    events of each camera as :func:`seen_by` takes them, the truth and the frame times."""
    events, truth, frame_times = synthetic_events(4, 12, seed=4)
    instants = flash_instants_ms(events, truth)
    theirs = instants[1] + np.array([5000.0, 12000.0, 21000.0])
    cam1 = np.concatenate([instants[[0, 11]], instants[2:10] - 40.0, theirs])
    return [instants, cam1, instants, theirs], truth, frame_times


def test_a_camera_tied_by_pre_flashes_alone_whose_flashes_lie_a_delay_after_the_others_is_in_doubt():
    """The rig of :func:`tied_by_pre_flashes_alone` (random rig 182 of a bench of TTL flashes,
    fast readouts, two powers and auto exposure: its cam8, three pre-flashes and two flashes,
    38 ms off at error/sigma 4.2 with no word). No camera sees a burst, so nothing shows the
    rig's delay, and cam1 is matched by its pre-flashes to the others' flashes, 40 ms off:
    eight events against two at the true shift. Its flashes 0 and 11 then lie 40 ms after
    the others', where nothing fires: cam1 takes the 40 ms in its sigma, warned, and so does
    cam3, tied to the rest through cam1; cam2 keeps its own."""
    seen, truth, frame_times = tied_by_pre_flashes_alone()
    model, report = synchronize([seen_by(f"cam{c}", s, truth[c], frame_times[c]) for c, s in enumerate(seen)])
    (warning,) = [w for w in report.warnings if w.startswith("cam1.mp4: 2 of its bands matched to no flash lie 40 ms")]
    assert "its times may be off by 40 ms" in warning
    (warning,) = [w for w in report.warnings if w.startswith("cam3.mp4: tied through cam1, 2 of whose bands")]
    assert "its times may be off by 40 ms" in warning
    for c in (1, 3):
        error, sigma = clock_errors_ms(model, truth, frame_times, c)
        assert np.abs(error).mean() == pytest.approx(40.0, abs=1.0), error  # the premise: the pre-flashes' shift
        assert np.sqrt(np.mean((error / sigma) ** 2)) < 1.5, (error, sigma)
    error, sigma = clock_errors_ms(model, truth, frame_times, 2)
    assert np.abs(error).max() < 0.1 and sigma.max() < 1.0, (error, sigma)
    assert not [w for w in report.warnings if w.startswith(("cam0.mp4", "cam2.mp4")) and "nothing fires" in w]


def test_bands_next_to_a_flash_the_others_saw_are_no_doubt_though_a_delay_after_another(monkeypatch):
    """The rig of :func:`tied_by_pre_flashes_alone`, where the others also saw a flash 5 ms
    before each of cam1's two bands that lie 40 ms after a flash of theirs (random rig 154
    of a bench of TTL flashes: its cam3's flashes left unmatched 44-47 ms after the
    pre-flashes the others saw, and 5 ms from those flashes): such a band may be that
    flash, unmatched, so it tells no delay, and no doubt is raised."""
    gaps_after_flashes = pipeline._gaps_after_flashes

    def next_to_a_flash(best, model, flashes):
        gaps = gaps_after_flashes(best, model, flashes)
        return gaps + [(name, event, gap - 35.0) for name, event, gap in gaps if abs(gap - 40.0) < 1.0]

    monkeypatch.setattr(pipeline, "_gaps_after_flashes", next_to_a_flash)
    seen, truth, frame_times = tied_by_pre_flashes_alone()
    _, report = synchronize([seen_by(f"cam{c}", s, truth[c], frame_times[c]) for c, s in enumerate(seen)])
    assert not [w for w in report.warnings if "nothing fires" in w], report.warnings


def test_a_tie_at_a_bursts_second_is_outweighed_where_flashes_meet_more_of_their_firsts():
    """Two synthetic cameras (1080 rows) and twelve TTL flashes, each with a pre-flash 40 ms
    before it at 0.3 of its strength. cam0 (the reference) sees every pre-flash and flashes
    0-4; cam1, blind to the pre-flashes, misses flashes 0 and 5-9 and has a band as bright as
    its flashes 40 ms after flash 0. cam1 is matched by its six flashes to cam0's
    pre-flashes, 40 ms off, four of them the first of a burst, and by that band to cam0's
    flash 0, the second of one: one tie against four (FP8's rig-1135, two cameras read the
    wrong way up, whose solve matched four of cam1's pre-flashes and one flash to cam2's
    flashes: 14.8 ms off at error/sigma 63 with no word). cam1's events there are as bright
    as its others, flashes (:func:`~flashsync.pipeline._flashes_at_firsts`, below): the one
    tie is outweighed, and cam1 takes the 40 ms in its sigma, warned."""
    events, truth, frame_times = synthetic_events(2, 12, seed=4)
    instants = flash_instants_ms(events, truth)
    cam0 = np.concatenate([instants - 40.0, instants[:5]])
    cam1 = np.concatenate([instants[1:5], instants[10:], instants[:1] + 40.0])
    cameras = [
        seen_by("cam0", cam0, truth[0], frame_times[0], strength=np.r_[np.tile([0.15, 0.5], 5), [0.15] * 7]),
        seen_by("cam1", cam1, truth[1], frame_times[1]),
    ]
    model, report = synchronize(cameras)
    error, sigma = clock_errors_ms(model, truth, frame_times, 1)
    (warning,) = [w for w in report.warnings if w.startswith("cam1.mp4: the flashes that tie cam1 to the rest of")]
    assert "match the first (at 4; at 1 the second)" in warning and "its times may be off by 40 ms" in warning
    assert np.abs(error).mean() == pytest.approx(40.0, abs=1.0), error  # the premise: the pre-flashes' shift
    assert np.sqrt(np.mean((error / sigma) ** 2)) < 1.5, (error, sigma)


@pytest.mark.parametrize(
    "firsts, at_them, told",
    [
        pytest.param(0.15, 0.5, True, id="flashes at pre-flashes"),
        pytest.param(0.15, 0.15, False, id="pre-flashes alone at pre-flashes"),
        pytest.param(0.5, 0.6, False, id="bursts of two flashes"),
    ],
)
def test_events_at_the_first_of_bursts_are_flashes_where_as_bright_as_their_cameras_others(firsts, at_them, told):
    """cam0 sees twelve bursts (its firsts at strength ``firsts``, its seconds at 0.5); cam1's
    events 0-5 are matched to the first of six of them, its events 6-11 elsewhere, at 0.5.
    cam1's matched events are its flashes where they are as bright as its others while
    cam0's firsts are faint (pre-flashes): not where they are faint too (pre-flashes whose
    flashes cam1 missed: rig-128's cam10 and cam11 of a TTL bench with fast readouts, read
    right, were doubted at 39.5 ms by a first draft that counted ties alone), nor where
    cam0's firsts are as bright as its seconds (no pre-flash to mistake a flash for)."""
    events, truth, frame_times = synthetic_events(2, 12, seed=4)
    instants = flash_instants_ms(events, truth)
    cameras = {
        "cam0": seen_by(
            "cam0", np.r_[instants - 40.0, instants], truth[0], frame_times[0], strength=[firsts, 0.5] * 12
        ),
        "cam1": seen_by("cam1", instants, truth[1], frame_times[1], strength=np.r_[[at_them] * 6, [0.5] * 6]),
    }
    best = SimpleNamespace(connected=list(cameras), cameras=cameras)
    followed = {("cam0", 2 * k): 40.0 for k in range(12)}
    following = {("cam0", 2 * k + 1): 40.0 for k in range(12)}
    at_firsts = {frozenset(cameras): [("cam1", k) for k in range(6)]}
    assert bool(pipeline._flashes_at_firsts(best, followed, following, at_firsts)) == told
