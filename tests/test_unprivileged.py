"""flashsync run by an account that may not write everywhere (a service account): a package
folder and home it cannot write (numba compiles in memory), a folder it cannot write, a file
it cannot read. Run in a subprocess as that account (``nobody`` where the tests run as root)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]


def unprivileged(*command: str) -> list[str]:
    """``command`` run as an account that file permissions bind (root ignores them)."""
    if os.geteuid() != 0:
        return list(command)
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        pytest.skip("running as root without setpriv: file permissions cannot be tested")
    return [setpriv, "--reuid=65534", "--regid=65534", "--clear-groups", *command]


@pytest.fixture
def shared_tmp():
    """A temporary folder the unprivileged account can enter (pytest's are private to root)."""
    folder = Path(tempfile.mkdtemp(prefix="flashsync-unprivileged-"))
    folder.chmod(0o755)
    yield folder
    for path in [folder, *folder.rglob("*")]:
        if path.is_dir():
            path.chmod(0o755)
    shutil.rmtree(folder)


def make_read_only(folder: Path) -> None:
    for path in [*folder.rglob("*"), folder]:
        path.chmod(0o555 if path.is_dir() else 0o444)


def run(*args: str, cwd: Path, **env: str) -> subprocess.CompletedProcess:
    environment = dict(os.environ, **env)
    return subprocess.run(unprivileged(*args), cwd=cwd, env=environment, capture_output=True, text=True, timeout=300)


def test_numba_without_a_writable_cache_compiles_in_memory(shared_tmp, tiny_scenario):
    """The package in a read-only folder, $HOME and $NUMBA_CACHE_DIR read-only: importing the
    compiled kernels failed with 'cannot cache function _fit_ramp'; now they compile in memory
    and a video is detected."""
    package = shared_tmp / "site"
    shutil.copytree(ROOT / "flashsync", package / "flashsync", ignore=shutil.ignore_patterns("__pycache__"))
    home = shared_tmp / "home"
    home.mkdir()
    video = shared_tmp / "cam1.mp4"
    shutil.copy(tiny_scenario / "cam1.mp4", video)
    make_read_only(package)
    make_read_only(home)
    script = (
        "import flashsync, flashsync.detect; "
        "print(flashsync.__file__); "
        f"print(len(flashsync.detect.detect_video({str(video)!r}).events))"
    )
    result = run(
        sys.executable,
        "-c",
        script,
        cwd=shared_tmp,
        PYTHONPATH=str(package),
        HOME=str(home),
        NUMBA_CACHE_DIR=str(home / "numba"),
    )
    assert result.returncode == 0, result.stderr
    module, events = result.stdout.split()
    assert module.startswith(str(package)) and int(events) > 0


def test_an_output_folder_without_write_permission_fails_before_any_work(shared_tmp, synced_scenario):
    detections = shared_tmp / "d.csv"
    pd.DataFrame({"camera": ["r"], "frame": [2], "y": [3.0]}).to_csv(detections, index=False)
    model = shared_tmp / "sync.json"
    shutil.copy(synced_scenario / "sync.json", model)
    closed = shared_tmp / "closed"
    closed.mkdir()
    make_read_only(closed)
    for path in (detections, model):
        path.chmod(0o644)
    result = run(
        sys.executable,
        "-m",
        "flashsync",
        "restamp",
        str(detections),
        "--model",
        str(model),
        "-o",
        str(closed / "out.csv"),
        cwd=shared_tmp,
    )
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "-o " in lines[0] and "cannot be written in" in lines[0], result.stderr
    assert "Permission denied" in lines[0]
    assert not list(closed.iterdir())


def test_a_file_without_read_permission_is_named_as_such(shared_tmp, tiny_scenario):
    video = shared_tmp / "cam1.mp4"
    shutil.copy(tiny_scenario / "cam1.mp4", video)
    video.chmod(0o000)
    out = shared_tmp / "out"
    out.mkdir(mode=0o777)
    out.chmod(0o777)
    result = run(sys.executable, "-m", "flashsync", "detect", str(video), "-o", str(out / "e.csv"), cwd=shared_tmp)
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "cam1.mp4: cannot be read (permission denied)" in lines[0], result.stderr
