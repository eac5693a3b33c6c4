"""The checked, user-facing methods of a general model (:class:`CheckedGeneral`, a part of
:class:`pfaff.NumericModel`): matrices at a state, the checked accelerations with the inertia
check, the KKT mode of a run, and the linearization."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sps

from pfaff.core.errors import ConstraintError, InertiaError
from pfaff.numeric.checkedsolve import checked_solve, fused_accelerations
from pfaff.numeric.checks import check_finite
from pfaff.numeric.general import augmentation
from pfaff.numeric.inertia import inertia_test, undetermined_message
from pfaff.numeric.linearizer import linearize_model
from pfaff.numeric.redundant import dense_rows, independent_rows, persistent, warn

if TYPE_CHECKING:
    from pfaff.numeric.linearization import Linearization


# n + m up to which a checked call runs without limiting BLAS threads: on the Whipple bicycle
# (n + m = 11) under two busy-loop processes with the default OpenBLAS threads, accelerations() took
# 148 µs unlimited and 184 µs with threadpoolctl's limit around it (no thread waits left: the small
# solves are LAPACK's unthreaded paths); larger dense systems are limited once per call.
UNLIMITED_UP_TO = 64


class CheckedGeneral:
    """Checked methods of :class:`pfaff.NumericModel` (see the module docstring)."""

    if TYPE_CHECKING:
        n: int
        m: int
        dense: bool
        coordinate_names: list[str]
        _is_run: bool
        _run_state: dict

        def __getattr__(self, name: str) -> Any: ...

    def mass_matrix(
        self, t: float, q: object, qd: object | None = None
    ) -> np.ndarray | sps.csr_matrix:
        """M(q, t), shape (n, n): a dense array when small, else a SciPy CSR matrix.

        With a fused kernel, from it (the template kernels, made on first use, took a minute
        for a 7-joint arm's entries)."""
        if self._fused is None:
            M = super().mass_matrix(t, q, qd)  # type: ignore[misc]
            return M.toarray() if self.dense else M
        t, q, qd = self._state(t, q, np.zeros(self.n) if qd is None else qd)
        M = self._kkt(t, q, qd)[0][: self.n, : self.n]
        check_finite(t, "M", M)
        return M if self.dense else sps.csr_matrix(M)

    def forcing(self, t: float, q: object, qd: object) -> np.ndarray:
        """Q - h, shape (n,) (from the fused kernel when the model has one)."""
        if self._fused is None:
            return super().forcing(t, q, qd)  # type: ignore[misc]
        t, q, qd = self._state(t, q, qd)
        out = np.array(self._kkt(t, q, qd)[1])
        check_finite(t, "Q - h", out)
        return out

    def constraint_matrix(self, t: float, q: object) -> np.ndarray | sps.csr_matrix:
        """A(q, t), shape (m, n): dense when small, else CSR."""
        A = super().constraint_matrix(t, q)  # type: ignore[misc]
        return A.toarray() if self.dense else A

    def kkt_matrix(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """The symmetric augmented matrix [[M, Aᵀ], [A, 0]] and right-hand side [Q - h; -bias]."""
        t, q, qd = self._state(t, q, qd)
        K, forcing, _, bias, _, _ = self._kkt(t, q, qd)
        check_finite(t, "[[M, Aᵀ], [A, 0]] or its right-hand side", K, forcing, bias)
        return K, np.concatenate([forcing, -bias])

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
        for this call only (one left out is 0); nothing is written into the model.
        See :func:`pfaff.numeric.linearizer.linearize_model`.

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

    def accelerations(
        self, t: float, q: object, qd: object, *, inputs: dict | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Solve M q̈ + h = Q + Aᵀλ, A q̈ + Ȧq̇ + ḃ = 0 for q̈ (shape (n,)) and λ (shape (m,)).

        ``inputs``: the values of inputs declared with ``System.add_input``, by name, for this
        call only (a missing input is 0); nothing is written into the model.

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
        if inputs is not None:
            return self._with_inputs(inputs).accelerations(t, q, qd)
        fast = fused_accelerations(self, t, q, qd)  # type: ignore[arg-type]
        if fast is not None:  # the generated solve's pivots: nothing for the checks to find
            return fast
        if self.n + self.m <= UNLIMITED_UP_TO:  # tiny solves: no BLAS thread waits, no limit
            return self._checked_accelerations(t, q, qd)
        with self._threads():
            return self._checked_accelerations(t, q, qd)

    def _checked_accelerations(
        self, t: float, q: object, qd: object
    ) -> tuple[np.ndarray, np.ndarray]:
        t, q, qd = self._state(t, q, qd)
        if not self.dense:
            try:
                return self.solve(t, q, qd)
            except ConstraintError:
                self.check_determined(t, q, qd)  # the precise error when M is the cause
                K, forcing, _, bias, _, _ = self._kkt(t, q, qd)
                A = dense_rows(K, self.n, t)  # redundant rows? (refused above REDUNDANT_DENSE)
                rows = independent_rows(A)
                if rows is None:
                    raise
                warn(self.constraint_names, A, f"at t = {t:g}")
                return self._solve_kkt(K, forcing, -bias, t, rows=rows)
        K, forcing, _, bias, _, _ = self._kkt(t, q, qd)
        last = self._run_state["last"]  # set when the machine code solved this state in _kkt
        solved = last is not None and last[0] == t and last[1] == q.tobytes()
        if not solved:  # one pass: the checks' factors solve (None: a check needs the full path)
            fast = checked_solve(K, forcing, -bias, self.n)
            if fast is not None:
                self.stats["kkt_solves"] += 1
                return fast
        full = inertia_test(K, t, self.n, self.m, self.coordinate_names)
        rows = independent_rows(K[self.n :, : self.n]) if self.m else None
        if rows is not None:  # redundant rows here: q̈ exact, λ minimum-norm
            warn(self.constraint_names, K[self.n :, : self.n], f"at t = {t:g}")
            return self._solve_kkt(K, forcing, -bias, t, full=full, rows=rows)
        if not full and solved and last is not None:
            if last[2] == qd.tobytes():  # the machine code solved this state with _kkt
                self._run_state["last"] = None
                return last[3][: self.n].copy(), last[3][self.n :].copy()
        return self._solve_kkt(K, forcing, -bias, t, full=full)

    def check_determined(self, t: float, q: object, qd: object) -> None:
        """Check that M is positive definite on the admissible velocities at a state.

        With Z an orthonormal basis of null(A), ZᵀMZ must be positive definite: else some
        acceleration is undetermined (a coordinate without inertia that no constraint fixes) or
        the kinetic energy is negative along an admissible motion. M itself may be singular
        (quaternion attitude coordinates are, along the quaternion) as long as the constraints
        fix what M leaves free; a run (:meth:`for_run`) then solves the whole augmented matrix
        by LU: its mode, set here at its first state; a user's model keeps no mode. Dense models
        pay one Cholesky factorization of M when M is safely positive definite, and an SVD of A
        and an eigenvalue decomposition of ZᵀMZ only when it is not. Sparse models (n + m >
        ``DENSE_LIMIT``) get the O(nnz) part of the test only: coordinates with neither a mass
        entry nor a constraint entry. Then one solve: no acceleration may satisfy the
        constraints here.

        Raises
        ------
        InertiaError
            Naming the coordinates that span the undetermined (or negative) directions.
        ConstraintError
            The constraints are inconsistent at this state.
        """
        t, q, qd = self._state(t, q, qd)
        n, K = self.n, self._kkt(t, q, qd)[0]
        run = self._run_state
        if not self.dense:
            Kc = sps.csc_matrix(K)
            Kc.eliminate_zeros()
            free = np.flatnonzero(np.diff(Kc.indptr)[:n] == 0)  # a column of zeros in M and A
            if free.size:
                raise InertiaError(undetermined_message(self.coordinate_names, t, free))
        elif self._is_run:
            run["full"], run["rho"], run["rows"] = False, 0.0, None  # no stale mode if it raises
            run["full"] = inertia_test(K, t, n, self.m, self.coordinate_names)
            run["rho"] = augmentation(self, K, t, q, qd) if run["full"] else 0.0
            full = run["full"]
            run["rows"] = self._redundant_rows(K[n:, :n], t, q, qd)
        else:
            full = inertia_test(K, t, n, self.m, self.coordinate_names)
        if self.m:
            if self.dense and not self._is_run:
                _, forcing, _, bias, _, _ = self._kkt(t, q, qd)
                rows = independent_rows(K[n:, :n])
                self._solve_kkt(K, forcing, -bias, t, full=full, rows=rows)
            elif not self.dense:
                try:
                    self._solve(t, q, qd)
                except ConstraintError:  # redundant rows (persistent ones become the run's)
                    A = dense_rows(K, n, t)
                    rows = self._redundant_rows(A, t, q, qd) if self._is_run else None
                    rows = independent_rows(A) if rows is None and not self._is_run else rows
                    if rows is None:
                        raise
                    if self._is_run:
                        run["rows"] = rows
                    _, forcing, _, bias, _, _ = self._kkt(t, q, qd)
                    self._solve_kkt(K, forcing, -bias, t, rows=rows)
            else:
                self._solve(t, q, qd)

    def _redundant_rows(
        self, A: np.ndarray, t: float, q: np.ndarray, qd: np.ndarray
    ) -> np.ndarray | None:
        """The independent rows a run keeps where its constraints are persistently redundant
        (warned), else None: full rank, or an isolated rank loss (a fold: the floored solve
        follows the branch). See :func:`pfaff.numeric.redundant.persistent`."""
        rows = independent_rows(A) if self.m else None
        if rows is None:
            return None
        n = self.n
        hol = np.asarray(self.holonomic, dtype=bool)
        if not persistent(
            A, rows, q, lambda q_: self._kkt(t, q_, qd)[0][n:, :n],
            lambda q_: self.residual(t, q_, qd)[0], hol,
        ):  # fmt: skip
            return None
        warn(self.constraint_names, A, f"at the first state (t = {t:g})")
        return rows
