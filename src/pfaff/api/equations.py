"""``pfaff.EquationsOfMotion``: the derivation result as users see it, with ``compile()``."""

from __future__ import annotations

from pfaff.core.errors import ModelError, OptionError
from pfaff.derive.compile import compile_equations
from pfaff.derive.compile_family import compile_structured
from pfaff.derive.equations import Derivation, Solution
from pfaff.numeric.model import SOLVERS as GENERAL_SOLVERS
from pfaff.numeric.model import NumericModel
from pfaff.numeric.structured import SOLVERS as STRUCTURED_SOLVERS
from pfaff.numeric.structured import StructuredModel

__all__ = ["EquationsOfMotion", "Solution"]


class EquationsOfMotion(Derivation):
    """Lagrange's equations with multipliers in block form.

    The canonical form is

        M(q,t) q̈ + h(q,q̇,t) = Q(q,q̇,t) + A(q,t)ᵀ λ
        A(q,t) q̈ + Ȧ q̇ + ḃ = 0            (differentiated Pfaffian constraints A q̇ + b = 0)

    i.e. the augmented (KKT) system [[M, -Aᵀ], [A, 0]] [q̈; λ] = [Q - h; -(Ȧq̇ + ḃ)]. For a
    holonomic constraint f(q,t) = 0, A = ∂f/∂q and b = ∂f/∂t, so Aᵀλ is the generalized constraint
    force. Matrices are SymPy ``ImmutableMatrix`` (a read-only ``SparseMatrix`` beyond 500
    coordinates) in the user's coordinates (functions of :data:`pfaff.t`). The named matrices,
    ``lagrange_equations``, ``latex()`` and ``solve()`` come from the derivation stage
    (:class:`pfaff.derive.equations.Derivation`); this class adds :meth:`compile`.

    Attributes
    ----------
    coordinates : tuple of Function, length n
    mass_matrix : Matrix, shape (n, n)
        M.
    velocity_terms : Matrix, shape (n, 1)
        h: velocity products, explicit time dependence and ∂V/∂q.
    generalized_forces : Matrix, shape (n, 1)
        Q from applied forces (virtual work) and generalized forces.
    forcing : Matrix, shape (n, 1)
        Q - h.
    constraint_matrix : Matrix, shape (m, n)
        A.
    constraint_bias : Matrix, shape (m, 1)
        b.
    acceleration_constraints : Matrix, shape (m, 1)
        A q̈ + Ȧ q̇ + ḃ (each entry = 0).
    multipliers : tuple of Symbol, length m
        λ, one per constraint, in the order the constraints were added.

    Examples
    --------
    >>> import pfaff
    >>> eom = pfaff.models.cartesian_pendulum().equations()
    >>> eom.lagrange_equations[1]
    Eq(g*m + m*Derivative(y(t), (t, 2)), 2*lambda1*y(t))
    """

    def compile(
        self, parameters: dict | None = None, *, solver: str | None = None
    ) -> NumericModel | StructuredModel:
        """Compile to a numeric model with the given parameter values.

        A model with families compiles to a :class:`pfaff.numeric.structured.StructuredModel`
        (template kernels over index progressions, O(N) solves), any other to a
        :class:`pfaff.NumericModel`.

        Parameters
        ----------
        parameters : dict
            Value for every symbol in :attr:`parameters`, keyed by Symbol or by name.
        solver : str, optional
            The KKT solver (:mod:`pfaff.numeric.kkt`). General models: ``"range-space"`` (the
            default up to 400 unknowns, with the rank-loss floor), ``"lu"`` or ``"sparse"`` (the
            default above). Models with families: ``"triangular"`` (the default where the
            constraints have that structure) or ``"sparse"``.

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
        >>> qdd, lam = model.accelerations(0.0, [0.5], [0.0])
        >>> round(float(qdd[0]), 6)
        -2.351582
        """
        if "dependent_velocities" in self.extra:
            raise ModelError(
                "these reduced equations still contain dependent coordinates (projection form): "
                "they cannot be compiled; give `solutions` for the dependent coordinates to "
                "System.reduce, or compile the full equations"
            )
        kinds = STRUCTURED_SOLVERS if self.family else GENERAL_SOLVERS
        if solver is not None and solver not in kinds:
            kind = "with families" if self.family else "without families"
            raise OptionError(
                f"`solver` of a model {kind} must be one of {', '.join(kinds)}; got {solver!r:.80}"
            )
        if self.family:
            return compile_structured(self, parameters or {}, solver=solver)
        return compile_equations(self, parameters or {}, solver=solver)
