"""Text reports of a solved model: the per-camera parameter table (paper's Table 1)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from flashsync.model import SyncModel


def camera_table(model: SyncModel) -> pd.DataFrame:
    """One row per camera: drift (ppm and rows/s), shift (ms), time per row (ms), their
    standard deviations, matched events and the residual std (ms) of inlier events."""
    rows = []
    for name, camera in model.cameras.items():
        std = np.sqrt(np.maximum(np.diag(camera.covariance), 0.0))
        events = model.events[model.events["camera"] == name] if len(model.events) else model.events
        inliers = events[events["inlier"]] if len(events) else events
        rows.append({
            "camera": name,
            "alpha": camera.alpha,
            "drift_ppm": (camera.alpha - 1.0) * 1e6,
            "drift_rows_per_s": (camera.alpha - 1.0) * 1000.0 / camera.row_time_ms,
            "shift_ms": camera.beta_ms,
            "shift_std_ms": std[1],
            "row_time_ms": camera.row_time_ms,
            "row_time_std_ms": std[2],
            "events": len(inliers),
            "rejected": len(events) - len(inliers),
            "residual_std_ms": float(np.std(inliers["residual_ms"])) if len(inliers) else float("nan"),
        })
    return pd.DataFrame(rows)


def sync_table(model: SyncModel) -> str:
    """The per-camera table as aligned text, reference camera marked with ``*``."""
    table = camera_table(model)
    lines = [f"{'camera':<12} {'drift ppm':>10} {'rows/s':>9} {'shift ms':>14} {'± ms':>8} "
             f"{'T_row ms':>10} {'± %':>6} {'events':>6} {'rej':>4} {'res std ms':>10}"]
    for row in table.itertuples():
        name = row.camera + ("*" if row.camera == model.reference else "")
        lines.append(
            f"{name:<12} {row.drift_ppm:>10.3f} {row.drift_rows_per_s:>9.4f} {row.shift_ms:>14.3f} "
            f"{row.shift_std_ms:>8.4f} {row.row_time_ms:>10.6f} "
            f"{100 * row.row_time_std_ms / row.row_time_ms:>6.2f} {row.events:>6d} {row.rejected:>4d} "
            f"{row.residual_std_ms:>10.4f}")
    return "\n".join(lines)
