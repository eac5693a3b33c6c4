"""One interrupt path for every command and stage: Ctrl-C and SIGTERM end it the same way.

From the start of :func:`pfaff.cli.main.main` (``import pfaff`` loads no stage: the stages
import inside it) to its end, SIGINT raises ``KeyboardInterrupt`` and SIGTERM raises
:class:`Terminated`, a ``KeyboardInterrupt`` too (the handlers are put back if something replaced
them), so that whatever stage is running unwinds as it does for Ctrl-C: a simulation returns what it has
(status "interrupted"; the command writes it and exits 3), a write in progress removes its
temporary file and leaves the old one (:mod:`pfaff.core.files`), anything else ends with one line,
``pfaff: interrupted`` (exit 130) or ``pfaff: terminated`` (exit 143, 128 + SIGTERM), also when
a library turned the interrupt into an error of its own (NumPy importing its C extension).

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


_RECEIVED: list[int] = []  # the signals the handlers below raised on, since `interrupts` began


@contextlib.contextmanager
def interrupts() -> Iterator[None]:
    """SIGINT and SIGTERM raise while the block runs; the previous handlers come back after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before[0])
        signal.signal(signal.SIGTERM, before[1])


def forget() -> None:
    """Start a command afresh: the signals of a command run before in this process are its own."""
    _RECEIVED.clear()


def swallowed(code: int) -> tuple[str, int] | None:
    """The one line and exit code of an interrupt that a library swallowed, when a command
    that received SIGINT or SIGTERM still ended with ``code`` 0; else None.

    Python raises the handler's ``KeyboardInterrupt`` wherever the main thread is, and inside
    a finalizer or a C extension's callback it is printed and dropped ("Exception ignored"):
    the signal was received, so the command ends as interrupted all the same.

    Examples
    --------
    >>> forget()
    >>> swallowed(0) is None
    True
    """
    return _last_received() if code == 0 else None


def _last_received() -> tuple[str, int] | None:
    """The one line and exit code of the last signal the handlers raised on, or None."""
    if not _RECEIVED:
        return None
    return interrupted(Terminated() if _RECEIVED[-1] == signal.SIGTERM else KeyboardInterrupt())


def _interrupt(signum: int, frame: FrameType | None) -> None:
    _RECEIVED.append(signum)
    raise KeyboardInterrupt


def _terminate(signum: int, frame: FrameType | None) -> None:
    _RECEIVED.append(signum)
    raise Terminated


def signalled(e: BaseException) -> tuple[str, int] | None:
    """The one line and exit code when ``e`` ends a command because of a signal: an interrupt,
    or another error raised while one unwound (NumPy, importing its C extension, turns a
    KeyboardInterrupt into an ImportError); None for any other error.

    Examples
    --------
    >>> signalled(Terminated()), signalled(ValueError("not a signal")) is None
    (('terminated', 143), True)
    """
    if isinstance(e, KeyboardInterrupt):
        return interrupted(e)
    return _last_received()


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
        sys.stderr.write(f"pfaff: {name}\n")  # one write: an interrupt cannot split the line
        sys.stderr.flush()
