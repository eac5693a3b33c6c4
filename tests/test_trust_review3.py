"""The third hostile review (issue 28): each finding that was not a correct result or a clear
error, now one of them. The corpus of the review itself lived outside the repository; these are
its regressions, one per finding, grouped by the module that now refuses the value."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff import ModelError, ModelTypeError, OptionError
from pfaff.cli.main import main
from pfaff.core.safe_expr import MAX_WRITTEN_OUT, tree_size
from pfaff.sweep import parse_vary

EXAMPLES = Path(__file__).parents[1] / "examples"
PENDULUM = (EXAMPLES / "pendulum.toml").read_text()


# ---------------------------------------------------------------- core.files: a path's type
@pytest.mark.parametrize("path", [3, None, b"m.toml", "", 2.5])
def test_a_path_that_is_no_path_is_named(path: object) -> None:
    for call in (pfaff.load_model, pfaff.load_urdf):
        with pytest.raises(OptionError, match="`path` must be a file path"):
            call(path)  # type: ignore[arg-type]


def test_writing_to_a_path_that_is_no_path(tmp_path: Path) -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    traj = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 0.1))
    with pytest.raises(OptionError, match="`path` must be a file path"):
        traj.to_csv(42)  # type: ignore[arg-type]


# ---------------------------------------------------------------- core.safe_expr: inputs of inputs
def test_tree_size_counts_shared_subexpressions_once_per_use() -> None:
    x = sp.Symbol("x")
    u, sizes = x + 1, []  # 3 nodes
    for _ in range(3):
        u = sp.Mul(u, sp.Add(u, x, evaluate=False), evaluate=False)  # 1 + s + (1 + s + 1)
        sizes.append(tree_size(u))
    assert [tree_size(x), tree_size(x + 1), *sizes] == [1, 3, 9, 21, 45]


def test_inputs_that_double_at_each_level_are_refused_early(tmp_path: Path) -> None:
    """Forty inputs, each using the one before it twice: 2^40 terms written out. The file is
    refused at the input where the count passes MAX_WRITTEN_OUT, in well under a second."""
    chain = '[[inputs]]\nname = "u40"\nvalue = "x"\n\n' + "".join(
        f'[[inputs]]\nname = "u{i}"\nvalue = "(u{i + 1} + u{i + 1})*(u{i + 1} + x)"\n\n'
        for i in range(39, -1, -1)
    )
    force = '[[generalized_forces]]\ncoordinate = "x"\nexpr = "u0"\n\n'
    path = tmp_path / "m.toml"
    path.write_text(PENDULUM.replace("[[particles]]", chain + force + "[[particles]]"))
    start = time.process_time()
    with pytest.raises(
        pfaff.PfaffError, match=rf"inputs\[1[0-9]\].*more than {MAX_WRITTEN_OUT} terms"
    ):
        pfaff.load_model(path)
    assert time.process_time() - start < 30  # (a guard: unrefused, it never ends)


def test_inputs_of_inputs_within_the_bound_are_kept(tmp_path: Path) -> None:
    chain = '[[inputs]]\nname = "a"\nvalue = "x + y"\n\n[[inputs]]\nname = "b"\nvalue = "a*a"\n\n'
    force = '[[generalized_forces]]\ncoordinate = "x"\nexpr = "-b"\n\n'
    path = tmp_path / "m.toml"
    path.write_text(PENDULUM.replace("[[particles]]", chain + force + "[[particles]]"))
    mf = pfaff.load_model(path)
    x, y = (s for s in mf.system.coordinates)
    assert sp.simplify(mf.inputs["b"] - (x + y) ** 2) == 0


# ---------------------------------------------------------------- api
def test_from_sympy_parameters_of_the_wrong_kind() -> None:
    from sympy.physics.mechanics import (
        LagrangesMethod,
        Lagrangian,
        Particle,
        Point,
        ReferenceFrame,
        dynamicsymbols,
    )

    q, m = dynamicsymbols("q"), sp.Symbol("m")
    frame, origin = ReferenceFrame("N"), Point("O")
    point = origin.locatenew("P", q * frame.x)
    point.set_vel(frame, q.diff() * frame.x)
    lm = LagrangesMethod(Lagrangian(frame, Particle("p", point, m)), [q])
    for bad in (42, "m", 2.5):
        with pytest.raises(ModelTypeError, match="`parameters` must be a mapping"):
            pfaff.from_sympy(lm, parameters=bad)  # type: ignore[arg-type]
    assert list(pfaff.from_sympy(lm, parameters=["m"]).coordinates) == [q]


def test_root_locus_of_too_many_values() -> None:
    eom = pfaff.models.pendulum().equations()
    (th,) = eom.coordinates
    point = {th: 0, **{str(p): 1.0 for p in eom.parameters}}
    with pytest.raises(ModelError, match=r"`vary\['L'\]`: 100001 values, more than 100000"):
        pfaff.root_locus(eom, point, [th], {"L": np.linspace(1, 2, 100_001)})


# ---------------------------------------------------------------- sweep
@pytest.mark.parametrize("count", ["0", "1000001", "1000000000"])
def test_vary_count_out_of_range(count: str) -> None:
    with pytest.raises(OptionError, match="COUNT must be a whole number from 1 to 1000000"):
        parse_vary(f"g=1:2:{count}")
    assert parse_vary("g=1:2:3")[1].tolist() == [1.0, 1.5, 2.0]


# ---------------------------------------------------------------- cli: an output over an input
@pytest.mark.parametrize("through_link", [False, True])
def test_an_output_that_is_the_model_file_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], through_link: bool
) -> None:
    """A model file read whatever its name (here one ending in .csv), and the output named as
    it or linked to it: the run is refused before anything is written."""
    model = tmp_path / "pendulum.csv"
    model.write_text(PENDULUM)
    out = tmp_path / "run.csv" if through_link else model
    if through_link:
        out.symlink_to(model)
    assert main(["run", str(model), "--t-end", "0.1", "--output", str(out)]) == 2
    assert "is the model file this command reads" in capsys.readouterr().err
    assert model.read_text() == PENDULUM  # not replaced


def test_a_sweep_output_linked_to_the_model_file_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model = tmp_path / "pendulum.toml"
    model.write_text(PENDULUM)
    out = tmp_path / "sweep.nc"
    out.symlink_to(model)
    argv = ["sweep", str(model), "--vary", "g=9:10:2", "--scheduler", "synchronous",
            "--output", str(out)]  # fmt: skip
    assert main(argv) == 2
    assert "is the model file this command reads" in capsys.readouterr().err
    assert model.read_text() == PENDULUM


def test_a_fit_plot_linked_to_the_data_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data.csv"
    data.write_text("t,x,y\n0,0.84,-0.54\n0.1,0.8,-0.6\n")
    plot = tmp_path / "fit.png"
    plot.symlink_to(data)
    argv = ["fit", str(EXAMPLES / "pendulum.toml"), str(data), "--fit", "g=9", "--plot", str(plot)]
    assert main(argv) == 2
    assert "is the data file this command reads" in capsys.readouterr().err
    assert data.read_text().startswith("t,x,y")


# ---------------------------------------------------------------- numeric: a model without inertia
def test_a_urdf_link_without_inertia_is_an_inertia_error(tmp_path: Path) -> None:
    """A joint that moves only a link without <inertial>: M = 0, no entry at all (the KKT
    pattern of no entries was a raw ValueError); now the inertia check names the joint."""
    inertial = (
        '<inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>'
        "</inertial>"
    )
    path = tmp_path / "r.urdf"
    path.write_text(
        f'<robot name="r"><link name="base">{inertial}</link><link name="a"/>'
        '<joint name="j0" type="continuous"><parent link="base"/><child link="a"/>'
        '<axis xyz="0 0 1"/></joint></robot>'
    )
    model = pfaff.load_urdf(path).equations().compile({})
    with pytest.raises(pfaff.InertiaError, match="`j0` is undetermined"):
        model.accelerations(0.0, [0.0], [1.0])


# ---------------------------------------------------------------- api.fit: data whose squares overflow
def test_fit_of_data_beyond_the_squares_range() -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    t, measured = np.array([0.0, 0.1]), np.full((2, 1), 1e200)
    with pytest.raises(OptionError, match=r"`measured` has values beyond ±1e\+150"):
        pfaff.fit(model, t, measured, {"g": 9.0}, ["x"], [1.0, 0.0], [0.0, 0.0])
