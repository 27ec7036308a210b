"""How far the flashes themselves move each camera's clock: the joint solve re-run with
each group of flashes left out (the delete-a-group jackknife).

The solve's covariance knows the edges' noise as their residuals show it. An error that a
flash brings to its edges in one camera (a codec that erased half a ramp, a tone curve on a
long xenon tail, an LED pulse longer than the exposure, a split band) moves that camera's
clock and leaves residuals hardly larger: with few flashes the clock bends to fit it. Left
out, the flash no longer moves it. Over ``G`` solves that each leave one group of flashes
out, ``(G - 1) / G`` times the sum of the squared deviations of a parameter from their mean
estimates its variance whatever the flashes' errors are, so long as they differ from flash
to flash. A camera's clock is on the reference's, so the scatter of a camera holds the
reference's edges' share too (the reference's shift is 0 by definition).

An error that all of a camera's bands split across two frames share, the jackknife cannot
see: every flash brings it alike. Their lengths tie the time per row to the frame period
(the band runs through the rows hidden between frames), so it moves the time per row;
:func:`split_scatter` moves them by the error their mean may hold (one all share, and the
bands' own over the root of their number, which the jackknife sees only where several tie a
camera) and solves again. So, by :func:`moved_scatter`, does any error of known size and
direction that a camera's edges may hold: a lone edge whose ramp the frame's cut hides lies
further from the cut than its flash puts it, and where it alone places a flash that alone
places a camera, neither the residuals nor the flashes left out can show it. And
:func:`rival_scatter` holds what another reading of which flash each edge saw moves (two
solved flashes closer than the matching tells apart, solved as one).

Where one flash's split bands alone tie the times per row (cameras of one rate in one
phase, as line-locked ones are), that flash left out leaves them to the prior and is not
counted, and one camera's band read wrong (a decay tail read as the band) may decide all
of them, the others' rejected. :func:`split_left_out_scatter` leaves each camera's split
bands out in turn: where they move its time per row further than the noise and every other
error allow, they disagree with the rest, which is right the solve cannot tell, and the
change is in sigma.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from flashsync.errors import NotEnoughDataError
from flashsync.solve import CameraSolution, Observations, Priors, Solution, solve_clocks

#: Flashes are left out in this many groups at most (the k-th of the sorted flash indices
#: in group k mod GROUPS), one solve each; fewer flashes are left out one at a time.
GROUPS = 10
#: A solve that leaves a camera's time per row to its prior (its standard deviation over
#: this share of the prior's) where the whole solve did not is not counted in that camera's
#: scatter: its time per row then moves by the prior's pull, not by what the group's edges
#: got wrong (under :func:`~flashsync.pipeline.row_time_prior_ms`, the reference of
#: ``tests/test_video_formats.py`` re-encoded as VP9 gave its 50 fps camera a sigma of 2.06 ms
#: for an error of 0.015; the twins of ``tests/test_accuracy.py``, whose times per row rest
#: on one flash, had 1.09 and 1.88 ms for 0.009 and 0.046 under the nominal prior).
PRIOR_BOUND_SHARE = 0.5


def flash_scatter(
    events: Observations, n_cameras: int, reference: int, solution: Solution, priors: Priors
) -> list[np.ndarray]:
    """Per camera, the jackknife covariance of its clock's parameters and its exposure over
    solves that each leave one group of flashes out: ``alpha``, ``beta_ms``, ``row_time_ms``
    and its warp (the layout of :attr:`~flashsync.solve.CameraSolution.covariance`), then
    ``exposure_ms``: (4 + k, 4 + k), the last row and column NaN for a camera without one.

    Each solve is made as ``solution`` was (:func:`_solved_as`). A solve the remaining
    flashes cannot support is skipped, and so, for a camera, one that leaves its time per
    row to the prior where ``solution`` did not (:data:`PRIOR_BOUND_SHARE`); with fewer than
    two solves a camera's matrix is zero. Its exposure's row and column are over the solves
    that read it (a group left out may leave it none of its bands: EC2's rig-1075 cam7, its
    exposure on its split bands and a time per row the flashes move, had none added).
    """
    solved = []
    for group in _in_groups(np.unique(events.flash)):
        left_out = np.isin(events.flash, group)
        try:
            solved.append(_solved_as(solution, events.take(~left_out), n_cameras, reference, priors).cameras)
        except NotEnoughDataError:
            continue
    scatter = []
    for c, camera in enumerate(solution.cameras):
        bound = _prior_bound_ms(priors, c)
        informed = camera.row_time_std_ms <= bound
        kept = [_parameters(trial[c]) for trial in solved if not informed or trial[c].row_time_std_ms <= bound]
        count = len(kept)
        if count < 2:
            scatter.append(_none(camera))
            continue
        matrix = _jackknife(np.array(kept), count)
        read = np.array([values for values in kept if np.isfinite(values[-1])])
        if 2 <= len(read) < count:  # its exposure over the solves that read it
            matrix[-1, :] = matrix[:, -1] = _jackknife(read, count)[-1]
        scatter.append(matrix)
    return scatter


def _jackknife(values: np.ndarray, count: int) -> np.ndarray:
    """The delete-a-group jackknife covariance of ``values`` (n, k), the parameters of
    ``n`` of ``count`` solves that each left a group out: ``(count - 1) / n`` times the sum
    of their deviations' outer products (``(count - 1) / count`` of it where all are given)."""
    deviation = values - values.mean(axis=0)
    return (count - 1) / len(values) * deviation.T @ deviation


#: The error common to the lengths of one camera's bands split across two frames, rows (one
#: sigma). Against the truth, each camera's split bands' mean length less its whole ones'
#: median spreads 0.34 rows over the 14 cameras with both on the first world's rigs of
#: ``tests/test_accuracy.py`` and four more draws of its mixed rig (about 0.27 without the
#: bands' own noise; on mixed-1 and -3 the 144-row camera's two split bands are both 0.57-0.59
#: rows short and, without this, its time per row 0.36 % off at 3.3-3.9 sigma), 0.72 over 43
#: cameras of random rigs 412-427 (robust; about 0.57 without their own noise), where the
#: other errors already widen sigma (error/sigma median 0.42). The first world's is taken.
SPLIT_OFFSET_ROWS = 0.3
#: The error of one split band's length of its own, rows (one sigma), of which a camera's
#: few split bands leave the mean of their errors: ``SPLIT_BAND_ROWS / sqrt(n)`` for ``n``
#: bands. The flashes left out show it only where several split bands tie a camera's time
#: per row (:func:`flash_scatter`: a solve that leaves it to the prior is not counted, and two
#: bands are one deviation). Against the truth, the lengths of the 458 split bands of eight
#: kept benches (``bench_rigs.py``: the issue's six recipes at seeds 1-4 and random rigs 0-47)
#: spread 0.73 rows (MAD; 0.91 half their 16-84 % range); random rig 49's reference had two,
#: 3.2 and 2.8 rows long, its time per row 0.76 % off at 4.8 sigma.
SPLIT_BAND_ROWS = 0.75


def split_scatter(
    events: Observations, n_cameras: int, reference: int, solution: Solution, priors: Priors
) -> list[np.ndarray]:
    """Per camera, the covariance that an error of the mean of each camera's split bands'
    lengths brings to its clock's parameters and its exposure (:func:`moved_scatter`): every
    camera's such bands, ``n`` of them, with their trailing edges later by the error their
    mean may hold (:data:`SPLIT_OFFSET_ROWS` and :data:`SPLIT_BAND_ROWS` over the root of
    ``n``, in quadrature). Zero where no camera has a split band whose both edges the solve
    pairs."""
    if events.split is None or events.leading_of is None:
        return moved_scatter(events, n_cameras, reference, solution, priors, np.zeros(len(events.camera)))
    lengths = events.split & (events.leading_of >= 0)
    cameras, counts = np.unique(events.camera[lengths], return_counts=True)
    offset = np.zeros(n_cameras)
    offset[cameras] = np.hypot(SPLIT_OFFSET_ROWS, SPLIT_BAND_ROWS / np.sqrt(counts))
    moves = np.where(lengths, offset[events.camera], 0.0)
    return moved_scatter(events, n_cameras, reference, solution, priors, moves)


#: A camera's split bands left out (:func:`split_left_out_scatter`) disagree with the other
#: edges where they move its time per row by more than this many of the change's sigmas (the
#: solve's without them and the camera's own with every other error in it, in quadrature).
#: On the eighteen cached benches at 3 only `line-locked`'s three cameras (RC11) count it,
#: whose times per row were 1.2 % off at 4.5-4.7 sigma: one of the three bands its one split
#: flash left decided them, the two others rejected.
SPLIT_APART_SIGMAS = 3.0
#: Where a camera's split bands alone pin its time per row (left out, the solve leaves it to
#: its prior), nothing checks them, and each one's length may be off as far as the tail of
#: split bands goes: this many rows (one sigma) times its edges' noise in clean edges'
#: (:func:`_band_noise`). Against the truth, 95 % of the 653 split bands of clean edges (noise
#: under 1.2) of the 25 cached benches lie within 3.8 rows of their length, of the 170 at
#: 1.2-2 within 11.7 (:data:`SPLIT_BAND_ROWS` is their MAD, 0.70 over all 882):
#: `line-locked` at recipe seed 15, whose one split band (its reference's, its leading edge
#: in the last row, its edges' noise 3.4) read 12.5 rows long, had its three cameras' times
#: per row 3.3-3.5 % long at 5.3-8.2 sigma, 0.70-0.76 ms off at error/sigma 4.6-4.8.
SPLIT_UNCHECKED_ROWS = 2.0


def split_left_out_scatter(
    events: Observations,
    n_cameras: int,
    reference: int,
    solution: Solution,
    priors: Priors,
    row_time_var: np.ndarray,
) -> list[np.ndarray]:
    """Per camera, the covariance that split bands which disagree with the other edges bring
    to its clock's parameters and its exposure (the layout of :func:`flash_scatter`). Each
    camera's split bands (both edges of those whose both edges the solve pairs) are left out
    in turn (in :data:`GROUPS` groups of cameras at most) and the joint solve re-run as
    ``solution`` was; where a left-out camera's time per row moves by more than
    :data:`SPLIT_APART_SIGMAS` times the root of its variance in that solve plus
    ``row_time_var`` (ms², shape (n_cameras,): each camera's with every other error in it),
    the change of every camera's parameters squared is added. A solve that leaves a camera's
    time per row to its prior (:data:`PRIOR_BOUND_SHARE`) where ``solution`` did not does not
    count for it: there its split bands alone pin it, and nothing checks them; what moving
    them by :data:`SPLIT_UNCHECKED_ROWS` times their noise moves (:func:`moved_scatter`) is
    added instead. Zero where no camera's split bands disagree or alone pin it."""
    scatter = [_none(camera) for camera in solution.cameras]
    if events.split is None or events.leading_of is None:
        return scatter
    paired = events.split & (events.leading_of >= 0)
    bands = paired.copy()
    bands[events.leading_of[paired]] = True
    for group in _in_groups(np.unique(events.camera[paired])):
        mine = np.isin(events.camera, group)
        try:
            trial = _solved_as(solution, events.take(~(bands & mine)), n_cameras, reference, priors)
        except NotEnoughDataError:
            continue
        bounds = {c: _prior_bound_ms(priors, c) for c in group}
        if any(_apart(solution.cameras[c], trial.cameras[c], row_time_var[c], bounds[c]) for c in group):
            scatter = [total + change for total, change in zip(scatter, _changes(solution, trial))]
        if any(solution.cameras[c].row_time_std_ms <= bounds[c] < trial.cameras[c].row_time_std_ms for c in group):
            moves = np.where(paired & mine, SPLIT_UNCHECKED_ROWS * _band_noise(events), 0.0)
            unchecked = moved_scatter(events, n_cameras, reference, solution, priors, moves)
            scatter = [total + change for total, change in zip(scatter, unchecked)]
    return scatter


def _band_noise(events: Observations) -> np.ndarray:
    """Per observation, a trailing edge's band's noise in units of a clean edge's: the mean of
    its and its leading edge's ``sigma_factor`` (1 without them or for an unpaired edge)."""
    if events.sigma_factor is None or events.leading_of is None:
        return np.ones(len(events.camera))
    paired = events.leading_of >= 0
    leading = events.sigma_factor[np.where(paired, events.leading_of, np.arange(len(events.camera)))]
    return np.where(paired, 0.5 * (events.sigma_factor + leading), 1.0)


def _apart(camera: CameraSolution, trial: CameraSolution, row_time_var: float, bound_ms: float) -> bool:
    """Whether a camera's time per row moved from ``camera`` to ``trial`` by more than
    :data:`SPLIT_APART_SIGMAS` sigmas (the trial's variance plus ``row_time_var``, ms²), the
    trial not leaving it to its prior where ``camera`` did not (``bound_ms``: the std past
    which it does)."""
    if camera.row_time_std_ms <= bound_ms < trial.row_time_std_ms:
        return False
    moved = abs(trial.row_time_ms - camera.row_time_ms)
    return moved > SPLIT_APART_SIGMAS * np.sqrt(trial.covariance[2, 2] + row_time_var)


def moved_scatter(
    events: Observations, n_cameras: int, reference: int, solution: Solution, priors: Priors, moves_rows: np.ndarray
) -> list[np.ndarray]:
    """Per camera, the covariance that an error of ``moves_rows`` (readout rows, shape (n,):
    each observation's, all of one camera's at once, 0 for none) brings to its clock's
    parameters and its exposure (the layout of :func:`flash_scatter`): for every camera with
    a move, the joint solve re-run with its edges so moved, the change of every camera's
    parameters squared (its outer product), summed over those cameras; each solve made as
    ``solution`` was (:func:`_solved_as`). Past :data:`GROUPS` such cameras they move in that
    many groups (the k-th in group k mod GROUPS), one solve each, a camera's change then
    holding its group's others' small share. Zero where nothing moves."""
    scatter = [_none(camera) for camera in solution.cameras]
    for moved in (np.isin(events.camera, group) for group in _in_groups(np.unique(events.camera[moves_rows != 0]))):
        shifted = replace(events, q=np.where(moved, events.q + moves_rows, events.q))
        trial = _solved_as(solution, shifted, n_cameras, reference, priors)
        scatter = [total + change for total, change in zip(scatter, _changes(solution, trial))]
    return scatter


def rival_scatter(
    events: Observations, n_cameras: int, reference: int, solution: Solution, priors: Priors
) -> list[np.ndarray]:
    """Per camera, the outer product of the change of its clock's parameters and its exposure
    (the layout of :func:`flash_scatter`) when ``events`` (the edges of ``solution`` matched
    otherwise: another reading of which flash each saw) are solved as ``solution`` was; zero
    where they cannot be solved."""
    try:
        trial = _solved_as(solution, events, n_cameras, reference, priors)
    except NotEnoughDataError:
        return [_none(camera) for camera in solution.cameras]
    return _changes(solution, trial)


def _changes(solution: Solution, trial: Solution) -> list[np.ndarray]:
    """Per camera, the outer product of the change of its parameters (:func:`_parameters`)
    from ``solution`` to ``trial`` (a change NaN on either side counts 0)."""
    changes = [np.nan_to_num(_parameters(b) - _parameters(a)) for a, b in zip(solution.cameras, trial.cameras)]
    return [np.outer(change, change) for change in changes]


def _none(camera: CameraSolution) -> np.ndarray:
    """A camera's scatter where nothing moves it: zeros in the layout of :func:`flash_scatter`."""
    return np.zeros((len(camera.covariance) + 1,) * 2)


def _in_groups(indices: np.ndarray) -> list[np.ndarray]:
    """Flash or camera ``indices`` (k,) in :data:`GROUPS` groups at most, the k-th in group
    k mod GROUPS; one group each where they are fewer."""
    groups = min(len(indices), GROUPS)
    return [indices[group::groups] for group in range(groups)]


def _prior_bound_ms(priors: Priors, camera: int) -> float:
    """The standard deviation of a camera's time per row (ms) past which a solve has left it
    to its prior (:data:`PRIOR_BOUND_SHARE` of the prior's); infinite without a prior."""
    return PRIOR_BOUND_SHARE * priors.row_time[camera][1] if camera in priors.row_time else np.inf


def _solved_as(solution: Solution, events: Observations, n_cameras: int, reference: int, priors: Priors) -> Solution:
    """``events`` solved as ``solution`` was: with its drift model (its warps' knots, the
    cameras solved without the drift prior) and ``priors``."""
    knots = {c: camera.knots_ms for c, camera in enumerate(solution.cameras) if len(camera.knots_ms)}
    priors = priors.without_drift_prior(solution.free_drift)
    return solve_clocks(events, n_cameras, reference, priors=priors, drift_knots=knots)


def _parameters(camera: CameraSolution) -> np.ndarray:
    """A camera's solved clock as one vector, in its covariance's order, then its exposure."""
    return np.concatenate([[camera.alpha, camera.beta_ms, camera.row_time_ms], camera.warp_ms, [camera.exposure_ms]])
