"""Compile stage for models with families: template kernels over index progressions.

Each block becomes the stream parts of :class:`pfaff.numeric.structured.StructuredModel`
(:func:`pfaff.derive.compile.dyn_streams`, the same as for any model): one generated kernel per
template, evaluated over all its instances through strided views, with the family's rows and
columns as progressions (:class:`pfaff.numeric.streams.Index`).
"""

from __future__ import annotations

from collections.abc import Sequence

from pfaff.core.lazy import LazySeq
from pfaff.derive.compile import con_streams, dyn_streams, model_parameter_values
from pfaff.derive.equations import Derivation
from pfaff.derive.geometry import build_geometry
from pfaff.derive.memory import check_memory
from pfaff.numeric.structured import StructuredModel


def _names(eom: Derivation) -> LazySeq:
    """Coordinate names as plain strings, made on demand (no SymPy object per family member)."""
    coords = eom.coordinates
    fams = list(getattr(eom.system, "families", []))
    p = eom.n - sum(f.n for f in fams)

    def name(i: int) -> str:
        if i < p:
            return str(coords[i].func)
        for f in fams:
            if f.offset <= i < f.offset + f.n:
                return f"{f.name}{f.first + i - f.offset}"
        return str(coords[i].func)

    def bulk(lo: int, hi: int) -> list[str]:
        out = [name(i) for i in range(lo, min(hi, p))]
        for f in fams:
            a, b = max(lo, f.offset), min(hi, f.offset + f.n)
            if a < b:
                d = f.first - f.offset
                out += [f"{f.name}{j}" for j in range(a + d, b + d)]
        return out

    return LazySeq(eom.n, name, bulk)


def structured_model(
    eom: Derivation, values: Sequence[float], *, solver: str | None = None
) -> StructuredModel:
    """Build the :class:`StructuredModel` of ``eom`` with ordered parameter values.

    ``solver`` is ``None`` (the triangular solver where the structure allows, else sparse),
    ``"triangular"``, ``"sparse"``, or ``"none"`` (kernels only: residuals and matrices).
    """
    params = tuple(eom.parameters)
    dyn = [dyn_streams(b, params, values) for b in eom.blocks if b.local.kind == "dynamics"]
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
    )
    model.geometry = build_geometry(eom, values)  # what Trajectory.animate draws
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
