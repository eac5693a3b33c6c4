"""SparseSolver: the COLAMD ordering of the first factorization is reused as it is.

Regression: the reused column permutation was applied inverted (answers exact, fill not), so at
N = 4096 the second factorization of the ring's KKT matrix stored about 4.2 million entries
against 45 thousand for the first. Fill, not time, is the check.
"""

import numpy as np
import pytest

import pfaff
from pfaff.derive.compile_family import compile_structured

N = 4096
PARAMS = {"M": 1.0, "r": 0.5, "F": 2.0}


@pytest.fixture(scope="module")
def sparse_ring():
    eom = pfaff.models.rolling_ring(N, force=True, family=True).equations()
    model = compile_structured(eom, PARAMS, solver="sparse")
    assert model.solver == "sparse"
    return model


def _check(qdd: np.ndarray, lam: np.ndarray) -> None:
    """θ̈_k = F/(2Mr) = 2, ẍ = F/(2M) = 1 and λ_1 = -F/2 = -1 for the pushed ring."""
    np.testing.assert_allclose(qdd[1:], 2.0, rtol=0, atol=1e-9)
    assert qdd[0] == pytest.approx(1.0, abs=1e-9)
    assert lam[0] == pytest.approx(-1.0, abs=1e-9)


def test_reused_ordering_keeps_the_first_fill(sparse_ring):
    model, solver = sparse_ring, sparse_ring._solver
    q, qd = pfaff.models.ring_state(N, radius=0.5, theta=0.3)
    _check(*model.accelerations(0.0, q, qd))  # COLAMD
    first = solver.fill
    assert first is not None and model.stats["fill"] == first
    _check(*model.accelerations(0.0, q, qd))  # the same state, COLAMD's ordering reused
    # The same ordering, hence the same fill, but for pivot ties: SuperLU prefers the entry in
    # the diagonal position of the permuted matrix, which the pre-permuted K moves (45051 → 45050
    # here). The inverted permutation gave ~94x.
    assert solver.fill == pytest.approx(first, rel=1e-3)
    q2, qd2 = pfaff.models.ring_state(N, radius=0.5, theta=1.1, theta_dot=0.7)
    _check(*model.accelerations(0.25, q2, qd2))  # another state: other values, same ordering
    assert solver.fill <= 1.5 * first
    assert model.stats["fill"] == solver.fill
