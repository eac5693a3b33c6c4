"""Converged central differences: the reference of the sensitivity tests."""

from __future__ import annotations

import numpy as np


def stencil(f, x0: float, h: float) -> np.ndarray:
    """Fourth-order central difference of f at x0 with step h."""
    a, b, c, d = (f(x0 + s * h) for s in (-2, -1, 1, 2))
    return (a - 8 * b + 8 * c - d) / (12 * h)


def converged(f, x0: float) -> np.ndarray:
    """The central difference with relative step 1e-3, checked against the one with 2e-3 (they
    must agree to 2e-7 of the column's size, well inside the 1e-6 the tests compare with)."""
    h = 1e-3 * max(1.0, abs(x0))
    d1, d2 = stencil(f, x0, h), stencil(f, x0, 2 * h)
    assert np.abs(d1 - d2).max() <= 2e-7 * np.abs(d1).max()
    return d1


def close(exact: np.ndarray, reference: np.ndarray, rel: float = 1e-6) -> bool:
    """Agreement to ``rel`` of the reference's largest entry."""
    return bool(np.abs(exact - reference).max() <= rel * np.abs(reference).max())
