"""The pace of a run: the stall test, the step limit and the memory estimate of :func:`pfaff.simulate`.

A run is judged against its own history and scale, never against the length of its span (a
smooth run over a long span takes steady steps and proceeds until it ends or is interrupted):

- *a step-size collapse*: over the last ``WINDOW`` steps the mean step is below ``COLLAPSE``
  times the largest step the run has taken (chattering at a discontinuity such as Coulomb
  friction's sign(q̇) about q̇ = 0 shrinks steps by ten orders of magnitude);
- *no progress*: the mean step is below ``ULPS`` units in the last place of t (time no longer
  advances in floating point);
- ``max_steps`` (an option, default unlimited);
- ``max_seconds`` (an option, default unlimited): the run's wall-clock time from its first step
  (a sweep's per-run time limit); it fails with the verb "timed out";
- a run that records every step (no ``t_eval``) and whose states would fill more than
  :func:`memory_limit` at its measured pace warns once (:class:`pfaff.LongRunWarning`), with the
  estimate.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from pfaff.core.errors import LongRunWarning
from pfaff.core.memory import available_bytes
from pfaff.core.stack import outside_pfaff
from pfaff.integrate.stepper import _RunFailure

WINDOW = 200  # steps over which the pace is measured
COLLAPSE = 1e-7  # a mean step below this fraction of the run's largest step is a collapse
ULPS = 4096.0  # a mean step of fewer ulps of t does not advance time
EPS = float(np.finfo(float).eps)
WARN_BYTES = 1 << 30  # warn about recorded states beyond this (or half the available memory)


def state_bytes(n: int, m: int) -> int:
    """Bytes one recorded state costs (its arrays while running, then the trajectory's rows)."""
    recorded = 2 * (112 + 8 * n) + 2 * 32  # q, q̇ as arrays; t and the work as floats
    trajectory = 8 * (5 * n + 3 * m + 6)  # t, q, q̇, q̈, λ, residuals, energies, work
    return recorded + trajectory


def memory_limit() -> int:
    """Bytes of recorded states beyond which a run warns: 1 GiB or half the available memory."""
    return min(WARN_BYTES, available_bytes() // 2)


class Pace:
    """Watches the steps of one run; :meth:`step` raises the run's failure when it must stop.

    Parameters
    ----------
    t1 : float
        End of the span (only for the memory estimate of the remaining steps).
    max_steps : int or None
        Fail after this many steps; None: no limit.
    state_bytes : int or None
        Bytes per recorded step when every step is recorded (no ``t_eval``); None: the run's
        memory is bounded, nothing to estimate.
    max_seconds : float or None
        Fail (:class:`TimeLimit`) once this many seconds of wall-clock time have passed since
        the first step; None: no limit.

    Examples
    --------
    A steady run never stalls, however long its span; a collapse of the steps does:

    >>> p = Pace(t1=1e9, max_steps=None, state_bytes=None)
    >>> for k in range(2000):
    ...     p.step(0.05 * k, 0.05 * (k + 1))
    >>> try:
    ...     for k in range(WINDOW):
    ...         p.step(100.0 + 1e-9 * k, 100.0 + 1e-9 * (k + 1))
    ... except Exception as e:
    ...     print(str(e)[:19])
    step-size collapse:
    """

    def __init__(
        self,
        t1: float,
        max_steps: int | None,
        state_bytes: int | None,
        max_seconds: float | None = None,
    ) -> None:
        self.t1, self.max_steps, self.state_bytes = t1, max_steps, state_bytes
        self.max_seconds, self._deadline = max_seconds, None if max_seconds is None else 0.0
        self.steps = 0
        self.largest = 0.0  # the largest step so far (the run's history)
        self._count, self._start = 0, 0.0  # steps and start time of the current window
        self._warned = state_bytes is None

    def restart(self) -> None:
        """A new history from here (after an impact: the motion's time scale may change); the
        steps taken still count towards ``max_steps``."""
        self.largest, self._count = 0.0, 0

    def limit(self) -> None:
        """Before a step: fail when ``max_steps`` have been taken or ``max_seconds`` passed."""
        if self._deadline is not None:
            now = time.perf_counter()
            if not self._deadline:  # the first step: the clock starts
                self._deadline = now + float(self.max_seconds)  # type: ignore[arg-type]
            elif now > self._deadline:
                raise TimeLimit(
                    f"the run took longer than max_seconds = {self.max_seconds:g} s of wall-clock "
                    "time (simulate(max_seconds=...), a sweep's run_timeout)", hint=False
                )  # fmt: skip
        if self.max_steps is not None and self.steps >= self.max_steps:
            raise _RunFailure(
                f"reached max_steps = {self.max_steps} (simulate(max_steps=...)) before the end "
                "of the span", hint=False
            )  # fmt: skip

    def step(self, before: float, after: float) -> None:
        """Account for one accepted step from ``before`` to ``after``."""
        self.steps += 1
        if self._count == 0:
            self._start = before
        self._count += 1
        self.largest = max(self.largest, after - before)
        if self._count >= WINDOW:
            self._judge(after)

    @property
    def quiet(self) -> bool:
        """Whether judging a window can only fail (no memory warning is left to give): then a
        compiled loop judges the windows itself (:mod:`pfaff.integrate.loop`)."""
        return self._warned

    def history(self) -> tuple[int, int, float, float]:
        """(steps, steps in the current window, its start, the largest step): what
        :meth:`resume` takes."""
        return self.steps, self._count, self._start, self.largest

    def resume(self, steps: int, count: int, start: float, largest: float, after: float) -> None:
        """Take the history a compiled loop reached by the same rule as :meth:`step` (ending
        at ``after``), and judge the window if it is full (raising the run's failure, or
        warning, as :meth:`step` does).

        Examples
        --------
        >>> p = Pace(t1=10.0, max_steps=None, state_bytes=None)
        >>> p.resume(400, 150, 1.0, 0.01, 1.5)  # 150 steps into a window: not judged yet
        >>> try:  # 200 steps averaging 5e-9 in a run whose largest step was 1
        ...     p.resume(600, 200, 2.0, 1.0, 2.0 + 1e-6)
        ... except Exception as e:
        ...     print(str(e)[:19])
        step-size collapse:
        """
        self.steps, self._count, self._start, self.largest = steps, count, start, largest
        if self._count >= WINDOW:
            self._judge(after)

    def _judge(self, after: float) -> None:
        mean = (after - self._start) / self._count
        self._count = 0
        if mean < COLLAPSE * self.largest:
            raise _RunFailure(
                f"step-size collapse: the last {WINDOW} steps averaged {mean:.3g}, "
                f"{self.largest / mean:.2g} times less than the largest step of the run "
                f"({self.largest:.3g}). {HINT}"
            )
        if mean <= ULPS * EPS * abs(after):
            raise _RunFailure(
                f"time no longer advances: the last {WINDOW} steps averaged {mean:.3g}, "
                f"fewer than {ULPS:.0f} units in the last place of t. {HINT}"
            )
        if not self._warned:
            self._warn(after, mean)

    def _warn(self, after: float, mean: float) -> None:
        """Warn once when the states still to record at this pace would exceed the limit."""
        estimate = (self.t1 - after) / mean * self.state_bytes  # type: ignore[operator]
        if estimate > memory_limit():
            self._warned = True
            warnings.warn(
                f"this run records every step, and at its pace ({mean:.3g} per step) the "
                f"remaining {self.t1 - after:.3g} of its span would need about "
                f"{estimate / 2**30:.3g} GiB of memory: pass t_eval to keep only chosen times",
                LongRunWarning,
                stacklevel=outside_pfaff(),
            )


class TimeLimit(_RunFailure):
    """A run stopped by ``max_seconds``: status "failed", its message starting "timed out"."""

    verb = "timed out"


HINT = (
    "The equations may be discontinuous there (sign() or abs() of a velocity: Coulomb friction "
    "chattering about q̇ = 0; smooth it, e.g. tanh(q̇/ε)), stiff (try method='ida'), or "
    "constrained where no state satisfies every constraint (a rheonomic one driving too far)"
)
