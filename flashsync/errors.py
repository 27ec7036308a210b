"""Errors: one clear line each, naming the data, the problem and what to do; no traceback.

:class:`FlashsyncError` is the base a front end catches; its subclasses say what kind of
problem it is. Messages speak of data (files, cameras, events), never of a front end's
options: an error about the value of one argument of a library call names that argument in
:attr:`FlashsyncError.parameter` and starts its message with the value, so the command line
can put its own option in front (``--reference cam9: ...``).
"""

from __future__ import annotations


class FlashsyncError(Exception):
    """A flashsync error; the message names the data, the problem and what to do.

    Parameters
    ----------
    message : str
        One line.
    parameter : str, optional
        The argument of the library call whose value is wrong (e.g. ``"reference"``); the
        message then starts with that value.
    """

    def __init__(self, message: str, *, parameter: str | None = None):
        super().__init__(message)
        self.parameter = parameter


class InputError(FlashsyncError):
    """An input that cannot be used: a file that is missing, unreadable or malformed, or an
    argument naming something that is not there."""


class ModelFileError(InputError):
    """A model file (``sync.json``) that is missing, damaged or of another format version."""


class NotEnoughDataError(FlashsyncError):
    """Valid data that cannot determine the answer: too few flashes, cameras that share too
    few events, a video too short."""


class UntiedReferenceError(NotEnoughDataError):
    """A reference camera that shares too few flashes with any other to be tied to it.

    Parameters
    ----------
    message : str
    instead : str, optional
        The camera to take as the reference instead: of the largest group of cameras tied
        among themselves, the one with the most matched events (None: no two are tied).
    """

    def __init__(self, message: str, *, instead: str | None = None):
        super().__init__(message)
        self.instead = instead
