"""The stabilized index-2 DAE of a stream model and its sparse Newton matrix: :class:`GGLNewton`.

Unknowns y = [q, v, λ, μ] (μ one per position constraint), residuals (Gear–Gupta–Leimkuhler),

    F₁ = q' − v − A_hᵀ μ,   F₂ = M(q) v' − (Q − h) − Aᵀ λ,   F₃ = A v + b,   F₄ = f_h(q),

evaluated over the template streams (M and A never assembled). The Newton matrix
J = ∂F/∂y + c_j ∂F/∂y' is assembled in CSC on a pattern fixed once:

- exact where the blocks are the matrices themselves: c_j I and −I (F₁), c_j M (F₂ by v'),
  −Aᵀ and −A_hᵀ (the λ and μ columns), A (F₃ by v, F₄ by q);
- the state derivatives of the varying template outputs (M's entries times v', the forcing
  Q − h, A's entries times λ, μ and v, b) by forward differences of each template's kernel in
  its *local* coordinates: one kernel call per local slot perturbs that slot of every instance
  at once and yields every instance's partial derivative, which lands at the instance's global
  row and column. The groups are the template's slots (two for the ring's particle: x and θ_k),
  not the columns of J: a column colouring of J itself degenerates to N groups on the ring,
  whose x row meets every angle's column.

An equation coupled to every instance (the ring's x row: M_xθ_k and ∂h_x/∂θ_k for every k) is
weighted by 2⁻⁵⁰ (residual and Newton row alike: the same Newton corrections). SuperLU with
partial pivoting (SciPy's, threshold 1, and SUNDIALS' SuperLU_MT alike) pivots by magnitude:
unweighted, that row is chosen as a pivot early and the factors fill in (115 times the matrix's
entries on the ring of 1024; SuperLU_MT's storage ran out); weighted, 1.8 times: it pivots last.

Factored (IDA's preconditioner setup, :meth:`GGLNewton.factor`) as a narrow band with a dense
border where the pattern allows (:class:`pfaff.numeric.bordered.BorderedBand`: the ring's x
position and velocity are the border, the rest a band 4 wide either side after reverse
Cuthill–McKee), the terms summed straight into the band's storage; else by SuperLU (COLAMD).
On the ring of 2^16 one factorization took 0.5 s by SuperLU, 0.03 to 0.06 s as a band.

IDA asks for a new preconditioner whenever c_j moves by more than about 5/3 since the last one
(or its Newton iteration failed). The factors of J(c_j') still precondition J(c_j) well when
c_j is within ``KEEP_RATIO`` of c_j' (the preconditioned matrix's spectrum is two clusters, at 1
and near c_j / c_j'): GMRES then takes an iteration or two more, and a factorization costs
several of its iterations. A request at the c_j of the previous request (IDA retrying a failed
Newton iteration with a fresh matrix) always refactors. On the ring of 2^16, 1 s: ratio 3, 7
factorizations and 19 steps (14 and 19 refactoring at every request; ratio 2: 8 and 21; 4: 5 and
22; 8: 4 and 23; never: 2 and 26); ratio 6, 5 factorizations and 23 steps, 8–15 % less time than
3 on an idle machine (``benchmarks/ida_ring.py`` alternated, 2.41–2.75 s against 2.62–3.02 s);
ratio 8, 4 factorizations and 23 steps with one residual more, faster than 6 in 8 of 9
alternated pairs (medians 1.55 against 1.63 s); ratio 16 (today's, once the band's solves had
become faster), 3 factorizations and the same 23 steps with two residuals fewer: 1.04 against
1.17 s, medians of 9 alternated in one process (32: 3 and 23 again).

The algebraic diagonal gets the dense path's regularization (:mod:`pfaff.integrate.ida`) divided
by size²: ε_i = 1e-8 · s_i / (c_j size²), s_i the largest A_i D⁻¹A_iᵀ (D = diag M) or A_i A_iᵀ
seen so far. A chain of N constraint rows (the ring's spacings) has A M⁻¹Aᵀ eigenvalues spread
over about N², like a discrete Laplacian, and the dense path's 1e-8 moved its softest modes: on
the ring of 8192 IDA's step size collapsed at t = 0.34 (Newton failing); scaled, 19 steps for
1 s at every N from 2^10 to 2^16 (43 with IDA's own first step).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from pfaff.core.errors import ConstraintError
from pfaff.numeric.gglshape import NewtonShape
from pfaff.numeric.streams import Index, indices, scatter_add, take

if TYPE_CHECKING:
    from pfaff.numeric.base import StreamModel

SQRT_EPS = float(np.sqrt(np.finfo(float).eps))
DENSE_ROW_WEIGHT = 2.0**-50  # the weight of an equation coupled to every instance (see above)
KEEP_RATIO = 16.0  # factors kept while c_j stays within this factor of theirs (see above)


class GGLNewton:
    """The GGL residual and Newton matrix of a stream model (see the module docstring).

    Parameters
    ----------
    model : StreamModel
    hrows : ndarray of int, shape (m_h,)
        The position-constraint rows (those with a μ).
    t, y, yp : float, ndarray (size,), ndarray (size,)
        A state at which the template kernels can be evaluated (the pattern does not depend
        on it).
    regularization : float
        ε of the algebraic diagonal, divided by size² (see the module docstring).
    algebraic_scale : float
        s: the unknowns are λ/s and μ/s (J's λ and μ columns times s), so that one scalar
        absolute tolerance a leaves them out of IDA's error test in effect (their weight is
        1/(s a + rtol |λ|): a power of 2 near 1e12/a, as an absolute tolerance of 1e12 did),
        without the per-entry tolerance vector that scikit-sundae checks element by element
        in Python (0.12 s at 2^16 members). A power of 2: exact.

    Attributes
    ----------
    size : int
        2n + m + m_h.
    pattern : scipy.sparse.csc_matrix, shape (size, size)
        The structure of J (32-bit indices, as SUNDIALS takes them).

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.rolling_ring(8, force=True, family=True).equations().compile(
    ...     {"M": 1, "r": 0.5, "F": 2})
    >>> q, qd = pfaff.models.ring_state(8, radius=0.5, theta=0.3)
    >>> qdd, lam = model.accelerations(0.0, q, qd)
    >>> y = np.concatenate([q, qd, lam, np.zeros(8)])
    >>> yp = np.concatenate([qd, qdd, np.zeros(16)])
    >>> newton = GGLNewton(model.for_run(), np.arange(8), 0.0, y, yp)
    >>> res = np.empty(newton.size)
    >>> newton.residual(0.0, y, yp, res)
    >>> newton.size, bool(abs(res).max() < 1e-12)
    (34, True)
    """

    def __init__(
        self,
        model: StreamModel,
        hrows: np.ndarray,
        t: float,
        y: np.ndarray,
        yp: np.ndarray,
        regularization: float = 1e-8,
        algebraic_scale: float = 1.0,
    ) -> None:
        self.model = model
        self.scale = float(algebraic_scale)
        n, m = model.n, model.m
        self.hrows = np.asarray(hrows, dtype=np.int64)
        mh = self.hrows.size
        self._every = bool(np.array_equal(self.hrows, np.arange(m)))  # (slices, not gathers)
        self.n, self.m, self.mh = n, m, mh
        self.size = 2 * n + m + mh
        self.regularization = regularization / float(self.size) ** 2
        self._hpos = np.full(m, -1, dtype=np.int64)
        self._hpos[self.hrows] = np.arange(mh)
        # per constraint block: the instances on position rows (None: all) and their μ index
        self._holo: list = []
        for part in model.con:
            pos = self._hpos[np.broadcast_to(indices(part.rows), (part.acc.count,))]
            sel = np.flatnonzero(pos >= 0)
            if sel.size == 0:
                self._holo.append(None)
            else:
                self._holo.append((None if sel.size == pos.size else sel, pos))
        self._diag = [  # per dynamics block and mass entry: on M's diagonal
            [np.array_equal(indices(r), indices(c)) for r, c in part.mass] for part in model.dyn
        ]
        self._ref, self._ref_h = np.zeros(m), np.zeros(mh)
        self.factorizations = 0
        self.solves = 0
        self._cj = 0.0  # c_j of the factors kept, and of IDA's last request
        self._asked = 0.0
        # the pattern and band plan depend on the parts alone: made once per model (ModelValue)
        key = ("ggl", m, self.hrows.tobytes())
        shape = model.derived(key, lambda: self._shape(t, y, yp))
        self.shape = shape
        self.nnz, self.pattern = shape.nnz, shape.pattern
        self.dense_rows = shape.dense_rows
        self.band = None if shape.band is None else shape.band.fresh()
        self._solve = None

    def _shape(self, t: float, y: np.ndarray, yp: np.ndarray) -> NewtonShape:
        """The structure of J from its terms at one state (their places do not depend on it)."""
        terms, _ = self._terms(t, y, yp, 1.0)
        self._ref[:], self._ref_h[:] = 0.0, 0.0  # (sizes are gathered from the run's states)
        rows = np.concatenate([_expand(a, ra, k, s) for a, ra, _, _, k, s in terms])
        cols = np.concatenate([_expand(b, cb, k, s) for _, _, b, cb, k, s in terms])
        return NewtonShape.of(rows, cols, self.size)

    # ------------------------------------------------------------------ the residual
    def _split(self, y: np.ndarray) -> tuple:
        n, m, s = self.n, self.m, self.scale
        lam = y[2 * n : 2 * n + m] * s
        if self._every:  # every row a position constraint, in order
            return y[:n], y[n : 2 * n], lam, y[2 * n + m :] * s
        mu = np.zeros(m)
        mu[self.hrows] = y[2 * n + m :] * s
        return y[:n], y[n : 2 * n], lam, mu

    def _transpose_product(self, avals: list, w: np.ndarray, out: np.ndarray) -> None:
        """out -= Aᵀw from the evaluated constraint entries."""
        for part, vals in zip(self.model.con, avals, strict=True):
            wr = take(part.rows, w)
            for c, val in zip(part.cols, vals, strict=True):
                scatter_add(out, c, -np.multiply(val, wr))

    def residual(self, t: float, y: np.ndarray, yp: np.ndarray, res: np.ndarray) -> None:
        """The GGL residuals F(t, y, y') written into ``res``, shape (size,)."""
        model, n, m = self.model, self.n, self.m
        q, v, lam, mu = self._split(y)
        mvals, forcing = model._dynamics(t, q, v)
        avals, b, _, f = model._constraints(t, q, v)
        r1 = res[:n]
        np.subtract(yp[:n], v, out=r1)
        if self.mh:
            self._transpose_product(avals, mu, r1)
        r2 = res[n : 2 * n]
        model.matvec(mvals, yp[n : 2 * n], out=r2)
        r2 -= forcing
        self._transpose_product(avals, lam, r2)
        res[2 * n : 2 * n + m] = model.a_matvec(avals, v) + b
        res[2 * n + m :] = f if self._every else f[self.hrows]
        res[self.dense_rows] *= DENSE_ROW_WEIGHT

    # ------------------------------------------------------------------ the Newton matrix
    def jacobian(
        self, t: float, y: np.ndarray, yp: np.ndarray, res: np.ndarray, cj: float, JJ: np.ndarray
    ) -> None:
        """J = ∂F/∂y + c_j ∂F/∂y' in CSC order into ``JJ``, shape (nnz,) (IDA's ``jacfn``)."""
        shape = self.shape
        JJ[:] = np.bincount(shape.slot, weights=self._values(t, y, yp, cj), minlength=self.nnz)
        JJ[shape.dense_entries] *= DENSE_ROW_WEIGHT

    def _values(self, t: float, y: np.ndarray, yp: np.ndarray, cj: float) -> np.ndarray:
        """Every term's value per instance, in the order of ``shape.slot``."""
        terms, values = self._terms(t, y, yp, cj)
        algebraic, scale = 2 * self.n, self.scale  # (the λ and μ columns: times s)
        return np.concatenate([
            np.broadcast_to(v if b < algebraic else np.multiply(v, scale), (k,))[
                slice(None) if s is None else s]
            for (_, _, b, _, k, s), v in zip(terms, values, strict=True)
        ])  # fmt: skip

    def factor(self, t: float, y: np.ndarray, yp: np.ndarray, res: np.ndarray, cj: float) -> None:
        """Assemble J and factor it: IDA's preconditioner setup, skipped (the factors kept) while
        c_j stays within ``KEEP_RATIO`` of theirs unless IDA asks again at the same c_j. Fresh
        factors are exact, so its GMRES converges at once until c_j drifts. The band and border
        (:class:`pfaff.numeric.bordered.BorderedBand`) where the pattern has one, else (or where
        that B is singular) SuperLU (COLAMD, partial pivoting)."""
        asked, self._asked = self._asked, cj
        ratio = cj / self._cj if self._cj else 0.0
        if self._solve is not None and cj != asked and 1 / KEEP_RATIO <= ratio <= KEEP_RATIO:
            return  # the factors kept: GMRES iterates a little more (see the module docstring)
        self._cj = cj
        self.factorizations += 1
        band = self.band
        if band is not None:
            flat = band.assemble(self.shape.band_slot, self._values(t, y, yp, cj))
            flat[self.shape.band_dense] *= DENSE_ROW_WEIGHT
            if band.factor(flat):
                self._solve = band.solve
                return
        try:
            lu = spla.splu(self.matrix(t, y, yp, cj), permc_spec="COLAMD", diag_pivot_thresh=1.0)
        except (RuntimeError, MemoryError) as e:  # exactly singular, or the factors too large
            raise ConstraintError(
                f"IDA's Newton matrix could not be factored at t = {t:.17g}: {e}"
            ) from None
        self._solve = lambda r, out: np.copyto(out, lu.solve(r))

    def precondition(
        self,
        t: float,
        y: np.ndarray,
        yp: np.ndarray,
        res: np.ndarray,
        rvec: np.ndarray,
        zvec: np.ndarray,
        cj: float,
        delta: float,
    ) -> None:
        """zvec = J⁻¹ rvec with the last factors (IDA's preconditioner solve)."""
        self.solves += 1
        self._solve(np.asarray(rvec), zvec)

    def matrix(self, t: float, y: np.ndarray, yp: np.ndarray, cj: float) -> sps.csc_matrix:
        """J as a SciPy CSC matrix, shape (size, size) (for checks)."""
        data = np.empty(self.nnz)
        self.jacobian(t, y, yp, np.empty(0), cj, data)
        p = self.pattern  # (its index arrays are the shared, read-only ones: copied)
        return sps.csc_matrix((data, p.indices.copy(), p.indptr.copy()), shape=p.shape)

    def _terms(self, t: float, y: np.ndarray, yp: np.ndarray, cj: float) -> tuple[list, list]:
        """Every term of J: where it goes (row offset, row index set, column offset, column
        index set, instances, selection or None) and its values (per instance or one)."""
        n, m = self.n, self.m
        q, v, lam, mu = self._split(y)
        whole = Index(0, 1, n)
        terms: list = [(0, whole, 0, whole, n, None), (0, whole, n, whole, n, None)]
        values: list = [cj, -1.0]
        diag = self._dynamics_terms(t, q, v, yp[n : 2 * n], cj, terms, values)
        squares = self._constraint_terms(t, q, v, lam, mu, diag, terms, values)
        eps = self.regularization / cj
        L, U = 2 * n, 2 * n + m
        terms.append((L, Index(0, 1, m), L, Index(0, 1, m), m, None))
        values.append(eps * self._ref)
        if self.mh:
            self._ref_h = np.maximum(self._ref_h, squares[self.hrows])
            terms.append((U, Index(0, 1, self.mh), U, Index(0, 1, self.mh), self.mh, None))
            values.append(eps * self._ref_h)
        return terms, values

    def _dynamics_terms(
        self, t: float, q: np.ndarray, v: np.ndarray, vp: np.ndarray, cj: float,
        terms: list, values: list,
    ) -> np.ndarray:  # fmt: skip
        """The F₂ rows: c_j M, ∂(M v')/∂q and −∂(Q − h)/∂(q, v); returns diag M (1 where 0)."""
        V = self.n
        diag = np.zeros(self.n)
        for part, ondiag in zip(self.model.dyn, self._diag, strict=True):
            kern, cols = part.kernel, part.kernel.columns
            k = kern.count
            outs, dq, dv = _partials(kern, t, q, v, wrt_velocities=True)
            nu = len(part.upper)
            which = list(range(nu)) + [i for i, (_, _, sym) in enumerate(part.upper) if sym]
            for (r, c), e, on in zip(part.mass, which, ondiag, strict=True):
                terms.append((V, r, V, c, k, None))
                values.append(cj * outs[e])
                if on:
                    scatter_add(diag, r, outs[e])
                for j, col in enumerate(cols if e in dq else ()):
                    terms.append((V, r, 0, col, k, None))
                    values.append(dq[e][j] * take(c, vp))
            for i, ix in enumerate(part.forcing):
                for d, off in ((dq, 0), (dv, V)):
                    for j, col in enumerate(cols if nu + i in d else ()):
                        terms.append((V, ix, off, col, k, None))
                        values.append(-d[nu + i][j])
        diag[~(diag > 0)] = 1.0
        return diag

    def _constraint_terms(
        self, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, mu: np.ndarray,
        diag: np.ndarray, terms: list, values: list,
    ) -> np.ndarray:  # fmt: skip
        """−Aᵀ, −A_hᵀ, A and their curvature (by λ, μ, v) and ∂b/∂q; updates the rows' sizes
        s_i and returns Σ_k A_ik² per row."""
        n, m = self.n, self.m
        V, L, U = n, 2 * n, 2 * n + m
        ref, squares = np.zeros(m), np.zeros(m)
        for part, holo in zip(self.model.con, self._holo, strict=True):
            kern, cols, rows = part.res, part.res.columns, part.rows
            k = kern.count
            outs, dq, _ = _partials(kern, t, q, v, wrt_velocities=False)
            lr, mr = take(rows, lam), take(rows, mu)
            for a, c in enumerate(part.cols):
                terms += [(V, c, L, rows, k, None), (L, rows, V, c, k, None)]
                values += [-outs[a], outs[a]]
                sq = np.multiply(outs[a], outs[a])
                scatter_add(ref, rows, sq / take(c, diag))
                scatter_add(squares, rows, sq)
                if holo is not None:
                    sel, mus = holo  # (mus: μ index per instance, -1 off position rows)
                    terms += [(0, c, U, mus, k, sel), (U, mus, 0, c, k, sel)]
                    values += [-outs[a], outs[a]]
                for j, col in enumerate(cols if a in dq else ()):
                    terms += [(V, c, 0, col, k, None), (L, rows, 0, col, k, None)]
                    values += [-dq[a][j] * lr, dq[a][j] * take(c, v)]
                    if holo is not None:
                        terms.append((0, c, 0, col, k, holo[0]))
                        values.append(-dq[a][j] * mr)
            na = len(part.cols)
            for j, col in enumerate(cols if na in dq else ()):  # ∂b/∂q
                terms.append((L, rows, 0, col, k, None))
                values.append(dq[na][j])
        self._ref = np.maximum(self._ref, ref)
        return squares


def _partials(kernel, t: float, q: np.ndarray, v: np.ndarray, wrt_velocities: bool) -> tuple:
    """A template kernel's outputs per instance and, per varying output, its partial
    derivatives by each local slot: ``(outs, dq, dv)``, ``dq[e][j]`` = ∂out_e/∂q_j (an array
    over the instances or a scalar), by forward differences of the local arguments (one call
    per slot, every instance at once); ``dv`` likewise by the velocities (empty unless
    ``wrt_velocities``)."""
    cols = kernel.columns
    nk = len(cols)
    args = [take(c, q) for c in cols] + [take(c, v) for c in cols]
    outs = kernel.local(t, args)
    varying = [e for e, c in enumerate(kernel.const) if c is None]
    dq: dict = {e: [None] * nk for e in varying}
    dv: dict = {e: [None] * nk for e in varying} if wrt_velocities else {}
    for j in range(2 * nk if wrt_velocities else nk):
        a = args[j]
        stepped = a + SQRT_EPS * np.maximum(np.abs(a), 1.0)
        h = stepped - a  # the step as represented
        moved = kernel.local(t, [*args[:j], stepped, *args[j + 1 :]])
        d = dq if j < nk else dv
        for e in varying:
            d[e][j % nk] = (moved[e] - outs[e]) / h
    return outs, dq, dv


def _expand(offset: int, ix: Index | np.ndarray, count: int, sel: np.ndarray | None) -> np.ndarray:
    """Global indices of a term over its instances (``sel``: those it has; None: all)."""
    arr = np.broadcast_to(indices(ix), (count,))
    return offset + (arr if sel is None else arr[sel])
