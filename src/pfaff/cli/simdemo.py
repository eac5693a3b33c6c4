"""Simulation demos behind ``pfaff demo ring --simulate`` and ``pfaff demo pendulum``."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from pfaff import models
from pfaff.integrate.simulation import simulate
from pfaff.numeric.protocol import DynamicsModel
from pfaff.results.figures import MAX_LINES
from pfaff.results.trajectory import Trajectory


def _summary(traj: Trajectory, wall: float) -> dict[str, Any]:
    """The numbers every simulation demo reports.

    ``energy_drift`` is the largest |T + V − E₀| (kept for compatibility: with applied forces it is
    mostly their work); ``energy_balance_error`` the largest |T + V − E₀ − W_nc|, what an exact
    motion keeps at 0; ``nc_work`` W_nc at the end, ``impact_work`` the impacts' W at the end.
    The residuals leave out the gaps of open contacts.
    """
    res = np.abs(traj.constraint_residual)
    res[:, 0][traj.contact_open] = 0.0  # an open contact's gap is not a residual
    k = len(traj.t)
    return {
        "method": traj.method,
        "status": traj.status,
        "message": traj.message,
        "points": len(traj.t),
        "t_end": float(traj.t[-1]) if len(traj.t) else None,
        "max_position_residual": float(res[:, 0].max(initial=0.0)),
        "max_velocity_residual": float(res[:, 1].max(initial=0.0)),
        "energy_drift": float(np.abs(traj.energy - traj.energy[0]).max()) if k else None,
        "energy_balance_error": float(np.abs(traj.energy_balance).max()) if k else None,
        "nc_work": float(traj.nc_work[-1]) if k else None,
        "impact_work": float(traj.impact_work[-1]) if k else None,
        "stats": {  # only the statistics this method keeps (IDA counts no rejected steps)
            key: (int(v) if isinstance(v, int | np.integer) else v)
            for key, v in traj.stats.items()
            if v is not None
        },
        "wall_time_s": wall,
        "events": [
            {"name": e.name, "t": float(e.t), "kind": e.kind} for e in getattr(traj, "events", [])
        ],
    }


# A reported state costs 48 n bytes (q, q̇, q̈, λ, f, g): 401 of them at n = 2^20 would be 20 GB.
TRAJECTORY_BYTES = 1 << 30
STATE_BYTES = 48  # per coordinate or constraint row of one reported state


def reported_times(t_end: float, n: int, m: int, most: int, least: int = 2) -> np.ndarray:
    """``most`` equally spaced times over [0, t_end], fewer (never below ``least``) when their
    states would take more than :data:`TRAJECTORY_BYTES` (48 (n + m) bytes each: a family of
    millions of pieces).

    Examples
    --------
    >>> len(reported_times(2.0, 5, 4, 201)), len(reported_times(1.0, 2**24, 2**24, 201))
    (201, 2)
    """
    fit = TRAJECTORY_BYTES // (STATE_BYTES * max(n + m, 1))
    return np.linspace(0.0, t_end, max(least, min(most, fit)))


def _run(model: DynamicsModel, q0, qd0, opts: dict) -> tuple[Trajectory, float]:
    t0 = time.perf_counter()
    t_eval = reported_times(opts["t_end"], model.n, model.m, 401, least=11)
    traj = simulate(
        model, q0, qd0, (0.0, opts["t_end"]), method=opts["method"],
        rtol=opts["rtol"], atol=opts["atol"], t_eval=t_eval, progress=None,
        output=opts.get("output"),
    )  # fmt: skip
    return traj, time.perf_counter() - t0


def ring_simulation(
    n: int, *, force: float, mass: float, radius: float, theta_dot: float, opts: dict
) -> tuple[dict, Trajectory]:
    """Simulate the pushed ring from θ₁ = π and compare with x(t) = x₀ + r θ̇₀ t + F t²/(4M)."""
    system = models.rolling_ring(n, force=True)
    model = system.equations().compile({"M": mass, "r": radius, "F": force})
    q0, qd0 = models.ring_state(n, radius=radius, theta=math.pi, theta_dot=theta_dot)
    traj, wall = _run(model, q0, qd0, opts)
    t = traj.t
    x_exact = q0[0] + radius * theta_dot * t + force * t**2 / (4 * mass)
    rep = _summary(traj, wall)
    rep.update(
        system="rolling ring",
        particles=n,
        x_final=float(traj.q[-1, 0]),
        x_exact_final=float(x_exact[-1]),
        max_x_error=float(np.abs(traj.q[:, 0] - x_exact).max()),
        friction_min=float(traj.multipliers[:, 0].min()),
        friction_max=float(traj.multipliers[:, 0].max()),
        friction_exact=-force / 2,
    )
    return rep, traj


def pendulum_simulation(
    *, mass: float, length: float, gravity: float, angle_deg: float, opts: dict
) -> tuple[dict, Trajectory]:
    """Simulate the Cartesian pendulum released at rest ``angle_deg`` from the downward vertical."""
    model = models.cartesian_pendulum().equations().compile({"m": mass, "g": gravity, "L": length})
    a = math.radians(angle_deg)
    q0 = np.array([length * math.sin(a), -length * math.cos(a)])
    traj, wall = _run(model, q0, np.zeros(2), opts)
    tension = -2 * length * traj.multipliers[:, 0]
    rep = _summary(traj, wall)
    rep.update(
        system="cartesian pendulum",
        max_tension=float(tension.max()),
        # T(θ) = m g (3 cos θ − 2 cos θ₀) peaks at the bottom: a reference only for a run that
        # gets there (not when released upright, or stopped before the first swing is down)
        max_tension_exact=float(mass * gravity * (3 - 2 * math.cos(a)))
        if _passes_bottom(traj.q)
        else None,
        min_y=float(traj.q[:, 1].min()),
    )
    return rep, traj


def _passes_bottom(q: np.ndarray) -> bool:
    """True when the bob is at or passes through the bottom (x = 0, y < 0) during the run."""
    x, y = q[:, 0], q[:, 1]
    if len(x) == 0:
        return False
    if x[0] == 0 and y[0] < 0:  # released hanging: at the bottom throughout
        return True
    crossing = (x[:-1] * x[1:] <= 0) & ((y[:-1] < 0) | (y[1:] < 0))
    return bool(np.any(crossing))


def simulation_units(demo: str, traj: Trajectory, shown: int = MAX_LINES) -> dict[str, str]:
    """SI units of a demo's coordinates and multipliers, for the first ``shown`` of each.

    Ring: x in m, θ_k in rad; λ₁ (no slip x − r θ₁) in N, λ_k (spacing, in rad) in N m.
    Pendulum: x, y in m; λ (f = x² + y² − L²) in N/m.
    """
    qn, ln = traj.coordinate_names[:shown], traj.multiplier_names[:shown]
    if demo == "ring":
        units = {name: ("m" if j == 0 else "rad") for j, name in enumerate(qn)}
        units.update({name: ("N" if j == 0 else "N m") for j, name in enumerate(ln)})
        return units
    return {**dict.fromkeys(qn, "m"), **dict.fromkeys(ln, "N/m")}


def format_simulation(rep: dict) -> str:
    """Human-readable lines for a simulation report."""
    lines = [
        f"{rep['system']}: {rep['method']} to t = {rep['t_end']:g} — {rep['status']} ({rep['message']})"
    ]
    if "x_final" in rep:
        lines.append(
            f"  x(t_end) = {rep['x_final']:.12g}   F t²/(4M) law: {rep['x_exact_final']:.12g}   max error {rep['max_x_error']:.2e}"
        )
        lines.append(
            f"  friction λ₁ in [{rep['friction_min']:.12g}, {rep['friction_max']:.12g}]   expected −F/2 = {rep['friction_exact']:g}"
        )
    if "max_tension" in rep:
        exact = rep["max_tension_exact"]
        lines.append(
            f"  max rod tension {rep['max_tension']:.10g}"
            + (f"   m g (3 − 2 cos θ₀) = {exact:.10g}" if exact is not None else "")
        )
    energy = ""
    if rep["energy_balance_error"] is not None:
        energy = f"   energy balance |T + V − E₀ − W| ≤ {rep['energy_balance_error']:.2e}"
        if rep["nc_work"]:
            energy += f" (W = work of the non-conservative forces = {rep['nc_work']:.6g})"
    lines.append(
        f"  max |f| = {rep['max_position_residual']:.2e}   max |A q̇ + b| = {rep['max_velocity_residual']:.2e}"
        + energy
    )
    s = rep["stats"]
    counts = [f"{s[key]} {label}" for key, label in STAT_LABELS if isinstance(s.get(key), int)]
    lines.append("  " + ", ".join([*counts, f"{rep['wall_time_s']:.3f} s"]))
    return "\n".join(lines)


# the statistics of a run shown in the text, when the method keeps them
STAT_LABELS = (
    ("steps", "steps"),
    ("nfev", "evaluations"),
    ("rejected", "rejected"),
    ("projections", "projections"),
)
