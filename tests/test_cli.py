"""The command line: the ring demo's text, JSON and plot."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from pfaff.cli import main


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


def test_console_script_runs() -> None:
    res = subprocess.run(
        [sys.executable, "-m", "pfaff.cli", "demo", "ring", "--particles", "3", "--json"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert json.loads(res.stdout)["theta_ddot"] == pytest.approx(2.0, abs=1e-12)
