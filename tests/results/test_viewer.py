"""The 3-D viewer and the drawn solids: the solids' semi-axes against the closed forms of uniform
ellipsoids and boxes, the page's scene against positions and attitudes computed independently
(the pendulum's closed-form bob, the body's direction cosines from a separate run), no network
reference in the page, file sizes, and a headless browser's screenshot where one is installed."""

from __future__ import annotations

import base64
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.errors import ModelError, OptionError, StateError
from pfaff.results import animation
from pfaff.results.animation import sample_frames
from pfaff.results.solids import semi_axes, solids_of
from pfaff.results.viewer import Viewer, render

#: what a page must never contain: any way to load another file or reach a network address
NETWORK = re.compile(
    r"<script[^>]*\bsrc\s*=|<link\b|<img\b|<iframe\b|\bhref\s*=|\bsrc\s*=|\bimport\s*\(|"
    r"\bimport\s+[\w{*]|\bfetch\s*\(|XMLHttpRequest|WebSocket|EventSource|sendBeacon|"
    r"https?://|url\s*\(|@import",
    re.IGNORECASE,
)


def scene_of(page: str) -> dict:
    block = re.search(r'<script id="pfaff-data" type="application/json">(.*?)</script>', page, re.S)
    assert block is not None
    return json.loads(block.group(1))


def floats(b64: str, dtype: type = np.float32) -> np.ndarray:
    return np.frombuffer(base64.b64decode(b64), dtype=dtype)


def rotation(q: np.ndarray) -> np.ndarray:
    """Rotation matrices of unit quaternions (w, x, y, z), shape (..., 4) -> (..., 3, 3)."""
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


@pytest.fixture(scope="module")
def pendulum_run():
    model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    run = pfaff.simulate(model, [1.0], [0.0], (0.0, 2.0))
    run.source_model = model  # for the reference run of the test below
    return run


@pytest.fixture(scope="module")
def body_run():
    system = pfaff.models.torque_free_body("quaternion")
    model = system.equations().compile({"I1": 1.0, "I2": 2.0, "I3": 2.5})
    att = system.bodies[0].attitude
    q0 = att.from_dcm(np.eye(3))
    qd0 = att.rates(q0, [0.01, 2.0, 0.05])  # near the intermediate axis: it tumbles
    return model, pfaff.simulate(model, q0, qd0, (0.0, 6.0)), (q0, qd0)


@pytest.fixture(scope="module")
def ring_run():
    n = 1024
    model = pfaff.models.rolling_ring(n, force=True, family=True).equations()
    model = model.compile({"M": 1.0, "r": 0.5, "F": 2.0})
    q, qd = pfaff.models.ring_state(n, 0.5, 0.0)
    return pfaff.simulate(model, q, qd, (0.0, 2.0))


# ---------------------------------------------------------------------------- solids
@pytest.mark.parametrize("solid, c", [("ellipsoid", 5.0), ("box", 3.0)])
def test_semi_axes_give_back_the_inertia_of_the_uniform_solid(solid, c):
    """I = m (b² + c²)/5 … (ellipsoid), m (b² + c²)/3 … (box), turned by any rotation."""
    from scipy.spatial.transform import Rotation

    m, half = 2.5, np.array([0.3, 1.2, 0.7])
    moments = m * ((half**2).sum() - half**2) / c
    R = Rotation.from_euler("zyx", [0.3, -1.1, 2.0]).as_matrix()
    got, axes = semi_axes(m, R @ np.diag(moments) @ R.T, solid)
    world = R.T @ axes  # each found axis is one of the body's principal axes
    order = np.argmax(np.abs(world), axis=0)
    np.testing.assert_allclose(np.abs(world[order, range(3)]), 1.0, atol=1e-9)
    np.testing.assert_allclose(got, half[order], rtol=1e-12)
    assert np.linalg.det(axes) == pytest.approx(1.0)


def test_a_thin_rod_is_a_box_of_its_length():
    """A rod of length L: I = m L²/12 across it, 0 along it → half-length L/2 (box)."""
    m, L = 0.7, 1.8
    half, axes = semi_axes(m, np.diag([m * L**2 / 12, 0.0, m * L**2 / 12]), "box")
    long = int(np.argmax(half))
    assert half[long] == pytest.approx(L / 2, rel=1e-12)
    np.testing.assert_allclose(np.abs(axes[:, long]), [0, 1, 0], atol=1e-12)
    assert sorted(half)[0] == pytest.approx(0.06 * L / 2)  # raised to THIN of the largest


def test_no_mass_means_no_size():
    half, _ = semi_axes(0.0, np.eye(3))
    assert np.isnan(half).all()


# ---------------------------------------------------------------------------- the page's scene
def test_pendulum_scene_holds_the_bob_where_the_closed_form_puts_it(pendulum_run):
    page = render(pendulum_run, fps=20)
    s = scene_of(page)
    t = floats(s["t"], np.float64)
    assert s["nframes"] == len(t) == 41 and t[0] == 0.0 and t[-1] == pytest.approx(2.0)
    pts = floats(s["points"]).reshape(len(t), 1, 2)
    ref = pfaff.simulate(pendulum_run.source_model, [1.0], [0.0], (0.0, 2.0), t_eval=t, rtol=1e-10)
    th = ref.q[:, 0]
    np.testing.assert_allclose(pts[:, 0, 0], 2 * np.sin(th), atol=2e-5)
    np.testing.assert_allclose(pts[:, 0, 1], -2 * np.cos(th), atol=2e-5)
    assert s["links"] == [[-1, 0]]  # the rod to the pivot


def test_body_scene_turns_as_the_direction_cosines(body_run):
    model, run, (q0, qd0) = body_run
    s = scene_of(render(run, fps=10))
    t = floats(s["t"], np.float64)
    quats = floats(s["quaternions"]).reshape(len(t), 1, 4)
    ref = pfaff.simulate(model, q0, qd0, (0.0, 6.0), t_eval=t, rtol=1e-10)
    _, dcm = model.geometry.bodies(ref.q, ref.t)
    solids = solids_of(model.geometry, "ellipsoid")
    expect = dcm @ solids.axes  # the solid's principal axes in inertial components
    np.testing.assert_allclose(rotation(quats.astype(float)), expect, atol=2e-5)
    # semi-axes of the unit-mass ellipsoid of I = (1, 2, 2.5): a_i² = 5/2 (I_j + I_k − I_i)
    moments = np.array([1.0, 2.0, 2.5])
    half = np.sqrt(2.5 * (moments.sum() - 2 * moments))
    np.testing.assert_allclose(sorted(s["half"][0]), sorted(half), rtol=1e-5)


@pytest.mark.parametrize("which", ["pendulum", "body", "ring"])
def test_pages_reach_for_nothing(which, pendulum_run, body_run, ring_run, tmp_path):
    run = {"pendulum": pendulum_run, "body": body_run[1], "ring": ring_run}[which]
    path = run.to_html(tmp_path / f"{which}.html")
    page = path.read_text(encoding="utf-8")
    assert NETWORK.search(page) is None, NETWORK.search(page)
    assert page.count("<script") == 2  # the data block and the inlined renderer
    assert path.stat().st_size < 4.5e6


def test_ring_of_1024_keeps_its_frames_under_the_data_budget(ring_run):
    s = scene_of(render(ring_run))
    assert s["npoints"] >= 1024
    data = sum(len(base64.b64decode(s[k])) for k in ("t", "points", "centres", "quaternions"))
    assert data <= 3_000_000
    assert s["nframes"] == 61  # 2 s at 30 frames per second fit the budget


def test_arrows_carry_the_rod_force_at_the_frames():
    """The Cartesian pendulum's rod force Aᵀλ = 2λ (x, y) on the bob: the page's arrows hold it
    at each frame (interpolated from the reported states) against a run reported at those times."""
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    run = pfaff.simulate(model, [2.0, 0.0], [0.0, 0.0], (0.0, 1.0), t_eval=np.linspace(0, 1, 2001))

    def rod(t, q, qd, lam):
        return q, 2 * lam[0] * q

    s = scene_of(render(run, fps=20, arrows={"rod": rod}))
    t = floats(s["t"], np.float64)
    arrows = floats(s["arrows"]).reshape(len(t), 1, 6)
    ref = pfaff.simulate(model, [2.0, 0.0], [0.0, 0.0], (0.0, 1.0), t_eval=t)
    force = 2 * ref.multipliers[:, :1] * ref.q
    np.testing.assert_allclose(arrows[:, 0, :2], ref.q, atol=1e-5)
    np.testing.assert_allclose(arrows[:, 0, 3:5], force, atol=1e-4 * np.abs(force).max())
    # |force| = tension; the largest arrow is a quarter of the scene
    top = np.linalg.norm(arrows[:, 0, 3:], axis=1).max()
    assert s["arrow_scale"] * top == pytest.approx(0.25 * s["extent"], rel=1e-6)
    with pytest.raises(OptionError, match="arrows"):
        render(run, arrows={"bad": lambda *a: 1.0})


def test_names_cannot_break_out_of_the_page(pendulum_run):
    page = render(pendulum_run, title="</script><script>alert(1)</script>")
    assert page.count("<script") == 2
    assert scene_of(page)["title"] == "</script><script>alert(1)</script>"


def test_show_is_the_page_in_a_sandboxed_frame(pendulum_run, tmp_path):
    viewer = pendulum_run.show(height=300)
    assert isinstance(viewer, Viewer)
    frame = viewer._repr_html_()
    assert frame.startswith('<iframe srcdoc="') and 'sandbox="allow-scripts"' in frame
    assert "height: 300px" in frame and "<script" not in frame  # escaped inside srcdoc
    saved = viewer.save(tmp_path / "v.html")
    assert saved.read_text(encoding="utf-8") == viewer.html


def test_bad_options_are_refused(pendulum_run, tmp_path):
    with pytest.raises(OptionError, match=r"must end in \.html"):
        pendulum_run.to_html(tmp_path / "v.gif")
    with pytest.raises(OptionError, match="`up`"):
        pendulum_run.to_html(tmp_path / "v.html", up="down")
    with pytest.raises(OptionError, match="`solid`"):
        pendulum_run.to_html(tmp_path / "v.html", solid="cone")
    with pytest.raises(OptionError, match="`fps`"):
        pendulum_run.to_html(tmp_path / "v.html", fps=-1)
    with pytest.raises(OptionError, match="does not exist"):
        pendulum_run.to_html(tmp_path / "missing" / "v.html")
    assert not list(tmp_path.iterdir())


def test_a_model_without_geometry_is_refused(tmp_path):
    """Energies alone place nothing in space: there is nothing to draw."""
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_kinetic_energy(x.diff(pfaff.t) ** 2 / 2)
    run = pfaff.simulate(s.equations().compile({}), [0.0], [1.0], (0.0, 1.0))
    with pytest.raises(StateError, match="no geometry"):
        run.to_html(tmp_path / "v.html")


# ---------------------------------------------------------------------------- add_shape
def test_shapes_are_drawn_and_change_nothing_else():
    plain = pfaff.models.pendulum()
    shaped = pfaff.models.pendulum()
    th = pfaff.coordinates("theta")
    shaped.add_shape([2 * sp.sin(th), -2 * sp.cos(th), 0], sp.eye(3), size=[0.3, 0.2, 0.1])
    values = {"m": 1, "g": 9.81, "L": 2}
    a, b = (s.equations().compile(values) for s in (plain, shaped))
    state = (0.0, [0.7], [0.3])
    np.testing.assert_array_equal(a.accelerations(*state)[0], b.accelerations(*state)[0])
    assert b.geometry.body_names == ["shape0"]
    centres, _ = b.geometry.bodies([0.7])
    np.testing.assert_allclose(centres[0], [2 * np.sin(0.7), -2 * np.cos(0.7), 0.0])
    kinds = solids_of(b.geometry)
    assert kinds.kinds == ["ellipsoid"] and kinds.half.tolist() == [[0.3, 0.2, 0.1]]


def test_bad_shapes_are_refused():
    s = pfaff.models.pendulum()
    with pytest.raises(ModelError, match="either `size`"):
        s.add_shape([0, 0, 0], sp.eye(3))
    with pytest.raises(ModelError, match="positive"):
        s.add_shape([0, 0, 0], sp.eye(3), size=[1, -1, 1])
    with pytest.raises(ModelError, match="rotation"):
        s.add_shape([0, 0, 0], 2 * sp.eye(3), size=[1, 1, 1])
    with pytest.raises(ModelError, match="`kind`"):
        s.add_shape([0, 0, 0], sp.eye(3), size=[1, 1, 1], kind="torus")


# ---------------------------------------------------------------------------- GIF solids
def test_gif_draws_the_body_as_its_ellipsoid(body_run):
    """Every vertex of the drawn solid lies on the ellipsoid x = c + C A diag(a) u, |u| = 1."""
    model, run, _ = body_run
    data = sample_frames(run, 3)
    geo = model.geometry
    scene = animation._Scene(geo, data, [], 2.0, 30, "body", blit=True)
    try:
        solids = solids_of(geo, "ellipsoid")
        for i in range(3):
            scene.update(i)
            verts = scene.faces.reshape(-1, 3)
            M = data.dcm[i, 0] @ solids.axes[0] * solids.half[0]
            u = np.linalg.solve(M, (verts - data.centres[i, 0]).T)
            np.testing.assert_allclose(np.linalg.norm(u, axis=0), 1.0, atol=1e-9)
    finally:
        scene.fig.clear()


def test_planar_gif_draws_the_disc_section():
    """A disc rolling down an incline: its outline is the circle of radius √(5 I/(2m))."""
    system = pfaff.models.rolling_on_incline("disk")
    model = system.equations().compile({"m": 2, "r": 0.5, "g": 9.81, "alpha": 0.3})
    run = pfaff.simulate(model, [0.0, 0.0], [0.0, 0.0], (0.0, 0.5))
    data = sample_frames(run, 2)
    scene = animation._Scene(model.geometry, data, [], 2.0, 30, "disc", blit=True)
    try:
        scene.update(1)
        outline = scene.bodies.get_paths()[0].vertices[:-1]
        r = np.linalg.norm(outline - data.centres[1, 0], axis=1)
        m, izz = (model.geometry.sizes()[0][1][k] for k in (0, 9))
        np.testing.assert_allclose(r, np.sqrt(5 * izz / (2 * m)), rtol=1e-9)
    finally:
        scene.fig.clear()


# ---------------------------------------------------------------------------- the bicycle
@pytest.mark.slow
def test_twenty_seconds_of_the_bicycle_fit_in_five_megabytes(tmp_path):
    from pfaff.models.bicycle import bicycle_state

    bike, values, _ = pfaff.models.whipple_bicycle()
    model = bike.equations().compile(values)
    q, qd = bicycle_state(values, speed=4.6, phi_dot=0.5)
    run = pfaff.simulate(model, q, qd, (0.0, 20.0))
    assert run.success
    path = run.to_html(tmp_path / "bicycle.html", up="-z")
    page = path.read_text(encoding="utf-8")
    assert NETWORK.search(page) is None
    assert path.stat().st_size < 5e6
    s = scene_of(page)
    assert s["nbodies"] == 4 and s["nframes"] == 601 and s["follow"]
    # the wheels touch the ground: the lowest point of anything drawn is at z = 0
    assert abs(s["ground"]) < 1e-3
    if BROWSER is not None:
        assert drawn_fraction(path, tmp_path / "bicycle.png") > 0.005


# ---------------------------------------------------------------------------- a real browser
BROWSER = next(
    (shutil.which(b) for b in ("chromium", "chromium-browser", "google-chrome") if shutil.which(b)),
    None,
)
OFFLINE = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
    "--host-resolver-rules=MAP * ~NOTFOUND",  # no name resolves: the network is off
    "--proxy-server=127.0.0.1:9",
    "--window-size=480,360",
    "--virtual-time-budget=2000",
]


@pytest.mark.slow
@pytest.mark.skipif(BROWSER is None, reason="no headless Chromium on this machine")
@pytest.mark.parametrize("which", ["body", "ring"])
def test_headless_browser_draws_a_scene_offline(which, body_run, ring_run, tmp_path):
    run = {"body": body_run[1], "ring": ring_run}[which]
    page = run.to_html(tmp_path / "scene.html")
    assert drawn_fraction(page, tmp_path / "scene.png") > 0.005  # the solid or the ring


def drawn_fraction(page: Path, shot: Path) -> float:
    """Screenshot ``page`` headless with the network off: the share of the canvas not background."""
    from PIL import Image

    subprocess.run(
        [BROWSER, *OFFLINE, f"--screenshot={shot}", page.as_uri()],
        capture_output=True,
        timeout=120,
        check=False,
    )
    dom = subprocess.run(
        [BROWSER, *OFFLINE, "--dump-dom", page.as_uri()],
        capture_output=True,
        timeout=120,
        text=True,
    ).stdout
    assert 'data-ready="yes"' in dom  # the script ran and drew
    rgb = np.asarray(Image.open(shot).convert("RGB"), dtype=int)[:-40]  # above the controls
    background = np.array([247, 247, 245])
    return float((np.abs(rgb - background).sum(axis=-1) > 60).mean())
