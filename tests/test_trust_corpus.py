"""The bad-input corpus: every entry point, careless and hostile input, one exact outcome each.

Each case ends in pfaff's own error whose message names the argument and the problem, or in a
correct result. No case may run a user's string as code (a canary file proves it), leave a file
half-written or lost, or end in a traceback from inside SymPy, NumPy or SciPy.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff import (
    ConstraintError,
    ModelError,
    ModelTypeError,
    OptionError,
    ParameterError,
    StateError,
)

CANARY = Path("pfaff_corpus_canary")
HOSTILE = [
    f"__import__('os').system('touch {CANARY}')",
    f"open('{CANARY}', 'w')",
    "lambda: 0",
    "[x for x in ()]",
    "().__class__.__bases__[0].__subclasses__()",
    "10**10**10",
    "x" * 100_000,
    "m; import os",
    "",
    "1e3",
]
PEND = {"m": 1.0, "g": 9.81, "L": 1.0}


def _pendulum():
    return pfaff.models.cartesian_pendulum().equations().compile(PEND)


def _xy():
    return pfaff.coordinates("x y")


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.chdir(tmp_path)
    yield
    assert not CANARY.exists(), "a user's string ran as code"


# ---------------------------------------------------------------- hostile strings
@pytest.mark.parametrize("text", HOSTILE)
@pytest.mark.parametrize(
    "model", ["cartesian_pendulum", "pendulum", "rolling_ring", "rolling_ring_minimal"]
)
@pytest.mark.parametrize("arg", ["mass", "gravity", "radius", "length", "force"])
def test_zoo_parameters_never_evaluate_strings(model: str, arg: str, text: str) -> None:
    fn = getattr(pfaff.models, model)
    kwargs = {arg: text}
    args = (3,) if model == "rolling_ring" else ()
    try:
        fn(*args, **kwargs)
    except TypeError as e:  # this model has no such parameter: Python's own signature error
        if "unexpected keyword argument" in str(e):
            return
        assert isinstance(e, ModelTypeError) and f"`{arg}`" in str(e)
    # a string is a name or it is refused; "1e3" is neither a name nor evaluated


@pytest.mark.parametrize("text", HOSTILE)
def test_expressions_refuse_strings(text: str) -> None:
    x, y = _xy()
    s = pfaff.System([x, y])
    for call in (
        lambda: s.add_particle(text, [x, y]),
        lambda: s.add_particle(1, [text, y]),
        lambda: s.add_potential_energy(text),
        lambda: s.add_kinetic_energy(text),
        lambda: s.add_holonomic_constraint(text),
        lambda: s.add_velocity_constraint(text),
        lambda: s.add_generalized_force(x, text),
        lambda: s.add_force([text, 0], at=[x, y]),
    ):
        with pytest.raises(ModelTypeError):
            call()


@pytest.mark.parametrize("text", HOSTILE)
def test_coordinate_names_are_names(text: str) -> None:
    if text.isidentifier():
        assert str(pfaff.coordinates(text).func) == text
        return
    with pytest.raises(ModelTypeError, match="`names`"):
        pfaff.coordinates(text)


@pytest.mark.parametrize("text", HOSTILE)
def test_parameter_values_refuse_strings(text: str) -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    with pytest.raises(ParameterError, match=r"`m`.*string"):
        eom.compile({**PEND, "m": text})


# ---------------------------------------------------------------- the model builder
MODEL_CASES: list[tuple[str, Callable[[], object], type, str]] = [
    ("System(5)", lambda: pfaff.System(5), ModelTypeError, "`coordinates`"),
    ("System('x')", lambda: pfaff.System("x"), ModelTypeError, "`coordinates`"),
    ("System(symbol)", lambda: pfaff.System([sp.Symbol("x")]), ModelTypeError, "function of time"),
    ("coordinate twice", lambda: pfaff.System([_xy()[0], _xy()[0]]), ModelTypeError, "twice"),
    ("coordinates(3)", lambda: pfaff.coordinates(3), ModelTypeError, "`names`"),
]


def _system():
    x, y = _xy()
    s = pfaff.System([x, y])
    return s, x, y


def _add(method: str, *args, **kw):
    def run():
        s, x, y = _system()
        fill = {"X": x, "Y": y}
        a = [fill.get(v, v) if isinstance(v, str) and v in fill else v for v in args]
        kw2 = {
            k: ([fill.get(c, c) for c in v] if isinstance(v, list) else v) for k, v in kw.items()
        }
        a = [[fill.get(c, c) for c in v] if isinstance(v, list) else v for v in a]
        return getattr(s, method)(*a, **kw2)

    return run


MODEL_CASES += [
    ("negative mass", _add("add_particle", -1, ["X", "Y"]), ModelError, "mass"),
    ("zero mass", _add("add_particle", 0, ["X", "Y"]), ModelError, "mass"),
    ("NaN mass", _add("add_particle", math.nan, ["X", "Y"]), ModelError, "NaN"),
    ("inf mass", _add("add_particle", math.inf, ["X", "Y"]), ModelError, "NaN or infinity"),
    ("complex mass", _add("add_particle", 1 + 2j, ["X", "Y"]), ModelTypeError, "mass"),
    ("complex potential", _add("add_potential_energy", sp.I * sp.Symbol("k")), ModelError, "real"),
    ("None potential", _add("add_potential_energy", None), ModelTypeError, "potential"),
    ("bool potential", _add("add_potential_energy", True), ModelTypeError, "potential"),
    ("list as potential", _add("add_potential_energy", [1, 2]), ModelTypeError, "potential"),
    ("position of 4 components", _add("add_particle", 1, ["X", "Y", 0, 0]), ModelError, "position"),
    ("force without point", _add("add_force", [1, 0], at=None), ModelError, "at"),
    ("genforce on a non-coordinate", _add("add_generalized_force", sp.Symbol("z"), 1), ModelError, "coordinate"),
    ("constant constraint", _add("add_holonomic_constraint", 1), ConstraintError, "names no coordinate"),
    ("velocity constraint without velocity", _add("add_velocity_constraint", "X"), ConstraintError, "velocity"),
]  # fmt: skip


@pytest.mark.parametrize(
    ("name", "call", "error", "match"), MODEL_CASES, ids=[c[0] for c in MODEL_CASES]
)
def test_model_builder(name: str, call: Callable[[], object], error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        call()


def test_nonlinear_velocity_constraint_refused() -> None:
    s, x, y = _system()
    with pytest.raises(ConstraintError, match="not Pfaffian"):
        s.add_velocity_constraint(x.diff(pfaff.t) ** 2 - y.diff(pfaff.t))


def test_redundant_and_inconsistent_constraints() -> None:
    s, x, y = _system()
    s.add_particle(1, [x, y])
    s.add_holonomic_constraint(x - y, name="a")
    s.add_holonomic_constraint(2 * y - 2 * x + 1, name="b")  # contradicts a
    with pytest.raises(ConstraintError, match="inconsistent constraints: `a`, `b`"):
        s.equations()


def test_too_many_constraints() -> None:
    """More rows than coordinates: accepted when consistent, refused naming them when not."""
    s, x, y = _system()
    s.add_particle(1, [x, y])
    s.add_holonomic_constraint(x, name="a")
    s.add_holonomic_constraint(y, name="b")
    s.add_holonomic_constraint(x + y - 1, name="c")  # x = y = 0 makes it -1
    with pytest.raises(ConstraintError, match="inconsistent constraints: `a`, `b`, `c`"):
        s.equations()


# ---------------------------------------------------------------- compile
@pytest.mark.parametrize(
    ("value", "match"),
    [(math.nan, "NaN"), (math.inf, "infinite"), ("abc", "string"), ([1.0], "real number"),
     (None, "real number"), (1 + 1j, "real number")],
)  # fmt: skip
def test_compile_bad_values(value: object, match: str) -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    with pytest.raises(ParameterError, match=f"`g`.*{match}|{match}.*`g`"):
        eom.compile({**PEND, "g": value})


def test_compile_unknown_and_missing() -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    with pytest.raises(ParameterError, match=r"unknown parameter `mass`.*missing value for `m`"):
        eom.compile({"mass": 1.0, "g": 9.81, "L": 1.0})
    with pytest.raises(ParameterError, match="`parameters` must be a dict"):
        eom.compile([1, 2, 3])  # type: ignore[arg-type]


def test_compile_matches_a_parameter_with_other_assumptions() -> None:
    """A user's m = Symbol('m', positive=True) names the model's plain m: the same numbers."""
    eom = pfaff.models.cartesian_pendulum().equations()
    mp = sp.Symbol("m", positive=True)
    a = eom.compile({mp: 2.0, "g": 9.81, "L": 1.0}).accelerations(0.0, [0.6, -0.8], [0.0, 0.0])
    b = eom.compile({"m": 2.0, "g": 9.81, "L": 1.0}).accelerations(0.0, [0.6, -0.8], [0.0, 0.0])
    np.testing.assert_array_equal(a[0], b[0])


# ---------------------------------------------------------------- numeric entry points
@pytest.mark.parametrize(
    ("q", "qd", "match"),
    [([0.0], [0.0, 0.0], "`q`.*shape"), ([0.0, 1.0], [0.0], "`qd`.*shape"),
     ([math.nan, 1.0], [0.0, 0.0], "`q`.*NaN"), ([0.0, 1.0], [math.inf, 0.0], "`qd`.*NaN"),
     ("ab", [0.0, 0.0], "`q`|`t`"), ([[0.0, 1.0]], [0.0, 0.0], "`q`.*shape")],
)  # fmt: skip
def test_accelerations_bad_states(q: object, qd: object, match: str) -> None:
    with pytest.raises(StateError, match=match):
        _pendulum().accelerations(0.0, q, qd)


def test_accelerations_bad_time() -> None:
    with pytest.raises(StateError, match="`t`"):
        _pendulum().accelerations(math.nan, [0.0, -1.0], [0.0, 0.0])


def test_accelerations_correct_on_good_input() -> None:
    """Hanging at rest: q̈ = 0 and tension −2Lλ = m g (hand derivation, DESIGN.md)."""
    qdd, lam = _pendulum().accelerations(0.0, [0.0, -1.0], [0.0, 0.0])
    np.testing.assert_allclose(qdd, [0.0, 0.0], atol=1e-14)
    assert -2 * 1.0 * lam[0] == pytest.approx(9.81, rel=1e-14)


# ---------------------------------------------------------------- simulate
SIM_OPTIONS = [
    ({"method": "rk4"}, "method"),
    ({"rtol": 0.0}, "rtol"),
    ({"rtol": math.nan}, "rtol"),
    ({"atol": -1.0}, "atol"),
    ({"constraint_tol": 0.0}, "constraint_tol"),
    ({"t_eval": [0.5, 0.1]}, "t_eval"),
    ({"t_eval": [0.0, 5.0]}, "t_eval"),
    ({"t_eval": "abc"}, "t_eval"),
    ({"integrator": "Radau"}, "integrator"),
    ({"alpha": -1.0}, "alpha"),
    ({"ida_jacobian": "exact"}, "ida_jacobian"),
]


@pytest.mark.parametrize(("kw", "name"), SIM_OPTIONS, ids=[n for _, n in SIM_OPTIONS])
def test_simulate_bad_options(kw: dict, name: str) -> None:
    with pytest.raises(OptionError, match=f"`{name}`|{name}"):
        pfaff.simulate(_pendulum(), [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), **kw)


@pytest.mark.parametrize("span", [(1.0, 0.0), (0.0, 0.0), (0.0, math.inf), (0.0,), "ab", None])
def test_simulate_bad_span(span: object) -> None:
    with pytest.raises(OptionError, match="`t_span`"):
        pfaff.simulate(_pendulum(), [1.0, 0.0], [0.0, 0.0], span)  # type: ignore[arg-type]


def test_simulate_state_off_the_rod_refused() -> None:
    with pytest.raises(StateError, match=r"off the constraint manifold.*`rod`"):
        pfaff.simulate(_pendulum(), [1.3, 0.0], [0.0, 0.0], (0.0, 1.0))


def test_simulate_state_off_the_rod_projected_on_request() -> None:
    traj = pfaff.simulate(_pendulum(), [1.3, 0.0], [0.0, 0.0], (0.0, 0.5), project_initial=True)
    assert traj.status == "success"
    assert np.hypot(*traj.q[0]) == pytest.approx(1.0, abs=1e-12)


def test_simulate_interrupted_keeps_partial_output(monkeypatch: pytest.MonkeyPatch) -> None:
    from pfaff.integrate import integrators

    calls = {"n": 0}
    step = integrators.ProjectedRK.step

    def interrupted(self) -> None:
        calls["n"] += 1
        if calls["n"] == 5:
            raise KeyboardInterrupt
        step(self)

    monkeypatch.setattr(integrators.ProjectedRK, "step", interrupted)
    monkeypatch.setenv("PFAFF_LOOP", "0")  # the Python stepper (the compiled loop: test_loop)
    traj = pfaff.simulate(_pendulum(), [1.0, 0.0], [0.0, 0.0], (0.0, 5.0))
    assert traj.status == "interrupted" and "interrupted" in traj.message
    assert 1 < len(traj.t) <= 5 and traj.t[-1] < 5.0


def test_rank_loss_at_the_start_is_a_correct_result() -> None:
    """A constraint whose row vanishes at the start (y(x − 1) = 0 at x = 1): the floored solve
    keeps going, and the particle at rest with no force stays at rest."""
    x, y = _xy()
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_holonomic_constraint(y, name="floor")
    s.add_holonomic_constraint(y * (x - 1), name="wall")
    model = s.equations().compile({})
    traj = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0))
    assert traj.status == "success"
    np.testing.assert_allclose(traj.q, np.tile([1.0, 0.0], (len(traj.t), 1)), atol=1e-12)
    assert np.all(np.isfinite(traj.multipliers))


# ---------------------------------------------------------------- files
def _traj():
    return pfaff.simulate(_pendulum(), [1.0, 0.0], [0.0, 0.0], (0.0, 0.2))


@pytest.mark.parametrize("writer", ["to_csv", "to_netcdf"])
def test_write_through_a_symbolic_link(tmp_path: Path, writer: str) -> None:
    """The link is kept and its target gets the new contents (issue: the link was replaced)."""
    ext = ".csv" if writer == "to_csv" else ".nc"
    (tmp_path / "data").mkdir()
    real = tmp_path / "data" / f"results{ext}"
    real.write_text("old")
    link = tmp_path / f"latest{ext}"
    link.symlink_to(Path("data") / real.name)
    getattr(_traj(), writer)(link)
    assert link.is_symlink() and os.readlink(link) == str(Path("data") / real.name)
    assert real.read_bytes() != b"old" and len(real.read_bytes()) > 100
    assert sorted(p.name for p in (tmp_path / "data").iterdir()) == [real.name]  # no temp left


def test_write_keeps_the_old_file_when_the_writer_fails(tmp_path: Path, monkeypatch) -> None:
    target = tmp_path / "out.csv"
    target.write_text("precious")
    traj = _traj()

    def broken(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr("csv.writer", broken)
    with pytest.raises(OSError, match="disk full"):
        traj.to_csv(target)
    assert target.read_text() == "precious"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_write_into_a_missing_folder(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="does not exist"):
        _traj().to_csv(tmp_path / "nowhere" / "out.csv")


def test_write_keeps_permissions(tmp_path: Path) -> None:
    target = tmp_path / "out.csv"
    target.write_text("x")
    target.chmod(0o640)
    _traj().to_csv(target)
    assert target.stat().st_mode & 0o777 == 0o640


# ---------------------------------------------------------------- from the hostile review
@pytest.mark.parametrize("text", HOSTILE)
def test_work_at_refuses_strings(text: str) -> None:
    x, y = _xy()
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_force([1, 0], at=[x, y])
    with pytest.raises(ModelTypeError, match="`at"):
        s.work()[0].does_work(at={x: text})
    with pytest.raises(ModelTypeError, match="`at` keys"):
        s.work()[0].does_work(at={"x": 1})


@pytest.mark.parametrize("name", ["_q0", "_qd1", "_fq0", "_fqd2"])
def test_placeholder_names_are_refused(name: str) -> None:
    """pfaff's template placeholders as parameter names would silently change the equations."""
    with pytest.raises(ModelError, match="placeholders"):
        pfaff.models.pendulum(gravity=name)


def test_reduce_solutions_must_satisfy_the_constraints() -> None:
    s = pfaff.models.cartesian_pendulum()
    x, y = s.coordinates
    L = sp.Symbol("L")
    with pytest.raises(ConstraintError, match="do not satisfy"):
        s.reduce([x], solutions={y: x})
    with pytest.raises(ModelError, match="independent coordinates only"):
        s.reduce([x], solutions={y: y})
    with pytest.raises(ModelTypeError, match="`solutions`"):
        s.reduce([x], solutions=5)  # type: ignore[arg-type]
    with pytest.raises(ModelTypeError, match="solutions"):
        s.reduce([x], solutions={y: "x"})
    red = s.reduce([x], solutions={y: -sp.sqrt(L**2 - x**2)})
    assert red.n == 1  # the right branch is accepted
    with pytest.raises(ModelError, match="cannot be compiled"):
        s.reduce([x]).compile(PEND)  # unsolved: projection form


def test_csv_keeps_every_column_when_names_collide(tmp_path: Path) -> None:
    """A coordinate named t (or T, V, energy) must not replace the time column."""
    a, b = pfaff.coordinates("t T")
    s = pfaff.System([a, b])
    s.add_particle(1, [a, b])
    s.add_potential_energy(9.81 * b)
    s.add_holonomic_constraint(a**2 + b**2 - 1, name="rod")
    traj = pfaff.simulate(s.equations().compile({}), [1.0, 0.0], [0.0, 0.0], (0.0, 0.5))
    header = traj.to_csv(tmp_path / "n.csv").read_text().splitlines()[0].split(",")
    assert len(header) == len(set(header)) == len(traj._columns())
    data = np.loadtxt(tmp_path / "n.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(data[:, header.index("t")], traj.t)
    np.testing.assert_array_equal(data[:, header.index("t~2")], traj.q[:, 0])
    np.testing.assert_array_equal(data[:, header.index("T")], traj.q[:, 1])


def test_tiny_atol_is_not_a_crash() -> None:
    traj = pfaff.simulate(_pendulum(), [1.0, 0.0], [0.0, 0.0], (0.0, 0.1), atol=1e-300)
    assert traj.status in ("success", "failed")
    if traj.status == "success":
        assert np.hypot(*traj.q[-1]) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize(
    "args", [(3, "a"), (-1, 1.0), (3.5, 1.0), (2**40, 1.0), (3, math.nan), (3, 0.5, 1j), (3, -1.0)]
)
def test_ring_state_bad_arguments(args: tuple) -> None:
    with pytest.raises(ModelError):
        pfaff.models.ring_state(*args)


@pytest.mark.parametrize("t", [math.nan, None, "abc", 1j, [], [[0.1, 0.2]], 2.0, -0.1])
def test_trajectory_at_bad_times(t: object) -> None:
    with pytest.raises(StateError, match="`t`"):
        _traj().at(t)  # type: ignore[arg-type]


def test_trajectory_at_is_on_the_rod() -> None:
    q, qd = _traj().at(0.1)
    assert np.hypot(*q) == pytest.approx(1.0, abs=1e-12) and q @ qd == pytest.approx(0, abs=1e-10)


def test_max_step_that_would_never_end() -> None:
    with pytest.raises(OptionError, match=r"`max_step`.*steps"):
        pfaff.simulate(_pendulum(), [1.0, 0.0], [0.0, 0.0], (0.0, 1.0), max_step=1e-300)


def test_projecting_from_a_singular_configuration() -> None:
    with pytest.raises(StateError, match="could not be projected"):
        pfaff.simulate(_pendulum(), [0.0, 0.0], [0.0, 0.0], (0.0, 1.0), project_initial=True)


def test_ida_far_from_zero_is_a_failed_run() -> None:
    traj = pfaff.simulate(_pendulum(), [1.0, 0.0], [0.0, 0.0], (1e16, 1e16 + 4), method="ida")
    assert traj.status == "failed" and "t = " in traj.message
