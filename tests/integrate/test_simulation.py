"""pfaff.simulate against closed forms and an independent one-angle integration."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import pfaff
import pfaff.core.symbols
from methods import ALL_METHODS

G, L = 9.81, 1.0


@pytest.fixture(scope="module")
def pendulum() -> pfaff.NumericModel:
    return pfaff.models.cartesian_pendulum().equations().compile({"m": 1.0, "g": G, "L": L})


def one_angle(t_end: float, t_eval: np.ndarray) -> np.ndarray:
    """Angle φ below the horizontal of a pendulum released at rest from horizontal (DOP853)."""
    sol = solve_ivp(
        lambda t, y: [y[1], G / L * math.cos(y[0])], (0, t_end), [0.0, 0.0],
        method="DOP853", rtol=1e-13, atol=1e-13, t_eval=t_eval,
    )  # fmt: skip
    return sol.y[0]


@pytest.mark.parametrize(("method", "periods"), [("projection", 100), ("ida", 5)])
@pytest.mark.slow  # (over a second: the full suite runs it)
def test_pendulum_against_one_angle(pendulum, method: str, periods: int) -> None:
    """x = L cos φ, y = −L sin φ to 1e-7 with |f| <= 1e-10 at every reported point."""
    t_end = periods * 2.3678  # period of a release from horizontal, L = 1
    te = np.linspace(0, t_end, 20 * periods + 1)
    tol = {"rtol": 1e-11, "atol": 1e-12}
    traj = pfaff.simulate(
        pendulum, [L, 0.0], [0.0, 0.0], (0, t_end), method=method, t_eval=te, **tol
    )
    phi = one_angle(t_end, te)
    assert traj.status == "success"
    err = np.hypot(traj.q[:, 0] - L * np.cos(phi), traj.q[:, 1] + L * np.sin(phi)).max()
    assert err < 1e-7
    assert np.abs(traj.position_residual).max() <= 1e-10
    assert np.abs(traj.velocity_residual).max() <= 1e-10


def test_tension_history(pendulum) -> None:
    """−2Lλ = m (v²/L + g cos θ) along the motion; 3 m g at the bottom."""
    traj = pfaff.simulate(
        pendulum, [L, 0.0], [0.0, 0.0], (0, 0.5 * 2.3678), t_eval=np.linspace(0, 1.1839, 200)
    )
    v2 = (traj.qd**2).sum(axis=1)
    cos_theta = -traj.q[:, 1] / L
    tension = -2 * L * traj.multipliers[:, 0]
    np.testing.assert_allclose(tension, v2 / L + G * cos_theta, rtol=1e-8, atol=1e-9)
    bottom = traj.at(0.25 * 2.3678)  # a quarter period: the bottom
    _, lam = pendulum.accelerations(0.0, *bottom)
    assert -2 * L * lam[0] == pytest.approx(3 * G, rel=1e-8)


def test_baumgarte_bounded_and_unstabilized_grows(pendulum) -> None:
    te = np.linspace(0, 60, 601)
    stab = pfaff.simulate(
        pendulum, [L, 0.0], [0.0, 0.0], (0, 60), method="baumgarte", t_eval=te, rtol=1e-8, atol=1e-8
    )
    raw = pfaff.simulate(
        pendulum,
        [L, 0.0],
        [0.0, 0.0],
        (0, 60),
        method="baumgarte",
        alpha=0,
        beta=0,
        t_eval=te,
        rtol=1e-8,
        atol=1e-8,
    )
    f_stab, f_raw = np.abs(stab.position_residual[:, 0]), np.abs(raw.position_residual[:, 0])
    tenth = len(te) // 10
    assert f_stab[-tenth:].max() <= 3 * f_stab[:tenth].max() + 1e-12  # bounded, not growing
    assert f_raw[-tenth:].max() > 10 * f_raw[:tenth].max()  # the plain index-1 form drifts
    assert f_stab.max() < f_raw.max() / 10


@pytest.mark.parametrize("method", ALL_METHODS)
def test_pushed_ring_law(method: str) -> None:
    """x(t) = x₀ + F t²/(4M) from rest, θ₁ = x/r, friction λ₁ = −F/2 throughout."""
    n, M, r, F = 5, 2.0, 0.25, 3.0
    model = pfaff.models.rolling_ring(n, force=True).equations().compile({"M": M, "r": r, "F": F})
    q0, qd0 = pfaff.models.ring_state(n, radius=r, theta=math.pi)
    te = np.linspace(0, 2, 21)
    traj = pfaff.simulate(model, q0, qd0, (0, 2), method=method, t_eval=te, max_step=0.05)
    assert traj.status == "success"
    np.testing.assert_allclose(traj.q[:, 0], q0[0] + F * te**2 / (4 * M), rtol=0, atol=1e-8)
    np.testing.assert_allclose(traj.q[:, 1], traj.q[:, 0] / r, rtol=0, atol=1e-8)
    np.testing.assert_allclose(traj.multipliers[:, 0], -F / 2, atol=1e-8)
    np.testing.assert_allclose(traj.energy - traj.energy[0], F * (traj.q[:, 0] - q0[0]), atol=1e-7)


def test_methods_agree(pendulum) -> None:
    te = np.linspace(0, 3, 31)
    runs = [
        pfaff.simulate(
            pendulum, [0.6, -0.8], [0.0, 0.0], (0, 3), method=m, t_eval=te, rtol=1e-10, atol=1e-11
        )
        for m in ALL_METHODS
    ]
    for other in runs[1:]:
        np.testing.assert_allclose(other.q, runs[0].q, atol=1e-6)
        np.testing.assert_allclose(other.multipliers, runs[0].multipliers, atol=1e-5)


def test_interpolation_energy_and_stats(pendulum) -> None:
    traj = pfaff.simulate(pendulum, [L, 0.0], [0.0, 0.0], (0, 5))
    ts = np.array([0.123, 1.777, 4.321])
    q, _ = traj.at(ts)
    phi = one_angle(5.0, ts)
    np.testing.assert_allclose(q, np.column_stack([L * np.cos(phi), -L * np.sin(phi)]), atol=1e-6)
    assert np.abs((q**2).sum(axis=1) - L**2).max() <= 1e-10
    assert np.abs(traj.energy - traj.energy[0]).max() < 1e-6
    np.testing.assert_allclose(traj.jacobi, traj.energy, atol=1e-12)  # T quadratic in q̇
    assert traj.stats["steps"] > 10 and traj.stats["nfev"] > 100 and traj.stats["projections"] > 0


def test_files_roundtrip(pendulum, tmp_path) -> None:
    xr = pytest.importorskip("xarray")
    traj = pfaff.simulate(pendulum, [L, 0.0], [0.0, 0.0], (0, 1), t_eval=np.linspace(0, 1, 11))
    data = np.genfromtxt(traj.to_csv(tmp_path / "a.csv"), delimiter=",", names=True)
    np.testing.assert_allclose(data["y"], traj.q[:, 1], rtol=1e-15)
    np.testing.assert_allclose(data["lambda1"], traj.multipliers[:, 0], rtol=1e-15)
    with xr.open_dataset(traj.to_netcdf(tmp_path / "a.nc")) as ds:
        np.testing.assert_allclose(ds["q"].values, traj.q)
        assert list(ds["coordinate"].values) == ["x", "y"]
    with pytest.raises(FileNotFoundError):
        traj.to_csv(tmp_path / "missing" / "a.csv")
    assert not (tmp_path / "missing").exists()


def test_consistent_state() -> None:
    model = pfaff.models.rolling_ring(6).equations().compile({"M": 1.0, "r": 0.5})
    q_ref, qd_ref = pfaff.models.ring_state(6, radius=0.5, theta=0.7, theta_dot=2.0)
    guess_q, guess_qd = np.zeros(7), np.zeros(7)
    guess_q[0], guess_qd[0] = q_ref[0], qd_ref[0]
    q, qd = pfaff.consistent_state(model, guess_q, guess_qd, ["x"])
    np.testing.assert_allclose(q, q_ref, atol=1e-12)
    np.testing.assert_allclose(qd, qd_ref, atol=1e-12)


def test_bad_input(pendulum) -> None:
    ok = ([L, 0.0], [0.0, 0.0])
    with pytest.raises(pfaff.StateError, match="off the constraint manifold"):
        pfaff.simulate(pendulum, [1.1, 0.0], [0.0, 0.0], (0, 1))
    traj = pfaff.simulate(pendulum, [1.1, 0.0], [0.0, 0.0], (0, 0.1), project_initial=True)
    assert abs(traj.q[0] @ traj.q[0] - L**2) < 1e-12
    for span, word in (((1, 0), "reversed"), ((1, 1), "empty")):
        with pytest.raises(pfaff.OptionError, match=word):
            pfaff.simulate(pendulum, *ok, span)
    with pytest.raises(pfaff.StateError, match="NaN"):
        pfaff.simulate(pendulum, [np.nan, 0.0], [0.0, 0.0], (0, 1))
    with pytest.raises(pfaff.StateError, match=r"shape \(2,\)"):
        pfaff.simulate(pendulum, [1.0, 0.0, 0.0], [0.0, 0.0], (0, 1))
    with pytest.raises(pfaff.OptionError, match="unknown method"):
        pfaff.simulate(pendulum, *ok, (0, 1), method="euler")
    with pytest.raises(pfaff.OptionError, match="inside t_span"):
        pfaff.simulate(pendulum, *ok, (0, 1), t_eval=[0.5, 2.0])
    with pytest.raises(pfaff.OptionError, match="integrator"):
        pfaff.simulate(pendulum, *ok, (0, 1), integrator="Radau")


def test_nonfinite_midrun_fails_with_time() -> None:
    """ẍ = 1/(1 − x) from rest reaches the singularity at x = 1 in finite time."""
    x = pfaff.coordinates("x")
    sys = pfaff.System([x])
    sys.add_kinetic_energy(sp.Rational(1, 2) * pfaff.core.symbols.speed(x) ** 2)
    sys.add_generalized_force(x, 1 / (1 - x))
    model = sys.equations().compile({})
    traj = pfaff.simulate(model, [0.0], [0.0], (0, 5))
    assert traj.status == "failed" and "at t = " in traj.message
    assert 0.5 < traj.t[-1] < 1.5 and len(traj.t) > 3
    with pytest.raises(pfaff.SimulationError, match="at t = "):
        pfaff.simulate(model, [0.0], [0.0], (0, 5), throw=True)


def test_ctrl_c_returns_partial(pendulum, monkeypatch) -> None:
    from pfaff.numeric.protocol import OdeFunction

    calls = {"n": 0}
    real = type(pendulum).ode_function  # (models are immutable: the class is patched)

    class Interrupting(OdeFunction):
        def __init__(self, fun: OdeFunction) -> None:
            self.fun = fun
            self.on_lists = self._lists if self.fun.on_lists is not None else None

        def _lists(self, t, y):
            calls["n"] += 1
            if calls["n"] > 400:
                raise KeyboardInterrupt
            return self.fun.on_lists(t, y)

        def __call__(self, t, y):
            return np.array(self._lists(t, y.tolist())) if self.on_lists else self.fun(t, y)

    monkeypatch.setattr(
        type(pendulum), "ode_function", lambda self, *a, **kw: Interrupting(real(self, *a, **kw))
    )
    traj = pfaff.simulate(pendulum, [L, 0.0], [0.0, 0.0], (0, 50))
    assert traj.status == "interrupted" and len(traj.t) > 5 and traj.t[-1] < 50
    assert np.abs(traj.position_residual).max() <= 1e-10
