"""The joint, robust least-squares solve of every camera's clock from matched events.

Each observation of flash ``k`` by camera ``c`` in frame time ``t`` (ms) at readout row
``q`` gives one linear equation in the unknowns (the flash's global time ``tau_k`` is one
of them, so cameras need not share flashes with the reference directly)::

    alpha_c * t + beta_c + q * T_row_c - tau_k = 0          (reference: alpha = 1, beta = 0)

A band's trailing edge is timing evidence too: its row's exposure *started* at the flash,
one exposure ``E_c`` (ms, reference clock; one unknown per camera) after the leading edge's
ended::

    alpha_c * t + beta_c + q * T_row_c - tau_k - E_c = 0

So both edges of every band measure the flash, and information inside one camera enters
(docs/architecture.md, "a trap"): a band split across two frames, whose rows skip the hidden
rows, is as long as the camera's unbroken bands, which ties ``T_row_c`` to the frame period.
A band whose both edges are observed enters as their mean (its midpoint, the flash plus half
an exposure) and their difference (its length, the exposure), each with its own noise: its
two edges' errors are seldom independent (an LED pulse as long as the exposure trades them,
a frame's time moves both), those of its midpoint and length nearly are where the edges are
about equally noisy.

All equations form one sparse system. Drift is solved as ``alpha - 1`` about the camera's
mid time for conditioning. Iteratively reweighted least squares with Cauchy weights keeps a
bad event from moving a camera; equations beyond ``reject_sigma`` robust sigmas (a sigma
no smaller than the camera's edge floor, :data:`EDGE_FLOOR_ROWS` of a row) are rejected
and the final fit uses the rest, each weighed by the noise of its camera's equations of
its kind (leading edges and band midpoints; trailing edges and band lengths).
Priors (a datasheet ``T_row``, a weak nominal one, clock drift within a few tens of ppm)
enter as pseudo-observations. A time per row multiplies a measured row, whose noise would
pull it towards zero wherever the rows' spread does not pin it; each solve takes that
noise out of the times per row's information (:meth:`_System._take_row_noise`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sparse
from scipy import linalg
from threadpoolctl import threadpool_limits

from flashsync.compiled import njit
from flashsync.errors import NotEnoughDataError
from flashsync.model import hat_basis
from flashsync.robust import MIN_SCALE_MS, cauchy_irls, mad_sigma


@dataclass(frozen=True)
class Observations:
    """Matched sync events: one entry per (camera, flash) observation.

    ``camera``, ``flash``: int arrays (n,); ``t_frame_ms``: frame timestamps (n,), ms;
    ``q``: readout rows (n,); ``sigma_factor``: each event's noise in units of a clean
    edge's (n,; None: all 1), e.g. :data:`flashsync.detect.SATURATED_EDGE_SIGMA` for a clipped band;
    ``trailing``: bool (n,), the edge is a band's trailing edge, one exposure after the
    flash (None: all leading); ``leading_of``: int (n,), for a trailing edge the index of its
    band's leading edge among these observations, -1 for none and for leading edges (None:
    no pairs); ``split``: bool (n,), a trailing edge whose band is split across two frames
    (None: none). A pair enters the solve as its band's midpoint and length (:class:`_System`).
    """

    camera: np.ndarray
    flash: np.ndarray
    t_frame_ms: np.ndarray
    q: np.ndarray
    sigma_factor: np.ndarray | None = None
    trailing: np.ndarray | None = None
    leading_of: np.ndarray | None = None
    split: np.ndarray | None = None

    def take(self, keep: np.ndarray) -> Observations:
        """The observations a boolean mask (n,) keeps, a trailing edge's ``leading_of``
        renumbered (-1 where its leading edge is not kept)."""
        keep = np.asarray(keep, dtype=bool)

        def kept(values: np.ndarray | None) -> np.ndarray | None:
            return None if values is None else np.asarray(values)[keep]

        leading_of = None
        if self.leading_of is not None:
            index = np.full(len(keep) + 1, -1)  # index[-1] = -1: no leading edge stays none
            index[np.flatnonzero(keep)] = np.arange(np.count_nonzero(keep))
            leading_of = index[np.asarray(self.leading_of)[keep]]
        return Observations(
            kept(self.camera),
            kept(self.flash),
            kept(self.t_frame_ms),
            kept(self.q),
            kept(self.sigma_factor),
            kept(self.trailing),
            leading_of,
            kept(self.split),
        )


#: Prior std of a camera's clock rate about the reference's (``alpha - 1``): oscillators of
#: consumer cameras keep within some tens of ppm.
DRIFT_PRIOR_STD = 50e-6
#: Prior correlation of the times per row of cameras that :attr:`Priors.shared_readout`
#: groups (one size and frame rate: mostly one model, one readout). Where their flashes tell
#: only the differences of their times per row (one rate and phase), their common part is
#: then known as well as one camera's prior tells it, not sqrt(n) better; 0.9 still lets
#: two of them differ by a third of the prior's std.
SHARED_READOUT_CORRELATION = 0.9


@dataclass(frozen=True)
class Priors:
    """Pseudo-observations: ``row_time`` maps a camera index to (mean, std) of ``T_row`` in
    ms; ``drift_std`` is the prior std of ``alpha - 1`` for every camera (None: no prior),
    ``wider_drift_std`` a larger one for some camera indices (a frame clock whose rate is
    uncertain); ``shared_readout`` groups camera indices whose ``row_time`` priors are
    correlated :data:`SHARED_READOUT_CORRELATION` (identical cameras)."""

    row_time: dict[int, tuple[float, float]]
    drift_std: float | None = DRIFT_PRIOR_STD
    wider_drift_std: dict[int, float] = field(default_factory=dict)
    shared_readout: tuple[tuple[int, ...], ...] = ()

    def row_time_information(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The times per row's prior as a Gaussian: the camera indices that have one (k,),
        their means (k,), ms, and the inverse of their covariance (k, k), 1/ms²."""
        cameras = np.array(sorted(self.row_time), dtype=np.int64)
        mean = np.array([self.row_time[c][0] for c in cameras])
        std = np.array([self.row_time[c][1] for c in cameras])
        correlation = np.eye(len(cameras))
        for group in self.shared_readout:
            shared = np.isin(cameras, group)
            correlation[np.ix_(shared, shared)] = SHARED_READOUT_CORRELATION
        np.fill_diagonal(correlation, 1.0)
        return cameras, mean, np.linalg.inv(correlation * np.outer(std, std))

    def without_drift_prior(self, cameras: tuple[int, ...]) -> Priors:
        """These priors with no drift prior on the given camera indices."""
        return replace(self, wider_drift_std={**self.wider_drift_std, **dict.fromkeys(cameras, np.inf)})


@dataclass(frozen=True)
class CameraSolution:
    """One camera's solved clock: ``alpha``, ``beta_ms``, ``row_time_ms``, the warp of a
    clock whose rate changes (values ``warp_ms`` (k,) at the interior of ``knots_ms``
    (k + 2,), both empty for an affine clock), the covariance (3 + k, 3 + k) in that order,
    ``edge_sigma_ms`` and ``trailing_sigma_ms``, the noise of its leading edges and band
    midpoints, and of its trailing edges and band lengths (ms, a clean edge's; NaN without),
    and its exposure (ms, reference clock) with its standard deviation (NaN without trailing
    edges)."""

    alpha: float
    beta_ms: float
    row_time_ms: float
    covariance: np.ndarray
    knots_ms: np.ndarray
    warp_ms: np.ndarray
    edge_sigma_ms: float = float("nan")
    trailing_sigma_ms: float = float("nan")
    exposure_ms: float = float("nan")
    exposure_std_ms: float = float("nan")

    @property
    def row_time_std_ms(self) -> float:
        """Standard deviation of ``row_time_ms``, ms (0 where the covariance holds none)."""
        return float(np.sqrt(max(self.covariance[2, 2], 0.0)))


@dataclass(frozen=True)
class Solution:
    """Result of :func:`solve_clocks`.

    ``residual_ms`` (each edge's own, ms), ``inlier`` and ``sigma_factor`` (the equations'
    noise in units of a clean edge's) have one entry per event; where a band's both edges
    are observed, its leading edge's ``inlier`` is its midpoint's, its trailing edge's its
    length's. ``flash_ms`` the global
    time of each flash index (NaN for an index no inlier event names); ``sigma_ms`` is the
    robust scale of the residuals over their sigma factors. ``free_drift``: the camera
    indices whose drift prior the events contradicted, solved without it
    (:func:`solve_with_drift_model`).
    """

    cameras: list[CameraSolution]
    flash_ms: np.ndarray
    residual_ms: np.ndarray
    inlier: np.ndarray
    sigma_ms: float
    n_unknowns: int
    sigma_factor: np.ndarray
    free_drift: tuple[int, ...] = ()


#: Noise of an edge against which the priors are weighed, ms.
EVENT_SIGMA_MS = 0.05
#: Equations beyond this many robust sigmas are rejected, the sigma no less than the camera's
#: edge floor (:data:`EDGE_FLOOR_ROWS` of its time per row): with few flashes the residuals'
#: MAD is a few microseconds and edges half a row off, as located as edges are, were rejected.
REJECT_SIGMA = 5.0
#: Cauchy weights at this many robust sigmas (95 % efficiency for Gaussian noise).
CAUCHY_K = 2.385
#: Solves of the robust iterations, in all.
ITERATIONS = 10
#: Robust iterations whose Cauchy scale rises to this many times their first were thrown off
#: (:func:`_robust_iterations`). One of three cameras' edges matched to the neighbouring flash
#: of 12 failed the solve in 13 of 20 draws and put that camera 27 and 136 ms off in two more
#: (of 8: 12 failed, 4 were 0.13-5.1 s off, two of them after their scale had risen and
#: fallen again; ``tests/test_solve.py``); random rig 176 (``bench_rigs.py --seeds 172:180``
#: with the four departures) failed its right reading so, and a camera read upside down on
#: three flashes won instead, 17 ms off. On eight kept benches (338 cameras) only one other
#: rig moved, within its σ.
THROWN_OFF_SHARE = 2.0


def solve_clocks(
    events: Observations,
    n_cameras: int,
    reference: int = 0,
    priors: Priors | None = None,
    drift_knots: dict[int, np.ndarray] | None = None,
    event_sigma_ms: float = EVENT_SIGMA_MS,
    reject_sigma: float = REJECT_SIGMA,
    cauchy_k: float = CAUCHY_K,
    iterations: int = ITERATIONS,
) -> Solution:
    """Solve all cameras' clocks jointly and robustly.

    Parameters
    ----------
    events : matched band edges, leading and trailing.
    n_cameras : number of cameras (indices 0..n_cameras-1).
    reference : index of the reference camera.
    priors : pseudo-observations, weighed against events of ``event_sigma_ms`` noise;
        None: the events alone.
    drift_knots : per camera index (not the reference), knots in camera time (ms, shape
        (k + 2,), the first and last at the ends of its events) of a piecewise-linear warp
        added to its affine clock, for a rate that changes during the recording.

    Raises
    ------
    NotEnoughDataError
        When the equations cannot determine every unknown.
    """
    with threadpool_limits(1, user_api="blas"):  # small dense factorisations: threads only cost
        return _solve(
            _System(events, n_cameras, reference, priors or Priors({}, None), drift_knots or {}, event_sigma_ms),
            n_cameras,
            reject_sigma,
            cauchy_k,
            iterations,
        )


def _robust_iterations(
    system: _System, cauchy_k: float, iterations: int, take_row_noise: bool
) -> tuple[np.ndarray, np.ndarray] | None:
    """The Cauchy iterations of :func:`_solve` (``iterations`` solves in all): the solution
    and its residuals (ms, shape (n_equations,)); with ``take_row_noise``, the rows' noise the
    last residuals give taken out of the times per row before each solve but the first.

    None where, so taken, their Cauchy scale rises over :data:`THROWN_OFF_SHARE` times its
    first: residuals that a wrong match or a clock not yet fitted makes seconds are no
    rows' noise, yet taken for it they left the times per row nothing but their priors while
    their equations' right-hand sides kept what the rows gave, and the next solve was thrown
    off by seconds."""
    system.clear_row_noise()
    scales = []

    def scale(residual: np.ndarray, _: float | None) -> float:
        scales.append(cauchy_k * mad_sigma(residual, MIN_SCALE_MS))
        return scales[-1]

    def residuals(x: np.ndarray) -> np.ndarray:
        residual = system.residuals(x)
        if take_row_noise:
            system.estimate_row_noise(x, mad_sigma(residual))
        return residual

    x, residual, _ = cauchy_irls(system.solve, residuals, system.n_equations, scale, iterations - 1)
    return None if take_row_noise and max(scales) > THROWN_OFF_SHARE * scales[0] else (x, residual)


def _solve(system: _System, n_cameras: int, reject_sigma: float, cauchy_k: float, iterations: int) -> Solution:
    """The robust iterations of :func:`solve_clocks` on a built system: Cauchy weights at
    ``cauchy_k`` robust sigmas, ``iterations`` solves in all; then the inliers weighed by
    their groups' own noise (:meth:`_System.group_scales`), which the covariance states.
    Every solve but the first takes the rows' noise, as the last residuals give it, out of
    the times per row's information (:meth:`_System._take_row_noise`): a time per row pulled
    short in the robust iterations moves which events are rejected. Where that throws the
    iterations off (:func:`_robust_iterations`), they are made again without it."""
    x, residual = _robust_iterations(system, cauchy_k, iterations, take_row_noise=True) or _robust_iterations(
        system, cauchy_k, iterations, take_row_noise=False
    )
    sigma = mad_sigma(residual, MIN_SCALE_MS)
    floor = _edge_floor_ms(system, x, n_cameras)[system.camera]
    inlier = np.abs(residual) <= reject_sigma * np.maximum(sigma, floor)
    idle = IDLE_WEIGHT * _all_rejected(system.group, inlier)
    weights = inlier + idle
    x = system.solve(weights)
    scale = np.full(system.n_equations, np.nan)
    leading = ~system.trailing
    for _ in range(GROUP_SCALE_ROUNDS):
        scale = system.group_scales(x, weights, inlier)
        system.estimate_row_noise(x, scale)
        scale = np.maximum(scale, MIN_SCALE_MS)
        floor = _edge_floor_ms(system, x, n_cameras)
        scale[leading] = np.maximum(scale[leading], floor[system.camera[leading]])
        # trailing edges (band lengths) no less noisy than their camera's leading edges (band midpoints): a
        # camera of a few bands fits
        # them almost exactly (rig-20: two bands, a scale of 3 microseconds) and its time per row,
        # which its split bands tie to the frame period, would claim 0.02 % while 1.6 % off
        floor = np.fmax(floor, _camera_values(system.camera[leading], scale[leading], n_cameras))
        scale[~leading] = np.maximum(scale[~leading], floor[system.camera[~leading]])
        weights = inlier * (system.event_sigma_ms / scale) ** 2 + idle
        x = system.solve(weights)
    residual = system.residuals(x)
    sigma = mad_sigma(residual[inlier], MIN_SCALE_MS)
    covariance = system.covariance(weights, system.event_sigma_ms**2)
    flash_ms = np.full(int(system.flash_ids.max()) + 1 if system.flash_ids.size else 0, np.nan)
    seen = np.bincount(system.flash_index[inlier & system.names_flash], minlength=len(system.flash_ids)) > 0
    flash_ms[system.flash_ids[seen]] = x[system.flash_columns[seen]]
    edge_sigma = _camera_values(system.camera[leading], scale[leading], n_cameras)
    trailing_sigma = _camera_values(system.camera[~leading], scale[~leading], n_cameras)
    return Solution(
        [
            replace(
                system.camera_solution(x, covariance, c),
                edge_sigma_ms=edge_sigma[c],
                trailing_sigma_ms=trailing_sigma[c],
            )
            for c in range(n_cameras)
        ],
        flash_ms,
        system.edge_residuals(x),
        inlier,
        sigma,
        system.n_unknowns,
        system.sigma_factor,
    )


def _camera_values(camera: np.ndarray, values: np.ndarray, n_cameras: int) -> np.ndarray:
    """Per camera (shape (n_cameras,)), the value its equations share (``values``, one per
    equation of ``camera``); NaN for a camera with none."""
    out = np.full(n_cameras, np.nan)
    out[camera] = values
    return out


def _all_rejected(group: np.ndarray, inlier: np.ndarray) -> np.ndarray:
    """The equations of groups (shape (n,) each) none of whose equations is an inlier. A
    camera's trailing edges all rejected would leave its exposure unknown undetermined and
    fail the whole solve (rig-5 read the right way up: one camera's band lengths off by
    0.2-7 ms), its leading edges and band midpoints all rejected its shift (MS11's rig-990:
    a fast-readout camera's three midpoints 0.08-0.97 ms off, nine cameras unsolved); they
    stay in the fit with :data:`IDLE_WEIGHT`, not as inliers."""
    kept = np.bincount(group, inlier, minlength=group.max() + 1 if group.size else 0) > 0
    return ~kept[group]


def _edge_floor_ms(system: _System, x: np.ndarray, n_cameras: int) -> np.ndarray:
    """Each camera's least edge noise, ms (shape (n_cameras,)): :data:`EDGE_FLOOR_ROWS` of its
    time per row. A camera of a few events fits them almost exactly and would claim a noise
    no band edge has."""
    columns = np.array([system.param_columns[c][2] for c in range(n_cameras)])
    return EDGE_FLOOR_ROWS * np.where(columns >= 0, np.abs(x[np.maximum(columns, 0)]), 0.0)


#: Weight of equations kept only to determine an unknown (:func:`_all_rejected`); an inlier
#: weighs 1 to 100: they move nothing else.
IDLE_WEIGHT = 1e-6
#: Least time per row by which a row noise is converted (ms): a time per row solved at zero
#: would make it infinite.
MIN_ROW_TIME_MS = 1e-6
#: The least noise of a band edge, rows: clean edges are located to 0.10-0.16 rows RMS
#: (`benchmarks/bench_edges.py`, README "Edge precision").
EDGE_FLOOR_ROWS = 0.15
#: Rounds of reweighting by the groups' noise scales (each camera's leading edges, each
#: camera's trailing edges): their edges differ (exposure, pulse, size, codec), by a factor of ten.
GROUP_SCALE_ROUNDS = 3
#: The pooled scale counts as this many equations of each group's own (a group of a few
#: events does not get a scale from them alone).
POOLED_EQUATIONS = 3.0


#: Segments per camera tried for a clock whose rate changes (1 = affine).
DRIFT_SEGMENTS = (1, 2, 4, 8, 16)
#: Fewest events per segment and camera for a segment to be fitted.
MIN_EVENTS_PER_SEGMENT = 4
#: Fewest flashes of a camera whose clock may be given a changing rate (two segments).
MIN_FLASHES_FOR_CHANGING_RATE = MIN_EVENTS_PER_SEGMENT * DRIFT_SEGMENTS[1]
#: BIC decrease that counts as strong evidence for a richer drift model.
MIN_BIC_GAIN = 10.0
#: A camera's drift prior is dropped where the events alone put its (affine) drift this many
#: combined standard deviations from it, and it has flashes enough for a changing rate
#: (:data:`MIN_FLASHES_FOR_CHANGING_RATE`): a few flashes matched by chance fit any rate.
DRIFT_CONTRADICTION_SIGMAS = 5.0


def solve_with_drift_model(events: Observations, n_cameras: int, reference: int = 0, **options) -> Solution:
    """:func:`solve_clocks` with the drift model chosen by the data.

    Each camera's clock is tried affine, then with its rate changing piecewise-linearly
    over 2, 4, 8 and 16 equal segments of its recording (cameras with fewer than
    :data:`MIN_EVENTS_PER_SEGMENT` leading edges per segment stay at what they support). A richer
    model is kept only if it lowers the Bayesian information criterion (on the inlier
    equations) by :data:`MIN_BIC_GAIN`: strong evidence. First, the drift prior is dropped
    for every camera whose events contradict it (:func:`_drift_prior_contradicted`).
    """
    free_drift = _drift_prior_contradicted(events, n_cameras, reference, options)
    if free_drift:
        options = {**options, "priors": options["priors"].without_drift_prior(free_drift)}
    leading = _leading(events)
    camera = np.asarray(events.camera)[leading]
    t_frame = np.asarray(events.t_frame_ms, dtype=np.float64)[leading]
    best = solve_clocks(events, n_cameras, reference, **options)
    best_bic = _bic(best)
    knots = {}
    for segments in DRIFT_SEGMENTS[1:]:
        for c in range(n_cameras):
            times = t_frame[camera == c]
            if c != reference and len(times) >= MIN_EVENTS_PER_SEGMENT * segments:
                knots[c] = np.linspace(times.min(), times.max(), segments + 1)
        if not knots:
            break
        try:
            trial = solve_clocks(events, n_cameras, reference, drift_knots=dict(knots), **options)
        except NotEnoughDataError:
            break
        bic = _bic(trial)
        if bic < best_bic - MIN_BIC_GAIN:
            best, best_bic = trial, bic
    return replace(best, free_drift=free_drift)


def _drift_prior_contradicted(events: Observations, n_cameras: int, reference: int, options: dict) -> tuple:
    """The camera indices whose affine drift, solved from the events without the drift prior,
    lies over :data:`DRIFT_CONTRADICTION_SIGMAS` combined standard deviations (its own and
    the prior's) from the prior's 0, on cameras of flashes enough for a changing rate
    (:data:`MIN_FLASHES_FOR_CHANGING_RATE`): a clock hundreds of ppm off the
    reference's (a rate that changes during the recording, stamps written at a nominal rate)
    is not one the prior of consumer oscillators describes, and held to it, the robust solve
    gives up flashes instead of the prior. ``options``: those of :func:`solve_clocks`."""
    priors = options.get("priors")
    enough = np.bincount(np.asarray(events.camera)[_leading(events)], minlength=n_cameras) >= (
        MIN_FLASHES_FOR_CHANGING_RATE
    )
    enough[reference] = False
    if priors is None or priors.drift_std is None or not enough.any():
        return ()
    try:
        free = solve_clocks(events, n_cameras, reference, **{**options, "priors": replace(priors, drift_std=None)})
    except NotEnoughDataError:
        return ()

    def contradicted(c: int, camera: CameraSolution) -> bool:
        own = np.sqrt(max(camera.covariance[0, 0], 0.0))
        prior = max(priors.drift_std, priors.wider_drift_std.get(c, 0.0))
        return abs(camera.alpha - 1.0) > DRIFT_CONTRADICTION_SIGMAS * np.hypot(own, prior)

    return tuple(c for c, camera in enumerate(free.cameras) if enough[c] and contradicted(c, camera))


def _leading(events: Observations) -> np.ndarray:
    """Which events are leading edges (bool, shape (n,)): one per flash a camera saw."""
    return np.ones(len(events.camera), dtype=bool) if events.trailing is None else ~np.asarray(events.trailing)


def _bic(solution: Solution) -> float:
    """Bayesian information criterion of a solution on its inlier equations."""
    residual = (solution.residual_ms / solution.sigma_factor)[solution.inlier]
    n = len(residual)
    return n * np.log(max(float(np.mean(residual**2)), 1e-18)) + solution.n_unknowns * np.log(n)


class _System:
    """The sparse design of :func:`solve_clocks`, columns scaled to unit norm.

    Columns: per camera but the reference, drift about mid time and shift at mid time; the
    warp values of cameras with drift knots; one exposure per camera that has trailing
    edges; every camera's time per row; one global time per flash. Rows: events,
    then priors; each event row divided by its sigma factor (priors carry their own weight).
    A band whose both edges are observed enters as its midpoint and its length
    (:func:`_band_transform`), each with its own noise.
    """

    def __init__(
        self,
        events: Observations,
        n_cameras: int,
        reference: int,
        priors: Priors,
        drift_knots: dict[int, np.ndarray],
        event_sigma_ms: float,
    ):
        camera = np.asarray(events.camera, dtype=np.int64)
        t_frame = np.asarray(events.t_frame_ms, dtype=np.float64)
        q = np.asarray(events.q, dtype=np.float64)
        n_events = len(camera)
        trailing = np.zeros(n_events, dtype=bool) if events.trailing is None else np.asarray(events.trailing, bool)
        self.camera, self.trailing = camera, trailing
        self.flash_ids, flash = np.unique(np.asarray(events.flash, dtype=np.int64), return_inverse=True)
        self.flash_index = flash
        self.mid_ms = np.array(
            [
                np.median(t_frame[(camera == c) & ~trailing]) if np.any((camera == c) & ~trailing) else 0.0
                for c in range(n_cameras)
            ]
        )
        self.param_columns = np.full((n_cameras, 3), -1)
        n_columns = 0
        for c in range(n_cameras):
            if c != reference:
                self.param_columns[c, :2] = n_columns, n_columns + 1
                n_columns += 2
        self.knots = {c: np.asarray(knots, dtype=np.float64) for c, knots in drift_knots.items()}
        self.warp_columns = {}
        for c, knots in self.knots.items():
            self.warp_columns[c] = n_columns + np.arange(len(knots) - 2)
            n_columns += len(knots) - 2
        self.exposure_columns = np.full(n_cameras, -1)
        for c in np.unique(camera[trailing]):
            self.exposure_columns[c] = n_columns
            n_columns += 1
        # the times per row last: the Cholesky factor's last block is then their information, every
        # other camera unknown profiled out (_take_row_noise)
        self.param_columns[:, 2] = n_columns + np.arange(n_cameras)
        n_columns += n_cameras
        self.n_camera_columns = n_columns
        self.flash_columns = n_columns + np.arange(len(self.flash_ids))
        self.n_unknowns = n_columns + len(self.flash_ids)

        triplets = _Triplets()
        rows = np.arange(n_events)
        for k, value in enumerate([t_frame - self.mid_ms[camera], np.ones(n_events), q]):
            triplets.add(rows, self.param_columns[camera, k], value)
        triplets.add(rows, self.flash_columns[flash], -np.ones(n_events))
        triplets.add(rows[trailing], self.exposure_columns[camera[trailing]], -np.ones(int(trailing.sum())))
        for c, knots in self.knots.items():
            mine = np.flatnonzero(camera == c)
            hats = hat_basis(knots, t_frame[mine])
            for j, column in enumerate(self.warp_columns[c]):
                triplets.add(mine, np.full(len(mine), column), hats[:, j])
        rhs = [-t_frame]
        pairs = self._band_pairs(events, trailing)
        #: the equations that name their flash (a band's length does not)
        self.names_flash = np.ones(n_events, dtype=bool)
        self.names_flash[pairs[:, 1]] = False
        self.n_equations = n_events
        #: noise group of each equation: camera c's leading edges and band midpoints are c, its trailing
        #: edges and band lengths n_cameras + c
        self.group = camera + n_cameras * trailing
        self.event_sigma_ms = event_sigma_ms

        # prior rows (columns, weights, value): each row's weights times its columns' unknowns = value;
        # the times per row's rows are a root of their information (event_sigma_ms^2 times it)
        prior_rows = []
        with_prior, mean, information = priors.row_time_information()
        root = event_sigma_ms * linalg.cholesky(information) if len(with_prior) else np.zeros((0, 0))
        for weights in root:
            prior_rows.append((self.param_columns[with_prior, 2], weights, float(weights @ mean)))
        for c in range(n_cameras):
            if c != reference and priors.drift_std is not None:
                std = max(priors.drift_std, priors.wider_drift_std.get(c, 0.0))
                prior_rows.append((self.param_columns[[c], 0], np.array([event_sigma_ms / std]), 0.0))
        for i, (columns, weights, _) in enumerate(prior_rows):
            triplets.add(np.full(len(columns), self.n_equations + i), columns, weights)
        rhs.append(np.array([value for _, _, value in prior_rows]))
        self.n_priors = len(prior_rows)
        factor = np.ones(n_events) if events.sigma_factor is None else np.asarray(events.sigma_factor, np.float64)
        self.sigma_factor = factor
        row_weight = np.concatenate([1.0 / self.sigma_factor, np.ones(self.n_priors)])
        edges = triplets.matrix((self.n_equations + self.n_priors, self.n_unknowns))
        #: equations from edge rows: a band's pair becomes its midpoint (the leading edge's row) and
        #: its length (the trailing edge's row); every other row stays itself
        self.edges_to_equations = _band_transform(pairs, self.n_equations + self.n_priors)
        self.edge_rhs = np.concatenate(rhs)
        self.edge_matrix = edges
        self.rhs = (self.edges_to_equations @ self.edge_rhs) * row_weight
        matrix = sparse.diags(row_weight) @ self.edges_to_equations @ edges
        norms = np.sqrt(np.asarray(matrix.multiply(matrix).sum(axis=0))).ravel()
        if np.any(norms == 0):
            raise NotEnoughDataError(
                "the matched events leave a camera parameter undetermined; "
                "each camera needs events on flashes shared with other cameras"
            )
        self.column_scale = 1.0 / norms
        self.matrix = (matrix @ sparse.diags(self.column_scale)).tocsc()
        self.matrix.eliminate_zeros()  # a warp's hats are 0 beyond their two knots
        self._last_reduced = (None, None)
        #: each equation's row noise, rows² (its sigma factor's worth; shape (n_equations,)): the
        #: variance its rows add to its time per row's column (:meth:`_take_row_noise`)
        self.row_noise = np.zeros(self.n_equations)
        #: the times per row's prior's information on the Schur complement's last block (scaled),
        #: (n_cameras, n_cameras)
        self.row_time_prior = np.zeros((n_cameras, n_cameras))
        scale = event_sigma_ms * self.column_scale[self.param_columns[with_prior, 2]]
        self.row_time_prior[np.ix_(with_prior, with_prior)] = information * np.outer(scale, scale)
        self.cams = self.matrix[:, : self.n_camera_columns].tocsr()
        self.flashes = self.matrix[:, self.n_camera_columns :].tocsr()
        named = self.flashes[: self.n_equations].tocoo()
        #: each equation's coefficient of its flash (scaled; 0 for a band's length) and that flash's index
        self.flash_coefficient = np.zeros(self.n_equations)
        self.flash_of = np.zeros(self.n_equations, dtype=np.int64)
        self.flash_coefficient[named.row], self.flash_of[named.row] = named.data, named.col
        #: each equation's camera columns and their coefficients (scaled), padded with column 0 and
        #: coefficient 0 to the most an equation has: two arrays of shape (n_equations, width)
        self.camera_entries = _padded_rows(self.cams[: self.n_equations])

    @staticmethod
    def _band_pairs(events: Observations, trailing: np.ndarray) -> np.ndarray:
        """(leading, trailing) row indices of the bands whose both edges are observed, shape (m, 2)."""
        if events.leading_of is None:
            return np.zeros((0, 2), dtype=np.int64)
        leading_of = np.asarray(events.leading_of, dtype=np.int64)
        mine = np.flatnonzero(trailing & (leading_of >= 0))
        return np.column_stack([leading_of[mine], mine])

    def edge_residuals(self, x: np.ndarray) -> np.ndarray:
        """Each edge's own residual (ms, shape (n_equations,)), not its band's midpoint's or
        length's: ``t`` mapped by the solved clock minus the flash (and the exposure)."""
        return (self.edge_matrix @ x - self.edge_rhs)[: self.n_equations]

    def _reduced(self, weights: np.ndarray):
        """The normal equations with the flash times eliminated.

        Each equation names at most one flash, so the flash block of the normal matrix is
        diagonal (``d``) and the camera block's Schur complement ``S`` is small (three to
        four unknowns per camera, however many flashes). A flash whose every observation
        has weight 0 (all rejected) gets ``d = 1``: it solves to 0 instead of making the
        system singular (its time is reported as NaN).

        Returns the Cholesky factor of ``S`` and what back-substitution needs; the last
        weights' are kept (a solve, then its leverages and covariance, use the same).
        """
        last_weights, last = self._last_reduced
        if last_weights is not None and np.array_equal(last_weights, weights):
            return last
        w = np.concatenate([weights, np.ones(self.n_priors)])
        d = np.bincount(self.flash_of, self.flash_coefficient**2 * weights, minlength=len(self.flash_ids))
        d = np.where(d > 0, d, 1.0)
        cams, f = self.cams, self.flash_coefficient
        schur, coupling = _camera_products(
            cams.indptr, cams.indices, cams.data, w, self.flash_of, f, (cams.shape[1], len(d))
        )
        scaled = coupling / np.sqrt(d)
        schur -= scaled @ scaled.T  # a @ a.T: one BLAS syrk
        right_cams = self.cams.T @ (w * self.rhs)
        right_flashes = self.flashes.T @ (w * self.rhs)
        factor = _cholesky(schur)
        if factor is not None and np.any(self.row_noise):
            factor = self._take_row_noise(factor, w[: self.n_equations], d, np.max(np.diag(schur)))
        if factor is None:
            raise NotEnoughDataError(
                "the matched events cannot separate every camera's drift, shift and time per row "
                "(too few flashes, or all at the same rows); record more flashes seen by several "
                "cameras, or give the cameras' times per row (datasheet)"
            )
        self._last_reduced = (weights.copy(), (factor, coupling, d, right_cams, right_flashes))
        return self._last_reduced[1]

    def estimate_row_noise(self, x: np.ndarray, noise_ms: np.ndarray | float) -> None:
        """Set each equation's row noise (:attr:`row_noise`) from its noise ``noise_ms`` (ms, a
        clean edge's; scalar or shape (n_equations,)), all of it taken to be in the rows, over
        its camera's time per row in ``x``."""
        row_time = np.abs(x[self.param_columns[:, 2]])[self.camera]
        self.row_noise = (np.broadcast_to(noise_ms, self.camera.shape) / np.maximum(row_time, MIN_ROW_TIME_MS)) ** 2
        self._last_reduced = (None, None)

    def clear_row_noise(self) -> None:
        """No row noise (:attr:`row_noise`) in the next solves."""
        self.row_noise = np.zeros(self.n_equations)
        self._last_reduced = (None, None)

    def _take_row_noise(
        self, factor: tuple[np.ndarray, bool], w: np.ndarray, d: np.ndarray, largest: float
    ) -> tuple[np.ndarray, bool] | None:
        """The Cholesky factor of the Schur complement (``factor``, upper, of weights ``w`` and
        flash diagonal ``d``) without the information on the times per row that the rows' noise
        alone gives it; None where what is left is singular (a pivot under 1e-12 of
        ``largest``, the complement's largest diagonal entry).

        A time per row multiplies a measured row, so the noise of the rows enters its column
        of the design: ``sum(w q**2)`` grows by ``w`` times each row's variance (less its
        flash's share, which the flash's own time takes), and a least-squares time per row
        is pulled towards zero as if fewer rows had been needed (regression dilution). The
        more the rows' spread pins it (cameras of other rates or phases, bands split across
        frames, many flashes) the less the pull; where nothing does (cameras of one rate and
        phase, as line-locked ones are) the noise alone made it collapse (three 50 fps
        cameras: 89 % short at 57 sigma). The factor's last block (the times per row's
        columns come last) gives the events' information on them ``M``, every other camera
        unknown profiled out, their own priors left out; with the noise's ``D``,
        ``D^-1/2 M D^-1/2 = V diag(l) V'``, and what is kept is
        ``D^1/2 V diag(max(l - 1, 0)) V' D^1/2``: the rows' spread beyond their noise, never
        below nothing, so the priors decide where the events do not. Only that block of the
        factor changes; the covariance is its inverse (the priors' where nothing is kept).
        """
        t = self.param_columns[:, 2]
        kept = w * self.row_noise * (1.0 - w * self.flash_coefficient**2 / d[self.flash_of])
        noise = np.bincount(self.camera, kept, minlength=len(t)) * self.column_scale[t] ** 2
        block = np.triu(factor[0][t[0] :, t[0] :])
        information = block.T @ block - self.row_time_prior
        noisy = np.flatnonzero(noise > 0)
        root = np.sqrt(noise[noisy])
        values, vectors = np.linalg.eigh(information[np.ix_(noisy, noisy)] / np.outer(root, root))
        information[np.ix_(noisy, noisy)] = (vectors * np.maximum(values - 1.0, 0.0)) @ vectors.T * np.outer(root, root)
        corrected = _cholesky(information + self.row_time_prior, largest)
        if corrected is None:
            return None
        factor[0][t[0] :, t[0] :] = np.triu(corrected[0])  # cho_factor's own array: the solves read its upper triangle
        return factor

    def solve(self, weights: np.ndarray) -> np.ndarray:
        """Weighted least-squares solution (unscaled units); a clear error where the
        equations are too few or (nearly) singular."""
        n_used = int(np.count_nonzero(weights)) + self.n_priors
        if n_used < self.n_unknowns:
            raise NotEnoughDataError(
                f"the cameras share too few events: {n_used} equations for {self.n_unknowns} "
                "unknowns; record more flashes seen by several cameras, or give the cameras' times "
                "per row (datasheet)"
            )
        factor, coupling, d, right_cams, right_flashes = self._reduced(weights)
        x_cams = linalg.cho_solve(factor, right_cams - coupling @ (right_flashes / d))
        x_flashes = (right_flashes - coupling.T @ x_cams) / d
        return np.concatenate([x_cams, x_flashes]) * self.column_scale

    def group_scales(self, x: np.ndarray, weights: np.ndarray, inlier: np.ndarray) -> np.ndarray:
        """Each equation's noise (ms, a clean edge's; shape (n_equations,)): the RMS of its
        group's inlier residuals over the degrees of freedom they leave (their count less
        their leverages, i.e. the trace of the inverse normal matrix times the group's own),
        shrunk towards the pooled scale of its kind (leading edges and band midpoints;
        trailing edges and band lengths) with :data:`POOLED_EQUATIONS`."""
        residual = self.residuals(x)
        leverages = self._leverages(weights)
        if leverages is None:
            return np.full(self.n_equations, self.event_sigma_ms)
        n_cameras = len(self.param_columns)
        groups = 2 * n_cameras
        leverage = np.bincount(self.group, leverages, minlength=groups)
        squares = np.where(inlier, residual**2, 0.0)
        sums = np.bincount(self.group, squares, minlength=groups)
        dof = np.maximum(np.bincount(self.group, inlier.astype(np.float64), minlength=groups) - leverage, 0.0)
        pooled = np.zeros(groups)
        for kind in (slice(0, n_cameras), slice(n_cameras, groups)):  # leading, then trailing edges
            pooled[kind] = sums[kind].sum() / max(dof[kind].sum(), 1.0)
        scale = np.sqrt((sums + POOLED_EQUATIONS * pooled) / (dof + POOLED_EQUATIONS))
        return scale[self.group]

    def _leverages(self, weights: np.ndarray) -> np.ndarray | None:
        """Each equation's leverage ``w_i a_i' N^-1 a_i`` (shape (n_equations,)) for the normal
        matrix ``N`` of ``weights``, from its flash-eliminated form (:meth:`_reduced`): with
        ``M = B / d`` (coupling over the flash diagonal), an equation of camera part ``c`` and
        flash coefficient ``f`` on flash ``k`` has ``a' N^-1 a = (c - f M_k)' S^-1 (c - f M_k)
        + f^2 / d_k``. A flash whose every equation has weight 0 is left out (its equations'
        leverages are 0; :meth:`_reduced` keeps it from the factor): returning None there sent
        every scale to ``event_sigma_ms``. None where ``S`` is singular."""
        w = np.concatenate([weights, np.ones(self.n_priors)])
        try:
            factor, coupling, d, _, _ = self._reduced(weights)
        except NotEnoughDataError:
            return None
        inverse = _cho_inverse(factor)
        moved = coupling / d
        spread = inverse @ moved
        flash_term = 1.0 / d + np.sum(moved * spread, axis=0)
        f, k = self.flash_coefficient, self.flash_of
        columns, values = self.camera_entries
        own = _quadratic_forms(columns, values, inverse)
        cross = np.einsum("ia,ia->i", values, spread[columns, k[:, None]])
        return w[: self.n_equations] * (own - 2 * f * cross + f**2 * flash_term[k])

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Residuals of the events over their sigma factors, ms (what a clean
        edge off by as much would be)."""
        return ((self.matrix @ (x / self.column_scale)) - self.rhs)[: self.n_equations]

    def covariance(self, weights: np.ndarray, scale: float) -> np.ndarray:
        """Covariance of the camera unknowns (unscaled units) for residual variance ``scale``:
        the inverse of the Schur complement."""
        factor = self._reduced(weights)[0]
        inverse = _cho_inverse(factor)
        column_scale = self.column_scale[: self.n_camera_columns]
        return scale * inverse * np.outer(column_scale, column_scale)

    def camera_solution(self, x: np.ndarray, covariance: np.ndarray, c: int) -> CameraSolution:
        """Camera ``c``'s (alpha, beta, T_row, warp) and their covariance, from the solved
        (drift, shift at mid time, T_row, warp); and its exposure with its standard deviation."""
        warp = self.warp_columns.get(c, np.zeros(0, dtype=np.int64))
        columns = np.concatenate([self.param_columns[c], warp])
        used = columns >= 0
        values = np.where(used, x[np.maximum(columns, 0)], 0.0)
        local = np.zeros((len(columns), len(columns)))
        local[np.ix_(used, used)] = covariance[np.ix_(columns[used], columns[used])]
        jacobian = np.eye(len(columns))
        jacobian[1, 0] = -self.mid_ms[c]
        drift, shift, row_time = values[:3]
        exposure = self.exposure_columns[c]
        return CameraSolution(
            1.0 + drift,
            shift - drift * self.mid_ms[c],
            row_time,
            jacobian @ local @ jacobian.T,
            self.knots.get(c, np.zeros(0)),
            values[3:],
            exposure_ms=float(x[exposure]) if exposure >= 0 else float("nan"),
            exposure_std_ms=float(np.sqrt(max(covariance[exposure, exposure], 0.0))) if exposure >= 0 else float("nan"),
        )


@njit
def _camera_products(indptr, columns, values, weights, flash, coefficient, shape):  # pragma: no cover - compiled
    """The camera block ``C' W C`` (n_columns, n_columns) and the coupling ``C' W F``
    (``shape``: (n_columns, n_flashes)) of the normal matrix of weights ``W`` (``weights``,
    one per row). ``C``: the camera columns, CSR (``indptr``, ``columns``, ``values``; the
    equations' rows, then the priors'); ``F``: the flash columns, each equation's
    ``coefficient`` on its ``flash`` (shape (n_equations,)). Summed row by row in row order,
    as scipy's sparse products sum them, and the coupling in Fortran order, as their
    ``toarray`` gives it (BLAS sums its products in another order in the other): the same
    values to the last bit."""
    n_columns, n_flashes = shape
    gram = np.zeros((n_columns, n_columns))
    coupling = np.zeros((n_flashes, n_columns))
    for row in range(len(indptr) - 1):
        start, stop = indptr[row], indptr[row + 1]
        for p in range(start, stop):
            weighted = values[p] * weights[row]
            for q in range(start, stop):
                gram[columns[q], columns[p]] += values[q] * weighted
            if row < len(flash) and coefficient[row] != 0.0:
                coupling[flash[row], columns[p]] += weighted * coefficient[row]
    return gram, coupling.T


def _padded_rows(matrix: sparse.csr_matrix) -> tuple[np.ndarray, np.ndarray]:
    """Each row's column indices and values of a CSR matrix, in its order, padded with
    column 0 and value 0 to the most a row holds: shapes (n_rows, width)."""
    counts = np.diff(matrix.indptr)
    width = int(counts.max()) if counts.size else 0
    slot = np.arange(width) < counts[:, None]
    columns = np.zeros((len(counts), width), dtype=np.int64)
    values = np.zeros((len(counts), width))
    columns[slot], values[slot] = matrix.indices, matrix.data
    return columns, values


@njit
def _quadratic_forms(columns, values, matrix):  # pragma: no cover - compiled
    """``v_i' A v_i`` for every row ``i`` (shape (n,)) of sparse vectors padded as
    :func:`_padded_rows` gives them (``columns``, ``values``: (n, width)) and a matrix ``A``;
    summed as ``np.einsum("ia,ib,iab->i", ...)`` sums them: the same values to the last bit."""
    out = np.zeros(len(values))
    for i in range(len(values)):
        total = 0.0
        for a in range(values.shape[1]):
            for b in range(values.shape[1]):
                total += values[i, a] * values[i, b] * matrix[columns[i, a], columns[i, b]]
        out[i] = total
    return out


def _cholesky(matrix: np.ndarray, largest: float | None = None) -> tuple[np.ndarray, bool] | None:
    """The upper :func:`scipy.linalg.cho_factor` of a symmetric matrix; None where it is not
    positive definite by a margin: a pivot under 1e-12 of ``largest`` (None: the matrix's
    largest diagonal entry)."""
    try:
        factor = linalg.cho_factor(matrix, check_finite=False)
    except linalg.LinAlgError:
        return None
    largest = np.max(np.diag(matrix)) if largest is None else largest
    return factor if np.min(np.diag(factor[0])) ** 2 > 1e-12 * largest else None


def _cho_inverse(factor: tuple[np.ndarray, bool]) -> np.ndarray:
    """The inverse of a symmetric positive-definite matrix from its :func:`scipy.linalg.cho_factor`."""
    inverse, info = linalg.lapack.dpotri(factor[0], lower=factor[1])
    if info != 0:
        raise linalg.LinAlgError("the Cholesky factor is singular")
    return np.triu(inverse) + np.triu(inverse, 1).T if not factor[1] else np.tril(inverse) + np.tril(inverse, -1).T


def _band_transform(pairs: np.ndarray, n_rows: int) -> sparse.csr_matrix:
    """The map (n_rows, n_rows) from edge equations to the solve's: a band's leading row
    becomes the mean of its two edges (its midpoint: the flash plus half an exposure), its
    trailing row their difference (its length: the exposure). The two carry different noise
    (:meth:`_System.group_scales`): where an LED pulse is about as long as the exposure, the
    band fit trades the two edges against each other (leading early, trailing late by as
    much), which moves the length, not the midpoint. The map's determinant is 1."""
    lead, trail = pairs[:, 0], pairs[:, 1]
    diagonal = np.ones(n_rows)
    diagonal[lead] = 0.5
    rows = np.concatenate([np.arange(n_rows), lead, trail])
    columns = np.concatenate([np.arange(n_rows), trail, lead])
    values = np.concatenate([diagonal, np.full(len(pairs), 0.5), np.full(len(pairs), -1.0)])
    return sparse.csr_matrix((values, (rows, columns)), shape=(n_rows, n_rows))


class _Triplets:
    """Collects (row, column, value) entries of a sparse matrix; negative columns are skipped."""

    def __init__(self):
        self.rows, self.columns, self.values = [], [], []

    def add(self, rows: np.ndarray, columns: np.ndarray, values: np.ndarray) -> None:
        keep = columns >= 0
        self.rows.append(rows[keep])
        self.columns.append(columns[keep])
        self.values.append(values[keep])

    def matrix(self, shape: tuple[int, int]) -> sparse.csr_matrix:
        return sparse.csr_matrix(
            (np.concatenate(self.values), (np.concatenate(self.rows), np.concatenate(self.columns))), shape=shape
        )
