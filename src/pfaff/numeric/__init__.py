"""The numeric stage: compiled kernels, numeric models and KKT solvers. No SymPy here.

:class:`NumericModel` (general systems) and :class:`pfaff.numeric.structured.StructuredModel`
(families, O(N) solves) are built by the derivation stage's compiler from generated functions and
index arrays; both implement :class:`pfaff.numeric.protocol.DynamicsModel`, all the integrators use.
"""

from pfaff.numeric.checks import check_state
from pfaff.numeric.model import NumericModel
from pfaff.numeric.protocol import DynamicsModel

__all__ = ["DynamicsModel", "NumericModel", "check_state"]
