"""
An overconstrained mechanism: the Bricard linkage
=================================================

The Bricard linkage (IFToMM benchmark A04) is five rods with six revolute joints closing a loop:
by Grübler's count it should not move, yet it has one degree of freedom, so its constraint rows
are dependent on the motion. pfaff finds the dependency at the first state of a run, integrates
the motion with a maximal independent set of rows, and reports how many rows it dropped.
"""

import matplotlib.pyplot as plt
import numpy as np

import pfaff
from pfaff.models import BRICARD, bricard, bricard_state

model = bricard().equations().compile(BRICARD)
q0, qd0 = bricard_state()
te = np.linspace(0.0, 0.5, 51)
traj = pfaff.simulate(model, q0, qd0, (0.0, 0.5), t_eval=te)
print(traj.status, traj.message)
print(
    "constraint rows:", traj.multipliers.shape[1], "dropped as redundant:", traj.redundant_rows[0]
)

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
ax1.plot(te, traj.energy - traj.energy[0])
ax1.set(xlabel="t (s)", ylabel="E − E₀ (J)", title="energy")
ax2.semilogy(te, np.abs(traj.position_residual).max(axis=1) + 1e-17)
ax2.set(xlabel="t (s)", ylabel="max |f|", title="position constraints")
fig.tight_layout()
