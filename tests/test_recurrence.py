"""A flash happens once: the recurrence filter on hand-made bands."""

from flashsync.recurrence import RecurrenceFilter, Stripe


def run(bands_by_frame, candidates):
    """Feed bands frame by frame, hold ``candidates`` ({frame: [bands]}) when their last frame
    is reached; return the payloads released."""
    recurrence = RecurrenceFilter()
    released = []
    last = max(bands_by_frame)
    for frame in range(last + 1):
        for band in bands_by_frame.get(frame, []):
            recurrence.see(band)
        for bands in candidates.get(frame, []):
            recurrence.hold(bands, bands[0].level, bands[0].frame)
        released += recurrence.release(frame)
    return released + recurrence.release(), recurrence.dropped


def test_a_flash_keeps_its_weaker_echo_from_dropping_it_and_the_echo_goes():
    flash = Stripe(10, 100, 112, 0.30)
    echo = Stripe(11, 103, 110, 0.12)  # the B-frame next to it: the middle, weaker
    released, dropped = run({10: [flash], 11: [echo]}, {10: [[flash]], 11: [[echo]]})
    assert released == [10] and dropped == 1


def test_a_codec_ghost_chain_goes():
    flash = Stripe(40, 62, 72, 0.16)
    ghosts = [Stripe(frame, 62, 71, 0.045) for frame in (43, 46, 49, 52)]
    bands = {40: [flash], **{g.frame: [g] for g in ghosts}}
    released, dropped = run(bands, {40: [[flash]], **{g.frame: [[g]] for g in ghosts}})
    assert released == [40] and dropped == 4


def test_a_pattern_that_returns_to_the_same_rows_goes():
    repeats = [Stripe(frame, 226, 240, 0.035) for frame in (2, 5, 8, 11)]
    released, dropped = run({b.frame: [b] for b in repeats}, {b.frame: [[b]] for b in repeats})
    assert released == [] and dropped == 4


def test_flashes_a_few_frames_apart_at_overlapping_rows_are_kept():
    """Long exposures: bands of 90 rows, flashes six frames apart; the later band runs off
    the bottom of the frame (its end there is the frame's, not the band's)."""
    first = Stripe(10, 77, 175, 0.35)
    second = Stripe(16, 111, 180, 0.40, cut_stop=True)
    third = Stripe(22, 132, 180, 0.30, cut_stop=True)
    released, dropped = run({10: [first], 16: [second], 22: [third]}, {10: [[first]], 16: [[second]], 22: [[third]]})
    assert released == [10, 16, 22] and dropped == 0


def test_a_darkening_band_is_no_evidence_against_a_brightening_one():
    flash = Stripe(10, 100, 112, 0.30)
    shadow = Stripe(9, 100, 112, -0.40)
    released, _ = run({9: [shadow], 10: [flash]}, {10: [[flash]]})
    assert released == [10]


def test_unchecked_candidates_pass_and_keep_their_order():
    step = Stripe(5, 0, 240, 0.6, cut_start=True, cut_stop=True)
    again = Stripe(6, 0, 240, 0.6, cut_start=True, cut_stop=True)
    recurrence = RecurrenceFilter()
    recurrence.see(step)
    recurrence.see(again)
    recurrence.hold([step], 0.6, "on", checked=False)
    assert recurrence.release() == ["on"]
