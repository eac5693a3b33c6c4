"""A 1 mm pendulum is held on its circle as tightly, relative to its length, as a 1 m one: the
default constraint tolerance scales with the constraints (pfaff.integrate.scale)."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff


@pytest.fixture(scope="module")
def pendulum_eom():
    return pfaff.models.cartesian_pendulum().equations()


@pytest.mark.parametrize("length", [1e-3, 1.0])
def test_relative_drift_of_the_length_is_independent_of_the_scale(pendulum_eom, length) -> None:
    model = pendulum_eom.compile({"m": 1, "g": 9.81, "L": length})
    q0 = [length * np.sin(1.0), -length * np.cos(1.0)]
    tr = pfaff.simulate(model, q0, [0, 0], (0, 20 * np.sqrt(length / 9.81)))  # ~3 periods
    assert tr.status == "success"
    drift = np.abs(np.hypot(tr.q[:, 0], tr.q[:, 1]) / length - 1).max()
    assert drift < 1e-10  # (was 2e-7 at L = 1 mm under the absolute 1e-12)
    # the reported residual x² + y² − L² ≈ 2 L² · drift tells the same, relative to L²
    reported = np.abs(tr.constraint_residual[:, 0]).max() / length**2
    assert reported < 2e-10


def test_an_explicit_constraint_tol_is_kept(pendulum_eom) -> None:
    model = pendulum_eom.compile({"m": 1, "g": 9.81, "L": 1e-3})
    q0 = [1e-3 * np.sin(1.0), -1e-3 * np.cos(1.0)]
    loose = pfaff.simulate(model, q0, [0, 0], (0, 0.2), constraint_tol=1e-12)
    tight = pfaff.simulate(model, q0, [0, 0], (0, 0.2))
    drift = [np.abs(np.hypot(*tr.q.T) / 1e-3 - 1).max() for tr in (loose, tight)]
    assert drift[0] > 100 * drift[1]  # the absolute 1e-12 allows the old drift, the default not
