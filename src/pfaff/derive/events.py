"""The compile stage of ``System.add_event``: a declared condition as a numeric g(t, q, q̇).

:func:`compile_events` turns each :class:`pfaff.mechanics.events.EventSpec` of a system into a
:class:`CompiledEvent`, the form :func:`pfaff.simulate` reads from ``model.events``. The
condition is kept as a SymPy expression in plain symbols (``_q0 …``, ``_qd0 …`` for the
coordinates it reads, t, the parameters); its code (``lambdify``) is made on first use, takes the
parameter values as arguments (so :meth:`CompiledEvent.with_parameters` shares it) and is not
pickled: a pickled model carries the expression and makes the code again.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import sympy as sp

from pfaff.core.errors import ModelError
from pfaff.core.symbols import local_q, local_qd, speed, t

if TYPE_CHECKING:
    from pfaff.derive.equations import Derivation


class CompiledEvent:
    """An event of a compiled model: ``name, direction, terminal`` and ``fn(t, q, qd) -> float``.

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.pendulum()
    >>> s.add_event(s.coordinates[0] - sp.Symbol("L") / 10, name="past")
    >>> model = s.equations().compile({"m": 1, "g": 9.81, "L": 2})
    >>> ev = model.events[0]
    >>> ev.name, ev.fn(0.0, np.array([0.5]), np.zeros(1))
    ('past', 0.3)
    >>> model.with_parameters({"L": 1}).events[0].fn(0.0, np.array([0.5]), np.zeros(1))
    0.4
    """

    def __init__(
        self,
        name: str,
        direction: int,
        terminal: int,
        expr: sp.Expr,
        cols: tuple[int, ...],
        params: tuple[str, ...],
        values: tuple[float, ...],
    ) -> None:
        self.name, self.direction, self.terminal = name, direction, terminal
        self.expr, self.cols, self.params, self.values = expr, cols, params, values
        self._idx = np.array(cols, dtype=np.int64)
        self._code: Callable | None = None

    def _lambdified(self) -> Callable:
        if self._code is None:
            k = len(self.cols)
            args = [t, *map(local_q, range(k)), *map(local_qd, range(k))]
            args += [sp.Symbol(p) for p in self.params]
            self._code = sp.lambdify(args, self.expr, modules="numpy", cse=True)
        return self._code

    def fn(self, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """g(t, q, q̇) of the condition with the model's parameter values."""
        idx = self._idx
        return float(self._lambdified()(t, *q[idx], *qd[idx], *self.values))

    def with_parameters(self, parameters: Mapping[str, float]) -> CompiledEvent:
        """This event with other parameter values (the same code)."""
        new = CompiledEvent(
            self.name, self.direction, self.terminal, self.expr, self.cols, self.params,
            tuple(float(parameters[p]) for p in self.params),
        )  # fmt: skip
        new._code = self._code
        return new

    def __getstate__(self) -> dict[str, Any]:
        return {k: v for k, v in self.__dict__.items() if k != "_code"}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state, _code=None)

    def __repr__(self) -> str:
        return f"CompiledEvent({self.name!r}: {self.expr}, direction={self.direction})"


def compile_events(
    eom: Derivation, params: Sequence[sp.Symbol], values: Sequence[float]
) -> tuple[CompiledEvent, ...]:
    """The events declared on ``eom``'s system, compiled with the parameter ``values``."""
    system = getattr(eom, "system", None)
    specs = getattr(system, "events", ())
    if not specs:
        return ()
    coords = list(eom.coordinates)
    value_of = {p.name: float(v) for p, v in zip(params, values, strict=True)}
    out = []
    for spec in specs:
        qs = [coords[j] for j in spec.coords]
        sub = {speed(q): local_qd(a) for a, q in enumerate(qs)}
        expr = spec.condition.xreplace(sub).xreplace({q: local_q(a) for a, q in enumerate(qs)})
        local = {t, *sub.values(), *map(local_q, range(len(qs)))}
        names = sorted(s.name for s in expr.free_symbols - local)
        unknown = [p for p in names if p not in value_of]
        if unknown:
            raise ModelError(
                f"event `{spec.name}`: `condition` names {', '.join(unknown)}, which the compiled "
                f"model has no value for (its parameters: {', '.join(value_of) or 'none'})"
            )
        pv = tuple(value_of[p] for p in names)
        out.append(
            CompiledEvent(
                spec.name, spec.direction, spec.terminal, expr, spec.coords, tuple(names), pv
            )
        )
    return tuple(out)
