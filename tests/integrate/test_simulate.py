"""pfaff.simulate and pfaff.Trajectory against closed forms and independent integrations.

References: the one-angle pendulum θ̈ = -(g/L) sin θ integrated here by SciPy's DOP853 at tight
tolerances (written by hand, not taken from pfaff), its period 4K(1/2)/√(g/L) and the rod tension
m(v²/L + g cos θ); the pushed ring's x = F t²/(4M), θ = x/r, λ₁ = -F/2; a particle pushed by
1/(1 - x) reaching x = 1 at t = √(π/2).
"""

from __future__ import annotations

import csv
import itertools
import math
import re

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.special import ellipk

import pfaff
from methods import ALL_METHODS
from pfaff.numeric.protocol import OdeFunction

MASS, LENGTH, G = 0.7, 1.0, 9.81
OMEGA = math.sqrt(G / LENGTH)
PERIOD = 4 * ellipk(0.5) / OMEGA  # released at rest from horizontal: amplitude π/2, k² = 1/2
RING = {"M": 2.0, "r": 0.5, "F": 3.0}


# ---------------------------------------------------------------------------------- references
def angle_reference(t_eval: np.ndarray, theta0: float = math.pi / 2, omega0: float = 0.0):
    """θ, θ̇ of m L² θ̈ + m g L sin θ = 0 (θ from the downward vertical) and the Cartesian image."""
    sol = solve_ivp(
        lambda t, y: [y[1], -G / LENGTH * math.sin(y[0])],
        (0.0, float(t_eval[-1])),
        [theta0, omega0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        t_eval=t_eval,
    )
    assert sol.success
    th, om = sol.y
    q = np.column_stack([LENGTH * np.sin(th), -LENGTH * np.cos(th)])
    qd = np.column_stack([LENGTH * np.cos(th) * om, LENGTH * np.sin(th) * om])
    return th, om, q, qd


def rod_residuals(q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """f = x² + y² - L² and ḟ = 2(x ẋ + y ẏ), computed here, not by pfaff."""
    f = q[..., 0] ** 2 + q[..., 1] ** 2 - LENGTH**2
    g = 2 * (q[..., 0] * qd[..., 0] + q[..., 1] * qd[..., 1])
    return f, g


@pytest.fixture(scope="module")
def pend() -> pfaff.NumericModel:
    system = pfaff.models.cartesian_pendulum()
    return system.equations().compile({"m": MASS, "g": G, "L": LENGTH})


@pytest.fixture(scope="module")
def ring() -> pfaff.NumericModel:
    return pfaff.models.rolling_ring(4, force=True).equations().compile(RING)


Q0, QD0 = [LENGTH, 0.0], [0.0, 0.0]  # at rest, rod horizontal


# ---------------------------------------------------------------------------------- 1. long runs
@pytest.mark.slow
def test_pendulum_100_periods_projection(pend: pfaff.NumericModel) -> None:
    """100 periods (≈ 237 s of motion) from horizontal: positions to 1e-7, |f| <= 1e-10."""
    te = np.linspace(0.0, 100 * PERIOD, 1001)
    traj = pfaff.simulate(pend, Q0, QD0, (0.0, te[-1]), t_eval=te, rtol=1e-11, atol=1e-12)
    assert traj.status == "success"
    _, _, q_ref, qd_ref = angle_reference(te)
    assert np.abs(traj.q - q_ref).max() < 1e-7
    assert np.abs(traj.qd - qd_ref).max() < 1e-6
    f, g = rod_residuals(traj.q, traj.qd)
    assert np.abs(f).max() <= 1e-10 and np.abs(g).max() <= 1e-10
    assert np.abs(traj.position_residual).max() <= 1e-10
    # after a whole number of periods the bob is back at (L, 0)
    np.testing.assert_allclose(traj.q[-1], [LENGTH, 0.0], atol=1e-7)


@pytest.mark.slow
def test_pendulum_ida_few_periods(pend: pfaff.NumericModel) -> None:
    """IDA (BDF) over 5 periods only: 100 periods at this accuracy take ~30 s, too slow here."""
    te = np.linspace(0.0, 5 * PERIOD, 201)
    traj = pfaff.simulate(
        pend, Q0, QD0, (0.0, te[-1]), method="ida", t_eval=te, rtol=1e-11, atol=1e-12
    )
    assert traj.status == "success"
    _, _, q_ref, _ = angle_reference(te)
    assert np.abs(traj.q - q_ref).max() < 1e-7
    f, g = rod_residuals(traj.q, traj.qd)
    assert np.abs(f).max() <= 1e-10 and np.abs(g).max() <= 1e-10


# ---------------------------------------------------------------------------------- 2. tension
def test_rod_tension_closed_form(pend: pfaff.NumericModel) -> None:
    """Tension -2Lλ = m(v²/L + g cos θ) along the swing; 3mg at the bottom (t = T/4, 3T/4)."""
    bottoms = [PERIOD / 4, 3 * PERIOD / 4]
    te = np.unique(np.concatenate([np.linspace(0.0, PERIOD, 41), bottoms]))
    traj = pfaff.simulate(pend, Q0, QD0, (0.0, PERIOD), t_eval=te, rtol=1e-12, atol=1e-12)
    th, om, _, _ = angle_reference(te)
    tension = -2 * LENGTH * traj.multipliers[:, 0]
    expected = MASS * (LENGTH * om**2 + G * np.cos(th))
    np.testing.assert_allclose(tension, expected, rtol=0, atol=1e-8 * 3 * MASS * G)
    at_bottom = tension[np.searchsorted(te, bottoms)]
    np.testing.assert_allclose(at_bottom, 3 * MASS * G, rtol=1e-8)
    assert tension[0] == pytest.approx(0.0, abs=1e-12)  # at rest, rod horizontal


# ---------------------------------------------------------------------------------- 3. drift
def _max_f(traj: pfaff.Trajectory) -> tuple[float, float]:
    f, _ = rod_residuals(traj.q, traj.qd)
    k = len(traj.t)
    first = np.abs(f[traj.t <= traj.t[-1] / 10]).max()
    last = np.abs(f[traj.t >= 0.9 * traj.t[-1]]).max()
    assert k > 100
    return first, last


def test_baumgarte_residual_bounded(pend: pfaff.NumericModel) -> None:
    """α = β = 10: the drift is damped, so max |f| in the last tenth is no larger than the first's."""
    traj = pfaff.simulate(pend, Q0, QD0, (0.0, 100.0), method="baumgarte", rtol=1e-6, atol=1e-8)
    assert traj.status == "success"
    first, last = _max_f(traj)
    assert last < 2 * first
    assert max(first, last) < 1e-6
    # unprojected output: the reported residual is the real drift
    np.testing.assert_allclose(
        traj.position_residual[:, 0], rod_residuals(traj.q, traj.qd)[0], rtol=1e-6, atol=1e-15
    )


def test_unstabilized_residual_grows(pend: pfaff.NumericModel) -> None:
    """α = β = 0 and no projection: the acceleration-level equations let f drift away."""
    traj = pfaff.simulate(
        pend,
        Q0,
        QD0,
        (0.0, 100.0),
        method="baumgarte",
        alpha=0.0,
        beta=0.0,
        project_output=False,
        rtol=1e-6,
        atol=1e-8,
    )
    first, last = _max_f(traj)
    assert last > 20 * first
    stabilized = pfaff.simulate(
        pend, Q0, QD0, (0.0, 100.0), method="baumgarte", rtol=1e-6, atol=1e-8
    )
    assert last > 20 * _max_f(stabilized)[1]


# ---------------------------------------------------------------------------------- 4. ring
@pytest.mark.parametrize("method", ALL_METHODS)
def test_pushed_ring(ring: pfaff.NumericModel, method: str) -> None:
    """From rest: x = F t²/(4M), θ_k = x/r + (k-1)π/2, friction λ₁ = -F/2 at every point."""
    M, r, F = RING["M"], RING["r"], RING["F"]
    q0, qd0 = pfaff.models.ring_state(4, radius=r)
    te = np.linspace(0.0, 2.0, 21)
    traj = pfaff.simulate(ring, q0, qd0, (0.0, 2.0), method=method, t_eval=te)
    assert traj.status == "success"
    x = F * te**2 / (4 * M)
    np.testing.assert_allclose(traj.q[:, 0], x, atol=1e-9)
    for k in range(4):
        np.testing.assert_allclose(traj.q[:, 1 + k], x / r + k * math.pi / 2, atol=1e-9)
    np.testing.assert_allclose(traj.qd[:, 0], F * te / (2 * M), atol=1e-9)
    np.testing.assert_allclose(traj.qdd[:, 1:], F / (2 * M * r), atol=1e-8)
    np.testing.assert_allclose(traj.multipliers[:, 0], -F / 2, atol=1e-8)
    drift = 1e-7 if method == "baumgarte" else 1e-10  # Baumgarte output is not projected
    assert np.abs(traj.constraint_residual).max() < drift


# ---------------------------------------------------------------------------------- 5. agreement
def test_methods_agree(pend: pfaff.NumericModel) -> None:
    te = np.linspace(0.0, 3.0, 31)
    _, _, q_ref, _ = angle_reference(te)
    runs = {m: pfaff.simulate(pend, Q0, QD0, (0.0, 3.0), method=m, t_eval=te) for m in ALL_METHODS}
    for m, traj in runs.items():
        assert traj.status == "success", m
        assert np.abs(traj.q - q_ref).max() < 1e-6, m
    for a, b in itertools.combinations(ALL_METHODS, 2):
        assert np.abs(runs[a].q - runs[b].q).max() < 1e-6, (a, b)
        assert np.abs(runs[a].qd - runs[b].qd).max() < 1e-5, (a, b)


@pytest.mark.parametrize("integrator", ["DOP853", "RK45", "RK23"])
def test_integrators(pend: pfaff.NumericModel, integrator: str) -> None:
    te = np.linspace(0.0, 1.0, 11)
    traj = pfaff.simulate(
        pend, Q0, QD0, (0.0, 1.0), t_eval=te, integrator=integrator, rtol=1e-8, atol=1e-10
    )
    _, _, q_ref, _ = angle_reference(te)
    assert traj.status == "success"
    assert np.abs(traj.q - q_ref).max() < 1e-6
    assert np.abs(rod_residuals(traj.q, traj.qd)[0]).max() < 1e-11


# ---------------------------------------------------------------------------------- 6. at(t)
def test_interpolation_between_points(pend: pfaff.NumericModel) -> None:
    traj = pfaff.simulate(pend, Q0, QD0, (0.0, 3.0))
    assert len(traj) > 20
    mid = 0.5 * (traj.t[1:] + traj.t[:-1])
    q, qd = traj.at(mid)
    _, _, q_ref, qd_ref = angle_reference(mid)
    assert q.shape == (len(mid), 2)
    assert np.abs(q - q_ref).max() < 1e-6
    assert np.abs(qd - qd_ref).max() < 1e-5
    f, g = rod_residuals(q, qd)
    assert np.abs(f).max() <= 1e-10 and np.abs(g).max() <= 1e-10
    q1, qd1 = traj(float(mid[3]))  # scalar time, __call__
    assert qd1.shape == (2,)
    assert q1.shape == (2,)
    np.testing.assert_allclose(q1, q_ref[3], atol=1e-6)
    with pytest.raises(pfaff.StateError, match="inside the simulated span"):
        traj.at(3.5)


# ---------------------------------------------------------------------------------- 7. energy
def test_energy_and_jacobi(pend: pfaff.NumericModel) -> None:
    traj = pfaff.simulate(pend, Q0, QD0, (0.0, 20.0))
    _, om, _, _ = angle_reference(traj.t)
    E0 = MASS * G * 0.0  # at rest at height y = 0
    assert traj.energy[0] == pytest.approx(E0, abs=1e-15)
    assert np.abs(traj.energy - E0).max() < 1e-8 * MASS * G * LENGTH
    np.testing.assert_allclose(traj.kinetic, 0.5 * MASS * LENGTH**2 * om**2, atol=1e-6)
    np.testing.assert_allclose(traj.potential, MASS * G * traj.q[:, 1], atol=1e-12)
    np.testing.assert_allclose(traj.jacobi, traj.energy, atol=1e-12)


# ---------------------------------------------------------------------------------- 8. files
@pytest.fixture(scope="module")
def short(pend: pfaff.NumericModel) -> pfaff.Trajectory:
    return pfaff.simulate(pend, Q0, QD0, (0.0, 1.0), t_eval=np.linspace(0.0, 1.0, 11))


HEADER = (
    "t x y x_dot y_dot x_ddot y_ddot lambda1 T V energy jacobi nc_work energy_balance "
    "f_lambda1 g_lambda1"
).split()


def test_to_csv(short: pfaff.Trajectory, tmp_path) -> None:
    path = short.to_csv(tmp_path / "run.csv")
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == HEADER
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (11, len(HEADER))
    col = {name: data[:, j] for j, name in enumerate(HEADER)}
    np.testing.assert_allclose(col["t"], np.linspace(0.0, 1.0, 11), rtol=0, atol=0)
    _, _, q_ref, _ = angle_reference(col["t"])
    np.testing.assert_allclose(col["x"], q_ref[:, 0], atol=1e-8)
    np.testing.assert_allclose(col["y"], q_ref[:, 1], atol=1e-8)
    np.testing.assert_allclose(col["x"] ** 2 + col["y"] ** 2, LENGTH**2, atol=1e-12)
    np.testing.assert_allclose(col["V"], MASS * G * col["y"], atol=1e-12)
    np.testing.assert_allclose(col["lambda1"], short.multipliers[:, 0], rtol=1e-15)  # repr exact


def test_to_netcdf(short: pfaff.Trajectory, tmp_path) -> None:
    xr = pytest.importorskip("xarray")
    path = short.to_netcdf(tmp_path / "run.nc")
    with xr.open_dataset(path) as ds:
        ds = ds.load()
    assert list(ds["coordinate"].values) == ["x", "y"]
    assert list(ds["multiplier"].values) == ["lambda1"]
    np.testing.assert_allclose(ds["time"].values, np.linspace(0.0, 1.0, 11))
    q = ds["q"].values
    np.testing.assert_allclose(q[:, 0] ** 2 + q[:, 1] ** 2, LENGTH**2, atol=1e-12)
    np.testing.assert_allclose(q, short.q, rtol=0, atol=0)
    assert ds["constraint_residual"].shape == (11, 2, 1)
    assert ds.attrs["method"] == "projection" and ds.attrs["status"] == "success"
    assert ds.attrs["parameter_m"] == MASS


@pytest.mark.parametrize("writer", ["to_csv", "to_netcdf"])
def test_write_into_missing_folder(short: pfaff.Trajectory, tmp_path, writer: str) -> None:
    target = tmp_path / "missing" / "run.out"
    with pytest.raises(FileNotFoundError, match="does not exist"):
        getattr(short, writer)(target)
    assert not (tmp_path / "missing").exists()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("writer", ["to_csv", "to_netcdf"])
def test_existing_file_replaced_whole(short: pfaff.Trajectory, tmp_path, writer: str) -> None:
    target = tmp_path / "run.out"
    fresh = tmp_path / "fresh" / "run.out"
    fresh.parent.mkdir()
    getattr(short, writer)(fresh)
    target.write_bytes(b"old content " * 100_000)  # longer than the new file
    getattr(short, writer)(target)
    assert target.read_bytes() == fresh.read_bytes()
    assert b"old content" not in target.read_bytes()
    assert target.stat().st_size == fresh.stat().st_size
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fresh", "run.out"]  # no temp files


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_plot(short: pfaff.Trajectory, tmp_path) -> None:
    pytest.importorskip("pfaff.results.figures")
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    path = tmp_path / "run.png"
    short.plot(path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# ---------------------------------------------------------------------------------- 9. bad input
def test_inconsistent_initial_state(pend: pfaff.NumericModel) -> None:
    """x² + y² - L² = 0.01 at (1, 0.1): refused with the residual; projected on request."""
    with pytest.raises(pfaff.StateError, match=r"off the constraint manifold: max \|f\| = 0\.01"):
        pfaff.simulate(pend, [1.0, 0.1], [0.0, 0.0], (0.0, 1.0))
    with pytest.raises(pfaff.StateError, match=r"max \|A q̇ \+ b\| = 2"):
        pfaff.simulate(pend, [1.0, 0.0], [1.0, 0.0], (0.0, 1.0))  # velocity along the rod
    traj = pfaff.simulate(pend, [1.0, 0.1], [0.0, 0.0], (0.0, 1.0), project_initial=True)
    assert traj.status == "success"
    f, g = rod_residuals(traj.q, traj.qd)
    assert abs(f[0]) < 1e-12 and abs(g[0]) < 1e-12
    angle = math.atan2(1.0, 0.1)  # the nearest point of the circle (equal masses: Euclidean)
    np.testing.assert_allclose(traj.q[0], [math.sin(angle), math.cos(angle)], atol=1e-12)


@pytest.mark.parametrize(
    ("q0", "qd0", "match"),
    [
        ([math.nan, 0.0], [0.0, 0.0], "NaN or infinity"),
        ([1.0, 0.0], [math.inf, 0.0], "NaN or infinity"),
        ([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], r"shape \(2,\)"),
        ([[1.0, 0.0]], [0.0, 0.0], r"shape \(2,\)"),
    ],
)
def test_bad_state(pend: pfaff.NumericModel, q0, qd0, match: str) -> None:
    with pytest.raises(pfaff.StateError, match=match):
        pfaff.simulate(pend, q0, qd0, (0.0, 1.0))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"t_span": (1.0, 0.0)}, "reversed"),
        ({"t_span": (1.0, 1.0)}, "empty"),
        ({"t_span": (0.0, math.inf)}, "finite"),
        ({"t_span": (0.0,)}, "two numbers"),
        ({"t_eval": [0.0, 0.5, 2.0]}, "inside t_span"),
        ({"t_eval": [-0.1, 0.5]}, "inside t_span"),
        ({"t_eval": [0.0, 0.5, 0.5]}, "strictly increasing"),
        ({"t_eval": [0.5, 0.2]}, "strictly increasing"),
        ({"t_eval": []}, "non-empty"),
        ({"method": "euler"}, "unknown method 'euler'"),
        ({"integrator": "LSODA"}, "`integrator` must be one of DOP853, RK45, RK23"),
        ({"rtol": -1.0}, "rtol"),
        ({"atol": 0.0}, "positive"),
    ],
)
def test_bad_options(pend: pfaff.NumericModel, kwargs: dict, match: str) -> None:
    kw = {"t_span": (0.0, 1.0), **kwargs}
    with pytest.raises(pfaff.OptionError, match=match) as info:
        pfaff.simulate(pend, Q0, QD0, **kw)
    assert not isinstance(info.value, pfaff.StateError)  # one meaning per error class


def _particle(force: sp.Expr) -> pfaff.NumericModel:
    """One coordinate x, T = ½ẋ², a generalized force Q(x): ẍ = Q(x)."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x], name="pushed particle")
    s.add_kinetic_energy(x.diff(pfaff.t) ** 2 / 2)
    s.add_generalized_force(x, force(x))
    return s.equations().compile({})


def _failure_time(message: str) -> float:
    return float(re.search(r"failed at t = ([0-9.eE+-]+)", message).group(1))


def test_singular_force_fails_with_time() -> None:
    """ẍ = 1/(1 - x) from rest: ½ẋ² = -ln(1 - x), x = 1 at t* = ∫₀^∞ e^(-u)/√(2u) du = √(π/2)."""
    model = _particle(lambda x: 1 / (1 - x))
    traj = pfaff.simulate(model, [0.0], [0.0], (0.0, 3.0))
    assert traj.status == "failed" and not traj.success
    assert _failure_time(traj.message) == pytest.approx(math.sqrt(math.pi / 2), abs=1e-6)
    assert traj.t[-1] == pytest.approx(math.sqrt(math.pi / 2), abs=1e-6)
    assert len(traj) > 10
    x, xd = traj.q[:, 0], traj.qd[:, 0]  # energy, away from the singularity
    x, xd = x[x < 0.999], xd[x < 0.999]
    assert len(x) > 10
    np.testing.assert_allclose(0.5 * xd**2, -np.log1p(-x), rtol=1e-6, atol=1e-12)
    with pytest.raises(pfaff.SimulationError, match=r"failed at t = 1\.25331"):
        pfaff.simulate(model, [0.0], [0.0], (0.0, 3.0), throw=True)


def _sqrt_crossing_time() -> float:
    """ẍ = √(1 - x), x(0) = 0, ẋ(0) = 1: ẋ² = 1 + (4/3)(1 - (1 - x)^(3/2)); time to reach x = 1."""
    from scipy.integrate import quad

    return quad(lambda x: 1 / math.sqrt(1 + 4 / 3 * (1 - (1 - x) ** 1.5)), 0.0, 1.0)[0]


def test_non_finite_force_fails_with_time() -> None:
    """Q = √(1 - x) turns non-real once x > 1: a failed status naming the time, not a crash."""
    model = _particle(lambda x: sp.sqrt(1 - x))
    t_cross = _sqrt_crossing_time()
    traj = pfaff.simulate(model, [0.0], [1.0], (0.0, 3.0))
    assert traj.status == "failed"
    assert t_cross - 0.05 < _failure_time(traj.message) <= t_cross + 1e-9
    with pytest.raises(pfaff.SimulationError, match="failed at t = "):
        pfaff.simulate(model, [0.0], [1.0], (0.0, 3.0), throw=True)


# ---------------------------------------------------------------------------------- 10. states
def _consistent_state():
    if not hasattr(pfaff, "consistent_state"):
        pytest.skip("pfaff.consistent_state not implemented yet")
    return pfaff.consistent_state


@pytest.mark.parametrize("independent", [["x"], [0]])
def test_consistent_state_pendulum(pend: pfaff.NumericModel, independent) -> None:
    """x = 0.6, ẋ = 0.8 with y below the pivot: y = -0.8, ẏ = -xẋ/y = 0.6."""
    cs = _consistent_state()
    q, qd = cs(pend, [0.6, -1.0], [0.8, 0.0], independent)
    np.testing.assert_allclose(q, [0.6, -0.8], atol=1e-12)
    np.testing.assert_allclose(qd, [0.8, 0.6], atol=1e-12)
    traj = pfaff.simulate(pend, q, qd, (0.0, 0.5))  # accepted as consistent
    assert traj.status == "success"


def test_consistent_state_ring(ring: pfaff.NumericModel) -> None:
    cs = _consistent_state()
    r = RING["r"]
    q, qd = cs(ring, [0.3, 0, 0, 0, 0], [0.25, 0, 0, 0, 0], ["x"])
    q_ref, qd_ref = pfaff.models.ring_state(4, radius=r, theta=0.3 / r, theta_dot=0.25 / r)
    np.testing.assert_allclose(q, q_ref, atol=1e-12)
    np.testing.assert_allclose(qd, qd_ref, atol=1e-12)


def test_consistent_state_impossible(pend: pfaff.NumericModel) -> None:
    cs = _consistent_state()
    with pytest.raises(pfaff.ConstraintError, match="no consistent state"):
        cs(pend, [2.0, -1.0], [0.0, 0.0], ["x"])  # |x| > L


def test_consistent_state_stops_when_the_residual_stops_falling(
    pend: pfaff.NumericModel, monkeypatch
) -> None:
    """No solution and a huge iteration budget: the projection's policy stops at the first
    step that does not reduce the residual (a handful of Newton steps), then refuses."""
    import pfaff.integrate.initial as initial

    calls = {"n": 0}
    real = initial.newton_projection

    def counting(linearize, *args, **kw):
        def counted(q, qd):
            calls["n"] += 1
            return linearize(q, qd)

        return real(counted, *args, **kw)

    monkeypatch.setattr(initial, "newton_projection", counting)
    with pytest.raises(pfaff.ConstraintError, match="no consistent state"):
        _consistent_state()(pend, [2.0, -1.0], [0.0, 0.0], ["x"], max_iter=10**9)
    assert calls["n"] < 100


# ---------------------------------------------------------------------------------- 11. stats
@pytest.mark.parametrize("method", ALL_METHODS)
def test_stats(pend: pfaff.NumericModel, method: str) -> None:
    traj = pfaff.simulate(pend, Q0, QD0, (0.0, 2.0), method=method)
    assert traj.status == "success" and traj.success
    assert traj.message
    assert traj.stats["steps"] > 0 and traj.stats["nfev"] > traj.stats["steps"]
    if method == "projection":
        assert traj.stats["projections"] > 0
        assert len(traj) == traj.stats["steps"] + 1  # every step reported, and t0
    assert traj.t[0] == 0.0 and traj.t[-1] == 2.0
    assert traj.method == method


# ---------------------------------------------------------------------------------- 12. Ctrl-C
def test_keyboard_interrupt_keeps_points(pend: pfaff.NumericModel, monkeypatch) -> None:
    original = type(pend).ode_function  # (models are immutable: the class is patched)

    class Interrupted(OdeFunction):  # the array path: FloatDOP853 is not used without on_lists
        def __init__(self, fun: OdeFunction) -> None:
            self.fun, self.calls = fun, itertools.count()

        def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
            if next(self.calls) >= 600:
                raise KeyboardInterrupt
            return self.fun(t, y)

    monkeypatch.setattr(
        type(pend), "ode_function", lambda self, *a, **kw: Interrupted(original(self, *a, **kw))
    )
    traj = pfaff.simulate(pend, Q0, QD0, (0.0, 100.0))
    assert traj.status == "interrupted" and not traj.success
    assert "interrupted" in traj.message
    assert 1 < len(traj) and traj.t[-1] < 100.0
    _, _, q_ref, _ = angle_reference(traj.t)
    assert np.abs(traj.q - q_ref).max() < 1e-7  # the points kept are right


def test_keyboard_interrupt_ida(pend: pfaff.NumericModel, monkeypatch) -> None:
    original, calls = type(pend).dae_blocks, itertools.count()

    def blocks(*args):
        if next(calls) >= 400:
            raise KeyboardInterrupt
        return original(*args)

    monkeypatch.setattr(type(pend), "dae_blocks", blocks)
    traj = pfaff.simulate(pend, Q0, QD0, (0.0, 100.0), method="ida")
    assert traj.status == "interrupted"
    assert 1 < len(traj) and traj.t[-1] < 100.0
