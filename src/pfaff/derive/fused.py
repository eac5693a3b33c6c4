"""Compile stage, small systems: one fused scalar kernel for the whole KKT system.

For a handful of coordinates the vectorized template kernels of :mod:`pfaff.derive.codegen` spend their
time in NumPy call overhead on arrays of length one. Here the whole system — M, A, Q - h, b,
Ȧq̇ + ḃ and f — is generated as a single Python function on floats (``math`` module, common
subexpressions shared), whose flat output is scattered into the dense augmented matrix by
precomputed indices. The result is checked against the template kernels before it is used.
"""

from __future__ import annotations

import json
import math
import re
from typing import TYPE_CHECKING

import numpy as np
import symengine
import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from pfaff.core.symbols import accel, t
from pfaff.derive import cache
from pfaff.derive.engine import engine_safe
from pfaff.derive.fusedpower import power_expression
from pfaff.derive.loopcode import loop_factory
from pfaff.derive.machine_kernel import cached_machine, kernel_factory
from pfaff.numeric.checkedsolve import PASS
from pfaff.numeric.fused import FusedKernel
from pfaff.numeric.generated import Portable, register
from pfaff.numeric.smallsolve import NAMESPACE, schur_expressions, schur_solver, schur_source

if TYPE_CHECKING:
    from collections.abc import Callable

    from pfaff.derive.equations import Derivation

FUSED_LIMIT = 32  # n + m up to which a fused scalar kernel and its generated solve are made
CHECKS = 3  # the pivot checks at the end of the machine code's outputs (FusedKernel.checks)
KERNEL_LIMIT = 128  # up to which the fused kernel alone serves models of distinct pieces


def _plain(eom: Derivation) -> tuple[dict, list[sp.Symbol]]:
    """One replacement, applied in one pass, to the names of the generated code: t -> ``_t``,
    q(t) -> ``_y{i}``, q̇(t) -> ``_y{n+i}``, q̈ -> 0, parameters -> ``_p{k}``; and the new
    argument symbols in order (q̈ and q̇ match as whole nodes before the q inside them)."""
    n = eom.n
    args = [
        sp.Symbol("_t"),
        *(sp.Symbol(f"_y{i}") for i in range(2 * n)),
        *(sp.Symbol(f"_p{k}") for k in range(len(eom.parameters))),
    ]
    rule: dict = {accel(c): sp.S.Zero for c in eom.coordinates}
    rule.update(zip([t, *eom.coordinates, *eom.speeds, *eom.parameters], args, strict=True))
    return rule, args


def build_fused(eom: Derivation) -> tuple[FusedKernel | None, str]:
    """Generate the fused kernel of a small system (None when it is too big) and say where its
    code came from: ``"hit"``, ``"miss"`` or ``"off"`` (the on-disk cache).

    The generated source and, once made, the machine code are kept in the on-disk cache
    (:mod:`pfaff.derive.cache`), so a model compiled before is not generated again."""
    n, m = eom.n, eom.m
    if not _fusable(eom):
        return None, "off"
    solve = n + m <= FUSED_LIMIT
    key = cache.model_key(eom) if cache.cache_dir() is not None else None
    code, fns = _cached_code(key, n) if key is not None else (None, None)
    status = "off" if key is None else "hit"
    if code is None or fns is None:
        code, fns = _generated_code(eom)
        status = "off" if key is None else "miss"
        if key is not None and fns[2]:
            cache.store(key, "code", json.dumps(code).encode())
    mass = [tuple(x) for x in code["mass"]]
    acon = [tuple(x) for x in code["acon"]]
    fn, vfn, _, efn = fns
    rfn = rfn_aug = cfn = afn = None  # the generated solve: straight-line code of O((n + m)³)
    if solve:
        rfn = _rhs_function(code["body"], code["outs"], mass, acon, n, m, len(eom.parameters))
        afn = _on_first_call(  # a checked accelerations() call's: made on its first call
            lambda: _rhs_function(
                code["body"], code["outs"], mass, acon, n, m, len(eom.parameters), checked=True
            )
        )
        rfn_aug = _on_first_call(  # needed only where M is singular (quaternions): made then
            lambda: _rhs_function(
                code["body"], code["outs"], mass, acon, n, m, len(eom.parameters), augmented=True
            )
        )
        cfn = schur_solver(n, m, mass, acon, damped=True)
    N = n + m
    index, source = [], []
    for s, (i, j) in enumerate(mass):
        index += [i * N + j, j * N + i] if i != j else [i * N + j]
        source += [s, s] if i != j else [s]
    for s, (i, j) in enumerate(acon, start=len(mass)):
        index += [(n + i) * N + j, j * N + n + i]
        source += [s, s]
    entries = [i * N + j for i, j in mass] + [(n + i) * N + j for i, j in acon]
    off = len(mass) + len(acon)
    return FusedKernel(
        fn,
        vfn,
        efn,
        rfn,
        cfn,
        np.array(index, dtype=np.int64),
        np.array(source, dtype=np.int64),
        np.array(entries, dtype=np.int64),
        (off, off + n, off + n + m, off + n + 2 * m),
        tuple(i for i, _ in acon),
        tuple(j for _, j in acon),
        _llvm_factory(eom, key) if solve else kernel_factory(n, m, key, lambda: _kernel_parts(eom)),
        rfn_aug,
        solve,
        _operations(code["body"] + code["outs"]),
        _on_first_call(lambda: power_function(eom)),
        afn,
        CHECKS if solve else 0,
        loop_factory(n, m, key, lambda: _loop_parts(eom)) if solve else None,
    ), status


def _loop_parts(eom: Derivation) -> tuple[list, int, object, list]:
    """What the compiled loop's machine code is made of (:mod:`pfaff.derive.loopcode`)."""
    (mass, acon, exprs, _), args = _parts(eom)
    return exprs, len(mass) + len(acon), power_expression(eom, _plain(eom)[0], args), args


def power_function(eom: Derivation) -> Callable | None:
    """``pfn(t, q…, q̇…, *params) -> [P]`` (:attr:`FusedKernel.pfn`): the power of the applied
    forces (:func:`pfaff.derive.fusedpower.power_expression`) printed as the kernel is; None
    without applied forces.

    Examples
    --------
    >>> import pfaff
    >>> pfn = power_function(pfaff.models.n_link_pendulum_on_cart(1).equations())
    >>> pfn(0.0, 0.0, 0.3, 2.0, 0.5, 0.7, 9.81, 1.0, 1.0, 1.0)  # F = 0.7 pushes the cart at 2 m/s
    [1.4]
    """
    rule, args = _plain(eom)
    P = power_expression(eom, rule, args)
    if P is None:
        return None
    body, outs, names = _shared_code([P], args)
    return _function("pfn", names, body, outs, MATH)


def _operations(lines: list[str]) -> int:
    """Operators and calls in printed code: the kernel's size for the evaluator rule."""
    return sum(len(_OPERATION.findall(line)) for line in lines)


_OPERATION = re.compile(r"[-+*/(]")


class _on_first_call:
    """A function that generates the function ``build`` returns on its first call, then calls
    it (``ValueError`` when it could not be generated). It pickles as that function."""

    def __init__(self, build: Callable[[], Callable | None]) -> None:
        self.build, self.made = build, None

    def _get(self) -> Callable:
        if self.build is not None:  # (once: a build that made nothing is not tried again)
            self.made, self.build = self.build(), None
        if self.made is None:
            raise ValueError("the generated function could not be made")
        return self.made

    def __call__(self, *args: object) -> object:
        return self._get()(*args)

    def function(self) -> Callable | None:
        """The function, made now if it was not yet; None when it cannot be made."""
        try:
            return self._get()
        except ValueError:
            return None

    def __reduce__(self) -> tuple:
        try:
            return (Portable.load, (Portable.of(self._get()),))
        except ValueError:
            return (_on_first_call, (_nothing,))  # unpickled: still nothing (function() None)


def _nothing() -> None:
    """The build of a generated function that could not be made (it pickles as this)."""
    return None


def _fusable(eom: Derivation) -> bool:
    """Small systems (n + m ≤ ``FUSED_LIMIT``) get the fused kernel and the generated solve;
    up to ``KERNEL_LIMIT``, systems of distinct pieces (a chain of rigid bodies, each its own
    template with expressions growing along the chain) get the fused kernel alone: one common-
    subexpression pass in SymEngine instead of a ``lambdify`` per template (the first
    ``accelerations()`` of 8 quaternion rods took 5 s that way, against 0.02 s). Repeated pieces
    (a ring of particles) keep the vectorized template kernels."""
    size = eom.n + eom.m
    if size <= FUSED_LIMIT:
        return True
    if size > KERNEL_LIMIT or eom.family:
        return False
    instances = sum(b.n_inst for b in eom.blocks)
    return instances <= 2 * len(eom.blocks)


def _parts(eom: Derivation) -> tuple[tuple, list]:
    """(mass pattern, A pattern, outputs, energies) in SymEngine when possible, and the
    arguments of the generated code."""
    rule, args = _plain(eom)
    parts = _engine_parts(eom, args)
    if parts is None:  # SymPy's assembly, renamed (a function SymEngine does not share)
        parts = _sympy_parts(eom, rule)
    return parts, args


def _generated_code(eom: Derivation) -> tuple[dict, tuple]:
    """The generated source (a JSON-able dict) and its functions (fn, vfn, whether vfn is the
    source itself, efn)."""
    (mass, acon, exprs, energies), args = _parts(eom)
    body, outs, names = _shared_code(exprs, args)
    ebody, eouts, _ = _shared_code(energies, args)
    code = {"mass": mass, "acon": acon, "names": names, "body": body, "outs": outs,
            "ebody": ebody, "eouts": eouts}  # fmt: skip
    fn, vfn = _functions(names, body, outs, exprs, args)
    efn = _functions(names, ebody, eouts, energies, args)[1]
    same = vfn.__name__ == "vfn" and efn.__name__ == "vfn"  # not lambdify's: cacheable
    return code, (fn, vfn, same, efn)


def _cached_code(key: str, n: int) -> tuple[dict | None, tuple | None]:
    """The cached source of ``key`` and its functions, checked as when generated; (None, None)
    when absent or when its vectorized twin does not pass the check."""
    raw = cache.load(key, "code")
    if raw is None:
        return None, None
    try:
        code = json.loads(raw)
        names, body, outs = code["names"], code["body"], code["outs"]
        fn, vfn = _functions(names, body, outs, None, [])
        efn = _functions(names, code["ebody"], code["eouts"], None, [])[1]
    except Exception:
        return None, None
    if vfn is None or efn is None or len(names) < 1 + 2 * n:
        return None, None
    return code, (fn, vfn, True, efn)


def _sympy_parts(eom: Derivation, rule: dict) -> tuple:
    """(mass pattern, A pattern, outputs, [T, V, T(q, 0, t)]) from the Derivation's SymPy
    assembly (:attr:`Derivation.numeric_parts`), renamed to the generated code's names."""
    n, m = eom.n, eom.m
    parts = eom.numeric_parts  # as derived: no simplification for reading
    Me, A = parts.mass, eom.constraint_matrix
    mass = sorted((i, j) for i, j in Me if i <= j)
    acon = [(i, j) for i in range(m) for j in range(n) if A[i, j] != 0]
    bias = [
        e.xreplace({accel(c): 0 for c in eom.coordinates}) for e in eom.acceleration_constraints
    ]
    f = [sp.S.Zero if e is None else e for e in eom.holonomic_constraints]
    exprs = (
        [Me[i, j] for i, j in mass]
        + [A[i, j] for i, j in acon]
        + list(parts.forcing)
        + [-e for e in bias]
        + list(eom.constraint_bias)
        + f
    )
    plain = [sp.sympify(e).xreplace(rule) for e in exprs]
    T, V = (sp.sympify(e).xreplace(rule) for e in (parts.kinetic, parts.potential))
    T0 = T.xreplace({rule[s]: sp.S.Zero for s in eom.speeds})
    return mass, acon, plain, [T, V, T0]


def _engine_parts(eom: Derivation, args: list) -> tuple | None:
    """The same outputs assembled in SymEngine from the templates' local forms: each template
    converted once, each instance a substitution of names (on the 20-link chain about half of
    ``compile()`` was SymPy's assembly and renaming). None when a template has a function
    SymEngine does not share with SymPy."""
    n, m = eom.n, eom.m
    se = symengine
    y = [se.Symbol(str(a)) for a in args]  # _t, _y…, _p…
    base = {se.Symbol("t"): y[0]}
    base.update({se.Symbol(str(p)): y[1 + 2 * n + k] for k, p in enumerate(eom.parameters)})
    M: dict = {}
    A: dict = {}
    F = [se.Integer(0)] * n
    b, nbias, f = ([se.Integer(0)] * m for _ in range(3))
    T = V = se.Integer(0)
    if len({p.name for p in eom.parameters} | {"t"}) != len(eom.parameters) + 1:
        return None  # two parameters of one name, or one named t: SymEngine would merge them
    try:
        for block in eom.blocks:
            loc = block.local
            exprs = [*loc.Q.values()]
            if loc.engine is None:  # derived in SymPy: the round trip must be exact
                exprs += [*loc.mass.values(), *loc.h.values(), loc.kinetic, loc.potential]
                exprs += [*loc.A.values(), loc.b, loc.bias]
                exprs += [] if loc.f is None else [loc.f]
            if not engine_safe(exprs):
                return None
            conv = _Converted(loc)
            for i, idx in enumerate(block.coords.tolist()):
                sub = dict(base)
                sub.update({se.Symbol(f"_q{a}"): y[1 + c] for a, c in enumerate(idx)})
                sub.update({se.Symbol(f"_qd{a}"): y[1 + n + c] for a, c in enumerate(idx)})
                if loc.kind == "dynamics":
                    for (a, c), e in conv.mass.items():
                        if a <= c:
                            key = (idx[a], idx[c]) if idx[a] <= idx[c] else (idx[c], idx[a])
                            M[key] = M.get(key, 0) + e.subs(sub)
                    for a, e in conv.Q.items():
                        F[idx[a]] += e.subs(sub)
                    for a, e in conv.h.items():
                        F[idx[a]] -= e.subs(sub)
                    T += conv.kinetic.subs(sub)
                    V += conv.potential.subs(sub)
                else:
                    r = int(block.rows[i])
                    for a, e in conv.A.items():
                        A[r, idx[a]] = e.subs(sub)
                    b[r], nbias[r] = conv.b.subs(sub), -conv.bias.subs(sub)
                    f[r] = se.Integer(0) if conv.f is None else conv.f.subs(sub)
    except Exception:
        return None
    mass = sorted(key for key, e in M.items() if e != 0)
    acon = sorted(key for key, e in A.items() if e != 0)
    exprs = [M[key] for key in mass] + [A[key] for key in acon] + F + nbias + b + f
    T0 = T.subs({y[1 + n + j]: se.Integer(0) for j in range(n)})
    return mass, acon, exprs, [T, V, T0]


class _Converted:
    """A template's local forms in SymEngine: as SymEngine derived them (``loc.engine``), or
    converted once."""

    def __init__(self, loc: object) -> None:
        c = symengine.sympify
        eng = loc.engine or {}
        if "mass" in eng:
            self.mass, self.h = eng["mass"], eng["h"]
            self.kinetic, self.potential = c(eng["kinetic"]), c(eng["potential"])
        else:
            self.mass = {key: c(e) for key, e in loc.mass.items()}
            self.h = {a: c(e) for a, e in loc.h.items()}
            self.kinetic, self.potential = c(loc.kinetic), c(loc.potential)
        self.Q = {a: c(e) for a, e in loc.Q.items()}
        if "A" in eng:
            self.A, self.b, self.bias = eng["A"], c(eng["b"]), c(eng["bias"])
            self.f = None if eng["f"] is None else c(eng["f"])
        else:
            self.A = {a: c(e) for a, e in loc.A.items()}
            self.b, self.bias = c(loc.b), c(loc.bias)
            self.f = None if loc.f is None else c(loc.f)


def _shared_code(exprs: list, args: list) -> tuple[list[str], list[str], list[str]]:
    """One common-subexpression pass over all outputs, printed once: the body lines, the output
    expressions and the argument names (``_t, _y0 … _y{2n-1}, _p0 …``) that every fused
    function is built from (a separate ``cse`` + ``lambdify`` per function took half of
    ``compile()`` on a bicycle-sized model).

    The pass runs in SymEngine: on the 20-link pendulum on a cart its ``cse`` and printing take
    0.05 s against 1.2 s for SymPy's. The printed code calls functions by their bare names
    (``sin``, ``sqrt``), bound to ``math`` or to NumPy by the namespace it runs in
    (:data:`MATH`, :data:`NUMPY`). SymPy prints what SymEngine cannot take.
    """
    names = [str(a) for a in args]
    try:
        repl, red = symengine.cse([symengine.sympify(e) for e in exprs])  # (no-op if converted)
        body = [f"_{x} = {_bare(e)}" for x, e in repl]
        return body, [_bare(e) for e in red], names
    except Exception:
        pass
    repl, red = sp.cse([sp.sympify(e) for e in exprs], sp.numbered_symbols("_x"))
    pr = PythonCodePrinter({"standard": "python3"})
    body = [f"{pr.doprint(x)} = {pr.doprint(e)}" for x, e in repl]
    return body, [pr.doprint(e) for e in red], names


_CSE_NAME = re.compile(r"\bx(\d+)\b")


def _bare(e: object) -> str:
    """SymEngine's printing of ``e`` with its cse symbols x0, x1, … renamed _x0, _x1, …"""
    return _CSE_NAME.sub(r"_x\1", str(e))


_FUNCTIONS = (
    "sin", "cos", "tan", "exp", "log", "sqrt", "sinh", "cosh", "tanh",
    "asin", "acos", "atan", "atan2", "asinh", "acosh", "atanh", "floor",
)  # fmt: skip
MATH = {"math": math, **{f: getattr(math, f) for f in _FUNCTIONS}, "pi": math.pi, "E": math.e}
NUMPY_RENAMED = {"asin": "arcsin", "acos": "arccos", "atan": "arctan", "atan2": "arctan2",
                 "asinh": "arcsinh", "acosh": "arccosh", "atanh": "arctanh", "fabs": "abs"}  # fmt: skip


def _function(name: str, args: list[str], body: list[str], outs: list[str], ns: dict) -> Callable:
    src = "\n".join(
        [f"def {name}({', '.join(args)}):", *(f"    {ln}" for ln in body),
         f"    return [{', '.join(outs)}]"]
    )  # fmt: skip
    namespace = dict(ns)
    filename = register(src + "\n", f"fused {name}")  # (in linecache: it pickles as its source)
    exec(compile(src + "\n", filename, "exec"), namespace)  # our own generated code
    return namespace[name]


class _NumpyMath:
    """``math.f`` of SymPy-printed code as NumPy's ufunc: the same source runs on arrays."""

    def __getattr__(self, name: str) -> object:
        return getattr(np, NUMPY_RENAMED.get(name, name))


NUMPY = {
    "math": _NumpyMath(),
    **{f: getattr(np, NUMPY_RENAMED.get(f, f)) for f in _FUNCTIONS},
    "pi": math.pi,
    "E": math.e,
}


def _functions(
    names: list[str], body: list[str], outs: list[str], plain: list | None, args: list
) -> tuple[Callable, Callable | None]:
    """``fn`` (the shared source on floats, ``math``) and its vectorized twin: the same source on
    arrays, checked against ``fn`` at two random states, or ``lambdify`` of ``plain`` when the
    printed code does not run on arrays (a Piecewise's ``if``; None without ``plain``)."""
    fn = _function("fn", names, body, outs, MATH)
    vfn = _function("vfn", names, body, outs, NUMPY)
    try:
        rng = np.random.default_rng(3)
        x = rng.uniform(0.2, 0.9, (len(names), 2))
        with np.errstate(all="ignore"):
            got = np.array([np.broadcast_to(o, (2,)) for o in vfn(*x)], dtype=float)
        want = np.array([fn(*x[:, j]) for j in range(2)], dtype=float).T
        if np.allclose(got, want, rtol=1e-12, atol=1e-12, equal_nan=True):
            return fn, vfn
    except Exception:
        pass
    if plain is None:
        return fn, None
    exprs = [sp.sympify(e) for e in plain]  # SymEngine's outputs back to SymPy for lambdify
    return fn, sp.lambdify(args, exprs, modules="numpy", cse=True, docstring_limit=0)


def _llvm_factory(eom: Derivation, key: str | None) -> Callable[..., Callable | None]:
    """``llvm`` of :class:`FusedKernel`: the right-hand side [q̇, q̈] as SymEngine expressions
    (the kernel's outputs, the constraint rows, and the floored Schur solve run on them by
    :func:`pfaff.numeric.smallsolve.schur_expressions`: the algorithm and floor of ``rfn``),
    compiled by SymEngine's LLVM backend on first use, or loaded from the on-disk cache
    (:func:`pfaff.derive.machine_kernel.cached_machine`). It holds ``eom`` (whose expressions it
    compiles) for as long as a model holds the kernel."""

    def build() -> Callable:
        (mass, acon, exprs, _), args = _parts(eom)  # a failure is reported by MachineCode
        return _llvm_rhs(mass, acon, exprs, eom.n, eom.m, args)

    return cached_machine(key, "llvm-checks", build)  # (the outputs end with the checks)


def _kernel_parts(eom: Derivation) -> tuple[list, list]:
    """The kernel's outputs and the generated code's arguments (for the machine-code kernel)."""
    (_, _, exprs, _), args = _parts(eom)
    return exprs, args


def _llvm_rhs(mass: list, acon: list, exprs: list, n: int, m: int, args: list) -> Callable:
    se = symengine
    ex = [se.sympify(e) for e in exprs]
    syms = [se.Symbol(str(a)) for a in args]  # _t, _y…, _p…
    y = syms[1 : 2 * n + 1]
    alpha, beta, cap = se.Symbol("_alpha"), se.Symbol("_beta"), se.Symbol("_cap")
    taus = [se.Symbol(f"_tau{j}") for j in range(m)]
    nM, nA = len(mass), len(acon)
    off = nM + nA
    g = [se.Integer(0)] * m
    for s, (i, j) in enumerate(acon):
        g[i] += ex[nM + s] * y[n + j]
    values = {f"m{s}": ex[s] for s in range(nM)}
    values |= {f"a{s}": ex[nM + s] for s in range(nA)}
    values |= {f"F{i}": ex[off + i] for i in range(n)}
    for i in range(m):
        nb, b, f = ex[off + n + i], ex[off + n + m + i], ex[off + n + 2 * m + i]
        values[f"c{i}"] = nb - 2 * alpha * (g[i] + b) - beta**2 * f
    values |= {f"tau{j}": taus[j] for j in range(m)} | {"cap": cap}
    namespace = {
        "sqrt": se.sqrt,
        "max": lambda *a: se.Max(*a),
        "pick": lambda d, tau: se.Piecewise(
            (d, d >= tau), (tau / 2 + se.Max(d, 0) ** 2 / (2 * tau), True)
        ),
        "capped": lambda tj, top: se.Min(tj, top),
        "min": lambda *a: se.Min(*a),
    }
    solved = schur_expressions(mass, acon, values, n, m, namespace, checked=True)
    inputs = [*syms, alpha, beta, *taus, cap]
    # outputs: q̇, q̈, λ, then the kernel's own outputs (those of fn): one call gives a model
    # everything it evaluates at a state (NumericModel.use_machine_code); last, the CHECKS
    # pivots a checked accelerations() reads (pfaff.numeric.checkedsolve.passes)
    k = n + m
    outs = [*y[n:], *solved[:k], *ex, *solved[k:]]
    return se.Lambdify(inputs, outs, backend="llvm", cse=True)


def _rhs_function(
    body: list[str],
    outs: list[str],
    mass: list,
    acon: list,
    n: int,
    m: int,
    n_params: int,
    augmented: bool = False,
    checked: bool = False,
) -> Callable | None:
    """``rfn`` (see :class:`FusedKernel`): the shared kernel code, the constraint rows
    c = −(Ȧq̇ + ḃ) − 2α(A q̇ + b) − β² f, and the floored Schur solve, in one function.

    ``augmented`` (``rfn_aug``, for a singular M such as quaternion coordinates give): the solve
    of (M + ρAᵀA) q̈ = Q − h + ρAᵀc + Aᵀλ, A q̈ = c, which has the same q̈ and λ (A q̈ = c makes
    the added terms equal) and a positive definite matrix where M is definite on null(A); ρ is
    the argument ``_rho`` of ``make`` after the floor's.

    ``checked`` (``afn``, for a checked ``accelerations()``): ``acc(t, q, q̇, params)`` returns
    (q̈, λ) as lists, without stabilization or floor, or None where a check of
    :func:`pfaff.numeric.smallsolve.schur_source` fails (:func:`_checked_function`)."""
    nM, nA = len(mass), len(acon)
    off = nM + nA
    Ms, As = [f"_m{k}" for k in range(nM)], [f"_a{k}" for k in range(nA)]
    Fs, cs = [f"_F{i}" for i in range(n)], [f"_c{i}" for i in range(m)]
    taus = [f"_tau{i}" for i in range(m)]
    lines = [f"{v} = {o}" for v, o in zip(Ms + As + Fs, outs[: off + n], strict=True)]
    g: list[list[str]] = [[] for _ in range(m)]
    for k, (i, j) in enumerate(acon):
        g[i].append(f"{As[k]}*_y{n + j}")
    for i in range(m):
        nb, b, f = outs[off + n + i], outs[off + n + m + i], outs[off + n + 2 * m + i]
        gi = " + ".join(g[i]) or "0.0"
        stabilized = f" - 2*_alpha*({gi} + ({b})) - _beta**2*({f})" if not checked else ""
        lines.append(f"{cs[i]} = ({nb}){stabilized}")
    if augmented:
        mass, Ms, Fs = _augment(mass, acon, Ms, As, Fs, cs, lines)
    ys = ", ".join(f"_y{i}" for i in range(2 * n))
    params = [f"_p{k}" for k in range(n_params)]
    if checked:
        return _checked_function(body, lines, mass, acon, (Ms, As, Fs, cs), params)
    schur, out = schur_source(mass, acon, Ms, As, Fs, cs, tau=taus, cap="_cap", prefix="_v")
    lines += [ln.strip() for ln in schur]
    rho = ["_rho"] if augmented else []
    src = "\n".join(
        [
            f"def make({', '.join([*params, '_alpha', '_beta', *taus, '_cap', *rho])}, _slow):",
            "    def rhs(_t, _y):",
            f"        {ys}, = _y",
            "        try:",
            *[f"            {ln}" for ln in body + lines],
            "        except (ValueError, ZeroDivisionError):",
            "            return _slow(_t, _y)",
            f"        return [{', '.join([f'_y{n + i}' for i in range(n)] + out)}]",
            "    return rhs",
        ]
    )
    namespace = {**MATH, **NAMESPACE}
    try:
        filename = register(src + "\n", "fused rhs")  # (in linecache: it pickles as its source)
        exec(compile(src + "\n", filename, "exec"), namespace)  # our own generated code
    except (SyntaxError, RecursionError):  # something the printer cannot write: the array path
        return None
    return namespace["make"]


def _checked_function(
    body: list[str],
    lines: list[str],
    mass: list,
    acon: list,
    names: tuple,
    params: list[str],
) -> Callable | None:
    """``afn`` (see :func:`_rhs_function`): the kernel, c = −(Ȧq̇ + ḃ) (α = β = 0) and the
    unfloored Schur solve, ``acc(t, q: list, q̇: list, params) -> ([q̈], [λ])``, or None where a
    check of :func:`pfaff.numeric.checkedsolve.passes` fails, a value is out of its domain or
    overflows, or anything (t, q, q̇, q̈, λ) is not a finite real (a fractional power of a negative
    value is complex in Python: the full path names it): the checks, the finiteness test and
    the split into q̈ and λ run here, on local floats (issue 25: ``accelerations()`` within 2×
    a right-hand side). ``acc(..., _raw=True)`` returns [q̈, λ, checks] unchecked."""
    lam: list[str] = []
    checks: list[str] = []
    schur, out = schur_source(
        mass, acon, *names, prefix="_v", multipliers=lam, checks=checks
    )  # fmt: skip
    n = len(out)
    qs, qds = [f"_y{i}" for i in range(n)], [f"_y{n + i}" for i in range(n)]
    results = [f"_r{i}" for i in range(len(out) + len(lam))]
    every = ["_t", *qs, *qds, *results]
    passed = " and ".join(f"({c}) > {bound}" for c, bound in zip(checks, PASS, strict=True))
    src = "\n".join(
        [
            "def acc(_t, _q, _qd, _p, _raw=False):",
            f"    {''.join(x + ', ' for x in qs)}= _q",
            f"    {''.join(x + ', ' for x in qds)}= _qd",
            f"    {''.join(p + ', ' for p in params)}= _p" if params else "",
            "    try:",
            *[f"        {ln}" for ln in body + lines + [x.strip() for x in schur]],
            *[f"        {r} = {e}" for r, e in zip(results, out + lam, strict=True)],
            "        if _raw:",
            f"            return [{', '.join(results + checks)}]",
            f"        if not ({passed}):",
            "            return None",
            f"        _s = {' + '.join(every)}",
            "    except (ValueError, ArithmeticError, TypeError):  # (TypeError: a complex value)",
            "        return None",
            "    if _s.__class__ is not float or _s - _s != 0.0:  # (complex, NaN or infinity)",
            "        return None",
            f"    return [{', '.join(results[:n])}], [{', '.join(results[n:])}]",
        ]
    )
    namespace = {**MATH, **NAMESPACE, "min": min, "max": max}
    try:
        filename = register(src + "\n", "fused acc")  # (in linecache: it pickles as its source)
        exec(compile(src + "\n", filename, "exec"), namespace)  # our own generated code
    except (SyntaxError, RecursionError):
        return None
    return namespace["acc"]


def _augment(
    mass: list, acon: list, Ms: list, As: list, Fs: list, cs: list, lines: list[str]
) -> tuple[list, list[str], list[str]]:
    """Lines of M + ρAᵀA and Q − h + ρAᵀc (appended to ``lines``); their pattern and names."""
    rows: dict[int, list[tuple[int, str]]] = {}
    for k, (i, j) in enumerate(acon):
        rows.setdefault(i, []).append((j, As[k]))
    extra: dict[tuple[int, int], list[str]] = {}
    for entries in rows.values():
        for j1, a1 in entries:
            for j2, a2 in entries:
                if j1 <= j2:
                    extra.setdefault((j1, j2), []).append(f"{a1}*{a2}")
    given = dict(zip(mass, Ms, strict=True))
    pattern = sorted(set(given) | set(extra))
    names = []
    for s, key in enumerate(pattern):
        name = f"_mt{s}"
        terms = " + ".join(extra.get(key, [])) or "0.0"
        lines.append(f"{name} = {given.get(key, '0.0')} + _rho*({terms})")
        names.append(name)
    forcing = []
    for j, F in enumerate(Fs):
        terms = [f"{a}*{cs[i]}" for i, entries in rows.items() for jj, a in entries if jj == j]
        name = f"_Ft{j}"
        lines.append(f"{name} = {F} + _rho*({' + '.join(terms) or '0.0'})")
        forcing.append(name)
    return pattern, names, forcing
