"""The structure of a family's GGL Newton matrix (:mod:`pfaff.numeric.ggl`): :class:`NewtonShape`.

Where each term of J lands in CSC order, the pattern itself, the rows coupled to every instance,
and the band-plus-border plan (:class:`pfaff.numeric.bordered.BorderedBand`) with each term's
place in its storage. All of it depends on the model's parts alone, not on the state or c_j,
and finding it is most of IDA's setup on a large family (0.25 s of a 2.3 s run on the ring of
2^16): a model makes it once (:meth:`pfaff.numeric.value.ModelValue.derived`) and every run of
that model shares it. Its arrays are read-only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps

from pfaff.numeric.bordered import BorderedBand


@dataclass(frozen=True)
class NewtonShape:
    """Where the terms of J go (see the module docstring); made by :meth:`of`.

    Attributes
    ----------
    size : int
        J's order.
    nnz : int
        Its structural entries.
    slot : ndarray of int, shape (terms,)
        Each term entry's index among them (CSC order; duplicates are summed).
    pattern : scipy.sparse.csc_matrix, shape (size, size)
        The structure (32-bit indices, as SUNDIALS takes them).
    dense_rows : ndarray of int
        Rows with more than ``max(16, 4 √size)`` entries (weighted, :mod:`pfaff.numeric.ggl`).
    dense_entries : ndarray of int
        The entries (CSC indices) on those rows.
    band : BorderedBand or None
        The band-plus-border plan (its factors are a run's: :meth:`BorderedBand.fresh`), or
        None where the pattern has no narrow band.
    band_slot, band_dense : ndarray of int
        ``slot`` and ``dense_entries`` as places in the band's flat storage (empty without one).

    Examples
    --------
    >>> import numpy as np
    >>> rows, cols = np.array([0, 1, 1, 0]), np.array([0, 0, 1, 0])  # (0, 0) twice
    >>> shape = NewtonShape.of(rows, cols, 2)
    >>> shape.nnz, shape.slot.tolist(), shape.pattern.toarray().tolist()
    (3, [0, 1, 2, 0], [[1.0, 0.0], [1.0, 1.0]])
    """

    size: int
    nnz: int
    slot: np.ndarray
    pattern: sps.csc_matrix
    dense_rows: np.ndarray
    dense_entries: np.ndarray
    band: BorderedBand | None
    band_slot: np.ndarray
    band_dense: np.ndarray

    @classmethod
    def of(cls, rows: np.ndarray, cols: np.ndarray, size: int) -> NewtonShape:
        """The shape of the terms at (``rows[i]``, ``cols[i]``), shape (terms,) each."""
        lin = cols * size + rows  # column-major: sorted order is CSC order
        uniq, slot = _unique(lin)
        counts = np.bincount(uniq // size, minlength=size)
        indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        idx = (uniq % size).astype(np.int32)
        nnz = int(uniq.size)
        pattern = sps.csc_matrix((np.ones(nnz), idx, indptr), shape=(size, size), copy=False)
        pattern.indices, pattern.indptr = idx, indptr  # (scipy may widen them)
        per_row = np.bincount(idx, minlength=size)
        dense = max(16.0, 4.0 * np.sqrt(size))
        dense_rows = np.flatnonzero(per_row > dense)
        dense_entries = np.flatnonzero(np.isin(idx, dense_rows))
        band = BorderedBand.plan(pattern, dense)
        none = np.zeros(0, dtype=np.int64)
        band_slot = none if band is None else band.positions[slot]
        band_dense = none if band is None else band.positions[dense_entries]
        arrays = (slot, idx, indptr, pattern.data, dense_rows, dense_entries, band_slot, band_dense)
        for a in arrays:
            a.flags.writeable = False
        return cls(size, nnz, slot, pattern, dense_rows, dense_entries, band, band_slot, band_dense)


def _unique(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(keys, return_inverse=True)`` by a stable sort: the terms' keys come in
    sorted runs (one per term), which it merges several times faster."""
    order = np.argsort(keys, kind="stable")
    ordered = keys[order]
    first = np.empty(keys.size, dtype=bool)
    first[:1] = True
    np.not_equal(ordered[1:], ordered[:-1], out=first[1:])
    inverse = np.empty(keys.size, dtype=np.int64)
    inverse[order] = np.cumsum(first) - 1
    return ordered[first], inverse
