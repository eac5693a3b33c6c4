"""Argument types of the ``pfaff`` commands: a bad value is a usage error naming it."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable


def finite(s: str) -> float:
    """A finite number.

    Examples
    --------
    >>> finite("2.5")
    2.5
    """
    try:
        v = float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {s!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {s!r}")
    return v


def positive(s: str) -> float:
    """A finite number above 0."""
    try:
        v = float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {s!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"expected a positive finite number, got {s!r}")
    return v


def whole(
    least: int, too_small: str = "expected at least {least}, got {v}"
) -> Callable[[str], int]:
    """A whole number of at least ``least``; ``too_small`` is the message otherwise.

    Examples
    --------
    >>> whole(2)("3")
    3
    """

    def parse(s: str) -> int:
        try:
            v = int(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {s!r}") from None
        if v < least:
            raise argparse.ArgumentTypeError(too_small.format(least=least, v=v))
        return v

    return parse
