"""Andrews' squeezing mechanism: the 7-body planar index-3 benchmark against its published solution.

Sources of every number below (parameters, consistent initial values, reference solution):

* E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., Springer,
  Section VII.7 ("Andrews' squeezing mechanism", after Giles 1978 and Manning 1981): the
  geometry, masses, inertias, spring and motor data, M(q), f(q, q̇) and the constraints g(q).
* "Test Set for IVP Solvers" (W. M. Lioen, J. J. B. de Swart, CWI Amsterdam; continued by
  F. Mazzia, C. Magherini, University of Bari), problem ``andrews`` (file ``andrews.f``): the
  same data, the consistent initial values with q̈(0) and λ(0), and the reference solution at
  t = 0.03 computed with PSIDE at rtol = atol = 1e-14 (Cray C90). Its convention is
  M q̈ = f(q, q̇) - Gᵀλ, pfaff's is M q̈ = Q + Aᵀλ, so λ_pfaff = -λ_testset.

Coordinates are the seven angles β, Θ, γ, Φ, δ, Ω, ε; gravity is zero. The model is built
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
from methods import ALL_METHODS

pytestmark = pytest.mark.slow  # the 7-body mechanism end to end: derivation and three runs

t = pfaff.t
NAMES = "beta Theta gamma Phi delta Omega epsilon"

# Hairer & Wanner VII.7 / test set `andrews`: masses, inertias, fixed points, geometry, spring, motor.
PARAMS = {
    "m1": 0.04325, "m2": 0.00365, "m3": 0.02373, "m4": 0.00706,
    "m5": 0.07050, "m6": 0.00706, "m7": 0.05498,
    "I1": 2.194e-6, "I2": 4.410e-7, "I3": 5.255e-6, "I4": 5.667e-7,
    "I5": 1.169e-5, "I6": 5.667e-7, "I7": 1.912e-5,
    "xa": -0.06934, "ya": -0.00227, "xb": -0.03635, "yb": 0.03273, "xc": 0.014, "yc": 0.072,
    "d": 28e-3, "da": 115e-4, "e": 2e-2, "ea": 1421e-5, "rr": 7e-3, "ra": 92e-5,
    "ss": 35e-3, "sa": 1874e-5, "sb": 1043e-5, "sc": 18e-3, "sd": 2e-2,
    "ta": 2308e-5, "tb": 916e-5, "u": 4e-2, "ua": 1228e-5, "ub": 449e-5,
    "zf": 2e-2, "zt": 4e-2, "fa": 1421e-5,
    "c0": 4530.0, "l0": 7785e-5, "mom": 33e-3,
}  # fmt: skip
SYM = {k: sp.Symbol(k) for k in PARAMS}
p = type("p", (), PARAMS)  # numeric parameters as attributes, for the reference formulas

# Test set, subroutine INITIAL: consistent q(0) (q̇(0) = 0), q̈(0) and λ(0) (other entries 0).
Q0 = np.array([
    -0.0617138900142764496358948458001, 0.0, 0.455279819163070380255912382449,
    0.222668390165885884674473185609, 0.487364979543842550225598953530,
    -0.222668390165885884674473185609, 1.23054744454982119249735015568,
])  # fmt: skip
QDD0 = np.array([14222.4439199541138705911625887, -10666.8329399655854029433719415, 0, 0, 0, 0, 0])
LAM0 = np.array([98.5668703962410896057654982170, -6.12268834425566265503114393122, 0, 0, 0, 0])

# Test set, subroutine SOLN: reference y(0.03) = (q, q̇, q̈, λ).
T_END = 0.03
Q_REF = np.array([
    0.1581077119629904e2, -0.1575637105984298e2, 0.4082224013073101e-1,
    -0.5347301163226948, 0.5244099658805304, 0.5347301163226948, 0.1048080741042263e1,
])  # fmt: skip
QD_REF = np.array([
    0.1139920302151208e4, -0.1424379294994111e4, 0.1103291221937134e2, 0.1929337464421385e2,
    0.5735699284790808, -0.1929337464421385e2, 0.3231791658026955,
])  # fmt: skip
QDD_REF = np.array([
    -0.2463176316945196e5, 0.5185037701610329e5, 0.3241025686413781e6, 0.5667493645176213e6,
    0.1674362929479361e5, -0.5667493645176222e6, 0.9826520791458422e4,
])  # fmt: skip
LAM_REF = np.array([
    0.1991753333731910e3, -0.2975531228015052e2, 0.2306654119098399e2,
    0.3145271365475927e2, 0.2264249232082739e2, 0.1161740700019673e2,
])  # fmt: skip


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


# ---------------------------------------------------------------- the pfaff model
def unit(a: sp.Expr) -> sp.Matrix:
    return sp.Matrix([sp.cos(a), sp.sin(a)])


def normal(a: sp.Expr) -> sp.Matrix:
    return sp.Matrix([-sp.sin(a), sp.cos(a)])


def squeezer() -> pfaff.System:
    q = pfaff.coordinates(NAMES)
    be, th, ga, ph, de, om, ep = q
    wb, wt, wg, wp, wd, wo, we = (c.diff(t) for c in q)
    s = SYM
    k4, k6 = s["e"] - s["ea"], s["zf"] - s["fa"]
    sys_ = pfaff.System(list(q), name="Andrews' squeezing mechanism")
    # Kinetic energy per coupled pair of bodies, Hairer's M(q) entries.
    m11 = s["m1"] * s["ra"] ** 2 + s["I1"] + s["I2"]
    m11 += s["m2"] * (s["rr"] ** 2 - 2 * s["da"] * s["rr"] * sp.cos(th) + s["da"] ** 2)
    m12 = s["m2"] * (s["da"] ** 2 - s["da"] * s["rr"] * sp.cos(th)) + s["I2"]
    m22 = s["m2"] * s["da"] ** 2 + s["I2"]
    sys_.add_kinetic_energy(m11 * wb**2 / 2 + m12 * wb * wt + m22 * wt**2 / 2, name="bodies 1, 2")
    m33 = s["m3"] * (s["sa"] ** 2 + s["sb"] ** 2) + s["I3"]
    sys_.add_kinetic_energy(m33 * wg**2 / 2, name="body 3")
    m44 = s["m4"] * k4**2 + s["I4"]
    m45 = s["m4"] * (k4**2 + s["zt"] * k4 * sp.sin(ph)) + s["I4"]
    m55 = s["m4"] * (s["zt"] ** 2 + 2 * s["zt"] * k4 * sp.sin(ph) + k4**2)
    m55 += s["m5"] * (s["ta"] ** 2 + s["tb"] ** 2) + s["I4"] + s["I5"]
    sys_.add_kinetic_energy(m44 * wp**2 / 2 + m45 * wp * wd + m55 * wd**2 / 2, name="bodies 4, 5")
    m66 = s["m6"] * k6**2 + s["I6"]
    m67 = s["m6"] * (k6**2 - s["u"] * k6 * sp.sin(om)) + s["I6"]
    m77 = s["m6"] * (k6**2 - 2 * s["u"] * k6 * sp.sin(om) + s["u"] ** 2)
    m77 += s["m7"] * (s["ua"] ** 2 + s["ub"] ** 2) + s["I6"] + s["I7"]
    sys_.add_kinetic_energy(m66 * wo**2 / 2 + m67 * wo * we + m77 * we**2 / 2, name="bodies 6, 7")
    # Spring between D on body 3 and the fixed point C; motor torque on the crank.
    B, C = sp.Matrix([s["xb"], s["yb"]]), sp.Matrix([s["xc"], s["yc"]])
    D = B + s["sd"] * unit(ga) - s["sc"] * normal(ga)
    length = sp.sqrt((D - C).dot(D - C))
    sys_.add_potential_energy(s["c0"] * (length - s["l0"]) ** 2 / 2, name="spring")
    sys_.add_generalized_force(be, s["mom"], name="motor")
    # Loop closure: the end F of rod 2 reached through body 3 (to B) and bodies 4/5, 6/7 (to A).
    F = s["rr"] * unit(be) - s["d"] * unit(be + th)
    xa, ya, xb, yb = s["xa"], s["ya"], s["xb"], s["yb"]
    e_, zt, zf, u = s["e"], s["zt"], s["zf"], s["u"]
    closures = {
        "B x": F[0] - s["ss"] * sp.sin(ga) - xb,
        "B y": F[1] + s["ss"] * sp.cos(ga) - yb,
        "A via 4,5 x": F[0] - e_ * sp.sin(ph + de) - zt * sp.cos(de) - xa,
        "A via 4,5 y": F[1] + e_ * sp.cos(ph + de) - zt * sp.sin(de) - ya,
        "A via 6,7 x": F[0] - zf * sp.cos(om + ep) - u * sp.sin(ep) - xa,
        "A via 6,7 y": F[1] - zf * sp.sin(om + ep) + u * sp.cos(ep) - ya,
    }
    for name, expr in closures.items():
        sys_.add_holonomic_constraint(expr, name=name)
    return sys_


@pytest.fixture(scope="module")
def eom():
    return squeezer().equations()


@pytest.fixture(scope="module")
def model(eom):
    return eom.compile(PARAMS)


def _numeric(expr: sp.Matrix, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    coords = pfaff.coordinates(NAMES)
    expr = expr.subs({SYM[k]: v for k, v in PARAMS.items()})
    expr = expr.subs({c.diff(t): v for c, v in zip(coords, qd, strict=True)})
    expr = expr.subs(dict(zip(coords, q, strict=True)))
    return np.array(expr.evalf(), dtype=float)


# ---------------------------------------------------------------- the derivation
def test_mass_matrix_matches_hairer(eom):
    rng = np.random.default_rng(7)
    for q in (Q0, rng.uniform(-3, 3, 7)):
        M = _numeric(eom.mass_matrix, q, np.zeros(7))
        np.testing.assert_allclose(M, hairer_mass_matrix(q), rtol=1e-13, atol=1e-20)
    assert hairer_mass_matrix(Q0)[0, 0] == pytest.approx(2.7455193e-06, rel=1e-7)


def test_forcing_matches_published_f(eom):
    """Spring sign, motor torque and the Coriolis terms pfaff derives from T, against f(q, q̇)."""
    rng = np.random.default_rng(3)
    q, qd = rng.uniform(-3, 3, 7), rng.uniform(-100, 100, 7)
    f = hairer_force(q, qd)
    np.testing.assert_allclose(_numeric(eom.forcing, q, qd).ravel(), f, rtol=1e-12, atol=1e-15)
    assert eom.constraint_matrix.shape == (6, 7)


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
    np.testing.assert_allclose(qdd[:2], QDD0[:2], rtol=1e-13)
    np.testing.assert_allclose(lam[:2], -LAM0[:2], rtol=1e-13)
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


@pytest.mark.parametrize("method", ALL_METHODS)
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
    err = np.abs(traj.q[-1] - Q_REF)
    assert err.max() < bound["q"], err
    assert np.abs(traj.constraint_residual).max() < bound["residual"]
    # Velocities up to 1.4e3 rad/s: measured 5.9e-7, 6.4e-7, 1.9e-5 (reference floor 5.4e-7).
    np.testing.assert_allclose(traj.qd[-1], QD_REF, rtol=0, atol=bound["qd"])
    if method == "projection":
        # q̈ (up to 5.7e5) and λ at t = 0.03: measured 1.0e-7 and 7e-8 relative to the largest.
        scale_a, scale_l = np.abs(QDD_REF).max(), np.abs(LAM_REF).max()
        np.testing.assert_allclose(traj.qdd[-1], QDD_REF, rtol=0, atol=1e-6 * scale_a)
        np.testing.assert_allclose(traj.multipliers[-1], -LAM_REF, rtol=0, atol=1e-6 * scale_l)
