"""
From SymPy's KanesMethod
========================

A double pendulum written the usual way with ``sympy.physics.mechanics`` (frames, points,
particles, loads, ``KanesMethod``) becomes a :class:`pfaff.System` with :func:`pfaff.from_sympy`.
Both are integrated from the same state: pfaff's compiled model, and SciPy's ``solve_ivp`` on
SymPy's own ``mass_matrix_full`` and ``forcing_full``.
"""

import matplotlib.pyplot as plt
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from sympy.physics.mechanics import (
    KanesMethod,
    Particle,
    Point,
    ReferenceFrame,
    dynamicsymbols,
)

import pfaff

q1, q2, u1, u2 = dynamicsymbols("q1 q2 u1 u2")
m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g")
N = ReferenceFrame("N")
A = N.orientnew("A", "Axis", [q1, N.z])
B = N.orientnew("B", "Axis", [q2, N.z])
A.set_ang_vel(N, u1 * N.z)
B.set_ang_vel(N, u2 * N.z)
pivot = Point("O")
pivot.set_vel(N, 0)
P1 = pivot.locatenew("P1", -l1 * A.y)
P2 = P1.locatenew("P2", -l2 * B.y)
P1.v2pt_theory(pivot, N, A)
P2.v2pt_theory(P1, N, B)
km = KanesMethod(N, [q1, q2], [u1, u2], kd_eqs=[q1.diff() - u1, q2.diff() - u2])
km.kanes_equations(
    [Particle("p1", P1, m1), Particle("p2", P2, m2)], [(P1, -m1 * g * N.y), (P2, -m2 * g * N.y)]
)

values = {"m1": 1.0, "m2": 2.0, "l1": 1.0, "l2": 0.5, "g": 9.81}
model = pfaff.from_sympy(km).equations().compile(values)
te = np.linspace(0.0, 5.0, 251)
traj = pfaff.simulate(model, [1.0, 2.0], [0.0, 0.0], (0.0, 5.0), t_eval=te, rtol=1e-11)

symbols = [m1, m2, l1, l2, g]
f = sp.lambdify([q1, q2, u1, u2, *symbols], [km.mass_matrix_full, km.forcing_full])
par = [values[s.name] for s in symbols]


def rhs(t, x):
    M, F = f(*x, *par)
    return np.linalg.solve(np.array(M, float), np.array(F, float).ravel())


ref = solve_ivp(rhs, (0.0, 5.0), [1.0, 2.0, 0.0, 0.0], t_eval=te, rtol=1e-11, atol=1e-12)

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
ax1.plot(te, traj.q[:, 0], label="q1 (pfaff)")
ax1.plot(te, traj.q[:, 1], label="q2 (pfaff)")
ax1.plot(te, ref.y[0], "k:", te, ref.y[1], "k:", lw=1)
ax1.set(xlabel="t (s)", ylabel="angle (rad)", title="double pendulum (dotted: SymPy + SciPy)")
ax1.legend()
ax2.semilogy(te, np.abs(traj.q - ref.y[:2].T).max(axis=1) + 1e-17)
ax2.set(xlabel="t (s)", ylabel="max |Δq| (rad)", title="pfaff against KanesMethod")
fig.tight_layout()
