"""Rigid bodies whose attitude is any rotation matrix (``Rotation(C)``) or a SymPy frame: a 3-link
spatial arm in joint angles against SymPy's KanesMethod on the same arm, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sympy.physics import mechanics as me

import pfaff
from pfaff.attitude import EulerAngles, Rotation
from pfaff.errors import ModelError, ModelTypeError

t = pfaff.t
MASS = (1.3, 0.9, 0.6)
LENGTH = (0.7, 0.8, 0.5)
INERTIA = (  # about the mass centre in body axes, full 3×3 (products of inertia)
    ((0.060, 0.004, -0.003), (0.004, 0.055, 0.002), (-0.003, 0.002, 0.020)),
    ((0.010, 0.002, 0.001), (0.002, 0.052, -0.003), (0.001, -0.003, 0.050)),
    ((0.004, -0.001, 0.0005), (-0.001, 0.015, 0.001), (0.0005, 0.001, 0.014)),
)
GRAVITY = 9.81
KP, KD, TARGET = 40.0, 6.0, (0.6, -0.4, 0.9)


def _frames(q: tuple) -> tuple:
    """N, then link 1 about N.z by q1, link 2 about its y by q2, link 3 about its y by q3."""
    n = me.ReferenceFrame("N")
    a = n.orientnew("A", "Axis", (q[0], n.z))
    b = me.ReferenceFrame("B")
    b.orient_axis(a, a.y, q[1])
    c = b.orientnew("C", "Axis", (q[2], b.y))
    return n, (a, b, c)


def _centres(n: me.ReferenceFrame, links: tuple) -> tuple:
    """Mass centres (Vectors from the fixed base): link 1 along its z, links 2 and 3 along x."""
    a, b, c = links
    top = LENGTH[0] * a.z
    elbow = top + LENGTH[1] * b.x
    return (LENGTH[0] / 2 * a.z, top + LENGTH[1] / 2 * b.x, elbow + LENGTH[2] / 2 * c.x), elbow


def _torques(q: tuple, u: tuple) -> tuple:
    return tuple(-KP * (q[i] - TARGET[i]) - KD * u[i] for i in range(3))


def pfaff_arm(kind: str) -> tuple:
    """The arm in pfaff, each link's attitude a Rotation(C) or the SymPy frame itself."""
    q = pfaff.coordinates("q1:4")
    qd = [c.diff(t) for c in q]
    n, links = _frames(q)
    centres, elbow = _centres(n, links)
    s = pfaff.System(list(q), frame=n)
    bodies = []
    for k, frame in enumerate(links):
        att = Rotation(n.dcm(frame)) if kind == "rotation" else frame
        inertia = sp.Matrix(INERTIA[k])
        body = s.add_rigid_body(MASS[k], inertia, centres[k], att, name=f"link{k + 1}")
        s.add_potential_energy(MASS[k] * GRAVITY * centres[k].dot(n.z))
        bodies.append(body)
    tau = _torques(q, qd)
    l1, l2, l3 = bodies
    s.add_torque([0, 0, tau[0]], on=l1)  # the motor at the base, inertial axis
    s.add_torque([0, -tau[1], 0], on=l1, frame="body")  # joint 2's reaction on link 1
    s.add_torque([0, tau[1], 0], on=l2, frame="body")
    s.add_torque(list(links[1].y.to_matrix(n) * -tau[2]), on=l2)  # joint 3's reaction, inertial
    s.add_torque([0, tau[2], 0], on=l3, frame="body")
    return s, bodies, q, (n, links, elbow)


def kane_arm() -> tuple:
    """The same arm with sympy.physics.mechanics: (M(q), F(q, u)) as NumPy functions, the tip
    velocity function, and the symbols."""
    q = me.dynamicsymbols("k1:4")
    u = me.dynamicsymbols("u1:4")
    n, (a, b, c) = _frames(q)
    a.set_ang_vel(n, u[0] * n.z)
    b.set_ang_vel(a, u[1] * a.y)
    c.set_ang_vel(b, u[2] * b.y)
    origin = me.Point("O")
    origin.set_vel(n, 0)
    centres, elbow = _centres(n, (a, b, c))
    bodies, loads = [], []
    for k, (frame, r) in enumerate(zip((a, b, c), centres, strict=True)):
        p = origin.locatenew(f"G{k}", r)
        p.set_vel(n, r.dt(n))
        inertia = me.inertia(frame, *(INERTIA[k][i][i] for i in range(3)), *(
            INERTIA[k][i][j] for i, j in ((0, 1), (1, 2), (0, 2))))  # fmt: skip
        bodies.append(me.RigidBody(f"L{k}", p, frame, MASS[k], (inertia, p)))
        loads.append((p, -MASS[k] * GRAVITY * n.z))
    tau = _torques(q, u)
    loads += [
        (a, tau[0] * n.z - tau[1] * a.y),
        (b, tau[1] * a.y - tau[2] * b.y),
        (c, tau[2] * b.y),
    ]
    kd = [u[i] - q[i].diff(t) for i in range(3)]
    kane = me.KanesMethod(n, q_ind=q, u_ind=u, kd_eqs=kd)
    kane.kanes_equations(bodies, loads)
    args = [*q, *u]
    mass = sp.lambdify(args, kane.mass_matrix, "numpy")
    forcing = sp.lambdify(args, kane.forcing, "numpy")
    tip = origin.locatenew("T", elbow + LENGTH[2] * c.x + 0.1 * c.y)
    vel = sp.lambdify(args, tip.pos_from(origin).dt(n).to_matrix(n), "numpy")
    return mass, forcing, vel


@pytest.fixture(scope="module")
def kane():
    return kane_arm()


@pytest.fixture(scope="module", params=["rotation", "frame"])
def arm(request):
    s, bodies, q, extra = pfaff_arm(request.param)
    return s, bodies, q, extra, s.equations().compile({})


def _kane_qdd(kane, q, u) -> np.ndarray:
    mass, forcing, _ = kane
    return np.linalg.solve(mass(*q, *u), np.ravel(forcing(*q, *u)))


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_accelerations_match_kane(arm, kane) -> None:
    *_, model = arm
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(20):
        q, u = rng.uniform(-np.pi, np.pi, 3), rng.uniform(-2, 2, 3)
        qdd, _ = model.accelerations(0.0, q, u)
        ref = _kane_qdd(kane, q, u)
        worst = max(worst, np.abs(qdd - ref).max() / max(1.0, np.abs(ref).max()))
    assert worst < 1e-10, worst


@pytest.mark.slow
def test_pd_simulation_matches_solve_ivp(arm, kane) -> None:
    *_, model = arm
    q0, u0 = np.array([0.1, 0.3, -0.5]), np.array([0.5, -0.2, 0.8])
    ts = np.linspace(0.0, 2.0, 21)
    traj = pfaff.simulate(model, q0, u0, (0.0, 2.0), t_eval=ts, rtol=1e-11, atol=1e-13)
    assert traj.status == "success", traj.message
    ref = solve_ivp(
        lambda _t, x: np.concatenate([x[3:], _kane_qdd(kane, x[:3], x[3:])]),
        (0.0, 2.0),
        np.concatenate([q0, u0]),
        method="DOP853",
        rtol=1e-11,
        atol=1e-13,
        t_eval=ts,
    )
    assert np.abs(traj.q - ref.y[:3].T).max() < 1e-8
    # the controller pulls every joint toward its target (a PD law leaves gravity's offset)
    assert np.all(np.abs(traj.q[-1] - TARGET) < np.abs(q0 - TARGET))


@pytest.mark.slow  # (its Kane fixture takes 2 s: the full suite runs it)
def test_angular_velocity_and_velocity_of_tip(arm, kane) -> None:
    _, bodies, q, (n, links, elbow), _ = arm
    tip = elbow + LENGTH[2] * links[2].x + 0.1 * links[2].y
    v = bodies[2].velocity_of(list(tip.to_matrix(n)))
    w = bodies[2].angular_velocity
    expect_w = links[2].ang_vel_in(n).to_matrix(links[2])
    rng = np.random.default_rng(3)
    for _ in range(5):
        qv, uv = rng.uniform(-np.pi, np.pi, 3), rng.uniform(-2, 2, 3)
        point = {c.diff(t): x for c, x in zip(q, uv, strict=True)}
        point.update(dict(zip(q, qv, strict=True)))
        got = np.array(v.xreplace(point).evalf(), dtype=float).ravel()
        ref = np.ravel(kane[2](*qv, *uv))
        assert np.abs(got - ref).max() < 1e-12
        dw = np.array((w - expect_w).xreplace(point).evalf(), dtype=float)
        assert np.abs(dw).max() < 1e-12


def test_rotation_bodies_share_coordinates_and_have_no_events(arm) -> None:
    _, bodies, q, *_ = arm
    assert [b.attitude.kind for b in bodies] == ["rotation"] * 3
    assert bodies[2].attitude.coordinates == tuple(q)
    assert [k for _, k, _, _ in arm[-1].attitudes] == ["rotation"] * 3


def test_non_orthogonal_rotation_refused_naming_the_body() -> None:
    q1 = pfaff.coordinates("q1")
    s = pfaff.System([q1])
    bad = sp.Matrix([[sp.cos(q1), -sp.sin(q1), 0], [sp.sin(q1), sp.cos(q1), 0], [0, 0, 1.001]])
    with pytest.raises(ModelError, match=r"body `wobbly`.*not a rotation"):
        s.add_rigid_body(1, [1, 1, 1], [0, 0, 0], Rotation(bad), name="wobbly")
    mirror = sp.diag(1, 1, -1) * bad.subs(1.001, 1)
    with pytest.raises(ModelError, match="not a rotation"):
        s.add_rigid_body(1, [1, 1, 1], [0, 0, 0], Rotation(mirror), name="mirror")


def test_rotation_has_no_inverse_maps() -> None:
    q1 = pfaff.coordinates("q1")
    r = Rotation(sp.Matrix([[1, 0, 0], [0, sp.cos(q1), -sp.sin(q1)], [0, sp.sin(q1), sp.cos(q1)]]))
    with pytest.raises(ModelError, match=r"no `from_dcm`.*EulerAngles"):
        r.from_dcm(np.eye(3))
    with pytest.raises(ModelError, match="no `rates`"):
        r.rates([0.0], [0.0, 0.0, 1.0])
    with pytest.raises(ModelTypeError, match="Rotation"):
        pfaff.attitude.dcm_from(r, [0.0])


def test_coordinate_sets_still_refuse_sharing() -> None:
    a, b, c, d = q = pfaff.coordinates("a b c d")
    s = pfaff.System(list(q))
    s.add_rigid_body(1, [1, 1, 1], [0, 0, 0], EulerAngles([a, b, c]), name="link1")
    with pytest.raises(ModelError, match="already an attitude coordinate of body"):
        s.add_rigid_body(1, [1, 1, 1], [0, 0, 0], EulerAngles([c, d, a]))
    rz = sp.Matrix([[sp.cos(a), -sp.sin(a), 0], [sp.sin(a), sp.cos(a), 0], [0, 0, 1]])
    with pytest.raises(ModelError, match="only Rotation and ReferenceFrame"):
        s.add_rigid_body(1, [1, 1, 1], [0, 0, 0], Rotation(rz))
    with pytest.raises(ModelTypeError, match="0 is not a coordinate"):
        EulerAngles([d, 0, a])


def test_frame_attitude_needs_the_inertial_frame_and_system_coordinates() -> None:
    q1, q2 = pfaff.coordinates("q1 q2")
    n = me.ReferenceFrame("N")
    b = n.orientnew("B", "Axis", (q1, n.z))
    with pytest.raises(ModelError, match="frame=N"):
        pfaff.System([q1]).add_rigid_body(1, [1, 1, 1], [0, 0, 0], b)
    with pytest.raises(ModelError, match=r"`q1\(t\)` is not a coordinate of this system"):
        pfaff.System([q2], frame=n).add_rigid_body(1, [1, 1, 1], [0, 0, 0], b)
    loose = me.ReferenceFrame("L")
    with pytest.raises(ModelError, match="not oriented relative"):
        pfaff.System([q1], frame=n).add_rigid_body(1, [1, 1, 1], [0, 0, 0], loose)


def test_accelerations_match_pinocchio(arm) -> None:
    """Optional: the forward dynamics (ABA) of Pinocchio on the same arm."""
    pin = pytest.importorskip("pinocchio")
    *_, model = arm
    robot = pin.Model()
    robot.gravity.linear = np.array([0.0, 0.0, -GRAVITY])
    joints = (pin.JointModelRZ(), pin.JointModelRY(), pin.JointModelRY())
    offsets = ((0.0, 0.0, 0.0), (0.0, 0.0, LENGTH[0]), (LENGTH[1], 0.0, 0.0))
    centres = ((0.0, 0.0, LENGTH[0] / 2), (LENGTH[1] / 2, 0.0, 0.0), (LENGTH[2] / 2, 0.0, 0.0))
    parent = 0
    for k in range(3):
        placement = pin.SE3(np.eye(3), np.array(offsets[k]))
        parent = robot.addJoint(parent, joints[k], placement, f"j{k + 1}")
        inertia = pin.Inertia(MASS[k], np.array(centres[k]), np.array(INERTIA[k]))
        robot.appendBodyToJoint(parent, inertia, pin.SE3.Identity())
    data = robot.createData()
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(20):
        q, u = rng.uniform(-np.pi, np.pi, 3), rng.uniform(-2, 2, 3)
        tau = np.array(_torques(tuple(q), tuple(u)))
        ref = pin.aba(robot, data, q, u, tau)
        qdd, _ = model.accelerations(0.0, q, u)
        worst = max(worst, np.abs(qdd - ref).max() / max(1.0, np.abs(ref).max()))
    assert worst < 1e-10, worst
