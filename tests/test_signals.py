"""SIGINT and SIGTERM sent for real to the flashsync command at several moments: every output
is either as it was or complete, no temporary file is left, and the last line says honestly
what was written."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from flashsync.io import load_model

ENV = dict(os.environ, PYTHONUNBUFFERED="1")


def interruptible() -> None:
    """In the child before exec: Ctrl-C as a terminal user has it. A shell starting a job in
    the background (``nohup pytest &``) ignores SIGINT, the child inherits that, and
    Python then keeps ignoring it, as it should: the commands would run to the end."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start(*args, cwd: Path, program: tuple[str, ...] = ("-m", "flashsync")) -> subprocess.Popen:
    """The command ``args`` as ``python -m flashsync`` runs it (or ``python *program``)."""
    return subprocess.Popen(
        [sys.executable, *program, *map(str, args)],
        cwd=cwd,
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=interruptible,
    )


def temporaries(folder: Path) -> list[Path]:
    return [path for path in folder.rglob(".*") if path.is_file()]


def open_files(pid: int, folder: Path) -> list[str]:
    """Files under ``folder`` the process has open (Linux: /proc/PID/fd). A descriptor
    closed between the listing and its link is skipped: the decoding threads open and close
    files all the time, and one such race used to hide every open video."""
    try:
        entries = list(Path(f"/proc/{pid}/fd").iterdir())
    except OSError:
        return []
    links = []
    for entry in entries:
        try:
            links.append(os.readlink(entry))
        except OSError:
            continue
    return [link for link in links if link.startswith(str(folder))]


def last_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines and "Traceback" not in err, err
    return lines[-1]


@pytest.fixture(scope="module")
def big_detections(tmp_path_factory, synced_scenario) -> Path:
    """Two million detections of the synced scenario's cameras (some 40 MB of CSV): long
    enough to signal restamp while it writes."""
    folder = tmp_path_factory.mktemp("big")
    rng = np.random.default_rng(3)
    n = 2_000_000
    cameras = np.array(["r", "f", "s"])[rng.integers(0, 3, n)]
    frames = rng.integers(0, 70, n)
    rows = np.round(rng.uniform(0, 140, n), 2)
    lines = [f"{c},{f},{y},puck" for c, f, y in zip(cameras.tolist(), frames.tolist(), rows.tolist())]
    (folder / "big.csv").write_text("camera,frame,y,object\n" + "\n".join(lines) + "\n")
    return folder / "big.csv"


@pytest.mark.parametrize("number, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_restamp_signalled_while_it_writes_keeps_the_old_output(
    big_detections, synced_scenario, tmp_path, number, code
):
    """The signal arrives once the hidden temporary output exists: the old output stays as it
    was, the temporary file goes, the line says nothing was written."""
    output = tmp_path / "out.csv"
    output.write_text("the old output\n")
    process = start("restamp", big_detections, "--model", synced_scenario / "sync.json", "-o", output, cwd=tmp_path)
    deadline = time.monotonic() + 60
    while not temporaries(tmp_path) and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.002)
    assert temporaries(tmp_path), "restamp finished before it could be signalled"
    process.send_signal(number)
    _, err = process.communicate(timeout=60)
    assert process.returncode == code, err
    assert last_line(err) == "flashsync restamp: interrupted; no output written"
    assert output.read_text() == "the old output\n"
    assert not temporaries(tmp_path)


@pytest.mark.parametrize("delay_s", [0.0, 0.3, 1.0])
def test_restamp_signalled_at_any_moment_leaves_old_or_complete_output(
    big_detections, synced_scenario, tmp_path, delay_s
):
    """SIGTERM at a few moments (while starting, reading the model, writing): the output is
    the old one or the complete new one, and the line says which."""
    output = tmp_path / "out.csv"
    output.write_text("the old output\n")
    process = start("restamp", big_detections, "--model", synced_scenario / "sync.json", "-o", output, cwd=tmp_path)
    time.sleep(delay_s)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert not temporaries(tmp_path)
    if process.returncode == 0:  # finished first: complete
        assert output.stat().st_size > 1_000_000
        return
    if process.returncode == -signal.SIGTERM:  # killed before flashsync installed its handler
        assert output.read_text() == "the old output\n"
        return
    assert process.returncode == 143, err
    assert last_line(err) == "flashsync restamp: interrupted; no output written"
    assert output.read_text() == "the old output\n"


def test_sync_interrupted_after_the_model_says_the_model_was_written(synced_scenario, tmp_path):
    """SIGINT once the table is printed (the model saved, the --pairwise table being solved):
    the line names what was written and what was not, and each file is complete or absent."""
    videos = [synced_scenario / name for name in ("r.mp4", "f.mkv", "s.mp4")]
    outputs = {"-o": tmp_path / "sync.json", "--events": tmp_path / "events.csv", "--json": tmp_path / "report.json"}
    process = start("sync", *videos, "--pairwise", *[str(a) for item in outputs.items() for a in item], cwd=tmp_path)
    first = process.stdout.readline()
    assert "drift ppm" in first, first + process.stderr.read()
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=120)
    line = last_line(err)
    assert not temporaries(tmp_path)
    if process.returncode == 0:  # everything finished before the signal landed
        return
    assert process.returncode == 130, err
    assert line.startswith("flashsync sync: interrupted; ") and "no output written" not in line, line
    load_model(outputs["-o"])  # complete
    assert f"{outputs['-o']}" in line.split("not")[0]
    for option, path in outputs.items():
        if path.exists():
            if path.suffix == ".json":
                json.loads(path.read_text())
            assert str(path) in line.split(" not ")[0], (option, line)
        else:
            assert f"{path}" in line and "not written" in line, (option, line)
    if "\npair " not in out:
        assert "the --pairwise table not printed" in line


# flashsync as its script runs it, with a thread that keeps the interpreter 3 s in its shutdown once
# the command is done (as joining threads and tearing down modules do, for a good part of a second,
# at every real exit), however long the command took.
SLOW_EXIT = """
import sys, threading, time
from flashsync.cli import process_main
done = threading.Event()
threading.Thread(target=lambda: (done.wait(), time.sleep(3))).start()
sys.argv[0] = "flashsync"
try:
    code = process_main()
finally:
    done.set()
sys.exit(code)
"""


def test_interrupt_while_the_interpreter_shuts_down_changes_nothing(synced_scenario, tmp_path):
    """A Ctrl-C after restamp wrote its output, while the interpreter shuts down: the exit code
    stays 0, nothing is printed after restamp's own line and the output stays complete."""
    output = tmp_path / "out.csv"
    command = ["restamp", synced_scenario / "detections.csv", "--model", synced_scenario / "sync.json", "-o", output]
    process = start(*command, cwd=tmp_path, program=("-c", SLOW_EXIT))
    deadline = time.monotonic() + 60
    while not output.exists() and time.monotonic() < deadline:
        time.sleep(0.002)
    time.sleep(0.5)  # main has returned: the interpreter waits for the thread
    assert process.poll() is None, "the interpreter did not wait for the thread"
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    rows = len((synced_scenario / "detections.csv").read_text().splitlines()) - 1
    assert process.returncode == 0, (process.returncode, err)
    assert err.splitlines() == [f"{command[1]} -> {output}: {rows} rows, {rows} stamped"], err
    assert len(output.read_text().splitlines()) == rows + 1


def restamp_as_a_script_with(work: str, synced_scenario: Path, tmp_path: Path) -> tuple[int, str, Path]:
    """``python -m`` a module that runs flashsync's ``restamp`` as its script does, its work
    replaced by ``work`` (Python source defining ``work(*args, **kwargs)``): the exit code,
    stderr and the output path."""
    (tmp_path / "replaced").mkdir()
    (tmp_path / "replaced" / "__main__.py").write_text(
        "import importlib, os, signal, sys, time\n"
        "from flashsync.cli import process_main\n"
        f"{work}\n"
        "importlib.import_module('tracking_adapter.restamp').restamp_file = work\n"
        "sys.exit(process_main())\n"
    )
    output = tmp_path / "out.csv"
    command = ["restamp", synced_scenario / "detections.csv", "--model", synced_scenario / "sync.json", "-o", output]
    process = start(*command, cwd=tmp_path, program=("-m", "replaced"))
    _, err = process.communicate(timeout=60)
    return process.returncode, err, output


def test_an_interrupt_that_leaves_a_string_exec_still_exits_130(synced_scenario, tmp_path):
    """restamp's work interrupted inside a string ``exec`` (as a Ctrl-C landing while a
    dataclass is built): exit 130 and the interrupted line, not "killed by SIGINT"."""
    work = "def work(*args, **kwargs):\n    exec('raise KeyboardInterrupt', {})"
    code, err, output = restamp_as_a_script_with(work, synced_scenario, tmp_path)
    assert code == 130, (code, err)
    assert last_line(err) == "flashsync restamp: interrupted; no output written"
    assert not output.exists()


def test_a_sigterm_while_a_class_is_built_still_exits_143(synced_scenario, tmp_path):
    """restamp's work terminated while a class is built (a descriptor's ``__set_name__``, as
    in the dataclasses pandas builds on import, where SIGTERM 0.3 s into restamp once
    landed): Python 3.11 wraps the interrupt in a RuntimeError, and the run came out as its
    traceback, exit 1. Now exit 143 and the interrupted line."""
    work = (
        "class Field:\n"
        "    def __set_name__(self, owner, name):\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "        time.sleep(5)\n"
        "def work(*args, **kwargs):\n"
        "    type('Built', (), {'field': Field()})"
    )
    code, err, output = restamp_as_a_script_with(work, synced_scenario, tmp_path)
    assert code == 143, (code, err)
    assert last_line(err) == "flashsync restamp: interrupted; no output written"
    assert not output.exists()


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs /proc to see when decoding starts")
def test_sync_terminated_while_decoding_stops_soon_and_writes_nothing(synced_scenario, tmp_path):
    """SIGTERM while 90 videos decode (in threads, ~30 s of work on a busy 2-core machine): exit 143 within a
    second or two, no output."""
    videos = tmp_path / "videos"
    videos.mkdir()
    for copy in range(30):
        for name in ("r.mp4", "f.mkv", "s.mp4"):
            (videos / f"{Path(name).stem}{copy}{Path(name).suffix}").write_bytes((synced_scenario / name).read_bytes())
    out = tmp_path / "out"
    process = start("sync", *sorted(videos.iterdir()), "-o", out / "sync.json", "--events", out / "e.csv", cwd=tmp_path)
    deadline = time.monotonic() + 60
    while not (opened := open_files(process.pid, videos)) and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)  # until a video is open: decoding has started
    assert opened, f"no video was opened (exit code {process.poll()})"
    time.sleep(0.2)
    sent = time.monotonic()
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 143, err
    assert time.monotonic() - sent < 6  # a busy CI machine took 4.2 s; the whole run takes far longer
    assert last_line(err) == "flashsync sync: interrupted; no output written"
    assert not out.exists() and not temporaries(tmp_path)
