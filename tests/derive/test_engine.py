"""Templates differentiated in SymEngine against the same templates in SymPy."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from pfaff.core.symbols import local_q, local_qd, t
from pfaff.derive.templates import _particle, _particle_sympy


def _numeric(e: sp.Expr, syms: list, values: np.ndarray) -> float:
    return float(sp.lambdify(syms, e, modules="math")(*values))


@pytest.mark.parametrize("positive", [False, True])
def test_particle_same_as_sympy(positive: bool) -> None:
    """A bob at the end of two links on a moving, rheonomic base: M, h and T agree at random
    points, and the parameters come back with their assumptions."""
    k = 3
    q = [local_q(a) for a in range(k)]
    l1, l2, m, w = sp.symbols("l1 l2 m w", positive=positive)
    x = q[0] + l1 * sp.sin(q[1]) + l2 * sp.sin(q[2]) + sp.cos(w * t)
    y = -l1 * sp.cos(q[1]) - l2 * sp.cos(q[2]) + sp.exp(-t) * q[0] ** 2
    key = ("particle", 2, m, x, y)
    fast, slow = _particle(key, k), _particle_sympy(m, (x, y), k)
    assert set(fast.mass) == set(slow.mass) and set(fast.h) == set(slow.h)
    syms = [*q, *(local_qd(a) for a in range(k)), t, l1, l2, m, w]
    rng = np.random.default_rng(1)
    for _ in range(3):
        vals = rng.uniform(0.3, 1.7, len(syms))
        for key_, e in fast.mass.items():
            assert _numeric(e, syms, vals) == pytest.approx(_numeric(slow.mass[key_], syms, vals))
        for a, e in fast.h.items():
            assert _numeric(e, syms, vals) == pytest.approx(_numeric(slow.h[a], syms, vals))
        assert _numeric(fast.kinetic, syms, vals) == pytest.approx(
            _numeric(slow.kinetic, syms, vals)
        )
    params = {s for e in fast.mass.values() for s in e.free_symbols} & {l1, l2, m}
    assert params == {l1, l2, m}  # the user's symbols, assumptions included
    assert fast.mass[1, 1] == m * l1**2  # sin² + cos² = 1 kept exact


def test_particle_with_other_functions_takes_sympy() -> None:
    """A function SymEngine does not share with SymPy (Abs here): the SymPy path, same result."""
    k = 1
    q = local_q(0)
    m = sp.Symbol("m")
    key = ("particle", 2, m, sp.Abs(q) + q, sp.Integer(0))
    fast, slow = _particle(key, k), _particle_sympy(m, (sp.Abs(q) + q, sp.Integer(0)), k)
    assert fast.mass == slow.mass and fast.h == slow.h


def test_lagrangian_same_as_sympy(monkeypatch) -> None:
    """A kinetic energy with a rheonomic, coupled metric and a potential: M and h from the
    SymEngine path against the SymPy path (forced by refusing the engine)."""
    import pfaff.derive.templates as templates
    from pfaff.derive.blocks import Local

    k = 2
    q, qd = [local_q(a) for a in range(k)], [local_qd(a) for a in range(k)]
    a_, b_ = sp.symbols("a b", positive=True)
    L = (a_ * qd[0] ** 2 + b_ * sp.cos(q[1]) * qd[0] * qd[1] + qd[1] ** 2 * sp.exp(t)) / 2
    L -= a_ * sp.sin(q[0]) * q[1]
    fast = templates._lagrangian(L, k, Local("dynamics", k))

    def refuse(exprs):
        raise templates._Unsupported

    monkeypatch.setattr(templates, "_Engine", refuse)
    slow = templates._lagrangian(L, k, Local("dynamics", k))
    assert set(fast.mass) == set(slow.mass) and set(fast.h) == set(slow.h)
    for key, e in fast.mass.items():
        assert sp.simplify(e - slow.mass[key]) == 0
    for a, e in fast.h.items():
        assert sp.simplify(e - slow.h[a]) == 0
    assert fast.mass[0, 1].free_symbols >= {b_}  # the positive symbol, not a plain copy
