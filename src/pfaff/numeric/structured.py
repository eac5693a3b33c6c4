"""The numeric model of a system with families: template kernels over index progressions, O(N) solves.

The same contract as :class:`pfaff.NumericModel` (:class:`pfaff.numeric.protocol.DynamicsModel`).
M and A are never assembled for the triangular solve: each template contributes *streams* of
entries (a value per instance at global row ``start + step*i`` and column ``start' + step'*i``),
applied with slice arithmetic.

Kernels (:class:`pfaff.numeric.streams.StreamKernel`) evaluate each template over chunks of instances on
two threads, take sin and cos of an angle together (:mod:`pfaff.numeric.trig`), and reduce outputs that
only count summed (a force on an ordinary coordinate, energies) without storing them.

Solvers (chosen once, at build time, from the structure; :mod:`pfaff.numeric.kkt`):
``triangular`` (:mod:`pfaff.numeric.triangular`) where the constraint Jacobian restricted to the
family coordinates is square and banded lower triangular (the ring), else ``sparse`` (SuperLU on
the augmented matrix, assembled in CSC from a pattern fixed at build time).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps

from pfaff.core.errors import ModelError, StateError
from pfaff.core.lazy import LazySeq
from pfaff.numeric.checks import check_finite, check_state, projection_options, real_vector
from pfaff.numeric.kkt import KKTSolver, KKTSystem, SparseSolver
from pfaff.numeric.projection import ArrayLinearization, newton_projection
from pfaff.numeric.protocol import ConstraintLinearization, OdeFunction
from pfaff.numeric.streams import Index, StreamKernel, add_product, indices, scatter_add, take
from pfaff.numeric.triangular import TriangularSolver, triangular_plan

SOLVERS = ("triangular", "sparse")


class DynStreams:
    """A dynamics block: mass entries (row, col) and forcing rows, as streams.

    Parameters
    ----------
    kernel : StreamKernel
        Outputs: the upper mass entries, then the forcing entries (summed where flagged).
    upper : list of (rows, cols, mirrored)
        Per upper mass entry (a <= b): its row and column streams and whether it also stands
        for (col, row).
    forcing : list of Index or ndarray
        Row of each forcing entry.
    energy_kernel : callable
        ``energy_kernel(which)`` makes the summed kernel of ``[T, V]`` (``"energy"``), of
        ``[T, V, T₀, T₂]`` (``"energies"``) or of the applied forces' power ``[Σ Q_a q̇_a]``
        (``"power"``), on first use.
    has_power : bool
        Whether the block has applied forces (else its power is zero and never evaluated).
    """

    def __init__(
        self,
        kernel: StreamKernel,
        upper: list[tuple[Index | np.ndarray, Index | np.ndarray, bool]],
        forcing: list[Index | np.ndarray],
        energy_kernel: Callable[[str], StreamKernel],
        has_power: bool = False,
    ) -> None:
        self.kernel, self.upper, self.forcing = kernel, upper, forcing
        # a force on a fixed coordinate (x of the ring) only ever counts summed over the instances
        self.summed = [isinstance(ix, Index) and ix.fixed for ix in forcing]
        self.mass = [(r, c) for r, c, _ in upper] + [(c, r) for r, c, sym in upper if sym]
        self._energy_kernel = energy_kernel
        self.has_power = has_power
        self._ekernel: StreamKernel | None = None
        self._pkernel: StreamKernel | None = None
        self._wkernel: StreamKernel | None = None

    def mass_values(self, outs: list) -> list:
        """Values of :attr:`mass` entries from the kernel outputs (mirrored entries repeated)."""
        nu = len(self.upper)
        return outs[:nu] + [v for (_, _, sym), v in zip(self.upper, outs, strict=False) if sym]

    def energy(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
        """(T, V) summed over the instances."""
        if self._ekernel is None:
            self._ekernel = self._energy_kernel("energy")
        return tuple(self._ekernel(t, q, qd))  # type: ignore[return-value]

    def power(self, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """Σ Q_a q̇_a of the applied forces, summed over the instances."""
        if not self.has_power:
            return 0.0
        if self._wkernel is None:
            self._wkernel = self._energy_kernel("power")
        return float(self._wkernel(t, q, qd)[0])

    def energies(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[float, ...]:
        """(T, V, T₀, T₂) summed over the instances: T₀ = T at q̇ = 0, T₂ its quadratic part."""
        if self._pkernel is None:
            self._pkernel = self._energy_kernel("energies")
        return tuple(self._pkernel(t, q, qd))


@dataclass
class ConStreams:
    """A constraint block: A entries over its rows, then b, bias (Ȧq̇ + ḃ) and f.

    Attributes
    ----------
    rows : Index or ndarray
        Constraint row of each instance.
    cols : list of Index or ndarray
        Column of each A entry.
    acc : StreamKernel
        Outputs ``[A entries..., bias]``.
    res : StreamKernel
        Outputs ``[A entries..., b, bias, f]``.
    """

    rows: Index | np.ndarray
    cols: list
    acc: StreamKernel
    res: StreamKernel


class StreamModel:
    """The numeric model of any system over template streams: the shared part of both kinds.

    Evaluation (M, Q − h, A, b, Ȧq̇ + ḃ, f, energies, power) runs the template kernels
    (:class:`pfaff.numeric.streams.StreamKernel`) over index progressions or index arrays;
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
    ) -> None:
        self.n, self.m = n, m
        self.coordinate_names = coordinate_names
        self.multiplier_names = multiplier_names or LazySeq(
            self.m,
            lambda i: f"lambda{i + 1}",
            lambda lo, hi: [f"lambda{i}" for i in range(lo + 1, hi + 1)],
        )
        self.constraint_names = constraint_names
        self.holonomic = np.asarray(holonomic, dtype=bool).reshape(self.m)
        self.parameters = dict(parameters)
        self.dyn, self.con = dyn, con  # the blocks, read by the solvers
        self.stats: dict = {"kkt_solves": 0}
        self._tmp: np.ndarray | None = None
        self._zero: np.ndarray | None = None
        self._pattern: KKTPattern | None = None
        self._names = coordinate_names if isinstance(coordinate_names, list) else None

    # ------------------------------------------------------------------ validation
    def _state(self, t: float, q: object, qd: object) -> tuple[float, np.ndarray, np.ndarray]:
        return check_state(t, q, qd, self.n, self._names)

    # ------------------------------------------------------------------ raw evaluation
    def _dynamics(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[list, np.ndarray]:
        """Mass-entry values per block and the forcing vector Q - h."""
        mvals, f = [], np.zeros(self.n)
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
            self._tmp = np.empty(max(counts, default=0))
        return self._tmp

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
        return _coo(pairs, vals, (self.n, self.n)).tocsr()

    def _jacobian(self, avals: list) -> sps.csr_matrix:
        pairs = [(part.rows, c) for part in self.con for c in part.cols]
        vals = [v for vs in avals for v in vs]
        return _coo(pairs, vals, (self.m, self.n)).tocsr()

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

    def acceleration_residual(self, t: float, q: object, qd: object, qdd: object) -> np.ndarray:
        """A q̈ + Ȧq̇ + ḃ, shape (m,): zero for accelerations that satisfy the constraints."""
        t, q, qd = self._state(t, q, qd)
        qdd = real_vector(qdd, "qdd", self.n)
        avals, bias = self._accel_constraints(t, q, qd)
        return self.a_matvec(avals, qdd) + self._rows_vector(bias)

    def generalized_constraint_force(
        self, t: float, q: object, qd: object, qdd: object
    ) -> np.ndarray:
        """M q̈ - (Q - h), shape (n,): the generalized constraint force Aᵀλ on a motion."""
        t, q, qd = self._state(t, q, qd)
        qdd = real_vector(qdd, "qdd", self.n)
        mvals, f = self._dynamics(t, q, qd)
        return self.matvec(mvals, qdd) - f

    def constraint_force(self, t: float, q: object, lam: object) -> np.ndarray:
        """Aᵀλ, shape (n,)."""
        t, q, qd = self._state(t, q, np.zeros(self.n))
        lam = real_vector(lam, "lam", self.m)
        avals, _ = self._accel_constraints(t, q, qd)
        y, tmp = np.zeros(self.n), self.scratch()
        for part, vals in zip(self.con, avals, strict=True):
            for c, val in zip(part.cols, vals, strict=True):
                add_product(y, c, val, take(part.rows, lam), tmp)
        return y

    def energy(self, t: float, q: object, qd: object) -> tuple[float, float]:
        """Kinetic and potential energy (T, V)."""
        t, q, qd = self._state(t, q, qd)
        TV = [part.energy(t, q, qd) for part in self.dyn]
        return float(sum(x for x, _ in TV)), float(sum(v for _, v in TV))

    @property
    def applied_power(self) -> bool:
        """True when some applied force can do work (see :meth:`power`)."""
        return any(part.has_power for part in self.dyn)

    def power(self, t: float, q: object, qd: object) -> float:
        """Power of the applied forces, Qᵀq̇: the rate of the work W_nc in the energy balance."""
        t, q, qd = self._state(t, q, qd)
        return self.power_function()(t, q, qd)

    def power_function(self) -> Callable[[float, np.ndarray, np.ndarray], float]:
        """:meth:`power` without the argument checks, for an integrator's checked states."""
        parts = [part for part in self.dyn if part.has_power]

        def power(t: float, q: np.ndarray, qd: np.ndarray) -> float:
            return math.fsum(part.power(t, q, qd) for part in parts)

        return power

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
        mvals, f = self._dynamics(t, q, qd)
        avals, bias = self._accel_constraints(t, q, qd)
        zero = all(np.ndim(b) == 0 and b == 0 for b in bias)
        c = None if zero else -self._rows_vector(bias)
        if alpha or beta:
            fr, g = self.residual(t, q, qd)
            c = (np.zeros(self.m) if c is None else c) - 2 * alpha * g - beta**2 * fr
        self.stats["kkt_solves"] += 1
        solved = self._solver.solve(
            self._system(mvals, f, avals, c), out=out, multipliers=multipliers
        )
        if isinstance(self._solver, SparseSolver):
            self.stats["fill"] = self._solver.fill
        return solved

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
        mvals, _ = self._dynamics(t, q, qd)
        avals, _ = self._accel_constraints(t, q, qd)
        sq = np.zeros(self.m)
        for part, vals in zip(self.con, avals, strict=True):
            for val in vals:
                scatter_add(sq, part.rows, np.multiply(val, val))

        def correct(r: np.ndarray) -> np.ndarray:
            system = self._system(mvals, self._zeros(), avals, r)
            return self._solver.solve(system, multipliers=False)[0]

        f = np.where(self.holonomic, f, 0.0)
        return ArrayLinearization(
            f, g, np.sqrt(sq), tol, correct, correct, lambda v: self.residual(t, q, v)[1]
        )

    def project(
        self, t: float, q: object, qd: object, *, tol: float = 1e-12, max_iter: int = 10
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """Project (q, q̇) onto f(q, t) = 0 and A q̇ + b = 0, mass-orthogonally.

        The projection the integrators use (:func:`pfaff.numeric.projection.newton_projection`)
        at one state: Newton on the positions, then the velocities. Returns the new q, q̇ and
        the number of Newton steps (1 when only the velocities moved; 0: nothing changed).

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
        >>> q, qd, steps = model.project(0.0, [0.6, -0.9], [1.0, 1.0])
        >>> bool(abs(q @ q - 1) < 1e-12 and abs(q @ qd) < 1e-12), steps > 0
        (True, True)
        """
        t, q, qd = self._state(t, q, qd)
        tol, max_iter = projection_options(tol, max_iter)
        if not self.m:
            return q, qd, 0
        return newton_projection(
            lambda q_, qd_: self.linearize_constraints(t, q_, qd_, tol), q, qd, max_iter=max_iter
        )

    def dae_blocks(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """(M, A, Q − h, f, g) at an unchecked state, M and A assembled as CSR (one pass of
        each kernel: A, b and f from the same constraint kernel)."""
        mvals, forcing = self._dynamics(t, q, qd)
        avals, b, _, f = self._constraints(t, q, qd)
        A = self._jacobian(avals)
        return self._mass(mvals), A, forcing, f, b + A @ qd

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
            ``qdd`` (k, n), ``multipliers`` (k, m), ``f`` and ``g`` (k, m), and (k,) arrays ``T``,
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
            _, out["multipliers"][i] = self._solve(ti, qi, qdi, out=out["qdd"][i])
            out["f"][i], out["g"][i] = self.residual(ti, qi, qdi)
            for part in self.dyn:
                for key, v in zip(("T", "V", "T0", "T2"), part.energies(ti, qi, qdi), strict=True):
                    out[key][i] += v
        return out

    def accelerations(self, t: float, q: object, qd: object) -> tuple[np.ndarray, np.ndarray]:
        """Solve M q̈ + h = Q + Aᵀλ, A q̈ + Ȧq̇ + ḃ = 0 for q̈ (shape (n,)) and λ (shape (m,)).

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
        t, q, qd = self._state(t, q, qd)
        qdd, lam = self.solve(t, q, qd)
        check_finite(t, "q̈ or λ", qdd, lam)  # NumPy kernels overflow to inf, silently
        return qdd, lam

    def check_determined(self, t: float, q: object, qd: object) -> None:
        """Validate the state (subclasses test more: :meth:`pfaff.NumericModel.check_determined`)."""
        self._state(t, q, qd)

    def _zeros(self) -> np.ndarray:
        if self._zero is None:
            self._zero = np.zeros(self.n)
        return self._zero


def _coo(pairs: list, vals: list, shape: tuple[int, int]) -> sps.coo_matrix:
    rows, cols, data = [], [], []
    for (r, c), v in zip(pairs, vals, strict=True):
        ri, ci = indices(r), indices(c)
        n = max(np.size(ri), np.size(ci))
        rows.append(np.broadcast_to(ri, (n,)))
        cols.append(np.broadcast_to(ci, (n,)))
        data.append(np.broadcast_to(np.asarray(v, dtype=float), (n,)))
    cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0)  # noqa: E731
    return sps.coo_matrix(
        (cat(data), (cat(rows).astype(np.int64), cat(cols).astype(np.int64))), shape=shape
    )


class StructuredModel(StreamModel):
    """Compiled equations of motion of a system with families (see the module docstring).

    Attributes
    ----------
    n, m : int
    coordinate_names, multiplier_names, constraint_names : sequence of str
        Made on demand (a family of 2^24 members has no list of names).
    holonomic : ndarray of bool, shape (m,)
    parameters : dict
    solver : str
        ``"triangular"`` or ``"sparse"``.
    stats : dict

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> ring = pfaff.models.rolling_ring(1000, force=True, family=True)
    >>> model = ring.equations().compile({"M": 1, "r": 0.5, "F": 2})
    >>> q, qd = pfaff.models.ring_state(1000, radius=0.5, theta=0.3)
    >>> qdd, lam = model.accelerations(0.0, q, qd)
    >>> model.solver, round(float(qdd[1]), 12), round(float(lam[0]), 12)
    ('triangular', 2.0, -1.0)
    """

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
        p: int,
        solver: str | None = None,
    ) -> None:
        super().__init__(
            n, m, dyn, con, coordinate_names=coordinate_names, constraint_names=constraint_names,
            holonomic=holonomic, parameters=parameters,
        )  # fmt: skip
        self.p = p  # ordinary (non-family) coordinates, first in q
        self.solver = "none"
        if solver != "none":
            plan = triangular_plan(self) if solver in (None, "triangular") else None
            if solver == "triangular" and plan is None:
                raise ModelError("the constraints have no square banded triangular structure")
            self._solver = TriangularSolver(self, plan) if plan is not None else SparseSolver(n, m)
            if plan is None:
                self._pattern = KKTPattern(self)
            self.solver = self.stats["solver"] = self._solver.name
            for part in self.dyn:
                part.kernel.warm()
            for part in self.con:
                part.acc.warm()
            self.scratch().fill(0.0)

    def proves_full_rank(self, t: float, q: np.ndarray) -> bool:
        """True when A has the triangular structure with non-zero pivots at (t, q), which proves
        rank m; False when it has no such structure (the rank must be found otherwise).

        Raises :class:`pfaff.ConstraintError` on a zero pivot.
        """
        plan = triangular_plan(self)
        if plan is None:
            return False
        avals, _ = self._accel_constraints(t, np.asarray(q, dtype=float), self._zeros())
        TriangularSolver(self, plan).factor(avals)
        return True

    def check_determined(self, t: float, q: object, qd: object) -> None:
        """Validate the state; the inertia test of :meth:`NumericModel.check_determined` is not run.

        Why: a family model has up to 2^24 coordinates, and the test there (ZᵀMZ positive
        definite, Z a basis of null(A)) is O(N³) dense, or O(nnz) with M and A assembled, which
        these models never do. Nor is it needed for an undetermined acceleration: the triangular
        solver determines every family coordinate from the constraints (it raises
        :class:`ConstraintError` on a zero pivot of A_L) and solves the p ordinary ones from the
        p×p projected matrix TᵀMT, which raises on a singular one; the sparse solver's SuperLU
        raises on an exactly singular augmented matrix. Negative particle masses are refused when
        the parameter values are given (``compile``).
        """
        self._state(t, q, qd)


class _StreamField(OdeFunction):
    """y' = [q̇, q̈] of a :class:`StructuredModel`: q̈ written in place, no λ computed."""

    def __init__(self, model: StreamModel, alpha: float, beta: float) -> None:
        self.model, self.alpha, self.beta = model, alpha, beta

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        n = self.model.n
        out = np.empty(2 * n)
        out[:n] = y[n:]
        self.model._solve(t, y[:n], y[n:], self.alpha, self.beta, out[n:], multipliers=False)
        if not math.isfinite(float(np.sum(out[n:]))):  # q̈ was just written: still in cache
            raise StateError(f"the accelerations are NaN or infinite at t = {t:.17g}")
        return out


class KKTPattern:
    """The augmented matrix [[M, Aᵀ], [A, 0]] of a stream model, its pattern fixed at build
    time, densely or in CSC.

    The entries that do not depend on the state (a particle's mass, a constant constraint
    gradient: on the ring all but M's x–θ couplings) are summed once, at build time; an assembly
    copies them and adds the state-dependent entries alone (on the ring of 64 particles 5 µs
    instead of 12 µs for all entries, a third of the general model's kernel time).
    """

    def __init__(self, model: StreamModel) -> None:
        self.model = model
        n, m = model.n, model.m
        N = self.N = n + m
        rows, cols, consts, sources = [], [], [], []
        for bi, part in enumerate(model.dyn):
            nu = len(part.upper)
            outs = list(range(nu)) + [k for k, (_, _, sym) in enumerate(part.upper) if sym]
            for (r, c), k in zip(part.mass, outs, strict=True):
                rows.append(_expand(r, c))
                cols.append(_expand(c, r))
                consts.append(part.kernel.const[k])
                sources.append((0, bi, k))
        for bi, part in enumerate(model.con):
            for k, c in enumerate(part.cols):
                rr, cc = n + _expand(part.rows, c), _expand(c, part.rows)
                rows += [rr, cc]
                cols += [cc, rr]
                consts += [part.acc.const[k]] * 2
                sources += [(1, bi, k)] * 2
        cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0, np.int64)  # noqa: E731
        lin = cat(cols) * N + cat(rows)  # column-major: sorted order is CSC order
        uniq, slot = np.unique(lin, return_inverse=True)
        self.indices = uniq % N
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(uniq // N, minlength=N))])
        ends = np.cumsum([len(r) for r in rows], dtype=np.int64).tolist()
        const = np.zeros(lin.size)
        self._varying: list = []  # (source, dense positions, CSC slots, (each distinct?) × 2)
        for a, b, c, src in zip([0, *ends[:-1]], ends, consts, sources, strict=True):
            if c is not None:
                const[a:b] = c
            else:
                pos, sl = lin[a:b], slot.ravel()[a:b]
                once = (np.unique(pos).size == pos.size, np.unique(sl).size == sl.size)
                self._varying.append((src, pos, sl, once))
        self._csc = np.bincount(slot.ravel(), weights=const, minlength=uniq.size)
        self._dense: np.ndarray | None = None  # flat, column-major; made on first use
        self._lin, self._const = lin, const

    def _add(self, flat: np.ndarray, mvals: list, avals: list, dense: bool) -> np.ndarray:
        for (kind, bi, k), pos, sl, once in self._varying:
            v = (mvals if kind == 0 else avals)[bi][k]
            at = pos if dense else sl
            if once[0] if dense else once[1]:
                flat[at] += v
            else:  # several instances on one entry (a fixed row and column): summed
                np.add.at(flat, at, np.broadcast_to(v, at.shape))
        return flat

    def assemble(self, mvals: list, avals: list) -> sps.csc_matrix:
        """K in CSC, shape (N, N)."""
        data = self._add(self._csc.copy(), mvals, avals, dense=False)
        return sps.csc_matrix((data, self.indices, self.indptr), shape=(self.N, self.N))

    def dense(self, mvals: list, avals: list) -> np.ndarray:
        """K as a dense array, shape (N, N)."""
        N = self.N
        if self._dense is None:
            self._dense = np.bincount(self._lin, weights=self._const, minlength=N * N)
        return self._add(self._dense.copy(), mvals, avals, dense=True).reshape(N, N).T


def _count(a: Index | np.ndarray, b: Index | np.ndarray) -> int:
    """Instances of a stream whose index sets are ``a`` and ``b``."""
    return max(
        np.size(indices(a)) if not isinstance(a, Index) else a.count,
        np.size(indices(b)) if not isinstance(b, Index) else b.count,
    )


def _expand(a: Index | np.ndarray, b: Index | np.ndarray) -> np.ndarray:
    """Indices of ``a`` over the instances of a stream whose other index set is ``b``."""
    return np.broadcast_to(indices(a), (_count(a, b),)).astype(np.int64)
