"""The numeric model over template streams: :class:`StreamModel`, the base of both model kinds.

:class:`pfaff.numeric.structured.StructuredModel` (families) and :class:`pfaff.NumericModel` (any
system) extend it. A compiled model is a value: built once by the compile stage, immutable
afterwards (:meth:`StreamModel.__setattr__` refuses), picklable. What changes during a run (the
KKT mode, counters, scratch arrays, the inputs' values) lives in a run copy
(:meth:`StreamModel.for_run`), never in the user's model.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Self

import numpy as np
import scipy.sparse as sps

from pfaff.core.errors import ConstraintError, ModelTypeError, StateError
from pfaff.core.lazy import NumberedNames
from pfaff.numeric.checks import check_finite, check_state
from pfaff.numeric.ggl import GGLNewton
from pfaff.numeric.kkt import KKTSolver, KKTSystem, SparseSolver
from pfaff.numeric.parts import ConStreams, DynStreams
from pfaff.numeric.pattern import KKTPattern, coo
from pfaff.numeric.projection import ArrayLinearization, thresholds
from pfaff.numeric.protocol import ConstraintLinearization, OdeFunction
from pfaff.numeric.quantities import Quantities
from pfaff.numeric.streams import add_product, fill_at, scatter_add, take
from pfaff.numeric.value import ModelValue


class StreamModel(Quantities, ModelValue):
    """The numeric model of any system over template streams: the shared part of both kinds.

    Evaluation (M, Q − h, A, b, Ȧq̇ + ḃ, f, energies, power) runs the template kernels
    (:class:`pfaff.numeric.kernel.StreamKernel`) over index progressions or index arrays;
    every checked method of :class:`pfaff.numeric.protocol.DynamicsModel` is here, and the
    unchecked ones with the KKT solver a subclass chooses (``self._solver``):
    :class:`StructuredModel` (families) and :class:`pfaff.NumericModel` (any system).
    """

    solver: str
    _solver: KKTSolver

    def __init__(
        self,
        n: int,
        m: int,
        dyn: list[DynStreams],
        con: list[ConStreams],
        *,
        coordinate_names: Sequence[str],
        constraint_names: Sequence[str],
        holonomic: np.ndarray,
        parameters: dict[str, float],
        multiplier_names: Sequence[str] | None = None,
        inputs: Sequence[str] = (),
        attitudes: Sequence[tuple[str, str, tuple[int, ...], str]] = (),
        events: Sequence[object] = (),
        contacts: object = None,
        geometry: object = None,
        linearizer: object = None,
        restream: Callable | None = None,
        timings: dict | None = None,
    ) -> None:
        self.n, self.m = n, m
        self.coordinate_names = coordinate_names
        self.multiplier_names = multiplier_names or NumberedNames([], [("lambda", 1, m)])
        self.constraint_names = constraint_names
        self.holonomic = np.asarray(holonomic, dtype=bool).reshape(self.m)
        self.parameters = dict(parameters)
        self.dyn, self.con = dyn, con  # the blocks, read by the solvers
        self.stats: dict = {"kkt_solves": 0}
        self._tmp: np.ndarray | None = None
        self._zero: np.ndarray | None = None
        self._force: np.ndarray | None = None
        self._pattern: KKTPattern | None = None
        self._names = coordinate_names if isinstance(coordinate_names, list) else None
        self.inputs = list(inputs)  # declared inputs (System.add_input), by name
        # per rigid body: (name, attitude kind, coordinate indices, Euler sequence); see
        # pfaff.integrate.events (MRP switching, the Euler-angle singularity)
        self.attitudes = tuple(attitudes)
        # the events declared on the system (System.add_event), compiled: objects with name,
        # direction, terminal, fn(t, q, qd) and with_parameters(values) (pfaff.derive.events)
        self.events = tuple(events)
        # the unilateral constraints (System.add_unilateral_constraint): None, or the models a
        # contact run switches between (pfaff.derive.contacts.CompiledContacts)
        self.contacts = contacts
        self.geometry = geometry  # what animations draw (pfaff.derive.geometry), or None
        # the linearization's kernel factory (pfaff.derive.linearize), or None
        self.linearizer = linearizer
        # restream(old values, new values, dyn, con) -> (dyn, con): the stream parts for other
        # parameter values (pfaff.derive.compile.Restream); None: the values are fixed
        self._restream = restream
        self.timings: dict[str, float | str] = dict(timings or {})

    events: tuple = ()  # (a model pickled before events were carried)
    contacts: object = None  # (likewise, before contacts)
    evaluator = "template"  # (general models choose theirs: pfaff.numeric.evaluator)
    mass_singular = False  # (a general model's run finds it at its first state)
    sparse_dae = False  # IDA's Newton matrix: dense (families: the sparse one of dae_newton)

    @property
    def dae_model(self) -> Self:
        """The model whose constraint rows the DAE method keeps: this one (a family may leave
        out a row dependent on the others:
        :attr:`pfaff.numeric.structured.StructuredModel.dae_model`)."""
        return self

    def compile_machine_code(self) -> bool:
        """False: this model evaluates with its template kernels (no machine code)."""
        return False

    def linearize(self, *args: object, **kwargs: object) -> object:
        """Refused: only general models linearize (:meth:`pfaff.NumericModel.linearize`)."""
        raise ModelTypeError(
            "models with families cannot linearize yet: compile the system without families "
            "(pfaff.models.rolling_ring(N, family=False)) to linearize it"
        )

    def _fresh_run_parts(self) -> None:
        d = self.__dict__
        d["_tmp"], d["_zero"], d["_force"] = None, None, None  # scratch arrays: a run's own

    def _unpickled(self) -> set[str]:
        return super()._unpickled() | {"_tmp", "_zero", "_force", "_pattern"}

    def _restored(self) -> None:
        for k in ("_tmp", "_zero", "_force", "_pattern"):
            object.__setattr__(self, k, None)

    # ------------------------------------------------------------------ validation
    def _state(self, t: float, q: object, qd: object) -> tuple[float, np.ndarray, np.ndarray]:
        return check_state(t, q, qd, self.n, self._names)

    # ------------------------------------------------------------------ raw evaluation
    def _dynamics(
        self, t: float, q: np.ndarray, qd: np.ndarray, f: np.ndarray | None = None
    ) -> tuple[list, np.ndarray]:
        """Mass-entry values per block and the forcing vector Q - h (into ``f`` when given,
        shape (n,): the run's buffer, zero except where the blocks write, which are cleared)."""
        mvals = []
        if f is None:
            f = np.zeros(self.n)
        else:
            for part in self.dyn:
                for ix in part.forcing:
                    fill_at(f, ix, 0.0)
        for part in self.dyn:
            outs = part.kernel(t, q, qd)
            nm = len(part.upper)
            mvals.append(outs[:nm])
            for ix, v, total in zip(part.forcing, outs[nm:], part.summed, strict=True):
                if total:
                    f[ix.start] += v
                else:
                    scatter_add(f, ix, v)
        return mvals, f

    def _constraints(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """A-entry values per block, and b, Ȧq̇ + ḃ and f as vectors (m,): all of them at once."""
        avals, rows = [], np.zeros((3, self.m))  # b, bias, f
        for part in self.con:
            outs = part.res(t, q, qd)
            na = len(part.cols)
            avals.append(outs[:na])
            for i in (0, 1, 2):
                val = outs[na + i]
                if type(val) is not float or val != 0.0:
                    scatter_add(rows[i], part.rows, val)
        return avals, rows[0], rows[1], rows[2]

    def _accel_constraints(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[list, list]:
        """A-entry values per block and bias (Ȧq̇ + ḃ) per block."""
        avals, bias = [], []
        for part in self.con:
            outs = part.acc(t, q, qd)
            avals.append(outs[:-1])
            bias.append(outs[-1])
        return avals, bias

    def matvec(
        self, mvals: list, v: np.ndarray, out: np.ndarray | None = None, add: bool = False
    ) -> np.ndarray:
        """M v from evaluated (upper-triangle) mass entries; ``add``: out += M v.

        Entries given as the number 0 are skipped (see ``varying_mass``).
        """
        y = np.zeros(self.n) if out is None else out
        if out is not None and not add:
            y.fill(0.0)
        tmp = self.scratch()
        for part, vals in zip(self.dyn, mvals, strict=True):
            for (r, c, sym), val in zip(part.upper, vals, strict=True):
                if np.ndim(val) == 0 and val == 0:
                    continue
                add_product(y, r, val, take(c, v), tmp)
                if sym:
                    add_product(y, c, val, take(r, v), tmp)
        return y

    def scratch(self) -> np.ndarray:
        if self._tmp is None:
            counts = [part.kernel.count for part in self.dyn] + [p.acc.count for p in self.con]
            object.__setattr__(self, "_tmp", np.empty(max(counts, default=0)))
        return self._tmp  # type: ignore[return-value]

    def a_matvec(self, avals: list, v: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """A v from evaluated constraint entries."""
        y = np.zeros(self.m) if out is None else out
        for part, vals in zip(self.con, avals, strict=True):
            for c, val in zip(part.cols, vals, strict=True):
                scatter_add(y, part.rows, np.multiply(val, take(c, v)))
        return y

    def _rows_vector(self, per_block: list) -> np.ndarray:
        out = np.zeros(self.m)
        for part, v in zip(self.con, per_block, strict=True):
            scatter_add(out, part.rows, v)
        return out

    # ------------------------------------------------------------------ public evaluation
    def forcing(self, t: float, q: object, qd: object) -> np.ndarray:
        """Q - h, shape (n,)."""
        t, q, qd = self._state(t, q, qd)
        out = self._dynamics(t, q, qd)[1]
        check_finite(t, "Q - h", out)
        return out

    def mass_matrix(self, t: float, q: object, qd: object | None = None) -> sps.csr_matrix:
        """M(q, t) as a SciPy CSR matrix, shape (n, n)."""
        t, q, qd = self._state(t, q, np.zeros(self.n) if qd is None else qd)
        M = self._mass(self._dynamics(t, q, qd)[0])
        check_finite(t, "M", M)
        return M

    def _mass(self, mvals: list) -> sps.csr_matrix:
        pairs = [rc for part in self.dyn for rc in part.mass]
        vals = [v for part, vs in zip(self.dyn, mvals, strict=True) for v in part.mass_values(vs)]
        return coo(pairs, vals, (self.n, self.n)).tocsr()

    def _jacobian(self, avals: list) -> sps.csr_matrix:
        pairs = [(part.rows, c) for part in self.con for c in part.cols]
        vals = [v for vs in avals for v in vs]
        return coo(pairs, vals, (self.m, self.n)).tocsr()

    def constraint_matrix(self, t: float, q: object) -> sps.csr_matrix:
        """A(q, t) as a SciPy CSR matrix, shape (m, n)."""
        t, q, qd = self._state(t, q, np.zeros(self.n))
        A = self._jacobian(self._accel_constraints(t, q, qd)[0])
        check_finite(t, "A", A)
        return A

    def residual(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unchecked (f, A q̇ + b), each shape (m,)."""
        f, g = np.zeros(self.m), np.zeros(self.m)
        tmp = self.scratch()
        for part in self.con:
            outs = part.res(t, q, qd)
            na = len(part.cols)
            for c, val in zip(part.cols, outs[:na], strict=True):
                add_product(g, part.rows, val, take(c, qd), tmp)
            for out, val in ((g, outs[na]), (f, outs[na + 2])):
                if np.ndim(val) or val != 0.0:
                    scatter_add(out, part.rows, val)
        return f, g

    def constraint_residual(self, t: float, q: object, qd: object) -> tuple[np.ndarray, np.ndarray]:
        """Position residuals f(q,t) (0 for velocity constraints) and velocity residuals A q̇ + b."""
        t, q, qd = self._state(t, q, qd)
        f, g = self.residual(t, q, qd)
        check_finite(t, "the constraint residual", f, g)
        return f, g

    # ------------------------------------------------------------------ solves
    def solve(
        self, t: float, q: np.ndarray, qd: np.ndarray, alpha: float = 0.0, beta: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Unchecked q̈, λ with the constraint rows' right-hand side -(Ȧq̇ + ḃ) - 2αg - β²f
        (:class:`pfaff.numeric.protocol.DynamicsModel`)."""
        return self._solve(t, q, qd, alpha, beta)  # type: ignore[return-value]

    def _solve(
        self,
        t: float,
        q: np.ndarray,
        qd: np.ndarray,
        alpha: float = 0.0,
        beta: float = 0.0,
        out: np.ndarray | None = None,
        multipliers: bool = True,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        # q̈ written in place (a run's right-hand side): the forcing vector in the run's buffer
        mvals, f = self._dynamics(t, q, qd, None if out is None else self._forcing_buffer())
        avals, bias = self._accel_constraints(t, q, qd)
        view, solved_avals, solved_bias = self._solved_rows(avals, bias)
        zero = all(np.ndim(b) == 0 and b == 0 for b in solved_bias)
        c = None if zero else -view._rows_vector(solved_bias)
        if alpha or beta:
            fr, g = self.residual(t, q, qd)
            mv = view.m  # (a left-out row is the last one)
            c = (np.zeros(mv) if c is None else c) - 2 * alpha * g[:mv] - beta**2 * fr[:mv]
        self.stats["kkt_solves"] += 1
        qdd, lam = self._solver.solve(
            view._system(mvals, f, solved_avals, c), out=out, multipliers=multipliers
        )
        if isinstance(self._solver, SparseSolver):
            self.stats["fill"] = self._solver.fill
        if multipliers and lam is not None and view is not self:
            lam = self._all_multipliers(lam, avals)
        return qdd, lam

    def _solved_rows(self, avals: list, bias: list) -> tuple[StreamModel, list, list]:
        """The model whose rows the solve uses and their entries: this one and all of them (a
        family model may leave out a row that depends on the others,
        :class:`pfaff.numeric.structured.StructuredModel`)."""
        return self, avals, bias

    def _all_multipliers(self, lam: np.ndarray, avals: list) -> np.ndarray:
        """λ over every row from the solved rows' λ (where :meth:`_solved_rows` left one out)."""
        return lam

    def _system(self, mvals: list, f: np.ndarray, avals: list, c: np.ndarray | None) -> KKTSystem:
        """The KKT system in the solver's form: streams, or K assembled for SuperLU."""
        if self._pattern is None:
            return KKTSystem(f, c, mvals=mvals, avals=avals)
        return KKTSystem(f, c, K=self._pattern.assemble(mvals, avals))

    def ode_function(
        self, alpha: float = 0.0, beta: float = 0.0, start: tuple | None = None
    ) -> OdeFunction:
        """y' = [q̇, q̈] of y = [q, q̇] for the integrators: q̈ written in place, no λ.

        ``start`` is not used: these solvers have no rank-loss floor.
        """
        return _StreamField(self, alpha, beta)

    def linearize_constraints(
        self, t: float, q: np.ndarray, qd: np.ndarray, tol: float
    ) -> ConstraintLinearization:
        """f, g, the row norms of A and the mass-metric correction M⁻¹Aᵀ(AM⁻¹Aᵀ)⁻¹r: the KKT
        solve with zero forcing, O(N) like every solve (:mod:`pfaff.numeric.projection`)."""
        f, g = self.residual(t, q, qd)
        avals, _ = self._accel_constraints(t, q, qd)
        view, solved, _ = self._solved_rows(avals, [0.0] * len(avals))
        mv = view.m  # a left-out row (the closed ring's last) is the last one: its residual
        # follows from the others' where they hold, so the correction is the kept rows'

        mvals: list = []  # M's entries, evaluated by the first correction: a state that
        # passes the tests (most states a run projects) needs no kernel pass of the dynamics

        def correct(r: np.ndarray) -> np.ndarray:
            if not mvals:
                mvals.append(self._dynamics(t, q, qd)[0])
            system = view._system(mvals[0], self._zeros(), solved, r[:mv])
            return self._solver.solve(system, multipliers=False)[0]

        if not self.holonomic.all():
            f = np.where(self.holonomic, f, 0.0)
        return ArrayLinearization(
            f, g, None, tol, correct, correct, lambda v: self.residual(t, q, v)[1],
            thr=self._row_thresholds(avals, tol),
        )  # fmt: skip

    def _row_thresholds(self, avals: list, tol: float) -> np.ndarray:
        """The projection's per-row thresholds from the row norms of A (evaluated entries
        ``avals``), :func:`pfaff.numeric.projection.thresholds`; kept by the model
        (:meth:`derived`) where every entry of A is a constant (the ring's: six passes over
        m-long arrays less per step)."""

        def made() -> np.ndarray:
            sq = np.zeros(self.m)
            for part, vals in zip(self.con, avals, strict=True):
                for val in vals:
                    scatter_add(sq, part.rows, np.multiply(val, val))
            thr = thresholds(np.sqrt(sq), tol)
            thr.flags.writeable = False  # (shared by the runs where A is constant)
            return thr

        constant = self.derived(("constant A", self.m), lambda: all(
            c is not None for p in self.con for c in p.acc.const[: len(p.cols)]
        ))  # fmt: skip
        return self.derived(("row thresholds", self.m, tol), made) if constant else made()

    def dae_blocks(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """(M, A, Q − h, f, g) at an unchecked state, M and A assembled as CSR (one pass of
        each kernel: A, b and f from the same constraint kernel)."""
        mvals, forcing = self._dynamics(t, q, qd)
        avals, b, _, f = self._constraints(t, q, qd)
        A = self._jacobian(avals)
        return self._mass(mvals), A, forcing, f, b + A @ qd

    def dae_newton(
        self, hrows: np.ndarray, t: float, y: np.ndarray, yp: np.ndarray,
        algebraic_scale: float = 1.0,
    ) -> GGLNewton:  # fmt: skip
        """The stabilized index-2 residual over the streams and its sparse Newton matrix
        (:class:`pfaff.numeric.ggl.GGLNewton`), its pattern made at the state (t, y, y') the
        first time a model is asked (then shared by its runs)."""
        return GGLNewton(self, hrows, t, y, yp, algebraic_scale=algebraic_scale)

    def evaluate_states(
        self, t: np.ndarray, q: np.ndarray, qd: np.ndarray
    ) -> dict[str, np.ndarray]:
        """What a trajectory reports at k states: q̈, λ, f, g, T, V, T(q, 0, t) and T₂.

        Parameters
        ----------
        t : ndarray, shape (k,)
        q, qd : ndarray, shape (k, n)

        Returns
        -------
        dict
            ``qdd`` (k, n), ``multipliers`` (k, m) (NaN at a state where the augmented matrix is
            singular: a run may pass through one, where a constraint's gradient vanishes),
            ``f`` and ``g`` (k, m), and (k,) arrays ``T``,
            ``V``, ``T0`` = T(q, 0, t) and ``T2`` (the part of T quadratic in q̇). One kernel pass
            per state for the energies (T, V, T₀ and T₂ together). ``f`` and ``g`` are views of
            ``residual`` (k, 2, m), the layout of ``Trajectory.constraint_residual``, so that a
            caller can keep it without a copy.
        """
        t = np.asarray(t, dtype=float)
        k = len(t)
        out = {"qdd": np.empty((k, self.n)), "multipliers": np.empty((k, self.m))}
        out["residual"] = np.empty((k, 2, self.m))  # f and g below are views of it
        out["f"], out["g"] = out["residual"][:, 0], out["residual"][:, 1]
        out |= {key: np.zeros(k) for key in ("T", "V", "T0", "T2")}
        for i in range(k):
            ti, qi, qdi = self._state(t[i], q[i], qd[i])
            try:
                _, out["multipliers"][i] = self._solve(ti, qi, qdi, out=out["qdd"][i])
            except ConstraintError:  # the KKT matrix singular at this state (every row of a
                out["qdd"][i] = out["multipliers"][i] = np.nan  # constraint vanishing): undefined
            out["f"][i], out["g"][i] = self.residual(ti, qi, qdi)
            for part in self.dyn:
                for key, v in zip(("T", "V", "T0", "T2"), part.energies(ti, qi, qdi), strict=True):
                    out[key][i] += v
        return out

    def accelerations(
        self, t: float, q: object, qd: object, *, inputs: dict | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Solve M q̈ + h = Q + Aᵀλ, A q̈ + Ȧq̇ + ḃ = 0 for q̈ (shape (n,)) and λ (shape (m,)).

        ``inputs``: values of declared inputs for this call (a missing input is 0).

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.rolling_ring(4, force=True, family=True).equations().compile(
        ...     {"M": 2, "r": 0.5, "F": 2})
        >>> q, qd = pfaff.models.ring_state(4, radius=0.5, theta=1.0, theta_dot=3.0)
        >>> qdd, lam = model.accelerations(0.0, q, qd)
        >>> round(float(qdd[0]), 12), round(float(lam[0]), 12)  # ẍ = F/(2M), λ_1 = -F/2
        (0.5, -1.0)
        """
        if inputs is not None:
            return self._with_inputs(inputs).accelerations(t, q, qd)
        t, q, qd = self._state(t, q, qd)
        qdd, lam = self.solve(t, q, qd)
        check_finite(t, "q̈ or λ", qdd, lam)  # NumPy kernels overflow to inf, silently
        return qdd, lam

    def check_determined(self, t: float, q: object, qd: object) -> None:
        """Validate the state (subclasses test more: :meth:`pfaff.NumericModel.check_determined`)."""
        self._state(t, q, qd)

    def _forcing_buffer(self) -> np.ndarray:
        """The forcing vector's buffer (n,) of the in-place solves, overwritten by each."""
        if self._force is None:
            object.__setattr__(self, "_force", np.zeros(self.n))
        return self._force  # type: ignore[return-value]

    def _zeros(self) -> np.ndarray:
        if self._zero is None:
            object.__setattr__(self, "_zero", np.zeros(self.n))
        return self._zero  # type: ignore[return-value]


class _StreamField(OdeFunction):
    """y' = [q̇, q̈] of a :class:`StructuredModel`: q̈ written in place, no λ computed."""

    def __init__(self, model: StreamModel, alpha: float, beta: float) -> None:
        self.model, self.alpha, self.beta = model, alpha, beta

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        out = np.empty(2 * self.model.n)
        self.into(t, y, out)
        return out

    def into(self, t: float, y: np.ndarray, out: np.ndarray) -> None:
        """y' written into ``out`` (shape (2n,)): no array of the state's length allocated."""
        n = self.model.n
        out[:n] = y[n:]
        self.model._solve(t, y[:n], y[n:], self.alpha, self.beta, out[n:], multipliers=False)
        if not math.isfinite(float(np.sum(out[n:]))):  # q̈ was just written: still in cache
            raise StateError(f"the accelerations are NaN or infinite at t = {t:.17g}")
