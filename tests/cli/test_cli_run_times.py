"""``pfaff run``: the reported times (201 equally spaced by default, ``--steps``, ``--samples``,
fewer for huge families) and a ``--help`` that gives every option's default."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from pfaff.cli import main
from pfaff.cli.simdemo import STATE_BYTES, TRAJECTORY_BYTES, reported_times

RING = Path(__file__).resolve().parents[2] / "examples" / "ring_push.toml"
X0, F, M, T_END = np.pi / 2, 2.0, 1.0, 2.0  # the file's x(0), push, mass and [simulate] t_end


def _rows(path: Path) -> dict[str, np.ndarray]:
    with path.open() as fh:
        rows = list(csv.reader(fh))
    return {name: np.array([float(r[j]) for r in rows[1:]]) for j, name in enumerate(rows[0])}


def test_default_is_201_equally_spaced_times_on_the_motion(tmp_path: Path, capsys) -> None:
    """The pushed ring from rest: ẍ = F/(2M), so x = x0 + F t²/(4M) at every reported time."""
    out = tmp_path / "run.csv"
    assert main(["run", str(RING), "--output", str(out), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    cols = _rows(out)
    np.testing.assert_allclose(cols["t"], np.linspace(0.0, T_END, 201), rtol=0, atol=1e-15)
    np.testing.assert_allclose(cols["x"], X0 + F * cols["t"] ** 2 / (4 * M), rtol=0, atol=1e-10)
    assert rep["points"] == 201 and rep["stats"]["steps"] < 20  # far fewer steps than times


def test_steps_reports_the_integrator_steps(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run.csv"
    assert main(["run", str(RING), "--steps", "--output", str(out), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    t = _rows(out)["t"]
    assert len(t) == rep["points"] == rep["stats"]["steps"] + 1  # the start and every step
    assert t[0] == 0.0 and t[-1] == T_END and np.all(np.diff(t) > 0)


def test_samples_and_steps_exclude_each_other(capsys) -> None:
    assert main(["run", str(RING), "--samples", "11", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["points"] == 11
    with pytest.raises(SystemExit) as e:
        main(["run", str(RING), "--samples", "11", "--steps"])
    assert e.value.code == 2 and "not allowed with argument" in capsys.readouterr().err


@pytest.mark.parametrize("states", [10, 50, 200])
def test_fewer_times_where_the_states_would_not_fit(states: int) -> None:
    """A family of n + m rows: as many times as fit in TRAJECTORY_BYTES at 48 (n + m) bytes."""
    rows = TRAJECTORY_BYTES // (STATE_BYTES * states)  # n + m at which `states` states fit
    t = reported_times(3.0, rows // 2, rows - rows // 2, 201)
    assert len(t) == min(states, 201) and t[0] == 0.0 and t[-1] == 3.0
    assert len(reported_times(3.0, 2**25, 2**25, 201)) == 2  # never fewer than the two ends


def test_help_gives_every_default(capsys) -> None:
    with pytest.raises(SystemExit) as e:
        main(["run", "--help"])
    assert e.value.code == 0
    text = capsys.readouterr().out
    options = text[text.index("options:") :]
    blocks = re.split(r"\n  (?=-)", options)[1:]  # one block per option, its help included
    flags = [b.split()[0].rstrip(",") for b in blocks]
    assert {"--t-end", "--method", "--rtol", "--atol", "--samples", "--steps", "--output"} <= set(
        flags
    )
    missing = [f for f, b in zip(flags, blocks, strict=True) if f != "-h" and "default" not in b]
    assert missing == []
