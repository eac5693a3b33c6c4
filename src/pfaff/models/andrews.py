"""Andrews' squeezing mechanism: the 7-body planar closed-loop benchmark and its published solution.

Seven rigid bodies in the plane, joined by revolute joints into two closed loops, driven by a
constant motor torque on the crank and pulled by a stiff spring; gravity is neglected. It is the
index-3 benchmark of

* E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., Springer (1996),
  Section VII.7 (after G. Giles 1978 and R. Manning 1981): geometry, masses, inertias, spring and
  motor data, the mass matrix M(q), the forces f(q, q̇) and the constraints g(q);
* W. Schiehlen (ed.), *Multibody Systems Handbook*, Springer (1990), the same mechanism;
* the "Test Set for IVP Solvers" (W. M. Lioen, J. J. B. de Swart, CWI Amsterdam; continued by
  F. Mazzia, C. Magherini, University of Bari), problem ``andrews``: the same data, consistent
  initial values with q̈(0) and λ(0), and the reference solution at t = 0.03 computed with PSIDE at
  rtol = atol = 1e-14.

Coordinates, in order: q = (β, Θ, γ, Φ, δ, Ω, ε), the seven joint angles. The test set writes
M q̈ = f(q, q̇) − Gᵀλ; pfaff writes M q̈ = Q + Aᵀλ, so λ_pfaff = −λ_testset.

:func:`andrews_squeezer` builds the model from Hairer's M(q) entries as kinetic energy terms (one
per group of coupled bodies), the spring as the potential ½ c0 (L − l0)², the motor as a generalized
force on β and the six loop-closure constraints; pfaff derives the Coriolis and centrifugal terms.
:data:`ANDREWS` holds the published parameter values, :func:`andrews_state` the consistent initial
state, :func:`andrews_reference` the reference solution at t = 0.03.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from pfaff.api import System
from pfaff.core.symbols import coordinates, t

__all__ = [
    "ANDREWS",
    "ANDREWS_COORDINATES",
    "ANDREWS_T_END",
    "andrews_reference",
    "andrews_squeezer",
    "andrews_state",
]

ANDREWS_COORDINATES = "beta Theta gamma Phi delta Omega epsilon"
"""Names of the seven angles of :func:`andrews_squeezer`, in order."""

ANDREWS = {
    # masses (kg) and moments of inertia about the mass centres (kg m²) of bodies 1 ... 7
    "m1": 0.04325, "m2": 0.00365, "m3": 0.02373, "m4": 0.00706,
    "m5": 0.07050, "m6": 0.00706, "m7": 0.05498,
    "I1": 2.194e-6, "I2": 4.410e-7, "I3": 5.255e-6, "I4": 5.667e-7,
    "I5": 1.169e-5, "I6": 5.667e-7, "I7": 1.912e-5,
    # fixed points A, B, C (m) and the bodies' dimensions (m)
    "xa": -0.06934, "ya": -0.00227, "xb": -0.03635, "yb": 0.03273, "xc": 0.014, "yc": 0.072,
    "d": 28e-3, "da": 115e-4, "e": 2e-2, "ea": 1421e-5, "rr": 7e-3, "ra": 92e-5,
    "ss": 35e-3, "sa": 1874e-5, "sb": 1043e-5, "sc": 18e-3, "sd": 2e-2,
    "ta": 2308e-5, "tb": 916e-5, "u": 4e-2, "ua": 1228e-5, "ub": 449e-5,
    "zf": 2e-2, "zt": 4e-2, "fa": 1421e-5,
    # spring stiffness (N/m) and rest length (m), motor torque (N m)
    "c0": 4530.0, "l0": 7785e-5, "mom": 33e-3,
}  # fmt: skip
"""The published parameter values (Hairer & Wanner VII.7; the test set's ``andrews``)."""

ANDREWS_T_END = 0.03
"""End time of the published reference solution (s)."""

_Q0 = (
    -0.0617138900142764496358948458001, 0.0, 0.455279819163070380255912382449,
    0.222668390165885884674473185609, 0.487364979543842550225598953530,
    -0.222668390165885884674473185609, 1.23054744454982119249735015568,
)  # fmt: skip
_QDD0 = (14222.4439199541138705911625887, -10666.8329399655854029433719415, 0, 0, 0, 0, 0)
_LAM0 = (98.5668703962410896057654982170, -6.12268834425566265503114393122, 0, 0, 0, 0)
_REFERENCE = {
    "q": (
        0.1581077119629904e2, -0.1575637105984298e2, 0.4082224013073101e-1,
        -0.5347301163226948, 0.5244099658805304, 0.5347301163226948, 0.1048080741042263e1,
    ),
    "qd": (
        0.1139920302151208e4, -0.1424379294994111e4, 0.1103291221937134e2,
        0.1929337464421385e2, 0.5735699284790808, -0.1929337464421385e2, 0.3231791658026955,
    ),
    "qdd": (
        -0.2463176316945196e5, 0.5185037701610329e5, 0.3241025686413781e6,
        0.5667493645176213e6, 0.1674362929479361e5, -0.5667493645176222e6,
        0.9826520791458422e4,
    ),
    "lam": (
        0.1991753333731910e3, -0.2975531228015052e2, 0.2306654119098399e2,
        0.3145271365475927e2, 0.2264249232082739e2, 0.1161740700019673e2,
    ),
}  # fmt: skip


def _unit(a: sp.Expr) -> sp.Matrix:
    return sp.Matrix([sp.cos(a), sp.sin(a)])


def _normal(a: sp.Expr) -> sp.Matrix:
    return sp.Matrix([-sp.sin(a), sp.cos(a)])


def andrews_squeezer() -> System:
    """Andrews' squeezing mechanism: 7 angles, 6 holonomic loop-closure constraints.

    Parameters are the symbols named as the keys of :data:`ANDREWS` (``m1`` … ``m7``, ``I1`` …
    ``I7``, ``xa`` … ``yc``, ``d``, ``da``, …, ``c0``, ``l0``, ``mom``). The kinetic energy is
    ½ q̇ᵀ M(q) q̇ with Hairer's M(q), block diagonal in the groups (β, Θ), γ, (Φ, δ), (Ω, ε); the
    spring joins the point D of body 3, B + sd (cos γ, sin γ) − sc (−sin γ, cos γ), to the fixed
    point C. The constraints close the loops at the end F of rod 2 through body 3 (to B) and
    through bodies 4/5 and 6/7 (to A).

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.andrews_squeezer()
    >>> s.n, s.n_constraints, len(s.parameters)
    (7, 6, 42)
    """
    q = coordinates(ANDREWS_COORDINATES)
    be, th, ga, ph, de, om, ep = q
    wb, wt, wg, wp, wd, wo, we = (c.diff(t) for c in q)
    s = {k: sp.Symbol(k) for k in ANDREWS}
    sq = System(list(q), name="Andrews' squeezing mechanism")
    m2, da, rr = s["m2"], s["da"], s["rr"]
    m11 = s["m1"] * s["ra"] ** 2 + m2 * (rr**2 - 2 * da * rr * sp.cos(th) + da**2)
    m11 += s["I1"] + s["I2"]
    m12 = m2 * (da**2 - da * rr * sp.cos(th)) + s["I2"]
    m22 = m2 * da**2 + s["I2"]
    sq.add_kinetic_energy(m11 * wb**2 / 2 + m12 * wb * wt + m22 * wt**2 / 2, name="bodies 1, 2")
    m33 = s["m3"] * (s["sa"] ** 2 + s["sb"] ** 2) + s["I3"]
    sq.add_kinetic_energy(m33 * wg**2 / 2, name="body 3")
    k4, zt, m4 = s["e"] - s["ea"], s["zt"], s["m4"]
    m44 = m4 * k4**2 + s["I4"]
    m45 = m4 * (k4**2 + zt * k4 * sp.sin(ph)) + s["I4"]
    m55 = m4 * (zt**2 + 2 * zt * k4 * sp.sin(ph) + k4**2)
    m55 += s["m5"] * (s["ta"] ** 2 + s["tb"] ** 2) + s["I4"] + s["I5"]
    sq.add_kinetic_energy(m44 * wp**2 / 2 + m45 * wp * wd + m55 * wd**2 / 2, name="bodies 4, 5")
    k6, u, m6 = s["zf"] - s["fa"], s["u"], s["m6"]
    m66 = m6 * k6**2 + s["I6"]
    m67 = m6 * (k6**2 - u * k6 * sp.sin(om)) + s["I6"]
    m77 = m6 * (k6**2 - 2 * u * k6 * sp.sin(om) + u**2)
    m77 += s["m7"] * (s["ua"] ** 2 + s["ub"] ** 2) + s["I6"] + s["I7"]
    sq.add_kinetic_energy(m66 * wo**2 / 2 + m67 * wo * we + m77 * we**2 / 2, name="bodies 6, 7")
    B, C = sp.Matrix([s["xb"], s["yb"]]), sp.Matrix([s["xc"], s["yc"]])
    D = B + s["sd"] * _unit(ga) - s["sc"] * _normal(ga)
    length = sp.sqrt((D - C).dot(D - C))
    sq.add_potential_energy(s["c0"] * (length - s["l0"]) ** 2 / 2, name="spring")
    sq.add_generalized_force(be, s["mom"], name="motor")
    F = rr * _unit(be) - s["d"] * _unit(be + th)
    xa, ya, xb, yb, e, zf = (s[k] for k in ("xa", "ya", "xb", "yb", "e", "zf"))
    closures = {
        "B x": F[0] - s["ss"] * sp.sin(ga) - xb,
        "B y": F[1] + s["ss"] * sp.cos(ga) - yb,
        "A via 4,5 x": F[0] - e * sp.sin(ph + de) - zt * sp.cos(de) - xa,
        "A via 4,5 y": F[1] + e * sp.cos(ph + de) - zt * sp.sin(de) - ya,
        "A via 6,7 x": F[0] - zf * sp.cos(om + ep) - u * sp.sin(ep) - xa,
        "A via 6,7 y": F[1] - zf * sp.sin(om + ep) + u * sp.cos(ep) - ya,
    }
    for name, expr in closures.items():
        sq.add_holonomic_constraint(expr, name=name)
    return sq


def andrews_state() -> tuple[np.ndarray, np.ndarray]:
    """The published consistent initial state (q, q̇) at t = 0: at rest, q̇ = 0.

    Returns
    -------
    q, qd : ndarray, shape (7,)

    Examples
    --------
    >>> q, qd = andrews_state()
    >>> round(float(q[2]), 6), float(qd.max())
    (0.45528, 0.0)
    """
    return np.array(_Q0), np.zeros(7)


def andrews_reference() -> dict[str, np.ndarray | float]:
    """The published solution: at t = 0 and at t = :data:`ANDREWS_T_END`, in pfaff's sign.

    Returns
    -------
    dict
        ``t_end``; ``q``, ``qd``, ``qdd`` (shape (7,)) and ``multipliers`` (shape (6,)) at t_end;
        ``qdd0`` and ``multipliers0`` at t = 0. Multipliers are pfaff's, λ = −λ_testset.
    """
    ref = {k: np.array(v) for k, v in _REFERENCE.items()}
    return {
        "t_end": ANDREWS_T_END,
        "q": ref["q"],
        "qd": ref["qd"],
        "qdd": ref["qdd"],
        "multipliers": -ref["lam"],
        "qdd0": np.array(_QDD0, dtype=float),
        "multipliers0": -np.array(_LAM0, dtype=float),
    }
