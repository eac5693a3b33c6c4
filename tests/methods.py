"""The one tuple of simulation methods every test parametrizes over, so that a new method
(a name in :data:`pfaff.integrate.simulation.METHODS`) gets the whole suite."""

from __future__ import annotations

import pytest

ALL_METHODS: tuple[str, ...] = ("projection", "baumgarte", "ida")
# the same, IDA's case in the full suite only (where it takes a second: `-m "not slow"` stays short)
IDA_SLOW: tuple = tuple(
    pytest.param(m, marks=pytest.mark.slow) if m == "ida" else m for m in ALL_METHODS
)
