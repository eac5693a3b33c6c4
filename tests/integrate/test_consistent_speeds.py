"""consistent_state with independent speeds apart from the independent coordinates: a rolling
disk (5 independent coordinates, 3 independent speeds) completed and checked by hand."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import pfaff

R = 0.5


@pytest.fixture(scope="module")
def disk():
    s = pfaff.models.rolling_disk()
    model = s.equations().compile({"m": 1.0, "r": R, "g": 9.81})
    att = s.bodies[0].attitude
    angles = list(att.coordinates)
    syms = sp.symbols("a0:3")
    dcm = sp.lambdify(syms, att.dcm.xreplace(dict(zip(angles, syms, strict=True))), "numpy")
    return model, dcm


def _omega(dcm, angles: np.ndarray, rates: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """ω in the fixed frame from Ċ Cᵀ (Ċ by central differences): no pfaff constraint code."""
    C = np.asarray(dcm(*angles), dtype=float)
    Cd = (np.asarray(dcm(*(angles + h * rates))) - np.asarray(dcm(*(angles - h * rates)))) / (2 * h)
    W = Cd @ C.T
    if abs(W[0, 1] + W[1, 0]) > 1e-6:  # (C maps the other way: ω̃ = Cᵀ Ċ in that convention)
        W = C.T @ Cd
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


IND_Q = ["x", "y", "psi", "theta", "phi"]
IND_QD = ["psi", "theta", "phi"]


@pytest.mark.parametrize("lean", [0.0, 0.3])
def test_rolling_disk_completed_by_hand(disk, lean: float) -> None:
    model, dcm = disk
    q = np.array([0.3, -0.2, 0.0, 0.7, lean, 0.4])  # z a wrong guess
    qd = np.array([0.0, 0.0, 0.0, 0.5, 0.2, 2.0])  # ẋ, ẏ, ż wrong guesses
    q2, qd2 = pfaff.consistent_state(model, q, qd, IND_Q, independent_speeds=IND_QD)
    keep_q, keep_qd = [0, 1, 3, 4, 5], [3, 4, 5]
    np.testing.assert_array_equal(q2[keep_q], q[keep_q])
    np.testing.assert_array_equal(qd2[keep_qd], qd[keep_qd])
    # contact height z = r cos θ and its rate ż = −r sin θ θ̇
    assert q2[2] == pytest.approx(R * np.cos(lean), abs=1e-12)
    assert qd2[2] == pytest.approx(-R * np.sin(lean) * qd[4], abs=1e-12)
    # no slip: the material point at the contact, C − r·(lean frame's z), has no velocity
    C = np.asarray(dcm(*q2[3:]), dtype=float)
    lean_z = np.asarray(dcm(q2[3], q2[4], 0.0), dtype=float)[:, 2]
    omega = _omega(dcm, q2[3:], qd2[3:])
    v_contact = qd2[:3] + np.cross(omega, -R * lean_z)
    np.testing.assert_allclose(v_contact[:2], 0.0, atol=1e-8)
    if lean == 0.0:  # upright: r φ̇ across the disk's axis (rolling), r θ̇ along it (tipping)
        assert np.hypot(*qd2[:2]) == pytest.approx(R * np.hypot(qd[5], qd[4]), rel=1e-12)
        assert abs(qd2[:3] @ C[:, 1]) == pytest.approx(R * qd[4], rel=1e-12)


def test_one_list_cannot_complete_a_rolling_disk(disk) -> None:
    """Today's behaviour without independent_speeds: the speeds of x and y are held too, and
    the no-slip rows have no solution; the message points at the new argument."""
    model, _ = disk
    q = np.array([0.3, -0.2, R, 0.7, 0.0, 0.4])
    qd = np.array([0.1, 0.1, 0.0, 0.5, 0.0, 2.0])
    with pytest.raises(pfaff.ConstraintError, match="independent_speeds"):
        pfaff.consistent_state(model, q, qd, IND_Q)
    with pytest.raises(pfaff.StateError, match="unknown coordinate `w` in `independent_speeds`"):
        pfaff.consistent_state(model, q, qd, IND_Q, independent_speeds=["w"])
