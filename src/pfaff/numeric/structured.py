"""The numeric model of a system with families: template kernels over index progressions, O(N) solves.

The same contract as :class:`pfaff.NumericModel` (:class:`pfaff.numeric.protocol.DynamicsModel`).
M and A are never assembled for the triangular solve: each template contributes *streams* of
entries (a value per instance at global row ``start + step*i`` and column ``start' + step'*i``),
applied with slice arithmetic.

Kernels (:class:`pfaff.numeric.kernel.StreamKernel`) evaluate each template over chunks of instances on
two threads, take sin and cos of an angle together (:mod:`pfaff.numeric.trig`), and reduce outputs that
only count summed (a force on an ordinary coordinate, energies) without storing them.

Solvers (chosen once, at build time, from the structure; :mod:`pfaff.numeric.kkt`):
``triangular`` (:mod:`pfaff.numeric.triangular`) where the constraint Jacobian restricted to the
family coordinates is square and banded lower triangular (the ring), else ``sparse`` (SuperLU on
the augmented matrix, assembled in CSC from a pattern fixed at build time).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from pfaff.core.errors import ModelError
from pfaff.numeric.base import StreamModel
from pfaff.numeric.parts import ConStreams, DynStreams
from pfaff.numeric.pattern import KKTPattern
from pfaff.numeric.solvers import check, family_solver, names
from pfaff.numeric.streams import Index
from pfaff.numeric.triangular import TriangularSolver, triangular_plan

SOLVERS = names("family")


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
        **fields: Any,
    ) -> None:
        super().__init__(
            n, m, dyn, con, coordinate_names=coordinate_names, constraint_names=constraint_names,
            holonomic=holonomic, parameters=parameters, **fields,
        )  # fmt: skip
        self.p = p  # ordinary (non-family) coordinates, first in q
        self.timings["evaluator"] = "template"
        self.solver = "none"
        self._requested = solver
        if solver != "none":
            check(solver, "family")
            self._setup(solver)
            self.stats["solver"] = self.solver
            for part in self.dyn:
                part.kernel.warm()
            for part in self.con:
                part.acc.warm()
            self.scratch().fill(0.0)
        self._freeze()

    def _setup(self, solver: str | None) -> None:
        """The plan, solver and (for SuperLU) the augmented matrix's pattern, all O(N): made
        when the model is built and again when it is unpickled (a pickle carries no N-long
        arrays)."""
        plan = triangular_plan(self) if solver in (None, "triangular") else None
        drop, view = None, self
        if plan is None and solver in (None, "triangular"):
            drop, view, plan = _dropped_plan(self)
        if solver == "triangular" and plan is None:
            raise ModelError("the constraints have no square banded triangular structure")
        set_ = object.__setattr__
        set_(self, "_plan", plan)
        set_(self, "_drop", drop)
        set_(self, "_view", view)
        set_(self, "_solver", family_solver(view, plan))
        set_(self, "_pattern", KKTPattern(self) if plan is None else None)
        set_(self, "solver", self._solver.name)

    def _fresh_run_parts(self) -> None:
        super()._fresh_run_parts()
        if self.solver != "none":
            self.__dict__["_solver"] = family_solver(self._view, self._plan)

    def _unpickled(self) -> set[str]:
        return super()._unpickled() | {"_plan", "_solver", "_drop", "_view"}

    # ------------------------------------------------------------------ a dropped row
    def _solved_rows(self, avals: list, bias: list) -> tuple[StreamModel, list, list]:
        """Where the structure drops a redundant row (the closed ring's last spacing), the
        others: the view the triangular plan was made for."""
        d = self.__dict__.get("_drop")
        if d is None:
            return self, avals, bias
        keep = [i for i in range(len(self.con)) if i != d]
        return self._view, [avals[i] for i in keep], [bias[i] for i in keep]

    def _all_multipliers(self, lam: np.ndarray, avals: list) -> np.ndarray:
        """λ = 0 on the dropped row, then the minimum-norm λ over all rows (same Aᵀλ)."""
        return _minimum_norm(self._jacobian(avals), np.append(lam, 0.0), self.p)

    def evaluate_states(
        self, t: np.ndarray, q: np.ndarray, qd: np.ndarray
    ) -> dict[str, np.ndarray]:
        out = super().evaluate_states(t, q, qd)
        if self.__dict__.get("_drop") is not None:  # one row dependent on the others throughout
            out["redundant_rows"] = np.ones(len(t), dtype=np.int64)
        return out

    def _restored(self) -> None:
        super()._restored()
        if self.solver != "none":
            self._setup(self._requested)

    def _rebuilt(self, parameters: dict[str, float]) -> StructuredModel:
        dyn, con = self.dyn, self.con
        old, new = list(self.parameters.values()), list(parameters.values())
        if new != old:
            dyn, con = self._restream(old, new, dyn, con)
        return StructuredModel(
            self.n, self.m, dyn, con, coordinate_names=self.coordinate_names,
            constraint_names=self.constraint_names, holonomic=self.holonomic,
            parameters=parameters, p=self.p, solver=self._requested, inputs=self.inputs,
            attitudes=self.attitudes, geometry=self.geometry, linearizer=self.linearizer,
            restream=self._restream, timings=self.timings,
        )  # fmt: skip

    @property
    def sparse_dae(self) -> bool:  # type: ignore[override]
        """IDA's Newton matrix in CSC (:mod:`pfaff.numeric.ggl`), unless a row depends on the
        others (the closed ring): its regularization, scaled for long chains, is too small to
        fix λ along the null space of Aᵀ (the ring of 64 went astray). Such a model's DAE is
        :attr:`dae_model`'s, without the dependent row."""
        return self.__dict__.get("_drop") is None

    @property
    def dae_model(self) -> StructuredModel:  # type: ignore[override]
        """The model whose rows the DAE keeps: this one, or, where the structure leaves out a
        row dependent on the others (the closed ring's last spacing), the model of the others
        (the same motion: the left-out row holds wherever they do; the trajectory's λ of every
        row comes from the whole model)."""
        d = self.__dict__.get("_drop")
        return self if d is None else _rows_view(self, d)  # (its plan and solver: this model's)

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


def _dropped_plan(model: StructuredModel) -> tuple[int | None, StructuredModel, object]:
    """(block index, view, plan) where leaving out the last constraint row, a single row of its
    own (the closed ring's ``spacing n``), gives the triangular structure; else (None, model,
    None). The row must depend on the others (checked at a random state)."""
    last = [
        i for i, part in enumerate(model.con)
        if isinstance(part.rows, Index) and part.rows.count == 1 and part.rows.start == model.m - 1
    ]  # fmt: skip
    if not last:
        return None, model, None
    view = _rows_view(model, last[0])
    plan = triangular_plan(view)
    if plan is None:
        return None, model, None
    rng = np.random.default_rng(20261127)
    q = rng.uniform(-1.3, 1.3, model.n)
    A = model._jacobian(model._accel_constraints(0.3, q, np.zeros(model.n))[0])
    w = _null_vector(A, model.p)
    if not np.isfinite(w).all() or np.abs(A.T @ w).max() > 1e-9 * (1 + abs(A).max()):
        return None, model, None  # the row is independent: not a redundant closure
    return last[0], view, plan


def _rows_view(model: StructuredModel, block: int) -> StructuredModel:
    """``model`` without its last constraint row (the single-row block ``block``): the same
    parts and per-run state (a run copy's view reads its inputs), m − 1 rows."""
    view = object.__new__(type(model))
    view.__dict__.update(model.__dict__)
    keep = np.delete(np.asarray(model.holonomic), model.m - 1)
    view.__dict__.update(
        con=[c for i, c in enumerate(model.con) if i != block], m=model.m - 1, holonomic=keep,
        _drop=None, _view=view,
    )  # fmt: skip
    return view


def _null_vector(A: sps.spmatrix, p: int) -> np.ndarray:
    """w with Aᵀw = 0 and w_last = 1, shape (m,): the other rows restricted to the family
    columns are the square triangular A_L of the plan, so A_Lᵀ w_s = −a_L (one sparse
    triangular solve, exact to rounding); the p ordinary columns then hold (the row is
    redundant)."""
    A = sps.csr_matrix(A)
    As, a = A[:-1, p:], A[-1, p:]
    return np.append(spla.spsolve(sps.csc_matrix(As.T), -a.toarray().ravel()), 1.0)


def _minimum_norm(A: sps.spmatrix, lam: np.ndarray, p: int) -> np.ndarray:
    """λ minus its component along the null vector of Aᵀ: the minimum-norm λ (same Aᵀλ)."""
    w = _null_vector(A, p)
    return lam - w * (w @ lam) / (w @ w)
