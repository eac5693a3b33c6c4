"""Argument types of the ``pfaff`` commands: a bad value is a usage error naming it."""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable, Sequence

from pfaff.core.errors import OptionError


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


def not_an_input(args: argparse.Namespace, flags: Sequence[str]) -> None:
    """Refuse an output that is one of the command's input files (the model file, the data),
    by name or through a link: writing it would replace the input."""
    inputs = {
        os.path.realpath(path): name
        for name in ("model", "data")
        if isinstance(path := getattr(args, name, None), str)
    }
    for flag in flags:
        name = inputs.get(os.path.realpath(getattr(args, flag)))
        if name is not None:
            raise OptionError(
                f"--{flag} {getattr(args, flag)!r} is the {name} file this command reads: "
                "writing it would replace it; give the output its own name"
            )
