"""Compile stage, small systems: the power of the applied forces as one generated scalar function.

A run integrates the work of the applied forces, W = ∫ Qᵀq̇ dt, from the power at every stage
of every step (:mod:`pfaff.integrate.work`). Through the template kernels that is a NumPy stream
pass per forced template and per stage: on the 8-link chain on a cart with its push, 10 s took
2.7× the run without it. Here P(t, q, q̇) = Σ Q_a q̇_a of every instance of every forced template
is generated once as a Python function on floats (the names and printing of the fused kernel,
:mod:`pfaff.derive.fused`), made on the first call.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import sympy as sp

from pfaff.core.symbols import local_q, local_qd
from pfaff.derive.codegen import power_exprs

if TYPE_CHECKING:
    from pfaff.derive.equations import Derivation


def power_expression(eom: Derivation, rule: dict, args: list) -> sp.Expr | None:
    """P = Σ Q_a q̇_a over every instance of every forced template of a system without
    families, in the generated code's names (``rule`` and ``args`` of
    :func:`pfaff.derive.fused._plain`: ``_t``, ``_y…``, ``_p…``); None without applied forces.

    Examples
    --------
    >>> import pfaff
    >>> from pfaff.derive.fused import _plain
    >>> eom = pfaff.models.n_link_pendulum_on_cart(1).equations()
    >>> power_expression(eom, *_plain(eom))
    _p0*_y2
    """
    n = eom.n
    terms = []
    for block in eom.blocks:
        if block.local.kind != "dynamics" or not block.local.Q:
            continue
        (P,) = power_exprs(block)
        for idx in block.coords.tolist():
            sub = {local_q(a): args[1 + c] for a, c in enumerate(idx)}
            sub.update({local_qd(a): args[1 + n + c] for a, c in enumerate(idx)})
            terms.append(sp.sympify(P).xreplace(sub).xreplace(rule))
    return sp.Add(*terms) if terms else None
