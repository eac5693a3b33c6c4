"""simulate(output=...): the reported states streamed to a netCDF file (pfaff.integrate.output),
checked against the in-memory trajectory of the same run and read back by SciPy's netCDF reader
(independent of pfaff's); an interrupted or failed run keeps its states, a crash leaves nothing."""

import csv

import numpy as np
import pytest
from scipy.io import netcdf_file

import pfaff
from pfaff.errors import OptionError, SimulationError
from pfaff.integrate import output
from pfaff.integrate.integrators import ProjectedRK
from pfaff.integrate.output import StreamedStates, output_kind

N = 16
T_EVAL = np.linspace(0.0, 0.5, 6)


@pytest.fixture(scope="module")
def ring():
    model = pfaff.models.rolling_ring(N, force=True, family=True).equations()
    return model.compile({"M": 1, "r": 0.5, "F": 2})


@pytest.fixture(scope="module")
def start():
    return pfaff.models.ring_state(N, 0.5, theta=np.pi, theta_dot=0.7)


FIELDS = ("t", "q", "qd", "qdd", "multipliers", "kinetic", "potential", "jacobi", "nc_work",
          "constraint_residual", "energy_balance", "redundant_rows")  # fmt: skip


@pytest.mark.parametrize("t_eval", [T_EVAL, None])  # given times; every step
def test_file_holds_the_trajectory(ring, start, tmp_path, t_eval):
    """The streamed run's arrays (memory maps of the file) equal the in-memory run's; SciPy's
    reader finds the same values, time as the record dimension, and the status."""
    path = tmp_path / "run.nc"
    a = pfaff.simulate(ring, *start, (0.0, 0.5), t_eval=t_eval)
    b = pfaff.simulate(ring, *start, (0.0, 0.5), t_eval=t_eval, output=path)
    assert b.output == path and b.status == a.status == "success"
    for key in FIELDS:
        np.testing.assert_array_equal(getattr(b, key), getattr(a, key), err_msg=key)
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left
    with netcdf_file(path, mmap=False) as f:
        assert f.dimensions["time"] is None  # the unlimited (record) dimension
        np.testing.assert_array_equal(f.variables["q"][:], a.q)
        np.testing.assert_array_equal(f.variables["constraint_residual"][:], a.constraint_residual)
        assert f.status == b"success" and f.stat_steps == a.stats["steps"]
        names = [bytes(r).rstrip(b"\0").decode() for r in f.variables["coordinate"][:]]
        assert names == list(a.coordinate_names)


class _Interrupted(ProjectedRK):
    """Ctrl-C during the third step (what the CLI's signal handler raises)."""

    calls = 0

    def step(self):
        type(self).calls += 1
        if type(self).calls == 3:
            raise KeyboardInterrupt
        super().step()


def test_interrupted_and_failed_runs_keep_their_states(ring, start, tmp_path):
    """Ctrl-C, and max_steps with throw=True: the file is at the target with the states
    reported before the stop, and says why it stopped."""
    every = pfaff.simulate(ring, *start, (0.0, 0.5), max_step=0.05)
    path = tmp_path / "stopped.nc"
    _Interrupted.calls = 0
    traj = pfaff.simulate(ring, *start, (0.0, 0.5), max_step=0.05, method=_Interrupted,
                          output=path)  # fmt: skip
    assert traj.status == "interrupted" and len(traj.t) == 3  # t0 and two steps
    np.testing.assert_allclose(traj.q, every.q[:3], rtol=1e-13, atol=1e-14)
    with netcdf_file(path, mmap=False) as f:
        assert f.status == b"interrupted" and f.variables["time"].shape == (3,)
    with pytest.raises(SimulationError, match=r"max_steps = 4.*states so far"):
        pfaff.simulate(ring, *start, (0.0, 0.5), max_step=0.05, max_steps=4, output=path,
                       throw=True)  # fmt: skip
    with netcdf_file(path, mmap=False) as f:
        assert f.status == b"failed" and f.variables["time"].shape == (5,)
        np.testing.assert_allclose(f.variables["qd"][:], every.qd[:5], rtol=1e-13, atol=1e-14)


def test_a_record_cut_short_is_dropped(ring, start, tmp_path, monkeypatch):
    """Ctrl-C in the middle of writing a record: the file ends with the complete ones."""
    take, calls = StreamedStates.take, []

    def half(self, *rows, **kw):
        calls.append(1)
        if len(calls) == 3:
            self.writer._fh.write(b"\1" * 100)  # part of a record, then the interrupt
            raise KeyboardInterrupt
        take(self, *rows, **kw)

    monkeypatch.setattr(StreamedStates, "take", half)
    path = tmp_path / "cut.nc"
    traj = pfaff.simulate(ring, *start, (0.0, 0.5), t_eval=T_EVAL, output=path)
    assert traj.status == "interrupted" and len(traj.t) == 2
    np.testing.assert_array_equal(traj.t, T_EVAL[:2])
    with netcdf_file(path, mmap=False) as f:
        assert f.variables["nc_work"].shape == (2,)


class _Bug(ProjectedRK):
    def step(self):
        raise RuntimeError("a bug in a stepper")


def test_a_crash_leaves_no_file(ring, start, tmp_path):
    path = tmp_path / "run.nc"
    path.write_text("the user's old file")
    with pytest.raises(RuntimeError, match="a bug"):
        pfaff.simulate(ring, *start, (0.0, 0.5), method=_Bug, output=path)
    assert path.read_text() == "the user's old file" and list(tmp_path.iterdir()) == [path]


def test_csv(ring, start, tmp_path, monkeypatch):
    """A small run's CSV is the trajectory's; a wide one is refused before the run, naming
    `output`; other suffixes are refused."""
    path = tmp_path / "run.csv"
    traj = pfaff.simulate(ring, *start, (0.0, 0.5), t_eval=T_EVAL, output=path)
    with open(path) as fh:
        rows = list(csv.reader(fh))
    assert len(rows) == 1 + len(T_EVAL) and float(rows[-1][1]) == traj.q[-1, 0]
    columns = 1 + 3 * (2**24 + 1) + 3 * 2**24 + 6  # t; q, q̇, q̈; λ, f, g; six energy columns
    with pytest.raises(OptionError, match=rf"`output`: a CSV of {columns} columns.*'big\.nc'"):
        output_kind("big.csv", 2**24 + 1, 2**24)
    monkeypatch.setattr(output, "CSV_COLUMNS", 50)
    with pytest.raises(OptionError, match="`output`: a CSV of"):
        pfaff.simulate(ring, *start, (0.0, 0.5), output=tmp_path / "wide.csv")
    with pytest.raises(OptionError, match=r"`output` must end in \.nc"):
        pfaff.simulate(ring, *start, (0.0, 0.5), output=tmp_path / "run.txt")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]


def test_events_streamed(ring, start, tmp_path):
    """A user event's state is a reported state in the file, and its record keeps its state."""
    event = pfaff.Event(lambda t, q, qd: q[0] - 1.7, "x = 1.7")
    a = pfaff.simulate(ring, *start, (0.0, 0.5), t_eval=T_EVAL, events=[event])
    b = pfaff.simulate(ring, *start, (0.0, 0.5), t_eval=T_EVAL, events=[event],
                       output=tmp_path / "run.nc")  # fmt: skip
    assert len(b.events) == len(a.events) == 1 and len(b.t) == len(T_EVAL) + 1
    np.testing.assert_array_equal(b.t, a.t)
    np.testing.assert_array_equal(b.events[0].q, a.events[0].q)
    assert b.events[0].q[0] == pytest.approx(1.7, abs=1e-12)


def test_long_name_sequences_stay_the_models(ring, start, monkeypatch):
    """A trajectory lists its names when short, and keeps the model's own (immutable, lazy for
    a family) sequence when longer than LAZY_NAMES, as a streamed run does: listing 2^21 names
    took 3 s of CPU at the end of a run."""
    from pfaff.integrate import simulation

    short = pfaff.simulate(ring, *start, (0.0, 0.1))
    monkeypatch.setattr(simulation, "LAZY_NAMES", N // 2)
    long = pfaff.simulate(ring, *start, (0.0, 0.1))
    assert (
        type(short.coordinate_names) is list and short.coordinate_names is not ring.coordinate_names
    )
    assert long.coordinate_names is ring.coordinate_names
    assert (
        list(long.coordinate_names)
        == short.coordinate_names
        == ["x", *[f"theta{k}" for k in range(1, N + 1)]]
    )
    assert list(long.multiplier_names) == short.multiplier_names
