"""``pfaff equations robot.urdf`` and ``pfaff run robot.urdf --t-end T --q0 name=value``: a
pendulum (a point mass of 2 kg, 1 m below a hinge about y) against its closed-form equation
−m g L sin θ and against SciPy's DOP853 on θ̈ = −(g/L) sin θ; the default state q0 = q̇0 = 0 (it
hangs at rest); refused ``--q0`` names and values."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from pfaff.cli import main

PENDULUM = """<robot name="pendulum">
  <link name="base"/>
  <link name="bob"><inertial><origin xyz="0 0 -1"/><mass value="2"/>
    <inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="hinge" type="continuous"><parent link="base"/><child link="bob"/>
    <axis xyz="0 1 0"/></joint>
</robot>"""


@pytest.fixture
def urdf(tmp_path):
    path = tmp_path / "pendulum.urdf"
    path.write_text(PENDULUM)
    return path


def _value(text: str, values: dict) -> sp.Expr:
    """A printed entry at the file's values (the test's own parse of pfaff's output)."""
    names = {k: sp.Symbol(k.replace(".", "__")) for k in values}
    for k in sorted(values, key=len, reverse=True):
        text = text.replace(k, k.replace(".", "__"))
    theta = sp.Symbol("hinge")
    e = sp.sympify(text, locals={"hinge": theta, **{str(s): s for s in names.values()}})
    return e.subs({names[k]: v for k, v in values.items()}), theta


def test_equations_of_a_urdf(urdf, capsys):
    assert main(["equations", str(urdf), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["model"] == "pendulum" and rep["coordinates"] == ["hinge"]
    values = rep["parameters"]
    assert values["bob.mass"] == 2 and values["bob.com_z"] == -1 and values["gravity"] == 9.81
    m, theta = _value(rep["mass_matrix"][0][0], values)
    assert abs(float(m) - 2.0) < 1e-12  # m L²
    f, theta = _value(rep["forcing"][0], values)
    for th in (0.3, 1.2, -2.0):  # −m g L sin θ
        assert abs(float(f.subs(theta, th)) + 2 * 9.81 * math.sin(th)) < 1e-12


def test_run_a_urdf_from_q0(urdf, capsys):
    code = main(["run", str(urdf), "--t-end", "1.5", "--q0", "hinge=1.0", "--json"])
    assert code == 0
    rep = json.loads(capsys.readouterr().out)
    ref = solve_ivp(
        lambda _t, y: [y[1], -9.81 * math.sin(y[0])], (0, 1.5), [1.0, 0.0],
        method="DOP853", rtol=1e-12, atol=1e-12,
    )  # fmt: skip
    assert abs(rep["q_final"][0] - ref.y[0, -1]) < 1e-6
    assert abs(rep["qd_final"][0] - ref.y[1, -1]) < 1e-6


def test_run_a_urdf_defaults_to_rest(urdf, capsys):
    assert main(["run", str(urdf), "--t-end", "0.5", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert np.abs(rep["q_final"]).max() < 1e-12 and np.abs(rep["qd_final"]).max() < 1e-12


@pytest.mark.parametrize(
    ("arg", "match"),
    [("elbow=1", "coordinate name"), ("hinge", "name=value"), ("hinge=inf", "finite"),
     ("hinge=__import__('os')", "finite")],
)  # fmt: skip
def test_bad_q0_refused(urdf, capsys, arg, match):
    assert main(["run", str(urdf), "--t-end", "0.1", "--q0", arg]) == 2
    assert match in capsys.readouterr().err
