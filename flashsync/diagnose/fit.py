"""Fit a model (a set of effects) to the measurement and score it.

The model is linear in its parameters once its frame clocks and readout rows are fixed:
each edge gives one equation (see :mod:`flashsync.diagnose.effects`), unknowns are the
flashes' global times, the cameras' shifts, the shared exposure and the effects' columns.
It is solved by iteratively reweighted least squares under a Cauchy (Student-t, one degree
of freedom) likelihood with a fitted scale, no smaller than the edge noise the band lengths
show, so one bad edge neither moves the fit nor names an effect, while a step or a trend
shared by many edges weighs in full. Each camera's stamps are a second stream: their
residuals about the model's frame clock get a Cauchy likelihood of their own.

A model's score is its Bayesian information criterion over both streams::

    BIC = 2 * (negative log-likelihood) + (number of parameters) * ln(number of observations)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flashsync.diagnose.effects import CATALOGUE, DROPPED_FRAMES, EXPOSURE, FLIPPED, FRAME_CLOCK, Features
from flashsync.diagnose.measure import Measurement, readout_rows

#: Floor of a fitted residual scale, ms (exact stamps would otherwise have zero scale).
MIN_SCALE_MS = 1e-3
#: Most reweighting rounds of the robust fit and of a scale estimate; they stop earlier once
#: the scale changes by less than CONVERGED (relative).
ITERATIONS = 100
CONVERGED = 1e-5
#: Columns whose smallest singular value (unit-norm columns) is below this are undetermined.
MIN_SINGULAR = 1e-9


@dataclass(frozen=True, order=True)
class Term:
    """An effect applied to one camera (index into :attr:`Measurement.cameras`)."""

    effect: str
    camera: int


@dataclass(frozen=True)
class ModelClock:
    """A camera's frame times under a model of the ladder: ``offset + slot * period`` (the
    pipeline's :class:`flashsync.frame_clock.FrameClock` is the full model; here each part
    of it is an effect the workflow may or may not have added).

    Attributes
    ----------
    offset_ms, period_ms : float
        Time of slot 0 and frame period, ms.
    slots : int array of shape (n_frames,)
        Frame slot of each decoded frame (its index, or counted from the stamp gaps).
    median_step_ms : float
        The camera's median stamp step, ms.
    """

    offset_ms: float
    period_ms: float
    slots: np.ndarray
    median_step_ms: float

    @property
    def times_ms(self) -> np.ndarray:
        return self.offset_ms + self.slots * self.period_ms

    @property
    def missing(self) -> int:
        """Frame slots without a decoded frame."""
        return int(self.slots[-1] + 1 - len(self.slots))


def model_clock(stamps_ms: np.ndarray, count_gaps: bool, least_squares: bool) -> ModelClock:
    """The model's frame clock of one camera.

    Parameters
    ----------
    stamps_ms : array of shape (n_frames,)
        Container stamps, ms, increasing.
    count_gaps : bool
        Slots from the stamp gaps (a gap of two median steps skips a slot) instead of the
        frame index.
    least_squares : bool
        Offset and period fitted to all stamps; else the median step and the median offset.
    """
    step = float(np.median(np.diff(stamps_ms)))
    if count_gaps:
        gaps = np.maximum(np.round(np.diff(stamps_ms) / step), 1).astype(np.int64)
        slots = np.concatenate([[0], np.cumsum(gaps)])
    else:
        slots = np.arange(len(stamps_ms))
    if least_squares:
        period, offset = np.polyfit(slots, stamps_ms, 1)
    else:
        period, offset = step, float(np.median(stamps_ms - slots * step))
    return ModelClock(float(offset), float(period), slots, step)


@dataclass(frozen=True)
class Fit:
    """A model fitted to the measurement.

    Attributes
    ----------
    measurement : Measurement
    terms : frozenset of Term
        The effects switched on.
    clocks : list of ModelClock
        Per camera.
    flipped : list of bool
        Per camera: reads bottom-up under the model.
    features : Features
        Each edge's model time, readout row and kind.
    coefficients : dict
        ``(name, camera) -> value`` for ``shift`` (ms), ``exposure`` (ms; camera -1: the
        shared one) and every effect column (see :mod:`flashsync.diagnose.effects`).
    residual_ms : ndarray of shape (n_edges,)
        Measured minus predicted edge times, ms.
    stamp_residual_ms : list of ndarray
        Per camera, stamps minus the model's frame clock, ms.
    scale_ms : float
        Cauchy scale of the edge residuals, ms.
    bic : float
        Bayesian information criterion over edges and stamps.
    """

    measurement: Measurement
    terms: frozenset[Term]
    clocks: list[ModelClock]
    flipped: list[bool]
    features: Features
    coefficients: dict[tuple[str, int], float]
    residual_ms: np.ndarray
    stamp_residual_ms: list[np.ndarray]
    scale_ms: float
    bic: float

    @property
    def reference(self) -> int:
        return self.measurement.reference

    @property
    def rms_ms(self) -> float:
        """RMS of the edge residuals, ms: the gap between model and measurement."""
        return float(np.sqrt(np.mean(self.residual_ms**2)))

    @property
    def stamp_rms_ms(self) -> list[float]:
        """Per camera, RMS of the stamps about the model's frame clock, ms."""
        return [float(np.sqrt(np.mean(r**2))) for r in self.stamp_residual_ms]

    def coefficient(self, name: str, camera: int) -> float:
        """A parameter of the model; 0 where its effect is off."""
        return self.coefficients.get((name, camera), 0.0)

    def nominal_row_time_ms(self, camera: int) -> float:
        """Frame period / image height, ms."""
        return self.clocks[camera].period_ms / self.measurement.cameras[camera].height

    def exposure_ms(self, camera: int) -> float:
        """The camera's exposure (shared one plus its own offset), ms."""
        return self.coefficient(EXPOSURE, -1) + self.coefficient(EXPOSURE, camera)


def fit_model(measurement: Measurement, terms: frozenset[Term]) -> Fit | None:
    """Fit the model with the effects ``terms`` switched on; None when the measurement
    cannot determine its parameters."""
    cameras, edges = measurement.cameras, measurement.edges
    reflected = np.array([Term(FLIPPED, c) in terms for c in range(len(cameras))])
    flipped = [camera.flipped != flip for camera, flip in zip(cameras, reflected)]
    clocks = [
        model_clock(camera.stamps_ms, Term(DROPPED_FRAMES, c) in terms, Term(FRAME_CLOCK, c) in terms)
        for c, camera in enumerate(cameras)
    ]
    frame_ms, q, observed = (np.empty(len(edges)) for _ in range(3))
    for c, (camera, clock) in enumerate(zip(cameras, clocks)):
        mine = edges.camera == c
        frame_ms[mine] = clock.times_ms[edges.frame[mine]]
        q[mine] = readout_rows(edges.row[mine], camera.height, flipped[c])
        observed[mine] = frame_ms[mine] + q[mine] * clock.period_ms / camera.height
        frame_ms[mine] -= 0.5 * (clock.times_ms[0] + clock.times_ms[-1])
    features = Features(edges.camera, frame_ms, q, edges.trailing != reflected[edges.camera])
    keys, design = _design(measurement, terms, features)
    noise = measurement.noise_ms
    solved = robust_fit(design, observed, noise if np.isfinite(noise) else MIN_SCALE_MS)
    if solved is None:
        return None
    parameters, residual, scale = solved
    stamp_residuals = [camera.stamps_ms - clock.times_ms for camera, clock in zip(cameras, clocks)]
    log_likelihood = -cauchy_nll(residual, scale) - sum(cauchy_nll(r, cauchy_scale(r)) for r in stamp_residuals)
    n_parameters = design.shape[1] + 1 + 3 * len(cameras)  # + scales and frame clocks
    n_observations = len(residual) + sum(len(r) for r in stamp_residuals)
    bic = -2.0 * log_likelihood + n_parameters * np.log(n_observations)
    return Fit(
        measurement,
        terms,
        clocks,
        flipped,
        features,
        dict(zip(keys, parameters[: len(keys)].tolist())),
        residual,
        stamp_residuals,
        scale,
        float(bic),
    )


def _design(
    measurement: Measurement, terms: frozenset[Term], features: Features
) -> tuple[list[tuple[str, int]], np.ndarray]:
    """Keys of the named columns and the design, shape (n_edges, n_columns): each other
    camera's shift, the shared exposure, the effects' columns, then one per flash."""
    keys, columns = [], []
    for c in range(len(measurement.cameras)):
        if c != measurement.reference:
            keys.append(("shift", c))
            columns.append(-(features.camera == c).astype(np.float64))
    keys.append((EXPOSURE, -1))
    columns.append(features.trailing.astype(np.float64))
    for term in sorted(terms):
        column = CATALOGUE[term.effect].column
        if column is not None:
            keys.append((term.effect, term.camera))
            columns.append(np.where(features.camera == term.camera, column(features), 0.0))
    flash = measurement.edges.flash
    columns += list((flash[None, :] == np.arange(measurement.n_flashes)[:, None]).astype(np.float64))
    return keys, np.column_stack(columns)


def robust_fit(
    design: np.ndarray, observed: np.ndarray, min_scale_ms: float = MIN_SCALE_MS
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Cauchy IRLS fit of ``observed ≈ design @ parameters``, the scale refined along.

    Parameters
    ----------
    design : array of shape (n, p)
    observed : array of shape (n,), ms
    min_scale_ms : float
        Floor of the scale, ms: with few observations per parameter (four edges per flash)
        a free Cauchy scale collapses onto the few residuals the fit makes vanish.

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
    solution = np.linalg.lstsq(scaled, observed, rcond=None)[0]
    residual = observed - scaled @ solution
    scale = max(float(np.median(np.abs(residual))), min_scale_ms)
    for _ in range(ITERATIONS):
        root = np.sqrt(1.0 / (1.0 + (residual / scale) ** 2))
        solution = np.linalg.lstsq(scaled * root[:, None], observed * root, rcond=None)[0]
        residual = observed - scaled @ solution
        scale, previous = max(_scale_step(residual, scale), min_scale_ms), scale
        if abs(scale - previous) <= CONVERGED * previous:
            break
    return solution / norms, residual, scale


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
