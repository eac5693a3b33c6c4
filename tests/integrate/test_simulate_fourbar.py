"""A parallelogram four-bar through its flat (rank-deficient) configurations.

Ground pivots O = (0, 0) and P = (L, 0); crank OA of length a at angle θ1, coupler AB of length L
at angle θ2, rocker PB of length a at angle θ3. Loop closure:

    a cos θ1 + L cos θ2 - L - a cos θ3 = 0,    a sin θ1 + L sin θ2 - a sin θ3 = 0.

Uniform rods (crank and rocker about their pivots, I = m a²/3; coupler about its centre,
I = m L²/12) under gravity g along -y. On the parallelogram branch θ2 = 0, θ3 = θ1 = θ the coupler
translates, so by hand T = ½ (m1/3 + m3/3 + m2) a² θ̇² and V = (m1/2 + m2 + m3/2) g a sin θ, i.e.

    (m1/3 + m3/3 + m2) a θ̈ = -(m1/2 + m2 + m3/2) g cos θ.

At θ = 0 and π all links are collinear: the first row of A = ∂f/∂q, [-a sin θ1, -L sin θ2,
a sin θ3], vanishes and the Jacobian loses rank. Both branches (parallelogram and
anti-parallelogram) meet there; the velocity (θ̇, 0, θ̇) selects the parallelogram one.
"""

from __future__ import annotations

import itertools
import math
import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pfaff
from methods import ALL_METHODS

P = dict(pfaff.models.FOURBAR)
TH0, W0, T_END = 0.3, 8.0, 2.0  # passes θ = π, 2π, 3π, 4π (≈ 2.3 turns)
INERTIA = (P["m1"] / 3 + P["m3"] / 3 + P["m2"]) * P["a"] ** 2
GRAVITY_TORQUE = (P["m1"] / 2 + P["m2"] + P["m3"] / 2) * P["g"] * P["a"]


def four_bar() -> pfaff.System:
    return pfaff.models.parallelogram_fourbar()


@pytest.fixture(scope="module")
def model() -> pfaff.NumericModel:
    return four_bar().equations().compile(P)


def reference(t_eval: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """θ, θ̇ of the one-coordinate branch model, DOP853 at tight tolerances."""
    sol = solve_ivp(
        lambda t, y: [y[1], -GRAVITY_TORQUE * math.cos(y[0]) / INERTIA],
        (0.0, float(t_eval[-1])),
        [TH0, W0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        t_eval=t_eval,
    )
    assert sol.success
    return sol.y[0], sol.y[1]


def fold_times() -> np.ndarray:
    """Times at which θ passes a multiple of π (the flat configurations)."""
    te = np.linspace(0.0, T_END, 20001)
    th, _ = reference(te)
    k = np.floor(th / math.pi)
    return te[1:][np.diff(k) > 0]


def test_reference_passes_several_folds() -> None:
    assert len(fold_times()) >= 4


def test_accelerations_on_branch(model: pfaff.NumericModel) -> None:
    """Away from the folds, q̈ = (θ̈, 0, θ̈) with θ̈ from the hand-derived branch equation."""
    for th, w in [(0.3, 8.0), (1.2, -3.0), (2.5, 0.0), (4.0, 5.0)]:
        qdd, _ = model.accelerations(0.0, [th, 0.0, th], [w, 0.0, w])
        expected = -GRAVITY_TORQUE * math.cos(th) / INERTIA
        np.testing.assert_allclose(qdd, [expected, 0.0, expected], atol=1e-10)


def _check_branch(traj: pfaff.Trajectory, te: np.ndarray, tol: float) -> None:
    th, w = reference(te)
    assert len(traj) == len(te)
    assert np.abs(traj.q[:, 1]).max() < tol, "left the branch: θ2 != 0"
    assert np.abs(traj.q[:, 2] - traj.q[:, 0]).max() < tol, "left the branch: θ3 != θ1"
    assert np.abs(traj.q[:, 0] - th).max() < tol
    assert np.abs(traj.qd[:, 0] - w).max() < 1e3 * tol


@pytest.mark.parametrize("method", ALL_METHODS)
def test_before_first_fold(model: pfaff.NumericModel, method: str) -> None:
    """Every method follows the branch up to (just before) the first flat configuration."""
    t1 = 0.98 * fold_times()[0]
    te = np.linspace(0.0, t1, 41)
    traj = pfaff.simulate(
        model, [TH0, 0.0, TH0], [W0, 0.0, W0], (0.0, t1), method=method, t_eval=te
    )
    assert traj.status == "success"
    _check_branch(traj, te, 1e-6)


def test_projection_does_not_stall(model: pfaff.NumericModel) -> None:
    """Through the folds the projection run finishes in a reasonable number of steps."""
    traj = pfaff.simulate(model, [TH0, 0.0, TH0], [W0, 0.0, W0], (0.0, T_END), method="projection")
    assert traj.status == "success"
    assert traj.t[-1] == T_END
    assert traj.stats["steps"] < 20_000
    assert np.abs(traj.constraint_residual).max() < 1e-10


def test_accelerations_at_the_fold(model: pfaff.NumericModel) -> None:
    """At θ = π exactly A has rank 1; the floored solve still gives the branch's q̈, and near it
    the exact one to rounding (the floor of a single state is at rounding level)."""
    for th in [math.pi, math.pi - 1e-7, math.pi + 1e-4, 0.0, 2 * math.pi - 1e-6]:
        for w in [0.0, 8.0]:
            qdd, lam = model.accelerations(0.0, [th, 0.0, th], [w, 0.0, w])
            expected = -GRAVITY_TORQUE * math.cos(th) / INERTIA
            np.testing.assert_allclose(qdd, [expected, 0.0, expected], atol=1e-12)
            assert np.isfinite(lam).all()


def _run_through_folds(model, method: str, **kw) -> tuple[pfaff.Trajectory, np.ndarray]:
    te = np.linspace(0.0, T_END, 201)
    traj = pfaff.simulate(
        model, [TH0, 0.0, TH0], [W0, 0.0, W0], (0.0, T_END), method=method, t_eval=te, **kw
    )
    return traj, te


def test_projection_through_folds_on_branch(model: pfaff.NumericModel) -> None:
    """The default method passes four flat configurations on the parallelogram branch.

    The floored KKT solve keeps the accelerations bounded at the folds, and the mass-orthogonal
    projection after every step restores the constraint impulse the floor softened.
    """
    traj, te = _run_through_folds(model, "projection")
    assert traj.status == "success", traj.message
    _check_branch(traj, te, 1e-6)
    assert np.abs(traj.constraint_residual).max() < 1e-10
    E = traj.energy
    assert np.abs(E - E[0]).max() < 1e-6 * abs(E[0])


def test_projection_through_folds_tight(model: pfaff.NumericModel) -> None:
    """Tighter tolerances give a more accurate branch through the folds (no floor artefact)."""
    for rtol in (5e-13, 1e-12, 2e-12):
        traj, te = _run_through_folds(model, "projection", rtol=rtol, atol=rtol / 100)
        assert traj.status == "success", traj.message
        _check_branch(traj, te, 1e-9)


def test_baumgarte_through_folds_on_branch(model: pfaff.NumericModel) -> None:
    """Baumgarte follows the branch when its stabilization is fast against the motion.

    Nothing projects the state here, so the drift the folds leave must decay before the next fold
    (0.35 s apart at this speed): α = β = 30 does that; the default α = β = 10 does not and the
    linkage ends on the anti-parallelogram branch at the third fold, which its constraint residual
    (about 1e-4) shows.
    """
    traj, te = _run_through_folds(model, "baumgarte", alpha=30.0, beta=30.0)
    assert traj.status == "success", traj.message
    _check_branch(traj, te, 1e-6)
    assert np.abs(traj.constraint_residual).max() < 1e-8


def test_ida_through_folds_on_branch(model: pfaff.NumericModel) -> None:
    """IDA's regularized Newton matrix passes the folds at moderate tolerances."""
    traj, te = _run_through_folds(model, "ida", rtol=1e-6, atol=1e-8)
    assert traj.status == "success", traj.message
    assert np.abs(traj.q[:, 1]).max() < 1e-9
    assert np.abs(traj.q[:, 2] - traj.q[:, 0]).max() < 1e-9
    th, _ = reference(te)
    assert np.abs(traj.q[:, 0] - th).max() < 1e-3


def test_ida_tight_fold_fails_cleanly(model: pfaff.NumericModel, monkeypatch) -> None:
    """At rtol = 1e-9 IDA's corrector does not converge at a fold (the first or the second):
    a failed status there, quickly (no stall), with the branch kept up to there."""
    original, calls = type(model).dae_blocks, itertools.count()  # (models are immutable)

    def budget(*args):
        if next(calls) >= 20_000:
            raise KeyboardInterrupt  # a stall would end here with status "interrupted"
        return original(*args)

    monkeypatch.setattr(type(model), "dae_blocks", budget)
    traj, _ = _run_through_folds(model, "ida")
    assert traj.status == "failed", traj.message
    t_fail = float(re.search(r"t = ([0-9.eE+-]+)", traj.message).group(1))
    assert np.abs(fold_times() - t_fail).min() < 1e-3  # at a fold, not elsewhere
    assert np.abs(traj.q[:, 1]).max() < 1e-9


def test_square_parallelogram_ten_seconds() -> None:
    """All links 1 m and 1 kg, crank released vertical at 6 rad/s: 24 flat passes in 10 s.

    With a = L the linkage has a third branch through the folds as well (crank folded onto the
    coupler); the projection run stays on the parallelogram one, against the branch equation
    (1/3 + 1/3 + 1) θ̈ = −(1/2 + 1 + 1/2) g cos θ.
    """
    square = {"a": 1.0, "L": 1.0, "m1": 1.0, "m2": 1.0, "m3": 1.0, "g": 9.81}
    sq = four_bar().equations().compile(square)
    inertia, torque = 1 / 3 + 1 / 3 + 1, 2.0 * 9.81
    th0, w0, t_end = math.pi / 2, 6.0, 10.0
    te = np.linspace(0.0, t_end, 501)
    ref = solve_ivp(
        lambda t, y: [y[1], -torque * math.cos(y[0]) / inertia],
        (0.0, t_end),
        [th0, w0],
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
        t_eval=te,
    )
    assert ref.y[0, -1] // math.pi >= 24
    traj = pfaff.simulate(sq, [th0, 0.0, th0], [w0, 0.0, w0], (0.0, t_end), t_eval=te)
    assert traj.status == "success", traj.message
    assert np.abs(traj.q[:, 1]).max() < 1e-9
    assert np.abs(traj.q[:, 2] - traj.q[:, 0]).max() < 1e-9
    assert np.abs(traj.q[:, 0] - ref.y[0]).max() < 1e-6
    assert np.abs(traj.constraint_residual).max() < 1e-10
