"""
The seed's rolling ring
=======================

N particles held on a ring by a no-slip constraint and N − 1 spacing constraints, pushed at the
centre by a force F. Lagrange's equations with multipliers give θ̈ = F/(2Mr), ẍ = F/(2M) and the
friction force λ₁ = −F/2, whatever N. Here the ring of 6 particles is pushed for 2 s and its
centre follows x(t) = F t²/(4M); the multipliers are the constraint forces.
"""

import matplotlib.pyplot as plt
import numpy as np

import pfaff

values = {"M": 1.0, "r": 0.5, "F": 2.0}
ring = pfaff.models.rolling_ring(6, force=True)
eom = ring.equations()
model = eom.compile(values)
q0, qd0 = pfaff.models.ring_state(6, values["r"], 0.0)
qdd, lam = model.accelerations(0.0, q0, qd0)
print("x'' =", qdd[0], " (F/2M =", values["F"] / (2 * values["M"]), ")")
print("friction multiplier =", lam[0], " (-F/2 =", -values["F"] / 2, ")")

traj = pfaff.simulate(model, q0, qd0, (0.0, 2.0), t_eval=np.linspace(0.0, 2.0, 41))
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
ax1.plot(traj.t, traj.q[:, 0], "o", ms=4, label="pfaff")
ax1.plot(traj.t, values["F"] * traj.t**2 / (4 * values["M"]), "-", label="F t²/(4M)")
ax1.set(xlabel="t (s)", ylabel="x (m)", title="centre of the ring")
ax1.legend()
ax2.plot(np.arange(1, traj.multipliers.shape[1] + 1), traj.multipliers[-1], "s")
ax2.set(xlabel="constraint k", ylabel="λ_k", title="multipliers at t = 2 s")
fig.tight_layout()
