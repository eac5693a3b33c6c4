"""One interrupt path (pfaff.cli.signals): Ctrl-C and SIGTERM at any stage of any command end it
with one line, 130/143 before a simulation, 3 during one (its partial results written), and a
write in progress leaves the old file and no temporary file.

The signals are real: sent by the process to itself from inside a stage (deterministic), or to a
``pfaff`` subprocess once it has announced (``PFAFF_VERBOSE``) that it is inside the stage."""

from __future__ import annotations

import csv
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import pfaff
from pfaff.cli.main import main

EXAMPLE = str(Path(__file__).parents[2] / "examples" / "pendulum.toml")
SIGNALS = [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")]


def _signal_inside(monkeypatch: pytest.MonkeyPatch, owner: object, name: str, sig: int) -> None:
    """``owner.name`` sends ``sig`` to this process when called, then runs on."""
    real = getattr(owner, name)

    def patched(*args, **kwargs):
        os.kill(os.getpid(), sig)
        return real(*args, **kwargs)

    monkeypatch.setattr(owner, name, patched)


@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS)
def test_during_derivation_every_command_ends_in_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], sig, code, word
) -> None:
    _signal_inside(monkeypatch, pfaff.System, "equations", sig)
    for argv in (
        ["equations", EXAMPLE],
        ["run", EXAMPLE, "--t-end", "0.1"],
        ["demo", "pendulum", "--simulate", "--t-end", "0.1"],
        ["sweep", EXAMPLE, "--vary", "g=9:10:2", "--scheduler", "synchronous", "--samples", "3"],
    ):
        assert main(argv) == code, argv
        err = capsys.readouterr().err
        assert err.strip().splitlines() == [f"pfaff: {word}"] and "Traceback" not in err
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL  # handlers given back


class _Finalized:
    """An object whose finalizer is where the signal's KeyboardInterrupt lands: Python prints
    it ("Exception ignored") and drops it, as inside a library's callback."""

    def __init__(self, sig: int) -> None:
        self.sig = sig

    def __del__(self) -> None:
        signal.raise_signal(self.sig)  # the handler runs here, in the finalizer


@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS)
def test_a_signal_a_library_swallowed_still_ends_the_command(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], sig, code, word
) -> None:
    """The interrupt raised inside a finalizer is dropped and `equations` runs to its end; the
    signal was received, so the command reports it (one line, 130/143) instead of exit 0."""
    real = pfaff.System.equations

    def patched(*args, **kwargs):
        _Finalized(sig)  # made and dropped at once: its finalizer swallows the interrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(pfaff.System, "equations", patched)
    assert main(["equations", EXAMPLE]) == code
    err = capsys.readouterr().err
    assert err.strip().splitlines()[-1] == f"pfaff: {word}"
    monkeypatch.undo()
    assert main(["equations", EXAMPLE]) == 0  # (a later command: its own signals only)


@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS)
def test_during_a_write_the_old_file_stays(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path, sig, code, word
) -> None:
    out = tmp_path / "run.csv"
    out.write_text("the old results\n")
    real = csv.writer

    class HalfWriter:
        def __init__(self, fh):
            self.w = real(fh)

        def writerow(self, row):
            self.w.writerow(row)

        def writerows(self, rows):
            self.w.writerow(rows[0])
            os.kill(os.getpid(), sig)
            self.w.writerows(rows[1:])

    monkeypatch.setattr("pfaff.results.trajectory.csv.writer", HalfWriter)
    assert main(["run", EXAMPLE, "--t-end", "0.2", "--output", str(out)]) == code
    assert capsys.readouterr().err.strip().splitlines()[-1] == f"pfaff: {word}"
    assert out.read_text() == "the old results\n"
    assert [p.name for p in tmp_path.iterdir()] == ["run.csv"]  # no temporary file


def _read_until(
    proc: subprocess.Popen, marker: bytes | Callable[[bytes], bool], limit: float = 600.0
) -> bytes:
    """stderr of ``proc`` up to ``marker`` (bytes to find, or a test of all read so far; read in
    a thread; waits for the marker, not a time)."""
    seen = bytearray()
    found = threading.Event()
    test = marker if callable(marker) else lambda text: marker in text

    def pump() -> None:
        while chunk := os.read(proc.stderr.fileno(), 4096):
            seen.extend(chunk)
            if test(bytes(seen)):
                found.set()

    threading.Thread(target=pump, daemon=True).start()
    deadline = time.monotonic() + limit  # only a guard against a hung test, never the signal
    while not found.wait(1.0):
        assert proc.poll() is None and time.monotonic() < deadline, bytes(seen)[-2000:]
    return bytes(seen)


def _bar_past(t: float) -> Callable[[bytes], bool]:
    """Whether the progress bar (``simulating: ... t=186.6/1e+07``), printed from inside the
    stepping loop, has shown a time past ``t``."""

    def past(text: bytes) -> bool:
        shown = re.findall(rb"simulating:[^\r\n]*? t=([0-9.e+-]+)/", text)
        return bool(shown) and float(shown[-1]) > t

    return past


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_subprocess_run_interrupted_mid_simulation_writes_its_points(tmp_path, sig) -> None:
    """``pfaff run`` over (0, 1e7) is told to stop once its progress bar shows it stepping:
    status interrupted, exit 3, the points so far in the output file."""
    out = tmp_path / "long.csv"
    env = {**os.environ, "PFAFF_VERBOSE": "1", "PYTHONPATH": str(Path(pfaff.__file__).parents[1])}
    proc = subprocess.Popen(
        [sys.executable, "-m", "pfaff.cli", "run", EXAMPLE, "--t-end", "1e7", "--samples",
         "100001", "--output", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
    )  # fmt: skip
    _read_until(proc, _bar_past(200.0))  # two samples (t = 0, 100) recorded, whatever the load
    proc.send_signal(sig)
    stdout, _ = proc.communicate(timeout=600)
    assert proc.returncode == 3
    assert b"interrupted" in stdout
    rows = list(csv.reader(out.open()))
    times = [float(r[0]) for r in rows[1:]]
    assert len(times) >= 2 and times[0] == 0.0 and times[-1] < 1e7
    assert [p.name for p in tmp_path.iterdir()] == ["long.csv"]


@pytest.mark.parametrize(
    "sig", [pytest.param(signal.SIGINT, marks=pytest.mark.slow), signal.SIGTERM]
)
def test_a_sweep_interrupted_writes_the_runs_it_has(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path, sig
) -> None:
    """The signal arrives as the second of four runs starts: the first is kept (a success), the
    others are marked; the file is written and the exit is 3."""
    import xarray as xr

    from pfaff.sweep import worker

    calls = {"n": 0}
    real = worker.simulate

    def second_signals(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 2:
            os.kill(os.getpid(), sig)
        return real(*args, **kwargs)

    monkeypatch.setattr(worker, "simulate", second_signals)
    out = tmp_path / "sweep.nc"
    argv = ["sweep", EXAMPLE, "--vary", "g=9:10:4", "--scheduler", "synchronous", "--samples",
            "5", "--t-end", "1", "--output", str(out)]  # fmt: skip
    assert main(argv) == 3
    assert "pfaff: interrupted" in capsys.readouterr().err
    ds = xr.open_dataset(out)
    assert ds.attrs["status"] == "interrupted"
    assert list(ds["status"].values) == ["success", "interrupted", "interrupted", "interrupted"]
    assert np.isfinite(ds["q"].values[0]).all() and np.isnan(ds["q"].values[2:]).all()
