"""The compile stage: parameter values checked, kernels generated, a :class:`NumericModel` built.

Each block becomes stream parts (:class:`pfaff.numeric.parts.DynStreams`,
:class:`~pfaff.numeric.parts.ConStreams`): one generated kernel per template
(:func:`pfaff.derive.codegen.stream_code`, the one kernel generator of NumPy code), evaluated over
all its instances, with the global rows and columns as progressions
(:class:`pfaff.numeric.streams.Index`) where they are, else as index arrays. The same parts make
both model kinds (:mod:`pfaff.derive.compile_family` for families).
"""

from __future__ import annotations

import math
import time
import weakref
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
import sympy as sp

from pfaff.core.errors import ParameterError
from pfaff.core.symbols import local_qd, name_clash
from pfaff.derive.blocks import Block, raw_keys
from pfaff.derive.codegen import constraint_layout, energy_exprs, power_exprs, stream_code
from pfaff.derive.events import compile_events
from pfaff.derive.fused import build_fused
from pfaff.derive.geometry import build_geometry
from pfaff.derive.linearize import linearizer_for
from pfaff.numeric.fused import FusedKernel
from pfaff.numeric.kernel import StreamCode, StreamKernel
from pfaff.numeric.model import DENSE_LIMIT, NumericModel
from pfaff.numeric.parts import ConStreams, DynStreams
from pfaff.numeric.streams import Index

if TYPE_CHECKING:
    from pfaff.derive.equations import Derivation


def parameter_values(params: tuple[sp.Symbol, ...], given: dict) -> list[float]:
    """Check and order parameter values: every symbol needed, none unknown, all finite reals."""
    if not isinstance(given, dict):
        raise ParameterError(
            f"`parameters` must be a dict of symbol (or name) -> value, got {given!r}"
        )
    by_name = {p.name: p for p in params}
    values: dict[sp.Symbol, object] = {}
    problems = []
    for key, val in given.items():
        if isinstance(key, str) and (clash := name_clash(p for p in params if p.name == key)):
            problems.append(f"{clash}: give each its value by Symbol, or use one symbol")
            values.update(dict.fromkeys((p for p in params if p.name == key), val))
            continue
        sym = by_name.get(key) if isinstance(key, str) else key
        if sym not in params and isinstance(key, sp.Symbol):
            sym = by_name.get(key.name)  # the same name with other assumptions: the same parameter
        if sym not in params:
            problems.append(
                f"unknown parameter `{key}` (the model's are: {', '.join(by_name) or 'none'})"
            )
            continue
        values[sym] = val
    missing = [p.name for p in params if p not in values]
    if missing:
        problems.append(f"missing value for {', '.join(f'`{m}`' for m in missing)}")
    out = []
    for p in params:
        if p not in values:
            continue
        v = values[p]
        if isinstance(v, str | bytes):
            problems.append(f"parameter `{p}` must be a real number, got the string {v!r}")
            continue
        if isinstance(v, bool | np.bool_):  # float(True) is 1.0: a slip, not a value
            problems.append(f"parameter `{p}` must be a real number, got the boolean {v!r}")
            continue
        if isinstance(v, complex | np.complexfloating) or np.ndim(v) != 0:
            # float() of a NumPy complex drops the imaginary part; of a 1-element array, the array
            problems.append(f"parameter `{p}` must be a real number, got {v!r:.80}")
            continue
        try:
            fv = float(sp.sympify(v)) if isinstance(v, sp.Basic) else float(v)
        except (TypeError, ValueError):
            problems.append(f"parameter `{p}` must be a real number, got {v!r:.80}")
            continue
        if not math.isfinite(fv):
            problems.append(f"parameter `{p}` is {fv} (NaN or infinite)")
        out.append(fv)
    if problems:
        raise ParameterError("bad parameters: " + "; ".join(problems))
    return out


def check_masses(eom: Derivation, values: Sequence[float]) -> None:
    """Refuse particle masses that are not positive with these parameter values.

    ``add_particle`` checks a numeric mass; a mass given by parameters (``m``, ``rho*V``) is
    known only here. Each distinct mass expression is evaluated once (a ring of N particles of
    mass M/N: one evaluation). Negative inertia from kinetic-energy terms is caught by the
    inertia check at the first state (``check_determined``).
    """
    system = getattr(eom, "system", None)
    if system is None:  # equations given as matrices: no particles
        return
    subs = dict(zip(eom.parameters, (sp.Float(v) for v in values), strict=True))
    first: dict[sp.Expr, str] = {}
    for piece in system.pieces:
        if piece.kind == "particle" and not piece.exprs[0].is_number:
            first.setdefault(piece.exprs[0], piece.name)
    problems = []
    for mass, name in first.items():
        try:
            value = complex(mass.xreplace(subs))
        except (TypeError, ValueError):  # zoo, nan: not a number at all
            value = complex(math.nan)
        if value.imag == 0 and math.isfinite(value.real) and value.real > 0:
            continue
        given = ", ".join(
            f"`{s.name}` = {float(subs[s]):g}"
            for s in sorted(mass.free_symbols, key=lambda s: s.name)
            if s in subs
        )
        shown = f"{value.real:g}" if value.imag == 0 else f"{value:g}"
        problems.append(f"particle `{name}` has mass {mass} = {shown} with parameter {given}")
    if problems:
        raise ParameterError(
            "particle masses must be positive (finite and real): " + "; ".join(problems)
        )


def model_parameter_values(eom: Derivation, given: dict) -> list[float]:
    """:func:`parameter_values` of ``eom``'s parameters, with the particle masses they give checked."""
    values = parameter_values(tuple(eom.parameters), given)
    check_masses(eom, values)
    return values


def block_columns(block: Block) -> list:
    """Per local coordinate: an :class:`Index` (progression) or an index array."""
    if block.family:
        return [Index(s, d, block.n_inst) for s, d in block.progressions or []]
    return [Index.of(block.coords[:, a]) for a in range(block.coords.shape[1])]


def _kernel(
    cols: list,
    exprs: list | Callable[[], list],
    params: Sequence,
    values: Sequence[float],
    count: int,
    summed: list[bool] | None = None,
    lazy: bool = False,
) -> StreamKernel:
    """A template's kernel; ``lazy``: its code generated on first use."""
    make = _Code(len(cols), exprs, tuple(params), tuple(values), count, summed)
    return StreamKernel(cols, make if lazy else make(), count)


class _Code:
    """A template kernel's code, generated when called (:func:`stream_code`). An object, not a
    closure, so that a model pickles with its kernels not yet generated: a sweep's worker makes
    only those it uses."""

    def __init__(
        self, k: int, exprs: list | Callable[[], list], params: tuple, values: tuple,
        count: int, summed: list[bool] | None,
    ) -> None:  # fmt: skip
        self.k, self.exprs, self.params, self.values = k, exprs, params, values
        self.count, self.summed = count, summed

    def __call__(self) -> StreamCode:
        outs = self.exprs() if callable(self.exprs) else self.exprs  # the entries on demand
        return stream_code(self.k, outs, self.params, self.values, self.count, self.summed)


class _DynEntries:
    """The upper mass entries and the forcing entries of a dynamics template, read when called."""

    def __init__(self, loc: object, upper: list, fidx: list) -> None:
        self.loc, self.upper, self.fidx = loc, upper, fidx

    def __call__(self) -> list:
        loc = self.loc
        forcing = loc.forcing  # type: ignore[attr-defined]
        return [loc.mass.get(ab, sp.S.Zero) for ab in self.upper] + [  # type: ignore[attr-defined]
            forcing.get(a, sp.S.Zero) for a in self.fidx
        ]


class _EnergyKernels:
    """``energy_kernel(which)`` of :class:`pfaff.numeric.parts.DynStreams` (picklable)."""

    def __init__(self, block: Block, cols: list, params: tuple, values: tuple) -> None:
        self.block, self.cols, self.params, self.values = block, cols, params, values

    def __call__(self, which: str) -> StreamKernel:
        block, cols = self.block, self.cols
        T, V = energy_exprs(block)
        parts = power_exprs(block) if which == "power" else [T, V]
        if which == "energies":
            k = len(cols)
            T0 = T.xreplace({local_qd(a): 0 for a in range(k)})
            Tneg = T.xreplace({local_qd(a): -local_qd(a) for a in range(k)})
            parts += [T0, (T + Tneg) / 2 - T0]
        return _kernel(cols, parts, self.params, self.values, block.n_inst, [True] * len(parts))


def dyn_streams(
    block: Block,
    params: Sequence[sp.Symbol],
    values: Sequence[float],
    lazy: bool = False,
    inputs: frozenset[str] = frozenset(),
) -> DynStreams:
    """The stream parts of a dynamics block: M is symmetric, so only entries a <= b are made.

    ``lazy``: the kernels' code is generated on first use (general models, whose fused kernel
    may serve every evaluation: half of ``compile()`` on the 14-link pendulum on a cart).
    ``inputs``: the names of parameters whose values come per call or per run (their value here
    says nothing of whether the block's forces do work)."""
    loc = block.local
    if block.family:  # the SymPy entries (exact cancellations found) set the pattern
        upper = sorted(ab for ab in loc.mass if ab[0] <= ab[1])
        fidx = sorted(loc.forcing)
    else:  # the pattern without converting SymEngine's entries (LazyEntries)
        upper = sorted(ab for ab in raw_keys(loc.mass) if ab[0] <= ab[1])
        fidx = sorted(set(loc.Q) | set(raw_keys(loc.h)))
    cols = block_columns(block)
    rows = [cols[a] for a in fidx]
    summed = [False] * len(upper) + [isinstance(ix, Index) and ix.fixed for ix in rows]

    kernel = _kernel(
        cols, _DynEntries(loc, upper, fidx), params, values, block.n_inst, summed, lazy
    )
    energy_kernel = _EnergyKernels(block, cols, tuple(params), tuple(values))
    upper_streams = [(cols[a], cols[b], a != b) for a, b in upper]
    power = does_work(loc.Q, params, values, inputs)
    return DynStreams(kernel, upper_streams, rows, energy_kernel, has_power=power)


def does_work(
    Q: dict, params: Sequence[sp.Symbol], values: Sequence[float], inputs: frozenset[str]
) -> bool:
    """Whether a template's applied forces ``Q`` can do work at these parameter values: not
    when every entry vanishes with the values put in (a push of F = 0), so that a run does not
    integrate a power that is identically zero (issue 25: the 8-link chain on a cart ran 1.69×
    faster built without its zero push). Inputs keep their symbols.

    Examples
    --------
    >>> import sympy as sp
    >>> F, q = sp.symbols("F q")
    >>> does_work({0: F * sp.cos(q)}, [F], [0.0], frozenset()), does_work({0: F}, [F], [2.0], frozenset())
    (False, True)
    >>> does_work({0: F}, [F], [0.0], frozenset({"F"}))  # an input: its value comes later
    True
    """
    if not Q:
        return False
    fixed = {p: v for p, v in zip(params, values, strict=True) if p.name not in inputs}
    return any(sp.sympify(e).xreplace(fixed) != 0 for e in Q.values())


def con_streams(
    block: Block, params: Sequence[sp.Symbol], values: Sequence[float], lazy: bool = False
) -> ConStreams:
    """The stream parts of a constraint block: ``acc`` for the solve, ``res`` for residuals."""
    cols_local, exprs = constraint_layout(block)
    cols = block_columns(block)
    rows = Index(block.row0, 1, block.n_inst) if block.family else Index.of(block.rows)
    na = len(cols_local)
    acc = _kernel(cols, [*exprs[:na], exprs[na + 1]], params, values, block.n_inst, lazy=lazy)
    res = _kernel(cols, exprs, params, values, block.n_inst, lazy=lazy)
    return ConStreams(rows, [cols[a] for a in cols_local], acc, res)


def build_model(
    eom: Derivation,
    values: list[float],
    *,
    constraints_only: bool = False,
    solver: str | None = None,
    evaluator: str | None = None,
    inputs: Sequence[str] = (),
    timings: dict | None = None,
    contacts: Callable | None = None,
) -> NumericModel:
    """Assemble a :class:`NumericModel` from the blocks of ``eom`` and ordered parameter values,
    in one place: the stream parts, the fused kernel of a small system (checked by the model
    once, :mod:`pfaff.numeric.general`), the attitude sets, the events, the geometry, the linearization
    factory and the way to other parameter values. ``evaluator``: see
    :mod:`pfaff.numeric.evaluator`. ``contacts(eom, values)``: the model's unilateral
    constraints (:func:`pfaff.derive.contacts.compile_contacts`), or None.
    """
    params = tuple(eom.parameters)
    dyn = (
        []
        if constraints_only
        else [
            dyn_streams(b, params, values, lazy=True, inputs=frozenset(inputs))
            for b in eom.blocks
            if b.local.kind == "dynamics"
        ]
    )
    con = [
        con_streams(b, params, values, lazy=True)
        for b in eom.blocks
        if b.local.kind == "constraint"
    ]
    timings = dict(timings or {})
    fused, missing = None, "the system is too large or has no dynamics for one"
    n, m = eom.n, eom.m
    if solver is not None and solver != "range-space":
        missing = f"the solver is {solver!r} (the fused kernel's solve is range-space)"
    elif not constraints_only and n + m <= DENSE_LIMIT and evaluator != "template":
        start = time.process_time()
        fused, status = fused_kernel(eom)
        timings["codegen"] = time.process_time() - start
        timings["cache"] = status
        if fused is None:
            missing = (
                f"its generation {status}"
                if status.startswith("failed")
                else "the system is too large for it or uses a function its printer lacks"
            )
    elif evaluator == "template":
        missing = ""
    return NumericModel(
        n,
        m,
        dyn,
        con,
        coordinate_names=[str(q.func) for q in eom.coordinates],
        multiplier_names=[str(s) for s in eom.multipliers],
        constraint_names=list(eom.constraint_names),
        holonomic=np.array(eom.holonomic, dtype=bool),
        parameters={p.name: v for p, v in zip(params, values, strict=True)},
        solver=solver,
        fused=fused,
        fused_missing=missing,
        evaluator=evaluator,
        inputs=inputs,
        attitudes=attitude_sets(eom),
        events=compile_events(eom, params, values),  # System.add_event, found by simulate
        contacts=None if constraints_only or contacts is None else contacts(eom, values),
        geometry=None if constraints_only else build_geometry(eom, values),  # animations
        linearizer=None if constraints_only else linearizer_for(eom),  # NumericModel.linearize
        restream=Restream(eom, params, constraints_only),  # for model.with_parameters
        timings=timings,
    )


def attitude_sets(eom: Derivation) -> list[tuple[str, str, tuple[int, ...], str]]:
    """Per rigid body: (name, kind of attitude set, coordinate indices, Euler sequence or "")."""
    system = getattr(eom, "system", None)
    out = []
    for body in getattr(system, "bodies", ()):
        att = body.attitude
        idx = tuple(system._index[q] for q in att.coordinates)
        out.append((body.name, att.kind, idx, getattr(att, "sequence", "")))
    return out


_FUSED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def fused_kernel(eom: Derivation) -> tuple[FusedKernel | None, str]:
    """The fused kernel of ``eom`` (generated once per derivation while a model holds it: it takes
    the parameter values at run time, so compiling again with other values, a sweep, reuses it)
    and where it came from: ``"reused"``, or the on-disk cache's ``"hit"``, ``"miss"``, ``"off"``.
    (The kernel refers to ``eom`` for its machine code; the table refers to the kernel weakly.)"""
    ref = _FUSED.get(eom)
    fused = ref() if ref is not None else None
    if fused is not None:
        return fused, "reused"
    try:
        fused, status = build_fused(eom)
    except Exception as e:
        # a function the math module lacks (Piecewise, ...): the template kernels evaluate
        fused, status = None, f"failed: {type(e).__name__}: {str(e)[:200]}"
    if fused is not None:
        _FUSED[eom] = weakref.ref(fused)
    return fused, status


def input_names(eom: Derivation) -> list[str]:
    """The names of the inputs declared on ``eom``'s system (``System.add_input``)."""
    return [sym.name for sym in getattr(getattr(eom, "system", None), "inputs", ())]


def compile_equations(
    eom: Derivation,
    parameters: dict,
    *,
    solver: str | None = None,
    evaluator: str | None = None,
    contacts: Callable | None = None,
) -> NumericModel:
    """Check ``parameters`` against the model's symbols and compile (see pfaff.EquationsOfMotion.compile)."""
    start = time.process_time()
    inputs = input_names(eom)
    used = {p.name for p in eom.parameters}
    if isinstance(parameters, dict):  # inputs take their values per call or per run: 0 here
        given = {k.name if isinstance(k, sp.Symbol) else k for k in parameters}
        parameters = {**{i: 0.0 for i in inputs if i in used and i not in given}, **parameters}
    timings = {}
    if "equations" in getattr(eom, "timings", {}):
        timings["equations"] = eom.timings["equations"]
    values = model_parameter_values(eom, parameters)
    made = None if contacts is None else (lambda e, v: contacts(e, v, solver, evaluator))
    model = build_model(
        eom, values, solver=solver, evaluator=evaluator, inputs=inputs, timings=timings,
        contacts=made,
    )  # fmt: skip
    model.timings["compile"] = time.process_time() - start
    return model


class Restream:
    """The stream parts of a compiled model for other parameter values
    (:meth:`pfaff.NumericModel.with_parameters`): each template whose expressions use a changed
    parameter gets new kernels (lazy: generated on first use); the others are shared."""

    def __init__(
        self, eom: Derivation, params: tuple, constraints_only: bool, lazy: bool = True
    ) -> None:
        self.params, self.constraints_only, self.lazy = params, constraints_only, lazy
        self.inputs = frozenset(input_names(eom))
        self.dyn = [] if constraints_only else [b for b in eom.blocks if b.local.kind == "dynamics"]
        self.con = [b for b in eom.blocks if b.local.kind != "dynamics"]
        self._uses: tuple[list, list] | None = None

    def uses(self) -> tuple[list[frozenset], list[frozenset]]:
        """Per dynamics and per constraint block: the indices of the parameters it uses."""
        if self._uses is None:
            index = {p.name: i for i, p in enumerate(self.params)}

            def used(exprs: list) -> frozenset:
                names = {str(s) for e in exprs for s in sp.sympify(e).free_symbols}
                return frozenset(index[x] for x in names if x in index)

            loc = [b.local for b in self.dyn]
            dyn_exprs = [
                [*x.mass.values(), *x.forcing.values(), *energy_exprs(b), *power_exprs(b)]
                for b, x in zip(self.dyn, loc, strict=True)
            ]
            con_exprs = [constraint_layout(b)[1] for b in self.con]
            self._uses = ([used(e) for e in dyn_exprs], [used(e) for e in con_exprs])
        return self._uses

    def __call__(self, old: list, new: list, dyn: list, con: list) -> tuple[list, list]:
        changed = {i for i, (a, b) in enumerate(zip(old, new, strict=True)) if a != b}
        du, cu = self.uses()
        p = self.params
        dyn = [
            dyn_streams(b, p, new, lazy=self.lazy, inputs=self.inputs) if u & changed else d
            for b, u, d in zip(self.dyn, du, dyn, strict=True)
        ]
        con = [
            con_streams(b, p, new, lazy=self.lazy) if u & changed else c
            for b, u, c in zip(self.con, cu, con, strict=True)
        ]
        return dyn, con
