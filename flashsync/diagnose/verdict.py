"""The verdict on a fitted model's residuals: a χ² test against the edge noise the bands show.

Each edge residual is divided by its camera's edge noise (the scatter of its band lengths,
:attr:`~flashsync.diagnose.measure.Measurement.camera_noise_ms`); the sum of squares is χ²
with the edges less the fitted parameters as degrees of freedom. The residuals are
consistent with noise when its upper tail probability (``scipy.stats.chi2.sf``) is at least
:data:`SIGNIFICANCE`. Where it is not, the same test on each camera's edges and on each
:data:`SPANS`-th of the recording (by flash time) says where the excess is; each part
counts its share of the degrees of freedom.

The fit is robust (one bad edge moves nothing), and so is the test: the edges beyond
:data:`OUTLIER_SIGMAS` noise (a Gaussian edge gets there once in 16 000), if they are no
more than :data:`OUTLIER_SHARE` of all, are isolated bad edges (a codec echo, a moving
object), counted and left out of χ². More of them are structure and stay in.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.stats import chi2

#: The residuals exceed the noise when the χ² test's p-value is below this.
SIGNIFICANCE = 0.01
#: An edge this many of its camera's noise off is an outlier ...
OUTLIER_SIGMAS = 4.0
#: ... when no more than this share of the edges are (at least one edge may be).
OUTLIER_SHARE = 0.05
#: The recording is cut into this many equal spans of flash time to say where an excess is.
SPANS = 4


@dataclass(frozen=True)
class NoiseTest:
    """χ² of the edge residuals against the per-camera edge noise.

    Attributes
    ----------
    chi2 : float
        Sum of squared residuals over their camera's edge noise, outliers left out; NaN
        where no noise is known.
    dof : float
        Degrees of freedom: edges (outliers left out) minus fitted parameters (flash times,
        shifts, exposure, effects' columns).
    p_value : float
        ``chi2.sf(chi2, dof)``; NaN where no noise is known.
    noise_ms : dict
        Camera -> edge noise used, ms.
    outliers : list of str
        Edges left out as outliers, e.g. ``"cam1 flash 3 trailing (4.7 sigma)"``.
    cameras : list of str
        Where the test fails: cameras whose own edges fail it.
    spans_s : list of (float, float)
        Where the test fails: spans of the recording (s after the reference's first frame,
        adjacent failing spans joined) whose edges fail it.
    counted_rms_ms : float
        RMS of the residuals the test counts (outliers left out), ms.
    """

    chi2: float
    dof: float
    p_value: float
    noise_ms: dict[str, float]
    outliers: list[str] = field(default_factory=list)
    cameras: list[str] = field(default_factory=list)
    spans_s: list[tuple[float, float]] = field(default_factory=list)
    counted_rms_ms: float = float("nan")

    @property
    def known(self) -> bool:
        return bool(np.isfinite(self.p_value))

    @property
    def consistent(self) -> bool:
        """The residuals pass the test (p >= :data:`SIGNIFICANCE`); False where no noise is known."""
        return self.known and self.p_value >= SIGNIFICANCE

    def describe(self) -> str:
        """The test in words: statistic, p-value, threshold and, on failure, where the excess is."""
        if not self.known:
            return "noise unknown (fewer than three bands of a kind per camera): no test"
        noise = ", ".join(f"{name} {value:.4f}" for name, value in self.noise_ms.items())
        left_out = f", {len(self.outliers)} outlier edge{'s' * (len(self.outliers) != 1)} out" if self.outliers else ""
        test = (
            f"χ² {self.chi2:.1f} over {self.dof:g} degrees of freedom against the edge noise the band "
            f"lengths show ({noise} ms{left_out}), p = {self.p_value:.2g}"
        )
        if self.consistent:
            return f"residuals consistent with noise: {test} >= {SIGNIFICANCE:g}"
        where = []
        if self.cameras:
            where.append(f"on {', '.join(self.cameras)}")
        if self.spans_s:
            where.append("in " + ", ".join(f"{a:.1f}-{b:.1f} s" for a, b in self.spans_s) + " of the recording")
        excess = f"; the excess is {' and '.join(where)}" if where else "; no single camera or span carries the excess"
        return f"residuals exceed the noise: {test} < {SIGNIFICANCE:g}{excess}"


def noise_test(
    residual_ms: np.ndarray,
    camera: np.ndarray,
    time_s: np.ndarray,
    labels: list[str],
    names: list[str],
    camera_noise_ms: np.ndarray,
    n_parameters: int,
) -> NoiseTest:
    """The χ² test of edge residuals against their cameras' edge noise.

    Parameters
    ----------
    residual_ms : float array of shape (n_edges,)
    camera : int array of shape (n_edges,)
        Index into ``names`` and ``camera_noise_ms``.
    time_s : float array of shape (n_edges,)
        Each edge's flash time, s after the reference's first frame.
    labels : list of str, one per edge
        Words for an edge, e.g. ``"cam1 flash 3 trailing"``.
    names : list of str
    camera_noise_ms : float array of shape (n_cameras,)
        Edge noise per camera, ms (NaN: unknown).
    n_parameters : int
        Parameters fitted to the residuals.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> r = rng.normal(0, 0.02, 200); r[150:] += 0.1
    >>> t = noise_test(r, np.zeros(200, int), np.linspace(0, 40, 200), [""] * 200, ["cam1"], np.array([0.02]), 20)
    >>> t.consistent, t.cameras, t.spans_s
    (False, ['cam1'], [(30.0, 40.0)])
    """
    noise = {name: float(value) for name, value in zip(names, camera_noise_ms)}
    if not np.all(np.isfinite(camera_noise_ms)):
        dof = float(max(len(residual_ms) - n_parameters, 1))
        return NoiseTest(float("nan"), dof, float("nan"), noise, counted_rms_ms=_rms_ms(residual_ms))
    z = residual_ms / camera_noise_ms[camera]
    outlier = np.abs(z) > OUTLIER_SIGMAS
    if outlier.sum() > max(1, OUTLIER_SHARE * len(z)):
        outlier[:] = False
    outliers = [f"{labels[i]} ({abs(z[i]):.1f} sigma)" for i in np.flatnonzero(outlier)]
    counted_rms_ms = _rms_ms(residual_ms[~outlier])
    z2, camera, time_s = z[~outlier] ** 2, camera[~outlier], time_s[~outlier]
    n = len(z2)
    dof = float(max(n - n_parameters, 1))

    def fails(part: np.ndarray) -> bool:
        share = dof * part.sum() / n
        return bool(part.any()) and chi2.sf(z2[part].sum(), max(share, 1.0)) < SIGNIFICANCE

    total = float(z2.sum())
    p_value = float(chi2.sf(total, dof))
    if p_value >= SIGNIFICANCE:
        return NoiseTest(total, dof, p_value, noise, outliers, counted_rms_ms=counted_rms_ms)
    cameras = [name for c, name in enumerate(names) if fails(camera == c)]
    bounds = np.linspace(time_s.min(), time_s.max(), SPANS + 1)
    span = np.clip(np.searchsorted(bounds, time_s, side="right") - 1, 0, SPANS - 1)
    spans: list[tuple[float, float]] = []
    for k in range(SPANS):
        if not fails(span == k):
            continue
        if spans and spans[-1][1] == float(bounds[k]):
            spans[-1] = (spans[-1][0], float(bounds[k + 1]))
        else:
            spans.append((float(bounds[k]), float(bounds[k + 1])))
    return NoiseTest(total, dof, p_value, noise, outliers, cameras, spans, counted_rms_ms)


def _rms_ms(residual_ms: np.ndarray) -> float:
    """Root mean square of residuals, ms."""
    return float(np.sqrt(np.mean(residual_ms**2)))
