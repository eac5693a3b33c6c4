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


class FileSyntax:
    """A printer of one model's expressions in the file's syntax.

    The rule replacing ``q(t)``, its rate and acceleration by their file names is built once for
    the model's ``n`` coordinates, so printing an ``n × n`` matrix costs ``n²`` look-ups, not
    ``n³`` derivatives (a family of 48 members printed in well under a second).

    Parameters
    ----------
    coordinates : sequence of SymPy functions of ``t``, length n

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> th = pfaff.coordinates("theta")
    >>> FileSyntax([th])(sp.Abs(th.diff(pfaff.t)) + th.diff(pfaff.t, 2) * sp.sin(th))
    'ddot(theta)*sin(theta) + abs(dot(theta))'
    """

    def __init__(self, coordinates: Sequence[sp.Expr]) -> None:
        rates: dict = {}
        for q in coordinates:
            name = str(q.func)
            rates[q.diff(t, 2)] = sp.Symbol(f"ddot({name})")
            rates[q.diff(t)] = sp.Symbol(f"dot({name})")
        self._rates = rates
        self._values = {q: sp.Symbol(str(q.func)) for q in coordinates}
        self._printer = _FilePrinter({"order": "none"})

    def __call__(self, expr: object) -> str:
        """``expr`` as the file would write it."""
        e = sp.sympify(expr).xreplace(self._rates).xreplace(self._values)
        return self._printer.doprint(e)

    def matrix(self, m: sp.MatrixBase) -> list[list[str]]:
        """A matrix (shape r × c) as r rows of c strings."""
        return [[self(m[i, j]) for j in range(m.cols)] for i in range(m.rows)]


def file_syntax(expr: object, coordinates: Sequence[sp.Expr]) -> str:
    """``expr`` written as a model file would write it (one expression; see :class:`FileSyntax`).

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> th = pfaff.coordinates("theta")
    >>> file_syntax(sp.Abs(th.diff(pfaff.t)) + th.diff(pfaff.t, 2) * sp.sin(th), [th])
    'ddot(theta)*sin(theta) + abs(dot(theta))'
    """
    return FileSyntax(coordinates)(expr)


def matrix_syntax(m: sp.MatrixBase, coordinates: Sequence[sp.Expr]) -> list[list[str]]:
    """A matrix as a list of rows of strings in the file's syntax."""
    return FileSyntax(coordinates).matrix(m)
