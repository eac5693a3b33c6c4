"""The Whipple bicycle at 4.6 m/s: ∂(lean, steer)(2 s)/∂(rear wheel radius, trail) against
converged central differences of tight runs, each started from a state recompleted for its
parameter values (``bicycle_state``: fixed lean, steer and forward speed; the pitch and the
dependent rates solved from the constraints), to 1e-6 relative."""

from __future__ import annotations

import numpy as np
import pytest
from central_differences import close, converged

import pfaff
from pfaff.models.bicycle import MEIJAARD, bicycle_state

LEAN, STEER, SPEED = 0.05, 0.02, 4.6
TIGHT = {"rtol": 1e-12, "atol": 1e-14, "t_eval": [0.0, 2.0]}
LEAN_STEER = [3, 6]  # phi, delta


def start(values):
    return bicycle_state(dict(values), phi=LEAN, delta=STEER, speed=SPEED)


@pytest.mark.slow
def test_lean_and_steer_by_wheel_radius_and_trail():
    model = pfaff.models.whipple_bicycle().equations().compile(dict(MEIJAARD))
    run = pfaff.sensitivities(
        model,
        lambda p: start(p)[0],
        lambda p: start(p)[1],
        (0, 2),
        parameters=["rR", "c"],
        **TIGHT,
    )
    assert run.status == "success"
    for j, name in enumerate(["rR", "c"]):

        def end(v: float, name: str = name) -> np.ndarray:
            values = {**MEIJAARD, name: v}
            other = model.with_parameters({name: v})
            traj = pfaff.simulate(other, *start(values), (0, 2), **TIGHT)
            return traj.q[-1, LEAN_STEER]

        ref = converged(end, MEIJAARD[name])
        assert close(run.sensitivity[-1, LEAN_STEER, j], ref)
