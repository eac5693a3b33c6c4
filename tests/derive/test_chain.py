"""The n-link pendulum on a cart against SymPy's own model of it (``KanesMethod``)."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me
from sympy.physics.mechanics.models import n_link_pendulum_on_cart

import pfaff


@pytest.mark.parametrize("n", [1, 3])
def test_chain_matches_sympy_kane(n: int) -> None:
    rng = np.random.default_rng(n)
    names = [f"m{i}" for i in range(n + 1)] + [f"l{i}" for i in range(n)] + ["g", "F"]
    vals = {k: float(rng.uniform(0.5, 2.0)) for k in names}
    kane = n_link_pendulum_on_cart(n, cart_force=True, joint_torques=False)
    q, u = kane.q[:, 0], kane.u[:, 0]
    rep = {me.dynamicsymbols("F"): sp.Symbol("F")}
    args = [*q, *u, *(sp.Symbol(k) for k in names)]
    fM = sp.lambdify(args, kane.mass_matrix_full.xreplace(rep), modules="numpy")
    ff = sp.lambdify(args, kane.forcing_full.xreplace(rep), modules="numpy")
    model = pfaff.models.n_link_pendulum_on_cart(n).equations().compile(vals)
    for _ in range(3):
        q0, u0 = rng.uniform(-1.5, 1.5, n + 1), rng.uniform(-2.0, 2.0, n + 1)
        p = [vals[k] for k in names]
        ref = np.linalg.solve(fM(*q0, *u0, *p), np.ravel(ff(*q0, *u0, *p)))[n + 1 :]
        qdd, lam = model.accelerations(0.0, q0, u0)
        np.testing.assert_allclose(qdd, ref, rtol=1e-10, atol=1e-10)
        assert lam.shape == (0,)
    T, V = model.energy(0.0, q0, u0)  # one link: T = (m0+m1)ẋ²/2 - m1 l ẋ θ̇ cos θ + m1 l²θ̇²/2
    if n == 1:
        m0, m1, l0, g = vals["m0"], vals["m1"], vals["l0"], vals["g"]
        x_d, th, th_d = u0[0], q0[1], u0[1]
        expect = 0.5 * (m0 + m1) * x_d**2 - m1 * l0 * x_d * th_d * np.cos(th)
        expect += 0.5 * m1 * l0**2 * th_d**2
        assert T == pytest.approx(expect, rel=1e-12)
        assert V == pytest.approx(m1 * g * l0 * np.cos(th), rel=1e-12)


def test_chain_kernel_assembled_in_symengine() -> None:
    """The fused kernel's outputs come from the SymEngine forms the templates kept (a silent
    fall-back to SymPy's assembly once cost 4× in ``compile()``) and equal SymPy's assembly."""
    from pfaff.derive.fused import _engine_parts, _plain, _sympy_parts

    eom = pfaff.models.n_link_pendulum_on_cart(3).equations()
    particles = [b for b in eom.blocks if b.pieces[0].kind == "particle"]
    assert len(particles) == 4 and all(b.local.engine is not None for b in particles)
    rule, args = _plain(eom)
    parts = _engine_parts(eom, args)
    assert parts is not None
    ref = _sympy_parts(eom, rule)
    assert parts[0] == ref[0] and parts[1] == ref[1]
    rng = np.random.default_rng(5)
    point = dict(zip(args, rng.uniform(0.3, 1.2, len(args)), strict=True))
    for got, want in zip(parts[2], ref[2], strict=True):
        assert float(sp.sympify(got).xreplace(point)) == pytest.approx(
            float(sp.sympify(want).xreplace(point)), rel=1e-12, abs=1e-12
        )
