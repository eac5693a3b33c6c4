"""
The Whipple bicycle's root locus
================================

Meijaard, Papadopoulos, Ruina and Schwab (2007) give the benchmark bicycle's linearized
lean-and-steer equations and their eigenvalues against the forward speed: the weave mode becomes
stable at 4.29 m/s and the capsize mode unstable at 6.02 m/s. pfaff derives the full nonlinear
bicycle (8 coordinates, 4 nonholonomic and 1 holonomic constraint) and linearizes it about upright
straight running at each speed; the crosses are the published matrices' eigenvalues.
"""

import matplotlib.pyplot as plt
import numpy as np

import pfaff
from pfaff.models.bicycle import (
    bicycle_operating_point,
    lean_steer_eigenvalues,
    meijaard_eigenvalues,
    stability_speeds,
)

bike = pfaff.models.whipple_bicycle()
eom = bike.equations()
speeds = np.linspace(0.0, 10.0, 26)
eig = np.array(
    [
        lean_steer_eigenvalues(
            eom.linearize(bicycle_operating_point(v), bike.independent, bike.independent_speeds)
        )
        for v in speeds
    ]
)
published = np.array([meijaard_eigenvalues(v) for v in speeds])
weave, capsize = stability_speeds(eom)
print(f"weave speed {weave:.4f} m/s, capsize speed {capsize:.4f} m/s (published 4.292, 6.024)")

fig, ax = plt.subplots(figsize=(7, 4))
for k in range(eig.shape[1]):
    ax.plot(speeds, eig[:, k].real, "o", ms=3, color="tab:blue")
    ax.plot(speeds, np.abs(eig[:, k].imag), "o", ms=3, color="tab:orange")
ax.plot(speeds, published.real, "x", ms=5, color="k")
ax.axvspan(weave, capsize, color="tab:green", alpha=0.15, label="self-stable")
ax.axhline(0, color="0.5", lw=0.8)
ax.set(
    xlabel="speed v (m/s)",
    ylabel="eigenvalue (1/s)",
    ylim=(-10, 10),
    title="real (blue) and |imaginary| (orange) parts; × published real parts",
)
ax.legend()
fig.tight_layout()
