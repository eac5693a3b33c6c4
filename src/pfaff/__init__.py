"""pfaff: dynamics of constrained mechanical systems.

Describe a system by its coordinates, energies (or particles), constraints and forces; pfaff derives
Lagrange's equations with multipliers, M q̈ + h = Q + Aᵀλ with A q̈ + Ȧq̇ + ḃ = 0, reduces them to
minimal coordinates and compiles them to fast numeric code.

The package is laid out by pipeline stage, imports going only downward (see ARCHITECTURE.md):
:mod:`pfaff.core` < :mod:`pfaff.mechanics` < :mod:`pfaff.numeric` < :mod:`pfaff.derive` <
:mod:`pfaff.results` < :mod:`pfaff.integrate` < :mod:`pfaff.api` < :mod:`pfaff.models` <
:mod:`pfaff.cli`.
"""

from pfaff import models
from pfaff.api import EquationsOfMotion, Solution, System
from pfaff.core.errors import (
    ConstraintError,
    InertiaError,
    ModelError,
    ModelTypeError,
    OptionError,
    ParameterError,
    PfaffError,
    SimulationError,
    StateError,
)
from pfaff.core.symbols import coordinates, t
from pfaff.derive.work import ForceWork
from pfaff.integrate.initial import consistent_state
from pfaff.integrate.simulation import simulate
from pfaff.numeric import NumericModel
from pfaff.results.trajectory import Trajectory

__all__ = [
    "ConstraintError",
    "EquationsOfMotion",
    "ForceWork",
    "InertiaError",
    "ModelError",
    "ModelTypeError",
    "NumericModel",
    "OptionError",
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
