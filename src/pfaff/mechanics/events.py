"""``add_event``: a zero crossing of a condition on the state, declared on the system.

The condition is kept as the SymPy expression the user gave, with the indices of the coordinates
it reads; the compile stage (:mod:`pfaff.derive.events`) turns it into a numeric g(t, q, q̇) with
the model's parameter values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import sympy as sp

from pfaff.core.errors import ModelError, PfaffError
from pfaff.core.events import event_direction, event_terminal
from pfaff.core.keywords import checked_keywords
from pfaff.core.symbols import as_expr

if TYPE_CHECKING:
    from pfaff.mechanics.system import SystemSpec


@dataclass(frozen=True)
class EventSpec:
    """An event as declared: its name, condition (in q(t), q̇(t), t and parameters), the indices
    of the coordinates it reads, its direction and terminal count."""

    name: str
    condition: sp.Expr
    coords: tuple[int, ...]
    direction: int
    terminal: int


class EventsMixin:
    """``add_event`` (a part of SystemSpec)."""

    events: list[EventSpec]

    @checked_keywords
    def add_event(
        self: SystemSpec,
        condition: object,
        name: str | None = None,
        direction: int = 0,
        terminal: bool | int = False,
    ) -> None:
        """Declare an event: a zero crossing of ``condition`` that every simulation of the
        compiled model finds (``model.events``; see :class:`pfaff.Event`).

        Parameters
        ----------
        condition : sympy expression
            In the coordinates, their rates (``q.diff(pfaff.t)``), time and the parameters the
            system already uses (declare the event after the pieces that use them).
        name : str, optional
            Default ``"event1"``, ``"event2"``, ... in the order of declaration.
        direction : {0, 1, -1}
            +1 rising crossings only, -1 falling ones only, 0 both.
        terminal : bool or int
            True: the run stops at the first crossing; an integer k: at the k-th.

        Raises
        ------
        ModelError
            The condition names a symbol that is neither a parameter of the system nor time, a
            function that is not a coordinate, or a higher derivative.
        OptionError
            A bad ``direction``, ``terminal`` or ``name``.

        Examples
        --------
        >>> import pfaff
        >>> s = pfaff.models.pendulum()
        >>> theta = s.coordinates[0]
        >>> s.add_event(theta, name="bottom", direction=1)
        >>> model = s.equations().compile({"m": 1, "g": 9.81, "L": 1})
        >>> [ev.name for ev in model.events]
        ['bottom']
        """
        label = name if name is not None else f"event{len(self.events) + 1}"
        if not isinstance(label, str) or not label:
            raise ModelError(f"`name` of an event must be a non-empty string, got {name!r:.60}")
        if label in {e.name for e in self.events}:
            raise ModelError(f"`name`: there is already an event `{label}`")
        what = f"event `{label}`: `condition`"
        e = as_expr(condition, what)
        known = set(self._parameters)
        try:
            coords = self._scan((e,), what, speeds=True, smooth=False)
        finally:
            unknown = sorted(s.name for s in self._parameters - known)
            self._parameters = known
        inputs = sorted(s.name for s in e.free_symbols & set(self.inputs))
        if unknown or inputs:
            names = ", ".join(f"`{s}`" for s in unknown + inputs)
            raise ModelError(
                f"{what} names {names}, which "
                + ("is an input" if inputs and not unknown else "is not a parameter of the system")
                + " (its parameters: "
                + (", ".join(sorted(p.name for p in known - set(self.inputs))) or "none")
                + "; events read time, the coordinates, their rates and the parameters the "
                "system's pieces already use)"
            )
        if e.is_constant() and not e.free_symbols:
            raise ModelError(f"{what} is the constant {e}: it never crosses zero")
        try:
            d, k = event_direction(direction), event_terminal(terminal)
        except PfaffError as err:
            raise type(err)(f"event `{label}`: {err}") from None
        self.events.append(EventSpec(label, e, tuple(coords), d, k))
