"""Model parameters of the zoo: a default symbol, a number or expression, or a plain name."""

from __future__ import annotations

import keyword

import sympy as sp

from pfaff.core.errors import ModelTypeError
from pfaff.core.symbols import as_expr


def _param(value: object, default: str, arg: str) -> sp.Expr:
    """A model parameter: the default symbol, a number or expression, or a plain name.

    A string is a name (a new symbol) or it is refused: it is never parsed or evaluated.
    """
    if value is None or value is True:
        return sp.Symbol(default)
    if isinstance(value, str):
        if value.isidentifier() and not keyword.iskeyword(value):
            return sp.Symbol(value)
        raise ModelTypeError(
            f"`{arg}` must be a number, a SymPy expression or a plain name; got the string "
            f"{value!r} (a string is taken as a name, never evaluated)"
        )
    return as_expr(value, f"`{arg}`")
