"""pfaff.sweep in this process (``scheduler="synchronous"``): physics, layout, failures, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.special
import xarray as xr

import pfaff
from pfaff.sweep import make_grid, parse_vary, run_batch, summary, write_netcdf
from pfaff.sweep.driver import batch_size


def periods(t: np.ndarray, theta: np.ndarray) -> float:
    """Mean time between upward zero crossings of theta(t) (linear interpolation)."""
    i = np.flatnonzero((theta[:-1] < 0) & (theta[1:] >= 0))
    tc = t[i] - theta[i] * (t[i + 1] - t[i]) / (theta[i + 1] - theta[i])
    assert len(tc) >= 2
    return float(np.diff(tc).mean())


def test_small_angle_periods_across_lengths(pendulum):
    lengths = np.array([0.25, 0.5, 1.0, 2.0])
    ds = pfaff.sweep(pendulum, {"L": lengths}, t_end=8.0, samples=4001, scheduler="synchronous")
    assert (ds.status == "success").all()
    g = 9.81
    for L in lengths:
        theta = ds.q.sel(L=L, coordinate="theta").values
        expected = 2 * math.pi * math.sqrt(L / g) * (1 + 0.01**2 / 16)  # amplitude 0.01
        assert periods(ds.time.values, theta) == pytest.approx(expected, rel=2e-6)


def test_large_amplitude_periods_on_a_grid(pendulum):
    """Over L x q0.theta: T = 4 sqrt(L/g) K(sin^2(theta0/2)), the complete elliptic integral."""
    ds = pfaff.sweep(
        pendulum,
        {"L": [0.5, 1.5], "q0.theta": [0.5, 1.5, 2.5]},
        t_end=12.0,
        samples=6001,
        scheduler="synchronous",
    )
    assert ds.q.dims == ("L", "q0.theta", "time", "coordinate")
    for L in (0.5, 1.5):
        for th0 in (0.5, 1.5, 2.5):
            theta = ds.q.sel({"L": L, "q0.theta": th0, "coordinate": "theta"}).values
            assert theta[0] == th0
            exact = 4 * math.sqrt(L / 9.81) * scipy.special.ellipk(math.sin(th0 / 2) ** 2)
            assert periods(ds.time.values, theta) == pytest.approx(exact, rel=1e-5)
    assert float(ds.energy_error.max()) < 1e-6


def test_layout_and_defaults(cartesian):
    ds = pfaff.sweep(
        cartesian, {"g": [9.81, 1.62], "qd0.x": [0.0, 1.0, 2.0]}, scheduler="synchronous"
    )
    assert ds.sizes == {"g": 2, "qd0.x": 3, "time": 201, "coordinate": 2, "multiplier": 1}
    np.testing.assert_array_equal(ds.time.values, np.linspace(0.0, 2.0, 201))  # [simulate] t_end
    assert ds.multipliers.dims == ("g", "qd0.x", "time", "multiplier")
    assert ds.coordinate.values.tolist() == ["x", "y"]
    assert ds.constraint.values.tolist() == ["rod"]
    for name in ("status", "message", "energy_error", "constraint_residual"):
        assert ds[name].dims == ("g", "qd0.x")
    assert ds.status.dtype.kind == "U" and (ds.status == "success").all()
    assert float(ds.constraint_residual.max()) < 1e-9
    assert float(ds.energy_error.max()) < 1e-7
    # the rod tension at the bottom at t = 0: -2 L lambda = m g + m v^2 / L (m = 2, L = 1)
    lam0 = ds.multipliers.isel(time=0, multiplier=0)
    for g in (9.81, 1.62):
        for v in (0.0, 1.0, 2.0):
            tension = -2 * float(lam0.sel({"g": g, "qd0.x": v}))
            assert tension == pytest.approx(2 * g + 2 * v**2, rel=1e-9)


def test_identical_to_serial_simulate_runs(cartesian):
    """Each run equals pfaff.simulate of a model compiled afresh with the run's values."""
    vary = {"L": [1.0], "m": [0.5, 3.0], "qd0.x": [0.5, 1.5]}
    ds = pfaff.sweep(cartesian, vary, samples=51, scheduler="synchronous")
    mf = pfaff.load_model(cartesian)
    t_eval = np.linspace(0, 2.0, 51)
    for m in vary["m"]:
        for v in vary["qd0.x"]:
            model = mf.compile(m=m)
            traj = pfaff.simulate(
                model, mf.q0, [v, 0.0], (0, 2.0), t_eval=t_eval, rtol=1e-10, atol=1e-12
            )
            run = ds.sel({"L": 1.0, "m": m, "qd0.x": v})
            np.testing.assert_allclose(run.q.values, traj.q, rtol=0, atol=1e-12)
            np.testing.assert_allclose(run.qd.values, traj.qd, rtol=0, atol=1e-12)
            np.testing.assert_allclose(run.multipliers.values, traj.multipliers, rtol=1e-11)
            assert float(run.energy_error) == pytest.approx(np.abs(traj.energy_balance).max())


def test_a_loaded_model_file_with_edited_values(pendulum):
    mf = pfaff.load_model(pendulum)
    mf.parameters["g"] = 1.62  # the Moon
    ds = pfaff.sweep(mf, {"L": [1.0]}, t_end=12.0, samples=3001, scheduler="synchronous")
    theta = ds.q.sel(L=1.0, coordinate="theta").values
    assert periods(ds.time.values, theta) == pytest.approx(2 * math.pi / math.sqrt(1.62), rel=1e-5)


def test_a_failed_run_is_a_status(pendulum):
    ds = pfaff.sweep(
        pendulum, {"L": [0.0, 1.0], "m": [-1.0, 1.0]}, t_end=1.0, scheduler="synchronous"
    )
    status = ds.status.values
    assert status.tolist() == [["failed", "failed"], ["failed", "success"]]
    assert "undetermined" in str(ds.message.sel(L=0.0, m=1.0).values)  # no inertia
    assert "not positive definite" in str(ds.message.sel(L=1.0, m=-1.0).values)
    assert np.isnan(ds.q.sel(L=0.0, m=1.0)).all()
    assert np.isfinite(ds.q.sel(L=1.0, m=1.0)).all()
    s = summary(ds)
    assert (s["runs"], s["succeeded"], s["failed"]) == (4, 1, 3)
    assert s["failures"][0]["point"] == {"L": 0.0, "m": -1.0}


def test_a_run_that_fails_half_way_keeps_its_samples(tmp_path):
    """A value leaving the equations' domain mid-run: status failed, samples up to there."""
    p = tmp_path / "escape.toml"
    p.write_text(
        """
[model]
coordinates = ["x"]
parameters = { m = 1.0, b = 1.0 }
kinetic = "m*dot(x)**2/2"
potential = "-sqrt(b - x)/100"
[initial]
q = { x = 0.0 }
qd = { x = 1.0 }
[simulate]
t_end = 3.0
"""
    )
    ds = pfaff.sweep(p, {"b": [10.0, 1.5]}, samples=31, scheduler="synchronous")
    assert ds.status.sel(b=10.0) == "success"  # x grows about like t: it reaches 3 < 10
    assert ds.status.sel(b=1.5) == "failed"  # sqrt(1.5 - x) is not real beyond t = 1.5
    q = ds.q.sel(b=1.5, coordinate="x").values
    assert np.isfinite(q[:10]).all() and np.isnan(q[-1])
    assert "t = 1." in str(ds.message.sel(b=1.5).values)


def test_bad_vary_and_options(pendulum):
    sync = {"scheduler": "synchronous"}
    with pytest.raises(pfaff.OptionError, match="`M` is neither a parameter"):
        pfaff.sweep(pendulum, {"M": [1.0]}, **sync)
    with pytest.raises(pfaff.OptionError, match=r"`q0.phi` is not q0.<coordinate>"):
        pfaff.sweep(pendulum, {"q0.phi": [1.0]}, **sync)
    with pytest.raises(pfaff.OptionError, match="must be finite"):
        pfaff.sweep(pendulum, {"L": [1.0, np.nan]}, **sync)
    with pytest.raises(pfaff.OptionError, match="has no values"):
        pfaff.sweep(pendulum, {"L": []}, **sync)
    with pytest.raises(pfaff.OptionError, match="non-empty dict"):
        pfaff.sweep(pendulum, {}, **sync)
    with pytest.raises(pfaff.OptionError, match="one-dimensional sequence of numbers"):
        pfaff.sweep(pendulum, {"L": "1.0"}, **sync)
    with pytest.raises(pfaff.OptionError, match="`t_end` must be positive"):
        pfaff.sweep(pendulum, {"L": [1.0]}, t_end=-1.0, **sync)
    with pytest.raises(pfaff.OptionError, match="`samples`"):
        pfaff.sweep(pendulum, {"L": [1.0]}, samples=1, **sync)
    with pytest.raises(pfaff.OptionError, match="`workers`"):
        pfaff.sweep(pendulum, {"L": [1.0]}, workers=0, **sync)
    with pytest.raises(pfaff.OptionError, match="`scheduler` must be"):
        pfaff.sweep(pendulum, {"L": [1.0]}, scheduler=42)
    with pytest.raises(pfaff.OptionError, match="is not a scheduler address"):
        pfaff.sweep(pendulum, {"L": [1.0]}, scheduler="tls://host:8786")
    with pytest.raises(pfaff.OptionError, match="cannot reach the Dask scheduler"):
        pfaff.sweep(pendulum, {"L": [1.0]}, scheduler="tcp://127.0.0.1:1")
    with pytest.raises(TypeError, match="`model`"):
        pfaff.sweep(42, {"L": [1.0]}, **sync)  # type: ignore[arg-type]
    with pytest.raises(pfaff.ModelFileError, match="cannot be read"):
        pfaff.sweep(pendulum.parent / "missing.toml", {"L": [1.0]}, **sync)


def test_no_end_time(tmp_path):
    p = tmp_path / "no_end.toml"
    p.write_text('[model]\ncoordinates = ["x"]\nkinetic = "dot(x)**2/2"\n')
    with pytest.raises(pfaff.OptionError, match="no end time"):
        pfaff.sweep(p, {"q0.x": [1.0]}, scheduler="synchronous")
    ds = pfaff.sweep(p, {"qd0.x": [1.0, 2.0]}, t_end=1.0, samples=3, scheduler="synchronous")
    np.testing.assert_allclose(ds.q.sel(coordinate="x").isel(time=-1), [1.0, 2.0], rtol=1e-12)


def test_parse_vary():
    name, values = parse_vary("L=0.5:2:4")
    assert name == "L" and values.tolist() == [0.5, 1.0, 1.5, 2.0]  # STOP included
    assert parse_vary("q0.theta1=-1:1:3")[1].tolist() == [-1.0, 0.0, 1.0]
    assert parse_vary("c=3:3:1")[1].tolist() == [3.0]
    for bad, why in [
        ("L", "expected NAME=START:STOP:COUNT"),
        ("L=1:2", "expected NAME"),
        ("=1:2:3", "expected NAME"),
        ("L=a:2:3", "START and STOP must be numbers"),
        ("L=1:inf:3", "must be finite"),
        ("L=1:2:0", "COUNT must be a whole number"),
        ("L=1:2:2.5", "COUNT must be a whole number"),
    ]:
        with pytest.raises(pfaff.OptionError, match=why):
            parse_vary(bad)


def test_grid_order():
    g = make_grid({"b": [1, 2, 3], "a": [10, 20]}, ["a", "b"], [])
    assert g.names == ("b", "a") and g.shape == (3, 2)
    assert [g.point(i) for i in (0, 1, 5)] == [
        {"b": 1.0, "a": 10.0},
        {"b": 1.0, "a": 20.0},
        {"b": 3.0, "a": 20.0},
    ]


def test_batches_last_at_least_a_tenth_of_a_second():
    for seconds in (1e-4, 1e-3, 0.01, 0.05):
        for runs in (10, 256, 10_000):
            b = batch_size(seconds, runs, 2)
            assert b == runs or b * seconds >= 0.1
    assert batch_size(1.0, 256, 2) == 2  # long runs: tasks of about 2 s
    assert batch_size(5.0, 256, 2) == 1


def test_the_model_is_compiled_once_per_process(pendulum, monkeypatch):
    """Batches after the first take the cached model: no derivation, no compile again."""
    from pfaff.sweep import worker
    from pfaff.sweep.worker import SweepSpec

    calls = []
    real = worker._Compiled.__init__

    def counting(self, spec):
        calls.append(spec.key)
        real(self, spec)

    monkeypatch.setattr(worker._Compiled, "__init__", counting)
    monkeypatch.setattr(worker, "_MODELS", type(worker._MODELS)())
    grid = make_grid({"L": np.linspace(0.5, 2.0, 6)}, ["m", "L", "g"], ["theta"])
    spec = SweepSpec(
        pendulum.read_text(), "p.toml", {"m": 1.0, "L": 1.0, "g": 9.81}, (0.3,), (0.0,),
        ("theta",), grid, np.linspace(0, 1, 11),
    )  # fmt: skip
    outs = [run_batch(spec, b) for b in ([0, 1], [2, 3], [4, 5])]
    assert len(calls) == 1
    assert all(s == "success" for o in outs for s in o["status"])
    # the compiled code is shared: every run's model is the first one with new values
    entry = worker._MODELS[spec.key]
    assert entry.model({"m": 1.0, "L": 3.0, "g": 9.81})._fused is entry.base._fused


def test_netcdf_round_trip(cartesian, pendulum, tmp_path):
    for path, vary in ((cartesian, {"qd0.x": [0.0, 1.0]}), (pendulum, {"L": [1.0, 2.0]})):
        ds = pfaff.sweep(path, vary, samples=11, scheduler="synchronous")
        out = write_netcdf(ds, tmp_path / f"{path.stem}.nc")
        with xr.open_dataset(out) as back:
            back.load()
        np.testing.assert_array_equal(back.q.values, ds.q.values)
        assert back.status.values.tolist() == ds.status.values.tolist()
        assert list(back.q.dims) == list(ds.q.dims)
        if ds.sizes["multiplier"]:
            np.testing.assert_array_equal(back.multipliers.values, ds.multipliers.values)
        else:  # no constraints: SciPy's netCDF3 cannot read a dimension of length zero back
            assert "multipliers" not in back and back.attrs["omitted_empty_dimensions"]


RING = """
[model]
name = "pushed ring"
coordinates = ["x"]
parameters = { M = 1.0, r = 0.5, F = 2.0 }

[[families]]
name = "theta"
n = 4
first = 1

[[particles]]
mass = "M/4"
position = ["x + r*sin(theta[k])", "r*cos(theta[k])"]
over = "k"

[[forces]]
force = ["F", "0"]
at = ["x", "0"]

[[constraints]]
name = "no slip"
holonomic = "x - r*theta1"

[[constraints]]
name = "spacing"
holonomic = "theta[k+1] - theta[k] - pi/2"
over = ["k", 1, 3]

[initial]
q = { x = 0.0, theta = [0.0, 1.5707963267948966, 3.141592653589793, 4.71238898038469] }

[simulate]
t_end = 2.0
"""


def test_a_family_model(tmp_path):
    """The ring (a family; its model is compiled again per value of F) rolls with x'' = F/(2M)."""
    p = tmp_path / "ring.toml"
    p.write_text(RING)
    ds = pfaff.sweep(p, {"F": [0.0, 1.0, 2.0], "M": [1.0, 4.0]}, samples=5, scheduler="synchronous")
    assert (ds.status == "success").all()
    assert ds.coordinate.values.tolist() == ["x", "theta1", "theta2", "theta3", "theta4"]
    assert ds.constraint.values.tolist()[0] == "no slip"
    x_end = ds.q.sel(coordinate="x").isel(time=-1)
    for F in (0.0, 1.0, 2.0):
        for M in (1.0, 4.0):
            assert float(x_end.sel(F=F, M=M)) == pytest.approx(F / (2 * M) * 2.0**2 / 2, abs=1e-9)
    assert float(ds.energy_error.max()) < 1e-8  # the push's work accounted for
