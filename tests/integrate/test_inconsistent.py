"""A rheonomic constraint that drives the system where no configuration satisfies all the
constraints: the run fails there, named, instead of reporting success far off them."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff


@pytest.fixture(scope="module")
def driven_circle() -> pfaff.NumericModel:
    """A bead on the unit circle whose x is driven as t/2: consistent until t = 2 (x = 1)."""
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_holonomic_constraint(x - pfaff.t / 2, name="drive")
    s.add_holonomic_constraint(x**2 + y**2 - 1, name="circle")
    return s.equations().compile({})


def test_projection_fails_where_the_constraints_part(driven_circle: pfaff.NumericModel) -> None:
    ts = np.linspace(0, 1.9, 20)
    tr = pfaff.simulate(driven_circle, [0, -1], [0.5, 0], (0, 3), t_eval=ts)
    assert tr.status == "failed" and "constraints cannot be satisfied" in tr.message
    t_fail = float(tr.message.split("t = ")[1].split(":")[0])
    assert t_fail == pytest.approx(2.0, abs=1e-3)
    # up to there, the closed form y = −√(1 − t²/4), on the constraints
    np.testing.assert_allclose(tr.q[:, 1], -np.sqrt(1 - ts**2 / 4), atol=1e-8)
    assert np.abs(tr.constraint_residual).max() < 1e-9


def test_ida_fails_there_too(driven_circle: pfaff.NumericModel) -> None:
    tr = pfaff.simulate(driven_circle, [0, -1], [0.5, 0], (0, 3), method="ida", t_eval=[0, 1])
    assert tr.status == "failed"
    assert float(tr.message.split("t = ")[1].split(":")[0]) == pytest.approx(2.0, abs=1e-3)
