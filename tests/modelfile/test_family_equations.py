"""``pfaff equations`` on a model file with a 48-member family: printed once per entry, not
re-deriving every coordinate's rates per entry (it used to take minutes)."""

from __future__ import annotations

import json

import pytest
import sympy as sp

from pfaff.cli.main import main

N = 48
RING = f"""
[model]
name = "ring of {N}"
coordinates = ["x"]
parameters = {{ M = 1.0, r = 0.5, F = 2.0 }}

[[families]]
name = "theta"
n = {N}
first = 1

[[particles]]
mass = "M/{N}"
position = ["x + r*sin(theta[k])", "r*cos(theta[k])"]
over = "k"

[[forces]]
name = "push"
force = ["F", "0"]
at = ["x", "0"]

[[constraints]]
name = "no slip"
holonomic = "x - r*theta1"

[[constraints]]
name = "spacing"
holonomic = "theta[k+1] - theta[k] - 2*pi/{N}"
over = ["k", 1, {N - 1}]
"""


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_equations_of_a_48_member_family_against_the_hand_derivation(tmp_path, capsys) -> None:
    path = tmp_path / "ring.toml"
    path.write_text(RING)
    assert main(["equations", str(path), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    names = ["x"] + [f"theta{k}" for k in range(1, N + 1)]
    assert rep["coordinates"] == names
    M, r = sp.symbols("M r")
    ns = {n: sp.Symbol(n) for n in names} | {"M": M, "r": r}  # our own output, parsed in the test

    def parse(s: str) -> sp.Expr:
        return sp.sympify(s, locals=ns)

    # T = Σ_k M/(2N) [(ẋ + r cos θk θ̇k)² + (r sin θk θ̇k)²]
    mass = rep["mass_matrix"]
    assert len(mass) == N + 1 and all(len(row) == N + 1 for row in mass)
    assert parse(mass[0][0]) - M == 0
    for k in range(1, N + 1):
        th = ns[f"theta{k}"]
        assert sp.simplify(parse(mass[0][k]) - M * r * sp.cos(th) / N) == 0
        assert sp.simplify(parse(mass[k][0]) - M * r * sp.cos(th) / N) == 0
        assert sp.simplify(parse(mass[k][k]) - M * r**2 / N) == 0
        assert all(mass[k][j] == "0" for j in range(1, N + 1) if j != k)
    # A: no slip (1, −r, 0 …), then θ_{k+1} − θ_k
    a = rep["constraint_matrix"]
    assert len(a) == N and parse(a[0][0]) == 1 and parse(a[0][1]) == -r
    for k in range(1, N):
        row = [parse(e) for e in a[k]]
        assert row[k] == -1 and row[k + 1] == 1 and sum(e != 0 for e in row) == 2
    assert len(rep["lagrange_equations"]) == N + 1 and len(rep["multipliers"]) == N


def test_run_with_t_end_1e9_is_not_judged_stalled(tmp_path, capsys) -> None:
    """``pfaff run --t-end 1e9`` on the pendulum used to fail at t ≈ 103 as "stalled"; now only
    the file's ``max_steps`` ends it, far past that time, on the circle."""
    from pathlib import Path

    text = (Path(__file__).parents[2] / "examples" / "pendulum.toml").read_text()
    path = tmp_path / "long.toml"
    path.write_text(text.replace("t_end = 5.0", "t_end = 5.0\nmax_steps = 4000"))
    main(["run", str(path), "--t-end", "1e9", "--samples", "3", "--json"])
    rep = json.loads(capsys.readouterr().out)
    assert rep["status"] == "failed" and "max_steps = 4000" in rep["message"]
    assert "stall" not in rep["message"] and "collapse" not in rep["message"]
    assert float(rep["message"].split("t = ")[1].split(":")[0]) > 103.0  # past the old "stall"
