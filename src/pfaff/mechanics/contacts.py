"""``add_unilateral_constraint``: a gap g(q, t) ≥ 0 that pushes only while it is closed.

A unilateral constraint is kept as the expression the user gave, with its restitution
coefficient (a number in [0, 1] or an expression in the parameters). It is not a row of the
equations the system derives: the compile stage (:mod:`pfaff.derive.contacts`) makes the models
in which closed contacts are holonomic rows, and a run (:mod:`pfaff.integrate.contact`) switches
between them at impacts and releases.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import sympy as sp

from pfaff.core.errors import ModelError
from pfaff.core.symbols import as_expr, t

if TYPE_CHECKING:
    from pfaff.mechanics.system import SystemSpec


@dataclass(frozen=True)
class ContactSpec:
    """A unilateral constraint as declared: its name, gap (in q(t), t and parameters, ≥ 0 when
    admissible) and restitution coefficient (a number or an expression in the parameters)."""

    name: str
    gap: sp.Expr
    restitution: sp.Expr


class ContactsMixin:
    """``add_unilateral_constraint`` (a part of SystemSpec)."""

    contacts: list[ContactSpec]

    def add_unilateral_constraint(
        self: SystemSpec,
        gap: object,
        name: str | None = None,
        restitution: object = 0.0,
    ) -> None:
        """Declare a unilateral constraint gap(q, t) ≥ 0: a contact that can only push.

        While the gap is open the contact does nothing; it closes when the gap reaches 0 with a
        closing speed (an impact with Newton's restitution law ġ⁺ = −e ġ⁻), acts as a holonomic
        constraint gap = 0 while its multiplier λ ≥ 0 (Aᵀλ, A = ∂gap/∂q, is its force) and
        releases where λ crosses zero. A run reports each as an event ("impact", "release",
        "rest"; see :func:`pfaff.simulate`). Models with families do not support it.

        Parameters
        ----------
        gap : sympy expression
            In the coordinates, time and parameters; ≥ 0 on admissible configurations.
        name : str, optional
            Default ``"contact1"``, ``"contact2"``, ... in the order of declaration; it is also
            the name of its multiplier's constraint row.
        restitution : float or sympy expression
            Newton's coefficient e in [0, 1] (0: the contact closes without bouncing), or an
            expression in the parameters (checked when the model is compiled).

        Raises
        ------
        ModelError
            The gap depends on velocities or on functions that are not coordinates, is constant,
            or the name is taken; a numeric restitution outside [0, 1].

        Examples
        --------
        >>> import pfaff
        >>> y = pfaff.coordinates("y")
        >>> s = pfaff.System([y])
        >>> s.add_particle(1, [0, y]); s.add_potential_energy(9.81 * y)
        >>> s.add_unilateral_constraint(y, name="floor", restitution=0.5)
        >>> [c.name for c in s.contacts], s.n_constraints
        (['floor'], 0)
        """
        label = name if name is not None else f"contact{len(self.contacts) + 1}"
        if not isinstance(label, str) or not label:
            raise ModelError(
                f"`name` of a unilateral constraint must be a non-empty string, got {name!r:.60}"
            )
        taken = {c.name for c in self.contacts} | {p.name for p in self.constraints}
        if label in taken:
            raise ModelError(f"`name`: there is already a constraint `{label}`")
        if self.families:
            raise ModelError(
                f"unilateral constraint `{label}`: systems with families do not support "
                "unilateral constraints (contacts) yet"
            )
        if isinstance(gap, sp.Equality | sp.core.relational.Relational):
            raise ModelError(
                f"unilateral constraint `{label}`: `gap` must be an expression g(q, t) (meaning "
                "g ≥ 0), not a relation"
            )
        known = set(self._parameters)
        try:
            g = as_expr(gap, f"unilateral constraint `{label}`: `gap`")
            e = as_expr(restitution, f"unilateral constraint `{label}`: `restitution`")
            self._scan((g,), f"unilateral constraint `{label}`: `gap`", speeds=False)
            if not g.has(*self.coordinates):
                raise ModelError(
                    f"unilateral constraint `{label}`: `gap` = {g} does not depend on the coordinates"
                )
            self._scan((e,), f"unilateral constraint `{label}`: `restitution`", speeds=False)
            if e.has(t, *self.coordinates):
                raise ModelError(
                    f"unilateral constraint `{label}`: `restitution` must be a number or an "
                    f"expression in the parameters, got {e}"
                )
            if e.is_number and not (e.is_real and 0 <= float(e) <= 1):
                raise ModelError(
                    f"unilateral constraint `{label}`: `restitution` must lie in [0, 1], got {e}"
                )
        except Exception:
            self._parameters = known  # a refused constraint adds no parameter
            raise
        self.contacts.append(ContactSpec(label, g, e))
