"""An independent reference for ``pfaff.models.fourbar3d``: the planar four-bar in its crank angle.

Derived here in SymPy, without pfaff: the loop closure solved for the coupler angle φ(θ) (the
branch with B above the line AD) and the rocker angle ψ(θ); the bar centres as functions of θ;

    T = ½ J(θ) θ̇²,   J = Σ_k m_k |dc_k/dθ|² + I_k (dα_k/dθ)²,   V = g Σ_k m_k y_k(θ),
    J θ̈ + ½ J′(θ) θ̇² + V′(θ) = 0,

with I_k the transverse moment of rod k about its centre, m(3r² + L²)/12. Integrated by
``solve_ivp`` (DOP853) until the crank has turned once.

Examples
--------
The loop closes: the coupler's end, reached from the crank, is the rocker's end (a = 1,
b = 3.5, c = 3, d = 4), with B above the line AD.

>>> ref = FourBarReference()
>>> theta = 0.3
>>> phi, psi = ref.angles(theta)
>>> B = np.array([np.cos(theta), np.sin(theta)]) + 3.5 * np.array([np.cos(phi), np.sin(phi)])
>>> bool(np.allclose(B, [4.0 + 3.0 * np.cos(psi), 3.0 * np.sin(psi)], atol=1e-12)), bool(B[1] > 0)
(True, True)
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

VALUES = {"a": 1.0, "b": 3.5, "c": 3.0, "d": 4.0, "m1": 1.0, "m2": 2.0, "m3": 1.5, "r": 0.02}
G = 9.81


class FourBarReference:
    """J(θ), J′(θ), V(θ), V′(θ) and the angles φ(θ), ψ(θ), lambdified once."""

    def __init__(self, values: dict | None = None, gravity: float = G) -> None:
        self.values = {**VALUES, **(values or {})}
        self.gravity = gravity

    @cached_property
    def _functions(self) -> dict:
        th = sp.Symbol("theta")
        v = {k: sp.nsimplify(x) for k, x in self.values.items()}
        a, b, c, d, r = v["a"], v["b"], v["c"], v["d"], v["r"]
        A = sp.Matrix([a * sp.cos(th), a * sp.sin(th)])
        e = sp.Matrix([d, 0]) - A
        le2 = e.dot(e)
        phi = sp.atan2(e[1], e[0]) + sp.acos((b**2 + le2 - c**2) / (2 * b * sp.sqrt(le2)))
        B = A + b * sp.Matrix([sp.cos(phi), sp.sin(phi)])
        psi = sp.atan2(B[1], B[0] - d)
        centres = (A / 2, (A + B) / 2, (B + sp.Matrix([d, 0])) / 2)
        angles = (th, phi, psi)
        masses, lengths = (v["m1"], v["m2"], v["m3"]), (a, b, c)
        J = sp.Integer(0)
        V = sp.Integer(0)
        for cen, ang, m, L in zip(centres, angles, masses, lengths, strict=True):
            dc = cen.diff(th)
            J += m * dc.dot(dc) + m * (3 * r**2 + L**2) / 12 * ang.diff(th) ** 2
            V += m * sp.nsimplify(self.gravity) * cen[1]
        exprs = {"J": J, "dJ": J.diff(th), "V": V, "dV": V.diff(th), "phi": phi, "psi": psi}
        return {k: sp.lambdify(th, e, modules="numpy", cse=True) for k, e in exprs.items()}

    def angles(self, theta: float) -> tuple[float, float]:
        """(φ, ψ) at crank angle θ."""
        f = self._functions
        return float(f["phi"](theta)), float(f["psi"](theta))

    def energy(self, theta: np.ndarray, omega: np.ndarray) -> np.ndarray:
        f = self._functions
        return 0.5 * f["J"](theta) * omega**2 + f["V"](theta)

    def rhs(self, _t: float, y: np.ndarray) -> list[float]:
        f = self._functions
        th, w = y
        return [w, -(0.5 * f["dJ"](th) * w**2 + f["dV"](th)) / f["J"](th)]

    def full_turn(
        self, theta0: float, omega0: float, n_eval: int = 101, rtol: float = 1e-11
    ) -> dict[str, np.ndarray]:
        """From (θ0, ω0 > 0) until θ = θ0 + 2π: ``t`` (n_eval times, the last one the end of
        the turn), ``theta``, ``omega``, ``energy``."""

        def turned(_t: float, y: np.ndarray) -> float:
            return y[0] - theta0 - 2 * np.pi

        turned.terminal = True
        first = solve_ivp(
            self.rhs, (0.0, 100.0), [theta0, omega0], method="DOP853", rtol=rtol,
            atol=1e-12, events=turned,
        )  # fmt: skip
        if first.status != 1:
            raise RuntimeError("the crank did not complete a turn")
        t_end = float(first.t_events[0][0])
        t = np.linspace(0.0, t_end, n_eval)
        sol = solve_ivp(
            self.rhs, (0.0, t_end), [theta0, omega0], method="DOP853", rtol=rtol, atol=1e-12,
            t_eval=t,
        )  # fmt: skip
        return {
            "t": t,
            "theta": sol.y[0],
            "omega": sol.y[1],
            "energy": self.energy(sol.y[0], sol.y[1]),
        }
