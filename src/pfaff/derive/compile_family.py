"""Compile stage for models with families: template kernels over index progressions.

Each block becomes the stream parts of :class:`pfaff.numeric.structured.StructuredModel`: one
generated kernel per template (:func:`pfaff.derive.codegen.stream_code`), evaluated over all its
instances through strided views, with the global rows and columns as progressions
(:class:`pfaff.numeric.streams.Index`) instead of index arrays.
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

from pfaff.core.lazy import LazySeq
from pfaff.core.symbols import local_qd
from pfaff.derive.blocks import Block
from pfaff.derive.codegen import constraint_layout, energy_exprs, power_exprs, stream_code
from pfaff.derive.compile import model_parameter_values
from pfaff.derive.equations import Derivation
from pfaff.derive.memory import check_memory
from pfaff.numeric.streams import Index, StreamKernel
from pfaff.numeric.structured import ConStreams, DynStreams, StructuredModel


def block_columns(block: Block) -> list:
    """Per local coordinate: an :class:`Index` (progression) or an index array."""
    if block.family:
        return [Index(s, d, block.n_inst) for s, d in block.progressions or []]
    return [Index.of(block.coords[:, a]) for a in range(block.coords.shape[1])]


def _kernel(
    cols: list, exprs: list, params: Sequence, values: Sequence[float], count: int, summed=None
):
    return StreamKernel(cols, stream_code(len(cols), exprs, params, values, count, summed), count)


def dyn_streams(block: Block, params: Sequence[sp.Symbol], values: Sequence[float]) -> DynStreams:
    """The stream parts of a dynamics block: M is symmetric, so only entries a <= b are made."""
    loc = block.local
    upper = sorted(ab for ab in loc.mass if ab[0] <= ab[1])
    forcing = loc.forcing
    fidx = sorted(forcing)
    cols = block_columns(block)
    rows = [cols[a] for a in fidx]
    summed = [False] * len(upper) + [isinstance(ix, Index) and ix.fixed for ix in rows]
    exprs = [loc.mass[ab] for ab in upper] + [forcing[a] for a in fidx]
    kernel = _kernel(cols, exprs, params, values, block.n_inst, summed)

    def energy_kernel(which: str) -> StreamKernel:
        T, V = energy_exprs(block)
        parts = power_exprs(block) if which == "power" else [T, V]
        if which == "energies":
            k = len(cols)
            T0 = T.xreplace({local_qd(a): 0 for a in range(k)})
            Tneg = T.xreplace({local_qd(a): -local_qd(a) for a in range(k)})
            parts += [T0, (T + Tneg) / 2 - T0]
        return _kernel(cols, parts, params, values, block.n_inst, [True] * len(parts))

    upper_streams = [(cols[a], cols[b], a != b) for a, b in upper]
    return DynStreams(kernel, upper_streams, rows, energy_kernel, has_power=bool(loc.Q))


def con_streams(block: Block, params: Sequence[sp.Symbol], values: Sequence[float]) -> ConStreams:
    """The stream parts of a constraint block: ``acc`` for the solve, ``res`` for residuals."""
    cols_local, exprs = constraint_layout(block)
    cols = block_columns(block)
    rows = Index(block.row0, 1, block.n_inst) if block.family else Index.of(block.rows)
    na = len(cols_local)
    acc = _kernel(cols, [*exprs[:na], exprs[na + 1]], params, values, block.n_inst)
    res = _kernel(cols, exprs, params, values, block.n_inst)
    return ConStreams(rows, [cols[a] for a in cols_local], acc, res)


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
    return StructuredModel(
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
