"""
Events: the pendulum's period
=============================

A condition declared on the system, ``add_event(theta, direction=-1)``, is found in every run:
each downward crossing of θ = 0 is bracketed on the integrator's dense output by Brent's method.
The period from successive crossings matches 4 √(L/g) K(sin²(θ₀/2)) at every amplitude.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy.special import ellipk

import pfaff

L, g = 1.0, 9.81
system = pfaff.models.pendulum()
theta = system.coordinates[0]
system.add_event(theta, name="bottom", direction=-1)
model = system.equations().compile({"m": 1.0, "g": g, "L": L})

amplitudes = np.linspace(0.2, 2.8, 8)
measured = []
for a in amplitudes:
    traj = pfaff.simulate(model, [a], [0.0], (0.0, 12.0), rtol=1e-12, atol=1e-12)
    times = [e.t for e in traj.events if e.name == "bottom"]
    measured.append(np.diff(times).mean())
exact = 4 * np.sqrt(L / g) * ellipk(np.sin(amplitudes / 2) ** 2)

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
ax1.plot(np.degrees(amplitudes), measured, "o", label="events")
ax1.plot(np.degrees(amplitudes), exact, "-", label="4 √(L/g) K(sin²(θ₀/2))")
ax1.set(xlabel="amplitude θ₀ (°)", ylabel="period (s)", title="pendulum period")
ax1.legend()
ax2.semilogy(np.degrees(amplitudes), np.abs(np.array(measured) - exact) + 1e-17, "s")
ax2.set(xlabel="amplitude θ₀ (°)", ylabel="|error| (s)", title="against the closed form")
fig.tight_layout()
