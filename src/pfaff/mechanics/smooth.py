"""Kinks: ``abs`` and ``sign`` of the state in a term that the derivation differentiates.

Energies, particle positions, constraints and dissipation functions are differentiated with
respect to q or q̇ to form the equations of motion; the derivative of |u| is sign(u), whose own
derivative is not a function, and SymPy differentiates ``Abs`` of a function of time through
``re``/``im`` (not real-valued code). Such a term is refused where it enters, naming the kink;
forces and generalized forces are not differentiated, and take ``abs`` and ``sign`` freely (Coulomb
friction −μ N sign(q̇)).
"""

from __future__ import annotations

from collections.abc import Iterable

import sympy as sp
from sympy.core.function import AppliedUndef

KINKS = (sp.Abs, sp.sign, sp.Heaviside)


def kinks(exprs: Iterable[sp.Expr]) -> list[str]:
    """One problem per kink of the state (``abs``/``sign``/``Heaviside`` of q or q̇) in ``exprs``.

    Examples
    --------
    >>> import pfaff
    >>> x = pfaff.coordinates("x")
    >>> kinks([sp.Abs(x) + sp.Abs(sp.Symbol("a"))])[0][:30]
    'abs(x(t)) is not differentiabl'
    """
    problems = []
    for e in exprs:
        for k in sorted(e.atoms(*KINKS), key=sp.default_sort_key):
            if k.atoms(AppliedUndef):
                name = "abs" if isinstance(k, sp.Abs) else type(k).__name__
                problems.append(
                    f"{name}({k.args[0]}) is not differentiable where its argument vanishes, and "
                    "this term is differentiated to form the equations of motion: write it "
                    f"smooth (e.g. sqrt(u**2 + eps**2) for abs(u), tanh(u/eps) for sign(u)), or "
                    "apply the non-smooth part as a force or generalized force, which takes "
                    "abs() and sign()"
                )
    return problems
