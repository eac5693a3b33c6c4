"""The planar four-bar in 3-D (three redundant joint rows) against its one-angle reference."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from fourbar3d_reference import FourBarReference

import pfaff
from pfaff.attitude import EulerAngles, dcm_from
from pfaff.models import FOURBAR3D, fourbar3d, fourbar3d_state

TH0, W0 = 0.0, 5.0  # the crank turns once in ≈ 1.11 s, ω ≥ 3.5 rad/s on the way


@pytest.fixture(scope="module")
def turn() -> dict[str, np.ndarray]:
    return FourBarReference().full_turn(TH0, W0)


def test_reference_conserves_energy(turn: dict[str, np.ndarray]) -> None:
    """The reference through a full crank turn: energy constant, the crank never stops."""
    e = turn["energy"]
    assert np.abs(e - e[0]).max() < 1e-10 * max(1.0, np.abs(e).max())
    assert turn["omega"].min() > 1.0
    assert turn["theta"][-1] == pytest.approx(TH0 + 2 * np.pi, abs=1e-9)


def test_grashof_crank_rocker() -> None:
    a, b, c, d = (FOURBAR3D[k] for k in "abcd")
    s, *_, l_ = sorted((a, b, c, d))
    assert s == a and s + l_ <= sum((a, b, c, d)) - s - l_


def _joint_gaps(q: np.ndarray) -> float:
    """The 20 joint rows evaluated numerically from q, without the pfaff model."""
    p = FOURBAR3D
    L = (p["a"], p["b"], p["c"])
    att = EulerAngles(pfaff.coordinates("u v w"), "321")
    C = [dcm_from(att, q[6 * k + 3 : 6 * k + 6]) for k in range(3)]
    r = [q[6 * k : 6 * k + 3] for k in range(3)]

    def end(k: int, sign: int) -> np.ndarray:
        return r[k] + sign * L[k] / 2 * C[k][:, 0]

    pairs = [
        (np.zeros(3), end(0, -1), np.eye(3), C[0]),
        (end(0, 1), end(1, -1), C[0], C[1]),
        (end(1, 1), end(2, 1), C[1], C[2]),
        (end(2, -1), np.array([p["d"], 0, 0]), C[2], np.eye(3)),
    ]
    gaps = [np.abs(pa - pb).max() for pa, pb, _, _ in pairs]
    gaps += [abs(Ca[:, 2] @ Cb[:, i]) for _, _, Ca, Cb in pairs for i in (0, 1)]
    return float(max(gaps))


def test_state_is_consistent() -> None:
    """fourbar3d_state satisfies every joint row, and its velocity their time derivative."""
    for th in (0.0, 0.7, 2.5, 4.0):
        q, qd = fourbar3d_state(th, 2.0)
        assert _joint_gaps(q) < 1e-14
        h = 1e-7
        assert (_joint_gaps(q + h * qd) + _joint_gaps(q - h * qd)) / h < 1e-6


def test_inconsistent_rows_are_refused() -> None:
    """x − 1 = 0 and x − 2 = 0 cannot both hold: refused, naming both rows (also after issue
    22: redundancy is accepted, inconsistency is not)."""
    x, y = pfaff.coordinates("x y")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_holonomic_constraint(x - 1, name="one")
    s.add_holonomic_constraint(x - 2, name="two")
    with pytest.raises(pfaff.PfaffError, match=r"`one`.*`two`"):
        s.equations().compile({})


@pytest.mark.slow
def test_model_builds() -> None:
    s = fourbar3d()
    assert len(s.coordinates) == 18 and len(s.constraint_rows()[0]) == 20
    assert set(s.equations().parameters) == set(sp.symbols(" ".join(FOURBAR3D)))


@pytest.mark.slow
def test_pfaff_follows_reference(turn: dict[str, np.ndarray]) -> None:
    """The full 3-D model (3 of its 20 rows redundant) through one crank turn: the crank angle
    to 1e-8, the energy to 1e-10 relative (the reference's own drift is 4e-9 J of 100 J), the
    constraints to 1e-10."""
    model = fourbar3d().equations().compile(FOURBAR3D)
    q0, qd0 = fourbar3d_state(TH0, W0)
    t = turn["t"]
    traj = pfaff.simulate(model, q0, qd0, (0.0, t[-1]), t_eval=t, rtol=1e-10, atol=1e-12)
    assert traj.status == "success", traj.message
    assert np.abs(np.unwrap(traj.q[:, 3]) - turn["theta"]).max() < 1e-8
    assert np.abs(traj.energy - traj.energy[0]).max() < 1e-10 * abs(traj.energy[0])
    assert np.abs(traj.energy[0] - turn["energy"][0]) < 1e-9
    assert (traj.redundant_rows == 3).all()
    assert np.abs(traj.constraint_residual).max() < 1e-10
