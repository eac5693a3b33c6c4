"""The GGL residual and sparse Newton matrix of a family model (pfaff.numeric.ggl), against
central differences of the residual and the closed forms of the pushed ring."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff
from pfaff.numeric import trigjit
from pfaff.numeric.ggl import DENSE_ROW_WEIGHT, GGLNewton

N = 16  # (from 16 members on, the x row counts as dense: max(16, 4 √size) entries)


@pytest.fixture(scope="module")
def ring():
    model = pfaff.models.rolling_ring(N, force=True, family=True).equations()
    return model.compile({"M": 1.3, "r": 0.5, "F": 2.0}).for_run()


def _consistent(model, theta: float, theta_dot: float) -> tuple[np.ndarray, np.ndarray]:
    q, qd = pfaff.models.ring_state(N, radius=0.5, theta=theta, theta_dot=theta_dot)
    qdd, lam = model.solve(0.0, q, qd)
    y = np.concatenate([q, qd, lam, np.zeros(N)])
    return y, np.concatenate([qd, qdd, np.zeros(2 * N)])


def test_newton_matrix_matches_differences_of_the_residual(ring) -> None:
    rng = np.random.default_rng(7)
    y, yp = _consistent(ring, 0.4, 1.5)
    y += 0.1 * rng.standard_normal(y.size)  # off the manifold, μ ≠ 0: every term is exercised
    yp += 0.1 * rng.standard_normal(y.size)
    g = GGLNewton(ring, np.arange(N), 0.0, y, yp)
    cj = 37.0
    J = g.matrix(0.0, y, yp, cj).toarray()
    fd = np.empty_like(J)
    plus, minus = np.empty(g.size), np.empty(g.size)
    for j in range(g.size):  # F(y + h e_j, y' + cj h e_j): the column ∂F/∂y_j + cj ∂F/∂y'_j
        h = 1e-6 * max(1.0, abs(y[j]))
        e = np.zeros(g.size)
        e[j] = h
        g.residual(0.0, y + e, yp + cj * e, plus)
        g.residual(0.0, y - e, yp - cj * e, minus)
        fd[:, j] = (plus - minus) / (2 * h)
    alg = np.arange(2 * g.n, g.size)
    fd[alg, alg] = J[alg, alg]  # the regularization of the algebraic diagonal is not in F
    assert np.abs(J[alg, alg]).max() < 1e-7 * np.abs(J).max()
    np.testing.assert_allclose(J, fd, rtol=0, atol=1e-6 * np.abs(J).max())
    # the x row of the ring (every angle's column) is the one weighted row
    assert g.dense_rows.tolist() == [g.n]
    assert np.count_nonzero(J[g.n]) > 2 * N
    assert np.abs(J[g.n]).max() < 2 * DENSE_ROW_WEIGHT * np.abs(J).max()


def test_residual_vanishes_on_the_ring_motion(ring) -> None:
    """At a state on the manifold with q̈, λ from the KKT solve, F = 0; the x row's forcing
    −h_x = (M r/N) Σ sin θ_k θ̇² moves with θ̇, and the Newton row for x holds c_j M and, by
    each θ̇_k, the hand derivative below."""
    y, yp = _consistent(ring, 0.9, 2.0)
    g = GGLNewton(ring, np.arange(N), 0.0, y, yp)
    res = np.empty(g.size)
    g.residual(0.0, y, yp, res)
    assert np.abs(res).max() < 1e-12
    # the ring's closed forms: θ̈ = F/(2Mr), λ_1 = −F/2 whatever θ̇
    assert yp[g.n + 1] == pytest.approx(2.0 / (2 * 1.3 * 0.5), rel=1e-12)
    assert y[2 * g.n] == pytest.approx(-1.0, rel=1e-12)
    J = g.matrix(0.0, y, yp, 5.0).toarray() / DENSE_ROW_WEIGHT
    theta = y[1 : N + 1]
    # by θ̇_k: c_j M_xθ_k − ∂(−h_x)/∂θ̇_k = (M r/N)(c_j cos θ_k − 2 θ̇ sin θ_k), θ̇ = 2
    expected = 1.3 * 0.5 / N * (5.0 * np.cos(theta) - 2 * 2.0 * np.sin(theta))
    np.testing.assert_allclose(J[g.n, g.n + 1 : 2 * g.n], expected, rtol=1e-6, atol=1e-9)
    assert J[g.n, g.n] == pytest.approx(5.0 * 1.3)


def test_scaled_algebraic_unknowns_are_the_same_equations(ring) -> None:
    """Unknowns λ/s, μ/s (s a power of 2): the same residual to the last bit, and J's λ and μ
    columns exactly s times the unscaled ones (its other columns unchanged)."""
    rng = np.random.default_rng(3)
    y, yp = _consistent(ring, 0.4, 1.5)
    y += 0.1 * rng.standard_normal(y.size)
    s = 2.0**70
    plain = GGLNewton(ring, np.arange(N), 0.0, y, yp)
    ys = y.copy()
    ys[2 * plain.n :] /= s
    scaled = GGLNewton(ring, np.arange(N), 0.0, ys, yp, algebraic_scale=s)
    r0, r1 = np.empty(plain.size), np.empty(plain.size)
    plain.residual(0.0, y, yp, r0)
    scaled.residual(0.0, ys, yp, r1)
    np.testing.assert_array_equal(r1, r0)
    J0 = plain.matrix(0.0, y, yp, 21.0).toarray()
    J1 = scaled.matrix(0.0, ys, yp, 21.0).toarray()
    cols = np.ones(plain.size)
    cols[2 * plain.n :] = s
    np.testing.assert_array_equal(J1, J0 * cols)
    # the preconditioner solves for the scaled unknowns: s times smaller λ and μ parts
    scaled.factor(0.0, ys, yp, r1, 21.0)
    plain.factor(0.0, y, yp, r0, 21.0)
    z0, z1 = np.empty(plain.size), np.empty(plain.size)
    plain.precondition(0.0, y, yp, r0, r0, z0, 21.0, 0.0)
    scaled.precondition(0.0, ys, yp, r1, r1, z1, 21.0, 0.0)
    np.testing.assert_allclose(z1 * cols, z0, rtol=1e-9, atol=1e-12 * np.abs(z0).max())


def test_runs_of_one_model_share_its_pattern_not_their_factors() -> None:
    """The pattern and band plan are made once per model (ModelValue.derived); each run's
    factors are its own: factoring one leaves the other's solve as it was."""
    model = pfaff.models.rolling_ring(4096, force=True, family=True).equations()
    model = model.compile({"M": 1.0, "r": 0.5, "F": 2.0})
    q, qd = pfaff.models.ring_state(4096, radius=0.5, theta=0.2)
    runs = [model.for_run(), model.for_run()]
    qdd, lam = runs[0].solve(0.0, q, qd)
    y = np.concatenate([q, qd, lam, np.zeros(4096)])
    yp = np.concatenate([qd, qdd, np.zeros(2 * 4096)])
    a, b = (GGLNewton(r, np.arange(4096), 0.0, y, yp) for r in runs)
    assert a.shape is b.shape and a.band is not None and a.band is not b.band
    assert not a.shape.slot.flags.writeable and not a.band.order.flags.writeable
    res = np.empty(a.size)
    a.factor(0.0, y, yp, res, 10.0)
    r = np.random.default_rng(5).standard_normal(a.size)
    r.flags.writeable = False  # (as IDA's vectors: the compiled gather's one signature)
    za = a.band.solve(r)
    b.factor(0.0, y, yp, res, 1000.0)  # another c_j: another matrix, in b's own storage
    np.testing.assert_array_equal(a.band.solve(r), za)
    J = a.matrix(0.0, y, yp, 10.0)
    assert np.abs(J @ za - r).max() < 1e-8 * np.abs(J).max() * np.abs(za).max()
    # another parameter value is another model: its own pattern
    other = model.with_parameters({"F": 3.0}).for_run()
    assert GGLNewton(other, np.arange(4096), 0.0, y, yp).shape is not a.shape


def test_local_outputs_are_the_kernels_outputs(monkeypatch) -> None:
    """A template kernel's outputs from its local arguments (what the Newton matrix's
    differences perturb) equal its outputs over the streams, per instance, at an irregular
    state: with sin and cos of each angle taken once per array by the compiled pass (the
    thresholds lowered so that a small ring has it), by NumPy, and not hoisted at all."""
    from pfaff.numeric import streams
    from pfaff.numeric.streams import take

    rng = np.random.default_rng(5)
    for sincos_from, jit_from in ((1, 1), (1, 10**9), (10**9, 10**9)):
        monkeypatch.setattr(streams, "SINCOS_FROM", sincos_from)
        monkeypatch.setattr(streams, "JIT_FROM", jit_from)
        ring = pfaff.models.rolling_ring(N, force=True, family=True).equations()
        ring = ring.compile({"M": 1.3, "r": 0.5, "F": 2.0}).for_run()
        q = rng.uniform(-3.0, 3.0, ring.n)
        qd = rng.standard_normal(ring.n)
        kernels = [p.kernel for p in ring.dyn] + [p.res for p in ring.con]
        assert any(k.angles for k in kernels) == (sincos_from == 1)
        checked = 0
        for part in kernels:
            whole = [w if np.ndim(w) == 0 else np.array(w) for w in part(0.3, q, qd)]
            args = [take(c, q) for c in part.columns] + [take(c, qd) for c in part.columns]
            for e, (a, b) in enumerate(zip(whole, part.local(0.3, args), strict=True)):
                if part.const[e] is None and np.ndim(a) == 1:
                    np.testing.assert_allclose(np.broadcast_to(b, a.shape), a, rtol=1e-15)
                    checked += 1
            if part.angles and jit_from == 1 and trigjit.compiled() is not None:
                assert callable(part._jit)  # (the compiled pass did run)
        assert checked == 3  # (every per-instance output that varies with the state)
