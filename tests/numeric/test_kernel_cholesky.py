"""The compiled right-hand side above the fused limit (LLVM JIT through llvmlite, :mod:`pfaff.numeric.kernelchol`):
the Cholesky solve against NumPy's, the whole call on a hand-made two-function LLVM kernel
against the closed-form 2 × 2 solve, and in a model against the SciPy LAPACK path it replaces."""

from __future__ import annotations

import numpy as np
import pytest
import symengine as se
import sympy as sp

import pfaff
from pfaff.derive import fused
from pfaff.derive.machine_kernel import SplitKernel
from pfaff.numeric import kernelsolve
from pfaff.numeric.machineloop import entry_point

kernelchol = pytest.importorskip("pfaff.numeric.kernelchol")  # (llvmlite)


def _solved(A: np.ndarray, b: np.ndarray) -> tuple[int, np.ndarray]:
    """:func:`kernel_cholesky` with no LLVM function: its "outputs" set to A's upper
    triangle, row by row, and b; (what it returns, q̈)."""
    n = len(b)
    rows, cols = np.triu_indices(n)
    plan, work = kernelchol.plan_of([], rows * n + cols, n, rows.size + n)
    work[: rows.size + n] = np.concatenate([A[rows, cols], b])
    info = kernelchol.kernel_cholesky(plan, np.zeros(1 + 2 * n), work)
    return info, work[-n:]


@pytest.mark.parametrize("n", [7, 33, 65])  # (LLVM's vector loops and their remainders)
def test_the_cholesky_solve_matches_numpy_and_names_the_failing_pivot(n: int) -> None:
    rng = np.random.default_rng(3)
    B = rng.standard_normal((n, n))
    A, b = B @ B.T + 0.5 * np.eye(n), rng.standard_normal(n)
    info, x = _solved(A, b)
    assert info == 0
    want = np.linalg.solve(A, b)
    np.testing.assert_allclose(x, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    # [[1, 2], [2, 1]]: the second pivot is 1 − 2² < 0
    assert _solved(np.array([[1.0, 2.0], [2.0, 1.0]]), np.ones(2))[0] == 2


def _kernel_plan(f: float) -> tuple:
    """M = [[2 + q0², q1], [q1, 3]] and Q − h = [f·q0, 1] as two LLVM functions of
    x = [t, q0, q1, q̇0, q̇1] (3 + 2 outputs), and the plan of :func:`kernel_cholesky`."""
    t, q0, q1, u0, u1 = se.symbols("t q0 q1 u0 u1")
    x = [t, q0, q1, u0, u1]
    parts = [
        se.Lambdify(x, [2 + q0**2, q1, 3], backend="llvm", real=True),
        se.Lambdify(x, [f * q0, 1], backend="llvm", real=True),
    ]
    kernel = SplitKernel(parts, [3, 2])
    functions = [(*entry_point(p), o) for p, o in zip(parts, kernel.offsets[:2], strict=True)]
    upper = np.array([0, 1, 3])  # M00, M01, M11 at i·n + j
    return kernel, kernelchol.plan_of(functions, upper, 2, 5)


def test_one_call_gives_the_closed_form_accelerations() -> None:
    _keep, (plan, work) = _kernel_plan(4.0)  # (the LLVM functions stay alive)
    q0, q1, u = 0.5, 0.7, [0.3, -0.2]
    assert kernelchol.kernel_cholesky(plan, np.array([0.0, q0, q1, *u]), work) == 0
    a, b, c = 2 + q0**2, q1, 3.0  # [[a, b], [b, c]]⁻¹ [4 q0, 1] by Cramer's rule
    det = a * c - b * b
    want = [(c * 4 * q0 - b * 1) / det, (a * 1 - b * 4 * q0) / det]
    np.testing.assert_allclose(work[-4:], [*u, *want], rtol=1e-14)
    # M not positive definite (|q1| > sqrt(3 a)): the second pivot; q̈ not finite: −1
    assert kernelchol.kernel_cholesky(plan, np.array([0.0, 0.0, 3.0, *u]), work) == 2
    assert kernelchol.kernel_cholesky(plan, np.array([0.0, np.inf, 0.0, *u]), work) == -1


@pytest.fixture
def low_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fused, "FUSED_LIMIT", 2)


@pytest.mark.usefixtures("low_limit")
def test_a_models_compiled_rhs_matches_the_lapack_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """The 2-link chain on a cart above a lowered fused limit: the compiled call and SciPy's
    ``dppsv`` on the same kernel agree to rounding."""
    s = pfaff.models.n_link_pendulum_on_cart(2)
    values = {str(p): 1.0 + 0.1 * k for k, p in enumerate(s.equations().parameters)}
    model = s.equations().compile(values, evaluator="machine")
    y = np.random.default_rng(4).uniform(-1, 1, 6)
    got = model.ode_function().on_lists(0.3, y.tolist())
    assert model.timings["compiled_solve"] >= 0.0  # the compiled call was made
    monkeypatch.setattr(kernelsolve, "_compiled_rhs", lambda *args: None)
    want = model.ode_function().on_lists(0.3, y.tolist())
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)


@pytest.mark.usefixtures("low_limit")
def test_the_compiled_rhs_reads_a_runs_inputs() -> None:
    """A free particle in space pushed along x by an input u(t) = 4 + t: ẍ = u/2 for a mass of 2,
    so x(1) = (4/2 + 1/6)/2 from rest (the compiled call reads the run's parameter vector)."""
    x, y, z = pfaff.coordinates("x y z")
    u = sp.Symbol("u")
    s = pfaff.System([x, y, z])
    s.add_particle(2, [x, y, z])
    s.add_force([u, 0, 0], at=[x, y, z])
    s.add_input(u)
    model = s.equations().compile({}, evaluator="machine")
    run = pfaff.simulate(model, [0, 0, 0], [0, 0, 0], (0, 1), inputs={"u": lambda t: 4.0 + t})
    assert run.status == "success" and "compiled_solve" in model.timings
    np.testing.assert_allclose(run.q[-1], [(2.0 + 1.0 / 6.0) / 2, 0.0, 0.0], rtol=1e-8, atol=1e-12)
