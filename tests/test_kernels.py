"""No band can stop a run: the compiled fitters and kernels on whatever a video can hand them.

Property-based (hypothesis): constant rows, one to three points, NaN and infinity, clipped
(saturated) plateaus, ramps the wrong way round, a zero or negative level, empty and
single-row profiles. Nothing raises (numba's default error model raises
ZeroDivisionError on a float division by zero: a band whose plateau was 0 stopped a
15-minute run); every answer is finite or says it is not one.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from flashsync.compiled import cholesky_solve
from flashsync.detect import EventDetector, _median5, _median_in_place, _relative_change
from flashsync.flicker import (
    FlickerRemover,
    _basis,
    _fit_frame,
    _row_log_ratio,
    _row_pattern,
    _update_mean,
)
from flashsync.ramp import (
    BAND,
    FALLING,
    MAX_BLUR,
    MIN_DECAY,
    N_PARAMETERS,
    RISING,
    _fit,
    common_width,
    fit_pulse_band,
    fit_pulse_edge,
)

FAST = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
anything = st.floats(allow_nan=True, allow_infinity=True, width=32)
plain = st.floats(-2.0, 2.0, allow_nan=False, width=32)


def values(n_min=0, n_max=40, elements=anything):
    return st.integers(n_min, n_max).flatmap(lambda n: arrays(np.float64, n, elements=elements))


@st.composite
def ramps(draw):
    """A band edge as the detector hands it over: an exponential ramp to a plateau, rising or
    falling, maybe reversed, clipped, constant, with NaN rows, or a zero level."""
    n = draw(st.integers(0, 60))
    x = np.arange(n, dtype=np.float64)
    kind = draw(st.sampled_from(["ramp", "reversed", "clipped", "constant", "zero", "noise"]))
    edge, scale = draw(st.floats(-5, 65)), draw(st.floats(0.05, 60))
    level = draw(st.sampled_from([0.0, -0.2, 1e-9, 0.3, 5.0]))
    share = -np.expm1(-np.maximum(x - edge, 0.0) / scale)
    y = {
        "ramp": level * share,
        "reversed": level * share[::-1],
        "clipped": np.minimum(level * share, 0.5 * level),
        "constant": np.full(n, level),
        "zero": np.zeros(n),
        "noise": draw(arrays(np.float64, n, elements=plain)),
    }[kind]
    if n and draw(st.booleans()):
        y[draw(st.integers(0, n - 1))] = np.nan
    return x, y, level


@FAST
@given(ramps(), st.sampled_from([BAND, RISING, FALLING]), st.floats(-1.0, 1.0), st.floats(0.0, 30.0))
def test_band_fit_never_raises_and_stays_in_bounds(ramp, mode, f_scale, width):
    x, y, level = ramp
    p0 = np.array([x.mean() if x.size else 0.0, 1.0, 2.0, 0.3, width, level])
    p, converged = _fit(x, y, p0, np.ones(N_PARAMETERS, dtype=np.bool_), f_scale, mode)
    assert p.shape == (N_PARAMETERS,)
    if converged:
        assert np.all(np.isfinite(p))
        assert p[1] >= 0.0 and p[2] >= MIN_DECAY and 0.0 <= p[3] <= MAX_BLUR and p[4] >= 0.0


@FAST
@given(ramps(), st.floats(-10, 70) | st.just(np.nan), st.floats(-1, 20) | st.just(np.nan), st.booleans())
def test_pulse_edge_is_a_row_near_the_guess_or_nan(ramp, row, rise, rising):
    _, y, level = ramp
    edge = fit_pulse_edge(y, row, rise, level, rising)
    if np.isfinite(edge):
        assert abs(edge - row) <= 2.0 + 1e-9
    else:
        assert not (np.isfinite(row) and np.isfinite(rise) and level > 0)


@FAST
@given(ramps(), st.floats(-10, 70) | st.just(np.nan), st.floats(-5, 40), st.floats(-1, 20) | st.just(np.nan))
def test_pulse_band_is_two_ordered_rows_near_the_guesses_or_none(ramp, leading, width, rise):
    _, y, level = ramp
    fit = fit_pulse_band(y, leading, leading + width, rise, level)
    if fit is not None:
        assert np.isfinite(fit.leading) and fit.leading <= fit.trailing
        assert abs(fit.leading - leading) <= 2.0 + 2.0 * max(rise / np.log(3.0), 0.3) + 1e-9
        assert common_width([fit] * 3) is not None or fit.width <= 0


@FAST
@given(arrays(np.float64, (4, 4), elements=anything), arrays(np.float64, 4, elements=anything))
def test_the_small_solver_answers_or_gives_up(a, b):
    a = a @ a.T if np.all(np.isfinite(a)) else a
    solved, ok = cholesky_solve(a, b)
    assert solved.shape == (4,)
    if ok:
        assert np.all(np.isfinite(solved))


@FAST
@given(values(1, 9, plain))
def test_medians_are_medians(v):
    assert _median_in_place(v.copy(), len(v)) == pytest.approx(np.median(v))
    if len(v) >= 5:
        assert _median5(*v[:5]) == pytest.approx(np.median(v[:5]))


@st.composite
def profile_stacks(draw):
    """A baseline history (k, height, blocks) and a current profile: any values, dark, lit,
    clipped, NaN, a single row or block."""
    k, height, blocks = draw(st.integers(1, 5)), draw(st.integers(1, 12)), draw(st.integers(1, 8))
    fill = draw(st.sampled_from([anything, st.floats(0, 1, width=32), st.just(0.0), st.just(1.0)]))
    history = draw(arrays(np.float32, (k, height, blocks), elements=fill))
    current = draw(arrays(np.float32, (height, blocks), elements=fill))
    return history, current


@FAST
@given(profile_stacks(), st.floats(0, 0.1), st.floats(0, 0.02))
def test_relative_change_never_raises(stack, min_level, min_step):
    history, current = stack
    change, agree, blocks, noise, peak, lit_start, lit_stop = _relative_change(history, current, min_level, min_step)
    assert change.shape == agree.shape == (current.shape[0],)
    assert blocks.shape == current.shape
    assert np.all((agree >= 0) & (agree <= 1))
    assert 0 <= lit_start < lit_stop <= current.shape[0]


@FAST
@given(profile_stacks(), st.floats(0.002, 0.2), st.integers(1, 3), st.floats(0, 0.05))
def test_flicker_kernels_never_raise(stack, nu, harmonics, scale_hint):
    history, current = stack
    reference = history[0]
    y = _row_log_ratio(current, reference, 0.035)
    basis = _basis(len(y), nu, harmonics)
    init = np.zeros(basis.shape[1])
    coef, scale, num, den, ok = _fit_frame(y, basis, init, 3, scale_hint)
    if ok:
        assert np.all(np.isfinite(coef)) and np.all(np.isfinite(num)) and np.all(np.isfinite(den))
    sums = np.zeros((len(y), 5))
    pattern, follows = _row_pattern(y, basis, np.nan_to_num(coef), 0.01, sums, 0.05, 1e-4)
    assert pattern.shape == follows.shape == y.shape
    mean = reference.copy()
    _update_mean(mean, current, 0.01, 0.2)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.integers(1, 40),
    st.integers(2, 60),
    st.sampled_from([anything, st.floats(0, 1, width=32)]),
    st.booleans(),
    st.data(),
)
def test_a_stream_of_odd_profiles_never_stops_the_detector(height, frames, fill, flipped, data):
    """Whole frames of anything through flicker removal and detection: events or none, no
    exception."""
    from flashsync.detect import DetectorSettings

    profiles = data.draw(arrays(np.float32, (frames, height, 4), elements=fill))
    remover = FlickerRemover(height)
    detector = EventDetector("cam", height, DetectorSettings(flipped=flipped))
    for frame, (t_ms, profile) in enumerate(remover(zip(np.arange(frames) * 40.0, profiles))):
        detector.push(frame, t_ms, profile)
    events = detector.finish()
    assert set(events.edge.tolist()) <= {"leading", "trailing"}
    remover.estimate()
