"""Ctrl-C in a run of the Python API: status "interrupted" with the points so far, wherever the
signal lands, even between two of a recorded state's parts."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import pfaff
from pfaff.integrate.integrators import ProjectedRK

PEND = {"m": 1.0, "g": 9.81, "L": 1.0}


class _Interrupting:
    """A state whose conversion to an array is where Ctrl-C lands."""

    def __init__(self, q: np.ndarray) -> None:
        self.q = q

    def __array__(self, *args: object, **kwargs: object) -> np.ndarray:
        raise KeyboardInterrupt


class _InterruptedWhileRecording(ProjectedRK):
    """Ctrl-C after the time of the third step's state is recorded and before its q is."""

    name = "interrupted-while-recording"

    def __init__(self, *args: object) -> None:
        super().__init__(*args)
        self.steps = 0

    def step(self) -> None:
        super().step()
        self.steps += 1

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        q, qd = super().state()
        if self.steps == 3:
            self.steps += 1  # once
            return _Interrupting(q), qd  # type: ignore[return-value]
        return q, qd


def test_an_interrupt_inside_a_record_keeps_the_states_whole() -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile(PEND)
    tr = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0, 10), method=_InterruptedWhileRecording)
    assert tr.status == "interrupted"
    assert len(tr.t) == len(tr.q) == len(tr.qd) == len(tr.nc_work) == 3  # t0 and two steps
    np.testing.assert_allclose(np.hypot(tr.q[:, 0], tr.q[:, 1]), 1.0, atol=1e-12)


LONG_RUN = textwrap.dedent(
    """
    import json
    import pfaff
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0, 0.01))  # the stepping loop loaded: a
    print("simulating", flush=True)  # Ctrl-C while it loads ends the run at its first point
    tr = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0, 1e7))
    print(json.dumps({"status": tr.status, "t": tr.t.tolist(), "r": (tr.q ** 2).sum(1).tolist()}))
    """
)


def _default_sigint() -> None:
    """In the child, SIGINT as a terminal gives it: pytest-xdist's workers ignore SIGINT, a
    child inherits that, and Python then installs no KeyboardInterrupt handler (the run would go
    on, signalled or not)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.slow  # (three seconds of stepping, by design)
def test_the_long_pendulum_run_sent_sigint_after_3_s_returns_its_points() -> None:
    """pfaff.simulate over (0, 1e7) in a subprocess, SIGINT 3 s into the run: the call returns a
    trajectory with status "interrupted" and the points so far, on the rod."""
    env = {**os.environ, "PYTHONPATH": str(Path(pfaff.__file__).parents[1])}
    proc = subprocess.Popen(
        [sys.executable, "-c", LONG_RUN], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        env=env, text=True, preexec_fn=_default_sigint,
    )  # fmt: skip
    assert proc.stdout.readline().strip() == "simulating"  # imported and compiled
    time.sleep(3.0)  # (what is tested is what 3 s into the run gives, not a duration)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=600)
    assert proc.returncode == 0 and "Traceback" not in err, err[-2000:]
    got = json.loads(out)
    assert got["status"] == "interrupted"
    t = np.array(got["t"])
    assert len(t) > 10 and t[0] == 0 and 0 < t[-1] < 1e7 and (np.diff(t) > 0).all()
    np.testing.assert_allclose(got["r"], 1.0, atol=1e-9)
