"""Which rows of a matrix depend on the others: the support of the null space of Aᵀ.

A set of constraint rows is linearly dependent exactly when some y ≠ 0 has Aᵀy = 0; the rows that
take part in a dependency are those where an orthonormal basis Y of null(Aᵀ) is non-zero. Unlike
the pivots of a rank-revealing factorization (which name one arbitrary row of a dependent cycle,
chosen by the BLAS build's rounding), this set is determined by A alone.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse as sps
import scipy.sparse.linalg as spla

SUPPORT_TOL = 1e-8  # a row takes part when its row of Y has at least this norm
DENSE_LIMIT = 200  # rows up to which A is made dense and decomposed by SVD


def dependent_rows(A: np.ndarray | sps.spmatrix, seed: int = 20261124) -> tuple[int, np.ndarray]:
    """Rank of A and the rows that take part in a linear dependency among its rows.

    Parameters
    ----------
    A : ndarray or sparse matrix, shape (m, n)
        Finite values.
    seed : int
        Seed of the start vectors of the sparse path's inverse iteration.

    Returns
    -------
    rank : int
    rows : ndarray of int, shape (k,)
        Ascending indices i with ‖Y[i, :]‖ > 1e-8 for an orthonormal basis Y of null(Aᵀ); empty
        when the rows are independent.

    Examples
    --------
    >>> A = np.array([[1.0, -1.0, 0.0], [0.0, 1.0, -1.0], [1.0, 0.0, -1.0], [1.0, 1.0, 1.0]])
    >>> rank, rows = dependent_rows(A[:3])
    >>> rank, rows.tolist()
    (2, [0, 1, 2])
    >>> dependent_rows(A[[0, 1, 3]])[1].tolist()
    []
    """
    m = A.shape[0]
    if m == 0:
        return 0, np.zeros(0, dtype=np.int64)
    if sps.issparse(A) and m > DENSE_LIMIT:
        Y = _sparse_null_basis(sps.csr_matrix(A, dtype=float), seed)
    else:
        Y = _dense_null_basis(A.toarray() if sps.issparse(A) else np.asarray(A, dtype=float))
    rows = np.flatnonzero(np.linalg.norm(Y, axis=1) > SUPPORT_TOL) if Y.size else np.zeros(0, int)
    return m - Y.shape[1], rows.astype(np.int64)


def _dense_null_basis(A: np.ndarray) -> np.ndarray:
    """Orthonormal basis of null(Aᵀ), shape (m, m - rank), from the SVD of A."""
    m, n = A.shape
    U, s, _ = scipy.linalg.svd(A, full_matrices=True, lapack_driver="gesvd")
    tol = max(m, n) * np.finfo(float).eps * (s[0] if s.size else 0.0) * 10
    rank = int(np.sum(s > tol))
    return U[:, rank:]


def _sparse_null_basis(A: sps.csr_matrix, seed: int) -> np.ndarray:
    """Orthonormal basis of null(Aᵀ) for a large sparse A, shape (m, m - rank).

    A quick test first: the augmented matrix [[I, Aᵀ], [A, 0]] is regular exactly when A has full
    row rank. If it is not, block inverse iteration with S = A Aᵀ + δI (δ tiny) amplifies the
    null space of Aᵀ by 1/δ against every other direction; a Rayleigh–Ritz step on Aᵀ then keeps the
    combinations that Aᵀ annihilates. The block grows until it holds more than the null space.
    """
    m, n = A.shape
    G = sps.bmat([[sps.identity(n), A.T], [A, None]], format="csc")
    try:
        d = np.abs(spla.splu(G).U.diagonal())
        if d.min() >= 1e-11 * d.max():
            return np.zeros((m, 0))
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        pass
    S = (A @ A.T).tocsc()
    scale = float(S.diagonal().max()) or 1.0
    lu = spla.splu((S + 1e-13 * scale * sps.identity(m)).tocsc())
    rng = np.random.default_rng(seed)
    k = min(m, 8)
    while True:
        V = np.linalg.qr(rng.standard_normal((m, k)))[0]
        for _ in range(3):
            V = np.linalg.qr(lu.solve(V))[0]
        _, s, Wt = np.linalg.svd(A.T @ V, full_matrices=False)
        null = s <= 1e-10 * np.sqrt(scale)
        if not null.all() or k == m:
            return np.linalg.qr(V @ Wt[null].T)[0] if null.any() else np.zeros((m, 0))
        k = min(m, 2 * k)


def sparse_null_basis(A: sps.csr_matrix, seed: int = 20261124) -> np.ndarray:
    """An orthonormal basis of null(Aᵀ) of a large sparse A, shape (m, m - rank)."""
    return _sparse_null_basis(A, seed)


def null_basis(A: np.ndarray | sps.spmatrix) -> np.ndarray:
    """An orthonormal basis of null(Aᵀ), shape (m, m - rank) (dense SVD).

    Examples
    --------
    >>> null_basis(np.array([[1.0, 0.0], [2.0, 0.0]])).round(6).ravel().tolist()
    [-0.894427, 0.447214]
    """
    A = A.toarray() if sps.issparse(A) else np.asarray(A, dtype=float)
    if A.shape[0] == 0:
        return np.zeros((0, 0))
    return _dense_null_basis(A)


def redundant_sets(A: np.ndarray | sps.spmatrix) -> list[list[int]]:
    """The rows of A grouped into sets that depend on one another: rows joined when a null
    vector of Aᵀ (from a reduced echelon basis, so that independent dependencies stay apart) is
    non-zero on both. Empty when the rows are independent.

    Examples
    --------
    >>> A = np.array([[1.0, 0], [2.0, 0], [0, 1.0], [0, 3.0]])
    >>> redundant_sets(A)
    [[0, 1], [2, 3]]
    """
    Y = null_basis(A)
    if Y.shape[1] == 0:
        return []
    # a sparse basis of the same space: the reduced echelon form of Yᵀ (pivoted QR then solve)
    _, _, piv = scipy.linalg.qr(Y.T, pivoting=True, mode="economic")
    k = Y.shape[1]
    B = Y @ np.linalg.inv(Y[piv[:k]])  # rows piv[:k] of B are the identity
    parent = list(range(A.shape[0]))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    support = np.abs(B) > SUPPORT_TOL * np.abs(B).max(axis=0, keepdims=True)
    for col in support.T:
        idx = np.flatnonzero(col)
        for j in idx[1:]:
            parent[find(int(j))] = find(int(idx[0]))
    groups: dict[int, list[int]] = {}
    for i in np.flatnonzero(support.any(axis=1)):
        groups.setdefault(find(int(i)), []).append(int(i))
    return sorted(groups.values())
