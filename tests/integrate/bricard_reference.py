"""An independent reference for the Bricard mechanism (IFToMM benchmark A04), without pfaff.

The mechanism: five uniform bars of length L and mass m, closed with the fixed ground into a loop
of six revolute joints J0 … J5. In the published initial configuration (all bars at right angles)
the joints sit at

    J0 = (0, 0, 0), J1 = (L, 0, 0), J2 = (L, -L, 0), J3 = (L, -L, L), J4 = (0, -L, L), J5 = (0, 0, L)

with axes y, z, x, y, z, x; bar k runs from J(k-1) to Jk, J0 and J5 are fixed to the ground,
gravity g acts along -y. The mechanism starts at rest. Grübler's count gives 6·5 − 5·6 = 0
degrees of freedom, the special axes give one.

**Method** (nothing of pfaff's): the open chain ground–J0–bar 1–…–bar 5 with joint angles
θ1 … θ5 (product of exponentials from the initial configuration) and the loop closed by J5 with
angle θ6. The loop's velocity equation is J(θ) θ̇ = 0 with J the 6×6 matrix of the current joint
twists; its rank is 5 on the motion (one redundant closure row), so the admissible velocities are
θ̇ = σ̇ n(θ), n the unit null vector of J. Along this curve the mechanism is a one-degree-of-freedom
system in σ, and the projection of d'Alembert's principle on n gives

    m(θ) σ̈ = −Σ_k [m_k (c̈_k⁰ + g e_y)·δc_k + (I_k ω̇_k⁰ + ω_k × I_k ω_k)·δω_k],
    m(θ) = nᵀ M n = Σ_k m_k |δc_k|² + δω_kᵀ I_k δω_k,

with δc_k, δω_k the velocity of bar k's centre and its angular velocity per unit σ̇ and c̈⁰, ω̇⁰
the accelerations at σ̈ = 0 (θ̈ = σ̇² n′, n′ = −J⁺ (dJ/dσ) n, the twists' derivatives being Lie
brackets). State (θ1 … θ6, σ̇), DOP853 at rtol 1e-11; the sign of n is carried from step to step.
The positions of joints J0 … J4 follow the chain exactly; the closure at J5 is the only thing
that can drift (:func:`closure_residual`).

Examples
--------
>>> ref = BricardReference()
>>> float(ref.energy(np.zeros(6), 0.0))  # V at rest in the initial configuration (m g Σ y_c)
-29.43
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import DOP853

E = np.eye(3)
AXES = (1, 2, 0, 1, 2, 0)  # y, z, x, y, z, x: the axes of J0 … J5
POINTS = ((0, 0, 0), (1, 0, 0), (1, -1, 0), (1, -1, 1), (0, -1, 1), (0, 0, 1))  # × L


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` about the unit vector ``axis`` (Rodrigues)."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return E + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def bracket(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Lie bracket of two spatial twists (ω, v): (ω_a×ω_b, ω_a×v_b + v_a×ω_b)."""
    return np.concatenate([np.cross(a[:3], b[:3]), np.cross(a[:3], b[3:]) + np.cross(a[3:], b[:3])])


def _null(J: np.ndarray, ref: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The unit null vector of a rank-5 J (oriented along ``ref``), J's singular values, and
    J⁺ (the pseudo-inverse without the zero singular value), from one SVD."""
    u, s, vt = np.linalg.svd(J)
    n = vt[-1]
    if ref is not None and n @ ref < 0:
        n = -n
    pinv = vt[:5].T @ (u[:, :5] / s[:5]).T
    return n, s, pinv


@dataclass
class BricardReference:
    """The benchmark's parameters and the one-degree-of-freedom equations (see the module).

    ``inertia`` are the principal moments (axial, transverse) of a bar about its centre; the
    default is the benchmark's square section of side 0.1 m: m(2s²)/12 and m(L² + s²)/12.
    """

    length: float = 1.0
    mass: float = 1.0
    gravity: float = 9.81
    side: float = 0.1
    points: np.ndarray = field(init=False)
    axes: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.points = self.length * np.array(POINTS, dtype=float)
        self.axes = np.array([E[i] for i in AXES])
        m, L, s = self.mass, self.length, self.side
        i_axial, i_trans = m * 2 * s**2 / 12, m * (L**2 + s**2) / 12
        self.inertia0 = []  # world inertia of each bar in the initial configuration
        for k in range(5):
            d = self.points[k + 1] - self.points[k]
            d /= np.linalg.norm(d)
            self.inertia0.append(i_trans * (E - np.outer(d, d)) + i_axial * np.outer(d, d))
        self.centre0 = 0.5 * (self.points[:-1] + self.points[1:])

    # -- kinematics -------------------------------------------------------------------------
    def poses(self, theta: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """(R_k, p_k), x ↦ R_k x + p_k, of the ground (k = 0) and bars 1 … 5."""
        out = [(E, np.zeros(3))]
        for k in range(5):
            R0, p0 = out[-1]
            Rj = rotation(self.axes[k], theta[k])
            P = self.points[k]
            out.append((R0 @ Rj, R0 @ (P - Rj @ P) + p0))
        return out

    def twists(self, poses: list) -> np.ndarray:
        """The current joint twists (ω, q×ω) of J0 … J5, shape (6, 6), one per column."""
        cols = []
        for j in range(6):
            R, p = poses[j] if j < 5 else poses[0]
            w, q = R @ self.axes[j], R @ self.points[j] + p
            cols.append(np.concatenate([w, np.cross(q, w)]))
        return np.array(cols).T

    def joints(self, theta: np.ndarray) -> np.ndarray:
        """Positions of J0 … J5 (J5 as carried by bar 5), shape (6, 3)."""
        ps = self.poses(theta)
        return np.array(
            [ps[min(j + 1, 5)][0] @ P + ps[min(j + 1, 5)][1] for j, P in enumerate(self.points)]
        )

    def closure_residual(self, theta: np.ndarray) -> float:
        """|J5 as carried by bar 5 − J5| + |bar 5's J5 axis − x|: zero on the mechanism."""
        R, p = self.poses(theta)[5]
        gap = R @ self.points[5] + p - self.points[5]
        return float(np.linalg.norm(gap) + np.linalg.norm(R @ self.axes[5] - self.axes[5]))

    def tangent(self, theta: np.ndarray, ref: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """The unit null vector n of J (oriented along ``ref``) and the singular values of J."""
        n, s, _ = _null(self.twists(self.poses(theta)), ref)
        return n, s

    # -- dynamics ---------------------------------------------------------------------------
    def _bars(self, theta: np.ndarray, sd: float, ref: np.ndarray | None) -> tuple:
        """n, and per bar the virtual (per unit σ̇) and bias quantities of the module's equation."""
        ps = self.poses(theta)
        X = self.twists(ps)
        n, _, pinv = _null(X, ref)
        dX = np.zeros_like(X)  # dξ_j/dσ = [U_j, ξ_j], U_j the twist of the bar carrying J_j
        U = np.zeros((6, 6))  # U[:, k]: spatial velocity of body k per unit σ̇ (0: ground)
        for k in range(1, 6):
            U[:, k] = U[:, k - 1] + n[k - 1] * X[:, k - 1]
        for j in range(5):
            dX[:, j] = bracket(U[:, j], X[:, j])
        ndash = -pinv @ (dX @ n)
        out = []
        A = np.zeros(6)  # spatial acceleration per unit σ̇² at σ̈ = 0
        for k in range(1, 6):
            A = A + ndash[k - 1] * X[:, k - 1] + n[k - 1] * dX[:, k - 1]
            R, p = ps[k]
            c = R @ self.centre0[k - 1] + p
            inertia = R @ self.inertia0[k - 1] @ R.T
            u = U[:, k]
            dw, dc = u[:3], np.cross(u[:3], c) + u[3:]
            w, cd = sd * dw, sd * dc
            wd = sd**2 * A[:3]
            cdd = np.cross(wd, c) + sd**2 * A[3:] + np.cross(w, cd)
            out.append((c, inertia, dw, dc, w, wd, cdd))
        return n, out

    def rhs(self, theta: np.ndarray, sd: float, ref: np.ndarray | None) -> tuple:
        """(θ̇ (6), σ̈, n) at (θ, σ̇)."""
        m, g = self.mass, self.gravity
        meff = f0 = 0.0
        n, bars = self._bars(theta, sd, ref)
        for _c, inertia, dw, dc, w, wd, cdd in bars:
            meff += m * dc @ dc + dw @ inertia @ dw
            f0 += m * (cdd + g * E[1]) @ dc + (inertia @ wd + np.cross(w, inertia @ w)) @ dw
        return sd * n, -f0 / meff, n

    def energy(self, theta: np.ndarray, sd: float, ref: np.ndarray | None = None) -> float:
        """T + V with V = m g Σ_k y_{c,k} (zero at y = 0)."""
        m, g = self.mass, self.gravity
        total = 0.0
        for c, inertia, dw, dc, *_ in self._bars(theta, sd, ref)[1]:
            total += 0.5 * sd**2 * (m * dc @ dc + dw @ inertia @ dw) + m * g * c[1]
        return total

    def simulate(
        self, t_eval: np.ndarray, rtol: float = 1e-11, atol: float = 1e-12
    ) -> dict[str, np.ndarray]:
        """Integrate from rest in the initial configuration; states at ``t_eval``.

        Returns a dict: ``t``, ``theta`` (len(t), 6), ``sigma_dot``, ``joints`` (len(t), 6, 3),
        ``energy``, ``closure`` (the residual at J5), ``steps``.
        """
        t_eval = np.asarray(t_eval, dtype=float)
        ref = self.tangent(np.zeros(6), None)[0]
        _, sdd, _ = self.rhs(np.zeros(6), 0.0, ref)
        ref = ref if sdd > 0 else -ref  # σ grows along the motion that starts

        def f(_t: float, y: np.ndarray) -> np.ndarray:
            thd, sdd, _ = self.rhs(y[:6], y[6], ref)
            return np.concatenate([thd, [sdd]])

        solver = DOP853(
            f,
            float(t_eval[0]),
            np.zeros(7),
            float(t_eval[-1]),
            rtol=rtol,
            atol=atol,
            first_step=1e-3,
        )
        ys, i, steps = np.empty((len(t_eval), 7)), 0, 0
        ys[0], i = solver.y, 1
        while solver.status == "running" and i < len(t_eval):
            solver.step()
            steps += 1
            dense = solver.dense_output()
            while i < len(t_eval) and t_eval[i] <= solver.t:
                ys[i] = dense(t_eval[i])
                i += 1
            ref = self.tangent(solver.y[:6], ref)[0]
        if i < len(t_eval):
            raise RuntimeError(f"the reference integration stopped at t = {solver.t}")
        return {
            "t": t_eval,
            "theta": ys[:, :6],
            "sigma_dot": ys[:, 6],
            "joints": np.array([self.joints(y) for y in ys]),
            "energy": np.array([self.energy(y[:6], y[6]) for y in ys]),
            "closure": np.array([self.closure_residual(y) for y in ys]),
            "steps": np.array(steps),
        }
