"""Machine code above the fused limit (issue 25, item 1): the kernel alone compiled by LLVM and
solved with LAPACK agrees with the template kernels (an independent code generator) and with
the generated Python kernel, at single states, in the integrators' right-hand side and over a
run."""

from __future__ import annotations

import contextlib
import importlib.util
import pickle
from collections.abc import Iterator

import numpy as np
import pytest
import sympy as sp

import pfaff
import systems
from pfaff.derive import fused
from pfaff.numeric.evaluator import MACHINE_LIMIT, OPTIMIZED_LIMIT, machine_opt_level

CART = {"F": 0.7, "g": 9.81}


def cart_parameters(eom: object) -> dict:
    values = {str(p): 1.0 + 0.1 * k for k, p in enumerate(eom.parameters)}  # type: ignore[attr-defined]
    values.update(CART)
    return values


@pytest.fixture
def low_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    """Small systems take the path of large ones: no generated solve above 2 unknowns."""
    monkeypatch.setattr(fused, "FUSED_LIMIT", 2)


@contextlib.contextmanager
def no_array_path() -> Iterator[None]:
    """The machine-code right-hand side must not fall back to the array solve here."""

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("the right-hand side took the array path")

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(pfaff.NumericModel, "_solve", refuse)
        yield


def _models(system: pfaff.System, values: dict) -> dict:
    models = {
        ev: system.equations().compile(values, evaluator=ev)
        for ev in ("template", "python", "machine")
    }
    assert models["machine"].compile_machine_code()  # built (and checked) now
    return models


@pytest.mark.usefixtures("low_limit")
@pytest.mark.parametrize("links", [3])
def test_kernel_machine_code_matches_the_template_kernels(links: int) -> None:
    s = pfaff.models.n_link_pendulum_on_cart(links)
    values = cart_parameters(s.equations())
    models = _models(s, values)
    machine = models["machine"]
    rng = np.random.default_rng(5)
    q, qd = rng.uniform(-1, 1, links + 1), rng.uniform(-1, 1, links + 1)
    want = models["template"].accelerations(0.2, q, qd)[0]
    np.testing.assert_allclose(machine.accelerations(0.2, q, qd)[0], want, rtol=1e-10)
    assert machine.timings["machine_kind"] == "kernel+LAPACK"
    assert machine.timings["machine_opt_level"] == 2 and machine.timings["machine_code"] >= 0
    # the integrators' right-hand side (the preallocated LAPACK path)
    y = np.concatenate([q, qd])
    want = models["template"].ode_function()(0.2, y)
    with no_array_path():
        got = machine.ode_function()(0.2, y)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)


@pytest.mark.usefixtures("low_limit")
def test_kernel_machine_code_with_constraints_and_baumgarte() -> None:
    """The Cartesian pendulum (2 coordinates, 1 constraint): the constraint rows, the Baumgarte
    terms and the multiplier through the LAPACK solve, against the template kernels."""
    s = pfaff.models.cartesian_pendulum()
    values = {"m": 1.3, "g": 9.81, "L": 2.0}
    models = _models(s, values)
    q, qd = np.array([1.2, -1.6]), np.array([0.8, 0.6])  # on the circle, tangent velocity
    y = np.concatenate([q, qd]) + 0.01  # slightly off: the stabilization terms matter
    for alpha, beta in ((0.0, 0.0), (3.0, 2.0)):
        want = models["template"].ode_function(alpha, beta)(0.0, y)
        with no_array_path():
            got = models["machine"].ode_function(alpha, beta)(0.0, y)
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)
    lam = models["machine"].accelerations(0.0, q, qd)[1]
    # the rod's tension −2Lλ = m (g cos φ + v²/L), φ from the downward vertical, |v| = 1
    cos_phi = 1.6 / 2.0
    np.testing.assert_allclose(-2 * 2.0 * lam[0], 1.3 * (9.81 * cos_phi + 1.0 / 2.0), rtol=1e-10)


@pytest.mark.usefixtures("low_limit")
def test_a_run_on_kernel_machine_code_matches_the_generated_python() -> None:
    s = pfaff.models.n_link_pendulum_on_cart(2)
    values = cart_parameters(s.equations())
    q0, qd0 = np.array([0.0, 0.4, -0.3]), np.array([0.1, 0.0, 0.2])
    runs = {
        ev: pfaff.simulate(
            s.equations().compile(values, evaluator=ev), q0, qd0, (0, 1.0), rtol=1e-10, atol=1e-12
        )
        for ev in ("python", "machine")
    }
    assert runs["machine"].status == runs["python"].status == "success"
    np.testing.assert_allclose(runs["machine"].q[-1], runs["python"].q[-1], rtol=1e-7, atol=1e-9)


@pytest.mark.usefixtures("low_limit")
def test_kernel_machine_code_pickles_with_the_model() -> None:
    s = pfaff.models.n_link_pendulum_on_cart(2)
    model = s.equations().compile(cart_parameters(s.equations()), evaluator="machine")
    q, qd = np.array([0.1, 0.4, -0.3]), np.array([0.1, 0.0, 0.2])
    want = model.accelerations(0.0, q, qd)[0]
    there = pickle.loads(pickle.dumps(model))
    assert there.evaluator == "machine"
    np.testing.assert_allclose(there.accelerations(0.0, q, qd)[0], want, rtol=1e-12)


def test_the_optimization_level_follows_the_size() -> None:
    assert OPTIMIZED_LIMIT >= 65  # the 64-link chain on a cart: optimized (split, grouped)
    assert machine_opt_level(OPTIMIZED_LIMIT, 0) == 2
    assert machine_opt_level(MACHINE_LIMIT, 1) is None


@pytest.mark.slow
def test_no_cliff_at_32_unknowns() -> None:
    """The 32-link chain on a cart (33 unknowns): machine code by the rule, the same q̈ as the
    generated Python kernel solved by the array path."""
    s = pfaff.models.n_link_pendulum_on_cart(32)
    eom = s.equations()
    values = cart_parameters(eom)
    machine = eom.compile(values)
    python = eom.compile(values, evaluator="python")
    assert machine.evaluator == "machine"
    rng = np.random.default_rng(2)
    q, qd = rng.uniform(-0.5, 0.5, 33), rng.uniform(-0.5, 0.5, 33)
    y = np.concatenate([q, qd])
    got, want = machine.ode_function()(0.0, y), python.ode_function()(0.0, y)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    jit = importlib.util.find_spec("llvmlite") is not None  # then one compiled call solves
    assert machine.timings["machine_kind"] == ("kernel+Cholesky" if jit else "kernel+LAPACK")
    assert ("compiled_solve" in machine.timings) == jit


def test_a_zero_push_does_no_work_and_a_push_does() -> None:
    """Work integral only where work is done (issue 25, item 3): the chain's push F = 0 has no
    power to integrate (W_nc ≡ 0); F = 0.7 does F·(x(t) − x(0)) of work on the cart."""
    s = pfaff.models.n_link_pendulum_on_cart(2)
    values = cart_parameters(s.equations())
    q0, qd0 = np.array([0.0, 0.4, -0.3]), np.array([0.1, 0.0, 0.2])
    idle = s.equations().compile({**values, "F": 0.0})
    pushed = idle.with_parameters({**values, "F": 0.7})
    assert not idle.applied_power and pushed.applied_power
    still = pfaff.simulate(idle, q0, qd0, (0, 1.0))
    assert np.all(still.nc_work == 0.0) and abs(still.energy_balance).max() < 1e-7
    run = pfaff.simulate(pushed, q0, qd0, (0, 1.0))
    np.testing.assert_allclose(run.nc_work, 0.7 * (run.q[:, 0] - q0[0]), atol=1e-9)


@pytest.mark.usefixtures("low_limit")
def test_kernel_machine_code_reads_a_runs_inputs() -> None:
    """A particle on the line y = x pushed along x by an input u(t) = 4 + t: ẍ = ÿ = u/2, so
    x(1) = (4/2 + 1/6)/2 from rest (the machine-code kernel reads the run's parameter vector)."""
    model = systems.driven_particle().equations().compile({}, evaluator="machine")
    assert model.compile_machine_code() and model.timings["machine_kind"] == "kernel+LAPACK"
    run = pfaff.simulate(model, [0, 0], [0, 0], (0, 1), inputs={"u": lambda t: 4.0 + t})
    assert run.status == "success"
    np.testing.assert_allclose(run.q[-1], [(2.0 + 1.0 / 6.0) / 2] * 2, rtol=1e-8)


@pytest.mark.usefixtures("low_limit")
def test_a_split_kernel_matches_the_template_kernels(monkeypatch: pytest.MonkeyPatch) -> None:
    """The kernel as several LLVM functions of at most 4 outputs (SplitKernel) gives the same
    right-hand side as the template kernels; the count of functions is in ``timings``."""
    from pfaff.derive import machine_kernel

    monkeypatch.setattr(machine_kernel, "KERNEL_CHUNK", 4)
    monkeypatch.setenv("PFAFF_CACHE", "0")  # (a cached unsplit kernel would be loaded)
    s = pfaff.models.n_link_pendulum_on_cart(3)
    values = cart_parameters(s.equations())
    models = _models(s, values)
    machine = models["machine"]
    assert machine.timings["machine_functions"] == 4  # 10 M entries, 4 forcing terms: 14 outputs
    rng = np.random.default_rng(8)
    y = rng.uniform(-1, 1, 8)
    want = models["template"].ode_function()(0.1, y)
    with no_array_path():
        got = machine.ode_function()(0.1, y)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)


def test_a_negative_mass_matrix_takes_the_array_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """A particle at (x, √x): M = 1 + 1/(4x) is negative at x = −0.1, the in-place Cholesky of
    the kernel's right-hand side fails and the array path (an LU solve) answers with
    ẍ = ẋ²/(8x²M) (Lagrange's equation: M ẍ + M'ẋ²/2 = 0, M' = −1/(4x²))."""
    monkeypatch.setattr(fused, "FUSED_LIMIT", 0)
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(1, [x, sp.sqrt(x)])
    model = s.equations().compile({}, evaluator="machine")
    assert model.compile_machine_code() and model.timings["machine_kind"] == "kernel+LAPACK"
    calls = []
    solve = pfaff.NumericModel._solve
    monkeypatch.setattr(
        pfaff.NumericModel, "_solve", lambda *a, **k: calls.append(1) or solve(*a, **k)
    )
    f = model.ode_function()
    np.testing.assert_allclose(
        f(0.0, np.array([0.3, 0.5])), [0.5, 0.25 / (8 * 0.09 * (1 + 1 / 1.2))]
    )
    assert not calls
    np.testing.assert_allclose(f(0.0, np.array([-0.1, 0.5])), [0.5, 0.25 / (0.08 * -1.5)])
    assert calls


def test_a_mass_matrix_with_structural_zeros_is_solved_afresh_each_call(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Two pendulums hung from one cart: M[1, 2] = 0 is outside the kernel's pattern while
    Cholesky fills it in; the in-place factorization of one call must not leak into the next
    (three states in turn, against the template kernels)."""
    monkeypatch.setattr(fused, "FUSED_LIMIT", 0)
    x, a, b = pfaff.coordinates("x a b")
    s = pfaff.System([x, a, b])
    s.add_particle(2.0, [x, 0])
    s.add_particle(0.7, [x + 0.5 * sp.sin(a), -0.5 * sp.cos(a)])
    s.add_particle(1.3, [x + 0.8 * sp.sin(b), -0.8 * sp.cos(b)])
    s.add_potential_energy(9.81 * (-0.7 * 0.5 * sp.cos(a) - 1.3 * 0.8 * sp.cos(b)))
    models = _models(s, {})
    assert models["machine"].timings["machine_kind"] == "kernel+LAPACK"
    f, g = models["machine"].ode_function(), models["template"].ode_function()
    rng = np.random.default_rng(3)
    states = rng.uniform(-1.2, 1.2, (3, 6))
    want = [g(0.0, y) for y in states]
    with no_array_path():
        got = [f(0.0, y) for y in states]
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)


@pytest.mark.slow
def test_the_split_optimized_kernel_at_41_unknowns_matches_the_generated_python() -> None:
    """The 40-link chain on a cart (41 unknowns): grouped, split, optimized machine code by the
    rule, the same right-hand side as the generated Python kernel (its sums as derived, not
    grouped) solved by the array path. (The template kernels took 450 s here.)"""
    s = pfaff.models.n_link_pendulum_on_cart(40)
    eom = s.equations()
    values = cart_parameters(eom)
    machine = eom.compile(values)
    template = eom.compile(values, evaluator="python")
    rng = np.random.default_rng(4)
    y = rng.uniform(-0.5, 0.5, 82)
    got, want = machine.ode_function()(0.0, y), template.ode_function()(0.0, y)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    jit = importlib.util.find_spec("llvmlite") is not None  # then one compiled call solves
    assert machine.timings["machine_kind"] == ("kernel+Cholesky" if jit else "kernel+LAPACK")
    assert ("compiled_solve" in machine.timings) == jit
    assert machine.timings["machine_opt_level"] == 2 and machine.timings["machine_functions"] >= 2
