"""``add_shape``: a solid drawn with the system that adds nothing to its equations.

Animations and the 3-D viewer draw each rigid body (``add_rigid_body``) as the solid of its mass
and inertia. A system written as energies (the Whipple bicycle, a SymPy model) has no bodies to
draw: :meth:`ShapesMixin.add_shape` declares one, placed by a position and an attitude in the
system's coordinates, sized either by its semi-axes or, like a rigid body, by a mass and an
inertia. Shapes are read only by :mod:`pfaff.derive.geometry`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ModelError, ModelTypeError
from pfaff.core.symbols import as_expr, is_physics_vector, t
from pfaff.mechanics.attitude import Attitude, PlanarAngle, Rotation
from pfaff.mechanics.bodies import check_rotation, inertia_matrix

if TYPE_CHECKING:
    from pfaff.mechanics.system import SystemSpec

SHAPE_KINDS = ("ellipsoid", "box")


@dataclass
class Shape:
    """A drawn solid (made by ``add_shape``).

    Attributes
    ----------
    name : str
    position : Matrix, shape (d, 1)
        Inertial components of its centre, d = 2 or 3.
    dcm : Matrix, shape (3, 3)
        Its axes: r_inertial = C r_shape.
    kind : str or None
        ``"ellipsoid"`` or ``"box"`` for a shape given by ``size``; None for one given by its
        inertia (drawn as animations draw rigid bodies).
    size : tuple of 3 Expr or None
        Semi-axes along its own x, y, z.
    mass : Expr or None
    inertia : Matrix, shape (3, 3), or None
    """

    name: str
    position: sp.Matrix
    dcm: sp.Matrix
    kind: str | None
    size: tuple[sp.Expr, ...] | None
    mass: sp.Expr | None
    inertia: sp.Matrix | None


class ShapesMixin:
    """Drawn solids (a part of SystemSpec)."""

    shapes: list[Shape]

    def add_shape(
        self: SystemSpec,
        position: object,
        attitude: object,
        *,
        size: object = None,
        kind: str = "ellipsoid",
        mass: object = None,
        inertia: object = None,
        name: str | None = None,
        frame: object = None,
    ) -> Shape:
        """Add a solid to draw: nothing enters the equations of motion.

        Parameters
        ----------
        position : sequence of 2 or 3 Expr, Matrix or Vector
            Inertial components of its centre, functions of q and t.
        attitude : Matrix (3, 3), any attitude set, or ReferenceFrame
            Its axes C (r_inertial = C r_shape); unlike a rigid body's, they may share
            coordinates with any other. A matrix must be a rotation (checked at a random state).
        size : sequence of 3 Expr, optional
            Semi-axes along its x, y and z (parameters allowed), drawn as ``kind``.
        kind : {"ellipsoid", "box"}
            The solid of a shape given by ``size``.
        mass, inertia : optional
            Instead of ``size``: a mass and an inertia (as ``add_rigid_body`` takes them), drawn
            as the solid of the same mass and inertia, like a rigid body.
        name : str, optional
            ``shape0``, ``shape1``, … when omitted.
        frame : ReferenceFrame, optional
            The inertial frame of a Vector ``position`` and of a ReferenceFrame ``attitude``.

        Returns
        -------
        Shape

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> th = pfaff.coordinates("theta")
        >>> s = pfaff.models.pendulum()
        >>> wheel = s.add_shape([sp.sin(th), -sp.cos(th), 0], sp.eye(3), size=[0.2, 0.2, 0.02])
        >>> wheel.name, wheel.size
        ('shape0', (0.200000000000000, 0.200000000000000, 0.0200000000000000))
        """
        if name is not None and not isinstance(name, str):
            raise ModelTypeError(f"`name` must be a string, got {name!r:.60}")
        label = name or f"shape{len(self.shapes)}"
        if any(s.name == label for s in self.shapes):
            raise ModelError(f"a shape named `{label}` exists already")
        what = f"shape `{label}`"
        dcm = _dcm(self, attitude, frame, what)
        r = sp.Matrix(self._vector(position, f"position of {what}", frame))
        if (size is None) == (inertia is None):
            raise ModelError(f"{what}: give either `size` (semi-axes) or `mass` and `inertia`")
        if size is not None:
            if kind not in SHAPE_KINDS:
                raise ModelError(f"`kind` of {what} must be one of {SHAPE_KINDS}, got {kind!r:.40}")
            shape = Shape(label, r, dcm, kind, _size(size, what), None, None)
        else:
            if mass is None:
                raise ModelError(f"{what}: an `inertia` needs its `mass`")
            m = as_expr(mass, f"mass of {what}")
            planar = attitude if isinstance(attitude, PlanarAngle) else Rotation(sp.eye(3))
            shape = Shape(label, r, dcm, None, None, m, inertia_matrix(inertia, planar, what))
        self.shapes.append(shape)
        return shape


def _dcm(system: SystemSpec, attitude: object, frame: object, what: str) -> sp.Matrix:
    """C of a shape: an attitude set's, N.dcm(B) of a frame B (no angular velocity is formed),
    or a matrix checked to be a rotation."""
    if isinstance(attitude, Attitude):
        return attitude.dcm
    if is_physics_vector(attitude, "ReferenceFrame"):
        return system._frame_dcm(attitude, frame, what)[0]
    if isinstance(attitude, sp.MatrixBase | list | tuple):
        dcm = sp.Matrix(attitude)
        if dcm.shape != (3, 3):
            raise ModelError(f"attitude of {what} must be a 3×3 matrix, got shape {dcm.shape}")
        dcm = dcm.applyfunc(lambda e: as_expr(e, f"attitude of {what}"))
        check_rotation(dcm, f"attitude of {what}")
        return dcm
    raise ModelTypeError(
        f"`attitude` of {what} must be a 3×3 rotation matrix, a pfaff.attitude set or a "
        f"ReferenceFrame, got {type(attitude).__name__}"
    )


def _size(size: object, what: str) -> tuple[sp.Expr, ...]:
    if isinstance(size, str | bytes) or not hasattr(size, "__len__") or len(size) != 3:
        raise ModelError(f"`size` of {what} must be three semi-axes, got {size!r:.60}")
    dims = tuple(as_expr(v, f"`size` of {what}") for v in size)
    if any(e.is_number and not (e.is_real and e > 0) for e in dims):
        raise ModelError(f"`size` of {what} must be positive, got {size!r:.60}")
    if any(e.has(t) or e.atoms(AppliedUndef) for e in dims):
        raise ModelError(f"`size` of {what} must be constant (parameters only), got {size!r:.60}")
    return dims
