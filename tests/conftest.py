"""Shared fixtures: small rendered scenarios (real H.264 files), made once per test session."""

import os
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
os.environ.setdefault("CI", "1")  # rerun-sdk sends no usage analytics where CI is set


@pytest.fixture(scope="session")
def tiny_scenario(tmp_path_factory) -> Path:
    """The ``tiny`` preset rendered: two cameras (mp4 25 fps, mkv 30 fps), four flashes."""
    from flashsync.simulation import preset, render_scenario

    folder = tmp_path_factory.mktemp("tiny")
    render_scenario(preset("tiny"), folder)
    return folder
