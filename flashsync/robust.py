"""Robust statistics and the one robust fit: iteratively reweighted least squares under a
Cauchy likelihood, used by the joint solve (:mod:`flashsync.solve`, a sparse system) and by
``diagnose`` (:func:`cauchy_fit`, a dense one).

A Cauchy (Student-t, one degree of freedom) weight ``1 / (1 + (r / s)**2)`` lets one bad
observation neither move a fit nor hide in its scale, while a structure shared by many
observations weighs in full.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.linalg import lapack

#: A Gaussian's standard deviation over its median absolute deviation.
MAD_TO_SIGMA = 1.4826
#: Floor of a fitted residual scale, ms: below a microsecond, residuals are all equal (and
#: exact stamps would otherwise have zero scale).
MIN_SCALE_MS = 1e-3
#: Most reweighting rounds of :func:`cauchy_fit` and of :func:`cauchy_scale`; they stop
#: earlier once the scale changes by less than CONVERGED (relative).
ITERATIONS = 100
CONVERGED = 1e-5
#: Columns whose smallest singular value (unit-norm columns) is below this are undetermined.
MIN_SINGULAR = 1e-9
#: Smallest reciprocal condition number (LAPACK's 1-norm estimate) of the weighted normal
#: equations, columns scaled to unit norm, that :func:`cauchy_fit` solves by Cholesky; below it
#: (nearly dependent columns, or the rows that tell them apart all but weighed out), by lstsq's
#: SVD. The normal equations square the design's condition number: at 1e6 (a weighted design's
#: 400-1000) their error bound is 2e-10 relative, lstsq's 2e-13. Over the 185,039 weighted
#: solves of ``diagnose`` on eight cached rigs of 3-8 cameras, the weighted designs' condition
#: numbers were at most 387 (unweighted 101) and Cholesky's solutions lay at most 2e-12
#: relative from lstsq's, 6x faster (0.085 ms against 0.55 ms); the 12-camera rig S620-630
#: falls back on 103 of its 158,939 (condition numbers 404-4,770).
NORMAL_RCOND = 1e-6


def mad_sigma(values: np.ndarray, floor: float = 0.0) -> float:
    """Robust standard deviation of values about zero: :data:`MAD_TO_SIGMA` x their median
    absolute value, at least ``floor`` (``floor`` for no values)."""
    values = np.asarray(values)
    return max(MAD_TO_SIGMA * float(np.median(np.abs(values))), floor) if values.size else floor


def cauchy_irls(
    solve: Callable[[np.ndarray], np.ndarray],
    residuals: Callable[[np.ndarray], np.ndarray],
    n_observations: int,
    scale: Callable[[np.ndarray, float | None], float],
    iterations: int,
    converged: float | None = None,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Iteratively reweighted least squares with Cauchy weights.

    Starts from the unweighted solution; each round weighs every observation by
    ``1 / (1 + (r / s)**2)``, ``r`` its residual and ``s`` the Cauchy scale of the last
    residuals, and solves again.

    Parameters
    ----------
    solve : callable
        ``solve(weights)``: the weighted least-squares solution for weights of shape
        (n_observations,).
    residuals : callable
        ``residuals(solution)``: array of shape (n_observations,).
    n_observations : int
    scale : callable
        ``scale(residuals, previous)``: the Cauchy scale of residuals (``previous`` is the
        last scale, None at the start).
    iterations : int
        Reweighted solves at most.
    converged : float, optional
        Stop once the scale changes by at most this fraction; None: never early.

    Returns
    -------
    (solution, residuals, scale of those residuals)
    """
    solution = solve(np.ones(n_observations))
    residual = residuals(solution)
    current = scale(residual, None)
    for _ in range(iterations):
        solution = solve(1.0 / (1.0 + (residual / current) ** 2))
        residual = residuals(solution)
        current, previous = scale(residual, current), current
        if converged is not None and abs(current - previous) <= converged * previous:
            break
    return solution, residual, current


def cauchy_fit(
    design: np.ndarray, observed: np.ndarray, min_scale_ms: float = MIN_SCALE_MS, n_fixed: int = 0
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """:func:`cauchy_irls` fit of ``observed ≈ design @ parameters`` (dense), with the
    maximum-likelihood Cauchy scale refined along.

    Parameters
    ----------
    design : array of shape (n, p)
    observed : array of shape (n,), ms
    min_scale_ms : float
        Floor of the scale, ms: with few observations per parameter (four edges per flash)
        a free Cauchy scale collapses onto the few residuals the fit makes vanish.
    n_fixed : int
        The last rows are Gaussian (priors, pseudo-observations): they keep their full
        weight and stay out of the scale.

    Returns
    -------
    (parameters (p,), residuals (n,) in ms, Cauchy scale in ms), or None when the columns
    are not independent.
    """
    norms = np.linalg.norm(design, axis=0)
    if np.any(norms == 0):
        return None
    scaled = design / norms
    singular = np.linalg.svd(scaled, compute_uv=False)
    if singular[-1] < MIN_SINGULAR * singular[0]:
        return None

    robust = len(observed) - n_fixed

    def solve(weights: np.ndarray) -> np.ndarray:
        return _weighted_least_squares(scaled, observed, np.concatenate([weights[:robust], np.ones(n_fixed)]))

    def scale(residual: np.ndarray, previous: float | None) -> float:
        residual = residual[:robust]
        if previous is None:
            return max(float(np.median(np.abs(residual))), min_scale_ms)
        return max(_scale_step(residual, previous), min_scale_ms)

    solution, residual, final = cauchy_irls(
        solve, lambda x: observed - scaled @ x, len(observed), scale, ITERATIONS, CONVERGED
    )
    return solution / norms, residual, final


def _weighted_least_squares(design: np.ndarray, observed: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Weighted least-squares solution (p,) of ``observed ≈ design @ solution``, design (n, p),
    observed (n,) ms, row weights (n,): by Cholesky of the normal equations (their columns
    scaled to unit norm) where these are well conditioned (:data:`NORMAL_RCOND`), else by lstsq."""
    weighted = design * weights[:, None]
    normal = design.T @ weighted
    unit = 1.0 / np.sqrt(np.diag(normal))
    normal *= unit[:, None] * unit
    factor, info = lapack.dpotrf(normal)
    if info == 0 and lapack.dpocon(factor, np.abs(normal).sum(axis=0).max())[0] >= NORMAL_RCOND:
        return unit * lapack.dpotrs(factor, unit * (weighted.T @ observed))[0]
    root = np.sqrt(weights)
    return np.linalg.lstsq(design * root[:, None], observed * root, rcond=None)[0]


def cauchy_scale(residual: np.ndarray) -> float:
    """Maximum-likelihood scale (ms) of a Cauchy distribution centred on zero, at least
    :data:`MIN_SCALE_MS`: the fixed point of :func:`_scale_step`, started from the median
    absolute residual."""
    scale = max(float(np.median(np.abs(residual))), MIN_SCALE_MS)
    for _ in range(ITERATIONS):
        scale, previous = _scale_step(residual, scale), scale
        if abs(scale - previous) <= CONVERGED * previous:
            break
    return scale


def _scale_step(residual: np.ndarray, scale: float) -> float:
    """``sqrt(2 * mean(w * r**2))`` with Cauchy weights ``w = 1 / (1 + (r / scale)**2)``."""
    weights = 1.0 / (1.0 + (residual / scale) ** 2)
    return max(float(np.sqrt(2.0 * np.mean(weights * residual**2))), MIN_SCALE_MS)


def cauchy_nll(residual: np.ndarray, scale: float) -> float:
    """Negative log-likelihood of residuals under a Cauchy distribution of scale ``scale``."""
    return float(np.sum(np.log1p((residual / scale) ** 2)) + len(residual) * np.log(np.pi * scale))
