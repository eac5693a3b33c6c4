"""The stepping contract: a user's :class:`pfaff.Stepper` subclass as ``simulate(method=...)``, the
built-in methods' declared attributes, and which exceptions of a run are a "failed" status."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pfaff
from methods import ALL_METHODS
from pfaff.integrate.simulation import METHODS
from pfaff.integrate.work import hermite_work

G = 9.81


@pytest.fixture(scope="module")
def pendulum() -> pfaff.NumericModel:
    return pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": G, "L": 1})


class ProjectedRK4(pfaff.Stepper):
    """Classical Runge–Kutta with a fixed step, the end of each step projected: a user's method."""

    name = "rk4"
    projects_steps = True
    H = 2.0**-10  # exact in binary: the step ends are exact

    def __init__(self, model, t0, q0, qd0, t_end, options, projector) -> None:
        self.model, self.projector, self.t_end = model, projector, t_end
        self._t, self.q, self.qd = t0, q0, qd0
        self.ends: tuple = ()
        self.steps = 0

    @property
    def t(self) -> float:
        return self._t

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        return self.q, self.qd

    def _rate(self, t: float, y: np.ndarray) -> np.ndarray:
        n = len(y) // 2
        return np.concatenate([y[n:], self.model.accelerations(t, y[:n], y[n:])[0]])

    def step(self) -> None:
        t, y = self._t, np.concatenate([self.q, self.qd])
        h = min(self.H, self.t_end - t)
        k1 = self._rate(t, y)
        k2 = self._rate(t + h / 2, y + h / 2 * k1)
        k3 = self._rate(t + h / 2, y + h / 2 * k2)
        k4 = self._rate(t + h, y + h * k3)
        y1 = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        n = len(y) // 2
        q, qd, _ = self.projector(t + h, y1[:n], y1[n:])
        self._t, self.q, self.qd = t + h, q, qd
        y1 = np.concatenate([q, qd])
        self.ends = ((t, y, k1), (t + h, y1, self._rate(t + h, y1)))
        self.steps += 1

    def dense(self, ts: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        (t0, y0, f0), (t1, y1, f1) = self.ends
        h, n = t1 - t0, len(y0) // 2
        out = []
        for ti in ts:  # cubic Hermite of y through y and y' at both ends
            s = (ti - t0) / h
            w = (2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2)
            y = w[0] * y0 + h * w[1] * f0 + w[2] * y1 + h * w[3] * f1
            out.append((y[:n], y[n:]))
        return out

    def step_work(self, power) -> float:
        return hermite_work(self.ends, power, self.ends[0][0], self.ends[1][0])

    def work_until(self, power, b: float) -> float:
        return hermite_work(self.ends, power, self.ends[0][0], b)

    def finish(self) -> dict:
        return {"steps": self.steps, "rejected": 0, "nfev": 5 * self.steps}


def one_angle(theta0: float, te: np.ndarray) -> np.ndarray:
    sol = solve_ivp(
        lambda t, z: [z[1], -G * math.sin(z[0])],
        (0.0, float(te[-1])),
        [theta0, 0.0],
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
        t_eval=te,
    )
    return sol.y[0]


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_user_stepper_matches_the_minimal_pendulum(pendulum: pfaff.NumericModel) -> None:
    te = np.linspace(0.0, 2.0, 9)
    q0 = [math.sin(1.0), -math.cos(1.0)]
    traj = pfaff.simulate(pendulum, q0, [0.0, 0.0], (0.0, 2.0), method=ProjectedRK4, t_eval=te)
    assert traj.status == "success", traj.message
    assert traj.method == "rk4" and traj.stats["steps"] == 2048
    angle = np.arctan2(traj.q[:, 0], -traj.q[:, 1])
    np.testing.assert_allclose(angle, one_angle(1.0, te), atol=1e-9)
    assert np.ptp(traj.jacobi) < 1e-9  # energy conserved
    assert np.abs(traj.constraint_residual).max() < 1e-12  # reported states projected


def test_user_stepper_every_step(pendulum: pfaff.NumericModel) -> None:
    traj = pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0.0, 0.01), method=ProjectedRK4)
    assert len(traj.t) == 12 and traj.t[-1] == 0.01  # ten steps of H and a last, shorter one


def test_builtin_methods_declare_what_differs() -> None:
    assert set(METHODS) == set(ALL_METHODS)
    assert all(issubclass(cls, pfaff.Stepper) and cls.name == key for key, cls in METHODS.items())
    assert [m for m in ALL_METHODS if METHODS[m].projects_steps] == ["projection"]
    assert [m for m in ALL_METHODS if METHODS[m].reports_drift] == ["baumgarte"]
    assert ProjectedRK4.name == "rk4" and type("Mine", (ProjectedRK4,), {}).name == "Mine"


class NotAStepper:
    def step(self) -> None: ...


class Abstract(pfaff.Stepper):
    def step(self) -> None: ...


@pytest.mark.parametrize(
    ("method", "match"),
    [
        ("euler", r"unknown method 'euler'; `method` must be one of projection, baumgarte, ida"),
        (ProjectedRK4(None, 0.0, None, None, 1.0, None, None), "unknown method"),  # an instance
        (NotAStepper, "`method` must be one of .* or a subclass of pfaff.Stepper"),
        (Abstract, r"`method` Abstract is abstract: it does not implement __init__, dense"),
    ],
)
def test_method_must_be_a_name_or_a_stepper_class(
    pendulum: pfaff.NumericModel, method: object, match: str
) -> None:
    with pytest.raises(pfaff.OptionError, match=match):
        pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), method=method)


def _raising(exc: Exception, after: int = 3) -> type[pfaff.Stepper]:
    class Raising(ProjectedRK4):
        def step(self) -> None:
            if self.steps == after:
                raise exc
            super().step()

    return Raising


def test_stepper_failure_is_a_failed_run(pendulum: pfaff.NumericModel) -> None:
    class GivingUp(ProjectedRK4):
        def step(self) -> None:
            if self.steps == 3:
                self.fail("no more steps")
            super().step()

    traj = pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), method=GivingUp)
    assert traj.status == "failed" and traj.message == "failed at t = 0.0029296875: no more steps"
    assert len(traj.t) == 4  # the states before the failure are kept
    with pytest.raises(pfaff.SimulationError, match="no more steps"):
        pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), method=GivingUp, throw=True)


@pytest.mark.parametrize(
    "exc",
    [
        RuntimeError("a bug in the stepper"),
        KeyError("a bug in the stepper"),
        ValueError("a bug in the stepper"),  # not raised in generated code
        pfaff.OptionError("`H` must be positive: a bug in the stepper"),  # validation, mid-run
        pfaff.ModelError("a bug in the stepper"),
    ],
)
def test_unexpected_exception_in_a_run_raises(pendulum: pfaff.NumericModel, exc: Exception) -> None:
    """Only failures of the run are a "failed" status; anything else is raised as itself."""
    with pytest.raises(type(exc), match="a bug in the stepper"):
        pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), method=_raising(exc))


@pytest.mark.parametrize(
    "exc",
    [
        pfaff.StateError("the accelerations are NaN or infinite at t = 0.0029296875"),
        FloatingPointError("overflow encountered"),
        np.linalg.LinAlgError("singular matrix"),
        pfaff.ConstraintError("no acceleration satisfies the constraints"),
    ],
)
def test_numerical_failures_in_a_run_are_failed_runs(
    pendulum: pfaff.NumericModel, exc: Exception
) -> None:
    traj = pfaff.simulate(pendulum, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), method=_raising(exc))
    assert traj.status == "failed" and traj.message == f"failed at t = 0.0029296875: {exc}"


def test_stepper_options_are_frozen() -> None:
    opts = pfaff.StepperOptions(rtol=1e-6, max_step=0.1)
    with pytest.raises(AttributeError):
        opts.rtol = 1.0  # type: ignore[misc]
    assert opts.step_sizes() == {"max_step": 0.1}


def test_hermite_work_at_the_coordinates_the_power_reads() -> None:
    """A power naming the coordinates it reads (x and θ_3 of 40) gets the same ∫P dt as one
    that does not say (the whole interpolant at every node), over the step and inside it; on
    the pushed ring of 64, the family power F·ẋ names x alone."""
    rng = np.random.default_rng(11)
    n = 40
    ends = tuple((t, rng.standard_normal(2 * n), rng.standard_normal(2 * n)) for t in (0.0, 0.1))

    def plain(t, q, v):
        return float(2.0 * v[0] * np.sin(q[3]) + q[0] * t)

    class Named:
        coordinates = np.array([0, 3])

        def __call__(self, t, q, v):
            return plain(t, q, v)

    for a, b in ((0.0, 0.1), (0.02, 0.07)):
        whole, few = hermite_work(ends, plain, a, b), hermite_work(ends, Named(), a, b)
        assert few == pytest.approx(whole, rel=1e-14, abs=1e-15)
    ring = pfaff.models.rolling_ring(64, force=True, family=True).equations()
    power = ring.compile({"M": 1.0, "r": 0.5, "F": 2.0}).power_function()
    assert power.coordinates.tolist() == [0]
