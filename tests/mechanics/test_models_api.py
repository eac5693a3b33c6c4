"""Model API details: sympy.physics.vector input, single coordinates, the minimal ring."""

from __future__ import annotations

import pytest
import sympy as sp
from sympy.physics.vector import Point, ReferenceFrame

import pfaff

t = pfaff.t
L, m, g = sp.symbols("L m g")


def _pendulum_vectors():
    th = pfaff.coordinates("theta")
    N = ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    pivot = Point("O")
    P = pivot.locatenew("P", -L * B.y)
    return th, N, P.pos_from(pivot)


def test_vector_positions_need_the_inertial_frame() -> None:
    th, N, r = _pendulum_vectors()
    s = pfaff.System(th)
    with pytest.raises(pfaff.ModelError, match="inertial frame is ambiguous"):
        s.add_particle(m, r)  # r is expressed in the rotating frame B only
    s = pfaff.System(th, frame=N)
    s.add_particle(m, r)
    s.add_force(-m * g * N.y, at=r)
    eq = s.equations().lagrange_equations[0]
    assert sp.simplify(eq.lhs - eq.rhs - (m * L**2 * th.diff(t, 2) + m * g * L * sp.sin(th))) == 0


def test_vector_in_a_fixed_frame_is_accepted() -> None:
    x, y = pfaff.coordinates("x y")
    N = ReferenceFrame("N")
    s = pfaff.System([x, y])
    s.add_particle(m, x * N.x + y * N.y)
    assert s.equations().mass_matrix == sp.Matrix([[m, 0], [0, m]])


def test_minimal_ring_equation() -> None:
    M, r, F = sp.symbols("M r F")
    eq = pfaff.models.rolling_ring_minimal(force=True).equations().lagrange_equations[0]
    th = pfaff.coordinates("theta")
    assert eq.lhs == 2 * M * r**2 * th.diff(t, 2)
    assert eq.rhs == F * r


def test_coordinates_syntax() -> None:
    qs = pfaff.coordinates("x theta1:65")
    assert len(qs) == 65 and str(qs[-1]) == "theta64(t)"
    assert all(q.args == (t,) for q in qs)
    assert pfaff.t == sp.physics.vector.dynamicsymbols._t  # equal: sympy.physics not imported
