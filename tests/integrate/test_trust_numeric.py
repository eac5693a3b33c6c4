"""Bad input at the numeric stages ends in pfaff's own error naming the argument, or in a right answer.

Findings of the review "where values enter the numeric stages":

1. An acceleration nothing determines (a coordinate without inertia and without a constraint)
   used to come out of a least-squares solve as q̈ = 0; negative inertia went through unnoticed.
   Now: :class:`pfaff.InertiaError` naming the coordinates, at a single state and at the first
   state of a run (ZᵀMZ positive definite, Z a basis of null(A)). A singular M whose augmented
   matrix is regular (a unit "quaternion" in the plane) is a valid model and now solves at
   every state (it used to fail where a Cholesky factorization of M passed on rounding).
3. Complex states were cast to real with a mere ComplexWarning.
4. ``initial_tol=nan`` switched the initial check off; SciPy's own messages surfaced for
   ``max_step``/``first_step``.
5. A zero generalized force broke the assembly of Q - h.
6. ``simulate(eom, ...)`` (no ``.compile()``) gave an AttributeError; odd ``q0`` types gave
   messages not naming the argument.
7. An overflow in generated code escaped as a bare OverflowError.
8. Non-finite or non-real ``t``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import pfaff
from methods import ALL_METHODS
from pfaff import InertiaError, ModelTypeError, OptionError, StateError
from pfaff.numeric.model import NumericModel

T = pfaff.t


def pendulum_model(length: float = 1.0, evaluator: str | None = None) -> NumericModel:
    eom = pfaff.models.cartesian_pendulum().equations()
    return eom.compile({"m": 1.0, "g": 9.81, "L": length}, evaluator=evaluator)


def free_y_model(force_on_y: object = None) -> NumericModel:
    """x has a particle, y nothing at all: ÿ is undetermined."""
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, 0])
    if force_on_y is not None:
        s.add_generalized_force(y, force_on_y)
    return s.equations().compile({})


def unit_rotor(inertia: float = 2.0) -> NumericModel:
    """(a, b) on the unit circle, T = I (a ḃ − b ȧ)²/2: M = I [[b², −ab], [−ab, a²]] is singular
    along (a, b) at every state, but the constraint a² + b² = 1 fixes that direction (the planar
    analogue of quaternion attitude coordinates)."""
    a, b = pfaff.coordinates("a b")
    s = pfaff.System([a, b])
    s.add_kinetic_energy(sp.Symbol("I") * (a * b.diff(T) - b * a.diff(T)) ** 2 / 2)
    s.add_holonomic_constraint(a**2 + b**2 - 1, name="unit")
    return s.equations().compile({"I": inertia})


# ---------------------------------------------------------------- 1. undetermined accelerations
def test_undetermined_coordinate_named_at_a_state() -> None:
    model = free_y_model()
    with pytest.raises(InertiaError, match=r"acceleration of `y` is undetermined at t = 0"):
        model.accelerations(0.0, [0.0, 0.0], [1.0, 1.0])
    assert issubclass(InertiaError, pfaff.ConstraintError)


@pytest.mark.parametrize("method", ALL_METHODS)
def test_undetermined_coordinate_refuses_a_run(method: str) -> None:
    """It used to report success with y frozen at its initial value."""
    with pytest.raises(InertiaError, match=r"`y` is undetermined"):
        pfaff.simulate(free_y_model(), [0.0, 0.0], [1.0, 1.0], (0.0, 1.0), method=method)


def test_forced_coordinate_without_inertia_is_named() -> None:
    """A force on it makes the equations inconsistent: the cause is named, not only the symptom."""
    with pytest.raises(InertiaError, match=r"`y` is undetermined"):
        free_y_model(force_on_y=1).accelerations(0.0, [0.0, 0.0], [0.0, 0.0])


def test_undetermined_direction_names_its_coordinates_only() -> None:
    """u = v tied by a constraint, neither with inertia: the direction (0, 1, 1) is free."""
    x, u, v = pfaff.coordinates("x u v")
    s = pfaff.System([x, u, v])
    s.add_particle(1, [x, 0])
    s.add_holonomic_constraint(u - v, name="tie")
    model = s.equations().compile({})
    with pytest.raises(InertiaError, match=r"acceleration of `u`, `v` is undetermined") as info:
        model.accelerations(0.0, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    assert "`x`" not in str(info.value)


def test_sparse_model_names_the_free_coordinate() -> None:
    """n + m > 400: SuperLU's "singular" becomes the O(nnz) test naming the coordinate."""
    qs = pfaff.coordinates(" ".join(f"x{i}" for i in range(402)))
    s = pfaff.System(list(qs))
    for q in qs[:-1]:
        s.add_particle(1, [q, 0])
    model = s.equations().compile({})
    assert not model.dense
    with pytest.raises(InertiaError, match=r"`x401` is undetermined"):
        model.accelerations(0.0, np.zeros(402), np.zeros(402))
    with pytest.raises(InertiaError, match=r"`x401` is undetermined"):
        pfaff.simulate(model, np.zeros(402), np.ones(402), (0.0, 1.0))


def test_negative_inertia_of_a_kinetic_term() -> None:
    """T = I θ̇²/2 with I = −1: θ̈ = Q/I used to come out with the wrong sign, silently."""
    th = pfaff.coordinates("theta")
    s = pfaff.System([th])
    s.add_kinetic_energy(sp.Symbol("I") * th.diff(T) ** 2 / 2)
    s.add_generalized_force(th, 1)
    model = s.equations().compile({"I": -1.0})
    with pytest.raises(InertiaError, match=r"negative along a motion of `theta`"):
        model.accelerations(0.0, [0.0], [0.0])
    with pytest.raises(InertiaError, match=r"negative along a motion of `theta`"):
        pfaff.simulate(model, [0.0], [0.0], (0.0, 1.0))
    good = s.equations().compile({"I": 2.0})
    np.testing.assert_allclose(good.accelerations(0.0, [0.0], [0.0])[0], [0.5], rtol=1e-15)


def test_singular_mass_matrix_with_regular_augmented_matrix() -> None:
    """The unit rotor spinning at ω = 3: q̈ = −ω² q and λ = −I ω² (the a-equation at (1, 0):
    d/dt(−Iωb) − Iωḃ = −2Iω² = 2aλ), at every angle, not only where M's rounding is kind."""
    model = unit_rotor(2.0)
    for th in np.linspace(0.0, 3.0, 13):
        q = np.array([math.cos(th), math.sin(th)])
        qdd, lam = model.accelerations(0.0, q, 3.0 * np.array([-q[1], q[0]]))
        np.testing.assert_allclose(qdd, -9.0 * q, atol=1e-12)
        np.testing.assert_allclose(lam, [-18.0], rtol=1e-12)


@pytest.mark.parametrize("method", ["projection", "baumgarte"])
def test_singular_mass_matrix_simulates(method: str) -> None:
    """It used to fail at t = 4e-95 (garbage q̈ from a Cholesky of the singular M)."""
    te = np.array([0.0, 0.5, 1.0, 2.0])
    traj = pfaff.simulate(
        unit_rotor(2.0), [1.0, 0.0], [0.0, 3.0], (0.0, 2.0), t_eval=te, method=method
    )
    assert traj.status == "success", traj.message
    np.testing.assert_allclose(traj.q, np.c_[np.cos(3 * te), np.sin(3 * te)], atol=1e-8)
    np.testing.assert_allclose(traj.multipliers[:, 0], -18.0, rtol=1e-6)


def test_inertia_check_runs_once_per_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """The O(n³) test belongs to the first state, never to the right-hand side."""
    import pfaff.numeric.checked as numeric_model

    calls = []
    inner = numeric_model.inertia_test

    def spy(K: np.ndarray, t: float, *args: object) -> bool:
        calls.append(t)
        return inner(K, t, *args)

    monkeypatch.setattr(numeric_model, "inertia_test", spy)
    traj = pfaff.simulate(unit_rotor(), [1.0, 0.0], [0.0, 3.0], (0.0, 2.0))
    assert traj.status == "success" and traj.stats["nfev"] > 100
    assert calls == [0.0]


# ---------------------------------------------------------------- 3. complex states
def _entry_points(model: NumericModel) -> dict:
    return {
        "accelerations": lambda q, qd: model.accelerations(0.0, q, qd),
        "energy": lambda q, qd: model.energy(0.0, q, qd),
        "constraint_residual": lambda q, qd: model.constraint_residual(0.0, q, qd),
        "forcing": lambda q, qd: model.forcing(0.0, q, qd),
        "mass_matrix": lambda q, qd: model.mass_matrix(0.0, q, qd),
        "kkt_matrix": lambda q, qd: model.kkt_matrix(0.0, q, qd),
        "check_determined": lambda q, qd: model.check_determined(0.0, q, qd),
        "consistent_state": lambda q, qd: pfaff.consistent_state(model, q, qd, ["x"]),
    }


@pytest.mark.parametrize(
    "name",
    [
        "accelerations",
        "energy",
        "constraint_residual",
        "forcing",
        "mass_matrix",
        "kkt_matrix",
        "check_determined",
        "consistent_state",
    ],
)
def test_complex_state_refused_everywhere(name: str) -> None:
    call = _entry_points(pendulum_model())[name]
    with pytest.raises(StateError, match=r"`q` is complex"):
        call(np.array([1.0 + 1j, 0.0]), np.zeros(2))
    with pytest.raises(StateError, match=r"`qd` is complex"):
        call(np.array([1.0, 0.0]), np.array([0.0, 0j]))


def test_complex_state_refused_by_simulate_and_constraint_matrix() -> None:
    model = pendulum_model()
    with pytest.raises(StateError, match=r"`q0` is complex"):
        pfaff.simulate(model, np.array([1.0 + 0j, 0.0]), [0.0, 0.0], (0.0, 1.0))
    with pytest.raises(StateError, match=r"`qd0` is complex"):
        pfaff.simulate(model, [1.0, 0.0], np.array([0.0, 1j]), (0.0, 1.0))
    with pytest.raises(StateError, match=r"`q` is complex"):
        model.constraint_matrix(0.0, [1.0 + 1j, 0.0])


def test_complex_state_refused_by_a_family_model() -> None:
    ring = pfaff.models.rolling_ring(4, force=True, family=True)
    model = ring.equations().compile({"M": 1, "r": 0.5, "F": 2})
    q, qd = pfaff.models.ring_state(4, radius=0.5, theta=0.3)
    with pytest.raises(StateError, match=r"`q` is complex"):
        model.accelerations(0.0, q + 0j, qd)
    with pytest.raises(StateError, match=r"`qdd` is complex"):
        model.acceleration_residual(0.0, q, qd, np.zeros(5, dtype=complex))
    with pytest.raises(StateError, match=r"`lam` is complex"):
        model.constraint_force(0.0, q, np.zeros(4, dtype=complex))


def test_exact_numbers_are_real_numbers() -> None:
    """SymPy numbers and integers are real values: the same answer as floats."""
    model = pendulum_model()
    ref = model.accelerations(0.0, [0.6, -0.8], [0.8, 0.6])
    got = model.accelerations(0, [sp.Rational(3, 5), sp.Float(-0.8)], [sp.Float(0.8), 0.6])
    np.testing.assert_array_equal(got[0], ref[0])
    np.testing.assert_array_equal(got[1], ref[1])


# ---------------------------------------------------------------- 4. options
@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("initial_tol", math.nan),
        ("initial_tol", -1.0),
        ("initial_tol", math.inf),
        ("initial_tol", "1e-8"),
        ("max_step", 0.0),
        ("max_step", -0.1),
        ("max_step", math.nan),
        ("max_step", "0.1"),
        ("first_step", 0.0),
        ("first_step", -0.1),
        ("first_step", math.nan),
        ("first_step", 5.0),  # longer than t_span
        ("rtol", True),
        ("atol", 1j),
        ("alpha", math.nan),
        ("constraint_tol", "1e-9"),
        ("method", ["projection"]),
        ("integrator", "Radau"),
        ("integrator", None),
        ("ida_jacobian", "exact"),
        ("project_initial", "yes"),
        ("project_output", 1),
        ("progress", "no"),
        ("throw", None),
        ("t_eval", [0.0, 0.5j]),
    ],
)
def test_bad_option_named(key: str, value: object) -> None:
    with pytest.raises(OptionError, match=f"`{key}`|method"):
        pfaff.simulate(pendulum_model(), [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), **{key: value})


@pytest.mark.parametrize("method", ["projection", "ida"])
def test_max_step_zero_refused_before_scipy_or_ida(method: str) -> None:
    with pytest.raises(OptionError, match=r"`max_step` must be positive"):
        pfaff.simulate(
            pendulum_model(), [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), max_step=0, method=method
        )


def test_nan_initial_tol_does_not_switch_the_check_off() -> None:
    """0.3 off the rod used to be projected silently with initial_tol = nan."""
    model = pendulum_model()
    with pytest.raises(OptionError, match=r"`initial_tol` is NaN"):
        pfaff.simulate(model, [1.3, 0.0], [0.0, 0.0], (0.0, 1.0), initial_tol=math.nan)
    with pytest.raises(StateError, match=r"off the constraint manifold"):
        pfaff.simulate(model, [1.3, 0.0], [0.0, 0.0], (0.0, 1.0), initial_tol=1e-3)


def test_t_span_of_strings_refused_and_infinite_max_step_allowed() -> None:
    model = pendulum_model()
    with pytest.raises(OptionError, match=r"`t_span`"):
        pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], ("0", "1"))
    traj = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 0.5), max_step=math.inf)
    assert traj.status == "success"
    traj = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 0.5), first_step=0.5)
    assert traj.status == "success"


def test_consistent_state_options() -> None:
    model = pendulum_model()
    with pytest.raises(OptionError, match=r"`tol`"):
        pfaff.consistent_state(model, [0.6, -1.0], [0.8, 0.0], ["x"], tol=math.nan)
    with pytest.raises(OptionError, match=r"`max_iter`"):
        pfaff.consistent_state(model, [0.6, -1.0], [0.8, 0.0], ["x"], max_iter=-1)
    with pytest.raises(StateError, match=r"`independent`"):
        pfaff.consistent_state(model, [0.6, -1.0], [0.8, 0.0], "x")


# ---------------------------------------------------------------- 5. zero forces
def falling_point(zero_piece) -> NumericModel:
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_potential_energy(9.81 * y)
    zero_piece(s, x, y)
    return s.equations().compile({})


@pytest.mark.parametrize(
    "zero_piece",
    [
        lambda s, x, y: s.add_generalized_force(x, 0),
        lambda s, x, y: s.add_generalized_force(y, 0 * x),
        lambda s, x, y: s.add_force([0, 0], at=[x, y]),
    ],
    ids=["genforce x", "genforce y", "force"],
)
def test_zero_force_contributes_nothing(zero_piece) -> None:
    """Free fall from (0, 0) with (ẋ, ẏ) = (1, 1): x = t, y = t − g t²/2."""
    model = falling_point(zero_piece)
    np.testing.assert_array_equal(model.forcing(0.0, [0.0, 0.0], [1.0, 1.0]), [0.0, -9.81])
    np.testing.assert_array_equal(model.accelerations(0.0, [0.0, 0.0], [1.0, 1.0])[0], [0.0, -9.81])
    traj = pfaff.simulate(model, [0.0, 0.0], [1.0, 1.0], (0.0, 1.0), t_eval=[0.0, 0.5, 1.0])
    assert traj.status == "success", traj.message
    te = traj.t
    np.testing.assert_allclose(traj.q, np.c_[te, te - 9.81 * te**2 / 2], atol=1e-12)


def test_zero_generalized_force_in_a_family_model() -> None:
    ring = pfaff.models.rolling_ring(8, force=True, family=True)
    ring.add_generalized_force(ring.coordinates[0], 0)
    model = ring.equations().compile({"M": 1, "r": 0.5, "F": 2})
    q, qd = pfaff.models.ring_state(8, radius=0.5, theta=0.3)
    qdd, lam = model.accelerations(0.0, q, qd)
    assert (round(float(qdd[0]), 12), round(float(lam[0]), 12)) == (1.0, -1.0)  # ẍ = F/(2M)


# ---------------------------------------------------------------- 6. model and state types
def test_uncompiled_equations_named() -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    with pytest.raises(ModelTypeError, match=r"`model`.*call `\.compile\(parameters\)`") as info:
        pfaff.simulate(eom, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0))
    assert isinstance(info.value, TypeError)
    with pytest.raises(ModelTypeError, match=r"`model`.*\.compile\(parameters\)"):
        pfaff.consistent_state(eom, [1.0, 0.0], [0.0, 0.0], ["x"])
    with pytest.raises(ModelTypeError, match=r"`\.equations\(\)\.compile\(parameters\)`"):
        pfaff.simulate(pfaff.models.cartesian_pendulum(), [1.0, 0.0], [0.0, 0.0], (0.0, 1.0))
    with pytest.raises(ModelTypeError, match=r"`model` must be a compiled model; got str|got str"):
        pfaff.simulate("pendulum", [1.0, 0.0], [0.0, 0.0], (0.0, 1.0))


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        ("ab", "got str"),
        ({"x": 1.0}, "got dict"),
        (None, "got NoneType"),
        ([1.0, 0.0, 0.0], r"shape \(2,\)"),
        ([[1.0, 0.0]], r"shape \(2,\)"),
        ([1.0, [0.0]], "real numbers"),
        ([True, False], "dtype bool"),
        (["1", "0"], "dtype <U1"),
        ([1.0, math.nan], "NaN or infinity"),
    ],
)
def test_bad_initial_state_named(value: object, problem: str) -> None:
    model = pendulum_model()
    with pytest.raises(StateError, match=rf"`q0`.*{problem}"):
        pfaff.simulate(model, value, [0.0, 0.0], (0.0, 1.0))
    with pytest.raises(StateError, match=rf"`qd0`.*{problem}"):
        pfaff.simulate(model, [1.0, 0.0], value, (0.0, 1.0))
    with pytest.raises(StateError, match=rf"`q`.*{problem}"):
        model.accelerations(0.0, value, [0.0, 0.0])


# ---------------------------------------------------------------- 7. overflow
def test_overflow_at_a_state_is_a_state_error() -> None:
    """`pfaff demo pendulum --length 1e200`: L² overflows in the generated code."""
    model = pendulum_model(1e200)
    for call in (model.accelerations, model.constraint_residual, model.kkt_matrix):
        with pytest.raises(StateError, match=r"not defined at t = 0: a value overflowed"):
            call(0.0, [1e200, 0.0], [0.0, 0.0])
    model = pendulum_model(1e200, evaluator="template")  # the template kernels: the same error
    with pytest.raises(StateError, match=r"not defined at t = 0: a value overflowed"):
        model.accelerations(0.0, [1e200, 0.0], [0.0, 0.0])


def test_overflow_at_the_initial_state_is_a_state_error() -> None:
    with pytest.raises(StateError, match=r"not defined at t = 0: a value overflowed"):
        pfaff.simulate(pendulum_model(1e200), [1e200, 0.0], [0.0, 0.0], (0.0, 1.0))


def test_overflow_during_a_run_is_a_failed_run() -> None:
    """ẍ = exp(1000 t) from V = −x exp(1000 t): exp overflows past t = ln(max float)/1000 ≈
    0.7098, a failed run there (the energies reported on the way overflow to −inf first)."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_kinetic_energy(x.diff(T) ** 2 / 2)
    s.add_potential_energy(-x * sp.exp(1000 * T))
    model = s.equations().compile({})
    with np.errstate(all="ignore"):
        traj = pfaff.simulate(model, [0.0], [0.0], (0.0, 1.0))
    assert traj.status == "failed"
    assert "failed at t = 0.70" in traj.message
    assert "not defined" in traj.message or "NaN or infinite" in traj.message
    assert 0.70 < traj.t[-1] < 0.7098


def test_overflow_in_a_family_model_is_not_returned() -> None:
    """r² = 1e400 leaves the double range: the kernels take r at run time, where the overflow
    raises, and name the time; a state that overflows in NumPy's arrays (inf without raising)
    is checked, not returned."""
    ring = pfaff.models.rolling_ring(8, force=True, family=True)
    model = ring.equations().compile({"M": 1, "r": 1e200, "F": 2})
    q, qd = pfaff.models.ring_state(8, radius=1e200, theta=0.3)
    qd[:] = 1.0
    with np.errstate(all="ignore"):
        with pytest.raises(StateError, match=r"not defined at t = 0: a value overflowed"):
            model.accelerations(0.0, q, qd)
    model = ring.equations().compile({"M": 1, "r": 0.5, "F": 2})
    q, qd = pfaff.models.ring_state(8, radius=0.5, theta=0.3)
    qd[:] = 1e200  # T = M ẋ²: inf in NumPy, no exception
    with np.errstate(all="ignore"):
        with pytest.raises(StateError, match=r"NaN or infinite at t = 0"):
            model.accelerations(0.0, q, qd)


# ---------------------------------------------------------------- 8. time
@pytest.mark.parametrize(
    ("t", "problem"),
    [
        (math.nan, "not finite"),
        (math.inf, "not finite"),
        ("0", "real number"),
        (True, "real number"),
        (1j, "complex"),
    ],
)
def test_bad_time_named(t: object, problem: str) -> None:
    model = pendulum_model()
    with pytest.raises(StateError, match=rf"`t`.*{problem}"):
        model.accelerations(t, [1.0, 0.0], [0.0, 0.0])
    with pytest.raises(StateError, match=rf"`t`.*{problem}"):
        pfaff.consistent_state(model, [1.0, 0.0], [0.0, 0.0], ["x"], t=t)


def test_inertia_check_is_independent_of_units() -> None:
    """1 µg beside 1000 kg (ratio 1e-12) is a well-posed system: q̈ = −V'(q)/m for each."""
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1e-12, [x, 0])
    s.add_particle(1.0, [0, y])
    s.add_potential_energy(1e-12 * x**2 + y**2)
    qdd, _ = s.equations().compile({}).accelerations(0.0, [0.3, 0.1], [0.0, 0.0])
    np.testing.assert_allclose(qdd, [-0.6, -0.2], rtol=1e-12)
