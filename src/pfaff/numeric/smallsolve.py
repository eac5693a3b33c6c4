"""Straight-line code for the KKT solve of a small system with a known sparsity pattern.

For a handful of coordinates, calling LAPACK costs more in Python overhead than the arithmetic.
This module writes a Python function, once per model, that solves

    M q̈ − Aᵀλ = F,   A q̈ = c

by the range-space (Schur complement) method on floats: Cholesky M = L Lᵀ, y = M⁻¹F,
Z = M⁻¹Aᵀ, S = A Z, Cholesky of S, λ = S⁻¹(c − A y), q̈ = y + Z λ. Structural zeros of M and A
are skipped, so a diagonal M costs n divisions. When M is not positive definite (a coordinate
without inertia) the function raises ``ValueError`` or ``ZeroDivisionError`` and the caller falls
back to the general path.

Where the constraint Jacobian loses rank (a linkage folded flat) S becomes singular. With
``floor=True`` the j-th pivot d of its Cholesky factorization is replaced by
:func:`pfaff.numeric.kkt.floored` (d, τ_j), with thresholds τ_j given per constraint row: the one
floor of :mod:`pfaff.numeric.kkt`, which runs the same algorithm on arrays.

Why it exists (``benchmarks/simulate.py``): one right-hand side of the Cartesian pendulum costs
about 1.6 µs as generated code fused with the kernel, against 6–7 µs for one lambdified kernel and
a LAPACK solve and 90 µs through the template kernels.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from pfaff.numeric.generated import register
from pfaff.numeric.kkt import floored

Entry = str | None  # a variable name, or None for a structural zero


def _dot(pairs: list[tuple[Entry, Entry]]) -> str | None:
    terms = [f"{a}*{b}" for a, b in pairs if a is not None and b is not None]
    return " + ".join(terms) if terms else None


class _Writer:
    def __init__(self, prefix: str = "v", symbolic: bool = False) -> None:
        self.lines: list[str] = []
        self.count = 0
        self.prefix = prefix
        self.symbolic = symbolic  # no Python conditionals: the code runs on symbols too
        self.pivots: list[tuple[str, str]] | None = None  # (pivot, diagonal entry), if recorded

    def let(self, expr: str | None) -> Entry:
        if expr is None:
            return None
        self.count += 1
        name = f"{self.prefix}{self.count}"
        self.lines.append(f"    {name} = {expr}")
        return name

    def cholesky(self, S: list[list[Entry]], tau: list[str] | None = None) -> list[list[Entry]]:
        """Cholesky factor of S; with ``tau`` (variable names) pivot j is floored at tau[j]."""
        k = len(S)
        L: list[list[Entry]] = [[None] * k for _ in range(k)]
        for j in range(k):
            acc = _dot([(L[j][p], L[j][p]) for p in range(j)])
            diag = S[j][j] or "0.0"
            if acc is not None:
                diag = f"{diag} - ({acc})"
            if self.pivots is not None:  # the unfloored pivot, for the checks of a state
                diag = self.let(diag) or diag
                self.pivots.append((diag, S[j][j] or "0.0"))
            if tau and self.symbolic:  # one expression: Piecewise in the namespace's pick
                diag = f"pick({self.let(diag)}, {tau[j]})"
            elif tau:  # the common case d >= τ costs one comparison, no call
                d = self.let(diag)
                diag = f"{d} if {d} >= {tau[j]} else floored({d}, {tau[j]})"
            L[j][j] = self.let(f"sqrt({diag})")
            for i in range(j + 1, k):
                acc = _dot([(L[i][p], L[j][p]) for p in range(j)])
                if S[i][j] is None and acc is None:
                    continue
                num = S[i][j] or "0.0"
                if acc is not None:
                    num = f"{num} - ({acc})"
                L[i][j] = self.let(f"({num}) / {L[j][j]}")
        return L

    def solve(self, L: list[list[Entry]], b: list[Entry]) -> list[Entry]:
        """x = (L Lᵀ)⁻¹ b by forward and back substitution."""
        k = len(L)
        z: list[Entry] = [None] * k
        for i in range(k):
            acc = _dot([(L[i][p], z[p]) for p in range(i)])
            if b[i] is None and acc is None:
                continue
            num = b[i] or "0.0"
            z[i] = self.let(f"({num}{f' - ({acc})' if acc else ''}) / {L[i][i]}")
        x: list[Entry] = [None] * k
        for i in reversed(range(k)):
            acc = _dot([(L[p][i], x[p]) for p in range(i + 1, k)])
            if z[i] is None and acc is None:
                continue
            num = z[i] or "0.0"
            x[i] = self.let(f"({num}{f' - ({acc})' if acc else ''}) / {L[i][i]}")
        return x


def schur_solver(
    n: int,
    m: int,
    mass: list[tuple[int, int]],
    acon: list[tuple[int, int]],
    *,
    damped: bool = False,
) -> Callable[..., list[float]]:
    """Generate ``solve(*mass_values, *A_values, *F, *c) -> q̈ (list of n floats)``.

    With ``damped=True`` the function takes one more argument ``shift`` and solves with
    S + shift·trace(S)·I (the damped minimum-norm correction of :mod:`pfaff.numeric.projection`).
    (The floored solve of the right-hand side is generated inside the fused kernel from
    :func:`schur_source` with ``tau``.)

    Parameters
    ----------
    n, m : int
    mass : list of (i, j), i <= j
        Structurally nonzero entries of the upper triangle of M, in argument order.
    acon : list of (i, j)
        Structurally nonzero entries of A (m, n), in argument order.

    Examples
    --------
    >>> solve = schur_solver(2, 1, [(0, 0), (1, 1)], [(0, 0), (0, 1)])
    >>> [round(v, 12) for v in solve(1.0, 1.0, 0.6, -0.8, 0.0, -9.81, -1.0)]
    [-5.3088, -2.7316]
    """
    Ms = [f"m{s}" for s in range(len(mass))]
    As = [f"a{s}" for s in range(len(acon))]
    Fs, cs = [f"F{i}" for i in range(n)], [f"c{i}" for i in range(m)]
    lines, out = schur_source(mass, acon, Ms, As, Fs, cs, shift="shift" if damped else None)
    args = ", ".join(Ms + As + Fs + cs + (["shift"] if damped else []))
    src = f"def solve({args}):\n" + "\n".join(lines) + f"\n    return [{', '.join(out)}]\n"
    namespace: dict = dict(NAMESPACE)
    exec(compile(src, register(src, "smallsolve"), "exec"), namespace)  # our own generated code
    return namespace["solve"]


NAMESPACE = {"sqrt": math.sqrt, "floored": floored}  # what the generated lines call


def schur_source(
    mass: list[tuple[int, int]],
    acon: list[tuple[int, int]],
    Ms: list[str],
    As: list[str],
    Fs: list[str],
    cs: list[str],
    *,
    shift: str | None = None,
    tau: list[str] | None = None,
    cap: str | None = None,
    prefix: str = "v",
    symbolic: bool = False,
    multipliers: list | None = None,
    checks: list | None = None,
) -> tuple[list[str], list[str]]:
    """Lines (indented for a function body) computing q̈, and the n expressions of q̈.

    The inputs are variable names: M's entries ``Ms`` (pattern ``mass``), A's ``As`` (pattern
    ``acon``), the forcing ``Fs`` and the constraint right-hand side ``cs``; intermediate variables
    are ``{prefix}1, {prefix}2, …``. ``shift``, ``tau`` and ``cap`` as in :func:`schur_solver`.
    ``symbolic``: no Python conditionals (the floor and the cap call ``pick`` and ``capped``), so
    that the lines also run on symbolic values (:func:`schur_expressions`). ``multipliers``: a
    list that receives the m expressions of λ. ``checks``: a list that receives three
    expressions a checked call reads (:func:`pfaff.numeric.checkedsolve.passes`): the smallest
    Cholesky pivot of M over its diagonal entry's size (the pivot of the Jacobi-scaled M; a
    negative one where M is not definite, even where the algebra of the symbolic solve has
    cancelled the square roots that would fail), the same of S = A M⁻¹ Aᵀ (1.0 without
    constraints), and the smallest diagonal entry of S over the largest.

    Examples
    --------
    One coordinate of mass m0 and one constraint a0 q̈ = c0: q̈ = F0/m0 + (c0 − a0 F0/m0)/a0.

    >>> lines, out = schur_source([(0, 0)], [(0, 0)], ["m0"], ["a0"], ["F0"], ["c0"])
    >>> env = {**NAMESPACE, "m0": 2.0, "a0": 1.0, "F0": 4.0, "c0": 3.0}
    >>> exec(chr(10).join(line.strip() for line in lines), env)
    >>> eval(out[0], env)
    3.0
    """
    n, m = len(Fs), len(cs)
    w = _Writer(prefix, symbolic)
    if checks is not None:
        w.pivots = []
    M: list[list[Entry]] = [[None] * n for _ in range(n)]
    for name, (i, j) in zip(Ms, mass, strict=True):
        M[i][j] = M[j][i] = name
    A: list[list[Entry]] = [[None] * n for _ in range(m)]
    for name, (i, j) in zip(As, acon, strict=True):
        A[i][j] = name
    L = w.cholesky(M)
    y = w.solve(L, list(Fs))
    Z = [w.solve(L, A[r]) for r in range(m)]  # Z[r] = M⁻¹ A[r]ᵀ
    S: list[list[Entry]] = [[None] * m for _ in range(m)]
    for i in range(m):
        for j in range(i + 1):
            S[i][j] = S[j][i] = w.let(_dot(list(zip(A[i], Z[j], strict=True))))
    if shift and m:
        tr = w.let(f"{shift} * ({' + '.join(S[i][i] or '0.0' for i in range(m))})")
        for i in range(m):
            S[i][i] = w.let(f"{S[i][i] or '0.0'} + {tr}")
    r = []
    for i in range(m):
        acc = _dot(list(zip(A[i], y, strict=True)))
        r.append(w.let(f"{cs[i]} - ({acc})" if acc else cs[i]))
    if tau and cap and m:  # τ_j never above cap · max diag S: rows shrinking together stay exact
        top = w.let(f"{cap} * max({', '.join(S[i][i] or '0.0' for i in range(m))}, 0.0)")
        cap_of = "capped({0}, {1})" if symbolic else "{0} if {0} < {1} else {1}"
        tau = [w.let(cap_of.format(tj, top)) or tj for tj in tau]
    if checks is not None:
        checks.append(_smallest(w, _ratios(w)))
        w.pivots = []
    lam = w.solve(w.cholesky(S, tau), r) if m else []
    if checks is not None:
        diag = [S[i][i] or "0.0" for i in range(m)]
        spread = f"{_smallest(w, diag)} / max({', '.join(diag)}, 0.0)" if m else "1.0"
        checks += [_smallest(w, _ratios(w)) if m else "1.0", spread]
    if multipliers is not None:
        multipliers.extend(x if x is not None else "0.0" for x in lam)
    out = []
    for i in range(n):
        acc = _dot([(Z[k][i], lam[k]) for k in range(m)])
        terms = [x for x in (y[i], acc) if x is not None]
        out.append(" + ".join(terms) if terms else "0.0")
    return w.lines, out


def _ratios(w: _Writer) -> list[str]:
    """Each recorded pivot over the size of its diagonal entry. On symbols, the size is
    max(s, 0): the same ratio where s > 0, and where s ≤ 0 the pivot d ≤ s makes it −inf or
    NaN, which fails as the negative ratio d/|s| does. SymEngine's ``Abs`` of a large entry
    made the machine code of the ring of 8 take 17 s to build instead of 0.2 s; d/sqrt(s·s)
    became d·(s²)^(−1/2), a call of ``pow`` that cost the Cartesian pendulum's right-hand side
    more than the rest of it (two of them, about 40 ns of its 70)."""
    size = "max({0}, 0.0)" if w.symbolic else "abs({0})"
    return [f"{d} / {size.format(s)}" for d, s in w.pivots or []]


def _smallest(w: _Writer, exprs: list[str]) -> str:
    """A variable holding the smallest of ``exprs`` (``min`` in the namespace the code runs in)."""
    return w.let(exprs[0] if len(exprs) == 1 else f"min({', '.join(exprs)})") or "0.0"


def schur_expressions(
    mass: list[tuple[int, int]],
    acon: list[tuple[int, int]],
    values: dict[str, object],
    n: int,
    m: int,
    namespace: dict,
    checked: bool = False,
) -> list:
    """q̈ and λ (n + m) of the floored range-space solve as expressions: :func:`schur_source`'s lines (the same
    algorithm and floor) run on symbolic ``values`` for the names ``m{s}``, ``a{s}``, ``F{i}``,
    ``c{i}``, ``tau{j}`` and ``cap``; ``namespace`` gives ``sqrt``, ``max``, ``pick(d, tau)`` (the
    floored pivot) and ``capped(tau, top)`` for that algebra (and ``min``, with ``checked``:
    then the three check expressions of :func:`schur_source` follow λ).
    """
    Ms = [f"m{s}" for s in range(len(mass))]
    As = [f"a{s}" for s in range(len(acon))]
    Fs, cs = [f"F{i}" for i in range(n)], [f"c{i}" for i in range(m)]
    taus = [f"tau{j}" for j in range(m)]
    lam: list[str] = []
    checks: list[str] | None = [] if checked else None
    lines, out = schur_source(
        mass, acon, Ms, As, Fs, cs, tau=taus, cap="cap", symbolic=True, multipliers=lam,
        checks=checks,
    )  # fmt: skip
    names = [*Ms, *As, *Fs, *cs, *taus, "cap"]
    src = f"def schur({', '.join(names)}):\n" + "\n".join(lines)
    src += f"\n    return [{', '.join(out + lam + (checks or []))}]\n"
    env = dict(namespace)
    exec(compile(src, "<pfaff.smallsolve symbolic>", "exec"), env)  # our own generated code
    return env["schur"](*(values[k] for k in names))
