"""The command line keeps its word: early refusals, one-line errors, exit codes, honest reports.

Each outcome is exact: the exit code, one line on stderr naming the flag or the problem, no
traceback, and which files are (not) written.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import tracemalloc
from pathlib import Path

import pytest

import pfaff
from methods import ALL_METHODS
from pfaff.cli import main

HUGE = "2147483647"  # 2^31 - 1 particles: hundreds of GiB to solve


def _one_error_line(err: str) -> str:
    """The single stderr line of a failed run (asserting there is exactly one)."""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


def _main(argv: list[str]) -> int:
    """``main(argv)``; a KeyboardInterrupt escaping it fails the test (not the whole session)."""
    try:
        return main(argv)
    except KeyboardInterrupt:
        pytest.fail("KeyboardInterrupt escaped main()")


# ------------------------------------------------------------------ 1. memory refused first
def test_derive_checks_memory_before_building_the_derivation(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The estimate needs only n, m and the blocks: no Derivation, no constraint rows of size N."""
    from pfaff.derive import equations, templates

    def never(*args: object, **kw: object) -> None:
        raise AssertionError("something of size N was built before the memory check")

    monkeypatch.setattr(equations.Derivation, "__init__", never)
    monkeypatch.setattr(pfaff.System, "constraint_rows", never)
    ring = pfaff.models.rolling_ring(int(HUGE), force=True)
    with pytest.raises(pfaff.ModelError, match="memory"):
        templates.derive(ring)


@pytest.mark.parametrize("simulate", [[], ["--simulate"]])
def test_cli_refuses_huge_ring_without_allocating(
    simulate: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    """Traced allocations (NumPy's included) stay small: nothing of size N before the refusal."""
    tracemalloc.start()
    try:
        code = main(["demo", "ring", "--particles", HUGE, *simulate])
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert code == 2
    captured = capsys.readouterr()
    line = _one_error_line(captured.err)
    assert line.startswith("pfaff: error:") and "memory" in line
    assert captured.out == ""
    assert peak < 64 * 2**20, f"{peak / 2**20:.0f} MiB traced before the refusal"


@pytest.mark.slow
def test_huge_ring_refused_at_low_peak_rss(tmp_path: Path) -> None:
    """The whole process (imports included) stays far below 1 GB: it was 4.2 GB."""
    out, err = tmp_path / "out", tmp_path / "err"
    with out.open("w") as fo, err.open("w") as fe:
        proc = subprocess.Popen(
            [sys.executable, "-m", "pfaff.cli", "demo", "ring", "--particles", HUGE],
            stdout=fo,
            stderr=fe,
        )
        _, status, usage = os.wait4(proc.pid, 0)  # the resources of this child alone
    proc.returncode = os.waitstatus_to_exitcode(status)
    assert proc.returncode == 2
    assert "memory" in _one_error_line(err.read_text())
    assert out.read_text() == ""
    peak = usage.ru_maxrss * (1 if sys.platform == "darwin" else 1024)  # bytes
    assert peak < 1e9, f"peak RSS {peak / 2**20:.0f} MiB"


# ------------------------------------------------------------------ 2. errors in pfaff's words
@pytest.mark.parametrize("stage", ["derive", "compile"])
def test_ctrl_c_before_simulation_exits_130_in_one_line(
    stage: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from pfaff.derive import templates

    def interrupt(*args: object, **kw: object) -> None:
        raise KeyboardInterrupt

    if stage == "derive":
        monkeypatch.setattr(templates, "derive_template", interrupt)
    else:
        monkeypatch.setattr(pfaff.EquationsOfMotion, "compile", interrupt)
    for argv in (["demo", "ring", "-N", "4"], ["demo", "pendulum", "--simulate"]):
        assert _main(argv) == 130
        captured = capsys.readouterr()
        assert _one_error_line(captured.err) == "pfaff: interrupted"
        assert captured.out == ""


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_ctrl_c_during_simulation_keeps_partial_outputs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Interrupted while stepping: outputs written, status "interrupted", exit 3."""
    from pfaff.integrate import simulation

    base = simulation.METHODS["projection"]

    class Interrupted(base):  # type: ignore[misc, valid-type]
        def step(self) -> None:
            if self.t > 0.3:
                raise KeyboardInterrupt
            super().step()

    monkeypatch.setitem(simulation.METHODS, "projection", Interrupted)
    csv_path, png = tmp_path / "p.csv", tmp_path / "p.png"
    code = _main(
        ["demo", "pendulum", "--simulate", "--t-end", "2", "--output", str(csv_path),
         "--plot", str(png), "--json"]
    )  # fmt: skip
    assert code == 3
    captured = capsys.readouterr()
    rep = json.loads(captured.out)
    assert rep["status"] == "interrupted"
    assert 0.3 <= rep["t_end"] < 2
    assert csv_path.exists() and png.read_bytes()[:4] == b"\x89PNG"
    assert "Traceback" not in captured.err


@pytest.mark.slow
def test_sigint_during_derivation_exits_130(tmp_path: Path) -> None:
    """A real SIGINT while the derivation runs (made slow on purpose, and announced on stdout)."""
    script = textwrap.dedent(
        """
        import sys, time
        import pfaff.cli
        from pfaff.derive import templates
        real = templates.derive_template
        def slow(*args, **kw):
            print("deriving", flush=True)
            time.sleep(30)
            return real(*args, **kw)
        templates.derive_template = slow
        sys.exit(pfaff.cli.main(["demo", "ring", "--particles", "8"]))
        """
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == "deriving"
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130
    assert _one_error_line(err) == "pfaff: interrupted"
    assert out == ""


def test_unexpected_error_is_one_line_with_debug_hint(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from pfaff.cli import demo

    def boom(*args: object, **kw: object) -> None:
        raise RuntimeError("boom\nsecond line")

    monkeypatch.setattr(demo, "ring_report", boom)
    assert main(["demo", "ring"]) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert "RuntimeError: boom second line" in line and "--debug" in line
    for argv in (["--debug", "demo", "ring"], ["demo", "ring", "--debug"]):
        assert main(argv) == 1
        err = capsys.readouterr().err
        assert "Traceback" in err and 'raise RuntimeError("boom' in err
        assert err.splitlines()[-1].startswith("pfaff: unexpected error: RuntimeError: boom")


def test_overflow_in_generated_code_is_a_one_line_error(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """An ArithmeticError raised in generated code is the model's values, not a bug: exit 2."""
    import importlib

    cli_main = importlib.import_module("pfaff.cli.main")
    ns: dict = {}
    code = "def f(*a):\n    raise OverflowError(34, 'Numerical result out of range')\n"
    exec(compile(code, "<lambdifygenerated-999>", "exec"), ns)
    monkeypatch.setattr(cli_main, "run_pendulum", ns["f"])
    assert main(["demo", "pendulum"]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert line == (
        "pfaff: error: the equations cannot be evaluated with these values "
        "(OverflowError: Numerical result out of range)"
    )


@pytest.mark.parametrize("extra", [[], ["--simulate"]])
def test_pendulum_huge_length_is_clean(
    extra: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    """L = 1e200 overflows L²: a one-line error naming the overflow, exit 2."""
    assert main(["demo", "pendulum", "--length", "1e200", *extra]) == 2
    captured = capsys.readouterr()
    line = _one_error_line(captured.err)
    assert line.startswith("pfaff: error:") and "overflow" in line.lower()


def test_bare_command_prints_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: pfaff") and "demo" in out and "--debug" in out
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: pfaff demo") and "ring" in out and "pendulum" in out


# ------------------------------------------------------------------ 3. files checked first
@pytest.mark.parametrize(
    ("argv", "flag", "words"),
    [
        (["demo", "ring", "--plot", "ring.xyz"], "--plot", ".png"),
        (["demo", "ring", "--simulate", "--plot", "run.xyz"], "--plot", ".png"),
        (["demo", "pendulum", "--plot", "p"], "--plot", ".png"),
        (["demo", "ring", "--simulate", "--output", "run.txt"], "--output", ".nc or .csv"),
        (["demo", "ring", "--plot", "{tmp}/missing/ring.png"], "--plot", "does not exist"),
        (["demo", "pendulum", "--output", "{tmp}/missing/p.csv"], "--output", "does not exist"),
        (["demo", "pendulum", "--output", "{tmp}"], "--output", ".nc or .csv"),
    ],
)
def test_output_files_checked_before_computing(
    argv: list[str],
    flag: str,
    words: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    def never(*args: object, **kw: object) -> None:
        raise AssertionError("computed before checking the output files")

    monkeypatch.setattr(pfaff.System, "equations", never)
    monkeypatch.chdir(tmp_path)
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    captured = capsys.readouterr()
    line = _one_error_line(captured.err)
    assert line.startswith(f"pfaff: error: {flag}") and words in line
    assert captured.out == ""
    assert sorted(os.listdir(tmp_path)) == []


def test_plot_folder_is_a_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "fig.png").mkdir()
    assert main(["demo", "ring", "--plot", str(tmp_path / "fig.png")]) == 2
    assert "--plot" in _one_error_line(capsys.readouterr().err)


@pytest.mark.parametrize("option", [["--plot", "p.png"], ["--output", "p.csv"], ["--t-end", "0.2"]])
@pytest.mark.slow  # (over a second: the full suite runs it)
def test_pendulum_simulation_options_imply_simulate(
    option: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A figure or trajectory file (or an end time) asked for is made, not silently skipped."""
    monkeypatch.chdir(tmp_path)
    assert main(["demo", "pendulum", "--t-end", "0.2", *option]) == 0
    out = capsys.readouterr().out
    assert out.startswith("cartesian pendulum: projection to t = 0.2 — success")
    if option[0] in ("--plot", "--output"):
        assert (tmp_path / option[1]).stat().st_size > 0
        assert f"Wrote {option[1]}" in out


def test_ring_output_implies_simulate(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out_file = tmp_path / "ring.csv"
    assert main(["demo", "ring", "-N", "3", "--t-end", "0.1", "--output", str(out_file)]) == 0
    assert "rolling ring: projection to t = 0.1" in capsys.readouterr().out
    assert out_file.read_text().startswith("t,x,theta1")


@pytest.mark.parametrize(
    ("angle", "t_end", "reference"),
    [("180", "2", None), ("90", "0.2", None), ("90", "1", 3.0), ("-90", "1", 3.0), ("0", "1", 1.0)],
)
def test_pendulum_tension_reference_only_where_it_applies(
    angle: str, t_end: str, reference: float | None, capsys: pytest.CaptureFixture[str]
) -> None:
    """m g (3 − 2 cos θ₀) is the tension at the bottom: shown only for a run that gets there."""
    argv = ["demo", "pendulum", "--angle", angle, "--simulate", "--t-end", t_end]
    assert main([*argv, "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    if reference is None:
        assert rep["max_tension_exact"] is None
    else:
        assert rep["max_tension_exact"] == pytest.approx(reference * 9.81)
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert ("3 − 2 cos θ₀" in text) is (reference is not None)


def test_pendulum_release_text_reference_holds_at_any_angle(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """At rest the tension is m g cos θ₀ (a push, −m g, upright): the shown reference matches."""
    assert main(["demo", "pendulum", "--angle", "180"]) == 0
    text = capsys.readouterr().out
    assert "rod tension −2Lλ = -9.81" in text and "m g cos θ₀ = -9.81" in text


@pytest.mark.parametrize("method", ALL_METHODS)
def test_summary_shows_only_statistics_that_exist(
    method: str, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["demo", "pendulum", "--simulate", "--t-end", "0.3", "--method", method]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "None" not in text
    assert ("rejected" in text) is (method != "ida")  # IDA does not count rejected steps
    assert main([*argv, "--json"]) == 0
    stats = json.loads(capsys.readouterr().out)["stats"]
    assert None not in stats.values()


# ------------------------------------------------------------------ 5. energy balance, not drift
def test_ring_reports_energy_balance_not_push_work(capsys: pytest.CaptureFixture[str]) -> None:
    """The push does work F Δx = 4 by t = 2: that is no drift; the balance T + V − E₀ − W is ~0."""
    argv = ["demo", "ring", "-N", "4", "--simulate", "--t-end", "2"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "energy drift" not in text and "energy balance" in text
    assert main([*argv, "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["energy_drift"] == pytest.approx(4.0, rel=1e-9)  # kept: T + V − E₀
    assert rep["energy_balance_error"] < 1e-8
    assert rep["nc_work"] == pytest.approx(4.0, rel=1e-9)


def test_pendulum_reports_energy_balance(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "pendulum", "--simulate", "--t-end", "1", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["energy_balance_error"] == pytest.approx(rep["energy_drift"], abs=1e-15)
    assert rep["energy_balance_error"] < 1e-6
