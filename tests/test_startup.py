"""Start-up: a command imports only what it needs (timings: benchmarks/bench_startup.py)."""

import subprocess
import sys

import pytest

HEAVY = ("pandas", "scipy", "numba", "av", "cv2", "rerun", "dask", "distributed", "flashsync.detect")


def imported_by(code: str) -> set[str]:
    """The heavy modules a fresh Python process has imported after running ``code``."""
    probe = f"{code}\nimport sys\nprint(' '.join(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)"
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return set(result.stderr.split())


@pytest.mark.parametrize("command", ["", "detect", "sync", "restamp", "diagnose"])
def test_help_imports_nothing_heavy(command):
    arguments = [*command.split(), "--help"]
    code = f"from flashsync.cli import main\ntry:\n    main({arguments!r})\nexcept SystemExit:\n    pass"
    assert imported_by(code) == set()


def test_package_exports_are_lazy_and_complete():
    assert imported_by("import flashsync, flashsync.io, tracking_adapter") == set()
    import flashsync

    for name in flashsync.__all__:
        assert getattr(flashsync, name) is not None
    assert imported_by("from flashsync import synchronize") >= {"pandas", "scipy"}
    with pytest.raises(AttributeError, match="no_such_name"):
        flashsync.no_such_name
