"""Bad input: each problem raises a pfaff error whose message names it."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff import ConstraintError, ModelError, ParameterError, StateError

t = pfaff.t
x, y, th = pfaff.coordinates("x y theta")


def test_coordinate_not_function_of_time() -> None:
    with pytest.raises(TypeError, match="not a function of time"):
        pfaff.System([x, sp.Symbol("z")])
    with pytest.raises(ValueError, match="not a function of time"):
        pfaff.System([sp.Function("u")(sp.Symbol("s"))])
    with pytest.raises(ModelError, match="listed twice"):
        pfaff.System([x, x])
    with pytest.raises(ModelError, match="at least one coordinate"):
        pfaff.System([])


def test_velocity_constraint_not_linear() -> None:
    s = pfaff.System([x, y])
    with pytest.raises(ConstraintError, match="not linear in the velocities"):
        s.add_velocity_constraint(x.diff(t) ** 2 + y.diff(t))
    with pytest.raises(ConstraintError, match="not linear"):
        s.add_velocity_constraint(sp.sin(x.diff(t)) - y.diff(t))
    with pytest.raises(ConstraintError, match="contains no velocity"):
        s.add_velocity_constraint(x - y)


def test_holonomic_constraint_with_velocity() -> None:
    s = pfaff.System([x, y])
    with pytest.raises(ModelError, match="velocity"):
        s.add_holonomic_constraint(x.diff(t) - y)


def test_constraint_naming_no_coordinate() -> None:
    s = pfaff.System([x, y])
    with pytest.raises(ConstraintError, match="names no coordinate"):
        s.add_holonomic_constraint(sp.Symbol("a") - 1)


def test_more_constraints_than_coordinates() -> None:
    """Three consistent rows on two coordinates: accepted, the dependent set reported."""
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_holonomic_constraint(x - 1, name="a")
    s.add_holonomic_constraint(y - 2, name="b")
    s.add_holonomic_constraint(x + y - 3, name="c")
    with pytest.warns(pfaff.RedundancyWarning, match="rank 2 < 3"):
        eom = s.equations()
    assert eom.redundant_sets == [["a", "b", "c"]]
    s.add_holonomic_constraint(x - y + 2, name="d")  # x - y = -1 on the manifold: contradicts
    with pytest.raises(ConstraintError, match="inconsistent constraints"):
        s.equations()


def test_position_wrong_dimension() -> None:
    s = pfaff.System([x, y])
    with pytest.raises(ModelError, match="2 or 3 components"):
        s.add_particle(1, [x, y, 0, 1])
    with pytest.raises(ModelError, match="2 or 3 components"):
        s.add_particle(1, [x])
    with pytest.raises(ModelError, match="has 3 components but its point has 2"):
        s.add_force([1, 0, 0], at=[x, y])


def test_foreign_function_and_bad_mass() -> None:
    s = pfaff.System([x])
    z = sp.Function("z")(t)
    with pytest.raises(ModelError, match="not a coordinate of this system"):
        s.add_particle(1, [x, z])
    with pytest.raises(ModelError, match="must be constant"):
        s.add_particle(x, [x, 0])
    with pytest.raises(ModelError, match="positive"):
        s.add_particle(-1, [x, 0])
    with pytest.raises(ModelError, match="NaN or infinity"):
        s.add_particle(sp.nan, [x, 0])
    with pytest.raises(TypeError, match="must be a number or SymPy expression"):
        s.add_potential_energy("x**2")


@pytest.mark.parametrize(
    "extra",
    [
        lambda s: s.add_holonomic_constraint(2 * (x - y), name="c0"),  # a multiple of the first
        lambda s: s.add_holonomic_constraint(x - y - 1, name="c0") or "contradicts",
        lambda s: s.add_velocity_constraint(x.diff(t) - y.diff(t), name="c0"),  # its derivative
    ],
)
def test_redundant_or_inconsistent_constraints(extra) -> None:
    """A multiple or the time derivative of a constraint is reported; a contradiction refused."""
    s = pfaff.System([x, y, th])
    s.add_particle(1, [x, y])
    s.add_kinetic_energy(th.diff(t) ** 2)
    s.add_holonomic_constraint(x - y, name="first")
    name = extra(s)
    if name == "contradicts":
        with pytest.raises(ConstraintError, match="inconsistent constraints: `first`, `c0`"):
            s.equations()
        return
    with pytest.warns(pfaff.RedundancyWarning, match="`first`, `c0` depend on one another"):
        assert s.equations().redundant_sets == [["first", "c0"]]


def test_repeated_constraint_rejected_at_once() -> None:
    s = pfaff.System([x, y])
    s.add_holonomic_constraint(x - y, name="a")
    with pytest.raises(ConstraintError, match="repeats constraint `a`"):
        s.add_holonomic_constraint(x - y)
    s.add_holonomic_constraint(y - x, name="b")  # the negation: reported by the rank test
    with pytest.warns(pfaff.RedundancyWarning, match=r"`a`, `b` depend on one another"):
        s.equations()


def test_ring_closure_is_redundant() -> None:
    """Closing the ring (θ_1 - θ_N + (N-1)Δθ = 0) repeats the chain of spacings."""
    n = 5
    ring = pfaff.models.rolling_ring(n)
    ths = ring.coordinates[1:]
    ring.add_holonomic_constraint(ths[-1] - ths[0] - 2 * sp.pi * (n - 1) / n + 0, name="closure")
    with pytest.warns(pfaff.RedundancyWarning) as info:
        eom = ring.equations()
    # every row of the dependent cycle is named, and only those: whatever the BLAS pivoting
    named = set(re.findall(r"`([^`]+)`", str(info[0].message)))
    assert sorted(eom.redundant_sets[0]) == sorted(named)
    assert named == {"spacing 1", "spacing 2", "spacing 3", "spacing 4", "closure"}
    assert "rank 5 < 6" in str(info[0].message)


@pytest.mark.parametrize("family", [False, True])
@pytest.mark.slow  # (over a second: the full suite runs it)
def test_ring_closure_named_on_the_sparse_path(family: bool) -> None:
    """Above 200 rows the dependency is found by sparse inverse iteration: same rule, a count."""
    n = 300
    ring = pfaff.models.rolling_ring(n, family=family)
    ths = ring.coordinates[1:]
    ring.add_holonomic_constraint(ths[-1] - ths[0] - 2 * sp.pi * (n - 1) / n, name="closure")
    with pytest.warns(pfaff.RedundancyWarning) as info:
        ring.equations()
    msg = str(info[0].message)
    named = re.findall(r"`([^`]+)`", msg)
    assert named == [f"spacing {k}" for k in range(1, 9)]  # the first 8 of the 300
    assert f"and {n - 1 + 1 - 8} more" in msg and "no slip" not in msg
    assert f"rank {n} < {n + 1}" in msg


@pytest.mark.parametrize("bad", [math.nan, math.inf, "abc"])
def test_bad_parameters(bad) -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    with pytest.raises(ParameterError, match="`g`"):
        eom.compile({"m": 1.0, "g": bad, "L": 1.0})


def test_missing_and_unknown_parameters() -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    with pytest.raises(ParameterError, match="missing value for `L`"):
        eom.compile({"m": 1.0, "g": 9.81})
    with pytest.raises(ParameterError, match="unknown parameter `k`"):
        eom.compile({"m": 1.0, "g": 9.81, "L": 1.0, "k": 2})


def test_bad_states() -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    with pytest.raises(StateError, match=r"shape \(2,\)"):
        model.accelerations(0.0, [0.0, -1.0, 0.0], [0.0, 0.0])
    with pytest.raises(StateError, match="NaN"):
        model.accelerations(0.0, [np.nan, -1.0], [0.0, 0.0])
    with pytest.raises(StateError, match="`t`"):
        model.accelerations(np.inf, [0.0, -1.0], [0.0, 0.0])


def test_singular_configuration_reported() -> None:
    """At the pivot (x = y = 0) the rod constraint loses rank: a clear error, no LinAlgError."""
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    with pytest.raises(ConstraintError, match="singular"):
        model.accelerations(0.0, [0.0, 0.0], [0.0, 0.0])


def test_reduce_wrong_count() -> None:
    ring = pfaff.models.rolling_ring(3)
    with pytest.raises(ConstraintError, match="leave 1 independent"):
        ring.reduce(ring.coordinates[:2])
    with pytest.raises(ModelError, match="not coordinates"):
        ring.reduce([y])
