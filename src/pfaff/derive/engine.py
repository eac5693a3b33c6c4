"""The round trip SymPy -> SymEngine -> SymPy, for the derivation's speed (issue 13).

SymEngine differentiates, substitutes and finds common subexpressions 50–100 times faster than
SymPy on the expressions of a template; users read SymPy. :func:`engine_safe` says when the round
trip is exact: SymEngine has no symbol assumptions and shares only some functions with SymPy.
"""

from __future__ import annotations

import symengine
import sympy as sp

from pfaff.core.symbols import local_q, local_qd, t


class Unsupported(Exception):
    """An expression the SymEngine path does not take."""


_SHARED_FUNCTIONS = (sp.sin, sp.cos, sp.tan, sp.exp, sp.log, sp.sinh, sp.cosh, sp.tanh)
_ALLOWED = (sp.Add, sp.Mul, sp.Pow, sp.Number, type(sp.pi), type(sp.E), *_SHARED_FUNCTIONS)


def engine_safe(exprs: list) -> bool:
    """Whether SymEngine computes with ``exprs`` exactly as SymPy would: only sums, products,
    powers, numbers, π and e, the functions both share, and symbols that stay distinct without
    their assumptions (no two of one name, none named ``t`` but time itself)."""
    names: dict[str, sp.Symbol] = {}
    for e in exprs:
        for node in sp.preorder_traversal(sp.sympify(e)):
            if isinstance(node, sp.Symbol):
                if type(node) is not sp.Symbol or names.setdefault(node.name, node) != node:
                    return False
                if node.name == "t" and node != t:
                    return False
            elif not isinstance(node, _ALLOWED):
                return False
    return True


class Plain:
    """A template derived in SymPy itself: the interface of :class:`Engine`, with no round trip."""

    t = t

    @staticmethod
    def placeholders(k: int) -> tuple[list, list]:
        return [local_q(a) for a in range(k)], [local_qd(a) for a in range(k)]

    @staticmethod
    def to(e: object) -> sp.Expr:
        return sp.sympify(e)

    @staticmethod
    def back(e: sp.Expr) -> sp.Expr:
        return e

    @staticmethod
    def add(terms: object) -> sp.Expr:
        return sp.Add(*terms)


class Engine:
    """The round trip of one template through SymEngine: in, and back to SymPy with the
    original symbols (their assumptions, which SymEngine does not carry, restored)."""

    t = symengine.Symbol("t")

    def __init__(self, exprs: list) -> None:
        exprs = [sp.sympify(e) for e in exprs]
        if not engine_safe(exprs):
            raise Unsupported
        syms = set().union(*(e.free_symbols for e in exprs))
        self.restore = {sp.Symbol(s.name): s for s in syms if sp.Symbol(s.name) != s}

    @staticmethod
    def placeholders(k: int) -> tuple[list, list]:
        q = [symengine.Symbol(local_q(a).name) for a in range(k)]
        return q, [symengine.Symbol(local_qd(a).name) for a in range(k)]

    @staticmethod
    def to(e: object) -> symengine.Basic:
        try:
            return symengine.sympify(e)
        except Exception as err:
            raise Unsupported from err

    def back(self, e: symengine.Basic) -> sp.Expr:
        x = sp.sympify(e)
        return x.xreplace(self.restore) if self.restore else x

    @staticmethod
    def add(terms: object) -> symengine.Basic:
        return symengine.Add(*terms)


def algebra(exprs: list) -> Engine | Plain:
    """SymEngine for a template whose expressions allow the exact round trip, else SymPy."""
    try:
        return Engine(exprs)
    except Unsupported:
        return Plain()
