"""User-facing errors: one clear line, no traceback."""


class FlashsyncError(Exception):
    """Bad input or an impossible request; the message names the file, the problem and what to do."""
