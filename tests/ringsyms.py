"""The ring's parameter symbols and its constraint manifold, for the symbolic ring tests."""

from __future__ import annotations

import sympy as sp

import pfaff

M, r, F, g, alpha = sp.symbols("M r F g alpha")


def on_ring_manifold(coords: tuple, theta: sp.Expr | None = None) -> dict:
    """Substitution putting the ring on its constraint manifold: x = rθ, θ_k = θ + (k-1)2π/N."""
    n = len(coords) - 1
    th = theta if theta is not None else sp.Symbol("theta")
    thd, thdd = sp.Symbol("thetad"), sp.Symbol("thetadd")
    x = coords[0]
    t = pfaff.t
    rule = {
        x.diff(t, 2): r * thdd,
        x.diff(t): r * thd,
        x: r * th,
    }
    for k, q in enumerate(coords[1:]):
        rule[q.diff(t, 2)] = thdd
        rule[q.diff(t)] = thd
        rule[q] = th + 2 * sp.pi * k / n
    return rule
