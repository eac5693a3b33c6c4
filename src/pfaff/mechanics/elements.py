"""``add_rigid_body``, ``add_torque``, ``add_spring``, ``add_damper`` and ``add_dissipation``.

The methods of :class:`pfaff.mechanics.system.SystemSpec` that build rigid bodies and force
elements out of the basic pieces (see :mod:`pfaff.mechanics.bodies` for the mechanics).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import sympy as sp

from pfaff.core.errors import ModelError, ModelTypeError
from pfaff.core.keywords import checked_keywords
from pfaff.core.symbols import as_expr, is_physics_vector, t
from pfaff.mechanics.attitude import Attitude, PlanarAngle, Rotation
from pfaff.mechanics.bodies import Body, between, check_rotation, inertia_matrix, torque_exprs

if TYPE_CHECKING:
    from sympy.physics.vector import ReferenceFrame

    from pfaff.mechanics.system import SystemSpec


def quadratic_form(inertia: sp.Matrix, w: sp.Matrix) -> sp.Expr:
    """½ ωᵀ I ω as Σ_c I_cc ω_c²/2 + Σ_{c<d} I_cd ω_c ω_d, unexpanded: its second derivatives in
    q̇ are then the compact Σ I_cd (∂ω_c/∂q̇_a)(∂ω_d/∂q̇_b) (no halves, no expanded products).

    Examples
    --------
    >>> a, b, c = sp.symbols("a b c")
    >>> quadratic_form(sp.Matrix([[2, 1, 0], [1, 4, 0], [0, 0, 6]]), sp.Matrix([a, b, c]))
    a**2 + a*b + 2*b**2 + 3*c**2
    """
    terms = [inertia[i, i] / 2 * w[i] ** 2 for i in range(3)]
    terms += [inertia[i, j] * w[i] * w[j] for i in range(3) for j in range(i + 1, 3)]
    return sp.Add(*terms)


class ElementsMixin:
    """Rigid bodies, torques, springs, dampers and Rayleigh dissipation (a part of SystemSpec)."""

    bodies: list[Body]
    inputs: list[sp.Symbol]

    @checked_keywords
    def add_rigid_body(
        self: SystemSpec,
        mass: object,
        inertia: object,
        position: object,
        attitude: Attitude | ReferenceFrame,
        name: str | None = None,
        *,
        frame: object = None,
    ) -> Body:
        """Add a rigid body: T = ½ m v·v + ½ ωᵀ I ω.

        Parameters
        ----------
        mass : Expr or float
            Constant, positive.
        inertia : Matrix (3, 3), sequence of 3, or Expr
            About the mass centre in body axes: a symmetric matrix, the three principal moments,
            or (with :class:`~pfaff.attitude.PlanarAngle`) the one moment about z. Principal
            moments must satisfy the triangle inequality (equality allowed: thin disks, plates).
        position : sequence of 2 or 3 Expr, Matrix or Vector
            Inertial components of the mass centre, functions of q and t.
        attitude : EulerAngles, Quaternion, MRP, PlanarAngle, Rotation or ReferenceFrame
            Made from coordinates of this system. A coordinate set (EulerAngles, Quaternion,
            MRP, PlanarAngle) uses coordinates no other body's attitude uses. A quaternion adds
            the holonomic constraint ``"<name> unit norm"``: β·β − 1 = 0. A
            :class:`~pfaff.attitude.Rotation` C(q, t), or a ``sympy.physics.vector`` frame B
            (C = N.dcm(B) for the inertial frame N of ``frame=`` or ``System(..., frame=N)``),
            may share coordinates with other Rotation bodies (a kinematic chain); C must be a
            rotation (CᵀC = I, det C = 1, checked at a random state).
        name : str, optional
            ``body0``, ``body1``, … in order when omitted.
        frame : ReferenceFrame, optional
            The inertial frame of a Vector ``position`` and of a ReferenceFrame ``attitude``.

        Returns
        -------
        Body

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> b0, b1, b2, b3 = q = pfaff.coordinates("b0:4")
        >>> s = pfaff.System(q)
        >>> top = s.add_rigid_body(1, [1, 2, 3], [0, 0, 0], pfaff.attitude.Quaternion(q))
        >>> s.constraint_rows()[0]
        ('body0 unit norm',)
        """
        if name is not None and not isinstance(name, str):
            raise ModelTypeError(f"`name` must be a string, got {name!r:.60}")
        label = name or f"body{len(self.bodies)}"
        if any(b.name == label for b in self.bodies):
            raise ModelError(f"a body named `{label}` exists already")
        what = f"body `{label}`"
        attitude = self._attitude(attitude, frame, what)
        self._check_attitude_coordinates(attitude, what)
        if isinstance(attitude, Rotation):
            check_rotation(attitude.dcm, f"attitude of {what}")
        m = as_expr(mass, f"mass of {what}")
        r = sp.Matrix(self._vector(position, f"position of {what}", frame))
        if r.rows == 2 and not isinstance(attitude, PlanarAngle):
            raise ModelError(
                f"position of {what} has 2 components (planar) but its attitude is "
                f"{type(attitude).__name__}: a planar body turns by a PlanarAngle"
            )
        inertia_c = inertia_matrix(inertia, attitude, f"inertia of {what}")
        self._parameters.update(inertia_c.free_symbols)
        body = Body(label, m, inertia_c, r, attitude)
        w = attitude.angular_velocity
        v = getattr(attitude, "centre_velocity", None)
        if v is None:
            self.add_particle(m, list(r), name=label)  # the translation: m JᵀJ
            rot = sp.expand((w.T * inertia_c * w)[0, 0] / 2)
        else:  # a chain's link: both halves in body components, unexpanded (compact M entries)
            m = self._mass(m, what)
            self._scan(tuple(r), f"position of {what}", speeds=False)  # its parameters count
            self.add_kinetic_energy(m * sp.Add(*(vc**2 / 2 for vc in v)), name=label)
            rot = quadratic_form(inertia_c, w)
        if rot != 0:
            self.add_kinetic_energy(rot, name=f"{label} rotation")
        if attitude.constraint is not None:
            body.constraint = f"{label} unit norm"
            self.add_holonomic_constraint(attitude.constraint, name=body.constraint)
        self.bodies.append(body)
        return body

    def _attitude(self: SystemSpec, attitude: object, frame: object, what: str) -> Attitude:
        """The attitude set of a body; a ReferenceFrame B becomes Rotation(N.dcm(B))."""
        if is_physics_vector(attitude, "ReferenceFrame"):
            dcm, source = self._frame_dcm(attitude, frame, what)
            return Rotation(dcm, source=source)
        if not isinstance(attitude, Attitude):
            raise ModelTypeError(
                "`attitude` must be a pfaff.attitude set (EulerAngles, Quaternion, MRP, "
                "PlanarAngle, Rotation) or a sympy.physics.vector.ReferenceFrame, got "
                f"{type(attitude).__name__}"
            )
        return attitude

    def _frame_dcm(
        self: SystemSpec, attitude: ReferenceFrame, frame: object, what: str
    ) -> tuple[sp.Matrix, str]:
        """N.dcm(B) of a ReferenceFrame B, N the inertial frame, and where it came from."""
        inertial = frame if frame is not None else self.frame
        if inertial is None:
            raise ModelError(
                f"attitude of {what} is the ReferenceFrame {attitude}: give the inertial "
                "frame N as pfaff.System(..., frame=N) (or `frame=N`)"
            )
        try:
            dcm = inertial.dcm(attitude)
        except ValueError as e:
            raise ModelError(
                f"attitude of {what}: the frame {attitude} is not oriented relative to the "
                f"inertial frame {inertial} ({e})"
            ) from e
        return sp.Matrix(dcm), f"{inertial}.dcm({attitude})"

    def _check_attitude_coordinates(self: SystemSpec, attitude: Attitude, what: str) -> None:
        """Coordinates of this system; shared between bodies only by Rotation attitudes."""
        shares = isinstance(attitude, Rotation)
        for q in attitude.coordinates:
            if q not in self._index:
                raise ModelError(
                    f"attitude of {what}: `{q}` is not a coordinate of this system "
                    f"(coordinates: {', '.join(map(str, self.coordinates))})"
                )
            other = next(
                (
                    b
                    for b in self.bodies
                    if q in b.attitude.coordinates
                    and not (shares and isinstance(b.attitude, Rotation))
                ),
                None,
            )
            if other is not None:
                raise ModelError(
                    f"attitude of {what}: the coordinate `{q}` is already an attitude coordinate "
                    f"of body `{other.name}`; each body needs its own (only Rotation and "
                    "ReferenceFrame attitudes may share coordinates)"
                )

    @checked_keywords
    def add_torque(
        self: SystemSpec,
        torque: object,
        on: Body,
        frame: str = "inertial",
        *,
        name: str | None = None,
    ) -> None:
        """Add a torque on a body: Q_j = τ · ∂ω/∂q̇_j (partial angular velocities).

        Parameters
        ----------
        torque : sequence of 3 Expr (or one Expr for a planar body)
            Components in the inertial frame or, with ``frame="body"``, in body axes; may depend
            on q, q̇ and t.
        on : Body
        frame : {"inertial", "body"}

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> th = pfaff.coordinates("theta")
        >>> s = pfaff.System([th])
        >>> wheel = s.add_rigid_body(1, 2, [0, 0], pfaff.attitude.PlanarAngle(th))
        >>> s.add_torque(sp.Symbol("tau"), on=wheel)
        >>> s.equations().forcing
        Matrix([[tau]])
        """
        if not isinstance(on, Body) or on not in self.bodies:
            raise ModelTypeError("`on` must be a Body of this system (from add_rigid_body)")
        label = self._label(name, "torque")
        exprs = torque_exprs(on, torque, frame, f"torque `{label}`")
        coords = self._scan(exprs, f"torque `{label}`", speeds=True, smooth=False)
        self._add("torque", exprs, coords, label, 3)

    @checked_keywords
    def add_spring(
        self: SystemSpec,
        k: object,
        between: tuple,
        rest_length: object = 0,
        *,
        name: str | None = None,
    ) -> None:
        """Add a linear spring between two points: V = ½ k (ℓ − ℓ₀)², ℓ = |p₁ − p₂|.

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> x = pfaff.coordinates("x")
        >>> s = pfaff.System([x]); s.add_particle(1, [x, 0])
        >>> s.add_spring(3, between=([x, 0], [0, 0]))
        >>> s.equations().forcing
        Matrix([[-3*x(t)]])
        """
        label = self._label(name, "potential") if name is None else name
        p1, p2 = _pair(between, f"spring `{label}`")
        d = p1 - p2
        stiff = as_expr(k, f"stiffness of spring `{label}`")
        rest = as_expr(rest_length, f"rest length of spring `{label}`")
        stretch = d.dot(d) if rest == 0 else (sp.sqrt(d.dot(d)) - rest) ** 2
        self.add_potential_energy(stiff * stretch / 2, name=label)

    @checked_keywords
    def add_damper(self: SystemSpec, c: object, between: tuple, *, name: str | None = None) -> None:
        """Add a linear damper along the line of two points: R = ½ c ℓ̇², ℓ̇ = (d·ḋ)/|d|.

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> x = pfaff.coordinates("x")
        >>> s = pfaff.System([x]); s.add_particle(1, [x, 0])
        >>> s.add_damper(2, between=([x, 0], [-1, 0]))
        >>> s.equations().forcing
        Matrix([[-2*Derivative(x(t), t)]])
        """
        label = self._label(name, "dissipation")
        p1, p2 = _pair(between, f"damper `{label}`")
        d = p1 - p2
        rate = d.dot(d.diff(t))
        damping = as_expr(c, f"damping of damper `{label}`")
        self.add_dissipation(damping * rate**2 / (2 * d.dot(d)), name=label)

    @checked_keywords
    def add_input(self: SystemSpec, symbol: object) -> sp.Symbol:
        """Declare a parameter as an input: ``compile()`` does not ask for its value (0 until
        set), ``pfaff.simulate(model, ..., inputs={name: u})`` supplies it during a run (a number,
        u(t) or a feedback law u(t, q, q̇)), and ``linearize(..., inputs=[symbol])`` gives its
        column of B.

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> x = pfaff.coordinates("x")
        >>> s = pfaff.System([x]); s.add_particle(1, [x, 0])
        >>> F = s.add_input("F"); s.add_force([F, 0], at=[x, 0])
        >>> s.equations().compile({}).inputs
        ['F']
        """
        sym = _input_symbol(symbol)
        if sym.name in {p.name for p in self.inputs}:
            raise ModelError(f"`{sym.name}` is already an input")
        self.inputs.append(sym)
        return sym

    @checked_keywords
    def add_dissipation(self: SystemSpec, R: object, *, name: str | None = None) -> None:
        """Add a Rayleigh dissipation function R(q, q̇, t): Q_j = −∂R/∂q̇_j.

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> x = pfaff.coordinates("x")
        >>> s = pfaff.System([x]); s.add_particle(1, [x, 0])
        >>> s.add_dissipation(sp.Symbol("c") * x.diff(pfaff.t) ** 2 / 2)
        >>> s.equations().forcing
        Matrix([[-c*Derivative(x(t), t)]])
        """
        label = self._label(name, "dissipation")
        e = as_expr(R, f"dissipation function `{label}`")
        coords = self._scan((e,), f"dissipation function `{label}`", speeds=True)
        if not coords:
            raise ModelError(f"dissipation function `{label}` involves no coordinate: {e}")
        self._add("dissipation", (e,), coords, label)


def _pair(points: object, what: str) -> tuple[sp.Matrix, sp.Matrix]:
    p1, p2 = between(points, what)
    if p1.rows not in (2, 3):
        raise ModelError(f"{what}: points must have 2 or 3 components, got {p1.rows}")
    return p1, p2


def _input_symbol(value: object) -> sp.Symbol:
    if isinstance(value, str):
        if not value.isidentifier() or value.startswith("_"):
            raise ModelTypeError(f"an input name must be a plain identifier, got {value!r:.60}")
        return sp.Symbol(value)
    if isinstance(value, sp.Symbol):
        return value
    raise ModelTypeError(
        "`add_input` takes a parameter symbol (or its name); a prescribed function of time or a "
        f"feedback law is that symbol's value given to simulate(inputs=...), got {value!r:.60}"
    )
