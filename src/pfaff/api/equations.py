"""``pfaff.EquationsOfMotion``: the derivation result as users see it, with ``compile()``."""

from __future__ import annotations

import sympy as sp

from pfaff.core.errors import ModelError, OptionError
from pfaff.derive.compile import compile_equations
from pfaff.derive.compile_family import compile_structured
from pfaff.derive.contacts import compile_contacts
from pfaff.derive.equations import Derivation, Solution
from pfaff.derive.linearize import linearize as _linearize
from pfaff.numeric.linearization import Linearization
from pfaff.numeric.model import NumericModel
from pfaff.numeric.solvers import check as check_solver
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
        self,
        parameters: dict | None = None,
        *,
        solver: str | None = None,
        evaluator: str | None = None,
    ) -> NumericModel | StructuredModel:
        """Compile to a numeric model with the given parameter values.

        A model with families compiles to a :class:`pfaff.numeric.structured.StructuredModel`
        (template kernels over index progressions, O(N) solves), any other to a
        :class:`pfaff.NumericModel`.

        Parameters
        ----------
        parameters : dict
            Value for every symbol in :attr:`parameters`, keyed by Symbol or by name; a parameter
            left out takes its default (:meth:`pfaff.System.set_parameter_defaults`) if it has one.
        solver : str, optional
            The KKT solver (:mod:`pfaff.numeric.kkt`). General models: ``"range-space"`` (the
            default up to 400 unknowns, with the rank-loss floor), ``"lu"`` or ``"sparse"`` (the
            default above). Models with families: ``"triangular"`` (the default where the
            constraints have that structure) or ``"sparse"``.
        evaluator : {None, "template", "python", "machine"}, optional
            Which code evaluates a state (:mod:`pfaff.numeric.evaluator`): by default the rule
            there (machine code from 8 unknowns n + m on where the system is small enough for
            the fused kernel, else its generated Python, else the template kernels). Reported
            in ``model.timings["evaluator"]``. Models with families have only ``"template"``.

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
        check_solver(solver, "family" if self.family else "general")
        parameters = with_defaults(parameters, getattr(self.system, "parameter_defaults", {}))
        if self.family:
            if evaluator not in (None, "template"):
                raise OptionError(
                    f"`evaluator` of a model with families must be 'template'; got {evaluator!r:.80}"
                )
            return compile_structured(self, parameters or {}, solver=solver)
        return compile_equations(
            self, parameters or {}, solver=solver, evaluator=evaluator, contacts=compile_contacts
        )

    def linearize(
        self,
        op_point: dict,
        independent: object,
        independent_speeds: object = None,
        inputs: object = (),
    ) -> Linearization:
        """Linearize about an equilibrium or a steady motion: ẋ = A x + B u, δλ = C x + D u.

        The state is x = (δ of the ``independent`` coordinates, δ of the ``independent_speeds``
        rates); the other coordinates are eliminated through the holonomic constraints' Jacobian
        and the other rates through every constraint (holonomic and velocity), at the operating
        point. Derivatives are exact (symbolic).

        Parameters
        ----------
        op_point : dict
            Values keyed by coordinate (or its name), rate (``q.diff(pfaff.t)``), parameter (Symbol
            or name), input, and :data:`pfaff.t` (default 0). Every coordinate is required; a
            parameter left out stays symbolic; an input left out is 0; a rate left out is 0,
            except a dependent one (not kept), which the velocity constraints give. A steady
            motion is given by all its rates.
        independent : sequence of coordinates (or names)
            The coordinates kept in the state, in this order.
        independent_speeds : sequence of rates or coordinates (or names), optional
            The rates kept in the state; default: those of ``independent``.
        inputs : sequence, optional
            Parameters (Symbols or names) or functions of time (``F(t)``) whose columns B has.

        Returns
        -------
        Linearization
            ``A``, ``B`` (NumPy arrays when every value is numeric, else SymPy matrices),
            ``states``, ``inputs``, ``multipliers`` = (C, D), ``eigenvalues()``, ``modes()``,
            ``is_stable()``.

        Raises
        ------
        ConstraintError
            The point violates a constraint, or the kept coordinates (rates) leave the others
            undetermined (a count that does not match, a singular Jacobian block).
        StateError
            The point is not an equilibrium or steady motion: a kept rate accelerates, or a kept
            coordinate moves while the equations depend on it.
        ModelError
            A name that is not the model's, a coordinate named twice, a coordinate left out.

        Examples
        --------
        The pendulum hanging down, then upright, with symbolic parameters:

        >>> import pfaff, sympy as sp
        >>> eom = pfaff.models.pendulum().equations()
        >>> th = eom.coordinates[0]
        >>> eom.linearize({th: 0}, [th]).A
        Matrix([
        [   0, 1],
        [-g/L, 0]])
        >>> lin = eom.linearize({th: sp.pi, "m": 1, "g": 9.81, "L": 1}, [th])
        >>> lin.eigenvalues().real.round(4)
        array([-3.1321,  3.1321])
        >>> lin.is_stable()
        False
        """
        return _linearize(self, op_point, independent, independent_speeds, inputs)


def with_defaults(parameters: dict | None, defaults: dict[str, float]) -> dict | None:
    """``parameters`` completed by ``defaults`` (by name) where they give no value."""
    if not defaults or not (parameters is None or isinstance(parameters, dict)):
        return parameters
    given = {k.name if isinstance(k, sp.Symbol) else k for k in (parameters or {})}
    return {**{k: v for k, v in defaults.items() if k not in given}, **(parameters or {})}
