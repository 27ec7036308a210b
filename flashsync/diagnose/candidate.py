"""A candidate model (a set of effects) fitted to the measurement, and its score.

The model is linear in its parameters once its frame clocks and readout rows are fixed:
each edge gives one equation (see :mod:`flashsync.diagnose.effects`), unknowns are the
flashes' global times, the cameras' shifts, the shared exposure and the effects' columns.
It is solved by the pipeline's robust fit (:func:`flashsync.robust.cauchy_fit`: Cauchy IRLS
with a fitted scale, here no smaller than the edge noise the band lengths show), so one bad
edge neither moves the fit nor names an effect, while a step or a trend shared by many edges
weighs in full; each edge is weighted by its camera's edge noise, so a camera with blurry
bands does not drown one with sharp bands. Each camera's stamps are a second stream: their
residuals about the model's frame clock (:class:`flashsync.frame_clock.FrameClock` with the
parts the model's effects switch on) get a Cauchy likelihood of their own. Where a camera saw
rolling mains flicker, the time per row its period tells is a third: Gaussian about the
model's time per row, with the flicker's standard deviation; where the model fits that
camera's time per row, the flicker enters the fit as one more equation, and where it saw
none, ``sync``'s weak nominal prior does; where the model fits a camera's drift, ``sync``'s
drift prior does (:func:`_pseudo_rows`). These equations are Gaussian: they keep their full
weight in the robust fit, whatever the edges say.

A model's score is its Bayesian information criterion over all its streams::

    BIC = 2 * (negative log-likelihood) + (number of parameters) * ln(number of observations)
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np
import pandas as pd
from scipy import linalg

from flashsync.diagnose.effects import (
    CATALOGUE,
    DRIFT,
    DRIFT_RATE,
    DROPPED_FRAMES,
    EXPOSURE,
    FLICKER,
    FLIPPED,
    FRAME_CLOCK,
    PULSE_SHAPE,
    ROW_TIME,
    SATURATION,
    STAMP_RATE,
    CameraEstimate,
    Features,
)
from flashsync.diagnose.measure import Measurement
from flashsync.frame_clock import FrameClock
from flashsync.match import NOMINAL_HIDDEN_ROWS
from flashsync.model import MATCHED_EVENT_COLUMNS, CameraClock, SyncModel, readout_rows
from flashsync.pipeline import row_time_prior_ms
from flashsync.robust import MIN_SCALE_MS, cauchy_fit, cauchy_nll
from flashsync.solve import DRIFT_PRIOR_STD, Priors


@dataclass(frozen=True, order=True)
class Term:
    """An effect applied to one camera (index into :attr:`Measurement.cameras`)."""

    effect: str
    camera: int


@dataclass(frozen=True)
class Candidate:
    """A model fitted to the measurement.

    Attributes
    ----------
    measurement : Measurement
    terms : frozenset of Term
        The effects switched on.
    clocks : list of FrameClock
        Per camera, its frame clock under the model (never smoothed): what its stamps are
        compared with.
    timing : list of FrameTiming
        Per camera, its frames' times and period under the model: the clock's, or where
        the stamps change rate and the model says the sensor did not, one rate throughout.
    flipped : list of bool
        Per camera: reads bottom-up under the model.
    features : Features
        Each edge's model time, readout row and kind.
    coefficients : dict
        ``(name, camera) -> value`` for ``shift`` (ms), ``exposure`` (ms; camera -1: the
        shared one) and every effect column (see :mod:`flashsync.diagnose.effects`).
    flash_ms : ndarray of shape (n_flashes,)
        Each flash's global time (the instant its leading edges mark), ms.
    residual_ms : ndarray of shape (n_edges,)
        Measured minus predicted edge times, ms.
    scale_ms : float
        Cauchy scale of the weighted edge residuals (:func:`_edge_weights`), ms.
    bic : float
        Bayesian information criterion over edges, stamps and flicker.
    """

    measurement: Measurement
    terms: frozenset[Term]
    clocks: list[FrameClock]
    timing: list[FrameTiming]
    flipped: list[bool]
    features: Features
    coefficients: dict[tuple[str, int], float]
    flash_ms: np.ndarray
    residual_ms: np.ndarray
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
        return [float(np.sqrt(np.mean(clock.residual_ms**2))) for clock in self.clocks]

    def coefficient(self, name: str, camera: int) -> float:
        """A parameter of the model; 0 where its effect is off."""
        return self.coefficients.get((name, camera), 0.0)

    def edge_shift_ms(self, effects: tuple[str, ...]) -> np.ndarray:
        """How much later the model's ``effects`` put each measured edge than its flash and
        clock alone would, ms, shape (n_edges,): their columns times their parameters."""
        shift = np.zeros(len(self.features.camera))
        for term in self.terms:
            if term.effect in effects:
                values = CATALOGUE[term.effect].column(self.features).reshape(len(shift), -1)
                parameters = [self.coefficient(_key(term.effect, i), term.camera) for i in range(values.shape[1])]
                mine = self.features.camera == term.camera
                shift[mine] += values[mine] @ parameters
        return shift

    def _parameters(self, keys: list[tuple[str, int]]) -> np.ndarray:
        """The named parameters in the order of ``keys``, then the flash times."""
        return np.concatenate([[self.coefficients[key] for key in keys], self.flash_ms])

    def nominal_row_time_ms(self, camera: int) -> float:
        """Frame period / image height, ms."""
        return self.timing[camera].period_ms / self.measurement.cameras[camera].height

    def row_time_ms(self, camera: int) -> float:
        """The camera's time per row under the model, ms: its base (:func:`_base_row_time_ms`)
        plus the ``row_time`` effect's correction."""
        return _base_row_time_ms(self.measurement, self.terms, self.timing, camera) + self.coefficient(ROW_TIME, camera)

    @property
    def flicker_gap_ms(self) -> list[float]:
        """Per camera, how far the time per row its rolling flicker tells is off the model's,
        over the image height, ms; NaN where it saw no flicker."""
        return [
            abs(self.row_time_ms(c) - self.measurement.flicker_row_time_ms(c)[0]) * camera.height
            for c, camera in enumerate(self.measurement.cameras)
        ]

    def exposure_ms(self, camera: int) -> float:
        """The camera's exposure (shared one plus its own offset), ms."""
        return self.coefficient(EXPOSURE, -1) + self.coefficient(EXPOSURE, camera)

    def physical(self, cameras: set[int]) -> bool:
        """Each of ``cameras`` has a positive time per row and exposure under this model (a
        fit may reach either sign: a time per row below zero reads the rows the other way)."""
        return all(self.row_time_ms(c) > 0 and self.exposure_ms(c) > 0 for c in cameras)

    def estimates(self) -> list[CameraEstimate]:
        """Every camera under this model, in plain numbers."""
        stamp_rms = self.stamp_rms_ms
        return [
            CameraEstimate(
                camera=camera.camera,
                reference=c == self.reference,
                flipped=bool(self.flipped[c]),
                frame_period_ms=self.timing[c].period_ms,
                median_step_ms=clock.median_step_ms,
                missing_frames=clock.missing,
                rate_changes=clock.rate_changes,
                stamp_rms_ms=stamp_rms[c],
                drift_ppm=1e6 * self.coefficient(DRIFT, c),
                drift_rate_ppm_per_s=2e9 * self.coefficient(DRIFT_RATE, c),
                shift_ms=self.coefficient("shift", c),
                row_time_ms=self.row_time_ms(c),
                nominal_row_time_ms=self.nominal_row_time_ms(c),
                exposure_ms=self.exposure_ms(c),
                saturation_ms=self.coefficient(SATURATION, c),
                saturation_share=self.coefficient(_key(SATURATION, 1), c),
                pulse_trailing=self.coefficient(PULSE_SHAPE, c),
                pulse_leading=self.coefficient(_key(PULSE_SHAPE, 1), c),
                longest_excess_ms=float(np.max(self.features.excess_ms[self.features.camera == c], initial=0.0)),
                flicker_hz=flicker.hz if flicker else np.nan,
                flicker_depth=flicker.depth if flicker else np.nan,
                flicker_period_rows=flicker.period_rows if flicker else np.nan,
                flicker_row_time_ms=self.measurement.flicker_row_time_ms(c)[0],
                effects=sorted(t.effect for t in self.terms if t.camera == c),
            )
            for c, (camera, clock, flicker) in enumerate(
                zip(self.measurement.cameras, self.clocks, self.measurement.flicker or (None,) * len(self.clocks))
            )
        ]

    def sync_model(self) -> SyncModel:
        """This model as the pipeline's :class:`~flashsync.model.SyncModel` (what ``flashsync
        sync`` writes and ``restamp`` uses).

        Each camera's frame times are its frame clock's under the model (the ladder, free of
        the stamps' jitter); its map is ``alpha = 1 + drift``, ``beta`` the shift about its
        mid time, the time per row the model's, and a drift-rate change the
        piecewise-linear warp at :data:`WARP_KNOTS` interior knots. The covariance of
        (alpha, beta, time per row) is the robust fit's (Cauchy weights, residual scale);
        the matched events are the leading edges of the measured bands, with their residuals.
        """
        measurement = self.measurement
        keys, design = _design(measurement, self.terms, self.features)
        weight = _edge_weights(measurement)
        weighted = self.residual_ms * weight
        rows, observed, row_weight = _pseudo_rows(measurement, self.terms, self.timing, keys)
        covariance = _covariance(
            np.vstack([design * weight[:, None], rows * row_weight[:, None]]),
            np.concatenate([weighted, (observed - rows @ self._parameters(keys)) * row_weight]),
            self.scale_ms,
            n_fixed=len(rows),
        )
        clocks = {}
        for c, (camera, clock, timing) in enumerate(zip(measurement.cameras, self.clocks, self.timing)):
            ladder = timing.times_ms
            mid = 0.5 * (ladder[0] + ladder[-1])
            half = 0.5 * (ladder[-1] - ladder[0])
            drift, rate = self.coefficient(DRIFT, c), self.coefficient(DRIFT_RATE, c)
            knots = np.linspace(ladder[0], ladder[-1], WARP_KNOTS + 2) if rate else np.zeros(0)
            warp = rate * ((knots[1:-1] - mid) ** 2 - half**2)
            gradient = np.zeros((3, design.shape[1]))  # d(alpha, beta, T_row) / d(parameters)
            for name, row, factor in (("shift", 1, 1.0), (DRIFT, 0, 1.0), (DRIFT, 1, -mid), (ROW_TIME, 2, 1.0)):
                if (name, c) in keys:
                    gradient[row, keys.index((name, c))] = factor
            block = np.zeros((3 + len(warp),) * 2)
            block[:3, :3] = gradient @ covariance @ gradient.T
            if Term(FLICKER, c) in self.terms and (ROW_TIME, c) not in keys:
                block[2, 2] = measurement.flicker_row_time_ms(c)[1] ** 2
            clocks[camera.camera] = CameraClock(
                camera.camera,
                ladder,
                camera.height,
                camera.width,
                alpha=1.0 + drift,
                beta_ms=self.coefficient("shift", c) - drift * mid + rate * half**2,
                row_time_ms=self.row_time_ms(c),
                flipped=bool(self.flipped[c]),
                covariance=block,
                exposure_ms=self.exposure_ms(c),
                video=str(camera.video),
                drift_knots_ms=knots,
                drift_warp_ms=warp,
                frame_std_ms=clock.std_ms,
                display_rotation_deg=camera.display_rotation_deg,
            )
        edges = measurement.edges
        leading = ~self.features.trailing
        names = np.array([camera.camera for camera in measurement.cameras])
        events = pd.DataFrame(
            {
                "flash": edges.flash[leading],
                "camera": names[edges.camera[leading]],
                "event": edges.event[leading],
                "frame": edges.frame[leading],
                "row": edges.row[leading],
                "t_frame_ms": [self.timing[c].times_ms[f] for c, f in zip(edges.camera[leading], edges.frame[leading])],
                "t_global_ms": self.flash_ms[edges.flash[leading]],
                "residual_ms": self.residual_ms[leading],
                "inlier": np.abs(weighted[leading]) <= INLIER_SCALES * self.scale_ms,
            }
        ).astype(MATCHED_EVENT_COLUMNS)
        return SyncModel(names[self.reference], clocks, events)


#: Interior knots of the warp that carries a drift-rate change into a :class:`SyncModel`
#: (the parabola's chord error over a segment is rate x (length / 2)**2: 0.005 ms for
#: 100 ppm/s over 40 s).
WARP_KNOTS = 64
#: An edge whose residual is within this many Cauchy scales counts as an inlier of the model.
INLIER_SCALES = 5.0


def _covariance(design: np.ndarray, residual: np.ndarray, scale: float, n_fixed: int) -> np.ndarray:
    """Covariance of a Cauchy IRLS fit's parameters, shape (p, p): ``s**2 (X' W X)^-1`` with
    the final Cauchy weights ``W`` (1 on the last ``n_fixed`` rows, the Gaussian ones) and
    ``s**2`` their weighted mean squared residual over the degrees of freedom."""
    weights = 1.0 / (1.0 + (residual / scale) ** 2)
    weights[len(weights) - n_fixed :] = 1.0
    dof = max(weights.sum() - design.shape[1], 1.0)
    variance = float(np.sum(weights * residual**2) / dof)
    return variance * np.linalg.pinv(design.T @ (design * weights[:, None]))


@dataclass(frozen=True)
class FrameTiming:
    """A camera's frame times under a model.

    Attributes
    ----------
    times_ms : ndarray of shape (n_frames,)
        Each decoded frame's time, ms.
    period_ms : float
        Frame period, ms.
    """

    times_ms: np.ndarray
    period_ms: float


def frame_timings(clock: FrameClock, one_rate: bool) -> list[FrameTiming]:
    """The frame times a model may give a camera: its clock's ladder; with ``one_rate``,
    instead, where its stamps change rate, one per rate of its segments as if the sensor
    had kept that rate throughout (:meth:`FrameClock.one_rate_alternatives`), none without
    a rate change."""
    if not one_rate:
        return [FrameTiming(clock.ladder_ms, clock.period_ms)]
    slots = clock.slots[-1] - clock.slots[0]
    return [FrameTiming(times, float((times[-1] - times[0]) / slots)) for _, times in clock.one_rate_alternatives()]


def fit_candidate(measurement: Measurement, terms: frozenset[Term]) -> Candidate | None:
    """Fit the model with the effects ``terms`` switched on; None when the measurement
    cannot determine its parameters. Where a camera's frame times leave a choice (a stamp
    rate change), the choice with the lowest BIC."""
    cameras = measurement.cameras
    reflected = np.array([Term(FLIPPED, c) in terms for c in range(len(cameras))])
    flipped = [bool(camera.flipped != flip) for camera, flip in zip(cameras, reflected)]
    parts = [(c, Term(DROPPED_FRAMES, c) in terms, Term(FRAME_CLOCK, c) in terms) for c in range(len(cameras))]
    clocks = [measurement.frame_clock(*part) for part in parts]
    stamp_nll = sum(measurement.stamp_nll(*part) for part in parts)
    choices = [frame_timings(clock, Term(STAMP_RATE, c) in terms) for c, clock in enumerate(clocks)]
    fits = [
        fit
        for timing in product(*choices)
        if (fit := _fit(measurement, terms, clocks, stamp_nll, list(timing), flipped, reflected)) is not None
    ]
    return min(fits, key=lambda fit: fit.bic) if fits else None


def _fit(
    measurement: Measurement,
    terms: frozenset[Term],
    clocks: list[FrameClock],
    stamp_nll: float,
    timing: list[FrameTiming],
    flipped: list[bool],
    reflected: np.ndarray,
) -> Candidate | None:
    """The model with these frame clocks (stamps; ``stamp_nll`` the negative log-likelihood
    of the stamps about them, :meth:`Measurement.stamp_nll` summed) and frame times (edges)."""
    cameras, edges = measurement.cameras, measurement.edges
    frame_ms, q, observed = (np.empty(len(edges)) for _ in range(3))
    for c, (camera, times) in enumerate(zip(cameras, timing)):
        mine = edges.camera == c
        frame_ms[mine] = times.times_ms[edges.frame[mine]]
        q[mine] = readout_rows(edges.row[mine], camera.height, flipped[c])
        observed[mine] = frame_ms[mine] + q[mine] * _base_row_time_ms(measurement, terms, timing, c)
        frame_ms[mine] -= 0.5 * (times.times_ms[0] + times.times_ms[-1])
    features = Features(
        edges.camera,
        frame_ms,
        q,
        edges.trailing != reflected[edges.camera],
        edges.saturated,
        edges.excess_ms,
        edges.clip_ms,
        edges.split,
    )
    keys, design = _design(measurement, terms, features)
    noise = measurement.noise_ms
    weight = _edge_weights(measurement)
    rows, row_observed, row_weight = _pseudo_rows(measurement, terms, timing, keys)
    solved = cauchy_fit(
        np.vstack([design * weight[:, None], rows * row_weight[:, None]]),
        np.concatenate([observed * weight, row_observed * row_weight]),
        noise if np.isfinite(noise) else MIN_SCALE_MS,
        n_fixed=len(rows),
    )
    if solved is None:
        return None
    parameters, weighted, scale = solved
    weighted = weighted[: len(edges)]
    residual = weighted / weight
    coefficients = dict(zip(keys, parameters[: len(keys)].tolist()))
    flicker_nll, n_flicker = _flicker_nll(measurement, terms, timing, coefficients)
    log_likelihood = -cauchy_nll(weighted, scale) - stamp_nll - flicker_nll
    n_parameters = design.shape[1] + 1 + 3 * len(cameras)  # + scales and frame clocks
    n_observations = len(residual) + sum(len(clock.stamps_ms) for clock in clocks) + n_flicker
    bic = -2.0 * log_likelihood + n_parameters * np.log(n_observations)
    return Candidate(
        measurement,
        terms,
        clocks,
        timing,
        flipped,
        features,
        coefficients,
        parameters[len(keys) :],
        residual,
        scale,
        float(bic),
    )


def _base_row_time_ms(
    measurement: Measurement, terms: frozenset[Term], timing: list[FrameTiming], camera: int
) -> float:
    """The camera's time per row before the ``row_time`` effect, ms: its rolling flicker's
    where the ``flicker`` effect is on, else frame period / height."""
    if Term(FLICKER, camera) in terms:
        return measurement.flicker_row_time_ms(camera)[0]
    return timing[camera].period_ms / measurement.cameras[camera].height


def _pseudo_rows(
    measurement: Measurement, terms: frozenset[Term], timing: list[FrameTiming], keys: list[tuple[str, int]]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fit's equations beyond the edges, those of ``sync``'s solve: on the cameras whose
    time per row the model fits (``row_time``), their priors, each ``correction = its
    rolling flicker's time per row - base`` where it saw flicker, else the weak prior's
    (:func:`~flashsync.pipeline.row_time_prior_ms` of the frame period /
    (:data:`~flashsync.match.NOMINAL_HIDDEN_ROWS` x height)), the weak priors of cameras of
    one size and rate correlated (:attr:`Measurement.readout_groups`); per camera
    whose drift it fits (but those of :attr:`Measurement.free_drift`), the drift prior (0,
    std :data:`~flashsync.solve.DRIFT_PRIOR_STD`). Design rows of shape
    (k, len(keys) + n_flashes), whitened (a root of the priors' information), right-hand
    sides (k,) and weights (k,) that put them on the edges' scale (the pooled edge noise)."""
    noise = measurement.noise_ms if np.isfinite(measurement.noise_ms) else MIN_SCALE_MS
    row_times, base = {}, {}
    for c, camera in enumerate(measurement.cameras):
        if (ROW_TIME, c) in keys:
            base[c] = _base_row_time_ms(measurement, terms, timing, c)
            row_times[c] = measurement.flicker_row_time_ms(c)
            if not np.isfinite(row_times[c][0]):
                row_times[c] = row_time_prior_ms(timing[c].period_ms / (NOMINAL_HIDDEN_ROWS * camera.height))
    groups = tuple(tuple(c for c in group if c in row_times) for group in measurement.readout_groups)
    priors = Priors(row_times, shared_readout=groups)
    cameras, mean, information = priors.row_time_information()
    root = linalg.cholesky(information) if len(cameras) else np.zeros((0, 0))
    drifts = [c for c in range(len(measurement.cameras)) if (DRIFT, c) in keys and c not in measurement.free_drift]
    rows = np.zeros((len(cameras) + len(drifts), len(keys) + measurement.n_flashes))
    rows[np.ix_(range(len(cameras)), [keys.index((ROW_TIME, c)) for c in cameras])] = root
    for row, c in enumerate(drifts, start=len(cameras)):
        rows[row, keys.index((DRIFT, c))] = 1.0 / DRIFT_PRIOR_STD
    observed = np.concatenate([root @ (mean - np.array([base[c] for c in cameras])), np.zeros(len(drifts))])
    return rows, observed, np.full(len(rows), noise)


def _flicker_nll(
    measurement: Measurement, terms: frozenset[Term], timing: list[FrameTiming], coefficients: dict
) -> tuple[float, int]:
    """Gaussian negative log-likelihood of the flicker stream under a model, and its number
    of observations: each camera's flicker time per row about the model's."""
    nll, count = 0.0, 0
    for c in range(len(measurement.cameras)):
        row_time, std = measurement.flicker_row_time_ms(c)
        if np.isfinite(row_time):
            model = _base_row_time_ms(measurement, terms, timing, c) + coefficients.get((ROW_TIME, c), 0.0)
            nll += 0.5 * ((model - row_time) / std) ** 2 + np.log(np.sqrt(2.0 * np.pi) * std)
            count += 1
    return nll, count


def _edge_weights(measurement: Measurement) -> np.ndarray:
    """Each edge's weight in the fit, shape (n_edges,): the pooled edge noise over its
    camera's (1 where unknown), so that a camera with sharp bands is not drowned by one with
    noisy ones."""
    weight = measurement.noise_ms / measurement.camera_noise_ms[measurement.edges.camera]
    return np.where(np.isfinite(weight) & (weight > 0), weight, 1.0)


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
            values = column(features).reshape(len(features.camera), -1)
            for i, values in enumerate(values.T):
                keys.append((_key(term.effect, i), term.camera))
                columns.append(np.where(features.camera == term.camera, values, 0.0))
    flash = measurement.edges.flash
    columns += list((flash[None, :] == np.arange(measurement.n_flashes)[:, None]).astype(np.float64))
    return keys, np.column_stack(columns)


def _key(effect: str, i: int) -> str:
    """The name of an effect's ``i``-th parameter (its column in the design)."""
    return f"{effect}.{i}" if i else effect
