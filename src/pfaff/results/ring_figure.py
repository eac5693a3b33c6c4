"""Figures: the rolling ring with its constraint forces, and the multipliers against particle index."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from pfaff.results.figures import figure_format, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PLOT_POINTS = 20_000  # multipliers drawn at most


def plot_ring(rep: dict, path: str | os.PathLike | None = None) -> Figure:
    """Draw the ring demo of :func:`pfaff.cli.demo.ring_report` (to ``path`` if given).

    Left: the ring, its particles, the push at the centre, the friction λ_1 at the contact and the
    tangential constraint force on each particle ((Aᵀλ)_θk / r along e_θ); the legend sits below
    the drawing, never on a particle. Right: the multipliers λ_k against k, with the no-slip
    friction λ_1 marked. Units are SI (the demo's M in kg, r in m, F in N).

    Parameters
    ----------
    rep : dict
        The report, with its ``_arrays``.
    path : str or PathLike, optional
        Figure file (PNG, SVG, PDF, ...: :func:`pfaff.results.figures.figure_formats`).

    Returns
    -------
    matplotlib.figure.Figure
        Made without pyplot (nothing is left open there); shown once in Jupyter, or not at all
        when written to ``path`` (:class:`pfaff.results.notebook.NotebookFigure`).
    """
    from pfaff.results.notebook import NotebookFigure

    if path is not None:
        figure_format(path)  # refuse an unknown format before drawing anything

    arr = rep["_arrays"]
    q, lam, gcf = arr["q"], arr["lam"], arr["generalized_constraint_force"]
    n, r = rep["particles"], rep["parameters"]["r"]
    F = rep["parameters"]["F"]
    x, th = q[0], q[1:]
    fig = NotebookFigure(figsize=(12, 6), layout="constrained")
    ax, bx = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.25]})
    # --- the ring
    s = np.linspace(0, 2 * np.pi, 400)
    ax.plot(x + r * np.sin(s), r * np.cos(s), color="0.75", lw=1.5, zorder=1)
    ax.axhline(-r, color="0.3", lw=1.2)
    ax.fill_between([x - 2 * r, x + 2 * r], -r - 0.12 * r, -r, color="0.9", zorder=0)
    shown = np.linspace(0, n - 1, min(n, 64)).astype(int)
    px, py = x + r * np.sin(th[shown]), r * np.cos(th[shown])
    ax.scatter(
        px, py, s=max(8, 600 / max(len(shown), 1)), c="tab:blue", zorder=3, label="particles"
    )
    ax.scatter(px[:1], py[:1], s=60, c="tab:red", zorder=4, label="particle 1 (contact)")
    scale = 0.6 * r / max(abs(F), 1e-12)
    tang = gcf[1:][shown] / r
    et = np.stack([np.cos(th[shown]), -np.sin(th[shown])])
    tscale = 0.35 * r / max(float(np.max(np.abs(tang))), 1e-300)  # own scale: these are small
    ax.quiver(
        px,
        py,
        et[0] * tang * tscale,
        et[1] * tang * tscale,
        angles="xy",
        scale_units="xy",
        scale=1,
        color="tab:green",
        width=0.004,
        label=f"tangential constraint force (max {np.max(np.abs(tang)):.3g} N, own scale)",
    )
    ax.annotate(
        "",
        xy=(x + F * scale, 0),
        xytext=(x, 0),
        arrowprops={"arrowstyle": "-|>", "color": "k", "lw": 2},
    )
    ax.text(x + F * scale / 2, 0.06 * r, f"F = {F:g} N", ha="center")
    ax.annotate(
        "",
        xy=(x + lam[0] * scale, -r),
        xytext=(x, -r),
        arrowprops={"arrowstyle": "-|>", "color": "tab:red", "lw": 2},
    )
    ax.text(
        x + lam[0] * scale / 2,
        -r - 0.1 * r,
        rf"friction $\lambda_1$ = {lam[0]:.4g} N",
        ha="center",
        va="top",
        color="tab:red",
    )
    ax.set_aspect("equal")
    ax.set_xlim(x - 1.6 * r, x + 1.6 * r)
    ax.set_ylim(-1.35 * r, 1.3 * r)
    ax.set_title(
        rf"Rolling ring, N = {n}: $\ddot\theta$ = {rep['theta_ddot']:.6g} rad/s², "
        rf"$\ddot x$ = {rep['x_ddot']:.6g} m/s²"
    )
    # below the axes: a legend inside would cover particles wherever the ring has turned them
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), fontsize=8, ncols=2)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("height above the centre (m)")
    # --- multipliers
    # every multiplier up to PLOT_POINTS, else a log-spaced sample (16 million points draw nothing new)
    k = np.unique(np.geomspace(1, n, PLOT_POINTS).astype(np.int64)) if n > PLOT_POINTS else None
    k = np.arange(1, n + 1) if k is None else k
    bx.plot(
        k[1:],
        lam[k[1:] - 1],
        ".-",
        ms=3 if n > 64 else 6,
        color="tab:blue",
        label=r"spacing multipliers $\lambda_k$ (k ≥ 2, N m)",
    )
    bx.plot(
        [1],
        [lam[0]],
        "o",
        color="tab:red",
        label=rf"no-slip multiplier $\lambda_1$ = {lam[0]:.4g} N (= −F/2)",
    )
    bx.axhline(0, color="0.6", lw=0.8)
    bx.set_xlabel("constraint k")
    bx.set_ylabel(r"$\lambda_k$ (N m; $\lambda_1$ in N)")
    bx.set_title(r"Multipliers (found by back-substitution from $\lambda_N$ down to $\lambda_1$)")
    bx.legend(fontsize=8)
    if n > 64:
        bx.set_xscale("log")
    if path is not None:
        save_figure(fig, path, dpi=120)
    return fig
