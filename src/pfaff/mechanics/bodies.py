"""Rigid bodies, torques and force elements of the model stage.

A rigid body of mass m, inertia I about its mass centre (body axes), mass centre at r_c(q, t) and
attitude C(q) (an :mod:`pfaff.mechanics.attitude` set) has the kinetic energy

    T = ½ m ṙ_c·ṙ_c + ½ ωᵀ I ω,      ω = B(q) q̇ (body components),

which enters the model as two pieces: a particle (the translation, whose mass matrix is m JᵀJ) and
a kinetic-energy term (the rotation). A quaternion adds its unit-norm constraint. A torque τ on a
body has the generalized forces Q_j = τ_body · ∂ω/∂q̇_j (partial angular velocities); a Rayleigh
function R(q, q̇) has Q_j = −∂R/∂q̇_j.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import BodyInertiaError, ModelError, ModelTypeError
from pfaff.core.symbols import as_expr, t
from pfaff.mechanics.attitude import Attitude, PlanarAngle

TORQUE_FRAMES = ("inertial", "body")
ROTATION_TOL = 1e-9  # CᵀC = I and det C = 1 to this, at a random state


@dataclass(eq=False)
class Body:
    """A rigid body of a :class:`pfaff.System` (made by ``add_rigid_body``).

    Attributes
    ----------
    name : str
    mass : Expr
    inertia : Matrix, shape (3, 3)
        About the mass centre, in body axes.
    position : Matrix, shape (d, 1)
        Inertial components of the mass centre, d = 2 (planar) or 3.
    attitude : Attitude
    dcm : Matrix, shape (3, 3)
        C with r_inertial = C r_body.
    angular_velocity : Matrix, shape (3, 1)
        Body components of ω.

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> x, y, th = pfaff.coordinates("x y theta")
    >>> s = pfaff.System([x, y, th])
    >>> rod = s.add_rigid_body(2, sp.Rational(1, 6), [x, y], pfaff.attitude.PlanarAngle(th))
    >>> rod.name, rod.velocity_of([x + sp.cos(th), y + sp.sin(th)]).T
    ('body0', Matrix([[-sin(theta(t))*Derivative(theta(t), t) + Derivative(x(t), t), cos(theta(t))*Derivative(theta(t), t) + Derivative(y(t), t)]]))
    """

    name: str
    mass: sp.Expr
    inertia: sp.Matrix
    position: sp.Matrix
    attitude: Attitude
    constraint: str | None = field(default=None)

    @property
    def dcm(self) -> sp.Matrix:
        return self.attitude.dcm

    @property
    def angular_velocity(self) -> sp.Matrix:
        return self.attitude.angular_velocity

    @property
    def angular_velocity_inertial(self) -> sp.Matrix:
        """Inertial components of ω, C ω_body, shape (3, 1)."""
        if isinstance(self.attitude, PlanarAngle):
            return self.attitude.angular_velocity
        return self.attitude.dcm * self.attitude.angular_velocity

    @property
    def velocity(self) -> sp.Matrix:
        """Inertial velocity of the mass centre, shape (d, 1)."""
        return self.position.diff(t)

    @property
    def kinetic_energy(self) -> sp.Expr:
        """½ m v·v + ½ ωᵀ I ω."""
        w = self.angular_velocity
        v = self.velocity
        return self.mass * v.dot(v) / 2 + (w.T * self.inertia * w)[0, 0] / 2

    def velocity_of(self, point: object) -> sp.Matrix:
        """Inertial velocity of the body's material point now at ``point``: v_c + ω × (p − r_c).

        Parameters
        ----------
        point : sequence of d Expr
            Inertial components of the point (expressions in q and t), as many as ``position``.

        Returns
        -------
        Matrix, shape (d, 1)
            What a no-slip contact constraint sets to zero.
        """
        d = self.position.rows
        p = _components(point, f"`point` of body `{self.name}`", d)
        rel = list(p - self.position) + [sp.S.Zero] * (3 - d)
        w = self.angular_velocity_inertial
        turn = w.cross(sp.Matrix(rel))
        return sp.Matrix([self.velocity[i] + turn[i] for i in range(d)])


def _components(value: object, what: str, d: int | None = None) -> sp.Matrix:
    if isinstance(value, sp.MatrixBase):
        comps = list(value)
    elif isinstance(value, list | tuple) or hasattr(value, "__array__"):
        comps = list(value.tolist() if hasattr(value, "tolist") else value)
    else:
        raise ModelTypeError(f"{what} must be a list of expressions, got {type(value).__name__}")
    if d is not None and len(comps) != d:
        raise ModelError(f"{what} must have {d} components, got {len(comps)}")
    return sp.Matrix([as_expr(c, f"{what} component {i}") for i, c in enumerate(comps)])


def inertia_matrix(inertia: object, attitude: Attitude, what: str) -> sp.Matrix:
    """The 3×3 inertia from a matrix, three principal moments, or (planar) one scalar; checked
    for symmetry and, where numeric, positive definiteness and the triangle inequality."""
    planar = isinstance(attitude, PlanarAngle)
    if isinstance(inertia, sp.MatrixBase | list | tuple | np.ndarray):
        arr = sp.Matrix(inertia) if not isinstance(inertia, sp.MatrixBase) else inertia
        if arr.shape in ((3, 1), (1, 3)):
            mat = sp.diag(*[as_expr(v, f"{what} principal moment {i}") for i, v in enumerate(arr)])
        elif arr.shape == (3, 3):
            mat = arr.applyfunc(lambda v: as_expr(v, f"{what} entry"))
        else:
            raise ModelError(
                f"{what} must be a 3×3 matrix, three principal moments or (with PlanarAngle) one "
                f"number; got shape {arr.shape}"
            )
    else:
        if not planar:
            raise ModelError(
                f"{what} is one number, which only a PlanarAngle body takes: give three principal "
                "moments or a 3×3 matrix"
            )
        mat = sp.diag(0, 0, as_expr(inertia, what))
    asym = [
        (i, j) for i in range(3) for j in range(i + 1, 3) if sp.expand(mat[i, j] - mat[j, i]) != 0
    ]
    if asym:
        raise BodyInertiaError(
            f"{what} is not symmetric: entries {asym} differ from their transposes"
        )
    if any(
        e.has(t) or e.atoms(sp.Derivative) or e.atoms(sp.core.function.AppliedUndef) for e in mat
    ):
        raise ModelError(f"{what} must be constant (parameters and numbers only)")
    if all(e.is_number for e in mat):
        check_inertia(np.array(mat.tolist(), dtype=float), what, planar)
    return sp.ImmutableMatrix(mat)


def check_inertia(mat: np.ndarray, what: str, planar: bool = False) -> None:
    """Positive definite (planar: I_zz > 0) with principal moments satisfying the triangle
    inequality (equality allowed: thin disks and plates); raise :class:`BodyInertiaError`."""
    if planar and mat[0, 0] == mat[1, 1] == mat[0, 1] == mat[0, 2] == mat[1, 2] == 0:
        if not mat[2, 2] > 0:
            raise BodyInertiaError(f"{what} must be positive, got {mat[2, 2]:g}")
        return
    moments = np.linalg.eigvalsh(mat)
    if not moments[0] > 0:
        raise BodyInertiaError(
            f"{what} is not positive definite: principal moments {np.round(moments, 12).tolist()}"
        )
    a, b, c = moments
    if c > a + b + 1e-12 * c:
        raise BodyInertiaError(
            f"{what} violates the triangle inequality of principal moments: "
            f"{c:g} > {a:g} + {b:g} (no rigid body has these)"
        )


def check_rotation(dcm: sp.Matrix, what: str, seed: int = 20231) -> None:
    """Refuse a C that is not a rotation: CᵀC = I and det C = 1 (to ``ROTATION_TOL``) at a random
    state (coordinates, t and parameters drawn from a fixed seed)."""
    rng = np.random.default_rng(seed)
    funcs = sorted({f for e in dcm for f in e.atoms(AppliedUndef)}, key=str)
    values: dict = {f: sp.Float(rng.uniform(-np.pi, np.pi)) for f in funcs}
    c = dcm.xreplace(values)
    symbols = sorted(set().union(*(e.free_symbols for e in c)), key=str)
    c = c.xreplace({s: sp.Float(rng.uniform(0.5, 1.5)) for s in symbols})
    try:
        num = np.array(c.evalf().tolist(), dtype=float)
    except (TypeError, ValueError) as e:
        raise ModelError(f"{what}: C does not evaluate to numbers at a random state ({e})") from e
    err = max(np.abs(num.T @ num - np.eye(3)).max(), abs(np.linalg.det(num) - 1))
    if not err <= ROTATION_TOL:
        raise ModelError(
            f"{what} is not a rotation matrix: at a random state |CᵀC − I| or |det C − 1| is "
            f"{err:.3g} > {ROTATION_TOL:g}; C must map body to inertial components, r_N = C r_B"
        )


def torque_exprs(body: Body, torque: object, frame: str, what: str) -> tuple[sp.Expr, ...]:
    """(τ_body components, ω_body components) of a torque piece."""
    if frame not in TORQUE_FRAMES:
        raise ModelError(f"`frame` must be one of {', '.join(TORQUE_FRAMES)}; got {frame!r:.40}")
    if isinstance(torque, sp.MatrixBase | list | tuple | np.ndarray):
        tau = _components(torque, what, 3)
    elif isinstance(body.attitude, PlanarAngle):
        tau = sp.Matrix([0, 0, as_expr(torque, what)])
    else:
        raise ModelTypeError(f"{what} must have 3 components (one number only for a planar body)")
    if frame == "inertial":
        tau = body.dcm.T * tau
    return (*tau, *body.angular_velocity)


def between(points: object, what: str) -> tuple[sp.Matrix, sp.Matrix]:
    """The two points of a spring or damper, as matrices of equal length."""
    if not isinstance(points, list | tuple) or len(points) != 2:
        raise ModelTypeError(f"{what}: `between` must be a pair of points (p1, p2)")
    p1 = _components(points[0], f"{what}: first point")
    p2 = _components(points[1], f"{what}: second point", p1.rows)
    return p1, p2
