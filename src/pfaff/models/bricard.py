"""Bricard's mechanism, IFToMM benchmark A04: an overconstrained loop of five bars and six joints.

Five uniform bars (length L, mass m, square section of side s) and the ground form a closed loop
of six revolute joints J0 … J5. In the benchmark's initial configuration, at rest, the joints sit
at

    J0 = (0, 0, 0), J1 = (L, 0, 0), J2 = (L, −L, 0), J3 = (L, −L, L), J4 = (0, −L, L), J5 = (0, 0, L)

with axes along y, z, x, y, z, x; bar k runs from J(k−1) to Jk; J0 and J5 hold bars 1 and 5 to
the ground; gravity g acts along −y. Grübler's count gives 6·5 − 5·6 = 0 degrees of freedom; the
special directions of the axes give one, so one of the 30 joint rows is redundant on the motion.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from pfaff.api import System
from pfaff.core.symbols import coordinates
from pfaff.mechanics.attitude import Quaternion
from pfaff.models.params import _param

BRICARD = {"L": 1.0, "m": 1.0, "g": 9.81, "s": 0.1}  # the benchmark's values (SI units)

_POINTS = ((0, 0, 0), (1, 0, 0), (1, -1, 0), (1, -1, 1), (0, -1, 1), (0, 0, 1))  # × L
_AXES = (1, 2, 0, 1, 2, 0)  # y, z, x, y, z, x


def _frames() -> list[np.ndarray]:
    """Each bar's initial attitude: body x along the bar, body y the axis of J(k−1)."""
    eye, out = np.eye(3), []
    for k in range(5):
        d = np.subtract(_POINTS[k + 1], _POINTS[k]).astype(float)
        e2 = eye[_AXES[k]]
        out.append(np.column_stack([d, e2, np.cross(d, e2)]))
    return out


def bricard(
    *, length: object = None, mass: object = None, gravity: object = None, side: object = None
) -> System:
    """Bricard's mechanism (IFToMM A04) as a user would write it: five free rigid bodies and six
    revolute joints as holonomic constraints.

    Coordinates, bar by bar (k = 1 … 5): the centre ``x_k, y_k, z_k`` and the Euler parameters
    ``b_k0 … b_k3`` (35). Constraints: the five ``bar k unit norm`` rows and, per joint ``Jj``,
    ``Jj x``, ``Jj y``, ``Jj z`` (the joint points coincide) and ``Jj axis 1``, ``Jj axis 2``
    (the axis of one side is perpendicular to two directions of the other): 35 rows, rank 34 on
    the motion (mobility 1). :data:`BRICARD` holds the benchmark's parameter values and
    :func:`bricard_state` its initial state.

    Examples
    --------
    >>> s = bricard()
    >>> len(s.coordinates), len(s.constraint_rows()[0])
    (35, 35)
    """
    L, m = _param(length, "L", "length"), _param(mass, "m", "mass")
    g, side = _param(gravity, "g", "gravity"), _param(side, "s", "side")
    i_axial, i_trans = m * 2 * side**2 / 12, m * (L**2 + side**2) / 12
    frames, bars = _frames(), []
    qs: list = []
    for k in range(1, 6):
        pos = coordinates(f"x_{k} y_{k} z_{k}")
        att = Quaternion(coordinates(f"b_{k}0 b_{k}1 b_{k}2 b_{k}3"))
        qs += [*pos, *att.coordinates]
        bars.append((pos, att))
    s = System(qs, name="Bricard mechanism (IFToMM A04)")
    for k, (pos, att) in enumerate(bars, start=1):
        s.add_rigid_body(m, [i_axial, i_trans, i_trans], list(pos), att, name=f"bar {k}")
        s.add_potential_energy(m * g * pos[1], name=f"gravity {k}")
    half = sp.Matrix([L / 2, 0, 0])
    for j in range(6):
        point = L * sp.Matrix(_POINTS[j])
        axis = sp.Matrix(np.eye(3)[_AXES[j]].astype(int))
        sides = []
        for k, sign in ((j, 1), (j + 1, -1)):  # the bar before Jj (ends there), the bar after
            if k in (0, 6):
                sides.append((point, sp.eye(3), None))
                continue
            pos, att = bars[k - 1]
            C = att.dcm
            sides.append((sp.Matrix(pos) + sign * C * half, C, frames[k - 1]))
        (pa, Ca, Fa), (pb, Cb, Fb) = sides
        for row, name in zip(pa - pb, "xyz", strict=True):
            s.add_holonomic_constraint(row, name=f"J{j} {name}")
        # the axis in A's body axes; two body directions of B perpendicular to it
        ua = sp.Matrix((Fa.T @ np.eye(3)[_AXES[j]]).round().astype(int)) if Fa is not None else axis
        fb = Fb if Fb is not None else np.eye(3)
        normals = [i for i in range(3) if abs(fb[_AXES[j], i]) < 0.5]
        for n, i in enumerate(normals, start=1):
            s.add_holonomic_constraint(
                (Ca * ua).dot(Cb * sp.Matrix(np.eye(3, dtype=int)[i])), name=f"J{j} axis {n}"
            )
    return s


def bricard_state(length: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The benchmark's initial state (q0, q̇0) of :func:`bricard`: the right-angled configuration
    of the module docstring, at rest.

    Examples
    --------
    >>> q0, qd0 = bricard_state()
    >>> q0[:7].round(6).tolist(), float(abs(qd0).max())
    ([0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], 0.0)
    """
    q = []
    for k, frame in enumerate(_frames()):
        centre = 0.5 * length * (np.add(_POINTS[k], _POINTS[k + 1]))
        att = Quaternion(coordinates(f"b_{k + 1}0 b_{k + 1}1 b_{k + 1}2 b_{k + 1}3"))
        q += [*centre, *att.from_dcm(frame)]
    q0 = np.array(q) + 0.0
    return q0, np.zeros_like(q0)
