"""Compile stage, mid-size systems: the fused kernel alone as machine code, solved with LAPACK.

Up to :data:`pfaff.derive.fused.FUSED_LIMIT` unknowns the whole right-hand side (kernel and
floored range-space solve) is one machine-code function (:func:`pfaff.derive.fused.build_fused`).
Above it the generated solve is too long to write out (O((n + m)³) lines), and the generated
Python kernel was most of a call: one right-hand side of the 32-link chain on a cart cost about
325 µs through it. Here the kernel alone (M, A, Q − h, −(Ȧq̇ + ḃ), b, f: the outputs of ``fn``)
is compiled by SymEngine's LLVM backend and the model solves the assembled KKT system with LAPACK
(without constraints: the Cholesky solve in loops compiled by LLVM's JIT, the kernel called
from them, :mod:`pfaff.numeric.kernelchol`; ``benchmarks/engines.py``).

SymEngine's LLVM compile time grows quickly with the kernel's size (about as n^4.5 for the
chain on a cart as it came: 4.4–5.8 s at 32 unknowns, 32 s at 48). Three levers keep it bounded,
all rules on sizes, never timings: sums of parameters are grouped first
(:func:`collect_parameters`: the chain's mass matrix O(n³) -> O(n²) operations), the kernel is
split into LLVM functions of at most :data:`KERNEL_CHUNK` outputs (:class:`SplitKernel`), and
the optimization level follows n + m (:func:`pfaff.numeric.evaluator.machine_opt_level`). The
result is kept in the on-disk cache (:mod:`pfaff.derive.cache`) as the whole right-hand side of
a small system is; above :data:`pfaff.numeric.evaluator.MACHINE_LIMIT` there is no machine
code and the model evaluates as before.
"""

from __future__ import annotations

import contextlib
import pickle
import threading
from typing import TYPE_CHECKING, Any

import numpy as np
import symengine

from pfaff.derive import cache
from pfaff.numeric.evaluator import machine_opt_level

if TYPE_CHECKING:
    from collections.abc import Callable

KERNEL_CHUNK = 512  # outputs per machine-code function of a kernel (:class:`SplitKernel`)


def cached_machine(
    key: str | None, kind: str, builder: Callable[[], Callable]
) -> Callable[..., Callable | None]:
    """``make(build=True)``: the machine code of ``builder()``, made on its first call and kept in
    memory and under (``key``, ``kind``) in the on-disk cache; ``make(build=False)`` only loads
    it from the cache (None when it is not there). A failure of ``builder`` propagates (the
    caller, :class:`pfaff.numeric.evaluator.MachineCode`, warns and falls back)."""
    done: list = []
    lock = threading.RLock()  # (another thread waits for the build instead of seeing its None)

    def make(build: bool = True) -> Callable | None:
        if done:
            return done[0]
        with lock:
            return done[0] if done else _made(build)

    def _made(build: bool) -> Callable | None:
        raw = cache.load(key, kind) if key is not None else None
        if raw is not None:
            with contextlib.suppress(Exception):
                done.append(pickle.loads(raw))  # our own entry: private folder, hash verified
                return done[0]
        if not build:
            return None
        try:
            made = builder()
        except BaseException:
            done.append(None)  # (a failed build is not tried again)
            raise
        done.append(made)
        if key is not None:
            with contextlib.suppress(Exception):
                cache.store(key, kind, pickle.dumps(done[0]))
        return done[0]

    return make


def kernel_factory(
    n: int, m: int, key: str | None, parts: Callable[[], tuple[list, list]]
) -> Callable[..., Callable | None] | None:
    """``llvm`` of a :class:`pfaff.numeric.fused.FusedKernel` whose solve is not generated: the
    kernel's outputs alone as machine code, ``f(x) -> fn's outputs`` on the same flat input
    ``x = [t, q, q̇, params, alpha, beta, taus, cap]`` as the whole right-hand side (the last
    2 + m + 1 entries unused), or None above :data:`pfaff.numeric.evaluator.MACHINE_LIMIT`.
    ``parts()`` gives (the kernel's output expressions, the arguments ``_t, _y…, _p…``); it is
    called only when the code is built, not when it comes from the cache.

    Examples
    --------
    >>> import symengine as se
    >>> x = se.Symbol("_y0")
    >>> make = kernel_factory(40, 0, None, lambda: ([se.sin(x), 2 * x], [se.Symbol("_t"), x]))
    >>> [round(v, 12) for v in make()([0.0, 0.5, 0.0, 0.0, 0.0]).tolist()]
    [0.479425538604, 1.0]
    >>> kernel_factory(400, 0, None, lambda: ([], [])) is None
    True
    """
    level = machine_opt_level(n, m)
    if level is None:
        return None
    return cached_machine(key, f"kernel{level}", lambda: _kernel(*parts(), m, level))


def _kernel(exprs: list, args: list, m: int, level: int) -> Callable:
    se = symengine
    inputs = [se.Symbol(str(a)) for a in args]  # _t, _y…, _p…
    inputs += [se.Symbol(name) for name in ("_alpha", "_beta")]
    inputs += [se.Symbol(f"_tau{j}") for j in range(m)] + [se.Symbol("_cap")]
    params = {a for a in inputs if str(a).startswith("_p")}
    outs = collect_parameters([se.sympify(e) for e in exprs], params)
    count = -(-len(outs) // KERNEL_CHUNK)  # functions, of equal numbers of outputs
    step = -(-len(outs) // count) if outs else 1
    chunks = [outs[a : a + step] for a in range(0, max(len(outs), 1), step)]
    return SplitKernel(
        [
            se.Lambdify(inputs, chunk, backend="llvm", cse=True, real=True, opt_level=level)
            for chunk in chunks
        ],
        [len(chunk) for chunk in chunks],
    )


class SplitKernel:
    """Machine-code functions of the same input whose outputs, side by side, are the kernel's.

    SymEngine's LLVM compile time grows faster than the function (the 64-link chain on a cart,
    its sums grouped, at opt_level 2: 11.3 s as one function of 2210 outputs, 4.1 s as four of
    553, measured on this project's busy machine; the same call time, 18 µs): so the kernel is
    compiled as functions of at most :data:`KERNEL_CHUNK` outputs, each with its own common
    subexpressions (those shared across functions are computed once in each: sines and cosines
    of the angles, sums of parameters). It is called like one of SymEngine's functions.

    Attributes
    ----------
    parts : list
        The LLVM functions (``LLVMDouble``), in output order; ``parts[k]`` writes
        ``out[offsets[k] : offsets[k + 1]]``.
    offsets : list of int

    Examples
    --------
    >>> import symengine as se
    >>> x = se.Symbol("x")
    >>> f = SplitKernel([se.Lambdify([x], [x, 2 * x], backend="llvm"),
    ...                  se.Lambdify([x], [se.cos(x)], backend="llvm")], [2, 1])
    >>> f(np.array([0.0])).tolist()
    [0.0, 0.0, 1.0]
    """

    def __init__(self, parts: list, sizes: list[int]) -> None:
        self.parts = parts
        self.offsets = [0, *np.cumsum(sizes).tolist()]

    def __call__(self, x: np.ndarray) -> np.ndarray:
        out = np.empty(self.offsets[-1])
        self.unsafe_real(np.ascontiguousarray(x, dtype=float), out)
        return out

    def unsafe_real(self, x: np.ndarray, out: np.ndarray) -> None:
        """``out[:] = kernel(x)``, unchecked: x and out contiguous float64 of the right sizes."""
        for part, start in zip(self.parts, self.offsets):  # noqa: B905 - one more offset
            part.unsafe_real(x, out, 0, start)


def collect_parameters(exprs: list, params: set) -> list:
    """The same expressions with each sum's terms grouped by their factor that is not a product
    of parameters: Σ_k X·p_k -> X·(Σ_k p_k), in sums at every depth.

    A chain's mass-matrix entry M_ij = X_ij·(m_j + … + m_n) arrives as n − j products, one per
    mass beyond the joint: O(n) operations per entry and O(n³) for M, all through LLVM (the
    kernel of the 64-link chain on a cart: 2.9e5 µs a call at opt_level 0). Grouped, the sums of
    parameters are shared between entries by the common subexpressions and M costs O(n²)
    (33 unknowns: 20 400 operations after CSE -> 9 000, the call 9.7 -> 5.8 µs, the compile at
    opt_level 2 3.5 -> 1.1 s). Equal up to rounding (the sums are reassociated). Used for the
    kernel alone, not for the whole right-hand side of small systems
    (:func:`pfaff.derive.fused.build_fused`): there, through the 24 folds of the square
    four-bar in ``tests/integrate/test_simulate_fourbar.py``, it moved the angle after 10 s by
    9e-6 instead of 1.2e-7 (the kernel alone, grouped, solved with LAPACK: 9e-8).

    Parameters
    ----------
    exprs : list of SymEngine expressions
    params : set of SymEngine symbols
        The parameters (``_p…``): their products and sums are the coefficients.

    Examples
    --------
    >>> import symengine as se
    >>> x, y, a, b = se.symbols("x y a b")
    >>> collect_parameters([a * x + b * x + a * y, 2 * a * x - 3 * b * x], {a, b})
    [a*y + x*(a + b), x*(2*a - 3*b)]
    """
    memo: dict = {}

    def walk(e: Any) -> Any:
        got = memo.get(e)
        if got is not None:
            return got
        if isinstance(e, symengine.Add):
            groups: dict = {}
            for term in e.args:
                factors = term.args if isinstance(term, symengine.Mul) else (term,)
                coef, rest = [], []
                for f in factors:
                    plain = f.free_symbols <= params  # (numbers too: 2a·x + 3b·x -> x(2a + 3b))
                    (coef if plain else rest).append(f if plain else walk(f))
                key = symengine.Mul(*rest) if rest else symengine.Integer(1)
                groups.setdefault(key, []).append(
                    symengine.Mul(*coef) if coef else symengine.Integer(1)
                )
            out = symengine.Add(*[k * symengine.Add(*c) for k, c in groups.items()])
        elif isinstance(e, symengine.Mul):
            out = symengine.Mul(*[walk(f) for f in e.args])
        elif isinstance(e, symengine.Pow):
            out = symengine.Pow(walk(e.args[0]), e.args[1])
        else:
            out = e
        memo[e] = out
        return out

    return [walk(e) for e in exprs]
