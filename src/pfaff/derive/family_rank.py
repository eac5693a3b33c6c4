"""The constraint rank of a family, proved on a small instance of its templates.

The rank check of :mod:`pfaff.derive.rank` evaluates A at a random state; for a family that
meant a numeric model of full size: 87 % of the 2^24 ring's ``equations()`` (issue 25). A
family's constraint rows are a few templates repeated over index progressions, so where A has
the triangular structure of :mod:`pfaff.numeric.triangular`, its rank follows from the templates
alone:

- the structure itself (which rows touch which members, A_L = the family columns of A square,
  banded and lower triangular, every row with its diagonal entry) is read from the index
  progressions: a few numbers per template, whatever N;
- then det A_L is the product of its diagonal entries, each the value of one template's entry
  E at one instance's coordinates. E is analytic (the kinks a constraint may not have are
  refused when it is added), so where it is non-zero at one point it vanishes only on a set of
  measure zero, and the product over every instance is non-zero at almost every state: A has
  rank m there, the same "probability one" argument as the full check's one random state. E is
  evaluated on a small instance: the template's kernel over :data:`SAMPLES` random points of its
  local coordinates (a constant entry is its value).

One more row than that structure takes (the closed ring's ``spacing N``, the last row, alone
in its template) is :func:`closure_rows`: where every entry of the triangular rows is a constant
of its template, A_L and the border columns A_G are known without a state, and the extra row a
depends on the others exactly when the w of A_Lᵀ w = −a_L (one O(N) banded solve,
:class:`pfaff.numeric.banded.LowerBand`) also gives A_Gᵀ w = −a_G; the rows where w is
non-zero, and a, are then the one dependent set (what the full check's null space of Aᵀ
finds). Its entries are sampled at a random point, as the full check's state is.

Where this cannot conclude (no triangular structure: more rows than family members beyond one
closing row, entries of the triangular rows that depend on the state, an entry that is zero or
undefined at a sample, two diagonal entries on one row), both say so and the full check runs as
before, which finds and names the dependent sets or refuses the inconsistent ones.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from types import SimpleNamespace

import numpy as np

from pfaff.derive.blocks import Block
from pfaff.derive.codegen import constraint_layout
from pfaff.derive.compile import con_streams
from pfaff.derive.equations import Derivation
from pfaff.numeric.banded import LowerBand
from pfaff.numeric.rank import SUPPORT_TOL
from pfaff.numeric.streams import Index, scatter_add
from pfaff.numeric.triangular import triangular_plan

SAMPLES = 4  # random points at which each diagonal template entry must be non-zero


def proves_full_rank(
    eom: Derivation, values: Sequence[float], t: float, rng: np.random.Generator
) -> bool:
    """True when the constraint matrix of the family system ``eom`` has full row rank at almost
    every state, proved from its templates (module docstring); False when this cannot tell.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> ring = pfaff.models.rolling_ring(2**20, force=True).equations()
    >>> proves_full_rank(ring, [2.0, 1.0, 0.5], 0.3, np.random.default_rng(1))
    True
    >>> closed = pfaff.models.rolling_ring(8, family=True, closed=True)
    >>> import warnings
    >>> with warnings.catch_warnings(record=True):
    ...     eom = closed.equations()  # (its spacing rows are redundant: the full check says so)
    >>> proves_full_rank(eom, [1.0, 0.5], 0.3, np.random.default_rng(1))
    False
    """
    if not eom.family or eom.m == 0 or eom.m > eom.n:
        return False
    params = tuple(eom.parameters)
    blocks = [b for b in eom.blocks if b.local.kind != "dynamics"]
    con = [con_streams(b, params, values, lazy=True) for b in blocks]  # (no code made yet)
    families = getattr(eom.system, "families", [])
    p = eom.n - sum(len(f) for f in families)
    plan = triangular_plan(SimpleNamespace(p=p, m=eom.m, n=eom.n, con=con))  # type: ignore[arg-type]
    if plan is None:
        return False
    diagonal = [(bi, ei, rows) for bi, ei, off, rows in plan.band if off == 0]
    if _overlap([rows for _, _, rows in diagonal]):
        return False  # two entries on one diagonal element: their sum is not one template's
    for bi in sorted({bi for bi, _, _ in diagonal}):
        entries = [ei for b, ei, _ in diagonal if b == bi]
        if not _nonzero_on_small_instance(blocks[bi], params, values, t, entries, rng):
            return False
    return True


def _overlap(rows: list) -> bool:
    """Whether two of these row sets (progressions of step 1, or single rows) share a row."""
    spans = []
    for r in rows:
        if not isinstance(r, Index):
            return True  # (an index array: not read here)
        spans.append((r.start, r.start + max(r.count, 1)))
    spans.sort()
    return any(b[0] < a[1] for a, b in itertools.pairwise(spans))


def _nonzero_on_small_instance(
    block: Block,
    params: tuple,
    values: Sequence[float],
    t: float,
    entries: list[int],
    rng: np.random.Generator,
) -> bool:
    """Whether A entries ``entries`` (in the block's column order) of the block's template are
    finite and non-zero at :data:`SAMPLES` random points of its local coordinates: the
    template's kernel over a small instance of its own, members 0 … k·SAMPLES − 1."""
    k = block.coords.shape[1] if not block.family else len(block.progressions or [])
    small = Block(
        block.local,
        np.arange(k * SAMPLES, dtype=np.int64).reshape(SAMPLES, k),
        np.arange(SAMPLES, dtype=np.int64),
        [],
    )
    part = con_streams(small, params, values)
    q = rng.uniform(-1.3, 1.3, k * SAMPLES)
    with np.errstate(all="ignore"):
        try:
            out = part.acc(t, q, np.zeros_like(q))
        except (ArithmeticError, ValueError):  # not defined at a sample: the full check decides
            return False
    for ei in entries:
        v = np.broadcast_to(np.asarray(out[ei], dtype=float), (SAMPLES,))
        if not (np.isfinite(v).all() and (v != 0).all()):
            return False
    return True


def closure_rows(
    eom: Derivation, values: Sequence[float], t: float, rng: np.random.Generator
) -> np.ndarray | None:
    """The rows of the one dependent set of a family whose last row closes a triangular
    structure (module docstring): empty when that row is independent (A has full rank), None
    when this cannot tell.

    Examples
    --------
    >>> import warnings, numpy as np, pfaff
    >>> with warnings.catch_warnings(record=True):
    ...     eom = pfaff.models.rolling_ring(5, family=True, closed=True).equations()
    >>> closure_rows(eom, [1.0, 0.5], 0.3, np.random.default_rng(1)).tolist()  # spacing 1 … 5
    [1, 2, 3, 4, 5]
    """
    m, n = eom.m, eom.n
    if not eom.family or m < 2:
        return None
    params = tuple(eom.parameters)
    blocks = [b for b in eom.blocks if b.local.kind != "dynamics"]
    last = [
        i for i, b in enumerate(blocks) if not b.family and b.n_inst == 1 and b.rows[0] == m - 1
    ]
    if not last:
        return None
    con = [con_streams(b, params, values, lazy=True) for b in blocks]
    rest = [c for i, c in enumerate(con) if i != last[0]]
    p = n - sum(len(f) for f in getattr(eom.system, "families", []))
    plan = triangular_plan(SimpleNamespace(p=p, m=m - 1, n=n, con=rest))  # type: ignore[arg-type]
    if plan is None:
        return None
    R, G = np.zeros((plan.w + 1, m - 1)), np.zeros((p, m - 1))
    for into, entries in ((R, plan.band), (G, plan.border)):
        for bi, ei, at, rows in entries:
            value = rest[bi].acc.const[ei]  # (the template's code, made now: a few per family)
            if value is None:
                return None  # an entry that depends on the state: the full check evaluates it
            scatter_add(into[at], rows, value)
    band = LowerBand(R, constant=True)
    if not (np.isfinite(R[0]).all() and (R[0] != 0).all()):
        return None
    a = _row_at_random_point(blocks[last[0]], params, values, t, n, rng)
    if a is None:
        return None
    w = band.solve_t(-a[p:])
    off = G @ w + a[:p] if p else np.zeros(0)
    scale = (1.0 + np.abs(R).max() + np.abs(G).max(initial=0.0)) * (1.0 + np.abs(w).max())
    if not np.isfinite(w).all() or (off.size and np.abs(off).max() > 1e-9 * scale):
        return np.zeros(0, dtype=np.int64) if np.isfinite(w).all() else None
    y = np.append(w, 1.0)
    return np.flatnonzero(np.abs(y) > SUPPORT_TOL * np.linalg.norm(y)).astype(np.int64)


def _row_at_random_point(
    block: Block, params: tuple, values: Sequence[float], t: float, n: int,
    rng: np.random.Generator,
) -> np.ndarray | None:  # fmt: skip
    """The one row of an ordinary constraint block at random values of its coordinates, as a
    dense vector of length n; None where it is not finite there."""
    cols = block.coords[0]
    k = cols.size
    small = Block(block.local, np.arange(k, dtype=np.int64)[None, :], np.zeros(1, np.int64), [])
    part = con_streams(small, params, values)
    q = rng.uniform(-1.3, 1.3, k)
    with np.errstate(all="ignore"):
        try:
            out = part.acc(t, q, np.zeros_like(q))
        except (ArithmeticError, ValueError):
            return None
    row = np.zeros(n)
    for ei, a in enumerate(constraint_layout(block)[0]):  # (the order of the kernel's outputs)
        row[cols[a]] += float(np.asarray(out[ei], dtype=float).ravel()[0])
    return row if np.isfinite(row).all() else None
