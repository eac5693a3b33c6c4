"""A closed four-bar linkage written with SymPy's joints, converted by ``pfaff.from_sympy`` and
simulated: the loop SymPy cannot simulate by itself (its ``KanesMethod`` gives the equations,
but no integrator that keeps the loop closed).

The ground pivots A = (0, 0) and D = (d, 0); the crank AB (length a), the coupler BC (b) and
the rocker CD (c) are uniform rods of mass m_i turning in the vertical x-y plane about z, under
gravity along −y. Three ``PinJoint``s chain ground → crank → coupler → rocker; the rocker's free
end must meet D: two holonomic constraints (the loop). Run it::

    python examples/fourbar_sympy.py
"""

from __future__ import annotations

import numpy as np
import sympy as sp
from sympy.physics.mechanics import (
    PinJoint,
    Point,
    ReferenceFrame,
    RigidBody,
    System,
    dynamicsymbols,
    inertia,
)

import pfaff

VALUES = {"a": 0.3, "b": 1.0, "c": 0.8, "d": 1.0, "m1": 1.0, "m2": 2.0, "m3": 1.5, "g": 9.81}


def fourbar_system() -> System:
    """The four-bar as a ``sympy.physics.mechanics.System`` (coordinates q1, q2, q3: the
    relative joint angles; q2 and q3 dependent through the loop)."""
    a, b, c, d, g = sp.symbols("a b c d g")
    masses = sp.symbols("m1 m2 m3")
    q1, q2, q3 = dynamicsymbols("q1 q2 q3")
    u1, u2, u3 = dynamicsymbols("u1 u2 u3")
    ground = RigidBody("ground", frame=ReferenceFrame("N"), masscenter=Point("A"))
    rods = []
    for name, m, length in zip(("crank", "coupler", "rocker"), masses, (a, b, c), strict=True):
        frame, centre = ReferenceFrame(f"{name}_frame"), Point(f"{name}_centre")
        rod = RigidBody(name, centre, frame, m, (inertia(frame, 0, 0, m * length**2 / 12), centre))
        rods.append((rod, length))
    system = System.from_newtonian(ground)
    parent, parent_length = ground, None
    joints = []
    for (rod, length), q, u in zip(rods, (q1, q2, q3), (u1, u2, u3), strict=True):
        on_parent = (
            parent.masscenter if parent_length is None else parent_length / 2 * parent.frame.x
        )
        joints.append(PinJoint(f"J_{rod.name}", parent, rod, q, u, parent_point=on_parent,
                               child_point=-length / 2 * rod.frame.x,
                               joint_axis=parent.frame.z))  # fmt: skip
        parent, parent_length = rod, length
    system.add_joints(*joints)
    rocker, length = rods[2]
    tip = rocker.masscenter.locatenew("tip", length / 2 * rocker.frame.x)
    gap = tip.pos_from(ground.masscenter) - d * ground.frame.x
    system.add_holonomic_constraints(gap.dot(ground.frame.x), gap.dot(ground.frame.y))
    system.q_ind, system.q_dep = [q1], [q2, q3]
    system.u_ind, system.u_dep = [u1], [u2, u3]
    system.apply_uniform_gravity(-g * ground.frame.y)
    system.validate_system()
    return system


def closed_state(theta1: float, rate1: float) -> tuple[np.ndarray, np.ndarray]:
    """A consistent state: the crank at θ1 (rate θ̇1), the loop closed with the coupler above
    the ground line (relative angles q2 = θ2 − θ1, q3 = θ3 − θ2)."""
    a, b, c, d = (VALUES[k] for k in "abcd")
    bx, by = a * np.cos(theta1), a * np.sin(theta1)
    dist = np.hypot(d - bx, -by)
    # C on the circle about B (radius b) and about D (radius c), the upper intersection
    along = (b**2 - c**2 + dist**2) / (2 * dist)
    h = np.sqrt(b**2 - along**2)
    ex, ey = (d - bx) / dist, -by / dist
    cx, cy = bx + along * ex - h * ey, by + along * ey + h * ex
    th2, th3 = np.arctan2(cy - by, cx - bx), np.arctan2(-cy, d - cx)
    q = np.array([theta1, th2 - theta1, th3 - th2])
    # velocities: the loop's velocity rows fix q̇2, q̇3 from q̇1 (solved below by pfaff)
    return q, np.array([rate1, 0.0, 0.0])


def main(t_end: float = 5.0) -> pfaff.Trajectory:
    system = pfaff.from_sympy(fourbar_system())
    model = system.equations().compile(VALUES)
    q0, qd0 = closed_state(np.pi / 3, 2.0)
    q0, qd0 = pfaff.consistent_state(model, q0, qd0, independent=[0])
    run = pfaff.simulate(model, q0, qd0, (0.0, t_end), rtol=1e-10, atol=1e-12, throw=True)
    # gravity comes as SymPy's loads (generalized forces, not a potential): the balance
    # T(t) − T(0) − W(t) of the kinetic energy and the loads' work is the conservation check
    drift = np.abs(run.energy_balance).max()
    print(f"four-bar from SymPy joints: {len(run.t)} states to t = {t_end}, {run.status}")
    print(f"  crank angle q1(t_end) = {run.q[-1, 0]:.6f} rad, energy balance error {drift:.2e} J")
    print(f"  largest loop residual {np.abs(run.position_residual).max():.2e} m")
    return run


if __name__ == "__main__":
    main()
