"""The float DOP853: SciPy's OdeSolver contract, SciPy's numbers, and order 8 observed."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import DOP853, DenseOutput, OdeSolver, solve_ivp

from pfaff.integrate.fastrk import FloatDOP853


def _oscillator(t: float, y: np.ndarray) -> np.ndarray:
    return np.array([y[1], -y[0]])


def test_is_a_scipy_solver_usable_by_solve_ivp() -> None:
    """solve_ivp drives it like any OdeSolver: SciPy's DOP853's step count and answers."""
    kw = {"rtol": 1e-10, "atol": 1e-12, "dense_output": True}
    ours = solve_ivp(_oscillator, (0, 10), [0.0, 1.0], method=FloatDOP853, **kw)
    ref = solve_ivp(_oscillator, (0, 10), [0.0, 1.0], method=DOP853, **kw)
    assert issubclass(FloatDOP853, OdeSolver) and ours.status == 0
    assert abs(len(ours.t) - len(ref.t)) <= 2  # the same controller (rounding may shift a step)
    np.testing.assert_allclose(ours.y[:, -1], ref.y[:, -1], atol=1e-9)
    ts = np.linspace(0, 10, 37)
    np.testing.assert_allclose(ours.sol(ts), ref.sol(ts), atol=1e-9)
    np.testing.assert_allclose(ours.sol(ts)[0], np.sin(ts), atol=1e-9)


def test_dense_output_is_scipy_dense_output() -> None:
    s = FloatDOP853(_oscillator, 0.0, [0.0, 1.0], 1.0, rtol=1e-10, atol=1e-12)
    s.step()
    d = s.dense_output()
    assert isinstance(d, DenseOutput) and d(s.t).shape == (2,)
    np.testing.assert_allclose(d(s.t), s.y, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(d(s.t_old), [0.0, 1.0], atol=1e-15)


@pytest.mark.parametrize(("kw", "match"), [({"max_step": 0.0}, "max_step"),
                                           ({"first_step": -1.0}, "first_step"),
                                           ({"first_step": 5.0}, "first_step")])  # fmt: skip
def test_bad_step_options(kw: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        FloatDOP853(_oscillator, 0.0, [0.0, 1.0], 1.0, **kw)


def test_convergence_order_eight() -> None:
    """Fixed steps h (max_step = first_step = h, tolerances too loose to reject): the error at
    t = 2 of y' = (y₂, −y₁) against sin, cos falls as h⁸."""
    errors, hs = [], [1.0, 1 / 2, 1 / 4, 1 / 8]  # at 1/16 the error reaches rounding
    for h in hs:
        s = FloatDOP853(
            _oscillator, 0.0, [0.0, 1.0], 2.0, rtol=1e3, atol=1e3, max_step=h, first_step=h
        )
        while s.status == "running":
            s.step()
        assert s.t == 2.0
        errors.append(math.hypot(s.y[0] - math.sin(2.0), s.y[1] - math.cos(2.0)))
    orders = np.diff(np.log(errors)) / np.diff(np.log(hs))
    assert np.all(orders > 7.5) and np.all(orders < 9.0), orders
