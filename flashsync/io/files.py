"""What every format's reader shares: the file must exist, a library's error is cut to one line."""

from __future__ import annotations

from pathlib import Path

from flashsync.errors import InputError


def existing_file(path: str | Path) -> Path:
    """``path`` as a Path, or an :class:`~flashsync.errors.InputError` if no such file exists."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file; check the path")
    return path


def first_line(error: Exception) -> str:
    """The first line of an exception's message (library messages can be long)."""
    lines = str(error).strip().splitlines()
    return lines[0] if lines else type(error).__name__
