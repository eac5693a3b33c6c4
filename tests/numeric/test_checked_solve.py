"""The one-pass checked solve of ``accelerations()`` (issue 25, item 4) against the floored
range-space solve it replaces, and the cases it must hand back to the full path."""

from __future__ import annotations

import numpy as np
import pytest

from pfaff.numeric.checkedsolve import checked_solve
from pfaff.numeric.kkt import solve_floored


def _kkt(M: np.ndarray, A: np.ndarray) -> np.ndarray:
    n, m = M.shape[0], A.shape[0]
    K = np.zeros((n + m, n + m))
    K[:n, :n], K[n:, :n], K[:n, n:] = M, A, A.T
    return K


@pytest.mark.parametrize("n, m", [(1, 0), (4, 0), (5, 2), (9, 4)])
def test_agrees_with_the_floored_range_space_solve(n: int, m: int) -> None:
    rng = np.random.default_rng(n + 10 * m)
    B = rng.normal(size=(n, n))
    M = B @ B.T + n * np.eye(n) * rng.uniform(0.5, 3.0, n)  # units of very different sizes too
    A, F, c = rng.normal(size=(m, n)), rng.normal(size=n), rng.normal(size=m)
    got = checked_solve(_kkt(M, A), F, c, n)
    assert got is not None
    want = solve_floored(M, A, F, c)
    np.testing.assert_allclose(got[0], want[0], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(got[1], want[1], rtol=1e-10, atol=1e-12)
    # and it is the solution: M q̈ = F + Aᵀλ, A q̈ = c
    np.testing.assert_allclose(M @ got[0], F + A.T @ got[1], rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(A @ got[0], c, rtol=1e-9, atol=1e-10)


def test_hands_back_what_the_full_path_must_decide() -> None:
    M, F = np.eye(3), np.ones(3)
    singular = np.diag([1.0, 1.0, 0.0])
    assert checked_solve(_kkt(singular, np.zeros((0, 3))), F, np.zeros(0), 3) is None
    redundant = np.array([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    assert checked_solve(_kkt(M, redundant), F, np.zeros(2), 3) is None
    zero_row = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert checked_solve(_kkt(M, zero_row), F, np.zeros(2), 3) is None
    assert (
        checked_solve(_kkt(M, np.zeros((0, 3))), np.array([1.0, np.nan, 0.0]), np.zeros(0), 3)
        is None
    )
