"""Ctrl-C and SIGTERM while the ``pfaff`` command starts (importing the stages, building its
parser, deriving): one line and exit 130/143, never a KeyboardInterrupt traceback.

``import pfaff`` imports only its table of names (:mod:`pfaff.core.exports`), so the command's
interrupt path is in place before the stages load; a subprocess announces each stage
(``PFAFF_VERBOSE``) and the signal is sent once it has, or a while after."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import pfaff

SIGNALS = [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")]
RING = ["demo", "ring", "--particles", "1000"]
# the console script's own code ([project.scripts] pfaff = "pfaff.cli:main"), and python -m
ENTRIES = {
    "script": [sys.executable, "-c", "import sys; from pfaff.cli import main; sys.exit(main())"],
    "module": [sys.executable, "-m", "pfaff.cli"],
}


def _start(entry: str) -> tuple[subprocess.Popen, bytearray, threading.Event]:
    env = {**os.environ, "PFAFF_VERBOSE": "1", "PYTHONPATH": str(Path(pfaff.__file__).parents[1])}
    proc = subprocess.Popen(
        ENTRIES[entry] + RING, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env
    )
    seen, changed = bytearray(), threading.Event()

    def pump() -> None:
        while chunk := os.read(proc.stderr.fileno(), 4096):
            seen.extend(chunk)
            changed.set()
        changed.set()

    threading.Thread(target=pump, daemon=True).start()
    return proc, seen, changed


def _until(proc: subprocess.Popen, seen: bytearray, changed: threading.Event, marker: bytes):
    deadline = time.monotonic() + 600  # a guard against a hung test only
    while marker not in seen:
        changed.wait(1.0)
        changed.clear()
        assert proc.poll() is None and time.monotonic() < deadline, bytes(seen)[-2000:]


def _ends_in_one_line(proc, seen, sig: int, code: int, word: str) -> None:
    proc.send_signal(sig)
    proc.wait(timeout=600)
    time.sleep(0.05)  # the reader's last chunk
    lines = bytes(seen).decode().strip().splitlines()
    assert proc.returncode == code, lines
    assert "Traceback" not in bytes(seen).decode() and lines[-1] == f"pfaff: {word}", lines
    assert [ln for ln in lines if not ln.startswith("pfaff: ")] == []


@pytest.mark.parametrize("entry", ENTRIES)
@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS)
def test_a_signal_as_the_command_starts(entry: str, sig: int, code: int, word: str) -> None:
    """Sent as soon as the command says it has started: the stages are still to import."""
    proc, seen, changed = _start(entry)
    _until(proc, seen, changed, b"pfaff: starting")
    _ends_in_one_line(proc, seen, sig, code, word)


@pytest.mark.slow  # (the stages import for seconds: a signal at several points of it)
@pytest.mark.parametrize("delay", [0.2, 0.6, 1.5])
@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS)
def test_a_signal_while_the_stages_import(delay: float, sig: int, code: int, word: str) -> None:
    proc, seen, changed = _start("script")
    _until(proc, seen, changed, b"pfaff: starting")
    time.sleep(delay)
    _ends_in_one_line(proc, seen, sig, code, word)


@pytest.mark.slow
@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS)
def test_a_signal_while_the_ring_is_derived(sig: int, code: int, word: str) -> None:
    proc, seen, changed = _start("script")
    _until(proc, seen, changed, b"pfaff: deriving")
    _ends_in_one_line(proc, seen, sig, code, word)
