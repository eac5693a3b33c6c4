"""The right-hand side of a mid-size model without constraints as one compiled call (llvmlite).

Used by :func:`pfaff.numeric.kernelsolve.kernel_rhs`, where llvmlite is installed (else the model
solves with SciPy's LAPACK wrappers, as before). The function calls the machine-code kernel's
LLVM functions through their C entry points (:func:`pfaff.numeric.machineloop.entry_point`),
writes M's upper triangle from the kernel's outputs, and solves M q̈ = Q − h by the Cholesky
factorization M = UᵀU in compiled loops: no return to Python between the kernel, the
factorization and the two triangular solves.

Why not LAPACK: at these sizes SciPy's ``dppsv`` is the factorization's level-2 BLAS calls, one
per column, behind the wrapper's argument checks; the loops here write M from the outputs,
factor and solve it in about 5.6 µs at 33 unknowns against 7.6 µs for ``dppsv`` on the packed
outputs (CPU medians on this project's machine), and the 32-link chain on a cart's right-hand
side costs about Pinocchio's ``aba`` (``benchmarks/engines.py``). The algorithm is LAPACK's
unblocked ``dpotf2`` (right-looking, the pivot's reciprocal scaling its row), in IEEE arithmetic
(no fast-math, no contraction into fused multiply-adds): the results agree with the LAPACK path to
rounding.

Why llvmlite's IR builder and not numba: the function is a few loops, written here as LLVM IR
and compiled by LLVM's JIT in each process in 0.1–0.25 s of CPU (:func:`compile_solver`); numba's
import and start cost 0.35–0.95 s of CPU in the first right-hand side of every process (issue
25: +14–18 % on a cold build of the 32-link chain). llvmlite is the library numba generates its
code with; no disk cache is needed.

The plan (``int64``) is [n, parts, entries, outputs, (address, data, offset) per LLVM function,
the flat index i·n + j (i ≤ j) of each M entry in output order]; the work array (float64) is
[the kernel's outputs | W: n × n | q̇, q̈].
"""

from __future__ import annotations

import contextlib
import ctypes
import threading
import warnings
from collections.abc import Callable
from typing import Any

import llvmlite.binding as llvm
import llvmlite.ir as ir
import numpy as np

HEAD = 4  # the plan's leading integers: n, parts, entries, outputs
_I64, _F64 = ir.IntType(64), ir.DoubleType()
_PD, _PI, _PV = _F64.as_pointer(), _I64.as_pointer(), ir.IntType(8).as_pointer()
_NUW = ("nuw", "nsw")  # (indices never wrap: LLVM may vectorize the row updates)
Solver = Callable[[int, int, int], int]


class _Code:
    """Loops and memory in IR: a builder with the helpers the function below is written in."""

    def __init__(self, b: ir.IRBuilder, entry: ir.Block) -> None:
        self.b, self.entry = b, entry

    def const(self, v: int) -> ir.Constant:
        return ir.Constant(_I64, v)

    def add(self, x: Any, y: Any) -> Any:
        return self.b.add(x, y, flags=_NUW)

    def mul(self, x: Any, y: Any) -> Any:
        return self.b.mul(x, y, flags=_NUW)

    def at(self, base: Any, i: Any) -> Any:
        return self.b.gep(base, [i], inbounds=True)

    def load(self, base: Any, i: Any) -> Any:
        return self.b.load(self.at(base, i))

    def store(self, v: Any, base: Any, i: Any) -> None:
        self.b.store(v, self.at(base, i))

    def var(self, ty: ir.Type, init: Any) -> Any:
        """A local variable (an alloca in the entry block, which LLVM turns into registers)."""
        with self.b.goto_block(self.entry):
            self.b.position_at_start(self.entry)
            slot = self.b.alloca(ty)
        self.b.store(init, slot)
        return slot

    def loop(self, start: Any, stop: Any, body: Callable[[Any], None]) -> None:
        """``for i in range(start, stop): body(i)`` (unsigned i)."""
        b = self.b
        before = b.block
        head, inner, done = (b.append_basic_block() for _ in range(3))
        b.branch(head)
        b.position_at_end(head)
        i = b.phi(_I64)
        i.add_incoming(start, before)
        b.cbranch(b.icmp_unsigned("<", i, stop), inner, done)
        b.position_at_end(inner)
        body(i)
        i.add_incoming(self.add(i, self.const(1)), b.block)
        b.branch(head)
        b.position_at_end(done)


def _module() -> ir.Module:
    """``int64 kernel_cholesky(int64 *plan, double *x, double *work)``: the kernel's outputs of
    ``x`` = [t, q, q̇, …] into ``work``, then [q̇, q̈] at its end; returns 0, a pivot's position
    + 1 (M not positive definite there), or −1 (q̈ not finite)."""
    mod = ir.Module(name="pfaff_kernelchol")
    fn = ir.Function(mod, ir.FunctionType(_I64, [_PI, _PD, _PD]), name="kernel_cholesky")
    plan, x, work = fn.args
    for arg in fn.args:  # (three separate arrays: LLVM may keep values in registers)
        arg.add_attribute("noalias")
    entry = fn.append_basic_block("entry")
    b = ir.IRBuilder(entry)
    c = _Code(b, entry)
    one, zero = c.const(1), ir.Constant(_F64, 0.0)
    n, parts, entries, size = (c.load(plan, c.const(k)) for k in range(HEAD))
    kernel = ir.FunctionType(_PV, [_PD, _PD, _PV])

    def call(p: Any) -> None:  # LLVM function p of the kernel: f(out + offset, x, data)
        a = c.add(c.const(HEAD), c.mul(c.const(3), p))
        address, data = c.load(plan, a), c.load(plan, c.add(a, one))
        offset = c.load(plan, c.add(a, c.const(2)))
        f = b.inttoptr(address, kernel.as_pointer())
        b.call(f, [c.at(work, offset), x, b.inttoptr(data, _PV)])

    c.loop(c.const(0), parts, call)
    w = c.at(work, size)
    nn = c.mul(n, n)
    res = c.at(w, nn)
    rhs = c.at(res, n)
    c.loop(c.const(0), nn, lambda i: c.store(zero, w, i))
    first = c.add(c.const(HEAD), c.mul(c.const(3), parts))
    c.loop(
        c.const(0), entries, lambda e: c.store(c.load(work, e), w, c.load(plan, c.add(first, e)))
    )
    c.loop(c.const(0), n, lambda i: c.store(c.load(work, c.add(entries, i)), rhs, i))
    _factor(c, w, n)
    _solve(c, w, rhs, n)
    total = c.var(_F64, zero)

    def copy(i: Any) -> None:  # q̇ before q̈; the sum of q̈ for the finiteness test
        c.store(c.load(x, c.add(c.add(one, n), i)), res, i)
        b.store(b.fadd(b.load(total), c.load(rhs, i)), total)

    c.loop(c.const(0), n, copy)
    s = b.load(total)
    finite = b.fcmp_ordered("==", b.fsub(s, s), zero)  # (inf − inf and NaN are not 0)
    b.ret(b.select(finite, c.const(0), c.const(-1)))
    return mod


def _factor(c: _Code, w: Any, n: Any) -> None:
    """W = UᵀU in place (W's upper triangle, row-major); returns k + 1 from the function where
    the k-th pivot is not positive."""
    b, one = c.b, c.const(1)

    def column(k: Any) -> None:
        kn = c.mul(k, n)
        kk = c.add(kn, k)
        d = c.load(w, kk)
        with b.if_then(b.not_(b.fcmp_ordered(">", d, ir.Constant(_F64, 0.0))), likely=False):
            b.ret(c.add(k, one))
        d = b.call(_sqrt(b), [d])
        c.store(d, w, kk)
        r = b.fdiv(ir.Constant(_F64, 1.0), d)
        k1 = c.add(k, one)
        c.loop(k1, n, lambda j: c.store(b.fmul(c.load(w, c.add(kn, j)), r), w, c.add(kn, j)))

        def row(i: Any) -> None:
            s = c.load(w, c.add(kn, i))
            i_n = c.mul(i, n)

            def update(j: Any) -> None:
                at = c.add(i_n, j)
                c.store(b.fsub(c.load(w, at), b.fmul(s, c.load(w, c.add(kn, j)))), w, at)

            c.loop(i, n, update)

        c.loop(k1, n, row)

    c.loop(c.const(0), n, column)


def _solve(c: _Code, w: Any, v: Any, n: Any) -> None:
    """Uᵀ z = v, then U x = z, in place in ``v``."""
    b, one = c.b, c.const(1)

    def forward(k: Any) -> None:
        kn = c.mul(k, n)
        z = b.fdiv(c.load(v, k), c.load(w, c.add(kn, k)))
        c.store(z, v, k)

        def update(j: Any) -> None:
            c.store(b.fsub(c.load(v, j), b.fmul(c.load(w, c.add(kn, j)), z)), v, j)

        c.loop(c.add(k, one), n, update)

    c.loop(c.const(0), n, forward)

    def backward(kk: Any) -> None:
        k = b.sub(b.sub(n, one), kk)
        kn = c.mul(k, n)
        s = c.var(_F64, c.load(v, k))

        def update(j: Any) -> None:
            b.store(b.fsub(b.load(s), b.fmul(c.load(w, c.add(kn, j)), c.load(v, j))), s)

        c.loop(c.add(k, one), n, update)
        c.store(b.fdiv(b.load(s), c.load(w, c.add(kn, k))), v, k)

    c.loop(c.const(0), n, backward)


def _sqrt(b: ir.IRBuilder) -> ir.Function:
    mod = b.module
    try:
        return mod.get_global("llvm.sqrt.f64")
    except KeyError:
        return ir.Function(mod, ir.FunctionType(_F64, [_F64]), name="llvm.sqrt.f64")


_ENGINE: list = []  # the JIT engine and its module, kept alive with the process
_LOCK = threading.Lock()


def compile_solver() -> Solver:
    """The compiled ``kernel_cholesky`` as ``f(plan address, x address, work address) -> int``
    (ctypes): made once per process by LLVM's JIT at optimization level 3 (0.1–0.25 s of CPU).

    Examples
    --------
    A 1 × 1 system of no LLVM function: M = [4], Q − h = [3], so q̈ = 0.75 (q̇ = x[2] = 0.25).

    >>> plan, work = plan_of([], np.zeros(1, dtype=np.int64), 1, 2)
    >>> work[:2] = 4.0, 3.0
    >>> x = np.array([0.0, 0.0, 0.25])
    >>> compile_solver()(plan.ctypes.data, x.ctypes.data, work.ctypes.data), work[-2:].tolist()
    (0, [0.25, 0.75])
    """
    with _LOCK:
        if not _ENGINE:
            _ENGINE[:] = _compiled()
    return _ENGINE[1]


def _compiled() -> list:
    """[the JIT engine, the function]: ``kernel_cholesky`` optimized and compiled for this CPU."""
    with warnings.catch_warnings():  # (llvmlite 0.44 needs it; later ones refuse it)
        warnings.simplefilter("ignore", DeprecationWarning)
        with contextlib.suppress(RuntimeError):
            llvm.initialize()
    llvm.initialize_native_target()
    llvm.initialize_native_asmprinter()
    target = llvm.Target.from_default_triple().create_target_machine(
        cpu=llvm.get_host_cpu_name(),
        features=llvm.get_host_cpu_features().flatten(),
        opt=3,
        jit=True,
    )  # (this machine's vector instructions, as numba and SymEngine's LLVM use them)
    parsed = llvm.parse_assembly(str(_module()))
    parsed.triple, parsed.data_layout = target.triple, str(target.target_data)  # (optimized for it)
    parsed.verify()
    builder = llvm.create_pass_builder(target, llvm.create_pipeline_tuning_options(speed_level=3))
    builder.getModulePassManager().run(parsed, builder)
    engine = llvm.create_mcjit_compiler(parsed, target)
    engine.finalize_object()
    kind = ctypes.CFUNCTYPE(ctypes.c_int64, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
    return [engine, kind(engine.get_function_address("kernel_cholesky"))]


def kernel_cholesky(plan: np.ndarray, x: np.ndarray, work: np.ndarray) -> int:
    """The compiled function on arrays made by :func:`plan_of` and an ``x`` of the kernel's
    inputs (their dtypes, contiguity and the sizes ``plan`` names are checked, not the plan's
    indices): 0, a pivot's position + 1, or −1; [q̇, q̈] at the end of ``work``. A right-hand side calls the compiled
    function on its arrays' addresses instead (:func:`pfaff.numeric.kernelsolve.kernel_rhs`).

    Examples
    --------
    M = [[1, 2], [2, 1]] is indefinite: its second pivot, 1 − 4, is not positive.

    >>> plan, work = plan_of([], np.array([0, 1, 3]), 2, 5)
    >>> work[:5] = 1.0, 2.0, 1.0, 1.0, 1.0
    >>> kernel_cholesky(plan, np.zeros(5), work)
    2
    """
    n = int(plan[0])
    if not (
        plan.dtype == np.int64 and x.dtype == work.dtype == np.float64
        and plan.flags.c_contiguous and x.flags.c_contiguous and work.flags.c_contiguous
        and x.size >= 1 + 2 * n and work.size >= int(plan[3]) + n * n + 2 * n
    ):  # fmt: skip
        raise ValueError("kernel_cholesky: plan (int64), x and work (float64) of plan_of's sizes")
    return int(compile_solver()(plan.ctypes.data, x.ctypes.data, work.ctypes.data))


def plan_of(
    functions: list[tuple[int, int, int]], upper: np.ndarray, n: int, size: int
) -> tuple[np.ndarray, np.ndarray]:
    """(plan, work) of the compiled function: ``functions`` the (address, data, offset) of each
    LLVM function, ``upper`` the flat index i·n + j of each M entry among the kernel's first
    outputs, ``size`` the kernel's outputs."""
    plan = [n, len(functions), len(upper), size]
    for f in functions:
        plan.extend(f)
    plan.extend(np.asarray(upper).tolist())
    return np.array(plan, dtype=np.int64), np.zeros(size + n * n + 2 * n)
