"""Integrate stage: what the compiled loop's numba code is built on (imported with it).

``cached``, ``helper`` and ``inlined`` (numba's compilation of the loop and of its helpers),
``call_entry`` (a call through a C entry point ``void *f(double *out, const double *in, void
*data)``, SymEngine's LLVM functions': :mod:`pfaff.numeric.machineloop`) and ``copy_into``.
"""

from __future__ import annotations

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

# Every function of the loop is compiled without numba's runtime (NRT, the numba option
# ``_nrt``): they allocate nothing, and with it every array argument of every call was counted
# in and out by atomic increments, which took about half of the loop's time (the Cartesian
# pendulum's run of benchmarks/loop.py: 0.15 s, 0.09 s without them). The arrays all belong to
# the caller (loop._Buffers), alive for the whole call.
_OPTIONS = {"error_model": "numpy", "_nrt": False}


def helper(fn):
    """A helper of :func:`advance`: compiled with it (and kept in its cache entry)."""
    return njit(**_OPTIONS)(fn)


def inlined(fn):
    """A small helper of :func:`advance` called in its innermost loops: inlined where called
    (a call passes every array as its seven fields: 30 ns a call of ``_rhs``, about what the
    model's right-hand side itself costs)."""
    return njit(inline="always", **_OPTIONS)(fn)


def cached(fn):
    """``njit`` with numba's on-disk cache (beside this file, or numba's user-wide folder when
    that is read-only, or ``NUMBA_CACHE_DIR``); without it where no folder is writable."""
    try:
        return njit(cache=True, **_OPTIONS)(fn)
    except RuntimeError:  # "no locator available": compiled once per process instead
        return njit(**_OPTIONS)(fn)


@intrinsic
def call_entry(typingctx, addr, out, inp, data):
    """Call ``void *f(double *out, const double *in, void *data)`` at the address ``addr``."""
    sig = types.void(types.int64, out, inp, types.int64)

    def codegen(context, builder, signature, args):
        a, o, i, d = args
        dptr, vptr = ir.DoubleType().as_pointer(), ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(vptr, [dptr, dptr, vptr])
        fptr = builder.inttoptr(a, fnty.as_pointer())
        oarr = context.make_array(signature.args[1])(context, builder, o)
        iarr = context.make_array(signature.args[2])(context, builder, i)
        builder.call(fptr, [oarr.data, iarr.data, builder.inttoptr(d, vptr)])
        return context.get_dummy_value()

    return sig, codegen


@inlined
def copy_into(src, dst):
    for i in range(src.size):
        dst[i] = src[i]
