"""Compatibility: pfaff's exceptions live in :mod:`pfaff.core.errors` (also at the top level)."""

from pfaff.core.errors import *  # noqa: F403
from pfaff.core.errors import __all__  # noqa: F401
