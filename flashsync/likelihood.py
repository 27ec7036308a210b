"""How well a reading of the cameras explains their band edges: the log-likelihood that
chooses readout directions and frame times (:func:`edge_log_likelihood`, the score of a
whole match-and-solve), and a cheap estimate of it for one camera refitted alone against
the other cameras' flashes held where they are (:func:`held_log_likelihood`).

An edge the solve keeps (an inlier) counts as Gaussian about the fit with its camera's
noise for edges of its kind; every other edge as uniform over a frame period. The held
estimate lets the readout search skip the flips that cannot pay and try together those
that must (:func:`flashsync.pipeline._held_gains`): a whole match-and-solve of 64 cameras
x 500 flashes takes about 2 s, a camera refitted alone about a millisecond.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flashsync.robust import MIN_SCALE_MS, cauchy_irls, mad_sigma
from flashsync.solve import CAUCHY_K, EDGE_FLOOR_ROWS, EVENT_SIGMA_MS, ITERATIONS, REJECT_SIGMA

#: No edge is located better than this (ms): a residual scale below it is a fit with almost
#: no equations to spare, not evidence for a reading.
SCORE_MIN_SIGMA_MS = 0.02


def edge_log_likelihood(sigma_ms: np.ndarray, n_edges: int, period_ms: float) -> float:
    """Log-likelihood of ``n_edges`` band edges: the inliers, of noise ``sigma_ms`` (ms, shape
    (k,), one per inlier), Gaussian about the fit (at their noise on average); the other
    ``n_edges - k`` uniform over ``period_ms``."""
    return float(np.sum(-np.log(sigma_ms * np.sqrt(2.0 * np.pi)) - 0.5) - (n_edges - len(sigma_ms)) * np.log(period_ms))


def residual_log_likelihood(
    residual_ms: np.ndarray, sigma_ms: np.ndarray, flash: np.ndarray, n_edges: int, period_ms: float
) -> float:
    """Log-likelihood of ``n_edges`` band edges of which the fitted ones have residuals
    ``residual_ms`` at noise ``sigma_ms`` about the times of their flashes ``flash`` (ms,
    ms, flash indices; shape (k,) each): each the larger of its Gaussian density and the
    uniform one over ``period_ms`` (an edge the fit misses by many sigmas is no better than
    one it does not explain); the other ``n_edges - k`` uniform. Each flash's time is
    integrated out, uniform over ``period_ms`` (Laplace: ``log(sqrt(2 pi) sigma_f /
    period_ms)``, ``sigma_f`` the std its explained edges give it): a flash's time is free,
    so one of its edges only places it, and a matching that names more flashes is not
    credited with the edges that placed them. Fits of one set of edges compared at one
    noise: a loose fit that explains more edges pays for every residual, where its own
    wider noise would hide them."""
    gaussian = -np.log(sigma_ms * np.sqrt(2.0 * np.pi)) - 0.5 * (residual_ms / sigma_ms) ** 2
    explained = gaussian > -np.log(period_ms)
    precision = np.bincount(flash[explained], weights=sigma_ms[explained] ** -2.0)
    placing = np.sum(np.log(np.sqrt(2.0 * np.pi / precision[precision > 0]) / period_ms))
    unexplained = n_edges - int(explained.sum())
    return float(np.sum(gaussian[explained]) + placing - unexplained * np.log(period_ms))


@dataclass(frozen=True)
class ReadingEdges:
    """One camera's band edges in one reading, arrays of shape (n,): ``t_frame_ms`` frame
    times (ms, the camera's clock), ``q`` readout rows, ``approximate_ms`` their times on the
    camera's clock with a nominal time per row (:func:`flashsync.match.approximate_times_ms`),
    ``trailing`` (bool: a band's trailing edge, one exposure after its flash), ``band`` the
    event number a band's edges share, and ``sigma_factor`` each edge's noise in units of a
    clean edge's. A trailing edge's band has its leading edge among them, or none visible:
    then the edge's approximate time is its band's start's (one exposure earlier)."""

    t_frame_ms: np.ndarray
    q: np.ndarray
    approximate_ms: np.ndarray
    trailing: np.ndarray
    band: np.ndarray
    sigma_factor: np.ndarray


@dataclass(frozen=True)
class HeldClock:
    """What :func:`held_log_likelihood` knows of the camera: its clock on the held flashes'
    clock, coarsely (``alpha``, ``beta_ms``: global = alpha x own + beta), its frame period
    (ms), the prior on its time per row (``row_time_ms``: mean and std, ms), and the largest
    time per row a sensor of its frame period can have (ms)."""

    alpha: float
    beta_ms: float
    period_ms: float
    row_time_ms: tuple[float, float]
    max_row_time_ms: float


#: An edge takes the held flash within this many frame periods of its coarse time (its
#: approximate time mapped by the coarse clock: off by up to a readout, less than a period) and
#: none where two flashes lie that close.
ASSIGN_PERIODS = 1.2
#: Prior std of the refit's drift about the coarse clock's: a camera's rate does not depend
#: on which way up its rows are read.
DRIFT_STD = 50e-6


def held_log_likelihood(edges: ReadingEdges, flash_ms: np.ndarray, clock: HeldClock, uniform_ms: float) -> float:
    """:func:`edge_log_likelihood` of one camera's ``edges`` with its clock refitted alone
    (drift, shift, time per row, exposure; robustly, with priors) against the flashes'
    global times ``flash_ms`` (ms, any order, NaN for unknown) held fixed: each leading edge
    takes the flash nearest its coarse time (:data:`ASSIGN_PERIODS`), a trailing edge its
    band's. Edges without a flash, rejected ones, and all of them where the fitted time per
    row is no sensor's (not positive, or above ``clock.max_row_time_ms``) count as uniform
    over ``uniform_ms``."""
    n_edges = len(edges.t_frame_ms)
    flash = _nearest_flash(edges, np.sort(flash_ms[np.isfinite(flash_ms)]), clock)
    use = np.isfinite(flash)
    t, q, trailing = edges.t_frame_ms[use], edges.q[use], edges.trailing[use]
    factor = edges.sigma_factor[use]
    if len(t) < 2:
        return edge_log_likelihood(np.zeros(0), n_edges, uniform_ms)
    mid = float(np.median(t))
    design = np.column_stack([t - mid, np.ones(len(t)), q, -trailing.astype(np.float64)]) / factor[:, None]
    observed = (flash[use] - clock.alpha * t - clock.beta_ms) / factor  # what the refit adds to the coarse clock
    if not trailing.any():
        design = design[:, :3]
    row_mean, row_std = clock.row_time_ms
    priors = np.zeros((2, design.shape[1]))
    priors[0, 0], priors[1, 2] = EVENT_SIGMA_MS / DRIFT_STD, EVENT_SIGMA_MS / row_std
    prior_values = np.array([0.0, row_mean * priors[1, 2]])
    norms = np.linalg.norm(np.vstack([design, priors]), axis=0)
    design, priors = design / norms, priors / norms

    def solve(weights: np.ndarray) -> np.ndarray:
        root = np.sqrt(np.concatenate([weights, np.ones(2)]))
        matrix = np.vstack([design, priors]) * root[:, None]
        return np.linalg.lstsq(matrix, np.concatenate([observed, prior_values]) * root, rcond=None)[0]

    x, residual, _ = cauchy_irls(
        solve,
        lambda x: observed - design @ x,
        len(observed),
        lambda residual, _: CAUCHY_K * mad_sigma(residual, MIN_SCALE_MS),
        ITERATIONS - 1,
    )
    edge_floor = EDGE_FLOOR_ROWS * abs(float(x[2] / norms[2]))  # as the solve rejects
    inlier = np.abs(residual) <= REJECT_SIGMA * max(mad_sigma(residual, MIN_SCALE_MS), edge_floor)
    x = solve(inlier.astype(np.float64))
    residual = observed - design @ x
    row_time = float(x[2] / norms[2])
    if not 0.0 < row_time <= clock.max_row_time_ms:
        return edge_log_likelihood(np.zeros(0), n_edges, uniform_ms)
    floor = max(EDGE_FLOOR_ROWS * row_time, SCORE_MIN_SIGMA_MS)
    noise = np.zeros(len(residual))
    for kind, unknowns in ((~trailing, 3), (trailing, 1)):
        kept = inlier & kind
        squares = float(np.sum(residual[kept] ** 2))
        noise[kind] = max(np.sqrt(squares / max(int(kept.sum()) - unknowns, 1)), floor)
    return edge_log_likelihood((noise * factor)[inlier], n_edges, uniform_ms)


def _nearest_flash(edges: ReadingEdges, flashes: np.ndarray, clock: HeldClock) -> np.ndarray:
    """Per edge (shape (n,)), the global time of its flash (ms; NaN for none): for a leading
    edge, or a trailing edge whose leading edge is hidden, the held flash (``flashes``
    sorted) within :data:`ASSIGN_PERIODS` frame periods of its coarse time, where exactly one
    lies there; for any other trailing edge its band's leading edge's."""
    flash = np.full(len(edges.t_frame_ms), np.nan)
    lone = edges.trailing & ~np.isin(edges.band, edges.band[~edges.trailing])
    placed = np.flatnonzero(~edges.trailing | lone)
    coarse = clock.alpha * edges.approximate_ms[placed] + clock.beta_ms
    window = ASSIGN_PERIODS * clock.period_ms
    first = np.searchsorted(flashes, coarse - window)
    one = np.searchsorted(flashes, coarse + window, side="right") - first == 1
    flash[placed[one]] = flashes[first[one]]
    of_band = dict(zip(edges.band[placed].tolist(), flash[placed].tolist()))
    for index in np.flatnonzero(edges.trailing & ~lone):
        flash[index] = of_band.get(int(edges.band[index]), np.nan)
    return flash
