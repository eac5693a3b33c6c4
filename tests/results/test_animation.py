"""Animations: the model's geometry against hand-computed positions, GIFs of a pendulum, a double
pendulum, the ring (a family model) and a torque-free body, frame counts, bounded memory, and bad
paths refused before any work."""

from __future__ import annotations

import pickle
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from PIL import Image

import pfaff
from pfaff.attitude import dcm_from
from pfaff.cli.main import main
from pfaff.derive.geometry import MAX_POINTS, build_geometry
from pfaff.errors import OptionError, ParameterError, StateError
from pfaff.results import animation
from pfaff.results.animation import sample_frames
from pfaff.results.trajectory import Trajectory

SMALL = {"frames": 4, "dpi": 30, "size": 3.0}  # 90 × 90 pixels: fast


def double_pendulum() -> pfaff.System:
    """Two point masses on rods in absolute angles (the file format's example, without damper)."""
    th1, th2 = pfaff.coordinates("theta1 theta2")
    m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g")
    s = pfaff.System([th1, th2], name="double pendulum")
    p1 = [l1 * sp.sin(th1), -l1 * sp.cos(th1)]
    p2 = [p1[0] + l2 * sp.sin(th2), p1[1] - l2 * sp.cos(th2)]
    s.add_particle(m1, p1, name="upper")
    s.add_particle(m2, p2, name="lower")
    s.add_potential_energy(g * (m1 * p1[1] + m2 * p2[1]))
    return s


DOUBLE = {"m1": 1.0, "m2": 2.0, "l1": 1.0, "l2": 0.5, "g": 9.81}
RING = {"M": 1.0, "r": 0.5, "F": 2.0}


@pytest.fixture(scope="module")
def pendulum_model():
    return pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})


@pytest.fixture(scope="module")
def pendulum_run(pendulum_model) -> Trajectory:
    t_eval = np.linspace(0.0, 1.0, 5)
    return pfaff.simulate(pendulum_model, [1.0], [0.0], (0.0, 1.0), t_eval=t_eval)


@pytest.fixture(scope="module")
def double_model():
    return double_pendulum().equations().compile(DOUBLE)


@pytest.fixture(scope="module")
def ring_model():
    return pfaff.models.rolling_ring(64, force=True, family=True).equations().compile(RING)


@pytest.fixture(scope="module")
def body():
    system = pfaff.models.torque_free_body("mrp")
    return system, system.equations().compile({"I1": 1, "I2": 2, "I3": 3})


def frame_count(path: Path) -> int:
    with Image.open(path) as im:
        return im.n_frames


# ---------------------------------------------------------------------------- geometry
def test_pendulum_geometry_is_the_bob_on_its_rod(pendulum_model):
    geo = pendulum_model.geometry
    theta = np.array([[0.0], [np.pi / 2], [1.0]])
    expected = np.stack([2 * np.sin(theta[:, 0]), -2 * np.cos(theta[:, 0])], axis=-1)
    assert geo.dim == 2 and geo.names == ["bob"]
    np.testing.assert_allclose(geo.points(theta)[:, 0], expected, atol=1e-15)
    assert geo.links == [(-1, 0)]  # the rod: its length is built into the position


def test_double_pendulum_geometry_and_chain_links(double_model):
    geo = double_model.geometry
    rng = np.random.default_rng(1)
    q = rng.uniform(-3, 3, (7, 2))
    p1 = np.stack([np.sin(q[:, 0]), -np.cos(q[:, 0])], axis=-1)
    p2 = p1 + 0.5 * np.stack([np.sin(q[:, 1]), -np.cos(q[:, 1])], axis=-1)
    np.testing.assert_allclose(geo.points(q), np.stack([p1, p2], axis=1), atol=1e-14)
    assert geo.links == [(-1, 0), (0, 1)]  # origin -> upper -> lower; not origin -> lower


def test_links_from_a_rod_constraint_and_a_chain_on_a_cart():
    cart = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    assert cart.geometry.links == [(-1, 0)]  # x² + y² − L² = 0 links the bob to the pivot
    values = {"F": 0, "g": 9.81, "l0": 1, "l1": 1, "m0": 1, "m1": 1, "m2": 1}
    chain = pfaff.models.n_link_pendulum_on_cart(2).equations().compile(values)
    assert chain.geometry.names == ["cart", "bob1", "bob2"]
    assert chain.geometry.links == [(0, 1), (1, 2)]  # the cart moves: no link to the origin


def test_ring_geometry_is_its_particles_and_centre(ring_model):
    geo = ring_model.geometry
    q, _ = pfaff.models.ring_state(64, 0.5, theta=0.3)
    pts = geo.points(q)
    theta = q[1:]
    expected = np.stack([q[0] + 0.5 * np.sin(theta), 0.5 * np.cos(theta)], axis=-1)
    assert geo.families == [("particle", 0, 64)] and geo.kinds[-1] == "force"
    np.testing.assert_allclose(pts[:64], expected, atol=1e-15)
    np.testing.assert_allclose(pts[64], [q[0], 0.0])  # the push acts at the centre
    np.testing.assert_allclose(pts[:64].mean(axis=0), [q[0], 0.0], atol=1e-15)
    assert geo.links == []  # a family is drawn as points, centre and spoke


def test_large_family_is_subsampled():
    n = 1_000_000
    eom = pfaff.models.rolling_ring(n, force=True).equations()
    geo = build_geometry(eom, [2.0, 1.0, 0.5])  # F, M, r
    assert len(geo.names) <= MAX_POINTS + 1 and len(geo.columns) <= MAX_POINTS + 1
    q, _ = pfaff.models.ring_state(n, 0.5, theta=0.1)
    pts = geo.points(q)
    ks = [int(name.split()[-1]) for name in geo.names[:-1]]  # particle k is theta_k
    expected = np.stack([q[0] + 0.5 * np.sin(q[ks]), 0.5 * np.cos(q[ks])], axis=-1)
    np.testing.assert_allclose(pts[:-1], expected, atol=1e-14)
    assert ks[0] == 1 and ks[-1] > n - n // MAX_POINTS - 1  # spread over the whole ring
    only = q[geo.columns]  # the columns the geometry reads are enough
    np.testing.assert_array_equal(geo.points(only), pts)


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_body_geometry_is_its_dcm(body):
    system, model = body
    att = system.bodies[0].attitude
    rng = np.random.default_rng(2)
    q = rng.uniform(-0.8, 0.8, (5, 3))
    centres, dcm = model.geometry.bodies(q)
    assert centres.shape == (5, 1, 3) and not centres.any()
    for k in range(5):
        np.testing.assert_allclose(dcm[k, 0], dcm_from(att, q[k]), atol=1e-14)


def test_geometry_pickles_and_takes_new_parameters(pendulum_model):
    geo = pendulum_model.geometry
    again = pickle.loads(pickle.dumps(geo))
    np.testing.assert_array_equal(again.points([0.4]), geo.points([0.4]))
    longer = geo.with_parameters({"L": 3.0})
    np.testing.assert_allclose(longer.points([0.0]), [[0.0, -3.0]], atol=1e-15)
    assert geo.parameters["L"] == 2.0  # unchanged
    with pytest.raises(ParameterError, match="unknown parameter `l`"):
        geo.with_parameters({"l": 3.0})
    with pytest.raises(StateError, match="must have 1 coordinates"):
        geo.points([0.0, 1.0])


def test_no_geometry_without_particles_or_bodies():
    minimal = pfaff.models.rolling_ring_minimal(force=True).equations().compile(RING)
    traj = pfaff.simulate(minimal, [0.0], [0.0], (0.0, 0.1))
    assert minimal.geometry is None and traj.geometry is None
    with pytest.raises(StateError, match="no geometry"):
        traj.animate("never.gif")


# ---------------------------------------------------------------------------- frames
def test_frames_show_the_geometry_at_the_sampled_times(pendulum_run):
    f = sample_frames(pendulum_run, 5)  # the run reported exactly these times
    np.testing.assert_array_equal(f.t, pendulum_run.t)
    theta = pendulum_run.q[:, 0]
    expected = np.stack([2 * np.sin(theta), -2 * np.cos(theta)], axis=-1)
    np.testing.assert_allclose(f.points[:, 0], expected, atol=1e-14)


def test_frames_between_reports_are_interpolated(pendulum_model):
    run = pfaff.simulate(pendulum_model, [1.0], [0.0], (0.0, 1.0), rtol=1e-12, atol=1e-12)
    f = sample_frames(run, 7)
    q, _ = run.at(f.t)
    np.testing.assert_allclose(f.points, pendulum_model.geometry.points(q), atol=1e-7)


@pytest.mark.slow  # (its body's run takes over a second: the full suite runs it)
def test_frames_across_mrp_switches_follow_the_motion(body):
    system, model = body
    att = system.bodies[0].attitude
    q0 = att.from_dcm(np.eye(3))
    qd0 = att.rates(q0, [0.01, 1.0, 0.0])  # near the intermediate axis: it flips
    run = pfaff.simulate(model, q0, qd0, (0.0, 8.0))
    assert run.switches  # |σ| passed 1: the coordinates jump to the shadow set
    f = sample_frames(run, 60)
    ref = pfaff.simulate(model, q0, qd0, (0.0, 8.0), t_eval=f.t)
    _, dcm = model.geometry.bodies(ref.q, ref.t)
    np.testing.assert_allclose(f.dcm, dcm, atol=1e-2)


def test_scene_draws_the_sampled_positions(double_model):
    run = pfaff.simulate(double_model, [1.0, 0.5], [0.0, 0.0], (0.0, 0.5))
    data = sample_frames(run, 3)
    geo = double_model.geometry
    scene = animation._Scene(geo, data, geo.links, 2.0, 30, "test", blit=True)
    try:
        for i in range(3):
            scene.update(i)
            (ix, artist), *_ = scene.markers
            np.testing.assert_array_equal(np.column_stack(artist.get_data()), data.points[i][ix])
            segs = np.array(scene.lines.get_segments())  # origin -> upper, upper -> lower
            np.testing.assert_allclose(segs[0], [[0.0, 0.0], data.points[i][0]])
            np.testing.assert_allclose(segs[1], data.points[i][:2])
            assert f"t = {data.t[i]:.2f}" in scene.label.get_text()
    finally:
        scene.fig.clear()


# ---------------------------------------------------------------------------- files
def test_gif_of_a_pendulum(pendulum_run, tmp_path):
    out = pendulum_run.animate(tmp_path / "pendulum.gif", **SMALL)
    assert out == tmp_path / "pendulum.gif" and frame_count(out) == 4
    with Image.open(out) as im:
        assert im.size == (90, 90)
    assert [p.name for p in tmp_path.iterdir()] == ["pendulum.gif"]  # no temporary left


def test_gif_of_a_double_pendulum(double_model, tmp_path):
    run = pfaff.simulate(double_model, [1.0, 0.5], [0.0, 0.0], (0.0, 1.0))
    assert frame_count(run.animate(tmp_path / "double.GIF", **SMALL)) == 4


def test_gif_of_the_ring(ring_model, tmp_path):
    q0, qd0 = pfaff.models.ring_state(64, 0.5, theta_dot=1.0)
    run = pfaff.simulate(ring_model, q0, qd0, (0.0, 1.0))
    assert frame_count(run.animate(tmp_path / "ring.gif", **SMALL)) == 4


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_gif_of_a_torque_free_body(body, tmp_path):
    system, model = body
    att = system.bodies[0].attitude
    q0 = att.from_dcm(np.eye(3))
    run = pfaff.simulate(model, q0, att.rates(q0, [0.01, 1.0, 0.0]), (0.0, 2.0))
    out = run.animate(tmp_path / "tumble.gif", **{**SMALL, "frames": 5})
    assert frame_count(out) == 5


def test_frames_are_capped_and_a_short_run_is_interpolated(pendulum_model, tmp_path):
    run = pfaff.simulate(pendulum_model, [1.0], [0.0], (0.0, 1.0), t_eval=[0.0, 0.5, 1.0])
    out = run.animate(tmp_path / "short.gif", frames=6, dpi=30, size=3.0)
    assert frame_count(out) == 6  # more frames than reported states: interpolated
    one = Trajectory(**{**_fields(run), "t": run.t[:1], "q": run.q[:1]})
    assert frame_count(one.animate(tmp_path / "one.gif", frames=6, dpi=30, size=3.0)) == 1


def _fields(run: Trajectory) -> dict:
    keys = ("t", "q", "qd", "qdd", "multipliers", "kinetic", "potential", "jacobi")
    keys += ("constraint_residual", "stats", "status", "message", "method")
    keys += ("coordinate_names", "multiplier_names", "geometry")
    return {k: getattr(run, k) for k in keys}


def test_memory_is_bounded_by_frames_not_by_the_run(pendulum_model, tmp_path):
    k = 2_000_000  # reported states: 16 MB per array
    t = np.linspace(0.0, 1000.0, k)
    theta = np.sin(t)[:, None]
    long_run = Trajectory(
        t=t,
        q=theta,
        qd=np.cos(t)[:, None],
        qdd=-theta,
        multipliers=np.zeros((k, 0)),
        kinetic=np.zeros(k),
        potential=np.zeros(k),
        jacobi=np.zeros(k),
        constraint_residual=np.zeros((k, 2, 0)),
        stats={},
        status="success",
        message="",
        method="projection",
        coordinate_names=["theta"],
        multiplier_names=[],
        geometry=pendulum_model.geometry,
    )
    long_run.animate(tmp_path / "warm.gif", **SMALL)  # fonts and caches loaded once
    tracemalloc.start()
    try:
        out = long_run.animate(tmp_path / "long.gif", **SMALL)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert frame_count(out) == 4
    assert peak < 8e6, f"peak {peak / 1e6:.1f} MB: something scales with the run's length"


# ---------------------------------------------------------------------------- refusals
@pytest.mark.parametrize(
    ("name", "options", "match"),
    [
        ("run.avi", {}, r"must end in \.gif or \.mp4"),
        ("no/such/folder/run.gif", {}, "does not exist"),
        ("run.gif", {"frames": 0}, "between 1 and"),
        ("run.gif", {"frames": 2.5}, "whole number"),
        ("run.gif", {"frames": True}, "whole number"),
        ("run.gif", {"fps": -1}, "`fps` must be positive"),
        ("run.gif", {"links": [(0, 7)]}, "not a point"),
        ("run.gif", {"links": "origin"}, "pairs"),
    ],
)
def test_bad_options_refused_before_any_work(
    pendulum_run, tmp_path, monkeypatch, name, options, match
):
    def no_work(*args, **kwargs):
        raise AssertionError("frames were sampled before the options were checked")

    monkeypatch.setattr(animation, "sample_frames", no_work)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(OptionError, match=match):
        pendulum_run.animate(name, **options)
    assert list(tmp_path.iterdir()) == []


def test_a_folder_is_not_a_file(pendulum_run, tmp_path):
    (tmp_path / "x.gif").mkdir()
    with pytest.raises(OptionError, match="it is a folder"):
        pendulum_run.animate(tmp_path / "x.gif")


def test_mp4_needs_ffmpeg(pendulum_run, tmp_path, monkeypatch):
    monkeypatch.setattr(animation, "ffmpeg_available", lambda: False)
    with pytest.raises(OptionError, match="needs ffmpeg"):
        pendulum_run.animate(tmp_path / "run.mp4")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not animation.ffmpeg_available(), reason="no ffmpeg on this machine")
def test_mp4_where_ffmpeg_exists(pendulum_run, tmp_path):
    out = pendulum_run.animate(tmp_path / "run.mp4", frames=4, dpi=40, size=4.0)
    assert out.stat().st_size > 0


def test_a_failure_leaves_an_existing_file_untouched(pendulum_run, tmp_path, monkeypatch):
    target = tmp_path / "keep.gif"
    target.write_bytes(b"old")

    def broken(self, i):
        raise RuntimeError("drawing failed")

    monkeypatch.setattr(animation._Scene, "update", broken)
    with pytest.raises(RuntimeError, match="drawing failed"):
        pendulum_run.animate(target, **SMALL)
    assert target.read_bytes() == b"old" and list(tmp_path.iterdir()) == [target]


def test_explicit_links(double_model, tmp_path):
    run = pfaff.simulate(double_model, [1.0, 0.5], [0.0, 0.0], (0.0, 0.2))
    out = run.animate(tmp_path / "links.gif", links=[("origin", "lower"), (0, 1)], **SMALL)
    assert frame_count(out) == 4
    assert frame_count(run.animate(tmp_path / "none.gif", links=[], **SMALL)) == 4


# ---------------------------------------------------------------------------- command line
def test_cli_ring_animation_implies_simulate(tmp_path, capsys):
    out = tmp_path / "ring.gif"
    argv = ["demo", "ring", "--particles", "4", "--t-end", "0.5"]
    code = main([*argv, "--animate", str(out), "--frames", "3"])
    assert code == 0, capsys.readouterr().err
    assert frame_count(out) == 3 and f"Wrote {out}" in capsys.readouterr().out


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_cli_tumble_animation(tmp_path, capsys):
    out = tmp_path / "tumble.gif"
    code = main(["demo", "tumble", "--t-end", "1", "--animate", str(out), "--frames", "2"])
    assert code == 0, capsys.readouterr().err
    assert frame_count(out) == 2


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["demo", "ring", "--animate", "ring.avi"], "--animate"),
        (["demo", "tumble", "--animate", "ring.mp4"], "ffmpeg"),
    ],
)
def test_cli_refuses_a_bad_animation_file_first(tmp_path, capsys, monkeypatch, argv, match):
    monkeypatch.setattr(animation, "ffmpeg_available", lambda: False)
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert match in capsys.readouterr().err and list(tmp_path.iterdir()) == []


def test_cli_frames_must_be_positive(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "ring", "--animate", "x.gif", "--frames", "0"])
    assert "--frames" in capsys.readouterr().err
