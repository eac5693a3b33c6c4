"""The one tuple of simulation methods every test parametrizes over, so that a new method
(a name in :data:`pfaff.integrate.simulation.METHODS`) gets the whole suite."""

from __future__ import annotations

ALL_METHODS: tuple[str, ...] = ("projection", "baumgarte", "ida")
