"""The one registry of KKT solvers, by name, with the model kinds that can use each.

A solver is chosen once, when a model is built (``compile(..., solver=...)`` or by structure),
and made anew for every run copy (its work arrays are the run's). **A new KKT solver** is a
:class:`pfaff.numeric.kkt.KKTSolver` subclass registered here, with the kinds it serves, and
added to ``tests/numeric/test_solvers.py``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from pfaff.core.errors import OptionError
from pfaff.numeric.kkt import KKTSolver, LUSolver, RangeSpaceSolver, SparseSolver
from pfaff.numeric.triangular import TriangularSolver

if TYPE_CHECKING:
    from pfaff.numeric.structured import StructuredModel


@dataclass(frozen=True)
class SolverEntry:
    """A registered solver: its name and the model kinds (``"general"``, ``"family"``) it serves."""

    name: str
    kinds: frozenset[str]
    summary: str


REGISTRY: dict[str, SolverEntry] = {
    e.name: e
    for e in (
        SolverEntry("range-space", frozenset({"general"}), "dense, M⁻¹ with the rank-loss floor"),
        SolverEntry("lu", frozenset({"general"}), "dense LU of the whole augmented matrix"),
        SolverEntry("triangular", frozenset({"family"}), "the ring's O(N) elimination"),
        SolverEntry("sparse", frozenset({"general", "family"}), "SuperLU, ordering reused"),
    )
}


def names(kind: str) -> tuple[str, ...]:
    """The solvers a model kind can use.

    Examples
    --------
    >>> names("general"), names("family")
    (('range-space', 'lu', 'sparse'), ('triangular', 'sparse'))
    """
    return tuple(name for name, e in REGISTRY.items() if kind in e.kinds)


def check(solver: str | None, kind: str) -> None:
    """Refuse a solver name the model kind cannot use, naming ``solver``."""
    if solver is not None and solver not in names(kind):
        raise OptionError(
            f"`solver` of a model {'with' if kind == 'family' else 'without'} families must be "
            f"one of {', '.join(names(kind))}; got {solver!r:.80}"
        )


def general_solver(name: str, n: int, m: int) -> tuple[KKTSolver, LUSolver]:
    """The solver of a general model and the LU solver it falls back to (M singular)."""
    check(name, "general")
    made: KKTSolver = {"range-space": RangeSpaceSolver, "lu": LUSolver, "sparse": SparseSolver}[
        name
    ](n, m)
    return made, LUSolver(n, m)


def family_solver(model: StructuredModel, plan: object) -> KKTSolver:
    """The solver of a family model: triangular where ``plan`` exists, else sparse."""
    if plan is not None:
        return TriangularSolver(model, plan)  # type: ignore[arg-type]
    return SparseSolver(model.n, model.m)
