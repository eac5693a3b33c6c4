"""A :class:`pfaff.System` from a model built with :mod:`sympy.physics.mechanics`.

:func:`from_sympy` reads a ``LagrangesMethod``, a ``KanesMethod`` or a mechanics ``System`` and
rebuilds the same mechanics as pfaff pieces, all in the coordinates q and their rates q̇:

* ``LagrangesMethod``: the Lagrangian L (its q̇-free part as the potential energy −L|q̇=0, the
  rest as a kinetic energy term), the ``forcelist`` as generalized forces Q_j = F · ∂v/∂q̇_j
  (points) and τ · ∂ω/∂q̇_j (frames), ``hol_coneqs`` as holonomic constraints and
  ``nonhol_coneqs`` as velocity constraints.
* ``KanesMethod`` and ``System``: the kinematic differential equations solved for the speeds,
  u = u(q, q̇, t), replace every u; the kinetic energy is Σ body.kinetic_energy(N); the loads are
  generalized forces as above; configuration constraints are holonomic, velocity constraints
  (in u) are velocity constraints in q̇, except those that only restate the derivative of a
  configuration constraint (Kane needs them for its dependent speeds; pfaff would count them
  twice).

A body's ``potential_energy`` is ignored for ``KanesMethod`` and ``System`` as Kane's method
ignores it (gravity enters as loads); in ``LagrangesMethod`` it counts only through the
Lagrangian the user gave.

Multiplier sign: pfaff writes M q̈ + h = Q + Aᵀλ with A = ∂f/∂q, so Aᵀλ is the constraint force.
For a ``LagrangesMethod`` the rows are the same (holonomic first, in SymPy's order), and
λ_pfaff = +λ from solving SymPy's ``mass_matrix_full``/``forcing_full`` and = −λ of SymPy's
``eom`` and ``solve_multipliers()`` (SymPy stores −A as ``lam_coeffs``, sympy#30215; see
``tests/derive/test_sympy_agreement.py``). Kane's method has no multipliers.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
import sympy as sp

from pfaff.api.system import System
from pfaff.core.errors import ModelError, ModelTypeError
from pfaff.core.keywords import checked_keywords
from pfaff.core.symbols import t

if TYPE_CHECKING:
    from sympy.physics import mechanics as me


@checked_keywords
def from_sympy(obj: object, parameters: Mapping | Sequence | None = None) -> System:
    """Build a :class:`pfaff.System` equal to a SymPy mechanics model.

    Parameters
    ----------
    obj : LagrangesMethod, KanesMethod or sympy.physics.mechanics.System
        The model; a ``KanesMethod`` needs its bodies and loads (given to the constructor or
        to ``kanes_equations``). Its equations need not have been formed.
    parameters : dict or sequence of Symbol, optional
        A dict fixes symbols for good: its values (keyed by Symbol or name) are substituted into
        every expression. A sequence declares the parameters: a free symbol of the model outside
        it is refused. Either way the remaining symbols are the System's ``parameters``, whose
        values :meth:`EquationsOfMotion.compile` takes.

    Returns
    -------
    System
        Coordinates ``obj.q`` (SymPy's own dynamicsymbols, in SymPy's order).

    Raises
    ------
    ModelTypeError
        For any other object.
    ModelError
        For what cannot be mapped (auxiliary speeds, kinematic equations that do not determine
        the speeds, loads on something other than a point or a frame, a velocity SymPy cannot
        give or one in functions of time other than q and its speeds, an undeclared parameter, a parameter value that is not a number or expression).

    Notes
    -----
    Speeds u that are not the rates q̇ are replaced by u(q, q̇, t), the kinematic differential
    equations k_ku u + k_kq̇ q̇ + f_k = 0 solved for u (they must be linear in u and q̇, one per
    speed, with k_ku invertible). SymPy's joints all have u = q̇.

    Multiplier sign: pfaff's equations are M q̈ + h = Q + Aᵀλ, A = ∂f/∂q for the holonomic rows
    (∂g/∂q̇ for the velocity rows), in the order of SymPy's ``holonomic_constraints`` then
    ``nonholonomic_constraints`` (``hol_coneqs`` then ``nonhol_coneqs``). Against a
    ``LagrangesMethod`` with the same constraints, λ_pfaff = +λ solved from its
    ``mass_matrix_full`` / ``forcing_full`` and −λ of its ``eom`` and of
    ``solve_multipliers()``: SymPy stores −A as ``lam_coeffs`` (sympy#30215).

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> from sympy.physics.mechanics import LagrangesMethod, dynamicsymbols
    >>> q = dynamicsymbols("q"); m, k = sp.symbols("m k")
    >>> lm = LagrangesMethod(m * q.diff(pfaff.t) ** 2 / 2 - k * q**2 / 2, [q])
    >>> pfaff.from_sympy(lm).equations().forcing
    Matrix([[-k*q(t)]])
    """
    from sympy.physics import mechanics as me  # loaded already where obj was made

    if isinstance(obj, me.LagrangesMethod):
        system = _from_lagrange(obj)
    elif isinstance(obj, me.KanesMethod):
        system = _from_kane(obj)
    elif isinstance(obj, me.System):
        system = _from_system(obj)
    else:
        raise ModelTypeError(
            "`obj` must be a sympy.physics.mechanics LagrangesMethod, KanesMethod or System, "
            f"got {type(obj).__name__}"
        )
    return _with_parameters(system, parameters)


# --------------------------------------------------------------------------- the three sources
def _from_lagrange(lm: me.LagrangesMethod) -> _Pieces:
    q = list(lm.q)
    qd = [c.diff(t) for c in q]
    L = sp.sympify(lm._L[0])
    L0 = L.xreplace(dict.fromkeys(qd, 0))
    pieces = _Pieces(q, name="LagrangesMethod")
    pieces.kinetic = L - L0
    pieces.potential = -L0
    if lm.forcelist:
        if lm.inertial is None:
            raise ModelError("LagrangesMethod has a `forcelist` but no inertial `frame`")
        pieces.genforces = _generalized_forces(lm.forcelist, lm.inertial, qd, {})
    pieces.holonomic = list(lm._hol_coneqs)
    n_hol = len(pieces.holonomic)
    pieces.velocity = list(lm.coneqs[n_hol:])
    return pieces


def _from_kane(km: me.KanesMethod) -> _Pieces:
    if km._uaux:
        raise ModelError(f"KanesMethod: auxiliary speeds {list(km._uaux)} cannot be mapped")
    if km._qdot_u_map is None:
        raise ModelError("KanesMethod: no kinematic differential equations `kd_eqs`")
    kdes = list(km._k_ku_implicit * km.u + km._k_kqdot_implicit * km._qdot + km._f_k_implicit)
    f_nh = list(km._k_nh * km.u + km._f_nh) if km._k_nh else []
    return _from_kinematics(
        "KanesMethod", km.q, km.u, kdes, km._f_h, f_nh, km.bodies, km.loads, km._inertial
    )


def _from_system(s: me.System) -> _Pieces:
    if s.u_aux:
        raise ModelError(f"System: auxiliary speeds {list(s.u_aux)} cannot be mapped")
    loads = list(s.loads) + [ld for act in s.actuators for ld in act.to_loads()]
    return _from_kinematics(
        "System",
        s.q,
        s.u,
        list(s.kdes),
        list(s.holonomic_constraints),
        list(s.nonholonomic_constraints),
        s.bodies,
        loads,
        s.frame,
    )


def _from_kinematics(name, q, u, kdes, f_h, f_nh, bodies, loads, frame) -> _Pieces:
    q, u = list(q), list(u)
    qd = [c.diff(t) for c in q]
    if not q:
        raise ModelError(f"{name}: no generalized coordinates")
    if not bodies:
        raise ModelError(f"{name}: no bodies (give them to the constructor or kanes_equations)")
    u_of_qd = _speeds(name, kdes, q, u, qd)
    pieces = _Pieces(q, name=name)
    pieces.kinetic = sum((_kinetic_energy(b, frame) for b in bodies), sp.S.Zero).xreplace(u_of_qd)
    pieces.genforces = _generalized_forces(loads or [], frame, qd, u_of_qd)
    pieces.holonomic = list(f_h)
    velocity = [sp.sympify(g).xreplace(u_of_qd) for g in f_nh]
    pieces.velocity = _new_rows(pieces.holonomic, velocity, q, qd)
    return pieces


# --------------------------------------------------------------------------- the mappings
class _Pieces:
    """What a SymPy model becomes, before it is a System: all in q, q̇ and t."""

    def __init__(self, q: list, *, name: str) -> None:
        self.q, self.name = q, name
        self.kinetic = sp.S.Zero
        self.potential = sp.S.Zero
        self.genforces: list = [sp.S.Zero] * len(q)
        self.holonomic: list = []
        self.velocity: list = []

    def exprs(self) -> list:
        return [self.kinetic, self.potential, *self.genforces, *self.holonomic, *self.velocity]

    def build(self, subs: dict) -> System:
        def x(e):
            return sp.sympify(e).xreplace(subs) if subs else sp.sympify(e)

        s = System(self.q, name=self.name)
        if x(self.kinetic) == 0:
            raise ModelError(f"{self.name}: the kinetic energy is zero")
        s.add_kinetic_energy(x(self.kinetic), name="T")
        if x(self.potential) != 0:
            s.add_potential_energy(x(self.potential), name="V")
        for c, Q in zip(self.q, self.genforces, strict=True):
            if x(Q) != 0:
                s.add_generalized_force(c, x(Q), name=f"Q_{c.func.__name__}")
        for i, f in enumerate(self.holonomic):
            s.add_holonomic_constraint(x(f), name=f"holonomic{i + 1}")
        for i, g in enumerate(self.velocity):
            s.add_velocity_constraint(x(g), name=f"nonholonomic{i + 1}")
        return s


def _speeds(name: str, kdes: list, q: list, u: list, qd: list) -> dict:
    """The speeds in terms of q̇ from k_ku u + k_kq̇ q̇ + f_k = 0 (linear in u and q̇)."""
    if len(kdes) != len(u):
        raise ModelError(
            f"{name}: {len(kdes)} kinematic differential equations for {len(u)} speeds; "
            "the speeds must be determined by q and q̇"
        )
    K = sp.Matrix(kdes)
    k_ku = K.jacobian(u)
    rest = K.xreplace(dict.fromkeys(u, 0))
    if k_ku.has(*u, *qd) or rest.jacobian(qd).has(*u, *qd):
        raise ModelError(f"{name}: the kinematic differential equations are not linear in u, q̇")
    if k_ku.det() == 0:
        raise ModelError(f"{name}: the kinematic differential equations do not determine u")
    return dict(zip(u, list(k_ku.LUsolve(-rest)), strict=True))


def _generalized_forces(loads, frame, qd: list, u_of_qd: dict) -> list:
    """Q_j = Σ F · ∂v_P/∂q̇_j + Σ τ · ∂ω_B/∂q̇_j, every u replaced by u(q, q̇)."""
    from sympy.physics import mechanics as me

    Q = [sp.S.Zero] * len(qd)
    for load in loads:
        try:
            where, vec = load
        except (TypeError, ValueError):
            raise ModelError(
                f"a load must be (Point or ReferenceFrame, Vector), got {load!r}"
            ) from None
        if isinstance(where, me.Point):
            v = _sympy_kinematics(f"the load on point `{where}`", where.vel, frame)
        elif isinstance(where, me.ReferenceFrame):
            v = _sympy_kinematics(f"the load on frame `{where}`", where.ang_vel_in, frame)
        else:
            raise ModelError(
                f"a load acts on a {type(where).__name__}; only points and frames are mapped"
            )
        if not isinstance(vec, me.Vector):
            raise ModelError(f"the load on {where} is not a Vector: {vec!r}")
        v = v.xreplace(u_of_qd) if u_of_qd else v
        _in_rates(where, v, frame, qd)
        vec = vec.xreplace(u_of_qd) if u_of_qd and vec != 0 else vec
        (partials,) = me.partial_velocity([v], qd, frame)
        for j, pv in enumerate(partials):
            Q[j] += vec.dot(pv) if vec != 0 and pv != 0 else sp.S.Zero
    return Q


def _in_rates(where, v, frame, qd: list) -> None:
    """Refuse a velocity with a function of time other than q, q̇: its partial velocities in q̇
    would miss those terms (a load would be dropped in silence)."""
    from sympy.physics import mechanics as me

    q = [r.expr for r in qd]  # q̇ are Derivative(q, t)
    stray = me.find_dynamicsymbols(v, exclude=[*q, *qd], reference_frame=frame)
    if stray:
        names = ", ".join(sorted(str(s) for s in stray))
        raise ModelError(
            f"the load on `{where}`: its velocity in `{frame}` depends on {names}, which is not a "
            "coordinate or a coordinate's rate (write a LagrangesMethod's velocities in q̇; give "
            "a KanesMethod or System every speed and its kinematic differential equation)"
        )


def _kinetic_energy(body, frame) -> sp.Expr:
    return _sympy_kinematics(f"body `{body}`", body.kinetic_energy, frame)


def _sympy_kinematics(what: str, method, frame):
    """``method(frame)``, a SymPy velocity look-up; its ValueError (no velocity defined in
    ``frame``) as a ModelError naming ``what``."""
    try:
        return method(frame)
    except ValueError as exc:
        why = " ".join(str(exc).split())
        raise ModelError(f"{what}: SymPy cannot give its velocity ({why})") from None


def _new_rows(holonomic: list, velocity: list, q: list, qd: list) -> list:
    """The velocity rows that add to the rank of [∂f/∂q, ∂f/∂t] at two random states.

    Kane's method restates each configuration constraint as a velocity constraint for its
    dependent speeds; pfaff differentiates the holonomic constraint itself.
    """
    if not holonomic or not velocity:
        return velocity
    rng = np.random.default_rng(12345)
    rows = [sp.Matrix([sp.sympify(f).diff(t)]).jacobian(qd) for f in holonomic]
    rows = [
        r.row_join(sp.Matrix([sp.sympify(f).diff(t)]).xreplace(dict.fromkeys(qd, 0)))
        for r, f in zip(rows, holonomic, strict=True)
    ]
    vrows = [
        sp.Matrix([g]).jacobian(qd).row_join(sp.Matrix([g]).xreplace(dict.fromkeys(qd, 0)))
        for g in velocity
    ]
    free = sorted(set().union(*(r.free_symbols for r in rows + vrows)) - {t}, key=str)
    points = [
        {
            **dict(zip(q, rng.uniform(-1, 1, len(q)), strict=True)),
            t: rng.uniform(0, 1),
            **{s: rng.uniform(0.5, 1.5) for s in free},
        }
        for _ in range(2)
    ]

    def num(r, p):
        return np.array(r.xreplace(p).evalf(), dtype=float)

    kept, stacks = [], [np.vstack([num(r, p) for r in rows]) for p in points]
    for g, vr in zip(velocity, vrows, strict=True):
        new = [np.vstack([s, num(vr, p)]) for s, p in zip(stacks, points, strict=True)]
        if all(
            np.linalg.matrix_rank(n) > np.linalg.matrix_rank(s)
            for n, s in zip(new, stacks, strict=True)
        ):
            kept.append(g)
            stacks = new
    return kept


def _value(key: object, value: object) -> sp.Expr:
    """A fixed parameter's value: a real number or a SymPy expression, never a string."""
    if isinstance(value, sp.Expr):
        return value
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        if not np.isfinite(value):
            raise ModelError(f"`parameters`: the value of {key!r} is not finite: {value!r}")
        return sp.Float(value) if isinstance(value, (float, np.floating)) else sp.Integer(value)
    raise ModelTypeError(
        f"`parameters`: the value of {key!r} must be a real number or a SymPy expression, "
        f"got {type(value).__name__}"
    )


def _with_parameters(pieces: _Pieces, parameters: Mapping | Sequence | None) -> System:
    free = set().union(*(sp.sympify(e).free_symbols for e in pieces.exprs())) - {t}
    subs: dict = {}
    if isinstance(parameters, Mapping):
        by_name = {s.name: s for s in free}
        for key, value in parameters.items():
            sym = by_name.get(key) if isinstance(key, str) else key
            if sym not in free:
                raise ModelError(f"`parameters`: {key!r} is not a symbol of the model")
            subs[sym] = _value(key, value)
    elif parameters is not None:
        if isinstance(parameters, str | bytes) or not isinstance(parameters, Sequence | set):
            raise ModelTypeError(
                "`parameters` must be a mapping of symbols or names to values, or a list of "
                f"names, got {type(parameters).__name__} {parameters!r:.80}"
            )
        declared = {p if isinstance(p, str) else getattr(p, "name", p) for p in parameters}
        stray = sorted((s for s in free if s.name not in declared), key=str)
        if stray:
            raise ModelError(
                f"`parameters`: the model has symbols outside the declared parameters: {stray}"
            )
    return pieces.build(subs)
