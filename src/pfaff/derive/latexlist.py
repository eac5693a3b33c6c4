"""Lists that Jupyter renders as LaTeX: the Lagrange equations and the work of each force.

A :class:`LatexList` is a ``list`` (equal to the plain list of the same items; indexing and
slicing give what a list gives) with ``_repr_latex_``: one aligned row per item, dots for rates
(:func:`sympy.physics.vector.printing.vlatex`), the first :attr:`LatexList.MAX_SHOWN` rows.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

_TEXT_ESCAPES = {
    "\\": r"\textbackslash{}",
    "{": r"\{",
    "}": r"\}",
    "$": r"\$",
    "&": r"\&",
    "%": r"\%",
    "#": r"\#",
    "_": r"\_",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
}


def latex_text(name: str) -> str:
    r"""A user's name as LaTeX text, its special characters escaped.

    Examples
    --------
    >>> print(latex_text("no_slip & 100%"))
    \text{no\_slip \& 100\%}
    """
    return r"\text{" + "".join(_TEXT_ESCAPES.get(c, c) for c in name) + "}"


def vlatex(expr: Any) -> str:
    """:func:`sympy.physics.vector.printing.vlatex` (dots for rates), imported when a list is
    first shown: :mod:`sympy.physics` is not loaded with pfaff."""
    from sympy.physics.vector.printing import vlatex as printer

    return printer(expr)


class LatexList(list):
    """A list whose items each render as one row of an ``aligned`` LaTeX block."""

    MAX_SHOWN = 20  # rows rendered; a longer list ends in a vertical ellipsis

    def _latex_row(self, item: Any) -> str:
        """One row, with ``&`` where the rows align."""
        raise NotImplementedError

    def _repr_latex_(self) -> str:
        rows = [self._latex_row(x) for x in self[: self.MAX_SHOWN]]
        if len(self) > self.MAX_SHOWN:
            rows.append(rf"&\vdots \quad \text{{({len(self) - self.MAX_SHOWN} more)}}")
        return "$\\begin{aligned} " + r" \\ ".join(rows) + " \\end{aligned}$"


class EquationList(LatexList):
    """A list of :class:`sympy.Eq` that Jupyter renders as aligned LaTeX (dots for rates).

    Equal to the plain list of the same equations; indexing and slicing work as on a list.

    Examples
    --------
    >>> x = sp.Symbol("x")
    >>> eqs = EquationList([sp.Eq(x, 1)])
    >>> eqs == [sp.Eq(x, 1)], eqs[0]
    (True, Eq(x, 1))
    >>> print(eqs._repr_latex_())
    $\\begin{aligned} x &= 1 \\end{aligned}$
    """

    def _latex_row(self, item: sp.Equality) -> str:
        return f"{vlatex(item.lhs)} &= {vlatex(item.rhs)}"


class WorkList(LatexList):
    """The :class:`pfaff.ForceWork` of each applied force (what :meth:`pfaff.System.work`
    returns): a list that Jupyter renders as one row per force, its generalized force Qᵀ and its
    virtual power P on the admissible motions (P = 0: the force does no work).
    """

    def _latex_row(self, item: Any) -> str:
        Q = vlatex(sp.Matrix(item.generalized_force).T)
        P = vlatex(item.virtual_power)
        return rf"{latex_text(item.name)} &: \quad Q^{{T}} = {Q}, \quad P = {P}"
