"""How often unrelated event sequences line up by chance: the evidence of a pair alignment.

Flashes fired by hand are irregular, so their intervals are a fingerprint: two cameras'
events line up under one shift only if they saw the same flashes. But with the shift free
(offsets of minutes), the drift free (up to :data:`flashsync.match.MAX_DRIFT`) and a
tolerance of a few ms, a few unrelated events also line up somewhere. The a-contrario
count (the expected number of false alarms, as in Desolneux, Moisan & Morel's Gestalt
theory) says how often: under the hypothesis that one camera's events fall independently
of the other's, each event of the camera with fewer (``n``) finds one of the other's ``m``
events, spread over its span ``S``, within ``tau`` with probability ``p = min(1, 2 tau m /
S)``; the matched count (one-to-one, so at most ``n``) under one map is binomial, and the
maps that differ by more than ``tau`` somewhere number ``(S_a + S_b) / (2 tau)`` shifts
times ``1 + drift S_b / tau`` drifts. The expected number of maps under which at least
``k`` events match by chance is

    chance = maps(tau) * P(Binomial(n, p(tau)) >= k)

An alignment is evidence where that is far below one. The matched pairs of a true
alignment sit much closer than the search tolerance (their spread is the error of the
nominal time per row, not the tolerance), so the count is taken at the tolerance and at
:data:`LEVELS` halvings of it, keeping the smallest, times the number of levels tried.
"""

from __future__ import annotations

import numpy as np
from scipy.special import bdtrc

#: Tolerances tried: the search tolerance and this many halvings of it.
LEVELS = 5


def chance_alignments(
    residuals_ms: np.ndarray,
    n_a: int,
    n_b: int,
    span_a_ms: float,
    span_b_ms: float,
    tolerance_ms: float,
    max_drift: float,
) -> float:
    """Expected number of maps (shift and drift free) under which unrelated events match as
    well as these do.

    Parameters
    ----------
    residuals_ms : float array of shape (k,)
        Matched pairs' distances from the fitted map, ms (``|t_a - (alpha t_b + beta)|``).
    n_a, n_b : int
        Events of the two cameras.
    span_a_ms, span_b_ms : float
        Time the events of each camera span, ms.
    tolerance_ms : float
        Search tolerance, ms.
    max_drift : float
        Largest relative clock drift searched.

    Returns
    -------
    float: the expected number of chance alignments as good (fewer than 1e-6 is strong
    evidence; about 1 or more is none).
    """
    residuals = np.abs(np.asarray(residuals_ms, dtype=np.float64))
    if n_a == 0 or n_b == 0 or not residuals.size:
        return float("inf")
    tolerances = tolerance_ms / 2.0 ** np.arange(LEVELS)
    counts = (residuals[None, :] <= tolerances[:, None]).sum(axis=1)
    span_a, span_b = max(span_a_ms, tolerance_ms), max(span_b_ms, tolerance_ms)
    trials, others, other_span = (n_a, n_b, span_b) if n_a <= n_b else (n_b, n_a, span_a)
    p = np.minimum(1.0, 2.0 * tolerances * others / other_span)
    maps = (span_a + span_b) / (2.0 * tolerances) * (1.0 + max_drift * span_b / tolerances)
    tails = np.where(counts > 0, bdtrc(np.maximum(counts - 1, 0), trials, p), 1.0)  # P(Binomial >= count)
    return float(LEVELS * np.min(maps * tails))
