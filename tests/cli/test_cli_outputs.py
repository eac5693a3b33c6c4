"""The CLI's outputs: strict JSON, distinct regular files, never a device or pipe replaced."""

from __future__ import annotations

import json
import math
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from pfaff.cli.jsontext import dumps
from pfaff.cli.main import main
from pfaff.core.files import atomic_path

EXAMPLE = str(Path(__file__).parents[2] / "examples" / "pendulum.toml")


def test_json_has_no_nan_or_infinity() -> None:
    """NaN and ±∞ become null; the text parses with a strict parser and keeps the finite
    values."""
    rep = {"drift": math.nan, "t": [0.5, math.inf, -math.inf], "nested": {"r": 1e-3}}

    def strict(token: str) -> None:
        raise AssertionError(f"non-JSON constant {token}")

    back = json.loads(dumps(rep), parse_constant=strict)
    assert back == {"drift": None, "t": [0.5, None, None], "nested": {"r": 1e-3}}


def test_cli_json_is_strict(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", EXAMPLE, "--t-end", "0.2", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(c))
    assert rep["status"] == "success"


def test_plot_and_animation_to_one_file_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "a.gif"
    link = tmp_path / "b.gif"
    link.symlink_to(out)
    for second in (out, link):
        code = main(["run", EXAMPLE, "--plot", str(out), "--animate", str(second)])
        assert code == 2
        assert "--plot and --animate are the same file" in capsys.readouterr().err
    assert not out.exists()


def test_a_named_pipe_or_device_is_never_replaced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fifo = tmp_path / "run.csv"
    os.mkfifo(fifo)
    dev = tmp_path / "dev.csv"
    dev.symlink_to(os.devnull)
    for path, kind in ((fifo, "a named pipe"), (dev, "a character device")):
        assert main(["run", EXAMPLE, "--t-end", "0.1", "--output", str(path)]) == 2
        assert f"is {kind}, not a regular file" in capsys.readouterr().err
        with pytest.raises(FileExistsError, match=kind), atomic_path(path) as tmp:
            tmp.write_text("never")
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert stat.S_ISCHR(os.stat(os.devnull).st_mode) and dev.is_symlink()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dev.csv", "run.csv"]  # no temp file


def test_huge_samples_and_grids_refused_before_allocating(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """10**12 reported times (4.7e14 bytes of states) or a 10**9-run grid: refused with the
    estimate before anything of that size exists (was a MemoryError, or gigabytes first)."""
    import pfaff

    assert main(["run", EXAMPLE, "--samples", str(10**12)]) == 2
    err = capsys.readouterr().err
    assert f"--samples {10**12} would need about" in err and "GiB" in err
    with pytest.raises(pfaff.OptionError, match="a sweep of 1000000000 runs of 1000 samples"):
        pfaff.sweep(
            EXAMPLE,
            {"g": np.linspace(1, 10, 100_000), "L": np.linspace(1, 2, 10_000)},
            samples=1000,
            scheduler="synchronous",
        )
