"""Small systems several test modules build alike."""

from __future__ import annotations

import sympy as sp

import pfaff


def driven_particle(*rows: str) -> pfaff.System:
    """A unit particle in the plane pushed along x by an input u and held on the line y = x by
    the given rows (``"a"``: x − y, ``"b"``: 2x − 2y; none given: one unnamed y − x)."""
    x, y = pfaff.coordinates("x y")
    u = sp.Symbol("u")
    s = pfaff.System([x, y])
    s.add_particle(1, [x, y])
    s.add_force([u, 0], at=[x, y])
    s.add_input(u)
    forms = {"a": x - y, "b": 2 * x - 2 * y}
    if not rows:
        s.add_holonomic_constraint(y - x)
    for name in rows:
        s.add_holonomic_constraint(forms[name], name=name)
    return s
