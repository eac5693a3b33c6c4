"""pfaff.root_locus: eigenvalues over one parameter, from a dict or a function of the value."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff


def test_pendulum_locus_over_a_parameter() -> None:
    eom = pfaff.models.pendulum().equations()
    th = eom.coordinates[0]
    g = np.array([1.0, 4.0, 9.0])
    values, eig, fig = pfaff.root_locus(eom, {th: 0, "m": 1, "L": 1}, [th], vary={"g": g})
    assert eig.shape == (3, 2)
    np.testing.assert_allclose(eig.imag, np.c_[-np.sqrt(g), np.sqrt(g)], rtol=1e-14)
    np.testing.assert_array_equal(values, g)
    assert len(fig.axes) == 2


def test_symbol_in_the_operating_point() -> None:
    """The varied symbol may appear in the operating point's values: a pendulum turned by a
    constant angle a from the bottom is no equilibrium unless a = 0, π."""
    eom = pfaff.models.pendulum().equations()
    th = eom.coordinates[0]
    a = sp.Symbol("a")
    res = pfaff.root_locus(eom, {th: a, "m": 1, "L": 1, "g": 4}, [th], vary={a: [0.0, np.pi]})
    np.testing.assert_allclose(res.eigenvalues[0], [-2j, 2j], atol=1e-12)
    np.testing.assert_allclose(res.eigenvalues[1], [-2, 2], atol=1e-12)


def test_bad_vary() -> None:
    eom = pfaff.models.pendulum().equations()
    th = eom.coordinates[0]
    with pytest.raises(pfaff.ModelTypeError, match="`vary`"):
        pfaff.root_locus(eom, {th: 0}, [th], vary={"g": [1], "L": [2]})
    with pytest.raises(pfaff.ModelError, match="finite"):
        pfaff.root_locus(eom, {th: 0}, [th], vary={"g": [np.inf]})


def test_vary_refuses_strings_and_names_the_model_lacks() -> None:
    """A string value used to be read as a number by NumPy, and a name the model does not have
    gave the same eigenvalues at every value: both refused, named."""
    eom = pfaff.models.pendulum().equations()
    th = eom.coordinates[0]
    point = {th: 0, "m": 1, "L": 1, "g": 4}
    for bad in (["1", "4"], [True, False], [1 + 2j]):
        with pytest.raises(pfaff.ModelTypeError, match=r"`vary\['g'\]` must be real numbers"):
            pfaff.root_locus(eom, {th: 0, "m": 1, "L": 1}, [th], vary={"g": bad})
    with pytest.raises(pfaff.ModelError, match=r"`k` is not a parameter of the model .*L, g, m"):
        pfaff.root_locus(eom, point, [th], vary={"k": [1.0, 2.0]})
