"""Integrate stage: what the compiled loop's numba code is built on (imported with it).

``cached``, ``helper`` and ``inlined`` (numba's compilation of the loop and of its helpers,
without numba's runtime), ``call_entry`` (:mod:`pfaff.numeric.numbacode`: a call through a C
entry point, SymEngine's LLVM functions') and ``copy_into``.
"""

from __future__ import annotations

from pfaff.numeric import numbacode
from pfaff.numeric.numbacode import call_entry

__all__ = ["cached", "call_entry", "copy_into", "helper", "inlined"]

# Every function of the loop is compiled without numba's runtime (NRT, the numba option
# ``_nrt``): they allocate nothing, and with it every array argument of every call was counted
# in and out by atomic increments, which took about half of the loop's time (the Cartesian
# pendulum's run of benchmarks/loop.py: 0.15 s, 0.09 s without them). The arrays all belong to
# the caller (loop._Buffers), alive for the whole call.
BARE = {"_nrt": False}


def helper(fn):
    """A helper of :func:`advance`: compiled with it (and kept in its cache entry)."""
    return numbacode.helper(fn, **BARE)


def inlined(fn):
    """A small helper of :func:`advance` called in its innermost loops: inlined where called
    (a call passes every array as its seven fields: 30 ns a call of ``_rhs``, about what the
    model's right-hand side itself costs)."""
    return numbacode.helper(fn, inline="always", **BARE)


def cached(fn):
    """:func:`pfaff.numeric.numbacode.cached` without numba's runtime."""
    return numbacode.cached(fn, **BARE)


@inlined
def copy_into(src, dst):
    for i in range(src.size):
        dst[i] = src[i]
