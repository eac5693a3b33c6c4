"""What a notebook shows: one PNG per plot() call, HTML summaries of results, LaTeX equations.

The fast tests read the representations IPython asks for; the slow one executes a notebook in a
fresh Jupyter kernel (nbclient) and counts what it displayed.
"""

from __future__ import annotations

import base64
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import pfaff
from pfaff.core.display import number
from pfaff.results.notebook import NotebookFigure


@pytest.fixture(scope="module")
def pendulum_run() -> pfaff.Trajectory:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    return pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 0.5))


def _oscillator() -> tuple[pfaff.System, sp.Function]:
    """m ẍ + c ẋ + k x = 0: eigenvalues −c/2m ± i√(k/m − c²/4m²)."""
    x = pfaff.coordinates("x")
    m, c, k = sp.symbols("m c k")
    s = pfaff.System([x])
    s.add_particle(m, [x, 0])
    s.add_potential_energy(k * x**2 / 2)
    s.add_generalized_force(x, -c * x.diff(pfaff.t))
    return s, x


def _cells(page: str) -> dict[str, str]:
    """The (label, value) rows of a summary table, unescaped."""
    import html

    rows = re.findall(r"<th[^>]*>(.*?)</th><td[^>]*>(.*?)</td>", page)
    return {html.unescape(k): html.unescape(v) for k, v in rows}


# ------------------------------------------------------------------ figures
@pytest.mark.slow  # (over a second: the full suite runs it)
def test_figure_shows_one_png_unless_written(
    pendulum_run: pfaff.Trajectory, tmp_path: Path
) -> None:
    shown = NotebookFigure(figsize=(2, 1))._repr_mimebundle_()
    assert set(shown) == {"image/png", "text/plain"}
    assert shown["image/png"].startswith(b"\x89PNG\r\n\x1a\n")
    width, height = (int.from_bytes(shown["image/png"][k : k + 4], "big") for k in (16, 20))
    assert (width, height) == (200, 100)  # 2 × 1 inches at 100 dpi, no cropping
    written = pendulum_run.plot(tmp_path / "run.png")
    assert written._repr_mimebundle_() == {
        "text/plain": f"<Figure written to {str(tmp_path / 'run.png')!r}>"
    }
    assert (tmp_path / "run.png").read_bytes().startswith(b"\x89PNG")


def test_figure_display_goes_through_one_publish(monkeypatch: pytest.MonkeyPatch) -> None:
    """IPython asks ``_ipython_display_`` before any printer the inline backend registered for
    figures: the figure publishes itself once, as PNG."""
    display = pytest.importorskip("IPython.display")
    published: list[dict] = []
    monkeypatch.setattr(display, "display", lambda obj, raw=False: published.append(obj))
    NotebookFigure(figsize=(2, 1))._ipython_display_()
    assert len(published) == 1 and "image/png" in published[0]


# ------------------------------------------------------------------ HTML summaries
def test_trajectory_summary(pendulum_run: pfaff.Trajectory) -> None:
    cells = _cells(pendulum_run._repr_html_())
    assert cells["status"] == "success"
    assert cells["span"] == f"t = 0 … 0.5 ({len(pendulum_run.t)} reported times)"
    assert f"steps {pendulum_run.stats['steps']}," in cells["steps"]
    f = np.abs(pendulum_run.constraint_residual[:, 0]).max()
    assert cells["constraint residual"].startswith(f"max |f| {number(f)}")
    balance = float(cells["energy balance"].rsplit(" ", 1)[1])
    assert balance == pytest.approx(np.abs(pendulum_run.energy_balance).max(), rel=1e-2)


def test_failed_run_summary_says_why() -> None:
    x = pfaff.coordinates("x")
    s = pfaff.System([x])
    s.add_particle(1, [x, 0])
    s.add_generalized_force(x, sp.sqrt(1 - x))  # pushed past x = 1, where it is undefined
    traj = pfaff.simulate(s.equations().compile({}), [0.0], [1.0], (0.0, 5.0))
    cells = _cells(traj._repr_html_())
    assert traj.status == "failed" and cells["status"] == f"failed: {traj.message}"


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_names_are_escaped() -> None:
    s, x = _oscillator()
    s.add_event(x, name="<b>x</b> & zero")
    model = s.equations().compile({"m": 1, "c": 0, "k": 1})
    traj = pfaff.simulate(model, [1.0], [0.0], (0.0, 2.0))
    page = traj._repr_html_()
    assert "<b>x" not in page and "&lt;b&gt;x&lt;/b&gt; &amp; zero × 1" in page


def test_linearization_summary_against_closed_form() -> None:
    s, x = _oscillator()
    lin = s.equations().linearize({x: 0, "m": 2.0, "c": 0.8, "k": 8.0}, [x])
    page = lin._repr_html_()
    assert _cells(page)["stable"] == "yes" and _cells(page)["states"] == "x, x_dot"
    imag = np.sqrt(8.0 / 2.0 - 0.8**2 / 16)  # 1.98997...
    rows = re.findall(r"<tr><td>(.*?)</td><td>(.*?)</td><td>(.*?)</td></tr>", page)
    assert rows == [
        (f"-0.2 − {number(imag)}i", "2", number(0.1)),
        (f"-0.2 + {number(imag)}i", "2", number(0.1)),
    ]


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_root_locus_summary_stable_where_damped() -> None:
    s, x = _oscillator()
    locus = pfaff.root_locus(
        s.equations(), {x: 0, "m": 1, "k": 4}, [x], vary={"c": [-1, -0.5, 0.5, 1, 2]}
    )
    assert locus.stable_ranges() == [(0.5, 2.0)]
    page = locus._repr_html_()
    cells = _cells(page)
    assert (
        cells["c"] == "5 values, -1 … 2"
        and cells["stable (nonzero eigenvalues with Re s < 0)"] == "0.5 … 2"
    )
    png = re.search(r'src="data:image/png;base64,([^"]+)"', page)
    assert png and base64.b64decode(png.group(1)).startswith(b"\x89PNG")


def test_sweep_summary(tmp_path: Path) -> None:
    path = tmp_path / "spring.toml"
    path.write_text(
        '[model]\ncoordinates = ["x"]\nparameters = { m = 1.0, k = 1.0 }\n'
        'kinetic = "m*dot(x)**2/2"\npotential = "k*x**2/2"\n[initial]\nq = { x = 1.0 }\n'
        "[simulate]\nt_end = 1.0\n"
    )
    ds = pfaff.sweep(path, {"k": [1.0, 4.0, -1e300]}, samples=3, scheduler="synchronous")
    cells = _cells(ds._repr_html_())
    failed = int((ds.status.values != "success").sum())
    assert cells["runs"] == f"{3 - failed} of 3 succeeded" and cells["grid"] == "k × 3"
    assert cells["span"] == "t = 0 … 1 (3 times)"
    assert float(cells["max energy balance error"]) == pytest.approx(
        float(np.nanmax(ds.energy_error.where(ds.status == "success"))), rel=1e-2
    )
    assert type(ds.sel(k=1.0)) is type(ds)  # still the dataset, with its summary


# ------------------------------------------------------------------ LaTeX
def test_work_renders_as_latex() -> None:
    s, _ = _oscillator()
    work = s.work()
    assert isinstance(work, list) and work == [work[0]] and len(work[:1]) == 1
    latex = work._repr_latex_()
    assert latex.startswith("$\\begin{aligned}") and latex.endswith("\\end{aligned}$")
    # the damper: Q = −c ẋ, power −c ẋ² on every motion
    assert r"Q^{T} = \left[\begin{matrix}- c \dot{x}\end{matrix}\right]" in latex
    assert r"P = - c \dot{x}^{2}" in latex


# ------------------------------------------------------------------ a real kernel
NOTEBOOK = [
    "import pfaff\n"
    "model = pfaff.models.cartesian_pendulum().equations().compile({'m': 1, 'g': 9.81, 'L': 1})\n"
    "traj = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 0.5))",
    "traj.plot()",  # a fresh kernel: no pyplot, no %matplotlib inline
    "fig = traj.plot('written.png')\nfig",  # written, not displayed
    "%matplotlib inline",
    "traj.plot()",  # the inline backend's figure printer is registered now
    "import matplotlib.pyplot as plt\nplt.close('all')\ntraj.plot(units={'x': 'm'})",
    "traj",
    "pfaff.models.cartesian_pendulum().equations().lagrange_equations",
]
PLOTS_SHOWN = {1: 1, 2: 0, 4: 1, 5: 1}  # cell -> PNGs it must display


@pytest.mark.slow
def test_notebook_in_a_fresh_kernel(tmp_path: Path) -> None:
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    from jupyter_client import KernelManager
    from jupyter_client.kernelspec import KernelSpecManager

    spec = tmp_path / "kernels" / "pfaff-test"
    spec.mkdir(parents=True)
    argv = [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"]
    (spec / "kernel.json").write_text(
        json.dumps({"argv": argv, "display_name": "pfaff test", "language": "python"})
    )
    km = KernelManager(
        kernel_name="pfaff-test",
        kernel_spec_manager=KernelSpecManager(kernel_dirs=[str(spec.parent)]),
    )
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in NOTEBOOK])
    client = nbclient.NotebookClient(
        nb, km=km, timeout=600, resources={"metadata": {"path": str(tmp_path)}}
    )
    kernel = client.setup_kernel()
    try:
        kernel.__enter__()
    except Exception as e:  # no kernel can start here (sandbox, no sockets)
        pytest.skip(f"no Jupyter kernel could start: {e}")
    try:
        for i, cell in enumerate(nb.cells):
            client.execute_cell(cell, i)
    finally:
        kernel.__exit__(None, None, None)

    def outputs(i: int, mime: str) -> list:
        return [o["data"][mime] for o in nb.cells[i].outputs if mime in o.get("data", {})]

    pngs = {i: len(outputs(i, "image/png")) for i in range(len(NOTEBOOK))}
    assert pngs == {i: PLOTS_SHOWN.get(i, 0) for i in range(len(NOTEBOOK))}
    assert (tmp_path / "written.png").read_bytes().startswith(b"\x89PNG")
    assert outputs(2, "text/plain") == ["<Figure written to 'written.png'>"]
    (page,) = outputs(6, "text/html")
    assert "pfaff.Trajectory" in page and _cells(page)["status"] == "success"
    (latex,) = outputs(7, "text/latex")
    assert r"m \ddot{x} &= 2 \lambda_{1} x" in latex
