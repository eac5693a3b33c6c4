"""The grid of a sweep: what may be varied, its values, and the ``NAME=START:STOP:COUNT`` syntax.

A varied name is a parameter of the model file (``L``), an initial coordinate ``q0.<coordinate>``
or an initial speed ``qd0.<coordinate>``. The grid is the outer product of the values, one axis
per name in the order given; run ``i`` is the grid point ``numpy.unravel_index(i, shape)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pfaff.core.errors import OptionError

RESERVED = ("time", "coordinate", "multiplier", "constraint")  # dimensions of the result
MAX_COUNT = 1_000_000  # values of one --vary axis (a grid of more runs is refused later, by memory)


@dataclass(frozen=True)
class Grid:
    """Varied names and their values: the outer product of the axes.

    Attributes
    ----------
    names : tuple of str
        The varied names, in the order of the result's dimensions.
    axes : tuple of ndarray
        The values of each name, shape (k_i,).

    Examples
    --------
    >>> g = Grid(("L", "q0.theta"), (np.array([1.0, 2.0]), np.array([0.1, 0.2, 0.3])))
    >>> g.shape, g.size, g.point(4)
    ((2, 3), 6, {'L': 2.0, 'q0.theta': 0.2})
    """

    names: tuple[str, ...]
    axes: tuple[np.ndarray, ...]

    @property
    def shape(self) -> tuple[int, ...]:
        """The number of values of each name."""
        return tuple(len(a) for a in self.axes)

    @property
    def size(self) -> int:
        """The number of runs."""
        return math.prod(self.shape)

    def point(self, i: int) -> dict[str, float]:
        """The values of run ``i`` (C order: the last name varies fastest)."""
        idx = np.unravel_index(i, self.shape)
        return {n: float(a[j]) for n, a, j in zip(self.names, self.axes, idx, strict=True)}


def make_grid(
    vary: Mapping[str, Sequence[float] | np.ndarray],
    parameters: Sequence[str],
    coordinates: Sequence[str],
) -> Grid:
    """Check ``vary`` against a model's names and make the :class:`Grid`.

    Parameters
    ----------
    vary : mapping of str to array_like
        Name -> its values (one-dimensional, finite, at least one).
    parameters : sequence of str
        The model's parameters.
    coordinates : sequence of str
        Its coordinates (for ``q0.<name>`` and ``qd0.<name>``).

    Raises
    ------
    OptionError
        Naming every bad name or value.

    Examples
    --------
    >>> make_grid({"L": [1, 2]}, ["L", "g"], ["theta"]).axes
    (array([1., 2.]),)
    >>> make_grid({"q0.phi": [1]}, ["L"], ["theta"])
    Traceback (most recent call last):
    ...
    pfaff.core.errors.OptionError: bad `vary`: `q0.phi` is not q0.<coordinate> (the model's coordinates: theta)
    """
    if not isinstance(vary, Mapping) or not vary:
        raise OptionError(f"`vary` must be a non-empty dict of name -> values, got {vary!r:.80}")
    problems, axes = [], []
    for name, values in vary.items():
        problem = _check_name(name, parameters, coordinates)
        if problem is None:
            axis, problem = _check_values(name, values)
            axes.append(axis)
        if problem is not None:
            problems.append(problem)
    if problems:
        raise OptionError("bad `vary`: " + "; ".join(problems))
    return Grid(tuple(vary), tuple(axes))


def _check_name(name: object, parameters: Sequence[str], coordinates: Sequence[str]) -> str | None:
    if not isinstance(name, str):
        return f"names must be strings, got {name!r:.40}"
    if name in RESERVED:
        return f"`{name}` is a dimension of the result; it cannot be varied"
    kind, dot, rest = name.partition(".")
    if dot and kind in ("q0", "qd0"):
        if rest in coordinates:
            return None
        return (
            f"`{name}` is not {kind}.<coordinate> (the model's coordinates: "
            f"{_listing(coordinates)})"
        )
    if name in parameters:
        return None
    return (
        f"`{name}` is neither a parameter ({_listing(parameters)}) nor q0.<coordinate> or "
        "qd0.<coordinate>"
    )


def _check_values(name: str, values: object) -> tuple[np.ndarray, str | None]:
    bad = f"the values of `{name}` must be a number or a one-dimensional sequence of numbers"
    if isinstance(values, str | bytes | Mapping):
        return np.empty(0), bad
    try:
        axis = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        return np.empty(0), bad
    if axis.ndim > 1:
        return axis, bad
    axis = axis.reshape(-1)
    if axis.size == 0:
        return axis, f"`{name}` has no values"
    if not np.isfinite(axis).all():
        return axis, f"the values of `{name}` must be finite"
    return axis, None


def _listing(names: Sequence[str]) -> str:
    shown = ", ".join(names[:12])
    return (shown + (f" and {len(names) - 12} more" if len(names) > 12 else "")) or "none"


def parse_vary(text: str) -> tuple[str, np.ndarray]:
    """``NAME=START:STOP:COUNT`` -> (NAME, ``numpy.linspace(START, STOP, COUNT)``): STOP included.

    Raises
    ------
    OptionError
        Saying what is wrong with ``text``.

    Examples
    --------
    >>> name, values = parse_vary("q0.theta1=0:1:5")
    >>> name, values.tolist()
    ('q0.theta1', [0.0, 0.25, 0.5, 0.75, 1.0])
    >>> parse_vary("L=1:2")
    Traceback (most recent call last):
    ...
    pfaff.core.errors.OptionError: bad --vary 'L=1:2': expected NAME=START:STOP:COUNT (e.g. L=0.5:2:16)
    """
    usage = f"bad --vary {text!r:.80}: expected NAME=START:STOP:COUNT (e.g. L=0.5:2:16)"
    name, eq, spec = text.partition("=")
    parts = spec.split(":")
    name = name.strip()
    if not eq or not name or len(parts) != 3:
        raise OptionError(usage)
    try:
        start, stop = float(parts[0]), float(parts[1])
    except ValueError:
        raise OptionError(f"{usage}; START and STOP must be numbers") from None
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise OptionError(f"{usage}; START and STOP must be finite")
    try:
        count = int(parts[2])
    except ValueError:
        count = 0
    if not 1 <= count <= MAX_COUNT:
        raise OptionError(f"{usage}; COUNT must be a whole number from 1 to {MAX_COUNT}")
    return name, np.linspace(start, stop, count)
