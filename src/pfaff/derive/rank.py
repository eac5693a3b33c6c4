"""Generic-rank test of the constraint matrix: redundant or inconsistent constraints are refused.

A is evaluated at a random configuration with random parameter values; linear dependence that holds
everywhere (a repeated, combined or contradictory constraint) shows there with probability one. The
error names every constraint that takes part in the dependency (:func:`pfaff.numeric.rank.dependent_rows`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sps
import symengine

from pfaff.core.errors import ConstraintError
from pfaff.derive.compile import build_model
from pfaff.derive.compile_family import structured_model
from pfaff.derive.equations import Derivation
from pfaff.numeric.rank import dependent_rows

NAMES_SHOWN = 8


def check_constraint_rank(eom: Derivation, seed: int = 20261122) -> None:
    """Raise :class:`ConstraintError` naming the constraints that depend on one another.

    Examples
    --------
    >>> import pfaff
    >>> x, y = pfaff.coordinates("x y")
    >>> s = pfaff.System([x, y]); s.add_particle(1, [x, y])
    >>> s.add_holonomic_constraint(x - y, name="a"); s.add_holonomic_constraint(2 * x - 2 * y + 1, name="b")
    >>> s.equations()
    Traceback (most recent call last):
    ...
    pfaff.core.errors.ConstraintError: redundant or inconsistent constraints: the constraint matrix has rank 1 < 2; `a`, `b` depend on one another
    """
    n, m = eom.n, eom.m
    if m == 0:
        return
    if m > n:
        raise ConstraintError(
            f"{m} constraints on {n} coordinates: more constraints than coordinates"
        )
    rng = np.random.default_rng(seed)
    values = list(rng.uniform(0.7, 1.6, len(eom.parameters)))
    q = rng.uniform(-1.3, 1.3, n)
    tt = float(rng.uniform(0.1, 1.0))
    with np.errstate(all="ignore"):
        if eom.family:
            model = structured_model(eom, values, solver="none")
            if model.proves_full_rank(tt, q):  # raises on a zero pivot
                return
            A = model.constraint_matrix(tt, q)
        else:
            A = _engine_matrix(eom, values, q, tt)
            if A is None:
                A = build_model(eom, values, constraints_only=True).constraint_matrix(tt, q)
    if not np.all(np.isfinite(A.data if sps.issparse(A) else A)):
        return  # a singular random point; the numeric solve will report real problems
    rank, rows = dependent_rows(A)
    if rows.size:
        raise ConstraintError(
            "redundant or inconsistent constraints: the constraint matrix has rank "
            f"{rank} < {m}; {dependency_names(eom.constraint_names, rows)} depend on one another"
        )


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


def dependency_names(names: Sequence[str], rows: np.ndarray) -> str:
    """The first few constraint names of ``rows`` in backticks, and a count of the rest."""
    shown = ", ".join(f"`{names[int(i)]}`" for i in rows[:NAMES_SHOWN])
    more = rows.size - NAMES_SHOWN
    return shown + (f" and {more} more" if more > 0 else "")
