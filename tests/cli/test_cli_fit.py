"""``pfaff fit MODEL.toml data.csv --fit NAME=GUESS``: the damped pendulum's (c, l) recovered from
the CSV of a run at the true values (every coordinate and rate column observed)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import pfaff
from pfaff.cli.main import main

MODEL = """
[model]
name = "damped pendulum"
coordinates = ["theta"]
parameters = { m = 1.0, l = 1.0, g = 9.81, c = 0.1 }
potential = "-m*g*l*cos(theta)"
dissipation = "c*dot(theta)**2/2"

[[particles]]
mass = "m"
position = ["l*sin(theta)", "-l*cos(theta)"]

[initial]
q = { theta = 0.6 }
"""


@pytest.fixture()
def files(tmp_path: Path) -> tuple[str, str]:
    model_path = tmp_path / "pendulum.toml"
    model_path.write_text(MODEL)
    truth = pfaff.load_model(model_path).compile(l=0.8, c=0.05)
    t = np.linspace(0, 3, 61)
    run = pfaff.simulate(truth, [0.6], [0.0], (0, 3), t_eval=t, rtol=1e-12, atol=1e-14)
    data = tmp_path / "data.csv"
    run.to_csv(data)
    return str(model_path), str(data)


def test_fit_json(files, capsys):
    code = main(["fit", *files, "--fit", "c=0.1", "--fit", "l=1.0", "--json", "--rtol", "1e-11"])
    rep = json.loads(capsys.readouterr().out)
    assert code == 0 and rep["status"] == "success"
    assert rep["observed"] == ["theta", "theta_dot"]
    assert rep["estimates"]["c"] == pytest.approx(0.05, rel=1e-6)
    assert rep["estimates"]["l"] == pytest.approx(0.8, rel=1e-6)
    assert set(rep["standard_errors"]) == {"c", "l"}


def test_fit_text_with_observe(files, capsys):
    code = main(["fit", *files, "--fit", "c=0.1", "--fit", "l=0.9", "--observe", "theta"])
    out = capsys.readouterr().out
    values = {
        line.split("=")[0].strip(): float(line.split("=")[1].split("±")[0])
        for line in out.splitlines()
        if line.startswith("  ")
    }
    assert code == 0 and "(theta)" in out
    assert values["c"] == pytest.approx(0.05, rel=1e-6)
    assert values["l"] == pytest.approx(0.8, rel=1e-6)


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda text: text.replace("t,", "time,", 1), "no column `t`"),
        (lambda text: text.replace("\n0.05", "\n__import__('os')", 1), "is not a finite number"),
        (lambda text: text.replace("\n0.05", "\nnan", 1), "is not a finite number"),
    ],
)
def test_bad_data_refused(files, capsys, edit, message):
    model, data = files
    text = Path(data).read_text()
    Path(data).write_text(edit(text))
    assert main(["fit", model, data, "--fit", "c=0.1"]) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("spec", ["c", "c=abc", "os.system=1", "c=inf"])
def test_bad_fit_flag(files, capsys, spec):
    with pytest.raises(SystemExit) as e:
        main(["fit", *files, "--fit", spec])
    assert e.value.code == 2
    assert "--fit" in capsys.readouterr().err


def test_unknown_parameter(files, capsys):
    assert main(["fit", *files, "--fit", "zz=1"]) == 2
    assert "'zz' is neither a parameter" in capsys.readouterr().err
