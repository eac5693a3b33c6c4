"""``[[contacts]]`` and ``[[events]]`` in model files, and what ``pfaff run`` reports of them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import pfaff
from pfaff.cli.main import main
from pfaff.errors import PfaffError

EXAMPLE = Path(__file__).parents[2] / "examples" / "bouncing_ball.toml"


def test_example_loads_contacts_and_events():
    """The example's ball bounces at t₁ = √(2h/g) and t₂ = t₁ + 2e√(2h/g); its apex event
    falls between them at t₁ + e√(2h/g)."""
    mf = pfaff.load_model(EXAMPLE)
    assert [c.name for c in mf.system.contacts] == ["floor"]
    assert [e.name for e in mf.system.events] == ["apex"]
    model = mf.compile()
    traj = pfaff.simulate(model, mf.q0, mf.qd0, (0.0, 2.0), rtol=1e-12, atol=1e-14)
    t1, e = np.sqrt(2 * 1.0 / 9.81), 0.8
    kinds = [(r.name, r.kind) for r in traj.events[:3]]
    assert kinds == [("floor", "impact"), ("apex", "event"), ("floor", "impact")]
    times = [r.t for r in traj.events[:3]]
    np.testing.assert_allclose(times, [t1, t1 + e * t1, t1 + 2 * e * t1], rtol=1e-10)


def test_run_reports_impacts(capsys, tmp_path):
    out = tmp_path / "run.nc"
    assert main(["run", str(EXAMPLE), "--t-end", "1.5", "--json", "--output", str(out)]) == 0
    rep = json.loads(capsys.readouterr().out)
    floor = [e for e in rep["events"] if e["name"] == "floor"]
    assert [e["kind"] for e in floor] == ["impact", "impact"]
    v1 = np.sqrt(2 * 9.81)  # the first impact loses ½ m v₁²(1 − e²), the second e² of that
    lost = 0.5 * 0.5 * v1**2 * (1 - 0.8**2) * (1 + 0.8**2)
    assert rep["impact_work"] == pytest.approx(-lost, rel=1e-8)
    assert rep["energy_balance_error"] < 1e-8
    assert rep["max_position_residual"] < 1e-10  # the open floor's gap is not a residual
    assert main(["run", str(EXAMPLE), "--t-end", "1.5"]) == 0
    text = capsys.readouterr().out
    assert "floor impact at t = 0.4515236" in text and "impacts: 2" in text
    xr = pytest.importorskip("xarray")
    ds = xr.load_dataset(out)
    assert "impact" in [str(k) for k in ds["event_kind"].values]


@pytest.mark.parametrize(
    ("table", "match"),
    [
        ('[[contacts]]\nname = "floor"\n', "missing key"),
        ('[[contacts]]\ngap = "y"\nrestitution = 2\n', r"\[0, 1\]"),
        ("[[contacts]]\ngap = \"__import__('os')\"\n", "contacts\\[0\\].gap: names starting"),
        ('[[events]]\ncondition = "y"\ndirection = 2\n', "direction"),
        ('[[events]]\ncondition = "y"\nterminal = "yes"\n', "terminal"),
        ('[[events]]\ncondition = "y"\nwhen = 1\n', "unknown key"),
    ],
)
def test_bad_tables(tmp_path, table, match):
    text = EXAMPLE.read_text().split("[[contacts]]")[0] + table
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(PfaffError, match=match):  # ModelFileError, or the parser's own
        pfaff.load_model(path)


def test_sweep_batch_over_restitution():
    """A sweep's runs (in process) over e: the contact's multiplier column and name, the states
    at the samples only (not the impacts' own), and the rebound height e² h after the first
    impact, at t₁ + e t₁ (the first apex)."""
    from pfaff.sweep.grid import Grid
    from pfaff.sweep.worker import SweepSpec, run_batch

    t1 = np.sqrt(2 / 9.81)
    es = np.array([0.5, 0.8])
    t_eval = np.array([0.0, 0.2, t1 + 0.5 * t1, t1 + 0.8 * t1])
    spec = SweepSpec(
        EXAMPLE.read_text(), EXAMPLE.name, {"m": 0.5, "g": 9.81, "e": 0.8}, (0.0, 1.0),
        (0.0, 0.0), ("x", "y"), Grid(("e",), (es,)), t_eval, {"rtol": 1e-12, "atol": 1e-14},
    )  # fmt: skip
    out = run_batch(spec, [0, 1])
    assert out["status"] == ["success", "success"]
    assert out["constraint_names"] == ["floor"] and out["multipliers"].shape == (2, 4, 1)
    np.testing.assert_allclose(out["q"][[0, 1], [2, 3], 1], es**2, rtol=1e-10)
    np.testing.assert_allclose(out["q"][:, 1, 1], 1 - 0.5 * 9.81 * 0.2**2, rtol=1e-12)
    assert (out["constraint_residual"] < 1e-12).all()
