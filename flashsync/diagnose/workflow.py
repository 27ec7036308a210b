"""The discrepancy workflow: find the effects the time model misses, one at a time.

Starting from the plainest model (see :mod:`flashsync.diagnose.effects`), each round fits
every candidate (an effect of the catalogue on one camera, added to the current model) and
keeps the one that lowers the Bayesian information criterion most, among those that lower
it by more than :data:`THRESHOLD` and shrink the gap (the RMS of the edge residuals);
without such a candidate the residuals hold nothing the catalogue can explain and the loop
stops. The final residuals are then compared with the edge noise the band lengths show. The data never say which effect is there: frame stamps and band edges only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from flashsync.detect import CameraDetection
from flashsync.diagnose.effects import CATALOGUE, DRIFT, DRIFT_RATE, OTHER_CAMERAS, ROW_TIME
from flashsync.diagnose.fit import Fit, Term, fit_model
from flashsync.diagnose.measure import Measurement, measure
from flashsync.errors import FlashsyncError

#: Smallest drop of the BIC that adds an effect: "very strong" evidence (Kass & Raftery 1995).
THRESHOLD = 10.0
#: Residuals are consistent with noise when their RMS is within this factor of what the edge
#: noise seen in band lengths would leave. Band lengths miss the errors common to both edges
#: of a band (the sub-row bias of locating a half-rise on a curved ramp), which make the
#: residuals of a complete model 1 to 3 times that in simulations.
NOISE_FACTOR = 3.0


@dataclass(frozen=True)
class Step:
    """One effect added to the model.

    Attributes
    ----------
    effect, title : str
        Catalogue key and words for it.
    camera : str
    delta_bic : float
        How much the BIC fell, over edges and stamps.
    estimate : str
        What the effect's parameter came out as (the structure it explains).
    rms_before_ms, rms_after_ms : float
        RMS of the edge residuals before and after, ms.
    stamp_rms_before_ms, stamp_rms_after_ms : float
        RMS of the camera's stamps about its frame clock before and after, ms.
    """

    effect: str
    title: str
    camera: str
    delta_bic: float
    estimate: str
    rms_before_ms: float
    rms_after_ms: float
    stamp_rms_before_ms: float
    stamp_rms_after_ms: float

    @property
    def evidence(self) -> str:
        return f"ΔBIC {self.delta_bic:.1f} > {THRESHOLD:g}: {self.estimate}"


@dataclass(frozen=True)
class Diagnosis:
    """What :func:`diagnose` found.

    Attributes
    ----------
    cameras : list of str
        Cameras compared, input order.
    reference : str
    n_flashes, n_edges : int
        Flashes matched across cameras and their band edges.
    steps : list of Step
        Effects added, in order.
    initial_rms_ms, final_rms_ms : float
        RMS of the edge residuals of the plain and the final model, ms.
    expected_ms : float
        RMS the edge noise seen in band lengths (:attr:`Measurement.noise_ms`) would leave
        after fitting the final model's parameters, ms; NaN when unknown.
    consistent : bool
        ``final_rms_ms <= NOISE_FACTOR * expected_ms``.
    model : list of dict
        Final model per camera (readout, frame clock, drift, shift, time per row, exposure).
    residuals : dict
        ``{"initial": [...], "final": [...]}``: per camera, the residual structure (RMS,
        trend against time and row, trailing-minus-leading gap, frame intervals).
    warnings : list of str
    """

    cameras: list[str]
    reference: str
    n_flashes: int
    n_edges: int
    steps: list[Step]
    initial_rms_ms: float
    final_rms_ms: float
    expected_ms: float
    consistent: bool
    model: list[dict]
    residuals: dict[str, list[dict]]
    warnings: list[str] = field(default_factory=list)

    @property
    def verdict(self) -> str:
        """One line on the final residuals against the noise."""
        if not np.isfinite(self.expected_ms):
            return (f"residuals RMS {self.final_rms_ms:.4f} ms; noise unknown (fewer than three "
                    "bands of a kind per camera)")
        numbers = f"RMS {self.final_rms_ms:.4f} ms, expected {self.expected_ms:.4f} ms"
        if self.consistent:
            return f"residuals consistent with noise ({numbers})"
        return (f"residuals exceed the noise ({numbers}, more than {NOISE_FACTOR:g}x): an effect "
                "outside the catalogue remains, or the measurement cannot separate the ones it has")

    def to_dict(self) -> dict:
        """Plain dict (JSON-able) with every field, each step's evidence and the verdict."""
        data = asdict(self)
        for step, record in zip(self.steps, data["steps"]):
            record["evidence"] = step.evidence
        data.update(verdict=self.verdict, threshold_delta_bic=THRESHOLD, noise_factor=NOISE_FACTOR)
        return _finite(data)


def diagnose(detections: Sequence[CameraDetection], reference: str | None = None) -> Diagnosis:
    """Compare the time model with what the videos measured and add the effects it misses.

    Parameters
    ----------
    detections : one per camera, from :func:`flashsync.pipeline.detect_videos`.
    reference : camera whose clock is the global clock; default the first.

    Returns
    -------
    Diagnosis

    Raises
    ------
    FlashsyncError
        Fewer than two cameras sharing flashes, or too few flashes to fit the plain model.

    Examples
    --------
    >>> d = diagnose(detect_videos(["cam1.mp4", "cam2.mkv"]))   # doctest: +SKIP
    >>> print(format_diagnosis(d))                               # doctest: +SKIP
    """
    measurement = measure(detections, reference)
    plain = fit_model(measurement, frozenset())
    if plain is None:
        raise FlashsyncError(
            f"{measurement.n_flashes} flashes seen by several cameras cannot determine even the "
            "plain model; record more flashes")
    current, steps = plain, []
    while True:
        best: tuple[Term, Fit] | None = None
        for term in _candidates(measurement, current.terms):
            trial = fit_model(measurement, current.terms | _with_implied(term))
            if (trial is not None and current.bic - trial.bic > THRESHOLD and trial.rms_ms < current.rms_ms
                    and (best is None or trial.bic < best[1].bic)):
                best = (term, trial)
        if best is None:
            break
        term, better = best
        effect = CATALOGUE[term.effect]
        steps.append(Step(effect.name, effect.title, measurement.cameras[term.camera].name,
                          current.bic - better.bic, effect.describe(better, term.camera),
                          current.rms_ms, better.rms_ms, current.stamp_rms_ms[term.camera],
                          better.stamp_rms_ms[term.camera]))
        current = better
    return _diagnosis(measurement, plain, current, steps)


def _candidates(measurement: Measurement, terms: frozenset[Term]) -> list[Term]:
    """Every effect on every camera it applies to, not yet in the model, catalogue order."""
    return [Term(effect.name, c) for effect in CATALOGUE.values() for c in range(len(measurement.cameras))
            if Term(effect.name, c) not in terms
            and not (effect.scope == OTHER_CAMERAS and c == measurement.reference)]


def _with_implied(term: Term) -> frozenset[Term]:
    return frozenset([term] + [Term(name, term.camera) for name in CATALOGUE[term.effect].implies])


def _diagnosis(measurement: Measurement, plain: Fit, final: Fit, steps: list[Step]) -> Diagnosis:
    n_edges = len(measurement.edges)
    dof = max(n_edges - measurement.n_flashes - len(final.coefficients), 1)
    expected = measurement.noise_ms * np.sqrt(dof / n_edges)
    return Diagnosis(
        cameras=[c.name for c in measurement.cameras],
        reference=measurement.cameras[measurement.reference].name,
        n_flashes=measurement.n_flashes, n_edges=n_edges, steps=steps,
        initial_rms_ms=plain.rms_ms, final_rms_ms=final.rms_ms, expected_ms=float(expected),
        consistent=bool(final.rms_ms <= NOISE_FACTOR * expected),
        model=_camera_models(final),
        residuals={"initial": residual_structure(plain), "final": residual_structure(final)},
        warnings=list(measurement.warnings))


def _camera_models(fit: Fit) -> list[dict]:
    """The fitted model per camera, in plain numbers."""
    models = []
    for c, (camera, clock) in enumerate(zip(fit.measurement.cameras, fit.clocks)):
        models.append({
            "camera": camera.name, "reference": c == fit.reference,
            "readout": "bottom-up" if fit.flipped[c] else "top-down",
            "frame_period_ms": clock.period_ms, "missing_frames": clock.missing,
            "drift_ppm": 1e6 * fit.coefficient(DRIFT, c),
            "drift_rate_ppm_per_s": 2e9 * fit.coefficient(DRIFT_RATE, c),
            "shift_ms": fit.coefficient("shift", c),
            "row_time_ms": fit.nominal_row_time_ms(c) + fit.coefficient(ROW_TIME, c),
            "exposure_ms": fit.exposure_ms(c),
            "effects": sorted(t.effect for t in fit.terms if t.camera == c)})
    return models


def residual_structure(fit: Fit) -> list[dict]:
    """Per camera: what is left in the edge residuals and the stamps of a fitted model.

    Returns
    -------
    list of dict, one per camera, with ``edges``, ``rms_ms``, ``time_slope_ppm`` and
    ``row_slope_us_per_row`` (least-squares slopes of the residuals against model time and
    readout row), ``trailing_minus_leading_ms`` (mean residual gap between edge kinds),
    ``median_step_ms``, ``long_intervals`` (frame intervals over 1.5 median steps) and
    ``stamp_rms_ms`` (stamps about the model's frame clock).
    """
    structure = []
    for c, (camera, clock) in enumerate(zip(fit.measurement.cameras, fit.clocks)):
        mine = fit.features.camera == c
        residual, trailing = fit.residual_ms[mine], fit.features.trailing[mine]
        steps = np.diff(camera.stamps_ms)
        structure.append({
            "camera": camera.name, "edges": int(mine.sum()),
            "rms_ms": float(np.sqrt(np.mean(residual**2))),
            "time_slope_ppm": 1e6 * _slope(fit.features.t_ms[mine], residual),
            "row_slope_us_per_row": 1e3 * _slope(fit.features.q[mine], residual),
            "trailing_minus_leading_ms": float(np.mean(residual[trailing]) - np.mean(residual[~trailing])),
            "median_step_ms": clock.median_step_ms,
            "long_intervals": int(np.count_nonzero(steps > 1.5 * clock.median_step_ms)),
            "stamp_rms_ms": fit.stamp_rms_ms[c]})
    return structure


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of y against x (0 when x does not vary)."""
    spread = x - x.mean()
    return float(np.sum(spread * y) / np.sum(spread**2)) if np.any(spread) else 0.0


def _finite(value):
    """``value`` with NaN floats as None (JSON has no NaN), recursively."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value
