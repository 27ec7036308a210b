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
"""

from __future__ import annotations

import numpy as np

from flashsync.errors import NotEnoughDataError
from flashsync.solve import CameraSolution, Observations, Priors, Solution, solve_clocks

#: Flashes are left out in this many groups at most (the k-th of the sorted flash indices
#: in group k mod GROUPS), one solve each; fewer flashes are left out one at a time.
GROUPS = 10


def flash_scatter(
    events: Observations, n_cameras: int, reference: int, solution: Solution, priors: Priors
) -> list[np.ndarray]:
    """Per camera, the jackknife covariance of its clock's parameters and its exposure over
    solves that each leave one group of flashes out: ``alpha``, ``beta_ms``, ``row_time_ms``
    and its warp (the layout of :attr:`~flashsync.solve.CameraSolution.covariance`), then
    ``exposure_ms``: (4 + k, 4 + k), the last row and column NaN for a camera without one.

    Each solve keeps ``solution``'s drift model (its warps' knots, the cameras solved
    without the drift prior) and ``priors``. A solve the remaining flashes cannot support
    is skipped; with fewer than two solves every matrix is zero.
    """
    knots = {c: camera.knots_ms for c, camera in enumerate(solution.cameras) if len(camera.knots_ms)}
    priors = priors.without_drift_prior(solution.free_drift)
    flashes = np.unique(events.flash)
    groups = min(len(flashes), GROUPS)
    solved = []
    for group in range(groups):
        left_out = np.isin(events.flash, flashes[group::groups])
        try:
            trial = solve_clocks(events.take(~left_out), n_cameras, reference, priors=priors, drift_knots=knots)
        except NotEnoughDataError:
            continue
        solved.append([_parameters(camera) for camera in trial.cameras])
    if len(solved) < 2:
        return [np.zeros((len(camera.covariance) + 1,) * 2) for camera in solution.cameras]
    count = len(solved)
    scatter = []
    for c in range(n_cameras):
        deviation = np.array([trial[c] for trial in solved])
        deviation -= deviation.mean(axis=0)
        scatter.append((count - 1) / count * deviation.T @ deviation)
    return scatter


def _parameters(camera: CameraSolution) -> np.ndarray:
    """A camera's solved clock as one vector, in its covariance's order, then its exposure."""
    return np.concatenate([[camera.alpha, camera.beta_ms, camera.row_time_ms], camera.warp_ms, [camera.exposure_ms]])
