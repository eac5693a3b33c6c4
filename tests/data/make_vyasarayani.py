"""Make ``vyasarayani_pendulum.csv``: the data of opty's parameter-identification example.

Vyasarayani et al. (2011), Section 3.1, as set up in opty's example gallery (``plot_vyasarayani``):
the pendulum ÿ₁ = −p sin y₁ with p = 10, started from y₁ = π/6, y₂ = ẏ₁ = 0, sampled at 5000
equally spaced times on [0, 50] s; Gaussian noise of standard deviation 0.05 is added to the
angle y₁ and 0.1 to the rate y₂. opty's example draws its noise unseeded; here it comes from
``numpy.random.default_rng(SEED)`` (the angle's 5000 draws first, then the rate's), and the clean
motion from SciPy's ``solve_ivp`` (DOP853, rtol 1e-12, atol 1e-12), so the file can be made
again bit for bit from this script. Only the angle is fitted, as in the example; the noisy rate
is opty's starting guess of its rate trajectory.

The columns are named for ``pfaff.models.damped_pendulum()`` (``t``, ``theta``,
``theta_dot``): with m = l = 1, c = 0 its equation m l² θ̈ + c θ̇ + m g l sin θ = 0 is the
example's with p = g. Written once and committed; run from the project root to remake it::

    python tests/data/make_vyasarayani.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

SEED = 20110411
P_TRUE = 10.0
Y0 = (np.pi / 6.0, 0.0)
DURATION, NODES = 50.0, 5000
NOISE_ANGLE, NOISE_RATE = 0.05, 0.1
PATH = Path(__file__).with_name("vyasarayani_pendulum.csv")


def clean(t: np.ndarray) -> np.ndarray:
    """The noise-free motion (y₁, y₂) at the times t, shape (len(t), 2)."""
    from scipy.integrate import solve_ivp

    sol = solve_ivp(
        lambda _, y: [y[1], -P_TRUE * np.sin(y[0])],
        (t[0], t[-1]),
        Y0,
        method="DOP853",
        t_eval=t,
        rtol=1e-12,
        atol=1e-12,
    )
    return sol.y.T


def make() -> np.ndarray:
    """The noisy data (t, y₁, y₂), shape (NODES, 3)."""
    t = np.linspace(0.0, DURATION, NODES)
    y = clean(t)
    rng = np.random.default_rng(SEED)
    y[:, 0] += rng.normal(scale=NOISE_ANGLE, size=NODES)
    y[:, 1] += rng.normal(scale=NOISE_RATE, size=NODES)
    return np.column_stack((t, y))


if __name__ == "__main__":
    np.savetxt(
        PATH,
        make(),
        fmt=("%.10g", "%.7g", "%.7g"),
        delimiter=",",
        header="t,theta,theta_dot",
        comments="",
    )
    print(f"wrote {PATH}")
