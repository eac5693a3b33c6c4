"""Rigid bodies, torques and force elements as model pieces: their equations against hand
derivations, and bad input."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.attitude import MRP, EulerAngles, PlanarAngle, Quaternion

t = pfaff.t


def test_planar_body_kinetic_energy_and_velocity_of() -> None:
    x, y, th = q = pfaff.coordinates("x y theta")
    m, J, a = sp.symbols("m J a")
    s = pfaff.System(list(q))
    rod = s.add_rigid_body(m, J, [x, y], PlanarAngle(th))
    assert rod.name == "body0"
    eom = s.equations()
    assert eom.mass_matrix == sp.diag(m, m, J)
    tip = [x + a * sp.cos(th), y + a * sp.sin(th)]
    v = rod.velocity_of(tip)
    expect = sp.Matrix([d.diff(t) for d in tip])  # the material point moves with the body
    assert sp.simplify(v - expect) == sp.zeros(2, 1)


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_spatial_body_energy_matches_hand_form() -> None:
    """T of a body with Euler angles 3-2-1 against ½ m v² + ½ ωᵀIω with ω written out by hand."""
    x, y, z, psi, th, ph = q = pfaff.coordinates("x y z psi theta phi")
    m, I1, I2, I3 = sp.symbols("m I1 I2 I3")
    s = pfaff.System(list(q))
    body = s.add_rigid_body(m, [I1, I2, I3], [x, y, z], EulerAngles([psi, th, ph], "321"))
    d = [c.diff(t) for c in (psi, th, ph)]
    w = [  # body rates of the 3-2-1 sequence (Schaub & Junkins)
        -sp.sin(th) * d[0] + d[2],
        sp.sin(ph) * sp.cos(th) * d[0] + sp.cos(ph) * d[1],
        sp.cos(ph) * sp.cos(th) * d[0] - sp.sin(ph) * d[1],
    ]
    T = m * sum(c.diff(t) ** 2 for c in (x, y, z)) / 2
    T += (I1 * w[0] ** 2 + I2 * w[1] ** 2 + I3 * w[2] ** 2) / 2
    assert sp.simplify(body.kinetic_energy - T) == 0
    eom = s.equations()
    M = sp.Matrix(6, 6, lambda i, j: T.diff(q[i].diff(t), q[j].diff(t)))
    rng = np.random.default_rng(1)
    point = {**{c: v for c, v in zip(q, rng.uniform(-1, 1, 6), strict=True)}}
    point.update(
        {sp.Symbol(n): v for n, v in zip("m I1 I2 I3".split(), [2, 1, 2, 2.5], strict=True)}
    )
    num = sp.Matrix(eom.mass_matrix - M).subs({I1: 1, I2: 2, I3: 2.5, m: 2}).subs(point)
    assert max(abs(float(e)) for e in num) < 1e-12


def test_quaternion_body_adds_named_unit_norm_constraint() -> None:
    q = pfaff.coordinates("b0:4")
    s = pfaff.System(list(q))
    s.add_rigid_body(1, [1, 2, 3], [0, 0, 0], Quaternion(q), name="top")
    names, hol = s.constraint_rows()
    assert names == ("top unit norm",) and bool(hol[0])
    eom = s.equations()
    assert eom.constraint_matrix == sp.Matrix([[2 * c for c in q]])
    # T = ½ωᵀIω is degenerate along β: M β = 0 (M is singular, the augmented system is not)
    assert sp.simplify(eom.mass_matrix * sp.Matrix(q)) == sp.zeros(4, 1)


def test_torque_generalized_forces_by_partial_angular_velocities() -> None:
    _psi, th, _ph = q = pfaff.coordinates("psi theta phi")
    s = pfaff.System(list(q))
    body = s.add_rigid_body(1, [1, 2, 3], [0, 0, 0], EulerAngles(q, "313"))
    tau = sp.symbols("tau1:4")
    s.add_torque(list(tau), on=body, frame="body", name="motor")
    w = body.angular_velocity
    Q = sp.Matrix([sum(tau[i] * w[i].diff(c.diff(t)) for i in range(3)) for c in q])
    assert sp.simplify(s.equations().generalized_forces - Q) == sp.zeros(3, 1)
    # a torque about the inertial z axis: ω = ψ̇ z + θ̇ (line of nodes, ⊥ z) + φ̇ (body z, at
    # angle θ from z), so Q = (τ, 0, τ cos θ)
    s2 = pfaff.System(list(q))
    b2 = s2.add_rigid_body(1, [1, 2, 3], [0, 0, 0], EulerAngles(q, "313"))
    s2.add_torque([0, 0, tau[2]], on=b2)
    Q2 = sp.simplify(s2.equations().generalized_forces)
    assert Q2 == sp.Matrix([tau[2], 0, tau[2] * sp.cos(th)])
    (work,) = s2.work()
    assert work.name == "torque1" and work.point is None


def test_spring_damper_dissipation() -> None:
    x, y = pfaff.coordinates("x y")
    k, c, L0 = sp.symbols("k c L0", positive=True)
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_spring(k, between=([x, y], [0, 0]), rest_length=L0)
    s.add_damper(c, between=([x, y], [0, 0]))
    F = s.equations().forcing
    r = sp.sqrt(x**2 + y**2)
    rdot = (x * x.diff(t) + y * y.diff(t)) / r
    expect = sp.Matrix([-(k * (r - L0) + c * rdot) * v / r for v in (x, y)])
    assert sp.simplify(F - expect) == sp.zeros(2, 1)


def test_damper_power_in_the_energy_balance() -> None:
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(1, [x, 0])
    s.add_spring(4, between=([x, 0], [0, 0]))
    s.add_damper(0.3, between=([x, 0], [-1, 0]))
    model = s.equations().compile({})
    tr = pfaff.simulate(model, [1.0], [0.0], (0, 5), rtol=1e-10, atol=1e-12)
    # lightly damped oscillator: x = e^{-ζωt}(cos ω_d t + ζω/ω_d sin ω_d t), ω = 2, ζω = 0.15
    wd = np.sqrt(4 - 0.15**2)
    expect = np.exp(-0.15 * tr.t) * (np.cos(wd * tr.t) + 0.15 / wd * np.sin(wd * tr.t))
    np.testing.assert_allclose(tr.q[:, 0], expect, atol=1e-8)
    assert tr.nc_work[-1] < -1.0  # the damper took energy out ...
    assert abs(tr.energy_balance).max() < 1e-8  # ... exactly as much as the energy lost


@pytest.mark.parametrize(
    ("inertia", "match"),
    [
        ([[1, 0.5, 0], [0, 2, 0], [0, 0, 2]], "not symmetric"),
        ([1, -2, 2], "not positive definite"),
        ([1, 1, 3], "triangle inequality"),
        ([[1, 2, 0], [2, 1, 0], [0, 0, 1]], "not positive definite"),
    ],
)
def test_bad_inertia(inertia, match) -> None:
    q = pfaff.coordinates("b0:4")
    s = pfaff.System(list(q))
    with pytest.raises(pfaff.ModelError, match=match):
        s.add_rigid_body(1, inertia, [0, 0, 0], Quaternion(q))


def test_thin_disk_inertia_is_allowed() -> None:
    q = pfaff.coordinates("b0:4")
    s = pfaff.System(list(q))
    s.add_rigid_body(1, [0.25, 0.25, 0.5], [0, 0, 0], Quaternion(q))  # equality: a thin disk


def test_bad_attitude_and_body_input() -> None:
    a, b, c, d = q = pfaff.coordinates("a b c d")
    s = pfaff.System(list(q))
    with pytest.raises(pfaff.ModelError, match="needs 3 coordinates"):
        MRP([a, b])
    s.add_rigid_body(1, [1, 1, 1], [0, 0, 0], MRP([a, b, c]), name="one")
    with pytest.raises(pfaff.ModelError, match="already an attitude coordinate of body `one`"):
        s.add_rigid_body(1, [1, 1, 1], [0, 0, 0], EulerAngles([c, d, a]))
    f, g, h = pfaff.coordinates("f g h")
    s2 = pfaff.System([f, g, h])
    with pytest.raises(pfaff.ModelError, match="one number, which only a PlanarAngle"):
        s2.add_rigid_body(1, 2, [0, 0, 0], MRP([f, g, h]))
    with pytest.raises(pfaff.ModelError, match="planar"):
        s2.add_rigid_body(1, [1, 1, 1], [f, 0], MRP([f, g, h]))
    with pytest.raises(pfaff.ModelTypeError, match="attitude"):
        s.add_rigid_body(1, [1, 1, 1], [0, 0, 0], [a, b, c])
    e = pfaff.coordinates("e")
    with pytest.raises(pfaff.ModelError, match="not a coordinate of this system"):
        s.add_rigid_body(1, 1, [0, 0], PlanarAngle(e))


def test_quaternion_state_off_unit_norm_is_refused() -> None:
    s = pfaff.models.torque_free_body("quaternion")
    model = s.equations().compile({"I1": 1, "I2": 2, "I3": 3})
    q0 = np.array([1.0, 0.1, 0.0, 0.0])  # |β| = 1.005
    with pytest.raises(pfaff.StateError):
        pfaff.simulate(model, q0, np.zeros(4), (0, 1))
    tr = pfaff.simulate(model, q0, np.zeros(4), (0, 1), project_initial=True)
    assert tr.status == "success"
    assert abs(np.sum(tr.q**2, axis=1) - 1).max() < 1e-10
