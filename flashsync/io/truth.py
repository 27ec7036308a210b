"""``truth.json``: the ground truth of a rendered scenario (:class:`~flashsync.simulation.truth.GroundTruth`).

Written by the simulator beside its videos; read to score a synchronisation against it.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

from flashsync.atomic import write_text
from flashsync.errors import InputError
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
    except json.JSONDecodeError as err:
        raise InputError(f"{path}: not valid JSON ({err})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise InputError(f"{path}: not a flashsync ground-truth file")
    if data.get("version") != VERSION:
        raise InputError(f"{path}: ground-truth version {data.get('version')} is not supported (expected {VERSION})")
    cameras = {}
    for name, c in data["cameras"].items():
        c = dict(c, flashes_seen={int(k): v for k, v in c["flashes_seen"].items()})
        cameras[name] = CameraTruth(**c)
    return GroundTruth(data["reference"], cameras, data["flashes"], data["switches"], data["scenario"])
