"""The reduction stage: equations of motion in minimal (independent) coordinates.

Dependent coordinates are eliminated by back-substitution where the holonomic constraints can be
solved for them one at a time (q_d = φ(q_i, t)); otherwise their velocities are solved from the
Pfaffian constraints, q̇_d = N_d(q, t) q̇_i + n_0. Either way q̇ = N q̇_i + n_0, and the equations are
projected on the admissible velocities:

    (Nᵀ M N) q̈_i + Nᵀ (h + M ν) = Nᵀ Q,    ν = Ṅ q̇_i + ṅ_0,

which eliminates the multipliers because N spans the null space of A (A N = 0).
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ConstraintError, ModelError, ModelTypeError
from pfaff.core.symbols import as_expr, t
from pfaff.derive.equations import Derivation
from pfaff.derive.templates import derive
from pfaff.mechanics.system import SystemSpec

ZERO_DIGITS = 40  # numeric constants that vanish to this many digits are exact zeros


def _split_angle(arg: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
    const, var = arg.as_independent(*arg.free_symbols, as_Add=True)
    return var, const


def _expand_shifted_trig(e: sp.Expr) -> sp.Expr:
    """cos(u + c) -> cos u cos c - sin u sin c (and sin alike) for numeric constants c."""

    def cos_(arg: sp.Expr) -> sp.Expr:
        u, c = _split_angle(arg)
        if c == 0 or not u.free_symbols:
            return sp.cos(arg)
        return sp.cos(u) * sp.cos(c) - sp.sin(u) * sp.sin(c)

    def sin_(arg: sp.Expr) -> sp.Expr:
        u, c = _split_angle(arg)
        if c == 0 or not u.free_symbols:
            return sp.sin(arg)
        return sp.sin(u) * sp.cos(c) + sp.cos(u) * sp.sin(c)

    return e.replace(sp.cos, cos_).replace(sp.sin, sin_)


def _clean_constant(c: sp.Expr) -> sp.Expr:
    if c.is_Rational:
        return c
    val = c.evalf(ZERO_DIGITS + 10)
    if abs(val) < sp.Float(10) ** (-ZERO_DIGITS):
        return sp.S.Zero
    rat = sp.Rational(str(val)).limit_denominator(10**6)
    if abs(val - rat) < sp.Float(10) ** (-ZERO_DIGITS):
        return rat
    return c


def tidy(e: sp.Expr) -> sp.Expr:
    """Simplify a *small* expression, recognising numeric constants that vanish.

    Sums such as Σ_k cos(θ + 2πk/N) are exact zeros that SymPy does not see. Shifted angles are
    expanded, terms are grouped by their symbolic part, and each numeric coefficient is evaluated to
    50 digits: a coefficient below 1e-40 is dropped and one within 1e-40 of a simple rational is
    replaced by it. Then ``trigsimp`` combines sin² + cos² where the expression is small.

    Examples
    --------
    >>> import sympy as sp
    >>> th = sp.Symbol("theta")
    >>> tidy(sum(sp.cos(th + 2 * sp.pi * k / 64) for k in range(64)))
    0
    """
    e = sp.expand(_expand_shifted_trig(sp.sympify(e)))
    groups: dict[sp.Expr, list[sp.Expr]] = defaultdict(list)
    for term in sp.Add.make_args(e):
        const, rest = [], []
        for f in sp.Mul.make_args(term):
            (rest if f.free_symbols else const).append(f)
        groups[sp.Mul(*rest)].append(sp.Mul(*const))
    out = sp.Add(*(_clean_constant(sp.Add(*cs)) * rest for rest, cs in groups.items()))
    if out.has(sp.sin, sp.cos) and sp.count_ops(out) <= 120:
        s = sp.trigsimp(out)
        if sp.count_ops(s) <= sp.count_ops(out):
            out = s
    return sp.factor_terms(out)


def _check_solutions(eom: Derivation, phi: dict, given: dict) -> None:
    """The given branches must satisfy the holonomic constraints: checked numerically at a few
    random points (coordinates, parameters and t), where every term is real."""
    if not given:
        return
    rng = np.random.default_rng(20261124)
    for f in (f for f in eom.holonomic_constraints if f is not None):
        r = f.xreplace(phi)
        free = sorted(r.free_symbols | r.atoms(AppliedUndef), key=sp.default_sort_key)
        checked = 0
        for _ in range(20):
            point = {s: sp.Float(rng.uniform(0.2, 0.6)) for s in free}
            point.update({s: sp.Float(rng.uniform(1.5, 2.5)) for s in free if s in eom.parameters})
            try:
                v = complex(r.xreplace(point).evalf())
            except (TypeError, ValueError):
                continue
            if abs(v.imag) > 1e-9:
                continue
            checked += 1
            if abs(v.real) > 1e-8:
                raise ConstraintError(
                    f"`solutions` {given} do not satisfy the constraint {f} = 0 "
                    f"(residual {v.real:.3g} at a test point)"
                )
            if checked >= 3:
                break


def _solve_positions(eom: Derivation, dependent: list, solutions: dict) -> dict[sp.Expr, sp.Expr]:
    """Back-substitution: solve holonomic constraints one dependent coordinate at a time."""
    phi = dict(solutions)
    dep = set(dependent)
    pending = [f for f in eom.holonomic_constraints if f is not None]
    progress = True
    while progress and pending and len(phi) < len(dep):
        progress = False
        for f in list(pending):
            fs = f.xreplace(phi)
            unknown = [d for d in fs.atoms(AppliedUndef) if d in dep and d not in phi]
            if not unknown:
                pending.remove(f)
                continue
            if len(unknown) > 1:
                continue
            d = unknown[0]
            a = fs.diff(d)
            if a != 0 and not a.has(d):
                sol = [sp.expand(-fs.xreplace({d: sp.S.Zero}) / a)]
            else:
                sol = sp.solve(fs, d)
            if len(sol) == 1:
                phi[d] = sol[0]  # in independent coordinates only: fs had phi substituted
                pending.remove(f)
                progress = True
    return phi


def reduce(system: SystemSpec, independent: object, *, solutions: dict | None = None) -> Derivation:
    """Equations of motion of ``system`` in the independent coordinates ``independent``.

    Parameters
    ----------
    system : SystemSpec
    independent : sequence of Function
        The n - m coordinates to keep.
    solutions : dict, optional
        Explicit q_d = φ(q_i, t) for dependents whose constraint has several roots (a branch choice,
        e.g. ``{y: -sp.sqrt(L**2 - x**2)}`` for a hanging pendulum).

    Returns
    -------
    Derivation
        Unconstrained: M_red (k×k) q̈_i + h_red = Q_red. When every dependent coordinate was
        eliminated its ``extra["dependent"]`` maps q_d -> φ_d(q_i, t); otherwise the expressions
        still contain the remaining dependents and ``extra["dependent_velocities"]`` gives
        q̇_d = N_d q̇_i + n_0 (projection form; not compilable yet).

    Examples
    --------
    >>> import pfaff
    >>> ring = pfaff.models.rolling_ring(6, force=True)
    >>> red = ring.reduce([ring.coordinates[1]])
    >>> red.lagrange_equations[0]
    Eq(2*M*r**2*Derivative(theta1(t), (t, 2)), F*r)
    """
    eom = derive(system)
    if eom.redundant_sets:
        named = "; ".join(", ".join(f"`{c}`" for c in x) for x in eom.redundant_sets)
        raise ConstraintError(
            f"reduce needs independent constraints, and {named} depend on one another: drop the "
            "dependent ones (the numeric model keeps the independent rows by itself)"
        )
    coords = list(eom.coordinates)
    ind = [independent] if isinstance(independent, sp.Basic) else list(independent)
    bad = [str(q) for q in ind if q not in coords]
    if bad:
        raise ModelError(f"`independent` names {', '.join(bad)}, not coordinates of this system")
    if len(set(ind)) != len(ind):
        raise ModelError("`independent` lists a coordinate twice")
    dependent = [q for q in coords if q not in ind]
    if len(dependent) != eom.m:
        raise ConstraintError(
            f"{eom.n} coordinates with {eom.m} constraints leave {eom.n - eom.m} independent ones; "
            f"{len(ind)} were named"
        )
    if solutions is not None and not isinstance(solutions, dict):
        raise ModelTypeError(f"`solutions` must be a dict q_d -> φ(q_i, t), got {solutions!r:.80}")
    solutions = {k: as_expr(v, f"`solutions[{k}]`") for k, v in (solutions or {}).items()}
    for k, v in solutions.items():
        if k not in dependent:
            raise ModelError(f"`solutions` key {k} is not a dependent coordinate")
        if any(d in dependent for d in v.atoms(AppliedUndef)):
            raise ModelError(f"`solutions[{k}]` = {v} must be in the independent coordinates only")
    phi = _solve_positions(eom, dependent, solutions)
    _check_solutions(eom, phi, solutions)
    ind_speeds = [q.diff(t) for q in ind]
    vel: dict[sp.Expr, sp.Expr] = {q.diff(t): q.diff(t) for q in ind}
    for d, e in phi.items():
        vel[d.diff(t)] = e.diff(t)
    unsolved = [d for d in dependent if d not in phi]
    if unsolved:
        vel.update(_solve_speeds(eom, phi, vel, unsolved))
    subs = {**vel, **phi}
    nmat = [[sp.expand(vel[q.diff(t)]).coeff(u) for u in ind_speeds] for q in coords]
    accel_rule = {q.diff(t, 2): sp.S.Zero for q in ind}
    nu = []
    for q in coords:
        a = vel[q.diff(t)].diff(t).xreplace(accel_rule)
        nu.append(a.xreplace({d.diff(t): vel[d.diff(t)] for d in unsolved}))
    k = len(ind)
    Mfull = eom._mass_entries
    Msub = {jk: e.xreplace(subs) for jk, e in Mfull.items()}
    Mred = sp.zeros(k, k)
    hred = sp.zeros(k, 1)
    Qred = sp.zeros(k, 1)
    hq = [e.xreplace(subs) for e in eom._h_list]
    Qq = [e.xreplace(subs) for e in eom._Q_list]
    inertia_bias = [[] for _ in coords]
    for (j, c), e in Msub.items():
        inertia_bias[j].append(e * nu[c])
    for a in range(k):
        hred[a] = tidy(
            sp.Add(*(nmat[j][a] * (hq[j] + sp.Add(*inertia_bias[j])) for j in range(len(coords))))
        )
        Qred[a] = tidy(sp.Add(*(nmat[j][a] * Qq[j] for j in range(len(coords)))))
        for b in range(k):
            Mred[a, b] = tidy(sp.Add(*(nmat[j][a] * e * nmat[c][b] for (j, c), e in Msub.items())))
    extra = {"dependent": phi, "independent": ind}
    if unsolved:
        extra["dependent_velocities"] = {d.diff(t): vel[d.diff(t)] for d in unsolved}
    return Derivation.from_matrices(
        tuple(ind),
        Mred,
        hred,
        Qred,
        kinetic=tidy(eom.kinetic_energy.xreplace(subs)),
        potential=tidy(eom.potential_energy.xreplace(subs)),
        parameters=eom.parameters,
        extra=extra,
    )


def _solve_speeds(eom: Derivation, phi: dict, vel: dict, unsolved: list) -> dict:
    """q̇_d for dependents without a position solution, from the Pfaffian constraints."""
    speeds = [d.diff(t) for d in unsolved]
    eqs = []
    A, b = eom.constraint_matrix, eom.constraint_bias
    qd = sp.Matrix([q.diff(t) for q in eom.coordinates])
    known = {k: v for k, v in vel.items() if k not in speeds}
    for i in range(eom.m):
        row = (A[i, :] * qd)[0] + b[i]
        eqs.append(sp.expand(row.xreplace(known).xreplace(phi)))
    sol = sp.solve(eqs, speeds, dict=True)
    if len(sol) != 1 or any(s not in sol[0] for s in speeds):
        raise ConstraintError(
            "the constraints do not determine the velocities of "
            f"{', '.join(map(str, unsolved))} from the independent ones: choose other independent "
            "coordinates"
        )
    return {s: sp.factor_terms(sol[0][s]) for s in speeds}
