"""The rank check of a family on a small instance of its templates (issue 25) against the full
check on a numeric model of full size: the same verdict, sets and warnings for the ring, a
family with state-dependent pivots, and families that are redundant by design (where the small
instance cannot prove full rank and the full check must run)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.derive.family_rank import closure_rows, proves_full_rank
from pfaff.derive.rank import check_constraint_rank
from pfaff.derive.templates import derive

K = sp.Symbol("k", integer=True)


def _both(system: pfaff.System) -> tuple[bool, list, list, list, list]:
    """(small-instance proof, sets with it, sets of the full check, and the warnings of each)."""
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        eom = derive(system)
    proof = proves_full_rank(eom, [0.9] * len(eom.parameters), 0.3, np.random.default_rng(2))
    out = []
    for small in (True, False):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sets = check_constraint_rank(eom, small_instance=small)
        out += [sets, [str(w.message) for w in caught if w.category is pfaff.RedundancyWarning]]
    return (proof, *out)  # type: ignore[return-value]


@pytest.mark.parametrize("n", [2, 3, 7, 64, 700])
def test_the_ring_is_proved_of_full_rank_as_the_full_check_finds(n: int) -> None:
    """x − rθ₁ and θ_{k+1} − θ_k − 2π/n: A_L lower bidiagonal with −r and 1 on its diagonal."""
    proof, small, warned_small, full, warned_full = _both(
        pfaff.models.rolling_ring(n, force=True, family=True)
    )
    assert proof
    assert small == full == [] and warned_small == warned_full == []


@pytest.mark.parametrize("n", [3, 10, 300])
def test_the_closed_ring_finds_the_full_checks_dependent_set(n: int) -> None:
    """The closed ring (n + 1 rows on n + 1 coordinates): the n spacing rows sum to 0 = 0, one
    dependent set. No proof of full rank (there is none); the closing row's w (A_Lᵀ w = −a_L,
    one banded solve) names the same rows as the full check's null space of Aᵀ: with it above
    the dense limit (n = 300), and always from :func:`closure_rows`."""
    ring = pfaff.models.rolling_ring(n, family=True, closed=True)
    proof, small, warned_small, full, warned_full = _both(ring)
    assert not proof
    assert small == full and warned_small == warned_full and len(warned_full) == 1
    assert full == [[f"spacing {i}" for i in range(1, n + 1)]]
    with warnings.catch_warnings(record=True):
        eom = derive(ring)
    rows = closure_rows(eom, [0.9, 1.1], 0.3, np.random.default_rng(5))
    assert rows is not None and rows.tolist() == list(range(1, n + 1))


def test_an_independent_closing_row_is_full_rank_in_both() -> None:
    """x − r θ_N after the open ring: A_L w = −a_L gives w with A_Gᵀ w + a_G ≠ 0 (the row moves
    x against θ_N, which the ring's rows tie in another ratio): full rank, no warning."""
    n = 250
    ring = pfaff.models.rolling_ring(n, family=True)
    x, last = ring.coordinates[0], ring.families[0][n]
    ring.add_holonomic_constraint(x - 3 * last, name="extra")
    proof, small, warned_small, full, warned_full = _both(ring)
    assert not proof
    assert small == full == [] and warned_small == warned_full == []
    with warnings.catch_warnings(record=True):
        eom = derive(ring)
    rows = closure_rows(eom, [0.9, 1.1], 0.3, np.random.default_rng(5))
    assert rows is not None and rows.size == 0


def _wave(n: int, twice: bool = False) -> pfaff.System:
    """A chain of n angles held by sin θ_{k+1} = θ_k / 2 (pivots cos θ_{k+1}: non-zero at almost
    every state, so full rank); ``twice``: the same rows again, scaled by 2 (redundant)."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x], name="wave")
    s.add_particle(1, [x, 0])
    th = s.add_family("theta", n)
    s.add_particle(1, [sp.cos(th[K]), sp.sin(th[K])], over=K)
    s.add_holonomic_constraint(th[0] - sp.Symbol("a") * x, "start")
    s.add_holonomic_constraint(sp.sin(th[K + 1]) - th[K] / 2, "wave", over=(K, 0, n - 2))
    if twice:
        rows = 2 * sp.sin(th[K + 1]) - th[K]
        s.add_holonomic_constraint(rows, "again", over=(K, 0, n - 2))
    return s


@pytest.mark.parametrize("n", [3, 50])
def test_state_dependent_pivots_are_sampled_on_the_small_instance(n: int) -> None:
    proof, small, warned_small, full, warned_full = _both(_wave(n))
    assert proof
    assert small == full == [] and warned_small == warned_full == []


def test_a_repeated_template_is_redundant_in_both() -> None:
    """Each `again` row is twice its `wave` row: 4 dependent pairs of 2n − 1 rows on n members."""
    proof, small, warned_small, full, warned_full = _both(_wave(5, twice=True))
    assert not proof
    assert small == full and warned_small == warned_full
    pairs = sorted(sorted(s) for s in full)
    assert pairs == [sorted([f"wave {i}", f"again {i}"]) for i in range(4)]


def test_a_zero_pivot_template_is_not_proved() -> None:
    """a θ_{k+1} − θ_k with a = 0: the diagonal of A_L is zero, which the structure (the entry
    a is no constant of the template, a parameter) cannot show; the samples do."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x], name="dead")
    s.add_particle(1, [x, 0])
    th = s.add_family("theta", 4)
    a = sp.Symbol("a")
    s.add_particle(1, [th[K], 0], over=K)
    s.add_holonomic_constraint(th[0] - x, "start")
    s.add_holonomic_constraint(a * th[K + 1] - th[K], "link", over=(K, 0, 2))
    eom = derive(s)
    assert not proves_full_rank(eom, [0.0], 0.3, np.random.default_rng(0))
    assert proves_full_rank(eom, [1.0], 0.3, np.random.default_rng(0))
