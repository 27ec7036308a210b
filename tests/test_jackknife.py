from dataclasses import replace

import numpy as np
import pytest
from synthetic import observe

from flashsync import jackknife
from flashsync.jackknife import GROUPS, flash_scatter
from flashsync.solve import Observations, Priors, solve_clocks

CAMERAS = [  # alpha, beta_ms, row_time_ms, fps, height
    (1.0, 0.0, 0.0740, 25.0, 500),
    (1.0 + 12e-6, -31_234.5, 0.0620, 30.0, 510),
    (1.0 - 7e-6, 52_101.25, 0.0370, 50.0, 500),
]


def biased_rig(rng, n_flashes: int, bias_ms: float) -> tuple[Observations, np.ndarray]:
    """Every camera's edges of ``n_flashes`` flashes with 0.005 ms of noise; camera 2's
    edges of each flash moved by one offset of ``bias_ms`` std (ms), as a pulse shape, a
    codec's ramp or a split band moves all of a band's edges alike. Also camera 2's true
    clock (alpha, beta_ms, row_time_ms)."""
    tau = np.sort(rng.uniform(1_000.0, 20_000.0, n_flashes))
    offset = rng.normal(0.0, bias_ms, n_flashes)
    columns = [[], [], [], []]  # camera, flash, t_frame, q
    for index, (alpha, beta, row_time, fps, height) in enumerate(CAMERAS):
        frame_times = (np.arange(0, 25_000, 1000 / fps) - beta) / alpha
        seen, frame, rows = observe(tau, alpha, beta, row_time, frame_times, height)
        error_ms = rng.normal(0.0, 0.005, len(seen)) + (offset[seen] if index == 2 else 0.0)
        for column, values in zip(
            columns, (np.full(len(seen), index), seen, frame_times[frame], rows + error_ms / row_time)
        ):
            column.extend(values)
    return Observations(*(np.asarray(c) for c in columns)), np.array(CAMERAS[2][:3])


def camera_2_z(observations: Observations, truth: np.ndarray, with_scatter: bool) -> float:
    """Camera 2's error over its predicted sigma (RMS over its flashes' frames, first and
    last rows) from the solve's covariance, plus the flashes' scatter if asked."""
    priors = Priors({}, None)
    solution = solve_clocks(observations, 3, priors=priors)
    solved = solution.cameras[2]
    scatter = flash_scatter(observations, 3, 0, solution, priors)[2][:-1, :-1]  # the clock's, not the exposure's
    covariance = solved.covariance + (scatter if with_scatter else 0.0)
    t_frame = observations.t_frame_ms[observations.camera == 2]
    z = []
    for q in (0.0, CAMERAS[2][4] - 1.0):
        gradient = np.stack([t_frame, np.ones_like(t_frame), np.full_like(t_frame, q)], axis=1)
        error = gradient @ (np.array([solved.alpha, solved.beta_ms, solved.row_time_ms]) - truth)
        z.append(error / np.sqrt(np.einsum("ni,ij,nj->n", gradient, covariance, gradient)))
    return float(np.sqrt(np.mean(np.concatenate(z) ** 2)))


@pytest.mark.parametrize("n_flashes", [6, 12])
def test_a_flashs_error_in_all_of_a_cameras_edges_is_in_its_sigma(n_flashes):
    """An offset that a flash gives all of one camera's edges (0.05 ms, ten times the edges'
    noise, different for every flash) moves that camera's clock and barely shows in the
    residuals, which the solve's covariance comes from: over 30 draws its error is a median
    2.3-2.7 of those sigmas. With the flashes' scatter (each flash left out in turn; twelve
    in ten groups) it is 0.6-0.7, with twelve flashes RMS 0.94. Six solves are a rough
    estimate of a variance: with six flashes 3 of the 30 draws stay over two sigmas (RMS 1.7)."""
    rng = np.random.default_rng(7)
    draws = [biased_rig(rng, n_flashes, 0.05) for _ in range(30)]
    blind = np.array([camera_2_z(o, truth, False) for o, truth in draws])
    seen = np.array([camera_2_z(o, truth, True) for o, truth in draws])
    assert np.median(blind) > 2.0, np.sort(blind)
    assert 0.4 < np.median(seen) < 1.0 and (seen > 2.0).sum() <= 3, np.sort(seen)
    if n_flashes >= 12:
        assert np.sqrt(np.mean(seen**2)) < 1.2, np.sort(seen)


def test_without_such_errors_the_scatter_is_the_noises():
    """With the edges' noise alone the scatter holds what the covariance already does, and
    the sum widens sigma by less than the root of two: error/sigma RMS 0.55 -> 0.46 here."""
    rng = np.random.default_rng(8)
    draws = [biased_rig(rng, 12, 0.0) for _ in range(30)]
    blind = np.sqrt(np.mean([camera_2_z(o, truth, False) ** 2 for o, truth in draws]))
    seen = np.sqrt(np.mean([camera_2_z(o, truth, True) ** 2 for o, truth in draws]))
    assert 0.4 < blind < 1.5 and 0.7 < seen / blind < 0.95, (blind, seen)


def test_many_flashes_are_left_out_in_groups(monkeypatch):
    """Past GROUPS flashes, each solve leaves out every GROUPS-th flash: GROUPS solves, not
    one per flash; the scatter still holds the noise (sigma within a factor of two)."""
    rng = np.random.default_rng(9)
    observations, truth = biased_rig(rng, 3 * GROUPS, 0.0)
    calls = []

    def counted(*args, **kwargs):
        calls.append(1)
        return solve_clocks(*args, **kwargs)

    monkeypatch.setattr(jackknife, "solve_clocks", counted)
    assert camera_2_z(observations, truth, True) < 2.0
    assert len(calls) == GROUPS


def split_rig(rng, offset_rows: float, exposure_ms: float = 16.0, band_rows: float = 0.0) -> tuple[Observations, float]:
    """Two 25 fps cameras of 500 rows (at equal rates only band lengths tell a time per row),
    20 flashes; camera 1 (``exposure_ms``; 16 ms: 216 rows) sees both edges of every band it
    can, some split across two frames, whose trailing edges all move by one ``offset_rows``
    and each by its own error (``band_rows`` one sigma); 0.005 ms of noise on every edge.
    Also camera 1's true time per row, ms."""
    tau = np.sort(rng.uniform(1_000.0, 20_000.0, 20))
    clocks = [(1.0, 0.0, 0.0740), (1.0 + 12e-6, -31_234.5, 0.0740)]
    rows = []  # camera, flash, t_frame, q, trailing, leading_of, split
    for camera, (alpha, beta, row_time) in enumerate(clocks):
        frame_times = (np.arange(0, 25_000, 40.0) - beta) / alpha
        end_of = {f: (k, q) for f, k, q in zip(*observe(tau + exposure_ms, alpha, beta, row_time, frame_times, 500))}
        for flash, frame, q in zip(*observe(tau, alpha, beta, row_time, frame_times, 500)):
            rows.append((camera, flash, frame_times[frame], q, False, -1, False))
            if camera == 1 and flash in end_of:
                end_frame, end_q = end_of[flash]
                split = end_frame != frame
                end_q += offset_rows + rng.normal(0.0, band_rows) if split else 0.0
                rows.append((camera, flash, frame_times[end_frame], end_q, True, len(rows) - 1, split))
    camera, flash, t_frame, q, trailing, leading_of, split = (np.array(column) for column in zip(*rows))
    q = q + rng.normal(0.0, 0.005, len(q)) / 0.0740
    return Observations(camera, flash, t_frame, q, None, trailing, leading_of, split), clocks[1][2]


def test_an_error_common_to_a_cameras_split_bands_is_in_its_sigma():
    """At equal frame rates a camera's time per row comes from its band lengths, its split
    bands' (a frame period less the rows between its edges) against its whole ones'. An error
    all its split bands' lengths share (SPLIT_OFFSET_ROWS, one per draw), every flash brings
    alike: neither the residuals nor the flashes' scatter show it, and over 30 draws its time
    per row is a median 2.5 of those sigmas off. With the split bands moved by it and solved
    again (:func:`~flashsync.jackknife.split_scatter`): 0.69, RMS 1.0."""
    rng = np.random.default_rng(10)
    priors = Priors({0: (0.0740, 0.026), 1: (0.0740, 0.026)}, None)
    blind, seen = [], []
    for _ in range(30):
        observations, truth = split_rig(rng, rng.normal(0.0, jackknife.SPLIT_OFFSET_ROWS))
        assert observations.split.any() and (observations.trailing & ~observations.split).any()  # the premise
        solution = solve_clocks(observations, 2, priors=priors)
        flashes = flash_scatter(observations, 2, 0, solution, priors)[1][2, 2]
        split = jackknife.split_scatter(observations, 2, 0, solution, priors)[1][2, 2]
        error = solution.cameras[1].row_time_ms - truth
        variance = solution.cameras[1].covariance[2, 2] + flashes
        blind.append(abs(error) / np.sqrt(variance))
        seen.append(abs(error) / np.sqrt(variance + split))
    assert np.median(blind) > 2.0, np.sort(blind)
    assert 0.4 < np.median(seen) < 1.0 and np.sqrt(np.mean(np.square(seen))) < 1.5, np.sort(seen)


def test_the_own_errors_of_a_cameras_few_split_bands_are_in_its_sigma(monkeypatch):
    """The same two cameras, camera 1 at a 4 ms exposure (54 rows): of its bands one or two are
    split, and their lengths alone tie its time per row, each with an error of its own
    (SPLIT_BAND_ROWS, drawn per band). Left out, a sole split band leaves the time per row to
    the prior, which the flashes' scatter does not count, and two are one deviation: over 30
    draws with one or two split bands, moved only by the common SPLIT_OFFSET_ROWS the time per
    row is off by RMS 2.2 of its sigmas (10 over 2); moved by what their mean's own errors add
    (:data:`~flashsync.jackknife.SPLIT_BAND_ROWS` over the root of their number), RMS 0.9."""
    rng = np.random.default_rng(11)
    priors = Priors({0: (0.0740, 0.026), 1: (0.0740, 0.026)}, None)
    common, own = [], []
    while len(own) < 30:
        observations, truth = split_rig(rng, 0.0, exposure_ms=4.0, band_rows=jackknife.SPLIT_BAND_ROWS)
        if not 1 <= (observations.split & (observations.leading_of >= 0)).sum() <= 2:
            continue
        solution = solve_clocks(observations, 2, priors=priors)
        error = solution.cameras[1].row_time_ms - truth
        variance = solution.cameras[1].covariance[2, 2] + flash_scatter(observations, 2, 0, solution, priors)[1][2, 2]
        own.append(
            abs(error) / np.sqrt(variance + jackknife.split_scatter(observations, 2, 0, solution, priors)[1][2, 2])
        )
        with monkeypatch.context() as patch:
            patch.setattr(jackknife, "SPLIT_BAND_ROWS", 0.0)
            shared = jackknife.split_scatter(observations, 2, 0, solution, priors)[1][2, 2]
        common.append(abs(error) / np.sqrt(variance + shared))
    assert np.sqrt(np.mean(np.square(common))) > 1.8 and np.sum(np.array(common) > 2.0) >= 6, np.sort(common)
    assert np.sqrt(np.mean(np.square(own))) < 1.2 and np.sum(np.array(own) > 2.0) <= 2, np.sort(own)


def one_phase_rig(rng, late_rows: tuple[float, float, float]) -> tuple[Observations, float]:
    """Three 25 fps cameras of 500 rows in one phase (their frames 0, 0.7 and 1.5 ms apart,
    as line-locked ones are: their flashes tie only the ratios of their times per row), an
    8 ms exposure (108 rows); twelve flashes in mid-frame and one at the frames' turn, whose
    band every camera sees split across two frames, camera ``c``'s trailing edge
    ``late_rows[c]`` rows late; 0.005 ms of noise on every edge. Also the true time per row,
    ms (0.074 in all three)."""
    period, row_time, exposure = 40.0, 0.0740, 8.0
    mid_frame = rng.integers(25, 500, 12) * period + rng.uniform(3.0, 25.0, 12)
    tau = np.sort(np.append(mid_frame, 520 * period + 36.0))
    clocks = [(1.0, 0.0, 0.0), (1.0 + 12e-6, -31_234.5, 0.7), (1.0 - 7e-6, 52_101.25, 1.5)]
    rows = []  # camera, flash, t_frame, q, trailing, leading_of, split
    for camera, (alpha, beta, phase) in enumerate(clocks):
        frame_times = (np.arange(0, 25_000, period) + phase - beta) / alpha
        end_of = {f: (k, q) for f, k, q in zip(*observe(tau + exposure, alpha, beta, row_time, frame_times, 500))}
        for flash, frame, q in zip(*observe(tau, alpha, beta, row_time, frame_times, 500)):
            rows.append((camera, flash, frame_times[frame], q, False, -1, False))
            end_frame, end_q = end_of[flash]
            split = end_frame != frame
            rows.append(
                (camera, flash, frame_times[end_frame], end_q + late_rows[camera] * split, True, len(rows) - 1, split)
            )
    camera, flash, t_frame, q, trailing, leading_of, split = (np.array(column) for column in zip(*rows))
    q = q + rng.normal(0.0, 0.005, len(q)) / row_time
    return Observations(camera, flash, t_frame, q, None, trailing, leading_of, split), row_time


def one_phase_row_times(observations: Observations, priors: Priors, truth: float) -> tuple[np.ndarray, ...]:
    """The three cameras of :func:`one_phase_rig` solved: each one's time per row's error
    (ms), its variance with the flashes' scatter and its split bands' common error in it
    (ms²), and what :func:`~flashsync.jackknife.split_left_out_scatter` adds to it (ms²)."""
    solution = solve_clocks(observations, 3, priors=priors)
    solve = (observations, 3, 0, solution, priors)
    other = [a + b for a, b in zip(flash_scatter(*solve), jackknife.split_scatter(*solve))]
    variance = np.array([camera.covariance[2, 2] + extra[2, 2] for camera, extra in zip(solution.cameras, other)])
    left_out = np.array([extra[2, 2] for extra in jackknife.split_left_out_scatter(*solve, variance)])
    return np.array([camera.row_time_ms for camera in solution.cameras]) - truth, variance, left_out


@pytest.mark.parametrize("late_rows", [(17.0, 0.0, 5.0), (0.0, 0.0, 0.0)])
def test_split_bands_that_disagree_with_the_other_edges_are_in_sigma(late_rows):
    """The one split flash of three line-locked cameras (one rate, one phase) alone ties their
    times per row (the prior's correlation ties them together); left out, it leaves them to
    the prior and the flashes' scatter does not count it. With two of its three bands read
    long (RC11's line-locked recipe: 17 and 5 rows, a decay tail read as the band) the solve
    keeps the 5-row one and rejects the others: times per row 0.9 % off at 5-6 sigmas.
    Each camera's split bands left out in turn move the times per row far beyond their noise:
    with that in sigma (:func:`~flashsync.jackknife.split_left_out_scatter`) 0.7. Read right,
    they agree and nothing is added."""
    rng = np.random.default_rng(12)
    priors = Priors({c: (0.0740, 0.026) for c in range(3)}, shared_readout=((0, 1, 2),))
    for _ in range(3):
        observations, truth = one_phase_rig(rng, late_rows)
        assert observations.split.sum() == 3  # the premise: one split band in each camera
        error, variance, left_out = one_phase_row_times(observations, priors, truth)
        if not any(late_rows):
            assert np.all(np.abs(error) < 2.0 * np.sqrt(variance)) and np.all(left_out == 0.0), (error, variance)
            continue
        assert np.abs(error / np.sqrt(variance)).max() > 4.0, (error, variance)
        assert np.all(np.abs(error) < 1.5 * np.sqrt(variance + left_out)), (error, variance, left_out)


def one_edge_rig(rng, late_rows: float) -> tuple[Observations, float, int]:
    """Two cameras of 500 rows, 25 and 30 fps, 12 flashes, edges 0.005 ms noisy. Camera 0
    (2 ms exposure) sees both edges of every band but the ninth flash's, of which it sees a
    lone trailing edge ``late_rows`` late (its leading edge before the first row: a decay
    tail read as a cut band's ramp); camera 1 (15 ms) sees lone trailing edges but a leading
    edge of the ninth flash, which alone places its shift against its exposure. Also camera
    1's true shift (ms) and the index of camera 0's late edge."""
    tau = np.sort(rng.uniform(1_000.0, 20_000.0, 12))
    clocks = [(1.0, 0.0, 0.0740, 40.0, 2.0), (1.0 + 12e-6, -31_234.5, 0.0620, 33.3, 15.0)]
    rows = []  # camera, flash, t_frame, q, trailing, leading_of
    for camera, (alpha, beta, row_time, period, exposure) in enumerate(clocks):
        frame_times = (np.arange(0, 25_000, period) - beta) / alpha
        start = {f: (k, q) for f, k, q in zip(*observe(tau, alpha, beta, row_time, frame_times, 500))}
        end = {f: (k, q) for f, k, q in zip(*observe(tau + exposure, alpha, beta, row_time, frame_times, 500))}
        for flash in range(len(tau)):
            lone_trailing = (flash != 8) if camera == 1 else (flash == 8)
            if not lone_trailing and flash in start:
                rows.append((camera, flash, frame_times[start[flash][0]], start[flash][1], False, -1))
            if flash in end and (lone_trailing or camera == 0):
                late = late_rows if camera == 0 and flash == 8 else 0.0
                paired = -1 if lone_trailing else len(rows) - 1
                rows.append((camera, flash, frame_times[end[flash][0]], end[flash][1] + late, True, paired))
    camera, flash, t_frame, q, trailing, leading_of = (np.array(column) for column in zip(*rows))
    q = q + rng.normal(0.0, 0.005, len(q)) / np.where(camera == 0, 0.0740, 0.0620)
    late_edge = int(np.flatnonzero((camera == 0) & (flash == 8) & trailing)[0])
    return Observations(camera, flash, t_frame, q, None, trailing, leading_of), clocks[1][1], late_edge


def test_an_error_of_an_edge_that_alone_places_a_camera_is_in_its_sigma_when_moved():
    """A camera's shift that rests on one flash, whose time rests on one lone edge of
    another camera, takes that edge's error whole: neither the residuals (all zero) nor the
    flashes left out (without that flash its shift is not solved) show it, and 12 rows late
    (0.89 ms) the shift is far outside its sigma. With that edge moved by as much as its ramp
    may leave it (12 rows towards the cut) and solved again
    (:func:`~flashsync.jackknife.moved_scatter`) the error is within its sigma; moving no edge
    adds nothing."""
    rng = np.random.default_rng(12)
    observations, true_shift, late_edge = one_edge_rig(rng, 12.0)
    priors = Priors({0: (0.0740, 0.026), 1: (0.0620, 0.022)}, None)
    solution = solve_clocks(observations, 2, priors=priors)
    error = solution.cameras[1].beta_ms - true_shift
    variance = solution.cameras[1].covariance[1, 1] + flash_scatter(observations, 2, 0, solution, priors)[1][1, 1]
    moves = np.zeros(len(observations.q))
    moves[late_edge] = -12.0
    moved = jackknife.moved_scatter(observations, 2, 0, solution, priors, moves)[1][1, 1]
    assert abs(error) > 0.7 and abs(error) > 5.0 * np.sqrt(variance), (error, np.sqrt(variance))
    assert abs(error) < 1.5 * np.sqrt(variance + moved), (error, np.sqrt(variance + moved))
    assert not jackknife.moved_scatter(observations, 2, 0, solution, priors, 0.0 * moves)[1].any()


@pytest.mark.parametrize("late_rows", [12.0, 0.0])
def test_a_split_band_that_alone_pins_the_times_per_row_is_in_sigma_as_far_off_as_its_noise_lets_it_be(late_rows):
    """The line-locked rig of :func:`one_phase_rig` with only camera 0's band of the flash at
    the frames' turn split (the others' trailing edges of it unseen): it alone ties the three
    times per row, and left out it leaves them to the prior, so neither the flashes' scatter
    nor the split bands left out count it. Its edges 3.4 times a clean edge's noise
    (`line-locked` at recipe seed 15: its one split band, its leading edge in the last row,
    read 12.5 rows long; its cameras 0.7 ms off at error/sigma 4.6-4.8). Read 12 rows long,
    the times per row are off at over 4 sigmas without it; with what a band of that noise
    may be off in the tail (:data:`~flashsync.jackknife.SPLIT_UNCHECKED_ROWS` each clean
    edge's noise) within 2. Read right, within 2 as well."""
    rng = np.random.default_rng(12)
    priors = Priors({c: (0.0740, 0.026) for c in range(3)}, shared_readout=((0, 1, 2),))
    observations, truth = one_phase_rig(rng, (late_rows, 0.0, 0.0))
    observations = observations.take(~(observations.split & (observations.camera > 0)))
    assert observations.split.sum() == 1  # the premise: one split band in the rig
    noise = np.where(observations.split, 3.4, 1.0)
    noise[observations.leading_of[observations.split]] = 3.4
    observations = replace(observations, sigma_factor=noise)
    error, variance, left_out = one_phase_row_times(observations, priors, truth)
    if late_rows:
        assert np.abs(error / np.sqrt(variance)).max() > 4.0, (error, variance)
    assert np.all(np.abs(error) < 2.0 * np.sqrt(variance + left_out)), (error, variance, left_out)


def one_band_rig(rng, exposure_ms: float = 8.0) -> tuple[Observations, float]:
    """:func:`biased_rig` (12 flashes; camera 2's edges of each flash moved by one offset of
    0.05 ms std) with the trailing edge of camera 2's first band whose both edges lie in one
    frame, ``exposure_ms`` after its flash (8 ms: 216 rows) and moved alike: camera 2's
    exposure rests on that one band's rows and its time per row. Also the true exposure, ms."""
    observations, _ = biased_rig(rng, 12, 0.05)
    _, _, row_time, _, height = CAMERAS[2]
    leading = next(
        i for i in np.flatnonzero(observations.camera == 2) if observations.q[i] + exposure_ms / row_time <= height - 1
    )
    n = len(observations.camera)
    return Observations(
        np.append(observations.camera, 2),
        np.append(observations.flash, observations.flash[leading]),
        np.append(observations.t_frame_ms, observations.t_frame_ms[leading]),
        np.append(observations.q, observations.q[leading] + exposure_ms / row_time),
        None,
        np.append(np.zeros(n, bool), True),
        np.append(np.full(n, -1), leading),
        np.zeros(n + 1, bool),
    ), exposure_ms


def test_an_exposure_a_left_out_group_leaves_unread_has_the_scatter_of_the_solves_that_read_it():
    """Camera 2's exposure rests on one band and its time per row, which the flashes' errors
    in its edges move and its residuals barely show: over 30 draws the solve's sigma leaves
    it RMS 2.4 of its sigmas off, 10 over 2. The solve that leaves that band's flash out reads
    no exposure, and its scatter was NaN, none added (EC2's rig-1075 cam7, all its bands split:
    4.28 ± 0.41 ms for 14.81). Over the solves that read it: RMS 0.88, 1 over 2."""
    rng = np.random.default_rng(12)
    priors = Priors({}, None)
    blind, seen = [], []
    for _ in range(30):
        observations, truth = one_band_rig(rng)
        solution = solve_clocks(observations, 3, priors=priors)
        scatter = flash_scatter(observations, 3, 0, solution, priors)[2]
        solved = solution.cameras[2]
        error = abs(solved.exposure_ms - truth)
        blind.append(error / solved.exposure_std_ms)
        seen.append(error / np.sqrt(solved.exposure_std_ms**2 + np.nan_to_num(scatter[-1, -1])))
    blind, seen = np.array(blind), np.array(seen)
    assert np.sqrt(np.mean(blind**2)) > 2.0 and (blind > 2.0).sum() >= 8, np.sort(blind)
    assert np.sqrt(np.mean(seen**2)) < 1.1 and (seen > 2.0).sum() <= 2, np.sort(seen)
