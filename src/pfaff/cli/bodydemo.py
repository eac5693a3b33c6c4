"""Rigid-body demos: ``pfaff demo tumble``, ``pfaff demo top``, ``pfaff demo disk``."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from scipy.special import ellipk

from pfaff import models
from pfaff.attitude import dcm_from
from pfaff.cli.simdemo import _summary
from pfaff.integrate.simulation import simulate

TUMBLE_INERTIA = (1.0, 2.0, 3.0)
TUMBLE_OMEGA = (0.05, 1.0, 0.05)  # about the intermediate axis: the flip (Dzhanibekov effect)
TUMBLE_SEQUENCE = "231"  # Euler angles that stay clear of their singularity on this motion


def _omega(att: Any) -> Any:
    import sympy as sp

    n = len(att.coordinates)
    x = sp.symbols(f"_x0:{2 * n}")
    rule = dict(zip([*att.rates_symbols, *att.coordinates], [*x[n:], *x[:n]], strict=True))
    f = sp.lambdify([x], att.angular_velocity.xreplace(rule), "numpy")
    return lambda q, qd: np.ravel(f(np.concatenate([q, qd])))


def flip_period(inertia: tuple, w0: tuple) -> float:
    """The period 4K(k)/p of ω(t) of a torque-free body (I1 < I2 < I3; Landau & Lifshitz §37)."""
    I1, I2, I3 = inertia
    w = np.asarray(w0, dtype=float)
    T2 = float(np.dot(inertia, w**2))
    H2 = float(np.sum((np.asarray(inertia) * w) ** 2))
    if H2 > T2 * I2:
        p = math.sqrt((I3 - I2) * (H2 - T2 * I1) / (I1 * I2 * I3))
        k2 = (I2 - I1) * (T2 * I3 - H2) / ((I3 - I2) * (H2 - T2 * I1))
    else:
        p = math.sqrt((I2 - I1) * (T2 * I3 - H2) / (I1 * I2 * I3))
        k2 = (I3 - I2) * (H2 - T2 * I1) / ((I2 - I1) * (T2 * I3 - H2))
    return float(4 * ellipk(k2) / p)


def _run(model: Any, q0: Any, qd0: Any, t_end: float, points: int, **kw: Any) -> Any:
    start = time.perf_counter()
    traj = simulate(
        model, q0, qd0, (0.0, t_end), t_eval=np.linspace(0.0, t_end, points),
        rtol=kw.get("rtol", 1e-10), atol=kw.get("atol", 1e-12), progress=None,
    )  # fmt: skip
    return traj, time.perf_counter() - start


def tumble(attitude: str, *, t_end: float, sequence: str | None = None) -> tuple[dict, Any]:
    """The intermediate-axis flip of a torque-free body with I = (1, 2, 3), ω₀ = (0.05, 1, 0.05)."""
    seq = sequence or TUMBLE_SEQUENCE
    system = models.torque_free_body(attitude, sequence=seq)
    att = system.bodies[0].attitude
    model = system.equations().compile(dict(zip(("I1", "I2", "I3"), TUMBLE_INERTIA, strict=True)))
    q0 = att.from_dcm(np.eye(3))
    traj, wall = _run(model, q0, att.rates(q0, TUMBLE_OMEGA), t_end, 2001)
    omega = _omega(att)
    w = np.array([omega(q, qd) for q, qd in zip(traj.q, traj.qd, strict=True)])
    inertia = np.array(TUMBLE_INERTIA)
    C = np.array([dcm_from(att, q) for q in traj.q])
    H = np.einsum("kij,kj->ki", C, inertia * w) if len(C) else np.zeros((0, 3))
    H0 = inertia * np.array(TUMBLE_OMEGA)
    flips = _crossings(traj.t, w[:, 1]) if len(w) else []
    rep = _summary(traj, wall)
    rep.update(
        system="torque-free body (intermediate-axis flip)",
        attitude=attitude,
        sequence=seq if attitude == "euler" else None,
        inertia=list(TUMBLE_INERTIA),
        omega0=list(TUMBLE_OMEGA),
        omega_final=w[-1].tolist() if len(w) else None,
        omega_history={"t": traj.t[::50].tolist(), "omega": w[::50].tolist()},
        energy_error=float(np.abs(traj.kinetic - traj.kinetic[0]).max()) if len(w) else None,
        angular_momentum_error=float(np.abs(H - H0).max()) if len(w) else None,
        flip_times=flips,
        period_measured=float(flips[2] - flips[0]) if len(flips) >= 3 else None,
        period_exact=flip_period(TUMBLE_INERTIA, TUMBLE_OMEGA),
        switches=[[t, name] for t, name in traj.switches],
    )
    return rep, traj


def _crossings(t: np.ndarray, y: np.ndarray) -> list[float]:
    """Times where y changes sign (linear interpolation)."""
    s = np.sign(y)
    idx = np.nonzero(s[1:] * s[:-1] < 0)[0]
    return [float(t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])) for i in idx]


def top(attitude: str, *, t_end: float) -> tuple[dict, Any]:
    """A heavy top started on a steady precession: θ and ψ̇ must stay put."""
    m, g, L, I1, I3 = 1.0, 9.81, 0.4, 0.3, 0.25
    theta, w3 = 0.6, 40.0
    a, b, c = I1 * math.cos(theta), -I3 * w3, m * g * L
    rate = (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)  # m g l = Ω(I3 ω3 − I1 Ω cos θ)
    system = models.heavy_top(attitude)
    att = system.bodies[0].attitude
    model = system.equations().compile({"m": m, "g": g, "l": L, "I1": I1, "I3": I3})
    from pfaff.attitude import EulerAngles
    from pfaff.core.symbols import coordinates

    euler = EulerAngles(coordinates("_psi _theta _phi"), "313")
    q0 = att.from_dcm(dcm_from(euler, [0.0, theta, 0.0]))
    # body rates of the steady precession: ω = Ω ẑ (inertial) + spin about body z
    w_body = dcm_from(euler, [0.0, theta, 0.0]).T @ np.array([0.0, 0.0, rate])
    w_body[2] = w3
    traj, wall = _run(model, q0, att.rates(q0, w_body), t_end, 801)
    nut = np.array([math.acos(max(-1.0, min(1.0, dcm_from(att, q)[2, 2]))) for q in traj.q])
    rep = _summary(traj, wall)
    rep.update(
        system="heavy symmetric top (steady precession)",
        attitude=attitude,
        nutation_initial=theta,
        nutation_max_deviation=float(np.abs(nut - theta).max()) if len(nut) else None,
        precession_rate_exact=rate,
        spin_rate=w3,
        sleeping_threshold=math.sqrt(4 * m * g * L * I1 / I3**2),
    )
    return rep, traj


def disk(*, t_end: float) -> tuple[dict, Any]:
    """The rolling disk on a steady circle: energy, the contact forces, the constraints."""
    m, r, g = 1.0, 0.5, 9.81
    system = models.rolling_disk()
    model = system.equations().compile({"m": m, "r": r, "g": g})
    lean, spin = 0.3, 8.0
    yaw = steady_yaw_rate(model, lean, spin, r)
    q0, qd0 = _disk_state(model, lean, yaw, spin, r)
    traj, wall = _run(model, q0, qd0, t_end, 801)
    rep = _summary(traj, wall)
    lam = traj.multipliers
    rep.update(
        system="thin disk rolling without slip",
        normal_force_mean=float(lam[:, 0].mean()) if len(lam) else None,
        weight=m * g,
        friction_max=float(np.abs(lam[:, 1:]).max()) if len(lam) else None,
        lean_max_deviation=float(np.abs(traj.q[:, 4] - lean).max()) if len(lam) else None,
    )
    return rep, traj


def _disk_state(model: Any, lean: float, yaw: float, spin: float, r: float) -> tuple:
    from pfaff.integrate.initial import consistent_state

    q = np.array([0.0, 0.0, r * math.cos(lean), 0.0, lean, 0.0])
    qd = np.array([0.0, 0.0, 0.0, yaw, 0.0, spin])
    return consistent_state(model, q, qd, ["psi", "theta", "phi"])


def steady_yaw_rate(model: Any, lean: float, spin: float, r: float) -> float:
    """The yaw rate ψ̇ of steady rolling at lean θ and spin rate φ̇: the root of θ̈(ψ̇) = 0
    nearest zero (found numerically on the compiled model)."""
    from scipy.optimize import brentq

    def lean_acc(yaw: float) -> float:
        q, qd = _disk_state(model, lean, yaw, spin, r)
        return float(model.accelerations(0.0, q, qd)[0][4])

    grid = np.linspace(-40.0, 40.0, 41)
    vals = [lean_acc(y) for y in grid]
    roots = [
        brentq(lean_acc, a, b, xtol=1e-14)
        for a, b, fa, fb in zip(grid[:-1], grid[1:], vals[:-1], vals[1:], strict=True)
        if fa * fb < 0
    ]
    if not roots:
        raise ValueError("no steady rolling at this lean and spin")
    return float(min(roots, key=abs))


def format_body(rep: dict) -> str:
    """Human-readable lines of a body demo."""
    lines = [f"{rep['system']}: to t = {rep['t_end']:g} — {rep['status']} ({rep['message']})"]
    if "flip_times" in rep:
        seq = f" {rep['sequence']}" if rep.get("sequence") else ""
        lines.append(
            f"  attitude: {rep['attitude']}{seq}; ω₀ = {rep['omega0']}, I = {rep['inertia']}"
        )
        lines.append(
            f"  flips (ω₂ changes sign) at t = {', '.join(f'{x:.4f}' for x in rep['flip_times'])}"
        )
        if rep["period_measured"] is not None:
            lines.append(
                f"  period of ω {rep['period_measured']:.8f}   4K(k)/p = {rep['period_exact']:.8f}"
            )
        lines.append(
            f"  energy error {rep['energy_error']:.2e}   |H − H₀| ≤ {rep['angular_momentum_error']:.2e}"
        )
        if rep["switches"]:
            ts = ", ".join(f"{t:.4f}" for t, _ in rep["switches"])
            lines.append(f"  MRP shadow-set switches at t = {ts}")
    if "nutation_max_deviation" in rep:
        lines.append(
            f"  nutation θ = {rep['nutation_initial']:g} held to {rep['nutation_max_deviation']:.2e}; "
            f"precession rate {rep['precession_rate_exact']:.10g} (root of m g l = Ω(I₃ω₃ − I₁Ω cos θ))"
        )
    if "normal_force_mean" in rep:
        lines.append(
            f"  normal force {rep['normal_force_mean']:.10g} (weight m g = {rep['weight']:g});"
            f" max |friction| {rep['friction_max']:.4g}"
        )
    lines.append(
        f"  max |f| = {rep['max_position_residual']:.2e}   max |A q̇ + b| = "
        f"{rep['max_velocity_residual']:.2e}   energy balance ≤ {rep['energy_balance_error']:.2e}"
    )
    return "\n".join(lines)
