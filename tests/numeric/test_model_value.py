"""The compiled model as a value (issue 21): immutable, per-call inputs, run copies, evaluators
chosen by rule, pickles that round-trip bit for bit in a fresh process."""

from __future__ import annotations

import pickle
import subprocess
import sys

import numpy as np
import pytest
import sympy as sp

import pfaff
import systems
from methods import ALL_METHODS
from pfaff.errors import ModelTypeError, OptionError, ParameterError
from pfaff.numeric.evaluator import MACHINE_FROM

ROUND_TRIP = """
import pickle, sys
import numpy as np
model, t, q, qd = pickle.loads(sys.stdin.buffer.read())
qdd, lam = model.accelerations(t, q, qd)
sys.stdout.buffer.write(pickle.dumps((qdd, lam, model.timings["evaluator"])))
"""


def driven_particle() -> pfaff.NumericModel:
    """The issue's case: a particle pushed along x by an input u, held on the line y = x."""
    return systems.driven_particle().equations().compile({})


def chain(k: int) -> pfaff.System:
    """A planar chain of k unit point masses on unit rods, in absolute angles."""
    qs = [pfaff.coordinates(f"a{i}") for i in range(k)]
    s = pfaff.System(qs)
    x = y = 0
    for q in qs:
        x, y = x + sp.sin(q), y - sp.cos(q)
        s.add_particle(1, [x, y])
        s.add_potential_energy(sp.Float(9.81) * y)
    return s


@pytest.mark.parametrize("method", ALL_METHODS)
def test_traj_at_leaves_the_model_unchanged(method: str) -> None:
    """x'' = y'' = u/2 while u = 4 + t drives it; afterwards the model's u is still 0."""
    model = driven_particle()
    traj = pfaff.simulate(
        model, [0, 0], [0, 0], (0, 1), method=method, inputs={"u": lambda t: 4.0 + t}
    )
    assert traj.status == "success", traj.message
    state = traj.at(0.7)
    assert state is not None
    qdd, _ = model.accelerations(0.0, [0.0, 0.0], [0.0, 0.0])
    np.testing.assert_array_equal(qdd, [0.0, 0.0])  # not 2.35: the run's u stayed in the run
    assert model.parameters["u"] == 0.0
    # along the line x = y the mass is 2: x'' = (4 + t)/2, x(t) = t² + t³/12
    t = traj.t[-1]
    assert traj.q[-1, 0] == pytest.approx(t**2 + t**3 / 12, rel=1e-7)


def test_inputs_per_call_write_nothing() -> None:
    model = driven_particle()
    qdd, lam = model.accelerations(0.0, [0.0, 0.0], [0.0, 0.0], inputs={"u": 4.0})
    np.testing.assert_allclose(qdd, [2.0, 2.0], rtol=1e-14)  # m = 1 each way: u / 2
    np.testing.assert_allclose(lam, [2.0], rtol=1e-14)  # the line pushes y with u / 2
    np.testing.assert_array_equal(model.accelerations(0.0, [0, 0], [0, 0])[0], [0.0, 0.0])
    np.testing.assert_array_equal(
        model.accelerations(0.0, [0, 0], [0, 0], inputs={})[0], [0.0, 0.0]
    )  # a missing input is 0
    with pytest.raises(OptionError, match="`inputs`: `v` is not an input"):
        model.accelerations(0.0, [0, 0], [0, 0], inputs={"v": 1.0})
    with pytest.raises(OptionError, match=r"inputs\['u'\]"):
        model.accelerations(0.0, [0, 0], [0, 0], inputs={"u": "fast"})


def test_a_model_cannot_be_changed() -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    with pytest.raises(AttributeError, match="immutable"):
        model.solver = "lu"
    with pytest.raises(TypeError):
        model.parameters["m"] = 5.0  # type: ignore[index]
    assert model.with_parameters({"m": 5.0}).parameters["m"] == 5.0
    assert model.parameters["m"] == 1.0


def test_with_parameters_refuses_what_compile_refuses() -> None:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    for bad in (np.bool_(True), True, "1", 1 + 0j, np.array([1.0, 2.0])):
        with pytest.raises(ParameterError, match="parameter `m` must be a real number"):
            model.with_parameters({"m": bad})
        with pytest.raises(ParameterError, match="`m` must be a real number"):
            pfaff.models.cartesian_pendulum().equations().compile({"m": bad, "g": 9.81, "L": 2})


def test_evaluators_agree_and_are_reported() -> None:
    s = chain(4)
    q, qd = np.array([0.3, -0.2, 0.5, 0.1]), np.array([0.4, 0.0, -0.3, 0.2])
    results = {}
    for evaluator in ("template", "python", "machine"):
        model = s.equations().compile({}, evaluator=evaluator)
        assert model.evaluator == evaluator == model.timings["evaluator"]
        results[evaluator] = model.accelerations(0.0, q, qd)[0]
    np.testing.assert_allclose(results["python"], results["template"], rtol=1e-12)
    np.testing.assert_allclose(results["machine"], results["template"], rtol=1e-12)
    # the rule: the generated Python below MACHINE_FROM unknowns, machine code from there on
    assert chain(MACHINE_FROM - 1).equations().compile({}).evaluator == "python"
    assert chain(MACHINE_FROM).equations().compile({}).evaluator == "machine"
    with pytest.raises(OptionError, match="`evaluator` must be one of"):
        s.equations().compile({}, evaluator="fortran")
    ring = pfaff.models.rolling_ring(4, force=True, family=True).equations()
    with pytest.raises(OptionError, match="`evaluator` of a model with families"):
        ring.compile({"M": 1, "r": 0.5, "F": 2}, evaluator="python")
    with pytest.raises(OptionError, match="'python' needs the fused kernel"):
        s.equations().compile({}, solver="lu", evaluator="python")


def _fresh_process(model: object, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
    out = subprocess.run(
        [sys.executable, "-c", ROUND_TRIP],
        input=pickle.dumps((model, t, q, qd)),
        capture_output=True,
        check=False,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr.decode()[-3000:]
    return pickle.loads(out.stdout)


@pytest.mark.parametrize(
    "evaluator",
    [
        pytest.param("template", marks=pytest.mark.slow),
        pytest.param("python", marks=pytest.mark.slow),
        "machine",
    ],
)
@pytest.mark.slow  # (over a second: the full suite runs it)
def test_a_pickled_model_is_bit_identical_in_a_fresh_process(evaluator: str) -> None:
    model = chain(8).equations().compile({}, evaluator=evaluator)
    rng = np.random.default_rng(4)
    q, qd = rng.uniform(-1, 1, 8), rng.uniform(-1, 1, 8)
    qdd, lam, used = _fresh_process(model, 0.25, q, qd)
    want = model.accelerations(0.25, q, qd)
    assert used == evaluator
    np.testing.assert_array_equal(qdd, want[0])
    np.testing.assert_array_equal(lam, want[1])


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_a_pickled_family_model_round_trips_and_changes_values() -> None:
    N = 1024
    model = pfaff.models.rolling_ring(N, force=True, family=True).equations()
    model = model.compile({"M": 1.0, "r": 0.5, "F": 2.0})
    q, qd = pfaff.models.ring_state(N, radius=0.5, theta=0.3, theta_dot=1.0)
    qdd, lam, _ = _fresh_process(model, 0.0, q, qd)
    want = model.accelerations(0.0, q, qd)
    np.testing.assert_array_equal(qdd, want[0])
    np.testing.assert_array_equal(lam, want[1])
    again = pickle.loads(pickle.dumps(model)).with_parameters({"F": 6.0})
    qdd, lam = again.accelerations(0.0, q, qd)
    assert qdd[0] == pytest.approx(6.0 / 2.0, rel=1e-12)  # x'' = F / (2M)
    assert lam[0] == pytest.approx(-3.0, rel=1e-12)  # the friction multiplier -F/2


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_the_ring_pickles_without_its_work_arrays() -> None:
    """A pickle carries parts and values: O(1) in N, not the 2^16 particles' arrays."""
    sizes = []
    for N in (2**10, 2**16):
        model = pfaff.models.rolling_ring(N, force=True, family=True).equations()
        sizes.append(len(pickle.dumps(model.compile({"M": 1.0, "r": 0.5, "F": 2.0}))))
    assert sizes[1] < 200_000
    assert sizes[1] < 1.5 * sizes[0] + 20_000  # the flags pack to N/8 bytes at most


@pytest.mark.slow
def test_the_ring_of_2_20_pickles_under_a_megabyte() -> None:
    N = 2**20
    model = pfaff.models.rolling_ring(N, force=True, family=True).equations()
    data = pickle.dumps(model.compile({"M": 1.0, "r": 0.5, "F": 2.0}))
    assert len(data) < 1_000_000


def test_same_run_twice_is_bit_identical() -> None:
    model = chain(8).equations().compile({})
    q0 = np.array([0.3, -0.2, 0.5, 0.1, 0.0, 0.2, -0.1, 0.4])
    runs = [pfaff.simulate(model, q0, np.zeros(8), (0, 1.0)) for _ in range(2)]
    runs.append(pfaff.simulate(pickle.loads(pickle.dumps(model)), q0, np.zeros(8), (0, 1.0)))
    for other in runs[1:]:
        np.testing.assert_array_equal(other.q, runs[0].q)
        np.testing.assert_array_equal(other.multipliers, runs[0].multipliers)


def test_family_models_have_with_parameters_and_say_what_they_lack() -> None:
    ring = pfaff.models.rolling_ring(8, force=True, family=True).equations()
    model = ring.compile({"M": 1.0, "r": 0.5, "F": 2.0})
    heavy = model.with_parameters({"M": 4.0})
    q, qd = pfaff.models.ring_state(8, radius=0.5, theta=0.3)
    assert heavy.accelerations(0.0, q, qd)[0][0] == pytest.approx(2.0 / 8.0, rel=1e-12)
    assert model.accelerations(0.0, q, qd)[0][0] == pytest.approx(2.0 / 2.0, rel=1e-12)
    with pytest.raises(ModelTypeError, match="linearize"):
        model.linearize(0.0, q, qd, ["x"])


def test_compile_machine_code_switches_to_machine_code_now() -> None:
    small = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    q, qd = [0.5], [0.3]
    before = small.accelerations(0.0, q, qd)[0]
    assert small.evaluator == "python" and small.compile_machine_code() is True
    assert small.evaluator == "machine" == small.timings["evaluator"]
    np.testing.assert_allclose(small.accelerations(0.0, q, qd)[0], before, rtol=1e-13)
    big = chain(8).equations().compile({})
    assert big.compile_machine_code() is True
    assert big.evaluator == "machine" and "machine_code" in big.timings
    template = chain(4).equations().compile({}, evaluator="template")
    assert template.compile_machine_code() is False and template.evaluator == "template"


def test_an_unpickled_machine_model_changes_values_and_runs_the_same() -> None:
    """A sweep's worker gets the model pickled: other values through with_parameters, machine
    code included (it has no compiler of its own), bit for bit what the original gives."""
    model = chain(8).equations().compile({})
    assert model.evaluator == "machine"
    q0 = np.linspace(0.1, 0.8, 8)
    here = model.with_parameters({})
    there = pickle.loads(pickle.dumps(model)).with_parameters({})
    assert there.evaluator == "machine"
    a = pfaff.simulate(here, q0, np.zeros(8), (0, 0.5))
    b = pfaff.simulate(there, q0, np.zeros(8), (0, 0.5))
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.multipliers, b.multipliers)
