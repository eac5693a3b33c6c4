"""pfaff: dynamics of constrained mechanical systems.

Describe a system by its coordinates, energies (or particles), constraints and forces; pfaff derives
Lagrange's equations with multipliers, M q̈ + h = Q + Aᵀλ with A q̈ + Ȧq̇ + ḃ = 0, reduces them to
minimal coordinates and compiles them to fast numeric code.
"""

from . import models
from .equations import EquationsOfMotion, Solution
from .errors import (
    ConstraintError,
    ModelError,
    ModelTypeError,
    ParameterError,
    PfaffError,
    SimulationError,
    StateError,
)
from .initial import consistent_state
from .numeric import NumericModel
from .simulation import simulate
from .symbols import coordinates, t
from .system import System
from .trajectory import Trajectory
from .work import ForceWork

__all__ = [
    "ConstraintError",
    "EquationsOfMotion",
    "ForceWork",
    "ModelError",
    "ModelTypeError",
    "NumericModel",
    "ParameterError",
    "PfaffError",
    "SimulationError",
    "Solution",
    "StateError",
    "System",
    "Trajectory",
    "consistent_state",
    "coordinates",
    "models",
    "simulate",
    "t",
]
__version__ = "0.1.0"
