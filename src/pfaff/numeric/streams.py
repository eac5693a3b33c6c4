"""Template kernels evaluated over index progressions, without per-instance index arrays.

A family block's instance i uses global coordinate ``start + step*i`` for each local coordinate, so
the kernel's inputs are strided *views* of q and q̇ (no gather) and its outputs scatter back with
slice arithmetic. Outputs that do not depend on the state are evaluated once, at build time, to a
number. Evaluation runs in chunks of instances so that the temporaries of the generated NumPy code
stay in cache.
"""

from __future__ import annotations

import functools
import itertools
import math
import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import scipy.linalg.blas as blas

CHUNK = 1 << 15  # instances per kernel call
# NumPy releases the GIL inside ufunc loops: large kernels run their chunks on THREADS threads
# (PFAFF_KERNEL_THREADS=1 runs them on the calling thread; benchmarks/threads.py measures both).
THREADS = min(2, os.cpu_count() or 1)
if os.environ.get("PFAFF_KERNEL_THREADS", "").strip() in ("1", "2"):
    THREADS = min(int(os.environ["PFAFF_KERNEL_THREADS"]), os.cpu_count() or 1)
PARALLEL_FROM = 1 << 20
# OpenBLAS runs level-1 calls (daxpy, ddot) below 10,000 elements on the calling thread; on longer
# vectors it wakes its own threads, whose wake-up and spin-wait cost more than the call at 2^16
# elements (a solve at N = 65536 took 16 ms instead of 2.7 ms) and compete with the kernel threads.
# threadpoolctl's limit(1) around a solve does the same at a cost: entering and leaving it took
# 10 µs per BLAS library (two: NumPy's and SciPy's), a ring solve 150 -> 184 µs at N = 2^10 and
# 1304 -> 1349 µs at 2^16 (measured 2026-11-24), so the calls are cut into blocks instead.
BLAS_BLOCK = 8192
SINCOS_FROM = 1 << 12  # kernels over this many instances take sin and cos from trig.sincos
JIT_FROM = 1 << 16  # ... and from this many, in one compiled pass (trigjit: numba loaded once)
SPAN = 1 << 17  # elements per task of the streaming passes run on the threads (1 MiB)
_POOL: ThreadPoolExecutor | None = None
_THREAD = threading.local()


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:
        _POOL = ThreadPoolExecutor(THREADS - 1, thread_name_prefix="pfaff-kernel")
    return _POOL


def in_spans(count: int, step: int, fn: Callable[[int, int], None]) -> None:
    """fn(lo, hi) over [0, count) in spans of ``step``: on THREADS threads from PARALLEL_FROM on.

    Spans are handed out one at a time, so a thread slowed down (a busy core) takes fewer. ``fn``
    must release the GIL for most of its time (NumPy ufuncs do) to gain from the threads.
    """
    nested = threading.current_thread().name.startswith("pfaff-kernel")  # never wait on itself
    if count < PARALLEL_FROM or THREADS < 2 or nested:
        for lo in range(0, count, step):
            fn(lo, min(lo + step, count))
        return
    spans, last = itertools.count(), (count - 1) // step

    def work() -> None:
        while (i := next(spans)) <= last:  # next() on a count is atomic under the GIL
            fn(i * step, min((i + 1) * step, count))

    helpers = [_pool().submit(work) for _ in range(THREADS - 1)]
    work()
    for h in helpers:
        h.result()


def _span_scratch() -> np.ndarray:
    """A SPAN-long scratch vector of the calling thread."""
    buf = getattr(_THREAD, "span", None)
    if buf is None:
        buf = _THREAD.span = np.empty(SPAN)
    return buf


@dataclass(frozen=True)
class Index:
    """Global indices ``start + step*i`` for i < count (``step == 0``: one fixed index).

    Examples
    --------
    >>> import numpy as np
    >>> ix = Index(1, 2, 3)
    >>> ix.take(np.arange(10.0)).tolist(), ix.indices().tolist()
    ([1.0, 3.0, 5.0], [1, 3, 5])
    """

    start: int
    step: int
    count: int

    @classmethod
    def of(cls, idx: np.ndarray) -> Index | np.ndarray:
        """The progression an index array is, or the array itself when it is none."""
        idx = np.asarray(idx, dtype=np.int64)
        if idx.size == 1:
            return cls(int(idx[0]), 1, 1)
        d = np.diff(idx)
        if d.size and np.all(d == d[0]):
            return cls(int(idx[0]), int(d[0]), idx.size)
        return idx

    @property
    def fixed(self) -> bool:
        """All instances use the same index."""
        return self.step == 0

    @functools.cached_property
    def whole(self) -> slice:
        """The slice of all instances (not for fixed indices)."""
        return self._slice(0, self.count)

    def slice(self, lo: int = 0, hi: int | None = None) -> slice:
        """The slice of instances lo … hi-1 (not for fixed indices)."""
        if lo == 0 and (hi is None or hi == self.count):
            return self.whole
        return self._slice(lo, self.count if hi is None else hi)

    def _slice(self, lo: int, hi: int) -> slice:
        a = self.start + self.step * lo
        b = self.start + self.step * (hi - 1) + (1 if self.step > 0 else -1)
        return slice(a, b if b >= 0 else None, self.step)

    def take(self, x: np.ndarray, lo: int = 0, hi: int | None = None) -> np.ndarray | float:
        """x at the indices of instances lo … hi-1: a view, or a scalar when fixed."""
        return x[self.start] if self.fixed else x[self.slice(lo, hi)]

    def indices(self) -> np.ndarray:
        """The indices as an array, shape (count,)."""
        return self.start + self.step * np.arange(self.count, dtype=np.int64)


def take(ix: Index | np.ndarray, x: np.ndarray, lo: int = 0, hi: int | None = None):
    """x at an index set (view, scalar or gather)."""
    return ix.take(x, lo, hi) if isinstance(ix, Index) else x[ix[lo:hi]]


def scatter_add(out: np.ndarray, ix: Index | np.ndarray, vals: np.ndarray | float) -> None:
    """out[ix] += vals, summing over instances that share an index."""
    if isinstance(ix, Index):
        if ix.fixed:
            out[ix.start] += np.sum(vals) if np.ndim(vals) else vals * ix.count
        else:
            out[ix.slice()] += vals
    else:
        np.add.at(out, ix, np.broadcast_to(vals, ix.shape))


def fill_at(out: np.ndarray, ix: Index | np.ndarray, value: float) -> None:
    """out[ix] = value."""
    if isinstance(ix, Index):
        out[ix.start if ix.fixed else ix.slice()] = value
    else:
        out[ix] = value


def indices(ix: Index | np.ndarray) -> np.ndarray:
    """An index set as an array."""
    return ix.indices() if isinstance(ix, Index) else ix


def add_product(
    out: np.ndarray,
    row: Index | np.ndarray,
    val: np.ndarray | float,
    xv: np.ndarray | float,
    tmp: np.ndarray,
) -> None:
    """out[row] += val * xv over the instances, with as few passes over memory as possible.

    ``xv`` is x taken at the stream's columns (an array view or a scalar); ``tmp`` is scratch of
    at least the stream's length.
    """
    if not isinstance(row, Index):
        np.add.at(out, row, np.broadcast_to(np.multiply(val, xv), row.shape))
    elif row.fixed:
        out[row.start] += dot(val, xv) if np.ndim(val) or np.ndim(xv) else val * xv * row.count
    else:
        target = out[row.slice()]
        if np.ndim(val) and np.ndim(xv):
            t_ = tmp[: row.count]
            np.multiply(val, xv, out=t_)
            target += t_
        elif np.ndim(val) or np.ndim(xv):
            arr, s = (val, xv) if np.ndim(val) else (xv, val)
            if target.flags.c_contiguous and arr.flags.c_contiguous and row.count > 1:
                axpy(float(s), arr, target)  # in place, one pass
            else:
                target += np.multiply(arr, s)
        else:
            target += val * xv


def dot(vals: np.ndarray | float, x: np.ndarray | float) -> float:
    """Σ_i vals_i x_i, with scalars standing for constant arrays."""
    if np.ndim(vals) and np.ndim(x):
        n = np.shape(vals)[0]
        return math.fsum(  # type: ignore[index]
            float(np.dot(vals[lo : lo + BLAS_BLOCK], x[lo : lo + BLAS_BLOCK]))
            for lo in range(0, n, BLAS_BLOCK)
        )
    if np.ndim(vals) or np.ndim(x):
        arr, s = (vals, x) if np.ndim(vals) else (x, vals)
        return float(np.sum(arr)) * float(s)  # type: ignore[arg-type]
    return float(vals) * float(x)  # type: ignore[arg-type]


def dot3(
    vals: np.ndarray | float, a: np.ndarray | float, b: np.ndarray | float, tmp: np.ndarray
) -> float:
    """Σ_i vals_i a_i b_i, scalars standing for constant arrays; ``tmp``: scratch, as long."""
    arrays = [x for x in (vals, a, b) if np.ndim(x)]
    scale = math.prod(float(x) for x in (vals, a, b) if not np.ndim(x))  # type: ignore[arg-type]
    if len(arrays) < 3:
        if not arrays:
            return scale
        return scale * dot(*arrays) if len(arrays) == 2 else scale * float(np.sum(arrays[0]))
    n = np.shape(vals)[0]
    total = 0.0
    for lo in range(0, n, BLAS_BLOCK):
        t_ = tmp[: min(BLAS_BLOCK, n - lo)]
        np.multiply(vals[lo : lo + BLAS_BLOCK], a[lo : lo + BLAS_BLOCK], out=t_)  # type: ignore[index]
        total += float(np.dot(t_, b[lo : lo + BLAS_BLOCK]))  # type: ignore[index]
    return total


def axpy(a: float, x: np.ndarray, y: np.ndarray) -> None:
    """y += a x in place (1-D, contiguous), one pass, in blocks (see :data:`BLAS_BLOCK`).

    Long vectors go in spans over the threads, with ufuncs (SciPy's daxpy keeps the GIL).
    """
    n = y.shape[0]
    if n >= PARALLEL_FROM and THREADS > 1:

        def span(lo: int, hi: int) -> None:
            t_ = _span_scratch()[: hi - lo]
            np.multiply(x[lo:hi], a, out=t_)
            np.add(y[lo:hi], t_, out=y[lo:hi])

        in_spans(n, SPAN, span)
        return
    for lo in range(0, n, BLAS_BLOCK):
        blas.daxpy(x[lo : lo + BLAS_BLOCK], y[lo : lo + BLAS_BLOCK], a=a)


def scale(x: np.ndarray, a: float, out: np.ndarray) -> None:
    """out = a x (1-D), in spans over the threads for long vectors."""
    in_spans(out.shape[0], SPAN, lambda lo, hi: np.multiply(x[lo:hi], a, out=out[lo:hi]))
