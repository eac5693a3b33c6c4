"""How many terms an expression has once expanded: the bound on what SymPy may expand unasked.

Asking whether ``cosh(u)`` or ``abs(u)`` is real or positive makes SymPy split ``u`` into its
real and imaginary parts, which expands powers of sums: ``abs(cosh((x + a + b)**8))`` takes
seconds, ``**12`` tens of seconds, and every later rebuild of the expression (a substitution)
pays again. :func:`expanded_terms` counts the terms such an expansion would make from the sizes
alone, so that a parser can refuse an argument of those functions (:data:`EXPANDING`) beyond
:data:`MAX_FUNCTION_TERMS` terms before SymPy builds the call.
"""

from __future__ import annotations

import math

import sympy as sp

MAX_FUNCTION_TERMS = 16
"""Most terms an argument of a function of :data:`EXPANDING` may expand to ((x + y + z)**4: 15)."""

EXPANDING = (sp.Abs, sp.sign, sp.cosh, sp.sinh, sp.tanh)
"""The functions whose evaluation splits their argument into real and imaginary parts."""

_CAP = 1 << 40  # counts are capped here (they are only compared with small limits)


def expanded_terms(e: sp.Expr) -> int:
    """An upper bound on the number of terms of ``expand(e)``, capped at 2**40.

    A sum adds its terms' counts, a product multiplies them, an integer power n ≥ 2 of a sum of
    k terms has C(n + k − 1, k − 1); anything else (a symbol, a function call, a number) is one.

    Examples
    --------
    >>> x, y, z = sp.symbols("x y z")
    >>> expanded_terms((x + y + z) ** 4), expanded_terms((x + y) * (x - y) + sp.cos(x + y))
    (15, 5)
    """
    if e.is_Add:
        return min(_CAP, sum(expanded_terms(a) for a in e.args))
    if e.is_Mul:
        return min(_CAP, math.prod(expanded_terms(a) for a in e.args))
    if e.is_Pow and e.exp.is_Integer and e.exp > 1 and not e.base.is_number:
        k = expanded_terms(e.base)
        if k == 1:
            return 1
        n = int(min(e.exp, _CAP))
        return _CAP if n > 200 else min(_CAP, math.comb(n + k - 1, k - 1))
    return 1
