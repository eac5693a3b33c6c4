"""Exceptions raised by pfaff.

Every error a user can trigger derives from :class:`PfaffError`, a ``ValueError``. Errors about the
*kind* of an object (a coordinate that is not a function of time, a force that is not a vector) also
derive from ``TypeError``, so either ``except`` clause catches them.
"""

from __future__ import annotations

import types

__all__ = [
    "ConstraintError",
    "InertiaError",
    "KeywordError",
    "LongRunWarning",
    "ModelError",
    "ModelTypeError",
    "ModelWarning",
    "OptionError",
    "ParameterError",
    "PfaffError",
    "RedundancyWarning",
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


class InertiaError(ConstraintError):
    """M is not positive definite on the admissible motions at a state.

    Some acceleration is undetermined (a coordinate without inertia that no constraint fixes) or
    the kinetic energy is negative along an admissible motion (a negative mass or inertia). The
    message names the coordinates that span the offending direction.
    """


class BodyInertiaError(ModelError, InertiaError):
    """A rigid body's inertia is impossible: not symmetric, not positive definite, or principal
    moments violating the triangle inequality (both a model error and an inertia error)."""


class ParameterError(PfaffError):
    """Numeric parameter values are missing, unknown or not finite."""


class StateError(PfaffError):
    """A numeric state (t, q, q̇) has the wrong shape or is not finite."""


class OptionError(PfaffError):
    """An option of a numeric entry point (a tolerance, a method, a step size) is invalid.

    Not a :class:`StateError`: a state is what a run starts from or computes, an option how it
    is computed.
    """


class KeywordError(OptionError, TypeError):
    """A public function or method was called with a keyword it does not have (named, with the
    closest valid one and the full list). Also a ``TypeError``, as Python's own would be."""


class RedundancyWarning(UserWarning):
    """Some constraints depend on one another: the motion is still determined, but on those rows
    only Aᵀλ is; pfaff reports the minimum-norm multipliers (``model.redundancy`` names the
    indeterminate directions)."""


class LongRunWarning(UserWarning):
    """A run without ``t_eval`` whose recorded states, at its measured pace, would need more memory
    than is reasonable (the estimate is in the message): pass ``t_eval`` to bound it."""


class ModelWarning(UserWarning):
    """Something in a model is declared but has no effect: a parameter of a model file that no
    expression uses (its value is ignored), an input that nothing uses. The message names it."""


class SimulationError(PfaffError, RuntimeError):
    """A simulation failed (raised by ``simulate(..., throw=True)``; otherwise a status)."""


GENERATED_PREFIXES = ("<lambdifygenerated", "<pfaff.")


def raised_in_generated_code(e: BaseException) -> bool:
    """True when ``e`` was raised in code pfaff generated from the user's equations.

    A ``ValueError`` or ``ArithmeticError`` there (``math.sqrt`` of a negative value, an overflow,
    a division by zero) means the equations are not defined at that state: a failure to report.
    Anywhere else it is a bug, to be raised as such.
    """
    tb: types.TracebackType | None = e.__traceback__
    last = None
    while tb is not None:
        last, tb = tb, tb.tb_next
    return last is not None and last.tb_frame.f_code.co_filename.startswith(GENERATED_PREFIXES)


def undefined_at(e: BaseException, t: float) -> StateError:
    """The :class:`StateError` for ``e``, raised in generated code evaluated at time ``t``.

    Examples
    --------
    >>> str(undefined_at(OverflowError(34, "Numerical result out of range"), 0.5))
    'the equations are not defined at t = 0.5: a value overflowed the floating-point range (OverflowError: Numerical result out of range)'
    """
    if isinstance(e, OverflowError):
        what = "a value overflowed the floating-point range"
    elif isinstance(e, ZeroDivisionError):
        what = "a division by zero"
    elif isinstance(e, ValueError):
        what = "a math domain error (the square root or logarithm of a negative value?)"
    else:
        what = "an arithmetic error"
    detail = e.args[-1] if len(e.args) == 2 and isinstance(e.args[0], int) else e  # (errno, text)
    return StateError(
        f"the equations are not defined at t = {t:.17g}: {what} ({type(e).__name__}: {detail})"
    )
