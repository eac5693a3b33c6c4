"""The energy balance T + V − E₀ − W_nc(t): the work of applied forces accounted for."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff
from methods import ALL_METHODS


@pytest.mark.parametrize("method", ALL_METHODS)
def test_pushed_ring_work_is_force_times_distance(method: str) -> None:
    """The push F on the centre does work F·Δx; the balance stays at integration-error level."""
    n, F = 6, 2.0
    model = pfaff.models.rolling_ring(n, force=True).equations().compile({"M": 1, "r": 0.5, "F": F})
    q0, qd0 = pfaff.models.ring_state(n, 0.5, theta=0.2, theta_dot=1.0)
    te = np.linspace(0.0, 2.0, 9)
    traj = pfaff.simulate(model, q0, qd0, (0.0, 2.0), method=method, t_eval=te)
    assert traj.status == "success"
    np.testing.assert_allclose(traj.nc_work, F * (traj.q[:, 0] - q0[0]), atol=1e-8)
    assert np.abs(traj.energy - traj.energy[0]).max() > 1.0  # the push changes the energy ...
    # ... and the balance accounts for it; Baumgarte's constraint drift (~1e-6 here) shows in it
    assert np.abs(traj.energy_balance).max() < (1e-5 if method == "baumgarte" else 1e-7)


def test_damped_oscillator_dissipation_matches_closed_form() -> None:
    """m ẍ = −k x − c ẋ: W_nc(t) = E(t) − E₀ with the closed-form underdamped solution."""
    x = pfaff.coordinates("x")
    m, k, c = 1.0, 4.0, 0.3
    s = pfaff.System([x])
    s.add_particle(m, [x, 0])
    s.add_potential_energy(k * x**2 / 2)
    s.add_generalized_force(x, -c * x.diff(pfaff.t))
    model = s.equations().compile({})
    te = np.linspace(0.0, 5.0, 11)
    traj = pfaff.simulate(model, [1.0], [0.0], (0.0, 5.0), t_eval=te, rtol=1e-11, atol=1e-12)
    zeta_w, wd = c / (2 * m), np.sqrt(k / m - (c / (2 * m)) ** 2)
    xe = np.exp(-zeta_w * te) * (np.cos(wd * te) + zeta_w / wd * np.sin(wd * te))
    ve = -np.exp(-zeta_w * te) * (k / m) / wd * np.sin(wd * te)
    energy = 0.5 * m * ve**2 + 0.5 * k * xe**2
    np.testing.assert_allclose(traj.nc_work, energy - energy[0], atol=1e-9)
    assert np.abs(traj.energy_balance).max() < 1e-9


def test_no_applied_force_means_no_work() -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    assert not model.applied_power
    traj = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0))
    assert np.all(traj.nc_work == 0.0)
    np.testing.assert_array_equal(traj.energy_balance, traj.energy - traj.energy[0])


def test_energy_balance_in_files(tmp_path) -> None:
    model = pfaff.models.rolling_ring(3, force=True).equations().compile({"M": 1, "r": 0.5, "F": 2})
    traj = pfaff.simulate(model, *pfaff.models.ring_state(3, 0.5), (0.0, 0.5))
    ds = traj.to_xarray()
    np.testing.assert_array_equal(ds["energy_balance"].values, traj.energy_balance)
    np.testing.assert_array_equal(ds["nc_work"].values, traj.nc_work)
    header = traj.to_csv(tmp_path / "r.csv").read_text().splitlines()[0].split(",")
    assert "energy_balance" in header and "nc_work" in header
