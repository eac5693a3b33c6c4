"""User events: :class:`Event`, a scalar function of the state whose zero crossings a run finds,
and :class:`EventRecord`, one crossing (or a later discrete event) as a trajectory reports it.

A run (:func:`pfaff.simulate`) looks for sign changes of g(t, q, q̇) between accepted steps and
brackets each root on the integrator's dense output (:mod:`pfaff.integrate.events`). Events
declared on a system (``System.add_event``) are compiled with the model and reach the run as
``model.events``: objects with the same four fields ``name, direction, terminal, fn``.
"""

from __future__ import annotations

import numbers
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from pfaff.core.errors import OptionError


def event_direction(direction: object, what: str = "direction") -> int:
    """``direction`` checked: -1 (falling), 0 (both) or +1 (rising)."""
    if isinstance(direction, bool | np.bool_) or direction not in (-1, 0, 1):
        raise OptionError(
            f"`{what}` must be -1 (falling), 0 (both) or +1 (rising); got {direction!r:.60}"
        )
    return int(direction)  # type: ignore[call-overload]


def event_terminal(terminal: object, what: str = "terminal") -> int:
    """``terminal`` as a count of occurrences that stops the run: 0 never, True is 1."""
    if isinstance(terminal, bool | np.bool_):
        return int(terminal)
    if isinstance(terminal, numbers.Integral) and terminal >= 0:
        return int(terminal)
    raise OptionError(
        f"`{what}` must be True, False or a count >= 1 (stop at that occurrence); got "
        f"{terminal!r:.60}"
    )


def event_name(name: object, what: str = "name") -> str | None:
    if name is None or (isinstance(name, str) and name):
        return name
    raise OptionError(f"`{what}` must be a non-empty string or None; got {name!r:.60}")


class Event:
    """A zero crossing of g(t, q, q̇) that :func:`pfaff.simulate` finds and reports.

    Parameters
    ----------
    g : callable
        ``g(t, q, qd) -> float`` with ``q``, ``qd`` of shape (n,).
    name : str, optional
        Its name in :attr:`pfaff.Trajectory.events` (default: ``"event1"``, ``"event2"``, ... by
        position in ``simulate(events=...)``).
    direction : {0, 1, -1}
        As in SciPy: +1 counts only rising crossings (g from negative to non-negative), -1 only
        falling ones, 0 both.
    terminal : bool or int
        True: the run stops at the first crossing; an integer k: at the k-th; False: never.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> down = pfaff.Event(lambda t, q, qd: q[0], name="bottom", direction=1, terminal=True)
    >>> traj = pfaff.simulate(model, [-0.5], [0.0], (0, 5), events=[down])
    >>> traj.status, traj.events[0].name, bool(traj.events[0].t == traj.t[-1])
    ('success', 'bottom', True)
    """

    __slots__ = ("direction", "fn", "name", "terminal")

    def __init__(
        self,
        g: Callable[[float, np.ndarray, np.ndarray], float],
        name: str | None = None,
        direction: int = 0,
        terminal: bool | int = False,
    ) -> None:
        if not callable(g):
            raise OptionError(f"`g` of an Event must be callable g(t, q, qd); got {g!r:.60}")
        self.fn = g
        self.name = event_name(name)
        self.direction = event_direction(direction)
        self.terminal = event_terminal(terminal)

    @property
    def g(self) -> Callable[[float, np.ndarray, np.ndarray], float]:
        """The event function (``fn``)."""
        return self.fn

    def __repr__(self) -> str:
        return (
            f"Event({self.name or getattr(self.fn, '__name__', 'g')!s}, "
            f"direction={self.direction}, terminal={self.terminal})"
        )

    def __getstate__(self) -> dict:
        return {k: getattr(self, k) for k in self.__slots__}

    def __setstate__(self, state: dict) -> None:
        for k, v in state.items():
            object.__setattr__(self, k, v)


class EventRecord(NamedTuple):
    """One event of a run, in :attr:`pfaff.Trajectory.events`.

    Attributes
    ----------
    name : str
    t : float
    q, qd : ndarray, shape (n,)
        The state at the event (also a reported state of the trajectory).
    kind : str
        ``"event"`` for a zero crossing of a user event.
    """

    name: str
    t: float
    q: np.ndarray
    qd: np.ndarray
    kind: str = "event"
