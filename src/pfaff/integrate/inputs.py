"""Inputs during a run: parameters declared with ``System.add_input`` whose values a simulation
supplies at every evaluation: a number, a function of time u(t), or a feedback law u(t, q, q̇).

:class:`DrivenModel` wraps a compiled model: before each evaluation (the right-hand side, the
projection, the DAE blocks, the reported states) it writes the inputs' values into the model's
run's own parameter vector (a run copy of the model: the user's model is never written). That
needs compiled code that takes its parameters at run time, which small and medium systems have
(the fused kernel, as generated Python or machine code: the right-hand side stays the generated
one); models whose kernels fold the values in are refused with a clear error.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from pfaff.core.errors import ConstraintError, OptionError, StateError
from pfaff.numeric.checks import real_number
from pfaff.numeric.general import fused_states


def _arity(fn: Callable, name: str) -> int:
    try:
        params = [
            p
            for p in inspect.signature(fn).parameters.values()
            if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) and p.default is p.empty
        ]
    except (TypeError, ValueError):
        return 1
    if len(params) not in (1, 3):
        raise OptionError(
            f"input `{name}` must be a number, a function u(t) or a feedback law u(t, q, qd); "
            f"got a callable of {len(params)} arguments"
        )
    return len(params)


class DrivenModel:
    """A run of a compiled model whose inputs take values during it (see the module docstring).

    It wraps a run copy (:meth:`pfaff.numeric.value.ModelValue.for_run`): the inputs' values are
    written into the run's own parameter vector, never into the user's model, so a trajectory's
    later evaluations (``traj.at(t)``) use the run's inputs and leave the model as it was.

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> x = pfaff.coordinates("x")
    >>> s = pfaff.System([x]); s.add_particle(2, [x, 0]); u = sp.Symbol("u")
    >>> s.add_force([u, 0], at=[x, 0]); _ = s.add_input(u)
    >>> model = s.equations().compile({})
    >>> traj = pfaff.simulate(model, [0.0], [0.0], (0, 1), inputs={"u": lambda t: 4.0})
    >>> round(float(traj.q[-1, 0]), 9)   # x = u t² / (2 m)
    1.0
    """

    def __init__(self, run: Any, inputs: Mapping[str, object]) -> None:
        declared = list(run.inputs)
        if not isinstance(inputs, Mapping):
            raise OptionError(f"`inputs` must be a dict of input name -> value, got {inputs!r:.60}")
        if not run._runtime_parameters():
            raise OptionError(
                "`inputs` need a model whose compiled code takes its parameters at run time "
                "(the fused kernel of small and medium systems); this model "
                f"(evaluator {getattr(run, 'evaluator', 'template')!r}) folds them into its "
                "kernels: write the input into the model as a parameter and use "
                "with_parameters, or compile with evaluator='python'"
            )
        names = list(run.parameters)
        self._model = run
        self._p: list[float] = run._p  # the run's own parameter vector
        self._base: list[float] = []  # the inputs' values at compile time (in the kernels)
        self._slots: list[tuple[int, str, int, object]] = []
        for name, u in inputs.items():
            if name not in declared:
                raise OptionError(
                    f"`inputs`: `{name}` is not an input of this model (declared with "
                    f"System.add_input: {', '.join(declared) or 'none'})"
                )
            if name not in names:  # declared, but no equation uses it
                continue
            i = names.index(name)
            self._base.append(float(self._p[i]))
            if callable(u):
                self._slots.append((i, name, _arity(u, name), u))
            else:
                self._slots.append((i, name, 0, _value(u, name, None)))
        run._run_state["live"] = True

    def __getattr__(self, attr: str) -> Any:
        return getattr(self._model, attr)

    @property
    def dae_model(self) -> DrivenModel:
        """This driven model: its DAE keeps every row (the model it wraps, unwrapped, would
        lose the inputs, which only this wrapper writes)."""
        return self

    def set(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        """Write the inputs' values at (t, q, q̇) into the run's parameter vector."""
        p, isfinite = self._p, math.isfinite
        for i, name, kind, u in self._slots:
            if kind == 0:
                p[i] = u  # type: ignore[assignment]
                continue
            # a law gets copies: one that changes its arguments in place leaves the run's state
            v = u(t) if kind == 1 else u(t, q.copy(), qd.copy())  # type: ignore[operator]
            # the common case, a finite float (np.float64 too), without the full check
            p[i] = v if v.__class__ in _FLOATS and isfinite(v) else _value(v, name, t)

    # the methods of the DynamicsModel protocol, each after setting the inputs
    def solve(self, t: float, q: np.ndarray, qd: np.ndarray, alpha: float = 0.0, beta: float = 0.0):
        self.set(t, q, qd)
        return self._model._solve(t, q, qd, alpha, beta)

    def accelerations(self, t: float, q: Any, qd: Any):
        self.set(t, np.asarray(q, dtype=float), np.asarray(qd, dtype=float))
        return self._model.accelerations(t, q, qd)

    def check_determined(self, t: float, q: Any, qd: Any) -> None:
        self.set(t, np.asarray(q, dtype=float), np.asarray(qd, dtype=float))
        self._model.check_determined(t, q, qd)

    def residual(self, t: float, q: np.ndarray, qd: np.ndarray):
        self.set(t, q, qd)
        return self._model.residual(t, q, qd)

    def linearize_constraints(self, t: float, q: np.ndarray, qd: np.ndarray, tol: float):
        self.set(t, q, qd)
        return self._model.linearize_constraints(t, q, qd, tol)

    def dae_blocks(self, t: float, q: np.ndarray, qd: np.ndarray):
        self.set(t, q, qd)
        return self._model.dae_blocks(t, q, qd)

    def constraint_bias(self, t: float, q: np.ndarray, qd: np.ndarray):
        self.set(t, q, qd)
        return self._model.constraint_bias(t, q, qd)

    def ode_function(self, alpha: float = 0.0, beta: float = 0.0, start: tuple | None = None):
        """The run's right-hand side with the inputs set before every evaluation: the same
        generated (or machine) code as without inputs, reading the run's parameter vector."""
        if start is not None:
            self.set(*start)
        return self._model.ode_function(alpha, beta, start, before=self.set)

    def power_function(self) -> Callable:
        """Qᵀq̇ of the applied forces with the inputs' values: the compiled power (whose
        kernels hold the inputs' values at compile time) plus q̇ᵀ(Q(u) − Q(u₀)), taken from the
        run-time forcing Q − h (exact when the inputs enter only applied forces, as forces and
        torques do: h does not depend on them)."""
        model, p = self._model, self._p
        power = model.power_function()
        base = list(p)
        for (i, *_), v in zip(self._slots, self._base, strict=True):
            base[i] = v
        fn, o = model._fused.fn, model._fused.offsets  # (inputs need the fused kernel)

        def pw(t: float, q: np.ndarray, qd: np.ndarray) -> float:
            self.set(t, q, qd)
            ql, qdl = q.tolist(), qd.tolist()
            driven = fn(t, *ql, *qdl, *p)[o[0] : o[1]]  # Q − h: the kernel's forcing outputs
            at_base = fn(t, *ql, *qdl, *base)[o[0] : o[1]]
            extra = math.fsum(v * (a - b) for v, a, b in zip(qdl, driven, at_base, strict=True))
            return float(power(t, q, qd)) + extra

        return pw

    def evaluate_states(self, t: np.ndarray, q: np.ndarray, qd: np.ndarray) -> dict:
        """What a trajectory reports: the inputs' values per state, then all states at once
        through the fused kernel (state by state where M is singular or rows are redundant)."""
        model = self._model
        if len(t) and model._batched_states:
            params = [np.full(len(t), v) for v in self._p]
            for k in range(len(t)):
                self.set(float(t[k]), q[k], qd[k])
                for i, *_ in self._slots:
                    params[i][k] = self._p[i]
            try:
                return fused_states(model, np.asarray(t, dtype=float), q, qd, params)
            except (np.linalg.LinAlgError, ConstraintError):
                pass  # a redundant configuration somewhere: state by state below
        parts = []
        for k in range(len(t)):
            self.set(float(t[k]), q[k], qd[k])
            parts.append(self._model.evaluate_states(t[k : k + 1], q[k : k + 1], qd[k : k + 1]))
        if not parts:
            return self._model.evaluate_states(t, q, qd)
        return {key: np.concatenate([d[key] for d in parts]) for key in parts[0]}


_FLOATS = (float, np.float64)


def _value(v: object, name: str, t: float | None) -> float:
    """A given input value (an :class:`OptionError`), or one a callable returned at t (a
    :class:`StateError` naming t) as a finite float."""
    if t is None:
        return real_number(v, f"inputs['{name}']", OptionError)
    return real_number(v, f"inputs['{name}'] at t = {t:.17g}", StateError)
