"""An independent reference for ``pfaff.models.diffdrive``: SymPy's ``KanesMethod`` and a closed form.

Kane's model is built here from frames and points, not from pfaff's rows. q = (x, y, ψ, φ_L, φ_R)
in pfaff's order, u = q̇ (kinematic equations q̇ − u = 0); the independent speeds are the wheel
rates u_L, u_R, the dependent ones u_x, u_y, u_ψ. The nonholonomic constraints come from the
velocity of each wheel's *material contact point* (zero in a no-slip contact), and only the
independent ones are given: its forward component at either wheel, and its lateral component at
the left wheel. The motor torques act on the wheels about the axle, their reactions on the
chassis; τ_L, τ_R are functions of time so that ``linearize`` gives them columns of B.

The closed form, from Kane's equations in the speeds v (forward) and ω (yaw):

    (m_c + 2 m_w + 2 I_w/r²) v̇ − m_c d ω² = (τ_L + τ_R)/r
    I_P ω̇ + m_c d v ω = b (τ_R − τ_L)/r,   I_P = I_c + m_c d² + 2 m_w b² + 2 J_w + 2 I_w b²/r²

and ẍ = v̇ cos ψ − v ω sin ψ, ÿ = v̇ sin ψ + v ω cos ψ, ψ̈ = ω̇, φ̈_{L,R} = (v̇ ∓ b ω̇)/r.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping

import numpy as np
import sympy as sp
import sympy.physics.mechanics as me

NAMES = ("m_c", "I_c", "d", "m_w", "I_w", "J_w", "r", "b")


@functools.cache
def kane_diffdrive() -> tuple[me.KanesMethod, dict]:
    """Kane's equations of the robot; returns the KanesMethod and its symbols by role."""
    q = me.dynamicsymbols("q_x q_y q_psi q_L q_R")
    u = me.dynamicsymbols("u_x u_y u_psi u_L u_R")
    tau_l, tau_r = me.dynamicsymbols("tau_L tau_R")
    m_c, I_c, d, m_w, I_w, J_w, r, b = sp.symbols(NAMES)
    t = me.dynamicsymbols._t
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [q[2], N.z])
    B.set_ang_vel(N, u[2] * N.z)
    origin = me.Point("O")
    origin.set_vel(N, 0)
    P = origin.locatenew("P", q[0] * N.x + q[1] * N.y)  # the axle's midpoint
    P.set_vel(N, u[0] * N.x + u[1] * N.y)
    G = P.locatenew("G", d * B.x)
    G.v2pt_theory(P, N, B)
    chassis = me.RigidBody("chassis", G, B, m_c, (me.inertia(B, 0, 0, I_c), G))
    bodies, loads, contacts = [chassis], [], []
    for side, sign, angle, rate, tau in (("L", 1, q[3], u[3], tau_l), ("R", -1, q[4], u[4], tau_r)):
        W = B.orientnew(f"W{side}", "Axis", [angle, B.y])
        W.set_ang_vel(N, u[2] * N.z + rate * B.y)
        centre = P.locatenew(f"C{side}", sign * b * B.y)
        centre.v2pt_theory(P, N, B)
        contact = centre.locatenew(f"K{side}", -r * N.z)  # the wheel's material point there
        contact.v2pt_theory(centre, N, W)
        contacts.append(contact.vel(N))
        bodies.append(
            me.RigidBody(f"wheel {side}", centre, W, m_w, (me.inertia(W, J_w, I_w, J_w), centre))
        )
        loads += [(W, tau * B.y), (B, -tau * B.y)]
    velocity_constraints = [
        me.dot(contacts[0], B.x),
        me.dot(contacts[1], B.x),
        me.dot(contacts[0], B.y),
    ]
    kane = me.KanesMethod(
        N,
        q_ind=q,
        u_ind=[u[3], u[4]],
        u_dependent=[u[0], u[1], u[2]],
        kd_eqs=[qi.diff(t) - ui for qi, ui in zip(q, u, strict=True)],
        velocity_constraints=velocity_constraints,
    )
    kane.kanes_equations(bodies, loads)
    return kane, {"q": q, "u": u, "tau": (tau_l, tau_r), "params": sp.symbols(NAMES)}


@functools.cache
def _kane_functions() -> tuple[Callable, list[int]]:
    """Kane's mass matrix and forcing as one function, and where pfaff's q̈_j is in Kane's u̇
    (ordered independent speeds first)."""
    kane, s = kane_diffdrive()
    args = [*s["q"], *s["u"], *s["tau"], *s["params"]]
    order = [list(kane.u).index(ui) for ui in s["u"]]
    return sp.lambdify(args, [kane.mass_matrix, kane.forcing], "numpy", cse=True), order


def kane_accelerations(
    values: Mapping[str, float], q: np.ndarray, qd: np.ndarray, tau: tuple[float, float]
) -> np.ndarray:
    """Kane's q̈ (= u̇, all five) at a consistent state (q, q̇) with torques ``tau``."""
    function, order = _kane_functions()
    mass, forcing = function(*q, *qd, *tau, *(values[n] for n in NAMES))
    ud = np.linalg.solve(np.asarray(mass, dtype=float), np.asarray(forcing, dtype=float).ravel())
    return ud[order]


def closed_form_accelerations(
    values: Mapping[str, float], q: np.ndarray, qd: np.ndarray, tau: tuple[float, float]
) -> np.ndarray:
    """q̈ by the closed form of the module docstring."""
    m_c, I_c, d, m_w, I_w, J_w, r, b = (values[n] for n in NAMES)
    psi = q[2]
    v = qd[0] * np.cos(psi) + qd[1] * np.sin(psi)
    w = qd[2]
    i_p = I_c + m_c * d**2 + 2 * m_w * b**2 + 2 * J_w + 2 * I_w * b**2 / r**2
    vd = ((tau[0] + tau[1]) / r + m_c * d * w**2) / (m_c + 2 * m_w + 2 * I_w / r**2)
    wd = (b * (tau[1] - tau[0]) / r - m_c * d * v * w) / i_p
    return np.array(
        [
            vd * np.cos(psi) - v * w * np.sin(psi),
            vd * np.sin(psi) + v * w * np.cos(psi),
            wd,
            (vd - b * wd) / r,
            (vd + b * wd) / r,
        ]
    )


def rolling_state(q: np.ndarray, v: float, w: float, r: float, b: float) -> np.ndarray:
    """The rates q̇ of a no-slip motion with forward speed v and yaw rate w at heading q[2]."""
    psi = q[2]
    return np.array([v * np.cos(psi), v * np.sin(psi), w, (v - b * w) / r, (v + b * w) / r])


def kane_linearization(values: Mapping[str, float], speed: float) -> tuple[np.ndarray, np.ndarray]:
    """Kane's (A, B) about straight driving along x at ``speed``, torques zero; the state is
    (x, y, ψ, φ_L, φ_R, u_L, u_R), the inputs (τ_L, τ_R)."""
    kane, s = kane_diffdrive()
    r = values["r"]
    q, u = s["q"], s["u"]
    rates = [speed, 0.0, 0.0, speed / r, speed / r]
    op = {**dict.fromkeys(q, 0.0), **dict(zip(u, rates, strict=True))}
    op.update({qi.diff(me.dynamicsymbols._t): ri for qi, ri in zip(q, rates, strict=True)})
    op.update(dict.fromkeys([ui.diff(me.dynamicsymbols._t) for ui in u], 0.0))
    op.update(dict.fromkeys(s["tau"], 0.0))
    A, B, inputs = kane.linearize(op_point=op, A_and_B=True)
    assert list(inputs) == list(s["tau"])
    sub = {sp.Symbol(n): values[n] for n in NAMES}
    return np.array(A.subs(sub), dtype=float), np.array(B.subs(sub), dtype=float)


def closed_form_linearization(
    values: Mapping[str, float], speed: float
) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of :func:`kane_linearization` from the closed form: about v = speed, ω = 0,
    δv̇ = (δτ_L + δτ_R)/(r m_e) and δω̇ = (b (δτ_R − δτ_L)/r − m_c d v δω)/I_P (m_e = m_c + 2 m_w
    + 2 I_w/r²), with v = r (u_L + u_R)/2, ω = r (u_R − u_L)/(2b), u̇_{L,R} = (v̇ ∓ b ω̇)/r;
    kinematics ẋ = v, ẏ = v ψ, ψ̇ = ω, φ̇ = u."""
    m_c, I_c, d, m_w, I_w, J_w, r, b = (values[n] for n in NAMES)
    m_e = m_c + 2 * m_w + 2 * I_w / r**2
    i_p = I_c + m_c * d**2 + 2 * m_w * b**2 + 2 * J_w + 2 * I_w * b**2 / r**2
    v_of_u = np.array([r / 2, r / 2])  # v = v_of_u · (u_L, u_R)
    w_of_u = np.array([-r / (2 * b), r / (2 * b)])
    # (v̇, ω̇) = K (u_L, u_R) + G (τ_L, τ_R)
    K = np.vstack([np.zeros(2), -m_c * d * speed / i_p * w_of_u])
    G = np.array([[1 / (r * m_e), 1 / (r * m_e)], [-b / (r * i_p), b / (r * i_p)]])
    to_u = np.array([[1 / r, -b / r], [1 / r, b / r]])  # (u̇_L, u̇_R) from (v̇, ω̇)
    A = np.zeros((7, 7))
    A[0, 5:] = v_of_u
    A[1, 2] = speed
    A[2, 5:] = w_of_u
    A[3, 5] = A[4, 6] = 1.0
    A[5:, 5:] = to_u @ K
    B = np.zeros((7, 2))
    B[5:, :] = to_u @ G
    return A, B
