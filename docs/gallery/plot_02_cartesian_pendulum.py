"""
The Cartesian pendulum
======================

A point mass in x and y held on a circle by the holonomic constraint x² + y² − L² = 0. The
multiplier is the rod's tension: T = −2Lλ, which at the bottom of a swing released from rest at
angle θ₀ is m g (3 − 2 cos θ₀). The projection method keeps the constraint at rounding level.
"""

import matplotlib.pyplot as plt
import numpy as np

import pfaff

m, g, L = 1.0, 9.81, 2.0
model = pfaff.models.cartesian_pendulum().equations().compile({"m": m, "g": g, "L": L})
theta0 = np.pi / 2  # released from horizontal
traj = pfaff.simulate(model, [L, 0.0], [0.0, 0.0], (0.0, 3.0), t_eval=np.linspace(0, 3, 301))

x, y = traj.q.T
tension = -2 * L * traj.multipliers[:, 0]
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
ax1.plot(traj.t, tension, label="−2Lλ")
ax1.axhline(m * g * (3 - 2 * np.cos(theta0)), color="k", ls="--", label="m g (3 − 2 cos θ₀)")
ax1.set(xlabel="t (s)", ylabel="tension (N)", title="rod tension")
ax1.legend()
ax2.semilogy(traj.t, np.abs(x**2 + y**2 - L**2) + 1e-18)
ax2.set(xlabel="t (s)", ylabel="|x² + y² − L²|", title="constraint residual")
fig.tight_layout()
print("largest tension:", tension.max(), " closed form:", m * g * 3)
