"""
The heavy top
=============

A symmetric top with its tip fixed, in 3-1-3 Euler angles (precession ψ, nutation θ, spin φ).
Two quantities are conserved by the exact motion and are not built into the coordinates: the
energy and the axial angular velocity ω₃ = φ̇ + ψ̇ cos θ (the top is symmetric). A fast top
started without precession nutates between θ₀ and a lower limit while it precesses.
"""

import matplotlib.pyplot as plt
import numpy as np

import pfaff

values = {"m": 1.0, "l": 0.5, "g": 9.81, "I1": 0.4, "I3": 0.2}
model = pfaff.models.heavy_top("euler").equations().compile(values)
te = np.linspace(0.0, 3.0, 601)
traj = pfaff.simulate(model, [0.0, 0.6, 0.0], [0.0, 0.0, 40.0], (0.0, 3.0), t_eval=te, rtol=1e-10)
psi, theta, phi = traj.q.T
dpsi, _, dphi = traj.qd.T
w3 = dphi + dpsi * np.cos(theta)

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
ax1.plot(te, theta, label="nutation θ")
ax1.plot(te, psi, label="precession ψ")
ax1.set(xlabel="t (s)", ylabel="rad", title="heavy top")
ax1.legend()
ax2.semilogy(te, np.abs(traj.energy - traj.energy[0]) + 1e-17, label="|E − E₀|")
ax2.semilogy(te, np.abs(w3 - w3[0]) + 1e-17, label="|ω₃ − ω₃(0)|")
ax2.set(xlabel="t (s)", title="conserved quantities")
ax2.legend()
fig.tight_layout()
