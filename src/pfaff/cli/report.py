"""How every ``pfaff`` command ends on an error: one line on stderr and an exit code.

0 success, 1 an unexpected error (``--debug`` shows the traceback), 2 a usage, model, value or file
error, 130 interrupted (Ctrl-C), 143 terminated (SIGTERM); a command returns 3 itself for a
simulation that failed or was interrupted (:mod:`pfaff.cli.signals`).
"""

from __future__ import annotations

import sys
import traceback
from collections.abc import Callable

from pfaff.cli.signals import interrupted, interrupts, signalled
from pfaff.core.errors import PfaffError, raised_in_generated_code


def one_line(text: str) -> str:
    """``text`` with its lines joined by spaces.

    Examples
    --------
    >>> one_line("a\\n  b\\n")
    'a b'
    """
    return " ".join(part.strip() for part in str(text).splitlines() if part.strip())


def describe(e: BaseException) -> str:
    """``Type: message`` of an exception, without an errno tuple: one line."""
    args = e.args
    if len(args) == 2 and isinstance(args[0], int) and isinstance(args[1], str):
        msg = args[1]  # OverflowError(34, 'Numerical result out of range') from math
    else:
        msg = str(e)
    return one_line(f"{type(e).__name__}: {msg}" if msg else type(e).__name__)


def fail(message: str, code: int, debug: bool) -> int:
    """Print ``pfaff: message`` (after the traceback with ``debug``) and return ``code``."""
    if debug:
        traceback.print_exc()
    sys.stderr.write(f"pfaff: {message}\n")  # one write: a second signal cannot split it
    return code


def unexpected(e: BaseException) -> str:
    return f"unexpected error: {describe(e)} (rerun with --debug for the traceback)"


def guarded(action: Callable[[], int], debug: bool) -> int:
    """``action()``'s exit code, or the exit code of the error it raised (see the module)."""
    try:
        with interrupts():
            return action()
    except KeyboardInterrupt as e:  # Ctrl-C or SIGTERM, at any stage (pfaff.cli.signals)
        return fail(*interrupted(e), debug)
    except Exception as e:
        return fail(*outcome(e), debug)


def outcome(e: Exception) -> tuple[str, int]:
    """The one line and exit code of an error that ended a command (see the module).

    Examples
    --------
    >>> outcome(FileNotFoundError("no such file: run.toml"))
    ('error: no such file: run.toml', 2)
    """
    if (stopped := signalled(e)) is not None:  # an interrupt another library turned into its own
        return stopped
    if isinstance(e, PfaffError | OSError):
        return f"error: {one_line(str(e))}", 2
    if isinstance(e, ValueError | ArithmeticError) and raised_in_generated_code(e):
        # overflow, domain error or division by zero in the model's equations at these values
        return f"error: the equations cannot be evaluated with these values ({describe(e)})", 2
    return unexpected(e), 1
