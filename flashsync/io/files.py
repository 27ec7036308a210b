"""What every format's reader shares: the file must exist, a library's error is cut to one line."""

from __future__ import annotations

import os
from pathlib import Path

from flashsync.errors import InputError


def existing_file(path: str | Path) -> Path:
    """``path`` as a Path, or an :class:`~flashsync.errors.InputError` if it is not a file
    this process may read: no such file, a folder, no permission."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: is a folder, not a file; give the file's path")
    if not path.is_file():
        raise InputError(f"{path}: no such file; check the path")
    if not os.access(path, os.R_OK):
        raise InputError(f"{path}: cannot be read (permission denied); check its permissions")
    return path


def first_line(error: Exception) -> str:
    """The first line of an exception's message (library messages can be long)."""
    lines = str(error).strip().splitlines()
    return lines[0] if lines else type(error).__name__
