"""Templates differentiated in SymEngine against the same templates in SymPy."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from pfaff.core.symbols import local_q, local_qd, t
from pfaff.derive.engine import Plain
from pfaff.derive.templates import _particle, _particle_in


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
    fast, slow = _particle(key, k), _particle_in(Plain(), m, (x, y), k)
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
    fast, slow = _particle(key, k), _particle_in(Plain(), m, (sp.Abs(q) + q, sp.Integer(0)), k)
    assert fast.mass == slow.mass and fast.h == slow.h


def test_lagrangian_same_as_sympy(monkeypatch) -> None:
    """A kinetic energy with a rheonomic, coupled metric and a potential: M and h from the
    SymEngine path against the SymPy path (forced by choosing SymPy as the algebra)."""
    import pfaff.derive.templates as templates
    from pfaff.derive.blocks import Local

    k = 2
    q, qd = [local_q(a) for a in range(k)], [local_qd(a) for a in range(k)]
    a_, b_ = sp.symbols("a b", positive=True)
    L = (a_ * qd[0] ** 2 + b_ * sp.cos(q[1]) * qd[0] * qd[1] + qd[1] ** 2 * sp.exp(t)) / 2
    L -= a_ * sp.sin(q[0]) * q[1]
    fast = templates._lagrangian(L, k, Local("dynamics", k))

    monkeypatch.setattr(templates, "algebra", lambda exprs: Plain())
    slow = templates._lagrangian(L, k, Local("dynamics", k))
    assert set(fast.mass) == set(slow.mass) and set(fast.h) == set(slow.h)
    for key, e in fast.mass.items():
        assert sp.simplify(e - slow.mass[key]) == 0
    for a, e in fast.h.items():
        assert sp.simplify(e - slow.h[a]) == 0
    assert fast.mass[0, 1].free_symbols >= {b_}  # the positive symbol, not a plain copy


def test_symbols_sympy_keeps_apart_stay_apart() -> None:
    """Two symbols named m (one positive) and a parameter named t that is not time: SymEngine
    would merge them, so these templates take the SymPy path; the numbers are SymPy's."""
    import pfaff

    m1, m2 = sp.Symbol("m", positive=True), sp.Symbol("m")
    (x,) = pfaff.coordinates("x:1")
    s = pfaff.System([x])
    s.add_particle(m1 + 2 * m2, [x, 0])
    s.add_generalized_force(x, m1)
    qdd = s.equations().compile({m1: 1.0, m2: 10.0}).accelerations(0, [0.1], [0.0])[0]
    assert qdd[0] == pytest.approx(1 / 21, rel=1e-12)  # F/M = 1/(1 + 2·10)

    tp = sp.Symbol("t", positive=True)
    m, w = sp.symbols("m w", positive=True)
    s = pfaff.System([x])
    s.add_particle(m, [x + sp.sin(w * pfaff.t), 0])
    s.add_potential_energy(tp * x**2 / 2)
    eom = s.equations()
    values = {"m": 1.0, "w": 2.0, "t": 3.0}
    expect = -3.0 * 0.1 + 4.0 * np.sin(0.8)  # ẍ = -k x/m + w² sin(w t), k = 3
    for solver in ("range-space", "lu"):
        qdd = eom.compile(values, solver=solver).accelerations(0.4, [0.1], [0.0])[0]
        assert qdd[0] == pytest.approx(expect, rel=1e-12)


def test_functions_symengine_cannot_differentiate_take_sympy() -> None:
    """Max is no SymPy Function atom but SymEngine cannot differentiate it: the SymPy path."""
    import pfaff

    m, L = sp.symbols("m L", positive=True)
    (x,) = pfaff.coordinates("x:1")
    s = pfaff.System([x])
    s.add_particle(m, [sp.Max(L, 1) * x, 0])
    s.add_generalized_force(x, 1)
    eom = s.equations()
    assert not eom.velocity_terms[0].has(sp.Derivative)
    qdd = eom.compile({"m": 1.0, "L": 2.0}).accelerations(0, [0.1], [0.0])[0]
    assert qdd[0] == pytest.approx(0.25, rel=1e-12)  # 1 / (m Max(L, 1)²)
