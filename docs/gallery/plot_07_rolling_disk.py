"""
The rolling disk
================

A thin disk rolling without slip on a plane: its centre, 3-1-2 Euler angles, one holonomic
contact constraint and two nonholonomic no-slip constraints. Rolling upright at speed v it is
stable when v² > g r/3 (a classical result for the uniform thin disk): below, a small lean grows
far from upright (here to 0.9 rad) before the disk swings back; above, it wobbles about upright. The multipliers are the contact forces; the normal
force m g at rest is the multiplier of the height constraint.
"""

import matplotlib.pyplot as plt
import numpy as np

import pfaff

m, r, g = 1.0, 0.3, 9.81
model = pfaff.models.rolling_disk().equations().compile({"m": m, "r": r, "g": g})
v_crit = np.sqrt(g * r / 3)
te = np.linspace(0.0, 3.0, 301)
fig, ax = plt.subplots(figsize=(6, 3.5))
for factor in (0.7, 1.5):
    v = factor * v_crit
    spin = v / r  # rolling forward along x about its axle, the body y axis
    q0 = [0.0, 0.0, r * np.cos(0.02), 0.0, 0.02, 0.0]
    qd0 = [v, 0.0, 0.0, 0.0, 0.0, spin]
    traj = pfaff.simulate(model, q0, qd0, (0.0, 3.0), t_eval=te, project_initial=True)
    ax.plot(traj.t, traj.q[:, 4], label=f"v = {factor} v_c ({traj.status})")
ax.axhline(0, color="0.7", lw=0.8)
ax.set(xlabel="t (s)", ylabel="lean θ (rad)", title="upright rolling, v_c = √(g r/3)")
ax.legend()
fig.tight_layout()
