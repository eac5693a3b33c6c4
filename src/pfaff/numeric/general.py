"""The parts of a general model beyond the template streams: solvers, the fused kernel, the evaluator.

:class:`GeneralParts` is the constructor half of :class:`pfaff.NumericModel`: it takes the parts
the compile stage made, checks the fused kernel once, fixes the evaluator by rule
(:mod:`pfaff.numeric.evaluator`), and knows how to rebuild the model for other parameter values,
for a run and after unpickling. The evaluation itself is in :mod:`pfaff.numeric.model`.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from pfaff.core.errors import ConstraintError, PfaffError
from pfaff.numeric.evaluator import MachineCode, choose, machine_opt_level
from pfaff.numeric.kkt import STATE_FLOOR, augmentation_weight, solve_floored
from pfaff.numeric.redundant import independent_rows
from pfaff.numeric.solvers import general_solver

if TYPE_CHECKING:
    from pfaff.numeric.fused import FusedKernel
    from pfaff.numeric.model import NumericModel
    from pfaff.numeric.parts import ConStreams, DynStreams

DENSE_LIMIT = 400  # n + m up to which the KKT system is assembled and solved densely


class GeneralParts:
    """Construction of :class:`pfaff.NumericModel` (see the module docstring)."""

    _fused: FusedKernel | None
    _machine_code: MachineCode | None

    def __init__(
        self,
        n: int,
        m: int,
        dyn: list[DynStreams],
        con: list[ConStreams],
        *,
        coordinate_names: list[str],
        multiplier_names: list[str],
        constraint_names: list[str],
        holonomic: np.ndarray,
        parameters: dict[str, float],
        solver: str | None = None,
        fused: FusedKernel | None = None,
        fused_missing: str = "the model has none",
        evaluator: str | None = None,
        machine_code: MachineCode | None = None,
        **fields: Any,
    ) -> None:
        super().__init__(  # type: ignore[call-arg]
            n, m, dyn, con, coordinate_names=coordinate_names, constraint_names=constraint_names,
            holonomic=holonomic, parameters=parameters, multiplier_names=multiplier_names,
            **fields,
        )  # fmt: skip
        self._p = tuple(self.parameters.values())  # in the order of the fused kernel's arguments
        self._holonomic_list: list[bool] = self.holonomic.tolist()
        if solver is None:
            solver = "range-space" if n + m <= DENSE_LIMIT else "sparse"
        self.solver = solver
        self.dense = solver != "sparse"
        self._solver, self._lu = general_solver(solver, n, m)
        self._pattern = None
        why = fused_missing
        if fused is not None and solver != "range-space":
            fused, why = None, f"the solver is {solver!r} (the fused kernel's solve is range-space)"
        if fused is not None and machine_code is None:
            fused, why = self._checked_fused(fused)
        # (an unpickled kernel has no compiler, but its MachineCode carries the compiled code)
        has_machine = fused is not None and (
            fused.llvm is not None or (machine_code is not None and machine_code.available)
        )
        ops = fused.ops if fused is not None else 0
        self.evaluator = choose(evaluator, n, m, fused is not None, why, has_machine, ops)
        self._fused = None if self.evaluator == "template" else fused
        self._fused_kernel = fused  # kept for with_parameters (shared as it is)
        if machine_code is None and has_machine:
            machine_code = MachineCode(fused.llvm)  # type: ignore[union-attr]
        self._machine_code = machine_code
        self.timings["evaluator"] = self.evaluator
        if self.evaluator == "template" and why:
            self.timings["evaluator_reason"] = why
        self._freeze()  # type: ignore[attr-defined]

    # ------------------------------------------------------------------ the fused kernel
    def _checked_fused(self, fused: FusedKernel) -> tuple[FusedKernel | None, str]:
        """``fused`` if it gives finite real outputs at a random state, with ``rfn`` dropped
        when it disagrees with the array solve of those outputs; else None and the reason."""
        model: NumericModel = self  # type: ignore[assignment]
        rng = np.random.default_rng(7)
        t0, q, qd = 0.3, rng.uniform(0.2, 0.9, model.n), rng.uniform(-0.5, 0.5, model.n)
        try:
            v = np.array(fused.fn(t0, *q.tolist(), *qd.tolist(), *model._p))
        except (ValueError, ArithmeticError, TypeError, NameError) as e:  # NameError: a function
            # the printer wrote but the generated code's namespace lacks (sign, Heaviside, ...)
            return None, f"the fused kernel failed at a test state ({type(e).__name__}: {e})"
        if v.dtype.kind != "f" or not np.isfinite(v).all():
            return None, "the fused kernel is not finite and real at a test state"
        object.__setattr__(self, "_fused", dataclasses.replace(fused, rfn=None))
        object.__setattr__(self, "_run_state", self._new_run_state())
        object.__setattr__(self, "_machine_code", None)
        object.__setattr__(self, "evaluator", "python")
        try:
            slow = model._reference_solve(t0, q, qd)[0]
            fast = None
            if fused.rfn is not None:
                taus = [0.0] * (model.m + 1)  # no floor
                fast = fused.rfn(*model._p, 0.0, 0.0, *taus, lambda t, y: None)(
                    t0, [*q.tolist(), *qd.tolist()]
                )
        except (PfaffError, ValueError, ArithmeticError, TypeError, np.linalg.LinAlgError):
            return dataclasses.replace(fused, rfn=None), ""
        if fast is not None and np.allclose(fast[model.n :], slow, rtol=1e-10, atol=1e-13):
            return fused, ""
        return dataclasses.replace(fused, rfn=None), ""

    def _reference_solve(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """q̈, λ by the model's solver, or by LU on the whole augmented matrix where M is
        singular (quaternion coordinates): the reference generated code is checked against."""
        model: NumericModel = self  # type: ignore[assignment]
        try:
            return model._solve(t, q, qd)
        except PfaffError:
            K, forcing, _, bias, _, _ = model._kkt(t, q, qd)
            return model._solve_kkt(K, forcing, -bias, t, full=True)

    # ------------------------------------------------------------------ machine code
    def _machine(self) -> Callable | None:
        """The machine code when it is the evaluator (made on first use), else None."""
        mc = self._machine_code
        if self.evaluator != "machine" or mc is None:
            return None
        compiled = mc.get(self._machine_agrees)
        if "machine_code" not in self.timings:  # type: ignore[attr-defined]
            self._record_machine(mc)
        return compiled

    def _record_machine(self, mc: MachineCode) -> None:
        """The machine code's kind and cost in ``timings``: ``machine_code`` (CPU seconds to
        build or load it), ``machine_kind`` (``"rhs"``: the whole right-hand side;
        ``"kernel+LAPACK"``: the kernel alone, solved by LAPACK; ``"kernel+Cholesky"`` once a
        right-hand side calls it and its compiled Cholesky solve in one call,
        :mod:`pfaff.numeric.kernelchol`) and, for the kernel alone, ``machine_opt_level`` and
        ``machine_functions`` (the LLVM functions it is split into)."""
        fk = self._fused_kernel
        timings = self.timings  # type: ignore[attr-defined]
        timings["machine_code"] = mc.seconds
        timings["machine_kind"] = "rhs" if fk is None or fk.solves else "kernel+LAPACK"
        if fk is not None and not fk.solves:
            timings["machine_opt_level"] = machine_opt_level(self.n, self.m)  # type: ignore[attr-defined]
            timings["machine_functions"] = len(getattr(mc.compiled, "parts", [mc.compiled]))
        if mc.compiled is None:
            timings["machine_kind"] = "unavailable"

    def _machine_agrees(self, compiled: Callable) -> str:
        """ "" when the machine code agrees with ``fn`` and the array solve at a random state,
        else the reason."""
        model: NumericModel = self  # type: ignore[assignment]
        n, m, fk, p = model.n, model.m, self._fused, model._p
        assert fk is not None
        buf = np.zeros(1 + 2 * n + len(p) + 2 + m + 1)
        buf[1 + 2 * n : 1 + 2 * n + len(p)] = p
        rng = np.random.default_rng(11)
        t0, q, qd = 0.4, rng.uniform(0.2, 0.9, n), rng.uniform(-0.5, 0.5, n)
        buf[0], buf[1 : 1 + n], buf[1 + n : 1 + 2 * n] = t0, q, qd
        python = self.for_run()  # type: ignore[attr-defined]
        python.__dict__["evaluator"] = "python"  # the reference: the generated Python code
        try:
            out = np.array(compiled(buf), dtype=float)
            v = np.array(fk.fn(t0, *q.tolist(), *qd.tolist(), *p), dtype=float)
        except (PfaffError, ValueError, ArithmeticError, TypeError, RuntimeError) as e:
            return f"it could not be checked at a test state: {type(e).__name__}: {e}"
        try:
            qdd, lam = python._reference_solve(t0, q, qd)
        except PfaffError:  # no unique q̈ at this (inadmissible) state, as for redundant rows
            qdd = lam = None  # off their motion: the kernel's outputs are what can be compared
        k = 2 * n + m if fk.solves else 0  # the kernel alone: no q̈, λ of its own
        ok = out.shape == (k + v.size + fk.checks,)
        ok = ok and np.allclose(out[k : k + v.size], v, rtol=1e-11, atol=1e-13)
        if not fk.solves or qdd is None:  # (the run's solve checks its own pivots, and takes
            # the array path where they fail)
            return "" if ok else "it disagrees with the generated Python code at a test state"
        if not np.isfinite(out[n:k]).all():  # M not positive definite at the test state (a
            # quaternion's M is singular): the machine code's documented "take rfn"
            return "" if ok else "it disagrees with the generated Python code at a test state"
        K = np.zeros((n + m, n + m))
        K.flat[fk.kkt_index] = v[fk.kkt_source]
        if independent_rows(K[n:, :n]) is None:  # (redundant rows: λ is not unique, q̈ floored)
            ok = ok and np.allclose(out[n : 2 * n], qdd, rtol=1e-9, atol=1e-12)
            ok = ok and np.allclose(out[2 * n : k], lam, rtol=1e-9, atol=1e-12)
        return "" if ok else "it disagrees with the generated Python code at a test state"

    def compile_machine_code(self) -> bool:
        """Switch this model to machine code now: compile it (or load it from the on-disk
        cache) and make it the evaluator; False, and nothing changed, when the model cannot
        (no fused kernel, or SymEngine without LLVM, or a build that failed: warned).

        This is the one change a compiled model accepts after it is built, and only on this
        explicit request; results then follow the machine code's rounding
        (``model.timings["evaluator"]`` says which evaluator is in use). A model whose rule
        already chose machine code only pays the compilation now instead of at its first
        evaluation.

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
        >>> model.evaluator
        'python'
        >>> model.compile_machine_code(), model.evaluator
        (True, 'machine')
        """
        mc = self._machine_code
        if self._fused is None or mc is None or not mc.available:
            return False
        before = self.evaluator  # type: ignore[has-type]
        object.__setattr__(self, "evaluator", "machine")
        self._run_state.pop("fast", None)  # (accelerations()' fast path: the old evaluator's)
        if self._machine() is None:  # the build failed (warned): the model stays as it was
            object.__setattr__(self, "evaluator", before)
            return False
        self.timings["evaluator"] = "machine"  # type: ignore[attr-defined]
        self._record_machine(mc)
        return True

    def _runtime_parameters(self) -> bool:
        return self._fused is not None

    # ------------------------------------------------------------------ copies
    def _new_run_state(self) -> dict:
        state = {"full": False, "rho": 0.0, "last": None, "live": False, "rows": None}
        n, m = self.n, self.m  # type: ignore[attr-defined]
        state["buf"] = np.zeros(1 + 2 * n + len(self.parameters) + 2 + m + 1)  # type: ignore[attr-defined]
        return state

    def _fresh_run_parts(self) -> None:
        super()._fresh_run_parts()  # type: ignore[misc]
        d = self.__dict__
        d["_solver"], d["_lu"] = general_solver(d["solver"], d["n"], d["m"])

    def __getstate__(self) -> dict:
        # the machine code travels made (the receiver may lack the compiler), and so does
        # the compiled loop's (FusedKernel.loop), which a run makes whatever the evaluator: an
        # unpickled model (a sweep's) steps as this one would, not in Python
        self._machine()
        fk, mc = self._fused, self._machine_code
        if (
            fk is not None and fk.solves and fk.rfn is not None and fk.loop is not None
            and mc is not None and mc.available
        ):  # fmt: skip
            if mc.get(self._machine_agrees) is not None:
                with contextlib.suppress(Exception):  # (not made: the receiver steps in Python)
                    fk.loop()
        return super().__getstate__()  # type: ignore[misc]

    def _unpickled(self) -> set[str]:
        return super()._unpickled() | {"_solver", "_lu"}  # type: ignore[misc]

    def _restored(self) -> None:
        super()._restored()  # type: ignore[misc]
        d = self.__dict__
        d["_solver"], d["_lu"] = general_solver(d["solver"], d["n"], d["m"])

    def _rebuilt(self, parameters: dict[str, float]) -> NumericModel:
        model: NumericModel = self  # type: ignore[assignment]
        dyn, con = model.dyn, model.con
        old, new = list(model.parameters.values()), list(parameters.values())
        if new != old:  # new kernels for the templates that use a changed value
            dyn, con = model._restream(old, new, dyn, con)
        geometry = model.geometry
        if geometry is not None and new != old:
            geometry = geometry.with_parameters(parameters)  # type: ignore[attr-defined]
        return type(model)(
            model.n, model.m, dyn, con, coordinate_names=model.coordinate_names,
            multiplier_names=model.multiplier_names, constraint_names=model.constraint_names,
            holonomic=model.holonomic, parameters=parameters, solver=model.solver,
            fused=self._fused_kernel, evaluator=model.evaluator,
            machine_code=self._machine_code, inputs=model.inputs, attitudes=model.attitudes,
            events=tuple(e.with_parameters(parameters) for e in model.events),  # type: ignore[attr-defined]
            contacts=model.contacts and model.contacts.with_parameters(parameters),  # type: ignore[attr-defined]
            geometry=geometry, linearizer=model.linearizer, restream=model._restream,
            timings=model.timings,
        )  # fmt: skip


def augmentation(
    model: NumericModel, K: np.ndarray, t: float, q: np.ndarray, qd: np.ndarray
) -> float:
    """ρ of the generated solve with M + ρAᵀA (``rfn_aug``) for a singular M, checked
    against the LU solve of the whole augmented matrix at this state; 0 when unusable."""
    fk, n = model._fused, model.n
    if fk is None or fk.rfn_aug is None or not model.m:
        return 0.0
    M, A = K[:n, :n], K[n:, :n]
    rho = augmentation_weight(M, A)
    try:
        fn = fk.rfn_aug(*model._p, 0.0, 0.0, *([0.0] * (model.m + 1)), rho, lambda t, y: None)
        fast = fn(t, [*q.tolist(), *qd.tolist()])
        slow = model._solve(t, q, qd)[0]
    except (PfaffError, ValueError, ArithmeticError, TypeError, np.linalg.LinAlgError):
        return 0.0  # the generated augmented solve is not usable here: LU on K
    if fast is None or not np.allclose(fast[n:], slow, rtol=1e-9, atol=1e-12):
        return 0.0
    return rho


def fused_states(
    model: NumericModel,
    t: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    params: list | None = None,
) -> dict[str, np.ndarray]:
    """:meth:`pfaff.NumericModel.evaluate_states` of a fused model: the NumPy kernel over all
    states at once and a batched floored solve. ``params``: per parameter a value or an array of
    shape (k,), one per state (inputs that change along a run); default: the model's values."""
    fk, k, n, N = model._fused, len(t), model.n, model.n + model.m
    assert fk is not None
    p = list(model._p) if params is None else params
    args = [t, *q.T, *qd.T, *p]
    vals = np.empty((k, fk.offsets[3] + model.m))
    for i, o in enumerate(fk.vfn(*args)):
        vals[:, i] = o
    K = np.zeros((k, N * N))
    K[:, fk.kkt_index] = vals[:, fk.kkt_source]
    K = K.reshape(k, N, N)
    o = fk.offsets
    qdd, lam = solve_floored(
        K[:, :n, :n], K[:, n:, :n], vals[:, o[0] : o[1]], vals[:, o[1] : o[2]], STATE_FLOOR
    )
    if not (np.isfinite(qdd).all() and np.isfinite(lam).all()):
        raise ConstraintError(model._singular_message(float(t[0])))
    g = np.einsum("kij,kj->ki", K[:, n:, :n], qd) + vals[:, o[2] : o[3]]
    T, V, T0 = (np.broadcast_to(e, (k,)).astype(float) for e in fk.efn(*args))
    Tneg = np.broadcast_to(fk.efn(t, *q.T, *(-qd).T, *p)[0], (k,))
    T2 = 0.5 * (T + Tneg) - T0
    model.stats["kkt_solves"] += k
    return {"qdd": qdd, "multipliers": lam, "f": vals[:, o[3] :], "g": g, "T": T, "V": V,
            "T0": T0, "T2": T2}  # fmt: skip
