"""Simulated rolling-shutter videos with flashes, and their ground truth.

Render a named preset or a custom scenario into real H.264 files (MP4 with 90 kHz
stamps, MKV with 1 ms stamps), with ``truth.json``, ``detections.csv`` and
``homographies.json`` beside them (scenario files and ``truth.json``: :mod:`flashsync.io`).

Examples
--------
>>> from flashsync.simulation import preset, render_scenario
>>> truth = render_scenario(preset("tiny"), "out/tiny")  # doctest: +SKIP
>>> truth.cameras["cam2"].alpha  # doctest: +SKIP
1.000015
"""

from flashsync.simulation.render import render_scenario
from flashsync.simulation.scenario import PRESETS, CameraSpec, FlashSpec, LightSwitch, Scenario, preset
from flashsync.simulation.truth import GroundTruth

__all__ = [
    "PRESETS",
    "CameraSpec",
    "FlashSpec",
    "GroundTruth",
    "LightSwitch",
    "Scenario",
    "preset",
    "render_scenario",
]
