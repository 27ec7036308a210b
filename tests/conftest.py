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


@pytest.fixture(scope="session")
def synced_scenario(tmp_path_factory) -> Path:
    """Three cameras rendered and synchronised (``sync.json`` beside the videos): ``r``
    320x180 at 25 fps (reference), ``f`` 256x144 at 30 fps upside down with dropped frames
    (two in a row, then one), ``s`` 240x180 at 50 fps starting later; seven flashes."""
    from flashsync import detect_videos, save_model, synchronize
    from flashsync.simulation import CameraSpec, FlashSpec, Scenario, render_scenario

    cameras = (
        CameraSpec("r", 320, 180, 25.0, r0=8, r1=6, exposure_ms=10.0, noise_std=1.5),
        CameraSpec(
            "f",
            256,
            144,
            30.0,
            r0=6,
            r1=8,
            exposure_ms=8.0,
            start_ms=2000.0,
            offset_ms=-1900.0,
            drift_ppm=25.0,
            container="mkv",
            flipped=True,
            dropped_frames=(45, 46, 60),
            noise_std=1.5,
            position_m=(-7.0, 15.0, 14.0),
            look_at_m=(18.0, 15.0),
            hfov_deg=75.0,
        ),
        CameraSpec(
            "s",
            240,
            180,
            50.0,
            r0=6,
            r1=4,
            exposure_ms=6.0,
            start_ms=500.0,
            offset_ms=-200.0,
            drift_ppm=-15.0,
            noise_std=1.5,
            n_frames=140,
            position_m=(66.0, 33.0, 16.0),
            look_at_m=(44.0, 16.0),
            hfov_deg=55.0,
        ),
    )
    flashes = tuple(FlashSpec(t, 0.5) for t in (380.0, 870.0, 1330.0, 1720.0, 2210.0, 2650.0, 3010.0))
    folder = tmp_path_factory.mktemp("synced")
    render_scenario(Scenario("synced", cameras, duration_ms=3200.0, flashes=flashes, n_players=4, seed=4), folder)
    model, _ = synchronize(detect_videos([folder / "r.mp4", folder / "f.mkv", folder / "s.mp4"], estimate_readout=True))
    save_model(model, folder / "sync.json")
    return folder


@pytest.fixture(scope="session")
def local_cluster():
    """A real Dask LocalCluster of two worker processes (the cluster extra); its scheduler's
    tcp address."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        yield cluster.scheduler_address
