"""The compile stage: parameter values checked, kernels generated, a :class:`NumericModel` built."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import sympy as sp

from pfaff.core.errors import ParameterError
from pfaff.derive.blocks import Block
from pfaff.derive.codegen import (
    Kernel,
    constraint_layout,
    dynamics_layout,
    energy_exprs,
    make_kernel,
    power_exprs,
)
from pfaff.derive.fused import build_fused
from pfaff.numeric.model import ConstraintPart, DynamicsPart, NumericModel

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


def _cached(block: Block, what: str, params: tuple, build) -> Kernel:
    cache = block.__dict__.setdefault("_kernels", {})
    key = (what, params)
    if key not in cache:
        cache[key] = build()
    return cache[key]


def dynamics_part(block: Block, params: tuple) -> DynamicsPart:
    """Kernel and scatter indices for a dynamics block."""
    mass, fidx, exprs = dynamics_layout(block)
    kern = _cached(block, "dyn", params, lambda: make_kernel(block, exprs, params))
    energy = _cached(
        block, "energy", params, lambda: make_kernel(block, energy_exprs(block), params)
    )
    c = block.coords
    mr = np.array([c[:, a] for a, _ in mass], dtype=np.int64).reshape(len(mass), c.shape[0])
    mc = np.array([c[:, b] for _, b in mass], dtype=np.int64).reshape(len(mass), c.shape[0])
    fr = np.array([c[:, a] for a in fidx], dtype=np.int64).reshape(len(fidx), c.shape[0])
    pexprs = power_exprs(block)
    power = (
        _cached(block, "power", params, lambda: make_kernel(block, pexprs, params))
        if pexprs
        else None
    )
    return DynamicsPart(kern, mr, mc, fr, energy, power)


def constraint_part(block: Block, params: tuple) -> ConstraintPart:
    """Kernel and scatter indices for a constraint block."""
    cols, exprs = constraint_layout(block)
    kern = _cached(block, "con", params, lambda: make_kernel(block, exprs, params))
    c = block.coords
    ac = np.array([c[:, a] for a in cols], dtype=np.int64).reshape(len(cols), c.shape[0])
    return ConstraintPart(kern, block.rows, ac)


def build_model(
    eom: Derivation,
    values: list[float],
    *,
    constraints_only: bool = False,
    solver: str | None = None,
) -> NumericModel:
    """Assemble a :class:`NumericModel` from the blocks of ``eom`` and ordered parameter values.

    Small systems also get the fused scalar kernel (:mod:`pfaff.derive.fused`), which the model
    takes only if it agrees with the template kernels (:meth:`NumericModel.use_fused`).
    """
    params = tuple(eom.parameters)
    dyn = (
        []
        if constraints_only
        else [dynamics_part(b, params) for b in eom.blocks if b.local.kind == "dynamics"]
    )
    con = [constraint_part(b, params) for b in eom.blocks if b.local.kind == "constraint"]
    names = {
        "coordinates": [str(q.func) for q in eom.coordinates],
        "multipliers": [str(s) for s in eom.multipliers],
        "constraints": list(eom.constraint_names),
        "holonomic_rows": np.array(eom.holonomic, dtype=bool),
        "parameters": {p.name: v for p, v in zip(params, values, strict=True)},
    }
    model = NumericModel(eom.n, dyn, con, eom.m, values, names, solver=solver)
    if not constraints_only and model.solver == "range-space":
        try:
            fused = build_fused(eom)
        except Exception:  # a function the math module lacks (Piecewise, ...): keep the templates
            fused = None
        if fused is not None:
            model.use_fused(fused)
    return model


def compile_equations(
    eom: Derivation, parameters: dict, *, solver: str | None = None
) -> NumericModel:
    """Check ``parameters`` against the model's symbols and compile (see pfaff.EquationsOfMotion.compile)."""
    return build_model(eom, model_parameter_values(eom, parameters), solver=solver)
