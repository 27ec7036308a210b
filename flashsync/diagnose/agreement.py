"""How far ``diagnose``'s model lies from ``sync``'s on the same footage.

The workflow's end state is meant to be the model ``sync`` writes (one model): where the two
part by more than ``sync``'s own uncertainty, one of them misses an effect the other has, or
pairs a flash the other does not, and neither says which. The report says that they part,
where, and by how much.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flashsync.evaluate import probes
from flashsync.model import SyncModel

#: The models disagree on a camera whose times differ by more than this many of ``sync``'s
#: standard deviations (RMS over the frames and rows compared).
DISAGREEMENT_SIGMAS = 3.0


@dataclass(frozen=True)
class Gap:
    """One camera's times under the two models.

    Attributes
    ----------
    camera : str
    rms_ms : float
        RMS of ``diagnose``'s minus ``sync``'s global time over every frame and every 8th
        row (:func:`~flashsync.evaluate.probes`), ms.
    sigma_ms : float
        RMS of ``sync``'s standard deviation over the same, ms.
    """

    camera: str
    rms_ms: float
    sigma_ms: float

    @property
    def apart(self) -> bool:
        """The models disagree on this camera (:data:`DISAGREEMENT_SIGMAS`)."""
        return self.rms_ms > DISAGREEMENT_SIGMAS * self.sigma_ms


def model_gaps(diagnosed: SyncModel, synced: SyncModel) -> list[Gap]:
    """Per camera both models hold (``diagnosed``'s order), how far their times lie apart."""
    gaps = []
    for name, clock in diagnosed.cameras.items():
        other = synced.cameras.get(name)
        if other is None:
            continue
        frame, row = probes(clock)
        frame, row = frame[: other.n_frames], row[: other.n_frames]
        difference = clock.t_global_ms(frame, row) - other.t_global_ms(frame, row)
        sigma = other.t_global_std_ms(frame, row)
        gaps.append(Gap(name, float(np.sqrt(np.mean(difference**2))), float(np.sqrt(np.mean(sigma**2)))))
    return gaps


def agreement(gaps: list[Gap]) -> str:
    """One line on how the two models compare: every camera within
    :data:`DISAGREEMENT_SIGMAS` of ``sync``'s sigma (and the largest gap), or the cameras on
    which they disagree; no ``gaps``: ``sync`` could not solve the footage."""
    start = "against the model flashsync sync writes:"
    if not gaps:
        return f"{start} none (sync cannot solve these detections)"
    apart = [g for g in gaps if g.apart]
    if not apart:
        largest = max(gaps, key=lambda g: g.rms_ms / max(g.sigma_ms, 1e-12))
        return (
            f"{start} within {DISAGREEMENT_SIGMAS:g} sigma on every camera (largest: {largest.camera} "
            f"{largest.rms_ms:.4f} ms RMS apart, sigma {largest.sigma_ms:.4f} ms)"
        )
    cameras = ", ".join(f"{g.camera} {g.rms_ms:.3f} ms RMS apart (sigma {g.sigma_ms:.3f} ms)" for g in apart)
    return (
        f"{start} they disagree beyond {DISAGREEMENT_SIGMAS:g} sigma on {cameras}: one of them misses an "
        "effect or pairs a flash the other does not; check both against something known before using either"
    )
