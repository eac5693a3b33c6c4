"""An n-joint spatial robot arm in its joint angles (:func:`robot_arm`), with its numbers
(:func:`robot_arm_values`), a state (:func:`robot_arm_state`) and the same arm as a URDF file
(:func:`robot_arm_urdf`) for other tools (Pinocchio, MuJoCo) and for :func:`pfaff.load_urdf`.

The arm: link 0 is the fixed base; joint i (i = 1 … n) turns link i relative to link i − 1 by
the angle q_i about the axis ``ROBOT_ARM_AXES[(i - 1) % 3]`` of link i − 1's frame (z, y, x:
a waist, a shoulder, a roll, then again), at the point (0, 0, l_{i-1}) of link i − 1 (the
origin for i = 1). Link i is a rod along its own z axis: mass m_i, mass centre (0, 0, l_i / 2),
principal moments I_i (about x and y) and J_i (about z) at its centre. Gravity g along −z.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from pfaff.api import System
from pfaff.attitude import Rotation
from pfaff.core.errors import ModelError
from pfaff.core.symbols import coordinates

ROBOT_ARM_AXES = ("z", "y", "x")
_UNIT = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1)}
MAX_JOINTS = 64


def _count(n: object) -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or not 1 <= n <= MAX_JOINTS:
        raise ModelError(f"`n` must be an integer from 1 to {MAX_JOINTS}, got {n!r:.40}")
    return int(n)


def _symbols(n: int) -> list[dict[str, sp.Symbol]]:
    return [{k: sp.Symbol(f"{k}{i}") for k in ("m", "l", "I", "J")} for i in range(1, n + 1)]


def _turn(axis: str, q: sp.Expr) -> sp.Matrix:
    """The rotation by q about a frame axis (child to parent components)."""
    c, s = sp.cos(q), sp.sin(q)
    if axis == "x":
        return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "y":
        return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def robot_arm(n: int, *, frames: bool = False) -> System:
    """The n-joint spatial arm of the module docstring, in its joint angles ``q1 … qn``.

    Each link is a rigid body whose attitude is the link frame, C_i = C_{i-1} R_i(q_i) (r_N =
    C r_B): a :class:`pfaff.attitude.Rotation`, or with ``frames=True`` a SymPy
    ``ReferenceFrame`` oriented by ``orient_axis`` relative to the previous link's (the system's
    inertial frame ``N``). Parameters (symbols): ``m1 … mn``, ``l1 … ln``, ``I1 … In``,
    ``J1 … Jn`` and ``g``; :func:`robot_arm_values` has numbers for them.

    Parameters
    ----------
    n : int
        Number of joints (1 … ``MAX_JOINTS``).
    frames : bool
        Build the link attitudes as ReferenceFrames instead of Rotation matrices.

    Returns
    -------
    System
        With ``links``: the list of the n link bodies.

    Examples
    --------
    >>> import pfaff
    >>> arm = pfaff.models.robot_arm(2)
    >>> arm.coordinates
    (q1(t), q2(t))
    >>> model = arm.equations().compile(pfaff.models.robot_arm_values(2))
    >>> qdd, _ = model.accelerations(0.0, [0.0, 0.0], [0.0, 0.0])  # upright, at rest
    >>> bool(abs(qdd).max() < 1e-12)
    True
    """
    n = _count(n)
    q = coordinates(" ".join(f"q{i}" for i in range(1, n + 1)))
    q = list(q) if isinstance(q, tuple | list) else [q]
    par = _symbols(n)
    if frames:  # (sympy.physics imported only where it is used: import pfaff stays light)
        from sympy.physics.vector import ReferenceFrame
    frame_n = ReferenceFrame("N") if frames else None
    system = System(q, frame=frame_n)
    g = sp.Symbol("g")
    rot, origin, parent = sp.eye(3), sp.zeros(3, 1), frame_n
    links = []
    for i in range(n):
        axis = ROBOT_ARM_AXES[i % 3]
        if i:
            origin = origin + rot * sp.Matrix([0, 0, par[i - 1]["l"]])
        rot = rot * _turn(axis, q[i])
        p = par[i]
        centre = origin + rot * sp.Matrix([0, 0, p["l"] / 2])
        if frames:
            link = ReferenceFrame(f"L{i + 1}")
            link.orient_axis(parent, getattr(parent, axis), q[i])
            attitude, parent = link, link
        else:
            attitude = Rotation(rot, source=f"link {i + 1}")
        inertia = [p["I"], p["I"], p["J"]]
        links.append(
            system.add_rigid_body(p["m"], inertia, list(centre), attitude, name=f"link{i + 1}")
        )
        system.add_potential_energy(p["m"] * g * centre[2], name=f"link{i + 1} weight")
    system.links = links
    return system


def robot_arm_values(n: int) -> dict[str, float]:
    """Numbers for :func:`robot_arm` (SI units): links from 0.5 m and 4 kg at the base to
    lighter, shorter ones at the tip, rods of radius 4 cm (I = m(3r² + l²)/12, J = m r²/2),
    g = 9.81.

    Examples
    --------
    >>> v = robot_arm_values(2)
    >>> v["m2"], v["l2"], v["g"]
    (3.2, 0.45, 9.81)
    """
    n = _count(n)
    values: dict[str, float] = {}
    radius = 0.04
    for i in range(1, n + 1):
        m = 4.0 * 0.8 ** (i - 1)
        length = 0.5 * 0.9 ** (i - 1)
        values |= {
            f"m{i}": m,
            f"l{i}": length,
            f"I{i}": m * (3 * radius**2 + length**2) / 12,
            f"J{i}": m * radius**2 / 2,
        }
    values["g"] = 9.81
    return values


def robot_arm_state(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A reproducible state (q, q̇) of :func:`robot_arm`, shapes (n,): angles in (−π, π),
    rates in (−2, 2) rad/s.

    Examples
    --------
    >>> q, qd = robot_arm_state(3)
    >>> q.shape, bool(abs(q).max() < np.pi)
    ((3,), True)
    """
    n = _count(n)
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, n), rng.uniform(-2.0, 2.0, n)


def robot_arm_urdf(n: int, values: dict[str, float] | None = None) -> str:
    """The arm of :func:`robot_arm` as URDF text with the numbers ``values`` (default
    :func:`robot_arm_values`): links ``base``, ``link1`` … and revolute joints ``q1`` … (so that
    :func:`pfaff.load_urdf` names the coordinates as :func:`robot_arm` does).

    Examples
    --------
    >>> print(robot_arm_urdf(1).splitlines()[0])
    <robot name="robot_arm_1">
    """
    n = _count(n)
    v = robot_arm_values(n) | dict(values or {})
    lines = [f'<robot name="robot_arm_{n}">', '  <link name="base"/>']
    for i in range(1, n + 1):
        m, length, inertia, axial = (float(v[f"{k}{i}"]) for k in "mlIJ")
        lines += [
            f'  <link name="link{i}"><inertial><origin xyz="0 0 {length / 2!r}"/>',
            f'    <mass value="{m!r}"/><inertia ixx="{inertia!r}" iyy="{inertia!r}" '
            f'izz="{axial!r}" ixy="0" ixz="0" iyz="0"/></inertial></link>',
        ]
    for i in range(1, n + 1):
        parent = "base" if i == 1 else f"link{i - 1}"
        z = 0.0 if i == 1 else float(v[f"l{i - 1}"])
        axis = " ".join(str(c) for c in _UNIT[ROBOT_ARM_AXES[(i - 1) % 3]])
        lines += [
            f'  <joint name="q{i}" type="continuous"><parent link="{parent}"/>'
            f'<child link="link{i}"/>',
            f'    <origin xyz="0 0 {z!r}"/><axis xyz="{axis}"/></joint>',
        ]
    return "\n".join([*lines, "</robot>", ""])
