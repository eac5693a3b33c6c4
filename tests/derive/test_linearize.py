"""EquationsOfMotion.linearize against hand-derived matrices, a reduced equation and SymPy.

References: the pendulum (θ̈ = −(g/L) θ about the bottom); the cart-pole about upright, derived
by hand from T = ½ m0 ẋ² + ½ m1 (ẋ² − 2 l ẋ θ̇ cos θ + l² θ̇²), V = m1 g l cos θ:

    ẍ = (m1 g / m0) θ + F/m0,   θ̈ = ((m0 + m1) g / (m0 l)) θ + F/(m0 l);

the same cart-pole in Cartesian coordinates with a rod constraint (multiplier form); a four-bar
(two closure constraints) against the Lagrangian of its one-coordinate reduction, written
independently with SymPy from the closed-form position of the coupler; SymPy's
``KanesMethod.linearize`` on the cart-pole. Bad input is refused with errors that name it.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff import ConstraintError, ModelError, ModelTypeError, StateError

t = pfaff.t


@pytest.fixture(scope="module")
def pendulum():
    return pfaff.models.pendulum().equations()


@pytest.fixture(scope="module")
def cartpole():
    return pfaff.models.n_link_pendulum_on_cart(1).equations()


def test_pendulum_symbolic(pendulum) -> None:
    th = pendulum.coordinates[0]
    g, L = sp.symbols("g L")
    down = pendulum.linearize({th: 0}, [th])
    assert down.A == sp.Matrix([[0, 1], [-g / L, 0]])
    assert down.states == [th, th.diff(t)]
    up = pendulum.linearize({th: sp.pi}, [th])
    assert up.A == sp.Matrix([[0, 1], [g / L, 0]])
    assert not up.numeric


def test_pendulum_numeric_modes(pendulum) -> None:
    th = pendulum.coordinates[0]
    lin = pendulum.linearize({th: 0, "m": 2.0, "g": 9.81, "L": 0.5}, [th])
    assert isinstance(lin.A, np.ndarray)
    w = np.sqrt(9.81 / 0.5)
    np.testing.assert_allclose(lin.eigenvalues(), [-1j * w, 1j * w], atol=1e-12)
    modes = lin.modes()
    np.testing.assert_allclose(modes.frequencies, [w, w], rtol=1e-12)
    np.testing.assert_allclose(modes.damping_ratios, [0, 0], atol=1e-12)
    assert modes.shapes.shape == (2, 2)
    assert not lin.is_stable()  # undamped: not asymptotically stable


def test_cartpole_hand_derived(cartpole) -> None:
    q0, q1 = cartpole.coordinates
    m0, m1, g, l0, F = sp.symbols("m0 m1 g l0 F")
    lin = cartpole.linearize({q0: 0, q1: 0}, [q0, q1], inputs=[F])
    A = sp.Matrix(
        [[0, 0, 1, 0], [0, 0, 0, 1], [0, m1 * g / m0, 0, 0], [0, (m0 + m1) * g / (m0 * l0), 0, 0]]
    )
    B = sp.Matrix([0, 0, 1 / m0, 1 / (m0 * l0)])
    assert sp.simplify(lin.A - A) == sp.zeros(4, 4)
    assert sp.simplify(lin.B - B) == sp.zeros(4, 1)
    assert lin.inputs == [F]


def test_cartpole_inputs_by_name_and_value(cartpole) -> None:
    """A numeric input column; the operating value of the input enters where it matters."""
    q0, q1 = cartpole.coordinates
    vals = {"m0": 2.0, "m1": 0.5, "g": 9.81, "l0": 0.8}
    lin = cartpole.linearize({q0: 0, q1: 0, **vals}, [q0, q1], inputs=["F"])
    np.testing.assert_allclose(lin.B[:, 0], [0, 0, 1 / 2.0, 1 / (2.0 * 0.8)], rtol=1e-14)
    with pytest.raises(StateError, match="accelerate"):  # a push is no equilibrium
        cartpole.linearize({q0: 0, q1: 0, "F": 1.0, **vals}, [q0, q1], inputs=["F"])


def cartesian_cartpole() -> pfaff.System:
    """The cart-pole in multiplier form: cart x, bob (xb, yb), rod (xb − x)² + yb² − l² = 0."""
    x, xb, yb = pfaff.coordinates("x xb yb")
    m0, m1, g, ell, F = sp.symbols("m0 m1 g l F")
    s = pfaff.System([x, xb, yb], name="cart-pole (Cartesian)")
    s.add_particle(m0, [x, 0], name="cart")
    s.add_particle(m1, [xb, yb], name="bob")
    s.add_potential_energy(m1 * g * yb)
    s.add_holonomic_constraint((xb - x) ** 2 + yb**2 - ell**2, name="rod")
    s.add_generalized_force(x, F, name="push")
    return s


def test_cartpole_multiplier_form_matches_minimal() -> None:
    """The multiplier form, linearized with xb kept and yb eliminated, is the minimal cart-pole
    under δθ = −(δxb − δx)/l; its multiplier's deviation is C x."""
    eom = cartesian_cartpole().equations()
    x, xb, yb = eom.coordinates
    vals = {"m0": 2.0, "m1": 0.5, "g": 9.81, "l": 0.8}
    lin = eom.linearize({x: 0, xb: 0, yb: 0.8, **vals}, [x, xb], inputs=["F"])
    m0, m1, g, ell = vals["m0"], vals["m1"], vals["g"], vals["l"]
    # (x, θ) = S (x, xb): θ = (x − xb)/l
    S = np.array([[1.0, 0.0], [1 / ell, -1 / ell]])
    T = np.kron(np.eye(2), S)
    Amin = np.array(
        [[0, 0, 1, 0], [0, 0, 0, 1], [0, m1 * g / m0, 0, 0], [0, (m0 + m1) * g / (m0 * ell), 0, 0]]
    )
    Bmin = np.array([0, 0, 1 / m0, 1 / (m0 * ell)])
    np.testing.assert_allclose(T @ lin.A @ np.linalg.inv(T), Amin, atol=1e-12)
    np.testing.assert_allclose(T @ lin.B[:, 0], Bmin, atol=1e-12)
    C, D = lin.multipliers
    assert C.shape == (1, 4) and D.shape == (1, 1)
    # the rod force on the bob is 2λ (xb − x, yb): at rest upright λ0 = m1 g /(2 l)
    np.testing.assert_allclose(lin.lambda0, [m1 * g / (2 * ell)], rtol=1e-14)


def test_cartesian_pendulum_symbolic_multiplier() -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    x, y = eom.coordinates
    L, g, m = sp.symbols("L g m")
    lin = eom.linearize({x: 0, y: -L}, [x])
    assert lin.A == sp.Matrix([[0, 1], [-g / L, 0]])
    assert lin.lambda0 == sp.Matrix([-g * m / (2 * L)])
    C, _ = lin.multipliers
    assert C == sp.zeros(1, 2)  # the tension changes to second order only


# --------------------------------------------------------------------------- four-bar
FOURBAR = {"a": 1.0, "b": 2.2, "c": 1.6, "d": 2.0, "m1": 1.0, "m2": 2.0, "m3": 1.5, "g": 9.81}


def fourbar() -> pfaff.System:
    """Crank (length a, angle θ1 at the origin), coupler (b, θ2), rocker (c, θ3 at (d, 0));
    point masses at the crank tip, the coupler's midpoint and the rocker tip; gravity −y."""
    th1, th2, th3 = pfaff.coordinates("th1 th2 th3")
    a, b, c, d, m1, m2, m3, g = sp.symbols("a b c d m1 m2 m3 g")
    B = sp.Matrix([a * sp.cos(th1), a * sp.sin(th1)])
    C = B + b * sp.Matrix([sp.cos(th2), sp.sin(th2)])
    s = pfaff.System([th1, th2, th3], name="four-bar")
    s.add_particle(m1, list(B))
    s.add_particle(m2, list((B + C) / 2))
    s.add_particle(m3, list(C))
    s.add_potential_energy(g * (m1 * B[1] + m2 * (B[1] + C[1]) / 2 + m3 * C[1]))
    D = sp.Matrix([d + c * sp.cos(th3), c * sp.sin(th3)])
    s.add_holonomic_constraint((C - D)[0], name="closure x")
    s.add_holonomic_constraint((C - D)[1], name="closure y")
    return s


def reduced_fourbar() -> tuple[float, float, float, float]:
    """θ1*, θ2*, θ3* of the equilibrium and ω² = V''/m_eff of the one-coordinate Lagrangian
    T = ½ m_eff(θ1) θ̇1², V(θ1), with C on the intersection of the circles about B and (d, 0)."""
    p = {k: sp.Float(v) for k, v in FOURBAR.items()}
    th = sp.Symbol("th")
    B = sp.Matrix([p["a"] * sp.cos(th), p["a"] * sp.sin(th)])
    e = sp.Matrix([p["d"], 0]) - B
    dist2 = e.dot(e)
    along = (p["b"] ** 2 - p["c"] ** 2 + dist2) / (2 * dist2)
    h = sp.sqrt(p["b"] ** 2 - along**2 * dist2)
    C = B + along * e + h * sp.Matrix([-e[1], e[0]]) / sp.sqrt(dist2)  # the elbow-up branch
    pts = [(p["m1"], B), (p["m2"], (B + C) / 2), (p["m3"], C)]
    V = p["g"] * sum(m * r[1] for m, r in pts)
    meff = sum(m * r.diff(th).dot(r.diff(th)) for m, r in pts)
    dV = V.diff(th)
    th1 = float(sp.nsolve(dV, th, -1.2))
    w2 = float(V.diff(th, 2).subs(th, th1) / meff.subs(th, th1))
    Cv = np.array(C.subs(th, th1), dtype=float).ravel()
    Bv = np.array(B.subs(th, th1), dtype=float).ravel()
    th2 = float(np.arctan2(*(Cv - Bv)[::-1]))
    th3 = float(np.arctan2(Cv[1], Cv[0] - FOURBAR["d"]))
    return th1, th2, th3, w2


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_fourbar_against_reduced_equation() -> None:
    eom = fourbar().equations()
    th1, th2, th3 = eom.coordinates
    a1, a2, a3, w2 = reduced_fourbar()
    assert w2 > 0  # the hanging equilibrium is a centre
    lin = eom.linearize({th1: a1, th2: a2, th3: a3, **FOURBAR}, [th1])
    np.testing.assert_allclose(lin.A, [[0, 1], [-w2, 0]], atol=1e-9 * w2)
    # any other kept coordinate gives the same eigenvalues
    lin3 = eom.linearize({th1: a1, th2: a2, th3: a3, **FOURBAR}, [th3])
    np.testing.assert_allclose(lin3.eigenvalues(), lin.eigenvalues(), atol=1e-9)


# --------------------------------------------------------------------------- SymPy
def test_agrees_with_kanes_method(cartpole) -> None:
    """SymPy's own n_link_pendulum_on_cart, linearized by KanesMethod, about upright."""
    from sympy.physics.mechanics.models import n_link_pendulum_on_cart

    kane = n_link_pendulum_on_cart(n=1, cart_force=True, joint_torques=False)
    vals = {"m0": 2.0, "m1": 0.5, "g": 9.81, "l0": 0.8}
    subs = {sp.Symbol(k): v for k, v in vals.items()}
    op = dict.fromkeys([*kane.q, *kane.u], 0)
    Ak, Bk, _ = kane.linearize(op_point=op, A_and_B=True)
    Ak = np.array(Ak.subs(subs), dtype=float)
    Bk = np.array(Bk.subs(subs), dtype=float)
    q0, q1 = cartpole.coordinates
    lin = cartpole.linearize({q0: 0, q1: 0, **vals}, [q0, q1], inputs=["F"])
    np.testing.assert_allclose(lin.A, Ak, atol=1e-12)
    np.testing.assert_allclose(lin.B, Bk, atol=1e-12)


# --------------------------------------------------------------------------- bad input
def test_off_the_constraints() -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    x, y = eom.coordinates
    with pytest.raises(ConstraintError, match=r"`rod`: f = -0\.39"):
        eom.linearize({x: 0, y: -1.9, "m": 1, "g": 9.81, "L": 2}, [x])
    with pytest.raises(ConstraintError, match=r"`rod`: A q̇ \+ b"):
        eom.linearize({x: 0, y: -2, y.diff(t): 0.5, "m": 1, "g": 9.81, "L": 2}, [x])


def test_singular_dependent_block() -> None:
    """Keeping y at the bottom leaves x undetermined: ∂f/∂x = 2x = 0 there."""
    eom = pfaff.models.cartesian_pendulum().equations()
    x, y = eom.coordinates
    with pytest.raises(ConstraintError, match=r"dependent coordinates \(`x`\) is singular"):
        eom.linearize({x: 0, y: -2, "m": 1, "g": 9.81, "L": 2}, [y])
    with pytest.raises(ConstraintError, match="must be fixed by the holonomic constraints"):
        eom.linearize({x: 0, y: -2, "m": 1, "g": 9.81, "L": 2}, [x, y])


def test_not_an_equilibrium(pendulum) -> None:
    th = pendulum.coordinates[0]
    with pytest.raises(StateError, match="q̈ of `theta`"):
        pendulum.linearize({th: 0.3, "m": 1, "g": 9.81, "L": 1}, [th])
    with pytest.raises(StateError, match=r"`theta` .*change"):
        pendulum.linearize({th: 0, th.diff(t): 1.0, "m": 1, "g": 9.81, "L": 1}, [th])
    # without gravity θ is ignorable: a steady rotation
    lin = pendulum.linearize({th: 0, th.diff(t): 1.0, "m": 1, "g": 0.0, "L": 1}, [th])
    assert lin.ignorable() == [0, 1]


def test_bad_names(pendulum, cartpole) -> None:
    th = pendulum.coordinates[0]
    q0, q1 = cartpole.coordinates
    with pytest.raises(ModelError, match="names `q1` twice"):
        cartpole.linearize({q0: 0, q1: 0}, [q0, q1, q1])
    with pytest.raises(ModelError, match="names `q1` twice"):
        cartpole.linearize({q0: 0, q1: 0}, [q0, "q1"], [q1, q1.diff(t)])
    with pytest.raises(ModelError, match="no value for the coordinates q1"):
        cartpole.linearize({q0: 0}, [q0, q1])
    with pytest.raises(ModelError, match="not a coordinate"):
        pendulum.linearize({th: 0}, ["phi"])
    with pytest.raises(ModelError, match="`op_point`: k is not"):
        pendulum.linearize({th: 0, "k": 1}, [th])
    with pytest.raises(ModelTypeError, match="must be a number"):
        pendulum.linearize({th: "0"}, [th])
    with pytest.raises(ModelError, match="not a parameter"):
        pendulum.linearize({th: 0}, [th], inputs=["F"])
    with pytest.raises(ModelTypeError, match="must be a dict"):
        pendulum.linearize([(th, 0)], [th])


# --------------------------------------------------------------------------- rolling disk
def test_rolling_disk_critical_spin() -> None:
    """A thin disk (I = m r²/4 about a diameter, m r²/2 about its axis) rolling upright is
    stable (marginally: no dissipation) above the spin ω_c = √(g/(3r)), i.e. v² > g r/3, and
    capsizes below. Only the spin rate is given: the dependent rates (ẋ, ż) are computed."""
    eom = pfaff.models.rolling_disk().equations()
    x, y, z, psi, th, ph = eom.coordinates
    r, g = 0.5, 9.81
    wc = np.sqrt(g / (3 * r))

    def growth(w: float) -> float:
        op = {x: 0, y: 0, z: r, psi: 0, th: 0, ph: 0, ph.diff(t): w, "m": 1.0, "r": r, "g": g}
        lin = eom.linearize(op, [x, y, psi, th, ph], [psi, th, ph])
        assert {0, 1, 2, 4, 7} <= set(lin.ignorable())  # x, y, yaw, spin angle and rate
        keep = [k for k in range(8) if k not in lin.ignorable()]
        return float(np.linalg.eigvals(lin.A[np.ix_(keep, keep)]).real.max())

    assert growth(0.999 * wc) > 1e-2
    assert abs(growth(1.001 * wc)) < 1e-9
    assert abs(growth(3 * wc)) < 1e-9
    assert growth(0.0) == pytest.approx(
        np.sqrt(g / r * 4 / 5), rel=1e-12
    )  # falling over: m g r / (I + m r²)
