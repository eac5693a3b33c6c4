"""pfaff against SymPy's own ``sympy.physics.mechanics.LagrangesMethod``.

Every system is built twice, independently: once with pfaff's API and once with SymPy's mechanics
objects (frames, points, particles, rigid bodies, ``forcelist``). The two derivations are compared
numerically (q̈ and λ at random states and random parameter values) and symbolically (mass matrix,
forcing, constraint Jacobian, differentiated constraints).

Sign relation of the multipliers (found by reading sympy 1.14 lagrange.py, and asserted below)
--------------------------------------------------------------------------------------------
pfaff: M q̈ + h = Q + Aᵀ λ_pfaff, A = ∂f/∂q (holonomic f) or ∂g/∂q̇ (velocity constraint g).

SymPy builds its constraint rows as ``coneqs = [ḟ; g]`` (``__init__``), so for holonomic AND
nonholonomic constraints alike C := coneqs.jacobian(q̇) = A (ḟ = (∂f/∂q) q̇ + ∂f/∂t). Then in
``form_lagranges_equations``

    self.lam_coeffs = -coneqs.jacobian(qds)          # line 201: the negated Jacobian, sympy #30215
    self._term3 = self.lam_coeffs.T * self.lam_vec   # = -Aᵀ λ
    self.eom = without_lam - self._term3             # line 227: M q̈ + h - Q + Aᵀ λ = 0

but ``mass_matrix`` (line 253) is ``self._m_d.row_join(self.lam_coeffs.T)`` = [M | -Aᵀ], with
``forcing`` = Q - h, i.e. mass_matrix · [q̈; λ] = forcing means M q̈ + h - Q - Aᵀ λ = 0. The two
are NOT the same equations: SymPy is inconsistent with itself (the ``-`` of line 201 enters ``eom``
through ``- self._term3`` but enters ``mass_matrix`` directly). Hence, for holonomic and
nonholonomic constraints alike:

* λ from solving ``mass_matrix_full · [q̇; q̈; λ] = forcing_full`` (or mass_matrix / forcing):
  **λ_pfaff = +λ_sympy_matrices**;
* λ satisfying SymPy's own ``eom`` (the symbols ``lam_vec``) and ``solve_multipliers()`` (which
  solves [[M, -Aᵀ], [A, 0]] x = -[forcing; f_cd], negating the matrix-form solution):
  **λ_pfaff = -λ_sympy_eom**.

SymPy orders its multipliers holonomic first, then nonholonomic; the pfaff systems below add their
constraints in that same order, so the multipliers correspond one to one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

import numpy as np
import pytest
import sympy as sp
from sympy.physics.mechanics import (
    LagrangesMethod,
    Lagrangian,
    Particle,
    Point,
    ReferenceFrame,
    RigidBody,
    dynamicsymbols,
    inertia,
)

import pfaff

t = pfaff.t
RTOL = 1e-10


# ---------------------------------------------------------------------------------------------
# The systems, each built in both tools
# ---------------------------------------------------------------------------------------------
@dataclass
class Case:
    """One system built twice: a pfaff System and a formed SymPy LagrangesMethod."""

    name: str
    system: pfaff.System
    lm: LagrangesMethod
    q: tuple  # SymPy's coordinates (dynamicsymbols), in the same order as pfaff's
    params: tuple[sp.Symbol, ...]
    n_holonomic: int
    n_nonholonomic: int
    random_state: Callable[[np.random.Generator], tuple[float, np.ndarray, np.ndarray]]


def _uniform_state(n: int, scale: float = 1.0):
    def draw(rng: np.random.Generator) -> tuple[float, np.ndarray, np.ndarray]:
        return (
            float(rng.uniform(-2.0, 2.0)),
            scale * rng.uniform(-1.0, 1.0, n),
            rng.uniform(-1.5, 1.5, n),
        )

    return draw


def _particle(name: str, frame: ReferenceFrame, origin: Point, mass, position) -> Particle:
    """A SymPy particle at ``position`` (a Vector from ``origin``), velocity by differentiation."""
    P = origin.locatenew(name, position)
    P.set_vel(frame, position.dt(frame))
    return Particle(name, P, mass)


def _inertial() -> tuple[ReferenceFrame, Point]:
    N = ReferenceFrame("N")
    No = Point("O")
    No.set_vel(N, 0)
    return N, No


def _form(L, qs, **kwargs) -> LagrangesMethod:
    lm = LagrangesMethod(L, qs, **kwargs)
    lm.form_lagranges_equations()
    return lm


@cache
def cartesian_pendulum() -> Case:
    """(1) Point mass on a rod, Cartesian: x² + y² - L² = 0, gravity -y (pfaff's own model)."""
    m, g, L = sp.symbols("m g L")
    system = pfaff.models.cartesian_pendulum()

    x, y = dynamicsymbols("x y")
    N, No = _inertial()
    bob = _particle("bob", N, No, m, x * N.x + y * N.y)
    bob.potential_energy = m * g * y
    lm = _form(Lagrangian(N, bob), [x, y], frame=N, hol_coneqs=[x**2 + y**2 - L**2])
    return Case("cartesian pendulum", system, lm, (x, y), (m, g, L), 1, 0, _uniform_state(2))


@cache
def rotating_hoop() -> Case:
    """(2) Bead on a vertical hoop of radius R spinning at rate w about the vertical z axis.

    Cartesian q = (x, y, z); constraints: sphere x² + y² + z² - R² = 0 (scleronomic) and the hoop's
    plane -x sin(wt) + y cos(wt) = 0 (rheonomic: b = ∂f/∂t = -w(x cos wt + y sin wt) ≠ 0).
    """
    m, g, R, w = sp.symbols("m g R w")
    sphere = lambda x, y, z: x**2 + y**2 + z**2 - R**2  # noqa: E731
    plane = lambda x, y: -x * sp.sin(w * t) + y * sp.cos(w * t)  # noqa: E731

    px, py, pz = pfaff.coordinates("x y z")
    system = pfaff.System([px, py, pz], name="bead on rotating hoop")
    system.add_particle(m, [px, py, pz])
    system.add_potential_energy(m * g * pz)
    system.add_holonomic_constraint(sphere(px, py, pz), name="hoop radius")
    system.add_holonomic_constraint(plane(px, py), name="hoop plane")

    x, y, z = dynamicsymbols("x y z")
    N, No = _inertial()
    bead = _particle("bead", N, No, m, x * N.x + y * N.y + z * N.z)
    bead.potential_energy = m * g * z
    lm = _form(Lagrangian(N, bead), [x, y, z], frame=N, hol_coneqs=[sphere(x, y, z), plane(x, y)])
    return Case("rotating hoop", system, lm, (x, y, z), (m, g, R, w), 2, 0, _uniform_state(3))


@cache
def driven_pendulum() -> Case:
    """(2b) Cartesian pendulum whose pivot is shaken horizontally: (x - a sin wt)² + y² - L² = 0."""
    m, g, L, a, w = sp.symbols("m g L a w")
    rod = lambda x, y: (x - a * sp.sin(w * t)) ** 2 + y**2 - L**2  # noqa: E731

    px, py = pfaff.coordinates("x y")
    system = pfaff.System([px, py], name="driven pendulum")
    system.add_particle(m, [px, py])
    system.add_potential_energy(m * g * py)
    system.add_holonomic_constraint(rod(px, py), name="rod")

    x, y = dynamicsymbols("x y")
    N, No = _inertial()
    bob = _particle("bob", N, No, m, x * N.x + y * N.y)
    bob.potential_energy = m * g * y
    lm = _form(Lagrangian(N, bob), [x, y], frame=N, hol_coneqs=[rod(x, y)])
    return Case("driven pendulum", system, lm, (x, y), (m, g, L, a, w), 1, 0, _uniform_state(2, 2))


def _sleigh(belt: bool, groove: bool) -> Case:
    """(3) Chaplygin sleigh: rigid body (mass m, inertia I about its centre G), knife edge at the
    contact point P = (x, y), G = P + a (cos θ, sin θ). Nonholonomic constraint: P has no velocity
    across the blade relative to the ground, which is a belt moving along x with speed
    u(t) = v cos(wt) when ``belt`` (then b ≠ 0):  -(ẋ - u) sin θ + ẏ cos θ = 0.
    Loads: a thrust Fb along the blade at P, a torque tau, gravity g along -y on G.
    With ``groove``, P is in addition held on the circle x² + y² = c² (holonomic, listed first).
    """
    m, Izz, a, g, Fb, tau = sp.symbols("m I a g F_b tau")
    params = [m, Izz, a, g, Fb, tau]
    if belt:
        v, w = sp.symbols("v w")
        params += [v, w]
        u = v * sp.cos(w * t)
    else:
        u = sp.S.Zero
    if groove:
        c = sp.Symbol("c")
        params.append(c)

    # pfaff, with explicit components
    px, py, pth = pfaff.coordinates("x y theta")
    system = pfaff.System([px, py, pth], name="Chaplygin sleigh")
    gx, gy = px + a * sp.cos(pth), py + a * sp.sin(pth)
    system.add_particle(m, [gx, gy], name="body")
    system.add_kinetic_energy(Izz * pth.diff(t) ** 2 / 2, name="rotation")
    system.add_potential_energy(m * g * gy)
    system.add_force([Fb * sp.cos(pth), Fb * sp.sin(pth)], at=[px, py], name="thrust")
    system.add_generalized_force(pth, tau)
    if groove:
        system.add_holonomic_constraint(px**2 + py**2 - c**2, name="groove")
    system.add_velocity_constraint(
        -(px.diff(t) - u) * sp.sin(pth) + py.diff(t) * sp.cos(pth), name="knife edge"
    )

    # SymPy, with frames, a rigid body and vectors
    x, y, th = dynamicsymbols("x y theta")
    N, No = _inertial()
    B = N.orientnew("B", "Axis", (th, N.z))
    P = No.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, x.diff(t) * N.x + y.diff(t) * N.y)
    G = P.locatenew("G", a * B.x)
    G.v2pt_theory(P, N, B)
    body = RigidBody("body", G, B, m, (inertia(B, 0, 0, Izz), G))
    body.potential_energy = m * g * G.pos_from(No).dot(N.y)
    knife = (P.vel(N) - u * N.x).dot(B.y)
    lm = _form(
        Lagrangian(N, body),
        [x, y, th],
        frame=N,
        forcelist=[(P, Fb * B.x), (B, tau * N.z)],
        hol_coneqs=[x**2 + y**2 - c**2] if groove else None,
        nonhol_coneqs=[knife],
    )
    name = "sleigh" + (" on belt" if belt else "") + (" in groove" if groove else "")
    return Case(name, system, lm, (x, y, th), tuple(params), int(groove), 1, _uniform_state(3, 2))


@cache
def sleigh() -> Case:
    return _sleigh(belt=False, groove=False)


@cache
def sleigh_on_belt() -> Case:
    return _sleigh(belt=True, groove=False)


@cache
def sleigh_in_groove() -> Case:
    return _sleigh(belt=True, groove=True)


@cache
def dumbbell() -> Case:
    """(4) Two masses on a massless rigid rod of length l in a vertical plane, gravity -y, a
    horizontal force F on mass 2 and a linear drag -c v on mass 1 (velocity-dependent load).
    """
    m1, m2, g, ell, F, c = sp.symbols("m1 m2 g l F c")
    rod = lambda x1, y1, x2, y2: (x1 - x2) ** 2 + (y1 - y2) ** 2 - ell**2  # noqa: E731

    q = pfaff.coordinates("x1 y1 x2 y2")
    x1, y1, x2, y2 = q
    system = pfaff.System(q, name="dumbbell")
    system.add_particle(m1, [x1, y1])
    system.add_particle(m2, [x2, y2])
    system.add_potential_energy(m1 * g * y1 + m2 * g * y2)
    system.add_holonomic_constraint(rod(x1, y1, x2, y2), name="rod")
    system.add_force([F, 0], at=[x2, y2], name="push")
    system.add_force([-c * x1.diff(t), -c * y1.diff(t)], at=[x1, y1], name="drag")

    sq = dynamicsymbols("x1 y1 x2 y2")
    X1, Y1, X2, Y2 = sq
    N, No = _inertial()
    p1 = _particle("p1", N, No, m1, X1 * N.x + Y1 * N.y)
    p2 = _particle("p2", N, No, m2, X2 * N.x + Y2 * N.y)
    p1.potential_energy = m1 * g * Y1
    p2.potential_energy = m2 * g * Y2
    P1, P2 = p1.point, p2.point
    lm = _form(
        Lagrangian(N, p1, p2),
        list(sq),
        frame=N,
        forcelist=[(P2, F * N.x), (P1, -c * P1.vel(N))],
        hol_coneqs=[rod(X1, Y1, X2, Y2)],
    )
    params = (m1, m2, g, ell, F, c)
    return Case("dumbbell", system, lm, tuple(sq), params, 1, 0, _uniform_state(4, 2))


@cache
def rolling_ring3() -> Case:
    """(5) pfaff's rolling ring with N = 3 particles and a push F at the centre."""
    n = 3
    M, r, F = sp.symbols("M r F")
    system = pfaff.models.rolling_ring(n, force=True)

    sq = dynamicsymbols(f"x theta1:{n + 1}")
    x, th = sq[0], sq[1:]
    N, No = _inertial()
    parts = [
        _particle(f"p{k}", N, No, M / n, (x + r * sp.sin(th[k])) * N.x + r * sp.cos(th[k]) * N.y)
        for k in range(n)
    ]
    C = No.locatenew("C", x * N.x)
    C.set_vel(N, x.diff(t) * N.x)
    hol = [x - r * th[0]] + [th[k + 1] - th[k] - 2 * sp.pi / n for k in range(n - 1)]
    lm = _form(Lagrangian(N, *parts), list(sq), frame=N, forcelist=[(C, F * N.x)], hol_coneqs=hol)

    def draw(rng: np.random.Generator) -> tuple[float, np.ndarray, np.ndarray]:
        return (0.0, rng.uniform(-np.pi, np.pi, n + 1), rng.uniform(-1.5, 1.5, n + 1))

    return Case("rolling ring N=3", system, lm, tuple(sq), (M, r, F), n, 0, draw)


CASES = {
    f.__name__: f
    for f in (
        cartesian_pendulum,
        rotating_hoop,
        driven_pendulum,
        sleigh,
        sleigh_on_belt,
        sleigh_in_groove,
        dumbbell,
        rolling_ring3,
    )
}


# ---------------------------------------------------------------------------------------------
# Numerics on SymPy's side: solve mass_matrix_full · [q̇; q̈; λ] = forcing_full
# ---------------------------------------------------------------------------------------------
@cache
def sympy_kkt(case_name: str):
    """Lambdified (t, q, q̇, params) -> (mass_matrix_full, forcing_full) of LagrangesMethod."""
    case = CASES[case_name]()
    lm = case.lm
    n = len(case.q)
    qs = sp.symbols(f"q0:{n}")
    us = sp.symbols(f"u0:{n}")
    ts = sp.Symbol("t_")
    rule = {qi.diff(t): ui for qi, ui in zip(case.q, us, strict=True)}
    rule.update(dict(zip(case.q, qs, strict=True)))
    rule[t] = ts
    MM = lm.mass_matrix_full.xreplace(rule)
    FF = lm.forcing_full.xreplace(rule)
    leftover = (MM.free_symbols | FF.free_symbols) - {ts, *qs, *us, *case.params}
    assert not leftover, f"unexpected symbols in SymPy's equations: {leftover}"
    f = sp.lambdify((ts, qs, us, case.params), (MM, FF), modules="numpy")
    return f


def sympy_solution(name: str, t0, q, qd, values) -> tuple[np.ndarray, np.ndarray]:
    """q̈ and λ (SymPy's sign) of system ``name`` at (t0, q, q̇) for parameter ``values``."""
    n = len(CASES[name]().q)
    MM, FF = sympy_kkt(name)(t0, q, qd, values)
    MM = np.asarray(MM, dtype=float)
    FF = np.asarray(FF, dtype=float).ravel()
    sol = np.linalg.solve(MM, FF)
    np.testing.assert_allclose(sol[:n], qd, rtol=1e-13, atol=1e-13)  # the kinematic rows
    return sol[n : 2 * n], sol[2 * n :]


@cache
def sympy_eom_residual(case_name: str):
    """Lambdified (t, q, q̇, q̈, λ, params) -> LagrangesMethod.eom (its equations, = 0)."""
    case = CASES[case_name]()
    n, m = len(case.q), len(case.lm.lam_vec)
    qs, us, ws = sp.symbols(f"q0:{n}"), sp.symbols(f"u0:{n}"), sp.symbols(f"w0:{n}")
    ls, ts = sp.symbols(f"l0:{m}"), sp.Symbol("t_")
    rule = {qi.diff(t, 2): wi for qi, wi in zip(case.q, ws, strict=True)}
    rule.update({qi.diff(t): ui for qi, ui in zip(case.q, us, strict=True)})
    rule.update(dict(zip(case.q, qs, strict=True)))
    rule.update(dict(zip(case.lm.lam_vec, ls, strict=True)))
    rule[t] = ts
    eom = case.lm.eom.xreplace(rule)
    assert not eom.free_symbols - {ts, *qs, *us, *ws, *ls, *case.params}
    return sp.lambdify((ts, qs, us, ws, ls, case.params), eom, modules="numpy")


@cache
def pfaff_equations(case_name: str):
    return CASES[case_name]().system.equations()


def _close(a: np.ndarray, b: np.ndarray, what: str, info: str) -> None:
    scale = max(1.0, float(np.max(np.abs(b), initial=0.0)))
    np.testing.assert_allclose(a, b, rtol=RTOL, atol=RTOL * scale, err_msg=f"{what}: {info}")


# ---------------------------------------------------------------------------------------------
# Tests
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_same_coordinates_and_multiplier_count(name):
    case = CASES[name]()
    assert tuple(case.system.coordinates) == case.q
    eom = pfaff_equations(name)
    m = case.n_holonomic + case.n_nonholonomic
    assert len(eom.multipliers) == m
    assert len(case.lm.lam_vec) == m
    assert case.lm.mass_matrix.shape == (len(case.q), len(case.q) + m)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("name", list(CASES))
def test_accelerations_and_multipliers_agree(name, seed):
    """q̈ and λ from pfaff's compiled model against LagrangesMethod at random states/parameters.

    The states need not satisfy the constraints: both tools solve the same augmented system at the
    same (t, q, q̇), so they must agree anywhere the system is nonsingular.
    """
    case = CASES[name]()
    rng = np.random.default_rng(1000 * seed + sum(map(ord, name)))
    values = rng.uniform(0.5, 2.0, len(case.params))
    model = pfaff_equations(name).compile(
        {p: float(v) for p, v in zip(case.params, values, strict=True)}
    )
    for _ in range(3):
        t0, q, qd = case.random_state(rng)
        qdd_p, lam_p = model.accelerations(t0, q, qd)
        qdd_s, lam_s = sympy_solution(name, t0, q, qd, values)
        info = f"{case.name}, params={dict(zip(case.params, values, strict=True))}, t={t0!r}, "
        info += f"q={q.tolist()}, qd={qd.tolist()}; pfaff qdd={qdd_p}, lam={lam_p}; "
        info += f"sympy qdd={qdd_s}, lam={lam_s}"
        assert np.all(np.isfinite(qdd_s)) and np.all(np.isfinite(lam_s))
        assert qdd_p.shape == qdd_s.shape and lam_p.shape == lam_s.shape
        _close(qdd_p, qdd_s, "accelerations", info)
        # matrix form of SymPy: λ_pfaff = +λ_sympy, holonomic and nonholonomic (module docstring)
        _close(lam_p, lam_s, "multipliers (λ_pfaff = +λ from mass_matrix_full)", info)
        # SymPy's own eom is satisfied by pfaff's q̈ with the opposite multipliers -λ_pfaff ...
        res = np.asarray(sympy_eom_residual(name)(t0, q, qd, qdd_p, -lam_p, values), dtype=float)
        size = np.max(np.abs(np.asarray(model.forcing(t0, q, qd))), initial=1.0)
        np.testing.assert_allclose(res.ravel(), 0.0, atol=1e-10 * size, err_msg=info)
        # ... and not by +λ_pfaff (the two signs are really distinguishable here)
        res = np.asarray(sympy_eom_residual(name)(t0, q, qd, qdd_p, lam_p, values), dtype=float)
        assert np.max(np.abs(res)) > 1e-6 * size, info


def test_multipliers_are_not_trivially_zero():
    """Guard against a vacuous sign check: the compared λ are of order one at a generic state."""
    for name in CASES:
        case = CASES[name]()
        rng = np.random.default_rng(7)
        values = rng.uniform(0.5, 2.0, len(case.params))
        t0, q, qd = case.random_state(rng)
        _, lam_s = sympy_solution(name, t0, q, qd, values)
        assert np.all(np.abs(lam_s) > 1e-6), (name, lam_s)


def test_rolling_ring_known_values_in_both_tools():
    """At a consistent state the ring obeys θ̈ = F/(2Mr), ẍ = F/(2M); the no-slip multiplier is
    λ1 = -F/2 in pfaff and in SymPy's matrix form, +F/2 in SymPy's eom / solve_multipliers."""
    M, r, F = 1.3, 0.7, 2.2
    model = pfaff_equations("rolling_ring3").compile({"M": M, "r": r, "F": F})
    q, qd = pfaff.models.ring_state(3, r, theta=0.4, theta_dot=-1.1)
    qdd_p, lam_p = model.accelerations(0.0, q, qd)
    qdd_s, lam_s = sympy_solution("rolling_ring3", 0.0, q, qd, [M, r, F])
    expected = np.array([F / (2 * M)] + [F / (2 * M * r)] * 3)
    np.testing.assert_allclose(qdd_p, expected, rtol=1e-10)
    np.testing.assert_allclose(qdd_s, expected, rtol=1e-10)
    assert lam_p[0] == pytest.approx(-F / 2, rel=1e-10)
    assert lam_s[0] == pytest.approx(-F / 2, rel=1e-10)
    case = CASES["rolling_ring3"]()
    op = {qi: v for qi, v in zip(case.q, q, strict=True)}
    op.update({qi.diff(t): v for qi, v in zip(case.q, qd, strict=True)})
    op.update({sp.Symbol("M"): M, sp.Symbol("r"): r, sp.Symbol("F"): F})
    lam_solve = case.lm.solve_multipliers(op, sol_type="Matrix")
    assert float(lam_solve[0]) == pytest.approx(F / 2, rel=1e-10)


def test_cartesian_pendulum_known_multiplier_in_both_tools():
    """Bob at rest hanging down (x, y) = (0, -L): tension m g, λ_pfaff = m g y/(2L²) = -m g/(2L);
    the same from SymPy's mass_matrix_full, the opposite from its solve_multipliers."""
    m, g, L = 0.8, 9.81, 1.5
    model = pfaff_equations("cartesian_pendulum").compile({"m": m, "g": g, "L": L})
    q, qd = np.array([0.0, -L]), np.zeros(2)
    qdd_p, lam_p = model.accelerations(0.0, q, qd)
    qdd_s, lam_s = sympy_solution("cartesian_pendulum", 0.0, q, qd, [m, g, L])
    np.testing.assert_allclose(qdd_p, 0.0, atol=1e-12)
    np.testing.assert_allclose(qdd_s, 0.0, atol=1e-12)
    assert lam_p[0] == pytest.approx(-m * g / (2 * L), rel=1e-12)
    assert lam_s[0] == pytest.approx(-m * g / (2 * L), rel=1e-12)
    x, y = CASES["cartesian_pendulum"]().q
    op = {x: 0.0, y: -L, x.diff(t): 0.0, y.diff(t): 0.0}
    op.update({sp.Symbol("m"): m, sp.Symbol("g"): g, sp.Symbol("L"): L})
    lam_solve = CASES["cartesian_pendulum"]().lm.solve_multipliers(op, sol_type="Matrix")
    assert float(lam_solve[0]) == pytest.approx(m * g / (2 * L), rel=1e-12)


SYMBOLIC = ["cartesian_pendulum", "rotating_hoop", "driven_pendulum", "sleigh_on_belt", "dumbbell"]


@pytest.mark.parametrize("name", SYMBOLIC)
def test_symbolic_matrices_agree(name):
    """Mass matrix, forcing Q - h and constraint Jacobian: pfaff's M equals SymPy's
    mass_matrix[:, :n], pfaff's Q - h equals SymPy's forcing, and SymPy's multiplier columns
    mass_matrix[:, n:] are -Aᵀ (``lam_coeffs.T``, the negated Jacobian of sympy #30215)."""
    case = CASES[name]()
    eom = pfaff_equations(name)
    n = len(case.q)
    lmM = case.lm.mass_matrix
    assert sp.simplify(sp.Matrix(eom.mass_matrix) - lmM[:, :n]) == sp.zeros(n, n)
    assert sp.simplify(sp.Matrix(eom.forcing) - case.lm.forcing) == sp.zeros(n, 1)
    A = sp.Matrix(eom.constraint_matrix)
    assert sp.simplify(lmM[:, n:] + A.T) == sp.zeros(*A.T.shape)
    assert A != sp.zeros(*A.shape)


@pytest.mark.parametrize("name", ["rotating_hoop", "driven_pendulum", "sleigh_on_belt"])
def test_rheonomic_constraint_rows_agree(name):
    """For the time-dependent constraints b ≠ 0, and pfaff's A q̈ + Ȧq̇ + ḃ equals the time
    derivative of SymPy's constraint rows (coneqs = [ḟ; g])."""
    case = CASES[name]()
    eom = pfaff_equations(name)
    b = sp.Matrix(eom.constraint_bias)
    assert any(sp.simplify(bi) != 0 for bi in b)
    assert any(bi.has(t) for bi in b)
    sympy_rows = case.lm.coneqs.diff(t)
    diff = sp.simplify(sp.Matrix(eom.acceleration_constraints) - sympy_rows)
    assert diff == sp.zeros(*diff.shape)
    # and the velocity-level rows: A q̇ + b is SymPy's coneqs
    qd = sp.Matrix([qi.diff(t) for qi in case.q])
    assert sp.simplify(sp.Matrix(eom.constraint_matrix) * qd + b - case.lm.coneqs) == sp.zeros(
        *b.shape
    )
