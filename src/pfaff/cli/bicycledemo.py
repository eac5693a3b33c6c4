"""``pfaff demo bicycle``: the Whipple bicycle benchmark (Meijaard et al. 2007) linearized.

The lean-steer eigenvalues of upright straight running at a speed, against the published
linearized equations; the weave and capsize speeds by root finding on pfaff's linearization,
against the published ones; and, with ``--plot``, the root locus over 0–10 m/s.
"""

from __future__ import annotations

import time

import numpy as np

from pfaff.models.bicycle import (
    MEIJAARD_CAPSIZE_SPEED,
    MEIJAARD_WEAVE_SPEED,
    bicycle_operating_point,
    lean_steer_eigenvalues,
    meijaard_eigenvalues,
    stability_speeds,
    whipple_bicycle,
)


def bicycle_report(speed: float, plot: str | None = None, points: int = 81) -> dict:
    """The demo's numbers (a JSON-able dict); the root-locus figure written to ``plot``."""
    start = time.process_time()
    bike = whipple_bicycle()
    eom = bike.equations()
    derived = time.process_time()
    lin = eom.linearize(bicycle_operating_point(speed), bike.independent, bike.independent_speeds)
    w = lean_steer_eigenvalues(lin)
    linearized = time.process_time()
    weave, capsize = stability_speeds(eom)
    rep = {
        "model": "Whipple bicycle, benchmark parameters of Meijaard et al. (2007)",
        "speed": speed,
        "eigenvalues": [[float(e.real), float(e.imag)] for e in w],
        "stable": lin.is_stable(),
        "max_error_vs_published_equations": float(np.abs(w - meijaard_eigenvalues(speed)).max()),
        "weave_speed": weave,
        "capsize_speed": capsize,
        "published": {"weave_speed": MEIJAARD_WEAVE_SPEED, "capsize_speed": MEIJAARD_CAPSIZE_SPEED},
        "cpu_seconds": {"equations": derived - start, "linearize": linearized - derived},
    }
    if plot:
        from pfaff.results.figures import save_figure
        from pfaff.results.locus import locus_figure

        speeds = np.linspace(0.0, 10.0, points)
        eig = np.array(
            [
                lean_steer_eigenvalues(
                    eom.linearize(
                        bicycle_operating_point(v), bike.independent, bike.independent_speeds
                    )
                )
                for v in speeds
            ]
        )
        fig = locus_figure(speeds, eig, "speed v (m/s)")
        for ax in fig.axes:
            for v in (weave, capsize):
                ax.axvline(v, color="0.5", lw=0.8, ls=":")
        fig.axes[0].set_title("Whipple bicycle: lean-steer eigenvalues (Meijaard et al. 2007)")
        fig.axes[0].set_ylim(-10, 10)
        save_figure(fig, plot)
        rep["plot"] = plot
    return rep


def format_bicycle(rep: dict) -> str:
    """The report as text."""
    lines = [rep["model"], f"upright straight running at v = {rep['speed']:g} m/s:"]
    for re, im in rep["eigenvalues"]:
        lines.append(f"  eigenvalue {re:+.12f} {im:+.12f}i")
    lines.append(
        f"  {'self-stable' if rep['stable'] else 'unstable'} "
        f"(largest difference from the published equations {rep['max_error_vs_published_equations']:.1e})"
    )
    pub = rep["published"]
    lines.append(
        f"weave speed   {rep['weave_speed']:.14f} m/s (published {pub['weave_speed']:.14f})"
    )
    lines.append(
        f"capsize speed {rep['capsize_speed']:.14f} m/s (published {pub['capsize_speed']:.14f})"
    )
    if "plot" in rep:
        lines.append(f"Wrote {rep['plot']}")
    return "\n".join(lines)
