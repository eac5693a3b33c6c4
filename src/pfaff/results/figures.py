"""Figures of a simulated trajectory: coordinates, multipliers, energy balance and residuals.

Figures are made without pyplot, as :class:`pfaff.results.notebook.NotebookFigure` objects:
nothing is left open in pyplot's list of figures, the user's backend is never switched, and
Jupyter shows a returned figure exactly once (or not at all when it was written to a file).
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pfaff.core.errors import OptionError
from pfaff.core.files import atomic_path

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from pfaff.results.notebook import NotebookFigure
    from pfaff.results.trajectory import Trajectory

MAX_LINES = 8  # curves per panel; large systems show the first few
# formats matplotlib writes with its own backends or Pillow (pgf needs a TeX system: checked)
FIGURE_FORMATS = (
    "png", "pdf", "svg", "svgz", "eps", "ps", "jpg", "jpeg", "tif", "tiff", "webp", "gif", "pgf",
)  # fmt: skip
_GREEK = {
    "alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa",
    "lambda", "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi",
    "omega", "Gamma", "Delta", "Theta", "Lambda", "Xi", "Pi", "Sigma", "Upsilon", "Phi", "Psi",
    "Omega",
}  # fmt: skip


def figure_formats() -> tuple[str, ...]:
    """File name extensions a figure can be written to here (lower case, without the dot).

    Examples
    --------
    >>> "png" in figure_formats() and "xyz" not in figure_formats()
    True
    """
    from matplotlib import rcParams
    from matplotlib.backend_bases import FigureCanvasBase

    known = FigureCanvasBase.get_supported_filetypes()
    tex = shutil.which(str(rcParams["pgf.texsystem"])) is not None
    return tuple(f for f in FIGURE_FORMATS if f in known and (f != "pgf" or tex))


def figure_format(path: str | os.PathLike) -> str:
    """The format of a figure file from its extension; OptionError for an unknown one.

    Examples
    --------
    >>> figure_format("run.PNG")
    'png'
    """
    suffix = Path(path).suffix.lstrip(".").lower()
    formats = figure_formats()
    if suffix not in formats:
        raise OptionError(
            f"a figure file must end in one of {', '.join('.' + f for f in formats)}; "
            f"got {os.fspath(path)!r}"
        )
    return suffix


def save_figure(fig: Figure, path: str | os.PathLike, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` atomically, in the format of its extension; a
    :class:`~pfaff.results.notebook.NotebookFigure` then shows in Jupyter as its file's name."""
    from pfaff.results.notebook import mark_written

    fmt = figure_format(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=fmt)
    mark_written(fig, path)


def math_name(name: str) -> str:
    """A coordinate or multiplier name as matplotlib mathtext: ``theta12`` → ``$\\theta_{12}$``.

    Names that are not a letter word with an optional index are returned unchanged.

    Examples
    --------
    >>> math_name("lambda1"), math_name("x"), math_name("my name")
    ('$\\\\lambda_{1}$', '$x$', 'my name')
    """
    m = re.fullmatch(r"([A-Za-z]+?)_?(\d*)", name)
    if m is None:
        return name
    base, index = m.groups()
    if base in _GREEK:
        base = "\\" + base
    elif len(base) > 1:
        base = rf"\mathrm{{{base}}}"
    return f"${base}_{{{index}}}$" if index else f"${base}$"


def _with_unit(label: str, unit: str | None) -> str:
    return f"{label} ({unit})" if unit else label


def _lines(
    ax: Axes, t: np.ndarray, Y: np.ndarray, names: list[str], units: Mapping[str, str], what: str
) -> None:
    """Up to MAX_LINES curves with math legend entries; the y label carries the common unit."""
    shown = list(range(min(Y.shape[1], MAX_LINES)))
    curve_units = {units.get(names[j]) for j in shown}
    common = curve_units.pop() if len(curve_units) == 1 else None
    for j in shown:
        unit = None if common else units.get(names[j])
        ax.plot(t, Y[:, j], lw=1.2, label=_with_unit(math_name(names[j]), unit))
    if shown:
        ax.legend(fontsize=7, ncols=2, loc="best")
    ax.set_ylabel(_with_unit(what, common))
    if Y.shape[1] > MAX_LINES:
        ax.set_title(ax.get_title() + f" (first {MAX_LINES} of {Y.shape[1]})", fontsize=9)


def _energy_panel(ax: Axes, traj: Trajectory, energy_unit: str | None) -> None:
    t = traj.t
    ax.set_title("energy balance")
    balance = np.asarray(traj.energy_balance)
    change = traj.energy - traj.energy[0]
    worked = not np.allclose(balance, change, rtol=1e-12, atol=1e-12)
    label = r"$T + V - E_0 - W_{nc}$" if worked else r"$T + V - E_0$"
    ax.plot(t, balance, lw=1.2, label=f"energy balance {label}")
    if not np.allclose(traj.jacobi - traj.jacobi[0], change, rtol=1e-12, atol=1e-12):
        ax.plot(t, traj.jacobi - traj.jacobi[0], lw=1.0, ls="--", label=r"Jacobi $J - J_0$")
    ax.legend(fontsize=7)
    ax.set_ylabel(_with_unit("energy", energy_unit))


def _residual_panel(ax: Axes, traj: Trajectory) -> None:
    t = traj.t
    ax.set_title("constraint residuals")
    tiny = 1e-18  # exact zeros sit on the floor instead of stretching the axis
    pos = np.maximum(np.abs(traj.position_residual).max(axis=1), tiny)
    vel = np.maximum(np.abs(traj.velocity_residual).max(axis=1), tiny)
    ax.semilogy(t, pos, lw=1.2, label=r"$\max\,|f|$")
    ax.semilogy(t, vel, lw=1.2, label=r"$\max\,|A\dot{q} + b|$")
    ax.legend(fontsize=7)
    ax.set_ylabel("residual (constraint units)")


def plot_trajectory(
    traj: Trajectory,
    path: str | os.PathLike | None = None,
    *,
    units: Mapping[str, str] | None = None,
) -> NotebookFigure:
    """Coordinates q(t), multipliers λ(t), the energy balance and the constraint residuals.

    A panel with nothing to show is left out: a model without constraints has neither multipliers
    nor residuals; an empty trajectory shows only its (empty) coordinates.

    Parameters
    ----------
    traj : Trajectory
    path : str or PathLike, optional
        Write the figure there (format from the extension: PNG, PDF, SVG, ...; atomically).
    units : mapping of str to str, optional
        Units by coordinate or multiplier name, and for ``"t"`` and ``"energy"`` (defaults:
        ``"s"`` and ``"J"``; pass ``None`` values to leave them out). An axis shows the unit its
        curves share; otherwise each legend entry shows its own.

    Returns
    -------
    NotebookFigure
        A :class:`matplotlib.figure.Figure` not registered with pyplot. Without ``path``, Jupyter
        displays it exactly once when it is returned (in a fresh kernel, with or without
        ``%matplotlib inline``); with ``path`` it is written there and not displayed (Jupyter
        shows the file's name instead). ``fig.savefig`` writes it again.

    Examples
    --------
    >>> import pfaff
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> traj = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 0.2))
    >>> fig = plot_trajectory(traj, units={"x": "m", "y": "m"})
    >>> [ax.get_title() for ax in fig.axes]  # doctest: +NORMALIZE_WHITESPACE
    ['coordinates', 'multipliers (constraint forces)', 'energy balance', 'constraint residuals']
    """
    from pfaff.results.notebook import NotebookFigure

    if path is not None:
        figure_format(path)  # refuse an unknown format before drawing anything
    units = {"t": "s", "energy": "J", **(units or {})}
    t = traj.t
    m = traj.multipliers.shape[1] if traj.multipliers.ndim == 2 else 0
    panels = ["q"]
    if m and len(t):
        panels.append("lambda")
    if len(t):
        panels.append("energy")
    if m and len(t):
        panels.append("residual")
    rows, cols = (2, 2) if len(panels) == 4 else (len(panels), 1)
    fig = NotebookFigure(
        figsize=(11, 7) if cols == 2 else (9, 2.6 * rows + 0.8), layout="constrained"
    )
    axes = fig.subplots(rows, cols, sharex=True, squeeze=False).ravel()
    for ax, panel in zip(axes, panels, strict=True):
        if panel == "q":
            ax.set_title("coordinates")
            _lines(ax, t, traj.q, traj.coordinate_names, units, r"$q$")
        elif panel == "lambda":
            ax.set_title("multipliers (constraint forces)")
            _lines(ax, t, traj.multipliers, traj.multiplier_names, units, r"$\lambda$")
        elif panel == "energy":
            _energy_panel(ax, traj, units.get("energy"))
        else:
            _residual_panel(ax, traj)
    for ax in axes[-cols:]:
        ax.set_xlabel(_with_unit("time $t$", units.get("t")))
    fig.suptitle(f"pfaff: {traj.method} ({traj.status}), {len(t)} points")
    if path is not None:
        save_figure(fig, path)
    return fig
