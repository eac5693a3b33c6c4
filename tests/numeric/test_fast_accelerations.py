"""The fast path of a checked ``accelerations()`` (issue 25): the generated solve's own pivots
decide whether the full path's checks (inertia test, redundant rows, consistency) could find
anything. Where they pass, the result must be the full path's; where they cannot, the full path
must still run and raise or warn as before."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff import InertiaError, StateError
from pfaff.numeric.checkedsolve import fused_accelerations, passes
from pfaff.numeric.inertia import M_PIVOT
from pfaff.numeric.smallsolve import NAMESPACE, schur_source

T = sp.Symbol("t")
EVALUATORS = ["python", "machine"]


def _compiled(system: pfaff.System, values: dict, evaluator: str) -> pfaff.NumericModel:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pfaff.RedundancyWarning)
        model = system.equations().compile(values, evaluator=evaluator)
    assert model.evaluator == evaluator
    return model


def _states(model: pfaff.NumericModel, k: int, seed: int) -> list:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(k):
        q0, qd0 = rng.uniform(-0.8, 0.8, model.n), rng.uniform(-1.0, 1.0, model.n)
        q, qd, _ = model.project(0.0, q0, qd0)
        out.append((float(rng.uniform(0, 2)), q, qd))
    return out


def _models() -> list:
    cart = pfaff.models.n_link_pendulum_on_cart(3)
    return [
        (pfaff.models.cartesian_pendulum(), {"m": 1.3, "g": 9.81, "L": 0.7}),
        (cart, {str(p): 1.0 + 0.1 * i for i, p in enumerate(cart.equations().parameters)}),
        (pfaff.models.parallelogram_fourbar(), pfaff.models.FOURBAR),  # 3 + 2
    ]


@pytest.mark.parametrize("evaluator", EVALUATORS)
@pytest.mark.parametrize("which", [0, 1, 2])
def test_fast_path_is_the_full_checked_path(evaluator: str, which: int) -> None:
    """At regular states the fast path answers (not None) and agrees with the full path
    (assembled augmented matrix, inertia test, redundancy test, LAPACK solve) to 1e-12."""
    system, values = _models()[which]
    model = _compiled(system, values, evaluator)
    for t, q, qd in _states(model, 4, which):
        fast = fused_accelerations(model, t, q, qd)
        assert fast is not None
        full = model._checked_accelerations(t, q, qd)
        scale = 1.0 + np.abs(full[0]).max() + np.abs(full[1]).max(initial=0.0)
        np.testing.assert_allclose(fast[0], full[0], rtol=1e-12, atol=1e-12 * scale)
        np.testing.assert_allclose(fast[1], full[1], rtol=1e-12, atol=1e-12 * scale)
        got = model.accelerations(t, q, qd)  # the public call takes the fast path
        np.testing.assert_array_equal(got[0], fast[0])
        # and it is the solution of M q̈ = Q − h + Aᵀλ, A q̈ = −(Ȧq̇ + ḃ)
        K, rhs = model.kkt_matrix(t, q, qd)
        n = model.n
        res = K @ np.concatenate([got[0], -got[1]]) - rhs
        assert np.abs(res).max() < 1e-10 * (1 + np.abs(K).max() * scale)
        assert got[0].shape == (n,) and got[1].shape == (model.m,)
        np.testing.assert_allclose(_generated_checks(model, t, q, qd), _pivots(K, n), rtol=1e-9)


def _pivots(K: np.ndarray, n: int) -> list[float]:
    """The three checks from NumPy: the smallest Cholesky pivot of the Jacobi-scaled M and of
    the unit-diagonal S = A M⁻¹ Aᵀ, and S's smallest diagonal entry over its largest."""

    def smallest(X: np.ndarray) -> float:
        s = 1 / np.sqrt(np.diag(X))
        return float((np.diag(np.linalg.cholesky(X * s[:, None] * s)) ** 2).min())

    M, A = K[:n, :n], K[n:, :n]
    if not A.shape[0]:
        return [smallest(M), 1.0, 1.0]
    S = A @ np.linalg.solve(M, A.T)
    return [smallest(M), smallest(S), float(np.diag(S).min() / np.diag(S).max())]


def _generated_checks(model: pfaff.NumericModel, t: float, q: np.ndarray, qd: np.ndarray) -> list:
    """The checks the fast path read: the machine code's last outputs, or ``afn``'s."""
    if model.evaluator == "machine":
        return model._machine()(model._run_state["buf"])[-3:].tolist()
    acc = model._fused.afn.function()  # (its checks, before it tests them: _raw)
    return acc(t, q.tolist(), qd.tolist(), model._p, _raw=True)[-3:]


def _free_y(evaluator: str) -> pfaff.NumericModel:
    """x has a particle, y an inertia k ẏ²/2 with k = 0: ÿ is undetermined (a model with a
    fused kernel, whose generated solve meets the zero pivot)."""
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, 0])
    s.add_kinetic_energy(sp.Symbol("k") * y.diff(T) ** 2 / 2)
    s.add_generalized_force(y, sp.sin(x))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # (no machine code: no reference solve)
        return s.equations().compile({"k": 0.0}, evaluator=evaluator)


@pytest.mark.parametrize("evaluator", EVALUATORS)
def test_singular_and_indefinite_mass_are_still_named(evaluator: str) -> None:
    q, qd = np.zeros(2), np.ones(2)
    model = _free_y(evaluator)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        assert fused_accelerations(model, 0.0, q, qd) is None
    with pytest.raises(InertiaError, match=r"acceleration of `y` is undetermined at t = 0"):
        model.accelerations(0.0, q, qd)
    th = pfaff.coordinates("theta")
    s = pfaff.System([th])
    s.add_kinetic_energy(sp.Symbol("I") * th.diff(T) ** 2 / 2)
    s.add_generalized_force(th, 1)
    with pytest.raises(InertiaError, match=r"negative along a motion of `theta`"):
        _compiled(s, {"I": -1.0}, evaluator).accelerations(0.0, np.zeros(1), np.zeros(1))
    good = _compiled(s, {"I": 2.0}, evaluator)
    np.testing.assert_allclose(good.accelerations(0.0, np.zeros(1), np.zeros(1))[0], [0.5])


@pytest.mark.parametrize("evaluator", EVALUATORS)
def test_redundant_rows_are_named_and_lambda_is_minimum_norm(evaluator: str) -> None:
    """x = y twice over (test_solvers' hand derivation): q̈ = (−g/2, −g/2), λ = (−g/10, −g/5)."""
    x, y = pfaff.coordinates("x y")
    g = 9.81
    s = pfaff.System([x, y])
    s.add_particle(1.0, [x, y])
    s.add_potential_energy(g * y)
    s.add_holonomic_constraint(x - y, name="a")
    s.add_holonomic_constraint(2 * x - 2 * y, name="b")
    model = _compiled(s, {}, evaluator)
    q, qd = np.array([0.3, 0.3]), np.array([0.1, 0.1])
    assert fused_accelerations(model, 0.0, q, qd) is None
    with pytest.warns(pfaff.RedundancyWarning, match="`a`, `b` depend on one another"):
        qdd, lam = model.accelerations(0.0, q, qd)
    np.testing.assert_allclose(qdd, [-g / 2, -g / 2], rtol=1e-12)
    np.testing.assert_allclose(lam, [-g / 10, -g / 5], rtol=1e-12)


@pytest.mark.parametrize("evaluator", EVALUATORS)
def test_a_singular_mass_fixed_by_a_constraint_takes_the_full_path(evaluator: str) -> None:
    """(a, b) on the unit circle with T = I (a ḃ − b ȧ)²/2: M singular along (a, b), which the
    constraint fixes. Along the circle, a = cos φ: φ̈ = 0 unforced, so q̈ = −φ̇² (a, b)."""
    a, b = pfaff.coordinates("a b")
    s = pfaff.System([a, b])
    s.add_kinetic_energy(sp.Symbol("I") * (a * b.diff(T) - b * a.diff(T)) ** 2 / 2)
    s.add_holonomic_constraint(a**2 + b**2 - 1, name="unit")
    model = _compiled(s, {"I": 2.0}, evaluator)
    phi, w = 0.4, 1.5
    q = np.array([np.cos(phi), np.sin(phi)])
    qd = w * np.array([-np.sin(phi), np.cos(phi)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # (SymEngine cannot compile its 1/0)
        assert fused_accelerations(model, 0.0, q, qd) is None
    qdd, _ = model.accelerations(0.0, q, qd)
    np.testing.assert_allclose(qdd, -(w**2) * q, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("evaluator", EVALUATORS)
def test_bad_states_raise_the_same_errors(evaluator: str) -> None:
    model = _compiled(pfaff.models.cartesian_pendulum(), {"m": 1, "g": 9.81, "L": 1}, evaluator)
    q, qd = np.array([0.6, -0.8]), np.array([0.8, 0.6])
    cases = [
        ((0.0, np.array([np.nan, -0.8]), qd), r"`q` contains NaN or infinity"),
        ((0.0, q, np.array([np.inf, 0.6])), r"`qd` contains NaN or infinity"),
        ((float("nan"), q, qd), r"`t` is not finite"),
        ((0.0, np.zeros(3), qd), r"`q` must have shape \(2,\)"),
        ((0.0, q, np.zeros((2, 1))), r"`qd` must have shape \(2,\)"),
        ((0.0, q + 0j, qd), r"`q` is complex"),
        ((0.0, np.array([True, False]), qd), r"`q` must be an array of 2 real numbers"),
        ((0.0, q, np.array([1e200, 0.6])), r"not defined at t = 0: a value overflowed"),  # (q̇²)
    ]
    for args, message in cases:
        assert fused_accelerations(model, *args) is None
        with pytest.raises(StateError, match=message):
            model.accelerations(*args)
    # x = 0 is no state to refuse: the cart's position enters no equation, yet ∞ is refused
    cart = pfaff.models.n_link_pendulum_on_cart(1)
    cm = _compiled(cart, {str(p): 1.0 for p in cart.equations().parameters}, evaluator)
    with pytest.raises(StateError, match=r"`q` contains NaN or infinity"):
        cm.accelerations(0.0, np.array([np.inf, 0.1]), np.zeros(2))


def test_the_generated_pivots_are_the_scaled_cholesky_pivots() -> None:
    """The three checks of the generated solve against NumPy: the Cholesky pivots of the
    Jacobi-scaled M and of the unit-diagonal S = A M⁻¹ Aᵀ, and S's diagonal spread."""
    rng = np.random.default_rng(4)
    n, m = 4, 2
    B = rng.normal(size=(n, n))
    M = B @ B.T + np.diag([1e-3, 1.0, 10.0, 100.0])
    A = rng.normal(size=(m, n)) * [[1.0], [30.0]]
    mass = [(i, j) for i in range(n) for j in range(i, n)]
    acon = [(i, j) for i in range(m) for j in range(n)]
    Ms, As = [f"m{s}" for s in range(len(mass))], [f"a{s}" for s in range(len(acon))]
    Fs, cs = [f"F{i}" for i in range(n)], [f"c{i}" for i in range(m)]
    checks: list = []
    lines, _ = schur_source(mass, acon, Ms, As, Fs, cs, checks=checks)
    env = {**NAMESPACE, "min": min, "max": max}
    env |= {name: M[i, j] for name, (i, j) in zip(Ms, mass, strict=True)}
    env |= {name: A[i, j] for name, (i, j) in zip(As, acon, strict=True)}
    env |= {name: 1.0 for name in Fs + cs}
    exec("\n".join(line.strip() for line in lines), env)
    got = [eval(c, env) for c in checks]

    def pivots(X: np.ndarray) -> np.ndarray:
        s = 1 / np.sqrt(np.diag(X))
        return np.diag(np.linalg.cholesky(X * s[:, None] * s)) ** 2

    S = A @ np.linalg.solve(M, A.T)
    want = [pivots(M).min(), pivots(S).min(), np.diag(S).min() / np.diag(S).max()]
    np.testing.assert_allclose(got, want, rtol=1e-10)
    assert passes(*got)
    assert not passes(M_PIVOT / 2, *got[1:])


@pytest.mark.parametrize("evaluator", EVALUATORS)
def test_a_complex_value_is_refused_and_numpy_times_are_fast(evaluator: str) -> None:
    """A force −x^(3/2) at x = −1: Python's (−1.0)**1.5 is complex, not an error, and the
    pivots (of M alone) pass; the generated solve gives it up and the full path names it. A
    NumPy float t takes the fast path (``traj.t[i]`` is one): the same q̈ as a float t."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(2, [x, 0])
    s.add_generalized_force(x, -(x ** sp.Rational(3, 2)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # (SymEngine: no machine code for it)
        model = s.equations().compile({}, evaluator=evaluator)
    with pytest.raises(StateError, match="fractional power of a negative value"):
        model.accelerations(0.0, np.array([-1.0]), np.zeros(1))
    assert fused_accelerations(model, 0.0, np.array([-1.0]), np.zeros(1)) is None
    got = fused_accelerations(model, np.float64(0.5), np.array([4.0]), np.zeros(1))
    if evaluator == "python" or model.evaluator == "machine":
        assert got is not None
        np.testing.assert_allclose(got[0], [-8.0 / 2.0], rtol=1e-15)  # −4^(3/2) / m
