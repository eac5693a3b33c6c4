"""Expressions printed back in the model file's own syntax: ``dot(q)``, ``ddot(q)``, ``abs``."""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp
from sympy.printing.str import StrPrinter

from pfaff.core.symbols import t


class _FilePrinter(StrPrinter):
    """SymPy's str printer with the model file's function names."""

    def _print_Abs(self, e: sp.Abs) -> str:
        return f"abs({self._print(e.args[0])})"

    def _print_Exp1(self, e: object) -> str:
        return "exp(1)"


def file_syntax(expr: object, coordinates: Sequence[sp.Expr]) -> str:
    """``expr`` written as a model file would write it.

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> th = pfaff.coordinates("theta")
    >>> file_syntax(sp.Abs(th.diff(pfaff.t)) + th.diff(pfaff.t, 2) * sp.sin(th), [th])
    'ddot(theta)*sin(theta) + abs(dot(theta))'
    """
    e = sp.sympify(expr)
    rule: dict = {}
    for q in coordinates:
        name = str(q.func)
        rule[q.diff(t, 2)] = sp.Symbol(f"ddot({name})")
        rule[q.diff(t)] = sp.Symbol(f"dot({name})")
    e = e.xreplace(rule)
    e = e.xreplace({q: sp.Symbol(str(q.func)) for q in coordinates})
    return _FilePrinter({"order": "none"}).doprint(e)


def matrix_syntax(m: sp.MatrixBase, coordinates: Sequence[sp.Expr]) -> list[list[str]]:
    """A matrix as a list of rows of strings in the file's syntax."""
    return [[file_syntax(m[i, j], coordinates) for j in range(m.cols)] for i in range(m.rows)]
