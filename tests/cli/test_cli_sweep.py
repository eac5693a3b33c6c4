"""`pfaff sweep` through the `pfaff` command (the sweep itself: tests/sweep)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pfaff.cli.main import main

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "double_pendulum_damper.toml"


def test_sweep_command_in_process(capsys) -> None:
    argv = ["sweep", str(EXAMPLE), "--vary", "c=0:1:2", "--vary", "q0.theta2=0:0.5:2"]
    code = main([*argv, "--t-end", "0.5", "--samples", "5", "--scheduler", "synchronous", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["runs"] == 4 and out["failed"] == 0
    assert out["dims"] == {"c": 2, "q0.theta2": 2}
    assert np.isfinite(out["max_energy_error"])


def test_sweep_command_bad_vary(capsys) -> None:
    with pytest.raises(SystemExit) as exc:  # argparse refuses it: exit 2, the usage on stderr
        main(["sweep", str(EXAMPLE), "--vary", "c=1:0", "--scheduler", "synchronous"])
    assert exc.value.code == 2
    assert "vary" in capsys.readouterr().err
