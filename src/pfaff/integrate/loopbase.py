"""Integrate stage: what the compiled loop's numba code is built on (imported with it).

``cached``, ``helper`` and ``call_entry`` (:mod:`pfaff.numeric.numbacode`: numba's compilation
of the loop and of its helpers, a call through SymEngine's C entry points) and ``copy_into``.
"""

from __future__ import annotations

from pfaff.numeric.numbacode import cached, call_entry, helper

__all__ = ["cached", "call_entry", "copy_into", "helper"]


@helper
def copy_into(src, dst):
    for i in range(src.size):
        dst[i] = src[i]
