"""Andrews' squeezing mechanism: the 7-body planar index-3 benchmark against its published solution.

Sources of every number used (parameters, consistent initial values, reference solution):

* E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., Springer,
  Section VII.7 ("Andrews' squeezing mechanism", after Giles 1978 and Manning 1981): the
  geometry, masses, inertias, spring and motor data, M(q), f(q, q̇) and the constraints g(q).
* "Test Set for IVP Solvers" (W. M. Lioen, J. J. B. de Swart, CWI Amsterdam; continued by
  F. Mazzia, C. Magherini, University of Bari), problem ``andrews`` (file ``andrews.f``): the
  same data, the consistent initial values with q̈(0) and λ(0), and the reference solution at
  t = 0.03 computed with PSIDE at rtol = atol = 1e-14 (Cray C90). Its convention is
  M q̈ = f(q, q̇) - Gᵀλ, pfaff's is M q̈ = Q + Aᵀλ, so λ_pfaff = -λ_testset.

Coordinates are the seven angles β, Θ, γ, Φ, δ, Ω, ε; gravity is zero. The model,
:func:`pfaff.models.andrews_squeezer` (data and reference in ``pfaff/models/andrews.py``), is built
the way a user would: T = ½ q̇ᵀ M(q) q̇ per coupled pair of bodies (Hairer's entries), the spring
as a potential ½ c0 (L - l0)², the motor torque as a generalized force on β and the six
loop-closure constraints; pfaff derives the Coriolis/centrifugal terms itself. The (β, Θ) pair
is also built from its bodies' centres of mass and inertias to check the published M and f.

Measured here (2 cores, shared): the projection method at rtol = 1e-10 ends 1.55e-9 rad from the
reference angles, Baumgarte 1.67e-9, IDA 4.7e-8. The floor is the reference itself: projection
and Baumgarte at rtol = 1e-12 and an independent index-1 ``solve_ivp(DOP853)`` at rtol = 1e-13
agree with one another to 1e-12 and all sit 1.43e-9 (β, Θ ≈ 16 rad: 9e-11 relative) from it.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.models.andrews import ANDREWS_COORDINATES, andrews_reference, andrews_state

t = pfaff.t

PARAMS = pfaff.models.ANDREWS
SYM = {k: sp.Symbol(k) for k in PARAMS}
p = type("p", (), PARAMS)  # numeric parameters as attributes, for the reference formulas
Q0, _ = andrews_state()
REF = andrews_reference()
T_END = REF["t_end"]


# ---------------------------------------------------------------- published formulas, in NumPy
def hairer_mass_matrix(q: np.ndarray) -> np.ndarray:
    """M(q) entry by entry as printed by Hairer & Wanner (symmetric, block diagonal)."""
    th, ph, om = q[1], q[3], q[5]
    k4, k6 = p.e - p.ea, p.zf - p.fa
    M = np.zeros((7, 7))
    M[0, 0] = p.m1 * p.ra**2 + p.m2 * (p.rr**2 - 2 * p.da * p.rr * np.cos(th) + p.da**2)
    M[0, 0] += p.I1 + p.I2
    M[0, 1] = M[1, 0] = p.m2 * (p.da**2 - p.da * p.rr * np.cos(th)) + p.I2
    M[1, 1] = p.m2 * p.da**2 + p.I2
    M[2, 2] = p.m3 * (p.sa**2 + p.sb**2) + p.I3
    M[3, 3] = p.m4 * k4**2 + p.I4
    M[3, 4] = M[4, 3] = p.m4 * (k4**2 + p.zt * k4 * np.sin(ph)) + p.I4
    M[4, 4] = p.m4 * (p.zt**2 + 2 * p.zt * k4 * np.sin(ph) + k4**2)
    M[4, 4] += p.m5 * (p.ta**2 + p.tb**2) + p.I4 + p.I5
    M[5, 5] = p.m6 * k6**2 + p.I6
    M[5, 6] = M[6, 5] = p.m6 * (k6**2 - p.u * k6 * np.sin(om)) + p.I6
    M[6, 6] = p.m6 * (k6**2 - 2 * p.u * k6 * np.sin(om) + p.u**2)
    M[6, 6] += p.m7 * (p.ua**2 + p.ub**2) + p.I6 + p.I7
    return M


def hairer_force(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """f(q, q̇): motor torque, spring and the Coriolis/centrifugal terms, as published."""
    th, ga, ph, om = q[1], q[2], q[3], q[5]
    bd, thd, _, phd, ded, omd, epd = qd
    k4, k6 = p.e - p.ea, p.zf - p.fa
    xd = p.sd * np.cos(ga) + p.sc * np.sin(ga) + p.xb
    yd = p.sd * np.sin(ga) - p.sc * np.cos(ga) + p.yb
    length = np.hypot(xd - p.xc, yd - p.yc)
    force = -p.c0 * (length - p.l0) / length
    fx, fy = force * (xd - p.xc), force * (yd - p.yc)
    return np.array([
        p.mom - p.m2 * p.da * p.rr * thd * (thd + 2 * bd) * np.sin(th),
        p.m2 * p.da * p.rr * bd**2 * np.sin(th),
        fx * (p.sc * np.cos(ga) - p.sd * np.sin(ga)) + fy * (p.sd * np.cos(ga) + p.sc * np.sin(ga)),
        p.m4 * p.zt * k4 * ded**2 * np.cos(ph),
        -p.m4 * p.zt * k4 * phd * (phd + 2 * ded) * np.cos(ph),
        -p.m6 * p.u * k6 * epd**2 * np.cos(om),
        p.m6 * p.u * k6 * omd * (omd + 2 * epd) * np.cos(om),
    ])  # fmt: skip


def unit(a: sp.Expr) -> sp.Matrix:
    return sp.Matrix([sp.cos(a), sp.sin(a)])


@pytest.fixture(scope="module")
def eom():
    return pfaff.models.andrews_squeezer().equations()


@pytest.fixture(scope="module")
def model(eom):
    return eom.compile(PARAMS)


def _numeric(expr: sp.Matrix, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    coords = pfaff.coordinates(ANDREWS_COORDINATES)
    expr = expr.subs({SYM[k]: v for k, v in PARAMS.items()})
    expr = expr.subs({c.diff(t): v for c, v in zip(coords, qd, strict=True)})
    expr = expr.subs(dict(zip(coords, q, strict=True)))
    return np.array(expr.evalf(), dtype=float)


# ---------------------------------------------------------------- the derivation
@pytest.mark.slow  # SymPy substitution into the full equations
def test_mass_matrix_matches_hairer(eom):
    rng = np.random.default_rng(7)
    for q in (Q0, rng.uniform(-3, 3, 7)):
        M = _numeric(eom.mass_matrix, q, np.zeros(7))
        np.testing.assert_allclose(M, hairer_mass_matrix(q), rtol=1e-13, atol=1e-20)
    assert hairer_mass_matrix(Q0)[0, 0] == pytest.approx(2.7455193e-06, rel=1e-7)


@pytest.mark.slow  # SymPy substitution into the full equations
def test_forcing_matches_published_f(eom):
    """Spring sign, motor torque and the Coriolis terms pfaff derives from T, against f(q, q̇)."""
    rng = np.random.default_rng(3)
    q, qd = rng.uniform(-3, 3, 7), rng.uniform(-100, 100, 7)
    f = hairer_force(q, qd)
    np.testing.assert_allclose(_numeric(eom.forcing, q, qd).ravel(), f, rtol=1e-12, atol=1e-15)
    assert eom.constraint_matrix.shape == (6, 7)


@pytest.mark.slow  # sp.simplify of a 2x2 block
def test_crank_and_rod_from_their_bodies():
    """Bodies 1 and 2 as centres of mass plus inertias give Hairer's 2x2 block of M and f."""
    be, th = pfaff.coordinates("beta Theta")
    s = SYM
    wb, wt = be.diff(t), th.diff(t)
    pair = pfaff.System([be, th])
    pair.add_particle(s["m1"], s["ra"] * unit(be), name="crank")
    pair.add_kinetic_energy(s["I1"] * wb**2 / 2, name="crank rotation")
    pair.add_particle(s["m2"], s["rr"] * unit(be) - s["da"] * unit(be + th), name="rod")
    pair.add_kinetic_energy(s["I2"] * (wb + wt) ** 2 / 2, name="rod rotation")
    pair.add_generalized_force(be, s["mom"], name="motor")
    eq = pair.equations()
    m2, da, rr = s["m2"], s["da"], s["rr"]
    m11 = s["m1"] * s["ra"] ** 2 + m2 * (rr**2 - 2 * da * rr * sp.cos(th) + da**2) + s["I1"]
    M = sp.Matrix(
        [
            [m11 + s["I2"], m2 * (da**2 - da * rr * sp.cos(th)) + s["I2"]],
            [m2 * (da**2 - da * rr * sp.cos(th)) + s["I2"], m2 * da**2 + s["I2"]],
        ]
    )
    f = sp.Matrix(
        [
            s["mom"] - m2 * da * rr * wt * (wt + 2 * wb) * sp.sin(th),
            m2 * da * rr * wb**2 * sp.sin(th),
        ]
    )
    assert sp.simplify(eq.mass_matrix - M) == sp.zeros(2, 2)
    assert sp.simplify(eq.forcing - f) == sp.zeros(2, 1)


def test_initial_accelerations_and_multipliers(model):
    qdd, lam = model.accelerations(0.0, Q0, np.zeros(7))
    np.testing.assert_allclose(qdd[:2], REF["qdd0"][:2], rtol=1e-13)
    np.testing.assert_allclose(lam[:2], REF["multipliers0"][:2], rtol=1e-13)
    # The other entries are zero; accelerations are O(1e4), so 1e-10 is rounding level.
    assert np.abs(qdd[2:]).max() < 1e-10
    assert np.abs(lam[2:]).max() < 1e-12


# ---------------------------------------------------------------- the reference solution
# Bounds from the measurements in the module docstring: about twice the measured error for the
# Runge-Kutta methods (whose error sits at the 1.43e-9 floor of the reference), five times for
# IDA, whose error at rtol = 1e-10 is its own. Residuals measured: projection 5e-13, IDA 3e-14,
# Baumgarte 7e-11 (its reported states are not projected).
CASES = {
    "projection": dict(q=3e-9, qd=1.5e-6, residual=1e-10),
    "baumgarte": dict(q=3e-9, qd=1.5e-6, residual=1e-9),
    "ida": dict(q=2.5e-7, qd=1e-4, residual=1e-10),
}


@pytest.mark.parametrize(
    "method",
    [
        "projection",  # the fast check: about 1 s with the derivation
        pytest.param("baumgarte", marks=pytest.mark.slow),
        pytest.param("ida", marks=pytest.mark.slow),  # 2-8 s
    ],
)
def test_angles_at_t_end_match_reference(model, method):
    traj = pfaff.simulate(
        model,
        Q0,
        np.zeros(7),
        (0.0, T_END),
        method=method,
        rtol=1e-10,
        atol=1e-12,
        t_eval=np.linspace(0.0, T_END, 13),
        progress=False,
    )
    assert traj.status == "success", traj.message
    assert traj.t[-1] == pytest.approx(T_END)
    bound = CASES[method]
    err = np.abs(traj.q[-1] - REF["q"])
    assert err.max() < bound["q"], err
    assert np.abs(traj.constraint_residual).max() < bound["residual"]
    # Velocities up to 1.4e3 rad/s: measured 5.9e-7, 6.4e-7, 1.9e-5 (reference floor 5.4e-7).
    np.testing.assert_allclose(traj.qd[-1], REF["qd"], rtol=0, atol=bound["qd"])
    if method == "projection":
        # q̈ (up to 5.7e5) and λ at t = 0.03: measured 1.0e-7 and 7e-8 relative to the largest.
        scale_a, scale_l = np.abs(REF["qdd"]).max(), np.abs(REF["multipliers"]).max()
        np.testing.assert_allclose(traj.qdd[-1], REF["qdd"], rtol=0, atol=1e-6 * scale_a)
        np.testing.assert_allclose(
            traj.multipliers[-1], REF["multipliers"], rtol=0, atol=1e-6 * scale_l
        )
