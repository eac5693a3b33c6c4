"""Parameters given by name: a name two different symbols share (other assumptions) is refused
naming both sets of assumptions; by Symbol, each gets its own value."""

from __future__ import annotations

import pytest
import sympy as sp

import pfaff
from pfaff.derive.compile import parameter_values

M_POS, M = sp.Symbol("m", positive=True), sp.Symbol("m")
CLASH = r"two different symbols are both named `m` \(assumptions positive=True and none\)"


@pytest.fixture(scope="module")
def eom() -> pfaff.EquationsOfMotion:
    """A mass m (positive) in a field of strength m (no assumptions): ẍ = −m/m_pos."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(M_POS, [x, 0])
    s.add_potential_energy(M * x, name="field")
    return s.equations()


def test_a_shared_name_is_refused_naming_both(eom: pfaff.EquationsOfMotion) -> None:
    """compile({"m": 1}) used to say "missing value for `m`" though m was given."""
    with pytest.raises(pfaff.ParameterError, match=CLASH + ": give each its value by Symbol"):
        eom.compile({"m": 1.0})
    with pytest.raises(pfaff.ParameterError, match="missing value") as info:
        eom.compile({M_POS: 2.0})
    assert "both named" not in str(info.value)


def test_by_symbol_each_gets_its_value(eom: pfaff.EquationsOfMotion) -> None:
    model = eom.compile({M_POS: 2.0, M: 3.0})
    assert model.accelerations(0.0, [0.0], [0.0])[0][0] == pytest.approx(-1.5, rel=1e-14)


def test_parameter_values_orders_by_symbol() -> None:
    g = sp.Symbol("g")
    with pytest.raises(pfaff.ParameterError, match=CLASH):
        parameter_values((M, M_POS, g), {"m": 1.0, "g": 9.81})
    assert parameter_values((M, M_POS, g), {M: 1.0, M_POS: 2.0, "g": 9.81}) == [1.0, 2.0, 9.81]
