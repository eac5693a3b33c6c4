"""Generic-rank test of the constraint matrix: redundant constraints reported, inconsistent refused.

A is evaluated at a random configuration with random parameter values; linear dependence that holds
everywhere (a repeated, combined or contradictory constraint) shows there with probability one.
Dependent rows form *sets* (rows that share a null vector of Aᵀ, :func:`redundant_sets`). A set is
*consistent* when the constraints can hold together: from the random point, Gauss–Newton on the
independent rows reaches the manifold they define, and there the dependent rows hold too (position
rows: f = 0; every row: Aᵀ's null vectors annihilate b, so that A q̇ + b = 0 has solutions).
Consistent sets are reported (a :class:`pfaff.RedundancyWarning` and ``eom.redundant_sets``); an
inconsistent set is refused, naming every row of it. Redundancy that appears only on the
constraint manifold (the Bricard linkage) is found at the first state of a run
(:meth:`pfaff.NumericModel.redundancy`).
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sps
import symengine

from pfaff.core.errors import ConstraintError, RedundancyWarning
from pfaff.core.stack import outside_pfaff
from pfaff.derive.compile import build_model
from pfaff.derive.compile_family import structured_model
from pfaff.derive.equations import Derivation
from pfaff.derive.family_rank import closure_rows, proves_full_rank
from pfaff.numeric.rank import DENSE_LIMIT, dependent_rows, null_basis, redundant_sets
from pfaff.numeric.redundant import dependency_names, onto_positions

CONSISTENT = 1e-9  # a dependent row's residual on the manifold below this (relative): consistent


def check_constraint_rank(
    eom: Derivation, seed: int = 20261122, small_instance: bool = True
) -> list[list[str]]:
    """The sets of constraints that depend on one another everywhere (a warning names them), or
    :class:`ConstraintError` naming every row of an inconsistent set.

    A family's full rank is proved on a small instance of its templates where its structure
    allows (:func:`pfaff.derive.family_rank.proves_full_rank`; ``small_instance=False``: the
    full check only, on a numeric model of full size).

    Examples
    --------
    >>> import warnings, pfaff
    >>> x, y = pfaff.coordinates("x y")
    >>> s = pfaff.System([x, y]); s.add_particle(1, [x, y])
    >>> s.add_holonomic_constraint(x - y, name="a"); s.add_holonomic_constraint(2 * x - 2 * y + 1, name="b")
    >>> s.equations()
    Traceback (most recent call last):
    ...
    pfaff.core.errors.ConstraintError: inconsistent constraints: `a`, `b` cannot hold together (the constraint matrix has rank 1 < 2 and the rows contradict one another)
    >>> s = pfaff.System([x, y]); s.add_particle(1, [x, y])
    >>> s.add_holonomic_constraint(x - y, name="a"); s.add_holonomic_constraint(2 * x - 2 * y, name="b")
    >>> with warnings.catch_warnings(record=True):
    ...     s.equations().redundant_sets
    [['a', 'b']]
    """
    n, m = eom.n, eom.m
    if m == 0:
        return []
    rng = np.random.default_rng(seed)
    values = list(rng.uniform(0.7, 1.6, len(eom.parameters)))
    q = rng.uniform(-1.3, 1.3, n)
    tt = float(rng.uniform(0.1, 1.0))
    model = None
    with np.errstate(all="ignore"):
        if eom.family:  # its templates on a small instance first (issue 25), then in full
            if small_instance and proves_full_rank(eom, values, tt, rng):
                return []
            closing = closure_rows(eom, values, tt, rng) if small_instance else None
            if closing is not None and m > DENSE_LIMIT:  # (smaller: the full check, consistency)
                return _reported(eom, m - 1, [closing.tolist()]) if closing.size else []
            model = structured_model(eom, values, solver="none")
            if m <= n and model.proves_full_rank(tt, q):  # raises on a zero pivot
                return []
            A = model.constraint_matrix(tt, q)
        else:
            A = _engine_matrix(eom, values, q, tt)
            if A is None:
                model = build_model(eom, values, constraints_only=True)
                A = model.constraint_matrix(tt, q)
    if not np.all(np.isfinite(A.data if sps.issparse(A) else A)):
        return []  # a singular random point; the numeric solve will report real problems
    rank, rows = dependent_rows(A)
    if not rows.size:
        return []
    names = eom.constraint_names
    if (
        sps.issparse(A) and m > DENSE_LIMIT
    ):  # (the sets told apart, checked densely below)  # one set of the rows that take part; the
        # consistency of so large a set is left to the first state of a run (the solve checks)
        sets, bad = [rows.tolist()], np.zeros(0, dtype=np.int64)
    else:
        sets = redundant_sets(A)
        if model is None:
            model = build_model(eom, values, constraints_only=True)
        bad = _inconsistent(model, tt, q, rows)
    if bad.size:
        raise ConstraintError(
            f"inconsistent constraints: {dependency_names(names, bad)} cannot hold together (the "
            f"constraint matrix has rank {rank} < {m} and the rows contradict one another)"
        )
    return _reported(eom, rank, sets)


def _reported(eom: Derivation, rank: int, sets: list[list[int]]) -> list[list[str]]:
    """The dependent sets by name, warned (a :class:`pfaff.RedundancyWarning`)."""
    names, m = eom.constraint_names, eom.m
    named = [_names_of(names, np.asarray(s, dtype=np.int64)) for s in sets]
    text = "; ".join(dependency_names(names, np.asarray(s)) for s in sets)
    warnings.warn(
        f"redundant constraints: the constraint matrix has rank {rank} < {m}; {text} depend on "
        "one another. The motion is determined; on these rows only Aᵀλ is, and pfaff reports "
        "the minimum-norm multipliers (eom.redundant_sets, model.redundancy)",
        RedundancyWarning,
        stacklevel=outside_pfaff(),
    )
    return named


def _names_of(names: object, rows: np.ndarray) -> list[str]:
    """The names of these rows; a run of consecutive rows in one slice (a lazy family's names
    are then made in bulk: per name, the 2^20 spacing rows of a closed ring took 50 s)."""
    if rows.size > 1 and rows[-1] - rows[0] + 1 == rows.size and (np.diff(rows) == 1).all():
        return [str(x) for x in names[int(rows[0]) : int(rows[-1]) + 1]]  # type: ignore[index]
    return [str(names[int(i)]) for i in rows]  # type: ignore[index]


def _inconsistent(model: object, t: float, q: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The dependent rows (of ``rows``) that do not hold where the independent rows do: empty
    when the set is consistent (or when the manifold could not be reached: not refused then)."""
    hol = np.asarray(model.holonomic, dtype=bool)  # type: ignore[attr-defined]
    qd = np.zeros(model.n)  # type: ignore[attr-defined]
    with np.errstate(all="ignore"):
        reached = onto_positions(
            q, lambda q_: _dense(model.constraint_matrix(t, q_)),  # type: ignore[attr-defined]
            lambda q_: model.residual(t, q_, qd)[0], hol, 12, 1e-14, 1e-10,  # type: ignore[attr-defined]
        )  # fmt: skip
        if reached is None:
            return np.zeros(0, dtype=np.int64)
        q = reached
        A = _dense(model.constraint_matrix(t, q))  # type: ignore[attr-defined]
        f, g = model.residual(t, q, qd)  # type: ignore[attr-defined]
    scale = 1.0 + np.abs(A).max() * (1 + np.abs(q).max())
    Y = null_basis(A)
    b = g  # A q̇ + b at q̇ = 0
    off = np.zeros(model.m, dtype=bool)  # type: ignore[attr-defined]
    if Y.shape[1]:
        c = Y.T @ b  # null vectors of Aᵀ must annihilate b
        for k in np.flatnonzero(np.abs(c) > CONSISTENT * scale * max(1.0, np.abs(b).max())):
            off |= np.abs(Y[:, k]) > 1e-8
    off |= hol & (np.abs(f) > CONSISTENT * scale)  # position rows left unsatisfied
    off &= np.isin(np.arange(off.size), rows)
    if off.any():  # name the whole set of each row found contradicting
        sets = redundant_sets(A)
        hit = [s for s in sets if off[np.asarray(s)].any()]
        return (
            np.unique(np.concatenate([np.asarray(s) for s in hit])) if hit else np.flatnonzero(off)
        )
    return np.zeros(0, dtype=np.int64)


def _dense(A: object) -> np.ndarray:
    return A.toarray() if sps.issparse(A) else np.asarray(A, dtype=float)  # type: ignore[attr-defined]


ENGINE_ROWS = 512  # up to this many constraint rows, A is evaluated from SymEngine directly


def _engine_matrix(eom: Derivation, values: list, q: np.ndarray, tt: float) -> np.ndarray | None:
    """A at (t, q) from the templates' SymEngine forms, without generating kernels (which took
    1.7 s of the Whipple bicycle's 2.1 s ``equations()``); None when a template has none."""
    blocks = [b for b in eom.blocks if b.local.kind == "constraint"]
    if eom.m > ENGINE_ROWS or any(b.local.engine is None for b in blocks):
        return None
    subs = {symengine.Symbol("t"): tt}
    subs.update({symengine.Symbol(p.name): v for p, v in zip(eom.parameters, values, strict=True)})
    A = np.zeros((eom.m, eom.n))
    for b in blocks:
        entries = b.local.engine["A"]
        for row, idx in zip(b.rows.tolist(), b.coords.tolist(), strict=True):
            point = dict(subs)
            point.update({symengine.Symbol(f"_q{a}"): q[c] for a, c in enumerate(idx)})
            for a, e in entries.items():
                try:
                    A[row, idx[a]] = float(e.subs(point))
                except (RuntimeError, TypeError, ValueError):  # not real, or not defined here
                    A[row, idx[a]] = np.nan
    return A
