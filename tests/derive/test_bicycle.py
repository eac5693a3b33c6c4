"""The Whipple bicycle (Meijaard et al. 2007): pfaff on a large rigid-body model with four
nonholonomic no-slip constraints and one holonomic contact constraint.

The model builder lives in ``benchmarks/bicycle.py`` (loaded from there): the kinetic energy of
four rigid bodies from ``sympy.physics.mechanics`` frames and points, handed to pfaff as one
expression per body. Checked against

* the published benchmark: the linearized lean and steer equations M, C1, K0, K2 about upright
  straight running, and the speeds where the weave and capsize modes change stability;
* SymPy's ``KanesMethod`` on the same kinematics, at a random state satisfying the constraints.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "bicycle.py"

# The model alone costs about 5 s of CPU (build 0.7, equations() 2.1, compile 0.4, the state
# solver's lambdified constraints 1), Kane's reference 20 s more: all slow.
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def bike():
    """The benchmark module ``benchmarks/bicycle.py``."""
    spec = importlib.util.spec_from_file_location("pfaff_benchmark_bicycle", PATH)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop(spec.name, None)


@pytest.fixture(scope="module")
def model(bike):
    return bike.whipple_bicycle().equations().compile(bike.MEIJAARD)


def test_model_shape(bike, model) -> None:
    assert (model.n, model.m) == (8, 5)
    assert list(model.constraint_names) == [
        "front contact",
        "rear no slip x",
        "rear no slip y",
        "front no slip x",
        "front no slip y",
    ]
    q, qd = bike.random_state(bike.MEIJAARD, np.random.default_rng(1))
    f, g = model.constraint_residual(0.0, q, qd)
    assert np.abs(f).max() < 1e-14 and np.abs(g).max() < 1e-13


def test_straight_running_is_steady(bike, model) -> None:
    """Upright and straight at 5 m/s: no acceleration; the contact forces carry the weight."""
    q, qd = bike.bicycle_state(bike.MEIJAARD, speed=5.0)
    qdd, lam = model.accelerations(0.0, q, qd)
    assert np.abs(qdd).max() < 1e-12
    p = bike.MEIJAARD
    weight = p["g"] * (p["mR"] + p["mB"] + p["mH"] + p["mF"])
    # λ of the front contact (f = its z, down) is minus the front normal force; moments
    # about the rear contact: N_F w = Σ m g x of the mass centres (wheels at 0 and w)
    front = p["g"] * (p["mB"] * p["xB"] + p["mH"] * p["xH"] + p["mF"] * p["w"]) / p["w"]
    assert lam[0] == pytest.approx(-front, rel=1e-12)
    assert 0 < front < weight
    assert np.abs(lam[1:]).max() < 1e-12  # no friction needed


@pytest.mark.parametrize("speed", [0.0, 2.0, 5.0])
def test_linearized_equations_match_meijaard(bike, model, speed: float) -> None:
    """∂(φ̈, δ̈)/∂(φ, δ, φ̇, δ̇) of pfaff's equations, by central differences at consistent states
    about upright straight running, against -M⁻¹[g K0 + v² K2, v C1] of the benchmark paper."""

    def acc(q, qd):
        return model.accelerations(0.0, q, qd)[0]

    J = bike.lean_steer_matrix(acc, bike.MEIJAARD, speed)
    ref = bike.meijaard_lean_steer(speed)
    assert np.abs(J - ref).max() <= 1e-8 * np.abs(ref).max()


def test_weave_and_capsize_speeds(bike, model) -> None:
    """The benchmark's self-stable speed range, 4.2924 < v < 6.0243 m/s, from pfaff's equations:
    linearized at v = 0, 1, 2 the lean-steer matrix is J0 + v J1 + v² J2 exactly."""

    def acc(q, qd):
        return model.accelerations(0.0, q, qd)[0]

    J0, J1, J2 = (bike.lean_steer_matrix(acc, bike.MEIJAARD, v) for v in (0.0, 1.0, 2.0))
    lin, quad = (4 * J1 - J2 - 3 * J0) / 2, (J2 - 2 * J1 + J0) / 2

    def eigenvalues(v: float) -> np.ndarray:
        A = np.zeros((4, 4))
        A[0, 2] = A[1, 3] = 1.0
        A[2:] = J0 + v * lin + v * v * quad
        return np.linalg.eigvals(A)

    def weave(v: float) -> float:
        return max(e.real for e in eigenvalues(v) if abs(e.imag) > 1e-9)

    def capsize(v: float) -> float:
        return max(e.real for e in eigenvalues(v) if abs(e.imag) <= 1e-9)

    assert brentq(weave, 3.0, 5.0, xtol=1e-13) == pytest.approx(bike.MEIJAARD_WEAVE_SPEED, 1e-7)
    assert brentq(capsize, 5.0, 7.0, xtol=1e-13) == pytest.approx(bike.MEIJAARD_CAPSIZE_SPEED, 1e-7)


def test_accelerations_agree_with_kane(bike, model) -> None:
    """q̈ of pfaff against SymPy's KanesMethod (u = q̇, dependent speeds, configuration
    constraint, lambdified full mass matrix and forcing) at random consistent states."""
    kane, q, u = bike.kane_bicycle()
    rhs = bike.kane_accelerations(kane, q, u, bike.MEIJAARD)
    rng = np.random.default_rng(2007)
    for _ in range(2):
        qs, qds = bike.random_state(bike.MEIJAARD, rng)
        ref = rhs(qs, qds)
        qdd, _ = model.accelerations(0.0, qs, qds)
        assert np.abs(qdd - ref).max() <= 1e-9 * np.abs(ref).max()
