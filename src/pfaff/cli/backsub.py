"""The ring demo's multipliers by back-substitution, the seed's "step backwards" (a demonstration).

Given the generalized constraint force Aᵀλ (M q̈ − (Q − h) at a solved state), a column of A
holding a single unknown multiplier gives it directly; removing its contribution frees the next.
For the rolling ring this finds λ_N first and the no-slip friction λ_1 last, in O(nnz).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from pfaff.core.errors import ConstraintError


def multipliers_by_back_substitution(
    A: np.ndarray | sps.spmatrix, residual: np.ndarray
) -> tuple[np.ndarray, list[int]]:
    """Solve Aᵀλ = residual by peeling, as in the seed's "step backwards".

    Repeatedly take a column of A in which exactly one not-yet-known multiplier appears, solve for
    it, and move the known terms to the right-hand side. For the rolling ring this finds λ_N first,
    then λ_{N-1}, …, and λ_1 (the no-slip friction) last; O(nnz) work.

    Parameters
    ----------
    A : ndarray or sparse matrix, shape (m, n)
    residual : ndarray, shape (n,)
        M q̈ - (Q - h), the generalized constraint force Aᵀλ.

    Returns
    -------
    lam : ndarray, shape (m,)
    order : list of int
        Multiplier indices in the order they were determined.

    Raises
    ------
    ConstraintError
        When no column isolates a single unknown multiplier (use the KKT solve instead).

    Examples
    --------
    >>> import numpy as np
    >>> A = np.array([[1.0, -2.0, 0.0], [0.0, -1.0, 1.0]])
    >>> lam, order = multipliers_by_back_substitution(A, A.T @ np.array([3.0, 5.0]))
    >>> lam.tolist(), order
    ([3.0, 5.0], [1, 0])
    """
    Ac = sps.csc_matrix(A)
    m, n = Ac.shape
    rhs = np.array(residual, dtype=float)
    lam = np.full(m, np.nan)
    unknown_count = np.diff(Ac.indptr).astype(np.int64)
    col_rows = [Ac.indices[Ac.indptr[j] : Ac.indptr[j + 1]] for j in range(n)]
    col_vals = [Ac.data[Ac.indptr[j] : Ac.indptr[j + 1]] for j in range(n)]
    Ar = sps.csr_matrix(A)
    ready = [j for j in range(n) if unknown_count[j] == 1]
    order: list[int] = []
    while ready:
        j = ready.pop()
        if unknown_count[j] != 1:
            continue
        rows, vals = col_rows[j], col_vals[j]
        mask = np.isnan(lam[rows])
        i = int(rows[mask][0])
        lam[i] = rhs[j] / vals[mask][0]
        order.append(i)
        cols = Ar.indices[Ar.indptr[i] : Ar.indptr[i + 1]]
        vals_i = Ar.data[Ar.indptr[i] : Ar.indptr[i + 1]]
        rhs[cols] -= vals_i * lam[i]
        unknown_count[cols] -= 1
        ready.extend(int(c) for c in cols if unknown_count[c] == 1)
    if np.isnan(lam).any():
        raise ConstraintError(
            "the constraint matrix has no triangular structure for back-substitution; "
            "use NumericModel.accelerations (KKT solve)"
        )
    return lam, order
