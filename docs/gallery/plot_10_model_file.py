"""
A model file
============

A system written as a TOML file and read without running anything the file says
(:func:`pfaff.load_model`). ``examples/slider_crank.toml`` is a crank and connecting rod driving
a slider; the loader gives the system, its parameters, the initial state and the run settings.
"""

from pathlib import Path

import matplotlib.pyplot as plt

import pfaff

here = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
root = next(p for p in (here, *here.parents) if (p / "examples" / "slider_crank.toml").exists())
path = root / "examples" / "slider_crank.toml"
print(path.read_text())
mf = pfaff.load_model(path)
print(mf.system.coordinates, mf.parameters)
model = mf.compile()
settings = {k: v for k, v in mf.simulate.items() if k not in ("t_end", "samples")}
traj = pfaff.simulate(model, mf.q0, mf.qd0, (0.0, 2.0), **settings)
print(traj.status, len(traj.t), "reported states")

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
ax1.plot(traj.t, traj.q)
ax1.set(xlabel="t (s)", title="coordinates")
ax1.legend([str(c) for c in mf.system.coordinates], fontsize=8)
ax2.semilogy(traj.t, abs(traj.energy_balance) + 1e-17)
ax2.set(xlabel="t (s)", ylabel="|T + V − E₀ − W_nc|", title="energy balance")
fig.tight_layout()
