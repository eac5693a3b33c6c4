"""Work accounting: no-slip friction and the normal force do no work; a push does."""

from __future__ import annotations

import sympy as sp

import pfaff


def _ring_with_contact_forces(n: int, contact: int) -> tuple[pfaff.System, list]:
    ring = pfaff.models.rolling_ring(n, force=True)
    x, *th = ring.coordinates
    r, Ff, Nn = sp.symbols("r F_f N")
    pos = [x + r * sp.sin(th[contact]), r * sp.cos(th[contact])]
    ring.add_force([Ff, 0], at=pos, name="friction")
    ring.add_force([0, Nn], at=pos, name="normal")
    return ring, th


def test_contact_forces_do_no_work_at_the_contact() -> None:
    ring, th = _ring_with_contact_forces(6, contact=2)
    works = {w.name: w for w in ring.work([th[0]])}
    at_contact = {th[2]: sp.pi}
    assert works["friction"].does_work(at=at_contact) is False
    assert works["normal"].does_work(at=at_contact) is False
    # The contact point does not move on admissible motions (the seed's argument).
    v = works["friction"].admissible_point_velocity.subs(at_contact)
    assert v == sp.zeros(2, 1)
    # Away from the contact the same material point moves, and friction would do work.
    assert works["friction"].does_work(at={th[2]: sp.pi / 2}) is True
    assert works["normal"].does_work(at={th[2]: sp.pi / 2}) is True
    # The push at the centre always does work: power F r θ̇.
    r, F = sp.symbols("r F")
    assert works["push"].does_work() is True
    assert sp.simplify(works["push"].virtual_power - F * r * th[0].diff(pfaff.t)) == 0


def test_generalized_force_partial_velocities() -> None:
    """Q_j = F · ∂r/∂q_j for a force at a particle of the ring."""
    ring, th = _ring_with_contact_forces(3, contact=1)
    w = {w.name: w for w in ring.work()}["friction"]
    r, Ff = sp.symbols("r F_f")
    expected = sp.Matrix([Ff, 0, Ff * r * sp.cos(th[1]), 0])
    assert sp.simplify(w.generalized_force - expected) == sp.zeros(4, 1)


def test_minimal_rolling_disk_friction() -> None:
    """Minimal coordinates: friction at the contact of a rolling disk has zero virtual power."""
    x, th = pfaff.coordinates("x theta")
    r, f, m = sp.symbols("r f m")
    s = pfaff.System([x, th])
    s.add_particle(m, [x, 0])
    s.add_kinetic_energy(m * r**2 * th.diff(pfaff.t) ** 2 / 4)
    s.add_holonomic_constraint(x - r * th, name="no slip")
    contact = [x + r * sp.sin(th + sp.pi), r * sp.cos(th + sp.pi)]
    s.add_force([f, 0], at=contact, name="friction")
    w = s.work([th])[0]
    assert w.does_work(at={th: 0}) is False
    assert w.does_work(at={th: 1}) is True
