"""Regressions from review: the rank-loss machinery must not touch regular systems, odd inputs fail
clearly.

* A constraint written with a small constant factor, 1e-5·(x² + y² − 1), is the same constraint:
  the floor of :mod:`pfaff.numeric.kkt` is relative to each row's own size and must leave it exact.
* A coordinate without inertia (singular M) tied to another one: every method, IDA included.
* A particle on the unit circle and on its tangent y = 1 moving with ẋ = 1: no acceleration
  satisfies both constraints, an error rather than a motion.
* A fractional power of a negative value: a failed run naming the time, not a raw TypeError.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import pfaff
from methods import IDA_SLOW
from pfaff.errors import ConstraintError, StateError


def one_angle(theta0: float, te: np.ndarray, g: float = 9.81) -> np.ndarray:
    sol = solve_ivp(
        lambda t, z: [z[1], -g * math.sin(z[0])],
        (0.0, float(te[-1])),
        [theta0, 0.0],
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
        t_eval=te,
    )
    return sol.y[0]


@pytest.mark.parametrize("method", IDA_SLOW)
def test_small_constant_factor_is_the_same_constraint(method: str) -> None:
    xa, ya, xb, yb = pfaff.coordinates("xa ya xb yb")
    s = pfaff.System([xa, ya, xb, yb])
    s.add_particle(1, [xa, ya])
    s.add_particle(1, [xb, yb])
    s.add_potential_energy(9.81 * (ya + yb))
    s.add_holonomic_constraint(xa**2 + ya**2 - 1, name="A")
    s.add_holonomic_constraint(sp.Float(1e-5) * (xb**2 + yb**2 - 1), name="B")
    model = s.equations().compile({})
    te = np.linspace(0.0, 5.0, 11)
    q0 = [math.sin(1.0), -math.cos(1.0), math.sin(0.5), -math.cos(0.5)]
    kw = {"alpha": 30.0, "beta": 30.0} if method == "baumgarte" else {}
    traj = pfaff.simulate(model, q0, [0.0] * 4, (0.0, 5.0), t_eval=te, method=method, **kw)
    assert traj.status == "success", traj.message
    tol = 1e-6 if method == "ida" else 1e-8
    np.testing.assert_allclose(
        np.arctan2(traj.q[:, 0], -traj.q[:, 1]), one_angle(1.0, te), atol=tol
    )
    np.testing.assert_allclose(
        np.arctan2(traj.q[:, 2], -traj.q[:, 3]), one_angle(0.5, te), atol=tol
    )


@pytest.mark.parametrize("method", ["projection", "ida"])
def test_coordinate_without_inertia(method: str) -> None:
    """s follows x (no mass of its own, a spring k s²/2 on it): the pendulum feels −k x along x."""
    x, y, s_ = pfaff.coordinates("x y s")
    m, g, L, k = sp.symbols("m g L k")
    s = pfaff.System([x, y, s_])
    s.add_particle(m, [x, y])
    s.add_potential_energy(m * g * y + k * s_**2 / 2)
    s.add_holonomic_constraint(x**2 + y**2 - L**2, name="rod")
    s.add_holonomic_constraint(s_ - x, name="follow")
    model = s.equations().compile({"m": 1.0, "g": 9.81, "L": 1.0, "k": 3.0})
    # the same pendulum with the spring on x, as one angle: θ̈ = −g sin θ − k sin θ cos θ
    te = np.linspace(0.0, 3.0, 7)
    ref = solve_ivp(
        lambda t, z: [z[1], -9.81 * math.sin(z[0]) - 3.0 * math.sin(z[0]) * math.cos(z[0])],
        (0.0, 3.0),
        [1.0, 0.3],
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
        t_eval=te,
    ).y[0]
    c, sn = math.cos(1.0), math.sin(1.0)
    traj = pfaff.simulate(
        model, [sn, -c, sn], [0.3 * c, 0.3 * sn, 0.3 * c], (0.0, 3.0), t_eval=te, method=method
    )
    assert traj.status == "success", traj.message
    np.testing.assert_allclose(np.arctan2(traj.q[:, 0], -traj.q[:, 1]), ref, atol=1e-6)
    np.testing.assert_allclose(traj.q[:, 2], traj.q[:, 0], atol=1e-10)


def test_inconsistent_accelerations_refused() -> None:
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_holonomic_constraint(x**2 + y**2 - 1, name="circle")
    s.add_holonomic_constraint(y - 1, name="line")
    model = s.equations().compile({})
    with pytest.raises(ConstraintError, match="inconsistent"):
        model.accelerations(0.0, [0.0, 1.0], [1.0, 0.0])
    with pytest.raises(ConstraintError, match="inconsistent"):
        pfaff.simulate(model, [0.0, 1.0], [1.0, 0.0], (0.0, 1.0))


def test_fractional_power_of_negative_fails_with_time() -> None:
    """A force −c·x^(1/3) pushes x through zero: the run fails there, naming the time."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_kinetic_energy(x.diff(pfaff.t) ** 2 / 2)
    s.add_generalized_force(x, -(x ** sp.Rational(1, 3)))
    model = s.equations().compile({})
    traj = pfaff.simulate(model, [1.0], [0.0], (0.0, 5.0))
    assert traj.status == "failed"
    assert "not real" in traj.message and "t = " in traj.message
    with pytest.raises(StateError, match="not real"):
        model.accelerations(0.0, [-1.0], [0.0])


def test_constraint_tol_must_be_positive() -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    with pytest.raises(pfaff.OptionError, match="constraint_tol"):
        pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), constraint_tol=0.0)


def test_bad_options_are_option_errors() -> None:
    """Options get their own error class, no longer a StateError (a state is something else)."""
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    for kw in ({"method": "euler"}, {"rtol": -1.0}, {"t_eval": [0.5, 0.2]}):
        with pytest.raises(pfaff.OptionError) as info:
            pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), **kw)
        assert not isinstance(info.value, StateError)
    with pytest.raises(pfaff.OptionError, match="t_span"):
        pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (1.0, 0.0))


def test_sqrt_of_negative_in_generated_code_is_a_failed_run() -> None:
    """math.sqrt of a negative value inside the user's equations: status "failed" with the time."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_kinetic_energy(x.diff(pfaff.t) ** 2 / 2)
    s.add_generalized_force(x, -sp.sqrt(x))  # not defined once x < 0
    model = s.equations().compile({})
    traj = pfaff.simulate(model, [1.0], [0.0], (0.0, 5.0))
    assert traj.status == "failed" and "t = " in traj.message


@pytest.mark.parametrize("path", ["python", "compiled loop"])
def test_a_bug_surfaces_as_a_bug(monkeypatch: pytest.MonkeyPatch, path: str) -> None:
    """A ValueError raised by pfaff's own code during a run is not reported as a failed run,
    on the Python path (a stepper's step) and in the compiled loop's driver alike."""
    from pfaff.integrate import integrators, loop

    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})

    def broken(self: object, *args: object) -> None:
        raise ValueError("an internal bug")

    if path == "python":
        monkeypatch.setenv("PFAFF_LOOP", "0")
        monkeypatch.setattr(integrators.ProjectedRK, "step", broken)
    else:
        monkeypatch.setattr(loop.CompiledLoop, "advance", broken)
    with pytest.raises(ValueError, match="an internal bug"):
        pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0))
