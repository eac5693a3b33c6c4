"""
A parameter sweep
=================

:func:`pfaff.sweep` runs a grid of parameter values and initial states of a model file on a Dask
cluster (here ``scheduler="synchronous"``: every run in this process) into an
:class:`xarray.Dataset`. The pendulum of ``examples/pendulum.toml`` (L = 1 m) released at 1 rad
under a range of gravities: its period follows 4 √(L/g) K(sin²(θ₀/2)), with K the complete
elliptic integral of the first kind. (Varying L would move the file's initial state off the
rod's circle: that run would be refused as inconsistent, as it should.)
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.special import ellipk

import pfaff

here = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
root = next(p for p in (here, *here.parents) if (p / "examples" / "pendulum.toml").exists())
gravities = np.array([4.0, 9.81, 16.0, 25.0])
result = pfaff.sweep(
    root / "examples" / "pendulum.toml",
    vary={"g": gravities},
    t_end=3.0,
    samples=601,
    scheduler="synchronous",
)
print(result["status"].values)

t = result["time"].values
periods = []
for k in range(len(gravities)):
    x = result["q"].values[k, :, 0]
    k0 = np.flatnonzero(np.sign(x[:-1]) != np.sign(x[1:]))  # crossings of x = 0, each half period
    cross = t[k0] - x[k0] * (t[k0 + 1] - t[k0]) / (x[k0 + 1] - x[k0])
    periods.append(2 * np.diff(cross).mean())
theta0 = 1.0
exact = 4 * np.sqrt(1.0 / gravities) * ellipk(np.sin(theta0 / 2) ** 2)

fig, ax = plt.subplots(figsize=(6, 3.5))
ax.plot(gravities, periods, "o", label="sweep (crossings of x = 0)")
ax.plot(gravities, exact, "-", label="4 √(L/g) K(sin²(θ₀/2))")
ax.set(xlabel="g (m/s²)", ylabel="period (s)", title="pendulum period over a sweep of g")
ax.legend()
fig.tight_layout()
print("sweep:", np.round(periods, 5), "closed form:", np.round(exact, 5))
