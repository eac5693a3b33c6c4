"""Parameter values at ``compile``: real finite numbers only, and particle masses they make positive.

A numeric mass is checked by ``add_particle``; a mass written with parameters (``m``, ``M/N``)
is known only at ``compile`` and used to be accepted whatever its sign.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff import ParameterError


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        (True, "boolean"),
        (np.bool_(False), "boolean"),
        (1j, "real number"),
        (np.complex128(9.81), "real number"),
        ("9.81", "string"),
        ([9.81], "real number"),
        (np.array([9.81]), "real number"),
        (math.nan, "NaN or infinite"),
        (sp.I, "real number"),
    ],
)
def test_parameter_value_must_be_a_real_number(value: object, problem: str) -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    with pytest.raises(ParameterError, match=rf"`g`.*{problem}"):
        eom.compile({"m": 1.0, "g": value, "L": 1.0})


def test_real_numbers_of_other_types_are_accepted() -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    model = eom.compile({"m": np.float32(1.0), "g": sp.Rational(981, 100), "L": np.array(1.0)})
    assert model.parameters == {"L": 1.0, "g": 9.81, "m": 1.0}


@pytest.mark.parametrize("mass", [-1.0, 0.0])
def test_particle_mass_from_parameters_must_be_positive(mass: float) -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    with pytest.raises(
        ParameterError, match=rf"particle `bob` has mass m = {mass:g}.*`m` = {mass:g}"
    ):
        eom.compile({"m": mass, "g": 9.81, "L": 1.0})


def test_particle_mass_expression_must_be_real() -> None:
    x, y = pfaff.coordinates("x y")
    k = sp.Symbol("k")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, 0])
    s.add_particle(sp.sqrt(k), [0, y], name="root")
    with pytest.raises(
        ParameterError, match=r"particle `root` has mass sqrt\(k\) = 0\+1j.*`k` = -1"
    ):
        s.equations().compile({"k": -1.0})
    assert s.equations().compile({"k": 4.0}).mass_matrix(0.0, [0.0, 0.0]).tolist() == [
        [1.0, 0.0],
        [0.0, 2.0],
    ]


@pytest.mark.parametrize("family", [False, True])
def test_ring_mass_checked_for_every_compiler(family: bool) -> None:
    """The family compiler (StructuredModel) checks the same way; M/N is evaluated once."""
    ring = pfaff.models.rolling_ring(6, force=True, family=family)
    with pytest.raises(ParameterError, match=r"mass M/6 = -0.333333 with parameter `M` = -2"):
        ring.equations().compile({"M": -2.0, "r": 0.5, "F": 2.0})
