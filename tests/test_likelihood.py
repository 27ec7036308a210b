"""The held estimate of a camera's log-likelihood (:func:`flashsync.likelihood.held_log_likelihood`),
which screens the readout search's flips, judges edges as the solve does."""

from __future__ import annotations

import numpy as np

from flashsync.likelihood import HeldClock, ReadingEdges, held_log_likelihood

ROW_TIME_MS, PERIOD_MS, HEIGHT = 0.05, 40.0, 700


def test_an_edge_half_a_row_off_is_an_inlier_of_the_held_estimate_too():
    """Twelve exact leading edges, three of them then moved half a row: the refit's residuals
    have a MAD of nearly 0, and rejecting beyond 5 of it (as the solve did before its edge
    floor) counted the three as unexplained: 11.4 where all twelve explained score 29.9
    (each explained edge about 2.5, its noise the least a score allows, 0.02 ms; each
    unexplained one -log(40 ms) = -3.7)."""
    rng = np.random.default_rng(3)
    flash_ms = np.sort(rng.uniform(1_000.0, 60_000.0, 12))
    t_frame = np.floor(flash_ms / PERIOD_MS) * PERIOD_MS
    q = (flash_ms - t_frame) / ROW_TIME_MS
    q[[2, 6, 9]] += [0.5, -0.5, 0.5]
    edges = ReadingEdges(
        t_frame_ms=t_frame,
        q=q,
        approximate_ms=t_frame + q * ROW_TIME_MS,
        trailing=np.zeros(12, dtype=bool),
        band=np.arange(12),
        sigma_factor=np.ones(12),
    )
    clock = HeldClock(1.0, 0.0, PERIOD_MS, (ROW_TIME_MS, 0.1 * ROW_TIME_MS), PERIOD_MS / HEIGHT)
    assert held_log_likelihood(edges, flash_ms, clock, PERIOD_MS) > 25.0
