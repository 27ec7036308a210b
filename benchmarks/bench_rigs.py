"""flashsync on the simulator's second world: random rigs and the issues' rigs, against truth.

Run: python benchmarks/bench_rigs.py [--seeds 0:20] [--max-height 540] [--duration-s 12] [--preflash MS]
                                   [--readout LO:HI] [--flash-powers SHARE] [--exposure-changes SHARE]
     python benchmarks/bench_rigs.py --recipes all [--recipe-duration-s S]

Each rig (`flashsync.simulation.rigs`: ``random_rig(seed)`` or a named recipe) is rendered
into a temporary folder (removed afterwards; with ``--keep DIR`` into ``DIR/<rig>``, and a
rig kept there with the same scenario is reused, not rendered again) and run as a new user would, with no options,
exactly as ``flashsync sync`` does: ``detect_videos(videos)`` (both ways up) then
``synchronize(detections)``. Every camera is measured against the truth over all frames and
every 8th row (`flashsync.evaluate.camera_accuracy`): sync error (RMS, max), exposure
error, time-per-row error, and the calibration of the predicted sigma (RMS of error/sigma
and the share of probes within 2 sigma, per camera and pairwise). Detection is checked too:
events on frames that show no flash are false, flashes seen with no event are missed; and
every clean edge (no flag) against the row its flash truly marks, by its band's quality, with
the noise the solve assumes there (`flashsync.pipeline.edge_noise_rows`), and every flash
edge's median error by its camera's tone curve and its kind (paired, or lone), their
spread by the encoder's crf, and the lone ones' and those of bands split across two frames
by their distance from the frame's cut; and
every rolling flicker period that named the mains frequency against the true one, over the
standard deviation flashsync takes (``Flicker.period_rows_sigma``) and over its spread alone.

Prints one line per rig, then the distribution over rigs and cameras and a line for each
camera whose σ understates its error, then every failure
(an exception is a result: it is counted and shown, the run goes on).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
import traceback
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from flashsync import CameraDetection, detect_videos, synchronize
from flashsync.evaluate import camera_accuracy
from flashsync.events import Band, Edge, Flag
from flashsync.io.scenario import scenario_from_dict
from flashsync.io.truth import load_ground_truth
from flashsync.pipeline import edge_noise_rows
from flashsync.robust import MAD_TO_SIGMA
from flashsync.simulation import Scenario, render_scenario
from flashsync.simulation.rigs import (
    RECIPES,
    random_rig,
    recipe,
    with_exposure_changes,
    with_fast_readout,
    with_flash_powers,
    with_preflashes,
)
from flashsync.simulation.truth import CameraTruth, GroundTruth

#: Targets of the honest-numbers issue, for cameras with >= 8 shared flashes and >= 360 rows.
TARGET_RMS_MS, TARGET_MAX_MS, TARGET_EXPOSURE_MS = 0.03, 0.1, 0.1


def detection_counts(detection: CameraDetection, truth_camera: CameraTruth) -> dict:
    """False events (no flash on any of their frames) and missed flashes (seen by the
    camera, no event on their frames) of one camera's detection, in its reading in use."""
    flash_frames = {k: set(frames) for k, frames in truth_camera.flashes_seen.items() if frames}
    lit = set().union(*flash_frames.values())
    events = detection.events
    frames_of: dict[int, set[int]] = {}
    for event, frame in zip(events.event.tolist(), events.frame.tolist()):
        frames_of.setdefault(event, set()).add(frame)
    false = sum(1 for frames in frames_of.values() if not frames & lit)
    found = set().union(*frames_of.values())
    missed = sum(1 for frames in flash_frames.values() if not frames & found)
    return {
        "events": len(frames_of),
        "false_events": false,
        "flashes_seen": len(flash_frames),
        "missed_flashes": missed,
    }


def edge_errors(detection: CameraDetection, truth: GroundTruth) -> dict:
    """The flash edges of one camera's reading in use against the truth: each edge's row
    minus the row whose exposure ended (a leading edge) or started (a trailing one) when its
    flash had given half its light, rows; for the clean ones (no flag) with their band's
    ``quality`` (``edge_quality``, ``edge_error_rows``), for all with their kind
    (``flash_edge_kinds``: leading or trailing, paired or lone where the other edge is
    hidden; ``flash_edge_error_rows``) and, for a lone one or one of a band split across two
    frames, how far it lies from the frame's end its band runs past, in its ramp's 25 %-to-75 %
    rises (``flash_edge_cut_rises``: readout rows to the last row from a leading edge, from the
    first to a trailing one; NaN for an edge of a band within one frame). An edge on a frame of
    no flash the camera saw is left out, and every edge of a reading that is not the camera's
    true one."""
    camera = truth.cameras[detection.camera]
    events = detection.events if detection.flipped == camera.flipped else detection.events.take(slice(0, 0))
    clean = np.array([not flags for flags in events.flags], dtype=bool)
    lone = events.has_flag(Flag.LEADING_HIDDEN) | events.has_flag(Flag.TRAILING_HIDDEN)
    cut_short = lone | events.has_flag(Flag.SPLIT)
    readout = events.row if not detection.flipped else detection.height - 1 - events.row
    cut = np.where(events.edge == Edge.LEADING, detection.height - 1 - readout, readout) / events.rise_rows
    quality, error, kinds, errors, cuts = [], [], [], [], []
    for i in np.flatnonzero(events.band == Band.PULSE):
        frame = int(events.frame[i])
        flashes = [int(k) for k, frames in camera.flashes_seen.items() if frame in frames]
        if not flashes:
            continue
        top, bottom = truth.global_time_ms(detection.camera, [frame, frame], [0.0, detection.height - 1.0])
        late = 0.0 if events.edge[i] == Edge.LEADING else camera.exposure_ms
        rows = [
            (truth.flashes[k]["half_rise_global_ms"] + late - top) / (bottom - top) * (detection.height - 1)
            for k in flashes
        ]
        true_row = min(rows, key=lambda row: abs(row - events.row[i]))
        kinds.append(f"{events.edge[i]} {'lone' if lone[i] else 'paired'}")
        errors.append(float(events.row[i] - true_row))
        cuts.append(float(cut[i]) if cut_short[i] else float("nan"))
        if clean[i]:
            quality.append(float(events.quality[i]))
            error.append(errors[-1])
    return {
        "edge_quality": quality,
        "edge_error_rows": error,
        "flash_edge_kinds": kinds,
        "flash_edge_error_rows": errors,
        "flash_edge_cut_rises": cuts,
    }


def flicker_error(detection: CameraDetection, scenario, truth: GroundTruth) -> dict:
    """The camera's rolling flicker period against the truth, where it named the scenario's
    mains frequency: ``flicker_error_pct`` (measured minus true period, % of the true one),
    ``flicker_sigma_pct`` (the standard deviation taken, :attr:`Flicker.period_rows_sigma`)
    and ``flicker_spread_pct`` (its spread alone); NaN elsewhere."""
    flicker = detection.flicker
    if not scenario.flicker_depth or flicker is None or flicker.hz != scenario.flicker_hz:
        return {"flicker_error_pct": np.nan, "flicker_sigma_pct": np.nan, "flicker_spread_pct": np.nan}
    true = 1000.0 / scenario.flicker_hz / truth.cameras[detection.camera].row_time_ms
    return {
        "flicker_error_pct": 100.0 * (flicker.period_rows / true - 1.0),
        "flicker_sigma_pct": 100.0 * flicker.period_rows_sigma / true,
        "flicker_spread_pct": 100.0 * flicker.period_rows_std / true,
    }


def flicker_block(cameras: pd.DataFrame) -> list[str]:
    """The flicker periods against the truth, and their error over the standard deviation
    taken and over the spread alone."""
    named = cameras.dropna(subset=["flicker_error_pct"])
    if not len(named):
        return []
    z = named["flicker_error_pct"] / named["flicker_sigma_pct"]
    spread_z = named["flicker_error_pct"] / named["flicker_spread_pct"]
    return [
        f"rolling flicker period against the truth ({len(named)} cameras that named the mains frequency):",
        f"  |error| %                {distribution(named['flicker_error_pct'].abs(), '%')}",
        f"  error/σ: RMS {np.sqrt(np.mean(z**2)):.2f}; within 2σ {100 * np.mean(np.abs(z) <= 2):.1f} %; "
        f"error/spread alone: RMS {np.sqrt(np.mean(spread_z**2)):.2f}",
    ]


def edge_block(cameras: pd.DataFrame) -> list[str]:
    """Clean edges' errors by their band's quality: robust sigma (rows) against the noise
    the solve assumes at the bin's median quality."""
    quality = np.concatenate([np.asarray(q, dtype=float) for q in cameras["edge_quality"]])
    error = np.concatenate([np.asarray(e, dtype=float) for e in cameras["edge_error_rows"]])
    lines = [f"clean edges against the truth by band quality ({len(error)} edges):"]
    for low, high in ((0, 1000), (1000, 1700), (1700, 3000), (3000, np.inf)):
        binned = (quality >= low) & (quality < high)
        mine = error[binned]
        if mine.size:
            assumed = float(edge_noise_rows(np.median(quality[binned])))
            lines.append(
                f"  quality {low:>4}-{high:<5} n {mine.size:>5}  median {np.median(mine):+.2f}  robust σ "
                f"{MAD_TO_SIGMA * np.median(np.abs(mine - np.median(mine))):.2f} rows (assumed {assumed:.2f})"
            )
    return lines


def flash_edges(cameras: pd.DataFrame, columns: list[str]) -> pd.DataFrame:
    """Every flash edge of ``cameras`` (one row each): its kind, its error against the truth
    (rows), where the run recorded it its rises from the frame's cut (``cut_rises``,
    :func:`edge_errors`) and its camera's ``columns``; an edge over 50 rows off (matched to
    the wrong flash) left out."""
    counts = [len(k) for k in cameras["flash_edge_kinds"]]
    edges = pd.DataFrame(
        {
            **{column: np.repeat(cameras[column].to_numpy(), counts) for column in columns},
            "kind": np.concatenate([np.asarray(k, dtype=object) for k in cameras["flash_edge_kinds"]]),
            "error": np.concatenate([np.asarray(e, dtype=float) for e in cameras["flash_edge_error_rows"]]),
        }
    )
    if "flash_edge_cut_rises" in cameras:  # not in the --json files of runs before 2026-11-29, eighth
        edges["cut_rises"] = np.concatenate([np.asarray(c, dtype=float) for c in cameras["flash_edge_cut_rises"]])
    return edges[edges["error"].abs() < 50]


def tone_block(cameras: pd.DataFrame) -> list[str]:
    """Flash edges' median error (rows) by their camera's tone curve and their kind (a lone
    edge's partner is hidden): a tone curve compresses the light of a band's plateau, so
    its half-level crossings move out, leading edges early and trailing ones late, the
    more the longer the ramp."""
    edges = flash_edges(cameras, ["tone"])
    kinds = ["leading paired", "trailing paired", "leading lone", "trailing lone"]
    lines = [f"flash edges against the truth by tone curve, median rows (count): {', '.join(kinds)}"]
    for tone, mine in edges.groupby("tone"):
        medians = [mine.loc[mine["kind"] == kind, "error"] for kind in kinds]
        lines.append(f"  {tone:<7}" + "".join(f"  {m.median():+6.2f} ({m.size:>4})" for m in medians))
    return lines


#: The encoder's crf bins of :func:`codec_block`, each (first, last): the simulator's rigs
#: are encoded at crf 18-30 (`flashsync.simulation.rigs`).
CRF_BINS = ((18, 20), (21, 23), (24, 26), (27, 30))


def codec_block(cameras: pd.DataFrame) -> list[str]:
    """Paired flash edges' spread against the truth (robust σ, rows, and the share more than
    2 rows off) by their camera's crf: the codec's dead zone erases the faint foot of a ramp,
    the more the higher the crf, and the edge moves."""
    edges = flash_edges(cameras, ["crf"])
    edges = edges[edges["kind"].str.endswith("paired")]
    lines = ["paired flash edges against the truth by the encoder's crf:"]
    for low, high in CRF_BINS:
        error = edges.loc[edges["crf"].between(low, high), "error"].to_numpy()
        if error.size:
            lines.append(f"  crf {low}-{high}  n {error.size:>5}  {spread(error)}")
    return lines


def spread(error: np.ndarray) -> str:
    """Edges' errors (rows, shape (n,)) as the blocks print their spread: the robust σ and
    the share more than 2 rows off."""
    sigma = MAD_TO_SIGMA * np.median(np.abs(error - np.median(error)))
    return f"robust σ {sigma:.2f} rows  over 2 rows {100 * np.mean(np.abs(error) > 2):4.1f} %"


#: The bins of :func:`cut_block`: an edge's distance from the frame's cut, in its ramp's rises.
CUT_BINS = ((0, 2), (2, 4), (4, 8), (8, 16), (16, np.inf))


def cut_block(cameras: pd.DataFrame) -> list[str]:
    """Lone flash edges (their partner hidden beyond the frame's first or last row) and the
    edges of bands split across two frames against the truth by their kind and how many
    rises of their ramp lie between them and the cut their band runs past: the median and
    robust σ (rows) and the share more than 2 rows off. Near the cut the rows the detector
    reads a band's level from are still on its ramp (a trailing edge's under the leading ramp
    of a pulse's tail). An edge whose rise was not measured is not binned, nor a split band's
    in the --json files of runs before 2026-12-04, thirty-fifth."""
    edges = flash_edges(cameras, [])
    lines = ["lone and split flash edges against the truth by their distance from the frame's cut (ramp rises):"]
    # a paired edge with a distance to the cut is an edge of a band split across two frames
    kinds = {
        "leading lone": "leading lone",
        "trailing lone": "trailing lone",
        "leading paired": "leading split",
        "trailing paired": "trailing split",
    }
    for kind, label in kinds.items():
        mine = edges[edges["kind"] == kind]
        for low, high in CUT_BINS:
            error = mine.loc[(mine["cut_rises"] >= low) & (mine["cut_rises"] < high), "error"].to_numpy()
            if error.size:
                head = f"  {label:<14} {low:>2}-{high:<3} n {error.size:>4}  median {np.median(error):+.2f}"
                lines.append(f"{head}  {spread(error)}")
    return lines


def describe(scenario) -> dict:
    """What a rig is, for its line and for grouping: size range, rates, pulse, flicker."""
    heights = [c.height for c in scenario.cameras]
    rates = sorted({round(c.fps, 2) for c in scenario.cameras})
    pulse = scenario.flashes[0].shape if scenario.flashes else "none"
    flicker = (
        f"{100 * scenario.flicker_depth:.1f}% {scenario.flicker_hz:.0f} Hz {scenario.flicker_waveform}"
        if scenario.flicker_depth
        else "no flicker"
    )
    return {
        "rig": scenario.name,
        "cameras": len(scenario.cameras),
        "rows": f"{min(heights)}-{max(heights)}",
        "rates": "/".join(f"{r:g}" for r in rates),
        "equal_rate": len(rates) == 1,
        "pulse": pulse,
        "flicker": flicker,
        "flashes": len(scenario.flashes),
    }


def shared_flashes(truth) -> dict[str, int]:
    """Per camera: flashes it saw that at least one other camera saw too."""
    seen = {name: {k for k, frames in c.flashes_seen.items() if frames} for name, c in truth.cameras.items()}
    return {name: len({k for k in mine if any(k in seen[o] for o in seen if o != name)}) for name, mine in seen.items()}


def rendered(scenario, folder: Path):
    """The truth of `scenario` rendered into `folder`: an earlier rendering of exactly this
    scenario kept there (same name, seed, size cap and duration; a field added since, at its
    default, counts as the same) or a new one."""
    try:
        truth = load_ground_truth(folder)
        if scenario_from_dict(truth.scenario) == scenario:
            return truth
    except Exception:  # noqa: BLE001 - nothing usable kept: render
        pass
    return render_scenario(scenario, folder)


def run_rig(scenario, keep: Path | None = None) -> tuple[dict, pd.DataFrame]:
    """Render (or reuse a kept rendering), detect, sync and measure one rig; returns its
    summary and per-camera table."""
    info = describe(scenario)
    stage = "render"
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="flashsync-rig-") as tmp:
        folder = keep / scenario.name if keep else Path(tmp)
        try:
            truth = rendered(scenario, folder) if keep else render_scenario(scenario, folder)
            info["render_s"] = time.perf_counter() - start
            stage = "detect"
            videos = [folder / truth.cameras[c.name].file for c in scenario.cameras]
            detections = detect_videos(videos)
            stage = "sync"
            model, report = synchronize(detections)
            stage = "evaluate"
            table = camera_accuracy(model, truth)
        except Exception as error:  # noqa: BLE001 - every failure is a result
            info.update(failure=f"{stage}: {type(error).__name__}: {error}", traceback=traceback.format_exc(limit=-3))
            if stage in ("sync", "evaluate"):
                counts = [
                    detection_counts(d.read_flipped(spec.flipped) if d.undecided else d, truth.cameras[d.camera])
                    for d, spec in zip(detections, scenario.cameras)
                ]
                info["false_events"] = sum(c["false_events"] for c in counts)
                info["missed_flashes"] = sum(c["missed_flashes"] for c in counts)
            info["total_s"] = time.perf_counter() - start
            return info, pd.DataFrame()
    info["total_s"] = time.perf_counter() - start
    shared = shared_flashes(truth)
    by_name = {d.camera: d for d in detections}
    counts = []
    for spec in scenario.cameras:
        detection = by_name[spec.name]
        if detection.undecided and spec.name in model.cameras:
            detection = detection.read_flipped(model.cameras[spec.name].flipped)
        counts.append(
            detection_counts(detection, truth.cameras[spec.name])
            | edge_errors(detection, truth)
            | flicker_error(detection, scenario, truth)
        )
    extra = pd.DataFrame(counts).assign(
        rig=scenario.name,
        height=[c.height for c in scenario.cameras],
        fps=[c.fps for c in scenario.cameras],
        exposure_ms=[c.exposure_ms for c in scenario.cameras],
        tone=[c.tone for c in scenario.cameras],
        crf=[c.crf for c in scenario.cameras],
        true_flipped=[c.flipped for c in scenario.cameras],
        equal_rate=info["equal_rate"],
        shared_flashes=[shared[c.name] for c in scenario.cameras],
    )
    table = pd.concat([table.reset_index(drop=True), extra], axis=1)
    table["flip_ok"] = [
        bool(model.cameras[n].flipped == f) if n in model.cameras else False
        for n, f in zip(table["camera"], table["true_flipped"])
    ]
    solved = table[table["solved"]]
    info.update(
        rms_ms=float(np.sqrt(np.mean(solved["rms_ms"] ** 2))),
        max_ms=float(solved["max_ms"].max()),
        left_out=int((~table["solved"]).sum()),
        false_events=int(table["false_events"].sum()),
        missed_flashes=int(table["missed_flashes"].sum()),
        warnings=len(report.warnings),
        wrong_flip=int((~table["flip_ok"] & table["solved"]).sum()),
    )
    return info, table


def rig_line(info: dict, table: pd.DataFrame) -> str:
    head = (
        f"{info['rig']:<20} {info['cameras']:>2} cams {info['rows']:>9} rows {info['rates']:<22} "
        f"{info['pulse']:<12} {info['flicker']:<22}"
    )
    if "failure" in info:
        return f"{head} FAILED {info['failure'][:110]}"
    solved = table[table["solved"]]
    z = solved["z_rms"].dropna()
    return (
        f"{head} RMS {info['rms_ms']:.3f} max {info['max_ms']:.3f} ms | exp err "
        f"{solved['exposure_error_ms'].abs().max():.2f} ms | T_row {solved['row_time_error_pct'].abs().max():.2f} % | "
        f"z {z.max() if len(z) else float('nan'):.1f} pair-in-2σ {100 * solved['pair_within_2sigma'].min():.0f} % | "
        f"false {info['false_events']} missed {info['missed_flashes']} out {info['left_out']} "
        f"flip {info['wrong_flip']} | {info['total_s']:.0f} s ({info['render_s']:.0f} render)"
    )


def distribution(values: pd.Series, unit: str = "", scale: float = 1.0) -> str:
    v = values.dropna().to_numpy(dtype=float) * scale
    if v.size == 0:
        return "no values"
    p10, p50, p90 = np.percentile(v, [10, 50, 90])
    return (
        f"n {v.size:>4}  p10 {p10:8.3f}  median {p50:8.3f}  p90 {p90:8.3f}  max {v.max():8.3f}  "
        f"mean {v.mean():+8.3f} {unit}"
    )


def camera_block(cameras: pd.DataFrame) -> list[str]:
    """Distribution lines of the accuracy of solved cameras."""
    others = cameras[~cameras["reference"]]
    z = others["z_rms"].dropna()
    lines = [
        f"  sync RMS ms              {distribution(cameras['rms_ms'], 'ms')}",
        f"  sync max ms              {distribution(cameras['max_ms'], 'ms')}",
    ]
    if "reference_rms_ms" in cameras:  # not in the --json files of runs before 2026-11-26
        lines.append(f"  RMS against ref, ms      {distribution(others['reference_rms_ms'], 'ms')}")
    for label, part in (
        ("exposure <= 6 ms, err ms", cameras[cameras["exposure_ms"] <= 6.0]),
        ("exposure > 6 ms, err ms", cameras[cameras["exposure_ms"] > 6.0]),
    ):
        lines.append(f"  {label:<25}{distribution(part['exposure_error_ms'], 'ms')}")
    if "exposure_frames_rms_ms" in cameras:  # not in the --json files of runs before 2026-12-03
        lines += [
            f"  exposure by frame, ms    {distribution(cameras['exposure_frames_rms_ms'], 'ms')}",
            f"  its error/σ RMS          {distribution(cameras['exposure_frames_z_rms'])}",
        ]
    for label, part in (
        ("|T_row error| %, equal", cameras[cameras["equal_rate"]]),
        ("|T_row error| %, mixed", cameras[~cameras["equal_rate"]]),
    ):
        lines.append(f"  {label:<25}{distribution(part['row_time_error_pct'].abs(), '%')}")
    # not in the --json files of runs before 2026-11-26 and 2026-11-29
    for label, column in (("T_row", "row_time_z"), ("exposure", "exposure_z")):
        if column in cameras:
            scores = cameras[column].dropna()
            lines.append(
                f"  {label} error/σ: RMS {np.sqrt(np.mean(scores**2)):.2f}; within 2σ "
                f"{100 * np.mean(scores.abs() <= 2):.1f} %, over 3: {int((scores.abs() > 3).sum())} of "
                f"{len(scores)} cameras"
            )
    lines += [
        f"  error/σ RMS (non-ref)    {distribution(others['z_rms'])}",
        f"  within 2σ % (non-ref)    {distribution(others['within_2sigma'], '%', 100)}",
        f"  error/σ over all non-ref cameras: RMS {np.sqrt(np.mean(z**2)):.2f}; cameras under 0.5: "
        f"{int((z < 0.5).sum())}, over 2: {int((z > 2).sum())} of {len(z)}",
        f"  pair error/σ RMS         {distribution(cameras['pair_z_rms'])}",
        f"  pair within 2σ %         {distribution(cameras['pair_within_2sigma'], '%', 100)}",
        f"  predicted σ RMS ms       {distribution(cameras['sigma_rms_ms'], 'ms')}",
    ]
    target = cameras[(cameras["shared_flashes"] >= 8) & (cameras["height"] >= 360)]
    if len(target):
        meets = (
            (target["rms_ms"] <= TARGET_RMS_MS)
            & (target["max_ms"] <= TARGET_MAX_MS)
            & (target["exposure_error_ms"].abs() <= TARGET_EXPOSURE_MS)
        )
        lines += [
            f"  >= 8 shared flashes and >= 360 rows: {len(target)} cameras, {int(meets.sum())} meet RMS <= "
            f"{TARGET_RMS_MS} ms, max <= {TARGET_MAX_MS} ms and exposure within {TARGET_EXPOSURE_MS} ms",
            f"    sync RMS ms            {distribution(target['rms_ms'], 'ms')}",
            f"    sync max ms            {distribution(target['max_ms'], 'ms')}",
        ]
    return lines


def overconfident_block(cameras: pd.DataFrame) -> list[str]:
    """One line per solved camera whose σ understates its error: times over 2σ (error/σ RMS
    of a non-reference camera), or its time per row or exposure over 3σ."""
    over = cameras[
        (cameras["z_rms"] > 2)
        | (cameras.get("row_time_z", pd.Series(0.0, cameras.index)).abs() > 3)
        | (cameras.get("exposure_z", pd.Series(0.0, cameras.index)).abs() > 3)
    ]
    lines = [f"cameras whose σ understates the error (times over 2σ, time per row or exposure over 3σ): {len(over)}"]
    for _, c in over.iterrows():
        lines.append(
            f"  {c['rig']} {c['camera']}: {c['rms_ms']:.3f} ms RMS at error/σ {c['z_rms']:.1f}, time per row "
            f"{c['row_time_error_pct']:+.2f} % at {c.get('row_time_z', float('nan')):.1f}σ, exposure "
            f"{c['exposure_error_ms']:+.3f} ms at {c.get('exposure_z', float('nan')):.1f}σ"
        )
    return lines


def summary(infos: list[dict], tables: pd.DataFrame) -> str:
    """The distribution over rigs and cameras (exposures split at 6 ms, time per row by
    equal and mixed frame rates), over all solved cameras and over the rigs whose readout
    directions all came out right (a wrong one makes every other number of its rig moot)."""
    ok = [i for i in infos if "failure" not in i]
    lines = [
        f"rigs: {len(infos)}, solved {len(ok)}, failed {len(infos) - len(ok)}; cameras: "
        f"{sum(i['cameras'] for i in infos)}, solved {int(tables['solved'].sum()) if len(tables) else 0}"
    ]
    if not len(tables):
        return "\n".join(lines)
    solved = tables[tables["solved"]]
    wrong = solved[~solved["flip_ok"].astype(bool)]
    clean = solved[~solved["rig"].isin(wrong["rig"])]
    lines += [
        f"readout direction wrong: {len(wrong)} cameras in {wrong['rig'].nunique()} rigs; cameras left out: "
        f"{int((~tables['solved']).sum())}",
        "over rigs (all cameras of a rig pooled):",
        f"  sync RMS ms              {distribution(pd.Series([i['rms_ms'] for i in ok]), 'ms')}",
        f"  sync max ms              {distribution(pd.Series([i['max_ms'] for i in ok]), 'ms')}",
        f"all solved cameras ({len(solved)}):",
        *camera_block(solved),
        f"cameras of the {clean['rig'].nunique()} rigs with every readout direction right ({len(clean)}):",
        *camera_block(clean),
        *overconfident_block(solved),
        "detection, every camera:",
        f"  false events             {distribution(tables['false_events'])}",
        f"  missed flashes           {distribution(tables['missed_flashes'])}",
    ]
    if "edge_error_rows" in tables:  # not in the --json files of runs before 2026-11-27
        lines += edge_block(tables)
    if "flash_edge_kinds" in tables:  # not in the --json files of earlier runs
        lines += tone_block(tables)
    if "crf" in tables:  # not in the --json files of runs before 2026-11-29, seventh
        lines += codec_block(tables)
    if "flash_edge_cut_rises" in tables:  # not in the --json files of runs before 2026-11-29, eighth
        lines += cut_block(tables)
    if "flicker_error_pct" in tables:  # not in the --json files of runs before 2026-11-29
        lines += flicker_block(tables)
    return "\n".join(lines)


def parse_seeds(text: str) -> list[int]:
    first, _, last = text.partition(":")
    return list(range(int(first), int(last))) if last else [int(first)]


def readout_fractions(text: str) -> tuple[float, float]:
    """``LO:HI`` of ``--readout``: the fractions of the frame period a sensor may read its rows in."""
    try:
        low, high = (float(x) for x in text.split(":"))
    except ValueError:
        low = high = float("nan")
    if not 0.0 < low <= high <= 1.0:
        raise argparse.ArgumentTypeError(f"{text}: give LO:HI with 0 < LO <= HI <= 1, e.g. 0.45:0.75")
    return low, high


def share(text: str) -> float:
    """``SHARE`` of ``--flash-powers`` or ``--exposure-changes``: a share (of flashes, of cameras)."""
    try:
        share = float(text)
    except ValueError:
        share = float("nan")
    if not 0.0 <= share <= 1.0:
        raise argparse.ArgumentTypeError(f"{text}: give a share between 0 and 1, e.g. 0.3")
    return share


def add_world_options(parser: argparse.ArgumentParser) -> None:
    """The options that change the random rigs' world (:func:`dressed`)."""
    parser.add_argument(
        "--preflash",
        type=float,
        metavar="MS",
        help="fire the random rigs' flashes as TTL flashes: a pre-flash at 0.3 of each flash's strength MS ms "
        "before it (rigs named rig-N-ttlMS; each camera blind to the pre-flashes p 1/2; with_preflashes)",
    )
    parser.add_argument(
        "--preflash-jitter-ms", type=float, default=1.0, help="std of the pre-flashes' delay, ms (default 1)"
    )
    parser.add_argument(
        "--readout",
        type=readout_fractions,
        metavar="LO:HI",
        help="give the random rigs' sensors a fast readout: each camera reads its rows in a fraction U(LO, HI) of "
        "its frame period (rigs named rig-N-readLO-HI; with_fast_readout)",
    )
    parser.add_argument(
        "--flash-powers",
        type=share,
        metavar="SHARE",
        help="fire the random rigs' flashes at two powers: each p SHARE at full power, its pulse 2-3 ms long to a "
        "tenth of its peak, else at a low power, 0.05-0.3 ms (rigs named rig-N-powerSHARE; with_flash_powers)",
    )
    parser.add_argument(
        "--exposure-changes",
        type=share,
        metavar="SHARE",
        help="give the random rigs' cameras auto exposure: each p SHARE changes its exposure once, in the middle half "
        "of its recording, to 0.4-0.7 or 1.4-2 times it (rigs named rig-N-aeSHARE; with_exposure_changes)",
    )


def dressed(rigs: list[Scenario], args: argparse.Namespace) -> list[Scenario]:
    """The random rigs in the world :func:`add_world_options`' options ask for, each renamed
    after what was added."""
    if args.preflash is not None:
        rigs = [
            replace(
                with_preflashes(rig, args.preflash, jitter_ms=args.preflash_jitter_ms, seed=rig.seed),
                name=f"{rig.name}-ttl{args.preflash:g}",
            )
            for rig in rigs
        ]
    if args.readout is not None:
        low, high = args.readout
        rigs = [
            replace(with_fast_readout(rig, (low, high), seed=rig.seed), name=f"{rig.name}-read{low:g}-{high:g}")
            for rig in rigs
        ]
    if args.flash_powers is not None:
        rigs = [
            replace(
                with_flash_powers(rig, args.flash_powers, seed=rig.seed), name=f"{rig.name}-power{args.flash_powers:g}"
            )
            for rig in rigs
        ]
    if args.exposure_changes is not None:
        rigs = [
            replace(
                with_exposure_changes(rig, args.exposure_changes, seed=rig.seed),
                name=f"{rig.name}-ae{args.exposure_changes:g}",
            )
            for rig in rigs
        ]
    return rigs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--seeds", help="random rigs A:B (seeds A..B-1) or one seed; default 0:20 unless --recipes is given"
    )
    parser.add_argument("--max-height", type=int, default=540, help="largest image height of random rigs")
    parser.add_argument("--duration-s", type=float, default=12.0, help="length of random rigs, s")
    add_world_options(parser)
    parser.add_argument("--recipes", help=f"'all' or a comma list of: {', '.join(RECIPES)}")
    parser.add_argument(
        "--recipe-duration-s",
        type=float,
        help="length of recipe rigs, s (default: each recipe's own, 15 min for long-pair)",
    )
    parser.add_argument("--recipe-seed", type=int, default=0)
    parser.add_argument(
        "--keep",
        type=Path,
        help="keep the rendered rigs in this folder; a rig kept there with the same scenario is not rendered again",
    )
    parser.add_argument("--json", type=Path, help="write every rig and camera result here")
    parser.add_argument(
        "--summarise",
        type=Path,
        metavar="JSON",
        help="print the lines and summary of a --json file of an earlier run, render nothing",
    )
    args = parser.parse_args()
    if args.summarise:
        saved = json.loads(args.summarise.read_text())
        cameras = pd.DataFrame(saved["cameras"])
        for info in saved["rigs"]:
            print(rig_line(info, cameras[cameras["rig"] == info["rig"]] if len(cameras) else cameras))
        print()
        print(summary(saved["rigs"], cameras))
        return
    scenarios = []
    if args.recipes:
        names = list(RECIPES) if args.recipes == "all" else args.recipes.split(",")
        duration_ms = args.recipe_duration_s * 1000.0 if args.recipe_duration_s else None
        scenarios += [recipe(n, args.recipe_seed, duration_ms) for n in names]
    if args.seeds or not args.recipes:
        rigs = [
            random_rig(s, max_height=args.max_height, duration_ms=args.duration_s * 1000.0)
            for s in parse_seeds(args.seeds or "0:20")
        ]
        scenarios += dressed(rigs, args)
    infos, tables = [], []
    for scenario in scenarios:
        info, table = run_rig(scenario, args.keep)
        infos.append(info)
        tables.append(table)
        print(rig_line(info, table), flush=True)
    all_tables = (
        pd.concat([t for t in tables if len(t)], ignore_index=True) if any(len(t) for t in tables) else pd.DataFrame()
    )
    print()
    print(summary(infos, all_tables))
    failures = [i for i in infos if "failure" in i]
    if failures:
        print(f"\nfailures ({len(failures)}):")
        for info in failures:
            extra = (
                f" (false events {info['false_events']}, missed flashes {info['missed_flashes']})"
                if "false_events" in info
                else ""
            )
            print(f"  {info['rig']}: {info['failure']}{extra}")
    if args.json:
        args.json.write_text(
            json.dumps({"rigs": infos, "cameras": all_tables.to_dict(orient="records")}, indent=1, default=str)
        )


if __name__ == "__main__":
    main()
