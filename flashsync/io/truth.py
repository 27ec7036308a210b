"""``truth.json``: the ground truth of a rendered scenario (:class:`~flashsync.simulation.truth.GroundTruth`).

Written by the simulator beside its videos; read to score a synchronisation against it.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from flashsync.atomic import write_text
from flashsync.errors import InputError
from flashsync.io.fields import Fields, check_types, describe, is_number
from flashsync.simulation.truth import CameraTruth, GroundTruth

FORMAT = "flashsync-truth"
VERSION = 1


def save_ground_truth(truth: GroundTruth, path: str | Path) -> None:
    """Write ``truth`` to ``path`` as JSON, atomically."""
    document = {
        "format": FORMAT,
        "version": VERSION,
        "reference": truth.reference,
        "cameras": {name: asdict(camera) for name, camera in truth.cameras.items()},
        "flashes": truth.flashes,
        "switches": truth.switches,
        "scenario": truth.scenario,
    }
    write_text(path, json.dumps(document, indent=1))


def load_ground_truth(path: str | Path) -> GroundTruth:
    """Read a ``truth.json`` written by :func:`save_ground_truth`.

    Parameters
    ----------
    path : str or Path
        The file, or the folder holding ``truth.json``.
    """
    path = Path(path)
    if path.is_dir():
        path = path / "truth.json"
    if not path.is_file():
        raise InputError(f"{path}: no such ground-truth file; render a scenario first")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise InputError(f"{path}: not valid JSON ({err}); render the scenario again") from None
    fix = "render the scenario again"
    top = Fields(data, str(path), fix=fix)
    if data.get("format") != FORMAT:
        raise InputError(f"{path}: not a flashsync ground-truth file")
    version = data.get("version")
    if not is_number(version) or isinstance(version, float) or version != VERSION:
        top.fail("version", f"is {describe(version)}, expected the number {VERSION}")
    cameras = Fields(top.value("cameras"), str(path), "cameras", fix=fix)
    truths = {}
    for name in cameras.data:
        entry = Fields(cameras.value(name), str(path), f"camera {name!r}", fix=fix)
        check_types(CameraTruth, entry.data, entry.where, str(path), fix=fix)
        for key in ("frame_times_ms", "stamps_ms"):
            entry.numbers(key, increasing=True)
        seen = Fields(entry.value("flashes_seen"), str(path), f"camera {name!r} flashes_seen", fix=fix)
        changes = _exposure_changes(entry)
        try:
            c = dict(
                entry.data,
                flashes_seen={int(k): [int(f) for f in v] for k, v in seen.data.items()},
                exposure_changes=[(int(f), float(e)) for f, e in changes],
            )
            truths[name] = CameraTruth(**c)
        except (TypeError, ValueError) as err:
            raise InputError(f"{path}: camera {name!r}: {err}; {fix}") from None
    reference = top.text("reference")
    if reference not in truths:
        top.fail("reference", f"is {reference!r}, which is not among the cameras")
    return GroundTruth(reference, truths, top.value("flashes"), top.value("switches"), top.value("scenario"))


def _exposure_changes(entry: Fields) -> np.ndarray:
    """A camera's ``exposure_changes``, shape (n, 2): ``[file frame, exposure_ms]`` rows, frames
    whole and increasing, exposures positive; none in a file written before they existed."""
    if not entry.has("exposure_changes"):
        return np.empty((0, 2))
    value = entry.value("exposure_changes")
    changes = entry.matrix("exposure_changes", (len(value) if isinstance(value, list) else 0, 2)).reshape(-1, 2)
    frames = changes[:, 0]
    if np.any(frames < 0) or np.any(frames != np.round(frames)) or np.any(np.diff(frames) <= 0):
        entry.fail("exposure_changes", "has frames that are not whole, >= 0 and increasing")
    if np.any(changes[:, 1] <= 0):
        entry.fail("exposure_changes", "has an exposure that is not positive")
    return changes
