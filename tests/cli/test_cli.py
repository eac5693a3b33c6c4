"""The command line: the ring demo's text, JSON and plot."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pfaff.cli import main


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_ring_json_64(capsys: pytest.CaptureFixture[str]) -> None:
    """The issue's check through the CLI: N = 64, M = 1, r = 0.5, F = 2."""
    code = main(
        [
            "demo",
            "ring",
            "--particles",
            "64",
            "--force",
            "2",
            "--mass",
            "1",
            "--radius",
            "0.5",
            "--json",
        ]
    )
    assert code == 0
    rep = json.loads(capsys.readouterr().out)
    assert abs(rep["theta_ddot"] - 2.0) < 1e-9
    assert abs(rep["friction"] + 1.0) < 1e-9
    assert abs(rep["x_ddot"] - 1.0) < 1e-9
    assert len(rep["multipliers"]) == 64
    assert rep["constraint_residual"] < 1e-9
    assert rep["reduced_equation"] == "2*M*r**2*theta1'' = F*r"
    assert {"build", "derive", "compile", "solve", "total"} <= set(rep["timings"])
    assert rep["back_substitution_max_difference"] < 1e-12


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_ring_text_and_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "ring.png"
    assert main(["demo", "ring", "--particles", "5", "--plot", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Pfaffian constraint matrix" in text and "λ_1 = -1" in text
    assert "2*M*r**2*theta1'' = F*r" in text
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp file left


def test_plot_into_missing_folder_is_clean_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["demo", "ring", "--plot", str(tmp_path / "nope" / "x.png")]) == 2
    assert "does not exist" in capsys.readouterr().err


@pytest.mark.parametrize("args", [["--particles", "1"], ["--particles", "abc"], ["--force", "nan"]])
def test_bad_arguments(args: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main(["demo", "ring", *args])
    assert e.value.code == 2
    assert "error" in capsys.readouterr().err


@pytest.mark.slow
def test_console_script_runs() -> None:
    res = subprocess.run(
        [sys.executable, "-m", "pfaff.cli", "demo", "ring", "--particles", "3", "--json"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert json.loads(res.stdout)["theta_ddot"] == pytest.approx(2.0, abs=1e-12)


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_ring_simulate_json(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """x(t) = x₀ + r θ̇₀ t + F t²/(4M) and friction −F/2 throughout, through the CLI."""
    out = tmp_path / "ring.nc"
    code = main(
        ["demo", "ring", "-N", "5", "--force", "3", "--mass", "2", "--radius", "0.25",
         "--theta-dot", "1.5", "--simulate", "--t-end", "1.5", "--output", str(out), "--json"]
    )  # fmt: skip
    assert code == 0
    rep = json.loads(capsys.readouterr().out)
    x0 = 0.25 * np.pi  # θ₁ = π, no slip
    assert rep["x_exact_final"] == pytest.approx(x0 + 0.25 * 1.5 * 1.5 + 3 * 1.5**2 / 8, rel=1e-14)
    assert rep["max_x_error"] < 1e-9
    assert rep["friction_min"] == pytest.approx(-1.5, abs=1e-9)
    assert rep["friction_max"] == pytest.approx(-1.5, abs=1e-9)
    assert rep["max_position_residual"] <= 1e-10
    assert rep["energy_balance_error"] < 1e-8
    import xarray as xr

    with xr.open_dataset(out) as ds:
        assert ds["q"].shape == (rep["points"], 6)
        assert float(ds["multipliers"][-1, 0]) == pytest.approx(-1.5, abs=1e-9)


@pytest.mark.parametrize("method", ["projection", "ida"])
def test_pendulum_simulate_tension(
    method: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """Released from horizontal, the rod tension peaks at 3 m g at the bottom."""
    csv_path = tmp_path / "p.csv"
    code = main(
        ["demo", "pendulum", "--mass", "2", "--length", "0.5", "--simulate", "--t-end", "1.0",
         "--method", method, "--output", str(csv_path), "--json"]
    )  # fmt: skip
    assert code == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["max_tension_exact"] == pytest.approx(3 * 2 * 9.81)
    # the reported points bracket the bottom only approximately: tension there is 3mg − O(Δt²)
    assert rep["max_tension"] == pytest.approx(3 * 2 * 9.81, rel=2e-3)
    assert rep["max_position_residual"] <= 1e-10
    header = csv_path.read_text().splitlines()[0].split(",")
    assert header[:3] == ["t", "x", "y"] and "lambda1" in header


def test_pendulum_text_and_bad_output(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main(["demo", "pendulum", "--angle", "0"]) == 0
    text = capsys.readouterr().out
    assert "rod tension −2Lλ = 9.81" in text  # hanging at rest: m g
    bad = tmp_path / "x.txt"
    code = main(["demo", "pendulum", "--simulate", "--t-end", "0.1", "--output", str(bad)])
    assert code == 2
    assert ".nc or .csv" in capsys.readouterr().err
    assert not bad.exists()
