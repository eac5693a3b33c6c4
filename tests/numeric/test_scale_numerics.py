"""The O(N) numerics under the family model: shared sin/cos, blocked BLAS, threaded kernels, bands."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff
import pfaff.numeric.streams as streams
from pfaff.numeric import trigjit
from pfaff.numeric.banded import LowerBand
from pfaff.numeric.trig import LIMIT, sincos

VALS = {"M": 2.0, "r": 0.5, "F": 3.0}


def test_sincos_matches_libm() -> None:
    rng = np.random.default_rng(0)
    for scale in (1e-6, 1.0, 30.0, 1e4, LIMIT):
        x = rng.uniform(-scale, scale, 50_000)
        s, c = sincos(x)
        assert np.abs(s - np.sin(x)).max() <= 2.3e-16
        assert np.abs(c - np.cos(x)).max() <= 2.3e-16
    x = np.array([0.0, -0.0, np.pi / 2, np.pi, -np.pi, 2 * np.pi, 1e-300, 5e-324])
    s, c = sincos(x)
    np.testing.assert_allclose(s, np.sin(x), rtol=1e-15, atol=2.3e-16)
    np.testing.assert_allclose(c, np.cos(x), rtol=1e-15, atol=2.3e-16)
    assert s[0] == 0.0 and c[0] == 1.0


def test_sincos_strided_out_and_fallback() -> None:
    x = np.linspace(-50, 50, 20_001)
    s, c = np.empty(10_001), np.empty(10_001)
    sincos(x[::2], s, c)  # a strided view, caller's buffers
    np.testing.assert_allclose(s, np.sin(x[::2]), atol=2.3e-16)
    big = np.array([1.0, 3e7, 1e300, -2.5])  # beyond LIMIT: this block goes to the C library
    np.testing.assert_array_equal(sincos(big)[0], np.sin(big))
    with np.errstate(invalid="ignore"):
        bad = sincos(np.array([0.5, np.nan, np.inf]))
    assert np.isnan(bad[0][1:]).all() and bad[1][0] == np.cos(0.5)


def test_compiled_sincos_against_mpmath_and_libm() -> None:
    """The compiled pass (pfaff.numeric.trigjit): π/2's three parts sum to π/2 (mpmath), sin
    and cos within 1.6e-16 of 40-digit values and 2.3e-16 of the C library's up to LIMIT, a
    strided argument, and the C library's values beyond LIMIT, for NaN and infinity."""
    import mpmath

    with mpmath.workdps(50):
        assert (
            abs(sum(map(mpmath.mpf, (trigjit.P1, trigjit.P2, trigjit.P3))) - mpmath.pi / 2) < 1e-35
        )
    fn = trigjit.compiled()
    if fn is None:
        pytest.skip("numba is not installed")
    rng = np.random.default_rng(3)
    for scale in (1e-6, 1.0, 30.0, 1e4, LIMIT):
        x = rng.uniform(-scale, scale, 20_000)
        s, c = np.empty_like(x), np.empty_like(x)
        trigjit.sincos(fn, x, s, c, np.empty(0))
        assert np.abs(s - np.sin(x)).max() <= 2.3e-16 and np.abs(c - np.cos(x)).max() <= 2.3e-16
        with mpmath.workdps(40):
            for i in range(0, 20_000, 500):
                assert abs(mpmath.sin(x[i]) - s[i]) < 1.6e-16
                assert abs(mpmath.cos(x[i]) - c[i]) < 1.6e-16
    x = np.array([0.0, -0.0, np.pi / 2, np.pi, 1e-300, 3e7, 1e300, -np.inf, np.nan, -2.5])
    s, c = np.empty((2, 10)), np.empty((2, 10))
    with np.errstate(invalid="ignore"):
        trigjit.sincos(fn, x, s[0], c[0], np.empty(0))
        trigjit.sincos(fn, np.repeat(x, 2)[::2], s[1], c[1], np.empty(3))  # strided, short tmp
        np.testing.assert_allclose(s, np.sin([x, x]), rtol=1e-15, atol=2.3e-16)
        np.testing.assert_allclose(c, np.cos([x, x]), rtol=1e-15, atol=2.3e-16)
    assert s[0, 0] == 0.0 and c[0, 0] == 1.0 and s[0, 6] == np.sin(1e300)


@pytest.mark.parametrize("n", [1, 8191, 8192, 20_000])
def test_blocked_blas_helpers(n: int) -> None:
    rng = np.random.default_rng(n)
    x, y = rng.normal(size=n), rng.normal(size=n)
    assert streams.dot(x, y) == pytest.approx(float(x @ y), rel=1e-12, abs=1e-12)
    assert streams.dot(x, 2.0) == pytest.approx(2 * x.sum(), rel=1e-12, abs=1e-12)
    expect = y + 0.5 * x
    streams.axpy(0.5, x, y)
    np.testing.assert_allclose(y, expect, rtol=1e-15)


def test_cumsum_band_with_scaled_diagonal() -> None:
    """The running-sum solves with a unit diagonal (no scaling pass) and with a scaled one."""
    m = 300
    for a0 in (1.0, 2.5):
        R = np.vstack([np.full(m, a0), np.full(m, -a0)])
        R[0, 0] = -3.0
        L = np.diag(R[0]) + np.diag(R[1, 1:], -1)
        band = LowerBand(R, constant=True)
        assert band.method == "cumsum"
        c = np.random.default_rng(1).normal(size=m)
        np.testing.assert_allclose(L @ band.solve(c), c, atol=1e-12)
        np.testing.assert_allclose(L.T @ band.solve_t(c), c, atol=1e-12)


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_compiled_backward_running_sum(monkeypatch: pytest.MonkeyPatch) -> None:
    """Lᵀ z = c by the compiled running sum from the end (long bands) and by NumPy's cumsum:
    the same additions in the same order, so the same numbers; and Lᵀ z = c holds."""
    import pfaff.numeric.banded as banded

    m = 5000
    c = np.random.default_rng(2).normal(size=m)
    for a0 in (1.0, 2.5):
        R = np.vstack([np.full(m, a0), np.full(m, -a0)])
        R[0, :2] = [-3.0, 1.5]  # a head of rows that differ from the constant tail
        L = np.diag(R[0]) + np.diag(R[1, 1:], -1)
        monkeypatch.setattr(banded, "JIT_FROM", 10**9)
        ref = LowerBand(R, constant=True).solve_t(c)
        monkeypatch.setattr(banded, "JIT_FROM", 1)
        z = LowerBand(R, constant=True).solve_t(c)
        assert banded._summer() is None or z.strides[0] > 0  # (the compiled path's own array)
        np.testing.assert_array_equal(z, ref)
        np.testing.assert_allclose(L.T @ z, c, atol=1e-9)


def _ring(n: int):
    return pfaff.models.rolling_ring(n, force=True, family=True).equations().compile(VALS)


def test_shared_trig_and_threaded_kernels_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    """sincos path, threads over small chunks, plain NumPy path: the same numbers."""
    n = 5000
    q, qd = pfaff.models.ring_state(n, 0.5, theta=2.0, theta_dot=-4.0)
    q = q + np.random.default_rng(5).normal(0, 0.01, q.shape)  # off the manifold: a real test
    fast = _ring(n)
    assert fast.dyn[0].kernel.angles  # n >= SINCOS_FROM: sin and cos share one reduction
    monkeypatch.setattr(streams, "CHUNK", 512)
    monkeypatch.setattr(streams, "PARALLEL_FROM", 1000)
    threaded = _ring(n)
    monkeypatch.setattr(streams, "JIT_FROM", 1000)  # (compiled sin and cos, on both threads)
    compiled = _ring(n)
    monkeypatch.setattr(streams, "JIT_FROM", 10**9)
    monkeypatch.setattr(streams, "SINCOS_FROM", 10**9)
    monkeypatch.setattr(streams, "PARALLEL_FROM", 10**9)
    plain = _ring(n)
    assert not plain.dyn[0].kernel.angles
    ref = plain.accelerations(0.0, q, qd)
    for model in (fast, threaded, compiled):
        for _ in range(2):  # buffers and partial sums are reused
            qdd, lam = model.accelerations(0.0, q, qd)
            np.testing.assert_allclose(qdd, ref[0], rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(lam, ref[1], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(model.energy(0, q, qd), plain.energy(0, q, qd), rtol=1e-12)
        np.testing.assert_allclose(model.forcing(0, q, qd), plain.forcing(0, q, qd), rtol=1e-12)
    assert compiled.dyn[0].kernel._jit is trigjit.compiled() and not fast.dyn[0].kernel._jit


def test_large_ring_closed_form_with_fast_kernels() -> None:
    n = 2**14
    model = _ring(n)
    q, qd = pfaff.models.ring_state(n, 0.5, theta=np.pi, theta_dot=0.7)
    qdd, lam = model.accelerations(0.0, q, qd)
    np.testing.assert_allclose(qdd[1:], 3.0 / (2 * 2.0 * 0.5), rtol=1e-9)
    assert lam[0] == pytest.approx(-1.5, rel=1e-9)
    assert np.abs(model.acceleration_residual(0.0, q, qd, qdd)).max() <= 1e-9
    # T = ½ M ẋ² + ½ M r² θ̇² for the rolling ring at x = r θ (I = M r², centre speed r θ̇)
    T, V = model.energy(0.0, q, qd)
    assert T == pytest.approx(0.5 * 2.0 * (0.5 * 0.7) ** 2 * 2, rel=1e-12) and V == 0.0


def _two_body_family(n: int):
    """x, y free-ish (p = 2) and a family whose particles couple θ_k and θ_(k+1) in M."""
    import sympy as sp

    k = sp.Symbol("k", integer=True)
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    th = s.add_family("theta", n, first=1)
    r = 0.4
    mid = [x + r * sp.sin(th[k]) + 0.5 * r * sp.sin(th[k + 1]), y + r * sp.cos(th[k + 1])]
    s.add_particle(1.0, mid, name="link", over=(k, 1, n - 1))
    s.add_particle(0.7, [x + r * sp.sin(th[k]), y + r * sp.cos(th[k])], over=k)
    s.add_particle(0.5, [x, y], name="hub")
    s.add_potential_energy(9.81 * y, name="gravity")
    s.add_holonomic_constraint(x - r * th[1], name="no slip")
    s.add_holonomic_constraint(th[k + 1] - th[k] - 0.1, "spacing", over=(k, 1, n - 1))
    return s.equations()


@pytest.mark.parametrize("n", [5, 300])
def test_fused_triangular_path_matches_superlu(n: int) -> None:
    """Tᵀ M T entry by entry (three-array products, p = 2) equals the assembled KKT solve."""
    from pfaff.derive.compile_family import compile_structured

    eom = _two_body_family(n)
    tri, lu = compile_structured(eom, {}), compile_structured(eom, {}, solver="sparse")
    assert tri.solver == "triangular" and tri._solver.C is not None and tri.p == 2
    rng = np.random.default_rng(2)
    q, qd = rng.normal(0, 1, tri.n), rng.normal(0, 1, tri.n)
    for alpha, beta in [(0.0, 0.0), (2.0, 3.0)]:  # fused (c = 0) and general (Baumgarte) paths
        a = tri.solve(0.0, q, qd, alpha, beta)
        b = lu.solve(0.0, q, qd, alpha, beta)
        np.testing.assert_allclose(a[0], b[0], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(a[1], b[1], rtol=1e-9, atol=1e-9)
    qdd = tri.ode_function()(0.0, np.concatenate([q, qd]))[tri.n :]  # q̈ alone, no λ
    np.testing.assert_allclose(qdd, lu.accelerations(0.0, q, qd)[0], rtol=1e-9, atol=1e-9)


def test_ode_function_refuses_non_finite_accelerations() -> None:
    model = _ring(64)
    q, qd = pfaff.models.ring_state(64, 0.5, theta=1.0, theta_dot=0.5)
    fun = model.ode_function()
    y = np.concatenate([q, qd])
    np.testing.assert_allclose(fun(0.0, y)[65 + 1 :], 3.0 / (2 * 2.0 * 0.5), rtol=1e-12)
    y[70] = np.inf
    with np.errstate(invalid="ignore"), pytest.raises(pfaff.StateError, match="NaN or infinite"):
        fun(0.25, y)


def test_streaming_passes_in_spans(monkeypatch: pytest.MonkeyPatch) -> None:
    """axpy and scale over the threads (small spans forced) equal the one-thread results."""
    monkeypatch.setattr(streams, "PARALLEL_FROM", 100)
    monkeypatch.setattr(streams, "SPAN", 64)
    monkeypatch.setattr(streams, "_THREAD", __import__("threading").local())
    rng = np.random.default_rng(4)
    x, y = rng.normal(size=1000), rng.normal(size=1000)
    expect = y + 0.25 * x
    streams.axpy(0.25, x, y)
    np.testing.assert_allclose(y, expect, rtol=1e-15)
    out = np.empty(1000)
    streams.scale(x, -3.0, out)
    np.testing.assert_array_equal(out, -3.0 * x)
    seen: list = []
    streams.in_spans(1000, 64, lambda lo, hi: seen.append((lo, hi)))
    assert sorted(seen) == [(lo, min(lo + 64, 1000)) for lo in range(0, 1000, 64)]
