"""``pfaff.load_urdf``: a planar double pendulum against its closed form, the 6-joint example
arm against Pinocchio (when installed) and by energy conservation, damping, and hostile files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pfaff
from pfaff.errors import ModelError
from pfaff.modelfile import urdf

G = 9.81


def _point_link(name: str, z: float, mass: float) -> str:
    return (
        f'<link name="{name}"><inertial><origin xyz="0 0 {z}"/><mass value="{mass}"/>'
        '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>'
    )


def _hinge(name: str, parent: str, child: str, z: float, extra: str = "") -> str:
    return (
        f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="0 0 {z}"/><axis xyz="0 1 0"/>'
        f'<limit lower="-3" upper="3" effort="1" velocity="1"/>{extra}</joint>'
    )


def _write(tmp_path: Path, body: str, name: str = "r.urdf") -> Path:
    p = tmp_path / name
    p.write_text(f'<?xml version="1.0"?>\n<robot name="r">{body}</robot>')
    return p


M1, M2, L1, L2 = 1.3, 0.7, 0.9, 0.6


def double_pendulum(tmp_path: Path) -> Path:
    """Two point masses hanging down (−z) from hinges about y, the second hinge at the first mass."""
    body = (
        '<link name="base"/>'
        + _point_link("upper", -L1, M1)
        + _point_link("lower", -L2, M2)
        + _hinge("shoulder", "base", "upper", 0.0)
        + _hinge("elbow", "upper", "lower", -L1)
    )
    return _write(tmp_path, body)


def test_double_pendulum_closed_form(tmp_path):
    s = pfaff.load_urdf(double_pendulum(tmp_path))
    assert list(s.urdf_coordinates) == ["shoulder", "elbow"]
    assert s.joint_limits == {"shoulder": (-3.0, 3.0), "elbow": (-3.0, 3.0)}
    assert s.urdf_values["upper.mass"] == M1 and s.urdf_values["lower.com_z"] == -L2
    model = s.equations().compile(s.urdf_values)
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = rng.uniform(-np.pi, np.pi, 2)
        qd = rng.uniform(-2, 2, 2)
        a, b = q
        c = np.cos(b)
        m_ref = np.array(
            [
                [(M1 + M2) * L1**2 + M2 * L2**2 + 2 * M2 * L1 * L2 * c, M2 * (L2**2 + L1 * L2 * c)],
                [M2 * (L2**2 + L1 * L2 * c), M2 * L2**2],
            ]
        )
        # x = −L sin(angle) for a hinge about +y, z = −L cos(angle)
        grav = -G * np.array(
            [(M1 + M2) * L1 * np.sin(a) + M2 * L2 * np.sin(a + b), M2 * L2 * np.sin(a + b)]
        )
        s2 = M2 * L1 * L2 * np.sin(b)
        h = np.array([-s2 * (2 * qd[0] * qd[1] + qd[1] ** 2), s2 * qd[0] ** 2])
        np.testing.assert_allclose(model.mass_matrix(0.0, q), m_ref, rtol=0, atol=1e-10)
        np.testing.assert_allclose(model.forcing(0.0, q, qd), grav - h, rtol=0, atol=1e-10)


def test_damping_loses_energy_at_rate_d_qdot_squared(tmp_path):
    d = 0.35
    body = (
        '<link name="base"/>'
        + _point_link("bob", -1.0, 2.0)
        + _hinge("swing", "base", "bob", 0.0, f'<dynamics damping="{d}"/>')
    )
    s = pfaff.load_urdf(_write(tmp_path, body))
    assert s.urdf_values["swing.damping"] == d
    model = s.equations().compile(s.urdf_values)
    for q, qd in ((0.4, 1.1), (-1.0, -0.3), (2.0, 2.5)):
        # Ė = q̇ (M q̈ + ∂V/∂q) = q̇ · Q_damping = −d q̇²
        qdd, _ = model.accelerations(0.0, [q], [qd])
        power = qd * (2.0 * qdd[0] + 2.0 * G * np.sin(q))  # M = m L², L = 1
        assert power == pytest.approx(-d * qd**2, abs=1e-12)


def test_point_pendulum_sign(tmp_path):
    body = '<link name="base"/>' + _point_link("bob", -0.5, 1.5) + _hinge("j", "base", "bob", 0)
    s = pfaff.load_urdf(_write(tmp_path, body))
    model = s.equations().compile(s.urdf_values)
    assert model.forcing(0.0, [0.3], [0.0])[0] == pytest.approx(-1.5 * G * 0.5 * np.sin(0.3))


def test_entity_bomb_refused(tmp_path):
    p = tmp_path / "bomb.urdf"
    p.write_text(
        '<?xml version="1.0"?>\n<!DOCTYPE lolz [<!ENTITY lol "lol">'
        '<!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">]>\n'
        '<robot name="r"><link name="&lol2;"/></robot>'
    )
    with pytest.raises(ModelError, match="DOCTYPE declaration; refused"):
        pfaff.load_urdf(p)


def test_entity_without_doctype_refused(tmp_path):
    p = _write(tmp_path, '<!ENTITY x "y"><link name="a"/>')
    with pytest.raises(ModelError, match="ENTITY"):
        pfaff.load_urdf(p)


def test_huge_file_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(urdf, "MAX_BYTES", 1000)
    p = _write(tmp_path, "<!-- " + "x" * 2000 + " -->")
    with pytest.raises(ModelError, match=f"{p.stat().st_size} bytes, above the cap of 1000"):
        pfaff.load_urdf(p)


def test_too_many_links_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(urdf, "MAX_ELEMENTS", 5)
    p = _write(tmp_path, "".join(f'<link name="l{i}"/>' for i in range(6)))
    with pytest.raises(ModelError, match="6 links, more than 5"):
        pfaff.load_urdf(p)


@pytest.mark.parametrize(
    ("value", "match"),
    [
        ("abc", "link `bob` <mass>: `value` is not a number"),
        ("nan", "must be finite"),
        ("1 2", "must be 1 number"),
    ],
)
def test_bad_number_names_the_link(tmp_path, value, match):
    body = (
        '<link name="base"/><link name="bob"><inertial><mass value="' + value + '"/>'
        '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>'
        + _hinge("j", "base", "bob", 0)
    )
    with pytest.raises(ModelError, match=match):
        pfaff.load_urdf(_write(tmp_path, body))


def test_missing_number_names_the_joint(tmp_path):
    body = '<link name="base"/>' + _point_link("bob", -1, 1) + _hinge("j", "base", "bob", 0)
    body = body.replace('<origin xyz="0 0 0"/>', '<origin xyz="0 0"/>')
    with pytest.raises(ModelError, match="joint `j` <origin>: `xyz` must be 3 number"):
        pfaff.load_urdf(_write(tmp_path, body))


def test_mimic_refused(tmp_path):
    body = (
        '<link name="base"/>'
        + _point_link("a", -1, 1)
        + _point_link("b", -1, 1)
        + _hinge("j1", "base", "a", 0)
        + _hinge("j2", "a", "b", -1, '<mimic joint="j1"/>')
    )
    with pytest.raises(ModelError, match="joint `j2`: <mimic> joints are not supported"):
        pfaff.load_urdf(_write(tmp_path, body))


@pytest.mark.parametrize("kind", ["planar", "floating"])
def test_planar_floating_refused(tmp_path, kind):
    body = (
        '<link name="base"/>'
        + _point_link("a", -1, 1)
        + f'<joint name="free" type="{kind}"><parent link="base"/><child link="a"/></joint>'
    )
    with pytest.raises(ModelError, match=f"joint `free`: {kind} joints are not supported"):
        pfaff.load_urdf(_write(tmp_path, body))


def test_transmission_refused(tmp_path):
    body = (
        '<link name="base"/>'
        + _point_link("a", -1, 1)
        + _hinge("j", "base", "a", 0)
        + '<transmission name="t1"><type>x</type></transmission>'
    )
    with pytest.raises(ModelError, match="transmission `t1`"):
        pfaff.load_urdf(_write(tmp_path, body))


def test_two_roots_refused(tmp_path):
    body = (
        '<link name="base"/><link name="other"/>'
        + _point_link("a", -1, 1)
        + _hinge("j", "base", "a", 0)
    )
    with pytest.raises(ModelError, match="one root; roots: `base`, `other`"):
        pfaff.load_urdf(_write(tmp_path, body))


def test_two_parents_and_unknown_link_refused(tmp_path):
    body = (
        '<link name="base"/>'
        + _point_link("a", -1, 1)
        + _hinge("j1", "base", "a", 0)
        + _hinge("j2", "base", "a", 0)
    )
    with pytest.raises(ModelError, match="link `a` has two parent joints"):
        pfaff.load_urdf(_write(tmp_path, body))
    body = '<link name="base"/>' + _hinge("j1", "base", "ghost", 0)
    with pytest.raises(ModelError, match="joint `j1`: link `ghost` is not defined"):
        pfaff.load_urdf(_write(tmp_path, body))


def test_names_sanitized(tmp_path):
    body = (
        '<link name="base"/>' + _point_link("arm-1", -1, 1) + _hinge("joint 1", "base", "arm-1", 0)
    )
    s = pfaff.load_urdf(_write(tmp_path, body))
    (q,) = s.urdf_coordinates.values()
    assert str(q) == "joint_1(t)" and s.urdf_links == {"arm-1": "arm_1"}
    assert "arm_1.mass" in s.urdf_values


# --- the 6-joint example arm (slow: about 3 minutes to load and compile) ----------------------
