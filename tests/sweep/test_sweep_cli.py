"""``pfaff sweep`` (pfaff.cli.sweepcmd): exit codes, messages, the summary and the output file."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from pfaff.cli import sweepcmd


def sweep(*argv: str) -> int:
    return sweepcmd.main(list(argv))


@pytest.mark.parametrize(
    ("vary", "message"),
    [
        ("L=1:2", "expected NAME=START:STOP:COUNT"),
        ("L", "expected NAME=START:STOP:COUNT"),
        ("L=1:x:3", "START and STOP must be numbers"),
        ("L=1:2:0", "COUNT must be a whole number"),
        ("L=nan:2:3", "must be finite"),
    ],
)
def test_bad_vary_syntax(pendulum, capsys, vary, message):
    assert sweep(str(pendulum), "--vary", vary, "--scheduler", "synchronous") == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--vary", "M=1:2:3"], "`M` is neither a parameter"),
        (["--vary", "q0.phi=1:2:3"], "`q0.phi` is not q0.<coordinate>"),
        (["--vary", "L=1:2:3", "--vary", "L=1:3:3"], "--vary L is given twice"),
        (["--vary", "L=1:2:3", "--output", "out.csv"], "--output must be a netCDF file"),
        (["--vary", "L=1:2:3", "--output", "/no/such/folder/out.nc"], "does not exist"),
        (["--vary", "L=1:2:3", "--t-end", "-1"], "expected a positive finite number"),
        (["--vary", "L=1:2:3", "--samples", "1"], "expected at least 2"),
        (["--vary", "L=1:2:3", "--workers", "0"], "expected at least 1"),
        (["--vary", "L=1:2:3", "--scheduler", "tcp://127.0.0.1:1"], "cannot reach the Dask"),
        (["--vary", "L=1:2:3", "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"], "`workers`"),
    ],
)
def test_errors_exit_non_zero_with_a_message(pendulum, capsys, args, message):
    code = sweep(str(pendulum), *args)
    err = capsys.readouterr().err
    assert code == 2, err
    assert message in err and "Traceback" not in err


def test_missing_or_hostile_file(tmp_path, capsys):
    assert sweep(str(tmp_path / "none.toml"), "--vary", "L=1:2:2") == 2
    assert "cannot be read" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text("[model]\ncoordinates = [\"x\"]\nkinetic = \"__import__('os').system('x')\"\n")
    assert sweep(str(bad), "--vary", "q0.x=1:2:2", "--t-end", "1") == 2
    assert "bad.toml" in capsys.readouterr().err


def test_a_sweep_with_failed_runs_exits_0_and_lists_them(pendulum, tmp_path, capsys):
    out = tmp_path / "sweep.nc"
    code = sweep(
        str(pendulum), "--vary", "L=0:2:3", "--vary", "q0.theta=0.1:0.3:2",
        "--t-end", "1", "--samples", "11", "--scheduler", "synchronous", "--output", str(out),
    )  # fmt: skip
    text = capsys.readouterr().out
    assert code == 0
    assert "6 runs over L (3) × q0.theta (2)" in text
    assert "4 succeeded, 2 failed" in text
    assert "failed at L = 0, q0.theta = 0.1: the acceleration of `theta` is undetermined" in text
    with xr.open_dataset(out) as ds:
        ds.load()
    assert ds.q.dims == ("L", "q0.theta", "time", "coordinate")
    assert ds.L.values.tolist() == [0.0, 1.0, 2.0]  # STOP included
    assert ds.time.values.tolist() == pytest.approx(np.linspace(0, 1, 11).tolist())
    assert ds.status.values.tolist() == [["failed", "failed"], ["success"] * 2, ["success"] * 2]


def test_json_summary(cartesian, capsys):
    code = sweep(
        str(cartesian), "--vary", "qd0.x=0:1:2", "--samples", "5", "--scheduler", "synchronous",
        "--json",
    )  # fmt: skip
    assert code == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["runs"] == 2 and rep["succeeded"] == 2 and rep["failed"] == 0
    assert rep["dims"] == {"qd0.x": 2} and rep["failures"] == []
    assert rep["t_end"] == 2.0 and rep["samples"] == 5 and rep["output"] is None
    assert rep["max_constraint_residual"] < 1e-9
