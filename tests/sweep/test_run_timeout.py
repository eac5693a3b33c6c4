"""A sweep's per-run time limit: a run over ``run_timeout`` is marked "timeout", the sweep goes on."""

from __future__ import annotations

import numpy as np
import pytest

import pfaff

SPRING = """
[model]
coordinates = ["x"]
parameters = { m = 1.0, k = 1.0 }
kinetic = "m*dot(x)**2/2"
potential = "k*x**2/2"
[initial]
q = { x = 1.0 }
[simulate]
t_end = 10.0
"""


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_a_run_over_its_time_limit_is_marked_and_the_sweep_goes_on(tmp_path) -> None:
    path = tmp_path / "spring.toml"
    path.write_text(SPRING)
    # k = 1: ~10^3 steps (milliseconds). k = 1e12: 1.6e6 periods over 10 s, ~10^8 steps (hours).
    ds = pfaff.sweep(path, {"k": [1.0, 1e12]}, samples=11, scheduler="synchronous", run_timeout=1.0)
    assert ds.status.values.tolist() == ["success", "timeout"]
    assert ds.attrs["status"] == "complete"
    assert "timed out" in str(ds.message.values[1]) and "max_seconds = 1 s" in str(
        ds.message.values[1]
    )
    t = ds.time.values
    np.testing.assert_allclose(ds.q.sel(k=1.0, coordinate="x").values, np.cos(t), atol=1e-7)
    slow = ds.q.sel(k=1e12, coordinate="x").values
    assert slow[0] == 1.0 and np.isnan(slow[-1])  # its start kept, its unreached samples NaN


@pytest.mark.parametrize("bad", [0, -1.0, float("inf"), float("nan"), "3", True])
def test_bad_run_timeout_is_refused(tmp_path, bad) -> None:
    path = tmp_path / "spring.toml"
    path.write_text(SPRING)
    with pytest.raises(pfaff.OptionError, match="`run_timeout` must be a positive number"):
        pfaff.sweep(path, {"k": [1.0]}, scheduler="synchronous", run_timeout=bad)


def test_simulate_max_seconds_refused_when_not_positive() -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    with pytest.raises(pfaff.OptionError, match="`max_seconds` must be a positive number"):
        pfaff.simulate(model, [1, 0], [0, 0], (0, 1), max_seconds=-1)


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_cli_run_timeout(tmp_path, capsys) -> None:
    import json

    from pfaff.cli.main import main

    path = tmp_path / "spring.toml"
    path.write_text(SPRING)
    argv = ["sweep", str(path), "--vary", "k=1:1e12:2", "--samples", "5"]
    code = main([*argv, "--scheduler", "synchronous", "--run-timeout", "1", "--json"])
    rep = json.loads(capsys.readouterr().out)
    assert code == 0 and rep["runs"] == 2 and rep["succeeded"] == 1
    assert rep["failures"] == [
        {"point": {"k": 1e12}, "status": "timeout", "message": rep["failures"][0]["message"]}
    ]
    assert rep["failures"][0]["message"].startswith("timed out at t = ")
