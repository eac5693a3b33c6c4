"""The derivation result: Lagrange's equations with multipliers as named SymPy matrices.

:class:`Derivation` holds the blocks the templates were derived into and assembles M, h, Q, A, b and
the bias from them on demand. The user sees it as :class:`pfaff.EquationsOfMotion`, which adds
``compile()`` on top (:mod:`pfaff.api`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
import sympy as sp

from pfaff.core.errors import ConstraintError, PfaffError
from pfaff.core.lazy import LazySeq
from pfaff.core.symbols import accel, local_q, local_qd, speed, t
from pfaff.derive.blocks import Block, Local
from pfaff.derive.latexlist import EquationList, vlatex

if TYPE_CHECKING:
    from pfaff.mechanics.system import SystemSpec

DENSE_SYMBOLIC_LIMIT = 500  # above this many coordinates, M and A are sparse
SOLVE_LIMIT = 40  # largest n + m for the symbolic solve
SYMBOLIC_LIMIT = 100_000  # largest n for symbolic matrices (the templates are derived at any n)


_TRIG = (sp.sin, sp.cos, sp.tan)
READABLE_NODES = 500  # no entry of at most 80 operations has more nodes: a cheap first bound
READABLE_ANGLES = 2  # Fu's rules and trigsimp on 3 angles: 1-20 s per entry of a 6-joint arm
READABLE_SYMBOLS = 5  # angles + parameters: Fu's factoring took 1-5 s per arm entry of 6, for
# nothing (a link's mass, centre and inertia entries are 10 parameters)


def bounded_nodes(e: sp.Expr, limit: int) -> int:
    """The number of nodes of ``e``, counting at most ``limit + 1`` (a bounded walk, where
    ``count_ops`` walks the whole tree: seconds for an arm's entries of 10⁵ operations)."""
    return sum(1 for _ in itertools.islice(sp.preorder_traversal(e), limit + 1))


def readable_form(e: sp.Expr) -> sp.Expr:
    """An entry simplified for reading: sin² + cos², angle sums (Fu's rules, then ``trigsimp``).

    Bounded: ``trigsimp`` costs about a second on 60 operations with two angles, so bigger
    expressions go through Fu's rules first and ``trigsimp`` sees only what they left, when it
    is small; over 80 operations, over two angles or over five angles and parameters together
    an entry is shown as derived (Fu's rules took 20 s on one 75-operation entry of three angles
    of a 6-joint arm, and 1-5 s on entries of two angles and four parameters, and left them as
    they were). Applied per template when a
    readable property is first read, never on the way to numbers (``compile``).

    Examples
    --------
    >>> a, b = sp.symbols("a b")
    >>> readable_form(sp.sin(a) * sp.sin(b) + sp.cos(a) * sp.cos(b))
    cos(a - b)
    """
    if not e.has(*_TRIG) or bounded_nodes(e, READABLE_NODES) > READABLE_NODES:
        return e
    n = sp.count_ops(e)
    angles = {f.args[0] for f in e.atoms(*_TRIG)}
    symbols = {s for s in e.free_symbols if not s.name.startswith("_q")} - {t}
    if n > 80 or len(angles) > READABLE_ANGLES or len(angles) + len(symbols) > READABLE_SYMBOLS:
        return e
    s = e if n <= 24 else sp.fu(e)
    if sp.count_ops(s) <= 24:
        s = sp.trigsimp(s)
    return s if sp.count_ops(s) <= n else e


@dataclass(frozen=True)
class NumericParts:
    """What code is generated from: M's nonzero entries, Q − h, T and V, in the coordinates."""

    mass: dict
    forcing: list
    kinetic: sp.Expr
    potential: sp.Expr


def _mapped(seq, fn):
    """``fn`` over a sequence: a tuple for short ones, lazily for long ones."""
    if len(seq) <= 4096 and not isinstance(seq, LazySeq):
        return tuple(fn(x) for x in seq)
    return LazySeq(len(seq), lambda i: fn(seq[i]))


class Solution(dict):
    """Symbolic q̈ and λ: a dict keyed by ``q.diff(t, 2)`` and multiplier symbols.

    Attributes ``accelerations`` (Matrix, n×1) and ``multipliers`` (Matrix, m×1) give the same values
    in coordinate and constraint order.
    """

    accelerations: sp.Matrix
    multipliers: sp.Matrix


def _placeholder_calls(loc: Local) -> list[sp.Expr]:
    """Function calls f(_q_a, ...) whose arguments are all bare local coordinates."""
    cached = loc.__dict__.get("_calls")
    if cached is None:
        exprs = [*loc.mass.values(), *loc.h.values(), *loc.Q.values(), *loc.A.values()]
        exprs += [loc.b, loc.bias, loc.kinetic, loc.potential] + (
            [loc.f] if loc.f is not None else []
        )
        placeholders = {local_q(a) for a in range(loc.k)}
        cached = sorted(
            {
                f
                for e in exprs
                for f in e.atoms(sp.Function)
                if f.args and all(a in placeholders for a in f.args)
            },
            key=sp.default_sort_key,
        )
        loc.__dict__["_calls"] = cached
    return cached


class Derivation:
    """The equations of a system as derived blocks, with the named SymPy matrices made from them.

    M q̈ + h = Q + Aᵀλ with A q̈ + Ȧq̇ + ḃ = 0; the attributes (``mass_matrix``, ``forcing``,
    ``constraint_matrix``, ``lagrange_equations``, ...) are documented on the user's class,
    :class:`pfaff.EquationsOfMotion`, which is this one plus ``compile()``. Each matrix is assembled
    from the per-template blocks the first time it is asked for.

    Parameters
    ----------
    system : SystemSpec or None
        The model the blocks come from (None for equations given as matrices: ``from_matrices``).
    blocks : list of Block

    Examples
    --------
    >>> import pfaff
    >>> from pfaff.derive.templates import derive
    >>> d = derive(pfaff.models.cartesian_pendulum())
    >>> d.n, d.m, d.constraint_matrix
    (2, 1, Matrix([[2*x(t), 2*y(t)]]))
    """

    def __init__(
        self,
        system: SystemSpec | None,
        blocks: list[Block],
        *,
        coordinates: tuple | None = None,
        constraint_names: list[str] | None = None,
        holonomic: list[bool] | None = None,
        parameters: tuple | None = None,
        extra: dict | None = None,
    ) -> None:
        # sets of constraint names that depend on one another everywhere (derive.rank)
        self.redundant_sets: list[list[str]] = []
        self.system = system
        self.blocks = blocks
        if system is not None:
            coordinates = system.coordinates
            constraint_names, holonomic = system.constraint_rows()
            parameters = system.parameters
        coordinates = () if coordinates is None else coordinates
        self.coordinates = coordinates if isinstance(coordinates, LazySeq) else tuple(coordinates)
        self.constraint_names = (
            constraint_names
            if isinstance(constraint_names, LazySeq)
            else list(constraint_names or [])
        )
        self.holonomic = holonomic if holonomic is not None else []
        self.parameters: tuple = tuple(parameters or ())
        self.extra = extra or {}
        self.timings: dict[str, float] = {}  # CPU seconds of the derivation (set by derive)

    @cached_property
    def speeds(self) -> tuple | LazySeq:
        """q̇, in coordinate order."""
        return _mapped(self.coordinates, speed)

    @cached_property
    def accels(self) -> tuple | LazySeq:
        """q̈, in coordinate order."""
        return _mapped(self.coordinates, accel)

    @cached_property
    def multipliers(self) -> tuple | LazySeq:
        """λ_1 … λ_m, one per constraint row."""
        return _mapped(range(self.m), lambda i: sp.Symbol(f"lambda{i + 1}"))

    @property
    def n(self) -> int:
        """Number of coordinates."""
        return len(self.coordinates)

    @property
    def m(self) -> int:
        """Number of constraints (multipliers)."""
        return len(self.constraint_names)

    @property
    def family(self) -> bool:
        """True when some block is a family template (compiled to a structured model)."""
        return any(getattr(b, "family", False) for b in self.blocks)

    def _check_symbolic_size(self) -> None:
        if self.n > SYMBOLIC_LIMIT:
            raise PfaffError(
                f"symbolic matrices of {self.n} coordinates are too large to build (limit "
                f"{SYMBOLIC_LIMIT}); the templates are derived: use .compile(parameters) for numbers"
            )

    # ------------------------------------------------------------------ assembly
    def _instances(self, kind: str):
        """Yield (block, instance index, coordinate indices, local -> global rule) per instance."""
        self._check_symbolic_size()
        for block in self.blocks:
            if block.local.kind != kind:
                continue
            calls = _placeholder_calls(block.local)
            for i, idx in enumerate(block.coords.tolist()):
                rule = {}
                for a, c in enumerate(idx):
                    rule[local_q(a)] = self.coordinates[c]
                    rule[local_qd(a)] = self.speeds[c]
                # f(q_a) of a bare coordinate never evaluates further: build it without SymPy's
                # eval (the same object, several times faster than letting xreplace rebuild it).
                for call in calls:
                    rule[call] = call.func(*(rule[a] for a in call.args), evaluate=False)
                yield block, i, idx, rule

    def _local(self, block: Block, attr: str, readable: bool) -> dict:
        """A template's entries (``mass``, ``h`` or ``Q``): as derived, or simplified for reading
        (:func:`readable_form`, once per template and cached)."""
        entries = getattr(block.local, attr)
        if not readable or attr == "Q":
            return entries
        key = (id(block), attr)
        cache = self._readable_cache
        if key not in cache:
            # one simplification per distinct entry: a link's rows of parallel joint axes repeat
            # (six equal entries of the UR-type arm's wrist)
            forms = cache.setdefault("forms", {})
            cache[key] = {
                k: forms[e] if e in forms else forms.setdefault(e, readable_form(e))
                for k, e in entries.items()
            }
        return cache[key]

    @cached_property
    def _readable_cache(self) -> dict:
        return {}

    def _assemble_mass(self, readable: bool) -> dict[tuple[int, int], sp.Expr]:
        mass: dict[tuple[int, int], list] = {}
        for block, _, idx, rule in self._instances("dynamics"):
            for (a, c), e in self._local(block, "mass", readable).items():
                if a <= c:
                    ge = e.xreplace(rule)
                    mass.setdefault((idx[a], idx[c]), []).append(ge)
                    if a != c:
                        mass.setdefault((idx[c], idx[a]), []).append(ge)
        return {k: s for k, v in mass.items() if (s := sp.Add(*v)) != 0}

    @cached_property
    def _mass_entries(self) -> dict[tuple[int, int], sp.Expr]:
        """M's nonzero entries as derived (no simplification): what code is generated from."""
        return self._assemble_mass(readable=False)

    @cached_property
    def _readable_mass_entries(self) -> dict[tuple[int, int], sp.Expr]:
        return self._assemble_mass(readable=True)

    def _vector_terms(self, attr: str, readable: bool = False) -> list[sp.Expr]:
        out: list[list] = [[] for _ in range(self.n)]
        for block, _, idx, rule in self._instances("dynamics"):
            for a, e in self._local(block, attr, readable).items():
                out[idx[a]].append(e.xreplace(rule))
        return [sp.Add(*v) for v in out]

    @cached_property
    def _constraint_entries(self) -> dict:
        m = self.m
        A: dict[tuple[int, int], sp.Expr] = {}
        b, bias, f = [sp.S.Zero] * m, [sp.S.Zero] * m, [None] * m
        for block, i, idx, rule in self._instances("constraint"):
            loc, r = block.local, int(block.rows[i])
            for a, e in loc.A.items():
                A[r, idx[a]] = e.xreplace(rule)
            b[r], bias[r] = loc.b.xreplace(rule), loc.bias.xreplace(rule)
            f[r] = None if loc.f is None else loc.f.xreplace(rule)
        return {"A": A, "b": b, "bias": bias, "f": f}

    def _energy(self, attr: str) -> sp.Expr:
        return sp.Add(
            *(
                getattr(blk.local, attr).xreplace(rule)
                for blk, _, _, rule in self._instances("dynamics")
            )
        )

    @cached_property
    def _h_list(self) -> list[sp.Expr]:
        return self._vector_terms("h")

    @cached_property
    def _readable_h_list(self) -> list[sp.Expr]:
        return self._vector_terms("h", readable=True)

    @cached_property
    def numeric_parts(self) -> NumericParts:
        """M (its nonzero entries), Q − h, T and V as derived, without the simplification the
        readable properties get: what the compile stage generates code from."""
        return NumericParts(
            self._mass_entries,
            [q - h for q, h in zip(self._Q_list, self._h_list, strict=True)],
            self.kinetic_energy,
            self.potential_energy,
        )

    @cached_property
    def _Q_list(self) -> list[sp.Expr]:
        return self._vector_terms("Q")

    def _matrix(self, rows: int, cols: int, entries: dict) -> sp.MatrixBase:
        if max(rows, cols) > DENSE_SYMBOLIC_LIMIT:
            # SymPy's ImmutableSparseMatrix sorts all its entries into a Dict (seconds at N = 4096);
            # the mutable SparseMatrix is built directly. Treat it as read-only.
            return sp.SparseMatrix(rows, cols, entries)
        M = sp.zeros(rows, cols)
        for (i, j), e in entries.items():
            M[i, j] = e
        return sp.ImmutableMatrix(M)

    @cached_property
    def mass_matrix(self) -> sp.MatrixBase:
        """M, shape (n, n), its entries simplified for reading (per template, on first access)."""
        return self._matrix(self.n, self.n, self._readable_mass_entries)

    @cached_property
    def velocity_terms(self) -> sp.MatrixBase:
        """h, shape (n, 1): velocity products, explicit time dependence and ∂V/∂q."""
        return sp.ImmutableMatrix(self._readable_h_list)

    @cached_property
    def generalized_forces(self) -> sp.MatrixBase:
        """Q, shape (n, 1): generalized applied forces by virtual work."""
        return sp.ImmutableMatrix(self._Q_list)

    @cached_property
    def forcing(self) -> sp.MatrixBase:
        """Q - h, shape (n, 1)."""
        return sp.ImmutableMatrix(
            [q - h for q, h in zip(self._Q_list, self._readable_h_list, strict=True)]
        )

    @cached_property
    def constraint_matrix(self) -> sp.MatrixBase:
        """A, shape (m, n)."""
        return self._matrix(self.m, self.n, self._constraint_entries["A"])

    @cached_property
    def constraint_bias(self) -> sp.MatrixBase:
        """b, shape (m, 1), with A q̇ + b = 0."""
        return sp.ImmutableMatrix(self.m, 1, self._constraint_entries["b"])

    @cached_property
    def acceleration_constraints(self) -> sp.MatrixBase:
        """A q̈ + Ȧ q̇ + ḃ, shape (m, 1); each entry vanishes on a motion."""
        rows = [[] for _ in range(self.m)]
        for (i, j), e in self._constraint_entries["A"].items():
            rows[i].append(e * self.accels[j])
        return sp.ImmutableMatrix(
            self.m,
            1,
            [sp.Add(*r, c) for r, c in zip(rows, self._constraint_entries["bias"], strict=True)],
        )

    @cached_property
    def holonomic_constraints(self) -> list[sp.Expr | None]:
        """f(q, t) of each holonomic constraint (None for a velocity constraint)."""
        return list(self._constraint_entries["f"])

    @cached_property
    def kinetic_energy(self) -> sp.Expr:
        """T(q, q̇, t)."""
        return self._energy("kinetic")

    @cached_property
    def potential_energy(self) -> sp.Expr:
        """V(q, t)."""
        return self._energy("potential")

    @cached_property
    def lagrange_equations(self) -> EquationList:
        """One ``Eq(M q̈ + h, Q + Aᵀλ)`` per coordinate.

        A list of :class:`sympy.Eq` (equal to the plain list) that Jupyter shows as LaTeX.
        """
        lhs: list[list] = [[] for _ in range(self.n)]
        rhs: list[list] = [[q] for q in self._Q_list]
        for (i, j), e in self._readable_mass_entries.items():
            lhs[i].append(e * self.accels[j])
        for (i, j), e in self._constraint_entries["A"].items():
            rhs[j].append(e * self.multipliers[i])
        return EquationList(
            sp.Eq(sp.Add(*lhs[j], self._readable_h_list[j]), sp.Add(*rhs[j]), evaluate=False)
            for j in range(self.n)
        )

    # ------------------------------------------------------------------ output
    def latex(self, max_equations: int = 12) -> str:
        """LaTeX ``align*`` of the Lagrange equations and acceleration constraints (dots for rates).

        Examples
        --------
        >>> import pfaff
        >>> print(pfaff.models.pendulum().equations().latex())  # doctest: +ELLIPSIS
        \\begin{align*}
        ...
        """
        lines = []
        for eq in self.lagrange_equations[:max_equations]:
            lines.append(f"{vlatex(eq.lhs)} &= {vlatex(eq.rhs)}")
        if self.n > max_equations:
            lines.append(rf"&\vdots \quad \text{{({self.n - max_equations} more)}}")
        for e in list(self.acceleration_constraints)[:max_equations]:
            lines.append(f"{vlatex(e)} &= 0")
        if self.m > max_equations:
            lines.append(rf"&\vdots \quad \text{{({self.m - max_equations} more)}}")
        return "\\begin{align*}\n" + " \\\\\n".join(lines) + "\n\\end{align*}"

    def _repr_latex_(self) -> str:
        return "$$" + self.latex() + "$$"

    def __repr__(self) -> str:
        return f"<pfaff.EquationsOfMotion: {self.n} coordinates, {self.m} multipliers>"

    # ------------------------------------------------------------------ solving
    def solve(self, *, simplify: bool = False) -> Solution:
        """Solve the augmented system symbolically for q̈ and λ (small systems only).

        Uses an LU solve of [[M, -Aᵀ], [A, 0]]; M is never inverted.

        Examples
        --------
        >>> import pfaff, sympy as sp
        >>> x = pfaff.coordinates("x")
        >>> s = pfaff.System([x]); s.add_particle(2, [x, 0]); s.add_generalized_force(x, 6)
        >>> s.equations().solve()[x.diff(pfaff.t, 2)]
        3
        """
        n, m = self.n, self.m
        if n + m > SOLVE_LIMIT:
            raise PfaffError(
                f"symbolic solve is for small systems (n + m <= {SOLVE_LIMIT}, here {n + m}); "
                "use .compile(parameters).accelerations(t, q, qd)"
            )
        if self.redundant_sets:
            named = "; ".join(", ".join(f"`{c}`" for c in x) for x in self.redundant_sets)
            raise ConstraintError(
                f"the symbolic solve needs independent constraints, and {named} depend on one "
                "another: drop the dependent ones, or compile the model (its numeric solve keeps "
                "the independent rows and reports the minimum-norm multipliers)"
            )
        M, A = sp.Matrix(self.mass_matrix), sp.Matrix(self.constraint_matrix)
        K = sp.zeros(n + m, n + m)
        K[:n, :n] = M
        K[:n, n:] = -A.T
        K[n:, :n] = A
        rhs = sp.Matrix.vstack(
            sp.Matrix(self.forcing),
            -sp.Matrix(self._constraint_entries["bias"]) if m else sp.zeros(0, 1),
        )
        try:
            sol = K.LUsolve(rhs)
        except (ValueError, ZeroDivisionError) as e:
            raise PfaffError(
                "the augmented matrix is singular: redundant constraints or singular mass matrix"
            ) from e
        if simplify:
            sol = sol.applyfunc(sp.simplify)
        out = Solution(zip(self.accels + self.multipliers, sol, strict=True))
        out.accelerations = sp.ImmutableMatrix(sol[:n])
        out.multipliers = sp.ImmutableMatrix(m, 1, list(sol[n:]))
        return out

    # ------------------------------------------------------------------ construction from matrices
    @classmethod
    def of(cls, other: Derivation) -> Derivation:
        """The same derivation (blocks and cached matrices shared, not copied) as an instance of
        ``cls``: how the façade :class:`pfaff.EquationsOfMotion` wraps what this stage returns."""
        if type(other) is cls:
            return other
        out = cls.__new__(cls)
        out.__dict__ = other.__dict__
        return out

    @classmethod
    def from_matrices(
        cls,
        coordinates: tuple,
        mass: sp.MatrixBase,
        h: sp.MatrixBase,
        Q: sp.MatrixBase,
        *,
        kinetic: sp.Expr = sp.S.Zero,
        potential: sp.Expr = sp.S.Zero,
        parameters: tuple = (),
        extra: dict | None = None,
    ) -> Derivation:
        """Unconstrained equations M q̈ + h = Q given as whole matrices (used by reduction)."""
        n = len(coordinates)
        rule = {}
        for a, q in enumerate(coordinates):
            rule[speed(q)] = local_qd(a)
            rule[q] = local_q(a)
        loc = Local("dynamics", n)
        for i in range(n):
            for j in range(n):
                if mass[i, j] != 0:
                    loc.mass[i, j] = mass[i, j].xreplace(rule)
            if h[i] != 0:
                loc.h[i] = h[i].xreplace(rule)
            if Q[i] != 0:
                loc.Q[i] = Q[i].xreplace(rule)
        loc.kinetic, loc.potential = kinetic.xreplace(rule), potential.xreplace(rule)
        block = Block(loc, np.arange(n, dtype=np.int64).reshape(1, n), None, [])
        return cls(
            None,
            [block],
            coordinates=coordinates,
            constraint_names=[],
            holonomic=[],
            parameters=parameters,
            extra=extra,
        )
