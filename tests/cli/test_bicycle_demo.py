"""``pfaff demo bicycle``: the benchmark's eigenvalues and speeds, as text and JSON."""

from __future__ import annotations

import json

import pytest

from pfaff.cli.main import main

pytestmark = pytest.mark.slow  # the bicycle's equations and two root findings: about 10 s


def test_json_report(capsys) -> None:
    assert main(["demo", "bicycle", "--speed", "5", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["stable"] is True
    assert rep["max_error_vs_published_equations"] < 1e-10
    assert rep["weave_speed"] == pytest.approx(4.29238253634111, abs=1e-12)
    assert rep["capsize_speed"] == pytest.approx(6.02426201538837, abs=1e-12)
    re, im = rep["eigenvalues"][1]
    assert (re, im) == pytest.approx((-0.77534188219585, -4.46486771378823), abs=1e-10)


def test_bad_options(capsys) -> None:
    assert main(["demo", "bicycle", "--speed", "nan"]) == 2
    assert "--speed must be finite" in capsys.readouterr().err
    assert main(["demo", "bicycle", "--plot", "locus.unknown"]) == 2
