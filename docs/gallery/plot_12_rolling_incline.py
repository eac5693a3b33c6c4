"""
Rolling down an incline
=======================

A hoop, a disk and a sphere (I = k m r², k = 1, ½, ⅖) rolling without slip down a slope of
angle α. The no-slip velocity constraint's multiplier is the friction force; the closed forms are
the acceleration g sin α /(1 + k) and the friction m g sin α k/(1 + k). Here the distance covered
after 1 s against ½ g sin α t²/(1 + k).
"""

import matplotlib.pyplot as plt
import numpy as np

import pfaff

values = {"m": 2.0, "r": 0.5, "g": 9.81, "alpha": 0.3}
k_of = {"hoop": 1.0, "disk": 0.5, "sphere": 0.4}
te = np.linspace(0.0, 1.0, 51)
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
for shape, k in k_of.items():
    model = pfaff.models.rolling_on_incline(shape).equations().compile(values)
    traj = pfaff.simulate(model, [0.0, 0.0], [0.0, 0.0], (0.0, 1.0), t_eval=te)
    accel = values["g"] * np.sin(values["alpha"]) / (1 + k)
    ax1.plot(te, traj.q[:, 0], label=shape)
    ax1.plot(te, accel * te**2 / 2, "k:", lw=1)
    friction = values["m"] * values["g"] * np.sin(values["alpha"]) * k / (1 + k)
    ax2.plot(te, traj.multipliers[:, 0], label=f"{shape}: closed form {friction:.4f} N")
ax1.set(xlabel="t (s)", ylabel="x (m)", title="distance down the slope (dotted: closed form)")
ax1.legend()
ax2.set(xlabel="t (s)", ylabel="friction multiplier (N)", title="no-slip force")
ax2.legend(fontsize=8)
fig.tight_layout()
