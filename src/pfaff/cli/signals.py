"""One interrupt path for every command and stage: Ctrl-C and SIGTERM end it the same way.

While a command runs, SIGINT raises ``KeyboardInterrupt`` (Python's own handler, put back if
something replaced it) and SIGTERM raises :class:`Terminated`, a ``KeyboardInterrupt`` too, so
that whatever stage is running unwinds as it does for Ctrl-C: a simulation returns what it has
(status "interrupted"; the command writes it and exits 3), a write in progress removes its
temporary file and leaves the old one (:mod:`pfaff.core.files`), anything else ends with one line,
``pfaff: interrupted`` (exit 130) or ``pfaff: terminated`` (exit 143, 128 + SIGTERM).

``PFAFF_VERBOSE=1`` prints each stage on stderr as it starts (``pfaff: deriving``...), and the
progress bar of a simulation.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from types import FrameType


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the process is, and handled as Ctrl-C is."""


@contextlib.contextmanager
def interrupts() -> Iterator[None]:
    """SIGINT and SIGTERM raise while the block runs; the previous handlers come back after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before[0])
        signal.signal(signal.SIGTERM, before[1])


def _terminate(signum: int, frame: FrameType | None) -> None:
    raise Terminated


def interrupted(e: KeyboardInterrupt) -> tuple[str, int]:
    """The one line and the exit code of an interrupted command.

    Examples
    --------
    >>> interrupted(KeyboardInterrupt()), interrupted(Terminated())
    (('interrupted', 130), ('terminated', 143))
    """
    if isinstance(e, Terminated):
        return "terminated", 128 + signal.SIGTERM
    return "interrupted", 128 + signal.SIGINT


def verbose() -> bool:
    """Whether ``PFAFF_VERBOSE`` asks for the stages on stderr."""
    return os.environ.get("PFAFF_VERBOSE", "").strip().lower() not in ("", "0", "false", "no")


def stage(name: str) -> None:
    """Announce a stage on stderr (with ``PFAFF_VERBOSE``)."""
    if verbose():
        print(f"pfaff: {name}", file=sys.stderr, flush=True)
