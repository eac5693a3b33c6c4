"""The integration stage: ``simulate``, projection, Baumgarte, IDA, the float DOP853, initial states.

A method of integration is a :class:`Stepper` subclass (:mod:`pfaff.integrate.stepper`), given the
run's :class:`StepperOptions`.
"""

from pfaff.integrate.stepper import Stepper, StepperOptions

__all__ = ["Stepper", "StepperOptions"]
