"""Bricard's mechanism (IFToMM benchmark A04): pfaff's full model against an independent reference.

The reference (``bricard_reference``) is a one-degree-of-freedom model written with NumPy and
SciPy only. The full model (``pfaff.models.bricard``) has one redundant joint row on the motion
(Grübler: 0 degrees of freedom; Bricard: 1), found at the first state of the run (it holds only
on the constraint manifold) and solved with the independent rows through the benchmark's 10 s.
"""

from __future__ import annotations

import numpy as np
import pytest
from bricard_reference import BricardReference

import pfaff
from pfaff.attitude import dcm_from
from pfaff.models import BRICARD, bricard, bricard_state

T_END = 10.0
T_EVAL = np.linspace(0.0, T_END, 201)


@pytest.fixture(scope="module")
def reference() -> dict[str, np.ndarray]:
    return BricardReference().simulate(T_EVAL)


def joints_of(system: pfaff.System, q: np.ndarray) -> np.ndarray:
    """J1 … J5 from pfaff's coordinates: the far end of bar k, r_k + C_k (L/2, 0, 0)."""
    half = np.array([BRICARD["L"] / 2, 0.0, 0.0])
    out = []
    for k, body in enumerate(system.bodies):
        beta = q[7 * k + 3 : 7 * k + 7]
        out.append(q[7 * k : 7 * k + 3] + dcm_from(body.attitude, beta) @ half)
    return np.array(out)


def test_reference_one_degree_of_freedom() -> None:
    """The published fact: Grübler's count gives 0, the mechanism moves with 1 (the 6×6 matrix
    of the joint twists has rank 5), and the rest state is not an equilibrium."""
    ref = BricardReference()
    assert 6 * 5 - 5 * 6 == 0
    _, s = ref.tangent(np.zeros(6), None)
    assert s[4] > 0.5 and s[5] < 1e-12
    _, sdd, _ = ref.rhs(np.zeros(6), 0.0, None)
    assert abs(sdd) > 1.0
    assert ref.energy(np.zeros(6), 0.0) == pytest.approx(-3 * 9.81)  # m g Σ y_c, Σ y_c = −3 m


@pytest.mark.slow
def test_reference_conserves_energy_and_closes(reference: dict[str, np.ndarray]) -> None:
    """The benchmark's criterion (the energy varies by zero) holds for the reference, the loop
    stays closed at J5, and the motion keeps the loop's symmetry θ1 = θ3 = θ5, θ2 = θ4 = θ6."""
    assert np.abs(reference["energy"] - reference["energy"][0]).max() < 2e-9
    assert reference["closure"].max() < 1e-9
    th = reference["theta"]
    assert np.abs(th[:, [2, 4]] - th[:, [0]]).max() < 1e-8
    assert np.abs(th[:, [3, 5]] - th[:, [1]]).max() < 1e-8
    assert np.abs(th[:, 0]).max() > 2.5  # a large motion, not a small oscillation


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_model_builds_with_one_redundant_row() -> None:
    """35 coordinates, 35 constraint rows; at the initial state the rows hold and have rank 34."""
    system = bricard()
    names, _ = system.constraint_rows()
    assert len(system.coordinates) == 35 and len(names) == 35
    model = system.equations().compile(BRICARD)
    q0, qd0 = bricard_state()
    f, fd = model.constraint_residual(0.0, q0, qd0)
    assert np.abs(f).max() < 1e-15 and np.abs(fd).max() < 1e-15
    A = model.constraint_matrix(0.0, q0)
    A = A.toarray() if hasattr(A, "toarray") else np.asarray(A)
    s = np.linalg.svd(A, compute_uv=False)
    assert int((s > 1e-9 * s[0]).sum()) == 34
    np.testing.assert_allclose(joints_of(system, q0)[:4], BricardReference().points[1:5])


@pytest.mark.slow
def test_initial_accelerations_match_reference() -> None:
    """The bar centres' accelerations at the release, pfaff against the reference."""
    ref = BricardReference()
    _, sdd, n = ref.rhs(np.zeros(6), 0.0, None)
    _, bars = ref._bars(np.zeros(6), 0.0, n)
    expected = np.array([sdd * dc for _c, _i, _dw, dc, *_ in bars])
    model = bricard().equations().compile(BRICARD)
    q0, qd0 = bricard_state()
    qdd, _ = model.accelerations(0.0, q0, qd0)
    got = np.array([qdd[7 * k : 7 * k + 3] for k in range(5)])
    np.testing.assert_allclose(got, expected, atol=1e-10)


@pytest.mark.slow
def test_pfaff_follows_reference(reference: dict[str, np.ndarray]) -> None:
    """pfaff's full model through the benchmark's 10 s: the joints' paths to 1e-8 m, the energy
    to 1e-9 J, the constraints to 1e-10."""
    system = bricard()
    model = system.equations().compile(BRICARD)
    q0, qd0 = bricard_state()
    traj = pfaff.simulate(model, q0, qd0, (0.0, T_END), t_eval=T_EVAL, rtol=1e-10, atol=1e-12)
    assert traj.status == "success", traj.message
    got = np.array([joints_of(system, q) for q in traj.q])
    assert np.abs(got[:, :5] - reference["joints"][:, 1:]).max() < 1e-8
    assert np.abs(traj.energy - traj.energy[0]).max() < 1e-9
    assert np.abs(traj.energy[0] - reference["energy"][0]) < 1e-12
    assert np.abs(traj.constraint_residual).max() < 1e-10
