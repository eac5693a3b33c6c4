"""The one contract between numeric models and the integrators: :class:`DynamicsModel`.

A numeric model holds the equations of motion of a system with n coordinates q and m constraints
at fixed parameter values,

    M(q, t) q̈ + h(q, q̇, t) = Q(q, q̇, t) + A(q, t)ᵀ λ        (n equations)
    A(q, t) q̇ + b(q, t) = 0                                  (m constraints; g = A q̇ + b)
    f(q, t) = 0                                              (the holonomic rows, whose A = ∂f/∂q)

and, differentiated once more, A q̈ + Ȧq̇ + ḃ = 0. Solving both for q̈ and λ is the KKT solve
(:mod:`pfaff.numeric.kkt`). Two kinds implement the contract:
:class:`pfaff.numeric.model.NumericModel` (any system; dense, or sparse above a few hundred unknowns)
and :class:`pfaff.numeric.structured.StructuredModel` (families of identical pieces, O(N)). The
integrators, the projection and the trajectory use nothing else of a model.

Methods come in two sets. The *checked* ones (``accelerations``, ``constraint_residual``,
``energy``, ...) are for users: they validate their arguments and name a bad one. The *unchecked*
ones (``solve``, ``residual``, ``linearize_constraints``, ``ode_function``, ``evaluate_states``,
``dae_blocks``, ``power_function``) are for the integrators, on states already checked (float t,
float arrays of shape (n,)), where a check would cost more than the evaluation.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from typing import Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sps

Vector = np.ndarray
Power = Callable[[float, np.ndarray, np.ndarray], float]


class ConstraintLinearization(ABC):
    """The constraints at one state, linearized for the projection (:mod:`pfaff.numeric.projection`).

    With f the position residuals (0 on the rows of velocity constraints), g = A q̇ + b and the
    row thresholds τ_i = tol · clip(|A_i| / max_j |A_j|, 1e-4, 1):

    Attributes
    ----------
    position_excess, velocity_excess : float
        max_i |f_i| / τ_i and max_i |g_i| / τ_i: at most 1 means "on the manifold".
    """

    position_excess: float
    velocity_excess: float

    @abstractmethod
    def corrected_positions(self, q: np.ndarray) -> np.ndarray:
        """q − Δ with Δ the least change, in the model's metric, with A Δ = f (a Newton step).

        Models use the mass metric, Δ = M⁻¹Aᵀ(A M⁻¹Aᵀ + δ²I)⁻¹ f (δ: a tiny damping where A
        loses rank).
        """

    @abstractmethod
    def corrected_velocities(self, qd: np.ndarray) -> np.ndarray:
        """q̇ − Δ with A Δ = g, in the same metric."""

    @abstractmethod
    def with_velocities(self, qd: np.ndarray) -> ConstraintLinearization:
        """The same linearization (same q, same A and metric) at other velocities; it may be
        ``self``, updated (the projection never uses the old one again)."""


class OdeFunction:
    """y' = [q̇, q̈] of y = [q, q̇], as SciPy's ``solve_ivp`` solvers take it: ``fun(t, y)``.

    Attributes
    ----------
    on_lists : callable or None
        The same function on lists of floats, ``(t, list) -> list`` (small systems, for
        :class:`pfaff.integrate.fastrk.FloatDOP853`), or None.
    into : callable or None
        The same function writing into a given array, ``(t, y, out) -> None`` (long states, for
        :class:`pfaff.integrate.inplace.InPlaceDOP853`), or None.
    """

    on_lists: Callable[[float, list], list] | None = None
    # into(t, y, out): y' written into out, shape (2n,) (long states,
    # pfaff.integrate.inplace.InPlaceDOP853); None when the field has no such form
    into: Callable[[float, np.ndarray, np.ndarray], None] | None = None

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def accepted(self, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        """Told after every accepted step (a field may update reference sizes); default: nothing."""


@runtime_checkable
class DynamicsModel(Protocol):
    """What every compiled numeric model offers (see the module docstring for the equations).

    Attributes
    ----------
    n, m : int
        Coordinates and constraints (multipliers).
    coordinate_names, multiplier_names, constraint_names : sequence of str
    holonomic : ndarray of bool, shape (m,)
        Which rows are position constraints f = 0.
    parameters : dict
        Parameter name -> value.
    stats : dict
        Counters of the model's work (``kkt_solves``, ...).
    solver : str
        The name of its KKT solver (:mod:`pfaff.numeric.kkt`).
    applied_power : bool
        Whether some applied force can do work.
    inputs : list of str
        Inputs declared with ``System.add_input`` (values per call or per run).
    attitudes : tuple
        Per rigid body (name, attitude kind, coordinate indices, Euler sequence):
        :mod:`pfaff.integrate.events`.
    geometry : object or None
        What animations draw (:mod:`pfaff.derive.geometry`).
    evaluator : str
        Which code evaluates a state (:mod:`pfaff.numeric.evaluator`).
    mass_singular : bool
        M found singular at a run's first state (the run solves the whole KKT matrix).
    sparse_dae : bool
        Whether IDA takes its Newton matrix in CSC from ``dae_newton`` (families) instead of
        assembling a dense one from ``dae_blocks``.
    dae_model : DynamicsModel
        The model whose constraint rows the DAE keeps: the model itself, or a family's without
        a row dependent on the others (the closed ring's last spacing).
    """

    n: int
    m: int
    coordinate_names: Sequence[str]
    multiplier_names: Sequence[str]
    constraint_names: Sequence[str]
    holonomic: np.ndarray
    parameters: Mapping[str, float]
    stats: dict
    solver: str
    inputs: list[str]
    attitudes: tuple
    geometry: object
    evaluator: str
    mass_singular: bool
    sparse_dae: bool
    dae_model: DynamicsModel

    @property
    def applied_power(self) -> bool: ...

    # ------------------------------------------------------------------ checked, for users
    def accelerations(
        self, t: float, q: object, qd: object, *, inputs: dict | None = None
    ) -> tuple[Vector, Vector]:
        """q̈ (n,) and λ (m,) at a state (``inputs``: declared inputs' values for this call)."""
        ...

    def constraint_residual(self, t: float, q: object, qd: object) -> tuple[Vector, Vector]:
        """f (m,) and A q̇ + b (m,) at a state."""
        ...

    def energy(self, t: float, q: object, qd: object) -> tuple[float, float]:
        """Kinetic and potential energy (T, V)."""
        ...

    def mass_matrix(self, t: float, q: object, qd: object | None = None) -> Vector | sps.spmatrix:
        """M, shape (n, n)."""
        ...

    def constraint_matrix(self, t: float, q: object) -> Vector | sps.spmatrix:
        """A, shape (m, n)."""
        ...

    def check_determined(self, t: float, q: object, qd: object) -> None:
        """Raise unless q̈ is determined and the constraints consistent at this state (once per run)."""
        ...

    # ------------------------------------------------------------------ unchecked, for integrators
    def solve(
        self, t: float, q: Vector, qd: Vector, alpha: float = 0.0, beta: float = 0.0
    ) -> tuple[Vector, Vector]:
        """q̈ and λ with the constraint rows A q̈ = −(Ȧq̇ + ḃ) − 2α g − β² f (Baumgarte when α, β > 0)."""
        ...

    def residual(self, t: float, q: Vector, qd: Vector) -> tuple[Vector, Vector]:
        """(f, g) = (f(q, t), A q̇ + b), each shape (m,)."""
        ...

    def linearize_constraints(
        self, t: float, q: Vector, qd: Vector, tol: float
    ) -> ConstraintLinearization:
        """The constraints linearized at a state, for the projection to tolerance ``tol``."""
        ...

    def ode_function(
        self, alpha: float = 0.0, beta: float = 0.0, start: tuple | None = None
    ) -> OdeFunction:
        """The acceleration-level ODE; ``start`` = (t0, q0, q̇0) sets the floor's row sizes."""
        ...

    def evaluate_states(self, t: Vector, q: Vector, qd: Vector) -> dict[str, Vector]:
        """q̈, λ, f, g, T, V, T₀ and T₂ at k states (``t`` (k,), ``q`` and ``qd`` (k, n))."""
        ...

    def dae_blocks(self, t: float, q: Vector, qd: Vector) -> tuple:
        """(M, A, Q − h, f, g) for a DAE residual: M (n, n) and A (m, n) dense or sparse."""
        ...

    def dae_newton(
        self, hrows: Vector, t: float, y: Vector, yp: Vector, algebraic_scale: float = 1.0
    ) -> object:
        """The stabilized index-2 DAE over y = [q, v, λ/s, μ/s] (μ per row of ``hrows``, s the
        ``algebraic_scale``): an object with ``size``, ``pattern`` (CSC), ``residual(t, y, y',
        res)`` and ``jacobian(t, y, y', res, c_j, data)`` (:class:`pfaff.numeric.ggl.GGLNewton`)."""
        ...

    def power_function(self) -> Power:
        """P(t, q, q̇) = Qᵀq̇ of the applied forces, unchecked."""
        ...
