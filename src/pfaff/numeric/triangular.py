"""The triangular KKT solver of :class:`pfaff.numeric.structured.StructuredModel` (the ring's).

The constraint Jacobian restricted to the family coordinates, A_L, is square and banded lower
triangular (the ring: no slip on θ_1, then θ_{k+1} - θ_k). Null-space elimination: the
constraints give q̈_L = w - Z q̈_G with w = -A_L⁻¹γ, Z = A_L⁻¹A_G; the p ordinary coordinates obey
the p×p projected equations TᵀMT q̈_G = Tᵀ(f - M[0; w]), T = [I; -Z]; and the multipliers follow
from A_Lᵀλ = (M q̈ - f)_L by back-substitution, λ_N first: the seed's "step backwards" as the
running sums of :mod:`pfaff.numeric.banded`. O(N) time and memory, no fill; M may have any sparsity.

Why it exists, measured on the 2-core development machine for the rolling ring
(``benchmarks/ring_scale.py``): at N = 2^20 SuperLU on the assembled augmented matrix
(:class:`pfaff.numeric.kkt.SparseSolver`, the fallback for any other structure) takes about 2 s
per solve, LAPACK's tridiagonal Cholesky of the Schur complement A M⁻¹ Aᵀ about 0.03 s, and this
elimination about 0.02 s, all of it streaming; at 2^24 about 0.29 s per solve.

When the constraint Jacobian is constant (the ring's), T = [I; -A_L⁻¹A_G] and M_const T are made
at build time and a solve touches only the state-dependent mass entries: TᵀMT is summed entry by
entry and M T is never formed, so a solve for q̈ alone (the integrators' right-hand side) streams
the varying entries, q̈ and T once each. Level-1 BLAS runs in blocks below OpenBLAS's threading
threshold (see :data:`pfaff.numeric.streams.BLAS_BLOCK`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from pfaff.core.errors import ConstraintError
from pfaff.numeric.banded import LowerBand
from pfaff.numeric.kkt import STATE_FLOOR, KKTSolver, KKTSystem
from pfaff.numeric.streams import (
    Index,
    add_product,
    axpy,
    dot,
    dot3,
    scale,
    scatter_add,
    take,
)

if TYPE_CHECKING:
    from pfaff.numeric.structured import StructuredModel

P_MAX = 32  # ordinary coordinates for the dense projected system
W_MAX = 8  # bandwidth of the triangular constraint structure


@dataclass
class TriangularPlan:
    """Where each constraint entry goes: the band of A_L (offset) or a column of A_G."""

    p: int
    w: int
    band: list = field(default_factory=list)  # (block, entry, offset, rows Index)
    border: list = field(default_factory=list)  # (block, entry, g, rows Index)


def triangular_plan(model: StructuredModel) -> TriangularPlan | None:
    """The triangular structure of A, or None when A_L is not square banded lower triangular."""
    p, m = model.p, model.m
    if m == 0 or m != model.n - p or p > P_MAX:
        return None
    plan = TriangularPlan(p, 0)
    diag = np.zeros(m, dtype=bool)
    for bi, part in enumerate(model.con):
        rows = part.rows
        if not isinstance(rows, Index) or (rows.step != 1 and rows.count > 1):
            return None
        for ei, c in enumerate(part.cols):
            if not isinstance(c, Index):
                return None
            if c.fixed or c.count == 1:
                if c.start < p:
                    plan.border.append((bi, ei, c.start, rows))
                    continue
                if c.fixed:
                    return None
            if c.start < p or (c.count > 1 and c.step != 1):
                return None
            off = rows.start - (c.start - p)
            if not 0 <= off <= W_MAX:
                return None
            plan.band.append((bi, ei, off, rows))
            plan.w = max(plan.w, off)
            if off == 0:
                diag[rows.slice()] = True
    return plan if diag.all() else None


class TriangularSolver(KKTSolver):
    """Null-space elimination through the triangular A_L (module docstring).

    Takes :class:`pfaff.numeric.kkt.KKTSystem` with ``mvals`` and ``avals`` (M and A are never
    assembled); no rank-loss floor: a zero pivot of A_L is a :class:`ConstraintError`.
    """

    name = "triangular"

    def __init__(self, model: StructuredModel, plan: TriangularPlan) -> None:
        self.model, self.plan = model, plan
        m, p = model.m, plan.p
        R0, G0 = np.zeros((plan.w + 1, m)), np.zeros((p, m))  # the constant entries
        self.var_band, self.var_border = [], []
        for bi, ei, off, rows in plan.band:
            val = model.con[bi].acc.const[ei]
            if val is None:
                self.var_band.append((bi, ei, off, rows))
            else:
                scatter_add(R0[off], rows, val)
        for bi, ei, g, rows in plan.border:
            val = model.con[bi].acc.const[ei]
            if val is None:
                self.var_border.append((bi, ei, g, rows))
            else:
                scatter_add(G0[g], rows, val)
        self.f_local_zero = all(
            isinstance(ix, Index) and (ix.fixed or ix.count == 1) and ix.start < p
            for part in model.dyn
            for ix in part.forcing
        )
        self._v = np.zeros(model.n)  # work vector, touched now rather than in the first solve
        self._v.fill(0.0)
        self._MT: list[np.ndarray] | None = None  # M T_g: made by the first solve that needs it
        self.band = None if self.var_band else LowerBand(R0, constant=True)
        self.T: np.ndarray | None = None  # T = [I; -Z], rows (p, n), when constant
        self.C: np.ndarray | None = None  # M_const T, rows (p, n), when T is constant
        if self.band is not None:
            self.band.check()
            if not self.var_border:
                self.T = self._t(self.band, G0)
                self.C = self._const_mt(self.T)
                self.TC = self.T @ self.C.T  # Tᵀ M_const T, (p, p)
        # per row of a constant T: the one value of its family part, or None (the ring's
        # θ̈_k = ẍ/r: T's family part is 1/r throughout, and the solve reads no N-long T)
        self.uniform = [_uniform(row[p:]) for row in self.T] if self.T is not None else []
        # the constant parts, once the band and T hold them: N-long arrays no longer kept
        self.R0: np.ndarray | None = None if self.band is not None else R0
        self.G0: np.ndarray | None = None if self.T is not None else G0

    def _const_mt(self, T: np.ndarray) -> np.ndarray:
        """M_const T: the state-independent mass entries times T, rows (p, n)."""
        model = self.model
        const = [
            [0.0 if c is None else c for c in part.kernel.const[: len(part.upper)]]
            for part in model.dyn
        ]
        return np.array([model.matvec(const, T[g]) for g in range(len(T))]).reshape(T.shape)

    def _t(self, band: LowerBand, G: np.ndarray) -> np.ndarray:
        """T = [I; -A_L⁻¹ A_G] as rows (p, n): a basis of the null space of A."""
        p, m = G.shape
        T = np.zeros((p, p + m))
        T[:, :p] = np.eye(p)
        if p:
            T[:, p:] = band.solve(G.T).T
            np.negative(T[:, p:], out=T[:, p:])
        return T

    def factor(self, avals: list) -> tuple[LowerBand, np.ndarray]:
        """The band of A_L and T = [I; -Z] at the given A-entry values (constant parts reused).

        Raises :class:`ConstraintError` on a zero pivot of A_L (then A has lost rank).
        """
        band, T = self.band, self.T
        if band is None:
            assert self.R0 is not None
            R = self.R0.copy()
            for bi, ei, off, rows in self.var_band:
                scatter_add(R[off], rows, avals[bi][ei])
            band = LowerBand(R, constant=False)
            band.check()
        if T is None:
            assert self.G0 is not None
            G = self.G0.copy()
            for bi, ei, g, rows in self.var_border:
                scatter_add(G[g], rows, avals[bi][ei])
            T = self._t(band, G)
        return band, T

    def solve(
        self,
        system: KKTSystem,
        *,
        floor: float = STATE_FLOOR,
        scales: np.ndarray | None = None,
        out: np.ndarray | None = None,
        multipliers: bool = True,
    ) -> tuple:
        """q̈ (n,) and λ (m,) with M q̈ - F = Aᵀλ and A q̈ = c (c None: zero).

        q̈ is written to ``out`` when given; λ is None unless ``multipliers``.
        """
        mvals, f, avals, c = system.mvals, system.F, system.avals, system.c
        assert mvals is not None and avals is not None
        model, p = self.model, self.plan.p
        band, T = self.factor(avals)
        TL = T[:, p:]  # -Z
        n = model.n
        r0 = f
        if c is not None:  # w = A_L⁻¹ c; f - M[0; w]
            w = band.solve(c)
            self._v[:p] = 0.0
            self._v[p:] = w
            r0 = f - model.matvec(mvals, self._v)
        fl = None if c is None and self.f_local_zero else r0[p:]
        fused = c is None and self.C is not None
        if fused:  # TᵀMT = Tᵀ M_const T (build time) + Tᵀ M_varying T: M T never formed
            Mr = self.TC + self._varying_form(mvals, T)
        else:
            MT = self._mt(mvals, T)
            Mr = np.array([[MT[g][h] + dot(TL[h], MT[g][p:]) for g in range(p)] for h in range(p)])
        TLs = self._family_rows(T)  # (a uniform row as its number)
        rr = np.array([r0[h] + (0.0 if fl is None else dot(TLs[h], fl)) for h in range(p)])
        try:
            qG = np.linalg.solve(Mr, rr) if p else np.zeros(0)
        except np.linalg.LinAlgError as e:
            raise ConstraintError(
                "the projected mass matrix TᵀMT is singular: a coordinate without inertia on "
                "the admissible motions"
            ) from e
        qdd = np.empty(n) if out is None else out
        qdd[:p] = qG
        _combine(qdd[p:], None if c is None else w, TLs, qG)  # q̈_L = w - Z q̈_G
        if not multipliers:
            return qdd, None
        res = self._v[p:]  # (M q̈ - f)_L = M[0; w]_L - f_L + Σ_g qG_g (MT_g)_L = Σ qG MT - r0
        if fused:  # = (M_const T qG)_L + (M_varying q̈)_L - f_L, as q̈ = T qG here
            _combine(res, None if fl is None else -fl, self.C[:, p:], qG)  # type: ignore[index]
            self._varying_rows(mvals, qdd)
        else:
            _combine(res, None if fl is None else -fl, [m_[p:] for m_ in MT], qG)
        return qdd, band.solve_t(res)

    def _varying(self, mvals: list):
        """(row, col, symmetric, values) of every state-dependent mass entry."""
        for part, vals in zip(self.model.dyn, mvals, strict=True):
            for (r, c, sym), val, const in zip(part.upper, vals, part.kernel.const, strict=False):
                if const is None:
                    yield r, c, sym, val

    def _family_rows(self, T: np.ndarray) -> list:
        """The family parts of T's rows, a row of one value (:attr:`uniform`) as that number."""
        p = self.plan.p
        if T is not self.T:
            return list(T[:, p:])
        return [T[g, p:] if u is None else u for g, u in enumerate(self.uniform)]

    def _taken(self, ix: Index | np.ndarray, T: np.ndarray, g: int) -> np.ndarray | float:
        """T[g] at the indices ``ix``: a number where they are all in a uniform family part."""
        u = self.uniform[g] if T is self.T else None
        if u is not None and isinstance(ix, Index):
            if min(ix.start, ix.start + ix.step * (ix.count - 1)) >= self.plan.p:
                return u
        return take(ix, T[g])

    def _varying_form(self, mvals: list, T: np.ndarray) -> np.ndarray:
        """Tᵀ M_varying T, (p, p), entry by entry without forming M T."""
        p = len(T)
        out = np.zeros((p, p))
        tmp = self.model.scratch()
        row = self._taken
        for r, c, sym, val in self._varying(mvals):
            for h in range(p):
                for g in range(h, p):
                    x = dot3(val, row(r, T, h), row(c, T, g), tmp)
                    if sym:
                        x += x if g == h else dot3(val, row(c, T, h), row(r, T, g), tmp)
                    out[h, g] += x
                    if g != h:
                        out[g, h] += x
        return out

    def _varying_rows(self, mvals: list, qdd: np.ndarray) -> None:
        """self._v[p:] += (M_varying q̈)_L: entries whose row is an ordinary coordinate skipped."""
        p, v, tmp = self.plan.p, self._v, self.model.scratch()
        for r, c, sym, val in self._varying(mvals):
            for row, col in ((r, c), (c, r)) if sym else ((r, c),):
                if not (isinstance(row, Index) and row.fixed and row.start < p):
                    add_product(v, row, val, take(col, qdd), tmp)

    def _mt(self, mvals: list, T: np.ndarray) -> list[np.ndarray]:
        """M T_g for every g (work buffers): M_const T from build time plus the varying part."""
        if self._MT is None:
            self._MT = [np.zeros(self.model.n) for _ in range(len(T))]
        model, MT = self.model, self._MT
        if self.C is None:
            for g in range(len(T)):
                model.matvec(mvals, T[g], out=MT[g])
            return MT
        varying = [
            [0.0 if c is not None else v for c, v in zip(part.kernel.const, vals, strict=False)]
            for part, vals in zip(model.dyn, mvals, strict=True)
        ]
        for g in range(len(T)):
            np.copyto(MT[g], self.C[g])
            model.matvec(varying, T[g], out=MT[g], add=True)
        return MT


def _uniform(row: np.ndarray) -> float | None:
    """The one value of a row whose entries are all equal, else None."""
    return float(row[0]) if row.size and bool(np.all(row == row[0])) else None


def _combine(out: np.ndarray, base: np.ndarray | None, vecs, coef) -> None:
    """out = base + Σ_g coef_g vecs_g, in place (a vector given as a number: that many times
    itself; the numbers are added together first, in one pass)."""
    number = math.fsum(float(c) * v for v, c in zip(vecs, coef, strict=True) if np.ndim(v) == 0)
    terms = [(v, float(c)) for v, c in zip(vecs, coef, strict=True) if np.ndim(v)]
    if base is not None:
        out[:] = base
        if number:
            out += number
    elif terms:
        scale(terms[0][0], terms[0][1], out)
        terms = terms[1:]
        if number:
            out += number
    else:
        out.fill(number)
    for v, c in terms:
        axpy(c, v, out)
