"""An exact LU of a sparse matrix that is a narrow band but for a few dense rows and columns.

The border S is the set of indices whose row or column holds more than ``dense`` entries (the
ring's x: its equation meets every angle, every angle's equation meets its velocity). The rest,
B = J[K, K] with K the other indices, is reordered by reverse Cuthill–McKee on the pattern of
B + Bᵀ; when its bandwidths then stay small, J is factored as the block system

    [B  C] [z_K]   [r_K]
    [R  D] [z_S] = [r_S]

with B in LAPACK band storage (``dgbtrf``, partial pivoting inside the band), X = B⁻¹C, and the
Schur complement D − R X (k × k, k = |S|, dense LU): z_S = (D − R X)⁻¹ (r_S − R B⁻¹ r_K),
z_K = B⁻¹ r_K − X z_S. The pattern is analysed once; each factorization takes one value per
pattern entry, laid out by :attr:`BorderedBand.positions` in one flat array (band storage, then
C, R and D), so that the caller can sum its terms straight into it.

On the GGL Newton matrix of the ring of 2^16 particles (262 146 unknowns, 1.2 million entries):
k = 2, bandwidths 4 and 4; SuperLU with COLAMD made 2.5 million entries of factors in 0.5 s,
the band about 3.4 million entries of storage in 0.03 s (CPU, the machine shared). There the
compiled path keeps the factors in compact L (kl wide) and U (its actual width: kl + ku with
the interchanges this matrix needs, ku without) for the solves, which are bound by reading them.
A band at most 4 wide either side (the ring's) is stored at those fixed widths and takes
:mod:`pfaff.numeric.bandlu`'s narrow path, whose factorization writes the compact factors as it
goes and whose solve gathers the right side itself: a factorization 11–12 ms, a solve 2.0 ms
(4.3 ms inside an IDA run, where the factors come from memory rather than cache), against 7 to
9 ms a solve before.
"""

from __future__ import annotations

from types import ModuleType

import numpy as np
import scipy.linalg as sla
import scipy.linalg.lapack as lapack
import scipy.sparse as sps

from pfaff.numeric.jit import loaded

MAX_BAND = 32  # kl + ku beyond which the band is not worth it (SuperLU instead)
MAX_BORDER = 16  # dense rows and columns at most
COMPILED_FROM = 4096  # B's order from which numba's band LU (pfaff.numeric.bandlu) is used


class BorderedBand:
    """The band-plus-border LU of a sparse pattern (see the module docstring).

    Made by :meth:`plan`, which returns None where the pattern does not fit.

    Attributes
    ----------
    size : int
        The matrix's order.
    border : ndarray of int, shape (k,)
        The dense indices S.
    order : ndarray of int, shape (size - k,)
        The other indices in band order (``order[p]`` is B's p-th row and column).
    kl, ku : int
        B's lower and upper bandwidths in that order.
    positions : ndarray of int, shape (nnz,)
        For each entry of the pattern (CSC order), its place in the flat value array.
    length : int
        The flat value array's length.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sps
    >>> n = 40  # a tridiagonal matrix with one dense row and column (index 0)
    >>> J = sps.diags([np.full(n - 1, -1.0), np.full(n, 4.0), np.full(n - 1, -1.0)], [-1, 0, 1])
    >>> J = sps.csc_matrix(J + sps.csc_matrix((np.ones(2 * n), (np.r_[np.zeros(n), np.arange(n)],
    ...     np.r_[np.arange(n), np.zeros(n)])), shape=(n, n)))
    >>> J.sort_indices()
    >>> band = BorderedBand.plan(J, dense=8)
    >>> band.border.tolist(), band.kl, band.ku
    ([0], 1, 1)
    >>> flat = np.bincount(band.positions, weights=J.data, minlength=band.length)
    >>> band.factor(flat)
    True
    >>> r = np.arange(n, dtype=float)
    >>> bool(np.allclose(J @ band.solve(r), r))
    True
    """

    def __init__(self, size: int, border: np.ndarray, order: np.ndarray, kl: int, ku: int) -> None:
        self.size, self.border, self.order = size, border, order
        self.kl, self.ku = kl, ku
        self.k, self.nb = border.size, order.size
        self.ldab = 2 * kl + ku + 1
        nb, k = self.nb, self.k
        self._c0 = self.ldab * nb  # C stored as (k, nb), R as (k, nb), D as (k, k)
        self._r0 = self._c0 + k * nb
        self._d0 = self._r0 + k * nb
        self.length = self._d0 + k * k
        self.positions = np.empty(0, dtype=np.int64)
        self._band: tuple = (None, None, None)
        self._schur: tuple | None = None
        self._buffer: np.ndarray | None = None
        self._factors: tuple = ()  # the compiled path's compact L and U (bandlu)
        self._x = np.empty(0)  # the narrow solve's buffer
        self._identity = np.empty(0, dtype=np.int64)  # its order for the border's columns
        self._narrow = False  # the factors are bandlu.narrow_factor's

    @classmethod
    def plan(
        cls, pattern: sps.csc_matrix, dense: float, max_band: int = MAX_BAND
    ) -> BorderedBand | None:
        """Analyse a square CSC pattern (sorted indices); None where the border exceeds
        ``MAX_BORDER`` indices or B's bandwidths ``kl + ku`` exceed ``max_band``."""
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        size = pattern.shape[0]
        rows = pattern.indices.astype(np.int64)
        cols = np.repeat(np.arange(size), np.diff(pattern.indptr))
        per_row = np.bincount(rows, minlength=size)
        per_col = np.bincount(cols, minlength=size)
        border = np.flatnonzero((per_row > dense) | (per_col > dense))
        if border.size > MAX_BORDER or border.size == size:
            return None
        inner = np.ones(size, dtype=bool)
        inner[border] = False
        keep = np.flatnonzero(inner)
        local = np.full(size, -1, dtype=np.int64)
        local[keep] = np.arange(keep.size)
        both = inner[rows] & inner[cols]
        nb = keep.size
        lr, lc = local[rows[both]], local[cols[both]]
        inside = sps.csr_matrix((np.ones(lr.size), (lr, lc)), shape=(nb, nb))
        sym = (inside + inside.T).tocsr()
        perm = np.asarray(reverse_cuthill_mckee(sym, symmetric_mode=True), dtype=np.int64)
        rank = np.empty(nb, dtype=np.int64)
        rank[perm] = np.arange(nb)
        pr, pc = rank[lr], rank[lc]
        kl = int(max(0, (pr - pc).max(initial=0)))
        ku = int(max(0, (pc - pr).max(initial=0)))
        if kl + ku > max_band:
            return None
        narrow = _kernels() if nb >= COMPILED_FROM else None
        if narrow is not None and kl <= narrow.NARROW_L and ku <= narrow.NARROW_K:
            kl, ku = narrow.NARROW_L, narrow.NARROW_K  # stored as the narrow band's fixed widths
        plan = cls(size, border, keep[perm], kl, ku)
        plan.positions = plan._positions(rows, cols, inner, local, rank)
        for a in (plan.border, plan.order, plan.positions):
            a.flags.writeable = False  # (shared by the runs of a model: NewtonShape)
        return plan

    def fresh(self) -> BorderedBand:
        """The same plan (its read-only arrays shared) with no factors yet: a run's own."""
        band = type(self)(self.size, self.border, self.order, self.kl, self.ku)
        band.positions = self.positions
        return band

    def _positions(
        self, rows: np.ndarray, cols: np.ndarray, inner: np.ndarray, local: np.ndarray,
        rank: np.ndarray,
    ) -> np.ndarray:  # fmt: skip
        """Each pattern entry's place in the flat array: band, C, R or D."""
        slot = np.full(self.size, -1, dtype=np.int64)  # band index, or border index
        slot[inner] = rank[local[inner]]
        slot[self.border] = np.arange(self.k)
        i, j = slot[rows], slot[cols]
        ri, ci = inner[rows], inner[cols]
        out = self._d0 + i * self.k + j  # D[i, j]
        band = ri & ci
        ib, jb = i[band], j[band]
        out[band] = jb * self.ldab + self.kl + self.ku + ib - jb  # B: ab[kl + ku + i - j, j]
        c = ri & ~ci
        out[c] = self._c0 + j[c] * self.nb + i[c]  # C[i, j], stored transposed (by rows)
        r = ~ri & ci
        out[r] = self._r0 + i[r] * self.nb + j[r]  # R[i, j]
        return out

    def assemble(self, slots: np.ndarray, values: np.ndarray) -> np.ndarray:
        """The flat value array of terms ``values`` at flat places ``slots`` (duplicates summed),
        in a buffer kept between factorizations where the band is long."""
        kernels = _kernels() if self.nb >= COMPILED_FROM else None
        if kernels is None:
            return np.bincount(slots, weights=values, minlength=self.length)
        if self._buffer is None:
            self._buffer = np.zeros(self.length)
        else:
            self._buffer.fill(0.0)
        kernels.sum_into(self._buffer, slots, values)
        return self._buffer

    def factor(self, flat: np.ndarray) -> bool:
        """Factor the matrix whose values ``flat`` holds (laid out by :attr:`positions`; it is
        overwritten). False where B or the Schur complement is singular."""
        nb, k = self.nb, self.k
        if not self._band_factor(flat[: self._c0]):
            return False
        if k == 0:
            self._schur = None
            return True
        Xt = flat[self._c0 : self._r0].reshape(k, nb)  # Cᵀ, then (B⁻¹C)ᵀ, in place
        live = np.flatnonzero(Xt.any(axis=1))  # (a column of zeros stays so)
        if live.size == k:
            self._band_solve(Xt)  # every column in one pass
        elif live.size:
            Xt[live] = self._band_solve(Xt[live])
        R = flat[self._r0 : self._d0].reshape(k, nb)
        lu, spiv, info = lapack.dgetrf(flat[self._d0 :].reshape(k, k) - R @ Xt.T)
        if info != 0 or not np.all(np.isfinite(lu)):
            return False
        self._schur = (Xt, R, (lu, spiv), live)
        return True

    def solve(self, r: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """z = J⁻¹ r with the last factors, shape (size,), into ``out`` if given."""
        kernels, factors, _ = self._band
        z = np.empty(self.size) if out is None else out
        if kernels is None:
            y = r[self.order]
            self._band_solve(y.reshape(1, self.nb))
        elif self._narrow:  # the narrow solve gathers r itself, into its own buffer
            kernels.narrow_solve(*factors, r, self.order, self._x)
            y = self._x
        else:
            y = np.empty(self.nb)
            kernels.gather(y, r, self.order)
            self._band_solve(y.reshape(1, self.nb))
        if self._schur is None:
            z[self.order] = y
            return z
        Xt, R, lu, live = self._schur
        zs = sla.lu_solve(lu, r[self.border] - R @ y, check_finite=False)
        if kernels is None:
            z[self.order] = y - Xt[live].T @ zs[live]
            z[self.border] = zs
        else:
            kernels.scatter_border(z, y, Xt, zs, self.order, self.border, live)
        return z

    # ------------------------------------------------------------------ the band's LU
    def _band_factor(self, band: np.ndarray) -> bool:
        """B's LU from its band storage (overwritten): numba's loops for a long band
        (:mod:`pfaff.numeric.bandlu`; at the narrow widths their fixed-width factorization,
        which also writes the factors its solve reads), LAPACK's ``dgbtrf`` otherwise."""
        kernels = _kernels() if self.nb >= COMPILED_FROM else None
        nb = self.nb
        widths = (self.kl, self.ku)
        self._narrow = kernels is not None and widths == (kernels.NARROW_L, kernels.NARROW_K)
        if kernels is None:
            ab = band.reshape(nb, self.ldab).T  # Fortran order, a view
            ab, piv, info = lapack.dgbtrf(ab, self.kl, self.ku, overwrite_ab=1)
        elif self._narrow:
            if not self._factors:  # (kept between factorizations)
                self._factors = (
                    np.empty((nb, kernels.NARROW_L)), np.empty(nb, dtype=np.int8),
                    np.empty((nb, kernels.NARROW_U + 1)),
                )  # fmt: skip
                self._x = np.empty(nb)
                self._identity = np.arange(nb)
                self._identity.flags.writeable = False  # (the plan's order's type)
            ab, piv = self._factors, None
            info = kernels.narrow_factor(band.reshape(nb, self.ldab), *ab)
        else:
            ab = band.reshape(nb, self.ldab)
            piv = np.empty(nb, dtype=np.int64)
            info = kernels.band_factor(ab, self.kl, self.ku, piv)
            if info == 0:
                ue = self.ku + int((piv - np.arange(nb)).max(initial=0))
                ab = self._split(kernels, ab, min(ue, self.kl + self.ku))
        self._band = (kernels, ab, piv)
        return info == 0

    def _split(self, kernels: ModuleType, ab: np.ndarray, ue: int) -> tuple:
        """(lower, upper): the factors in ab compacted (:func:`pfaff.numeric.bandlu.band_split`),
        into arrays kept between factorizations."""
        lower, upper = self._factors or (None, None)
        if lower is None or upper.shape[1] != ue + 1:
            lower, upper = np.empty((self.nb, self.kl)), np.empty((self.nb, ue + 1))
            self._factors = (lower, upper)
        kernels.band_split(ab, self.kl, self.ku, lower, upper)
        return lower, upper

    def _band_solve(self, b: np.ndarray) -> np.ndarray:
        """b ← B⁻¹ b in place, b of shape (columns, nb) (a right side per row), C-contiguous;
        returns b."""
        kernels, ab, piv = self._band
        if kernels is not None and self._narrow:
            for row in b:  # in place
                kernels.narrow_solve(*ab, row, self._identity, row)
        elif kernels is not None:
            kernels.band_solve(*ab, piv, b)
        else:
            b[:] = lapack.dgbtrs(ab, self.kl, self.ku, b.T, piv)[0].T
        return b


def _kernels() -> ModuleType | None:
    """:mod:`pfaff.numeric.bandlu`, compiled (or loaded from numba's cache) on first use
    (:func:`pfaff.numeric.jit.loaded`); None where numba cannot (LAPACK's routines then do
    the same)."""
    return loaded("bandlu", _load_bandlu)[0]


def _load_bandlu() -> ModuleType:
    from pfaff.numeric import bandlu

    # one call of each with the argument types of the runs (IDA's vectors and the plan's index
    # arrays are read-only)
    ab, piv, one = np.ones((1, 1)), np.zeros(1, dtype=np.int64), np.ones(1)
    fixed, index = np.ones(1), np.zeros(1, dtype=np.int64)
    fixed.flags.writeable = index.flags.writeable = False
    bandlu.band_factor(ab, 0, 0, piv)
    bandlu.band_split(ab, 0, 0, ab[:, :0], ab)
    bandlu.band_solve(ab[:, :0].copy(), ab, piv, np.ones((1, 1)))
    lower, off = np.zeros((1, bandlu.NARROW_L)), np.zeros(1, dtype=np.int8)
    upper, x = np.ones((1, bandlu.NARROW_U + 1)), np.zeros(1)
    narrow = np.ones((1, 2 * bandlu.NARROW_L + bandlu.NARROW_K + 1))
    bandlu.narrow_factor(narrow, lower, off, upper)
    bandlu.narrow_solve(lower, off, upper, fixed, index, x)  # (a right side of IDA's)
    bandlu.narrow_solve(lower, off, upper, one, index, one)  # (a border column's, in place)
    bandlu.sum_into(one, index, one)
    bandlu.gather(one, fixed, index)
    bandlu.scatter_border(one, one, ab, one, index, index, piv)
    return bandlu
