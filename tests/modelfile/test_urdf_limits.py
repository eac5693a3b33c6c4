"""load_urdf(..., enforce_limits=True): joint limits as stops (unilateral constraints)."""

import math

import numpy as np
import pytest

import pfaff
from pfaff.core.errors import ModelError

L, M, G = 0.8, 2.0, 9.81
LOWER, UPPER = -0.4, 0.5

PENDULUM = f"""<robot name="stop">
  <link name="base"/>
  <link name="bob"><inertial><origin xyz="0 0 -{L}"/><mass value="{M}"/>
    <inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="bob"/>
    <axis xyz="0 1 0"/><limit lower="{LOWER}" upper="{UPPER}" effort="1" velocity="1"/></joint>
</robot>"""


@pytest.fixture(scope="module")
def urdf(tmp_path_factory):
    path = tmp_path_factory.mktemp("urdf") / "stop.urdf"
    path.write_text(PENDULUM)
    return path


def test_a_pendulum_rebounds_from_its_joint_stop(urdf):
    e, w0 = 0.5, 3.0
    arm = pfaff.load_urdf(urdf, enforce_limits=True, restitution=e)
    assert [c.name for c in arm.contacts] == ["hinge lower", "hinge upper"]
    model = arm.equations().compile()  # the file's values are the defaults
    traj = pfaff.simulate(model, [0.0], [w0], (0.0, 0.3), rtol=1e-12, atol=1e-14)
    hit = next(r for r in traj.events if r.kind == "impact")
    # energy up to the stop: ω² = ω0² − 2 (g/L)(1 − cos q*), then Newton's rebound −e ω
    incoming = math.sqrt(w0**2 - 2 * G / L * (1 - math.cos(UPPER)))
    assert hit.q[0] == pytest.approx(UPPER, abs=1e-10)
    assert hit.qd[0] == pytest.approx(-e * incoming, rel=1e-9)
    assert traj.impact_work[-1] == pytest.approx(
        0.5 * M * L**2 * incoming**2 * (e**2 - 1), rel=1e-9
    )
    assert np.all(traj.q[:, 0] <= UPPER + 1e-9)


def test_limits_only_when_asked_and_bad_arguments(urdf):
    free = pfaff.load_urdf(urdf)
    assert free.contacts == [] and free.joint_limits == {"hinge": (LOWER, UPPER)}
    assert free.parameter_defaults == {
        k: v for k, v in free.urdf_values.items() if k in {p.name for p in free.parameters}
    }
    with pytest.raises(ModelError, match="restitution"):
        pfaff.load_urdf(urdf, enforce_limits=True, restitution=1.5)
    with pytest.raises(ModelError, match="enforce_limits"):
        pfaff.load_urdf(urdf, enforce_limits="yes")
