"""Exceptions raised by pfaff.

Every error a user can trigger derives from :class:`PfaffError`, a ``ValueError``. Errors about the
*kind* of an object (a coordinate that is not a function of time, a force that is not a vector) also
derive from ``TypeError``, so either ``except`` clause catches them.
"""

from __future__ import annotations

__all__ = [
    "ConstraintError",
    "ModelError",
    "ModelTypeError",
    "OptionError",
    "ParameterError",
    "PfaffError",
    "SimulationError",
    "StateError",
]


class PfaffError(ValueError):
    """Base class of every error pfaff raises on bad input."""


class ModelError(PfaffError):
    """The model description is invalid (coordinates, particles, energies, forces)."""


class ModelTypeError(ModelError, TypeError):
    """An argument is of the wrong kind (e.g. a coordinate that is not a function of ``t``)."""


class ConstraintError(PfaffError):
    """A constraint is malformed, not Pfaffian, redundant or inconsistent."""


class ParameterError(PfaffError):
    """Numeric parameter values are missing, unknown or not finite."""


class StateError(PfaffError):
    """A numeric state (t, q, q̇) has the wrong shape or is not finite."""


class OptionError(StateError):
    """An option of a numeric entry point (a tolerance, a method, a step size) is invalid.

    A :class:`StateError` too, for code written before options had their own class.
    """


class SimulationError(PfaffError, RuntimeError):
    """A simulation failed (raised by ``simulate(..., throw=True)``; otherwise a status)."""
