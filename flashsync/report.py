"""Reports of a solve: the joint table (paper's Table 1), the pairwise table (Table 2),
rejected events, as DataFrames, aligned text and JSON-able dicts."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict

import numpy as np
import pandas as pd

from flashsync.flicker import CODEC_PERIOD_SHARE
from flashsync.model import CameraClock, SyncModel


def detection_notes(detection) -> list[str]:
    """Lines on what a camera's detection (:class:`~flashsync.detect.CameraDetection`) found
    besides its events: the mains flicker it removed, the bands it dropped."""
    notes = []
    flicker = detection.flicker
    if flicker is not None:
        hz = f"{flicker.hz:.0f} Hz" if flicker.hz else "frequency not told (not mains, or too few frames)"
        depth = f"depth {100 * flicker.depth:.1f} %, " if np.isfinite(flicker.depth) else ""
        rolls = ""
        if flicker.bottom_up is not None:
            way = "bottom-up" if flicker.bottom_up else "top-down"
            rolls = f", rolling as a sensor reading {way} makes it"
            if not detection.undecided and detection.flipped != flicker.bottom_up:
                rolls += (
                    f" (read top-down as told: give --flipped {detection.camera} if it is mounted upside down)"
                    if flicker.bottom_up
                    else " (read bottom-up as told by --flipped: check its mounting)"
                )
        sigma = flicker.period_rows_sigma
        bent = "a codec bends the pattern"
        if flicker.floor_share > CODEC_PERIOD_SHARE:
            few = f"the scene more in a frame of only {flicker.periods:.2f} periods"
            bent += f" by {100 * CODEC_PERIOD_SHARE:.0f} %, {few}"
        floor = f" (at least {100 * flicker.floor_share:.2g} %: {bent}; its spread {flicker.period_rows_std:.2f})"
        notes.append(
            f"{detection.camera}: rolling flicker {hz}, period {flicker.period_rows:.2f} "
            f"± {sigma:.2f} readout rows{floor if sigma > flicker.period_rows_std else ''}, {depth}measured on "
            f"{flicker.n_frames} frames and removed before detection{rolls}"
        )
    dropped = [
        f"{n} {what}"
        for n, what in (
            (detection.n_recurring, "recurring at the same rows (codec echoes, leftover flicker)"),
            (detection.n_degenerate, "degenerate (no plateau to fit)"),
            (detection.n_whole_frames, "lit whole (every row at once: no edge)"),
        )
        if n
    ]
    if dropped:
        notes.append(f"{detection.camera}: bands dropped: {'; '.join(dropped)}")
    return notes


def sync_uncertainty_ms(camera: CameraClock) -> float:
    """Largest predicted std (ms) of ``t_global_ms`` over the camera's frames and rows."""
    frames = np.array([0, camera.n_frames // 2, camera.n_frames - 1])
    frames, rows = np.meshgrid(frames, [0.0, camera.height - 1.0])
    return float(np.max(camera.t_global_std_ms(frames, rows)))


def camera_table(model: SyncModel, report=None) -> pd.DataFrame:
    """One row per camera: drift (ppm and rows/s), shift (ms), time per row (ms), their
    standard deviations, predicted sync uncertainty (ms), exposure (ms), inlier and rejected
    events, the residual std (ms) of inliers, and (with a :class:`~flashsync.pipeline.SyncReport`)
    what was found in the frame stamps."""
    rows = []
    for name, camera in model.cameras.items():
        std = np.sqrt(np.maximum(np.diag(camera.covariance), 0.0))
        events = model.events[model.events["camera"] == name]
        inliers = events[events["inlier"].astype(bool)]
        row = {
            "camera": name,
            "reference": name == model.reference,
            "flipped": camera.flipped,
            "drift_ppm": (camera.alpha - 1.0) * 1e6,
            "drift_ppm_std": std[0] * 1e6,
            "drift_rows_per_s": (camera.alpha - 1.0) * 1000.0 / camera.row_time_ms,
            "shift_ms": camera.beta_ms,
            "shift_std_ms": std[1],
            "row_time_ms": camera.row_time_ms,
            "row_time_std_ms": std[2],
            "sync_std_ms": sync_uncertainty_ms(camera),
            "exposure_ms": camera.exposure_ms,
            "exposure_std_ms": camera.exposure_std_ms,
            "exposure_spans": [asdict(span) for span in camera.exposure_spans],
            "events": len(inliers),
            "rejected": len(events) - len(inliers),
            "residual_std_ms": float(np.std(inliers["residual_ms"])) if len(inliers) else float("nan"),
        }
        if report is not None and name in report.frame_clocks:
            clock = report.frame_clocks[name]
            row |= {
                "frame_period_ms": clock.period_ms,
                "stamps_steady": clock.steady,
                "stamp_quantum_ms": clock.quantum_ms,
                "stamp_noise_ms": clock.stamp_noise_ms,
                "dropped_frames": clock.dropped,
                "stamp_rate_changes": [frame for frame, _, _ in clock.rate_changes],
                "recording_gaps": clock.gaps,
            }
        rows.append(row)
    return pd.DataFrame(rows)


def sync_table(model: SyncModel, report=None) -> str:
    """The per-camera table as aligned text; ``*`` marks the reference, ``^`` a camera that
    reads bottom-up; a last line says what ``sync ± ms`` means (:data:`SIGMA_MEANING`)."""
    table = camera_table(model, report)
    lines = [
        f"{'camera':<12} {'drift ppm':>10} {'rows/s':>8} {'shift ms':>14} {'± ms':>7} "
        f"{'T_row ms':>10} {'± %':>5} {'sync ± ms':>9} {'exp ms':>6} {'± ms':>5} {'events':>6} {'rej':>3} "
        f"{'res std ms':>10}" + (f" {'stamps':>22}" if report is not None else "")
    ]
    for row in table.itertuples():
        name = row.camera + ("*" if row.reference else "") + ("^" if row.flipped else "")
        exposure = f"{_number(row.exposure_ms, 6, 2)} {_number(row.exposure_std_ms, 5, 2)}"
        line = (
            f"{name:<12} {row.drift_ppm:>10.3f} {row.drift_rows_per_s:>8.4f} {row.shift_ms:>14.3f} "
            f"{row.shift_std_ms:>7.4f} {row.row_time_ms:>10.6f} "
            f"{100 * row.row_time_std_ms / row.row_time_ms:>5.2f} {row.sync_std_ms:>9.4f} {exposure} "
            f"{row.events:>6d} {row.rejected:>3d} {row.residual_std_ms:>10.4f}"
        )
        if report is not None:
            line += f" {_stamps(row):>22}"
        lines.append(line)
    lines.append(SIGMA_MEANING)
    return "\n".join(lines)


#: What ``sync ± ms`` means, printed under the table.
SIGMA_MEANING = (
    "sync ± ms: 1σ of a camera's times against the true global clock: the edges' noise, the scatter of the solve "
    "with each flash left out, what an error its split bands' lengths share moves, what a tone curve may shift its "
    "times by against the reference's, and the reference's own (its rows' below its first and its stamps' rate's "
    "after its first frame, whose first row is the clock), which every camera shares: two cameras against each "
    "other are surer than their two σ together"
)


def _number(value: float | None, width: int, decimals: int) -> str:
    """``value`` right-aligned in ``width`` characters, ``-`` where it is unknown."""
    return f"{value:>{width}.{decimals}f}" if value is not None and np.isfinite(value) else f"{'-':>{width}}"


def _stamps(row) -> str:
    """E.g. ``1 ms grid, ±0.29 ms, 2 drops``, ``fine, ±1.19 ms, 0 drops, 1 gap``, ``rate
    change at 451`` or ``variable rate``."""
    if not row.stamps_steady:
        return "variable rate"
    if row.stamp_rate_changes:
        return "rate change at " + ", ".join(map(str, row.stamp_rate_changes))
    grid = f"{row.stamp_quantum_ms:g} ms grid" if row.stamp_quantum_ms >= 0.05 else "fine"
    text = f"{grid}, ±{row.stamp_noise_ms:.2f} ms, {row.dropped_frames} drop{'s' * (row.dropped_frames != 1)}"
    gaps = len(row.recording_gaps)
    return text + (f", {gaps} gap{'s' * (gaps != 1)}" if gaps else "")


def rejected_events(model: SyncModel) -> pd.DataFrame:
    """Matched events the robust solve rejected, with their residuals (ms)."""
    events = model.events
    return events[~events["inlier"].astype(bool)].reset_index(drop=True)


def pairwise_table(pairs: Sequence[tuple[str, str, SyncModel | str]]) -> pd.DataFrame:
    """Paper's Table 2 from :func:`~flashsync.pipeline.solve_pairs`: per pair, camera b on
    camera a's clock, or the reason the pair could not be solved."""
    rows = []
    for a, b, result in pairs:
        row = {"camera_a": a, "camera_b": b}
        if isinstance(result, str):
            rows.append(row | {"error": result})
            continue
        table = camera_table(result).set_index("camera")
        inliers = result.events["inlier"].astype(bool)
        rows.append(
            row
            | {
                "drift_ppm": table.loc[b, "drift_ppm"],
                "shift_ms": table.loc[b, "shift_ms"],
                "row_time_a_ms": table.loc[a, "row_time_ms"],
                "row_time_b_ms": table.loc[b, "row_time_ms"],
                "events": int(table.loc[b, "events"]),
                "residual_std_ms": float(np.std(result.events.loc[inliers, "residual_ms"])),
                "error": "",
            }
        )
    return pd.DataFrame(rows)


def pairwise_text(table: pd.DataFrame) -> str:
    """The pairwise table as aligned text."""
    lines = [
        f"{'pair':<22} {'drift ppm':>10} {'shift ms':>14} {'T_row a ms':>11} {'T_row b ms':>11} "
        f"{'events':>6} {'res std ms':>10}"
    ]
    for row in table.itertuples():
        pair = f"{row.camera_a} -> {row.camera_b}"
        if row.error:
            lines.append(f"{pair:<22} {row.error}")
            continue
        lines.append(
            f"{pair:<22} {row.drift_ppm:>10.3f} {row.shift_ms:>14.3f} {row.row_time_a_ms:>11.6f} "
            f"{row.row_time_b_ms:>11.6f} {row.events:>6d} {row.residual_std_ms:>10.4f}"
        )
    return "\n".join(lines)


def sync_summary(model: SyncModel, report=None, pairwise: pd.DataFrame | None = None) -> dict:
    """Everything the reports show, as plain JSON-able data for scripts."""
    summary = {
        "reference": model.reference,
        "cameras": _records(camera_table(model, report)),
        "rejected_events": _records(rejected_events(model)),
    }
    if report is not None:
        summary |= {
            "warnings": list(report.warnings),
            "flipped_found": list(report.flipped_found),
            "residual_sigma_ms": report.sigma_ms,
        }
    if pairwise is not None:
        summary["pairwise"] = _records(pairwise)
    return summary


def _records(table: pd.DataFrame) -> list[dict]:
    """Rows as dicts of plain Python values (NaN as None)."""
    clean = table.astype(object).where(table.notna(), None)
    return [
        {key: (value.item() if isinstance(value, np.generic) else value) for key, value in row.items()}
        for row in clean.to_dict(orient="records")
    ]
