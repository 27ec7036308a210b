"""The joint, robust least-squares solve of every camera's clock from matched events.

Each observation of flash ``k`` by camera ``c`` in frame time ``t`` (ms) at readout row
``q`` gives one linear equation in the unknowns (the flash's global time ``tau_k`` is one
of them, so cameras need not share flashes with the reference directly)::

    alpha_c * t + beta_c + q * T_row_c - tau_k = 0          (reference: alpha = 1, beta = 0)

All equations form one sparse system. Drift is solved as ``alpha - 1`` about the camera's
mid time for conditioning. Iteratively reweighted least squares with Cauchy weights keeps a
bad event from moving a camera; events beyond ``reject_sigma`` robust sigmas are rejected
and the final fit uses the rest. Optional priors on ``T_row`` (a datasheet value, or a
weak nominal value where the events cannot tell it) enter as pseudo-observations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sparse
import scipy.sparse.linalg as sparse_linalg

from flashsync.errors import FlashsyncError


@dataclass(frozen=True)
class CameraSolution:
    """One camera's solved clock: ``alpha``, ``beta_ms``, ``row_time_ms`` and their
    covariance (3, 3) in that order."""

    alpha: float
    beta_ms: float
    row_time_ms: float
    covariance: np.ndarray


@dataclass(frozen=True)
class Solution:
    """Result of :func:`solve_clocks`.

    ``residual_ms`` and ``inlier`` have one entry per observation; ``flash_ms`` the global
    time of each flash index (NaN for an index no observation names); ``sigma_ms`` is the
    robust residual scale.
    """

    cameras: list[CameraSolution]
    flash_ms: np.ndarray
    residual_ms: np.ndarray
    inlier: np.ndarray
    sigma_ms: float


def solve_clocks(camera: np.ndarray, flash: np.ndarray, t_frame_ms: np.ndarray, q: np.ndarray,
                 n_cameras: int, reference: int = 0,
                 row_time_prior: dict[int, tuple[float, float]] | None = None,
                 event_sigma_ms: float = 0.05, reject_sigma: float = 5.0,
                 cauchy_k: float = 2.385, iterations: int = 10) -> Solution:
    """Solve all cameras' clocks jointly.

    Parameters
    ----------
    camera, flash : int arrays of shape (n_obs,)
        Camera index (0..n_cameras-1) and flash index (0..n_flashes-1) per observation.
    t_frame_ms : float array of shape (n_obs,)
        Container timestamp of the frame holding the event, ms (camera clock).
    q : float array of shape (n_obs,)
        Readout row of the event edge (sub-row).
    reference : int
        Index of the reference camera.
    row_time_prior : dict camera index -> (mean_ms, std_ms), optional
        Prior knowledge of ``T_row``.
    event_sigma_ms : float
        Expected event-time noise, ms; weighs the priors against the events.

    Raises
    ------
    FlashsyncError
        When the events cannot determine every unknown.
    """
    camera = np.asarray(camera, dtype=np.int64)
    flash = np.asarray(flash, dtype=np.int64)
    t_frame_ms = np.asarray(t_frame_ms, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    flash_ids, flash = np.unique(flash, return_inverse=True)
    system = _System(camera, flash, t_frame_ms, q, n_cameras, len(flash_ids), reference,
                     row_time_prior or {}, event_sigma_ms)
    weights = np.ones(len(camera))
    for _ in range(iterations):
        x = system.solve(weights)
        residual = system.residuals(x)
        sigma = _robust_sigma(residual)
        weights = 1.0 / (1.0 + (residual / (cauchy_k * sigma)) ** 2)
    inlier = np.abs(residual) <= reject_sigma * sigma
    x = system.solve(inlier.astype(np.float64))
    residual = system.residuals(x)
    sigma = _robust_sigma(residual[inlier])
    dof = max(int(inlier.sum()) + system.n_priors - system.n_unknowns, 1)
    scale = float(np.sum(residual[inlier] ** 2)) / dof
    covariance = system.covariance(inlier.astype(np.float64), scale)
    flash_ms = np.full(int(flash_ids.max()) + 1 if flash_ids.size else 0, np.nan)
    flash_ms[flash_ids] = x[system.flash_columns]
    return Solution([system.camera_solution(x, covariance, c) for c in range(n_cameras)],
                    flash_ms, residual, inlier, sigma)


#: Floor of the robust residual scale, ms: below a microsecond, residuals are all equal.
MIN_SIGMA_MS = 1e-3


def _robust_sigma(residual: np.ndarray) -> float:
    """1.4826 x median absolute residual, ms (at least MIN_SIGMA_MS)."""
    return max(1.4826 * float(np.median(np.abs(residual))), MIN_SIGMA_MS) if residual.size else MIN_SIGMA_MS


class _System:
    """The sparse design of :func:`solve_clocks` with columns scaled to unit norm.

    Columns: per camera (drift about mid time, shift at mid time, row time) with the
    reference's first two left out, then one column per flash.
    """

    def __init__(self, camera, flash, t_frame_ms, q, n_cameras, n_flashes, reference,
                 row_time_prior, event_sigma_ms):
        self.camera, self.t_frame_ms, self.q = camera, t_frame_ms, q
        self.reference, self.n_cameras = reference, n_cameras
        self.mid_ms = np.array([np.median(t_frame_ms[camera == c]) if np.any(camera == c) else 0.0
                                for c in range(n_cameras)])
        self.param_columns = np.full((n_cameras, 3), -1)
        column = 0
        for c in range(n_cameras):
            for k in range(3):
                if c != reference or k == 2:
                    self.param_columns[c, k] = column
                    column += 1
        self.flash_columns = column + np.arange(n_flashes)
        self.n_unknowns = column + n_flashes
        rows, cols, values = [], [], []
        n_obs = len(camera)
        index = np.arange(n_obs)
        centred = t_frame_ms - self.mid_ms[camera]
        for k, value in enumerate([centred, np.ones(n_obs), q]):
            columns = self.param_columns[camera, k]
            keep = columns >= 0
            rows.append(index[keep]), cols.append(columns[keep]), values.append(value[keep])
        rows.append(index), cols.append(self.flash_columns[flash]), values.append(-np.ones(n_obs))
        self.rhs = -t_frame_ms.copy()
        self.n_priors = 0
        prior_rhs = []
        for c, (mean, std) in sorted(row_time_prior.items()):
            weight = event_sigma_ms / std
            rows.append(np.array([n_obs + self.n_priors])), cols.append(np.array([self.param_columns[c, 2]]))
            values.append(np.array([weight]))
            prior_rhs.append(weight * mean)
            self.n_priors += 1
        self.rhs = np.concatenate([self.rhs, prior_rhs])
        matrix = sparse.csr_matrix((np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
                                   shape=(n_obs + self.n_priors, self.n_unknowns))
        norms = np.sqrt(np.asarray(matrix.multiply(matrix).sum(axis=0))).ravel()
        if np.any(norms == 0):
            raise FlashsyncError("the matched events leave a camera parameter undetermined; "
                                 "each camera needs events on at least two flashes shared with others")
        self.column_scale = 1.0 / norms
        self.matrix = matrix @ sparse.diags(self.column_scale)

    def _normal(self, weights: np.ndarray):
        all_weights = np.concatenate([weights, np.ones(self.n_priors)])
        weighted = sparse.diags(all_weights) @ self.matrix
        return (self.matrix.T @ weighted).tocsc(), self.matrix.T @ (all_weights * self.rhs)

    def solve(self, weights: np.ndarray) -> np.ndarray:
        normal, right = self._normal(weights)
        n_used = int(np.count_nonzero(weights)) + self.n_priors
        if n_used < self.n_unknowns:
            raise FlashsyncError(
                f"the cameras share too few events: {n_used} equations for {self.n_unknowns} "
                "unknowns; record more flashes seen by several cameras, or give --row-time")
        dense = normal.toarray()
        eigenvalues = np.linalg.eigvalsh(dense)
        if eigenvalues[0] <= 1e-12 * eigenvalues[-1]:
            raise FlashsyncError(
                "the matched events cannot separate every camera's drift, shift and time per row "
                "(too few flashes, or all at the same rows); record more flashes seen by several "
                "cameras, or give --row-time")
        return sparse_linalg.spsolve(normal, right) * self.column_scale

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Observation residuals, ms (alpha t + beta + q T - tau)."""
        n_obs = len(self.camera)
        return ((self.matrix @ (x / self.column_scale)) - self.rhs)[:n_obs]

    def covariance(self, weights: np.ndarray, scale: float) -> np.ndarray:
        """Covariance of the unknowns (unscaled units) for residual variance ``scale``."""
        normal, _ = self._normal(weights)
        inverse = np.linalg.inv(normal.toarray())
        return scale * inverse * np.outer(self.column_scale, self.column_scale)

    def camera_solution(self, x: np.ndarray, covariance: np.ndarray, c: int) -> CameraSolution:
        """Camera ``c``'s (alpha, beta, T_row) and their covariance from (drift, shift at mid, T_row)."""
        columns = self.param_columns[c]
        values = np.array([x[k] if k >= 0 else 0.0 for k in columns])
        local = np.zeros((3, 3))
        used = columns >= 0
        local[np.ix_(used, used)] = covariance[np.ix_(columns[used], columns[used])]
        jacobian = np.array([[1.0, 0.0, 0.0], [-self.mid_ms[c], 1.0, 0.0], [0.0, 0.0, 1.0]])
        drift, shift, row_time = values
        return CameraSolution(1.0 + drift, shift - drift * self.mid_ms[c], row_time,
                              jacobian @ local @ jacobian.T)
