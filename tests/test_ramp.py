"""The flash ramp model and its fit, on synthetic ramps with a known edge."""

import numpy as np
import pytest
from scipy.stats import exponnorm

from flashsync.ramp import _ramp, fit_pulse_edge

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
