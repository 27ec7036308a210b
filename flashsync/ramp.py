"""The flash's ramp at a band edge, and its robust fit to a fraction of a row.

A row whose exposure ended ``z`` rows after the flash started integrated the share
``1 - exp(-z / k)`` of the flash's light, ``k`` rows being the flash tube's decay time over
the time per row: the leading edge. A row whose exposure started ``z`` rows after the flash
started missed the share ``1 - exp(-z / k)``: the trailing edge is the same ramp, falling.
The codec (quantisation, deblocking) and the lens blur that ramp across rows, and blur
moves the half point of such an asymmetric ramp late, by about ``blur**2 / (2 k)`` rows
(0.05 to 0.1 rows at H.264 crf 23). So the model is the exponential
ramp convolved with a Gaussian of ``blur`` rows (the distribution function of an
exponentially modified Gaussian), and the edge is its half point before the blur,
``start + k ln 2``: the row whose exposure ended (leading) or started (trailing) when the
flash had given half its light, the same instant in every camera.
"""

from __future__ import annotations

import math

import numpy as np

from flashsync.compiled import njit

#: Bounds of the ramp's decay length and blur, rows.
MIN_SCALE, MAX_SCALE = 0.1, 50.0
MAX_BLUR = 3.0
#: Blur the fit starts from, rows.
START_BLUR = 0.3
#: Std of a weak prior that the blur is small, rows: a blur of this many rows costs as much
#: as one row off by the loss scale. Without it the blur wanders where the ramp cannot tell
#: it (a foot lost in a dead zone) and stalls short of 0 in sharp video.
BLUR_PRIOR_STD = 2.0


def fit_pulse_edge(values: np.ndarray, row: float, rise: float, level: float, rising: bool) -> float:
    """Sub-row edge of a flash band from the rows around its half-level crossing.

    Parameters
    ----------
    values : float array of shape (rows,)
        Relative change per readout row, the band positive; NaN where blind.
    row : float
        Where ``values`` crosses half of ``level``, rows (the estimate to refine).
    rise : float
        Rows from 25 % to 75 % of ``level`` (sets the fit window).
    level : float
        The band's plateau near the edge.
    rising : bool
        A leading edge (the light rises with the row); False for a trailing edge.

    Returns
    -------
    float: the fitted edge, rows; ``row`` itself where fewer than six rows are usable, the
    fit does not converge or it would move the edge by more than two rows; NaN where the
    band is degenerate (a level that is not positive, a crossing or rise that is not finite).
    """
    if not (np.isfinite(row) and np.isfinite(rise) and np.isfinite(level) and level > 0):
        return float("nan")
    k = max(rise / np.log(3.0), 0.3)  # 25 % -> 75 % of an exponential ramp: k ln 3
    first, last = int(np.floor(row - 3 - 2 * k)), int(np.ceil(row + 2 + 6 * k))  # flat side, tail
    x = np.arange(max(first, 0), min(last, len(values) - 1) + 1)
    y = values[x]
    keep = np.isfinite(y) & (x != _censored_foot(values, row, rising))
    if keep.sum() < 6:
        return row
    fitted, converged = _fit_ramp(
        x[keep].astype(np.float64),
        y[keep].astype(np.float64),
        np.array([row - k * np.log(2.0), k, START_BLUR, level]),
        0.05 * level,
        rising,
    )
    refined = fitted[0] + fitted[1] * np.log(2.0)
    return float(refined) if converged and abs(refined - row) <= 2.0 else row


def _censored_foot(values: np.ndarray, row: float, rising: bool) -> int:
    """The unchanged row next to a ramp's first changed one (before it for a leading edge,
    after it for a trailing one), or -1. Its light was real but small: under the codec's
    dead zone and the detector's 1.5 DN step floor it reads exactly 0, so it only says
    "less than that", and the fit leaves it out rather than pull the ramp late."""
    step = -1 if rising else 1
    first = int(np.floor(row)) + (1 if rising else 0)  # a row over the half level
    while 0 <= first + step < len(values) and values[first + step] != 0 and np.isfinite(values[first + step]):
        first += step
    foot = first + step
    return foot if 0 <= foot < len(values) and values[foot] == 0 else -1


@njit
def _fit_ramp(x, y, p, f_scale, rising):  # pragma: no cover - compiled
    """Robust fit of ``y = plateau * ramp(x - start, scale, blur)`` (``rising``) or of
    ``y = plateau * (1 - ramp(...))``; ``p`` = (start, scale, blur, plateau) is the first
    guess. x, y: shape (n,).

    Levenberg-Marquardt on the soft-L1 cost ``sum 2 f^2 (sqrt(1 + (r / f)^2) - 1)`` (``f`` =
    ``f_scale``), the normal equations weighted by the loss's derivative (iteratively
    reweighted), so rows hit by a player or a compression artefact barely count; the blur
    has a weak prior at 0 (:data:`BLUR_PRIOR_STD`). Returns (p, converged); not converged
    where ``f_scale`` is not positive or anything turns non-finite (numba's "numpy" error
    model: a division by zero gives inf, it does not raise).
    """
    n = x.size
    p = _clamp(p.copy())
    if not (f_scale > 0.0 and np.isfinite(f_scale)) or n == 0 or not np.all(np.isfinite(p)):
        return p, False
    cost = _cost(x, y, p, f_scale, rising)
    if not np.isfinite(cost):
        return p, False
    damping = 1e-3
    jacobian = np.empty((n, 4))
    residual = np.empty(n)
    for _ in range(200):
        for i in range(n):
            shape = _shape(x[i], p, rising)
            residual[i] = p[3] * shape - y[i]
            jacobian[i, 3] = shape
        for j in range(3):  # forward differences; the plateau is linear
            step = 1e-6 * max(1.0, abs(p[j]))
            moved = p.copy()
            moved[j] += step
            for i in range(n):
                jacobian[i, j] = (moved[3] * _shape(x[i], moved, rising) - y[i] - residual[i]) / step
        weight = 1.0 / np.sqrt(1.0 + (residual / f_scale) ** 2)
        normal = jacobian.T @ (jacobian * weight[:, None])
        gradient = jacobian.T @ (weight * residual)
        normal[2, 2] += (f_scale / BLUR_PRIOR_STD) ** 2  # the prior's residual and slope
        gradient[2] += (f_scale / BLUR_PRIOR_STD) ** 2 * p[2]
        for _ in range(30):
            trial = _clamp(p - _solve_spd(normal + damping * np.diag(np.diag(normal) + 1e-12), gradient))
            trial_cost = _cost(x, y, trial, f_scale, rising)
            if trial_cost <= cost:
                break
            damping *= 10.0
        else:
            return p, True  # no step lowers the cost: at the minimum
        if not np.all(np.isfinite(trial)):
            return p, False
        moved_most = np.max(np.abs(trial - p))
        p, cost, damping = trial, trial_cost, max(damping * 0.3, 1e-9)
        if moved_most < 1e-7 * (1.0 + np.max(np.abs(p))):
            return p, True
    return p, False


@njit
def _clamp(p):  # pragma: no cover - compiled
    p[1] = min(max(p[1], MIN_SCALE), MAX_SCALE)
    p[2] = min(max(p[2], 0.0), MAX_BLUR)
    return p


@njit
def _cost(x, y, p, f_scale, rising):  # pragma: no cover - compiled
    """Soft-L1 cost of the ramp ``p`` = (start, scale, blur, plateau) against ``y``, plus the
    blur's prior."""
    total = 0.0
    for i in range(x.size):
        residual = p[3] * _shape(x[i], p, rising) - y[i]
        total += 2.0 * f_scale**2 * (math.sqrt(1.0 + (residual / f_scale) ** 2) - 1.0)
    return total + (f_scale * p[2] / BLUR_PRIOR_STD) ** 2


@njit
def _shape(x, p, rising):  # pragma: no cover - compiled
    """The band's level at row ``x`` relative to its plateau, for ``p`` = (start, scale,
    blur, plateau): the ramp rising from 0, or falling from 1."""
    share = _ramp(x - p[0], p[1], p[2])
    return share if rising else 1.0 - share


@njit
def _ramp(z, scale, blur):  # pragma: no cover - compiled
    """Share of the flash's light in a row ``z`` rows past its start: ``1 - exp(-z / scale)``
    (0 before), convolved with a Gaussian of ``blur`` rows. The tail term
    ``exp(a) Phi(b)`` is computed through ``erfcx`` where ``Phi(b)`` underflows."""
    if blur <= 0.0:
        return -math.expm1(-z / scale) if z > 0.0 else 0.0
    b = z / blur - blur / scale
    if b >= 0.0:
        tail = math.exp(-z / scale + 0.5 * (blur / scale) ** 2) * 0.5 * math.erfc(-b / math.sqrt(2.0))
    else:
        tail = 0.5 * math.exp(-0.5 * (z / blur) ** 2) * _erfcx(-b / math.sqrt(2.0))
    return 0.5 * math.erfc(-z / (blur * math.sqrt(2.0))) - tail


@njit
def _erfcx(t):  # pragma: no cover - compiled
    """``exp(t^2) erfc(t)`` for t >= 0 (asymptotic series past 25, where erfc underflows)."""
    if t < 25.0:
        return math.exp(t * t) * math.erfc(t)
    u = 1.0 / (t * t)
    return (1.0 - 0.5 * u + 0.75 * u * u) / (t * math.sqrt(math.pi))


@njit
def _solve_spd(a, b):  # pragma: no cover - compiled
    """``a^-1 b`` for a symmetric positive definite ``a`` by Cholesky; zeros if it is not."""
    n = b.size
    low = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            total = a[i, j]
            for m in range(j):
                total -= low[i, m] * low[j, m]
            if i != j:
                low[i, j] = total / low[j, j]
            elif total > 0.0:
                low[i, i] = math.sqrt(total)
            else:
                return np.zeros(n)
    out = b.copy()
    for i in range(n):  # forward: low z = b
        for m in range(i):
            out[i] -= low[i, m] * out[m]
        out[i] /= low[i, i]
    for i in range(n - 1, -1, -1):  # back: low^T x = z
        for m in range(i + 1, n):
            out[i] -= low[m, i] * out[m]
        out[i] /= low[i, i]
    return out
