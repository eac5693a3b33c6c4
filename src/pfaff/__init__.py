"""pfaff: dynamics of constrained mechanical systems.

Describe a system by its coordinates, energies (or particles), constraints and forces; pfaff derives
Lagrange's equations with multipliers, M q̈ + h = Q + Aᵀλ with A q̈ + Ȧq̇ + ḃ = 0, reduces them to
minimal coordinates and compiles them to fast numeric code.

The package is laid out by pipeline stage, imports going only downward (see ARCHITECTURE.md):
:mod:`pfaff.core` < :mod:`pfaff.mechanics` < :mod:`pfaff.numeric` < :mod:`pfaff.derive` <
:mod:`pfaff.results` < :mod:`pfaff.integrate` < :mod:`pfaff.api` < :mod:`pfaff.models` <
:mod:`pfaff.cli`.
"""

from pfaff import attitude, models
from pfaff.api import EquationsOfMotion, RootLocus, Solution, System, root_locus
from pfaff.api.fit import FitResult, fit
from pfaff.api.fromsympy import from_sympy
from pfaff.core.errors import (
    BodyInertiaError,
    ConstraintError,
    InertiaError,
    ModelError,
    ModelTypeError,
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

__all__ = [
    "MRP",
    "Body",
    "BodyInertiaError",
    "ConstraintError",
    "EquationsOfMotion",
    "EulerAngles",
    "Event",
    "EventRecord",
    "FitResult",
    "ForceWork",
    "InertiaError",
    "Linearization",
    "ModelError",
    "ModelFile",
    "ModelFileError",
    "ModelTypeError",
    "NumericModel",
    "OptionError",
    "ParameterError",
    "PfaffError",
    "PlanarAngle",
    "Quaternion",
    "RedundancyWarning",
    "RootLocus",
    "SimulationError",
    "Solution",
    "StateError",
    "Stepper",
    "StepperOptions",
    "System",
    "Trajectory",
    "attitude",
    "consistent_state",
    "coordinates",
    "fit",
    "from_sympy",
    "load_model",
    "load_urdf",
    "models",
    "root_locus",
    "sensitivities",
    "simulate",
    "sweep",
    "t",
]
__version__ = "0.1.0"
