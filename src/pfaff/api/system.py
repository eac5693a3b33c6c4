"""``pfaff.System``: the model builder with the methods that run the later stages."""

from __future__ import annotations

from pfaff.api.equations import EquationsOfMotion
from pfaff.core.keywords import checked_keywords
from pfaff.derive.reduce import reduce as _reduce
from pfaff.derive.templates import derive
from pfaff.derive.work import ForceWork
from pfaff.derive.work import work as _work
from pfaff.mechanics.system import SystemSpec


class System(SystemSpec):
    """A constrained mechanical system (see :class:`pfaff.mechanics.system.SystemSpec`).

    The equations pfaff derives are Lagrange's equations with multipliers,

        M(q,t) q̈ + h(q,q̇,t) = Q(q,q̇,t) + A(q,t)ᵀ λ,    A q̈ + Ȧ q̇ + ḃ = 0,

    for constraints in Pfaffian form A(q,t) q̇ + b(q,t) = 0. A holonomic constraint f(q,t) = 0 enters
    with A = ∂f/∂q and b = ∂f/∂t, so Aᵀλ is the generalized constraint force (sign convention).

    Parameters
    ----------
    coordinates : sequence of Function, optional
        Generalized coordinates q, each a function of :data:`pfaff.t`. Omit it when every
        coordinate comes from :meth:`add_family`.
    name : str, optional
    frame : sympy.physics.vector.ReferenceFrame, optional
        Inertial frame in which positions and forces given as ``Vector`` are resolved.

    Examples
    --------
    >>> import sympy as sp, pfaff
    >>> x, y = pfaff.coordinates("x y")
    >>> m, g, L = sp.symbols("m g L", positive=True)
    >>> pend = pfaff.System([x, y])
    >>> pend.add_particle(m, [x, y])
    >>> pend.add_potential_energy(m * g * y)
    >>> pend.add_holonomic_constraint(x**2 + y**2 - L**2, name="rod")
    >>> eom = pend.equations()
    >>> eom.constraint_matrix
    Matrix([[2*x(t), 2*y(t)]])
    """

    def equations(self) -> EquationsOfMotion:
        """Derive Lagrange's equations with multipliers (see :class:`pfaff.EquationsOfMotion`).

        Examples
        --------
        >>> import pfaff
        >>> eom = pfaff.models.rolling_ring(3).equations()
        >>> eom.constraint_matrix.shape
        (3, 4)
        """
        return EquationsOfMotion.of(derive(self))

    @checked_keywords
    def reduce(self, independent: object, *, solutions: dict | None = None) -> EquationsOfMotion:
        """Equations of motion in minimal coordinates (see :func:`pfaff.derive.reduce.reduce`)."""
        return EquationsOfMotion.of(_reduce(self, independent, solutions=solutions))

    @checked_keywords
    def work(self, independent: object = None) -> list[ForceWork]:
        """Generalized force and virtual power of every applied force (see
        :func:`pfaff.derive.work.work`): a list that Jupyter renders as LaTeX."""
        return _work(self, independent)
