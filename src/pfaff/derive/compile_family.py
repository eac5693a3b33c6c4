"""Compile stage for models with families: template kernels over index progressions.

Each block becomes the stream parts of :class:`pfaff.numeric.structured.StructuredModel`
(:func:`pfaff.derive.compile.dyn_streams`, the same as for any model): one generated kernel per
template, evaluated over all its instances through strided views, with the family's rows and
columns as progressions (:class:`pfaff.numeric.streams.Index`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pfaff.core.errors import ModelError
from pfaff.core.lazy import NumberedNames
from pfaff.derive.compile import (
    Restream,
    attitude_sets,
    con_streams,
    dyn_streams,
    input_names,
    model_parameter_values,
)
from pfaff.derive.equations import Derivation
from pfaff.derive.geometry import build_geometry
from pfaff.derive.memory import check_memory
from pfaff.numeric.structured import StructuredModel


def _names(eom: Derivation) -> NumberedNames:
    """Coordinate names as plain strings, made on demand (no SymPy object per family member)."""
    coords = eom.coordinates
    fams = sorted(getattr(eom.system, "families", []), key=lambda f: f.offset)
    p = eom.n - sum(f.n for f in fams)
    head = [str(coords[i].func) for i in range(p)]
    if any(f.offset < p for f in fams) or [f.offset for f in fams] != list(
        np.cumsum([p] + [f.n for f in fams])[:-1]
    ):
        return NumberedNames([str(c.func) for c in coords], [])  # not laid out as runs
    return NumberedNames(head, [(f.name, f.first, f.n) for f in fams])


def structured_model(
    eom: Derivation, values: Sequence[float], *, solver: str | None = None
) -> StructuredModel:
    """Build the :class:`StructuredModel` of ``eom`` with ordered parameter values.

    ``solver`` is ``None`` (the triangular solver where the structure allows, else sparse),
    ``"triangular"``, ``"sparse"``, or ``"none"`` (kernels only: residuals and matrices).
    """
    if getattr(eom.system, "events", None):
        raise ModelError(
            "events (System.add_event) are not supported by models with families yet: compile "
            "the system without families, or pass the events to pfaff.simulate(events=[pfaff."
            "Event(g, ...)]) as functions g(t, q, qd)"
        )
    if getattr(eom.system, "contacts", None):
        raise ModelError(
            "unilateral constraints (System.add_unilateral_constraint) are not supported by "
            "models with families yet: compile the system without families"
        )
    params = tuple(eom.parameters)
    live = frozenset(input_names(eom))
    dyn = [
        dyn_streams(b, params, values, inputs=live)
        for b in eom.blocks
        if b.local.kind == "dynamics"
    ]
    con = [con_streams(b, params, values) for b in eom.blocks if b.local.kind != "dynamics"]
    model = StructuredModel(
        eom.n,
        eom.m,
        dyn,
        con,
        coordinate_names=_names(eom),
        constraint_names=eom.constraint_names,
        holonomic=eom.holonomic,
        parameters={p.name: v for p, v in zip(params, values, strict=True)},
        p=eom.n - sum(len(f) for f in getattr(eom.system, "families", [])),
        solver=solver,
        inputs=input_names(eom),
        attitudes=attitude_sets(eom),
        geometry=build_geometry(eom, values),  # what Trajectory.animate draws
        restream=Restream(eom, params, False, lazy=False),  # for model.with_parameters
    )
    return model


def compile_structured(
    eom: Derivation, parameters: dict, *, solver: str | None = None
) -> StructuredModel:
    """Check parameter values and build a :class:`StructuredModel` (used by ``eom.compile``).

    Examples
    --------
    >>> import pfaff
    >>> eom = pfaff.models.rolling_ring(2000, force=True).equations()
    >>> compile_structured(eom, {"M": 1, "r": 0.5, "F": 2}).solver
    'triangular'
    """
    check_memory(eom.n, eom.m, eom.blocks)
    return structured_model(eom, model_parameter_values(eom, parameters), solver=solver)
