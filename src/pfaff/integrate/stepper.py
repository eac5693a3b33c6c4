"""The stepping contract of :func:`pfaff.simulate`: :class:`Stepper` and its :class:`StepperOptions`.

A method of integration is a :class:`Stepper` subclass. The driver (:mod:`pfaff.integrate.simulation`)
makes one from a consistent initial state, calls :meth:`Stepper.step` until :attr:`Stepper.t`
reaches the end of the span, reads the states and the work of the applied forces of each step, and
sums :meth:`Stepper.finish`'s statistics. It uses nothing else of a stepper; what differs between
methods is declared by class attributes (:attr:`Stepper.projects_steps`,
:attr:`Stepper.reports_drift`), never by the method's name or class.

A failure of the run (an integrator giving up, a step size underflowing) is :meth:`Stepper.fail`:
the run ends with status "failed" and the message. Any other exception a stepper raises propagates
out of :func:`pfaff.simulate` unchanged, except for the numerical errors of the model's equations
(non-finite accelerations, a singular KKT system, a math domain error in the generated code), which
also end the run as "failed".
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, NoReturn

import numpy as np

if TYPE_CHECKING:
    from pfaff.numeric.projection import Projector
    from pfaff.numeric.protocol import DynamicsModel

Power = Callable[[float, np.ndarray, np.ndarray], float]  # P(t, q, q̇) of the applied forces


class _RunFailure(Exception):
    """A run that cannot go on: only the driver of :func:`pfaff.simulate` catches it, as status
    "failed" with the message "failed at t = ...: <message>".

    ``hint``: the driver may add that Euler angles are near their singularity (an integrator
    giving up there); ``verb`` is the message's first word.
    """

    verb = "failed"

    def __init__(self, message: str, hint: bool = True) -> None:
        super().__init__(message)
        self.hint = hint


@dataclass(frozen=True)
class StepperOptions:
    """The options of :func:`pfaff.simulate` a stepper reads (checked by ``simulate``).

    Attributes
    ----------
    rtol, atol : float
        Relative and absolute tolerances of the local error, > 0.
    max_step : float or None
        Largest step; None: no limit.
    first_step : float or None
        First step size; None: the integrator's own choice.
    integrator : str
        Runge–Kutta method of "projection" and "baumgarte": "DOP853", "RK45" or "RK23".
    alpha, beta : float
        Baumgarte gains (1/time) of A q̈ + Ȧq̇ + ḃ = −2α(A q̇ + b) − β² f.
    ida_jacobian : {"fd", "approximate"} or None
        IDA's Newton matrix; None: by the size of the system.

    Examples
    --------
    >>> opts = StepperOptions(rtol=1e-8, atol=1e-10)
    >>> opts.integrator, opts.max_step
    ('DOP853', None)
    """

    rtol: float = 1e-9
    atol: float = 1e-11
    max_step: float | None = None
    first_step: float | None = None
    integrator: str = "DOP853"
    alpha: float = 10.0
    beta: float = 10.0
    ida_jacobian: str | None = None

    def step_sizes(self) -> dict[str, float]:
        """``max_step`` and ``first_step`` as keywords for SciPy or IDA, those that are set."""
        sizes = {"max_step": self.max_step, "first_step": self.first_step}
        return {k: v for k, v in sizes.items() if v is not None}


class Stepper(abc.ABC):
    """One method of integration, driven one step at a time by :func:`pfaff.simulate`.

    It advances y = [q, q̇] of M q̈ + h = Q + Aᵀλ, A q̈ + Ȧq̇ + ḃ = 0 (the model's
    :class:`pfaff.numeric.protocol.DynamicsModel`) from a state on f = 0, A q̇ + b = 0. Pass a
    subclass (the class, not an instance) as ``simulate(method=...)``; the driver constructs it
    as ``cls(model, t0, q0, qd0, t_end, options, projector)`` at the start of the run and again
    after every restart (an MRP switch), and uses exactly the members below.

    Class attributes
    ----------------
    name : str
        The method's name in :attr:`pfaff.Trajectory.method` (default: the class name).
    projects_steps : bool
        Its steps end on the constraint manifold (it projects them itself): the driver does not
        project the states it records after each step.
    reports_drift : bool
        Its constraint drift is part of what a run reports (Baumgarte): reported states are not
        projected unless ``simulate(project_output=True)``.

    Examples
    --------
    A method that wraps another one, here to count its steps:

    >>> import pfaff
    >>> from pfaff.integrate.integrators import ProjectedRK
    >>> class Counted(ProjectedRK):
    ...     name = "counted"
    ...     calls = 0
    ...     def step(self) -> None:
    ...         type(self).calls += 1
    ...         super().step()
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> traj = pfaff.simulate(model, [0.0, -1.0], [1.0, 0.0], (0, 1), method=Counted)
    >>> traj.method, traj.status, Counted.calls == traj.stats["steps"]
    ('counted', 'success', True)
    """

    name: ClassVar[str] = ""
    projects_steps: ClassVar[bool] = False
    reports_drift: ClassVar[bool] = False

    def __init_subclass__(cls, **kw: object) -> None:
        super().__init_subclass__(**kw)
        if not cls.__dict__.get("name"):
            cls.name = cls.__name__

    @abc.abstractmethod
    def __init__(
        self,
        model: DynamicsModel,
        t0: float,
        q0: np.ndarray,
        qd0: np.ndarray,
        t_end: float,
        options: StepperOptions,
        projector: Projector,
    ) -> None:
        """Start at the consistent state (t0, q0 (n,), q̇0 (n,)); integrate no further than
        ``t_end``. ``projector`` projects a state onto the constraints (``projector(t, q, qd)``
        → (q, q̇, changed)); a method uses it or not."""

    @property
    @abc.abstractmethod
    def t(self) -> float:
        """The time reached: the end of the last accepted step."""

    @abc.abstractmethod
    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """(q, q̇) at :attr:`t`, each shape (n,)."""

    @abc.abstractmethod
    def step(self) -> None:
        """Take one accepted step (its own size, ending no later than ``t_end``); call
        :meth:`fail` when the method cannot go on."""

    @abc.abstractmethod
    def dense(self, ts: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """(q, q̇), each shape (n,), at the times ``ts`` (k,) inside the last step (before any
        projection of its end point; the driver projects what it reports)."""

    @abc.abstractmethod
    def step_work(self, power: Power) -> float:
        """∫ P dt over the last step, P = Qᵀq̇ the power of the applied forces
        (:mod:`pfaff.integrate.work` has quadratures on a step's ends or dense output)."""

    @abc.abstractmethod
    def work_until(self, power: Power, b: float) -> float:
        """∫ P dt from the start of the last step to ``b`` inside it."""

    @abc.abstractmethod
    def finish(self) -> dict[str, int | float | None]:
        """The run's statistics: at least "steps", "rejected" (None when unknown) and "nfev"."""

    @staticmethod
    def fail(message: str) -> NoReturn:
        """End the run: :func:`pfaff.simulate` returns status "failed" with ``message`` (or
        raises :class:`pfaff.SimulationError` with ``throw=True``)."""
        raise _RunFailure(message)
