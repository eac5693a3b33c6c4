"""``examples/fourbar_sympy.py``: a closed four-bar of SymPy ``PinJoint``s converted by
``pfaff.from_sympy`` keeps its loop closed (|f| ≤ 1e-10 m) and balances its energy (T(t) − T(0)
equal to the work of SymPy's gravity loads to 1e-8 J) over 1 s; its start is the loop's closed
configuration computed by intersecting two circles (the dependent angles agree with pfaff's
Gauss-Newton completion)."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff


@pytest.fixture(scope="module")
def example(fourbar_example):
    return fourbar_example


def test_closed_state_is_on_the_loop(example):
    model = pfaff.from_sympy(example.fourbar_system()).equations().compile(example.VALUES)
    q, qd = example.closed_state(0.7, 1.0)
    assert np.abs(model.constraint_residual(0.0, q, qd)[0]).max() < 1e-12
    q2, _ = pfaff.consistent_state(model, q + np.array([0, 0.05, -0.05]), qd, independent=[0])
    assert np.abs(q2 - q).max() < 1e-10


def test_run_keeps_the_loop_and_the_energy(example, capsys):
    run = example.main(t_end=1.0)
    assert run.status == "success"
    assert np.abs(run.position_residual).max() < 1e-10
    assert np.abs(run.energy_balance).max() < 1e-8
    assert np.ptp(run.q[:, 0]) > 0.5  # the crank turned
    assert "four-bar" in capsys.readouterr().out
