"""The band-plus-border LU (pfaff.numeric.bordered, its compiled loops pfaff.numeric.bandlu)
against SciPy's SuperLU and LAPACK on the ring's GGL Newton matrix and small made-up matrices."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sps
import scipy.sparse.linalg as spla

import pfaff
from pfaff.numeric import bordered
from pfaff.numeric.bordered import BorderedBand
from pfaff.numeric.ggl import GGLNewton

N = 64  # (the ring's x column and row count as dense from 4 √size = 64 entries on)


@pytest.fixture(scope="module")
def newton():
    model = pfaff.models.rolling_ring(N, force=True, family=True).equations()
    model = model.compile({"M": 1.3, "r": 0.5, "F": 2.0}).for_run()
    q, qd = pfaff.models.ring_state(N, radius=0.5, theta=0.4, theta_dot=1.5)
    qdd, lam = model.solve(0.0, q, qd)
    y = np.concatenate([q, qd, lam, np.zeros(N)])
    yp = np.concatenate([qd, qdd, np.zeros(2 * N)])
    return GGLNewton(model, np.arange(N), 0.0, y, yp), y, yp


def _bordered(n: int, rng: np.random.Generator, kl: int = 2, ku: int = 1) -> sps.csc_matrix:
    """A random band (diagonally dominant) with a dense row and column at index 0."""
    J = sps.random(n, n, density=1.0, random_state=rng, format="lil")
    J = sps.csc_matrix(sps.tril(sps.triu(J, -kl), ku)) + sps.eye(n) * (kl + ku + 2)
    J = sps.lil_matrix(J)
    J[0, :], J[:, 0] = rng.standard_normal(n), rng.standard_normal((n, 1))
    J = sps.csc_matrix(J)
    J.sort_indices()
    return J


def test_the_ring_matrix_is_a_band_with_a_border_of_x(newton) -> None:
    """x's position and velocity columns (every angle's equation meets them) form the border;
    the rest, reordered, is a band 4 wide either side; the solve agrees with SuperLU's."""
    g, y, yp = newton
    band = g.band
    assert band is not None
    assert band.border.tolist() == [0, g.n]  # q_x and v_x (and F₂'s x row)
    assert band.kl <= 4 and band.ku <= 4
    J = g.matrix(0.0, y, yp, 25.0)
    g.factor(0.0, y, yp, np.empty(0), 25.0)
    r = np.random.default_rng(3).standard_normal(g.size)
    z = np.empty(g.size)
    g.precondition(0.0, y, yp, np.empty(0), r, z, 25.0, 0.0)
    ref = spla.splu(J, permc_spec="COLAMD").solve(r)
    np.testing.assert_allclose(z, ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())


@pytest.mark.parametrize(("kl", "ku", "narrow"), [(2, 1, True), (5, 3, False), (2, 6, False)])
def test_compiled_loops_agree_with_lapack(monkeypatch, kl, ku, narrow) -> None:
    """numba's band LU (used from COMPILED_FROM on: the narrow path for a band at most 4 wide
    either side, stored at those widths, else the general loops) and LAPACK's dgbtrf/dgbtrs
    give the same solution of a bordered band, with row interchanges (the band is not dominant
    by rows), factored twice in a row (the kept buffers and factors reused)."""
    rng = np.random.default_rng(11)
    J = _bordered(300, rng, kl, ku)
    J = sps.csc_matrix(J.multiply(rng.uniform(0.1, 10.0, (300, 1))))  # pivots move
    J.sort_indices()
    r = rng.standard_normal(300)
    solutions: list = []
    band: BorderedBand | None = None
    for start in (10**9, 0, 0):
        monkeypatch.setattr(bordered, "COMPILED_FROM", start)
        if len(solutions) < 2:  # (the third time, the second's band again)
            band = BorderedBand.plan(J, dense=20)
        assert band is not None and band.border.tolist() == [0]
        assert ((band.kl, band.ku) == (4, 4)) == (start == 0 and narrow)  # (stored widths)
        flat = band.assemble(band.positions, J.data)
        assert band.factor(flat)
        assert band._narrow == (start == 0 and narrow)
        solutions.append(band.solve(r))
    np.testing.assert_array_equal(solutions[2], solutions[1])
    np.testing.assert_allclose(solutions[1], solutions[0], rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(J @ solutions[1], r, rtol=0, atol=1e-10)


def test_singular_band_is_reported_and_wide_patterns_refused() -> None:
    """B singular (its first row zero once the border is left out) with J regular: factor
    says so (the Newton matrix then goes to SuperLU); a 2-D grid's band is too wide."""
    n = 30
    J = sps.lil_matrix(sps.eye(n) * 4.0)
    J[1, 1] = 0.0
    J[0, 1:] = 1.0  # the dense row and column
    J[1:, 0] = 1.0
    J[1, 0] = 1.0
    J = sps.csc_matrix(J)
    J.sort_indices()
    assert np.linalg.matrix_rank(J.toarray()) == n
    band = BorderedBand.plan(J, dense=10)
    assert band is not None and not band.factor(band.assemble(band.positions, J.data))
    side = 30
    line = sps.diags([-1.0, 2.0, -1.0], [-1, 0, 1], (side, side))
    grid = sps.csc_matrix(sps.kronsum(line, line))
    grid.sort_indices()
    assert BorderedBand.plan(grid, dense=10) is None


@pytest.mark.parametrize("live", [[], [1], [0, 2], [0, 1, 3]])
def test_the_border_scatter_against_numpy(live) -> None:
    """z[order] = y − Xtᵀ zs over the live rows, z[border] = zs, for none, one, two (the pass's
    own) and three live rows (one after the pass)."""
    kernels = bordered._kernels()
    if kernels is None:
        pytest.skip("numba is not installed")
    rng = np.random.default_rng(len(live))
    nb, k = 50, 4
    order = rng.permutation(nb).astype(np.int64)
    border = np.arange(nb, nb + k, dtype=np.int64)
    order.flags.writeable = border.flags.writeable = False
    y, Xt, zs = rng.standard_normal(nb), np.zeros((k, nb)), rng.standard_normal(k)
    rows = np.array(live, dtype=np.int64)
    Xt[rows] = rng.standard_normal((rows.size, nb))
    z = np.full(nb + k, np.nan)
    kernels.scatter_border(z, y, Xt, zs, order, border, rows)
    expected = np.empty(nb + k)
    expected[order] = y - Xt.T @ zs
    expected[border] = zs
    np.testing.assert_allclose(z, expected, rtol=1e-14, atol=1e-14)


def upper_rows(upper: np.ndarray) -> np.ndarray:
    """band_split's U by columns (upper[j, i] = U[j − i, j]) as the narrow one's, by rows."""
    rows = np.zeros_like(upper)
    rows[:, 0] = upper[:, 0]
    for i in range(1, upper.shape[1]):
        rows[:-i, i] = upper[i:, i]
    return rows


@pytest.mark.parametrize(("kl", "ku"), [(4, 4), (2, 1), (1, 3)])
def test_the_narrow_solve_is_the_band_solve_to_the_last_bit(kl, ku) -> None:
    """The narrow factorization and solve (fixed widths, U by rows, the gather inside) do
    band_factor's and band_solve's operations in their order, with row interchanges: the same
    pivots and the same result to the last bit (as values: a zero's sign may differ), from a
    right side in another order (gathered) or in band order (the identity order, in place); and
    it solves the matrix it factored."""
    kernels = bordered._kernels()
    if kernels is None:
        pytest.skip("numba is not installed")
    rng = np.random.default_rng(kl * 10 + ku)
    n = 200
    dense = np.zeros((n, n))
    for d in range(-kl, ku + 1):
        dense += np.diag(rng.standard_normal(n - abs(d)), d)
    dense += np.eye(n) * (kl + ku + 2)
    dense *= np.exp(rng.uniform(-7.0, 7.0, (n, 1)))  # rows scaled apart: the pivots move
    ab = np.zeros((n, 2 * kl + ku + 1))
    for i, j in zip(*np.nonzero(dense), strict=True):
        ab[j, kl + ku + i - j] = dense[i, j]
    piv = np.empty(n, dtype=np.int64)
    assert kernels.band_factor(ab, kl, ku, piv) == 0
    assert (piv != np.arange(n)).sum() > n // 10
    ue = min(kl + ku, ku + int((piv - np.arange(n)).max()))
    assert kl <= kernels.NARROW_L and ue <= kernels.NARROW_U
    lower, upper = np.empty((n, kl)), np.empty((n, ue + 1))
    kernels.band_split(ab, kl, ku, lower, upper)
    narrow = (
        np.empty((n, kernels.NARROW_L)), np.empty(n, dtype=np.int8),
        np.empty((n, kernels.NARROW_U + 1)),
    )  # fmt: skip
    # the narrow factorization: the same matrix stored at the fixed widths, the same factors
    L4, K4 = kernels.NARROW_L, kernels.NARROW_K
    ab4 = np.zeros((n, 2 * L4 + K4 + 1))
    for i, j in zip(*np.nonzero(dense), strict=True):
        ab4[j, L4 + K4 + i - j] = dense[i, j]
    assert kernels.narrow_factor(ab4, *narrow) == 0
    np.testing.assert_array_equal(narrow[1], piv - np.arange(n))
    np.testing.assert_array_equal(narrow[0][:, :kl], lower)
    np.testing.assert_array_equal(narrow[2][:, : ue + 1], upper_rows(upper))
    assert not narrow[0][:, kl:].any() and not narrow[2][:, ue + 1 :].any()
    order = rng.permutation(n).astype(np.int64)
    r = rng.standard_normal(n)
    expected = r[order][None, :].copy()
    kernels.band_solve(lower, upper, piv, expected)
    x = np.full(n, np.nan)
    kernels.narrow_solve(*narrow, r, order, x)
    np.testing.assert_array_equal(x, expected[0])
    x = r[order]  # in place
    kernels.narrow_solve(*narrow, x, np.arange(n), x)
    np.testing.assert_array_equal(x, expected[0])
    np.testing.assert_allclose(x, np.linalg.solve(dense, r[order]), rtol=1e-10, atol=1e-12)
