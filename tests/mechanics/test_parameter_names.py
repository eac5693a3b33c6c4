"""Parameters are given values by name: two different symbols with one name are refused where
the second enters the model, naming both sets of assumptions."""

from __future__ import annotations

import pytest
import sympy as sp

import pfaff
from pfaff.derive.compile import parameter_values

M_POS, M = sp.Symbol("m", positive=True), sp.Symbol("m")
CLASH = r"two different symbols are both named `m` \(assumptions positive=True and none\)"


def test_same_name_other_assumptions_refused_at_the_piece() -> None:
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(M_POS, [x, 0])
    with pytest.raises(pfaff.ModelError, match="potential energy `spring`: " + CLASH):
        s.add_potential_energy(M * x**2, name="spring")
    # the same symbol again is one parameter, and compile takes its value by name
    s.add_potential_energy(M_POS * 9.81 * x, name="gravity")
    model = s.equations().compile({"m": 2.0})
    assert model.parameters == {"m": 2.0}
    assert model.accelerations(0.0, [0.0], [0.0])[0] == pytest.approx(-9.81)


def test_same_name_in_a_body_inertia_refused() -> None:
    th = pfaff.coordinates("th")
    s = pfaff.System([th])
    s.add_potential_energy(M * th**2)
    with pytest.raises(pfaff.ModelError, match="inertia of .*" + CLASH):
        s.add_rigid_body(1, M_POS, [0, 0], pfaff.PlanarAngle(th), name="wheel")


def test_parameter_values_refuses_two_symbols_with_one_name() -> None:
    """Equations given as matrices reach compile without the system's check: refused there."""
    with pytest.raises(pfaff.ParameterError, match=CLASH):
        parameter_values((M, M_POS, sp.Symbol("g")), {"m": 1.0, "g": 9.81})
