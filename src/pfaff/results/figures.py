"""Figures of a simulated trajectory: coordinates, multipliers, energy error and residuals."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pfaff.core.files import atomic_path

if TYPE_CHECKING:
    from pfaff.results.trajectory import Trajectory

MAX_LINES = 8  # curves per panel; large systems show the first few


def _lines(ax: Any, t: np.ndarray, Y: np.ndarray, names: list[str]) -> None:
    for j in range(min(Y.shape[1], MAX_LINES)):
        ax.plot(t, Y[:, j], lw=1.2, label=names[j])
    if Y.shape[1]:
        ax.legend(fontsize=7, ncol=2, loc="best")
    if Y.shape[1] > MAX_LINES:
        ax.set_title(ax.get_title() + f" (first {MAX_LINES} of {Y.shape[1]})", fontsize=9)


def plot_trajectory(traj: Trajectory, path: str | Path | None = None) -> Any:
    """Four panels: q(t), λ(t), energy error E − E₀ (and Jacobi), max residuals (log scale).

    Parameters
    ----------
    traj : Trajectory
    path : str or Path, optional
        Write the figure there (PNG, PDF, SVG; atomically).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True, layout="constrained")
    t = traj.t
    ax = axes[0, 0]
    ax.set_title("coordinates q(t)")
    _lines(ax, t, traj.q, traj.coordinate_names)
    ax = axes[0, 1]
    ax.set_title("multipliers λ(t) (constraint forces)")
    _lines(ax, t, traj.multipliers, traj.multiplier_names)
    ax = axes[1, 0]
    ax.set_title("energy error")
    if len(t):
        ax.plot(t, traj.energy - traj.energy[0], lw=1.2, label="T + V − E₀")
        if not np.allclose(traj.jacobi, traj.energy, rtol=1e-12, atol=1e-12):
            ax.plot(t, traj.jacobi - traj.jacobi[0], lw=1.0, ls="--", label="Jacobi − J₀")
        ax.legend(fontsize=7)
    ax.set_xlabel("t")
    ax = axes[1, 1]
    ax.set_title("constraint residuals")
    if traj.constraint_residual.shape[-1] and len(t):
        tiny = 1e-18  # exact zeros sit on the floor instead of stretching the axis
        ax.semilogy(
            t, np.maximum(np.abs(traj.position_residual).max(axis=1), tiny), lw=1.2, label="max |f|"
        )
        ax.semilogy(
            t,
            np.maximum(np.abs(traj.velocity_residual).max(axis=1), tiny),
            lw=1.2,
            label="max |A q̇ + b|",
        )
        ax.legend(fontsize=7)
    ax.set_xlabel("t")
    fig.suptitle(f"pfaff: {traj.method} ({traj.status}), {len(t)} points")
    if path is not None:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=110, format=Path(path).suffix.lstrip(".") or "png")
        plt.close(fig)
    return fig
