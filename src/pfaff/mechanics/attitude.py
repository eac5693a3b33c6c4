"""Attitude coordinates of a rigid body: Euler angles, Euler parameters, MRPs, a planar angle, or
any rotation matrix of the system's coordinates (:class:`Rotation`).

Each set maps its coordinates q(t) to the direction cosine matrix C with ``r_inertial = C r_body``
and to the body components of the angular velocity ω, linear in q̇, such that

    Ċ = C [ω×],     [ω×] = [[0, -ω3, ω2], [ω3, 0, -ω1], [-ω2, ω1, 0]].

The symbolic forms (``dcm``, ``angular_velocity``, ``constraint``, ``singularity``) are for building
models; the numeric methods (``from_dcm``, ``rates``, :func:`dcm_from`) are for initial states and
post-processing.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np
import sympy as sp
from numpy.typing import ArrayLike, NDArray

from pfaff.core.errors import ModelError, ModelTypeError, StateError
from pfaff.core.symbols import is_coordinate_like, t

__all__ = [
    "MRP", "Attitude", "EulerAngles", "PlanarAngle", "Quaternion", "Rotation", "dcm_from",
]  # fmt: skip

SEQUENCES = ("121", "123", "131", "132", "212", "213", "231", "232", "312", "313", "321", "323")
TIDY_OPS = 600  # a Rotation's ω entries with more operations are left unsimplified
TIDY_ANGLES = 2  # nor do Fu's rules see entries of more angles (seconds each, for nothing)
SINGULAR_TOL = 1e-10  # |singularity| below this: the kinematic matrix is treated as singular


def _cross(v: sp.Matrix) -> sp.Matrix:
    """[v×], the matrix of the cross product v × ·."""
    return sp.Matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def _rotation(axis: int, angle: sp.Expr) -> sp.Matrix:
    """Rotation by ``angle`` about the body axis ``axis`` (0, 1, 2): columns are the new axes."""
    e = sp.Matrix([int(i == axis) for i in range(3)])
    return sp.cos(angle) * sp.eye(3) + (1 - sp.cos(angle)) * e * e.T + sp.sin(angle) * _cross(e)


def _rotation_np(axis: int, angle: float) -> NDArray[np.float64]:
    c, s = np.cos(angle), np.sin(angle)
    m, n = (axis + 1) % 3, (axis + 2) % 3
    r = np.eye(3)
    r[m, m], r[m, n], r[n, m], r[n, n] = c, -s, s, c
    return r


def _atan2(y: float, x: float) -> float:
    """atan2 in (-π, π] (NumPy's gives -π for y = -0.0)."""
    a = float(np.arctan2(y, x))
    return np.pi if a == -np.pi else a


def _angle_about(r: NDArray[np.float64], axis: int) -> float:
    """The angle of a rotation ``r`` about ``axis``: R e_m = cos a e_m + sin a e_n (m, n cyclic)."""
    m, n = (axis + 1) % 3, (axis + 2) % 3
    return _atan2(r[n, m], r[m, m])


def _quaternion_from_dcm(r: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit β (4,) with β0 ≥ 0 of a rotation matrix (Shepperd's method: the largest square first)."""
    tr = np.trace(r)
    squares = np.array([1 + tr, *(1 + 2 * np.diag(r) - tr)])  # 4 β_m²
    m = int(np.argmax(squares))
    beta = np.empty(4)
    beta[m] = 0.5 * np.sqrt(squares[m])
    sym = {(1, 2): r[0, 1] + r[1, 0], (1, 3): r[0, 2] + r[2, 0], (2, 3): r[1, 2] + r[2, 1]}
    skew = {1: r[2, 1] - r[1, 2], 2: r[0, 2] - r[2, 0], 3: r[1, 0] - r[0, 1]}  # 4 β0 β_n
    for n in range(4):
        if n != m:
            prod = skew[n or m] if 0 in (m, n) else sym[(min(m, n), max(m, n))]
            beta[n] = prod / (4 * beta[m])
    beta /= np.linalg.norm(beta)
    return (-beta if beta[0] < 0 else beta) + 0.0  # no -0.0


class Attitude:
    """Base of the attitude sets: coordinates, ``dcm``, ``angular_velocity`` and numeric helpers.

    Attributes
    ----------
    coordinates : tuple of Function
    rates_symbols : tuple of Derivative
        q̇, the rates ``angular_velocity`` is linear in.
    dcm : Matrix, shape (3, 3)
        C with r_inertial = C r_body.
    angular_velocity : Matrix, shape (3, 1)
        Body components of ω, with Ċ = C [ω×].
    kind : str
    constraint, singularity : Expr or None
    """

    kind: str = ""
    size: int = 0
    constraint: sp.Expr | None = None
    singularity: sp.Expr | None = None
    dcm: sp.Matrix
    angular_velocity: sp.Matrix

    def __init__(self, coords: object, what: str) -> None:
        self.coordinates: tuple[sp.Function, ...] = self._validate(coords, what)
        self.rates_symbols = tuple(sp.Derivative(q, t) for q in self.coordinates)

    def _validate(self, coords: object, what: str) -> tuple[sp.Function, ...]:
        name, n = type(self).__name__, self.size
        if isinstance(coords, sp.Basic) and n == 1:
            coords = (coords,)
        if isinstance(coords, str | sp.Basic) or not isinstance(coords, Sequence):
            raise ModelTypeError(
                f"`{what}` must be a sequence of {n} coordinates made with pfaff.coordinates, "
                f"got {type(coords).__name__} {coords!r}"
            )
        seq = tuple(coords)
        problems = []
        if len(seq) != n:
            problems.append(f"{name} needs {n} coordinate{'s' * (n > 1)}, got {len(seq)}")
        bad = [c for c in seq if not is_coordinate_like(c)]
        problems += [f"{c!r} is not a coordinate (a function of t alone)" for c in bad]
        dup = sorted({str(c) for c in seq if not bad and seq.count(c) > 1})
        if dup:
            problems.append(f"{name} repeats the coordinate {', '.join(dup)}")
        if problems:
            error = ModelTypeError if bad else ModelError
            raise error(f"`{what}`: " + "; ".join(problems))
        return seq

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.coordinates})"

    @cached_property
    def _numeric(self) -> tuple:
        """Lambdified (C(q), B(q), singularity(q)) with ω = B(q) q̇."""
        xs = sp.symbols(f"_x0:{self.size}", real=True)
        to_x = dict(zip(self.coordinates, xs, strict=True))
        kin = self.angular_velocity.jacobian(self.rates_symbols).xreplace(to_x)
        sing = self.singularity.xreplace(to_x) if self.singularity is not None else sp.Integer(1)
        return tuple(
            sp.lambdify([xs], e, modules="numpy") for e in (self.dcm.xreplace(to_x), kin, sing)
        )

    def _values(self, values: ArrayLike, what: str = "values") -> NDArray[np.float64]:
        v = np.atleast_1d(np.asarray(values, dtype=float))
        if v.shape != (self.size,) or not np.all(np.isfinite(v)):
            raise StateError(
                f"`{what}` of {type(self).__name__} must be {self.size} finite numbers, got "
                f"shape {v.shape}: {v}"
            )
        return v

    @staticmethod
    def _omega(omega_body: ArrayLike) -> NDArray[np.float64]:
        w = np.asarray(omega_body, dtype=float)
        if w.shape != (3,) or not np.all(np.isfinite(w)):
            raise StateError(f"`omega_body` must be 3 finite numbers, got shape {w.shape}: {w}")
        return w

    @staticmethod
    def _rotation_matrix(dcm: ArrayLike) -> NDArray[np.float64]:
        c = np.asarray(dcm, dtype=float)
        if c.shape != (3, 3) or not np.all(np.isfinite(c)):
            raise StateError(f"`dcm` must be a finite 3×3 array, got shape {c.shape}")
        if np.abs(c.T @ c - np.eye(3)).max() > 1e-6 or np.linalg.det(c) < 0:
            raise StateError(f"`dcm` is not a rotation matrix (orthonormal, det +1):\n{c}")
        return c

    def from_dcm(self, dcm: ArrayLike) -> NDArray[np.float64]:
        """Coordinate values of the rotation matrix ``dcm`` (3, 3), in their principal range."""
        raise NotImplementedError

    def rates(self, values: ArrayLike, omega_body: ArrayLike) -> NDArray[np.float64]:
        """Coordinate rates q̇ at ``values`` giving the body angular velocity ``omega_body`` (3,)."""
        raise NotImplementedError


class EulerAngles(Attitude):
    """Body-fixed (intrinsic) Euler angles (a, b, c) of a rotation sequence "ijk".

    C = R_i(a) R_j(b) R_k(c), the body turned by a about its axis i, then by b about its (new)
    axis j, then by c about its axis k; ω = R_k(c)ᵀ (R_j(b)ᵀ ȧ e_i + ḃ e_j) + ċ e_k. The kinematic
    matrix is singular (gimbal lock) where ``singularity`` vanishes: cos b for the asymmetric
    sequences (i, j, k distinct; b in [-π/2, π/2]), sin b for the symmetric ones (i = k; b in
    [0, π]).

    Parameters
    ----------
    angles : sequence of 3 coordinates
        The angles in the order of the rotations.
    sequence : str
        One of the 12 sequences "121", "123", …, "323"; "321" is yaw, pitch, roll.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> psi, theta, phi = pfaff.coordinates("psi theta phi")
    >>> e = EulerAngles((psi, theta, phi), "321")
    >>> e.singularity
    cos(theta(t))
    >>> e.angular_velocity[0]
    -sin(theta(t))*Derivative(psi(t), t) + Derivative(phi(t), t)
    >>> e.from_dcm(dcm_from(e, [0.1, 0.2, 0.3])).round(12)
    array([0.1, 0.2, 0.3])
    """

    kind = "euler"
    size = 3

    def __init__(self, angles: Sequence[sp.Function], sequence: str = "321") -> None:
        seq = str(sequence) if isinstance(sequence, int) else sequence
        if seq not in SEQUENCES:
            raise ModelError(
                f"`sequence` must be one of the body-fixed sequences {', '.join(SEQUENCES)}, "
                f"got {sequence!r}"
            )
        super().__init__(angles, "angles")
        self.sequence: str = seq
        self._axes = tuple(int(ch) - 1 for ch in seq)
        i, j, k = self._axes
        a, b, c = self.coordinates
        ad, bd, cd = self.rates_symbols
        self.dcm = _rotation(i, a) * _rotation(j, b) * _rotation(k, c)
        e = [sp.Matrix([int(n == m) for n in range(3)]) for m in range(3)]
        rk_t = _rotation(k, c).T
        self.angular_velocity = rk_t * (_rotation(j, b).T * e[i] * ad + e[j] * bd) + e[k] * cd
        self.singularity = sp.sin(b) if i == k else sp.cos(b)

    def __repr__(self) -> str:
        return f"EulerAngles({self.coordinates}, sequence={self.sequence!r})"

    def from_dcm(self, dcm: ArrayLike) -> NDArray[np.float64]:
        """Angles (3,) of ``dcm``: b in [0, π] (symmetric) or [-π/2, π/2], a and c in (-π, π].

        At gimbal lock only a ± c is defined; then c = 0.
        """
        r = self._rotation_matrix(dcm)
        i, j, k = self._axes
        eps = 1.0 if (j - i) % 3 == 1 else -1.0  # sign of the permutation (i, j, third axis)
        if i == k:
            ell = 3 - i - j
            s = np.hypot(r[i, j], r[i, ell])
            b, (y, x) = np.arctan2(s, r[i, i]), (r[i, j], eps * r[i, ell])
        else:
            s = np.hypot(r[i, i], r[i, j])
            b, (y, x) = np.arctan2(eps * r[i, k], s), (-eps * r[i, j], r[i, i])
        c = _atan2(y, x) if s > 1e-12 else 0.0
        a = _angle_about(r @ _rotation_np(k, c).T @ _rotation_np(j, b).T, i)
        return np.array([a, b, c])

    def rates(self, values: ArrayLike, omega_body: ArrayLike) -> NDArray[np.float64]:
        """Angle rates (3,) from ω = B(q) q̇; a :class:`StateError` at gimbal lock."""
        q, w = self._values(values), self._omega(omega_body)
        _, kin, sing = self._numeric
        if abs(sing(q)) < SINGULAR_TOL:
            raise StateError(
                f"EulerAngles {self.sequence}: the kinematic matrix is singular at "
                f"{self.coordinates[1]} = {q[1]:.17g} ({self.singularity} = 0, gimbal lock: the "
                "first and third rotation axes align); use another sequence or Quaternion/MRP"
            )
        return np.linalg.solve(np.asarray(kin(q), dtype=float), w)


class Quaternion(Attitude):
    """Euler parameters β = (β0, β1, β2, β3), scalar first, with β·β = 1 (``constraint``).

    C = (β0² - |v|²) I + 2 v vᵀ + 2 β0 [v×] with v = (β1, β2, β3), the rotation by φ about the unit
    axis e for β0 = cos(φ/2), v = e sin(φ/2); ω = 2 (β0 v̇ - β̇0 v - v × v̇), and conversely
    β̇0 = -v·ω/2, v̇ = (β0 ω + v × ω)/2.

    Parameters
    ----------
    coords : sequence of 4 coordinates

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> q = Quaternion(pfaff.coordinates("b0:4"))
    >>> q.constraint
    b0(t)**2 + b1(t)**2 + b2(t)**2 + b3(t)**2 - 1
    >>> half = np.sqrt(0.5)
    >>> dcm_from(q, [half, 0, 0, half]).round(12) + 0.0  # a quarter turn about z
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    >>> q.rates([1, 0, 0, 0], [0, 0, 2.0])
    array([0., 0., 0., 1.])
    """

    kind = "quaternion"
    size = 4

    def __init__(self, coords: Sequence[sp.Function]) -> None:
        super().__init__(coords, "coords")
        b0, *vec = self.coordinates
        bd0, *vecd = self.rates_symbols
        v, vd = sp.Matrix(vec), sp.Matrix(vecd)
        self.dcm = (b0**2 - v.dot(v)) * sp.eye(3) + 2 * v * v.T + 2 * b0 * _cross(v)
        self.angular_velocity = 2 * (b0 * vd - bd0 * v - v.cross(vd))
        self.constraint = sum(b**2 for b in self.coordinates) - 1

    def from_dcm(self, dcm: ArrayLike) -> NDArray[np.float64]:
        """Unit β (4,) of ``dcm`` with β0 ≥ 0."""
        return _quaternion_from_dcm(self._rotation_matrix(dcm))

    def rates(self, values: ArrayLike, omega_body: ArrayLike) -> NDArray[np.float64]:
        """β̇ (4,) = ½ β ⊗ (0, ω)."""
        beta, w = self._values(values), self._omega(omega_body)
        v = beta[1:]
        return 0.5 * np.concatenate([[-v @ w], beta[0] * w + np.cross(v, w)])


class MRP(Attitude):
    """Modified Rodrigues parameters σ = e tan(φ/4) = v/(1 + β0) of the Euler parameters (β0, v).

    C = I + (8 [σ×]² + 4 (1 - σ²) [σ×]) / (1 + σ²)² with σ² = σ·σ;
    σ̇ = B(σ) ω / 4 with B = (1 - σ²) I + 2 [σ×] + 2 σσᵀ, and ω = 4 Bᵀ σ̇ / (1 + σ²)² (BᵀB =
    (1 + σ²)² I). The shadow set -σ/σ² describes the same attitude (:meth:`shadow`).

    Parameters
    ----------
    coords : sequence of 3 coordinates

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> s = MRP(pfaff.coordinates("s1:4"))
    >>> sigma = s.from_dcm(dcm_from(s, [0.0, 0.0, 2.0]))  # |σ| > 1 comes back as the shadow
    >>> sigma
    array([ 0. ,  0. , -0.5])
    >>> s.shadow(sigma, [0.0, 0.0, 1.0])
    (array([0., 0., 2.]), array([0., 0., 4.]))
    """

    kind = "mrp"
    size = 3

    def __init__(self, coords: Sequence[sp.Function]) -> None:
        super().__init__(coords, "coords")
        s, sd = sp.Matrix(self.coordinates), sp.Matrix(self.rates_symbols)
        s2, cross = s.dot(s), _cross(s)
        self.dcm = sp.eye(3) + (8 * cross**2 + 4 * (1 - s2) * cross) / (1 + s2) ** 2
        b_t = (1 - s2) * sp.eye(3) - 2 * cross + 2 * s * s.T
        self.angular_velocity = 4 * b_t * sd / (1 + s2) ** 2

    def from_dcm(self, dcm: ArrayLike) -> NDArray[np.float64]:
        """σ (3,) of ``dcm`` with |σ| ≤ 1 (from the quaternion with β0 ≥ 0)."""
        beta = _quaternion_from_dcm(self._rotation_matrix(dcm))
        return beta[1:] / (1 + beta[0]) + 0.0  # no -0.0

    def rates(self, values: ArrayLike, omega_body: ArrayLike) -> NDArray[np.float64]:
        """σ̇ (3,) = ((1 - σ²) ω + 2 σ × ω + 2 σ (σ·ω)) / 4."""
        s, w = self._values(values), self._omega(omega_body)
        return 0.25 * ((1 - s @ s) * w + 2 * np.cross(s, w) + 2 * s * (s @ w))

    def shadow(
        self, values: ArrayLike, rates: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The shadow set σˢ = -σ/σ² and its rate σ̇ˢ = (2 σ (σ·σ̇) - σ² σ̇)/σ⁴ (same C, same ω)."""
        s, sd = self._values(values), self._values(rates, "rates")
        s2 = s @ s
        if s2 == 0:
            raise StateError("`values`: σ = 0 (no rotation) has no shadow set")
        return -s / s2 + 0.0, (2 * s * (s @ sd) - s2 * sd) / s2**2 + 0.0  # no -0.0


class PlanarAngle(Attitude):
    """One angle θ about the inertial z axis: C = R_z(θ), ω = (0, 0, θ̇).

    Parameters
    ----------
    angle : coordinate (or a sequence of one)

    Examples
    --------
    >>> import pfaff
    >>> p = PlanarAngle(pfaff.coordinates("theta"))
    >>> p.angular_velocity.T
    Matrix([[0, 0, Derivative(theta(t), t)]])
    >>> p.rates(0.3, [0.0, 0.0, 1.5])
    array([1.5])
    """

    kind = "planar"
    size = 1

    def __init__(self, angle: sp.Function | Sequence[sp.Function]) -> None:
        super().__init__(angle, "angle")
        self.dcm = _rotation(2, self.coordinates[0])
        self.angular_velocity = sp.Matrix([0, 0, self.rates_symbols[0]])

    def from_dcm(self, dcm: ArrayLike) -> NDArray[np.float64]:
        """θ (1,) in (-π, π] of a rotation ``dcm`` about z."""
        r = self._rotation_matrix(dcm)
        if abs(r[2, 2] - 1) > 1e-6:
            raise StateError(f"`dcm` is not a rotation about the z axis:\n{r}")
        return np.array([_angle_about(r, 2)])

    def rates(self, values: ArrayLike, omega_body: ArrayLike) -> NDArray[np.float64]:
        """θ̇ (1,) = ω_z; ``omega_body`` is ω_z or (3,), whose x and y parts a plane body lacks."""
        self._values(values)
        w = np.atleast_1d(np.asarray(omega_body, dtype=float))
        if w.shape not in ((1,), (3,)) or not np.all(np.isfinite(w)):
            raise StateError(f"`omega_body` must be ω_z or 3 finite numbers, got shape {w.shape}")
        return w[-1:].copy()


def _tidy(e: sp.Expr) -> sp.Expr:
    """sin² + cos² = 1 exactly, then Fu's rules (angle sums) on an entry small enough for them.

    First the normal form of a polynomial in sines and cosines: each sin(u)^k with k ≥ 2
    becomes sin(u)^(k-2) (1 − cos²u), expanded, until none is left, which cancels every
    sin² + cos² (a chain of three joints: ω's entries in milliseconds where Fu's rules took
    seconds each). Fu's rules then see only entries of at most ``TIDY_ANGLES`` angles.
    """
    for _ in range(8):
        rep = {
            p: p.base ** (p.exp - 2) * (1 - sp.cos(p.base.args[0]) ** 2)
            for p in e.atoms(sp.Pow)
            if p.base.func is sp.sin and p.exp.is_Integer and p.exp >= 2
        }
        if not rep:
            break
        e = sp.expand(e.xreplace(rep))
    if (
        sp.count_ops(e) > TIDY_OPS
        or len({f.args[0] for f in e.atoms(sp.sin, sp.cos)}) > TIDY_ANGLES
    ):
        return e
    return sp.fu(e)


class Rotation(Attitude):
    """Any rotation matrix C(q, t) of the system's coordinates: r_inertial = C r_body.

    The body angular velocity comes from C itself, [ω×] = Cᵀ Ċ, so ω is linear in q̇ (plus
    Cᵀ ∂C/∂t when C depends on t explicitly). Unlike the coordinate sets, several Rotation bodies
    may share coordinates (a kinematic chain: link 2's C uses q1 and q2); ``add_rigid_body``
    checks that the coordinates are the system's and that C is orthogonal with det C = 1 (at a
    random state). A ``sympy.physics.vector.ReferenceFrame`` B given as an attitude becomes
    ``Rotation(N.dcm(B))`` for the system's inertial frame N. There are no numeric conversions
    (``from_dcm``, ``rates``): the coordinates are the user's joint angles, not an attitude set.

    Parameters
    ----------
    dcm : Matrix, shape (3, 3)
        C, in coordinates (functions of t made with ``pfaff.coordinates``), t and parameters;
        no coordinate rates.
    source : str, optional
        What C came from, for messages.

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> q1, q2 = pfaff.coordinates("q1 q2")
    >>> rz = sp.Matrix([[sp.cos(q1), -sp.sin(q1), 0], [sp.sin(q1), sp.cos(q1), 0], [0, 0, 1]])
    >>> ry = sp.Matrix([[sp.cos(q2), 0, sp.sin(q2)], [0, 1, 0], [-sp.sin(q2), 0, sp.cos(q2)]])
    >>> r = Rotation(rz * ry)
    >>> r.coordinates
    (q1(t), q2(t))
    >>> r.angular_velocity.T
    Matrix([[-sin(q2(t))*Derivative(q1(t), t), Derivative(q2(t), t), cos(q2(t))*Derivative(q1(t), t)]])
    """

    kind = "rotation"
    #: Body components of the body's mass-centre velocity when whoever made C knows them (a
    #: chain built joint by joint, :func:`pfaff.load_urdf`): ``add_rigid_body`` then adds the
    #: translation as the kinetic energy ½ m |v|² in body axes, not as a particle at the
    #: inertial position (the same T; M entries without the rotations of the joints above).
    centre_velocity: sp.Matrix | None = None

    def __init__(self, dcm: object, source: str = "") -> None:
        if not isinstance(dcm, sp.MatrixBase | list | tuple | np.ndarray):
            raise ModelTypeError(
                f"`dcm` of Rotation must be a 3×3 SymPy Matrix, got {type(dcm).__name__}"
            )
        c = sp.Matrix(dcm)
        if c.shape != (3, 3):
            raise ModelError(f"`dcm` of Rotation must be 3×3, got shape {c.shape}")
        c = c.applyfunc(sp.sympify)
        if any(e.atoms(sp.Derivative) for e in c):
            raise ModelError("`dcm` of Rotation must not contain coordinate rates (Derivative)")
        self.source = source
        self.dcm = sp.ImmutableMatrix(c)
        funcs = {f for e in c for f in e.atoms(sp.core.function.AppliedUndef)}
        bad = sorted(str(f) for f in funcs if not is_coordinate_like(f))
        if bad:
            raise ModelTypeError(
                f"`dcm` of Rotation: {', '.join(bad)} is not a coordinate (a function of t alone)"
            )
        self.coordinates = tuple(sorted(funcs, key=str))
        self.size = len(self.coordinates)
        self.rates_symbols = tuple(sp.Derivative(q, t) for q in self.coordinates)
        self.angular_velocity = self._omega_of(c)

    def _omega_of(self, c: sp.Matrix) -> sp.Matrix:
        """ω = vee(Cᵀ Ċ), one q̇ at a time (plus ∂/∂t), each coefficient trig-simplified."""
        parts = [
            (c.diff(q), qd) for q, qd in zip(self.coordinates, self.rates_symbols, strict=True)
        ]
        dummies = {q: sp.Dummy(str(q)) for q in self.coordinates}
        fixed = c.xreplace(dummies)
        if fixed.has(t):  # ∂C/∂t with the coordinates held fixed
            back = {d: q for q, d in dummies.items()}
            parts.append((fixed.diff(t).xreplace(back), sp.S.One))
        w = sp.zeros(3, 1)
        for dc, rate in parts:
            skew = c.T * dc
            vee = (skew[2, 1] - skew[1, 2], skew[0, 2] - skew[2, 0], skew[1, 0] - skew[0, 1])
            w += sp.Matrix([_tidy(sp.expand(e / 2)) for e in vee]) * rate
        return w

    def __repr__(self) -> str:
        return f"Rotation({self.source})" if self.source else f"Rotation({self.coordinates})"

    def _refuse(self, what: str) -> None:
        raise ModelError(
            f"Rotation has no `{what}`: its coordinates are the user's (joint angles), not an "
            "attitude set; `from_dcm` and `rates` exist for EulerAngles, Quaternion, MRP and "
            "PlanarAngle only"
        )

    def from_dcm(self, dcm: ArrayLike) -> NDArray[np.float64]:
        """Refused: a Rotation has no inverse map (see the class docstring)."""
        self._refuse("from_dcm")

    def rates(self, values: ArrayLike, omega_body: ArrayLike) -> NDArray[np.float64]:
        """Refused: a Rotation has no inverse map (see the class docstring)."""
        self._refuse("rates")


def dcm_from(attitude: Attitude, values: ArrayLike) -> NDArray[np.float64]:
    """The numeric C (3, 3) of an attitude set at coordinate ``values``.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> p = PlanarAngle(pfaff.coordinates("theta"))
    >>> dcm_from(p, np.pi / 2).round(12) + 0.0
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    if not isinstance(attitude, Attitude) or isinstance(attitude, Rotation):
        raise ModelTypeError(
            "`attitude` must be an EulerAngles, Quaternion, MRP or PlanarAngle, got "
            f"{type(attitude).__name__} (a Rotation's C is model.geometry.bodies(q)[1])"
        )
    q = attitude._values(values)
    return np.asarray(attitude._numeric[0](q), dtype=float)
