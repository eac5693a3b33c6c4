"""pfaff.from_sympy on a closed four-bar: a ``sympy.physics.mechanics.System`` of three
``PinJoint``s with the loop as two ``holonomic_constraints`` (examples/fourbar_sympy.py).

Two references from SymPy itself, at 20 random consistent states:

* Kane: ``System.form_eoms()`` with the dependent speeds u2, u3; [q̇; u̇] from
  ``mass_matrix_full`` / ``forcing_full`` (what ``KanesMethod.rhs()`` inverts).
* The multiplier form: a ``LagrangesMethod`` of the same bodies (T from SymPy's
  ``kinetic_energy``, gravity as the potential Σ m g y) with the same loop as ``hol_coneqs``;
  [q̇; q̈; λ] from its ``mass_matrix_full`` / ``forcing_full``. pfaff's λ is SymPy's λ of that
  matrix form, and −λ of ``solve_multipliers()`` (SymPy stores −∂f/∂q̇ as ``lam_coeffs``,
  sympy#30215), as the ``from_sympy`` docstring says.

The states: the crank angle at random, the dependent angles from the loop closed by hand
(intersecting two circles, ``closed_state`` of the example), the dependent speeds from SymPy's
own ``velocity_constraints`` (solved numerically), the crank rate at random.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import LagrangesMethod

import pfaff

t = pfaff.t


@pytest.fixture(scope="module")
def example(fourbar_example):
    return fourbar_example


@pytest.fixture(scope="module")
def fourbar(example):
    system = example.fourbar_system()
    model = pfaff.from_sympy(system).equations().compile(example.VALUES)
    return system, model


@pytest.fixture(scope="module")
def lagrange(example):
    """The four-bar's LagrangesMethod in q, q̇ with the loop as hol_coneqs."""
    system = example.fourbar_system()
    q = list(system.q)
    u_to_qd = {u: c.diff(t) for c, u in zip(q, system.u, strict=True)}
    N, origin = system.frame, system.fixed_point
    bodies = [b for b in system.bodies if b.mass != 0]
    T = sum((b.kinetic_energy(N) for b in bodies), sp.S.Zero).xreplace(u_to_qd)
    V = sum(b.mass * sp.Symbol("g") * b.masscenter.pos_from(origin).dot(N.y) for b in bodies)
    lm = LagrangesMethod(T - V, q, hol_coneqs=list(system.holonomic_constraints))
    lm.form_lagranges_equations()
    return lm


def _states(example, system, n):
    """n random consistent states (q, q̇ = u): the loop closed, the speeds on its velocity rows."""
    pars = [sp.Symbol(k) for k in example.VALUES]
    q, u = list(system.q), list(system.u)
    qd = [c.diff(t) for c in q]
    rows = sp.Matrix(system.velocity_constraints)
    A = sp.lambdify([*q, *pars], rows.jacobian(u) + rows.jacobian(qd))
    rng = np.random.default_rng(23)
    for _ in range(n):
        qn, _ = example.closed_state(rng.uniform(-np.pi, np.pi), 0.0)
        An = np.array(A(*qn, *example.VALUES.values()), float)
        rate = rng.uniform(-3, 3)
        yield qn, np.concatenate([[rate], np.linalg.solve(An[:, 1:], -An[:, 0] * rate)])


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_fourbar_against_kane(example, fourbar):
    system, model = fourbar
    assert len(system.holonomic_constraints) == 2 and not system.nonholonomic_constraints
    pars = [sp.Symbol(k) for k in example.VALUES]
    system.form_eoms()
    full = sp.lambdify(
        [*system.q, *system.u, *pars], [system.mass_matrix_full, system.forcing_full]
    )
    # the KanesMethod the System formed converts too (its restated velocity rows dropped)
    from_km = pfaff.from_sympy(system.eom_method)
    assert from_km.n_constraints == 2
    from_km = from_km.equations().compile(example.VALUES)
    for qn, un in _states(example, system, 20):
        f, g = model.constraint_residual(0.0, qn, un)
        assert np.abs(f).max() < 1e-12 and np.abs(g).max() < 1e-12
        M, F = full(*qn, *un, *example.VALUES.values())
        ref = np.linalg.solve(np.array(M, float), np.array(F, float).ravel())[3:]
        for m in (model, from_km):
            qdd, _ = m.accelerations(0.0, qn, un)
            np.testing.assert_allclose(qdd, ref, rtol=0, atol=1e-12 * max(1.0, np.abs(ref).max()))


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_fourbar_against_lagrange_multiplier_form(example, fourbar, lagrange):
    system, model = fourbar
    lm = lagrange
    # the same model through LagrangesMethod: pfaff's own conversion of the multiplier form
    from_lm = pfaff.from_sympy(lm).equations().compile(example.VALUES)
    pars = [sp.Symbol(k) for k in example.VALUES]
    qd = [c.diff(t) for c in lm.q]
    full = sp.lambdify([*lm.q, *qd, *pars], [lm.mass_matrix_full, lm.forcing_full])
    for qn, v in _states(example, system, 20):
        M, F = full(*qn, *v, *example.VALUES.values())
        ref = np.linalg.solve(np.array(M, float), np.array(F, float).ravel())
        scale = max(1.0, np.abs(ref[3:]).max())
        for m in (model, from_lm):
            qdd, lam = m.accelerations(0.0, qn, v)
            np.testing.assert_allclose(qdd, ref[3:6], rtol=0, atol=1e-12 * scale)
            np.testing.assert_allclose(lam, ref[6:], rtol=0, atol=1e-12 * scale)


@pytest.mark.slow  # (its Lagrange fixture takes 4 s: the full suite runs it)
def test_fourbar_multiplier_sign_against_solve_multipliers(example, fourbar, lagrange):
    """λ_pfaff = −λ of LagrangesMethod.solve_multipliers (SymPy's −A, sympy#30215)."""
    system, model = fourbar
    lm = lagrange
    qd = [c.diff(t) for c in lm.q]
    pars = {sp.Symbol(k): v for k, v in example.VALUES.items()}
    for qn, v in _states(example, system, 3):
        point = {**dict(zip(lm.q, qn, strict=True)), **dict(zip(qd, v, strict=True)), **pars}
        sympy_lam = np.array(lm.solve_multipliers(op_point=point, sol_type="Matrix"), float)
        _, lam = model.accelerations(0.0, qn, v)
        assert np.abs(lam).max() > 0.1  # the loop carries load
        np.testing.assert_allclose(lam, -sympy_lam.ravel(), rtol=1e-11)


def test_docstring_states_the_multiplier_sign():
    doc = " ".join(pfaff.from_sympy.__doc__.split())
    assert (
        "sympy#30215" in doc
        and "solve_multipliers" in doc
        and "−λ of its ``eom`` and of ``solve_multipliers()``" in doc
    )
