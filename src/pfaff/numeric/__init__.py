"""The numeric stage: compiled kernels, numeric models and KKT solvers. No SymPy here.

:class:`NumericModel` (general systems) and :class:`pfaff.numeric.structured.StructuredModel`
(families, O(N) solves) are built by the derivation stage's compiler from generated functions and
index arrays; the integrators use them.
"""

from pfaff.numeric.backsub import multipliers_by_back_substitution
from pfaff.numeric.checks import check_state
from pfaff.numeric.model import NumericModel

__all__ = ["NumericModel", "check_state", "multipliers_by_back_substitution"]
