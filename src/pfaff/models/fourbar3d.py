"""A planar four-bar modelled in 3-D: three free rigid bodies and four 5-row revolute joints.

Ground pivots O = (0, 0, 0) and D = (d, 0, 0); crank OA (length a), coupler AB (b), rocker DB
(c), all turning about z; gravity g along −y. Each bar is a uniform rod of radius r about its
centre, body x along the bar. With the default dimensions (a, b, c, d) = (1, 3.5, 3, 4) the linkage
is a Grashof crank-rocker (s + l = 5 ≤ p + q = 6.5, the crank shortest): the crank turns fully
without a fold. The 3-D model has 18 coordinates and 20 joint rows of rank 17 on the motion
(mobility 1): three rows are redundant, as in every planar loop written with spatial joints.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from pfaff.api import System
from pfaff.core.symbols import coordinates
from pfaff.mechanics.attitude import EulerAngles
from pfaff.models.params import _param

FOURBAR3D = {
    "a": 1.0,
    "b": 3.5,
    "c": 3.0,
    "d": 4.0,
    "m1": 1.0,
    "m2": 2.0,
    "m3": 1.5,
    "r": 0.02,
    "g": 9.81,
}  # SI units


def fourbar3d(**params: object) -> System:
    """The four-bar of the module docstring, as a user would write it in 3-D.

    Coordinates, body by body (crank 1, coupler 2, rocker 3): the centre ``x_k, y_k, z_k`` and
    3-2-1 Euler angles ``psi_k, theta_k, phi_k`` (ψ about z: the planar angle). Constraints per
    joint ``O``, ``A``, ``B``, ``D``: ``<J> x``, ``<J> y``, ``<J> z`` (the points coincide) and
    ``<J> axis 1``, ``<J> axis 2`` (the z axis of one side is perpendicular to the x and y axes of
    the other). Parameters (symbols unless given as keywords): a, b, c, d, m1, m2, m3, r, g;
    :data:`FOURBAR3D` holds values and :func:`fourbar3d_state` a consistent state.

    Three of the 20 rows depend on the others on the motion (a planar mechanism written with
    spatial joints): equations() reports them (pfaff.RedundancyWarning), the motion is exact and
    the multipliers minimum-norm.

    Examples
    --------
    >>> s = fourbar3d()
    >>> len(s.coordinates), len(s.constraint_rows()[0])
    (18, 20)
    """
    p = {k: _param(params.get(k), k, k) for k in FOURBAR3D}
    lengths, masses = (p["a"], p["b"], p["c"]), (p["m1"], p["m2"], p["m3"])
    bodies, qs = [], []
    for k in (1, 2, 3):
        pos = coordinates(f"x_{k} y_{k} z_{k}")
        att = EulerAngles(coordinates(f"psi_{k} theta_{k} phi_{k}"), "321")
        qs += [*pos, *att.coordinates]
        bodies.append((sp.Matrix(pos), att))
    s = System(qs, name="four-bar in 3-D")
    r = p["r"]
    for (pos, att), L, m, k in zip(bodies, lengths, masses, (1, 2, 3), strict=True):
        moments = [m * r**2 / 2, m * (3 * r**2 + L**2) / 12, m * (3 * r**2 + L**2) / 12]
        s.add_rigid_body(m, moments, list(pos), att, name=f"bar {k}")
        s.add_potential_energy(m * p["g"] * pos[1], name=f"gravity {k}")

    def end(i: int, sign: int) -> tuple[sp.Matrix, sp.Matrix]:
        pos, att = bodies[i]
        return pos + sign * lengths[i] / 2 * att.dcm[:, 0], att.dcm

    ground = sp.eye(3)
    joints = {
        "O": ((sp.zeros(3, 1), ground), end(0, -1)),
        "A": (end(0, 1), end(1, -1)),
        "B": (end(1, 1), end(2, 1)),
        "D": (end(2, -1), (sp.Matrix([p["d"], 0, 0]), ground)),
    }
    for name, ((pa, Ca), (pb, Cb)) in joints.items():
        for row, axis in zip(pa - pb, "xyz", strict=True):
            s.add_holonomic_constraint(row, name=f"{name} {axis}")
        for i in (0, 1):
            s.add_holonomic_constraint(Ca[:, 2].dot(Cb[:, i]), name=f"{name} axis {i + 1}")
    return s


def fourbar_angles(theta: float, p: dict | None = None) -> tuple[float, float]:
    """The coupler and rocker angles (φ, ψ) at crank angle θ, on the branch with B above AD."""
    p = {**FOURBAR3D, **(p or {})}
    a, b, c, d = p["a"], p["b"], p["c"], p["d"]
    A = a * np.array([np.cos(theta), np.sin(theta)])
    e = np.array([d, 0.0]) - A
    le = float(np.hypot(*e))
    phi = np.arctan2(e[1], e[0]) + np.arccos((b**2 + le**2 - c**2) / (2 * b * le))
    B = A + b * np.array([np.cos(phi), np.sin(phi)])
    return float(phi), float(np.arctan2(B[1], B[0] - d))


def fourbar3d_state(
    theta: float, omega: float, p: dict | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """A consistent state (q, q̇) of :func:`fourbar3d` at crank angle θ and crank speed ω.

    Examples
    --------
    >>> q, qd = fourbar3d_state(0.0, 1.0)
    >>> q[:6].tolist(), qd[:6].round(12).tolist()
    ([0.5, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.5, 0.0, 1.0, 0.0, 0.0])
    """
    p = {**FOURBAR3D, **(p or {})}
    a, b, c, d = p["a"], p["b"], p["c"], p["d"]
    phi, psi = fourbar_angles(theta, p)

    def unit(x: float) -> np.ndarray:
        return np.array([np.cos(x), np.sin(x)])

    def perp(x: float) -> np.ndarray:
        return np.array([-np.sin(x), np.cos(x)])

    # a θ̇ perp(θ) + b φ̇ perp(φ) − c ψ̇ perp(ψ) = 0
    phid, psid = np.linalg.solve(
        np.column_stack([b * perp(phi), -c * perp(psi)]), -a * omega * perp(theta)
    )
    A, D = a * unit(theta), np.array([d, 0.0])
    centres = (A / 2, A + b / 2 * unit(phi), D + c / 2 * unit(psi))
    speeds = (
        a / 2 * omega * perp(theta),
        a * omega * perp(theta) + b / 2 * phid * perp(phi),
        c / 2 * psid * perp(psi),
    )
    q, qd = [], []
    for centre, v, ang, w in zip(
        centres, speeds, (theta, phi, psi), (omega, phid, psid), strict=True
    ):
        q += [centre[0], centre[1], 0.0, ang, 0.0, 0.0]
        qd += [v[0], v[1], 0.0, w, 0.0, 0.0]
    return np.array(q) + 0.0, np.array(qd) + 0.0
