"""Compile stage, small systems: one fused scalar kernel for the whole KKT system.

For a handful of coordinates the vectorized template kernels of :mod:`pfaff.derive.codegen` spend their
time in NumPy call overhead on arrays of length one. Here the whole system — M, A, Q - h, b,
Ȧq̇ + ḃ and f — is generated as a single Python function on floats (``math`` module, common
subexpressions shared), whose flat output is scattered into the dense augmented matrix by
precomputed indices. The result is checked against the template kernels before it is used.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from pfaff.core.symbols import accel, t
from pfaff.numeric.fused import FusedKernel
from pfaff.numeric.smallsolve import NAMESPACE, schur_solver, schur_source

if TYPE_CHECKING:
    from collections.abc import Callable

    from pfaff.derive.equations import Derivation

FUSED_LIMIT = 32  # n + m up to which a fused scalar kernel is generated


def _plain(eom: Derivation) -> tuple[dict, list[sp.Symbol], list[sp.Symbol]]:
    """Replace q(t), q̇(t) (and q̈ by 0) with plain symbols so ``math`` lambdify can take floats."""
    qs = [sp.Symbol(f"_fq{i}") for i in range(eom.n)]
    qds = [sp.Symbol(f"_fqd{i}") for i in range(eom.n)]
    rule: dict = {accel(c): sp.S.Zero for c in eom.coordinates}
    rule.update(dict(zip(eom.speeds, qds, strict=True)))
    return rule, qs, qds


def build_fused(eom: Derivation) -> FusedKernel | None:
    """Generate the fused kernel of a small system, or None when it is too big."""
    n, m = eom.n, eom.m
    if n + m > FUSED_LIMIT:
        return None
    rule, qs, qds = _plain(eom)
    qrule = dict(zip(eom.coordinates, qs, strict=True))
    M, A = eom.mass_matrix, eom.constraint_matrix
    mass = [(i, j) for i in range(n) for j in range(i, n) if M[i, j] != 0]
    acon = [(i, j) for i in range(m) for j in range(n) if A[i, j] != 0]
    bias = [
        e.xreplace({accel(c): 0 for c in eom.coordinates}) for e in eom.acceleration_constraints
    ]
    f = [sp.S.Zero if e is None else e for e in eom.holonomic_constraints]
    exprs = (
        [M[i, j] for i, j in mass]
        + [A[i, j] for i, j in acon]
        + list(eom.forcing)
        + [-e for e in bias]
        + list(eom.constraint_bias)
        + f
    )
    plain = [sp.sympify(e).xreplace(rule).xreplace(qrule) for e in exprs]
    args = [t, *qs, *qds, *eom.parameters]
    fn = sp.lambdify(args, plain, modules="math", cse=True, docstring_limit=0)
    vfn = sp.lambdify(args, plain, modules="numpy", cse=True, docstring_limit=0)
    T, V = (
        sp.sympify(e).xreplace(rule).xreplace(qrule)
        for e in (eom.kinetic_energy, eom.potential_energy)
    )
    T0 = T.xreplace(dict.fromkeys(qds, sp.S.Zero))
    efn = sp.lambdify(args, [T, V, T0], modules="numpy", cse=True, docstring_limit=0)
    rfn = _rhs_function(plain, mass, acon, n, m, args, qds)
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
    )


def _rhs_function(
    plain: list, mass: list, acon: list, n: int, m: int, args: list, qds: list
) -> Callable | None:
    """``rfn`` (see :class:`FusedKernel`) from the plain output expressions, or None."""
    g = [sp.S.Zero] * m
    for s, (i, j) in enumerate(acon, start=len(mass)):
        g[i] += plain[s] * qds[j]
    off = len(mass) + len(acon)
    neg_bias = plain[off + n : off + n + m]
    b, f = plain[off + n + m : off + n + 2 * m], plain[off + n + 2 * m :]
    alpha, beta = sp.Symbol("_alpha"), sp.Symbol("_beta")
    c = [
        nb - 2 * alpha * (gi + bi) - beta**2 * fi
        for nb, gi, bi, fi in zip(neg_bias, g, b, f, strict=True)
    ]
    try:
        return _rhs_factory(plain[: off + n] + c, mass, acon, n, m, args, (alpha, beta))
    except Exception:  # something the printer cannot write: the array path
        return None


def _rhs_factory(
    exprs: list, mass: list, acon: list, n: int, m: int, args: list, ab: tuple
) -> Callable:
    """Generate ``rfn`` (see :class:`FusedKernel`): the fused kernel and the Schur solve in one."""
    t_, qs, qds, params = args[0], args[1 : n + 1], args[n + 1 : 2 * n + 1], args[2 * n + 1 :]
    P = [sp.Symbol(f"_p{i}") for i in range(len(params))]
    rule = {**dict(zip(params, P, strict=True)), t_: sp.Symbol("_t")}
    rule.update({ab[0]: sp.Symbol("_alpha"), ab[1]: sp.Symbol("_beta")})
    rule.update({q: sp.Symbol(f"_y{i}") for i, q in enumerate([*qs, *qds])})
    repl, red = sp.cse([sp.sympify(e).xreplace(rule) for e in exprs], sp.numbered_symbols("_x"))
    pr = PythonCodePrinter({"standard": "python3"})
    nM, nA = len(mass), len(acon)
    Ms, As = [f"_m{k}" for k in range(nM)], [f"_a{k}" for k in range(nA)]
    Fs, cs = [f"_F{i}" for i in range(n)], [f"_c{i}" for i in range(m)]
    taus = [f"_tau{i}" for i in range(m)]
    body = [f"{pr.doprint(x)} = {pr.doprint(e)}" for x, e in repl]
    body += [f"{v} = {pr.doprint(e)}" for v, e in zip(Ms + As + Fs + cs, red, strict=True)]
    lines, out = schur_source(mass, acon, Ms, As, Fs, cs, tau=taus, cap="_cap", prefix="_v")
    body += [ln.strip() for ln in lines]
    ys = ", ".join(f"_y{i}" for i in range(2 * n))
    src = "\n".join(
        [
            f"def make({', '.join([*map(str, P), '_alpha', '_beta', *taus, '_cap'])}, _slow):",
            "    def rhs(_t, _y):",
            f"        {ys}, = _y",
            "        try:",
            *[f"            {ln}" for ln in body],
            "        except (ValueError, ZeroDivisionError):",
            "            return _slow(_t, _y)",
            f"        return [{', '.join([f'_y{n + i}' for i in range(n)] + out)}]",
            "    return rhs",
        ]
    )
    namespace = {**NAMESPACE, "math": math}
    exec(compile(src + "\n", "<pfaff.fused rhs>", "exec"), namespace)  # our own generated code
    return namespace["make"]
