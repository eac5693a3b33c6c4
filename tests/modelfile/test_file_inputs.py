"""``[[inputs]]`` of model files (expressions of t, q, dot(q)) and the unused-name warning."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import pfaff

OSCILLATOR = """
[model]
coordinates = ["x"]
parameters = { m = 2.0, k = 8.0, F0 = 3.0, w = 1.5 }
kinetic = "m*dot(x)**2/2"
potential = "k*x**2/2"
{inputs}
[[generalized_forces]]
coordinate = "x"
expr = "{force}"
[simulate]
t_end = 6.0
"""


def _file(tmp_path: Path, inputs: str, force: str = "u", name: str = "m.toml") -> Path:
    path = tmp_path / name
    path.write_text(OSCILLATOR.replace("{inputs}", inputs).replace("{force}", force))
    return path


def test_driven_oscillator_against_closed_form(tmp_path: Path) -> None:
    """m ẍ + k x = F0 sin(w t) from rest: x = F0/(m(ωn² − w²)) (sin wt − (w/ωn) sin ωn t)."""
    path = _file(tmp_path, '[[inputs]]\nname = "u"\nvalue = "F0*sin(w*t)"\n')
    mf = pfaff.load_model(path)
    assert list(mf.inputs) == ["u"] and str(mf.inputs["u"]) == "F0*sin(t*w)"
    t = np.linspace(0.0, 6.0, 61)
    traj = pfaff.simulate(mf.compile(), mf.q0, mf.qd0, (0.0, 6.0), t_eval=t, rtol=1e-11)
    wn = np.sqrt(8.0 / 2.0)
    exact = 3.0 / (2.0 * (wn**2 - 1.5**2)) * (np.sin(1.5 * t) - 1.5 / wn * np.sin(wn * t))
    np.testing.assert_allclose(traj.q[:, 0], exact, rtol=0, atol=1e-9)
    # the work of the input's force is the energy it put in
    assert np.abs(traj.energy_balance).max() < 1e-9


def test_feedback_law_is_the_closed_loop(tmp_path: Path) -> None:
    """u = −kp x − kd ẋ: eigenvalues of m s² + kd s + (k + kp) = 0, from linearize."""
    inputs = '[[inputs]]\nname = "u"\nvalue = "-kp*x - kd*dot(x)"\n'
    path = _file(tmp_path, inputs)
    path.write_text(path.read_text().replace("F0 = 3.0, w = 1.5 }", "kp = 10.0, kd = 1.2 }"))
    mf = pfaff.load_model(path)
    eom = mf.system.equations()
    (x,) = eom.coordinates
    lin = eom.linearize({x: 0, **mf.parameters}, [x])
    exact = np.roots([2.0, 1.2, 8.0 + 10.0])
    np.testing.assert_allclose(lin.eigenvalues(), sorted(exact, key=lambda z: (z.real, z.imag)))
    # ...and the run with the law is the run of that damped oscillator
    traj = pfaff.simulate(mf.compile(), [0.1], [0.0], (0.0, 4.0), t_eval=[4.0], rtol=1e-11)
    sigma, wd = 1.2 / 4.0, np.sqrt(18.0 / 2.0 - (1.2 / 4.0) ** 2)
    x4 = 0.1 * np.exp(-sigma * 4.0) * (np.cos(wd * 4.0) + sigma / wd * np.sin(wd * 4.0))
    assert traj.q[-1, 0] == pytest.approx(x4, abs=1e-9)


def test_an_input_may_use_an_earlier_one(tmp_path: Path) -> None:
    inputs = (
        '[[inputs]]\nname = "a"\nvalue = "F0"\n[[inputs]]\nname = "u"\nvalue = "2*a*cos(w*t)"\n'
    )
    mf = pfaff.load_model(_file(tmp_path, inputs))
    assert str(mf.inputs["u"]) == "2*F0*cos(t*w)"


@pytest.mark.parametrize(
    ("inputs", "match"),
    [
        ('[[inputs]]\nname = "u"\n', r"inputs\[0\]: missing key\(s\) value"),
        ('[[inputs]]\nname = "k"\nvalue = "1"\n', r"inputs\[0\]\.name: `k` is already"),
        ('[[inputs]]\nname = "x"\nvalue = "1"\n', r"inputs\[0\]\.name: `x` is already"),
        ('[[inputs]]\nname = "t"\nvalue = "1"\n', r"inputs\[0\]\.name: 't' is reserved"),
        ('[[inputs]]\nname = "u"\nvalue = "v"\n', r"inputs\[0\]\.value: .*'v'"),
        ('[[inputs]]\nname = "u"\nvalue = "u + 1"\n', r"inputs\[0\]\.value: .*'u'"),
        ('[[inputs]]\nname = "u"\nvalue = "__import__(\'os\')"\n', r"inputs\[0\]\.value: names"),
        ('[[inputs]]\nname = "u"\nvalue = "1"\nunit = "N"\n', r"unknown key\(s\) unit"),
        ("inputs = 3\n[model2]\n", r"unknown section|array of tables"),
    ],
)
def test_bad_inputs_refused_by_key(tmp_path: Path, inputs: str, match: str) -> None:
    text = OSCILLATOR.replace("{force}", "0")
    text = text.replace("{inputs}", "") if inputs.startswith("inputs =") else text
    path = tmp_path / "bad.toml"
    if inputs.startswith("inputs ="):
        path.write_text(inputs + text)
    else:
        path.write_text(text.replace("{inputs}", inputs))
    with pytest.raises(pfaff.ModelError, match=match):  # ModelFileError or ExpressionError
        pfaff.load_model(path)


def test_unused_parameter_warns_by_name_from_loader_and_compile(tmp_path: Path) -> None:
    path = _file(tmp_path, "", force="F0*sin(w*t)")
    path.write_text(path.read_text().replace("w = 1.5 }", "w = 1.5, g = 9.81 }"))
    with pytest.warns(pfaff.ModelWarning, match=r"parameter `g` declared but not used") as rec:
        mf = pfaff.load_model(path)
    assert len(rec) == 1 and rec[0].filename == __file__  # points at the caller's line
    with pytest.warns(pfaff.ModelWarning, match=r"parameter `g` declared but not used") as rec:
        model = mf.compile()
    assert len(rec) == 1 and rec[0].filename == __file__
    assert "g" not in model.parameters and issubclass(pfaff.ModelWarning, UserWarning)
    with pytest.raises(pfaff.ParameterError, match=r"`gee` is not a parameter of the file"):
        mf.compile(gee=1.0)


def test_unused_input_and_what_only_it_uses_warn(tmp_path: Path) -> None:
    inputs = '[[inputs]]\nname = "a"\nvalue = "w"\n[[inputs]]\nname = "u"\nvalue = "a*F0"\n'
    with pytest.warns(pfaff.ModelWarning) as rec:
        pfaff.load_model(_file(tmp_path, inputs, force="k*x"))
    messages = sorted(str(r.message) for r in rec)
    assert len(messages) == 2
    assert "inputs `a`, `u` declared but not used" in messages[0]
    assert "parameters `F0`, `w` declared but not used" in messages[1]


def test_used_inputs_and_parameters_do_not_warn(tmp_path: Path) -> None:
    inputs = '[[inputs]]\nname = "a"\nvalue = "w"\n[[inputs]]\nname = "u"\nvalue = "a*F0"\n'
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pfaff.load_model(_file(tmp_path, inputs)).compile()
