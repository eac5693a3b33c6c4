"""Where a warning should point: the first caller outside pfaff."""

from __future__ import annotations

import os
import sys

PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def outside_pfaff() -> int:
    """The ``stacklevel`` of the first caller outside pfaff, for a ``warnings.warn`` made in
    the function that calls this (however many pfaff frames, decorators included, lie between).

    Examples
    --------
    >>> import warnings
    >>> def f():
    ...     warnings.warn("here", stacklevel=outside_pfaff())
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     f()
    >>> w[0].filename == f.__code__.co_filename
    True
    """
    frame, level = sys._getframe(1), 1
    while frame is not None and frame.f_code.co_filename.startswith(PACKAGE):
        frame, level = frame.f_back, level + 1
    return level
