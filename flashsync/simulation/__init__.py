"""Simulated rolling-shutter videos with flashes, and their ground truth.

Render a named preset or a custom scenario into real H.264 files (MP4 with 90 kHz
stamps, MKV with 1 ms stamps), with ``truth.json``, ``detections.csv`` and
``homographies.json`` beside them.

Examples
--------
>>> from flashsync.simulation import preset, render_scenario
>>> truth = render_scenario(preset("tiny"), "out/tiny")  # doctest: +SKIP
>>> truth.cameras["cam2"].alpha  # doctest: +SKIP
1.000015
"""

from flashsync.simulation.render import render_scenario
from flashsync.simulation.scenario import PRESETS, CameraSpec, FlashSpec, LightSwitch, Scenario, load_scenario, preset
from flashsync.simulation.truth import GroundTruth, load_ground_truth

__all__ = [
    "PRESETS",
    "CameraSpec",
    "FlashSpec",
    "GroundTruth",
    "LightSwitch",
    "Scenario",
    "load_ground_truth",
    "load_scenario",
    "preset",
    "render_scenario",
]
