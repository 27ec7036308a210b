"""Atomic output files: write to a hidden temporary file beside the target, then rename.

An output is either the old file or the complete new one, never half written: the data go to
``.NAME.XXXX`` in the target's folder, which replaces the target in one rename once the
data are complete. An error or an interrupt removes the temporary file. SIGINT and SIGTERM
are held while a temporary file is created, renamed or removed (in the main thread; the
held signal is delivered right after), so no interrupt lands between creating a temporary
file and recording it; :func:`remove_temporaries` removes whatever an interrupt at the worst
moment left (the command line calls it on every interrupt).
"""

from __future__ import annotations

import os
import signal
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from flashsync.errors import InputError

#: Temporary files created and not yet renamed or removed.
_TEMPORARIES: set[Path] = set()
_HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def check_output(path: str | Path, folder: bool = False) -> Path:
    """``path`` as a Path if an output file (a folder of outputs, with ``folder``) can be
    written there, else an :class:`~flashsync.errors.InputError` naming it: a folder where a
    file is wanted or a file where a folder is, a parent that is a file, a folder one may
    not write in (tried by creating and removing a hidden file in it)."""
    path = Path(path)
    if path.is_dir() and not folder:
        raise InputError(f"{path}: is a folder; give a file name for the output")
    if path.exists() and folder and not path.is_dir():
        raise InputError(f"{path}: is a file; give a folder for the outputs")
    parent = path if folder and path.is_dir() else _existing_parent(path)
    if not parent.is_dir():
        raise InputError(f"{path}: cannot be written, {parent} is a file and not a folder; choose another path")
    try:
        with _signals_held():
            handle, name = tempfile.mkstemp(prefix=".flashsync-probe.", dir=parent)
            os.close(handle)
            os.unlink(name)
    except OSError as error:
        raise InputError(f"{path}: cannot be written in {parent} ({error.strerror}); choose another folder") from None
    return path


def _existing_parent(path: Path) -> Path:
    """The nearest ancestor of ``path`` that exists (the current folder at worst)."""
    parent = path.absolute().parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    return parent


@contextmanager
def atomic_output(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it to ``path`` if the block succeeds.

    An exception (or an interrupt) inside the block removes the temporary file (and the
    folders made for it), so a failed run never leaves a half-written output behind. A path
    that cannot be written is an :class:`~flashsync.errors.InputError` naming it.

    Examples
    --------
    >>> with atomic_output("events.csv") as tmp:     # doctest: +SKIP
    ...     table.to_csv(tmp, index=False)
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: is a folder; give a file name for the output")
    created = [folder for folder in (path.parent, *path.parent.parents) if not folder.exists()]  # deepest first
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with _signals_held():
            handle, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
            os.close(handle)
            temporary = Path(name)
            _TEMPORARIES.add(temporary)
    except OSError as error:
        _remove_empty(created)
        raise InputError(f"{path}: cannot be written ({error.strerror}); choose another path") from None
    done = False
    try:
        yield temporary
        with _signals_held():
            os.chmod(temporary, 0o666 & ~_umask())
            os.replace(temporary, path)
            _TEMPORARIES.discard(temporary)
            done = True
    except OSError as error:
        if error.filename in (str(temporary), str(path)):
            raise InputError(f"{path}: cannot be written ({error.strerror}); choose another path") from None
        raise
    finally:
        with _signals_held():
            temporary.unlink(missing_ok=True)
            _TEMPORARIES.discard(temporary)
            if not done:
                _remove_empty(created)


def _remove_empty(folders: list[Path]) -> None:
    """Remove the folders (deepest first) that are empty: the ones made for an output that
    was not written."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            return


def remove_temporaries() -> list[Path]:
    """Remove the temporary files of outputs not completed (an interrupt at the worst
    moment can leave one); returns their paths."""
    removed = sorted(_TEMPORARIES)
    for temporary in removed:
        temporary.unlink(missing_ok=True)
    _TEMPORARIES.clear()
    return removed


@contextmanager
def _signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM during the block (main thread only): a signal that arrives
    is delivered, to the handler in place before, when the block ends."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending = []
    previous = {number: signal.getsignal(number) for number in _HELD_SIGNALS}
    if None in previous.values():  # a handler not set from Python cannot be put back
        yield
        return
    for number in _HELD_SIGNALS:
        signal.signal(number, lambda received, frame: pending.append(received))
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        for number in pending:
            signal.raise_signal(number)


def _umask() -> int:
    """The process's file-creation mask (mkstemp makes files 0600; outputs get the usual mode)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_output(path) as temporary:
        temporary.write_text(text, encoding="utf-8")
