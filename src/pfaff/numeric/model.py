"""The numeric model of any system: :class:`NumericModel`, dense KKT solves and the small-system paths.

No SymPy here: the compile stage hands over template kernels over index arrays
(:class:`pfaff.numeric.structured.StreamModel` evaluates them, as for families). The augmented
system is solved in its symmetric form

    [[M, Aᵀ], [A, 0]] [q̈; -λ] = [Q - h; -(Ȧq̇ + ḃ)]

by one of the solvers of :mod:`pfaff.numeric.kkt` (``range-space`` with the rank-loss floor for
small systems, ``lu``, or ``sparse`` above ``DENSE_LIMIT`` unknowns). Up to
:data:`pfaff.derive.fused.FUSED_LIMIT` unknowns the compile stage also hands over a fused scalar
kernel (:mod:`pfaff.numeric.fused`): the whole system as one function on floats, and the
range-space solve as generated code.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.sparse as sps

from pfaff.core.errors import (
    ConstraintError,
    InertiaError,
    ModelTypeError,
    OptionError,
    ParameterError,
    PfaffError,
    StateError,
    raised_in_generated_code,
    undefined_at,
)
from pfaff.numeric.checks import check_finite
from pfaff.numeric.fused import FusedLinearization
from pfaff.numeric.kkt import (
    FLOOR,
    RESCALE_BELOW,
    STATE_FLOOR,
    KKTSystem,
    LUSolver,
    RangeSpaceSolver,
    SingularKKT,
    SparseSolver,
    augmentation_weight,
    row_scales,
    solve_floored,
)
from pfaff.numeric.linearization import Linearization, linearize_model
from pfaff.numeric.projection import ArrayLinearization, mass_metric_correction
from pfaff.numeric.protocol import ConstraintLinearization, OdeFunction
from pfaff.numeric.structured import ConStreams, DynStreams, KKTPattern, StreamModel

if TYPE_CHECKING:
    from pfaff.numeric.fused import FusedKernel

_potrf = scipy.linalg.lapack.dpotrf
DENSE_LIMIT = 400  # n + m up to which the KKT system is assembled and solved densely
SOLVERS = {c.name: c for c in (RangeSpaceSolver, LUSolver, SparseSolver)}
M_PIVOT = 1e-10  # a Cholesky pivot of M below this times max diag M: M is (nearly) singular


class NumericModel(StreamModel):
    """Compiled equations of motion for one set of parameter values.

    Attributes
    ----------
    n, m : int
        Number of coordinates and of constraints (multipliers).
    coordinate_names, multiplier_names : list of str
    parameters : dict
        Parameter name -> value used.
    timings : dict
        CPU seconds of the stages that made the model: ``equations``, ``compile`` (its
        ``codegen`` part: the fused kernel, generated or loaded from the on-disk cache, see
        ``cache``: ``"hit"``, ``"miss"`` or ``"off"``) and, once the first simulation has made or
        loaded it, ``machine_code``.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    >>> qdd, lam = model.accelerations(0.0, np.array([0.0, -2.0]), np.zeros(2))
    >>> float(-2 * 2 * lam[0])  # rod tension -2Lλ of a pendulum hanging at rest: mg
    9.81
    """

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
    ) -> None:
        super().__init__(
            n, m, dyn, con, coordinate_names=coordinate_names, constraint_names=constraint_names,
            holonomic=holonomic, parameters=parameters, multiplier_names=multiplier_names,
        )  # fmt: skip
        self._p = list(self.parameters.values())  # in the order of the fused kernel's arguments
        self.timings: dict[str, float | str] = {}
        # per rigid body: (name, attitude kind, coordinate indices, Euler sequence); see
        # pfaff.integrate.events (MRP switching, the Euler-angle singularity)
        self.attitudes: list[tuple[str, str, tuple[int, ...], str]] = []
        self._holonomic_list: list[bool] = self.holonomic.tolist()
        if solver is None:
            solver = "range-space" if n + m <= DENSE_LIMIT else "sparse"
        if solver not in SOLVERS:
            raise OptionError(f"`solver` must be one of {', '.join(SOLVERS)}; got {solver!r:.80}")
        self.solver: str = solver
        self._solver = SOLVERS[solver](n, m)
        self._lu = LUSolver(n, m)
        self.dense = solver != "sparse"
        self._pattern = None  # made on first use: the fused kernel may serve every evaluation
        self._fused: FusedKernel | None = None  # see use_fused
        self._prefer_machine: bool | None = None  # machine-code right-hand side faster? (timed)
        self._machine: Callable | None = None  # the machine code, once checked (_use_machine)
        self._machine_buf = np.zeros(0)
        self._machine_last: tuple | None = None  # (t, q, q̇, [q̈, λ]) of its last evaluation
        # M not safely positive definite at the first state of the run (check_determined): the
        # range-space solve (M⁻¹) is unusable, the whole augmented matrix is solved by LU
        self._full_kkt = False
        self._rho = 0.0  # M + ρAᵀA in the generated solve when M is singular (_augmentation)

    def use_fused(self, fused: FusedKernel) -> bool:
        """Evaluate through ``fused`` from now on, if it works at a random state.

        The test: finite real outputs of ``fused.fn``, and the one-function right-hand side
        (``fused.rfn``, dropped when it disagrees) against the array solve of those outputs.
        (``fn`` and ``vfn`` are compared by the generator.) Only the ``range-space`` solver
        takes it: its generated solve is that algorithm. The template kernels are then not
        generated until something needs them (a general model's ``energy``, ``mass_matrix``).
        """
        if self.solver != "range-space":
            return False
        rng = np.random.default_rng(7)
        t0, q, qd = 0.3, rng.uniform(0.2, 0.9, self.n), rng.uniform(-0.5, 0.5, self.n)
        try:
            v = np.array(fused.fn(t0, *q.tolist(), *qd.tolist(), *self._p))
            if v.dtype.kind != "f" or not np.isfinite(v).all():
                raise ValueError("the fused kernel is not finite and real at the test state")
            self._fused = dataclasses.replace(fused, rfn=None)
            slow = self._reference_solve(t0, q, qd)[0]
            fast = None
            if fused.rfn is not None:
                taus = [0.0] * (self.m + 1)  # no floor
                fast = fused.rfn(*self._p, 0.0, 0.0, *taus, lambda t, y: None)(
                    t0, [*q.tolist(), *qd.tolist()]
                )
        except Exception:  # anything wrong here: keep the template kernels
            self._fused = None
            return False
        if fast is not None and np.allclose(fast[self.n :], slow, rtol=1e-10, atol=1e-13):
            self._fused = fused
        if fused.llvm is not None:  # machine code made before (the on-disk cache): use it now
            compiled = fused.llvm(build=False)
            if compiled is not None:
                self._use_machine(compiled)
        return True

    def _reference_solve(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """q̈, λ by the model's solver, or by LU on the whole augmented matrix where M is
        singular (quaternion coordinates): the reference the generated code is checked against."""
        try:
            return self._solve(t, q, qd)
        except PfaffError:
            K, forcing, _, bias, _, _ = self._kkt(t, q, qd)
            return self._solve_kkt(K, forcing, -bias, t, full=True)

    def compile_machine_code(self) -> bool:
        """Compile (or load from the on-disk cache) the machine code of a small model now, so
        that :meth:`accelerations` uses it from the first call (a simulation compiles it
        anyway); False when the model has none (too large, or SymEngine without LLVM).

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
        >>> isinstance(model.compile_machine_code(), bool)
        True
        """
        fk = self._fused
        if self._machine is not None:
            return True
        if fk is None or fk.llvm is None:
            return False
        compiled = fk.llvm()
        return compiled is not None and self._use_machine(compiled)

    def _use_machine(self, compiled: Callable) -> bool:
        """Evaluate states through the machine code (outputs q̇, q̈, λ, then ``fn``'s outputs)
        once it agrees with ``fn`` and the array solve at a random state."""
        n, m = self.n, self.m
        buf = np.zeros(1 + 2 * n + len(self._p) + 2 + m + 1)
        buf[1 + 2 * n : 1 + 2 * n + len(self._p)] = self._p
        rng = np.random.default_rng(11)
        t0, q, qd = 0.4, rng.uniform(0.2, 0.9, n), rng.uniform(-0.5, 0.5, n)
        fk = self._fused
        try:
            buf[0], buf[1 : 1 + n], buf[1 + n : 1 + 2 * n] = t0, q, qd
            out = np.array(compiled(buf), dtype=float)
            v = np.array(fk.fn(t0, *q.tolist(), *qd.tolist(), *self._p), dtype=float)
            qdd, lam = self._reference_solve(t0, q, qd)
        except Exception:
            return False
        k = 2 * n + m
        ok = out.shape == (k + v.size,) and np.allclose(out[k:], v, rtol=1e-11, atol=1e-13)
        ok = ok and np.allclose(out[n : 2 * n], qdd, rtol=1e-9, atol=1e-12)
        ok = ok and np.allclose(out[2 * n : k], lam, rtol=1e-9, atol=1e-12)
        if ok and _machine_faster(compiled, buf, fk.fn, t0, q, qd, self._p):
            self._machine, self._machine_buf = compiled, buf
        return bool(ok)

    def mass_matrix(
        self, t: float, q: object, qd: object | None = None
    ) -> np.ndarray | sps.csr_matrix:
        """M(q, t), shape (n, n): a dense array when small, else a SciPy CSR matrix."""
        M = super().mass_matrix(t, q, qd)
        return M.toarray() if self.dense else M

    def constraint_matrix(self, t: float, q: object) -> np.ndarray | sps.csr_matrix:
        """A(q, t), shape (m, n): dense when small, else CSR."""
        A = super().constraint_matrix(t, q)
        return A.toarray() if self.dense else A

    def kkt_matrix(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """The symmetric augmented matrix [[M, Aᵀ], [A, 0]] and right-hand side [Q - h; -bias]."""
        t, q, qd = self._state(t, q, qd)
        K, forcing, _, bias, _, _ = self._kkt(t, q, qd)
        check_finite(t, "[[M, Aᵀ], [A, 0]] or its right-hand side", K, forcing, bias)
        return K, np.concatenate([forcing, -bias])

    def _kkt(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """K, Q - h, b, Ȧq̇ + ḃ, f and g = A q̇ + b at an (unchecked) state."""
        n, m = self.n, self.m
        N = n + m
        if self._fused is not None:
            fk = self._fused
            v = self._fused_values(t, q, qd)
            K = np.zeros((N, N))
            K.flat[fk.kkt_index] = v[fk.kkt_source]
            o = fk.offsets
            forcing, bias, b, f = v[o[0] : o[1]], -v[o[1] : o[2]], v[o[2] : o[3]], v[o[3] :]
            return K, forcing, b, bias, f, K[n:, :n] @ qd + b
        mvals, forcing = self._dynamics(t, q, qd)
        avals, b, bias, f = self._constraints(t, q, qd)
        if self._pattern is None:
            self._pattern = KKTPattern(self)
        if self.dense:
            K = self._pattern.dense(mvals, avals)
            g = K[n:, :n] @ qd + b
        else:
            K = self._pattern.assemble(mvals, avals)
            g = b + self.a_matvec(avals, qd)
        return K, forcing, b, bias, f, g

    def _solve_kkt(
        self,
        K: np.ndarray | sps.csc_matrix,
        forcing: np.ndarray,
        c: np.ndarray,
        t: float,
        floor: float = STATE_FLOOR,
        scales: np.ndarray | None = None,
        full: bool | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """q̈ and λ of K [q̈; −λ] = [Q − h; c] by the model's solver (:mod:`pfaff.numeric.kkt`).

        ``full`` (default: the model's mode, set by :meth:`check_determined`): M singular or
        nearly so, where a Cholesky factorization of M may pass on rounding and return garbage:
        LU on the whole K. ``floor`` and ``scales``: the rank-loss floor (``FLOOR`` with row
        scales in integrators, ``STATE_FLOOR`` for single states).
        """
        self.stats["kkt_solves"] += 1
        full = self._full_kkt if full is None else full
        solver = self._lu if full and self.dense else self._solver
        try:
            qdd, lam = solver.solve(KKTSystem(forcing, c, K), floor=floor, scales=scales)
            if isinstance(solver, SparseSolver):
                self.stats["fill"] = solver.fill
        except (np.linalg.LinAlgError, ValueError) as e:
            _check_finite(K, forcing, c, t)
            raise ConstraintError(self._singular_message(t, e)) from None
        if not math.isfinite(qdd.sum() + lam.sum()):  # type: ignore[union-attr]
            _check_finite(K, forcing, c, t)
            raise ConstraintError(self._singular_message(t))
        if floor == STATE_FLOOR and self.dense and self.m:
            self._check_consistent(K[self.n :, : self.n], qdd, c, t)
        return qdd, lam  # type: ignore[return-value]

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
        if self._machine is not None and not (alpha or beta or self._full_kkt):
            self._fused_values(t, q, qd)
            last = self._machine_last
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
        if not self.dense or not self.m or self._full_kkt:
            return None
        K = self._kkt(t, q, qd)[0]
        try:
            return row_scales(K[: self.n, : self.n], K[self.n :, : self.n])
        except np.linalg.LinAlgError:  # M singular: the full augmented matrix is used anyway
            return None

    def ode_function(
        self, alpha: float = 0.0, beta: float = 0.0, start: tuple | None = None
    ) -> AccelerationField:
        """y' = [q̇, q̈] of y = [q, q̇] (Baumgarte-stabilized when α, β > 0), for integrators.

        ``start`` = (t0, q0, q̇0) sets the reference row sizes of the rank-loss floor
        (:mod:`pfaff.numeric.kkt`); None: no floor.
        """
        scales = self._row_scales(*start) if start is not None else None
        return AccelerationField(self, alpha, beta, scales)

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
        mass-metric corrections, on Python floats for small fused systems
        (:class:`pfaff.numeric.fused.FusedLinearization`), else on arrays."""
        fk = self._fused
        if fk is not None and fk.cfn is not None and not self._full_kkt:
            try:
                return FusedLinearization(
                    fk, t, q.tolist(), qd.tolist(), self._p, tol, self._holonomic_list,
                    lambda: self._array_linearization(t, q, qd, tol),
                )  # fmt: skip
            except (ValueError, ArithmeticError, TypeError):
                pass  # not defined or not real here: the array path names the error
        return self._array_linearization(t, q, qd, tol)

    def _array_linearization(
        self, t: float, q: np.ndarray, qd: np.ndarray, tol: float
    ) -> ArrayLinearization:
        K, _, _, _, f, g = self._kkt(t, q, qd)
        n, cache = self.n, []
        A, M = K[n:, :n], K[:n, :n]
        if sps.issparse(K):  # the KKT solve with zero forcing: M⁻¹Aᵀ(A M⁻¹Aᵀ)⁻¹ r by SuperLU
            sq = np.asarray(A.multiply(A).sum(axis=1)).ravel()
            zeros = np.zeros(n)

            def correct(r: np.ndarray) -> np.ndarray:
                return self._solver.solve(KKTSystem(zeros, r, K), multipliers=False)[0]

        else:
            sq = (A * A).sum(1)

            def correct(r: np.ndarray) -> np.ndarray:
                if not cache:
                    cache.append(mass_metric_correction(M, A))
                return cache[0](r)

        f = np.where(self.holonomic, f, 0.0)
        return ArrayLinearization(
            f, g, np.sqrt(sq), tol, correct, correct, lambda v: self.residual(t, q, v)[1]
        )

    def dae_blocks(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """(M, A, Q − h, f, g) at an unchecked state: dense when small, else CSR."""
        K, forcing, _, _, f, g = self._kkt(t, q, qd)
        n = self.n
        if sps.issparse(K):
            K = sps.csr_matrix(K)
        return K[:n, :n], K[n:, :n], forcing, f, g

    @property
    def mass_singular(self) -> bool:
        """True when M was found singular (or nearly) at the last :meth:`check_determined`: the
        augmented system is still regular (quaternion coordinates), but M⁻¹ is not to be used."""
        return self._full_kkt

    def constraint_bias(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Ȧq̇ + ḃ at an unchecked state, shape (m,): A q̈ = −(Ȧq̇ + ḃ) on a motion."""
        return np.asarray(self._kkt(t, q, qd)[3], dtype=float)

    def _fused_rhs(self, alpha: float, beta: float, scales: np.ndarray | None):
        """``rhs(t, y: list) -> list`` of a fused model for given reference row sizes: the fused
        kernel and the generated floored range-space solve in one function; the array path where
        M is not positive definite."""
        n = self.n
        fk = self._fused
        assert fk is not None
        floor = FLOOR if scales is not None else STATE_FLOOR

        def slow(t: float, yl: list) -> list:
            y = np.array(yl)
            qdd = self._solve(t, y[:n], y[n:], alpha, beta, floor=floor, scales=scales)[0]
            return yl[n:] + qdd.tolist()

        if self._full_kkt and self._rho and fk.rfn_aug is not None:  # M singular: M + ρAᵀA
            return fk.rfn_aug(*self._p, alpha, beta, *([0.0] * (self.m + 1)), self._rho, slow)
        if self._full_kkt or fk.rfn is None:
            return slow
        # no reference sizes: no floor (a singular S then takes the array path)
        taus = [0.0] * self.m if scales is None else (FLOOR * np.asarray(scales)).tolist()
        taus.append(FLOOR if scales is not None else 0.0)  # the cap factor
        py = fk.rfn(*self._p, alpha, beta, *taus, slow)
        start = time.process_time()
        compiled = fk.llvm() if fk.llvm is not None else None
        self.timings.setdefault("machine_code", time.process_time() - start)
        if compiled is None:
            return py
        if self._machine is None:
            self._use_machine(compiled)
        machine = _machine_rhs(compiled, py, n, [*self._p, alpha, beta, *taus])
        if self._prefer_machine is None:  # timed once per model, not at every rescaling
            self._prefer_machine = _faster(py, machine, n) is machine
        return machine if self._prefer_machine else py

    def _fused_values(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The fused kernel's flat outputs at a state; non-real values are an error naming t."""
        assert self._fused is not None
        self._machine_last = None
        if self._machine is not None:  # one machine-code call: the outputs, q̈ and λ
            n, m = self.n, self.m
            buf = self._machine_buf
            buf[0], buf[1 : 1 + n], buf[1 + n : 1 + 2 * n] = t, q, qd
            buf[1 + 2 * n : 1 + 2 * n + len(self._p)] = self._p  # (with_parameters copies)
            out = self._machine(buf)
            if np.isfinite(out).all():
                self._machine_last = (t, q.tobytes(), qd.tobytes(), out[n : 2 * n + m])
                return out[2 * n + m :]
        try:
            v = np.array(self._fused.fn(t, *q.tolist(), *qd.tolist(), *self._p))
        except (ValueError, ArithmeticError) as e:  # math domain error, overflow, division by 0
            if isinstance(e, PfaffError) or not raised_in_generated_code(e):
                raise
            raise undefined_at(e, t) from None
        if v.dtype.kind == "c":
            raise StateError(not_real(t))
        return v

    def linearize(
        self,
        t: float,
        q: object,
        qd: object,
        independent: object,
        independent_speeds: object = None,
        inputs: object = (),
        *,
        input_values: Mapping[str, object] | None = None,
    ) -> Linearization:
        """Linearize about the state (q, q̇) at time t: ẋ = A x + B u (numeric).

        The same as :meth:`pfaff.EquationsOfMotion.linearize` with this model's parameter
        values, with exact derivatives (differentiated and generated into code once, on the
        first call; then numeric work only); the coordinates of ``independent`` and
        ``independent_speeds`` and the ``inputs`` (parameters) may be given by name.
        ``input_values`` (input name -> value) sets inputs declared with ``System.add_input``
        for this call only; one left out keeps the model's value (0 unless compiled with one).
        See :func:`pfaff.numeric.linearization.linearize_model`.

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
        >>> model.linearize(0.0, [0.0], [0.0], ["theta"]).A
        array([[ 0.  ,  1.  ],
               [-9.81,  0.  ]])
        """
        return linearize_model(
            self, t, q, qd, independent, independent_speeds, inputs, input_values
        )

    def accelerations(self, t: float, q: object, qd: object) -> tuple[np.ndarray, np.ndarray]:
        """Solve M q̈ + h = Q + Aᵀλ, A q̈ + Ȧq̇ + ḃ = 0 for q̈ (shape (n,)) and λ (shape (m,)).

        Examples
        --------
        >>> import numpy as np, pfaff
        >>> sys = pfaff.models.rolling_ring(8, force=True)
        >>> model = sys.equations().compile({"M": 1, "r": 0.5, "F": 2})
        >>> q, qd = pfaff.models.ring_state(8, radius=0.5, theta=0.3)
        >>> qdd, lam = model.accelerations(0.0, q, qd)
        >>> round(float(qdd[1]), 12), round(float(lam[0]), 12)
        (2.0, -1.0)

        Raises
        ------
        InertiaError
            Some acceleration is undetermined here (a coordinate without inertia that no
            constraint fixes) or M is not positive definite on the admissible motions.
        ConstraintError
            The constraints are inconsistent here.
        StateError
            A bad state, or equations not defined at it (an overflow, a math domain error).
        """
        t, q, qd = self._state(t, q, qd)
        if not self.dense:
            try:
                return self.solve(t, q, qd)
            except ConstraintError:
                self.check_determined(t, q, qd)  # the precise error when M is the cause
                raise
        K, forcing, _, bias, _, _ = self._kkt(t, q, qd)
        full = self._inertia(K, t)
        last = self._machine_last
        if not full and last is not None and last[0] == t and last[1] == q.tobytes():
            if last[2] == qd.tobytes():  # the machine code solved this state with _kkt
                self._machine_last = None
                return last[3][: self.n].copy(), last[3][self.n :].copy()
        return self._solve_kkt(K, forcing, -bias, t, full=full)

    def check_determined(self, t: float, q: object, qd: object) -> None:
        """Check that M is positive definite on the admissible velocities at a state.

        With Z an orthonormal basis of null(A), ZᵀMZ must be positive definite: else some
        acceleration is undetermined (a coordinate without inertia that no constraint fixes) or
        the kinetic energy is negative along an admissible motion. M itself may be singular
        (quaternion attitude coordinates are, along the quaternion) as long as the constraints
        fix what M leaves free; the model then solves the whole augmented matrix by LU (its
        mode until the next check). Run once per simulation (its first state) and by
        :meth:`accelerations`, never in the right-hand side: dense models pay one Cholesky
        factorization of M when M is safely positive definite, and an SVD of A and an
        eigenvalue decomposition of ZᵀMZ only when it is not. Sparse models (n + m >
        ``DENSE_LIMIT``) get the O(nnz) part of the test only: coordinates with neither a mass
        entry nor a constraint entry (SuperLU fails on any other exactly singular K). Then one
        solve: no acceleration may satisfy the constraints here.

        Raises
        ------
        InertiaError
            Naming the coordinates that span the undetermined (or negative) directions.
        ConstraintError
            The constraints are inconsistent at this state.
        """
        t, q, qd = self._state(t, q, qd)
        n, K = self.n, self._kkt(t, q, qd)[0]
        if not self.dense:
            Kc = sps.csc_matrix(K)
            Kc.eliminate_zeros()
            free = np.flatnonzero(np.diff(Kc.indptr)[:n] == 0)  # a column of zeros in M and A
            if free.size:
                raise InertiaError(self._undetermined_message(t, free))
        else:
            self._full_kkt = False  # the test below may raise: no stale mode left behind
            self._full_kkt = self._inertia(K, t)
            self._rho = self._augmentation(K, t, q, qd) if self._full_kkt else 0.0
        if self.m:
            self.solve(t, q, qd)

    def _augmentation(self, K: np.ndarray, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """ρ of the generated solve with M + ρAᵀA (``rfn_aug``) for a singular M, checked
        against the LU solve of the whole augmented matrix at this state; 0 when unusable."""
        fk, n = self._fused, self.n
        if fk is None or fk.rfn_aug is None or not self.m:
            return 0.0
        M, A = K[:n, :n], K[n:, :n]
        rho = augmentation_weight(M, A)
        try:
            fn = fk.rfn_aug(*self._p, 0.0, 0.0, *([0.0] * (self.m + 1)), rho, lambda t, y: None)
            fast = fn(t, [*q.tolist(), *qd.tolist()])
            slow = self._solve(t, q, qd)[0]
        except Exception:
            return 0.0
        if fast is None or not np.allclose(fast[n:], slow, rtol=1e-9, atol=1e-12):
            return 0.0
        return rho

    def _inertia(self, K: np.ndarray, t: float) -> bool:
        """The test of :meth:`check_determined` on a dense K: True when M is not safely definite.

        "Safely": every pivot of the Cholesky factorization of M above ``M_PIVOT`` times the
        largest diagonal entry; a singular M passes LAPACK's test with pivots of rounding size.
        """
        n = self.n
        if not np.isfinite(K).all():
            return False  # NaN or infinity: a StateError of the solve, not a question of inertia
        # Jacobi scaling (velocities u = D q̇, D = √diag M): the test is then independent of the
        # units, so 1 µg beside 1000 kg is not "no inertia"; a zero diagonal stays unscaled
        diag = np.diag(K[:n, :n]).copy()
        d = np.where(diag > 1e-300, np.sqrt(np.abs(diag)), 1.0)
        M = K[:n, :n] / d[:, None] / d[None, :]
        A = K[n:, :n] / d[None, :]
        U, info = _potrf(M)
        if info == 0 and np.diag(U).min() ** 2 > M_PIVOT * np.diag(M).max():
            return False  # positive definite: so is ZᵀMZ
        Z = scipy.linalg.null_space(A) if self.m else np.eye(n)
        if Z.shape[1] == 0:  # the constraints fix every acceleration
            return True
        H = Z.T @ M @ Z
        w, V = np.linalg.eigh(0.5 * (H + H.T))
        tol = 1e-12 * max(np.abs(w).max(), np.abs(np.diag(M)).max(), np.finfo(float).tiny)
        bad = w <= tol
        if not bad.any():
            return True
        U = np.abs((Z @ V[:, bad]) / d[:, None])  # the offending directions in coordinates
        coords = np.flatnonzero((U >= 1e-6 * U.max(axis=0)).any(axis=1))
        if (w[bad] < -tol).any():
            raise InertiaError(
                f"M is not positive definite on the admissible motions at t = {t:.17g}: the "
                f"kinetic energy is negative along a motion of {self._coordinate_list(coords)} "
                f"(eigenvalue {w.min():.3g} of ZᵀMZ); check the masses and kinetic-energy terms"
            )
        raise InertiaError(self._undetermined_message(t, coords))

    def _coordinate_list(self, idx: np.ndarray) -> str:
        names = ", ".join(f"`{self.coordinate_names[i]}`" for i in idx[:8])
        return names + (f" and {idx.size - 8} more" if idx.size > 8 else "")

    def _undetermined_message(self, t: float, idx: np.ndarray) -> str:
        return (
            f"the acceleration of {self._coordinate_list(idx)} is undetermined at t = {t:.17g}: "
            "no inertia and no constraint fixes it (M is singular on the admissible motions). "
            "Give it a mass or kinetic energy, or constrain it"
        )

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
        if self._fused is not None and not self._full_kkt:  # (a batched Cholesky of M)
            try:
                return self._fused_states(t, q, qd)
            except (np.linalg.LinAlgError, ConstraintError):
                pass  # a redundant configuration somewhere: state by state below
        return super().evaluate_states(t, q, qd)

    def _fused_states(self, t: np.ndarray, q: np.ndarray, qd: np.ndarray) -> dict[str, np.ndarray]:
        fk, k, n, N = self._fused, len(t), self.n, self.n + self.m
        assert fk is not None
        args = [t, *q.T, *qd.T, *self._p]
        vals = np.empty((k, fk.offsets[3] + self.m))
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
            raise ConstraintError(self._singular_message(float(t[0])))
        g = np.einsum("kij,kj->ki", K[:, n:, :n], qd) + vals[:, o[2] : o[3]]
        T, V, T0 = (np.broadcast_to(e, (k,)).astype(float) for e in fk.efn(*args))
        Tneg = np.broadcast_to(fk.efn(t, *q.T, *(-qd).T, *self._p)[0], (k,))
        T2 = 0.5 * (T + Tneg) - T0
        self.stats["kkt_solves"] += k
        return {
            "qdd": qdd,
            "multipliers": lam,
            "f": vals[:, o[3] :],
            "g": g,
            "T": T,
            "V": V,
            "T0": T0,
            "T2": T2,
        }

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

    # ------------------------------------------------------------------ other parameter values
    # set by the compile stage (pfaff.derive.compile.Restream): the template stream parts for new
    # values, restream(old values, new values, dyn, con) -> (dyn, con); None: values are fixed
    _restream: Callable[[list, list, list, list], tuple[list, list]] | None = None

    def with_parameters(self, values: Mapping[str, float]) -> NumericModel:
        """This compiled model with other parameter values: nothing derived or generated again.

        Parameters
        ----------
        values : mapping of str to float
            New values by parameter name; the parameters not named keep theirs.

        Returns
        -------
        NumericModel
            A new model sharing this one's compiled code (this one is unchanged).

        Notes
        -----
        The fused kernel of a small system and its machine code take the parameter values at
        run time: they are shared as they are (about 20 µs for the whole call). The template
        kernels fold the values into their code, so the templates whose expressions use a
        changed parameter get new kernels, generated on first use only (a few milliseconds
        each): a fused model uses them for the power of its applied forces (the energy
        balance), for the inertia check's fallback and for explicit calls such as
        :meth:`mass_matrix` of large systems. Particle masses are not checked again here: the
        inertia check at the first state of a simulation refuses a mass that is not positive.

        Raises
        ------
        ParameterError
            An unknown name, or a value that is not a finite real number.

        Examples
        --------
        >>> import numpy as np, pfaff
        >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
        >>> heavy = model.with_parameters({"m": 3})
        >>> lam = heavy.accelerations(0.0, np.array([0.0, -2.0]), np.zeros(2))[1]
        >>> round(float(-2 * 2 * lam[0]), 12), model.parameters["m"]  # tension m g; m unchanged
        (29.43, 1.0)
        """
        new = {**self.parameters}
        problems = []
        for name, v in values.items():
            if name not in new:
                problems.append(f"unknown parameter `{name}` (the model's: {', '.join(new)})")
            elif isinstance(v, bool | str | bytes | complex) or np.ndim(v) != 0:
                problems.append(f"parameter `{name}` must be a real number, got {v!r:.80}")
            elif not math.isfinite(v := float(v)):  # type: ignore[arg-type]
                problems.append(f"parameter `{name}` is {v} (NaN or infinite)")
            else:
                new[name] = v
        if problems:
            raise ParameterError("bad parameters: " + "; ".join(problems))
        p = list(new.values())
        if p != self._p and self._restream is None:
            raise ModelTypeError("this model was not compiled with a way to change its parameters")
        dyn, con = self.dyn, self.con
        if p != self._p:  # new kernels for the templates that use a changed value
            dyn, con = self._restream(self._p, p, dyn, con)  # type: ignore[misc]
        model = NumericModel(
            self.n, self.m, dyn, con, coordinate_names=self.coordinate_names,
            multiplier_names=self.multiplier_names, constraint_names=self.constraint_names,
            holonomic=self.holonomic, parameters=new, solver=self.solver,
        )  # fmt: skip
        model.attitudes, model._restream = self.attitudes, self._restream
        model.inputs = list(getattr(self, "inputs", []))
        model.linearizer = getattr(self, "linearizer", None)  # it takes the values at each call
        model.timings = dict(self.timings)
        model._fused, model._prefer_machine = self._fused, self._prefer_machine  # shared code
        if self._machine is not None:  # checked once: its buffer takes the values at each call
            model._machine, model._machine_buf = self._machine, self._machine_buf.copy()
        geometry = getattr(self, "geometry", None)  # what animations draw (derive.geometry)
        model.geometry = geometry.with_parameters(new) if geometry is not None else None
        return model


def _check_finite(
    K: np.ndarray | sps.spmatrix, forcing: np.ndarray, c: np.ndarray, t: float
) -> None:
    """A NaN or infinity in M, A, Q - h or Ȧq̇ + ḃ is a state error (an overflow), not a singular K."""
    check_finite(t, "[[M, Aᵀ], [A, 0]], Q - h or Ȧq̇ + ḃ", K, forcing, c)


def not_real(t: float) -> str:
    return (
        f"the equations are not real at t = {t:.17g}: a fractional power of a negative value "
        "(write it with sqrt, cbrt or Abs where the model allows)"
    )


class AccelerationField(OdeFunction):
    """y' = [q̇, q̈] of a :class:`NumericModel` for the integrators, with the rank-loss floor.

    Small fused systems get the generated right-hand side (a few microseconds per call) and
    :attr:`on_lists`, the same function on lists of floats (:mod:`pfaff.integrate.fastrk`).
    A non-finite q̈ raises :class:`StateError` naming the time.

    The floor's reference row sizes (:mod:`pfaff.numeric.kkt`) are kept current: a row that
    starts (nearly) collapsed, a linkage released from a flat configuration, has no size of its
    own yet; while any row is below ``RESCALE_BELOW`` of the largest, the sizes at each accepted
    step raise the references (a running maximum) and the right-hand side is rebuilt.
    """

    def __init__(
        self, model: NumericModel, alpha: float, beta: float, scales: np.ndarray | None
    ) -> None:
        self.model, self.alpha, self.beta = model, alpha, beta
        self.scales = None if scales is None else np.asarray(scales, dtype=float)
        self.active = self.scales is not None and self._small_rows()
        self._rhs: list = []  # [rhs(t, y: list) -> list] of a fused model, replaced on rescaling
        if model._fused is not None:
            self._rhs.append(model._fused_rhs(alpha, beta, self.scales))
            self.on_lists = _checked_lists(self._rhs)

    def _small_rows(self) -> bool:
        ref = self.scales
        return ref is not None and bool((ref < RESCALE_BELOW * ref.max()).any())

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        if self.on_lists is not None:
            return np.array(self.on_lists(t, y.tolist()))
        n = self.model.n
        out = np.empty(2 * n)
        out[:n] = y[n:]
        m = self.model
        out[n:] = m._solve(t, y[:n], y[n:], self.alpha, self.beta, floor=FLOOR, scales=self.scales)[
            0
        ]
        if not math.isfinite(out.sum()):
            raise StateError(f"the accelerations are NaN or infinite at t = {t:.17g}")
        return out

    def accepted(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        """Raise the reference row sizes to those at (t, q, q̇) while some row is small."""
        if not self.active or self.scales is None:
            return
        now = self.model._row_scales(t, q, qd)
        if now is None:
            return
        new = np.maximum(self.scales, now)
        if (new > self.scales).any():
            self.scales = new
            if self._rhs:
                self._rhs[0] = self.model._fused_rhs(self.alpha, self.beta, new)
        self.active = self._small_rows()


def _checked_lists(rhs: list) -> Callable[[float, list], list]:
    """``rhs[0]`` with its result checked: finite and real (a closure: the hot path of small systems)."""
    isfinite = math.isfinite

    def on_lists(t: float, yl: list) -> list:
        out = rhs[0](t, yl)
        try:
            finite = isfinite(sum(out))
        except TypeError:  # a complex number: a fractional power of a negative value
            raise StateError(not_real(t)) from None
        if not finite:
            raise StateError(f"the accelerations are NaN or infinite at t = {t:.17g}")
        return out

    return on_lists


def _machine_rhs(compiled: Callable, py: Callable, n: int, fixed: list) -> Callable:
    """The machine-code right-hand side on lists, ``py`` (the generated Python) where it gives
    anything non-finite (M not positive definite, a value out of its domain: ``py`` then takes
    the slow path or names the error). The compiled function's first 2n outputs are [q̇, q̈]."""
    buf = np.empty(1 + 2 * n + len(fixed))
    buf[1 + 2 * n :] = fixed
    isfinite = math.isfinite
    k = 2 * n

    def rhs(t: float, yl: list) -> list:
        buf[0] = t
        buf[1 : 1 + 2 * n] = yl
        out = compiled(buf)[:k].tolist()
        return out if isfinite(sum(out)) else py(t, yl)

    return rhs


def _machine_faster(
    compiled: Callable,
    buf: np.ndarray,
    fn: Callable,
    t: float,
    q: np.ndarray,
    qd: np.ndarray,
    p: list,
) -> bool:
    """Whether one machine-code call (q̈ and λ too) beats the generated Python kernel alone at a
    state: it does from a few coordinates on; on a pendulum the call's overhead rules."""
    args = [t, *q.tolist(), *qd.tolist(), *p]
    best = []
    for call in (lambda: fn(*args), lambda: compiled(buf)):
        call()
        start = time.perf_counter()
        for _ in range(50):
            call()
        best.append(time.perf_counter() - start)
    return best[1] < best[0]


def _faster(a: Callable, b: Callable, n: int) -> Callable:
    """Whichever of two equal right-hand sides is faster, timed at a state (machine code wins
    from a few coordinates on; Python's generated code below, where a call's overhead rules)."""
    yl = [0.3 + 0.01 * i for i in range(2 * n)]
    best = []
    for fn in (a, b):
        try:
            fn(0.1, yl)
            start = time.perf_counter()
            for _ in range(50):
                fn(0.1, yl)
            best.append(time.perf_counter() - start)
        except Exception:
            best.append(math.inf)
    return b if best[1] < best[0] else a
