"""The zoo's differential-drive robot: a chassis on two driven wheels and a passive caster ball,
its wheels' rolling and no-side-slip conditions written as a user writes them, one row redundant.
"""

from __future__ import annotations

import sympy as sp

from pfaff.api import System
from pfaff.core.symbols import coordinates, t
from pfaff.mechanics.attitude import PlanarAngle
from pfaff.models.params import _param


def diffdrive(
    *,
    mass: object = None,
    inertia: object = None,
    offset: object = None,
    wheel_mass: object = None,
    wheel_inertia: object = None,
    wheel_yaw_inertia: object = None,
    radius: object = None,
    half_track: object = None,
    torques: object = None,
    inputs: bool = False,
    redundant: bool = True,
) -> System:
    """A differential-drive robot on the plane: two driven wheels and a passive caster ball.

    Coordinates q = (x, y, ψ, φ_L, φ_R): the axle's midpoint P = (x, y), the heading ψ (forward
    e_f = (cos ψ, sin ψ), left e_l = (−sin ψ, cos ψ)) and the wheels' spin angles (positive
    rolling forward). The chassis (mass ``m_c``, yaw inertia ``I_c`` about its mass centre) has
    its mass centre at P + d e_f; the wheels (mass ``m_w``, spin inertia ``I_w``, inertia ``J_w``
    about a diameter) are centred at P ± b e_l (left +), with radius r. The caster ball is massless
    and only carries weight: it adds no term to the planar model. The torques τ_L, τ_R (motor
    on wheel; the reaction on the chassis acts about the axle and does no work in the plane) are
    the generalized forces of φ_L and φ_R.

    Constraints, velocity of each wheel centre c: ``rolling L``, ``rolling R``: ċ·e_f − r φ̇ = 0;
    ``no side slip L``, ``no side slip R``: ċ·e_l = 0. Both side-slip rows say that P has no
    lateral velocity, −ẋ sin ψ + ẏ cos ψ = 0, so the four rows have rank 3: one is redundant,
    and the redundancy subspace (the null space of Aᵀ) is spanned by (0, 0, 1, −1), equal and
    opposite lateral forces on the wheels. ``equations()`` reports it (a
    :class:`pfaff.RedundancyWarning`) and the multipliers are the minimum-norm ones;
    ``redundant=False`` writes the single independent row ``no side slip`` of the axle's midpoint
    instead.

    With the forward speed v = ẋ cos ψ + ẏ sin ψ and the yaw rate ω = ψ̇ (φ̇_{L,R} = (v ∓ b ω)/r):

        (m_c + 2 m_w + 2 I_w/r²) v̇ − m_c d ω² = (τ_L + τ_R)/r
        I_P ω̇ + m_c d v ω = b (τ_R − τ_L)/r,   I_P = I_c + m_c d² + 2 m_w b² + 2 J_w + 2 I_w b²/r²

    so equal torques τ from rest drive straight with v̇ = 2τ/(r (m_c + 2 m_w + 2 I_w/r²)).

    Parameters
    ----------
    mass, inertia, offset : Expr or float, optional
        Chassis ``m_c``, ``I_c``, ``d`` (default: those symbols).
    wheel_mass, wheel_inertia, wheel_yaw_inertia : Expr or float, optional
        ``m_w``, ``I_w``, ``J_w``.
    radius, half_track : Expr or float, optional
        ``r`` and ``b`` (the track is 2b).
    torques : pair, optional
        τ_L, τ_R (default: symbols ``tau_L``, ``tau_R``).
    inputs : bool, optional
        Declare the torques as inputs (:meth:`pfaff.System.add_input`); they must be names then.
    redundant : bool, optional
        Both wheels' side-slip rows (default), or one ``no side slip`` row for P: three
        independent rows, the same motion.

    Examples
    --------
    >>> import pfaff
    >>> s = pfaff.models.diffdrive()
    >>> s.constraint_rows()[0]
    ('rolling L', 'rolling R', 'no side slip L', 'no side slip R')
    >>> [str(p) for p in s.parameters]
    ['I_c', 'I_w', 'J_w', 'b', 'd', 'm_c', 'm_w', 'r', 'tau_L', 'tau_R']
    """
    m_c, I_c = _param(mass, "m_c", "mass"), _param(inertia, "I_c", "inertia")
    d = _param(offset, "d", "offset")
    m_w = _param(wheel_mass, "m_w", "wheel_mass")
    I_w = _param(wheel_inertia, "I_w", "wheel_inertia")
    J_w = _param(wheel_yaw_inertia, "J_w", "wheel_yaw_inertia")
    r, b = _param(radius, "r", "radius"), _param(half_track, "b", "half_track")
    tau_l, tau_r = (None, None) if torques is None else torques
    tau = [_param(tau_l, "tau_L", "torques"), _param(tau_r, "tau_R", "torques")]
    x, y, psi, phi_l, phi_r = qs = coordinates("x y psi phi_L phi_R")
    s = System(list(qs), name="differential drive")
    if inputs:
        tau = [s.add_input(u) for u in tau]
    ef = sp.Matrix([sp.cos(psi), sp.sin(psi)])
    el = sp.Matrix([-sp.sin(psi), sp.cos(psi)])
    axle = sp.Matrix([x, y])
    s.add_rigid_body(m_c, I_c, list(axle + d * ef), PlanarAngle(psi), name="chassis")
    for side, sign, phi, torque in (("L", 1, phi_l, tau[0]), ("R", -1, phi_r, tau[1])):
        centre = axle + sign * b * el
        s.add_particle(m_w, list(centre), name=f"wheel {side}")
        s.add_kinetic_energy(
            (I_w * phi.diff(t) ** 2 + J_w * psi.diff(t) ** 2) / 2, name=f"spin {side}"
        )
        s.add_generalized_force(phi, torque, name=f"torque {side}")
    for side, sign, phi in (("L", 1, phi_l), ("R", -1, phi_r)):
        v = (axle + sign * b * el).diff(t)
        s.add_velocity_constraint(v.dot(ef) - r * phi.diff(t), name=f"rolling {side}")
    if not redundant:
        s.add_velocity_constraint(axle.diff(t).dot(el), name="no side slip")
        return s
    for side, sign in (("L", 1), ("R", -1)):
        v = (axle + sign * b * el).diff(t)
        s.add_velocity_constraint(v.dot(el), name=f"no side slip {side}")
    return s
