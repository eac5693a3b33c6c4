"""``pfaff.load_urdf`` against Pinocchio reading the same file (``pin.buildModelFromUrdf``).

At 100 random states each: the compiled model's ``mass_matrix(t, q)`` against ``pin.crba`` and
``-forcing(t, q, qd)`` (= h − Q = C q̇ + g with no damping or inputs) against
``pin.rnea(q, qd, 0)``, to 1e-10, for ``examples/arm6.urdf`` (a six-joint arm with shoulder and
wrist offsets), ``tests/data/arm7_offsets.urdf`` (seven joints, tilted joint frames, an oblique
axis, a continuous joint, a fixed tool link, rotated inertial frames with full inertia tensors;
slow: about 5 s to derive) and ``tests/data/arm3_offsets.urdf`` (the same kinds of joints, frames
and inertias in three joints, and a fixed tool link with a mass: the fast suite's case).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pfaff

pin = pytest.importorskip("pinocchio")

ROOT = Path(__file__).resolve().parents[2]
FILES = [
    ROOT / "examples" / "arm6.urdf",
    pytest.param(ROOT / "tests" / "data" / "arm7_offsets.urdf", marks=pytest.mark.slow),
    ROOT / "tests" / "data" / "arm3_offsets.urdf",
]


class PinocchioArm:
    """Pinocchio's model of a URDF file, in the joint order and coordinates of pfaff's system
    (a continuous joint is (cos q, sin q) in Pinocchio's configuration)."""

    def __init__(self, path: Path, joint_names: list[str]) -> None:
        self.model = pin.buildModelFromUrdf(str(path))
        self.data = self.model.createData()
        joints = [self.model.joints[self.model.getJointId(name)] for name in joint_names]
        self.iq = [j.idx_q for j in joints]
        self.nq = [j.nq for j in joints]
        self.iv = np.array([j.idx_v for j in joints])

    def config(self, q: np.ndarray) -> np.ndarray:
        out = pin.neutral(self.model)
        for qi, i, nq in zip(q, self.iq, self.nq, strict=True):
            out[i : i + nq] = [np.cos(qi), np.sin(qi)] if nq == 2 else [qi]
        return out

    def velocity(self, qd: np.ndarray) -> np.ndarray:
        out = np.zeros(self.model.nv)
        out[self.iv] = qd
        return out

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        M = pin.crba(self.model, self.data, self.config(q))
        M = np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle
        return M[np.ix_(self.iv, self.iv)]

    def bias(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        zero = np.zeros(self.model.nv)
        return pin.rnea(self.model, self.data, self.config(q), self.velocity(qd), zero)[self.iv]

    def aba(self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        tau_pin = self.velocity(tau)
        return pin.aba(self.model, self.data, self.config(q), self.velocity(qd), tau_pin)[self.iv]


@pytest.fixture(scope="module", params=FILES, ids=lambda p: p.stem)
def arm(request):
    system = pfaff.load_urdf(request.param)
    model = system.equations().compile(system.urdf_values)
    return system, model, PinocchioArm(request.param, list(system.urdf_coordinates))


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_gravity_matches_pinocchio(arm):
    _, _, ref = arm
    assert np.allclose(ref.model.gravity.linear, [0, 0, -9.81])


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_mass_matrix_and_bias_against_pinocchio(arm):
    system, model, ref = arm
    n = len(system.urdf_coordinates)
    rng = np.random.default_rng(23)
    worst_m = worst_h = 0.0
    for _ in range(100):
        q = rng.uniform(-np.pi, np.pi, n)
        qd = rng.uniform(-2.0, 2.0, n)
        worst_m = max(worst_m, np.abs(model.mass_matrix(0.0, q) - ref.mass_matrix(q)).max())
        worst_h = max(worst_h, np.abs(-model.forcing(0.0, q, qd) - ref.bias(q, qd)).max())
    assert worst_m < 1e-10
    assert worst_h < 1e-10


@pytest.mark.slow  # (its two robots over two seconds: the full suite runs it)
def test_accelerations_against_aba(arm):
    system, model, ref = arm
    n = len(system.urdf_coordinates)
    rng = np.random.default_rng(7)
    for _ in range(20):
        q, qd = rng.uniform(-np.pi, np.pi, n), rng.uniform(-2.0, 2.0, n)
        qdd = model.accelerations(0.0, q, qd)[0]
        assert np.abs(qdd - ref.aba(q, qd, np.zeros(n))).max() < 1e-9


@pytest.mark.slow
def test_readable_equations_of_arm6_against_pinocchio():
    """The simplified-for-reading ``mass_matrix`` and ``forcing`` of the 6-joint arm (not what
    code is made from) at 5 random states, and the waist angle absent from both (the first
    joint turns about gravity's axis: nothing depends on it)."""
    import sympy as sp

    system = pfaff.load_urdf(FILES[0])
    eom = system.equations()
    M, F = eom.mass_matrix, eom.forcing
    q = list(system.urdf_coordinates.values())
    qd = [c.diff(pfaff.t) for c in q]
    xs, vs = sp.symbols("x0:6"), sp.symbols("v0:6")
    subs = {p: system.urdf_values[p.name] for p in eom.parameters}
    rule = dict(zip(qd, vs, strict=True)) | dict(zip(q, xs, strict=True))
    m_sym, f_sym = M.xreplace(subs).xreplace(rule), F.xreplace(subs).xreplace(rule)
    assert xs[0] not in m_sym.free_symbols | f_sym.free_symbols  # the waist angle
    m_fn, f_fn = sp.lambdify([xs], m_sym), sp.lambdify([xs, vs], f_sym)
    ref = PinocchioArm(FILES[0], list(system.urdf_coordinates))
    rng = np.random.default_rng(5)
    for _ in range(5):
        x, v = rng.uniform(-np.pi, np.pi, 6), rng.uniform(-2.0, 2.0, 6)
        assert np.abs(np.array(m_fn(x), dtype=float) - ref.mass_matrix(x)).max() < 1e-10
        assert np.abs(-np.ravel(f_fn(x, v)) - ref.bias(x, v)).max() < 1e-10
