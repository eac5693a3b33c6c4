"""Attitude sets: C orthonormal, Ċ = C[ω×] (which fixes every sign), numeric inverses, bad input."""

from __future__ import annotations

import re

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.core.errors import ModelError, ModelTypeError, StateError
from pfaff.mechanics.attitude import (
    MRP,
    SEQUENCES,
    Attitude,
    EulerAngles,
    PlanarAngle,
    Quaternion,
    dcm_from,
)

t = pfaff.t
A, B, C3 = pfaff.coordinates("a b c")
SETS: dict[str, Attitude] = {
    **{f"euler{s}": EulerAngles((A, B, C3), s) for s in SEQUENCES},
    "quaternion": Quaternion(pfaff.coordinates("b0:4")),
    "mrp": MRP(pfaff.coordinates("s1:4")),
    "planar": PlanarAngle(pfaff.coordinates("theta")),
}
ALL = list(SETS)
SPATIAL = [name for name in ALL if name != "planar"]


def skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def random_values(att: Attitude, rng: np.random.Generator) -> np.ndarray:
    """Coordinates inside the principal ranges of ``from_dcm``, away from singularities."""
    if isinstance(att, EulerAngles):
        i, _, k = att.sequence
        b = rng.uniform(0.1, np.pi - 0.1) if i == k else rng.uniform(-1.4, 1.4)
        return np.array([rng.uniform(-np.pi, np.pi), b, rng.uniform(-np.pi, np.pi)])
    if isinstance(att, Quaternion):
        beta = rng.normal(size=4)
        beta /= np.linalg.norm(beta)
        return beta if beta[0] >= 0 else -beta
    if isinstance(att, MRP):
        d = rng.normal(size=3)
        return d / np.linalg.norm(d) * rng.uniform(0.05, 0.99)
    return rng.uniform(-np.pi, np.pi, size=1)


def random_rates(att: Attitude, q: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    qd = rng.normal(size=q.shape)
    return qd - (qd @ q) * q if isinstance(att, Quaternion) else qd  # tangent to β·β = 1


def evaluate(att: Attitude, expr: sp.Basic, q: np.ndarray, qd: np.ndarray | None = None):
    rule = {} if qd is None else dict(zip(att.rates_symbols, map(float, qd), strict=True))
    expr = expr.subs(rule).subs(dict(zip(att.coordinates, map(float, q), strict=True)))
    return np.array(expr.evalf(), dtype=float)


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    beta = rng.normal(size=4)
    return dcm_from(SETS["quaternion"], beta / np.linalg.norm(beta))


@pytest.mark.parametrize("name", ALL)
def test_dcm_is_a_rotation_and_matches_its_numeric_form(name: str) -> None:
    att, rng = SETS[name], np.random.default_rng(1)
    for _ in range(4):
        q = random_values(att, rng)
        c = dcm_from(att, q)
        np.testing.assert_allclose(c.T @ c, np.eye(3), atol=1e-12)
        assert np.linalg.det(c) == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(evaluate(att, att.dcm, q), c, atol=1e-12)


@pytest.mark.parametrize("name", ALL)
@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_dcm_rate_is_dcm_times_omega_cross(name: str) -> None:
    """Ċ = C [ω×] with ω in body components, symbolically and by central differences."""
    att, rng = SETS[name], np.random.default_rng(2)
    cdot = att.dcm.diff(t)
    for _ in range(3):
        q = random_values(att, rng)
        qd = random_rates(att, q, rng)
        w = evaluate(att, att.angular_velocity, q, qd).ravel()
        expected = dcm_from(att, q) @ skew(w)
        np.testing.assert_allclose(evaluate(att, cdot, q, qd), expected, atol=1e-11)
        h = 1e-5
        fd = (dcm_from(att, q + h * qd) - dcm_from(att, q - h * qd)) / (2 * h)
        np.testing.assert_allclose(fd, expected, atol=1e-8)


def test_every_set_turns_the_body_x_axis_onto_inertial_y_for_a_quarter_turn_about_z() -> None:
    """r_inertial = C r_body, rotations by +φ about e (right hand): one convention for all."""
    phi = np.pi / 2
    cases = {
        "quaternion": [np.cos(phi / 2), 0, 0, np.sin(phi / 2)],
        "mrp": [0, 0, np.tan(phi / 4)],
        "planar": [phi],
        "euler321": [phi, 0, 0],
        "euler313": [phi, 0, 0],
        "euler123": [0, 0, phi],
    }
    for name, q in cases.items():
        c = dcm_from(SETS[name], q)
        np.testing.assert_allclose(c @ [1, 0, 0], [0, 1, 0], atol=1e-15, err_msg=name)
        np.testing.assert_allclose(c @ [0, 0, 1], [0, 0, 1], atol=1e-15, err_msg=name)


def test_mrp_is_the_quaternion_vector_over_one_plus_its_scalar() -> None:
    rng = np.random.default_rng(3)
    for _ in range(5):
        c = random_rotation(rng)
        beta, sigma = SETS["quaternion"].from_dcm(c), SETS["mrp"].from_dcm(c)
        np.testing.assert_allclose(sigma, beta[1:] / (1 + beta[0]), atol=1e-14)


@pytest.mark.parametrize("name", ALL)
def test_from_dcm_inverts_dcm_from(name: str) -> None:
    att, rng = SETS[name], np.random.default_rng(4)
    for _ in range(6):
        q = random_values(att, rng)
        back = att.from_dcm(dcm_from(att, q))
        np.testing.assert_allclose(back, q, atol=1e-11)
        np.testing.assert_allclose(dcm_from(att, back), dcm_from(att, q), atol=1e-12)


@pytest.mark.parametrize("name", SPATIAL)
def test_every_spatial_set_reproduces_one_rotation(name: str) -> None:
    att, rng = SETS[name], np.random.default_rng(5)
    for _ in range(8):
        c = random_rotation(rng)
        q = att.from_dcm(c)
        np.testing.assert_allclose(dcm_from(att, q), c, atol=1e-12)
        if isinstance(att, EulerAngles):
            symmetric = att.sequence[0] == att.sequence[2]
            lo, hi = (0, np.pi) if symmetric else (-np.pi / 2, np.pi / 2)
            assert lo <= q[1] <= hi
            assert -np.pi < q[0] <= np.pi and -np.pi < q[2] <= np.pi
        elif isinstance(att, Quaternion):
            assert q[0] >= 0 and np.linalg.norm(q) == pytest.approx(1.0)
        else:
            assert np.linalg.norm(q) <= 1 + 1e-15


def test_planar_and_spatial_sets_agree_on_a_rotation_about_z() -> None:
    c = dcm_from(SETS["planar"], [2.5])
    for name in ALL:
        np.testing.assert_allclose(dcm_from(SETS[name], SETS[name].from_dcm(c)), c, atol=1e-14)
    with pytest.raises(StateError, match="not a rotation about the z axis"):
        SETS["planar"].from_dcm(dcm_from(SETS["euler321"], [0.1, 0.2, 0.3]))


@pytest.mark.parametrize(
    "beta", [[0.1, 0.9, 0.3, 0.2], [0.05, 0.2, -0.95, 0.1], [0.0, -0.3, 0.2, 0.9], [0, 1, 0, 0]]
)
def test_quaternion_from_dcm_near_half_turns(beta: list[float]) -> None:
    """Every branch of the largest-square choice; β and -β are the same attitude."""
    b = np.array(beta) / np.linalg.norm(beta)
    back = SETS["quaternion"].from_dcm(dcm_from(SETS["quaternion"], b))
    assert back[0] >= 0
    if b[0] == 0:  # a half turn: β and -β both have β0 = 0
        b = b if back @ b > 0 else -b
    np.testing.assert_allclose(back, b, atol=1e-14)


@pytest.mark.parametrize("name", ALL)
def test_rates_reproduce_the_angular_velocity(name: str) -> None:
    att, rng = SETS[name], np.random.default_rng(6)
    for _ in range(4):
        q = random_values(att, rng)
        w = rng.normal(size=3)
        if isinstance(att, PlanarAngle):
            w[:2] = 0
        qd = att.rates(q, w)
        assert qd.shape == q.shape
        np.testing.assert_allclose(
            evaluate(att, att.angular_velocity, q, qd).ravel(), w, atol=1e-12
        )
        if isinstance(att, Quaternion):
            assert q @ qd == pytest.approx(0.0, abs=1e-15)  # stays on β·β = 1


def test_euler_angular_velocity_of_321_and_313() -> None:
    """The textbook forms: yaw-pitch-roll (ψ, θ, φ) and the orbit angles (Ω, i, ω)."""
    a, b, c = (q.diff(t) for q in (A, B, C3))
    ypr = sp.Matrix(
        [
            c - a * sp.sin(B),
            b * sp.cos(C3) + a * sp.sin(C3) * sp.cos(B),
            -b * sp.sin(C3) + a * sp.cos(C3) * sp.cos(B),
        ]
    )
    orbit = sp.Matrix(
        [
            a * sp.sin(B) * sp.sin(C3) + b * sp.cos(C3),
            a * sp.sin(B) * sp.cos(C3) - b * sp.sin(C3),
            a * sp.cos(B) + c,
        ]
    )
    assert sp.simplify(SETS["euler321"].angular_velocity - ypr) == sp.zeros(3, 1)
    assert sp.simplify(SETS["euler313"].angular_velocity - orbit) == sp.zeros(3, 1)


@pytest.mark.parametrize("seq", SEQUENCES)
def test_euler_singularity_is_the_kinematic_determinant(seq: str) -> None:
    att = SETS[f"euler{seq}"]
    det = att.angular_velocity.jacobian(att.rates_symbols).det()
    assert att.singularity == (sp.sin(B) if seq[0] == seq[2] else sp.cos(B))
    assert sp.simplify(det - att.singularity) == 0 or sp.simplify(det + att.singularity) == 0


@pytest.mark.parametrize(("seq", "b"), [("321", np.pi / 2), ("321", -np.pi / 2), ("313", 0.0)])
def test_euler_rates_raise_at_gimbal_lock(seq: str, b: float) -> None:
    att = SETS[f"euler{seq}"]
    with pytest.raises(
        StateError, match=rf"EulerAngles {seq}: .*singular.*{re.escape(str(att.singularity))} = 0"
    ):
        att.rates([0.3, b, -0.2], [0.1, 0.2, 0.3])
    assert np.all(np.isfinite(att.rates([0.3, b + 1e-3, -0.2], [0.1, 0.2, 0.3])))


@pytest.mark.parametrize(("seq", "b"), [("321", np.pi / 2), ("321", -np.pi / 2), ("313", 0.0)])
def test_euler_from_dcm_at_gimbal_lock(seq: str, b: float) -> None:
    att = SETS[f"euler{seq}"]
    c = dcm_from(att, [0.4, b, 0.7])
    q = att.from_dcm(c)
    assert q[2] == 0.0 and q[1] == pytest.approx(b, abs=1e-7)
    np.testing.assert_allclose(dcm_from(att, q), c, atol=1e-12)


def test_euler_from_dcm_at_the_other_symmetric_lock() -> None:
    att = SETS["euler313"]
    c = dcm_from(att, [0.4, np.pi, 0.7])
    q = att.from_dcm(c)
    assert q[1] == pytest.approx(np.pi) and q[2] == 0.0
    np.testing.assert_allclose(dcm_from(att, q), c, atol=1e-12)


@pytest.mark.parametrize(
    ("seq", "b"),
    [("321", np.pi / 2 - 1e-6), ("321", -np.pi / 2 + 1e-7), ("313", 1e-6), ("212", 3.14159)],
)
def test_euler_from_dcm_near_gimbal_lock(seq: str, b: float) -> None:
    """Close to the lock a and c are still found, and C is reproduced to rounding."""
    att = SETS[f"euler{seq}"]
    c = dcm_from(att, [0.4, b, 0.7])
    q = att.from_dcm(c)
    np.testing.assert_allclose(q, [0.4, b, 0.7], atol=1e-8)
    np.testing.assert_allclose(dcm_from(att, q), c, atol=1e-14)


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_mrp_shadow_set_is_the_same_attitude_and_motion() -> None:
    att, rng = SETS["mrp"], np.random.default_rng(7)
    for _ in range(4):
        s = random_values(att, rng)
        sd = rng.normal(size=3)
        ss, ssd = att.shadow(s, sd)
        assert np.linalg.norm(ss) == pytest.approx(1 / np.linalg.norm(s))
        np.testing.assert_allclose(dcm_from(att, ss), dcm_from(att, s), atol=1e-12)
        w = evaluate(att, att.angular_velocity, s, sd)
        np.testing.assert_allclose(evaluate(att, att.angular_velocity, ss, ssd), w, atol=1e-11)
        back, backd = att.shadow(ss, ssd)
        np.testing.assert_allclose(back, s, atol=1e-14)
        np.testing.assert_allclose(backd, sd, atol=1e-12)
    with pytest.raises(StateError, match="no shadow"):
        att.shadow([0, 0, 0], [1, 0, 0])


def test_attributes() -> None:
    kinds = {name: SETS[name].kind for name in ("euler321", "quaternion", "mrp", "planar")}
    assert kinds == {"euler321": "euler", "quaternion": "quaternion", "mrp": "mrp"} | {
        "planar": "planar"
    }
    beta = pfaff.coordinates("b0:4")
    assert SETS["quaternion"].constraint == sum(b**2 for b in beta) - 1
    assert SETS["quaternion"].coordinates == beta
    for name in ("euler321", "mrp", "planar"):
        assert SETS[name].constraint is None
    for name in ("quaternion", "mrp", "planar"):
        assert SETS[name].singularity is None
    th = pfaff.coordinates("theta")
    p = PlanarAngle(th)
    assert p.coordinates == (th,) and PlanarAngle([th]).coordinates == (th,)
    assert p.angular_velocity == sp.Matrix([0, 0, th.diff(t)])
    assert p.dcm == sp.Matrix(
        [[sp.cos(th), -sp.sin(th), 0], [sp.sin(th), sp.cos(th), 0], [0, 0, 1]]
    )
    for att in SETS.values():  # linear in the rates
        assert all(sp.diff(w, qd, 2) == 0 for w in att.angular_velocity for qd in att.rates_symbols)
        assert att.angular_velocity.subs(dict.fromkeys(att.rates_symbols, 0)) == sp.zeros(3, 1)


def test_bad_coordinates() -> None:
    a, b, c, d = pfaff.coordinates("a b c d")
    x = sp.Symbol("x")
    with pytest.raises(ModelError, match="`coords`: Quaternion needs 4 coordinates, got 3"):
        Quaternion((a, b, c))
    with pytest.raises(ModelError, match="MRP needs 3 coordinates, got 4"):
        MRP((a, b, c, d))
    with pytest.raises(ModelError, match="`angles`: EulerAngles needs 3 coordinates, got 2"):
        EulerAngles((a, b))
    with pytest.raises(ModelError, match="`angle`: PlanarAngle needs 1 coordinate, got 2"):
        PlanarAngle((a, b))
    with pytest.raises(ModelTypeError, match="`coords`: x is not a coordinate"):
        MRP((a, x, c))
    with pytest.raises(ModelTypeError, match=r"`angles`: .*a\(t\)\*\*2 is not a coordinate"):
        EulerAngles((a**2, b, c))
    with pytest.raises(ModelTypeError, match="`coords` must be a sequence of 4 coordinates"):
        Quaternion("a b c d")
    with pytest.raises(ModelTypeError, match="`coords` must be a sequence"):
        Quaternion(a)
    with pytest.raises(ModelError, match="`angles`: EulerAngles repeats the coordinate a"):
        EulerAngles((a, b, a), "313")
    with pytest.raises(ModelError, match="Quaternion repeats the coordinate b"):
        Quaternion((a, b, b, c))
    for seq in ("322", "xyz", "3213", ""):
        with pytest.raises(ModelError, match=f"`sequence` must be one of .*got '{seq}'"):
            EulerAngles((a, b, c), seq)
    assert EulerAngles((a, b, c), 313).sequence == "313"


def test_bad_numeric_input() -> None:
    q, e = SETS["quaternion"], SETS["euler321"]
    with pytest.raises(StateError, match="`values` of Quaternion must be 4 finite numbers"):
        dcm_from(q, [1, 0, 0])
    with pytest.raises(StateError, match="`values` of EulerAngles must be 3 finite numbers"):
        e.rates([0, np.nan, 0], [0, 0, 1])
    with pytest.raises(StateError, match="`omega_body` must be 3 finite numbers"):
        q.rates([1, 0, 0, 0], [0, 1])
    with pytest.raises(StateError, match="`dcm` must be a finite 3×3 array"):
        q.from_dcm(np.eye(2))
    with pytest.raises(StateError, match="`dcm` is not a rotation matrix"):
        e.from_dcm(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(StateError, match="`dcm` is not a rotation matrix"):
        SETS["mrp"].from_dcm(2 * np.eye(3))
    with pytest.raises(ModelTypeError, match="`attitude` must be an EulerAngles"):
        dcm_from(np.eye(3), [0, 0, 0])  # type: ignore[arg-type]
