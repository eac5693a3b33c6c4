"""The compile stage of ``System.add_unilateral_constraint``: the models a contact run switches.

A run of a system with k unilateral constraints steps, between events, the model in which the
closed contacts are holonomic rows appended after the bilateral ones (in the order of
declaration) and the open ones are absent. :class:`CompiledContacts` (a compiled model's
``contacts``) makes each such *variant* on first use, from the system with those rows added, with
the model's parameter values and compile options, and keeps it: ``variant(mask)`` for a tuple of
k booleans. The gaps themselves, their gradients a = ∂g/∂q and ∂g/∂t (what events and impacts
read, :mod:`pfaff.integrate.contact`) are one lambdified function, :meth:`CompiledContacts.gaps`
(no model of all contacts closed: a joint's lower and upper stops would contradict each other).

Variants and code are not pickled: a pickled model carries the system and makes them again.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import sympy as sp

from pfaff.core.errors import ModelError, ParameterError
from pfaff.core.symbols import local_q, t
from pfaff.derive.compile import build_model, input_names, model_parameter_values
from pfaff.derive.templates import derive

if TYPE_CHECKING:
    from pfaff.derive.equations import Derivation
    from pfaff.mechanics.system import SystemSpec
    from pfaff.numeric.model import NumericModel


class CompiledContacts:
    """The unilateral constraints of a compiled model.

    Attributes
    ----------
    names : tuple of str
        The contacts, in order of declaration (their multiplier columns follow the bilateral
        ones in a run's :attr:`pfaff.Trajectory.multipliers`).
    restitution : tuple of float
        Newton's coefficient of each, with the model's parameter values.

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.bouncing_ball()
    >>> model = s.equations().compile({"m": 1, "g": 9.81})
    >>> model.contacts.names, model.contacts.restitution
    (('floor',), (0.8,))
    >>> model.contacts.variant((True,)).constraint_names
    ['floor']
    >>> g, A, b = model.contacts.gaps(0.0, np.array([0.0, 0.5]))
    >>> g.tolist(), A.tolist(), b.tolist()
    ([0.5], [[0.0, 1.0]], [0.0])
    """

    def __init__(
        self,
        system: SystemSpec,
        parameters: Mapping[str, float],
        solver: str | None,
        evaluator: str | None,
    ) -> None:
        self.system, self.parameters = system, dict(parameters)
        self.solver, self.evaluator = solver, evaluator
        self.names = tuple(c.name for c in system.contacts)
        self.restitution = tuple(
            _restitution(c.name, c.restitution, self.parameters) for c in system.contacts
        )
        self._variants: dict[tuple[bool, ...], NumericModel] = {}
        # the variants of the model these contacts were made from by with_parameters: each
        # one's with_parameters (new kernels only where a value changed) is cheaper than a
        # derivation
        self._origin: dict[tuple[bool, ...], NumericModel] = {}
        self._code: Callable | None = None
        self._rows: list[tuple[int, int]] = []

    def gaps(self, t: float, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The gaps g (k,), their gradients A = ∂g/∂q (k, n) and b = ∂g/∂t (k,) at (t, q): the
        rates are ġ = A q̇ + b."""
        if self._code is None:
            self._code = self._lambdified()
        g, entries, b = self._code(t, *q)
        A = np.zeros((len(self.names), len(q)))
        for (j, i), v in zip(self._rows, entries, strict=True):
            A[j, i] = v
        return np.array(g, dtype=float), A, np.array(b, dtype=float)

    def _lambdified(self) -> Callable:
        coords = list(self.system.coordinates)
        qs = [local_q(i) for i in range(len(coords))]
        rule = dict(zip(coords, qs, strict=True))
        values = {sp.Symbol(k): sp.Float(v) for k, v in self.parameters.items()}
        exprs = [c.gap.xreplace(rule).xreplace(values) for c in self.system.contacts]
        index = {s: i for i, s in enumerate(qs)}
        self._rows, entries = [], []
        for j, g in enumerate(exprs):
            for i in sorted(index[s] for s in g.free_symbols if s in index):
                self._rows.append((j, i))
                entries.append(g.diff(qs[i]))
        rates = [g.diff(t) for g in exprs]
        return sp.lambdify([t, *qs], [exprs, entries, rates], modules="math", cse=True)

    def __len__(self) -> int:
        return len(self.names)

    def variant(self, mask: Sequence[bool]) -> NumericModel:
        """The model with the contacts where ``mask`` is True as holonomic rows (made once)."""
        key = tuple(bool(x) for x in mask)
        model = self._variants.get(key)
        if model is None:
            old = self._origin.get(key)
            made = self._compile(key) if old is None else old.with_parameters(self.parameters)
            model = self._variants[key] = made
        return model

    def _compile(self, mask: tuple[bool, ...]) -> NumericModel:
        closed = closed_system(self.system, mask)
        eom: Derivation = derive(closed)
        inputs = input_names(eom)
        given = {**{i: 0.0 for i in inputs}, **self.parameters}
        values = model_parameter_values(eom, given)
        model = build_model(
            eom, values, solver=self.solver, evaluator=self.evaluator, inputs=inputs
        )
        closed_names = [c.name for c, on in zip(self.system.contacts, mask, strict=True) if on]
        rows = list(model.constraint_names)
        if rows[len(rows) - len(closed_names) :] != closed_names:  # a run maps columns so
            raise ModelError(
                f"the closed contacts' rows are not the last ones ({rows}): a bug of pfaff"
            )
        return model

    def with_parameters(self, parameters: Mapping[str, float]) -> CompiledContacts:
        """The same contacts with other parameter values (the variants made so far are
        carried over by their own ``with_parameters`` when first used)."""
        new = CompiledContacts(self.system, parameters, self.solver, self.evaluator)
        new._origin = {**self._origin, **self._variants}
        return new

    def __getstate__(self) -> dict[str, Any]:
        skip = ("_variants", "_origin", "_code")
        return {k: v for k, v in self.__dict__.items() if k not in skip}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state, _variants={}, _origin={}, _code=None)

    def __repr__(self) -> str:
        return f"CompiledContacts({', '.join(self.names)})"


def closed_system(system: SystemSpec, mask: Sequence[bool]) -> SystemSpec:
    """A copy of ``system`` with the contacts of ``mask`` as holonomic constraints (appended
    after its own constraints, in declaration order), without contacts or events."""
    closed = copy.copy(system)
    closed.pieces = list(system.pieces)
    closed._counts = dict(system._counts)
    closed._constraint_keys = dict(system._constraint_keys)
    closed._parameters = set(system._parameters)
    closed.events, closed.contacts = [], []
    for spec, on in zip(system.contacts, mask, strict=True):
        if on:
            closed.add_holonomic_constraint(spec.gap, name=spec.name)
    return closed


def _restitution(name: str, e: sp.Expr, parameters: Mapping[str, float]) -> float:
    value = e.xreplace({s: sp.Float(parameters[s.name]) for s in e.free_symbols})
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ModelError(
            f"unilateral constraint `{name}`: `restitution` {e} is not a number"
        ) from None
    if not (math.isfinite(x) and 0.0 <= x <= 1.0):
        raise ParameterError(
            f"unilateral constraint `{name}`: the restitution {e} = {x:g} with these parameter "
            "values must lie in [0, 1]"
        )
    return x


def compile_contacts(
    eom: Derivation, values: Sequence[float], solver: str | None, evaluator: str | None
) -> CompiledContacts | None:
    """The contacts declared on ``eom``'s system (the model's ordered parameter ``values``),
    or None when it has none."""
    system = getattr(eom, "system", None)
    if not getattr(system, "contacts", None):
        return None
    parameters = {p.name: float(v) for p, v in zip(eom.parameters, values, strict=True)}
    return CompiledContacts(system, parameters, solver, evaluator)  # type: ignore[arg-type]
