"""The derivation stage: per-template Lagrange terms, grouped into blocks.

For each distinct local form (template) of a model piece the terms of

    M q̈ + h = Q + Aᵀλ,    A q̈ + (Ȧ q̇ + ḃ) = 0

are derived once, in local placeholder coordinates. A particle of mass m at r(q,t) contributes
M = m JᵀJ and h = m Jᵀ(J̇ q̇ + ṙ_t) with J = ∂r/∂q; a Lagrangian term L contributes M = ∂²L/∂q̇²,
h = (∂²L/∂q̇∂q) q̇ + ∂²L/∂q̇∂t - ∂L/∂q; a force F at r contributes Q = Jᵀ F. Nothing is ever
differentiated or simplified at the size of the whole system.
"""

from __future__ import annotations

import time

import numpy as np
import sympy as sp

from pfaff.core.errors import ModelError
from pfaff.core.symbols import local_q, local_qd, t
from pfaff.derive.blocks import Block, LazyEntries, Local
from pfaff.derive.engine import Engine, Plain, algebra
from pfaff.derive.equations import Derivation, bounded_nodes
from pfaff.derive.memory import check_memory
from pfaff.derive.rank import check_constraint_rank
from pfaff.mechanics.system import Piece, SystemSpec

TIDY_NODES = 160  # expressions up to this many nodes are tidied


def _tidy(e: sp.Expr) -> sp.Expr:
    """A cheap, bounded clean-up per template entry: sin²u + cos²u = 1.

    Each sin(u)² becomes 1 − cos(u)² and the result is expanded, kept when it has no more nodes
    than the original: a ring particle's m r²(sin²θ + cos²θ) becomes the constant m r² (which the
    numeric stage then never evaluates per instance). Nothing else is simplified: ``trigsimp``
    and ``fu`` took 98 % of ``equations()`` on the 4-link pendulum on a cart (8.2 s of 8.3 s)
    and bought no run-time speed; expressions over ``TIDY_NODES`` nodes are left alone, and
    size is a bounded walk (``count_ops`` cost half a millisecond per entry).
    """
    if not e.has(sp.sin):
        return e
    n = bounded_nodes(e, TIDY_NODES)
    if n > TIDY_NODES:
        return e
    rep = {
        p: 1 - sp.cos(p.base.args[0]) ** 2
        for p in e.atoms(sp.Pow)
        if p.base.func is sp.sin and p.exp == 2
    }
    if not rep:
        return e
    s = sp.expand(e.xreplace(rep))
    return s if bounded_nodes(s, n + 1) <= n else e


def _qs(k: int) -> tuple[list[sp.Symbol], list[sp.Symbol]]:
    return [local_q(a) for a in range(k)], [local_qd(a) for a in range(k)]


def dt_bias(e: sp.Expr, k: int) -> sp.Expr:
    """Time derivative of e(q, q̇, t) with q̈ = 0: Σ ∂e/∂q_a q̇_a + ∂e/∂t."""
    q, qd = _qs(k)
    return sp.Add(*(e.diff(q[a]) * qd[a] for a in range(k)), e.diff(t))


def _particle(key: tuple, k: int) -> Local:
    """A particle's M, h and T, differentiated in SymEngine when its expressions allow.

    SymEngine takes 4 ms where SymPy takes 210 ms for the 20th bob of the 20-link pendulum on a
    cart (21 coordinates); the results come back to SymPy (60 ms), which the rest of the
    derivation reads. Expressions with functions SymEngine does not share with SymPy, or
    symbols it cannot carry, are derived in SymPy (:func:`pfaff.derive.engine.algebra`).
    """
    m, r = key[2], key[3:]
    return _particle_in(algebra([m, *r]), m, r, k)


def _particle_in(alg: Engine | Plain, m: sp.Expr, r: tuple, k: int) -> Local:
    """:func:`_particle` in the algebra ``alg`` (SymEngine or SymPy), results in SymPy."""
    q, qd = alg.placeholders(k)
    M, R, T = alg.to(m), [alg.to(rc) for rc in r], alg.t
    J = [[rc.diff(q[a]) for a in range(k)] for rc in R]
    v = [
        alg.add([*(Jc[a] * qd[a] for a in range(k)), rc.diff(T)])
        for Jc, rc in zip(J, R, strict=True)
    ]
    acc = [alg.add([*(vc.diff(q[a]) * qd[a] for a in range(k)), vc.diff(T)]) for vc in v]
    kinetic = M * alg.add([vc**2 for vc in v]) / 2
    loc = Local("dynamics", k, kinetic=alg.back(kinetic))
    kept = _Kept(alg, loc, kinetic=kinetic)
    for a in range(k):
        for b in range(a, k):
            kept.mass(a, b, M * alg.add([Jc[a] * Jc[b] for Jc in J]), symmetric=True)
        kept.h(a, M * alg.add([Jc[a] * ac for Jc, ac in zip(J, acc, strict=True)]))
    return loc


class _Back:
    """SymEngine's entries back to SymPy, tidied (a class, not a closure: models pickle)."""

    def __init__(self, alg: Engine) -> None:
        self.alg = alg

    def __call__(self, raw: object) -> object:
        return _tidy(self.alg.back(raw))


class _Kept:
    """Stores a template's entries: in SymEngine (``loc.engine``) as SymEngine made them, and
    in SymPy (tidied, zeros dropped) converted lazily (:class:`pfaff.derive.blocks.LazyEntries`)
    when the algebra is SymEngine; in SymPy at once otherwise."""

    def __init__(self, alg: Engine | Plain, loc: Local, **energies: object) -> None:
        self.alg, self.loc = alg, loc
        self.lazy = isinstance(alg, Engine)
        if self.lazy:
            loc.engine = {"mass": {}, "h": {}, "kinetic": 0, "potential": 0, **energies}
            convert = _Back(alg)
            loc.mass = LazyEntries(loc.engine["mass"], convert)
            loc.h = LazyEntries(loc.engine["h"], convert)

    def mass(self, a: int, b: int, raw: object, *, symmetric: bool = False) -> None:
        keys = [(a, b), (b, a)] if symmetric and a != b else [(a, b)]
        if self.lazy:
            if raw != 0:
                for key in keys:
                    self.loc.engine["mass"][key] = raw
            return
        e = _tidy(self.alg.back(raw))
        if e != 0:
            for key in keys:
                self.loc.mass[key] = e

    def h(self, a: int, raw: object) -> None:
        if self.lazy:
            if raw != 0:
                self.loc.engine["h"][a] = raw
            return
        e = _tidy(self.alg.back(raw))
        if e != 0:
            self.loc.h[a] = e


def _lagrangian(L: sp.Expr, k: int, loc: Local) -> Local:
    """M and h of a kinetic or potential energy term (Lagrange's equations of L), differentiated
    in SymEngine when the expression allows (as :func:`_particle`), else in SymPy."""
    alg = algebra([L])
    q, qd = alg.placeholders(k)
    Ls, T = alg.to(L), alg.t
    energy = {"kinetic": Ls} if loc.potential == 0 else {"potential": -Ls}
    kept = _Kept(alg, loc, **energy)
    for a in range(k):
        p = Ls.diff(qd[a])
        for b in range(k):
            kept.mass(a, b, p.diff(qd[b]))
        kept.h(a, alg.add([*(p.diff(q[b]) * qd[b] for b in range(k)), p.diff(T), -Ls.diff(q[a])]))
    return loc


def _force(key: tuple, k: int) -> Local:
    dim = key[1]
    F, r = key[2 : 2 + dim], key[2 + dim :]
    q, _ = _qs(k)
    loc = Local("dynamics", k)
    for a in range(k):
        e = sp.Add(*(Fc * rc.diff(q[a]) for Fc, rc in zip(F, r, strict=True)))
        if e != 0:
            loc.Q[a] = e
    return loc


def _constraint(key: tuple, k: int) -> Local:
    """A, b, Ȧq̇ + ḃ (and f) of a constraint template, differentiated in SymEngine when the
    expression allows (on the Whipple bicycle SymPy's derivatives of the contact constraints
    took 1.5 s), the SymEngine forms kept in ``loc.engine`` for code generation."""
    alg = algebra([key[2]])
    q, qd = alg.placeholders(k)
    e, T = alg.to(key[2]), alg.t
    loc = Local("constraint", k)
    if key[0] == "holonomic":
        A = {a: d for a in range(k) if (d := e.diff(q[a])) != 0}
        b = e.diff(T)
        g = alg.add([*(A[a] * qd[a] for a in A), b])
    else:
        A = {a: d for a in range(k) if (d := e.diff(qd[a])) != 0}
        b = (
            e.subs(dict.fromkeys(qd, alg.to(0)))
            if isinstance(alg, Engine)
            else e.xreplace(dict.fromkeys(qd, sp.S.Zero))
        )
        g = e
    bias = alg.add([*(g.diff(q[a]) * qd[a] for a in range(k)), g.diff(T)])
    loc.A = {a: alg.back(d) for a, d in A.items()}
    loc.b, loc.bias = alg.back(b), alg.back(bias)
    loc.f = key[2] if key[0] == "holonomic" else None
    if isinstance(alg, Engine):
        loc.engine = {"A": A, "b": b, "bias": bias, "f": e if key[0] == "holonomic" else None}
    return loc


def derive_template(key: tuple, k: int) -> Local:
    """Derive the local contributions of one template (see the module docstring)."""
    kind = key[0]
    if kind == "particle":
        return _particle(key, k)
    if kind == "kinetic":
        return _lagrangian(key[2], k, Local("dynamics", k, kinetic=key[2]))
    if kind == "potential":
        return _lagrangian(-key[2], k, Local("dynamics", k, potential=key[2]))
    if kind == "force":
        return _force(key, k)
    if kind == "genforce":
        return Local("dynamics", k, Q={key[1]: key[2]})
    if kind == "torque":  # Q_a = τ_body · ∂ω/∂q̇_a
        _, qd = _qs(k)
        tau, w = key[2:5], key[5:8]
        Q = {
            a: sp.Add(*(ti * wi.diff(qd[a]) for ti, wi in zip(tau, w, strict=True)))
            for a in range(k)
        }
        return Local("dynamics", k, Q={a: e for a, e in Q.items() if e != 0})
    if kind == "dissipation":  # Q_a = −∂R/∂q̇_a
        _, qd = _qs(k)
        Q = {a: -key[2].diff(qd[a]) for a in range(k)}
        return Local("dynamics", k, Q={a: e for a, e in Q.items() if e != 0})
    return _constraint(key, k)


def group(system: SystemSpec) -> list[Block]:
    """Group the model's pieces by template and derive each template once."""
    groups: dict[tuple, list[tuple[Piece, int]]] = {}
    row = 0
    cache: dict[tuple, Local] = {}
    blocks = []
    for p in system.pieces:
        is_con = p.kind in ("holonomic", "velocity")
        if p.template is not None:
            blocks.append(_family_block(p, row if is_con else -1, cache))
        else:
            groups.setdefault(p.key, []).append((p, row if is_con else -1))
        row += p.count if is_con else 0
    for key, members in groups.items():
        local = _derived(key, len(members[0][0].coords), cache)
        coords = np.array([p.coords for p, _ in members], dtype=np.int64).reshape(len(members), -1)
        rows = (
            np.array([r for _, r in members], dtype=np.int64)
            if local.kind == "constraint"
            else None
        )
        blocks.append(Block(local, coords, rows, [p for p, _ in members]))
    return blocks


def _derived(key: tuple, k: int, cache: dict) -> Local:
    if key not in cache:
        cache[key] = derive_template(key, k)
    return cache[key]


def _family_block(p: Piece, row0: int, cache: dict) -> Block:
    tm = p.template
    local = _derived(p.key, len(tm.slots), cache)
    prog = [tm.progression(a) for a in range(len(tm.slots))]
    return Block(local, None, None, [p], progressions=prog, n_inst=tm.count, row0=row0)


def derive(system: SystemSpec) -> Derivation:
    """Derive the equations of motion of ``system`` and check its constraints for redundancy."""
    if system.n == 0:
        raise ModelError("a system needs at least one coordinate (ordinary or in a family)")
    start = time.process_time()
    blocks = group(system)  # a family block is its template and index progressions: O(1)
    # before anything of size n: the Derivation's constraint names and flags are per row
    check_memory(system.n, system.n_constraints, blocks)
    eom = Derivation(system, blocks)
    eom.redundant_sets = check_constraint_rank(eom)  # reported (warned), not refused
    eom.timings = {"equations": time.process_time() - start}
    return eom
