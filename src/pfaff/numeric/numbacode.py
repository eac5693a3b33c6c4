"""What pfaff's numba code is built on (imported only with that code, never with ``pfaff``).

``cached`` and ``helper`` (numba's compilation of a function, with or without its own entry in
numba's on-disk cache) and ``call_entry`` (a call through a C entry point
``void *f(double *out, const double *in, void *data)``, SymEngine's LLVM functions':
:func:`pfaff.numeric.machineloop.entry_point`). Used by the compiled right-hand side of mid-size
models (:mod:`pfaff.numeric.kernelchol`) and the compiled stepping loop
(:mod:`pfaff.integrate.loopkernel`).
"""

from __future__ import annotations

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic


def helper(fn, **options):
    """A helper of a cached function: compiled with it (and kept in its cache entry);
    ``options`` are numba's (``inline="always"``, ``_nrt=False``)."""
    return njit(error_model="numpy", **options)(fn)


def cached(fn, **options):
    """``njit`` with numba's on-disk cache (beside the module, or numba's user-wide folder when
    that is read-only, or ``NUMBA_CACHE_DIR``); without it where no folder is writable."""
    try:
        return njit(cache=True, error_model="numpy", **options)(fn)
    except RuntimeError:  # "no locator available": compiled once per process instead
        return njit(error_model="numpy", **options)(fn)


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
