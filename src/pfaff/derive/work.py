"""Work accounting: each applied force's generalized force, and whether it does work.

A force F at a point r(q,t) has generalized force Q_j = F · ∂r/∂q_j (partial velocities). Its
virtual power on the admissible motions q̇ = N u (A N = 0, u the independent speeds) is
P = Σ_a (Qᵀ N)_a u_a = Σ_a F · (J N)_a u_a. A force does no work on the constraint manifold when P
vanishes for every u: either the point's admissible velocity J N is zero (no-slip contact) or F is
orthogonal to it (a normal force).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ModelTypeError, PfaffError
from pfaff.core.symbols import as_expr, t
from pfaff.derive.latexlist import WorkList
from pfaff.derive.reduce import tidy
from pfaff.derive.templates import derive
from pfaff.mechanics.system import SystemSpec

WORK_LIMIT = 60  # largest n for the symbolic null space


@dataclass(frozen=True)
class ForceWork:
    """Work accounting of one applied force.

    Attributes
    ----------
    name : str
    force : Matrix, shape (d, 1) or None
        Force components; for a torque its body-axis components (then ``point`` is None and
        ``admissible_point_velocity`` is the body's admissible angular velocity); None for a
        generalized force given directly or a dissipation function.
    point : Matrix, shape (d, 1) or None
        Position of the point the force acts on.
    generalized_force : Matrix, shape (n, 1)
        Q_j = F · ∂r/∂q_j.
    admissible_point_velocity : Matrix, shape (d, k) or None
        Velocity of the point per unit independent speed on the constraint manifold (J N).
    virtual_power : Expr
        Qᵀ N u with u the independent speeds: the force's power on any admissible motion.
    independent_speeds : tuple of Expr, length k
    """

    name: str
    force: sp.Matrix | None
    point: sp.Matrix | None
    generalized_force: sp.Matrix
    admissible_point_velocity: sp.Matrix | None
    virtual_power: sp.Expr
    independent_speeds: tuple

    def does_work(self, at: dict | None = None) -> bool | None:
        """Whether the force does work on admissible motions, optionally at a configuration.

        Parameters
        ----------
        at : dict, optional
            Substitutions, e.g. ``{theta3: sp.pi}`` for the particle at the contact point.

        Returns
        -------
        bool or None
            False when the virtual power vanishes identically, True when it does not, None when
            SymPy cannot decide.
        """
        p = self.virtual_power
        if at is not None and not isinstance(at, dict):
            raise ModelTypeError(f"`at` must be a dict of coordinate -> value, got {at!r:.80}")
        if at:
            at = {_key(k): as_expr(v, f"`at[{k}]`") for k, v in at.items()}
            hold = {u: sp.Dummy(f"u{i}") for i, u in enumerate(self.independent_speeds)}
            p = p.xreplace(hold).subs(at).xreplace({v: k for k, v in hold.items()})
        p = tidy(p)
        if p == 0:
            return False
        z = p.equals(0)
        if z is not None:
            return not z
        return True if _numerically_nonzero(p) else None


def _key(k: object) -> sp.Basic:
    """A substitution key of ``does_work(at=...)``: a SymPy object, never a string to parse."""
    if not isinstance(k, sp.Basic):
        raise ModelTypeError(f"`at` keys must be coordinates or symbols, got {k!r:.80}")
    return k


def _numerically_nonzero(e: sp.Expr, tries: int = 3) -> bool:
    """True when ``e`` is clearly nonzero at a random point (a witness that it is not 0)."""
    import random

    rng = random.Random(7)
    atoms = list(e.atoms(sp.Derivative)) + list(e.atoms(AppliedUndef)) + list(e.free_symbols)
    for _ in range(tries):
        rule = {a: sp.Float(rng.uniform(0.3, 1.7)) for a in atoms}
        val = e.xreplace(rule).evalf(30)
        if val.is_number and abs(complex(val)) > 1e-12:
            return True
    return False


def _null_space(A: sp.Matrix, coords: tuple, independent: list | None) -> tuple[sp.Matrix, tuple]:
    n = len(coords)
    if A.rows == 0:
        return sp.eye(n), tuple(q.diff(t) for q in coords)
    if independent is None:
        basis = A.nullspace(simplify=True)
        N = sp.Matrix.hstack(*basis) if basis else sp.zeros(n, 0)
        free = [
            next(
                i
                for i in range(n)
                if N[i, a] == 1 and all(N[i, c] == 0 for c in range(N.cols) if c != a)
            )
            for a in range(N.cols)
        ]
        return N, tuple(coords[i].diff(t) for i in free)
    ind = [coords.index(q) for q in independent]
    dep = [i for i in range(n) if i not in ind]
    Nd = A[:, dep].LUsolve(-A[:, ind]).applyfunc(sp.cancel)
    N = sp.zeros(n, len(ind))
    for a, i in enumerate(ind):
        N[i, a] = 1
    for r, i in enumerate(dep):
        N[i, :] = Nd[r, :]
    return N, tuple(coords[i].diff(t) for i in ind)


def work(system: SystemSpec, independent: list | None = None) -> WorkList:
    """Generalized force and virtual power of every applied force of ``system``.

    Parameters
    ----------
    system : SystemSpec
        At most 60 coordinates (the admissible velocities come from a symbolic null space of A).
    independent : sequence of Function, optional
        Coordinates whose speeds parametrize the admissible motions (default: SymPy's null space).

    Returns
    -------
    WorkList
        One :class:`ForceWork` per applied force, in the order they were added: a ``list``
        that Jupyter renders as LaTeX (:class:`pfaff.derive.latexlist.WorkList`).

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> x, th = pfaff.coordinates("x theta")
    >>> r, f = sp.symbols("r f")
    >>> s = pfaff.System([x, th]); s.add_particle(1, [x, 0])
    >>> s.add_holonomic_constraint(x - r * th, name="no slip")
    >>> contact = [x + r * sp.sin(th + sp.pi), r * sp.cos(th + sp.pi)]  # material point at the floor
    >>> s.add_force([f, 0], at=contact, name="friction")
    >>> w = s.work([th])[0]
    >>> w.does_work(at={th: 0})
    False
    """
    if system.n > WORK_LIMIT:
        raise PfaffError(
            f"symbolic work accounting is for systems of up to {WORK_LIMIT} coordinates "
            f"(this one has {system.n})"
        )
    eom = derive(system)
    coords = eom.coordinates
    N, speeds = _null_space(sp.Matrix(eom.constraint_matrix), coords, independent)
    u = sp.Matrix(speeds)
    out = WorkList()
    for p in system.pieces:
        if p.kind not in ("force", "genforce", "torque", "dissipation"):
            continue
        if p.kind == "force":
            F = sp.Matrix(p.exprs[: p.dim])
            r = sp.Matrix(p.exprs[p.dim :])
            J = r.jacobian(sp.Matrix(coords))
            Q = (J.T * F).applyfunc(sp.expand)
            JN = (J * N).applyfunc(tidy)
        elif p.kind == "torque":  # τ (body axes) and the partial angular velocities ∂ω/∂q̇
            F, r = sp.Matrix(p.exprs[:3]), None
            Jw = sp.Matrix(p.exprs[3:]).jacobian(sp.Matrix([q.diff(t) for q in coords]))
            Q = (Jw.T * F).applyfunc(sp.expand)
            JN = (Jw * N).applyfunc(tidy)
        elif p.kind == "dissipation":  # Q = −∂R/∂q̇
            F = r = JN = None
            Q = sp.Matrix([-p.exprs[0].diff(q.diff(t)) for q in coords])
        else:
            F = r = JN = None
            Q = sp.zeros(len(coords), 1)
            Q[p.coords[p.dim], 0] = p.exprs[0]
        power = tidy(((Q.T * N) * u)[0]) if N.cols else sp.S.Zero
        out.append(ForceWork(p.name, F, r, Q, JN, power, speeds))
    return out
