"""``pfaff.models.robot_arm``: the 3-joint spatial arm in joint angles, its links' attitudes
given as ``Rotation`` matrices and as SymPy ``ReferenceFrame``s, against Pinocchio's articulated
body algorithm on the same arm (``robot_arm_urdf`` read by ``pin.buildModelFromUrdf``).

- q̈ at 100 random states against ``pin.aba`` to 1e-10;
- 2 s under a joint-space PD controller τ = −K_p (q − q*) − K_d q̇ against Pinocchio's ABA
  integrated by SciPy's DOP853 (rtol 1e-11), to 1e-9 rad;
- the same numbers through ``pfaff.load_urdf(robot_arm_urdf(3))``.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import pfaff
from pfaff.models import robot_arm, robot_arm_state, robot_arm_urdf, robot_arm_values

pin = pytest.importorskip("pinocchio")

N = 3
KP, KD = 40.0, 6.0
TARGET = np.array([0.6, -0.4, 0.9])


def _pinocchio() -> tuple:
    model = pin.buildModelFromXML(robot_arm_urdf(N))
    return model, model.createData()


def _config(model, q: np.ndarray) -> np.ndarray:
    """Pinocchio's configuration of continuous joints: (cos q, sin q) each."""
    out = np.empty(model.nq)
    out[0::2], out[1::2] = np.cos(q), np.sin(q)
    return out


def _aba(ref: tuple, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
    model, data = ref
    return pin.aba(model, data, _config(model, q), qd, tau)


@pytest.fixture(scope="module", params=[False, True], ids=["Rotation", "ReferenceFrame"])
def arm(request):
    return robot_arm(N, frames=request.param)


@pytest.fixture(scope="module")
def ref():
    return _pinocchio()


def test_attitudes(arm):
    kinds = {type(b.attitude).__name__ for b in arm.bodies}
    assert kinds == {"Rotation"} and len(arm.bodies) == N
    assert arm.coordinates == tuple(pfaff.coordinates("q1 q2 q3"))


def test_accelerations_against_aba(arm, ref):
    model = arm.equations().compile(robot_arm_values(N))
    worst = 0.0
    for seed in range(100):
        q, qd = robot_arm_state(N, seed)
        worst = max(
            worst, np.abs(model.accelerations(0.0, q, qd)[0] - _aba(ref, q, qd, 0 * q)).max()
        )
    assert worst < 1e-10


def test_urdf_of_the_arm_agrees(tmp_path, ref):
    path = tmp_path / "arm3.urdf"
    path.write_text(robot_arm_urdf(N))
    system = pfaff.load_urdf(path)
    assert list(system.urdf_coordinates) == ["q1", "q2", "q3"]
    model = system.equations().compile(system.urdf_values)
    for seed in range(20):
        q, qd = robot_arm_state(N, seed)
        assert np.abs(model.accelerations(0.0, q, qd)[0] - _aba(ref, q, qd, 0 * q)).max() < 1e-10


def _pd_system(frames: bool) -> pfaff.System:
    s = robot_arm(N, frames=frames)
    kp, kd = sp.symbols("kp kd")
    for q, target in zip(s.coordinates, sp.symbols("r1:4"), strict=True):
        s.add_generalized_force(q, -kp * (q - target) - kd * q.diff(pfaff.t))
    return s


@pytest.mark.slow
@pytest.mark.parametrize("frames", [False, True], ids=["Rotation", "ReferenceFrame"])
def test_pd_controlled_run_against_pinocchio(frames, ref):
    values = robot_arm_values(N) | {"kp": KP, "kd": KD}
    values |= {f"r{i + 1}": float(v) for i, v in enumerate(TARGET)}
    model = _pd_system(frames).equations().compile(values)
    q0, qd0 = robot_arm_state(N, 1)
    ts = np.linspace(0.0, 2.0, 41)
    run = pfaff.simulate(model, q0, qd0, (0.0, 2.0), rtol=1e-11, atol=1e-13, t_eval=ts, throw=True)

    def rhs(_t, y):
        q, qd = y[:N], y[N:]
        return np.concatenate([qd, _aba(ref, q, qd, -KP * (q - TARGET) - KD * qd)])

    sol = solve_ivp(rhs, (0.0, 2.0), np.concatenate([q0, qd0]), method="DOP853",
                    rtol=1e-11, atol=1e-13, t_eval=ts)  # fmt: skip
    assert sol.success
    assert np.abs(run.q - sol.y[:N].T).max() < 1e-9
    assert np.ptp(run.q, axis=0).max() > 0.5  # the arm moved: the agreement is not trivial
