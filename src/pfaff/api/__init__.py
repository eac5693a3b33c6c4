"""The user's façade: :class:`System` and :class:`EquationsOfMotion`, on top of the stages they call.

Nothing below imports this package: the model stage (:mod:`pfaff.mechanics`) holds the data, the
derivation stage (:mod:`pfaff.derive`) the symbolic work, the numeric stage (:mod:`pfaff.numeric`)
the compiled model. These classes add the methods that chain them.
"""

from pfaff.api.equations import EquationsOfMotion, Solution
from pfaff.api.locus import RootLocus, root_locus
from pfaff.api.system import System

__all__ = ["EquationsOfMotion", "RootLocus", "Solution", "System", "root_locus"]
