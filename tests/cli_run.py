"""Running the flashsync command in-process in tests, and checking its error line."""

from flashsync.cli import main


def run(capsys, *args):
    """Run the CLI in-process; return (exit code, stdout, stderr)."""
    code = main([str(a) for a in args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def one_error_line(err: str, *words: str) -> None:
    """``err`` is one line, an error, no traceback, holding every one of ``words``."""
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in err and "error:" in lines[0], err
    for word in words:
        assert word in lines[0], lines[0]
