"""``pfaff.attitude``: attitude coordinate sets of rigid bodies (see :mod:`pfaff.mechanics.attitude`).

Examples
--------
>>> import pfaff
>>> q = pfaff.attitude.Quaternion(pfaff.coordinates("b0:4"))
>>> q.constraint
b0(t)**2 + b1(t)**2 + b2(t)**2 + b3(t)**2 - 1
"""

from pfaff.mechanics.attitude import (
    MRP,
    Attitude,
    EulerAngles,
    PlanarAngle,
    Quaternion,
    Rotation,
    dcm_from,
)

__all__ = ["MRP", "Attitude", "EulerAngles", "PlanarAngle", "Quaternion", "Rotation", "dcm_from"]
