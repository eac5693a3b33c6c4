"""The numeric model of any system: :class:`NumericModel`, dense KKT solves and the small-system paths.

No SymPy here: the compile stage hands over template kernels over index arrays
(:class:`pfaff.numeric.base.StreamModel` evaluates them, as for families) and, for small
systems, the fused kernel. The augmented system is solved in its symmetric form

    [[M, Aᵀ], [A, 0]] [q̈; -λ] = [Q - h; -(Ȧq̇ + ḃ)]

by one of the solvers of :mod:`pfaff.numeric.solvers`. Which code evaluates a state is the
model's evaluator (:mod:`pfaff.numeric.evaluator`), fixed when it is built.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.sparse as sps

from pfaff.core.errors import (
    ConstraintError,
    PfaffError,
    StateError,
    raised_in_generated_code,
    undefined_at,
)
from pfaff.numeric.base import StreamModel
from pfaff.numeric.checked import CheckedGeneral
from pfaff.numeric.checks import check_finite
from pfaff.numeric.constraintlin import linearized_constraints
from pfaff.numeric.evaluator import machine_rhs
from pfaff.numeric.field import AccelerationField, not_real
from pfaff.numeric.general import DENSE_LIMIT, GeneralParts, fused_states
from pfaff.numeric.kernelsolve import kernel_rhs
from pfaff.numeric.kkt import FLOOR, STATE_FLOOR, KKTSystem, SingularKKT, SparseSolver, row_scales
from pfaff.numeric.machineloop import LoopCode, machine_loop
from pfaff.numeric.pattern import KKTPattern
from pfaff.numeric.protocol import ConstraintLinearization
from pfaff.numeric.redundant import independent_rows, min_norm_multipliers
from pfaff.numeric.solvers import names

if TYPE_CHECKING:
    from collections.abc import Callable


SOLVERS = names("general")
__all__ = ["DENSE_LIMIT", "SOLVERS", "NumericModel"]


class NumericModel(CheckedGeneral, GeneralParts, StreamModel):
    """Compiled equations of motion for one set of parameter values: an immutable value.

    Attributes
    ----------
    n, m : int
        Number of coordinates and of constraints (multipliers).
    coordinate_names, multiplier_names : list of str
    parameters : mapping
        Parameter name -> value used (read-only; :meth:`with_parameters` makes another model).
    inputs : tuple of str
        Inputs declared with ``System.add_input``: their values come per call
        (``accelerations(..., inputs=...)``) or per run (``simulate(..., inputs=...)``).
    evaluator : str
        ``"template"``, ``"python"`` or ``"machine"`` (:mod:`pfaff.numeric.evaluator`).
    timings : dict
        CPU seconds of the stages that made the model: ``equations``, ``compile`` (its
        ``codegen`` part, see ``cache``: ``"hit"``, ``"miss"``, ``"off"`` or ``"reused"``),
        ``evaluator`` and, once made, ``machine_code`` (and ``compiled_solve``: LLVM's JIT
        compile of the right-hand side's Cholesky solve above the fused limit, once per process,
        :mod:`pfaff.numeric.kernelchol`).

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    >>> qdd, lam = model.accelerations(0.0, np.array([0.0, -2.0]), np.zeros(2))
    >>> float(-2 * 2 * lam[0])  # rod tension -2Lλ of a pendulum hanging at rest: mg
    9.81
    """

    # ------------------------------------------------------------------ assembly

    def _kkt(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """K, Q - h, b, Ȧq̇ + ḃ, f and g = A q̇ + b at an (unchecked) state."""
        n, m = self.n, self.m
        if self._fused is not None:
            fk = self._fused
            v = self._fused_values(t, q, qd)
            K = np.zeros((n + m, n + m))
            K.flat[fk.kkt_index] = v[fk.kkt_source]
            o = fk.offsets
            forcing, bias, b, f = v[o[0] : o[1]], -v[o[1] : o[2]], v[o[2] : o[3]], v[o[3] :]
            return K, forcing, b, bias, f, K[n:, :n] @ qd + b
        mvals, forcing = self._dynamics(t, q, qd)
        avals, b, bias, f = self._constraints(t, q, qd)
        pattern = self._kkt_pattern()
        if self.dense:
            K = pattern.dense(mvals, avals)
            g = K[n:, :n] @ qd + b
        else:
            K = pattern.assemble(mvals, avals)
            g = b + self.a_matvec(avals, qd)
        return K, forcing, b, bias, f, g

    def _kkt_pattern(self) -> KKTPattern:
        if self._pattern is None:  # a cache of fixed structure, made on first use
            object.__setattr__(self, "_pattern", KKTPattern(self))
        return self._pattern  # type: ignore[return-value]

    def _fused_values(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The fused kernel's flat outputs at a state; non-real values are an error naming t.
        With machine code as the evaluator, one call also gives q̈ and λ (kept for
        :meth:`solve`)."""
        fk = self._fused
        assert fk is not None
        self._run_state["last"] = None
        machine = self._machine()
        if machine is not None:
            n, m = self.n, self.m
            buf = self._run_state["buf"]
            buf[0], buf[1 : 1 + n], buf[1 + n : 1 + 2 * n] = t, q, qd
            buf[1 + 2 * n : 1 + 2 * n + len(self._p)] = self._p
            out = machine(buf)
            if not fk.solves:  # the kernel alone (above FUSED_LIMIT): the caller solves
                if np.isfinite(out).all():
                    return out
            elif np.isfinite(out).all():
                self._run_state["last"] = (t, q.tobytes(), qd.tobytes(), out[n : 2 * n + m])
                return out[2 * n + m : out.size - fk.checks]
        try:
            v = np.array(fk.fn(t, *q.tolist(), *qd.tolist(), *self._p))
        except (ValueError, ArithmeticError) as e:  # math domain error, overflow, division by 0
            if isinstance(e, PfaffError) or not raised_in_generated_code(e):
                raise
            raise undefined_at(e, t) from None
        if v.dtype.kind == "c":
            raise StateError(not_real(t))
        return v

    # ------------------------------------------------------------------ solves
    def _solve_kkt(
        self,
        K: np.ndarray | sps.csc_matrix,
        forcing: np.ndarray,
        c: np.ndarray,
        t: float,
        floor: float = STATE_FLOOR,
        scales: np.ndarray | None = None,
        full: bool | None = None,
        rows: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """q̈ and λ of K [q̈; −λ] = [Q − h; c] by the model's solver (:mod:`pfaff.numeric.kkt`).

        ``rows`` (default: the run's, set where its constraints are redundant): solve with these
        independent rows only and report the minimum-norm λ over all
        (:mod:`pfaff.numeric.redundant`).

        ``full`` (default: the run's mode, set by :meth:`check_determined`): M singular or
        nearly so, where a Cholesky factorization of M may pass on rounding and return garbage:
        LU on the whole K. ``floor`` and ``scales``: the rank-loss floor (``FLOOR`` with row
        scales in integrators, ``STATE_FLOOR`` for single states).
        """
        rows = self._run_state["rows"] if rows is None else rows
        if rows is not None:
            if sps.issparse(K):
                K = K.toarray()  # (a model with redundant rows is at most REDUNDANT_DENSE large)
            return self._solve_rows(K, forcing, c, t, rows, floor == STATE_FLOOR)
        self.stats["kkt_solves"] += 1
        full = self._run_state["full"] if full is None else full
        solver = self._lu if full and self.dense else self._solver
        try:
            qdd, lam = solver.solve(KKTSystem(forcing, c, K), floor=floor, scales=scales)
            if isinstance(solver, SparseSolver):
                self.stats["fill"] = solver.fill
        except (np.linalg.LinAlgError, ValueError) as e:
            check_finite(t, "[[M, Aᵀ], [A, 0]], Q - h or Ȧq̇ + ḃ", K, forcing, c)
            raise ConstraintError(self._singular_message(t, e)) from None
        if not math.isfinite(qdd.sum() + lam.sum()):  # type: ignore[union-attr]
            check_finite(t, "[[M, Aᵀ], [A, 0]], Q - h or Ȧq̇ + ḃ", K, forcing, c)
            raise ConstraintError(self._singular_message(t))
        if floor == STATE_FLOOR and self.dense and self.m:
            self._check_consistent(K[self.n :, : self.n], qdd, c, t)
        return qdd, lam  # type: ignore[return-value]

    def _solve_rows(
        self, K: np.ndarray, forcing: np.ndarray, c: np.ndarray, t: float, rows: np.ndarray,
        check: bool,
    ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """q̈ from the independent ``rows`` (LU of the reduced augmented matrix), λ minimum-norm
        over all rows; ``check``: every row's A q̈ = c (a contradiction on the path is named)."""
        self.stats["kkt_solves"] += 1
        n = self.n
        idx = np.concatenate([np.arange(n), n + rows])
        try:
            sol = scipy.linalg.solve(K[np.ix_(idx, idx)], np.concatenate([forcing, c[rows]]))
        except (np.linalg.LinAlgError, ValueError):
            check_finite(t, "[[M, Aᵀ], [A, 0]], Q - h or Ȧq̇ + ḃ", K, forcing, c)
            raise ConstraintError(self._singular_message(t)) from None
        qdd, A = sol[:n], K[n:, :n]
        lam = min_norm_multipliers(A, rows, -sol[n:])
        if not math.isfinite(qdd.sum() + lam.sum()):
            check_finite(t, "[[M, Aᵀ], [A, 0]], Q - h or Ȧq̇ + ḃ", K, forcing, c)
            raise ConstraintError(self._singular_message(t))
        if check:
            self._check_consistent(A, qdd, c, t)
        return qdd, lam

    def _check_consistent(self, A: np.ndarray, qdd: np.ndarray, c: np.ndarray, t: float) -> None:
        """A single state's q̈ must satisfy A q̈ = c: else the constraints are inconsistent here."""
        r = np.abs(A @ qdd - c)
        scale = 1.0 + np.abs(c).max() + np.abs(A).max() * np.abs(qdd).max()
        if r.max() > 1e-8 * scale:
            i = int(np.argmax(r))
            raise ConstraintError(
                f"{self._singular_message(t)} (inconsistent equations: no acceleration satisfies "
                f"constraint `{self.constraint_names[i]}` together with the others)"
            )

    def solve(
        self, t: float, q: np.ndarray, qd: np.ndarray, alpha: float = 0.0, beta: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Unchecked q̈, λ with the constraint rows' right-hand side −(Ȧq̇+ḃ) − 2αg − β²f
        (:class:`pfaff.numeric.protocol.DynamicsModel`). With machine code and no
        stabilization: one call of it (q̈ and λ with the kernel's outputs)."""
        run = self._run_state
        if self.evaluator == "machine" and not (
            alpha or beta or run["full"] or run["rows"] is not None
        ):
            self._fused_values(t, q, qd)
            last = self._run_state["last"]
            if last is not None:
                return last[3][: self.n].copy(), last[3][self.n :].copy()
        return self._solve(t, q, qd, alpha, beta)

    def _solve(
        self,
        t: float,
        q: np.ndarray,
        qd: np.ndarray,
        alpha: float = 0.0,
        beta: float = 0.0,
        out: np.ndarray | None = None,
        multipliers: bool = True,
        floor: float = STATE_FLOOR,
        scales: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        K, forcing, _, bias, f, g = self._kkt(t, q, qd)
        c = -bias
        if alpha:
            c = c - 2.0 * alpha * g
        if beta:
            c = c - beta * beta * f
        qdd, lam = self._solve_kkt(K, forcing, c, t, floor, scales)
        if out is not None:
            out[:] = qdd
        return qdd, lam

    def _row_scales(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray | None:
        """Reference constraint row sizes for the integrators' floor (:func:`pfaff.numeric.kkt.row_scales`)."""
        if (
            not self.dense
            or not self.m
            or self._run_state["full"]
            or self._run_state["rows"] is not None
        ):
            return None
        K = self._kkt(t, q, qd)[0]
        try:
            return row_scales(K[: self.n, : self.n], K[self.n :, : self.n])
        except np.linalg.LinAlgError:  # M singular: the full augmented matrix is used anyway
            return None

    def ode_function(
        self,
        alpha: float = 0.0,
        beta: float = 0.0,
        start: tuple | None = None,
        before: Callable | None = None,
    ) -> AccelerationField:
        """y' = [q̇, q̈] of y = [q, q̇] (Baumgarte-stabilized when α, β > 0), for integrators.

        ``start`` = (t0, q0, q̇0) sets the reference row sizes of the rank-loss floor
        (:mod:`pfaff.numeric.kkt`); None: no floor. ``before(t, q, q̇)`` runs before every
        evaluation (a run's inputs, :class:`pfaff.integrate.inputs.DrivenModel`).
        """
        scales = self._row_scales(*start) if start is not None else None
        return AccelerationField(self, alpha, beta, scales, before)

    def _fused_rhs(self, alpha: float, beta: float, scales: np.ndarray | None) -> Callable:
        """``rhs(t, y: list) -> list``: the fused kernel and the generated floored range-space
        solve in one function (machine code when that is the evaluator); the array path where M
        is not positive definite. In a run with inputs, the run's parameter vector is read at
        every call."""
        n, fk, run = self.n, self._fused, self._run_state
        assert fk is not None
        floor = FLOOR if scales is not None else STATE_FLOOR
        live = self._p if run["live"] else None

        def slow(t: float, yl: list) -> list:
            y = np.array(yl)
            qdd = self._solve(t, y[:n], y[n:], alpha, beta, floor=floor, scales=scales)[0]
            return yl[n:] + qdd.tolist()

        if run["rows"] is not None:  # redundant rows: the exact reduced solve
            return slow
        if not fk.solves and not run["full"]:  # above FUSED_LIMIT: machine-code kernel + LAPACK
            machine = self._machine()
            if machine is not None:
                taus = [0.0] * (self.m + 1)  # (inputs of the whole right-hand side, unused here)
                fixed = [*self._p, alpha, beta, *taus]
                solve = (alpha, beta, floor, scales)
                rhs = kernel_rhs(fk, machine, n, fixed, live, solve, slow, self.stats)
                seconds = getattr(rhs, "compiled_solve", None)  # its JIT compile, once per process
                if seconds is not None:  # (the kernel and the Cholesky solve in one call)
                    self.timings.setdefault("compiled_solve", seconds)
                    self.timings["machine_kind"] = "kernel+Cholesky"
                return rhs
        if run["full"] and run["rho"] and fk.rfn_aug is not None:  # M singular: M + ρAᵀA
            fixed = (alpha, beta, *([0.0] * (self.m + 1)), run["rho"], slow)
            make = fk.rfn_aug
        elif run["full"] or fk.rfn is None:
            return slow
        else:  # no reference sizes: no floor (a singular S then takes the array path)
            taus = [0.0] * self.m if scales is None else (FLOOR * np.asarray(scales)).tolist()
            taus.append(FLOOR if scales is not None else 0.0)  # the cap factor
            fixed, make = (alpha, beta, *taus, slow), fk.rfn
            machine = self._machine()
            if machine is not None:
                py = _live(make, live, fixed) if live is not None else make(*self._p, *fixed)
                return machine_rhs(machine, py, n, [*self._p, *fixed[:-1]], live)
        if live is not None:
            return _live(make, live, fixed)
        return make(*self._p, *fixed)

    def machine_loop(self, field: AccelerationField) -> tuple[LoopCode | None, str]:
        """The machine code of the compiled stepping loop for a run on ``field`` (this run
        copy's ODE function), or None and why not (:mod:`pfaff.numeric.machineloop`)."""
        return machine_loop(self, field)

    def power_function(self) -> Callable[[float, np.ndarray, np.ndarray], float]:
        """P(t, q, q̇) = Qᵀq̇ of the applied forces at the compiled parameter values, unchecked:
        one generated scalar function where the model has a fused kernel (the template
        kernels' stream pass per forced template otherwise)."""
        fk = self._fused
        make = getattr(fk.pfn, "function", None) if fk is not None else None
        pfn = make() if make is not None else (fk.pfn if fk is not None else None)
        if pfn is None or not self.applied_power:
            return super().power_function()
        p = tuple(self.parameters.values())  # compile-time values (inputs: see DrivenModel)

        def power(t: float, q: np.ndarray, qd: np.ndarray) -> float:
            return float(pfn(t, *q.tolist(), *qd.tolist(), *p)[0])

        return power

    # ------------------------------------------------------------------ for the projection and IDA
    def residual(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unchecked (f, A q̇ + b), each shape (m,)."""
        if self._fused is not None:
            _, _, _, _, f, g = self._kkt(t, q, qd)
            return f, g
        return super().residual(t, q, qd)

    def linearize_constraints(
        self, t: float, q: np.ndarray, qd: np.ndarray, tol: float
    ) -> ConstraintLinearization:
        """The constraints linearized at a state for the projection (:mod:`pfaff.numeric.projection`):
        see :func:`pfaff.numeric.constraintlin.linearized_constraints`."""
        return linearized_constraints(self, t, q, qd, tol)

    def dae_blocks(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """(M, A, Q − h, f, g) at an unchecked state: dense when small, else CSR."""
        K, forcing, _, _, f, g = self._kkt(t, q, qd)
        n = self.n
        if sps.issparse(K):
            K = sps.csr_matrix(K)
        return K[:n, :n], K[n:, :n], forcing, f, g

    @property
    def mass_singular(self) -> bool:
        """True when this run found M singular (or nearly) at its first state
        (:meth:`check_determined`): the augmented system is still regular (quaternion
        coordinates), but M⁻¹ is not to be used. Always False for a user's model."""
        return bool(self._run_state["full"])

    def constraint_bias(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Ȧq̇ + ḃ at an unchecked state, shape (m,): A q̈ = −(Ȧq̇ + ḃ) on a motion."""
        return np.asarray(self._kkt(t, q, qd)[3], dtype=float)

    @property
    def _batched_states(self) -> bool:
        """Whether reported states go through the fused kernel in one batched, floored solve:
        not where M is singular or the run's constraints are redundant (minimum-norm λ)."""
        run = self._run_state
        return self._fused is not None and not run["full"] and run["rows"] is None

    def evaluate_states(
        self, t: np.ndarray, q: np.ndarray, qd: np.ndarray
    ) -> dict[str, np.ndarray]:
        """What a trajectory reports at k states: q̈, λ, f, g, T, V and T(q, 0, t).

        Parameters
        ----------
        t : ndarray, shape (k,)
        q, qd : ndarray, shape (k, n)

        Returns
        -------
        dict
            ``qdd`` (k, n), ``multipliers`` (k, m), ``f`` and ``g`` (k, m), and (k,) arrays ``T``,
            ``V``, ``T0`` = T(q, 0, t) and ``T2`` (the part of T quadratic in q̇).
        """
        t = np.asarray(t, dtype=float)
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        if self._batched_states:
            try:
                return fused_states(self, t, q, qd)
            except (np.linalg.LinAlgError, ConstraintError):
                pass  # a redundant configuration somewhere: state by state below
        out = super().evaluate_states(t, q, qd)
        if self._run_state["rows"] is not None:  # redundant rows: how many, state by state
            n, k = self.n, np.zeros(len(t), dtype=np.int64)
            for i in range(len(t)):
                rows = independent_rows(self._kkt(float(t[i]), q[i], qd[i])[0][n:, :n])
                k[i] = 0 if rows is None else self.m - rows.size
            out["redundant_rows"] = k
        return out

    def _singular_message(self, t: float, e: Exception | None = None) -> str:
        msg = (
            f"the augmented matrix [[M, Aᵀ], [A, 0]] is singular at t = {t:g}: the constraints are "
            "redundant or inconsistent in this configuration, or M is singular on the admissible "
            "motions (a coordinate without inertia)"
        )
        if isinstance(e, SingularKKT) and e.dead_rows.size:
            names = ", ".join(f"`{self.constraint_names[i]}`" for i in e.dead_rows[:5])
            return f"{msg}; constraint {names} has a zero gradient here"
        if isinstance(e, SingularKKT) and e.detail == "inconsistent equations":
            return f"{msg} (inconsistent equations)"
        return msg


def _live(make: Callable, live: list, fixed: tuple) -> Callable:
    """A generated right-hand side that takes the run's parameter vector ``live`` at every call
    (inputs): the generated function binds its parameters when made, so it is made per call."""

    def rhs(t: float, yl: list) -> list:
        return make(*live, *fixed)(t, yl)

    return rhs
