"""The seed's rolling-ring demo: derivation, multipliers by back-substitution, reduction, timings."""

from __future__ import annotations

import resource
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import sympy as sp
from sympy.physics.vector.printing import vsprint

from pfaff import models
from pfaff.cli.backsub import multipliers_by_back_substitution

MAX_LISTED = 1000  # multipliers listed in the report (all of them up to this N)
EXPLICIT_REDUCE_MAX = 64  # explicit reduction up to this N; the one-coordinate model beyond
SHOW_EQUATIONS_MAX = 8


class Stopwatch:
    """Collects wall-clock seconds per named stage."""

    def __init__(self) -> None:
        self.timings: dict[str, float] = {}

    def run(self, name: str, fn: Callable[[], Any]) -> Any:
        """Run ``fn`` and record its time under ``name``."""
        t0 = time.perf_counter()
        out = fn()
        self.timings[name] = self.timings.get(name, 0.0) + time.perf_counter() - t0
        return out


def peak_rss_mb() -> float:
    """Peak resident set size of this process in MiB."""
    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return kb / 1024 if sys.platform != "darwin" else kb / 2**20


def pfaffian_pattern(A: sp.MatrixBase, coords: tuple, max_rows: int = 9, max_cols: int = 10) -> str:
    """Text picture of the top-left corner of A with column labels."""
    rows, cols = min(A.rows, max_rows), min(A.cols, max_cols)
    names = [str(q.func) for q in coords[:cols]]
    cells = [[vsprint(A[i, j]) if A[i, j] != 0 else "·" for j in range(cols)] for i in range(rows)]
    w = max(max(len(s) for s in names), *(len(c) for r in cells for c in r))
    head = "      " + " ".join(s.rjust(w) for s in names) + (" …" if A.cols > cols else "")
    lines = [head]
    for i, r in enumerate(cells):
        lines.append(
            f"  {i + 1:>3} " + " ".join(c.rjust(w) for c in r) + (" …" if A.cols > cols else "")
        )
    if A.rows > rows:
        lines.append("    ⋮")
    return "\n".join(lines)


def ring_report(
    n: int, *, force: float = 2.0, mass: float = 1.0, radius: float = 0.5, theta_dot: float = 0.0
) -> dict:
    """Run the ring demo and return every number and string it shows.

    The state is θ_1 = π (particle 1 at the contact point), x = rπ, all θ̇_k = ``theta_dot``.

    Examples
    --------
    >>> rep = ring_report(6, force=2.0, mass=1.0, radius=0.5)
    >>> round(rep["theta_ddot"], 9), round(rep["friction"], 9)
    (2.0, -1.0)
    """
    sw = Stopwatch()
    M, r, F = sp.symbols("M r F")
    ring = sw.run("build", lambda: models.rolling_ring(n, mass=M, radius=r, force=F))
    eom = sw.run("derive", ring.equations)
    values = {"M": mass, "r": radius, "F": force}
    model = sw.run("compile", lambda: eom.compile(values))
    q, qd = models.ring_state(n, radius, theta=np.pi, theta_dot=theta_dot)
    qdd, lam = sw.run("solve", lambda: model.accelerations(0.0, q, qd))
    check = _family_checks if eom.family else _explicit_checks
    res, lam_bs, order, resid, bs_diff = check(sw, model, q, qd, qdd, lam)
    shown = slice(None) if n <= MAX_LISTED else slice(0, MAX_LISTED)
    rep: dict[str, Any] = {
        "particles": n,
        "parameters": {"M": mass, "r": radius, "F": force},
        "state": {"theta1": float(np.pi), "theta_dot": theta_dot},
        "theta_ddot": float(qdd[1]),
        "x_ddot": float(qdd[0]),
        "friction": float(lam[0]),
        "expected": {
            "theta_ddot": force / (2 * mass * radius),
            "x_ddot": force / (2 * mass),
            "friction": -force / 2,
        },
        "theta_ddot_max_error": float(np.max(np.abs(qdd[1:] - force / (2 * mass * radius)))),
        "model": "family" if eom.family else "explicit",
        "solver": model.stats.get("solver", "dense" if n + eom.m <= 400 else "superlu"),
        "multipliers": lam[shown].tolist(),
        "multipliers_listed": len(lam[shown]),
        "multipliers_back_substitution": lam_bs[shown].tolist(),
        "back_substitution_order": [int(i) + 1 for i in order[:5]],
        "back_substitution_max_difference": bs_diff,
        "constraint_residual": float(max(res.values())),
        "constraint_residual_detail": res,
    }
    small = eom if not eom.family else models.rolling_ring(min(n, 10), force=F).equations()
    sym_m = sw.run("symbolic_matrices", lambda: (small.constraint_matrix, small.mass_matrix))
    rep["pfaffian_pattern"] = pfaffian_pattern(sym_m[0], small.coordinates)
    if n <= SHOW_EQUATIONS_MAX:
        rep["equations"] = [f"{vsprint(e.lhs)} = {vsprint(e.rhs)}" for e in eom.lagrange_equations]
        rep["acceleration_constraints"] = [
            f"{vsprint(e)} = 0" for e in eom.acceleration_constraints
        ]
    if n <= EXPLICIT_REDUCE_MAX:
        red = sw.run("reduce", lambda: ring.reduce([ring.coordinates[1]]))
        rep["reduced_from"] = f"explicit {n}-particle model, independent coordinate theta1"
    else:
        mini = models.rolling_ring_minimal(mass=M, radius=r, force=F)
        red = sw.run("reduce", mini.equations)
        rep["reduced_from"] = (
            "one-coordinate model T = I θ̇² (explicit reduction is done for N <= 64)"
        )
    eq = red.lagrange_equations[0]
    rep["reduced_equation"] = f"{vsprint(eq.lhs)} = {vsprint(eq.rhs)}"
    rep["reduced_equation_latex"] = sp.latex(eq).replace(r"\frac{d^{2}}{d t^{2}}", r"\ddot")
    red_model = red.compile(values)
    rep["reduced_theta_ddot"] = float(red_model.accelerations(0.0, [np.pi], [theta_dot])[0][0])
    rep["timings"] = sw.timings
    rep["timings"]["total"] = float(sum(sw.timings.values()))
    rep["solve_ns_per_particle"] = 1e9 * rep["timings"]["solve"] / n
    rep["peak_rss_mb"] = peak_rss_mb()
    rep["_arrays"] = {"q": q, "qdd": qdd, "lam": lam, "generalized_constraint_force": resid}
    return rep


def _explicit_checks(sw: Stopwatch, model, q, qd, qdd, lam) -> tuple:
    """Residuals and the seed's back-substitution, from the assembled matrices."""
    f, g = model.constraint_residual(0.0, q, qd)
    A = model.constraint_matrix(0.0, q)
    acc = model.acceleration_residual(0.0, q, qd, qdd)
    resid = model.mass_matrix(0.0, q) @ qdd - model.forcing(0.0, q, qd)
    lam_bs, order = sw.run("back_substitution", lambda: multipliers_by_back_substitution(A, resid))
    return _residuals(f, g, acc), lam_bs, order, resid, float(np.max(np.abs(lam_bs - lam)))


def _family_checks(sw: Stopwatch, model, q, qd, qdd, lam) -> tuple:
    """Residuals of a family model, all O(N): the solver's λ *is* the back-substitution
    (λ_N first); the check is how well Aᵀλ reproduces the generalized constraint force."""
    f, g = sw.run("residuals", lambda: model.constraint_residual(0.0, q, qd))
    acc = model.acceleration_residual(0.0, q, qd, qdd)
    resid = model.generalized_constraint_force(0.0, q, qd, qdd)
    err = float(np.max(np.abs(model.constraint_force(0.0, q, lam) - resid)))
    order = list(range(len(lam) - 1, max(len(lam) - 6, -1), -1))
    return _residuals(f, g, acc), lam, order, resid, err


def _residuals(f, g, acc) -> dict:
    return {
        "position": float(np.max(np.abs(f))),
        "velocity": float(np.max(np.abs(g))),
        "acceleration": float(np.max(np.abs(acc))),
    }


def format_report(rep: dict) -> str:
    """Human-readable text of :func:`ring_report`."""
    n = rep["particles"]
    p = rep["parameters"]
    e = rep["expected"]
    out = [
        f"Rolling ring of N = {n} particles (M = {p['M']}, r = {p['r']}, push F = {p['F']} at the centre)",
        "q = (x, θ_1 … θ_N); no slip x - r θ_1 = 0; spacing θ_(k+1) - θ_k - 2π/N = 0",
        "",
        "Pfaffian constraint matrix A (A q̇ = 0), top-left corner:",
        rep["pfaffian_pattern"],
        "",
    ]
    if "equations" in rep:
        out.append("Lagrange's equations  M q̈ + h = Q + Aᵀλ  (' = d/dt):")
        out += [f"  {s}" for s in rep["equations"]]
        out.append("Differentiated constraints:")
        out += [f"  {s}" for s in rep["acceleration_constraints"]]
        out.append("")
    lam = rep["multipliers"]
    out += [
        f"At θ_1 = π (particle 1 at the contact), θ̇ = {rep['state']['theta_dot']}:",
        f"  θ̈  = {rep['theta_ddot']:.12g}   (F/(2Mr) = {e['theta_ddot']:.12g})",
        f"  ẍ  = {rep['x_ddot']:.12g}   (F/(2M)  = {e['x_ddot']:.12g})",
        f"  λ_1 = {rep['friction']:.12g}   (friction at the contact, -F/2 = {e['friction']:.12g})",
        "",
        "Multipliers by back-substitution (the seed's step backwards: λ_N first, λ_1 last):",
        f"  order: λ_{', λ_'.join(map(str, rep['back_substitution_order']))}, …",
    ]
    listed = len(lam)  # the report lists the first MAX_LISTED multipliers of a large ring
    show = list(range(min(listed, 4))) + ([listed - 1] if listed > 4 else [])
    for i in show:
        out.append(
            f"  λ_{i + 1:<4} = {lam[i]: .10f}   back-substituted {rep['multipliers_back_substitution'][i]: .10f}"
        )
    out += [
        f"  max |λ_KKT - λ_back-substitution| = {rep['back_substitution_max_difference']:.2e}",
        "",
        f"Reduced equation ({rep['reduced_from']}):",
        f"  {rep['reduced_equation']}      (F = 0: 2 M r² θ̈ = 0, the seed's result)",
        f"  its θ̈ = {rep['reduced_theta_ddot']:.12g}",
        "",
        f"Constraint residual (max |f|, |A q̇ + b|, |A q̈ + Ȧq̇|): {rep['constraint_residual']:.2e}",
        "Timings (s): " + ", ".join(f"{k} {v:.3f}" for k, v in rep["timings"].items()),
        f"Peak RSS: {rep['peak_rss_mb']:.0f} MiB",
    ]
    return "\n".join(out)
