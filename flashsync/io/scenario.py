"""Scenario files (YAML or JSON): a :class:`~flashsync.simulation.scenario.Scenario` by its field names.

A mapping with the fields of ``Scenario``; ``cameras``, ``flashes`` and ``switches`` are lists
of mappings with the fields of ``CameraSpec``, ``FlashSpec`` and ``LightSwitch``. A ``preset``
key starts from that preset and the other keys override it. Unknown keys are an error naming
the key.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import yaml

from flashsync.errors import InputError
from flashsync.io.fields import check_types, describe, is_number
from flashsync.io.files import existing_file
from flashsync.simulation.scenario import PRESETS, CameraSpec, FlashSpec, LightSwitch, Scenario, check_scenario, preset


def _build(cls: type, data: object, where: str, source: str):
    """Instantiate dataclass `cls` from dict `data`, refusing unknown keys and values of
    the wrong type (:func:`~flashsync.io.fields.check_types`)."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: {where} must be a mapping of field names to values")
    names = [f.name for f in dataclasses.fields(cls)]
    for key in data:
        if key not in names:
            raise InputError(f"{source}: unknown key '{key}' in {where}; valid keys: {', '.join(names)}")
    check_types(cls, data, where, source, skip=_RECORDS)
    try:
        return cls(**data)
    except TypeError as err:
        raise InputError(f"{source}: {where}: {err}") from None


#: Fields holding records of their own, checked by their own dataclass.
_RECORDS = ("cameras", "flashes", "switches")


def _camera(data: object, where: str, source: str) -> CameraSpec:
    cam = _build(CameraSpec, data, where, source)
    try:
        return dataclasses.replace(
            cam,
            dropped_frames=tuple(_whole(f) for f in cam.dropped_frames),
            frame_gaps=tuple((_whole(g[0]), _whole(g[1])) for g in cam.frame_gaps),
            stamp_rate_changes=tuple((_whole(c[0]), float(c[1])) for c in cam.stamp_rate_changes),
            exposure_changes=tuple((_whole(e[0]), float(e[1])) for e in cam.exposure_changes),
            missed_flashes=tuple(_whole(k) for k in cam.missed_flashes),
            gain_steps=tuple(tuple(float(v) for v in step) for step in cam.gain_steps),
            position_m=tuple(float(v) for v in cam.position_m),
            look_at_m=tuple(float(v) for v in cam.look_at_m),
        )
    except (TypeError, ValueError, IndexError) as err:
        raise InputError(
            f"{source}: {where}: a list holds a value of the wrong kind ({err}); fix the scenario"
        ) from None


def _whole(value: object) -> int:
    """A whole number (a frame or flash index), else a ValueError."""
    if not is_number(value) or value != int(value):
        raise ValueError(f"{value!r} is not a whole number")
    return int(value)


def scenario_from_dict(data: object, source: str = "<dict>") -> Scenario:
    """Build a `Scenario` from a plain dict with the dataclasses' field names.

    A ``preset`` key starts from that preset (see `preset`) and the other top-level keys
    replace its fields; ``cameras``, ``flashes`` and ``switches`` are replaced whole.

    Parameters
    ----------
    data : dict
        Scenario fields; cameras, flashes and switches are lists of dicts.
    source : str
        Name used in error messages (the file).

    Returns
    -------
    Scenario

    Raises
    ------
    InputError
        Unknown keys, wrong types or values that cannot be rendered.
    """
    if not isinstance(data, dict):
        raise InputError(f"{source}: the scenario must be a mapping of field names to values")
    data = dict(data)
    base = None
    if "preset" in data:
        name = data.pop("preset")
        if not isinstance(name, str) or name not in PRESETS:
            raise InputError(f"{source}: 'preset' is {describe(name)}, expected one of {', '.join(PRESETS)}")
        base = preset(name)
        data.setdefault("name", base.name)
    names = [f.name for f in dataclasses.fields(Scenario)]
    for key in data:
        if key not in names:
            raise InputError(f"{source}: unknown key '{key}' in the scenario; valid keys: preset, {', '.join(names)}")
    check_types(Scenario, data, "the scenario", source, skip=_RECORDS)
    if "cameras" in data:
        cams = data["cameras"]
        if not isinstance(cams, list):
            raise InputError(f"{source}: 'cameras' must be a list")
        data["cameras"] = tuple(_camera(c, f"cameras[{i}]", source) for i, c in enumerate(cams))
    for key, cls in (("flashes", FlashSpec), ("switches", LightSwitch)):
        if key in data:
            items = data[key]
            if not isinstance(items, list):
                raise InputError(f"{source}: '{key}' must be a list")
            data[key] = tuple(_build(cls, d, f"{key}[{i}]", source) for i, d in enumerate(items))
    if "player_radius_m" in data:
        data["player_radius_m"] = tuple(data["player_radius_m"])
    if base is not None:
        scenario = dataclasses.replace(base, **data)
    else:
        if "name" not in data or "cameras" not in data:
            raise InputError(f"{source}: a scenario needs 'name' and 'cameras' (or a 'preset')")
        scenario = _build(Scenario, data, "the scenario", source)
    try:
        check_scenario(scenario, source)
    except (TypeError, ValueError, IndexError) as err:
        raise InputError(f"{source}: a value has the wrong type or shape ({err}); fix the scenario") from None
    return scenario


def load_scenario(path: str | Path) -> Scenario:
    """Load a scenario from a YAML (.yaml, .yml) or JSON (.json) file, or a preset by name.

    Parameters
    ----------
    path : str or Path
        Scenario file: a mapping with the `Scenario` field names, optionally ``preset``;
        or the name of a preset (``sample``, ``tiny``, ``paper``) when no such file exists.

    Returns
    -------
    Scenario

    Examples
    --------
    A file holding ``{preset: tiny, seed: 7, duration_ms: 1500}`` gives the tiny
    preset with another seed and 1.5 s of video.

    >>> load_scenario("tiny").name
    'tiny'
    """
    path = Path(path)
    if str(path) in PRESETS and not path.is_file():
        return preset(str(path))
    if not path.exists():
        raise InputError(f"{path}: no such scenario file, nor a preset ({', '.join(PRESETS)})")
    suffix = path.suffix.lower()
    if suffix not in (".yaml", ".yml", ".json"):
        raise InputError(f"{path}: unknown scenario format '{suffix}'; use .yaml, .yml or .json")
    path = existing_file(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as err:
        raise InputError(f"{path}: not UTF-8 text (byte {err.start}); save the scenario as UTF-8") from None
    try:
        data = json.loads(text) if suffix == ".json" else yaml.safe_load(text)
    except (json.JSONDecodeError, yaml.YAMLError) as err:
        raise InputError(f"{path}: not valid {suffix[1:].upper()}: {str(err).splitlines()[0]}") from None
    return scenario_from_dict(data, str(path))
