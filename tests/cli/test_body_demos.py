"""``pfaff demo tumble|top|disk``: their reported numbers against closed forms."""

from __future__ import annotations

import json

import pytest

from pfaff.cli.main import main


def _json(capsys, *argv: str) -> tuple[int, dict]:
    code = main(["demo", *argv, "--json"])
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.slow  # an end-to-end run of the demo (the physics: tests/integrate)
@pytest.mark.parametrize("attitude", ["quaternion", "mrp", "euler"])
def test_tumble_period_and_invariants(capsys, attitude) -> None:
    code, rep = _json(capsys, "tumble", "--attitude", attitude)
    assert code == 0 and rep["status"] == "success"
    assert rep["period_measured"] == pytest.approx(rep["period_exact"], rel=1e-6)
    assert rep["energy_error"] < 1e-8 and rep["angular_momentum_error"] < 1e-8
    assert (len(rep["switches"]) > 0) == (attitude == "mrp")
    if attitude == "euler":
        assert rep["sequence"] == "231"


@pytest.mark.slow  # an end-to-end run of the demo (the physics: tests/integrate)
def test_top_holds_its_precession(capsys) -> None:
    code, rep = _json(capsys, "top", "--attitude", "mrp")
    assert code == 0
    assert rep["nutation_max_deviation"] < 1e-8


@pytest.mark.slow  # an end-to-end run of the demo (the physics: tests/integrate)
def test_disk_normal_force_is_the_weight(capsys, tmp_path) -> None:
    png = tmp_path / "disk.png"
    code, rep = _json(capsys, "disk", "--t-end", "1", "--plot", str(png))
    assert code == 0 and png.stat().st_size > 0
    assert rep["normal_force_mean"] == pytest.approx(rep["weight"], rel=1e-9)
    assert rep["lean_max_deviation"] < 1e-8


def test_bad_plot_file_refused_before_running(capsys, tmp_path) -> None:
    code = main(["demo", "top", "--plot", str(tmp_path / "nope" / "x.png")])
    assert code == 2
    assert "does not exist" in capsys.readouterr().err
