"""Model files: the examples against the Python API, and hostile or malformed files."""

from __future__ import annotations

import json
import os
import resource
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.cli.main import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
ISSUE_FILE = EXAMPLES / "double_pendulum_damper.toml"


def test_issue_example_matches_the_python_api() -> None:
    mf = pfaff.load_model(ISSUE_FILE)
    assert mf.name == "double pendulum with a damper"
    assert mf.parameters == {"m1": 1.0, "m2": 2.0, "l1": 1.0, "l2": 0.5, "g": 9.81, "c": 0.1}
    np.testing.assert_array_equal(mf.q0, [1.0, 0.0])
    assert mf.simulate == {"t_end": 10.0, "method": "projection"}
    th1, th2 = pfaff.coordinates("theta1 theta2")
    m1, m2, l1, l2, g, c = sp.symbols("m1 m2 l1 l2 g c")
    s = pfaff.System([th1, th2])
    r1 = [l1 * sp.sin(th1), -l1 * sp.cos(th1)]
    r2 = [l1 * sp.sin(th1) + l2 * sp.sin(th2), -l1 * sp.cos(th1) - l2 * sp.cos(th2)]
    s.add_particle(m1, r1)
    s.add_particle(m2, r2)
    s.add_potential_energy(g * (m1 * r1[1] + m2 * r2[1]))  # gravity along −y
    relative = c * (th2.diff(pfaff.t) - th1.diff(pfaff.t))  # the damper's torque on each link
    s.add_generalized_force(th1, relative)
    s.add_generalized_force(th2, -relative)
    ref, got = s.equations(), mf.system.equations()
    assert sp.simplify(ref.mass_matrix - got.mass_matrix) == sp.zeros(2, 2)
    assert sp.simplify(ref.forcing - got.forcing) == sp.zeros(2, 1)


def _run_json(capsys, *argv: str) -> tuple[int, dict]:
    code = main([*argv, "--json"])
    return code, json.loads(capsys.readouterr().out)


def test_run_pendulum_file_against_python(capsys, tmp_path) -> None:
    out = tmp_path / "run.csv"
    code, rep = _run_json(capsys, "run", str(EXAMPLES / "pendulum.toml"), "--output", str(out))
    assert code == 0 and rep["status"] == "success"
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    a = 1.0
    tr = pfaff.simulate(model, [np.sin(a), -np.cos(a)], [0, 0], (0, 5.0))
    np.testing.assert_allclose(rep["q_final"], tr.q[-1], rtol=0, atol=1e-12)
    assert rep["multiplier_names"] == tr.multiplier_names
    assert rep["energy_balance_error"] < 1e-7 and rep["max_constraint_residual"] < 1e-10
    header = out.read_text().splitlines()[0]
    assert header.split(",")[:3] == ["t", "x", "y"] and "lambda1" in header


def test_run_ring_file_pushed_law(capsys) -> None:
    code, rep = _run_json(capsys, "run", str(EXAMPLES / "ring_push.toml"))
    assert code == 0
    # x(t) = x0 + F t^2 / (4 M), friction -F/2 (DESIGN.md)
    assert rep["q_final"][0] == pytest.approx(np.pi / 2 + 2.0 * 4.0 / 4.0, abs=1e-9)
    assert rep["multipliers_final"][0] == pytest.approx(-1.0, abs=1e-9)


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_run_rolling_disk_and_slider_crank(capsys) -> None:
    code, rep = _run_json(capsys, "run", str(EXAMPLES / "rolling_disk.toml"))
    assert code == 0
    assert rep["q_final"][0] == pytest.approx(3.0 * 3.0, rel=1e-9)  # upright: x = r φ̇ t
    model = pfaff.models.rolling_disk().equations().compile({"m": 1, "r": 0.5, "g": 9.81})
    q = np.array([0.1, 0.2, 0.5 * np.cos(0.3), 0.4, 0.3, 0.5])
    mf = pfaff.load_model(EXAMPLES / "rolling_disk.toml")
    qd = np.array([0.0, 0.0, 0.0, 1.0, 0.2, 2.0])
    q, qd = pfaff.consistent_state(model, q, qd, ["psi", "theta", "phi"])
    a, b = model.accelerations(0.0, q, qd), mf.compile().accelerations(0.0, q, qd)
    np.testing.assert_allclose(a[0], b[0], atol=1e-12)
    np.testing.assert_allclose(a[1], b[1], atol=1e-12)
    code, rep = _run_json(capsys, "run", str(EXAMPLES / "slider_crank.toml"), "--t-end", "1")
    assert code == 0 and rep["max_constraint_residual"] < 1e-9
    assert rep["energy_balance_error"] < 1e-6  # the motor's work accounted for
    assert rep["nc_work"] > 0


def test_equations_json_contract(capsys) -> None:
    code, rep = _run_json(capsys, "equations", str(EXAMPLES / "pendulum.toml"))
    assert code == 0
    for key in ("coordinates", "mass_matrix", "forcing", "constraint_matrix", "constraint_bias",
                "multipliers", "lagrange_equations"):  # fmt: skip
        assert key in rep
    assert rep["coordinates"] == ["x", "y"]
    assert rep["mass_matrix"] == [["m", "0"], ["0", "m"]]
    assert rep["constraint_matrix"] == [["2*x", "2*y"]]
    assert rep["multipliers"] == ["lambda1"]
    lhs, rhs = rep["lagrange_equations"][0].split(" = ")
    ddot, x, m, lam = sp.Function("ddot"), *sp.symbols("x m lambda1")
    ns = {"ddot": ddot, "x": x, "m": m, "lambda1": lam}  # our own output, parsed in the test
    assert sp.sympify(lhs, locals=ns) - sp.sympify(rhs, locals=ns) == m * ddot(x) - 2 * lam * x


def test_flags_override_the_file(capsys) -> None:
    code, rep = _run_json(capsys, "run", str(ISSUE_FILE), "--t-end", "0.5", "--method", "baumgarte")
    assert code == 0 and rep["t_end"] == 0.5 and rep["method"] == "baumgarte"


# ---------------------------------------------------------------------------- hostile files
def _write(tmp_path: Path, text: str | bytes, name: str = "m.toml") -> Path:
    p = tmp_path / name
    (p.write_bytes if isinstance(text, bytes) else p.write_text)(text)
    return p


BASE = """
[model]
coordinates = ["q"]
parameters = {{ m = 1.0 }}
[[particles]]
mass = "m"
position = ["{expr}", "0"]
"""


@pytest.mark.parametrize(
    "expr",
    [
        "__import__('os').system('touch PWNED')",
        "().__class__.__bases__[0].__subclasses__()",
        "(lambda: 1)()",
        "[x for x in ()]",
        "q.__globals__",
        "open('PWNED', 'w')",
        "eval('1')",
        "10**10**10",
        "9**9**9**9",
        "(" * 5000 + "q" + ")" * 5000,
        "sin(q, m)",
        "q if m else q",
        "unknown_name*q",
    ],
)
def test_hostile_expressions_run_nothing(tmp_path, monkeypatch, capsys, expr) -> None:
    monkeypatch.chdir(tmp_path)
    p = _write(tmp_path, BASE.format(expr=expr.replace('"', "'")))
    code = main(["run", str(p), "--t-end", "1"])
    assert code == 2
    err = capsys.readouterr().err
    assert str(p) in err and "particles[0].position[0]" in err
    assert "Traceback" not in err
    assert not (tmp_path / "PWNED").exists()


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (b"\x00\xff\xfe garbage \x89PNG", "not UTF-8|not valid TOML"),
        ("[model\ncoordinates = [", "not valid TOML"),
        ('[model]\ncoordinates = ["q"]\nparameters = { m = nan }\n', "finite|NaN|nan"),
        ('[model]\ncoordinates = ["q"]\nparameters = { m = inf }\n', "finite|inf"),
        ('[model]\ncoordinates = ["q"]\nparameters = { m = "1.0" }\n', "number|string"),
        ('[model]\ncoordinates = ["q", "q"]\n', "named twice"),
        ('[model]\ncoordinates = ["__class__"]\n', "_"),
        ('[model]\ncoordinates = ["q"]\n[exploit]\na = 1\n', "unknown section"),
        (
            '[model]\ncoordinates = ["q"]\nparameters = { m = 1.0 }\n[initial]\nq = { z = 1.0 }\n',
            "not a coordinate",
        ),
    ],
)
def test_malformed_files_are_refused(tmp_path, capsys, text, match) -> None:
    p = _write(tmp_path, text)
    assert main(["equations", str(p)]) == 2
    err = capsys.readouterr().err
    assert str(p) in err
    import re

    assert re.search(match, err), err


def test_huge_file_refused_without_reading_it(tmp_path, capsys) -> None:
    p = tmp_path / "huge.toml"
    with p.open("wb") as fh:  # 100 MB, sparse: refused by its size before any read
        fh.truncate(100 * 1024 * 1024)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    assert main(["run", str(p)]) == 2
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 50 * 1024  # < 50 MB
    assert "above the cap" in capsys.readouterr().err
    with pytest.raises(pfaff.ModelFileError, match="above the cap"):
        pfaff.load_model(p)


def test_cap_can_be_raised(tmp_path) -> None:
    text = ISSUE_FILE.read_text() + "#" * 2_000_000 + "\n"
    p = _write(tmp_path, text)
    with pytest.raises(pfaff.ModelFileError, match="above the cap"):
        pfaff.load_model(p)
    assert pfaff.load_model(p, max_bytes=4_000_000).system.n == 2


def test_nothing_is_evaluated_while_loading(monkeypatch) -> None:
    import builtins

    def refuse(*a, **k):
        raise AssertionError("evaluated")

    monkeypatch.setattr(builtins, "eval", refuse)
    monkeypatch.setattr(builtins, "exec", refuse)
    monkeypatch.setattr(sp, "sympify", refuse)
    monkeypatch.setattr(sp, "parse_expr", refuse, raising=False)
    mf = pfaff.load_model(ISSUE_FILE)
    assert mf.system.n == 2


def test_symlink_and_folder_are_errors(tmp_path, capsys) -> None:
    assert main(["run", str(tmp_path)]) == 2
    assert main(["run", str(tmp_path / "missing.toml")]) == 2
    err = capsys.readouterr().err
    assert "cannot be read" in err or "not a regular file" in err
    assert os.path.exists(tmp_path)


def test_run_output_netcdf_of_an_unconstrained_model_reads_back(tmp_path, capsys) -> None:
    import xarray as xr

    out = tmp_path / "run.nc"
    code, rep = _run_json(capsys, "run", str(ISSUE_FILE), "--t-end", "1", "--output", str(out))
    assert code == 0
    with xr.open_dataset(out) as ds:
        np.testing.assert_allclose(ds["q"].values[-1], rep["q_final"], rtol=0, atol=0)
        assert ds.attrs["multipliers"] == 0


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_body_attitude_as_a_table(tmp_path) -> None:
    text = """
[model]
coordinates = ["s1", "s2", "s3"]
parameters = { m = 1.0 }
[[bodies]]
name = "box"
mass = "m"
inertia = [1.0, 2.0, 3.0]
position = [0, 0, 0]
attitude = { kind = "mrp", coordinates = ["s1", "s2", "s3"] }
"""
    mf = pfaff.load_model(_write(tmp_path, text))
    (body,) = mf.system.bodies
    assert body.name == "box" and body.attitude.kind == "mrp"
    assert mf.system.equations().mass_matrix[0, 0] != 0
