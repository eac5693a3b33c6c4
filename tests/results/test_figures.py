"""Figures and notebook display: labels with units, no empty panels, math λ, shown once."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
import sympy as sp
from matplotlib.backends.backend_agg import FigureCanvasAgg

import pfaff
from pfaff.cli.demo import ring_report
from pfaff.errors import OptionError
from pfaff.results.figures import plot_trajectory
from pfaff.results.ring_figure import plot_ring


@pytest.fixture(scope="module")
def pendulum_run() -> pfaff.Trajectory:
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    return pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 0.5))


@pytest.fixture(scope="module")
def pushed_ring_run() -> pfaff.Trajectory:
    model = pfaff.models.rolling_ring(3, force=True).equations().compile({"M": 1, "r": 0.5, "F": 2})
    q0, qd0 = pfaff.models.ring_state(3, 0.5, theta=np.pi)
    return pfaff.simulate(model, q0, qd0, (0.0, 1.0))


@pytest.fixture(scope="module")
def free_run() -> pfaff.Trajectory:
    """No constraints at all: the angle pendulum."""
    model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    return pfaff.simulate(model, [1.0], [0.0], (0.0, 0.5))


def _texts(fig) -> list[str]:
    out = [fig.get_suptitle()] if hasattr(fig, "get_suptitle") else []
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()]
        out += [t.get_text() for t in ax.texts]
        leg = ax.get_legend()
        if leg is not None:
            out += [t.get_text() for t in leg.get_texts()]
    return out


# ------------------------------------------------------------------ trajectory figure
def test_panels_labels_and_units(pendulum_run: pfaff.Trajectory) -> None:
    fig = pendulum_run.plot(units={"x": "m", "y": "m", "lambda1": "N/m"})
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == [
        "coordinates",
        "multipliers (constraint forces)",
        "energy balance",
        "constraint residuals",
    ]
    q_ax, lam_ax, e_ax, r_ax = fig.axes
    assert q_ax.get_ylabel() == "$q$ (m)"  # the unit both curves share
    assert lam_ax.get_ylabel() == r"$\lambda$ (N/m)"
    assert e_ax.get_ylabel() == "energy (J)"
    assert r_ax.get_ylabel().startswith("residual")
    assert [ax.get_xlabel() for ax in (e_ax, r_ax)] == ["time $t$ (s)"] * 2
    assert [t.get_text() for t in lam_ax.get_legend().get_texts()] == [r"$\lambda_{1}$"]
    assert [t.get_text() for t in q_ax.get_legend().get_texts()] == ["$x$", "$y$"]
    assert not any("λ" in s for s in _texts(fig))  # λ is typeset as math everywhere


def test_mixed_units_go_to_the_legend(pushed_ring_run: pfaff.Trajectory) -> None:
    units = {"x": "m", "theta1": "rad", "theta2": "rad", "theta3": "rad"}
    fig = plot_trajectory(pushed_ring_run, units=units)
    q_ax = fig.axes[0]
    assert q_ax.get_ylabel() == "$q$"
    legend = [t.get_text() for t in q_ax.get_legend().get_texts()]
    assert legend == [
        "$x$ (m)",
        r"$\theta_{1}$ (rad)",
        r"$\theta_{2}$ (rad)",
        r"$\theta_{3}$ (rad)",
    ]


def test_energy_panel_plots_the_energy_balance(pushed_ring_run: pfaff.Trajectory) -> None:
    """The push works on the ring: the panel shows T + V − E₀ − W_nc (≈ 0), not the work."""
    traj = pushed_ring_run
    assert float(traj.nc_work[-1]) == pytest.approx(1.0, rel=1e-9)  # F Δx = 2 · 1/2
    e_ax = plot_trajectory(traj).axes[2]
    assert e_ax.get_title() == "energy balance"
    (line, *_) = e_ax.get_lines()
    assert line.get_label() == r"energy balance $T + V - E_0 - W_{nc}$"
    np.testing.assert_array_equal(line.get_ydata(), traj.energy_balance)
    assert np.abs(line.get_ydata()).max() < 1e-8


def test_unconstrained_model_has_no_empty_panels(free_run: pfaff.Trajectory) -> None:
    fig = plot_trajectory(free_run)
    assert [ax.get_title() for ax in fig.axes] == ["coordinates", "energy balance"]
    assert all(ax.has_data() for ax in fig.axes)
    assert all(ax.get_ylabel() for ax in fig.axes)


@pytest.mark.slow  # (over a second: the full suite runs it)
def test_returned_figure_is_not_left_open_in_pyplot(
    pendulum_run: pfaff.Trajectory, tmp_path: Path
) -> None:
    """Jupyter shows a returned figure once: pyplot must not hold (and show) it again."""
    plt.close("all")
    fig = pendulum_run.plot()
    path = tmp_path / "run.svg"
    again = pendulum_run.plot(path)
    assert plt.get_fignums() == []
    assert type(fig).__name__ == "NotebookFigure" and again is not fig
    assert path.read_text().lstrip().startswith("<?xml")


def test_unknown_figure_format_refused_before_drawing(
    pendulum_run: pfaff.Trajectory, tmp_path: Path
) -> None:
    with pytest.raises(OptionError, match=r"\.png.*'.*run\.xyz'"):
        pendulum_run.plot(tmp_path / "run.xyz")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ ring figure
@pytest.mark.parametrize("n", [5, 12, 64])
@pytest.mark.slow  # (over a second: the full suite runs it)
def test_ring_legend_covers_no_particle(n: int) -> None:
    plt.close("all")
    fig = plot_ring(ring_report(n))
    assert plt.get_fignums() == []
    FigureCanvasAgg(fig).draw()
    ax = fig.axes[0]
    box = ax.get_legend().get_window_extent()
    for coll in ax.collections:
        offsets = coll.get_offsets()
        if len(offsets) == 0 or "particle" not in str(coll.get_label()):
            continue
        radius = np.sqrt(np.max(coll.get_sizes())) / 2 * fig.dpi / 72  # marker radius, pixels
        for px, py in ax.transData.transform(offsets):
            inside_x = box.x0 - radius < px < box.x1 + radius
            inside_y = box.y0 - radius < py < box.y1 + radius
            assert not (inside_x and inside_y), f"legend covers the particle at ({px}, {py})"


@pytest.mark.slow  # (over half a second: the full suite runs it)
def test_ring_figure_math_and_units(tmp_path: Path) -> None:
    rep = ring_report(6)
    path = tmp_path / "ring.pdf"
    fig = plot_ring(rep, path)
    assert path.read_bytes()[:4] == b"%PDF"
    texts = _texts(fig)
    assert not any("λ" in s for s in texts)
    assert any(r"$\lambda_1$" in s for s in texts) and any(r"$\lambda_k$" in s for s in texts)
    ax, bx = fig.axes
    assert ax.get_xlabel() == "x (m)" and "(m)" in ax.get_ylabel()
    assert bx.get_ylabel().startswith(r"$\lambda_k$ (N m")


# ------------------------------------------------------------------ equations in Jupyter
def test_lagrange_equations_render_as_latex() -> None:
    eom = pfaff.models.cartesian_pendulum().equations()
    eqs = eom.lagrange_equations
    x, y = eom.coordinates
    m, g = sp.symbols("m g")
    lam = eom.multipliers[0]
    plain = [
        sp.Eq(m * x.diff(pfaff.t, 2), 2 * lam * x),
        sp.Eq(g * m + m * y.diff(pfaff.t, 2), 2 * lam * y),
    ]
    assert isinstance(eqs, list) and eqs == plain and eqs[0] == plain[0]
    latex = eqs._repr_latex_()
    assert latex.startswith("$\\begin{aligned}") and latex.endswith("\\end{aligned}$")
    assert r"m \ddot{x} &= 2 \lambda_{1} x" in latex and r"\\" in latex


def test_long_equation_list_latex_is_truncated() -> None:
    eqs = pfaff.models.rolling_ring(30).equations().lagrange_equations
    latex = eqs._repr_latex_()
    assert latex.count("&=") == 20 and r"\text{(11 more)}" in latex
