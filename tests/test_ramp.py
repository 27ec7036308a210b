"""The flash ramp model and its fit, on synthetic ramps with a known edge and on one real
camera's bands (rig-415's cam1, fitted from its H.264 file)."""

from pathlib import Path

import numpy as np
import pytest
from scipy.stats import exponnorm

from flashsync.ramp import (
    BAND,
    MIN_DECAY,
    BandFit,
    _longest_minimum,
    _model,
    _ramp,
    common_width,
    fit_pulse_band,
    fit_pulse_edge,
)

CLIPS = Path(__file__).parent / "clips"
SCALE, PLATEAU = 2.9, 0.35  # decay length (rows) and band level of the test clips


@pytest.mark.parametrize("scale, blur", [(2.9, 0.5), (0.3, 2.0), (1.0, 0.01), (0.1, 3.0)])
def test_ramp_is_the_exponentially_modified_gaussian_distribution(scale, blur):
    z = np.linspace(-12.0, 25.0, 75)
    expected = exponnorm.cdf(z, scale / blur, scale=blur)
    assert np.allclose([_ramp(v, scale, blur) for v in z], expected, atol=1e-9)


def blurred_band(edge: float, blur: float, rising: bool = True, seed: int = 0) -> np.ndarray:
    """A band's relative change per row with its half point (before blur) at ``edge``: the
    exposures of the rows end (leading edge) or start (trailing) as the flash gives its light."""
    z = np.arange(120.0) - edge + SCALE * np.log(2.0)
    share = exponnorm.cdf(z, SCALE / blur, scale=blur) if blur else -np.expm1(-np.maximum(z, 0.0) / SCALE)
    values = PLATEAU * (share if rising else 1.0 - share)
    return values + np.random.default_rng(seed).normal(0.0, 0.002, z.size)


def half_crossing(values: np.ndarray, rising: bool) -> float:
    level = 0.5 * PLATEAU
    above = np.flatnonzero(values >= level)
    i = above[0] if rising else above[-1]
    j = i - 1 if rising else i + 1
    return j + (level - values[j]) / (values[i] - values[j]) * (i - j)


@pytest.mark.parametrize("rising", [True, False])
@pytest.mark.parametrize("blur", [0.0, 0.8, 1.5])
def test_fit_finds_the_edge_before_the_blur(rising, blur):
    """Blur (the codec's) moves the half point of the asymmetric ramp late by about
    blur^2 / (2 k) rows; the fit of the blurred model does not move."""
    edge = 60.37
    values = blurred_band(edge, blur, rising)
    crossing = half_crossing(values, rising)
    fitted = fit_pulse_edge(values, crossing, SCALE * np.log(3.0), PLATEAU, rising)
    assert abs(fitted - edge) < 0.03
    if blur >= 0.8:  # the plain crossing is off by more than 0.1 row
        assert abs(crossing - edge) > 0.1


def test_a_zeroed_foot_row_does_not_pull_the_edge_late():
    """The first lit row's neighbour, read as exactly 0 (dead zone), is left out."""
    edge = 60.37
    values = blurred_band(edge, 0.0)
    values[:60] = 0.0  # row 59 saw 20 % of the light, reads 0
    crossing = half_crossing(values, True)
    assert abs(fit_pulse_edge(values, crossing, SCALE * np.log(3.0), PLATEAU, True) - edge) < 0.05


def led_band(start: float, pulse: float, exposure: float, seed: int, noise: float = 0.002) -> np.ndarray:
    """Relative change per row of a band of a rectangular pulse of ``pulse`` rows seen with
    an exposure of ``exposure`` rows: the two rectangles convolved, blurred by 0.7 rows,
    with Gaussian noise of ``noise``."""
    x = np.arange(160.0)
    p = np.array([start, pulse, MIN_DECAY, 0.7, exposure, PLATEAU])
    values = np.array([_model(v, p, BAND) for v in x])
    return values + np.random.default_rng(seed).normal(0.0, noise, x.size)


def led_fits(pulses: list[float], exposure: float, noise: float = 0.002, first_seed: int = 0) -> list:
    """Each band fitted whole from its half-level crossings, as the detector does."""
    fits = []
    for seed, pulse in enumerate(pulses, start=first_seed):
        values = led_band(40.0, pulse, exposure, seed, noise)
        level = float(np.max(values))
        above = np.flatnonzero(values >= 0.5 * level)
        fits.append(fit_pulse_band(values, float(above[0]), float(above[-1]), 0.5 * min(pulse, exposure), level))
    return fits


def test_the_bands_of_pulses_that_outlast_the_exposure_tell_the_exposure():
    """A band alone reads the longer rectangle as the exposure: a 30-row pulse seen with a
    12-row exposure fits as a 30-row exposure. The pulses differ from flash to flash, the
    exposure does not: the camera's bands find 12 rows, and each band's refit with it puts
    its leading edge at the pulse's half-light row (start + pulse / 2)."""
    pulses = [20.0, 30.0, 42.0, 26.0, 36.0]
    fits = led_fits(pulses, 12.0)
    assert all(abs(fit.width - pulse) < 1.5 for fit, pulse in zip(fits, pulses))  # each alone: swapped
    width, longer, _ = common_width(fits)
    assert longer and abs(width - 12.0) < 0.5
    for fit, pulse in zip(fits, pulses):
        band, _ = fit.with_width(width, longer=True)
        assert abs(band.leading - (40.0 + 0.5 * pulse)) < 0.5


def test_one_pulse_length_or_a_longer_exposure_keeps_the_exposure_the_longer():
    """Pulses all of one length tell the two readings apart no better than one band: the
    longer stays the exposure; so it does where the exposure outlasts every pulse."""
    width, longer, _ = common_width(led_fits([30.0] * 5, 12.0))
    assert not longer and abs(width - 30.0) < 1.0
    width, longer, _ = common_width(led_fits([4.0, 9.0, 6.0, 12.0, 7.0], 25.0))
    assert not longer and abs(width - 25.0) < 0.5


def test_false_bands_do_not_make_pulses_of_one_length_outlast_the_exposure():
    """A 98-row exposure under pulses of 1.5-13 rows, four noisy bands, and two false narrow
    bands (7 and 23 rows, e.g. a moving object): their widths differ, and read with pulses
    longer than the exposure the narrow ones fit and every real band becomes a 98-row
    pulse. Pulses of one length are the exposure: the plain reading stays (a random rig's
    camera was read 10 rows so, its times 5 ms off)."""
    fits = (
        led_fits([13.0, 11.0, 10.0, 1.5], 98.0, noise=0.05, first_seed=10)
        + led_fits([1.0], 7.0, noise=0.05, first_seed=60)
        + led_fits([1.0], 23.0, noise=0.05, first_seed=61)
    )
    width, longer, _ = common_width(fits)
    assert not longer and abs(width - 98.0) < 1.0


@pytest.mark.parametrize(
    "pulses, exposure",
    [([4.3, 7.5, 34.4, 35.8, 39.6], 22.0), ([1.4, 1.6, 2.4, 2.4, 3.0, 7.0, 8.8, 9.0], 4.46)],
    ids=["most-outlast", "most-shorter"],
)
def test_pulses_shorter_and_longer_than_the_exposure_read_it_from_the_bands_one_exposure_long(pulses, exposure):
    """Some flashes shorter than the exposure, some longer (the pulses of two random rigs'
    LED cameras): a band is as long as the longer of its pulse and the exposure, so the
    bands of the shorter pulses are one exposure long and the others outlast it, and are
    refitted so. Before, the first was read plainly (22.0 rows, but no pulse found longer:
    three pulses of one length vetoed it; on the rig the plain reading was the three longer
    bands' 35 rows, its times 0.24 ms off), the second as an exposure of its 2.4-row pulses
    with every band outlasting it (2.2 rows for 4.46)."""
    width, longer, _ = common_width(led_fits(pulses, exposure))
    assert longer and abs(width - exposure) < 0.3


def test_an_exposure_every_pulse_outlasts_is_read_however_short():
    """A 4-row exposure under pulses of 8.5-14 rows: no band is as long as the exposure,
    each is as long as its pulse. Read plainly, the bands' lengths scatter; read the
    other way round, their ramps share 4 rows. Such a reading used to be refused under 8
    rows (it came out 8.7 rows, every pulse taken for the exposure)."""
    width, longer, _ = common_width(led_fits([9.0, 13.0, 10.5, 14.0, 8.5], 4.0))
    assert longer and abs(width - 4.0) < 0.5


def test_of_two_readings_nearly_as_good_the_longer_is_the_exposure():
    """The last local minimum within the limit: a shorter exposure blurred more mimics a
    longer one, never the other way round; a cost cut short (inf) is no minimum."""
    costs = np.array([5.0, 3.0, 9.0, 40.0, 20.0, 45.0, np.inf, 30.0, np.inf])
    assert _longest_minimum(costs, 3.0 + 50.0) == 7
    assert _longest_minimum(costs, 3.0 + 25.0) == 4
    assert _longest_minimum(costs, 3.0 + 10.0) == 1


def saved_band_fits(name: str) -> list[BandFit]:
    """A camera's bands as the detector fitted them whole, saved in ``tests/clips``: each
    band's rows ``x`` and changes ``y`` (concatenated, ``sizes`` long), parameters ``p`` and
    ``free``."""
    bands = np.load(CLIPS / name)
    ends = np.cumsum(bands["sizes"])
    return [
        BandFit(x, y, p, free)
        for x, y, p, free in zip(
            np.split(bands["x"], ends[:-1]), np.split(bands["y"], ends[:-1]), bands["p"], bands["free"]
        )
    ]


def test_a_short_exposure_only_one_band_asks_for_is_not_taken():
    """The ten bands of rig-415's cam1 as the detector fitted them whole from its H.264 file
    (sRGB, a 5.78-row exposure under rectangular pulses of 2.3-15.5 rows). The last, a faint
    band, was coded as one 8-row block, its rise one row high: read with it, pulses outlast a
    1.24-row exposure (the others' 5.8-row ramps blurred nearly fit that too, it fits
    nothing longer), and the camera's times came out 0.3 ms off. Read without the band that
    asks most for the short exposure, the rest find the exposure, and that is taken."""
    fits = saved_band_fits("rig415_cam1_bands.npz")
    width, longer, _ = common_width(fits)
    assert longer and abs(width - 5.78) < 0.3
    assert common_width(fits[:-1])[:2] == pytest.approx((width, True))


def test_a_short_exposure_two_bands_ask_for_is_taken():
    """The four bands of the second world's rig-4 cam1 (``random_rig(4, max_height=360,
    duration_ms=8000)``: gamma, crf 27, a 5.74-row exposure under rectangular pulses of 2.3-17
    rows) as the detector fitted them whole from its H.264 file. Pulses outlast a 6.5-row
    exposure at a cost of 31 against 146 for the plain reading; two bands ask for it. Without
    the one that asks most, the three left lack the evidence to find pulses longer at all:
    that is no reading of another exposure, and the short one stands (before, the camera, the
    rig's reference, was read 9.1 rows and every other camera's times 0.2 ms off)."""
    fits = saved_band_fits("rig4_cam1_bands.npz")
    width, longer, rival = common_width(fits)
    assert longer and abs(width - 5.74) < 1.0 and rival is None  # a reading taken leaves no rival


def test_a_reading_with_longer_pulses_that_explains_the_bands_better_but_not_by_enough_is_the_rival():
    """The four bands of rig-4's cam1 as ``bench_rigs.py --seeds 0:12`` renders it (540 rows
    at most, 12 s: gamma, crf 27, a 5.73-row exposure under rectangular pulses of 9.5-17.5
    rows), as the detector fitted them whole from its H.264 file: 13.8, 9.4, 16.9 and 9.8
    rows. With pulses longer than the exposure they cost 31 at best against 119 read
    plainly, but 84 at 7.3 rows, the longest that reading allows, holds charged: short of the
    lead of 50 a choice needs. The plain reading stands, 10.3 rows, and 7.3 is its rival."""
    width, longer, rival = common_width(saved_band_fits("rig4_540_cam1_bands.npz"))
    assert not longer and abs(width - 10.3) < 0.2 and abs(rival - 7.3) < 0.2, (width, rival)


def test_a_reading_with_longer_pulses_that_leaves_more_than_half_the_plain_cost_is_the_rival():
    """The five bands of auto-exposure rig-89's cam8 (``bench_rigs.py --seeds 84:92
    --exposure-changes 0.5``: linear, crf 19, a 15.2-row exposure under LED pulses of 0.9-2
    ms) as the detector fitted them whole from its H.264 file: 26.6-56.1 rows, each its
    pulse. They cost 302 read plainly (56 rows) and 157 with pulses longer than a 14.4-row
    exposure: better by the lead of 50 a choice needs but not to half, so the plain reading
    stands, and 14.4 rows is its rival (it had none: its exposure came out 1.14 ms long at
    2.5 sigmas)."""
    width, longer, rival = common_width(saved_band_fits("rig89_cam8_bands.npz"))
    assert not longer and abs(width - 56.0) < 0.5 and abs(rival - 15.2) < 1.5, (width, rival)


def test_a_band_that_cannot_measure_its_own_noise_does_not_choose_the_exposure():
    """The nine bands of the second world's rig-641 cam6 (``python benchmarks/bench_rigs.py
    --seeds 640:656 --max-height 360 --duration-s 8 --exposure-changes 0.5``: sRGB, crf 24, a
    steady 5.88-row exposure under rectangular pulses of 2.6-21 rows) as the detector fitted
    them whole from its H.264 file.
    One band has four rows of light and five parameters: its fit meets them exactly, so in
    units of its own noise every other width cost it the most a band counts, and it alone
    read the exposure as 1.5 rows (0.39 ms short, at 18σ). With the others' noise it counts
    as one band among nine."""
    fits = saved_band_fits("rig641_cam6_bands.npz")
    assert [fit.measures_noise for fit in fits] == [True] * 7 + [False, True]
    width, *_ = common_width(fits)
    assert abs(width - 5.88) < 0.3
