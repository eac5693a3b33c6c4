"""pfaff: dynamics of constrained mechanical systems.

Describe a system by its coordinates, energies (or particles), constraints and forces; pfaff derives
Lagrange's equations with multipliers, M q̈ + h = Q + Aᵀλ with A q̈ + Ȧq̇ + ḃ = 0, reduces them to
minimal coordinates and compiles them to fast numeric code.

The package is laid out by pipeline stage, imports going only downward (see ARCHITECTURE.md):
:mod:`pfaff.core` < :mod:`pfaff.mechanics` < :mod:`pfaff.numeric` < :mod:`pfaff.derive` <
:mod:`pfaff.results` < :mod:`pfaff.integrate` < :mod:`pfaff.api` < :mod:`pfaff.models` <
:mod:`pfaff.cli`.

``import pfaff`` imports only this table: each public name is imported from its stage on first use
(:mod:`pfaff.core.exports`), so that the command line is running, its interrupt path in place,
before anything heavy loads.
"""

# ruff: noqa: F401  (the imports under TYPE_CHECKING are for type checkers: __all__ is the table)

import importlib
from typing import TYPE_CHECKING

from pfaff.core.exports import lazy_exports

# each public name and the module it comes from, imported when first used
_EXPORTS = {
    "EquationsOfMotion": "pfaff.api",
    "RootLocus": "pfaff.api",
    "Solution": "pfaff.api",
    "System": "pfaff.api",
    "root_locus": "pfaff.api",
    "FitResult": "pfaff.api.fit",
    "fit": "pfaff.api.fit",
    "from_sympy": "pfaff.api.fromsympy",
    "attitude": "pfaff.attitude",
    "BodyInertiaError": "pfaff.core.errors",
    "ConstraintError": "pfaff.core.errors",
    "InertiaError": "pfaff.core.errors",
    "KeywordError": "pfaff.core.errors",
    "LongRunWarning": "pfaff.core.errors",
    "ModelError": "pfaff.core.errors",
    "ModelTypeError": "pfaff.core.errors",
    "ModelWarning": "pfaff.core.errors",
    "OptionError": "pfaff.core.errors",
    "ParameterError": "pfaff.core.errors",
    "PfaffError": "pfaff.core.errors",
    "RedundancyWarning": "pfaff.core.errors",
    "SimulationError": "pfaff.core.errors",
    "StateError": "pfaff.core.errors",
    "Event": "pfaff.core.events",
    "EventRecord": "pfaff.core.events",
    "coordinates": "pfaff.core.symbols",
    "t": "pfaff.core.symbols",
    "ForceWork": "pfaff.derive.work",
    "consistent_state": "pfaff.integrate.initial",
    "sensitivities": "pfaff.integrate.sensitivity",
    "simulate": "pfaff.integrate.simulation",
    "Stepper": "pfaff.integrate.stepper",
    "StepperOptions": "pfaff.integrate.stepper",
    "EulerAngles": "pfaff.mechanics.attitude",
    "MRP": "pfaff.mechanics.attitude",
    "PlanarAngle": "pfaff.mechanics.attitude",
    "Quaternion": "pfaff.mechanics.attitude",
    "Body": "pfaff.mechanics.bodies",
    "ModelFile": "pfaff.modelfile",
    "ModelFileError": "pfaff.modelfile",
    "load_model": "pfaff.modelfile",
    "load_urdf": "pfaff.modelfile.urdf",
    "models": "pfaff.models",
    "NumericModel": "pfaff.numeric",
    "Linearization": "pfaff.numeric.linearization",
    "Trajectory": "pfaff.results.trajectory",
    "sweep": "pfaff.sweep.driver",
}
__all__ = sorted(_EXPORTS)
__version__ = "0.1.0"
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

# the subpackage pfaff.sweep and the function pfaff.sweep share a name: the package is imported
# now (it is as light as this one), and its import binds the name to it, which goes: no later
# import sets it again, and the name is the function once used
importlib.import_module("pfaff.sweep")
del globals()["sweep"]

if TYPE_CHECKING:  # the same names, for type checkers and editors
    from pfaff import attitude, models
    from pfaff.api import EquationsOfMotion, RootLocus, Solution, System, root_locus
    from pfaff.api.fit import FitResult, fit
    from pfaff.api.fromsympy import from_sympy
    from pfaff.core.errors import (
        BodyInertiaError,
        ConstraintError,
        InertiaError,
        KeywordError,
        LongRunWarning,
        ModelError,
        ModelTypeError,
        ModelWarning,
        OptionError,
        ParameterError,
        PfaffError,
        RedundancyWarning,
        SimulationError,
        StateError,
    )
    from pfaff.core.events import Event, EventRecord
    from pfaff.core.symbols import coordinates, t
    from pfaff.derive.work import ForceWork
    from pfaff.integrate.initial import consistent_state
    from pfaff.integrate.sensitivity import sensitivities
    from pfaff.integrate.simulation import simulate
    from pfaff.integrate.stepper import Stepper, StepperOptions
    from pfaff.mechanics.attitude import MRP, EulerAngles, PlanarAngle, Quaternion
    from pfaff.mechanics.bodies import Body
    from pfaff.modelfile import ModelFile, ModelFileError, load_model
    from pfaff.modelfile.urdf import load_urdf
    from pfaff.numeric import NumericModel
    from pfaff.numeric.linearization import Linearization
    from pfaff.results.trajectory import Trajectory
    from pfaff.sweep import sweep
