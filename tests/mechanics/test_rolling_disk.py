"""The zoo's rolling disk (``pfaff.models.rolling_disk``) against real references: SymPy's
``KanesMethod`` on an independently built rolling disc, conservation of energy, the closed-form
steady circular rolling, and the contact forces (the multipliers) of its rolling constraints."""

from __future__ import annotations

import functools

import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me

import pfaff
from pfaff.attitude import EulerAngles

VALUES = {"m": 1.3, "r": 0.4, "g": 9.81}
X, Y, Z, PSI, THETA, PHI = range(6)  # the zoo model's coordinate order


@functools.cache
def _model():
    return pfaff.models.rolling_disk().equations().compile(VALUES)


def rolling_state(psi, theta, phi, psi_d, theta_d, phi_d, x=0.0, y=0.0):
    """A state on all three constraints, built from the physics (not from pfaff's rows): the
    centre at height r cos θ and moving with v = ω × (r k), k the lean frame's z axis (contact →
    centre), since the material contact point is at rest; ω = ψ̇ e_z + θ̇ i + φ̇ j with i the lean
    axis (horizontal) and j the disk's axis."""
    r = VALUES["r"]
    sp_, cp, st, ct = np.sin(psi), np.cos(psi), np.sin(theta), np.cos(theta)
    i, j, k = [cp, sp_, 0.0], [-sp_ * ct, cp * ct, st], [sp_ * st, -cp * st, ct]
    w = psi_d * np.array([0.0, 0.0, 1.0]) + theta_d * np.array(i) + phi_d * np.array(j)
    v = np.cross(w, r * np.array(k))
    q = np.array([x, y, r * ct, psi, theta, phi])
    qd = np.array([*v, psi_d, theta_d, phi_d])
    return q, qd


# ---------------------------------------------------------------------------------------------
# a. SymPy's KanesMethod on the same disc
# ---------------------------------------------------------------------------------------------


@functools.cache
def _kane_disc():
    """Rolling disc by Kane's method, built here: yaw q1 about N.z, lean q2 about Y.x, spin q3
    about L.y (the disc's axis); q4, q5 the mass centre's x, y (its height is r cos q2, so the
    contact height is built into the coordinates). Speeds u1..u3: the disc's angular velocity in
    lean-frame components; u4, u5 = q̇4, q̇5, dependent through the two no-slip constraints (the
    material contact point has no horizontal velocity). Returns a function of pfaff's (q, q̇)
    giving Kane's q̈ of q1..q5 (pfaff's ψ, θ, φ, x, y) and its no-slip residuals there."""
    q1, q2, q3, q4, q5 = q = me.dynamicsymbols("q1:6")
    u1, u2, u3, u4, u5 = u = me.dynamicsymbols("u1:6")
    m, r, g = sp.symbols("m r g")
    t = me.dynamicsymbols._t
    N = me.ReferenceFrame("N")
    Yf = N.orientnew("Y", "Axis", [q1, N.z])
    L = Yf.orientnew("L", "Axis", [q2, Yf.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    w_q = R.ang_vel_in(N)  # in q̇
    kd = [me.dot(w_q, L.x) - u1, me.dot(w_q, L.y) - u2, me.dot(w_q, L.z) - u3]
    kd += [q4.diff(t) - u4, q5.diff(t) - u5]
    R.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    origin = me.Point("O")
    origin.set_vel(N, 0)
    Dmc = origin.locatenew("Dmc", q4 * N.x + q5 * N.y + r * sp.cos(q2) * N.z)
    Dmc.set_vel(N, u4 * N.x + u5 * N.y - r * sp.sin(q2) * u1 * N.z)  # q̇2 = u1
    C = Dmc.locatenew("C", -r * L.z)  # the contact point
    C.v2pt_theory(Dmc, N, R)  # of the material point of R there
    nh = [me.dot(C.vel(N), N.x), me.dot(C.vel(N), N.y)]
    disc = me.RigidBody(
        "disc", Dmc, R, m, (me.inertia(L, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4), Dmc)
    )
    kane = me.KanesMethod(
        N,
        q_ind=q,
        u_ind=[u1, u2, u3],
        u_dependent=[u4, u5],
        kd_eqs=kd,
        velocity_constraints=nh,
    )
    kane.kanes_equations([disc], [(Dmc, -m * g * N.z)])
    # to Kane's state from pfaff's, and q̈ from u̇ by differentiating q̇(q, u)
    qs, qds = sp.symbols("_q1:6"), sp.symbols("_qd1:6")
    us, uds = sp.symbols("_u1:6"), sp.symbols("_ud1:6")
    qd_of = kane.kindiffdict()
    qdd = [qd_of[qi.diff(t)].diff(t).subs(qd_of) for qi in q]
    rep = {ui.diff(t): s for ui, s in zip(u, uds, strict=True)}
    rep |= {qi.diff(t): s for qi, s in zip(q, qds, strict=True)}
    rep |= dict(zip(u, us, strict=True)) | dict(zip(q, qs, strict=True))
    params = [m, r, g]
    speeds = [me.dot(w_q, L.x), me.dot(w_q, L.y), me.dot(w_q, L.z), q4.diff(t), q5.diff(t)]
    f_u = sp.lambdify([*qs, *qds], [e.xreplace(rep) for e in speeds])
    args = [*qs, *us, *params]
    f_M = sp.lambdify(args, kane.mass_matrix_full.xreplace(rep), cse=True)
    f_f = sp.lambdify(args, kane.forcing_full.xreplace(rep), cse=True)
    f_qdd = sp.lambdify([*qs, *us, *uds, *params], [e.xreplace(rep) for e in qdd], cse=True)
    f_nh = sp.lambdify(args, [e.xreplace(rep) for e in nh])

    def accelerations(q_pf: np.ndarray, qd_pf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Kane's (ψ̈, θ̈, φ̈, ẍ, ÿ) and its no-slip residuals at pfaff's state."""
        order = [PSI, THETA, PHI, X, Y]
        qv, qdv = q_pf[order], qd_pf[order]
        uv = np.array(f_u(*qv, *qdv), dtype=float)
        p = [VALUES[s] for s in ("m", "r", "g")]
        sol = np.linalg.solve(f_M(*qv, *uv, *p), np.ravel(f_f(*qv, *uv, *p)))
        np.testing.assert_allclose(sol[:5], qdv, rtol=0, atol=1e-12)  # q̇ back from u
        acc = np.array(f_qdd(*qv, *uv, *sol[5:], *p), dtype=float)
        return acc, np.array(f_nh(*qv, *uv, *p), dtype=float)

    return accelerations


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_accelerations_agree_with_kanes_method() -> None:
    kane = _kane_disc()
    model = _model()
    rng = np.random.default_rng(20261124)
    for _ in range(3):
        angles = rng.uniform([-np.pi, -1.0, -np.pi], [np.pi, 1.0, np.pi])
        rates = rng.uniform(-3.0, 3.0, 3)
        q, qd = rolling_state(*angles, *rates, *rng.uniform(-1.0, 1.0, 2))
        f, g = model.constraint_residual(0.0, q, qd)
        assert np.abs(f).max() < 1e-14 and np.abs(g).max() < 1e-13  # on pfaff's constraints too
        expect, nh = kane(q, qd)
        assert np.abs(nh).max() < 1e-13  # ... and on Kane's
        qdd, _ = model.accelerations(0.0, q, qd)
        np.testing.assert_allclose(qdd[[PSI, THETA, PHI, X, Y]], expect, rtol=0, atol=1e-9)
        # z is the mass centre's height r cos θ: z̈ = −r (sin θ θ̈ + cos θ θ̇²)
        r, th, thd = VALUES["r"], q[THETA], qd[THETA]
        z_dd = -r * (np.sin(th) * expect[1] + np.cos(th) * thd**2)
        assert abs(qdd[Z] - z_dd) < 1e-9


# ---------------------------------------------------------------------------------------------
# b. energy
# ---------------------------------------------------------------------------------------------


def test_energy_and_constraints_kept_over_a_simulation() -> None:
    model = _model()
    q0, qd0 = rolling_state(0.2, 0.3, 0.0, 1.0, -0.4, 9.0)  # rolling fast: stays up, wobbling
    tr = pfaff.simulate(
        model, q0, qd0, (0.0, 5.0), rtol=1e-10, atol=1e-12, t_eval=np.linspace(0, 5, 101)
    )
    assert tr.status == "success", tr.message
    assert np.ptp(tr.q[:, THETA]) > 0.05  # the lean does move (not a trivial steady state)
    assert np.abs(tr.q[:, THETA]).max() < 1.2
    assert np.abs(tr.energy - tr.energy[0]).max() < 1e-8
    assert np.abs(tr.constraint_residual).max() < 1e-9
    T, V = model.energy(0.0, q0, qd0)
    assert abs(tr.energy[0] - (T + V)) < 1e-12
    assert abs(V - VALUES["m"] * VALUES["g"] * q0[Z]) < 1e-12


# ---------------------------------------------------------------------------------------------
# c. steady rolling in a circle
# ---------------------------------------------------------------------------------------------
#
# Lean frame L (turned by ψ about the vertical, then by θ about its x axis): x horizontal, along
# the rolling direction; y the disk's axis; z from the contact P to the centre G. With s = sin θ,
# c = cos θ the vertical is s y + c z. In steady rolling (θ = θ0, ψ̇ = Ω, φ̇ constant) the frame
# turns with Ω (0, s, c) and the disk with
#     ω = Ω (0, s, c) + φ̇ (0, 1, 0) = (0, ω_y, Ω c),   ω_y = Ω s + φ̇.
# Rolling (P at rest): v_G = ω × (r z) = r ω_y x, so G moves on a circle with speed v = r ω_y
# and a_G = Ω (vertical) × v x = v Ω (c y − s z) (horizontal).
# Contact force F = m a_G + m g (vertical) (Newton), in L: F_y = m g s + m v Ω c,
# F_z = m g c − m v Ω s; its moment about G: (−r z) × F = r F_y x.
# Angular momentum about G, I = diag(A, C, A) (A = m r²/4, C = m r²/2, symmetric about y so L
# is principal): H = (0, C ω_y, A Ω c), constant in L, so dH/dt = Ω (0, s, c) × H
#     = Ω c (A Ω s − C ω_y) x.
# Euler: Ω c (A Ω s − C ω_y) = r m (g s + r ω_y Ω c), i.e.
#     g s = r c Ω (Ω s / 4 − 3 ω_y / 2)                                          (*)
# (the tilted-coin relation; for small Ω s it is g tan θ ≈ −(3/2) Ω v, the disk leaning into the
# turn). Given θ0 and Ω, (*) fixes ω_y and so φ̇ = ω_y − Ω s. The contact force is then
# F_vertical = m g and a horizontal friction m v Ω towards the circle's centre.


def steady_circle(theta0: float, omega: float, psi: float = 0.4):
    r, g = VALUES["r"], VALUES["g"]
    s, c = np.sin(theta0), np.cos(theta0)
    w_y = (r * c * omega**2 * s / 4 - g * s) / (1.5 * r * c * omega)  # from (*)
    q, qd = rolling_state(psi, theta0, 0.7, omega, 0.0, w_y - omega * s)
    return q, qd, r * w_y


def test_steady_circular_rolling() -> None:
    model = _model()
    theta0, omega = 0.25, 1.5
    q, qd, v = steady_circle(theta0, omega)
    assert abs(v) > 1.0  # rolling, not spinning in place
    qdd, lam = model.accelerations(0.0, q, qd)
    assert np.abs(qdd[[PSI, THETA, PHI]]).max() < 1e-10
    # the mass centre's acceleration is v Ω towards the circle's centre, (−sin ψ, cos ψ, 0)
    psi, m, g = q[PSI], VALUES["m"], VALUES["g"]
    a_g = v * omega * np.array([-np.sin(psi), np.cos(psi), 0.0])
    np.testing.assert_allclose(qdd[[X, Y, Z]], a_g, rtol=0, atol=1e-10)
    np.testing.assert_allclose(lam, [m * g, *(m * a_g[:2])], rtol=0, atol=1e-10)
    # off the relation (*) the lean does accelerate
    off = qd.copy()
    off[PHI] *= 1.1
    q2, qd2 = rolling_state(*q[3:], *off[3:])
    assert abs(model.accelerations(0.0, q2, qd2)[0][THETA]) > 0.1
    # and a short run keeps the lean and the rates
    tr = pfaff.simulate(model, q, qd, (0.0, 1.0), rtol=1e-11, atol=1e-12)
    assert tr.status == "success", tr.message
    assert np.abs(tr.q[:, THETA] - theta0).max() < 1e-8
    assert np.abs(tr.qd[:, [PSI, PHI]] - qd[[PSI, PHI]]).max() < 1e-8
    np.testing.assert_allclose(tr.q[-1, PSI], q[PSI] + omega * tr.t[-1], atol=1e-8)


# ---------------------------------------------------------------------------------------------
# d. the rolling constraints and their contact forces
# ---------------------------------------------------------------------------------------------


def test_no_slip_multipliers_are_the_friction_force() -> None:
    model = _model()
    assert tuple(model.constraint_names) == ("contact height", "no slip x", "no slip y")
    m, g = VALUES["m"], VALUES["g"]
    q, qd = rolling_state(0.3, 0.4, 1.0, 1.2, -0.5, 3.0)
    qdd, lam = model.accelerations(0.0, q, qd)
    # Aᵀλ is the generalized contact force; the rows' x, y, z columns are the identity (∂f/∂z = 1
    # for the height, ∂/∂ẋ, ∂/∂ẏ = 1 for the no-slip rows), so λ = (N, F_x, F_y) is the contact
    # force on the mass centre: Newton's m a = F − m g e_z
    np.testing.assert_allclose(m * qdd[[X, Y, Z]], [lam[1], lam[2], lam[0] - m * g], atol=1e-10)
    assert np.hypot(lam[1], lam[2]) > 0.5  # friction is working: the no-slip rows are active
    A = model.constraint_matrix(0.0, q)
    np.testing.assert_allclose(A[:, [X, Y, Z]], np.eye(3)[[2, 0, 1]], atol=1e-14)


def _disk_without_no_slip() -> pfaff.System:
    """The same disk with the contact height only (a disk on a frictionless plane)."""
    m, r, g = sp.symbols("m r g")
    x, y, z = pfaff.coordinates("x y z")
    att = EulerAngles(pfaff.coordinates("psi theta phi"), "312")
    s = pfaff.System([x, y, z, *att.coordinates], name="sliding disk")
    s.add_rigid_body(m, [m * r**2 / 4, m * r**2 / 2, m * r**2 / 4], [x, y, z], att, name="disk")
    s.add_potential_energy(m * g * z, name="gravity")
    s.add_holonomic_constraint(z - r * sp.cos(att.coordinates[1]), name="contact height")
    return s


def test_dropping_the_no_slip_constraints_changes_the_motion() -> None:
    rolling = _model()
    sliding = _disk_without_no_slip().equations().compile(VALUES)
    assert tuple(sliding.constraint_names) == ("contact height",)
    q, qd = rolling_state(0.3, 0.4, 1.0, 1.2, -0.5, 3.0)
    qdd_roll, _ = rolling.accelerations(0.0, q, qd)
    qdd_slide, _ = sliding.accelerations(0.0, q, qd)  # the state is on its one constraint too
    np.testing.assert_allclose(qdd_slide[[X, Y]], 0.0, atol=1e-12)  # no horizontal force
    assert np.abs(qdd_roll[[X, Y]]).max() > 0.5
    assert np.abs(qdd_roll - qdd_slide).max() > 0.5
    # the turning differs too: the friction's moment about the centre is gone
    assert np.abs(qdd_roll[[PSI, THETA, PHI]] - qdd_slide[[PSI, THETA, PHI]]).max() > 0.1


def test_static_upright_disk_normal_force() -> None:
    model = _model()
    m, r, g = VALUES["m"], VALUES["r"], VALUES["g"]
    q = np.array([0.1, -0.2, r, 0.5, 0.0, 0.3])
    qdd, lam = model.accelerations(0.0, q, np.zeros(6))
    np.testing.assert_allclose(qdd, 0.0, atol=1e-12)  # balanced (unstably) on its edge
    np.testing.assert_allclose(lam, [m * g, 0.0, 0.0], atol=1e-12)
    # leaning, released at rest: the contact force is still what Newton needs
    q[THETA] = 0.2
    q[Z] = r * np.cos(0.2)
    qdd, lam = model.accelerations(0.0, q, np.zeros(6))
    assert qdd[THETA] > 0  # falls further over
    assert 0 < lam[0] < m * g  # the centre accelerates downward
    np.testing.assert_allclose(m * qdd[[X, Y, Z]], [lam[1], lam[2], lam[0] - m * g], atol=1e-12)
