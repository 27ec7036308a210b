"""Start-up of the ``flashsync`` command against a bare Python process.

Target: ``flashsync --help`` within 0.3 s of ``python -c pass`` (whole processes).

Usage::

    python benchmarks/bench_startup.py [--repeat N]

Prints the best of N (default 10) wall times of ``python -c pass``, ``flashsync --help``
(the installed entry point) and ``flashsync COMMAND --help`` for every command, and what each
adds to the bare process.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import time


def best_time(command: list[str], repeat: int) -> float:
    """Best wall time of ``repeat`` runs of ``command``, s."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=10, help="runs of each, the best counts (default 10)")
    arguments = parser.parse_args()
    entry = shutil.which("flashsync") or sys.exit("bench_startup: the flashsync command is not installed")
    bare = best_time([sys.executable, "-c", "pass"], arguments.repeat)
    print(f"python -c pass            {bare:.3f} s")
    commands = ["detect", "sync", "restamp", "diagnose", "montage"]
    for extra in [[], *([name] for name in commands)]:
        took = best_time([entry, *extra, "--help"], arguments.repeat)
        label = " ".join(["flashsync", *extra, "--help"])
        print(f"{label:<25} {took:.3f} s  (+{took - bare:.3f} s)")


if __name__ == "__main__":
    main()
